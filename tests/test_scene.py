"""Scene files, the split pipeline and its report (thetasol.scenes.format, .pipeline, .report)."""
import sys
import textwrap
import types
from pathlib import Path

import numpy as np
import pytest

from thetasol import integrate_rotation, second_moments
from thetasol.core.inertia import inertia
from thetasol.integrators.multibody import initial_state
from thetasol.mechanics.trajectories import Trajectories, write_trajectories
from thetasol.scenes.format import Scene, demo_scene_path, load_scene
from thetasol.scenes.pipeline import rotation_kind
from thetasol.scenes.report import run

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "satellite_boom.toml"

SMALL = """
name = "small"
[potential]
a = [[1.0, 0.2, 0.0], [0.2, 0.5, 0.0], [0.0, 0.0, -0.1]]
b = [0.1, 0.0, 0.0]
[[bodies]]
name = "root"
mass = 4.0
I = [2.0, 2.5, 3.0]
[[bodies]]
name = "arm"
mass = 1.0
box = [1.0, 0.2, 0.2]
[[bodies]]
name = "tip"
mass = 0.5
J = [0.02, 0.03, 0.04]
center = [0.0, 0.1, 0.0]
[[joints]]
parent = "root"
child = "arm"
parent_point = [1.0, 0.0, 0.0]
child_point = "central"
[[joints]]
parent = "arm"
child = "tip"
parent_point = [0.5, 0.0, 0.0]
child_point = [0.0, 0.1, 0.0]
[initial]
q = [0.1, 0.2, 0.0]
v = [0.0, 0.1, 0.0]
[initial.attitude]
arm = [0.0, 0.0, 0.4]
tip = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
[initial.omega]
root = [0.1, 0.2, 0.3]
tip = [1.0, 0.0, 0.5]
[output]
t_end = 4.0
samples = 41
"""


def write(tmp_path, text, name="scene.toml"):
    p = tmp_path / name
    p.write_text(textwrap.dedent(text))
    return p


def test_demo_scene_is_a_c2_central_station():
    sc = load_scene(demo_scene_path())
    cfg = sc.config
    assert len(cfg) >= 4 and cfg.depth >= 2 and cfg.is_central()
    ev = np.linalg.eigvalsh(sc.a)
    assert np.min(np.diff(ev)) > 0.1 * np.max(np.abs(ev))  # distinct eigenvalues
    assert rotation_kind(sc.a) == "theta"
    assert sc.t[0] == 0 and np.all(np.diff(sc.t) > 0)


def test_load_solve_and_initial_state(tmp_path):
    sc = load_scene(write(tmp_path, SMALL))
    assert sc.config.order == ["root", "arm", "tip"]
    assert np.allclose(sc.config.joints["arm"].child_point, sc.config.effective_body("arm").center)
    assert np.allclose(sc.Q0["tip"], [[0, -1, 0], [1, 0, 0], [0, 0, 1]])
    assert np.array_equal(sc.omega0["arm"], np.zeros(3))
    traj = sc.solve()
    assert isinstance(traj, Trajectories)
    assert traj.position.shape == (3, 41, 3) and traj.attitude.shape == (3, 41, 3, 3)
    x, v, Q, w = initial_state(sc.config, sc.q0, sc.v0, sc.Q0, sc.omega0)
    # the rotations (closed forms where solve_rotation gives one) reproduce the initial state to 1e-13
    assert np.allclose(traj.position[:, 0], x, rtol=0, atol=1e-13)
    assert np.allclose(traj.velocity[:, 0], v, rtol=0, atol=1e-13)
    assert np.allclose(traj.attitude[:, 0], Q, rtol=0, atol=1e-13)
    assert np.allclose(traj.mass_center[0], sc.q0)
    models = traj.info["models"]
    assert [k for _, k in models["mass_center"]] == ["hyperbolic", "trigonometric", "trigonometric"]
    assert all("closed form" in m for m in models["rotations"].values())
    # the arm (a symmetric box at rest) turns as a pendulum; the tip is generic: genus 4, and so is the root,
    # whose principal axis z is an eigenvector of a
    assert models["rotations"]["root"].endswith("closed form theta/genus-4")
    assert models["rotations"]["arm"].endswith("closed form elliptic (pendulum/libration)")
    assert models["rotations"]["tip"].endswith("closed form theta/genus-4")


def test_run_report_and_checks(tmp_path):
    sc = load_scene(write(tmp_path, SMALL))
    traj, report, checks = run(sc)
    assert all(c.ok for c in checks), report
    assert {c.what.split(":")[0] for c in checks} >= {"mass centre", "split vs unsplit multibody"}
    for text in ("effective bodies", "J principal", "principal axes", "hyperbolic", "trigonometric",
                 "rotation of tip", "split vs unsplit multibody", "verdict: all checks passed"):
        assert text in report
    _, report2, checks2 = run(sc, check=False)
    assert "unsplit" not in report2 and len(checks2) == len(checks) - 1


def test_closed_form_rotation_is_used_and_checked(tmp_path, monkeypatch):
    """With an isotropic a the rotations are Euler tops; a stand-in solve_rotation exercises the
    closed-form branch of the pipeline (the real one lives in thetasol.solutions.rotation.dispatch)."""
    calls = []

    class Fake:
        model, method, case = "rotation", "elliptic", "fake"
        diagnostics = {"error_estimate": 1e-15}

        def __init__(self, J, a, Q0, w0):
            self.args = (J, a, Q0, w0)

        def __call__(self, t):
            calls.append(1)
            return integrate_rotation(inertia(self.args[0]), *self.args[1:], rtol=1e-13)(t)

    def solve_rotation(I, a, Q0, w0):
        if not np.allclose(a, a[0, 0] * np.eye(3)):
            raise NotImplementedError("theta functions: not in this stand-in")
        return Fake(second_moments(I), a, Q0, w0)

    monkeypatch.setitem(sys.modules, "thetasol.solutions.rotation.dispatch",
                        types.SimpleNamespace(solve_rotation=solve_rotation))
    text = SMALL.replace("a = [[1.0, 0.2, 0.0], [0.2, 0.5, 0.0], [0.0, 0.0, -0.1]]",
                         "a = [[0.3, 0.0, 0.0], [0.0, 0.3, 0.0], [0.0, 0.0, 0.3]]")
    sc = load_scene(write(tmp_path, text))
    assert rotation_kind(sc.a) == "elliptic"
    traj, report, checks = run(sc, check=False)
    assert len(calls) == 3
    assert all("closed form elliptic (fake)" in m for m in traj.info["models"]["rotations"].values())
    assert sum("rotation by elliptic (fake) vs integrate_rotation" in c.what for c in checks) == 3   # model, method, case
    assert all(c.ok for c in checks)
    # a generic a falls back to numerics and says why
    sc2 = load_scene(write(tmp_path, SMALL, "generic.toml"))
    traj2, report2, _ = run(sc2, check=False)
    assert "not in this stand-in" in report2
    assert all("numerical fallback" in m for m in traj2.info["models"]["rotations"].values())


def test_rotation_kind():
    assert rotation_kind(np.zeros((3, 3))) == "elliptic"
    assert rotation_kind(2 * np.eye(3)) == "elliptic"
    g = np.array([0.0, 0.6, 0.8])
    assert rotation_kind(3 * np.outer(g, g)).startswith("theta (rank-one")
    assert rotation_kind(np.diag([1.0, 2.0, 3.0])) == "theta"


def test_example_scene_solves():
    sc = load_scene(EXAMPLE)
    assert len(sc.config) == 4 and sc.config.depth == 2
    traj = sc.solve()
    assert np.all(np.isfinite(traj.position))


@pytest.mark.parametrize("fmt", ["npz", "csv"])
def test_write_round_trip(tmp_path, fmt):
    sc = load_scene(write(tmp_path, SMALL))
    traj = sc.solve()
    out = tmp_path / f"out.{fmt}"
    paths = write_trajectories(traj, out, report="the report")
    assert paths == [out, tmp_path / "out.report.txt"]
    assert (tmp_path / "out.report.txt").read_text() == "the report"
    if fmt == "npz":
        with np.load(out) as z:
            assert list(z["names"]) == list(traj.names)
            assert np.array_equal(z["attitude"], traj.attitude)
            assert np.array_equal(z["mass_center"], traj.mass_center)
            assert str(z["report"]) == "the report"
    else:
        header = out.read_text().splitlines()[0].split(",")
        data = np.loadtxt(out, delimiter=",", skiprows=1)
        assert data.shape == (41, len(header)) and header[:4] == ["t", "q_x", "q_y", "q_z"]
        k = header.index("tip.Q21")
        assert np.array_equal(data[:, k], traj.body("tip")["attitude"][:, 1, 0])  # %.17g round-trips
        assert np.array_equal(data[:, header.index("arm.wz")], traj.body("arm")["omega"][:, 2])
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["scene.toml", f"out.{fmt}", "out.report.txt"])


def test_write_errors_leave_nothing(tmp_path):
    sc = load_scene(write(tmp_path, SMALL))
    traj = sc.solve()
    with pytest.raises(ValueError, match=r"\.npz or \.csv"):
        write_trajectories(traj, tmp_path / "out.txt")
    with pytest.raises(ValueError, match="does not exist"):
        write_trajectories(traj, tmp_path / "missing" / "out.npz")
    (tmp_path / "out.report.txt").mkdir()
    with pytest.raises(ValueError, match="directory"):
        write_trajectories(traj, tmp_path / "out.npz", report="r")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.report.txt", "scene.toml"]


BAD = [
    ("name = [", "malformed TOML"),
    (SMALL + "\n[extra]\nx = 1\n", "unknown key"),
    (SMALL.replace("[potential]", "[potentiel]"), "unknown key"),
    (SMALL.replace("a = [[1.0, 0.2, 0.0], [0.2, 0.5, 0.0]", "a = [[1.0, 0.3, 0.0], [0.2, 0.5, 0.0]"), "symmetric"),
    (SMALL.replace("b = [0.1, 0.0, 0.0]", "b = [nan, 0.0, 0.0]"), "NaN or inf"),
    (SMALL.replace("q = [0.1, 0.2, 0.0]", "q = [inf, 0.2, 0.0]"), "NaN or inf"),
    (SMALL.replace("mass = 4.0", "mass = -4.0"), "mass .* positive"),
    (SMALL.replace("I = [2.0, 2.5, 3.0]", "I = [1.0, 1.0, 3.0]"), "not physical"),
    (SMALL.replace("I = [2.0, 2.5, 3.0]", "I = [2.0, -2.5, 3.0]"), "positive definite"),
    (SMALL.replace('parent = "arm"', 'parent = "hand"'), "unknown parent 'hand'"),
    (SMALL.replace('parent = "root"', 'parent = "tip"'), "cycle"),
    (SMALL.replace("tip = [[0.0, -1.0, 0.0]", "tip = [[0.0, -1.00000001, 0.0]"), "not orthogonal"),
    (SMALL.replace("tip = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]",
                   "tip = [[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]"), "reflection"),
    (SMALL.replace("child_point = [0.0, 0.1, 0.0]", "child_point = [0.0, 0.0, 0.0]"), "not C\\^k-central"),
    (SMALL.replace('name = "tip"\n', 'name = "arm"\n'), "duplicate body name"),
    (SMALL.replace("samples = 41", "samples = 4.5"), "samples"),
    (SMALL.replace("t_end = 4.0", "t_end = -1.0"), "t_end must be positive"),
    (SMALL.replace("t_end = 4.0\nsamples = 41", "times = [0.0, 2.0, 1.0]"), "strictly increasing"),
    (SMALL.replace("[output]\nt_end = 4.0\nsamples = 41", ""), "missing \\[output\\]"),
    (SMALL.replace("tip = [1.0, 0.0, 0.5]", "hand = [1.0, 0.0, 0.5]"), "unknown body 'hand'"),
    (SMALL.replace("J = [0.02, 0.03, 0.04]", "J = [0.02, 0.03]"), "shape"),
    (SMALL.replace("J = [0.02, 0.03, 0.04]", 'J = "big"'), "numeric"),
    (SMALL.replace("box = [1.0, 0.2, 0.2]", "box = [1.0, 0.2, 0.2]\nJ = [1.0, 1.0, 1.0]"), "exactly one"),
    (SMALL + "\n[solver]\nrtol = 2.0\n", "rtol must be below 1"),
    (SMALL + "\n[solver]\nmethod = \"Euler\"\n", "solver.method"),
    (SMALL + "\n[solver]\nmake_central = \"yes\"\n", "make_central"),
]


@pytest.mark.parametrize("text, match", BAD)
def test_bad_scenes(tmp_path, text, match):
    with pytest.raises(ValueError, match=match):
        load_scene(write(tmp_path, text))


def test_missing_file_and_binary(tmp_path):
    with pytest.raises(ValueError, match="cannot read"):
        load_scene(tmp_path / "nope.toml")
    p = tmp_path / "bin.toml"
    p.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(ValueError, match="UTF-8"):
        load_scene(p)


def test_make_central_shifts_the_joints(tmp_path):
    text = SMALL.replace("child_point = [0.0, 0.1, 0.0]", "child_point = [0.0, 0.0, 0.0]")
    sc = load_scene(write(tmp_path, text + "\n[solver]\nmake_central = true\n"))
    assert sc.config.is_central()
    assert np.allclose(sc.config.joints["tip"].child_point, [0.0, 0.1, 0.0])


def test_scene_from_dict_matches_file(tmp_path):
    import tomllib

    d = tomllib.loads(SMALL)
    a = Scene.from_dict(d)
    b = load_scene(write(tmp_path, SMALL))
    assert np.array_equal(a.t, b.t) and a.config.order == b.config.order
