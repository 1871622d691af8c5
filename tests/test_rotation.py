"""solve_rotation: dispatch, the result protocol (shapes, M, u, immutability) and validation."""
import dataclasses

import numpy as np
import pytest
from conftest import label

from thetasol import RotationSolution, inertia, integrate_rotation, second_moments, solve_gyrostat, solve_rotation
from thetasol.core.so3 import hat, vee

Z = np.zeros((3, 3))
J = np.array([0.7, 1.1, 1.9])
W0 = np.array([0.3, -1.2, 0.5])


def test_dispatch_free_and_isotropic():
    assert label(solve_rotation(inertia(J), Z, np.eye(3), W0)) == "elliptic"
    assert label(solve_rotation(inertia(J), -3.0 * np.eye(3), np.eye(3), W0)) == "elliptic"
    assert isinstance(solve_rotation(inertia(J), Z, np.eye(3), W0), RotationSolution)


def test_spherical_body_in_a_potential_feels_no_torque():
    a = np.array([[1.0, 0.3, 0.0], [0.3, -0.5, 0.2], [0.0, 0.2, 0.4]])
    sol = solve_rotation(inertia([0.8, 0.8, 0.8]), a, np.eye(3), W0)
    assert type(sol).__name__ == "EulerTopSolution"
    w, Q = sol(np.array([3.0, 17.0]))
    wr, Qr = integrate_rotation(inertia([0.8, 0.8, 0.8]), a, np.eye(3), W0, rtol=1e-13)(np.array([3.0, 17.0]))
    assert np.abs(w - wr).max() <= 1e-12 and np.abs(Q - Qr).max() <= 1e-11


def test_potential_with_torque_uses_theta_functions():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(3, 3))
    sol = solve_rotation(inertia(J), a + a.T, np.eye(3), W0)
    assert label(sol) == "theta/genus-4"
    # a repeated eigenvalue of a (gravity gradient): the nodal curve of genus 3
    g = np.array([0.3, -0.5, 0.81])
    sol = solve_rotation(inertia(J), -3.0 * np.outer(g, g) / (g @ g), np.eye(3), W0)
    assert label(sol) == "theta/genus-3:nodal"
    # a symmetric body: the node over E = infinity, genus 3; with the rank-one a as well, genus 2
    assert label(solve_rotation(inertia([0.7, 0.7, 1.9]), a + a.T, np.eye(3), W0)) == "theta/genus-3:symmetric"
    sol = solve_rotation(inertia([0.7, 0.7, 1.9]), -3.0 * np.outer(g, g) / (g @ g), np.eye(3), W0)
    assert label(sol) == "theta/genus-2:symmetric-nodal"


def test_shapes_and_protocol():
    sol = solve_rotation(inertia(J), Z, np.eye(3), W0)
    for t in (0.5, np.arange(4.0), np.ones((2, 3)), np.array([])):
        tt = np.asarray(t)
        w, Q = sol(t)
        assert w.shape == tt.shape + (3,) and Q.shape == tt.shape + (3, 3)
        assert sol.omega(t).shape == tt.shape + (3,)
        assert sol.Q(t).shape == tt.shape + (3, 3)
        assert sol.M(t).shape == tt.shape + (3, 3)
        assert sol.u(t).shape == tt.shape + (3, 3)
    t = np.array([[0.1, 2.0], [5.0, -1.0]])
    w, Q = sol(t)
    assert np.array_equal(w, sol.omega(t)) and np.array_equal(Q, sol.Q(t))
    # M = J hat(w) + hat(w) J (4.5), |m|^2 = -1/2 tr M^2 (4.7)
    Jm = np.diag(J)
    assert np.allclose(sol.M(t), Jm @ hat(w) + hat(w) @ Jm, atol=1e-15)
    assert np.allclose(-0.5 * np.trace(sol.M(t) @ sol.M(t), axis1=-2, axis2=-1), sol.invariants["m2"], rtol=1e-14)
    assert np.allclose(vee(sol.M(t)), sol.m(t))


def test_u_follows_the_library_sign():
    a = 0.8 * np.eye(3)
    Q0 = np.linalg.qr(np.random.default_rng(0).normal(size=(3, 3)))[0]
    Q0 *= np.linalg.det(Q0)
    sol = solve_rotation(inertia(J), a, Q0, W0)
    t = np.array([0.0, 3.0])
    Q = sol.Q(t)
    assert np.allclose(sol.u(t), -np.swapaxes(Q, -1, -2) @ a @ Q)


def test_result_is_immutable():
    sol = solve_rotation(inertia(J), Z, np.eye(3), W0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        sol.method = "x"


def test_same_conventions_as_integrate_rotation():
    rng = np.random.default_rng(3)
    A = rng.normal(size=(3, 3))
    Jt = A @ A.T + 0.2 * np.eye(3)
    Q0 = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    Q0 *= np.linalg.det(Q0)
    w0 = rng.normal(size=3)
    t = np.array([-2.0, 0.0, 1.0, 3.0])
    w, Q = solve_rotation(inertia(Jt), Z, Q0, w0)(t)
    wr, Qr = integrate_rotation(inertia(Jt), Z, Q0, w0, rtol=1e-13, atol=1e-16)(t)
    assert np.max(np.abs(w - wr)) < 1e-11 and np.max(np.abs(Q - Qr)) < 1e-11


@pytest.mark.parametrize("kw, msg", [
    (dict(I=[1.0, np.nan, 2.0]), "NaN"),
    (dict(I=[1.0, 2.0]), "principal values"),
    (dict(I=[[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]), "symmetric"),
    (dict(I=[1.0, -2.0, 2.0]), "positive definite"),
    (dict(I=[1.0, 1.0, 3.0]), "triangle inequality"),
    (dict(a=np.ones((2, 2))), "shape"),
    (dict(Q0=2 * np.eye(3)), "orthogonal"),
    (dict(Q0=-np.eye(3)), "reflection"),
    (dict(omega0=[1.0, np.inf, 0.0]), "NaN or inf"),
    (dict(dps=3), "dps"),
])
def test_bad_input(kw, msg):
    args = dict(I=inertia(J), a=Z, Q0=np.eye(3), omega0=W0)
    args.update(kw)
    dps = args.pop("dps", None)
    with pytest.raises(ValueError, match=msg):
        solve_rotation(**args, dps=dps)


def test_second_moments_passed_as_inertia_name_the_mix_up():
    """[0.6, 1.0, 1.7] is no inertia (1.7 > 0.6 + 1.0) but valid second moments: the message says so and
    how to convert; a tensor that fails the same way (rotated) gets the same hint."""
    a = np.diag([0.4, -0.3, 1.1])
    with pytest.raises(ValueError, match=r"triangle inequality.*look like second moments.*thetasol\.inertia\(J\)"):
        solve_rotation([0.6, 1.0, 1.7], a, np.eye(3), W0)
    R = np.linalg.qr(np.array([[1.0, 0.3, -0.2], [0.1, 1.0, 0.4], [0.5, -0.2, 1.0]]))[0]
    R *= np.linalg.det(R)
    with pytest.raises(ValueError, match="look like second moments"):
        solve_rotation(R @ np.diag([0.6, 1.0, 1.7]) @ R.T, a, np.eye(3), W0)
    # the converted values are printed: inertia of J = (1, 1, 3) is (4, 4, 2)
    with pytest.raises(ValueError, match=r"thetasol\.inertia\(J\) = \[4, 4, 2\]"):
        solve_rotation([1.0, 1.0, 3.0], a, np.eye(3), W0)
    # a flat plate (I_3 = I_1 + I_2 to rounding) is a body
    assert solve_rotation([1.0, 2.0, 3.0], Z, np.eye(3), W0).I[2, 2] == 3.0


def test_inertia_valid_either_way_is_the_inertia():
    """[2, 3, 4] is a valid inertia and valid second moments: it is solved as the inertia, the body whose
    second moments are (2.5, 1.5, 0.5); principal values and the tensor in a rotated frame agree."""
    I = np.array([2.0, 3.0, 4.0])
    Q0 = np.eye(3)
    sol = solve_rotation(I, Z, Q0, W0)
    assert np.array_equal(sol.J, np.diag([2.5, 1.5, 0.5])) and np.array_equal(sol.I, np.diag(I))
    # the kinetic energy is that of the inertia (2, 3, 4), not of the body with second moments (2, 3, 4)
    assert sol.invariants["energy"] == pytest.approx(0.5 * W0 @ (I * W0), rel=1e-14)
    R = np.linalg.qr(np.array([[1.0, 0.3, -0.2], [0.1, 1.0, 0.4], [0.5, -0.2, 1.0]]))[0]
    R *= np.linalg.det(R)
    rot = solve_rotation(R @ np.diag(I) @ R.T, Z, Q0 @ R.T, R @ W0)
    t = np.array([0.0, 1.3, 17.0])
    assert np.allclose(rot.omega(t), sol.omega(t) @ R.T, rtol=0, atol=1e-12)
    assert np.allclose(rot.I, R @ np.diag(I) @ R.T, rtol=0, atol=1e-14)


@pytest.mark.parametrize("I", [np.array([2.7, 2.3, 1.6]), np.array([75.6, 97.5, 57.2])])   # the second is rescaled
@pytest.mark.parametrize("solve", [lambda I: solve_rotation(I, Z, np.eye(3), W0),
                                   lambda I: solve_rotation(I, np.diag([0.3, -0.2, 0.5]), np.eye(3), W0),
                                   lambda I: solve_gyrostat(I, [0.0, 0.0, 0.3], np.eye(3), W0)])
def test_I_is_the_inertia_given(I, solve):
    """``sol.I`` is the inertia passed, bit for bit (principal values as a diagonal), not ``tr(J) 1 - J``
    recomputed from the second moments, which for these bodies is an ulp off in an entry."""
    assert not np.array_equal(inertia(second_moments(I)), I)   # the round trip is not exact here
    assert np.array_equal(solve(I).I, np.diag(I))


def test_bad_times():
    sol = solve_rotation(inertia(J), Z, np.eye(3), W0)
    with pytest.raises(ValueError, match="NaN"):
        sol.omega([0.0, np.nan])
