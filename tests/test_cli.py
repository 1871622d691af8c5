"""The command line: `python -m thetasol demo` and `python -m thetasol solve SCENE.toml`."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from thetasol.cli import main

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "satellite_boom.toml"


def test_demo_as_a_process(tmp_path):
    """The README's main job, as a user runs it (within a 120 s timeout; it takes 5-8 s, docs/mechanics.md)."""
    res = subprocess.run([sys.executable, "-m", "thetasol", "demo", "-o", str(tmp_path / "demo.npz")],
                         capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    out = res.stdout
    for text in ("effective bodies", "J principal", "principal axes", "mass centre (3.2): closed form",
                 "rotation of core", "numerical", "max abs deviation", "split vs unsplit multibody",
                 "when the closed form pays off", "cheaper for T >", "timings", "verdict: all checks passed"):
        assert text in out
    assert out.count("rotation of ") >= 4
    with np.load(tmp_path / "demo.npz") as z:
        assert z["position"].shape[0] >= 4
    assert (tmp_path / "demo.report.txt").read_text().startswith("scene: station")


def test_solve_writes_csv_and_report(tmp_path, capsys):
    out = tmp_path / "sat.csv"
    assert main(["solve", str(EXAMPLE), "-o", str(out), "--no-check"]) == 0
    printed = capsys.readouterr().out
    assert "verdict: all checks passed" in printed and "unsplit" not in printed
    header = out.read_text().splitlines()[0]
    assert header.startswith("t,q_x,q_y,q_z") and "magnetometer.Q33" in header
    assert (tmp_path / "sat.report.txt").read_text() in printed + "\n"


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

    sol = solve_rotation([0.6, 1.0, 1.7], np.diag([-1.0, 0.4, 1.5]), np.eye(3), [0.5, -0.8, 0.6])
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
