"""Error against cost for gyrostats with rotors (thetasol.solve_gyrostat(..., rotors=...)).

Run:  python benchmarks/bench_gyrostat_rotors.py

Prints, for carriers with 1-3 rotors, near-separatrix motions (mc ~ 1e-4, 1e-8) and a motion on
the separatrix: the set-up time with and without rotors, the terms of the rotor series, the cost
per time point of ``rotor_angles`` and of ``sol(t)`` (batches of 1e5 times in [0, 1e6]), and the
largest error of omega (relative), Q and the rotor angles (radians) over [0, 1000] ([0, 30] on
the separatrix) against heyoka (80-bit) integrating the full carrier-plus-rotors system, next to
that reference's own spread when omega0 moves by 1e-15 (the conditioning) and its wall time.
The bodies and the reference are those of tests/test_gyrostat_rotors.py.
"""
from __future__ import annotations

import os
import sys
import time

import numpy as np
from _common import best_of, docs_page, docs_section, machine_info

from thetasol import inertia, solve_gyrostat

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))
import test_gyrostat_rotors as T  # noqa: E402
from conftest import rand_Q  # noqa: E402


def main():
    print(machine_info("heyoka"))
    cases = [("1 rotor", T.make_body(1, 1), 1000.0), ("2 rotors", T.make_body(2, 2), 1000.0),
             ("3 rotors", T.make_body(3, 3), 1000.0), ("mc~1e-4", T.separatrix_body(1e-4), 1000.0),
             ("mc~1e-8", T.separatrix_body(1e-8), 1000.0), ("separatrix", T.separatrix_body(0.0), 30.0)]
    print("| case | method | setup (no rotors / rotors) | terms | angles / point | (omega, Q) / point "
          "| error omega, Q, phi | conditioning omega, Q, phi | reference time |")
    print("|---|---|---|---|---|---|---|---|---|")
    tt = np.linspace(0.0, 1e6, 100_000)
    for name, body, tmax in cases:
        rot = T.solver_rotors(body)
        N = np.sum([r["p"] * np.asarray(r["axis"]) for r in rot], axis=0)
        t0, _ = best_of(lambda: solve_gyrostat(inertia(body["J"]), N, np.eye(3), body["omega0"]))  # noqa: B023
        t1, sol = best_of(lambda: solve_gyrostat(inertia(body["J"]), None, np.eye(3), body["omega0"], rotors=rot))  # noqa: B023
        ta, _ = best_of(lambda: sol.rotor_angles(tt))  # noqa: B023
        te, _ = best_of(lambda: sol(tt))  # noqa: B023
        Q0 = rand_Q(np.random.default_rng(5))
        t = np.linspace(0.0, tmax, 51)
        c0 = time.perf_counter()
        _, err, cond, _ = T.compare(body, Q0, t)
        cref = (time.perf_counter() - c0) / 2
        print(f"| {name} | {sol.method} | {t0 * 1e3:.0f} / {t1 * 1e3:.0f} ms | {sol.diagnostics['rotor_series_terms']} "
              f"| {ta / tt.size * 1e6:.2f} us | {te / tt.size * 1e6:.2f} us "
              f"| {err['omega']:.1e}, {err['Q']:.1e}, {err['phi']:.1e} "
              f"| {cond['omega']:.1e}, {cond['Q']:.1e}, {cond['phi']:.1e} | {cref:.2f} s |")


if __name__ == "__main__":
    with docs_section(docs_page("docs/gyrostat.md"), "benchmarks/bench_gyrostat_rotors.py"):
        main()
