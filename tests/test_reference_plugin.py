"""The pytest plugin thetasol.reference.pytest_plugin, exercised as another project would use it.

A fresh project (a temporary directory holding one test file and no configuration) is tested in
a subprocess with ``-p thetasol.reference.pytest_plugin`` (the ``pytest11`` entry point loads the
same module once thetasol is installed).
"""
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from thetasol import reference

ROOT = Path(__file__).resolve().parents[1]

USER_TEST = '''
from scipy.integrate import solve_ivp


def test_my_integrator(thetasol_case):
    sol = solve_ivp(thetasol_case.rhs, thetasol_case.t_span, thetasol_case.y0, method="DOP853",
                    rtol=1e-10, atol=1e-10, t_eval=thetasol_case.times(11))
    assert thetasol_case.score(sol.t, sol.y).worst < 1e-6


def test_not_using_the_fixture():
    assert True
'''


def _pytest(project: Path, *args: str, entry_point_dir: Path | None = None) -> subprocess.CompletedProcess:
    """pytest on the project in a subprocess: the plugin module loaded with ``-p`` (entry points off,
    as an installed thetasol would otherwise register it twice), or through ``entry_point_dir``."""
    path = [str(ROOT)] + ([str(entry_point_dir)] if entry_point_dir else []) + [os.environ.get("PYTHONPATH", "")]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(path), "OPENBLAS_NUM_THREADS": "1"}
    plugin = []
    if entry_point_dir is None:
        env["PYTEST_DISABLE_PLUGIN_AUTOLOAD"] = "1"
        plugin = ["-p", "thetasol.reference.pytest_plugin"]
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *plugin,
           "--rootdir", str(project), *args, str(project / "test_user.py")]
    return subprocess.run(cmd, cwd=project, env=env, capture_output=True, text=True, timeout=600)


def _project(tmp_path: Path) -> Path:
    (tmp_path / "test_user.py").write_text(USER_TEST)
    return tmp_path


def test_plugin_collects_one_test_per_case(tmp_path):
    res = _pytest(_project(tmp_path), "--collect-only")
    assert res.returncode == 0, res.stdout + res.stderr
    ids = [line.split("[", 1)[1].rstrip("]") for line in res.stdout.splitlines() if "test_my_integrator[" in line]
    assert ids == reference.names()
    assert sum("test_not_using_the_fixture" in line for line in res.stdout.splitlines()) == 1


def test_plugin_runs_and_dop853_passes_every_case(tmp_path):
    res = _pytest(_project(tmp_path))
    assert res.returncode == 0, res.stdout + res.stderr
    assert f"{len(reference.names()) + 1} passed" in res.stdout


def test_plugin_options_select_cases(tmp_path):
    project = _project(tmp_path)
    res = _pytest(project, "--collect-only", "--thetasol-cases=kepler_ellipse,neumann")
    assert res.returncode == 0 and "test_my_integrator[kepler_ellipse]" in res.stdout
    assert "test_my_integrator[neumann]" in res.stdout and res.stdout.count("test_my_integrator[") == 2
    res = _pytest(project, "--collect-only", "--thetasol-model=heavy top")
    assert res.stdout.count("test_my_integrator[") == 2 and "simo_wong_top" in res.stdout


def test_plugin_catches_a_wrong_integrator(tmp_path):
    """A too-loose integrator fails the user's assertion: the plugin's tests can fail."""
    loose = USER_TEST.replace('method="DOP853",\n                    rtol=1e-10, atol=1e-10',
                              'method="RK23",\n                    rtol=1e-3, atol=1e-3')
    assert loose != USER_TEST
    (tmp_path / "test_user.py").write_text(loose)
    res = _pytest(tmp_path, "--thetasol-cases=free_top_long_axis,kepler_ellipse")
    assert res.returncode == 1 and "2 failed, 1 passed" in res.stdout, res.stdout


def test_the_pyproject_entry_point_loads_the_plugin(tmp_path):
    """pyproject's ``pytest11`` entry point, as an install would write it (a dist-info directory with
    entry_points.txt), gives the fixture without ``-p``."""
    eps = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["entry-points"]["pytest11"]
    assert eps == {"thetasol": "thetasol.reference.pytest_plugin"}
    site = tmp_path / "site"
    info = site / "thetasol_reference_probe-0.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: thetasol-reference-probe\nVersion: 0.0\n")
    (info / "entry_points.txt").write_text("[pytest11]\n" + "".join(f"{k} = {v}\n" for k, v in eps.items()))
    (info / "RECORD").write_text("")
    project = tmp_path / "project"
    project.mkdir()
    res = _pytest(_project(project), "--collect-only", "--thetasol-model=Kepler orbit", entry_point_dir=site)
    assert res.returncode == 0, res.stdout + res.stderr
    assert res.stdout.count("test_my_integrator[") == 2 and "kepler_hyperbola" in res.stdout


def test_an_unknown_case_name_is_a_usage_error(tmp_path):
    """A misspelt ``--thetasol-cases`` or ``--thetasol-model`` stops pytest with a usage error that
    names the known cases, not a KeyError reported against the user's test file."""
    project = _project(tmp_path)
    res = _pytest(project, "--collect-only", "--thetasol-cases=kepler_ellipse,kepler_elipse")
    assert res.returncode == pytest.ExitCode.USAGE_ERROR, res.stdout + res.stderr
    assert "unknown reference case(s) kepler_elipse" in res.stderr and "kepler_ellipse" in res.stderr
    assert "KeyError" not in res.stdout + res.stderr and "test_user.py" not in res.stdout + res.stderr
    res = _pytest(project, "--collect-only", "--thetasol-model=heavy tops")
    assert res.returncode == pytest.ExitCode.USAGE_ERROR and "known: " in res.stderr and "heavy top" in res.stderr


def test_loading_the_plugin_imports_nothing_heavy():
    """Every pytest session of the environment loads the plugin: a fresh interpreter importing it
    must not import numpy, scipy or the closed forms (they load when a test asks for a case)."""
    probe = ("import sys, thetasol.reference.pytest_plugin\n"
             "print(sorted(m for m in sys.modules if m.split('.')[0] in ('numpy', 'scipy', 'mpmath', 'sympy')"
             " or m.startswith(('thetasol.solutions', 'thetasol.reference.', 'thetasol.core'))"
             " and m != 'thetasol.reference.pytest_plugin'))")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    res = subprocess.run([sys.executable, "-c", probe], cwd=ROOT, env=env, capture_output=True, text=True,
                         timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "[]"
