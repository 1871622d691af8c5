"""The command line: `python -m thetasol demo` and `python -m thetasol solve SCENE.toml`."""
import os
import re
import stat
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
    """The README's main job, as a user runs it (within a 120 s timeout, far above its cost: docs/bench_mechanics.md)."""
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
    lines = captured.err.splitlines()       # not a terminal: a line per part; --no-check: no reference at all
    assert lines[0] == "thetasol: [1/1] split solution ..."
    assert lines[1].startswith("thetasol: done in ") and len(lines) == 2
    assert "not checked against numerical references" in printed and "vs integrate_" not in printed
    assert "-o station.npz" not in printed   # the hint is the demo's


def _fake_run(scene, check=True, out=None, progress=None, references=True):
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
    scene = tmp_path / "s.toml"
    scene.write_text(EXAMPLE.read_text().replace("check_multibody = true", "check_multibody = false"))
    import thetasol.scenes.references as refs

    monkeypatch.setattr(refs, "_heyoka_installed", lambda: False)    # DOP853 references: no model to compile
    assert main(["solve", str(scene), "--t-end", "2", "--samples", "9"]) == 1
    out = capsys.readouterr().out
    assert "verdict: FAILED: mass centre" in out and "the checked part is off by at least" in out


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


PIVOTED = ROOT / "thetasol" / "scenes" / "data" / "pivoted_top.toml"


def test_output_times_on_the_command_line(tmp_path, capsys):
    """--t-end and --samples replace the scene's times; a far horizon with --no-check finishes at once
    (the closed forms evaluate at any time) and runs no reference."""
    out = tmp_path / "far.npz"
    assert main(["solve", str(PIVOTED), "--t-end", "1e12", "--samples", "7", "--no-check", "-o", str(out)]) == 0
    captured = capsys.readouterr()
    assert "output: 7 times in [0, 1e+12]" in captured.out and "numerical references" not in captured.err
    with np.load(out) as z:
        assert np.array_equal(z["t"], np.linspace(0.0, 1e12, 7)) and np.all(np.isfinite(z["attitude"]))
    for bad, match in ((["--t-end", "-1"], "t_end must be positive"), (["--t-end", "nan"], "t_end must be finite"),
                       (["--samples", "1"], r"integer in \[2, 1e7\]")):
        assert main(["solve", str(PIVOTED), "--no-check", *bad]) == 2
        err = capsys.readouterr().err
        assert err.startswith("thetasol: error:") and re.search(match, err), err


def test_interrupt_exits_130_with_what_was_written(tmp_path, capsys, monkeypatch):
    """Ctrl-C during the checks: exit 130, a message, and no file (they are written whole, after the run)."""
    import thetasol.scenes.report as scene_mod

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(scene_mod, "run", interrupted)
    assert main(["solve", str(PIVOTED), "-o", str(tmp_path / "x.csv")]) == 130
    assert "thetasol: interrupted; no file was written" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_output_files_get_the_umask(tmp_path, capsys):
    """CSV, NPZ, report and PNG are created as open() would create them: 0666 less the umask."""
    old = os.umask(0o027)
    try:
        assert main(["solve", str(PIVOTED), "--no-check", "--samples", "5", "-o", str(tmp_path / "a.csv")]) == 0
        assert main(["solve", str(PIVOTED), "--no-check", "--samples", "5", "-o", str(tmp_path / "b.npz")]
                    + (["--plot", str(tmp_path / "b.png")] if _has_matplotlib() else [])) == 0
    finally:
        os.umask(old)
    files = sorted(tmp_path.iterdir())
    assert len(files) >= 4
    for p in files:
        assert stat.S_IMODE(p.stat().st_mode) == 0o640, p


def _has_matplotlib() -> bool:
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return False
    return True


def test_strings_in_a_scene_file_are_refused(tmp_path, capsys):
    """A number written as a string is an error naming the entry and the file, not a number."""
    bad = tmp_path / "bad.toml"
    bad.write_text(PIVOTED.read_text().replace("top = [0.5, 0.0, 12.0]", 'top = [0.5, 0.0, "12"]'))
    assert main(["solve", str(bad), "--no-check"]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and "initial.omega.top" in err and "'12'" in err and "not a number" in err
