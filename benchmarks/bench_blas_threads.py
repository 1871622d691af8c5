"""The library's own BLAS limit against the BLAS's default threads, in one run.

Run WITHOUT ``OPENBLAS_NUM_THREADS`` (the point is the default install):

    python benchmarks/bench_blas_threads.py [--cases generic,saddle,...]

For each reference body (tests/data/rotation/refs.json): the set-up of solve_rotation, dense
evaluation (2001 times on [0, 1000], per time) and one far time (t = 1e6), once with the library's
limit (``thetasol.core.threads.LIMIT = 1``, the default) and once with ``LIMIT = None`` (the BLAS on
its default threads, one per core).  Best of 3 for the evaluations, one set-up each.  One time of a
closed form runs without the limit either way (``Solution._run``): its two columns differ by noise.
"""
from __future__ import annotations

import argparse
import json
import pathlib

import numpy as np
from _common import best_of, docs_page, docs_section, machine_info

from thetasol import inertia, solve_rotation
from thetasol.core import threads

REFS = pathlib.Path(__file__).resolve().parent.parent / "tests" / "data" / "rotation" / "refs.json"


def measure(data):
    args = (inertia(np.diag(data["J"])), np.array(data["a"]), np.array(data["Q0"]), np.array(data["omega0"]))
    t_dense, t_far = np.linspace(0.0, 1000.0, 2001), np.array([1e6])
    ts, sol = best_of(lambda: solve_rotation(*args), repeat=1)
    td, _ = best_of(lambda: sol(t_dense), repeat=3)
    tf, _ = best_of(lambda: sol(t_far), repeat=5)
    return ts, td / t_dense.size, tf


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", default=None, help="comma-separated reference bodies (default: all)")
    args = ap.parse_args(argv)
    refs = json.loads(REFS.read_text())
    names = args.cases.split(",") if args.cases else list(refs)
    import scipy.linalg  # noqa: F401
    import threadpoolctl
    blas = [f"{i['internal_api']} {i['num_threads']} threads" for i in threadpoolctl.threadpool_info()
            if i["user_api"] == "blas"]
    print(f"machine: {machine_info('heyoka')}; BLAS found: {', '.join(blas)}\n")
    print("| case | set-up, limit 1 (s) | set-up, default BLAS (s) | dense, limit 1 (us/time) | "
          "dense, default BLAS (us/time) | t = 1e6, limit 1 (us) | t = 1e6, default BLAS (us) |")
    print("|---|---|---|---|---|---|---|")
    ratios = []
    for name in names:
        threads.LIMIT = 1
        lim = measure(refs[name])
        threads.LIMIT = None
        dflt = measure(refs[name])
        threads.LIMIT = 1
        ratios.append(dflt[1] / lim[1])
        print(f"| {name} | {lim[0]:.3f} | {dflt[0]:.3f} | {lim[1] * 1e6:.1f} | {dflt[1] * 1e6:.1f} | "
              f"{lim[2] * 1e6:.0f} | {dflt[2] * 1e6:.0f} |", flush=True)
    print(f"\ndense evaluation, default BLAS / limit 1: median {np.median(ratios):.2f}, "
          f"range {min(ratios):.2f} .. {max(ratios):.2f}")


if __name__ == "__main__":
    with docs_section(docs_page("docs/bench_theta_rotation.md"), "benchmarks/bench_blas_threads.py"):
        main()
