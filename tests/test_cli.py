"""The command line: `python -m thetasol demo` and `python -m thetasol solve SCENE.toml`."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from thetasol import inertia
from thetasol.cli import main

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "satellite_boom.toml"


def test_demo_as_a_process(tmp_path):
    """The README's main job, as a user runs it (within a 120 s timeout; it takes 5-8 s, docs/mechanics.md)."""
    res = subprocess.run([sys.executable, "-m", "thetasol", "demo", "-o", str(tmp_path / "demo.npz")],
                         capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    assert "[1/3] split solution ..." in res.stderr and "[3/3] unsplit multibody reference ..." in res.stderr
    out = res.stdout
    for text in ("effective bodies", "J principal", "principal axes", "mass centre (3.2): closed form",
                 "rotation of core", "numerical", "max abs deviation", "split vs unsplit multibody",
                 "when the closed form pays off", "cheaper for T >", "timings", "verdict: all checks passed"):
        assert text in out
    assert out.count("rotation of ") >= 4
    with np.load(tmp_path / "demo.npz") as z:
        assert z["position"].shape[0] >= 4
    assert (tmp_path / "demo.report.txt").read_text().startswith("scene: station")


def test_solve_writes_csv_report_and_plot(tmp_path, capsys):
    """-o writes trajectories and report, --plot a PNG; the parts in progress are announced on stderr."""
    pytest.importorskip("matplotlib")
    out = tmp_path / "sat.csv"
    assert main(["solve", str(EXAMPLE), "-o", str(out), "--no-check", "--plot", str(tmp_path / "sat.png")]) == 0
    captured = capsys.readouterr()
    printed = captured.out
    assert "verdict: all checks passed" in printed and "unsplit" not in printed
    header = out.read_text().splitlines()[0]
    assert header.startswith("t,q_x,q_y,q_z") and "magnetometer.Q33" in header
    assert (tmp_path / "sat.report.txt").read_text() in printed + "\n"
    assert (tmp_path / "sat.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"wrote {tmp_path / 'sat.png'}" in printed
    lines = captured.err.splitlines()       # not a terminal: a line per part
    assert lines[:2] == ["thetasol: [1/2] split solution ...", "thetasol: [2/2] numerical references ..."]
    assert lines[2].startswith("thetasol: done in ") and len(lines) == 3
    assert "-o station.npz" not in printed   # the hint is the demo's


def _fake_run(scene, check=True, out=None, progress=None):
    """A stand-in for scenes.report.run: one static body, the progress calls of a run without multibody."""
    from thetasol.mechanics.trajectories import Trajectories

    for k, label in enumerate(("split solution", "numerical references", "done")):
        progress(label, k, 2)
    t = np.linspace(0.0, 1.0, 5)
    z = np.zeros((1, 5, 3))
    traj = Trajectories(t=t, names=("a",), position=z, velocity=z, attitude=np.tile(np.eye(3), (1, 5, 1, 1)),
                        omega=z, mass_center=z[0], mass_center_velocity=z[0])
    print("verdict: all checks passed", file=out)
    return traj, "report\n", []


def test_demo_tells_about_output(capsys, monkeypatch):
    import thetasol.scenes.report as scene_mod

    monkeypatch.setattr(scene_mod, "run", _fake_run)
    assert main(["demo"]) == 0
    out = capsys.readouterr().out
    assert "not written: 'python -m thetasol demo -o station.npz' (or .csv)" in out and "--plot station.png" in out


def test_plot_refused_before_solving(tmp_path, capsys, monkeypatch):
    """A wrong suffix, a missing folder or no matplotlib: exit 2 naming the problem, nothing solved or written."""
    import thetasol.scenes.report as scene_mod

    def never(*args, **kwargs):
        raise AssertionError("solved before checking the plot file")

    monkeypatch.setattr(scene_mod, "run", never)
    assert main(["solve", str(EXAMPLE), "--plot", str(tmp_path / "x.jpg")]) == 2
    assert ".png, .pdf, .svg" in capsys.readouterr().err
    assert main(["demo", "--plot", str(tmp_path / "missing" / "x.png")]) == 2
    assert "does not exist" in capsys.readouterr().err
    monkeypatch.setitem(sys.modules, "matplotlib", None)       # as if not installed
    for name in [m for m in sys.modules if m.startswith("matplotlib.") or m == "thetasol.plot"]:
        monkeypatch.delitem(sys.modules, name)
    assert main(["demo", "--plot", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("thetasol: error: --plot: thetasol.plot needs matplotlib") and "thetasol[plot]" in err
    assert list(tmp_path.iterdir()) == []


def test_progress_bar_on_a_terminal(monkeypatch):
    """On a terminal with tqdm installed the parts drive a bar (its description names the part)."""
    pytest.importorskip("tqdm")
    import io

    from thetasol.cli import _Progress

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    err = Terminal()
    monkeypatch.setattr(sys, "stderr", err)
    with _Progress() as progress:
        progress("split solution", 0, 2)
        progress("numerical references", 1, 2)
        assert progress.bar.n == 1 and progress.bar.total == 2
    assert "numerical references" in err.getvalue() and "thetasol:" not in err.getvalue()


@pytest.mark.parametrize("scene_text, match", [
    ("[potential\n", "malformed TOML"),
    ("[potential]\na = [[1, 2, 0], [0, 1, 0], [0, 0, 1]]\n", "symmetric"),
])
def test_bad_scene_exits_2_and_writes_nothing(tmp_path, capsys, scene_text, match):
    bad = tmp_path / "bad.toml"
    if "symmetric" in match:
        scene_text = EXAMPLE.read_text().replace("[0.10, 0.20, 0.00]", "[0.11, 0.20, 0.00]")
    bad.write_text(scene_text)
    out = tmp_path / "out.npz"
    assert main(["solve", str(bad), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("thetasol: error:") and match in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


def test_existing_output_untouched_on_error(tmp_path, capsys):
    out = tmp_path / "keep.csv"
    out.write_text("old")
    bad = tmp_path / "bad.toml"
    bad.write_text(EXAMPLE.read_text().replace("mass = 3.0", "mass = nan"))
    assert main(["solve", str(bad), "-o", str(out)]) == 2
    assert "body 'boom': mass must be finite" in capsys.readouterr().err
    assert out.read_text() == "old"


def test_usage_errors(tmp_path, capsys):
    assert main(["solve", str(tmp_path / "missing.toml")]) == 2
    assert "cannot read" in capsys.readouterr().err
    assert main(["solve", str(EXAMPLE), "-o", str(tmp_path / "x.json")]) == 2
    assert ".npz or .csv" in capsys.readouterr().err
    assert not (tmp_path / "x.json").exists()
    with pytest.raises(SystemExit) as exc:
        main(["frobnicate"])
    assert exc.value.code == 2


def test_failed_check_exits_1(tmp_path, capsys, monkeypatch):
    """A check beyond its tolerance makes the verdict FAILED and the exit status 1."""
    import thetasol.scenes.pipeline as pipeline_mod

    real = pipeline_mod.MassCenterMotion

    class Off(real):
        def __call__(self, t, dps=None):
            q, v = real.__call__(self, t, dps)
            return q + 1e-6, v

    monkeypatch.setattr(pipeline_mod, "MassCenterMotion", Off)
    assert main(["solve", str(EXAMPLE), "--no-check"]) == 1
    assert "verdict: FAILED" in capsys.readouterr().out


def test_example_script_runs():
    res = subprocess.run([sys.executable, str(ROOT / "examples" / "solve_scene.py")], capture_output=True,
                         text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert "split vs unsplit" in res.stdout and "shifts:" in res.stdout


def test_readme_example():
    """The README's code example, as printed there: a theta-function solution of genus 4."""
    from thetasol import solve_rotation

    sol = solve_rotation(inertia([0.6, 1.0, 1.7]), np.diag([-1.0, 0.4, 1.5]), np.eye(3), [0.5, -0.8, 0.6])
    assert sol.method == "theta/genus-4"
    omega, Q = sol(np.linspace(0, 1000, 2001))
    assert omega.shape == (2001, 3) and Q.shape == (2001, 3, 3)


def test_unwritable_output_refused_before_solving(tmp_path, capsys, monkeypatch):
    """-o into a missing directory: exit 2 naming it, and the scene is never solved."""
    import thetasol.scenes.report as scene_mod

    def never(*args, **kwargs):
        raise AssertionError("solved before checking the output path")

    monkeypatch.setattr(scene_mod, "run", never)
    missing = tmp_path / "missing" / "out.csv"
    assert main(["solve", str(EXAMPLE), "-o", str(missing)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("thetasol: error:") and "does not exist" in err and str(tmp_path / "missing") in err
    assert not (tmp_path / "missing").exists()
