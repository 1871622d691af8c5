"""Corollary 5 made concrete: per-body LQR attitude controllers stabilize a whole orbiting station.

    PYTHONPATH=. python examples/station_lqr.py

The station of examples/orbiting_station.toml on its circular orbit (normalized units: mean motion
1, period 2 pi).  Each effective body gets its own target attitude, principal axes along the orbit
frame; the panel's target (long side along-track) is gravity-gradient UNSTABLE on its own.  Each
controller is an LQR designed on that effective body alone (thetasol.mechanics.attitude_control);
it is applied as a pure couple on the physical body, in the UNSPLIT station integrated in the exact
1/r field of its point masses.  Printed: the attitude errors without and with the controllers.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from thetasol.core.so3 import rodrigues
from thetasol.integrators.multibody_gravity import integrate_multibody_gravity
from thetasol.mechanics.attitude_control import station_controller
from thetasol.mechanics.gravity_gradient import orbit_frame
from thetasol.scenes.format import load_scene

SCENE = Path(__file__).with_name("orbiting_station.toml")


def targets(config):
    """Per body the axes to hold along (radial, along-track, normal): Lagrange for all but the panel."""
    out = {}
    for n, e in config.effective_bodies().items():
        ax = e.axes                                  # columns: J ascending, i.e. inertia descending
        cols = [1, 2, 0] if n == "panel" else [2, 1, 0]   # panel: least inertia along-track (unstable)
        B0 = ax[:, cols].copy()
        if np.linalg.det(B0) < 0:
            B0[:, 2] = -B0[:, 2]
        out[n] = B0
    return out


def initial_state(config, orbit, alignments, tilt=0.05, seed=1):
    """Attitudes ``tilt`` rad off each target (random axes), turning with the orbit frame."""
    rng = np.random.default_rng(seed)
    F = orbit_frame(orbit.r0, orbit.v0)
    n = orbit.diagnostics["mean_motion"]
    Q0, w0 = {}, {}
    for name, B0 in alignments.items():
        d = rng.normal(size=3)
        R = rodrigues(tilt * d / np.linalg.norm(d))
        Q0[name] = F @ R @ B0.T
        w0[name] = B0 @ (n * R.T[:, 2])              # omega_a = n R^T e3: no rate error
    return Q0, w0


def errors(traj, controller):
    """|theta| per body (rows) and time (columns)."""
    F = orbit_frame(traj.mass_center, traj.mass_center_velocity)
    out = []
    for i, n in enumerate(traj.names):
        theta, _ = controller.controllers[n].error(traj.attitude[i], traj.omega[i], F)
        out.append(np.linalg.norm(theta, axis=-1))
    return np.array(out)


def main(orbits: float = 4.0) -> dict:
    scene = load_scene(SCENE)
    cfg, orbit = scene.config, scene.orbit.orbit
    n = orbit.diagnostics["mean_motion"]
    B = targets(cfg)
    ctrl = station_controller(cfg, n, B)
    for name, c in ctrl.controllers.items():
        print(f"{name}: target {c.open_loop.region}, closed-loop eigenvalues real parts "
              f"{np.round(np.sort(c.closed_loop_eigenvalues.real), 3)} (units of n)")
    Q0, w0 = initial_state(cfg, orbit, B)
    T = 2 * np.pi / n
    t = np.linspace(0.0, orbits * T, int(8 * orbits) + 1)
    res = {}
    for label, torques in (("free", None), ("LQR", ctrl)):
        start = time.perf_counter()
        tr = integrate_multibody_gravity(cfg, orbit, Q0, w0, t, points=scene.orbit.points, torques=torques)
        e = errors(tr, ctrl)
        res[label] = e
        print(f"\n{label}: {time.perf_counter() - start:.1f} s; attitude error |theta| (rad) at whole orbits:")
        for i, name in enumerate(tr.names):
            print(f"  {name:6s}" + " ".join(f"{x:9.2e}" for x in e[i, ::8]))
    return res


if __name__ == "__main__":
    main()
