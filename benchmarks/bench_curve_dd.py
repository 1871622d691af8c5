"""Double-double against mpmath for the curve quadrature's critical intervals (set-up time of the theta rotation).

Run:  OPENBLAS_NUM_THREADS=1 python benchmarks/bench_curve_dd.py [case ...]   (a Python with thetasol's
dependencies and mpmath)

For every case of tests/data/rotation/refs.json with critical intervals (intervals whose float64
Gauss-Legendre sum is not accurate enough): the time of re-summing them in double-double
(thetasol.curves._dd, the default) and in mpmath at 20 digits (thetasol.curves._mp.interval_mp, the
alternative), measured side by side in one run, the error of each against 30-digit mpmath sums
of the same intervals (max |error| / max |interval sum| over all intervals, tracks and
differentials, before rounding to complex128), and the whole set-up time of solve_rotation with each
fallback.  Times are the best of 3 (the machine is shared).
"""
from __future__ import annotations

import json
import os
import sys
import time

import mpmath
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, ROOT)

from _common import best_of, docs_page, docs_section, machine_info  # noqa: E402

from thetasol import inertia, solve_rotation
from thetasol.curves import _quad as _curve_quad  # noqa: E402
from thetasol.curves._dd import curve_to_cdd, intervals_dd, numerators_to_cdd  # noqa: E402
from thetasol.curves._mp import interval_mp, numerators_mp  # noqa: E402

REFS = json.load(open(os.path.join(ROOT, "tests", "data", "rotation", "refs.json")))


def _args(name):
    r = REFS[name]
    return inertia(np.diag(r["J"])), np.array(r["a"]), np.array(r["Q0"]), np.array(r["omega0"])


def _capture(name):
    calls = []
    orig = _curve_quad.Tracked._add_dd

    def spy(self, out, exact, crit):
        calls.append((self, exact, list(crit)))
        return orig(self, out, exact, crit)

    _curve_quad.Tracked._add_dd = spy
    try:
        solve_rotation(*_args(name))
    finally:
        _curve_quad.Tracked._add_dd = orig
    return calls


def _mp_sums(tr, exact, crit, seeds, dps):
    with mpmath.workdps(dps + 10):
        nums = numerators_mp(exact, dps + 10)
        return [interval_mp(tr.pieces[p], lo, hi, N, s, tr.tracker.exact, nums, dps)
                for (p, k, (lo, hi, N)), s in zip(crit, seeds)]


def _setup_time(name, fallback):
    orig = _curve_quad.Tracked._add_dd
    if fallback == "mp":
        _curve_quad.Tracked._add_dd = _curve_quad.Tracked._add_mp
    try:
        solve_rotation(*_args(name))  # warm caches (Gauss-Legendre nodes, first-use imports)
        t, _ = best_of(lambda: solve_rotation(*_args(name)), repeat=3)
    finally:
        _curve_quad.Tracked._add_dd = orig
    return t


def run(names):
    rows = []
    for name in names:
        calls = _capture(name)
        if not calls:
            rows.append((name, 0, 0, None, None, None, None, _setup_time(name, "dd"), None))
            continue
        n_int = sum(len(c) for _, _, c in calls)
        n_pairs = sum(N * len(tr.pieces[p].y0) for tr, _, c in calls for p, _, (_, _, N) in c)
        prep = []
        for tr, exact, crit in calls:
            poly = tr.tracker.poly
            prep.append((tr, exact, crit, tr.interval_seeds(crit), curve_to_cdd(poly),
                         numerators_to_cdd(exact)))
        t_dd, dd = best_of(lambda: [intervals_dd(tr.pieces, crit, s, C, B, rounded=False)
                                    for tr, _, crit, s, C, B in prep], repeat=3)
        t_mp, mp20 = best_of(lambda: [_mp_sums(tr, ex, crit, s, 20) for tr, ex, crit, s, _, _ in prep], repeat=3)
        ref = [_mp_sums(tr, ex, crit, s, 30) for tr, ex, crit, s, _, _ in prep]
        e_dd = e_mp = 0.0
        with mpmath.workdps(40):
            for dcall, mcall, rcall in zip(dd, mp20, ref):
                for (rh, rl, ih, il), mint, rint in zip(dcall, mcall, rcall):
                    scale = max(abs(v) for row in rint for v in row)
                    for t, row in enumerate(rint):
                        for d, v in enumerate(row):
                            z = mpmath.mpc(mpmath.mpf(rh[t, d]) + mpmath.mpf(rl[t, d]),
                                           mpmath.mpf(ih[t, d]) + mpmath.mpf(il[t, d]))
                            e_dd = max(e_dd, float(abs(z - v) / scale))
                            e_mp = max(e_mp, float(abs(mint[t][d] - v) / scale))
        rows.append((name, n_int, n_pairs, t_dd, e_dd, t_mp, e_mp, _setup_time(name, "dd"), _setup_time(name, "mp")))
        print(f"  {name}: done", file=sys.stderr, flush=True)
    return rows


def main():
    names = sys.argv[1:] or list(REFS)
    print(machine_info("mpmath"))
    print()
    print("| case | intervals | node x track | dd time | dd error | mp (20 digits) time | mp error | "
          "set-up (dd) | set-up (mp) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name, ni, npairs, tdd, edd, tmp, emp, sdd, smp in run(names):
        if tdd is None:
            print(f"| {name} | 0 | 0 | - | - | - | - | {sdd:.2f} s | (same) |")
            continue
        print(f"| {name} | {ni} | {npairs} | {1e3 * tdd:.0f} ms | {edd:.1e} | {1e3 * tmp:.0f} ms | {emp:.1e} | "
              f"{sdd:.2f} s | {smp:.2f} s |")


if __name__ == "__main__":
    with docs_section(docs_page("docs/bench_curve_dd.md"), "benchmarks/bench_curve_dd.py"):
        t0 = time.perf_counter()
        main()
        print(f"\n(total {time.perf_counter() - t0:.0f} s)")
