"""Linear stability of the orbit-aligned attitude (Section 7, circular orbit) and the torque (7.16).

The formulas of :func:`gravity_gradient_stability` against the eigenvalues of the Jacobian of the
full nonlinear equations in the orbit frame, formed by central differences in 40-digit mpmath
(nothing of the module is used there), against the figures of docs' sources, and the JEOD
thin-rod periods.
"""
import math

import mpmath
import numpy as np
import pytest

from thetasol.core.inertia import inertia
from thetasol.mechanics.gravity_gradient import gravity_gradient_stability, gravity_gradient_torque, orbit_frame


def _jacobian_eigenvalues(I, n, dps=40, h="1e-12"):
    """Eigenvalues of the linearized full equations about the orbit-aligned attitude.

    State (theta, omega): body-to-orbit-frame rotation C = expm(hat theta), body angular velocity
    omega.  I omegadot = I omega x omega + 3 n^2 g x I g with g = C^T e_r; Cdot = C hat(omega) -
    hat(n e_n) C; at the equilibrium thetadot = vee(C^T Cdot) to first order.
    """
    with mpmath.workdps(dps):
        Im = [mpmath.mpf(float(x)) for x in I]
        nn = mpmath.mpf(float(n))

        def hat(v):
            return mpmath.matrix([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])

        def rhs(x):
            th, w = x[:3], x[3:]
            C = mpmath.expm(hat(th))
            g = [C[0, k] for k in range(3)]                     # C^T e_r
            Ig = [Im[k] * g[k] for k in range(3)]
            Iw = [Im[k] * w[k] for k in range(3)]
            cr = lambda a, b: [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]  # noqa: E731
            t1, t2 = cr(Iw, w), cr(g, Ig)
            wd = [(t1[k] + 3 * nn ** 2 * t2[k]) / Im[k] for k in range(3)]
            Cd = C * hat(w) - hat([0, 0, nn]) * C
            S = C.T * Cd
            thd = [S[2, 1], S[0, 2], S[1, 0]]
            return thd + wd

        x0 = [mpmath.mpf(0)] * 5 + [nn]
        hh = mpmath.mpf(h)
        A = mpmath.matrix(6, 6)
        for j in range(6):
            xp, xm = list(x0), list(x0)
            xp[j] += hh
            xm[j] -= hh
            fp, fm = rhs(xp), rhs(xm)
            for i in range(6):
                A[i, j] = (fp[i] - fm[i]) / (2 * hh)
        ev = mpmath.eig(A, left=False, right=False)
        return np.array([complex(e) for e in ev])


def _match(a, b):
    """Largest distance between two multisets of complex numbers, relative to max |b|."""
    a, b = list(a), list(b)
    worst = 0.0
    for x in a:
        j = min(range(len(b)), key=lambda k: abs(b[k] - x))
        worst = max(worst, abs(b[j] - x))
        b.pop(j)
    return worst


CASES = [   # principal inertia (radial, along-track, normal), expected region
    ((1.0, 1.5, 2.0), "lagrange"),
    ((1.5, 2.0, 3.0), "lagrange"),
    ((0.7, 1.0, 0.65), "debra-delp"),
    ((1.0, 2.0, 1.5), "unstable"),        # k3 < 0 < k1
    ((2.0, 1.0, 2.5), "unstable"),        # pitch
    ((0.6, 1.0, 0.59), "debra-delp"),
    ((0.3, 1.0, 0.75), "unstable"),       # DeBra-Delp side but b^2 < 16 k1 k3
]


@pytest.mark.parametrize("I, region", CASES)
@pytest.mark.parametrize("n", [1.0, 1.1e-3])
def test_against_the_jacobian_of_the_full_equations(I, region, n):
    s = gravity_gradient_stability(I, n)
    assert s.region == region and s.stable == (region in ("lagrange", "debra-delp"))
    ev = _jacobian_eigenvalues(I, n)
    # measured <= 2.4e-16 of n (eigenvalues), 4.4e-16 relative (frequencies)
    assert _match(s.eigenvalues, ev) < 2e-15 * n
    if s.stable:
        w = sorted(abs(e.imag) for e in ev)[::2]
        want = sorted([s.pitch_frequency, *s.roll_yaw_frequencies])
        assert np.allclose(w, want, rtol=4e-15, atol=0)


def test_published_frequencies():
    """Two check bodies, one in each stable region, Omega = 1: the pitch and roll-yaw frequencies of the
    linearized motion (Hughes, Spacecraft Attitude Dynamics, Wiley 1986, ch. 9; DeBra and Delp,
    J. Astronaut. Sci. 8 (1961) 14-17), checked independently against the Jacobian of (7.16)."""
    s = gravity_gradient_stability((1.5, 2.0, 3.0), 1.0)
    assert s.pitch_frequency == pytest.approx(0.707107, abs=1e-6)
    assert s.roll_yaw_frequencies == pytest.approx((0.802429, 1.762415), abs=1e-6)
    s = gravity_gradient_stability((0.7, 1.0, 0.65), 1.0)
    assert s.region == "debra-delp"
    assert s.pitch_frequency == pytest.approx(1.176697, abs=1e-6)
    assert s.roll_yaw_frequencies == pytest.approx((0.367648, 0.860136), abs=1e-6)


T_JEOD = 5642.92


def test_jeod_periods_are_the_thin_rod_limit():
    """JEOD RUN_10's 'analytic' 3257.94 s and 2821.46 s are T/sqrt(3) and T/2: the thin rod."""
    n = 2 * math.pi / T_JEOD
    for w in (1e-6, 1e-12):                       # rod along the radial: J = (L^2, w, w) L^2 = 1
        p = gravity_gradient_stability(inertia([1.0, w, w]), n).periods
        assert p["pitch"] == pytest.approx(T_JEOD / math.sqrt(3), rel=3 * w)
        assert p["roll_yaw"][1] == pytest.approx(T_JEOD / 2, rel=3 * w)
        assert p["roll_yaw"][0] == math.inf                  # spin about the rod: neutral
    p = gravity_gradient_stability(inertia([1.0, 1e-12, 1e-12]), n).periods
    assert round(p["pitch"], 2) == 3257.94 and round(p["roll_yaw"][1], 2) == 2821.46
    # JEOD's cylinder itself (I_axis = 500, I_transverse = 12250 kg m^2) is not a thin rod:
    # the exact linear periods are T / sqrt(3 (1 - 500/12250)) and T / sqrt(4 - 3 * 500/12250)
    s = gravity_gradient_stability((500.0, 12250.0, 12250.0), n)
    assert s.region == "marginal"                            # symmetric about the radial: k3 = 0
    assert s.periods["pitch"] == pytest.approx(T_JEOD / math.sqrt(3 * (1 - 500 / 12250)), rel=1e-14)
    assert s.periods["roll_yaw"][1] == pytest.approx(T_JEOD / math.sqrt(4 - 3 * 500 / 12250), rel=1e-14)
    assert round(s.periods["pitch"], 2) == 3326.54 and round(s.periods["roll_yaw"][1], 2) == 2865.66


def test_torque_is_the_gradient_of_the_tidal_potential():
    """tau = -(dV) for V = -(mu/2|r|^3) tr((3 g g^T - 1) Q J Q^T), by central differences in rotation."""
    rng = np.random.default_rng(3)
    J = np.diag([0.4, 1.1, 2.3])
    Q = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    Q *= np.linalg.det(Q)
    r = np.array([3.0, -1.0, 2.0])
    mu = 2.5

    def V(Qx):
        g = r / np.linalg.norm(r)
        return -mu / (2 * np.linalg.norm(r) ** 3) * np.trace((3 * np.outer(g, g) - np.eye(3)) @ Qx @ J @ Qx.T)

    tau = gravity_gradient_torque(inertia(J), Q, r, mu)
    h = 1e-6
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        K = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
        from scipy.linalg import expm
        dV = (V(Q @ expm(K)) - V(Q @ expm(-K))) / (2 * h)   # body-frame rotation by e_k
        assert abs(tau[k] + dV) < 1e-9 * np.abs(tau).max()


def test_orbit_frame():
    F = orbit_frame(np.array([2.0, 0, 0]), np.array([0.3, 1.0, 0]))
    assert np.allclose(F, np.eye(3), atol=1e-15)
    F = orbit_frame(np.array([[0, 3.0, 0]]), np.array([[-1.0, 0, 0.2]]))
    assert np.allclose(F[0] @ F[0].T, np.eye(3)) and np.linalg.det(F[0]) > 0


@pytest.mark.parametrize("I, n, what", [
    ([0.0, 1.0, 1.0], 1.0, "rod"), ([1.0, 3.0, 1.0], 1.0, "triangle inequality"), ([1.0, 1.0], 1.0, "I must"),
    ([1.0, 1.0, 1.0], 0.0, "mean_motion"), ([1.0, np.nan, 1.0], 1.0, "I contains"),
])
def test_bad_data(I, n, what):  # noqa: E741 - the inertia tensor's usual name
    with pytest.raises(ValueError, match=what):
        gravity_gradient_stability(I, n)
