"""Neumann branch of solve_rotation: error against heyoka (80-bit, rtol 1e-19) at the issue's times,
set-up time and evaluation cost per time (a batch of 1000 times spread over [0, 1e4]; best of 5, wall
clock and process CPU time, which is less disturbed by other jobs on a shared machine).

Run: OPENBLAS_NUM_THREADS=1 PYTHONPATH=. python benchmarks/bench_neumann.py  (needs heyoka for the
error columns)."""
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))
sys.path.insert(0, os.path.dirname(__file__))
from _common import best_of, machine_info  # noqa: E402
from test_neumann import CASES, T_FAR  # noqa: E402

from thetasol import integrate_rotation, solve_rotation  # noqa: E402


def main():
    print("# " + machine_info("heyoka"))
    try:
        import heyoka  # noqa: F401
        have = True
    except ImportError:
        have = False
    tt = np.sort(np.random.default_rng(0).uniform(0.0, 1e4, 1000))
    print("| case | method | set-up (s) | us/time | us/time (CPU) | "
          + " | ".join(f"t={t:g}" for t in T_FAR) + " |")
    print("|---|---|---|---|---|" + "---|" * len(T_FAR))
    for label, J, a, Q0, w0, _ in CASES:
        setup, sol = best_of(lambda: solve_rotation(J, a, Q0, w0))
        ev = best_of(lambda: sol(tt), repeat=5)[0] / tt.size * 1e6
        cpu = best_of(lambda: sol(tt), repeat=5, clock=time.process_time)[0] / tt.size * 1e6
        errs = ["-"] * len(T_FAR)
        if have:
            w, Q = sol(T_FAR)
            wr, Qr = integrate_rotation(J, a, Q0, w0, T_FAR, method="heyoka", dtype="ldbl", rtol=1e-19)
            e = np.maximum(np.abs(w - wr).max(-1), np.abs(Q - Qr).max((-1, -2)))
            errs = [f"{x:.1e}" for x in e]
        print(f"| {label} | {sol.method} | {setup:.3f} | {ev:.1f} | {cpu:.1f} | " + " | ".join(errs) + " |")


if __name__ == "__main__":
    main()
