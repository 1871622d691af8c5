"""thetasol.theta.riemann: identities, genus-1 closed forms (mpmath.jtheta), the mpmath path, the
Siegel reduction with the modular transformation law, API shapes and bad input.

FLINT comparisons are in test_theta_flint.py.
"""
import math

import mpmath
import numpy as np
import pytest

from thetasol import RiemannTheta, riemann_theta, riemann_theta_separated, siegel_reduce
from thetasol.theta import lattice
from thetasol.theta._core import (
    _tail_polynomials,
    _tail_polynomials_loop,
    group_jets,
    jet_layout,
)


def random_tau(g, rng, small=0.05, re=1.0):
    Qm, _ = np.linalg.qr(rng.normal(size=(g, g)))
    ev = np.concatenate([[small], rng.uniform(0.4, 2.0, g - 1)])
    Y = (Qm * ev) @ Qm.T
    X = rng.uniform(-re, re, (g, g))
    tau = X + 1j * Y
    return 0.5 * (tau + tau.T)


def half_chars(g):
    idx = np.arange(4 ** g)
    bits = (idx[:, None] >> np.arange(2 * g - 1, -1, -1)[None, :]) & 1
    return bits[:, :g] / 2.0, bits[:, g:] / 2.0


def close(a, b, tol, scale=None):
    a, b = np.asarray(a), np.asarray(b)
    s = np.maximum(np.abs(b), 1.0) if scale is None else scale
    err = np.max(np.abs(a - b) / s)
    assert err <= tol, f"error {err:.3g} > {tol:g}"
    return err


# ----------------------------------------------------------------------------------------
# genus 1 against mpmath.jtheta (nome q = exp(i pi tau); theta(z|tau) = jtheta(3, pi z, q))
# ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("tau", [0.3 + 1.1j, -0.45 + 0.06j, 0.2 + 3.0j, 7.3 + 0.5j])
def test_genus1_against_jtheta(tau):
    rng = np.random.default_rng(1)
    z = rng.uniform(-1, 1, 6) + 1j * rng.uniform(-1.5, 1.5, 6) * tau.imag
    th = RiemannTheta([[tau]])
    e, v = th.separated(z[:, None], char="all")  # chars (0,0), (0,1/2), (1/2,0), (1/2,1/2)
    e2, v2, d2 = th.jet(z[:, None], char="all", order=1, separated=True)
    with mpmath.workdps(40):
        q = mpmath.exp(1j * mpmath.pi * mpmath.mpc(tau))
        for p, zp in enumerate(z):
            w = mpmath.pi * mpmath.mpc(zp)
            ref = [mpmath.jtheta(3, w, q), mpmath.jtheta(4, w, q)]
            dref = [mpmath.pi * mpmath.jtheta(3, w, q, 1), mpmath.pi * mpmath.jtheta(4, w, q, 1)]
            if abs(tau.real) < 1:  # jtheta(1|2) use q^(1/4) = exp(i pi tau / 4) only for |Re tau| < 1
                ref += [mpmath.jtheta(2, w, q), -mpmath.jtheta(1, w, q)]
                dref += [mpmath.pi * mpmath.jtheta(2, w, q, 1), -mpmath.pi * mpmath.jtheta(1, w, q, 1)]
            s = mpmath.exp(-mpmath.mpf(float(e[p])))
            order = [0, 1, 2, 3][: len(ref)]
            close(v[p, order], np.array([complex(r * s) for r in ref]), 1e-13)
            close(d2[p, order, 0], np.array([complex(r * s) for r in dref]), 1e-12)


def test_genus1_jacobi_identities():
    """theta_3^4 = theta_2^4 + theta_4^4 and theta_1'(0) = theta_2 theta_3 theta_4 (in pi z)."""
    for tau in (0.1 + 0.8j, -0.4 + 0.07j, 3.2 + 2.0j):
        th = RiemannTheta([[tau]])
        t = th(np.zeros(1), char="all")  # [th3, th4, th2, -th1]
        th3, th4, th2 = t[0], t[1], t[2]
        close(th3 ** 4, th2 ** 4 + th4 ** 4, 1e-13, scale=abs(th3) ** 4)
        d = th.gradient(np.zeros(1), char=(np.array([0.5]), np.array([0.5])))[0]
        close(d, -math.pi * th2 * th3 * th4, 1e-13, scale=abs(th2 * th3 * th4) * math.pi)


# ----------------------------------------------------------------------------------------
# identities, g = 2..4
# ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("g", [2, 3, 4])
def test_quasi_periodicity_both_directions(g):
    rng = np.random.default_rng(g)
    tau = random_tau(g, rng)
    th = RiemannTheta(tau)
    z = rng.normal(size=(3, g)) + 1j * rng.normal(size=(3, g))
    A, B = half_chars(g)
    e0, v0 = th.separated(z, char="all")
    for _ in range(3):
        m = rng.integers(-3, 4, g).astype(float)
        # theta[a;b](z + m) = exp(2 pi i a.m) theta[a;b](z)
        e1, v1 = th.separated(z + m, char="all")
        close(e1, e0, 1e-12)
        close(v1, v0 * np.exp(2j * np.pi * (A @ m))[None, :], 1e-13)
        # theta[a;b](z + tau m) = exp(-2 pi i b.m - pi i m.tau.m - 2 pi i m.z) theta[a;b](z)
        e2, v2 = th.separated(z + tau @ m, char="all")
        expo = (-2j * np.pi * (B @ m))[None, :] - 1j * np.pi * (m @ tau @ m) - 2j * np.pi * (z @ m)[:, None]
        # magnitudes: |exp(expo)| exp(e0) = exp(e2) exactly
        ph = np.exp(1j * expo.imag + (expo.real + e0[:, None] - e2[:, None]))
        close(v2, v0 * ph, 1e-12)


@pytest.mark.parametrize("g", [1, 2, 3])
def test_parity_of_characteristics(g):
    rng = np.random.default_rng(10 + g)
    tau = random_tau(g, rng, small=0.3)
    th = RiemannTheta(tau)
    z = rng.normal(size=(4, g)) + 0.5j * rng.normal(size=(4, g))
    A, B = half_chars(g)
    sign = (-1.0) ** np.rint(4 * np.sum(A * B, axis=1))
    close(th(-z, char="all"), th(z, char="all") * sign[None, :], 1e-13)
    odd = sign < 0
    assert np.max(np.abs(th(np.zeros(g), char="all")[odd])) < 1e-14
    # gradients of even characteristics vanish at 0
    grad0 = th.gradient(np.zeros(g), char="all")
    assert np.max(np.abs(grad0[~odd])) < 1e-13


@pytest.mark.parametrize("g", [1, 2, 3])
def test_heat_equation(g):
    """d theta / d tau_jk = (1 + delta_jk)^{-1} (2 pi i)^{-1} d^2 theta / dz_j dz_k, with the
    tau-derivative from a Cauchy integral (trapezoid on a circle, spectrally accurate)."""
    rng = np.random.default_rng(20 + g)
    tau = random_tau(g, rng, small=0.2)
    z = rng.normal(size=(2, g)) + 0.3j * rng.normal(size=(2, g))
    H = RiemannTheta(tau).hessian(z)
    r, N = 0.02, 16
    for j in range(g):
        for k in range(j, g):
            E = np.zeros((g, g))
            E[j, k] = E[k, j] = 1.0
            acc = 0
            for n in range(N):
                w = r * np.exp(2j * np.pi * n / N)
                acc = acc + RiemannTheta(tau + w * E)(z) / w
            dtau = acc / N
            rhs = H[:, j, k] / (2j * np.pi) / (2.0 if j == k else 1.0)
            close(dtau, rhs, 1e-11, scale=np.maximum(np.abs(rhs), 1.0))


@pytest.mark.parametrize("g", [1, 2, 3])
def test_siegel_reduction_and_modular_law(g):
    """tau_red = gamma.tau, gamma symplectic, reduced; and the documented transformation law
    theta[a';b'](z'|tau') = kappa sqrt(det(C tau+D)) exp(pi i z.(C tau+D)^{-1}C z) theta[a;b](z|tau)
    with kappa a z-independent eighth root of unity."""
    rng = np.random.default_rng(30 + g)
    tau = random_tau(g, rng, small=0.03, re=3.0)
    tr, gam = siegel_reduce(tau)
    A, B, C, D = gam[:g, :g], gam[:g, g:], gam[g:, :g], gam[g:, g:]
    J = np.block([[np.zeros((g, g)), np.eye(g)], [-np.eye(g), np.zeros((g, g))]])
    assert np.array_equal(gam.T @ J @ gam, J)
    CtD = C @ tau + D
    close((A @ tau + B) @ np.linalg.inv(CtD), tr, 1e-12)
    assert np.all(np.abs(tr.real) <= 0.5 + 1e-12)
    assert abs(tr[0, 0]) >= 1 - 1e-12
    assert np.linalg.eigvalsh(tr.imag)[0] > np.linalg.eigvalsh(tau.imag)[0]
    th, thr = RiemannTheta(tau), RiemannTheta(tr)
    al, be = half_chars(g)
    for ci in rng.choice(4 ** g, size=min(4, 4 ** g), replace=False):
        a2 = D @ al[ci] - C @ be[ci] + 0.5 * np.diag(C @ D.T)
        b2 = -B @ al[ci] + A @ be[ci] + 0.5 * np.diag(A @ B.T)
        kap = []
        for _ in range(3):
            z = rng.normal(size=g) * 0.4 + 0.4j * rng.normal(size=g)
            zp = np.linalg.solve(CtD.T, z)
            lhs = thr(zp, char=(a2, b2))
            rhs = np.sqrt(np.linalg.det(CtD)) * np.exp(1j * np.pi * z @ np.linalg.solve(CtD, C @ z)) \
                * th(z, char=(al[ci], be[ci]))
            kap.append(lhs / rhs)
        kap = np.array(kap)
        close(np.abs(kap), np.ones(3), 1e-12)
        close(kap, np.full(3, kap[0]), 1e-12)
        close(kap[0] ** 8, 1.0, 1e-11)


def test_reduced_input_is_left_alone():
    tau = np.array([[1.1j, 0.3], [0.3, 1.7j]])
    tr, gam = siegel_reduce(tau)
    assert np.array_equal(gam, np.eye(4, dtype=np.int64))
    assert np.array_equal(tr, tau)


# ----------------------------------------------------------------------------------------
# mpmath path, engines, derivatives
# ----------------------------------------------------------------------------------------
def test_mpmath_path_and_global_precision():
    rng = np.random.default_rng(40)
    tau = random_tau(2, rng, small=0.1)
    z = rng.normal(size=2) + 1j * rng.normal(size=2)
    dps0 = mpmath.mp.dps
    v50 = riemann_theta(z, tau, char=(np.array([0.5, 0]), np.array([0, 0.5])), dps=50)
    v30 = riemann_theta(z, tau, char=(np.array([0.5, 0]), np.array([0, 0.5])), dps=30)
    assert mpmath.mp.dps == dps0
    assert isinstance(v50, mpmath.mpc)
    assert abs(v50 - v30) < 1e-28 * max(abs(v50), 1)
    v = riemann_theta(z, tau, char=(np.array([0.5, 0]), np.array([0, 0.5])))
    assert abs(complex(v50) - v) < 1e-13 * max(abs(v), 1)
    # separated form, derivative, several points
    zz = np.stack([z, 0.5 * z])
    e, d = riemann_theta_separated(zz, tau, derivs=[[1, 0.5j]], dps=30)
    e2, d2 = riemann_theta_separated(zz, tau, derivs=[[1, 0.5j]])
    assert d.shape == (2,) and e.shape == (2,)
    close(np.array([complex(x) for x in d]), d2, 1e-13)
    close(np.array([float(x) for x in e]), e2, 1e-14)


def test_directional_derivatives_orders_0_to_3_against_mpmath():
    g = 3
    rng = np.random.default_rng(41)
    tau = random_tau(g, rng, small=0.08)
    th = RiemannTheta(tau)
    z = rng.normal(size=g) + 1j * rng.normal(size=g)
    dirs = [rng.normal(size=g) + 1j * rng.normal(size=g) for _ in range(3)]
    char = (rng.uniform(0, 1, g), rng.uniform(0, 1, g))
    for k in range(4):
        ref = riemann_theta(z, tau, char=char, derivs=dirs[:k], dps=30)
        val = th(z, char=char, derivs=dirs[:k])
        close(val, complex(ref), 1e-12, scale=max(abs(complex(ref)), 1.0))


def test_zero_direction_gives_zero_derivative():
    th = RiemannTheta(np.array([[1j, 0.2], [0.2, 1.5j]]))
    z = np.array([0.1 + 0.2j, -0.3])
    assert th(z, derivs=[np.zeros(2)]) == 0
    assert th(z, derivs=[np.array([1.0, 0.0]), np.zeros(2)]) == 0
    assert complex(riemann_theta(z, th.tau, derivs=[np.zeros(2)], dps=20)) == 0


def test_gradient_hessian_consistent_with_directional_derivatives():
    g = 3
    rng = np.random.default_rng(42)
    tau = random_tau(g, rng)
    th = RiemannTheta(tau)
    z = rng.normal(size=(5, g)) + 1j * rng.normal(size=(5, g))
    v, G, H = th.jet(z, order=2)
    close(v, th(z), 1e-14)
    close(G, th.gradient(z), 1e-14)
    close(H, np.swapaxes(H, -1, -2), 1e-13)
    for i in range(g):
        close(G[:, i], th(z, derivs=[np.eye(g)[i]]), 1e-13)
        for j in range(g):
            close(H[:, i, j], th(z, derivs=[np.eye(g)[i], np.eye(g)[j]]), 1e-12)


@pytest.mark.parametrize("g", [1, 2, 4])
def test_split_and_direct_engines_agree(g):
    rng = np.random.default_rng(50 + g)
    th = RiemannTheta(random_tau(g, rng, small=0.1))
    lat = th.lattice
    lset = lat.points(lat.radius(1e-15, 1, 1.0))
    u = rng.normal(size=(7, g)) + 2j * rng.normal(size=(7, g))
    bits = (np.arange(1 << g)[:, None] >> np.arange(g - 1, -1, -1)[None, :]) & 1
    jet = jet_layout(g, 1)
    V = np.eye(g, dtype=complex)
    a = group_jets(lat, lset, u, np.full(g, 0.5), np.zeros(g), bits, jet, V, engine="direct")
    b = group_jets(lat, lset, u, np.full(g, 0.5), np.zeros(g), bits, jet, V, engine="split")
    close(b, a, 1e-13)


@pytest.mark.parametrize("g", [2, 4])
def test_zero_characteristic_constant_matches_the_general_form(g):
    """The zero characteristic's prefactor constant (computed alone) against the same constant from
    the quadratic form of all 4^g characteristics, on a tau that needs several reduction steps (large
    phases in the constant): values agree to rounding and truncation (the 4^g characteristics are summed
    over a larger radius; measured 1.5e-16 for g = 2, 1.2e-15 for g = 4)."""
    rng = np.random.default_rng(70 + g)
    tau = random_tau(g, rng, small=0.03, re=3.0)
    z = rng.normal(size=(5, g)) + 0.4j * rng.normal(size=(5, g))
    zero_only = RiemannTheta(tau).separated(z)[1]
    from_all = RiemannTheta(tau).separated(z, char="all")[1][:, 0]
    close(zero_only, from_all, 4e-15)


@pytest.mark.parametrize("r, o", [(0, 0), (1, 1), (1, 2), (4, 1), (3, 2), (8, 2)])
def test_tail_polynomials_direct_entries_are_the_general_loop(r, o):
    """The split engine's tail polynomials up to order 2, written entry by entry, equal the general loop
    over subsets bit for bit (signed zeros included)."""
    rng = np.random.default_rng(10 * r + o)
    jet = jet_layout(r, o)
    V = rng.normal(size=(r, 4)) + 1j * rng.normal(size=(r, 4))
    V[:, 0][::2] = 0.0  # zero entries: signed zeros of the products
    tails = rng.integers(-5, 6, size=(300, 3)).astype(float)
    oo = o if r else 0
    a = _tail_polynomials(jet, V, tails, oo)
    vk = tails @ V[:, 1:].T if r else np.zeros((300, 0))
    b = _tail_polynomials_loop(jet, V, vk, np.zeros((oo + 1, 300, jet.size), complex))
    for x, y in ((a.real, b.real), (a.imag, b.imag)):
        assert np.array_equal(x, y) and np.array_equal(np.signbit(x), np.signbit(y))


@pytest.mark.parametrize("c", [1, 2, 3, 5])
def test_unique_rows_is_numpy_unique(c):
    """theta.lattice.unique_rows (the split engine's tails, the flow's modes) against np.unique, also in a
    box larger than the rows' own and with no columns."""
    rng = np.random.default_rng(c)
    t0 = np.zeros((4, 0), dtype=np.int64)
    assert np.array_equal(lattice.unique_rows(t0)[0], np.unique(t0, axis=0))
    t = rng.integers(-6, 5, size=(300, c))
    rows, inv = lattice.unique_rows(t, np.full(c, -9), np.full(c, 20))
    ref, ref_inv = np.unique(t, axis=0, return_inverse=True)
    assert np.array_equal(rows, ref) and np.array_equal(inv, np.asarray(ref_inv).reshape(-1))
    for n in (1, 7, 500):
        t = rng.integers(-6, 5, size=(n, c))
        rows, inv = lattice.unique_rows(t)
        ref, ref_inv = np.unique(t, axis=0, return_inverse=True)
        assert np.array_equal(rows, ref) and np.array_equal(inv, np.asarray(ref_inv).reshape(-1))


# ----------------------------------------------------------------------------------------
# API: shapes, broadcasting, overflow, bad input
# ----------------------------------------------------------------------------------------
def test_shapes_and_broadcasting():
    g = 3
    rng = np.random.default_rng(60)
    th = RiemannTheta(random_tau(g, rng))
    z0, V = rng.normal(size=g), rng.normal(size=g) + 0.1j * rng.normal(size=g)
    c = rng.normal(size=(4, g)) + 1j * rng.normal(size=(4, g))
    t = np.linspace(0, 3, 11)
    z = (z0 + t[:, None] * V)[:, None, :] + c[None, :, :]
    assert th(z).shape == (11, 4)
    assert th.gradient(z).shape == (11, 4, g)
    assert th.hessian(z).shape == (11, 4, g, g)
    assert th(z, char="all").shape == (11, 4, 64)
    assert th.gradient(z, char="all").shape == (11, 4, 64, g)
    e, v = th.separated(z)
    assert e.shape == v.shape == (11, 4) and e.dtype == float
    val = th(z[0, 0])
    assert np.ndim(val) == 0 and isinstance(complex(val), complex)
    close(th(z)[3, 2], val if False else th(z[3, 2]), 1e-15)
    close(riemann_theta(z, th.tau), th(z), 1e-15)


def test_overflow_is_reported_and_separated_form_works():
    tau = np.array([[0.1 + 0.05j, 0.02], [0.02, 0.3 + 20j]])
    z = np.array([0.3 + 0.3j, 0.1 + 200j])
    with pytest.raises(OverflowError, match="separated"):
        riemann_theta(z, tau)
    e, v = riemann_theta_separated(z, tau)
    assert e > 709 and np.isfinite(v) and 0 < abs(v) < 10
    with mpmath.workdps(30):
        e_mp, v_mp = riemann_theta_separated(z, tau, dps=25)
    assert abs(float(e_mp) - e) < 1e-12 * e
    assert abs(complex(v_mp) - v) < 1e-12


@pytest.mark.parametrize(
    "tau, msg",
    [
        (np.array([[1j, 0.3], [0.3 + 1e-9, 1j]]), "symmetric"),
        (np.array([[1j, 0.3], [0.3, -1j]]), "positive definite"),
        (np.array([[1j, 2j], [2j, 1j]]), "positive definite"),
        (np.array([[1j, np.nan], [np.nan, 1j]]), "NaN"),
        (np.ones((2, 3)) * 1j, "square"),
        (np.array([1j, 2j]), "square"),
    ],
)
def test_bad_tau(tau, msg):
    with pytest.raises(ValueError, match=msg):
        RiemannTheta(tau)
    with pytest.raises(ValueError, match=msg):
        siegel_reduce(tau)


def test_symmetric_up_to_rounding_is_accepted():
    tau = np.array([[1j, 0.3], [0.3 * (1 + 1e-15), 1j]])
    th = RiemannTheta(tau)
    assert np.array_equal(th.tau, th.tau.T)


def test_bad_arguments():
    th = RiemannTheta(np.array([[1j, 0.3], [0.3, 1.2j]]))
    with pytest.raises(ValueError, match="shape"):
        th(np.zeros(3))
    with pytest.raises(ValueError, match="shape"):
        th(0.3)
    with pytest.raises(ValueError, match="NaN"):
        th(np.array([np.nan, 0]))
    with pytest.raises(ValueError, match="char"):
        th(np.zeros(2), char="odd")
    with pytest.raises(ValueError, match="alpha"):
        th(np.zeros(2), char=(np.zeros(3), np.zeros(2)))
    with pytest.raises(ValueError, match="derivs"):
        th(np.zeros(2), derivs=[np.zeros(3)])
    with pytest.raises(ValueError, match="tol"):
        RiemannTheta(np.eye(2) * 1j, tol=0)
    with pytest.raises(ValueError, match="order"):
        th.jet(np.zeros(2), order=3)
    with pytest.raises(ValueError, match="dps"):
        riemann_theta(np.zeros(2), th.tau, dps=0)


@pytest.mark.parametrize("g, r", [(2, 1), (3, 2), (4, 3)])
def test_flow_theta_against_riemann_theta(g, r):
    """thetasol.theta.flow.FlowTheta (the Fourier series along a real flow that the rotation solver
    evaluates per time) against RiemannTheta at s + t u, values and t-derivatives, at times up to 1e5
    (where only the phases t u mod 1 enter)."""
    from thetasol.theta.flow import FlowTheta

    rng = np.random.default_rng(40 + g)
    tau = random_tau(g, rng, small=0.4)
    u = rng.normal(size=r)
    shifts = rng.normal(size=(3, g)) + 0.3j * rng.normal(size=(3, g))
    flow = FlowTheta(tau, u, shifts)
    t = np.array([0.0, 0.37, 2.9, 41.3, 1e5 + 0.25])
    e, v, dv = flow(t)
    U = np.concatenate([u, np.zeros(g - r)])
    th = RiemannTheta(tau)
    # theta at s + t u: only the phases t u mod 1 matter (integer shifts of a real argument); the
    # reference takes them exactly (mpmath), as the compiled flow does
    with mpmath.workdps(40):
        ph = np.array([[float(mpmath.frac(mpmath.mpf(x) * mpmath.mpf(float(c)))) for c in U] for x in t])
    for j, s in enumerate(shifts):
        z = s[None, :] + ph
        ref = th(z)
        dref = th(z, derivs=[U])
        # measured 2.1e-15 and 2.6e-15; one coefficient of the series off by 1e-11 shows as 1.1e-11
        close(np.exp(e[j]) * v[:, j], ref, 1e-13, scale=np.abs(ref).max())
        close(np.exp(e[j]) * dv[:, j], dref, 1e-13, scale=np.abs(dref).max())


@pytest.mark.parametrize("g", [2, 3, 4])
def test_flow_theta_inside_level_implies_the_exact_test(g):
    """FlowTheta skips its exact ellipsoid test for candidates whose row-by-row sum is below
    ``_surely_inside``: on ill-conditioned Y (eigenvalues 0.02 .. 2) every such candidate passes the exact
    test, and the two sums differ by less than the stated bound (measured 1e-15 .. 7e-15 against 1e-13 .. 6e-13)."""
    import math

    from thetasol.theta.flow import _surely_inside, ellipsoid_candidates_many, lower_factor, row_sums

    rng = np.random.default_rng(90 + g)
    Y = random_tau(g, rng, small=0.02).imag
    bound = 12.0
    cs = rng.normal(size=(6, g))
    half = np.sqrt(bound * np.diag(np.linalg.inv(Y)))
    boxes = [[(math.floor(-c[i] - half[i]), math.ceil(-c[i] + half[i])) for i in range(g)] for c in cs]
    pts, own, used = ellipsoid_candidates_many(cs, lower_factor(Y), bound, boxes)
    d = pts + cs[own]
    form = row_sums((d @ Y) * d)
    inner = _surely_inside(Y, bound)
    assert inner > 0.99 * bound
    assert np.all(form[used <= inner] <= bound)
    lam = np.linalg.eigvalsh(Y)[0]
    disc = 8 * g * np.finfo(float).eps * (math.sqrt(np.trace(Y) / lam) + np.linalg.norm(Y) / lam)
    assert np.max(np.abs(form - used) / used) < disc


def test_mp_inverse_of_positive_definite_matrices():
    """The evaluator's mpmath inverse of Im tau (Gauss-Jordan without pivoting) against mpmath's matrix
    inverse at 40 digits, condition numbers up to 1e3: measured <= 1.6e-39 relative."""
    from thetasol.theta.riemann import _mp_inverse_spd

    ctx = mpmath.mp.clone()
    ctx.dps = 40
    rng = np.random.default_rng(5)
    for g in range(1, 6):
        A = rng.normal(size=(g, g))
        Y = A @ A.T + 0.01 * np.eye(g)
        a = _mp_inverse_spd(ctx, Y)
        b = ctx.matrix([[ctx.mpf(float(Y[i, j])) for j in range(g)] for i in range(g)]) ** -1
        err = max(abs(a[i][j] - b[i, j]) / abs(b[i, j]) for i in range(g) for j in range(g))
        assert err < 1e-37, (g, err)
