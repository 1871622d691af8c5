"""The free gyrostat (8.39)-(8.40) in closed form against numerical integration of
mdot = (m + N) x omega, Qdot = Q hat(omega) (scipy DOP853; heyoka in extended precision if
installed), and against the physics (conserved |h|, energy, space momentum Q h)."""
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from thetasol import RotationSolution, solve_gyrostat, solve_rotation
from thetasol._so3 import hat


def rand_Q(rng):
    Q = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    return Q * np.linalg.det(Q)


def inertia(J):
    J = np.diag(J) if np.ndim(J) == 1 else np.asarray(J)
    return np.trace(J) * np.eye(3) - J


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


def heyoka_ref(J, N, Q0, w0, t):
    hy = pytest.importorskip("heyoka")
    I = inertia(J)
    Ii = np.linalg.inv(I)
    xs = hy.make_vars(*[f"m{i}" for i in range(3)], *[f"q{i}{j}" for i in range(3) for j in range(3)])
    m = xs[:3]
    Q = [xs[3 + 3 * i: 6 + 3 * i] for i in range(3)]
    w = [sum(float(Ii[i, k]) * m[k] for k in range(3)) for i in range(3)]
    h = [m[i] + float(N[i]) for i in range(3)]
    md = [h[1] * w[2] - h[2] * w[1], h[2] * w[0] - h[0] * w[2], h[0] * w[1] - h[1] * w[0]]
    W = [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]]
    Qd = [sum(Q[i][k] * W[k][j] for k in range(3)) for i in range(3) for j in range(3)]
    fp = np.longdouble
    ta = hy.taylor_adaptive(list(zip(xs, md + Qd)), np.concatenate([I @ w0, Q0.ravel()]).astype(fp),
                            tol=fp(1e-19), fp_type=fp)
    st = np.asarray(ta.propagate_grid(np.asarray(t, dtype=fp))[-1], dtype=float)
    return st[:, :3] @ Ii.T, st[:, 3:].reshape(-1, 3, 3)


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
    sol = solve_gyrostat(J, N, Q0, w0)
    assert sol.method == "gyrostat/elliptic"
    t = np.linspace(0.0, 15.0, 31)
    w, Q = sol(t)
    wr, Qr = dop853(J, N, Q0, w0, t)
    s = max(1.0, np.abs(wr).max())
    assert np.max(np.abs(w - wr)) < 3e-11 * s
    assert np.max(np.abs(Q - Qr)) < 3e-11 * s


def test_both_elliptic_forms_are_exercised():
    kinds = {solve_gyrostat(*c)._impl.kind for c in generic_cases(24, seed=1)}
    assert kinds == {1, 3}  # one and three real roots of the Weierstrass cubic


def test_against_heyoka_extended_precision():
    for J, N, Q0, w0 in generic_cases(3, seed=2):
        sol = solve_gyrostat(J, N, Q0, w0)
        t = np.linspace(0.0, 60.0, 61)
        w, Q = sol(t)
        wr, Qr = heyoka_ref(J, N, Q0, w0, t)
        s = max(1.0, np.abs(wr).max())
        assert max(np.abs(w - wr).max(), np.abs(Q - Qr).max()) < 2e-12 * s


SPECIAL = {
    "zero-rotor": (np.array([0.8, 1.3, 2.1]), np.zeros(3), np.array([0.3, -0.5, 0.9]), "euler-top/elliptic"),
    "rest": (np.array([0.8, 1.3, 2.1]), np.array([0.3, 0.1, -0.2]), np.zeros(3), "rest"),
    "steady": (np.array([0.8, 1.3, 2.1]), np.array([0.0, 0.0, 0.5]), np.array([0.0, 0.0, 0.7]), "gyrostat/steady"),
    "sphere": (np.array([1.0, 1.0, 1.0]), np.array([0.3, 0.1, -0.2]), np.array([0.5, -0.4, 0.2]), "gyrostat/sphere"),
    "dual-spin-z": (np.array([1.0, 1.0, 0.5]), np.array([0.0, 0.0, 0.7]), np.array([0.4, 0.3, -0.6]), "gyrostat/axisymmetric"),
    "dual-spin-x": (np.array([0.4, 1.0, 1.0]), np.array([-0.9, 0.0, 0.0]), np.array([0.4, 0.3, -0.6]), "gyrostat/axisymmetric"),
    "dual-spin-y": (np.array([1.0, 0.6, 1.0]), np.array([0.0, 0.5, 0.0]), np.array([0.4, 0.3, -0.6]), "gyrostat/axisymmetric"),
}


@pytest.mark.parametrize("name", list(SPECIAL))
def test_special_closed_forms(name):
    J, N, w0, method = SPECIAL[name]
    Q0 = rand_Q(np.random.default_rng(3))
    sol = solve_gyrostat(J, N, Q0, w0)
    assert sol.method == method
    t = np.linspace(0.0, 20.0, 41)
    w, Q = sol(t)
    wr, Qr = dop853(J, N, Q0, w0, t)
    assert np.max(np.abs(w - wr)) < 2e-11 and np.max(np.abs(Q - Qr)) < 2e-11


@pytest.mark.parametrize("case", range(8))
def test_physics_over_long_times(case):
    J, N, Q0, w0 = generic_cases()[case]
    sol = solve_gyrostat(J, N, Q0, w0)
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
    assert np.allclose(sol.h(t), h, atol=1e-15 * G)
    assert isinstance(sol, RotationSolution)


def test_kinematics_by_finite_differences():
    J, N, Q0, w0 = generic_cases()[1]
    sol = solve_gyrostat(J, N, Q0, w0)
    h = 1e-3
    tc = np.array([0.0, 1.7, 33.0])
    Qs = [sol.Q(tc + k * h) for k in (-2, -1, 1, 2)]
    dQ = (Qs[0] - 8 * Qs[1] + 8 * Qs[2] - Qs[3]) / (12 * h)
    assert np.max(np.abs(dQ - sol.Q(tc) @ hat(sol.omega(tc)))) < 1e-9


def test_period_and_precession():
    J, N, Q0, w0 = generic_cases()[0]
    sol = solve_gyrostat(J, N, Q0, w0)
    T = sol.invariants["period"]
    t = np.array([0.2, 3.0])
    assert np.max(np.abs(sol.omega(t + T) - sol.omega(t))) < 1e-12
    L = Q0 @ (inertia(J) @ w0 + N)
    Lh = L / np.linalg.norm(L)
    ang = sol.invariants["precession_rate"] * T
    K = hat(Lh)
    Rl = np.eye(3) + np.sin(ang) * K + (1 - np.cos(ang)) * K @ K
    assert np.max(np.abs(sol.Q(t + T) - Rl @ sol.Q(t))) < 1e-11


def test_invariants_of_8_40():
    J, N, Q0, w0 = generic_cases()[2]
    sol = solve_gyrostat(J, N, Q0, w0)
    t = np.array([0.0, 5.0])
    M = sol.M(t)
    W = hat(sol.omega(t))
    Nh = hat(N)
    H = 0.5 * np.trace(M @ W, axis1=-2, axis2=-1)
    H2 = np.trace((M + Nh) @ (M + Nh), axis1=-2, axis2=-1)
    assert np.allclose(H, sol.invariants["H"], rtol=1e-13)
    assert np.allclose(H2, sol.invariants["H2"], rtol=1e-13)
    assert sol.invariants["H"] == pytest.approx(-2 * sol.invariants["energy"])


@pytest.mark.parametrize("eps", [1e-4, 1e-8, 1e-12])
def test_nearly_axisymmetric_dual_spin_keeps_accuracy(eps):
    """A nearly axisymmetric carrier with the rotor nearly on its axis: the orbit is nearly a
    plane circle, where the residual quadratic is evaluated next to its roots (its exact
    coefficients keep that accurate)."""
    J = np.array([1.0, 1.0 + eps, 0.5])
    N = np.array([eps, 0.0, 0.7])
    w0 = np.array([0.4, 0.3, -0.6])
    Q0 = rand_Q(np.random.default_rng(4))
    sol = solve_gyrostat(J, N, Q0, w0)
    assert sol.method == "gyrostat/elliptic"
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
    sol = solve_gyrostat(J, N, np.eye(3), w0)
    t = np.linspace(0.0, 20.0, 21)
    ref = solve_ivp(lambda _t, y: np.cross(y + N, np.linalg.solve(I, y)), (0, 20), I @ w0, t_eval=t,
                    rtol=1e-13, atol=1e-40 * scale, method="DOP853").y.T
    m = sol.m(t)
    assert np.max(np.abs(m - ref).max(-1) / np.abs(ref).max(-1)) < 5e-13


def test_generic_cases_do_not_warn():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for c in generic_cases(12, seed=5):
            assert solve_gyrostat(*c).invariants["error_estimate"] < 1e-11


def test_zero_rotor_is_the_euler_top():
    J, N, w0, _ = SPECIAL["zero-rotor"]
    Q0 = rand_Q(np.random.default_rng(6))
    t = np.array([0.5, 100.0])
    a = solve_gyrostat(J, N, Q0, w0)(t)
    b = solve_rotation(J, np.zeros((3, 3)), Q0, w0)(t)
    assert np.allclose(a[0], b[0], rtol=0, atol=1e-15) and np.allclose(a[1], b[1], rtol=0, atol=1e-15)


@pytest.mark.parametrize("kw, msg", [
    (dict(N=[1.0, np.nan, 0.0]), "NaN"),
    (dict(N=[1.0, 2.0]), "shape"),
    (dict(J=[1.0, 2.0, -5.0]), "physical|positive"),
    (dict(Q0=np.diag([1.0, 1.0, -1.0])), "reflection"),
    (dict(omega0=[0.0, 0.0]), "shape"),
])
def test_bad_input(kw, msg):
    args = dict(J=[0.8, 1.3, 2.1], N=[0.1, 0.2, 0.3], Q0=np.eye(3), omega0=[0.3, 0.2, 0.1])
    args.update(kw)
    with pytest.raises(ValueError, match=msg):
        solve_gyrostat(**args)
