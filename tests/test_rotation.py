"""solve_rotation: dispatch, the result protocol (shapes, M, u, immutability) and validation."""
import dataclasses

import numpy as np
import pytest

from thetasol import RotationSolution, integrate_rotation, solve_rotation
from thetasol.core.so3 import hat, vee
from thetasol.mechanics.equations import inertia

Z = np.zeros((3, 3))
J = np.array([0.7, 1.1, 1.9])
W0 = np.array([0.3, -1.2, 0.5])


def test_dispatch_free_and_isotropic():
    assert solve_rotation(J, Z, np.eye(3), W0).method == "euler-top/elliptic"
    assert solve_rotation(J, -3.0 * np.eye(3), np.eye(3), W0).method == "euler-top/elliptic"
    assert isinstance(solve_rotation(J, Z, np.eye(3), W0), RotationSolution)


def test_spherical_body_in_a_potential_feels_no_torque():
    a = np.array([[1.0, 0.3, 0.0], [0.3, -0.5, 0.2], [0.0, 0.2, 0.4]])
    sol = solve_rotation([0.8, 0.8, 0.8], a, np.eye(3), W0)
    assert sol.method.startswith("euler-top/")
    w, Q = sol(np.array([3.0, 17.0]))
    wr, Qr = integrate_rotation(inertia([0.8, 0.8, 0.8]), a, np.eye(3), W0, rtol=1e-13)(np.array([3.0, 17.0]))
    assert np.abs(w - wr).max() <= 1e-12 and np.abs(Q - Qr).max() <= 1e-11


def test_potential_with_torque_uses_theta_functions():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(3, 3))
    sol = solve_rotation(J, a + a.T, np.eye(3), W0)
    assert sol.method == "theta/genus-4"
    # a repeated eigenvalue of a (gravity gradient): the nodal curve of genus 3
    g = np.array([0.3, -0.5, 0.81])
    sol = solve_rotation(J, -3.0 * np.outer(g, g) / (g @ g), np.eye(3), W0)
    assert sol.method == "theta/nodal-genus-3"
    # a symmetric body: the node over E = infinity, genus 3; with the rank-one a as well, genus 2
    assert solve_rotation([0.7, 0.7, 1.9], a + a.T, np.eye(3), W0).method == "theta/symmetric-genus-3"
    sol = solve_rotation([0.7, 0.7, 1.9], -3.0 * np.outer(g, g) / (g @ g), np.eye(3), W0)
    assert sol.method == "theta/symmetric-nodal-genus-2"


def test_shapes_and_protocol():
    sol = solve_rotation(J, Z, np.eye(3), W0)
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
    sol = solve_rotation(J, a, Q0, W0)
    t = np.array([0.0, 3.0])
    Q = sol.Q(t)
    assert np.allclose(sol.u(t), -np.swapaxes(Q, -1, -2) @ a @ Q)


def test_result_is_immutable():
    sol = solve_rotation(J, Z, np.eye(3), W0)
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
    w, Q = solve_rotation(Jt, Z, Q0, w0)(t)
    wr, Qr = integrate_rotation(inertia(Jt), Z, Q0, w0, rtol=1e-13, atol=1e-16)(t)
    assert np.max(np.abs(w - wr)) < 1e-11 and np.max(np.abs(Q - Qr)) < 1e-11


@pytest.mark.parametrize("kw, msg", [
    (dict(J=[1.0, np.nan, 2.0]), "NaN"),
    (dict(J=[1.0, 2.0]), "principal values"),
    (dict(J=[[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]), "symmetric"),
    (dict(J=[1.0, -2.0, 2.0]), "not physical|positive"),
    (dict(a=np.ones((2, 2))), "shape"),
    (dict(Q0=2 * np.eye(3)), "orthogonal"),
    (dict(Q0=-np.eye(3)), "reflection"),
    (dict(omega0=[1.0, np.inf, 0.0]), "NaN or inf"),
    (dict(dps=3), "dps"),
])
def test_bad_input(kw, msg):
    args = dict(J=J, a=Z, Q0=np.eye(3), omega0=W0)
    args.update(kw)
    dps = args.pop("dps", None)
    with pytest.raises(ValueError, match=msg):
        solve_rotation(**args, dps=dps)


def test_bad_times():
    sol = solve_rotation(J, Z, np.eye(3), W0)
    with pytest.raises(ValueError, match="NaN"):
        sol.omega([0.0, np.nan])
