"""The exact reference cases (thetasol.reference): each case's closed form against its own ODE.

The ODE of a case (``rhs``) is written from the physics in thetasol/reference/_models.py and never
calls a closed form, so integrating it with scipy's DOP853 is an independent check of ``exact``.
"""
import json
import math
from functools import partial

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from thetasol import reference
from thetasol.cli import main

NAMES = reference.names()

# worst group error of DOP853 (rtol = atol = 1e-12) against exact over [t0, t0 + 10], 51 times:
# dominated by the integrator (Q's error grows like t * rtol * number of turns)
DOP853_MEASURED = {
    "free_top_long_axis": 3.7e-12, "free_top_short_axis": 4.6e-12, "free_top_near_separatrix": 4.4e-12,
    "free_top_symmetric": 5.5e-12, "potential_generic": 3.5e-12, "potential_rank_one": 4.8e-12,
    "potential_symmetric_body": 1.0e-11, "potential_pendulum": 5.2e-12, "gyrostat": 5.3e-12,
    "gyrostat_rotors": 5.2e-12, "lagrange_top": 1.8e-11, "simo_wong_top": 1.4e-10, "neumann": 1.6e-11,
    "kepler_ellipse": 2.0e-11, "kepler_hyperbola": 1.3e-12, "mass_centre": 1.8e-12,
    "gravity_gradient_pitch": 3.1e-11,
}


def _grid(c, n=51):
    t0 = c.t_span[0]
    return np.linspace(t0, t0 + min(10.0, c.t_span[1] - t0), n)


def test_catalogue_covers_every_model():
    cs = reference.cases()
    assert len(cs) >= 12 and len({c.model for c in cs}) >= 6
    assert len(set(NAMES)) == len(NAMES) == len(DOP853_MEASURED)
    assert {c.model for c in cs} == {"free rigid body", "body in a quadratic potential", "free gyrostat",
                                     "heavy top", "Neumann problem", "Kepler orbit",
                                     "mass centre in a quadratic potential", "orbiting rigid body"}


def test_each_model_uses_its_closed_form_branch():
    """The cases exercise the branches they name (theta genus 4, nodal, symmetric, pendulum, ...)."""
    methods = {c.name: c.method for c in reference.cases()}
    cases = {c.name: c.solution.case for c in reference.cases()}
    assert methods["potential_generic"] == "theta/genus-4"
    assert methods["potential_rank_one"] == "theta/genus-3" and cases["potential_rank_one"] == "nodal"
    assert methods["potential_symmetric_body"].startswith("theta/") and cases["potential_symmetric_body"] == "symmetric"
    assert methods["potential_pendulum"] == "elliptic" and cases["potential_pendulum"].startswith("pendulum/")
    assert methods["free_top_near_separatrix"] == "elliptic"
    assert methods["simo_wong_top"] == methods["lagrange_top"] == "elliptic"
    assert methods["neumann"] == "fourier/genus-2"
    assert methods["gravity_gradient_pitch"] == "elliptic" and cases["gravity_gradient_pitch"] == "pitch/libration"
    assert reference.case("gyrostat_rotors").solution.rotors


@pytest.mark.parametrize("name", NAMES)
def test_exact_at_t0_is_y0(name):
    # measured: <= 1.7e-15 (potential_generic), 0 to 4e-16 elsewhere
    c = reference.case(name)
    assert c.exact(c.t_span[0]).shape == c.y0.shape
    assert c.score([c.t_span[0]], c.y0[None, :]).worst <= 1e-14


@pytest.mark.parametrize("name", NAMES)
def test_dop853_on_the_case_ode_agrees_with_exact(name):
    c = reference.case(name)
    t = _grid(c)
    sol = solve_ivp(c.rhs, (t[0], t[-1]), c.y0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=t)
    assert sol.success
    err = c.score(sol.t, sol.y).worst
    assert err <= 1e-7 and err <= 10 * DOP853_MEASURED[name], err


@pytest.mark.parametrize("name", NAMES)
def test_score_of_exact_states_is_zero_and_of_perturbed_states_is_the_perturbation(name):
    c = reference.case(name)
    t = _grid(c, 21)
    ex = c.exact(t)
    assert c.score(t, ex).worst <= 1e-12
    assert c.score(t, ex.T).worst <= 1e-12                       # solve_ivp's (n, len(t)) layout
    for g in c.groups:
        y = ex.copy()
        scale = g.scale if g.scale is not None else np.abs(ex[:, g.start:g.stop]).max()
        y[7, g.start] += 1e-6 * scale
        s = c.score(t, y)
        assert s[g.name] == pytest.approx(1e-6, rel=1e-6)
        assert all(v <= 1e-12 for k, v in s.items() if k != g.name)


@pytest.mark.parametrize("name", NAMES)
def test_a_wrong_initial_state_scores_badly(name):
    """Integrating from y0 perturbed by 1e-5 (relative, first component group) is caught."""
    c = reference.case(name)
    t = _grid(c, 21)
    y0 = c.y0
    g = c.groups[0]
    y0[g.start:g.stop] += 1e-5 * max(np.abs(y0[g.start:g.stop]).max(), 1.0)
    sol = solve_ivp(c.rhs, (t[0], t[-1]), y0, method="DOP853", rtol=1e-10, atol=1e-10, t_eval=t)
    assert c.score(sol.t, sol.y).worst >= 1e-6


@pytest.mark.parametrize("name", NAMES)
def test_report_first_integrals_are_conserved_by_exact_and_drift_under_a_wrong_rhs(name):
    # along exact states: measured <= 1.5e-14 (potential_generic); along DOP853 at 1e-12: <= 2.9e-11
    c = reference.case(name)
    t = _grid(c, 41)
    rep = c.report(t, c.exact(t))
    assert set(rep.errors) == {g.name for g in c.groups}
    assert max(float(np.max(d)) for d in rep.drift.values()) <= 1e-13, str(rep)
    assert name in str(rep)
    # a 1e-3 spurious damping of the first group breaks some first integral by far more
    g = c.groups[0]

    def damped(tt, y):
        f = c.rhs(tt, y)
        f[g.start:g.stop] -= 1e-3 * y[g.start:g.stop]
        return f

    sol = solve_ivp(damped, (t[0], t[-1]), c.y0, method="DOP853", rtol=1e-10, atol=1e-10, t_eval=t)
    bad = c.report(sol.t, sol.y)
    assert max(float(np.max(d)) for k, d in bad.drift.items() if k != "orthogonality") >= 1e-5


def test_rhs_accepts_the_vectorized_layout():
    c = reference.case("lagrange_top")
    Y = np.stack([c.y0, c.exact(0.3)], axis=1)
    F = c.rhs(0.0, Y)
    assert F.shape == Y.shape and np.array_equal(F[:, 1], c.rhs(0.0, Y[:, 1]))


def test_score_refuses_states_of_the_wrong_shape():
    c = reference.case("kepler_ellipse")
    with pytest.raises(ValueError, match="do not match"):
        c.score([0.0, 1.0], np.zeros((2, 5)))


def test_export_csv_and_json_round_trip(tmp_path):
    c = reference.case("gyrostat_rotors")
    t = np.linspace(0.0, 3.0, 7)
    p = c.export(tmp_path / "g.csv", t)
    header, *rows = p.read_text().splitlines()
    assert header.split(",") == ["t", *c.columns] and header.endswith("phi_2")
    data = np.array([[float(x) for x in r.split(",")] for r in rows])
    assert np.array_equal(data[:, 0], t) and np.array_equal(data[:, 1:], c.exact(t))
    doc = json.loads(c.export(tmp_path / "g.json", t).read_text())
    for k in ("name", "model", "description", "equations", "units", "columns", "t", "states", "method"):
        assert k in doc
    assert doc["name"] == "gyrostat_rotors" and doc["columns"][0] == "t"
    assert np.array_equal(np.array(doc["states"]), c.exact(t)) and doc["t"] == t.tolist()
    with pytest.raises(ValueError, match=".csv or .json"):
        c.export(tmp_path / "g.txt", t)


def test_cli_reference_list_and_export(tmp_path, capsys):
    assert main(["reference", "list"]) == 0
    out = capsys.readouterr().out
    assert all(n in out for n in NAMES)
    f = tmp_path / "k.csv"
    assert main(["reference", "export", "kepler_ellipse", "-o", str(f), "--t0", "0", "--t1", "2",
                 "--n", "5"]) == 0
    rows = f.read_text().splitlines()
    assert len(rows) == 6 and rows[0].startswith("t,q_1")
    r1 = [float(x) for x in rows[-1].split(",")]
    assert r1[0] == 2.0 and np.array_equal(r1[1:], reference.case("kepler_ellipse").exact(2.0))
    assert main(["reference", "export", "no_such_case", "-o", str(f)]) == 2
    assert "unknown reference case" in capsys.readouterr().err
    assert main(["reference", "export", "neumann", "-o", str(tmp_path / "x.npz")]) == 2


def test_cli_imports_the_catalogue_lazily():
    import subprocess
    import sys
    code = "import sys, thetasol.cli; print('thetasol.reference' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"


def test_benchmark_table_and_figure():
    cs = reference.cases(["free_top_long_axis", "kepler_ellipse"])
    table, fig = reference.benchmark(partial(solve_ivp, method="RK45"), cases=cs, rtols=(1e-4, 1e-8))
    assert [(r["case"], r["rtol"]) for r in table] == [(c.name, r) for c in cs for r in (1e-4, 1e-8)]
    for c in cs:
        lo, hi = (r for r in table if r["case"] == c.name)
        # RK45's error falls with the tolerance and its work grows: measured 1e-4 -> ~1e-3, 1e-8 -> ~1e-7
        assert lo["success"] and hi["success"] and hi["error"] < 1e-2 * lo["error"] and hi["nfev"] > lo["nfev"]
    assert "free_top_long_axis" in str(table) and "nfev" in str(table)
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        assert fig is None
    else:
        assert len(fig.axes[0].get_lines()) == 2
    assert reference.benchmark(partial(solve_ivp, method="RK45"), cases=cs[:1], rtols=(1e-3,), plot=False)[1] is None


def test_benchmark_reports_a_failing_integrator_as_a_row():
    def broken(fun, t_span, y0, **kw):
        raise RuntimeError("diverged")

    table, _ = reference.benchmark(broken, cases=reference.cases(["mass_centre"]), rtols=(1e-6,), plot=False)
    (row,) = table
    assert not row["success"] and math.isnan(row["error"]) and "diverged" in row["message"]


def test_unknown_case_and_model_filter():
    with pytest.raises(KeyError, match="no_such"):
        reference.case("no_such")
    assert [c.name for c in reference.cases(model="heavy top")] == ["lagrange_top", "simo_wong_top"]
