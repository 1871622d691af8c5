"""Rotation about a fixed principal axis (reducible spectral curve): the planar pendulum."""
import numpy as np
import pytest
from conftest import label
from hypothesis import given, settings, strategies as st

from thetasol import inertia, integrate_rotation, invariants, second_moments, solve_rotation
from thetasol.core.so3 import rodrigues

J = np.array([0.7, 1.1, 1.9])
A = np.diag([1.0, 2.0, 3.0])


@pytest.mark.parametrize("Q0, w0, method", [
    (np.eye(3), np.zeros(3), "elementary:rest"),                                       # equilibrium (also unstable ones)
    (rodrigues([0, 0, 0.4]), np.zeros(3), "elliptic:pendulum/libration"),
    (rodrigues([0, 0, 0.4]), [0, 0, 0.3], "elliptic:pendulum/circulation"),
    (rodrigues([0, 0, 0.4]), [0, 0, 3.0], "elliptic:pendulum/circulation"),
    (rodrigues([0.7, 0, 0]), [-0.5, 0, 0], "elliptic:pendulum/circulation"),
    (rodrigues([0, 1.2, 0]), [0, 0.2, 0], "elliptic:pendulum/libration"),
])
def test_regimes_against_heyoka_or_dop853(Q0, w0, method):
    sol = solve_rotation(inertia(J), A, Q0, w0)
    assert label(sol) == method
    t = np.array([0.5, 3.0, 17.0, 102.0])
    w, Q = sol(t)
    wr, Qr = integrate_rotation(inertia(J), A, Q0, w0, rtol=1e-13)(t)
    assert np.abs(Q - Qr).max() < 1e-10 and np.abs(w - wr).max() < 1e-10


def test_uniform_rotation_about_an_axis_of_symmetry():
    """No torque about the axis: steady spin (the body is symmetric about e_3)."""
    Js = np.array([0.8, 0.8, 1.5])
    sol = solve_rotation(inertia(Js), A, rodrigues([0, 0, 0.3]), [0, 0, 1.3])
    assert label(sol) == "elementary:pendulum/uniform"
    w, Q = sol(np.array([2.0]))
    assert np.allclose(w, [[0, 0, 1.3]], atol=1e-15)


def test_separatrix_is_hyperbolic():
    """From the stable equilibrium with exactly the separatrix energy: tanh/sech, not elliptic.  The
    energy is that of the body solved, the inertia ``I``, through the second moments formed from it."""
    i, j, k = 2, 0, 1
    I = inertia(J)
    Jb = second_moments(I)
    Ii = Jb.sum() - Jb[i]
    rho = 0.5 * abs(A[k, k] - A[j, j])
    nu = np.sqrt(2 * abs(Jb[k] - Jb[j]) * rho / Ii)
    Q0 = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])   # exact quarter turn: stable
    sol = solve_rotation(I, A, Q0, [0, 0, nu])
    assert label(sol) == "elliptic:pendulum/separatrix"
    t = np.array([1.0, 5.0, 20.0])
    w, Q = sol(t)
    wr, Qr = integrate_rotation(I, A, Q0, [0, 0, nu], rtol=1e-13)(t)
    # the separatrix is unstable: the reference itself drifts off it like exp(nu t) * 1e-16
    assert np.abs(Q - Qr).max() < 1e-14 * np.exp(nu * t.max()) + 1e-12


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2), st.floats(-3.0, 3.0), st.floats(-2.0, 2.0),
       st.lists(st.floats(0.2, 2.0), min_size=3, max_size=3))
def test_property_invariants_and_orthogonality(axis, angle, spin, jj):
    Jr = np.sort(np.array(jj))
    if np.min(np.diff(Jr)) < 1e-3:
        return
    rot = np.zeros(3)
    rot[axis] = angle
    w0 = np.zeros(3)
    w0[axis] = spin
    sol = solve_rotation(inertia(Jr), A, rodrigues(rot), w0)
    assert sol.case.startswith("pendulum") or label(sol) == "elementary:rest"
    t = np.linspace(0.0, 40.0, 81)
    w, Q = sol(t)
    assert np.abs(np.swapaxes(Q, -1, -2) @ Q - np.eye(3)).max() < 1e-14
    e = invariants(inertia(np.diag(Jr)), A, Q, w)["energy"]
    assert np.abs(e - e[0]).max() <= 1e-12 * (1 + abs(e[0]))
