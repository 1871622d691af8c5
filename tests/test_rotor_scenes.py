"""Scenes with rotors: the split of Theorem 5 against the unsplit multibody system with rotors on revolute
joints (and shafts on a Hooke joint, CU^1), free and in a quadratic potential.

The reference (thetasol.integrators.multibody_rotors) knows nothing of effective gyrostats, rotor momenta
or the Routh reduction: every carrier and rotor is a body, every joint a constraint.  The bundled
spacecraft (4 carriers, 3 rotors, the turntable carrying the probe) and Hooke scenes are run to t = 10
here and to t = 40 (many rotor turns) in the slow tests.
"""
import re
import tomllib

import numpy as np
import pytest

from thetasol.core.inertia import inertia
from thetasol.integrators.multibody_rotors import integrate_gyrostat_multibody
from thetasol.scenes.format import demo_scene_path, load_scene
from thetasol.scenes.gyrostat_scene import GyrostatScene, gyrostat_scene_from_dict, run_gyrostat_scene
from thetasol.scenes.report import run

DATA = demo_scene_path().parent


def _scene(name, free, t_end):
    d = tomllib.loads((DATA / f"{name}.toml").read_text())
    if free:
        d["potential"] = {"a": [[0.0] * 3] * 3, "b": [0.0] * 3}
    d["output"] = {"t_end": t_end, "samples": int(10 * t_end) + 1}
    return gyrostat_scene_from_dict(d, name)


# measured at t <= 10: spacecraft free 2.8e-15 / 1.4e-14 / 1.4e-14 (positions / attitudes / rotor angles),
# in the potential 1.4e-12 / 2.4e-12 / 3.1e-13; Hooke free 1.2e-14 / 5.6e-14 / 5.6e-14, in the potential
# 3.8e-13 / 1.5e-12 / 1.2e-12.
@pytest.mark.parametrize("name,free,bound", [("spacecraft", True, 1e-12), ("spacecraft", False, 2e-11),
                                             ("hooke", True, 1e-12), ("hooke", False, 2e-11)])
def test_split_against_unsplit_multibody(name, free, bound):
    scene = _scene(name, free, 10.0)
    traj, text, checks = run_gyrostat_scene(scene)
    assert [c[0] for c in checks] == ["positions", "attitudes", "rotor angles"]
    for what, dev, tol in checks:
        assert dev < bound, (what, dev)
        assert dev <= tol
    assert "verdict: all checks passed" in text
    models = " ".join(traj.info["models"].values())
    assert ("gyrostat (8.39): closed form" in models) == free


@pytest.mark.slow
@pytest.mark.parametrize("name,free", [("spacecraft", True), ("spacecraft", False), ("hooke", True),
                                       ("hooke", False)])
def test_split_against_unsplit_multibody_many_periods(name, free):
    """The acceptance (1e-9) to t = 40, 25 turns of the fastest wheel: measured <= 3.6e-12 (Hooke in the
    potential), <= 1.3e-13 free."""
    _, _, checks = run_gyrostat_scene(_scene(name, free, 40.0))
    for what, dev, _ in checks:
        assert dev < 2e-11, (what, dev)


def test_rotor_momenta_constant_along_the_reference():
    """p = A (omega . l + phidot) (8.25) of the wheels, read off the unsplit reference: constant."""
    scene = _scene("spacecraft", False, 5.0)
    mb = integrate_gyrostat_multibody(scene.config, scene.a, scene.b, scene.q0, scene.v0, scene.Q0, scene.omega0,
                                      scene.t, rtol=1e-13)
    for wheel in ("wheel_x", "wheel_yz"):
        r = scene.config.rotors[wheel]
        i = mb.names.index(wheel)
        p = mb.omega[i] @ r.body.I @ r.axis
        split = scene.config.initial_momenta(scene.omega0)[r.carrier][scene.config.rotors_of[r.carrier].index(wheel)]
        assert abs(p[0] - split) < 1e-15 * abs(split) * 10
        assert np.max(np.abs(p - p[0])) < 1e-14 * abs(p[0])   # measured 5.0e-16 relative


def test_bundled_scenes_load_through_load_scene_and_report():
    sc = load_scene(DATA / "hooke.toml")
    assert isinstance(sc, GyrostatScene)
    traj, text, checks = run(sc, check=False)
    assert checks == [] and "cross" in text and traj.names == ("shaft_1", "shaft_2")
    sp = load_scene(DATA / "spacecraft.toml")
    assert sp.config.body_names == ["bus", "wheel_x", "wheel_yz", "boom", "turntable", "panel", "probe"]
    # the carriers with rotors are integrated, and the report says why (a is not isotropic)
    _, text, _ = run(sp, check=False, references=False)
    models = [line for line in text.splitlines() if "model: gyrostat (8.32): integrate_gyrostat" in line]
    assert len(models) == 2 and all("no closed form: the potential is not isotropic" in m for m in models)


@pytest.mark.parametrize("where, value, match", [
    (("rotors", 0, "mass"), "1.5", "rotor 'wheel_x': mass must be a number, got '1.5'"),
    (("rotors", 0, "point"), [0.5, "0.2", 0.1], "rotor 'wheel_x': point must be numbers, got '0.2'"),
    (("bodies", 0, "mass"), "40", "body 'bus': mass must be a number"),
    (("output", "t_end"), "40", "output.t_end must be a number"),
    (("solver", "check_rtol"), "1e-13", "solver.check_rtol must be a number"),
])
def test_strings_are_not_numbers_in_rotor_scenes(where, value, match):
    d = tomllib.loads((DATA / "spacecraft.toml").read_text())
    *path, key = where
    node = d
    for k in path:
        node = node[k]
    node[key] = value
    with pytest.raises(ValueError, match=re.escape(match)) as err:
        gyrostat_scene_from_dict(d, "myfile")
    assert str(err.value).startswith("myfile: ")


def test_scene_errors_name_the_file_and_the_reason():
    d = tomllib.loads((DATA / "spacecraft.toml").read_text())
    d["rotors"][0] = {**d["rotors"][0], "B": 0.01, "A": 0.03}
    with pytest.raises(ValueError, match=r"myfile: rotor 'wheel_x': need 0 < A <= 2 B"):
        gyrostat_scene_from_dict(d, "myfile")
    d = tomllib.loads((DATA / "spacecraft.toml").read_text())
    d["rotors"][2]["center"] = [1.0, -0.1, 0.0]
    with pytest.raises(ValueError, match=r"rotor 'turntable'.*off its axis"):
        gyrostat_scene_from_dict(d, "f")
    d = tomllib.loads((DATA / "spacecraft.toml").read_text())
    d["rotors"][1]["colour"] = "red"
    with pytest.raises(ValueError, match="unknown key"):
        gyrostat_scene_from_dict(d, "f")


def test_split_state_shapes_and_first_integrals():
    """state(t) on any shape; (8.34) of every effective gyrostat and (8.40) of the free ones along the split."""
    from thetasol.mechanics.rotors import gyrostat_energy

    for free in (True, False):
        scene = _scene("spacecraft", free, 10.0)
        sol = scene.solution()
        t = np.linspace(0.0, 10.0, 6).reshape(2, 3)
        q, qd, pos, vel, att, om, phi = sol.state(t)
        assert q.shape == (2, 3, 3) and pos.shape == (2, 3, 7, 3) and att.shape == (2, 3, 7, 3, 3)
        assert phi.shape == (2, 3, 3)
        traj = sol.trajectories(t.ravel())
        assert np.array_equal(traj.position, np.moveaxis(pos.reshape(6, 7, 3), 0, 1))
        W, Qs, _, _ = sol.evaluate_parts(np.linspace(0.0, 10.0, 51))
        for n, e in scene.config.effective_gyrostats().items():
            E = gyrostat_energy(inertia(e.J), e.I_gyro, scene.a, Qs[n], W[n])
            # measured <= 7.2e-15 (closed forms), 5.4e-13 (integrated at rtol 1e-12)
            assert np.max(np.abs(E - sol.invariants["energies"][n])) < (3e-12 if e.rotors and not free else 3e-14) \
                * abs(E[0])
            if free and e.rotors:
                h = W[n] @ e.I_gyro + e.N(sol.momenta[n])
                h2 = np.sum(h * h, axis=1)
                assert np.max(np.abs(h2 - h2[0])) < 5e-15 * h2[0]   # measured 6.5e-16


def test_cli_solves_a_rotor_scene(tmp_path, capsys):
    from thetasol.cli import main

    out = tmp_path / "hooke.npz"
    assert main(["solve", str(DATA / "hooke.toml"), "--no-check", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "effective gyrostats (8.17), (8.23)" in text and "(8.34) energy" in text
    with np.load(out) as f:
        assert f["position"].shape[0] == 2
