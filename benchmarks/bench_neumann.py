"""Neumann branch of solve_rotation: error against heyoka (80-bit, rtol 1e-19) at the issue's times,
set-up time and evaluation cost per time (batch of 1000 times in [0, 1000]), best of 3 runs.

Run: PYTHONPATH=. python benchmarks/bench_neumann.py  (needs heyoka for the error columns)."""
import os
import platform
import sys
import time

import numpy as np
import scipy

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))
from test_neumann import CASES  # noqa: E402

from thetasol import integrate_rotation, solve_rotation  # noqa: E402

T_FAR = np.array([0.7, 3.1, 17.3, 102.0, 997.0, 4002.0])


def best(f, n=3):
    out = []
    for _ in range(n):
        t0 = time.perf_counter()
        f()
        out.append(time.perf_counter() - t0)
    return min(out)


def main():
    cpu = next((ln.split(":", 1)[1].strip() for ln in open("/proc/cpuinfo") if ln.startswith("model name")), "?")
    print(f"# {cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, numpy {np.__version__}, "
          f"scipy {scipy.__version__}")
    try:
        import heyoka  # noqa: F401
        have = True
    except ImportError:
        have = False
    tt = np.linspace(0.0, 1000.0, 1000)
    print("| case | method | set-up (s) | us/time | " + " | ".join(f"t={t:g}" for t in T_FAR) + " |")
    print("|---|---|---|---|" + "---|" * len(T_FAR))
    for label, J, a, Q0, w0, _ in CASES:
        setup = best(lambda: solve_rotation(J, a, Q0, w0))
        sol = solve_rotation(J, a, Q0, w0)
        ev = best(lambda: sol(tt)) / tt.size * 1e6
        errs = ["-"] * len(T_FAR)
        if have:
            w, Q = sol(T_FAR)
            wr, Qr = integrate_rotation(J, a, Q0, w0, T_FAR, method="heyoka", dtype="ldbl", rtol=1e-19)
            e = np.maximum(np.abs(w - wr).max(-1), np.abs(Q - Qr).max((-1, -2)))
            errs = [f"{x:.1e}" for x in e]
        print(f"| {label} | {sol.method} | {setup:.3f} | {ev:.0f} | " + " | ".join(errs) + " |")


if __name__ == "__main__":
    main()
