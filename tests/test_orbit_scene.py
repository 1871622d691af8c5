"""The [orbit] entry of scene files (Theorem 4) and its check against the unsplit station in the exact 1/r field.

References: DOP853 on the two-body problem, integrate_orbiting_rotation, and the UNSPLIT station of point
masses in the exact field -mu/|x| (integrators.multibody_gravity: maximal coordinates, no expansion), whose
own first integrals (energy, angular momentum) are checked here too.
"""
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from conftest import label

from thetasol.integrators.multibody_gravity import (
    PointMassGravity,
    box_mass_points,
    integrate_multibody_gravity,
    mass_points,
)
from thetasol.mechanics.bodies import Body
from thetasol.mechanics.configuration import Configuration
from thetasol.scenes.format import Scene, load_scene
from thetasol.scenes.orbit_report import scaled_station
from thetasol.scenes.report import run
from thetasol.solutions.orbit.kepler import KeplerOrbit

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "orbiting_station.toml"


def _raw():
    return tomllib.loads(EXAMPLE.read_text())


def test_example_models_and_stability_table():
    scene = load_scene(EXAMPLE)
    assert np.array_equal(scene.q0, [1.0, 0.0, 0.0]) and np.array_equal(scene.v0, [0.0, 1.0, 0.0])
    sol = scene.solution()
    closed = {n: r["closed_form"] for n, r in sol.diagnostics["rotations"].items()}
    assert closed == {"core": False, "dock": True, "truss": False, "panel": True}
    assert label(sol.rotations["dock"]) == "elementary:relative-equilibrium"
    assert label(sol.rotations["panel"]) == "elliptic:pitch/libration"
    regions = {n: b.stability.region for n, b in sol.stability.items()}
    assert regions == {"core": "lagrange", "dock": "lagrange", "truss": "lagrange", "panel": "lagrange"}
    assert sol.stability["dock"].angle < 1e-12
    assert abs(sol.stability["panel"].angle - 0.3) < 1e-12     # pitched by 0.3 rad about a principal axis
    traj = sol.trajectories(scene.t)
    # the system mass centre of the placed bodies is the Kepler orbit
    m = np.array([scene.config.bodies[n].mass for n in traj.names])
    q = np.einsum("n,nti->ti", m, traj.position) / m.sum()
    assert np.max(np.abs(q - traj.mass_center)) < 1e-15 * 10


def test_report_split_against_exact_field_scales_as_size_squared():
    """The report runs the unsplit station at the scene's size and at half of it (L/R = 5.2e-3, 2.6e-3)."""
    traj, text, checks = run(load_scene(EXAMPLE))
    assert all(c.ok for c in checks), text
    assert "verdict: all checks passed" in text
    ratio = next(c for c in checks if "log2(position ratio)" in c.what)
    # measured |log2 ratio - 2| = 7.5e-5 (ratio 4.000): the quadrupole force the Kepler orbit leaves out
    assert ratio.deviation < 3e-4
    line = next(ln for ln in text.splitlines() if "attitude difference by" in ln)
    att_exponent = float(line.split("exponent ")[-1].rstrip(")"))
    # measured 1.038: the station's octupole torque, O(L/R)
    assert abs(att_exponent - 1.0) < 0.1
    orbit_line = next(c for c in checks if c.what.startswith("orbit:"))
    assert orbit_line.deviation < 2e-12                        # measured 4.6e-13


def test_split_and_unsplit_differ_by_size_squared_at_two_orbit_radii():
    """Same station, orbit radius 1 and 2 (same orbital periods elapsed): position difference / R ~ (L/R)^2."""
    out = []
    for R in (1.0, 2.0):
        d = _raw()
        d["orbit"] = {"mu": 1.0, "r0": [R, 0.0, 0.0], "v0": [0.0, R ** -0.5, 0.0]}
        d["output"] = {"times": [0.0, 2 * math.pi * R ** 1.5]}
        d["initial"]["omega"] = {k: (np.array(v) * R ** -1.5).tolist() for k, v in d["initial"]["omega"].items()}
        sc = Scene.from_dict(d)
        tr = sc.solve()
        mb = integrate_multibody_gravity(sc.config, KeplerOrbit(1.0, sc.q0, sc.v0), sc.Q0, sc.omega0, sc.t,
                                         points=sc.orbit.points)
        out.append(float(np.max(np.abs(tr.position - mb.position))) / R)
    # (L/R)^2 drops by 4 when R doubles: measured 1.53e-4 and 3.82e-5, ratio 4.0008
    assert out[0] / out[1] == pytest.approx(4.0, rel=0.01), out


@pytest.mark.parametrize("edit, message", [
    (lambda d: d.update(potential={"a": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}), "exclude each other"),
    (lambda d: d.update(constraint={"type": "sphere", "radius": 1.0}), "exclude each other"),
    (lambda d: d["initial"].update(q=[1.0, 0.0, 0.0]), "remove initial.q"),
    (lambda d: d["orbit"].pop("mu"), "needs 'mu'"),
    (lambda d: d["orbit"].update(mu=-1.0), "positive"),
    (lambda d: d["orbit"].update(v0=[1.0, 0.0, 0.0]), "radial"),
    (lambda d: d["orbit"].update(e=0.1), "unknown key"),
    (lambda d: d["orbit"].update(r0=[1.0, float("nan"), 0.0]), "orbit.r0"),
    (lambda d: d.update(solver={"method": "splitting"}), "not offered on an orbit"),
])
def test_orbit_entry_errors(edit, message):
    d = _raw()
    edit(d)
    with pytest.raises(ValueError, match=message):
        Scene.from_dict(d)


def test_elliptic_orbit_scene_is_numerical_with_no_stability_table():
    d = _raw()
    d["orbit"] = {"mu": 1.0, "r0": [1.0, 0.0, 0.0], "v0": [0.0, 1.2, 0.1]}
    d["output"] = {"t_end": 3.0, "samples": 31}
    d["solver"] = {"check_multibody": False}
    sc = Scene.from_dict(d)
    sol = sc.solution()
    assert sol.stability == {}
    assert not any(r["closed_form"] for r in sol.diagnostics["rotations"].values())
    traj, text, checks = run(sc)
    assert all(c.ok for c in checks) and "not circular" in text


# -- the unsplit reference in the exact field ------------------------------------------------------

def test_box_points_have_the_box_moments():
    m, p = box_mass_points(2.0, [1.0, 2.0, 3.0], [0.1, -0.2, 0.3])
    b = Body.from_point_masses(m, p)
    assert b.mass == pytest.approx(2.0, rel=1e-15)
    assert np.allclose(b.center, [0.1, -0.2, 0.3], atol=1e-15)
    assert np.allclose(b.J, Body.box(2.0, [1.0, 2.0, 3.0]).J, rtol=1e-14, atol=1e-15)
    d = p - b.center
    assert np.einsum("k,k->", m, d[:, 2] ** 4) == pytest.approx(2.0 * 3.0 ** 4 / 80, rel=1e-14)  # int x^4 = m l^4/80


def test_six_points_have_the_body_moments():
    body = Body(mass=3.0, J=[[1.0, 0.2, 0.0], [0.2, 2.0, 0.1], [0.0, 0.1, 0.5]], center=[1.0, 2.0, 3.0])
    m, p = mass_points(body)
    b = Body.from_point_masses(m, p)
    assert np.allclose(b.J, body.J, rtol=1e-14, atol=1e-14) and np.allclose(b.center, body.center, atol=1e-14)


def test_point_masses_must_match_the_body():
    cfg = Configuration([Body(mass=1.0, J=[1, 2, 3], name="a")])
    with pytest.raises(ValueError, match="mass and mass centre"):
        PointMassGravity(cfg, 1.0, {"a": (np.array([0.5]), np.zeros((1, 3)))})
    with pytest.raises(ValueError, match="unknown"):
        PointMassGravity(cfg, 1.0, {"b": (np.array([1.0]), np.zeros((1, 3)))})


def test_unsplit_station_conserves_energy_and_angular_momentum():
    """The exact-field loads are conservative and central: an independent check of forces AND torques."""
    scene = load_scene(EXAMPLE)
    cfg, pts = scaled_station(scene.config, scene.orbit.points, 20.0)     # L/R ~ 0.1: strong tidal coupling
    t = np.linspace(0.0, 4.0, 9)
    tr = integrate_multibody_gravity(cfg, KeplerOrbit(1.0, scene.q0, scene.v0), scene.Q0, scene.omega0, t, points=pts)
    grav = PointMassGravity(cfg, 1.0, pts)
    E, L = [], []
    for k in range(t.size):
        x, v, Q, w = tr.position[:, k], tr.velocity[:, k], tr.attitude[:, k], tr.omega[:, k]
        X = x[grav.idx] + np.einsum("kij,kj->ki", Q[grav.idx], grav.dk)
        Iw = np.einsum("nij,nj->ni", np.array([cfg.bodies[n].I for n in cfg.order]), w)
        E.append(0.5 * grav.m @ np.sum(v * v, 1) + 0.5 * np.sum(w * Iw)
                 - np.sum(grav.mk / np.linalg.norm(X, axis=1)))
        L.append(np.sum(grav.m[:, None] * np.cross(x, v), 0) + np.einsum("nij,nj->i", Q, Iw))
    E, L = np.array(E), np.array(L)
    # measured drift 3.6e-15 (energy; the rotational part is 1.7e-3 of it) and 1.8e-15 (angular momentum)
    assert np.max(np.abs(E - E[0])) < 2e-14 * abs(E[0])
    assert np.max(np.abs(L - L[0])) < 1e-14 * np.linalg.norm(L[0])


def test_single_small_body_follows_kepler():
    cfg = Configuration([Body.box(1.0, [2e-5, 1e-5, 5e-6], name="a")])
    t = [0.0, 2 * math.pi]
    tr = integrate_multibody_gravity(cfg, KeplerOrbit(1.0, [1, 0, 0], [0, 1, 0]), {}, {"a": [0, 0, 1.0]}, t)
    # (L/R)^2 = 4e-10: the quadrupole force moves the mass centre by ~1e-9 in one orbit
    assert np.max(np.abs(tr.mass_center[-1] - [1, 0, 0])) < 3e-9


def test_scaled_station_is_central_and_scaled():
    scene = load_scene(EXAMPLE)
    cfg, pts = scaled_station(scene.config, scene.orbit.points, 0.5)
    cfg.check_central()
    for n in cfg.order:
        assert np.allclose(cfg.effective_body(n).J, 0.25 * scene.config.effective_body(n).J, rtol=1e-14, atol=0)
    assert set(pts) == set(scene.orbit.points)


def test_leo_station_in_si_units():
    """The example scaled to a 52 m, 14.8 t station on a 400 km circular orbit (SI units)."""
    mu, R = 3.986004418e14, 6778137.0
    n, s = math.sqrt(mu / R ** 3), 1e4
    d = _raw()
    d["orbit"] = {"mu": mu, "r0": [R, 0.0, 0.0], "v0": [0.0, math.sqrt(mu / R), 0.0]}
    for b in d["bodies"]:
        for k in ("box", "center"):
            if k in b:
                b[k] = [x * s for x in b[k]]
        if "points" in b:
            b["points"] = [[x * s for x in p] for p in b["points"]]
            b["masses"] = [m * 1e3 for m in b["masses"]]
        else:
            b["mass"] *= 1e3
    for j in d["joints"]:
        j["parent_point"] = [x * s for x in j["parent_point"]]
    d["initial"]["omega"] = {k: [x * n for x in v] for k, v in d["initial"]["omega"].items()}
    d["output"] = {"t_end": 4 * math.pi / n, "samples": 101}
    traj, text, checks = run(Scene.from_dict(d))
    assert all(c.ok for c in checks), text
    # measured: positions 4.50e-3 m = 11.1 (L/R)^2 R at L/R = 7.7e-6, ratio 4.000 (|log2 ratio - 2| = 2.1e-7)
    assert next(c for c in checks if "log2" in c.what).deviation < 2e-6
    pos = float(next(ln for ln in text.splitlines() if "size x1:" in ln).split("positions ")[1].split()[0])
    assert 3e-3 < pos < 6e-3


def test_hyperbolic_orbit_scene_against_exact_field():
    """Any conic: a hyperbolic fly-by (e = 1.57), every rotation numerical, the split still within (L/R)^2."""
    d = _raw()
    d["orbit"] = {"mu": 1.0, "r0": [1.0, 0.0, 0.0], "v0": [0.0, 1.6, 0.1]}
    d["output"] = {"t_end": 3.0, "samples": 11}
    traj, text, checks = run(Scene.from_dict(d))
    assert all(c.ok for c in checks), text
    assert "hyperbolic" in text and "not circular" in text
    # measured ratio 4.000 (|log2 ratio - 2| = 1.7e-4), attitude exponent 1.001
    assert next(c for c in checks if "log2" in c.what).deviation < 5e-4


def test_tiny_station_is_checked_against_the_reference_resolution():
    """L/R ~ 5e-9: the truncation (~1e-16 R) is below what the unsplit integration resolves."""
    d = _raw()
    for b in d["bodies"]:
        for k in ("box", "center"):
            if k in b:
                b[k] = [x * 1e-6 for x in b[k]]
        if "points" in b:
            b["points"] = [[x * 1e-6 for x in p] for p in b["points"]]
    for j in d["joints"]:
        j["parent_point"] = [x * 1e-6 for x in j["parent_point"]]
    d["output"] = {"t_end": 3.0, "samples": 4}
    traj, text, checks = run(Scene.from_dict(d))
    assert all(c.ok for c in checks), text
    assert "not measurable here" in text
