"""The documented conventions against a body made of point masses (docs/conventions.md).

The reference integrates Newton's laws for the point masses in the space frame: total
angular momentum about the mass centre, torque sum x_k x (-m_k grad phi), inertia
recomputed from the point positions.  No formula of thetasol.mechanics.equations is used.
"""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from thetasol import integrate_rotation, invariants
from thetasol.core.inertia import inertia
from thetasol.core.so3 import hat


def point_mass_body(rng, n=6):
    r = rng.normal(size=(n, 3))
    mass = rng.uniform(0.5, 2.0, n)
    r -= (mass[:, None] * r).sum(0) / mass.sum()
    return mass, r


def brute_force(mass, r, a, b, Q0, omega0, t):
    """Rigid body of point masses in phi(x) = 1/2 x.a x + 1/2 b.x, mass centre held at 0."""
    def inertia_space(Q):
        x = r @ Q.T
        return sum(mk * (xk @ xk * np.eye(3) - np.outer(xk, xk)) for mk, xk in zip(mass, x))

    def rhs(_t, y):
        L, Q = y[:3], y[3:].reshape(3, 3)
        x = r @ Q.T
        w_space = np.linalg.solve(inertia_space(Q), L)
        force = -mass[:, None] * (x @ a.T + 0.5 * b)
        return np.concatenate([np.cross(x, force).sum(0), (hat(w_space) @ Q).ravel()])

    L0 = inertia_space(Q0) @ (Q0 @ omega0)
    sol = solve_ivp(rhs, (0, t[-1]), np.concatenate([L0, Q0.ravel()]), t_eval=t,
                    method="DOP853", rtol=1e-13, atol=1e-15)
    Q = sol.y[3:].T.reshape(-1, 3, 3)
    omega = [Qk.T @ np.linalg.solve(inertia_space(Qk), Lk) for Qk, Lk in zip(Q, sol.y[:3].T)]
    return Q, np.array(omega)


@pytest.mark.parametrize("method", ["DOP853", "splitting"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_point_masses_match_the_euler_equations(seed, method):
    rng = np.random.default_rng(seed)
    mass, r = point_mass_body(rng)
    J = np.einsum("k,ki,kj->ij", mass, r, r)  # a general (non-principal) tensor
    a = rng.normal(size=(3, 3))
    a = a + a.T
    b = rng.normal(size=3)
    Q0 = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    Q0 *= np.linalg.det(Q0)
    omega0 = rng.normal(size=3)
    t = np.linspace(0.0, 4.0, 9)
    Q_ref, w_ref = brute_force(mass, r, a, b, Q0, omega0, t)
    w, Q = integrate_rotation(inertia(J), a, Q0, omega0, method=method)(t)
    assert np.max(np.abs(Q - Q_ref)) < 1e-10
    assert np.max(np.abs(w - w_ref)) < 1e-10  # omega is the BODY-frame angular velocity


def test_paper_sign_described_as_documented():
    """u = -Q^T a Q makes (4.8) hold as printed; H of (4.9) is -2 (T + V)."""
    rng = np.random.default_rng(5)
    J = np.diag([0.4, 0.9, 1.3])
    a = rng.normal(size=(3, 3))
    a = a + a.T
    Q0 = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    Q0 *= np.linalg.det(Q0)
    w0 = rng.normal(size=3)
    h = 1e-4
    (w, Q) = integrate_rotation(inertia(J), a, Q0, w0, rtol=1e-13)(np.array([-h, 0.0, h]))
    W = hat(w)
    M = J @ W + W @ J
    u = -np.swapaxes(Q, -1, -2) @ a @ Q
    Mdot = (M[2] - M[0]) / (2 * h)
    udot = (u[2] - u[0]) / (2 * h)
    assert np.allclose(Mdot, M[1] @ W[1] - W[1] @ M[1] + u[1] @ J - J @ u[1], atol=1e-7)
    assert np.allclose(udot, u[1] @ W[1] - W[1] @ u[1], atol=1e-7)
    inv = invariants(inertia(J), a, Q, w)
    assert np.allclose(inv["H"], -2 * inv["energy"], rtol=1e-13)


def test_so3_helpers_match_numpy():
    """hat(v) w = v x w; the cheap cross is np.cross bit for bit (multibody relies on it)."""
    from thetasol.core.so3 import cross, rodrigues, vee

    rng = np.random.default_rng(9)
    u, v = rng.normal(size=(2, 4, 5, 3))
    assert np.array_equal(cross(u, v), np.cross(u, v))
    assert np.array_equal(cross(u[0, 0], v), np.cross(u[0, 0], v))  # broadcasting
    assert np.allclose((hat(u) @ v[..., None])[..., 0], np.cross(u, v), rtol=0, atol=1e-15)
    assert np.array_equal(vee(hat(u)), u)
    R = rodrigues(u)
    assert np.allclose(np.swapaxes(R, -1, -2) @ R, np.eye(3), atol=1e-15)
    assert np.allclose((R @ u[..., None])[..., 0], u, atol=1e-15)  # the axis is fixed


def test_one_implementation_of_the_body_conversions():
    """``thetasol.inertia``/``thetasol.second_moments`` are thetasol.core.inertia's, invert each other (to
    rounding) on principal values and tensors alike, and no other module writes ``tr(J) 1 - J`` or
    ``tr(I)/2 1 - I`` inline."""
    import pathlib
    import re

    import thetasol
    from thetasol.core import inertia as conv

    assert thetasol.inertia is conv.inertia and thetasol.second_moments is conv.second_moments
    J = np.array([0.6, 1.0, 1.7])
    assert np.allclose(conv.second_moments(conv.inertia(J)), J, rtol=0, atol=4e-16)
    R = np.linalg.qr(np.array([[1.0, 0.3, -0.2], [0.1, 1.0, 0.4], [0.5, -0.2, 1.0]]))[0]
    Jt = R @ np.diag(J) @ R.T
    assert np.allclose(conv.inertia(Jt), R @ np.diag(conv.inertia(J)) @ R.T, rtol=0, atol=1e-15)
    assert np.array_equal(conv.inertia(Jt), conv.inertia_from_moments(Jt))
    inline = re.compile(r"np\.trace\([^()]*\) \* np\.eye\(3\) -|0\.5 \* [A-Za-z_]+\.sum\(\) - ")
    root = pathlib.Path(thetasol.__file__).parent
    found = [str(p.relative_to(root)) for p in root.rglob("*.py")
             if p.name != "inertia.py" and inline.search(p.read_text())]
    assert found == []
