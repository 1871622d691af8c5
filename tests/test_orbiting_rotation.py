"""The rotation of one body on a Kepler orbit (Section 7): the numerical reference and the closed forms.

References: heyoka's Taylor integrator of the same equations with the orbit integrated alongside in
80-bit precision, a body of point masses in the exact 1/r field (integrated here, nothing of thetasol
used but the initial data), the Jacobi integral (7.18) on circular orbits.
"""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from thetasol.core.so3 import rodrigues
from thetasol.integrators.orbiting_rotation import integrate_orbiting_rotation
from thetasol.mechanics.gravity_gradient import orbit_frame
from thetasol.solutions.kepler import KeplerOrbit

MU = 3.986004418e14
R_LEO = 6378137.0 + 500e3
I_SAT = np.array([1200.0, 1500.0, 1800.0])          # kg m^2, principal inertia
J_SAT = 0.5 * I_SAT.sum() - I_SAT


def _orbit(e, mu=MU, rp=R_LEO, incl=0.9):
    v = math.sqrt(mu * (1 + e) / rp)
    return KeplerOrbit(mu, [rp, 0.0, 0.0], [0.0, v * math.cos(incl), v * math.sin(incl)])


def _initial(orb, kind, e=0.0, amp=0.2):
    n = orb.diagnostics["mean_motion"]
    F0 = orbit_frame(orb.r0, orb.v0)
    if kind == "librating":        # near the orbit-aligned attitude, turning with the orbit at periapsis
        Q0 = F0 @ rodrigues([0.5 * amp, -0.25 * amp, amp])
        w0 = Q0.T @ F0[:, 2] * n * (1 + e) ** 2 / (1 - e * e) ** 1.5 + np.array([0.0, 0.0, 0.3 * amp * n])
    else:
        Q0 = F0 @ rodrigues([0.4, 1.1, -0.3])
        w0 = np.array([3.0, -7.0, 5.0]) * n
    return Q0, w0


def _jacobi(I, orb, t, Q, w):
    """(7.18) H = 1/2 (M, I^-1 M) + (a0/2)(gamma, I gamma) - Omega (M, n), M = I omega, a0 = 3 Omega^2,
    gamma and n the radial and the orbit normal in the body frame (circular orbits)."""
    Om = orb.diagnostics["mean_motion"]
    r, v = orb(t)
    g = np.einsum("...ji,...j->...i", Q, r / np.linalg.norm(r, axis=-1, keepdims=True))
    h = np.cross(r, v)
    nb = np.einsum("...ji,...j->...i", Q, h / np.linalg.norm(h, axis=-1, keepdims=True))
    M = w * I
    return (0.5 * np.sum(M * w, -1) + 1.5 * Om ** 2 * np.sum(g * g * I, -1) - Om * np.sum(M * nb, -1))


@pytest.mark.parametrize("e, kind", [(0.0, "librating"), (0.0, "tumbling"), (0.05, "librating"), (0.3, "tumbling")])
def test_dop853_against_heyoka_80bit_20_orbits(e, kind):
    pytest.importorskip("heyoka")
    orb = _orbit(e)
    Q0, w0 = _initial(orb, kind, e)
    ts = np.linspace(0.0, 20 * orb.period, 6)[1:]
    w, Q = integrate_orbiting_rotation(J_SAT, orb, Q0, w0, ts)
    wr, Qr = integrate_orbiting_rotation(J_SAT, orb, Q0, w0, ts, method="heyoka", dtype="ldbl", rtol=1e-19)
    # the data's own conditioning: 1e-14 on omega0 moves the reference by <= 1.5e-11 here (e = 0.3
    # librating is chaotic, 1e-14 grows to 1e-2 in 20 orbits, so it is not a test case)
    dQ, dw = np.abs(Q - Qr).max(), np.abs(w - wr).max() / np.abs(wr).max()
    # measured 4.8e-12 / 2.9e-12 (circular, librating) ... 7.3e-11 / 3.4e-11 (e = 0.3, tumbling)
    assert dQ < 5e-10 and dw < 5e-10


@pytest.mark.parametrize("kind", ["librating", "tumbling"])
def test_jacobi_integral_circular(kind):
    orb = _orbit(0.0)
    Q0, w0 = _initial(orb, kind)
    ts = np.linspace(0.0, 5 * orb.period, 51)
    w, Q = integrate_orbiting_rotation(J_SAT, orb, Q0, w0, ts)
    H = _jacobi(I_SAT, orb, ts, Q, w)
    scale = np.abs(0.5 * np.sum(w * w * I_SAT, -1)).max()
    # measured 1.3e-13 (librating) / 4.7e-14 (tumbling) relative to the kinetic energy
    assert np.abs(H - H[0]).max() / scale < 1e-12


def _point_mass_body(s):
    """Six point masses on the principal axes (centrally symmetric: no odd moments), size s, mass 1."""
    d = s * np.array([1.0, 0.8, 0.55])
    mk = np.array([0.2, 0.15, 0.15])                 # per mass of each pair, total 1
    pts = np.concatenate([np.diag(d), -np.diag(d)])
    ms = np.concatenate([mk, mk])
    J = np.diag(2 * mk * d * d)
    return pts, ms, J


def _integrate_point_masses(pts, ms, mu, q0, v0, Q0, w0, ts):
    """Rigid body of point masses in the field -mu x/|x|^3: mass centre and rotation, no expansion."""
    J = np.einsum("k,ki,kj->ij", ms, pts, pts)
    I = np.trace(J) * np.eye(3) - J
    I_inv = np.linalg.inv(I)
    M = ms.sum()

    def rhs(_t, y):
        q, qd, m, Q = y[:3], y[3:6], y[6:9], y[9:].reshape(3, 3)
        x = q + pts @ Q.T
        F = -mu * ms[:, None] * x / np.linalg.norm(x, axis=1)[:, None] ** 3
        tau_space = np.cross(pts @ Q.T, F).sum(0)
        w = I_inv @ m
        W = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
        return np.concatenate([qd, F.sum(0) / M, np.cross(m, w) + Q.T @ tau_space, (Q @ W).ravel()])

    y0 = np.concatenate([q0, v0, I @ w0, Q0.ravel()])
    sol = solve_ivp(rhs, (0, ts[-1]), y0, method="DOP853", t_eval=ts, rtol=1e-13, atol=1e-16)
    y = sol.y.T
    return np.linalg.solve(I, y[:, 6:9, None])[..., 0], y[:, 9:].reshape(-1, 3, 3)


@pytest.mark.parametrize("e", [0.0, 0.1])
def test_point_mass_body_differs_by_size_squared(e):
    """The expansion (7.3) drops terms of relative order (size / r)^2 for a centrally symmetric body."""
    orb = _orbit(e, mu=1.0, rp=1.0)
    Q0, w0 = _initial(orb, "librating", e)
    ts = np.array([0.5, 1.0, 2.0]) * orb.period
    diffs = []
    for s in (1e-2, 1e-3):
        pts, ms, J = _point_mass_body(s)
        w, Q = integrate_orbiting_rotation(J, orb, Q0, w0, ts, rtol=1e-13)
        wp, Qp = _integrate_point_masses(pts, ms, 1.0, orb.r0, orb.v0, Q0, w0, ts)
        diffs.append(max(np.abs(Q - Qp).max(), np.abs(w - wp).max() / np.abs(wp).max()))
    ratio = diffs[0] / diffs[1]
    # measured differences 1.6e-3 / 1.6e-5 (circular), 2.6e-3 / 2.6e-5 (e = 0.1) after 2 orbits:
    # ratio 99.7 = (1e-2 / 1e-3)^2 (and 1.5e-6 at size 3e-4: the s^2 law holds over 3 decades)
    assert 1e-4 < diffs[0] < 1e-2 and 0.8 * 100 < ratio < 1.2 * 100


def test_bad_data():
    orb = _orbit(0.0)
    with pytest.raises(TypeError, match="KeplerOrbit"):
        integrate_orbiting_rotation(J_SAT, (orb.r0, orb.v0), np.eye(3), np.zeros(3), [1.0])
    with pytest.raises(ValueError, match="Q0"):
        integrate_orbiting_rotation(J_SAT, orb, 2 * np.eye(3), np.zeros(3), [1.0])
    with pytest.raises(ValueError, match="J"):
        integrate_orbiting_rotation([1.0, -1.0, 1.0], orb, np.eye(3), np.zeros(3), [1.0])


def test_shapes_and_negative_times():
    orb = _orbit(0.1)
    Q0, w0 = _initial(orb, "tumbling")
    t = np.array([[-300.0, 0.0], [250.0, -300.0]])
    w, Q = integrate_orbiting_rotation(J_SAT, orb, Q0, w0, t)
    assert w.shape == (2, 2, 3) and Q.shape == (2, 2, 3, 3)
    assert np.array_equal(Q[0, 0], Q[1, 1]) and np.allclose(Q[0, 1], Q0, atol=1e-15)
    # backward, then forward on the orbit restarted at t = -300, returns to the start
    orb2 = KeplerOrbit(MU, *orb(-300.0))
    w1, Q1 = integrate_orbiting_rotation(J_SAT, orb2, Q[0, 0], w[0, 0], [300.0])
    # measured 1.0e-14 / 4.6e-16
    assert np.abs(Q1[0] - Q0).max() < 1e-13 and np.abs(w1[0] - w0).max() < 1e-13 * np.abs(w0).max()
