"""The case tables of docs/reference_cases.md, measured on the catalogue and written into the page.

For every case of :mod:`thetasol.reference`: its description (the bodies by their inertia ``I``, as
the catalogue states them), the closed form's ``method`` and case, the size of the state, how well
``exact(t0)`` reproduces ``y0``, the drift of the first integrals along ``exact``, and the worst group
error of scipy's DOP853 (``rtol = atol = 1e-12``) on the case's own ODE over its first 10 time units
(51 times, as tests/test_reference.py measures it).  A second table runs
:func:`thetasol.reference.benchmark` with DOP853 at three tolerances on a few cases.  The errors are
deterministic (no timings), so a rerun rewrites the same figures unless an algorithm changed.

Usage: ``python benchmarks/bench_reference_cases.py`` prints the tables; ``--write-docs`` also writes them
into the generated sections of the page.
"""
from __future__ import annotations

import argparse
import math
import pathlib
import re
import sys
from functools import partial

import numpy as np
from scipy.integrate import solve_ivp

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from _common import docs_page, docs_section, machine_info  # noqa: E402

from thetasol import reference  # noqa: E402

PAGE = "docs/reference_cases.md"
SCRIPT = "benchmarks/bench_reference_cases.py"
RTOL = 1e-12                       # the tolerance of tests/test_reference.py's DOP853 check
ORIENTATION = ("free_top_long_axis", "potential_generic", "simo_wong_top", "neumann", "gravity_gradient_pitch")
ORIENTATION_RTOLS = (1e-6, 1e-9, 1e-12)


def cell(text: str) -> str:
    """Text for a table cell: a ``|`` would split it (``\\|`` renders as ``|``)."""
    return text.replace("|", "\\|")


def power(x: float) -> str:
    """A power of ten as the page writes it (``1e-6``, not ``1e-06``)."""
    return f"1e{round(math.log10(x))}"


def sci(x: float) -> str:
    """Two digits in the page's style (``7.3e-6``, not ``7.3e-06``)."""
    return re.sub(r"e([+-])0(\d)", r"e\1\2", f"{x:.1e}")


def grid(case, n: int = 51) -> np.ndarray:
    """The first 10 time units of the case (all of a shorter span), ``n`` times."""
    t0 = case.t_span[0]
    return np.linspace(t0, t0 + min(10.0, case.t_span[1] - t0), n)


def measure(case) -> dict:
    """The figures of one row of the case table."""
    t = grid(case)
    exact = case.exact(t)
    drift = case.report(t, exact).drift
    sol = solve_ivp(case.rhs, (t[0], t[-1]), case.y0, method="DOP853", rtol=RTOL, atol=RTOL, t_eval=t)
    sc = case.solution.case
    return {"name": case.name, "model": case.model, "description": case.description,
            "method": f"`{case.method}`" + (f" ({sc})" if sc else ""), "size": case.y0.size,
            "t0": case.score([t[0]], case.y0[None, :]).worst,
            "integrals": max((float(np.max(v)) for v in drift.values()), default=0.0),
            "dop853": case.score(sol.t, sol.y).worst if sol.success else float("nan")}


def case_table(rows: list[dict]) -> str:
    lines = [f"Measured by DOP853 (`rtol = atol = {power(RTOL)}`) on the case's `rhs` against `exact` over the first 10 "
             "time units, 51 times, worst group (tests/test_reference.py, "
             "`test_dop853_on_the_case_ode_agrees_with_exact`, asserts at most 10 times these figures and at most "
             f"1e-7).  `exact(t0)` reproduces `y0` to {sci(max(r['t0'] for r in rows))} or better, and the first "
             f"integrals along `exact` hold to {sci(max(r['integrals'] for r in rows))} or better.",
             "",
             "| name | model | description | closed form (`method`, case) | state | DOP853 vs exact |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| `{r['name']}` | {cell(r['model'])} | {cell(r['description'])} | {r['method']} | {r['size']} | "
                     f"{sci(r['dop853'])} |")
    return "\n".join(lines)


def orientation_table() -> str:
    """DOP853 through :func:`thetasol.reference.benchmark` at three tolerances on a few cases."""
    cases = reference.cases(list(ORIENTATION))
    table, _ = reference.benchmark(partial(solve_ivp, method="DOP853"), cases, rtols=ORIENTATION_RTOLS, plot=False)
    head = " | ".join(f"rtol {power(r)}" for r in ORIENTATION_RTOLS)
    lines = ["DOP853 over a few cases of the catalogue, for orientation (errors are the worst group over `t_span`):",
             "", f"| case | {head} | nfev at {power(ORIENTATION_RTOLS[-1])} |", "|---|" + "---|" * (len(ORIENTATION_RTOLS) + 1)]
    for name in ORIENTATION:
        rows = {r["rtol"]: r for r in table if r["case"] == name}
        errs = " | ".join(sci(rows[r]['error']) for r in ORIENTATION_RTOLS)
        lines.append(f"| `{name}` | {errs} | {rows[ORIENTATION_RTOLS[-1]]['nfev']} |")
    return "\n".join(lines)


def main() -> None:
    page = docs_page(PAGE)
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()
    with docs_section(page, SCRIPT, "cases"):
        print(machine_info())
        print()
        print(case_table([measure(c) for c in reference.cases()]))
    with docs_section(page, SCRIPT, "dop853"):
        print(machine_info())
        print()
        print(orientation_table())


if __name__ == "__main__":
    main()
