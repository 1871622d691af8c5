"""The theta-function rotation on the 13 reference cases: error, set-up cost and cost per time point.

For each case of tests/data/rotation/refs.json (heyoka in quadruple precision, tol 1e-25, with the
body's exact inverse inertia): max error in omega and Q of ``solve_rotation`` at the reference times
{0.7, 3.1, 17.3, 102, 997, 4002} (and at t <= 997), the set-up as the best of three runs in process
CPU time, and the evaluation cost per time point on 2001 times in [0, 1000] (best of three, after a
warm-up call), and what the exact exponents changed in the fitted ones (``diagnostics['nu_exact_change']``,
``diagnostics['node_gap_change']`` for symmetric bodies).  Results of a recorded run: docs/theta_rotation.md ("Accuracy and cost").

Run:  OPENBLAS_NUM_THREADS=1 python benchmarks/bench_theta_references.py
"""
from __future__ import annotations

import json
import pathlib
import time

import numpy as np
from _common import best_of, docs_page, docs_section, machine_info

from thetasol import inertia, solve_rotation

REFS = pathlib.Path(__file__).resolve().parent.parent / "tests" / "data" / "rotation" / "refs.json"


def main() -> None:
    refs = json.loads(REFS.read_text())
    print(f"machine: {machine_info()}\n")
    print("| case | method | error (t <= 4002) | error (t <= 997) | set-up CPU (s) | per time point (us) "
          "| exact-rate change | node-gap change |")
    print("|---|---|---|---|---|---|---|---|")
    dense = np.linspace(0.0, 1000.0, 2001)
    for name, r in refs.items():
        J, a, Q0, w0 = np.diag(r["J"]), np.array(r["a"]), np.array(r["Q0"]), np.array(r["omega0"])
        setup, sol = best_of(lambda J=J, a=a, Q0=Q0, w0=w0: solve_rotation(inertia(J), a, Q0, w0), clock=time.process_time)
        w, Q = sol(np.array(r["t"]))
        err = np.maximum(np.abs(w - np.array(r["omega"])).max(axis=1),
                         np.abs(Q - np.array(r["Q"])).max(axis=(1, 2)))
        sol(dense)
        run, _ = best_of(lambda sol=sol: sol(dense), clock=time.process_time)
        d = sol.diagnostics
        gap = "" if d["node_gap_change"] is None else f"{d['node_gap_change']:.1e}"
        print(f"| {name} | {sol.method} | {err.max():.1e} | {err[:5].max():.1e} | {setup:.2f} | "
              f"{run / dense.size * 1e6:.1f} | {d['nu_exact_change']:.1e} | {gap} |")


if __name__ == "__main__":
    with docs_section(docs_page("docs/theta_rotation.md"), "benchmarks/bench_theta_references.py"):
        main()
