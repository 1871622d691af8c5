"""Double-double fallback quadrature of the curve engine (thetasol.curves._dd).

References: the mpmath version of the same sums (thetasol.curves._mp.interval_mp, 30 digits) on the
critical intervals of a real spectral curve, and exact rational arithmetic for the primitives.
"""
import json
import pathlib
from fractions import Fraction

import mpmath
import numpy as np
import pytest

from thetasol import inertia, solve_rotation
from thetasol.core.dd import cdd_div, cdd_mul, dd_div
from thetasol.curves import _quad as _curve_quad
from thetasol.curves._dd import curve_to_cdd, intervals_dd, numerators_to_cdd
from thetasol.curves._mp import interval_mp, numerators_mp

REFS = json.loads((pathlib.Path(__file__).parent / "data" / "rotation" / "refs.json").read_text())


def _fr(h, l):
    return Fraction(float(h)) + Fraction(float(l))


def test_dd_primitives_against_fractions():
    rng = np.random.default_rng(7)
    K = 200
    a = tuple(v * s for v, s in zip(rng.standard_normal((4, K)), (1.0, 1e-17, 1.0, 1e-17)))
    b = tuple(v * s for v, s in zip(rng.standard_normal((4, K)), (1.0, 1e-17, 1.0, 1e-17)))
    m = cdd_mul(a, b)
    q = cdd_div(a, b)
    rq = dd_div(a[0], a[1], b[0], b[1])
    for k in range(K):
        ar, ai = _fr(a[0][k], a[1][k]), _fr(a[2][k], a[3][k])
        br, bi = _fr(b[0][k], b[1][k]), _fr(b[2][k], b[3][k])
        mr, mi = ar * br - ai * bi, ar * bi + ai * br
        scale = abs(float(ar)) * abs(float(br)) + abs(float(ai)) * abs(float(bi)) + \
            abs(float(ar)) * abs(float(bi)) + abs(float(ai)) * abs(float(br))
        assert abs(float(_fr(m[0][k], m[1][k]) - mr)) <= 1e-30 * scale
        assert abs(float(_fr(m[2][k], m[3][k]) - mi)) <= 1e-30 * scale
        den = br * br + bi * bi
        qr, qi = (ar * br + ai * bi) / den, (ai * br - ar * bi) / den
        qs = abs(complex(float(qr), float(qi)))
        assert abs(float(_fr(q[0][k], q[1][k]) - qr)) <= 1e-30 * qs
        assert abs(float(_fr(q[2][k], q[3][k]) - qi)) <= 1e-30 * qs
        assert abs(float(_fr(rq[0][k], rq[1][k]) - ar / br)) <= 1e-31 * abs(float(ar / br))


@pytest.fixture(scope="module")
def critical_call():
    """(tracked, exact numerators, critical intervals) of the first critical call in a fast-spin set-up."""
    calls = []
    orig = _curve_quad.Tracked._add_dd

    def spy(self, out, exact, crit):
        if not calls:
            calls.append((self, exact, list(crit)))
        return orig(self, out, exact, crit)

    mp = pytest.MonkeyPatch()
    mp.setattr(_curve_quad.Tracked, "_add_dd", spy)
    try:
        r = REFS["symmetric_fast_spin"]
        solve_rotation(inertia(np.diag(r["J"])), np.array(r["a"]), np.array(r["Q0"]), np.array(r["omega0"]))
    finally:
        mp.undo()
    assert calls, "no critical interval in this set-up: the test case no longer exercises the fallback"
    return calls[0]


def test_dd_interval_sums_match_mpmath(critical_call):
    """Unrounded double-double sums equal 30-digit mpmath sums to 1e-25 relative, interval by interval."""
    tr, exact, crit = critical_call
    poly = tr.tracker.poly
    seeds = tr.interval_seeds(crit)
    dd = intervals_dd(tr.pieces, crit, seeds, curve_to_cdd(poly),
                      numerators_to_cdd(exact), rounded=False)
    worst = 0.0
    with mpmath.workdps(40):
        nums = numerators_mp(exact, 40)
        for (p, _, (lo, hi, N)), s, (rh, rl, ih, il) in zip(crit, seeds, dd):
            ref = interval_mp(tr.pieces[p], lo, hi, N, s, tr.tracker.exact, nums, 30)
            for t, row in enumerate(ref):
                scale = max(abs(v) for v in row)
                assert scale > 0
                for d, v in enumerate(row):
                    err = abs(mpmath.mpc(mpmath.mpf(rh[t, d]) + mpmath.mpf(rl[t, d]),
                                         mpmath.mpf(ih[t, d]) + mpmath.mpf(il[t, d])) - v)
                    worst = max(worst, float(err / scale))
    assert worst <= 1e-25


def test_dd_root_leaving_its_sheet_is_refused(critical_call):
    tr, exact, crit = critical_call
    poly = tr.tracker.poly
    seeds = tr.interval_seeds(crit[:1])
    seeds[0] = seeds[0] * (1 + 1e-2)
    with pytest.raises(ValueError, match="moved away from its sheet"):
        intervals_dd(tr.pieces, crit[:1], seeds, curve_to_cdd(poly),
                     numerators_to_cdd(exact))


def test_second_differential_reuses_the_roots_bit_for_bit():
    """The curve engine keeps the numerator-free double-double stage of its period sums: the periods of
    further differentials after the holomorphic ones equal, bit for bit, those of a fresh curve that
    computes them first."""
    from thetasol.curves.spectral import spectral_curve

    r = REFS["symmetric_oblate"]
    sol = solve_rotation(inertia(np.diag(r["J"])), np.array(r["a"]), np.array(r["Q0"]), np.array(r["omega0"]))
    data = (np.diag(r["J"]), sol.m(0.0), sol.u(0.0))
    first = spectral_curve(*data)
    x, y = first.x, first.y
    first.period_matrix()
    again = first.period_matrix(differentials=[x ** 3, x * y])
    fresh = spectral_curve(*data).period_matrix(differentials=[x ** 3, x * y])
    assert first._edge_tracks._dd_roots, "no double-double stage kept: the test no longer exercises the reuse"
    assert np.array_equal(again, fresh)


def test_local_samples_fall_back_to_mpmath_only_where_double_double_loses_digits():
    """y^2 = (x - 1)^2 + 1e-26 sampled at |x - 1| = 3e-13: two sheets 6e-13 apart under O(1)
    coefficients, so even the compensated residual's second-order error (~eps^2 / |y|) is 4e-8 of y.
    The samples must come back exact to float64 (mpmath polish), and the flag alone (tracker rel
    above 1e-11) must not send well-conditioned samples to mpmath."""
    from types import SimpleNamespace

    import sympy as sp

    from thetasol.curves._mp import ExactEvaluator
    from thetasol.curves._places import _accurate_samples
    from thetasol.curves._poly import CurvePoly

    x, y = sp.symbols("x y")
    e2 = sp.Rational(1, 10**26)
    poly = CurvePoly(sp.expand(y**2 - (x - 1) ** 2 - e2), x, y)
    curve = SimpleNamespace(engine=SimpleNamespace(poly=poly, exact=ExactEvaluator(poly)))
    xs = 1 + 3e-13 * np.exp(2j * np.pi * np.arange(8) / 8)
    with mpmath.workdps(50):
        r = [complex(mpmath.sqrt((mpmath.mpc(complex(v)) - 1) ** 2 + mpmath.mpf(e2.p) / e2.q)) for v in xs]
    exact = np.array([r, [-v for v in r]])

    def err(Y):
        return (np.minimum(np.abs(Y - exact), np.abs(Y - exact[::-1])) / np.abs(exact)).max()

    start = exact * (1 + 1e-9)
    dd_only, _ = _accurate_samples(curve, xs, start.copy(), None)
    polished, _ = _accurate_samples(curve, xs, start.copy(), np.full(8, 1e-3))
    assert err(dd_only) > 1e-9        # the case really needs the fallback
    assert err(polished) <= 2e-16
    # well separated sheets (x far from 1): the same flag leaves the double-double result as it is
    xs2 = xs + 0.5
    with mpmath.workdps(50):
        r2 = [complex(mpmath.sqrt((mpmath.mpc(complex(v)) - 1) ** 2 + mpmath.mpf(e2.p) / e2.q)) for v in xs2]
    start2 = np.array([r2, [-v for v in r2]])
    no_mp = SimpleNamespace(engine=SimpleNamespace(poly=poly, exact=None))  # any use of the mpmath evaluator fails
    a, _ = _accurate_samples(no_mp, xs2, start2.copy(), None)
    b, _ = _accurate_samples(no_mp, xs2, start2.copy(), np.full(8, 1e-3))
    assert np.array_equal(a, b)


@pytest.mark.parametrize("start", [[1e8 + 2, 1e8 + 2.5, 1.0],     # both a third of the gap off
                                   [1e8 + 1.5, 1e8 + 4.5, 1.0],   # a quarter off
                                   [1e8 + 3, 1e8 + 3, 1.0]])      # merged into one float
def test_polish_separates_a_close_pair_far_from_zero(start):
    """Roots 1e8 and 1e8 + 6 (the far branch points of a symmetric body with a small axial spin):
    from starts that four compensated Newton steps do not fix (checked below), polish_dd (Ehrlich-Aberth
    finish) returns both roots exactly."""
    import sympy as sp

    from thetasol.curves._poly import CurvePoly, _newton_dd, _two_prod_c

    x, y = sp.symbols("x y")
    exact = np.array([1.0, 1e8, 1e8 + 6], complex)
    poly = CurvePoly(sp.expand((y - 10**8 - x) * (y - (10**8 + 6)) * (y - 1)), x, y)
    Ahi, Alo = poly.coeff_polys_dd(np.array([0j]))
    Y0 = np.array([start], complex)
    Y, _ = poly.polish_dd(Ahi, Alo, Y0.copy())
    assert np.array_equal(np.sort_complex(Y[0]), exact)
    dhi, dlo = _two_prod_c(Ahi[:, 1:], np.arange(1, 4))
    plain, _, _, _, _ = _newton_dd(Ahi, Alo, dhi, dlo + Alo[:, 1:] * np.arange(1, 4), Y0.copy(), 4)
    assert np.abs(np.sort_complex(plain[0]) - exact).max() > 1e-8


# -- the stored Gauss-Legendre table ---------------------------------------------------------------

@pytest.mark.parametrize("N", [4, 5, 17, 64, 80])
def test_gauss_legendre_table_is_the_computed_values(N):
    """The stored orders are gauss_legendre_dd_mp's values bit for bit (all orders: the slow test)."""
    from thetasol.curves._dd import gauss_legendre_dd, gauss_legendre_dd_mp
    for got, want in zip(gauss_legendre_dd(N), gauss_legendre_dd_mp(N), strict=True):
        np.testing.assert_array_equal(got, want)


@pytest.mark.slow
def test_gauss_legendre_table_every_order():
    from thetasol.curves._dd import TABLE_ORDERS, gauss_legendre_dd, gauss_legendre_dd_mp
    for N in TABLE_ORDERS:
        for got, want in zip(gauss_legendre_dd(N), gauss_legendre_dd_mp(N), strict=True):
            np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("degree", [2, 3, 4, 5])
def test_gauss_legendre_table_against_mpmath_quadrature(degree):
    """Against mpmath's own Gauss-Legendre rule (3 * 2^(degree - 1) nodes: 6, 12, 24, 48) at 40 digits:
    nodes to 2.8e-33, weights to 5.8e-33 relative (measured), double-double rounding."""
    from mpmath.calculus.quadrature import GaussLegendre

    from thetasol.curves._dd import gauss_legendre_dd
    with mpmath.workdps(40):
        ref = sorted(GaussLegendre(mpmath.mp).calc_nodes(degree, mpmath.mp.prec))
        th, tl, wh, wl = gauss_legendre_dd(3 * 2 ** (degree - 1))
        order = np.argsort(th)
        for (x, w), i in zip(ref, order, strict=True):
            assert abs(mpmath.mpf(th[i]) + mpmath.mpf(tl[i]) - x) <= 3e-32
            assert abs(mpmath.mpf(wh[i]) + mpmath.mpf(wl[i]) - w) <= 3e-32 * w
