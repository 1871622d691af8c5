"""The split as a solution object (thetasol.scenes.pipeline): any times, state arrays, first integrals.

References nobody here wrote for this object: the physical energy of every body summed from its own
mass, inertia, position and attitude (never the split's effective bodies), the maximal-coordinate
initial state of the unsplit multibody reference, and integrate_rotation.
"""
import dataclasses
import tomllib

import numpy as np
import pytest
from conftest import label
from test_scene import SMALL

from thetasol.core.inertia import inertia
from thetasol.integrators.multibody import initial_state
from thetasol.integrators.rotation import NumericalRotation, integrate_rotation
from thetasol.mechanics.equations import invariants
from thetasol.mechanics.trajectories import Trajectories
from thetasol.protocol import Solution
from thetasol.scenes.format import Scene
from thetasol.scenes.pipeline import ConfigurationSolution, solve_configuration
from thetasol.solutions.points.mass_center import MassCenterMotion


@pytest.fixture(scope="module")
def scene():
    return Scene.from_dict(tomllib.loads(SMALL))


@pytest.fixture(scope="module")
def closed(scene):
    return scene.solution()


@pytest.fixture(scope="module")
def numerical(scene):
    return solve_configuration(scene.config, scene.a, scene.b, scene.q0, scene.v0, scene.Q0, scene.omega0,
                               rotation="numerical", rtol=1e-13)


def physical_energy(cfg, a, b, X, V, Q, W):
    """Sum over the physical bodies of 1/2 m|v|^2 + m phi(x) + 1/2 w.I w + 1/2 tr(a Q J Q^T)."""
    E = 0.0
    for i, n in enumerate(cfg.order):
        B = cfg.bodies[n]
        phi = 0.5 * np.einsum("...i,ij,...j->...", X[i], a, X[i]) + 0.5 * X[i] @ b
        S = Q[i] @ B.J @ np.swapaxes(Q[i], -1, -2)
        E = E + 0.5 * B.mass * np.sum(V[i] ** 2, axis=-1) + B.mass * phi \
            + 0.5 * np.einsum("...i,ij,...j->...", W[i], B.I, W[i]) + 0.5 * np.trace(a @ S, axis1=-2, axis2=-1)
    return E


def test_protocol_and_parts(closed, scene):
    assert isinstance(closed, ConfigurationSolution) and isinstance(closed, Solution)
    with pytest.raises(dataclasses.FrozenInstanceError):
        closed.method = "x"
    assert isinstance(closed.mass_center, MassCenterMotion)
    assert list(closed.rotations) == scene.config.order == list(closed.names)
    assert (closed.model, closed.method) == ("configuration", "split")
    assert closed.diagnostics["parts"] == ("mass-center=elementary (trigonometric+hyperbolic); root=theta/genus-4, "
                                           "arm=elliptic (pendulum/libration), tip=theta/genus-4")
    d = closed.diagnostics
    assert d["rotation_kind"] == "theta"
    assert d["models"]["rotations"]["arm"] == "theta: closed form elliptic (pendulum/libration)"
    assert all(r["closed_form"] and r["reason"] == "" and r["setup_seconds"] > 0 for r in d["rotations"].values())
    assert d["setup_seconds"] >= sum(r["setup_seconds"] for r in d["rotations"].values())


def test_any_times_and_state_shapes(closed, numerical):
    """Unsorted and negative times; the closed-form split against the integrated one (DOP853, rtol 1e-13)."""
    t = np.array([-3.0, 5.0, 0.5, -1.0, 0.0, 12.0])
    traj = closed.trajectories(t)
    assert isinstance(traj, Trajectories) and np.array_equal(traj.t, t)
    dev = traj.deviation(numerical.trajectories(t))
    assert max(dev.values()) < 3e-12  # measured 2.9e-13 (attitude)
    # sorted times give the same values
    order = np.argsort(t)
    again = closed.trajectories(t[order])
    assert np.allclose(again.position, traj.position[:, order], rtol=0, atol=1e-14)  # measured 0
    # any shape: t.shape leading, then the body axis (.state is an alias)
    q, qd, x, v, Q, w = closed(t.reshape(2, 3))
    assert q.shape == qd.shape == (2, 3, 3) and x.shape == v.shape == w.shape == (2, 3, 3, 3)
    assert Q.shape == (2, 3, 3, 3, 3)
    assert np.array_equal(x.reshape(6, 3, 3).swapaxes(0, 1), traj.position)
    assert np.array_equal(Q.reshape(6, 3, 3, 3).swapaxes(0, 1), traj.attitude)
    assert np.array_equal(q.reshape(6, 3), traj.mass_center)
    q1 = closed.state(0.5)[0]
    assert q1.shape == (3,) and np.array_equal(q1, traj.mass_center[2])
    assert all(np.array_equal(a, b) for a, b in zip(closed.state(t), closed(t), strict=True))
    for bad in (t.reshape(2, 3), 0.5, np.array([])):
        with pytest.raises(ValueError, match="any shape"):
            closed.trajectories(bad)


def test_energy_is_the_physical_bodies_energy(closed, numerical, scene):
    """invariants["energy"] (mass centre + effective rotations) equals the energy of the physical bodies:
    at t = 0 from the unsplit reference's maximal coordinates, and all along both split solutions."""
    E0 = closed.invariants["energy"]
    x, v, Q, w = initial_state(scene.config, scene.q0, scene.v0, scene.Q0, scene.omega0)
    assert abs(physical_energy(scene.config, scene.a, scene.b, x, v, Q, w) - E0) < 2e-15 * abs(E0)  # measured 2.0e-16
    assert numerical.invariants["energy"] == E0
    t = np.linspace(0.0, 12.0, 25)
    for sol, bound in ((closed, 3e-14), (numerical, 3e-13)):  # measured 4.5e-15, 7.4e-14
        tr = sol.trajectories(t)
        E = physical_energy(scene.config, scene.a, scene.b, tr.position, tr.velocity, tr.attitude, tr.omega)
        assert np.max(np.abs(E - E0)) < bound * abs(E0)
    # the rotations' first integrals along the closed forms (measured <= 8.7e-15, the root's curve)
    tr = closed.trajectories(t)
    for i, n in enumerate(tr.names):
        inv = invariants(inertia(scene.config.effective_body(n).J), scene.a, tr.attitude[i], tr.omega[i])
        for k in ("energy", "I2", "I3", "curve"):
            ref = closed.invariants["rotations"][n][k]
            assert np.max(np.abs(inv[k] - ref)) < 1e-13 * (1 + np.max(np.abs(ref)))
    assert closed.invariants["mass_center"] is closed.mass_center.invariants


def test_numerical_rotations_on_demand(numerical, scene):
    """Bodies without a closed form integrate at the requested times, with the integrator's result."""
    t = np.array([7.0, -2.0, 0.0, 3.5])
    for n, rot in numerical.rotations.items():
        assert isinstance(rot, NumericalRotation) and label(rot) == "numerical/DOP853"
        e = scene.config.effective_body(n)
        w1, Q1 = rot(t)
        w2, Q2 = integrate_rotation(inertia(e.J), scene.a, scene.Q0[n], scene.omega0[n], rtol=1e-13)(t)
        # measured 0 (root, tip) and 5.4e-15 (arm: its Q0 from the scene is projected onto SO(3) once more)
        assert max(np.max(np.abs(w1 - w2)), np.max(np.abs(Q1 - Q2))) < 3e-14
        inv = invariants(inertia(e.J), scene.a, Q1, w1)
        # measured <= 3.6e-14 relative (root)
        assert np.max(np.abs(inv["energy"] - rot.invariants["energy"])) < 3e-13 * abs(rot.invariants["energy"])
    d = numerical.diagnostics["rotations"]
    assert all(not r["closed_form"] and r["reason"] == "rotation='numerical'" for r in d.values())
    assert numerical.diagnostics["parts"].startswith("mass-center=elementary (trigonometric+hyperbolic); "
                                                     "root=numerical/DOP853")


def test_bad_arguments(scene):
    args = (scene.config, scene.a, scene.b, scene.q0, scene.v0, scene.Q0, scene.omega0)
    with pytest.raises(ValueError, match="rotation must be"):
        solve_configuration(*args, rotation="exact")
    with pytest.raises(ValueError, match="Configuration"):
        solve_configuration("tree", *args[1:])
    with pytest.raises(TypeError):
        solve_configuration(*args, scene.t)  # the times go to the solution: solve_configuration(...)(t)
