"""Error against cost for Section 8 beyond the free gyrostat: scenes with rotors, gyrostats in a potential,
the Lagrange gyrostat.

Run:  python benchmarks/bench_rotor_scenes.py [--quick]

Prints three tables:

1. the bundled scenes (spacecraft with momentum wheels, Hooke joint), free and in their potential: the
   split of Theorem 5 against the unsplit multibody system (rotors on revolute joints) to t = 40, the
   largest gap in positions, attitudes and rotor angles, and the wall time of each side;
2. integrate_gyrostat (DOP853) in a quadratic potential at several rtol against 80-bit heyoka to
   t = 100: error of omega, Q and the rotor angles, and the time;
3. the Lagrange gyrostat: set-up, cost per time point (1e5 times in [0, 1e6]) and error against 80-bit
   heyoka to t = 100.
"""
from __future__ import annotations

import os
import sys
import time

import numpy as np
from _common import best_of, docs_page, docs_section, machine_info

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))
import test_gyrostat_potential as P  # noqa: E402
import test_rotor_scenes as S  # noqa: E402
from conftest import rand_Q  # noqa: E402

from thetasol.core.inertia import inertia
from thetasol.integrators.gyrostat import integrate_gyrostat, integrate_heavy_gyrostat  # noqa: E402
from thetasol.scenes.gyrostat_scene import run_gyrostat_scene  # noqa: E402
from thetasol.solutions.tops.lagrange_gyrostat import solve_lagrange_gyrostat  # noqa: E402


def scenes(t_end):
    print("| scene | potential | positions | attitudes | rotor angles | split | multibody (rtol 1e-13) |")
    print("|---|---|---|---|---|---|---|")
    for name in ("spacecraft", "hooke"):
        for free in (True, False):
            sc = S._scene(name, free, t_end)
            _, text, checks = run_gyrostat_scene(sc)
            line = [x for x in text.splitlines() if x.startswith("timings")][0]
            split, mb = (w.split()[0] for w in line.split("split ")[1].split("multibody "))
            dev = {w: d for w, d, _ in checks}
            print(f"| {name} | {'free' if free else 'quadratic'} | {dev['positions']:.1e} | {dev['attitudes']:.1e} "
                  f"| {dev['rotor angles']:.1e} | {split} s | {mb} s |")


def potential():
    rng = np.random.default_rng(2)
    Q0, w0 = rand_Q(rng), np.array([0.3, -0.5, 0.9])
    t = np.linspace(0.0, 100.0, 21)
    ref = integrate_gyrostat(inertia(P.J0), None, Q0, w0, rotors=P.ROTORS, a=P.A_POT, rtol=1e-19, method="heyoka",
                             fp_type=np.longdouble).evaluate_with_angles(t)
    print("| rtol | omega | Q | rotor angles | time |")
    print("|---|---|---|---|---|")
    for rtol in (1e-9, 1e-11, 1e-13):
        sec, out = best_of(lambda: integrate_gyrostat(inertia(P.J0), None, Q0, w0, rotors=P.ROTORS, a=P.A_POT,
                                                      rtol=rtol).evaluate_with_angles(t), repeat=2)
        err = [float(np.max(np.abs(x - y))) for x, y in zip(out, ref, strict=True)]
        print(f"| {rtol:g} | {err[0]:.1e} | {err[1]:.1e} | {err[2]:.1e} | {sec:.2f} s |")


def lagrange():
    print("| case | set-up | per point | omega error | Q error | reference (80-bit) time |")
    print("|---|---|---|---|---|---|")
    tt = np.linspace(0.0, 1e6, 100_000)
    t = np.linspace(0.0, 100.0, 201)
    for k in range(3):
        I, c, N, Q0, w0 = P._lagrange_case(k)
        ts, sol = best_of(lambda: solve_lagrange_gyrostat(I, c, Q0, w0, N=N, mass=2.0))  # noqa: B023
        te, _ = best_of(lambda: sol(tt))  # noqa: B023
        c0 = time.perf_counter()
        wh, Qh = integrate_heavy_gyrostat(I, c, Q0, w0, N=N, mass=2.0, rtol=1e-19, method="heyoka",
                                          fp_type=np.longdouble)(t)
        cref = time.perf_counter() - c0
        w, Q = sol(t)
        print(f"| {k} (lam = {N @ c / np.linalg.norm(c):g}) | {ts * 1e3:.1f} ms | {te / tt.size * 1e6:.2f} us "
              f"| {np.max(np.abs(w - wh)):.1e} | {np.max(np.abs(Q - Qh)):.1e} | {cref:.2f} s |")


def main():
    print(machine_info("heyoka"))
    quick = "--quick" in sys.argv
    scenes(10.0 if quick else 40.0)
    print()
    potential()
    print()
    lagrange()


if __name__ == "__main__":
    with docs_section(docs_page("docs/gyrostat.md"), "benchmarks/bench_rotor_scenes.py"):
        main()
