"""Error against cost for the heavy top: the Lagrange and Kovalevskaya tops in closed form against DOP853 and heyoka.

Run:  python benchmarks/bench_heavy_top.py [--quick] [--only lagrange|kovalevskaya]

Prints, for Simo-Wong's fast top, the Bruls-Cardona top (its axis passes 7.2e-7 rad from hanging
straight down), a random slow Lagrange top and two random Kovalevskaya tops (five real branch points,
three real and a complex pair; the tops of tests/test_kovalevskaya_top.py):

1. dense output over [0, T] (T = 100, 10 with --quick): wall time and max error in omega and Q of
   the closed form (set-up included), of integrate_heavy_top with DOP853 at two tolerances and of
   heyoka in float64; the reference is heyoka in 80-bit extended precision at tolerance 1e-19;
2. far time: the state at the single time T_far = 1000 (100 with --quick), same methods and reference;
3. the closed form's set-up cost and its cost per time point in batches of 1, 100 and 1e5 points, in CPU
   time of this process (time.process_time: robust on a shared machine; the closed form is single-threaded);
4. one far-time query t = 1, 1e3, 1e6: the cost is the same (arguments reduced modulo the periods).

Errors are max over the output times of max |omega - omega_ref| / max(1, |omega_ref|) and
max |Q - Q_ref|.
"""
from __future__ import annotations

import argparse
import sys
import time

import numpy as np
from _common import best_of, docs_page, docs_section, machine_info

from thetasol.core.so3 import rodrigues
from thetasol.integrators.heavy_top import integrate_heavy_top
from thetasol.solutions.tops.heavy_top import solve_heavy_top

CPU = time.process_time


def kovalevskaya_top(seed):
    """The random Kovalevskaya top ``_top(seed)`` of tests/test_kovalevskaya_top.py."""
    rng = np.random.default_rng(seed)
    R = rodrigues(rng.normal(size=3))
    I = R @ np.diag([2.0, 2.0, 1.0]) @ R.T * rng.uniform(0.3, 2.0)
    c = R @ [np.cos(seed), np.sin(seed), 0.0] * rng.uniform(0.2, 1.0)
    return I, c, rodrigues(rng.normal(size=3)), rng.normal(size=3) * rng.uniform(0.2, 4.0), \
        {"mass": 1.0, "gravity": [0, 0, -9.81]}


def problems(only=None):
    rng = np.random.default_rng(11)
    slow_Q0 = rodrigues(rng.normal(size=3))
    kova = {"Kovalevskaya top, five real branch points (test seed 2)": kovalevskaya_top(2),
            "Kovalevskaya top, three real branch points (test seed 17)": kovalevskaya_top(17)}
    if only == "kovalevskaya":
        return kova
    lagrange = {
        "Simo-Wong (I = diag(5, 5, 1), Mgl = 20, W0 = (0, 0, 50))":
            ([5.0, 5.0, 1.0], [0, 0, 1.0], rodrigues(np.array([0.05, 0, 0])), [0, 0, 50.0],
             {"mass": 20.0, "gravity": [0, 0, -1.0]}),
        "Bruls-Cardona (m = 15, symmetry axis 2, Omega0 = (0, 150, -4.61538))":
            (np.diag([15.234375, 0.46875, 15.234375]), [0, 1.0, 0], np.eye(3), [0, 150.0, -4.61538],
             {"mass": 15.0, "gravity": [0, 0, -9.81]}),
        "slow top (I = (2, 2, 1), l = 0.5, |omega0| ~ 3)":
            ([2.0, 2.0, 1.0], [0, 0, 0.5], slow_Q0, rng.normal(size=3) * 2, {"mass": 1.0, "gravity": [0, 0, -9.81]}),
    }
    return lagrange if only == "lagrange" else {**lagrange, **kova}


def err(a, b):
    (w, Q), (wr, Qr) = a, b
    ew = np.max(np.abs(w - wr) / np.maximum(1.0, np.abs(wr).max(-1, keepdims=True)))
    return max(ew, np.max(np.abs(Q - Qr)))


def _method_rows(case, t, ref, quick, repeat, warm):
    """(method, seconds, error) at the times ``t``: the closed form (set-up + evaluation, best of ``repeat``),
    DOP853 at rtol 1e-9 (and 1e-12 unless ``quick``), heyoka float64 after a warm-up call at ``warm``."""
    I, c, Q0, w0, kw = case
    cost, out = best_of(lambda: solve_heavy_top(I, c, Q0, w0, **kw)(t), repeat=repeat)
    rows = [("closed form (set-up + evaluation)", cost, err(out, ref))]
    for rtol in ([1e-9] if quick else [1e-9, 1e-12]):
        cost, out = best_of(lambda rtol=rtol: integrate_heavy_top(I, c, Q0, w0, rtol=rtol, **kw)(t), repeat=1)
        rows.append((f"DOP853 rtol={rtol:g}", cost, err(out, ref)))
    integrate_heavy_top(I, c, Q0, w0, method="heyoka", rtol=1e-16, **kw)(warm)
    cost, out = best_of(lambda: integrate_heavy_top(I, c, Q0, w0, method="heyoka", rtol=1e-16, **kw)(t), repeat=1)
    rows.append(("heyoka float64 tol=1e-16", cost, err(out, ref)))
    return rows


def dense(name, case, T, quick):
    I, c, Q0, w0, kw = case
    t = np.linspace(0.0, T, 1001)
    t0 = time.perf_counter()
    ref = integrate_heavy_top(I, c, Q0, w0, method="heyoka", fp_type=np.longdouble, rtol=1e-19, **kw)(t)
    tref = time.perf_counter() - t0
    print(f"\n## {name}: 1001 points on [0, {T:g}]  (reference: heyoka 80-bit, tol 1e-19, {tref:.2f} s "
          "including compilation)")
    rows = _method_rows(case, t, ref, quick, repeat=5, warm=t[:3])
    rows[0] = ("thetasol " + rows[0][0], *rows[0][1:])
    rows[-1] = (rows[-1][0] + " (2nd call, compiled code cached)", *rows[-1][1:])
    print("| method | wall time [s] | max error (omega, Q) |\n|---|---|---|")
    for r in rows:
        print(f"| {r[0]} | {r[1]:.3g} | {r[2]:.2e} |")


def far(name, case, T, quick):
    """The state at the single time ``T``: every method integrates (or evaluates) once."""
    I, c, Q0, w0, kw = case
    t = np.array([T])
    ref = integrate_heavy_top(I, c, Q0, w0, method="heyoka", fp_type=np.longdouble, rtol=1e-19, **kw)(t)
    rows = _method_rows(case, t, ref, quick, repeat=3, warm=t[:1] * 1e-3)
    print(f"| {name.split(' (')[0]} | " + " | ".join(f"{r[1]:.3g} s, {r[2]:.1e}" for r in rows) + " |")


def costs(name, case):
    I, c, Q0, w0, kw = case
    setup, sol = best_of(lambda: solve_heavy_top(I, c, Q0, w0, **kw), repeat=7, clock=CPU)
    line = [f"set-up {setup * 1e3:.2f} ms"]
    for n in (1, 100, 100000):
        t = np.linspace(0.0, 1e3, n)
        cost, _ = best_of(lambda t=t: sol(t), repeat=5, number=max(1, 2000 // n), clock=CPU)
        line.append(f"{n} pts: {cost / n * 1e6:.2f} us/pt")
    far = []
    for T in (1.0, 1e3, 1e6):
        cost, _ = best_of(lambda T=T: sol(np.array([T])), repeat=5, number=200, clock=CPU)
        far.append(f"t = {T:g}: {cost * 1e6:.0f} us")
    print(f"- {name} (CPU time): " + "; ".join(line) + "; one far query " + ", ".join(far))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--only", choices=["lagrange", "kovalevskaya"])
    args = ap.parse_args()
    print(machine_info("heyoka"))
    T = 10.0 if args.quick else 100.0
    for name, case in problems(args.only).items():
        dense(name, case, T, args.quick)
    T_far = 100.0 if args.quick else 1000.0
    print(f"\n## far time: the state at t = {T_far:g} alone (wall time, error against heyoka 80-bit)\n")
    print("| problem | closed form | DOP853 rtol 1e-9 |" + ("" if args.quick else " DOP853 rtol 1e-12 |")
          + " heyoka float64 tol 1e-16 (compiled) |\n|---|---|---|---|" + ("" if args.quick else "---|"))
    for name, case in problems(args.only).items():
        far(name, case, T_far, args.quick)
    print("\n## closed form: set-up, cost per time point, far-time queries")
    for name, case in problems(args.only).items():
        costs(name.split(" (")[0], case)


if __name__ == "__main__":
    page = docs_page("docs/heavy_top.md")
    only = [a for a in sys.argv[1:] if a in ("lagrange", "kovalevskaya")]
    with docs_section(page, "benchmarks/bench_heavy_top.py", section=" ".join(only)):
        main()
