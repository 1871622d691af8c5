"""The theta-function rotation against heyoka and DOP853, per reference body, as ratios to heyoka.

Measured in one run on this machine, for every reference body of tests/data/rotation/refs.json:

* **set-up**: solve_rotation (theta, or the body's closed form), best of 3 repeats, and the first
  set-up of the body ("new body": the curve engine's caches then hold nothing of its curve, as for any
  body a program meets once); heyoka's JIT compilation of one parametric float64 integrator, once for all
  bodies, reported apart (it is not a per-body cost);
* **dense**: the cost per output time on [0, 1000] with 20001 equally spaced times (and the
  reference times below 1000): theta's evaluation; heyoka float64 (tol 1e-16) propagate_grid, without
  compilation; scipy's DOP853 at rtol 1e-13 (integrate_rotation);
* **far time** t = 1e6: theta's cost of one evaluation (it reduces the arguments modulo the periods),
  and that cost in dense points; heyoka and DOP853 would integrate the whole way: their figure is
  their measured time to t = 1000 times 1000 (marked "est.");
* **far dense**: theta's cost per time of 20001 times on [1e6, 1e6 + 1000] over its dense cost on
  [0, 1000] (best of 3 each); no reference reaches there, so instead of an error the table gives the
  drift of two first integrals over each batch: energy and ``I2`` (4.13) (``= -2 |m|^2`` without
  potential), max ``|I(t) - I(0)|`` relative to the sum of the magnitudes of their terms at t = 0;
* **errors**: max over the components of omega and Q against the stored 80-bit references
  (heyoka in extended precision, tol 1e-19; tests/data/rotation/refs.json) at t = 0.7, 3.1, 17.3,
  102, 997; theta also at t = 4002;
* **cold start**: a fresh Python process importing thetasol and solving the generic body (imports,
  caches and any compilation included).

Ratios are to heyoka: set-up / heyoka's propagation to t = 1000, dense theta / dense heyoka.

Run:  python benchmarks/bench_theta_rotation.py [--quick] [--cases a,b] [--plot PNG] [--clock cpu] [--write-docs]
(``--quick``: five bodies, no DOP853; ``--write-docs``: the run replaces the generated section of
docs/bench_theta_rotation.md.)
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import subprocess
import sys
import time

import numpy as np
from _common import best_of, docs_page, docs_section, machine_info

from thetasol import inertia, integrate_rotation, invariants, solve_rotation
from thetasol.integrators.rotation import rotation_expressions

REFS = pathlib.Path(__file__).resolve().parent.parent / "tests" / "data" / "rotation" / "refs.json"
QUICK = "generic,saddle,rank_one,near_unstable_equilibrium,symmetric_oblate"
T_END, N_DENSE, T_FAR = 1000.0, 20001, 1e6
#: the clock of every timing: wall (perf_counter) or this process's CPU time (--clock cpu, for a shared
#: machine: every method here runs on one thread, so on a quiet machine the two agree)
CLOCK = [time.perf_counter]


# -- heyoka float64, compiled once: the body enters through runtime parameters -------------------

def heyoka_integrator():
    """(taylor_adaptive in float64 at tol 1e-16 with J, I^-1 and a as parameters, compile seconds)."""
    import heyoka as hy

    start = CLOCK[0]()
    xs = hy.make_vars(*[f"m{i}" for i in range(3)], *[f"q{i}{j}" for i in range(3) for j in range(3)])
    m, Q = xs[:3], [xs[3 + 3 * i: 6 + 3 * i] for i in range(3)]
    p = [hy.par[k] for k in range(27)]
    Iinv, J, A = ([p[o + 3 * i: o + 3 * i + 3] for i in range(3)] for o in (0, 9, 18))
    ta = hy.taylor_adaptive(list(zip(xs, rotation_expressions(m, Q, Iinv, J, A), strict=True)), np.zeros(12), tol=1e-16,
                            pars=np.zeros(27))
    return ta, CLOCK[0]() - start


def heyoka_run(ta, J, a, Q0, w0, grid):
    """(omega, Q) on ``grid`` (starting at 0): the float64 data as integrate_rotation's heyoka path sets them."""
    I = np.trace(J) * np.eye(3) - J
    Iinv = np.linalg.inv(I)
    ta.pars[:] = np.concatenate([Iinv.ravel(), J.ravel(), a.ravel()])
    ta.time = 0.0
    ta.state[:] = np.concatenate([I @ w0, Q0.ravel()])
    st = ta.propagate_grid(grid)[-1]
    return st[:, :3] @ Iinv.T, st[:, 3:].reshape(-1, 3, 3)


# -- one body -------------------------------------------------------------------------------------

def err(w, Q, wr, Qr):
    return float(max(np.abs(w - wr).max(), np.abs(Q - Qr).max()))


def drift(J, a, Q0, w0, w, Q) -> float:
    """Max relative drift of the energy and of I2 (4.13) over (w, Q) from the initial data (module docstring)."""
    I = np.trace(J) * np.eye(3) - J
    T0 = 0.5 * w0 @ I @ w0
    u0 = -(Q0.T @ a @ Q0)
    M0 = I @ w0
    scale_E = abs(T0) + abs(0.5 * np.trace(u0 @ J))
    scale_I2 = float(M0 @ M0) * 2 + abs(2 * np.trace(J @ J @ u0))   # |tr M^2| = 2 |m|^2
    i0, it = invariants(inertia(J), a, Q0, w0), invariants(inertia(J), a, Q, w)
    return float(max(np.abs(it["energy"] - i0["energy"]).max() / scale_E,
                     np.abs(it["I2"] - i0["I2"]).max() / scale_I2))


def bench_body(name, data, ta, quick):
    J, a, Q0, w0 = (np.diag(data["J"]), np.array(data["a"]), np.array(data["Q0"]), np.array(data["omega0"]))
    tr, wr, Qr = np.array(data["t"]), np.array(data["omega"]), np.array(data["Q"])
    near = tr <= T_END
    grid = np.union1d(np.linspace(0.0, T_END, N_DENSE), tr[near])
    at_refs = np.searchsorted(grid, tr[near])
    row = {"case": name}
    # a body new to the process (no cache holds anything of its curve), then repeats of it
    row["setup_new"], _ = best_of(lambda: solve_rotation(inertia(J), a, Q0, w0), repeat=1, clock=CLOCK[0])
    row["setup"], sol = best_of(lambda: solve_rotation(inertia(J), a, Q0, w0), repeat=3, clock=CLOCK[0])
    row["method"] = sol.method
    row["dense"], (w, Q) = best_of(lambda: sol(grid), repeat=3, clock=CLOCK[0])
    row["dense"] /= grid.size
    row["drift"] = drift(J, a, Q0, w0, w, Q)
    far_grid = T_FAR + np.linspace(0.0, T_END, N_DENSE)
    row["far_dense"], (wf, Qf) = best_of(lambda: sol(far_grid), repeat=3, clock=CLOCK[0])
    row["far_dense"] /= far_grid.size
    row["drift_far"] = drift(J, a, Q0, w0, wf, Qf)
    row["far"], _ = best_of(lambda: sol(np.array([T_FAR])), repeat=7, number=100, clock=CLOCK[0])
    row["err"] = err(w[at_refs], Q[at_refs], wr[near], Qr[near])
    w4, Q4 = sol(tr)
    row["err_4002"] = err(w4, Q4, wr, Qr)
    hy_run, (w, Q) = best_of(lambda: heyoka_run(ta, J, a, Q0, w0, grid), repeat=3, clock=CLOCK[0])
    row["hy_run"], row["hy_dense"], row["hy_err"] = hy_run, hy_run / grid.size, err(w[at_refs], Q[at_refs], wr[near],
                                                                                     Qr[near])
    if not quick:
        dop, (w, Q) = best_of(lambda: integrate_rotation(inertia(J), a, Q0, w0, rtol=1e-13)(grid), repeat=1,
                              clock=CLOCK[0])
        row["dop_run"], row["dop_dense"], row["dop_err"] = dop, dop / grid.size, err(w[at_refs], Q[at_refs],
                                                                                  wr[near], Qr[near])
    return row


def first_setup(data) -> float:
    """Seconds of this process's first set-up: its one-off costs (the imports of the set-up's modules, the
    BLAS controllers) stay out of the table.  The body is the given one with omega0 scaled by 1.01, so that
    the table's first body is new to the process too."""
    args = (inertia(np.diag(data["J"])), np.array(data["a"]), np.array(data["Q0"]), 1.01 * np.array(data["omega0"]))
    return best_of(lambda: solve_rotation(*args), repeat=1, clock=CLOCK[0])[0]


def cold_start(data) -> float:
    """Seconds for a fresh process to import thetasol and solve the body (interpreter start excluded)."""
    clock = "process_time" if CLOCK[0] is time.process_time else "perf_counter"
    code = (f"import time; t0 = time.{clock}(); import numpy as np; from thetasol import inertia, solve_rotation; "
            f"d = {json.dumps({k: data[k] for k in ('J', 'a', 'Q0', 'omega0')})}; "
            "solve_rotation(inertia(d['J']), np.array(d['a']), np.array(d['Q0']), np.array(d['omega0'])); "
            f"print(time.{clock}() - t0)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return float(out.stdout.split()[-1])


# -- output ---------------------------------------------------------------------------------------

def print_header(quick):
    header = ("| case | method | set-up (ms) | set-up / heyoka to 1000 | set-up, new body (ms) | dense theta (us/time) "
              "| dense heyoka (us/time) "
              "| dense theta / heyoka | t = 1e6 theta (us) | t = 1e6 in dense points | far dense / dense "
              "| drift near | drift far | heyoka to 1000 (ms) "
              + ("" if quick else "| DOP853 dense (us/time) | DOP853 / heyoka ") + "| error theta | error heyoka "
              + ("" if quick else "| error DOP853 ") + "| theta error to t = 4002 |")
    print(header)
    # the separator has the header's cell count, or the table renders as raw text
    print("|---" * (header.count("|") - 1) + "|", flush=True)


def print_row(r, quick):
    dop = "" if quick else f"| {r['dop_dense'] * 1e6:.3g} | {r['dop_dense'] / r['hy_dense']:.3g} "
    dop_err = "" if quick else f"| {r['dop_err']:.1e} "
    print(f"| {r['case']} | {r['method']} | {r['setup'] * 1e3:.0f} | {r['setup'] / r['hy_run']:.2f} | "
          f"{r['setup_new'] * 1e3:.0f} | {r['dense'] * 1e6:.2f} | {r['hy_dense'] * 1e6:.2f} | {r['dense'] / r['hy_dense']:.2f} | "
          f"{r['far'] * 1e6:.0f} | {r['far'] / r['dense']:.1f} | {r['far_dense'] / r['dense']:.2f} | "
          f"{r['drift']:.1e} | {r['drift_far']:.1e} | {r['hy_run'] * 1e3:.1f} {dop}| "
          f"{r['err']:.1e} | {r['hy_err']:.1e} {dop_err}| {r['err_4002']:.1e} |", flush=True)


def print_summary(rows, compile_s, cold, quick):
    su = np.array([r["setup"] / r["hy_run"] for r in rows])
    de = np.array([r["dense"] / r["hy_dense"] for r in rows])
    fa = np.array([r["far"] / r["dense"] for r in rows])
    print(f"\nheyoka: one compilation for all bodies {compile_s:.2f} s (not in any figure above); "
          f"far time t = 1e6 by integration (est. 1000 x its time to 1000): "
          f"{np.median([r['hy_run'] for r in rows]) * 1e3:.0f} s median")
    if not quick:
        print(f"DOP853 rtol 1e-13 to t = 1e6 (est. 1000 x its time to 1000): "
              f"{np.median([r['dop_run'] for r in rows]) * 1e3:.0f} s median")
    sn = np.array([r["setup_new"] / r["hy_run"] for r in rows])
    print(f"set-up / heyoka's propagation to 1000: median {np.median(su):.2f}, max {su.max():.2f} "
          "(targets: median <= 2, every body <= 6); a body new to the process: median "
          f"{np.median(sn):.2f}, max {sn.max():.2f}")
    print(f"dense theta / heyoka: median {np.median(de):.2f}, max {de.max():.2f} (targets: median <= 0.5, every "
          "body <= 2)")
    print(f"t = 1e6 in dense points: median {np.median(fa):.1f}, max {fa.max():.1f} (target <= 3)")
    fd = np.array([r["far_dense"] / r["dense"] for r in rows])
    dr = np.array([r["drift_far"] / max(r["drift"], 1e-300) for r in rows])
    print(f"far dense [1e6, 1e6 + 1000] / dense [0, 1000] per time: median {np.median(fd):.2f}, "
          f"max {fd.max():.2f}; first-integral drift there: max {max(r['drift_far'] for r in rows):.1e} "
          f"(near batch max {max(r['drift'] for r in rows):.1e}; far / near per body: max {dr.max():.1f})")
    print(f"cold start (fresh process: import + generic set-up): {cold:.2f} s (target <= 3 s)")


def plot(rows, path):
    """Set-up and dense cost of theta as ratios to heyoka, per body, with the targets."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    names = [r["case"] for r in rows]
    x = np.arange(len(rows))
    fig, ax = plt.subplots(figsize=(9, 4.2))
    ax.bar(x - 0.2, [r["setup"] / r["hy_run"] for r in rows], 0.4, label="set-up / heyoka to t = 1000")
    ax.bar(x + 0.2, [r["dense"] / r["hy_dense"] for r in rows], 0.4, label="dense per time / heyoka's")
    for y, style, lab in ((2, "--", "set-up target (median)"), (6, ":", "set-up target (each)"),
                          (0.5, "-.", "dense target (median)")):
        ax.axhline(y, color="0.3", ls=style, lw=1, label=lab)
    ax.axhline(1, color="k", lw=0.6)
    ax.set_yscale("log")
    ax.set_xticks(x, names, rotation=35, ha="right", fontsize=8)
    ax.set_ylabel("theta cost / heyoka cost")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.grid(True, axis="y", which="both", alpha=0.3)
    fig.savefig(path, dpi=130, bbox_inches="tight")
    print(f"\nplot written to {path}")


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help=f"five bodies ({QUICK}), no DOP853")
    ap.add_argument("--cases", default=None, help="comma-separated reference bodies (default: all)")
    ap.add_argument("--plot", default=None, help="write the ratio plot (needs matplotlib)")
    ap.add_argument("--clock", choices=("wall", "cpu"), default="wall",
                    help="wall time, or this process's CPU time (on a shared, loaded machine)")
    args = ap.parse_args(argv)
    CLOCK[0] = time.process_time if args.clock == "cpu" else time.perf_counter
    refs = json.loads(REFS.read_text())
    names = (args.cases or (QUICK if args.quick else ",".join(refs))).split(",")
    print(f"machine: {machine_info('heyoka')}; load average at start {os.getloadavg()[0]:.1f}")
    print(f"clock: {args.clock} time")
    print(f"dense: {N_DENSE} times on [0, {T_END:g}] plus the reference times; heyoka float64 tol 1e-16; "
          "errors against the 80-bit references at t <= 1000; best of 3 (set-up, evaluation, propagation)\n")
    cold = cold_start(refs["generic"])
    ta, compile_s = heyoka_integrator()
    first = first_setup(refs["generic"])
    rows = []
    print_header(args.quick)
    for name in names:
        rows.append(bench_body(name, refs[name], ta, args.quick))
        print_row(rows[-1], args.quick)
    print_summary(rows, compile_s, cold, args.quick)
    print(f"first set-up in this process (generic body, before the table; part of the cold start): "
          f"{first * 1e3:.0f} ms")
    if args.plot:
        plot(rows, args.plot)


if __name__ == "__main__":
    with docs_section(docs_page("docs/bench_theta_rotation.md"), "benchmarks/bench_theta_rotation.py"):
        main()
