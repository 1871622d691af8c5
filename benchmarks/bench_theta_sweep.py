"""The costs of bench_theta_rotation on random bodies of every regime, as ratios to heyoka.

    python benchmarks/bench_theta_sweep.py [--n 3] [--seed 0] [--clock cpu]

The bodies are those of benchmarks/bench_units_sweep.py (eleven regimes: generic, nearly symmetric,
symmetric, rank-one, rank-two, nearly isotropic, tiny a, huge a, fast spin, zero spin, near relative
equilibrium; ``--n`` per regime, units of order one).  Times are natural: ``T = 1000 / w``,
``w = max(|omega0|, sqrt|a|)``.  Per body, in one run:

* **set-up**: ``solve_rotation``, best of 3 (after one warm-up body), against heyoka's propagation to ``T``
  (compiled once, float64, tol 1e-16, 20001 output times);
* **dense**: the solution's cost per time on those 20001 times against heyoka's, best of 3;
* **one far time**: one call at ``t = 1e6 / w``, in dense points;
* **agreement**: max over the times of |omega - omega_heyoka| / max|omega| and |Q - Q_heyoka| (heyoka in
  float64: a cross-check, not an error; the 80-bit errors are bench_units_sweep's).

A body the closed forms refuse (``ClosedFormUnavailable``) is counted and left out of the ratios.
"""
from __future__ import annotations

import argparse
import os
import time
import warnings

import numpy as np
from _common import best_of, docs_page, docs_section, machine_info
from bench_theta_rotation import CLOCK, heyoka_integrator, heyoka_run
from bench_units_sweep import REGIMES, _body

from thetasol import ClosedFormUnavailable, inertia, solve_rotation

N_DENSE = 20001


def natural_rate(a: np.ndarray, w0: np.ndarray) -> float:
    """The body's natural rate max(|omega0|, sqrt|a|) (the unit of time of the sweep)."""
    return float(max(np.linalg.norm(w0), np.sqrt(np.abs(np.linalg.eigvalsh(a)).max()), 1e-300))


def bench_body(regime: str, J, a, Q0, w0, ta) -> dict:
    """One body's row: costs as in the module docstring, ``None`` ratios if refused."""
    rate = natural_rate(a, w0)
    grid = np.linspace(0.0, 1000.0 / rate, N_DENSE)
    row = {"regime": regime}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            row["setup"], sol = best_of(lambda: solve_rotation(inertia(J), a, Q0, w0), repeat=3, clock=CLOCK[0])
    except ClosedFormUnavailable:
        row["method"] = "refused"
        return row
    row["method"] = sol.method
    row["dense"], (w, Q) = best_of(lambda: sol(grid), repeat=3, clock=CLOCK[0])
    row["dense"] /= grid.size
    row["far"], _ = best_of(lambda: sol(np.array([1e6 / rate])), repeat=7, clock=CLOCK[0])
    row["hy_run"], (wh, Qh) = best_of(lambda: heyoka_run(ta, J, a, Q0, w0, grid), repeat=3, clock=CLOCK[0])
    row["hy_dense"] = row["hy_run"] / grid.size
    row["agree"] = float(max(np.abs(w - wh).max() / max(np.abs(wh).max(), 1e-300), np.abs(Q - Qh).max()))
    return row


def _ratios(rows: list[dict]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    done = [r for r in rows if "dense" in r]
    return (np.array([r["setup"] / r["hy_run"] for r in done]), np.array([r["dense"] / r["hy_dense"] for r in done]),
            np.array([r["far"] / r["dense"] for r in done]))


def _stat(x: np.ndarray) -> str:
    return f"{np.median(x):.2f} / {x.max():.2f}" if x.size else "-"


def print_table(rows: list[dict]) -> None:
    print("| regime | bodies | refused | methods | set-up (ms), median | set-up / heyoka, median / max "
          "| dense / heyoka, median / max | one far time in dense points, median / max | agreement with "
          "heyoka float64, max |")
    print("|---" * 9 + "|")
    for regime in REGIMES:
        rs = [r for r in rows if r["regime"] == regime]
        done = [r for r in rs if "dense" in r]
        su, de, fa = _ratios(rs)
        methods = ", ".join(sorted({r["method"] for r in done}))
        setup = f"{np.median([r['setup'] for r in done]) * 1e3:.0f}" if done else "-"
        agree = f"{max(r['agree'] for r in done):.1e}" if done else "-"
        print(f"| {regime} | {len(rs)} | {len(rs) - len(done)} | {methods} | {setup} | {_stat(su)} | {_stat(de)} "
              f"| {_stat(fa)} | {agree} |", flush=True)
    su, de, fa = _ratios(rows)
    print(f"\nall solved bodies ({su.size} of {len(rows)}): set-up / heyoka median {np.median(su):.2f}, "
          f"max {su.max():.2f} (targets: median <= 2, every body <= 6); dense / heyoka median {np.median(de):.2f}, "
          f"max {de.max():.2f} (targets: median <= 0.5, every body <= 2); one far time median {np.median(fa):.1f} "
          f"dense points (target <= 3)")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=3, help="bodies per regime")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--clock", choices=("wall", "cpu"), default="wall")
    args = ap.parse_args(argv)
    CLOCK[0] = time.process_time if args.clock == "cpu" else time.perf_counter
    print(f"machine: {machine_info('heyoka')}; load average at start {os.getloadavg()[0]:.1f}")
    print(f"clock: {args.clock} time; {args.n} bodies per regime, seed {args.seed}; dense: {N_DENSE} times on "
          "[0, 1000 / w]\n")
    rng = np.random.default_rng(args.seed)
    ta, _ = heyoka_integrator()
    J, a, Q0, w0 = _body("generic", np.random.default_rng(10**6))
    solve_rotation(inertia(J), a, Q0, w0)        # first-call costs, not counted
    rows = [bench_body(regime, *_body(regime, rng), ta) for _ in range(args.n) for regime in REGIMES]
    print_table(rows)


if __name__ == "__main__":
    with docs_section(docs_page("docs/bench_theta_rotation.md"), "benchmarks/bench_theta_sweep.py"):
        main()
