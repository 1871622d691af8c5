"""The free gyrostat (8.39)-(8.40) in closed form against numerical integration of
mdot = (m + N) x omega, Qdot = Q hat(omega) (scipy DOP853; heyoka in extended precision if
installed), and against the physics (conserved |h|, energy, space momentum Q h)."""
import warnings

import numpy as np
import pytest
from conftest import inertia, label, rand_Q
from scipy.integrate import solve_ivp

from thetasol import RotationSolution, solve_gyrostat, solve_rotation
from thetasol.core.so3 import hat


def dop853(J, N, Q0, w0, t):
    I = inertia(J)
    Ii = np.linalg.inv(I)

    def rhs(_t, y):
        m, Q = y[:3], y[3:].reshape(3, 3)
        w = Ii @ m
        return np.concatenate([np.cross(m + N, w), (Q @ hat(w)).ravel()])

    sol = solve_ivp(rhs, (0, t[-1]), np.concatenate([I @ w0, Q0.ravel()]), t_eval=t,
                    rtol=1e-13, atol=1e-15, method="DOP853")
    return sol.y[:3].T @ Ii.T, sol.y[3:].T.reshape(-1, 3, 3)


_TAYLOR = {}


def _taylor(fp, tol):
    """heyoka Taylor integrator of mdot = (m + N) x I^-1 m, Qdot = Q hat(I^-1 m), with I^-1 and N
    as runtime parameters (compiled once per precision, compact mode)."""
    hy = pytest.importorskip("heyoka")
    key = (str(fp), tol)
    if key not in _TAYLOR:
        xs = hy.make_vars(*[f"m{i}" for i in range(3)], *[f"q{i}{j}" for i in range(3) for j in range(3)])
        m = xs[:3]
        Q = [xs[3 + 3 * i: 6 + 3 * i] for i in range(3)]
        w = [sum(hy.par[3 * i + k] * m[k] for k in range(3)) for i in range(3)]
        h = [m[i] + hy.par[9 + i] for i in range(3)]
        md = [h[1] * w[2] - h[2] * w[1], h[2] * w[0] - h[0] * w[2], h[0] * w[1] - h[1] * w[0]]
        W = [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]]
        Qd = [sum(Q[i][k] * W[k][j] for k in range(3)) for i in range(3) for j in range(3)]
        _TAYLOR[key] = hy.taylor_adaptive(list(zip(xs, md + Qd)), np.zeros(12, dtype=fp), tol=fp(tol),
                                          fp_type=fp, pars=np.zeros(12, dtype=fp), compact_mode=True)
    return _TAYLOR[key]


def heyoka_ref(I, N, Q0, w0, t, quad=False):
    """Reference trajectory (omega, Q) at the times t (either sign) by heyoka in extended precision
    (80-bit, tol 1e-19), or with ``quad`` in quadruple precision (tol 1e-32: for orbits next to a
    separatrix, whose conditioning amplifies the reference's own errors).  ``I`` is the inertia the
    closed form was given, taken exactly; ``m = I omega0`` is formed in the working precision, as the
    closed form does (near a separatrix a float64 rounding of the data moves the phase by far more
    than round-off)."""
    hy = pytest.importorskip("heyoka")
    fp = hy.real128 if quad else np.longdouble
    ta = _taylor(fp, 1e-32 if quad else 1e-19)
    I = np.asarray(I, dtype=float)
    I = np.diag(I) if I.ndim == 1 else I

    def cv(x):
        return np.array([fp(float(v)) for v in np.ravel(x)])

    Iw = [list(cv(I[i])) for i in range(3)]
    m0 = np.array([sum(Iw[i][k] * fp(float(w0[k])) for k in range(3)) for i in range(3)])
    # I^-1 by Gauss-Jordan in the working precision (numpy.linalg is float64 only)
    A = [list(Iw[i]) + [fp(1) if i == j else fp(0) for j in range(3)] for i in range(3)]
    for c in range(3):
        p = max(range(c, 3), key=lambda r: abs(float(A[r][c])))
        A[c], A[p] = A[p], A[c]
        A[c] = [x / A[c][c] for x in A[c]]
        for r in range(3):
            if r != c:
                A[r] = [x - A[r][c] * y for x, y in zip(A[r], A[c])]
    Ii = np.array([A[i][3:] for i in range(3)])
    t = np.asarray(t, dtype=float)
    out = np.empty((t.size, 12))
    for sel in (t >= 0, t < 0):
        if not sel.any():
            continue
        idx = np.nonzero(sel)[0]
        order = np.argsort(np.abs(t[idx]))
        ta.pars[:] = np.concatenate([np.asarray(Ii).ravel(), cv(N)])
        ta.state[:] = np.concatenate([m0, cv(Q0)])
        ta.time = fp(0)
        grid = [fp(float(x)) for x in t[idx][order]]
        lead = [] if grid[0] == 0 else [fp(0)]
        res = np.asarray(ta.propagate_grid(np.array(lead + grid))[-1])[len(lead):].astype(float)
        out[idx[order]] = res
    Iif = np.linalg.inv(I)
    return out[:, :3] @ Iif.T, out[:, 3:].reshape(-1, 3, 3)


def generic_cases(n=8, seed=0):
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        J = rng.uniform(0.3, 2.0, 3)
        if k % 4 == 3:
            A = rng.normal(size=(3, 3))
            J = A @ A.T + 0.3 * np.eye(3)
        N = rng.normal(size=3) * 10 ** rng.uniform(-2, 1)
        out.append((J, N, rand_Q(rng), rng.normal(size=3)))
    return out


@pytest.mark.parametrize("case", range(8))
def test_generic_against_dop853(case):
    J, N, Q0, w0 = generic_cases()[case]
    sol = solve_gyrostat(inertia(J), N, Q0, w0)
    assert label(sol) == "elliptic"
    t = np.linspace(0.0, 15.0, 31)
    w, Q = sol(t)
    wr, Qr = dop853(J, N, Q0, w0, t)
    s = max(1.0, np.abs(wr).max())
    assert np.max(np.abs(w - wr)) < 3e-11 * s
    assert np.max(np.abs(Q - Qr)) < 3e-11 * s


def test_both_elliptic_forms_are_exercised():
    kinds = {solve_gyrostat(inertia(J), N, Q0, w0)._impl.orbit.c.kind for J, N, Q0, w0 in generic_cases(24, seed=1)}
    assert kinds == {1, 3}  # one and three real roots of the Weierstrass cubic


def test_against_heyoka_extended_precision():
    for J, N, Q0, w0 in generic_cases(3, seed=2):
        sol = solve_gyrostat(inertia(J), N, Q0, w0)
        t = np.linspace(0.0, 60.0, 61)
        w, Q = sol(t)
        wr, Qr = heyoka_ref(inertia(J), N, Q0, w0, t)
        s = max(1.0, np.abs(wr).max())
        assert max(np.abs(w - wr).max(), np.abs(Q - Qr).max()) < 2e-12 * s


SPECIAL = {
    "zero-rotor": (np.array([0.8, 1.3, 2.1]), np.zeros(3), np.array([0.3, -0.5, 0.9]), "elliptic"),
    "elementary:rest": (np.array([0.8, 1.3, 2.1]), np.array([0.3, 0.1, -0.2]), np.zeros(3), "elementary:rest"),
    "steady": (np.array([0.8, 1.3, 2.1]), np.array([0.0, 0.0, 0.5]), np.array([0.0, 0.0, 0.7]), "elementary:steady"),
    "sphere": (np.array([1.0, 1.0, 1.0]), np.array([0.3, 0.1, -0.2]), np.array([0.5, -0.4, 0.2]), "elementary:spherical"),
    "dual-spin-z": (np.array([1.0, 1.0, 0.5]), np.array([0.0, 0.0, 0.7]), np.array([0.4, 0.3, -0.6]), "elementary:axisymmetric"),
    "dual-spin-x": (np.array([0.4, 1.0, 1.0]), np.array([-0.9, 0.0, 0.0]), np.array([0.4, 0.3, -0.6]), "elementary:axisymmetric"),
    "dual-spin-y": (np.array([1.0, 0.6, 1.0]), np.array([0.0, 0.5, 0.0]), np.array([0.4, 0.3, -0.6]), "elementary:axisymmetric"),
}


@pytest.mark.parametrize("name", list(SPECIAL))
def test_special_closed_forms(name):
    J, N, w0, method = SPECIAL[name]
    Q0 = rand_Q(np.random.default_rng(3))
    sol = solve_gyrostat(inertia(J), N, Q0, w0)
    assert label(sol) == method
    t = np.linspace(0.0, 20.0, 41)
    w, Q = sol(t)
    wr, Qr = dop853(J, N, Q0, w0, t)
    assert np.max(np.abs(w - wr)) < 2e-11 and np.max(np.abs(Q - Qr)) < 2e-11


@pytest.mark.parametrize("case", range(8))
def test_physics_over_long_times(case):
    J, N, Q0, w0 = generic_cases()[case]
    sol = solve_gyrostat(inertia(J), N, Q0, w0)
    I = inertia(J)
    t = np.concatenate([np.linspace(-50, 50, 21), [1e4, 1e6 + 0.5]])
    w, Q = sol(t)
    h = w @ I.T + N
    h0 = I @ w0 + N
    G = np.linalg.norm(h0)
    assert np.max(np.abs(np.swapaxes(Q, -1, -2) @ Q - np.eye(3))) < 1e-14
    assert np.max(np.abs(np.linalg.norm(h, axis=-1) - G)) < 1e-14 * G
    E = 0.5 * np.einsum("ni,ij,nj->n", w, I, w)
    assert np.max(np.abs(E - 0.5 * w0 @ I @ w0)) < 1e-14 * max(1.0, G ** 2)
    L = np.einsum("nij,nj->ni", Q, h)
    assert np.max(np.abs(L - Q0 @ h0)) < 5e-14 * G
    # consistency with sol.h and the protocol
    assert np.allclose(sol.h(t), h, rtol=0, atol=1e-15 * G)
    assert isinstance(sol, RotationSolution)


def test_kinematics_by_finite_differences():
    J, N, Q0, w0 = generic_cases()[1]
    sol = solve_gyrostat(inertia(J), N, Q0, w0)
    h = 1e-3
    tc = np.array([0.0, 1.7, 33.0])
    Qs = [sol.Q(tc + k * h) for k in (-2, -1, 1, 2)]
    dQ = (Qs[0] - 8 * Qs[1] + 8 * Qs[2] - Qs[3]) / (12 * h)
    assert np.max(np.abs(dQ - sol.Q(tc) @ hat(sol.omega(tc)))) < 1e-9


def test_period_and_precession():
    J, N, Q0, w0 = generic_cases()[0]
    sol = solve_gyrostat(inertia(J), N, Q0, w0)
    T = sol.diagnostics["period"]
    t = np.array([0.2, 3.0])
    assert np.max(np.abs(sol.omega(t + T) - sol.omega(t))) < 1e-12
    L = Q0 @ (inertia(J) @ w0 + N)
    Lh = L / np.linalg.norm(L)
    ang = sol.diagnostics["precession_rate"] * T
    K = hat(Lh)
    Rl = np.eye(3) + np.sin(ang) * K + (1 - np.cos(ang)) * K @ K
    assert np.max(np.abs(sol.Q(t + T) - Rl @ sol.Q(t))) < 1e-11


def test_invariants_of_8_40():
    J, N, Q0, w0 = generic_cases()[2]
    sol = solve_gyrostat(inertia(J), N, Q0, w0)
    t = np.array([0.0, 5.0])
    M = sol.M(t)
    W = hat(sol.omega(t))
    Nh = hat(N)
    H = 0.5 * np.trace(M @ W, axis1=-2, axis2=-1)
    H2 = np.trace((M + Nh) @ (M + Nh), axis1=-2, axis2=-1)
    assert np.allclose(H, sol.invariants["H"], rtol=1e-13, atol=0)
    assert np.allclose(H2, sol.invariants["H2"], rtol=1e-13, atol=0)
    assert sol.invariants["H"] == pytest.approx(-2 * sol.invariants["energy"], rel=1e-15)


@pytest.mark.parametrize("eps", [1e-4, 1e-8, 1e-12])
def test_nearly_axisymmetric_dual_spin_keeps_accuracy(eps):
    """A nearly axisymmetric carrier with the rotor nearly on its axis: the orbit is nearly a
    plane circle, where the residual quadratic is evaluated next to its roots (its exact
    coefficients keep that accurate)."""
    J = np.array([1.0, 1.0 + eps, 0.5])
    N = np.array([eps, 0.0, 0.7])
    w0 = np.array([0.4, 0.3, -0.6])
    Q0 = rand_Q(np.random.default_rng(4))
    sol = solve_gyrostat(inertia(J), N, Q0, w0)
    assert label(sol) == "elliptic"
    t = np.linspace(0.0, 10.0, 11)
    w, Q = sol(t)
    wr, Qr = dop853(J, N, Q0, w0, t)
    assert max(np.abs(w - wr).max(), np.abs(Q - Qr).max()) < 1e-12


@pytest.mark.parametrize("scale", [1e-3, 1e-9, 1e-19])
def test_fast_rotor_keeps_relative_accuracy_of_omega(scale):
    """|m| << |N| (a momentum wheel, carrier nearly at rest): m(t) is a small loop about the
    relative equilibrium m = 0 and keeps its relative accuracy (reference: DOP853 on m alone
    with an absolute tolerance below |m|)."""
    J = np.array([0.8, 1.3, 2.1])
    N = np.array([0.3, -1.0, 1.0])
    w0 = np.array([1.0, 2.0, -1.0]) * scale
    I = inertia(J)
    sol = solve_gyrostat(inertia(J), N, np.eye(3), w0)
    t = np.linspace(0.0, 20.0, 21)
    ref = solve_ivp(lambda _t, y: np.cross(y + N, np.linalg.solve(I, y)), (0, 20), I @ w0, t_eval=t,
                    rtol=1e-13, atol=1e-40 * scale, method="DOP853").y.T
    m = sol.m(t)
    assert np.max(np.abs(m - ref).max(-1) / np.abs(ref).max(-1)) < 5e-13


def test_generic_cases_do_not_warn():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for J, N, Q0, w0 in generic_cases(12, seed=5):
            assert solve_gyrostat(inertia(J), N, Q0, w0).diagnostics["error_estimate"] < 1e-11


def test_zero_rotor_is_the_euler_top():
    J, N, w0, _ = SPECIAL["zero-rotor"]
    Q0 = rand_Q(np.random.default_rng(6))
    t = np.array([0.5, 100.0])
    a = solve_gyrostat(inertia(J), N, Q0, w0)(t)
    b = solve_rotation(inertia(J), np.zeros((3, 3)), Q0, w0)(t)
    assert np.allclose(a[0], b[0], rtol=0, atol=1e-15) and np.allclose(a[1], b[1], rtol=0, atol=1e-15)


@pytest.mark.parametrize("kw, msg", [
    (dict(N=[1.0, np.nan, 0.0]), "NaN"),
    (dict(N=[1.0, 2.0]), "shape"),
    (dict(I=[1.0, 2.0, -5.0]), "physical|positive"),
    (dict(Q0=np.diag([1.0, 1.0, -1.0])), "reflection"),
    (dict(omega0=[0.0, 0.0]), "shape"),
])
def test_bad_input(kw, msg):
    args = dict(I=inertia([0.8, 1.3, 2.1]), N=[0.1, 0.2, 0.3], Q0=np.eye(3), omega0=[0.3, 0.2, 0.1])
    args.update(kw)
    with pytest.raises(ValueError, match=msg):
        solve_gyrostat(**args)


# -- hard cases: the inversion's removable singularities, slow anchors, saddles -------------------

EPS = np.finfo(float).eps

# found by hypothesis (test_conservation_and_orthogonality).  Not a saddle: W&W's inversion formula
# based at a general point of the quartic has a numerator and a denominator with two common zeros
# per period, here on the real orbit; evaluated as written in float64 it is 0/0 there (1e-3 of the
# energy at t = 11.9335, 6.9e-11 at random times).  Measured on a grid over two periods: energy
# 3.5 eps, |h| 6 eps (test_property_failure_invariants_on_a_dense_grid)
PROPERTY_FAILURE = (np.array([4.5, 2.0, 3.5]), np.array([0.0, -1.75, 1.421875]), np.array([0.0, 3.0, 0.0]))

# generic data of generic_cases' distribution whose real orbit meets those common zeros (6 of 200
# draws; the formula evaluated as written loses 1.4e-9 to 5.6e-7 of the energy's scale).  Measured
# over +-1 period: energy <= 3.3 eps, |h| <= 8 eps
COMMON_ZERO_CASES = [
    ([1.3958581836582835, 1.845364322495386, 0.8034716083784583], [-0.2852280931686581, -0.2251507779770402, -0.44088770777595554], [1.3355454216308837, -0.5564888399932533, 0.7875408171027013]),
    ([0.4631907077037518, 0.54072397429931, 1.6616530718248295], [-0.018665030114593893, 0.013305645306260485, -0.028837324501231193], [0.3806924762430092, 1.164447913936147, -0.33621322049705094]),
    ([1.237449540606763, 1.3513329345914555, 1.6791056707920031], [0.12979833694670387, -0.0678208111038323, 0.09387535352726717], [-2.2665206299327094, -0.35789247427932736, 0.32613645199293473]),
]

# next to a saddle (found by sampling the singular level sets): a data point close to the
# saddle (the pencil's anchor moves to a fast point), a turning point of the pencil
# next to the saddle (a residual coefficient that cancels there), an orbit at 3e-11 from the
# separatrix
NEAR_SADDLE_CASES = [
    ([1.5422519500024736, 1.737423829414948, 1.0215431193207938], [-5.829591040703852, -3.4742576190041543, -4.5236231145773225], [52.78821807222933, -40.973780990940874, 7.149238634824681]),
    ([0.8802899850162753, 2.693647151186379, 0.41676817476893424], [-0.8480358053942576, 0.6699161416834842, -1.363954913923379], [-0.18837914651566254, -2.0416296115943746, -0.08081750545349492]),
    ([2.7629070883129443, 0.5567284253369378, 0.40597613492576967], [-0.8540264523001458, 3.018010470232149, -0.07613353000487062], [-4.794726015726387, -42.91838564850039, 7.713949081994629]),
]


def _energy_and_sphere_errors(J, N, w0, sol, t):
    I = inertia(J)
    w = sol.omega(t)
    h = w @ I.T + N
    G = np.linalg.norm(I @ w0 + N)
    T0 = 0.5 * w0 @ I @ w0
    dE = np.max(np.abs(0.5 * np.einsum("ni,ij,nj->n", w, I, w) - T0)) / (T0 + G * G / np.min(np.linalg.eigvalsh(I)))
    dG = np.max(np.abs(np.linalg.norm(h, axis=-1) / G - 1))
    return dE, dG


def test_property_failure_invariants_on_a_dense_grid():
    """Every point of two periods (5e-5 apart, the common zeros next to t = 9.9418, 11.9335 included)
    on the invariant sphere and ellipsoid to round-off (measured: energy 3.5 eps, |h| 6 eps)."""
    J, N, w0 = PROPERTY_FAILURE
    sol = solve_gyrostat(inertia(J), N, np.eye(3), w0)
    t = np.concatenate([np.arange(0.0, 40.0, 5e-5), [9.9418, 11.9335]])
    dE, dG = _energy_and_sphere_errors(J, N, w0, sol, t)
    assert dE < 16 * EPS and dG < 16 * EPS


@pytest.mark.parametrize("case", range(len(COMMON_ZERO_CASES)))
def test_common_zero_cases_invariants_on_a_dense_grid(case):
    J, N, w0 = (np.array(x) for x in COMMON_ZERO_CASES[case])
    sol = solve_gyrostat(inertia(J), N, np.eye(3), w0)
    T = sol.diagnostics["period"]
    dE, dG = _energy_and_sphere_errors(J, N, w0, sol, np.linspace(-T, T, 200001))
    assert dE < 16 * EPS and dG < 16 * EPS


def _nearby(case, k):
    """The property failure and data next to it (rotor and velocity moved by ~1e-3)."""
    J, N, w0 = case
    if k == 0:
        return J, N, w0
    rng = np.random.default_rng(100 + k)
    return J, N + 1e-3 * rng.normal(size=3), w0 * (1 + 1e-3 * rng.normal(size=3))


@pytest.mark.parametrize("k", range(3))
def test_property_failure_and_nearby_against_dop853(k):
    J, N, w0 = _nearby(PROPERTY_FAILURE, k)
    Q0 = rand_Q(np.random.default_rng(7))
    sol = solve_gyrostat(inertia(J), N, Q0, w0)
    t = np.linspace(0.0, 20.0, 201)
    w, Q = sol(t)
    wr, Qr = dop853(J, N, Q0, w0, t)  # DOP853's own error reaches ~5e-13 by t = 20
    s = max(1.0, np.abs(wr).max())
    assert np.max(np.abs(w - wr)) < 1e-12 * s and np.max(np.abs(Q - Qr)) < 1e-12


# (data, seed of Q0, start of the time span ending at t = 100)
_HEYOKA_T100 = ([pytest.param(_nearby(PROPERTY_FAILURE, k), 8, 0.0, id=f"property-failure-{k}")
                 for k in range(3)]
                + [pytest.param(tuple(np.array(x) for x in c), 9, -100.0, id=f"common-zero-{i}")
                   for i, c in enumerate(COMMON_ZERO_CASES)])


@pytest.mark.parametrize("data, seed, t0", _HEYOKA_T100)
def test_hard_cases_against_heyoka_to_t100(data, seed, t0):
    """The property failure, data next to it and the common-zero cases against heyoka (80-bit)."""
    J, N, w0 = data
    Q0 = rand_Q(np.random.default_rng(seed))
    sol = solve_gyrostat(inertia(J), N, Q0, w0)
    t = np.linspace(t0, 100.0, 401)
    w, Q = sol(t)
    wr, Qr = heyoka_ref(inertia(J), N, Q0, w0, t)
    s = max(1.0, np.abs(wr).max())
    assert np.max(np.abs(w - wr)) < 1e-12 * s and np.max(np.abs(Q - Qr)) < 1e-12


@pytest.mark.parametrize("case", range(len(NEAR_SADDLE_CASES)))
def test_near_saddle_cases_against_quad_heyoka(case):
    """Orbits at 7.5e-8 to 3e-11 from a separatrix: against heyoka in quadruple precision (whose
    errors the near-separatrix conditioning amplifies less than float64 rounding), over a
    stretch that passes the saddle; the error stays within the solution's own estimate."""
    J, N, w0 = (np.array(x) for x in NEAR_SADDLE_CASES[case])
    Q0 = rand_Q(np.random.default_rng(10))
    sol = solve_gyrostat(inertia(J), N, Q0, w0)
    assert label(sol) == "elliptic"
    T = sol.diagnostics["period"]
    t = np.linspace(-T, T, 121)
    w, Q = sol(t)
    wr, Qr = heyoka_ref(inertia(J), N, Q0, w0, t, quad=True)
    m, mr = w @ inertia(J).T, wr @ inertia(J).T
    err = np.max(np.abs(m - mr)) / np.max(np.abs(mr))
    est = sol.diagnostics["error_estimate"]
    assert err < 1e-13 and err <= 2 * est * 2.0  # two periods
    assert np.max(np.abs(Q - Qr)) < 1e-12


# an orbit exactly on a separatrix (float data: the saddle h = (0, 0, 5) on the rotor axis,
# the homoclinic loop through h = (0, 4, 3)), and data on a singular level set whose orbit is
# periodic (the elliptic parameter is exactly 0 there)
SEPARATRIX = (np.array([0.75, 0.25, 1.25]), np.array([0.0, 0.0, 2.0]), np.array([0.0, 2.0, 1.0]))
SINGULAR_PERIODIC = (np.array([0.25, 0.75, 1.75]), np.array([0.0, 0.0, 2.0]), np.array([0.0, 2.0, 1.0]))


def test_separatrix_closed_form_against_quad_heyoka():
    J, N, w0 = SEPARATRIX
    assert np.array_equal(inertia(J).diagonal(), [1.5, 2.0, 1.0])
    Q0 = rand_Q(np.random.default_rng(11))
    sol = solve_gyrostat(inertia(J), N, Q0, w0)
    assert label(sol) == "elliptic:separatrix"
    assert sol.diagnostics["period"] == np.inf
    t = np.linspace(-60.0, 60.0, 121)  # omega within 1e-10 of the saddle at both ends
    w, Q = sol(t)
    wr, Qr = heyoka_ref(inertia(J), N, Q0, w0, t, quad=True)
    assert np.max(np.abs(w - wr)) < 2e-15 * 3 and np.max(np.abs(Q - Qr)) < 1e-13
    assert np.max(np.abs(np.swapaxes(Q, -1, -2) @ Q - np.eye(3))) < 1e-14


def test_separatrix_limits_are_the_saddle():
    """t -> +-inf: omega -> omega_s = (0, 0, 3) (h_s = (0, 0, 5) = I omega_s + N), and the body
    turns uniformly about the space momentum at the saddle's rate |omega_s| = precession_rate."""
    J, N, w0 = SEPARATRIX
    Q0 = rand_Q(np.random.default_rng(12))
    sol = solve_gyrostat(inertia(J), N, Q0, w0)
    ws = np.array([0.0, 0.0, 3.0])
    for t in (1e3, -1e3, 1e6, -1e9):
        assert np.max(np.abs(sol.omega(np.array([t]))[0] - ws)) < 1e-15
    assert sol.diagnostics["precession_rate"] == pytest.approx(3.0, rel=1e-14)
    L = Q0 @ (inertia(J) @ w0 + N)
    K = hat(L / np.linalg.norm(L))
    t1, dt = np.array([400.0, -700.0]), 12.345
    ang = 3.0 * dt
    Rl = np.eye(3) + np.sin(ang) * K + (1 - np.cos(ang)) * K @ K
    assert np.max(np.abs(sol.Q(t1 + dt) - Rl @ sol.Q(t1))) < 1e-12


def test_separatrix_kinematics_and_invariants():
    J, N, w0 = SEPARATRIX
    Q0 = rand_Q(np.random.default_rng(13))
    sol = solve_gyrostat(inertia(J), N, Q0, w0)
    h = 1e-3
    tc = np.array([-7.0, 0.0, 2.5, 30.0])
    Qs = [sol.Q(tc + k * h) for k in (-2, -1, 1, 2)]
    dQ = (Qs[0] - 8 * Qs[1] + 8 * Qs[2] - Qs[3]) / (12 * h)
    assert np.max(np.abs(dQ - sol.Q(tc) @ hat(sol.omega(tc)))) < 1e-9
    t = np.linspace(-200.0, 200.0, 4001)
    dE, dG = _energy_and_sphere_errors(J, N, w0, sol, t)
    assert dE < 16 * EPS and dG < 16 * EPS
    w, Q = sol(t)
    L = np.einsum("nij,nj->ni", Q, w @ inertia(J).T + N)
    assert np.max(np.abs(L - Q0 @ (inertia(J) @ w0 + N))) < 2e-14 * 5


@pytest.mark.parametrize("eps", [1e-4, 1e-8, 1e-12])
def test_next_to_the_separatrix_against_quad_heyoka(eps):
    """Data moved off the separatrix by eps: the elliptic closed form (mc ~ eps) against heyoka
    in quadruple precision over the first passage of the saddle, and against the separatrix
    closed form where the two motions have not yet parted (|t| <= 10)."""
    J, N, w0 = SEPARATRIX
    w1 = w0 * np.array([1.0, 1.0 + eps, 1.0])
    Q0 = rand_Q(np.random.default_rng(14))
    sol = solve_gyrostat(inertia(J), N, Q0, w1)
    assert label(sol) == "elliptic"
    t = np.linspace(-60.0, 60.0, 61)
    w, Q = sol(t)
    wr, Qr = heyoka_ref(inertia(J), N, Q0, w1, t, quad=True)
    assert np.max(np.abs(w - wr)) < 1e-13 and np.max(np.abs(Q - Qr)) < 1e-12
    near = np.abs(t) <= 10
    ws, _ = solve_gyrostat(inertia(J), N, Q0, w0)(t[near])
    assert np.max(np.abs(w[near] - ws)) < 1e3 * eps + 1e-14


def test_singular_periodic_level_set():
    """The level set is singular (a relative equilibrium elsewhere on it) but the orbit through
    the data is periodic: the elliptic form with m = 0 exactly."""
    J, N, w0 = SINGULAR_PERIODIC
    Q0 = rand_Q(np.random.default_rng(15))
    sol = solve_gyrostat(inertia(J), N, Q0, w0)
    assert label(sol) == "elliptic" and sol._impl.orbit.c.m == 0.0
    t = np.linspace(0.0, 60.0, 61)
    w, Q = sol(t)
    wr, Qr = heyoka_ref(inertia(J), N, Q0, w0, t)
    assert np.max(np.abs(w - wr)) < 1e-13 * 3 and np.max(np.abs(Q - Qr)) < 1e-12


@pytest.mark.parametrize("n", [1e-3, 1e-5])
def test_nearly_planar_orbits_report_their_loss(n):
    """A rotor momentum small against |m| next to the Euler top's separatrix: the orbit nearly
    lies in a plane and the pencil degenerates (the known limitation).  The error against heyoka
    in quadruple precision stays within error_estimate, and above 1e-10 a RuntimeWarning says so."""
    J, N, w0 = np.array([2.0, 0.25, 1.0]), np.array([0.0, n, 0.0]), np.array([0.0, 0.0, 1.0])
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        sol = solve_gyrostat(inertia(J), N, np.eye(3), w0)
    est = sol.diagnostics["error_estimate"]
    assert any(issubclass(r.category, RuntimeWarning) for r in rec) == (est > 1e-10)
    T = sol.diagnostics["period"]
    t = np.linspace(-T, T, 41)
    w, _ = sol(t)
    wr, _ = heyoka_ref(inertia(J), N, np.eye(3), w0, t, quad=True)
    I = inertia(J)
    err = np.max(np.abs((w - wr) @ I.T)) / np.max(np.abs(wr @ I.T))
    assert err <= 2 * est  # two periods
    assert (est > 1e-10) == (n < 1e-4)
