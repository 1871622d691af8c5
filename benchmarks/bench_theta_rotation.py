"""Speed against error: the theta-function rotation in a quadratic potential against numerical integrators.

Everything is measured in one run on this machine:

* dense output on [0, 1000] (2001 times) and single far-time queries (t = 1e3, 1e4);
* thetasol.solve_rotation (set-up and evaluation timed separately), scipy's DOP853 at several
  tolerances (integrate_rotation), the symplectic splitting integrator, heyoka float64 (if
  installed; its JIT compilation is timed separately);
* errors against heyoka in 80-bit extended precision (tol 1e-19), within 4e-19..3.4e-14 of quadruple
  precision (tol 1e-25) on the default cases and the symmetric body to t = 1e4; not adequate next to an
  unstable relative equilibrium (5e-10 there, tests/data/rotation/make_refs.py).

Run:  OPENBLAS_NUM_THREADS=1 python benchmarks/bench_theta_rotation.py [--quick] [--plot PNG]
Writes a markdown table to stdout (docs/bench_theta_rotation.md holds a recorded run).
"""
from __future__ import annotations

import argparse
import json
import pathlib
import sys

import numpy as np
from _common import best_of, machine_info

from thetasol import integrate_rotation, solve_rotation

REFS = pathlib.Path(__file__).resolve().parent.parent / "tests" / "data" / "rotation" / "refs.json"


def have_heyoka():
    try:
        import heyoka  # noqa: F401
        return True
    except ImportError:
        return False


def err(w, Q, ref):
    wr, Qr = ref
    return float(max(np.abs(w - wr).max(), np.abs(Q - Qr).max()))


def bench_case(name, data, quick):
    J, a, Q0, w0 = (np.diag(data["J"]), np.array(data["a"]), np.array(data["Q0"]), np.array(data["omega0"]))
    rows = []
    t_dense = np.linspace(0.0, 1000.0, 2001)
    ref_dense = integrate_rotation(J, a, Q0, w0, t_dense, method="heyoka", dtype="ldbl", rtol=1e-19)
    # theta functions
    ts, sol = best_of(lambda: solve_rotation(J, a, Q0, w0), repeat=1)
    te, (w, Q) = best_of(lambda: sol(t_dense), repeat=3)
    rows.append(("dense", f"theta ({sol.method})", ts, te, err(w, Q, ref_dense)))
    for rtol in ((1e-10, 1e-13) if quick else (1e-8, 1e-10, 1e-12, 1e-13)):
        tt, (w, Q) = best_of(lambda r=rtol: integrate_rotation(J, a, Q0, w0, t_dense, rtol=r), repeat=1)
        rows.append(("dense", f"DOP853 rtol {rtol:g}", 0.0, tt, err(w, Q, ref_dense)))
    if not quick:
        tt, (w, Q) = best_of(lambda: integrate_rotation(J, a, Q0, w0, t_dense, method="splitting", step=1e-2), repeat=1)
        rows.append(("dense", "splitting (order 6, h = 0.01)", 0.0, tt, err(w, Q, ref_dense)))
    if have_heyoka():
        tc, _ = best_of(lambda: integrate_rotation(J, a, Q0, w0, t_dense[:2], method="heyoka", rtol=1e-16), repeat=1)
        tt, (w, Q) = best_of(lambda: integrate_rotation(J, a, Q0, w0, t_dense, method="heyoka", rtol=1e-16), repeat=1)
        rows.append(("dense", "heyoka float64 tol 1e-16", tc, tt, err(w, Q, ref_dense)))
    # single far-time queries
    for tf in (1e3, 1e4):
        tq = np.array([tf])
        ref = integrate_rotation(J, a, Q0, w0, tq, method="heyoka", dtype="ldbl", rtol=1e-19)
        te, (w, Q) = best_of(lambda: sol(tq), repeat=5)
        rows.append((f"t = {tf:g}", f"theta ({sol.method})", ts, te, err(w, Q, ref)))
        tt, (w, Q) = best_of(lambda: integrate_rotation(J, a, Q0, w0, tq, rtol=1e-13), repeat=1)
        rows.append((f"t = {tf:g}", "DOP853 rtol 1e-13", 0.0, tt, err(w, Q, ref)))
        if have_heyoka():
            tt, (w, Q) = best_of(lambda: integrate_rotation(J, a, Q0, w0, tq, method="heyoka", rtol=1e-16), repeat=1)
            rows.append((f"t = {tf:g}", "heyoka float64 tol 1e-16", 0.0, tt, err(w, Q, ref)))
    tq = np.array([1e6])
    te, (w, Q) = best_of(lambda: sol(tq), repeat=5)
    rows.append(("t = 1e6", f"theta ({sol.method})", ts, te, float("nan")))
    return rows


def plot(allrows, path):
    """Error against total cost of the dense query: colour = case, marker = method."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    kinds = [("theta", "o", 9), ("DOP853", "s", 6), ("splitting", "D", 6), ("heyoka", "^", 7)]
    cases = list(dict.fromkeys(nm for nm, *_ in allrows))
    colour = {nm: plt.cm.tab10(i) for i, nm in enumerate(cases)}
    fig, ax = plt.subplots(figsize=(8, 4.8))
    for nm, q, m, ts, tr, e in allrows:
        if q == "dense":
            marker, size = next((mk, sz) for key, mk, sz in kinds if m.startswith(key))
            ax.loglog(ts + tr, max(e, 1e-16), marker, color=colour[nm], markersize=size, alpha=0.85)
    ax.set_xlabel("total time for 2001 outputs on [0, 1000] (s)")
    ax.set_ylabel("max error in omega and Q")
    ax.grid(True, which="both", alpha=0.3)
    first = ax.legend([Line2D([], [], ls="", marker="o", color=colour[nm]) for nm in cases], cases,
                      fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), title="case")
    ax.add_artist(first)
    ax.legend([Line2D([], [], ls="", marker=mk, color="0.3") for _, mk, _ in kinds],
              ["theta (set-up + run)", "DOP853 rtol 1e-8 .. 1e-13", "splitting, order 6", "heyoka float64"],
              fontsize=7, loc="lower left", bbox_to_anchor=(1.01, 0.0), title="method")
    fig.savefig(path, dpi=130, bbox_inches="tight")
    print(f"\nplot written to {path}")


def _rows_from_table(text):
    """The rows of a table this script printed (for --replot)."""
    rows = []
    for line in text.splitlines():
        f = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(f) == 7 and f[0] not in ("case", "---"):
            rows.append((f[0], f[1], f[2], float(f[3]), float(f[4]), float(f[6])))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="fewer tolerances, no splitting")
    ap.add_argument("--cases", default="generic,saddle,rank_one,near_stable_equilibrium,symmetric_oblate")
    ap.add_argument("--plot", default=None, help="write an error-against-cost plot (needs matplotlib)")
    ap.add_argument("--replot", default=None, help="only redraw --plot from a saved output of this script")
    args = ap.parse_args(argv)
    if args.replot:
        plot(_rows_from_table(open(args.replot).read()), args.plot or "bench_theta_rotation.png")
        return
    refs = json.loads(REFS.read_text())
    print(f"machine: {machine_info('heyoka')}")
    print("errors: max over omega and Q against heyoka 80-bit (tol 1e-19); time in seconds (best of runs)\n")
    print("| case | query | method | set-up (s) | run (s) | per time (us) | max error |")
    print("|---|---|---|---|---|---|---|")
    allrows = []
    for name in args.cases.split(","):
        rows = bench_case(name, refs[name], args.quick)
        for q, m, ts, tr, e in rows:
            n = 2001 if q == "dense" else 1
            print(f"| {name} | {q} | {m} | {ts:.3g} | {tr:.3g} | {tr / n * 1e6:.3g} | {e:.1e} |")
            allrows.append((name, q, m, ts, tr, e))
        sys.stdout.flush()
    if args.plot:
        plot(allrows, args.plot)


if __name__ == "__main__":
    main()
