"""Theta on a torus grid (thetasol.theta.grid.theta_grid) against RiemannTheta.jet point by point, and the
Kovalevskaya attitude set-up that uses it.

Run:  OPENBLAS_NUM_THREADS=1 python benchmarks/bench_theta_grid.py

For the two Kovalevskaya tops of benchmarks/bench_heavy_top.py (test seeds 2 and 17) prints, in CPU time
(time.process_time, best of 7):

1. the seven theta values and their derivatives along V2 on n x n grids of the real torus: theta_grid and
   KovalevskayaMotion.values_at (RiemannTheta.jet, char="all", order 1), per point, the lattice terms per
   block and the largest difference relative to each point's largest value (values up to the common factor per
   point, and the Wronskians ``val_i der_j - val_j der_i``);
2. kovalevskaya_attitude's set-up (the torus lattice, the doubled phase grid, the FFT), its grid and tail.
"""
from __future__ import annotations

import time

import numpy as np
from _common import best_of, docs_page, docs_section, machine_info
from bench_heavy_top import kovalevskaya_top

from thetasol.solutions.tops.kovalevskaya_attitude import _torus_lattice, kovalevskaya_attitude
from thetasol.solutions.tops.kovalevskaya_top import kovalevskaya_motion
from thetasol.theta.grid import theta_grid

CPU = time.process_time


def grid_rows(m, k1, k2):
    chars = (None,) + m.chars1 + m.chars2
    for n in (32, 64, 128):
        a = np.arange(n) / n
        tg, G = best_of(lambda a=a: theta_grid(m.theta.tau, m.z0, k1, k2, a, a, chars, m.V2), repeat=7, clock=CPU)
        x = a[:, None, None] * k1 + a[None, :, None] * k2
        tp, (v, dv) = best_of(lambda x=x: m.values_at(x, 1), repeat=1 if n > 32 else 3, clock=CPU)
        # the two differ by a factor common to the characteristics (another lattice shift per point): compare
        # the values up to it and the Wronskians val_i der_j - val_j der_i (what quotients' derivatives use)
        r = np.sum(np.conj(v) * G.value, -1) / np.sum(np.abs(v) ** 2, -1)
        err = np.max(np.abs(G.value - r[..., None] * v) / np.max(np.abs(G.value), -1, keepdims=True))
        wr = lambda a, b: a[..., :, None] * b[..., None, :] - a[..., None, :] * b[..., :, None]  # noqa: E731
        W, Wr = wr(G.value, G.derivative), wr(v, dv) * (r * r)[..., None, None]
        err = max(err, np.max(np.abs(W - Wr) / np.max(np.abs(W), (-2, -1), keepdims=True)))
        print(f"| {n} x {n} | {tg * 1e3:8.2f} | {tg / n / n * 1e6:6.3f} | {tp / n / n * 1e6:6.2f} | {G.terms:4d} "
              f"| {err:.1e} |")


def main():
    print(machine_info())
    for seed in (2, 17):
        I, c, Q0, w0, kw = kovalevskaya_top(seed)
        m = kovalevskaya_motion(I, c, Q0, w0, **kw)
        k1, k2 = _torus_lattice(m)
        print(f"\n## Kovalevskaya top, test seed {seed}: k1 = {k1}, k2 = {k2}\n")
        print("| grid | theta_grid ms | us/point | values_at us/point | terms | max diff |")
        print("|---|---|---|---|---|---|")
        grid_rows(m, k1, k2)
        t, att = best_of(lambda m=m, I=I, c=c, Q0=Q0, w0=w0, kw=kw:
                         kovalevskaya_attitude(m, I, c, Q0, w0, kw["mass"], kw["gravity"]), repeat=7, clock=CPU)
        print(f"\nkovalevskaya_attitude set-up: {t * 1e3:.1f} ms (grid {att.grid[0]} x {att.grid[1]}, "
              f"{t / np.prod(att.grid) * 1e6:.2f} us per grid point, phase tail {att.tail:.1e})")


if __name__ == "__main__":
    with docs_section(docs_page("docs/theta.md"), "benchmarks/bench_theta_grid.py"):
        main()
