"""Corollary 5: LQR attitude controllers designed per effective body, applied to the unsplit station.

References: the nonlinear gravity-gradient equations written out here (finite-difference Jacobian),
the algebraic Riccati equation itself, and the UNSPLIT station of point masses in the exact 1/r field.
"""
import importlib.util
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from thetasol.core.inertia import inertia
from thetasol.core.so3 import rodrigues
from thetasol.integrators.multibody_gravity import integrate_multibody_gravity
from thetasol.mechanics.attitude_control import (
    gravity_gradient_linearization,
    lqr_attitude_controller,
    station_controller,
)
from thetasol.mechanics.gravity_gradient import gravity_gradient_stability
from thetasol.scenes.format import load_scene
from thetasol.scenes.orbit_report import scaled_station

ROOT = Path(__file__).resolve().parent.parent
BODIES = {"lagrange": [1.25, 0.75, 0.25], "debra-delp": [0.475, 0.175, 0.525], "unstable": [0.5, 1.5, 0.25],
          "pitch-unstable": [0.75, 1.25, 0.25]}


def _demo():
    spec = importlib.util.spec_from_file_location("station_lqr", ROOT / "examples" / "station_lqr.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _nonlinear(J, n, x, u=(0.0, 0.0, 0.0)):
    """(theta, rate)' of a body in the orbit frame: omega = rate + n R^T e3, torque 3 n^2 g x I g, g = R^T e1."""
    I = np.diag(np.sum(J) - np.asarray(J))
    th, rate = x[:3], x[3:]
    R = Rotation.from_rotvec(th).as_matrix()
    w = rate + n * R[2, :]
    g = R[0, :]
    wd = np.linalg.solve(I, -np.cross(w, I @ w) + 3 * n * n * np.cross(g, I @ g) + u)
    t = np.linalg.norm(th)
    H = np.array([[0, -th[2], th[1]], [th[2], 0, -th[0]], [-th[1], th[0], 0]])
    thd = rate if t == 0 else rate + 0.5 * H @ rate + (1 - (t / 2) / np.tan(t / 2)) / t ** 2 * H @ H @ rate
    return np.r_[thd, wd + n * np.cross(rate, R[2, :])]


@pytest.mark.parametrize("region", sorted(BODIES))
def test_linearization_is_the_jacobian_of_the_nonlinear_equations(region):
    J, n, h = np.array(BODIES[region]), 1.3, 1e-5
    A, B = gravity_gradient_linearization(inertia(J), n)
    jac = np.array([(_nonlinear(J, n, h * e) - _nonlinear(J, n, -h * e)) / (2 * h) for e in np.eye(6)]).T
    jac_u = np.array([(_nonlinear(J, n, np.zeros(6), h * e) - _nonlinear(J, n, np.zeros(6), -h * e)) / (2 * h)
                      for e in np.eye(3)]).T
    # measured 6.7e-11 (A, central differences' own error at h = 1e-5) and 1.7e-16 (B)
    assert np.max(np.abs(jac - A)) < 3e-10 * np.max(np.abs(A))
    assert np.max(np.abs(jac_u - B)) < 1e-14 * np.max(np.abs(B))
    ev = np.linalg.eigvals(A)
    ref = gravity_gradient_stability(inertia(J), n).eigenvalues
    assert max(np.min(np.abs(ref - e)) for e in ev) < 1e-12 * n
    assert max(np.min(np.abs(ev - r)) for r in ref) < 1e-12 * n


@pytest.mark.parametrize("region", sorted(BODIES))
def test_lqr_solves_the_riccati_equation_and_stabilizes(region):
    J, n = np.array(BODIES[region]), 0.7
    c = lqr_attitude_controller(inertia(J), n)
    assert c.open_loop.region == {"pitch-unstable": "unstable"}.get(region, region)
    Qw = np.diag(np.r_[np.ones(3), np.full(3, n ** -2)])
    Rw = np.diag((n * n * c.inertia) ** -2.0)
    res = c.A.T @ c.P + c.P @ c.A - c.P @ c.B @ np.linalg.solve(Rw, c.B.T @ c.P) + Qw
    assert np.max(np.abs(res)) < 1e-9 * np.max(np.abs(Qw))
    assert np.max(c.closed_loop_eigenvalues.real) < -0.5 * n        # measured <= -0.56 n over the four bodies


def test_error_and_torque_in_a_rotated_body_frame():
    J = np.array([1.25, 0.75, 0.25])
    B0 = rodrigues([0.3, -0.2, 1.0])                  # body frame turned from the principal one
    c = lqr_attitude_controller(inertia(B0 @ np.diag(J) @ B0.T), 1.0, alignment=B0)
    F = rodrigues([0.1, 0.5, -0.4])
    theta = np.array([0.01, -0.02, 0.03])
    R = rodrigues(theta)
    rate = np.array([0.002, 0.001, -0.003])
    Q = F @ R @ B0.T
    w = B0 @ (rate + R.T[:, 2])
    th, rt = c.error(Q, w, F)
    assert np.allclose(th, theta, atol=1e-15) and np.allclose(rt, rate, atol=1e-15)
    assert np.allclose(c.torque(Q, w, F), B0 @ (-c.K @ np.r_[theta, rate]), atol=1e-15)
    with pytest.raises(ValueError, match="not principal"):
        lqr_attitude_controller(inertia(B0 @ np.diag(J) @ B0.T), 1.0, alignment=np.eye(3))
    with pytest.raises(ValueError, match="needs the alignment"):
        lqr_attitude_controller(inertia(np.diag(J)), 1.0)


def _run(demo, scale, torques_on, orbits):
    scene = load_scene(demo.SCENE)
    cfg, pts = scaled_station(scene.config, scene.orbit.points, scale)
    orbit = scene.orbit.orbit
    B = demo.targets(cfg)
    ctrl = station_controller(cfg, 1.0, B)
    Q0, w0 = demo.initial_state(cfg, orbit, B)
    t = np.linspace(0.0, orbits * 2 * np.pi, int(4 * orbits) + 1)
    tr = integrate_multibody_gravity(cfg, orbit, Q0, w0, t, points=pts, torques=ctrl if torques_on else None)
    return dict(zip(tr.names, demo.errors(tr, ctrl), strict=True)), ctrl


def test_separately_designed_controllers_stabilize_the_unsplit_station():
    demo = _demo()
    free, ctrl = _run(demo, 1.0, False, 1.0)
    assert ctrl.controllers["panel"].open_loop.region == "unstable"
    # without control the panel (gravity-gradient unstable target) departs: measured 3.09 rad after one
    # orbit; the others stay near their Lagrange attitudes (measured <= 0.061 rad from 0.05)
    assert free["panel"][-1] > 1.0
    assert max(np.max(free[n]) for n in ("core", "dock", "truss")) < 0.1
    on, _ = _run(demo, 1.0, True, 3.0)
    half, _ = _run(demo, 0.5, True, 3.0)
    for n in on:
        assert on[n][0] == pytest.approx(0.05, rel=1e-12)
        # after 3 orbits every body is within its floor: measured 5.0e-4 (core), 9.3e-5 (dock),
        # 1.5e-3 (truss), 1.4e-3 (panel) rad
        assert on[n][-1] < 2e-3
        # the floor is the station's octupole torque, which no single-body design sees: O(L/R), so it
        # halves with the station (measured ratios 1.984-2.003)
        assert on[n][-1] / half[n][-1] == pytest.approx(2.0, rel=0.03), (n, on[n][-1], half[n][-1])
