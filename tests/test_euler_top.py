"""The exact free rigid body against numerical integration (scipy DOP853, heyoka in extended
precision), against its own mpmath path, and against the physics (conserved space angular
momentum, the kinematic equation Qdot = Q hat(omega) by finite differences)."""
import numpy as np
import pytest
from conftest import inertia, label, rand_Q

from thetasol import integrate_rotation, solve_rotation
from thetasol.core.so3 import hat

Z = np.zeros((3, 3))


def omega_from_m(J, m):
    return np.linalg.solve(inertia(J), m)


# J principal values [1, 2, 4] give I = [6, 5, 3]: separatrix m_0^2 = 4 m_2^2
SEP_J = np.array([1.0, 2.0, 4.0])


def regimes():
    rng = np.random.default_rng(42)
    out = {
        "generic-max-axis": (rng.uniform(0.5, 2, 3), rand_Q(rng), np.array([0.2, 0.3, 1.1])),
        "generic-min-axis": (np.array([1.0, 1.7, 2.3]), rand_Q(rng), np.array([0.05, 0.6, 0.4])),
        "tensor": (None, rand_Q(rng), rng.normal(size=3)),
        "symmetric-oblate": (np.array([1.0, 1.0, 0.4]), rand_Q(rng), rng.normal(size=3)),
        "symmetric-prolate": (np.array([0.3, 1.0, 1.0]), rand_Q(rng), rng.normal(size=3)),
        "nearly-symmetric": (np.array([1.0, 1.0 + 1e-12, 0.4]), rand_Q(rng), rng.normal(size=3)),
        "near-steady": (np.array([1.0, 1.5, 2.5]), rand_Q(rng), np.array([1e-9, -2e-9, 0.7])),
        "sphere": (np.array([1.3, 1.3, 1.3]), rand_Q(rng), rng.normal(size=3)),
        "steady-mid-axis": (SEP_J, rand_Q(rng), np.array([0.0, 0.8, 0.0])),
        "elementary:rest": (SEP_J, rand_Q(rng), np.zeros(3)),
        "separatrix": (SEP_J, rand_Q(rng), omega_from_m(SEP_J, [2.0, 0.7, -1.0])),
        "near-separatrix-1e-10": (SEP_J, rand_Q(rng), omega_from_m(SEP_J, [2.0 * (1 + 1e-10), 0.7, 1.0])),
        "near-separatrix-other-side": (SEP_J, rand_Q(rng), omega_from_m(SEP_J, [2.0 * (1 - 1e-10), -0.7, 1.0])),
    }
    A = rng.normal(size=(3, 3))
    out["tensor"] = (A @ A.T + np.eye(3), out["tensor"][1], out["tensor"][2])
    return out


REGIMES = regimes()
EXPECTED_METHOD = {
    "symmetric-oblate": "elementary:symmetric", "symmetric-prolate": "elementary:symmetric",
    "sphere": "elementary:steady", "steady-mid-axis": "elementary:steady", "elementary:rest": "elementary:rest",
    "separatrix": "elliptic:separatrix",
}


@pytest.mark.parametrize("name", list(REGIMES))
def test_against_dop853(name):
    J, Q0, w0 = REGIMES[name]
    sol = solve_rotation(inertia(J), Z, Q0, w0)
    assert label(sol) == EXPECTED_METHOD.get(name, "elliptic")
    t = np.linspace(0.0, 12.0, 25)
    w, Q = sol(t)
    wr, Qr = integrate_rotation(inertia(J), Z, Q0, w0, rtol=1e-13, atol=1e-16)(t)
    scale = max(1.0, np.linalg.norm(w0))
    assert np.max(np.abs(w - wr)) < 2e-11 * scale
    assert np.max(np.abs(Q - Qr)) < 2e-11 * scale
    # negative times run the motion backwards
    wn, Qn = sol(-t)
    wrn, Qrn = integrate_rotation(inertia(J), Z, Q0, w0, rtol=1e-13, atol=1e-16)(-t)
    assert np.max(np.abs(Qn - Qrn)) < 2e-11 * scale


@pytest.mark.parametrize("name", list(REGIMES))
def test_physics_residuals(name):
    """Q orthogonal, space angular momentum Q I omega constant, Qdot = Q hat(omega)."""
    J, Q0, w0 = REGIMES[name]
    sol = solve_rotation(inertia(J), Z, Q0, w0)
    I = inertia(J)
    t = np.concatenate([np.linspace(-30, 30, 41), [1e3, 1e5 + 0.123]])
    w, Q = sol(t)
    G = np.linalg.norm(I @ w0)
    assert np.max(np.abs(np.swapaxes(Q, -1, -2) @ Q - np.eye(3))) < 1e-14
    assert np.allclose(np.linalg.det(Q), 1.0, rtol=0, atol=1e-14)
    L = np.einsum("nij,jk,nk->ni", Q, I, w)
    L0 = Q0 @ I @ w0
    assert np.max(np.abs(L - L0)) <= 2e-14 * max(G, 1e-300) + 1e-300
    E = 0.5 * np.einsum("ni,ij,nj->n", w, I, w)
    E0 = 0.5 * w0 @ I @ w0
    assert np.max(np.abs(E - E0)) <= 4e-15 * max(E0, 1e-300)
    # kinematics by a fourth-order central difference
    h = 1e-3 / max(1.0, np.linalg.norm(w0))
    tc = np.array([-7.1, 0.0, 0.3, 2.9, 11.0])
    Qs = [sol.Q(tc + k * h) for k in (-2, -1, 1, 2)]
    dQ = (Qs[0] - 8 * Qs[1] + 8 * Qs[2] - Qs[3]) / (12 * h)
    Qc, wc = sol.Q(tc), sol.omega(tc)
    assert np.max(np.abs(dQ - Qc @ hat(wc))) < 1e-9 * max(1.0, np.linalg.norm(w0)) ** 5


def test_initial_values_are_reproduced():
    for name, (J, Q0, w0) in REGIMES.items():
        sol = solve_rotation(inertia(J), Z, Q0, w0)
        w, Q = sol(0.0)
        assert w.shape == (3,) and Q.shape == (3, 3)
        assert np.max(np.abs(w - w0)) <= 4e-16 * max(1.0, np.linalg.norm(w0)), name
        assert np.max(np.abs(Q - Q0)) <= 4e-15, name


def test_omega_alone_is_the_same_evaluation():
    """sol.omega(t) skips the attitude but must give the bits of sol(t)[0] (the separatrix used
    to form its argument with a different rounding)."""
    t = np.concatenate([np.linspace(-30, 30, 101), [1e3, -1e5 + 0.3]])
    for name, (J, Q0, w0) in REGIMES.items():
        sol = solve_rotation(inertia(J), Z, Q0, w0)
        assert np.array_equal(sol.omega(t), sol(t)[0]), name


def test_tensor_input_equals_principal_input():
    J, Q0, w0 = REGIMES["tensor"]
    ev, R = np.linalg.eigh(J)
    R[:, 2] *= np.linalg.det(R)
    sol = solve_rotation(inertia(J), Z, Q0, w0)
    solp = solve_rotation(inertia(ev), Z, Q0 @ R, R.T @ w0)
    t = np.array([0.5, 17.0, 250.0])
    w, Q = sol(t)
    wp, Qp = solp(t)
    assert np.max(np.abs(w - wp @ R.T)) < 1e-12
    assert np.max(np.abs(Q - Qp @ R.T)) < 1e-12


def test_isotropic_potential_exerts_no_torque():
    J, Q0, w0 = REGIMES["generic-max-axis"]
    sol0 = solve_rotation(inertia(J), Z, Q0, w0)
    sol = solve_rotation(inertia(J), 2.5 * np.eye(3), Q0, w0)
    t = np.array([1.0, 40.0])
    assert np.array_equal(sol0.Q(t), sol.Q(t))
    assert np.allclose(sol.u(t), -2.5 * np.eye(3), rtol=0, atol=1e-14)
    assert sol.invariants["energy"] == pytest.approx(sol0.invariants["energy"] + 1.25 * np.trace(np.diag(J)), rel=1e-15)


def test_invariants_and_period():
    for name in ("generic-max-axis", "generic-min-axis", "tensor", "symmetric-oblate", "near-separatrix-1e-10"):
        J, Q0, w0 = REGIMES[name]
        sol = solve_rotation(inertia(J), Z, Q0, w0)
        inv = sol.invariants
        I = inertia(J)
        assert inv["energy"] == pytest.approx(0.5 * w0 @ I @ w0, rel=1e-15)
        assert inv["m2"] == pytest.approx(np.sum((I @ w0) ** 2), rel=1e-15)
        T = sol.diagnostics["period"]
        t = np.array([0.3, 2.0])
        assert np.max(np.abs(sol.omega(t + T) - sol.omega(t))) < 1e-11 * np.linalg.norm(w0)
        # after one period the attitude has turned about the (space-fixed) angular momentum
        # by the mean precession angle nu T
        L = Q0 @ I @ w0
        Lh = L / np.linalg.norm(L)
        ang = sol.diagnostics["precession_rate"] * T
        K = hat(Lh)
        Rl = np.eye(3) + np.sin(ang) * K + (1 - np.cos(ang)) * K @ K
        assert np.max(np.abs(sol.Q(t + T) - Rl @ sol.Q(t))) < 1e-11 * max(1, ang)
    assert solve_rotation(inertia(REGIMES["separatrix"][0]), Z, *REGIMES["separatrix"][1:]).diagnostics["period"] == np.inf


def test_separatrix_is_hyperbolic_and_asymptotic():
    J, Q0, w0 = REGIMES["separatrix"]
    sol = solve_rotation(inertia(J), Z, Q0, w0)
    assert label(sol) == "elliptic:separatrix"
    I = inertia(J)
    G = np.linalg.norm(I @ w0)
    m_far = sol.m(np.array([-3000.0, 3000.0]))
    # the momentum tends to the unstable middle axis (axis 1 here) at both ends
    assert np.allclose(np.abs(m_far[:, 1]), G, rtol=1e-14, atol=0)
    assert np.max(np.abs(m_far[:, [0, 2]])) < 1e-100  # sech(lambda t), lambda = 0.156


def test_far_time_against_mpmath_path():
    """t = 1e6: the float result loses only what the rounding of the frequencies costs."""
    J, Q0, w0 = REGIMES["generic-max-axis"]
    sol = solve_rotation(inertia(J), Z, Q0, w0)
    ref = solve_rotation(inertia(J), Z, Q0, w0, dps=30)
    t = np.array([1.0, 1e6, -1e6 + 0.5])
    w, Q = sol(t)
    wr, Qr = ref(t)
    err_w = np.abs(w - wr.astype(float)).max(axis=-1)
    err_Q = np.abs(Q - Qr.astype(float)).max(axis=(-1, -2))
    assert err_w[0] < 1e-15 and err_Q[0] < 1e-15
    # a relative error of a few ulps in the frequencies, times |t|
    assert np.all(err_w[1:] < 2e-9) and np.all(err_Q[1:] < 2e-9)


@pytest.mark.parametrize("name", ["generic-min-axis", "tensor", "separatrix", "near-separatrix-1e-10",
                                  "symmetric-prolate", "sphere", "near-steady"])
def test_mpmath_path_matches_float(name):
    J, Q0, w0 = REGIMES[name]
    sol = solve_rotation(inertia(J), Z, Q0, w0)
    ref = solve_rotation(inertia(J), Z, Q0, w0, dps=25)
    assert label(ref) == label(sol)
    t = np.array([0.0, 0.9, -3.3, 40.0])
    wr, Qr = ref(t)
    assert wr.dtype == object
    w, Q = sol(t)
    tol = 1e-12 if "separatrix" not in name else 1e-9
    assert np.max(np.abs(w - wr.astype(float))) < tol
    assert np.max(np.abs(Q - Qr.astype(float))) < tol


@pytest.mark.parametrize("seed, n, Jlo, Jhi, scaled, npts, dtype, rtol", [
    pytest.param(7, 2, 0.5, 2.0, False, 51, "ldbl", 1e-19, id="extended"),
    pytest.param(8, 6, 0.3, 3.0, True, 21, "f128", 1e-32, id="quadruple", marks=pytest.mark.slow),
])
def test_heyoka_reference(seed, n, Jlo, Jhi, scaled, npts, dtype, rtol):
    """Random bodies against heyoka in extended (80-bit) or, slow, quadruple precision."""
    hy = pytest.importorskip("heyoka")
    rng = np.random.default_rng(seed)
    for _ in range(n):
        J = rng.uniform(Jlo, Jhi, 3)
        Q0 = rand_Q(rng)
        w0 = rng.normal(size=3) * (rng.uniform(0.3, 3) if scaled else 1.0)
        sol = solve_rotation(inertia(J), Z, Q0, w0)
        t = np.concatenate([np.linspace(0.0, 100.0, npts), [4000.0]])
        wr, Qr = integrate_rotation(inertia(J), Z, Q0, w0, method="heyoka",
                                      fp_type={"ldbl": np.longdouble, "f128": hy.real128}[dtype], rtol=rtol)(t)
        w, Q = sol(t)
        err = np.maximum(np.abs(w - wr).max(-1), np.abs(Q - Qr).max((-1, -2)))
        assert err[:-1].max() <= 1e-12
        assert err[-1] <= 1e-10


def test_closer_to_the_separatrix_than_float64_resolves():
    """k'^2 below the float range (momentum 1e-170 off the unstable axis): the same closed form
    is evaluated in mpmath and rounded; checked against the asymptotics and the physics."""
    J = SEP_J
    I = inertia(J)
    m0 = np.array([1e-170, 1.0, 0.0])
    Q0 = rand_Q(np.random.default_rng(1))
    sol = solve_rotation(inertia(J), Z, Q0, omega_from_m(J, m0))
    assert label(sol) == "elliptic"
    t = np.array([0.0, 50.0, 2500.0])
    w, Q = sol(t)
    assert w.dtype == float
    m = w @ I.T
    # |m| and the space angular momentum are conserved, Q is a rotation
    assert np.allclose(np.linalg.norm(m, axis=-1), 1.0, rtol=1e-15, atol=0)
    assert np.max(np.abs(np.einsum("nij,nj->ni", Q, m) - Q0 @ m0)) < 1e-14
    assert np.max(np.abs(np.swapaxes(Q, -1, -2) @ Q - np.eye(3))) < 1e-14
    # linearization about the unstable axis: m_0, m_2 grow like exp(lam t), lam^2 = (I_b - I_a)(I_c - I_b)/(I_a I_c) G^2/I_b^2
    lam = np.sqrt((6.0 - 5.0) * (5.0 - 3.0) / (6.0 * 3.0)) / 5.0
    ratio = abs(m[1, 0]) / 1e-170
    assert 0.5 * np.exp(lam * 50.0) < ratio < 2.0 * np.exp(lam * 50.0)
