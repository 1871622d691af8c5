"""Riemann theta: time per point against error, thetasol vs python-flint acb_theta (53 bits).

For g = 1..4 and two tau per genus (well conditioned; smallest eigenvalue of Im tau = 0.05),
a batch of points is evaluated by thetasol at tol = 1e-8, 1e-12, 1e-14, for one characteristic
and for all 2^(2g) at once, and by FLINT's acb_theta at 53 bits (which always returns all
characteristics).  Errors are measured on a subset of points against acb_theta at 128 bits,
relative to max(|theta|, exp(pi y.(Im tau)^{-1}.y)).  Timings are CPU time (process_time,
best of several runs) with single-threaded BLAS unless --threads is given: the machine is
shared, and FLINT is single threaded too.

Run:  python benchmarks/bench_theta.py [--points 2000] [--quick] [--write-docs]   (--write-docs: the run replaces
the generated section of docs/bench_theta.md)
"""
from __future__ import annotations

import argparse
import os
import sys

if "--threads" not in sys.argv:
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    os.environ.setdefault("OMP_NUM_THREADS", "1")

import time  # noqa: E402

import numpy as np  # noqa: E402
from _common import best_of, docs_page, docs_section, machine_info  # noqa: E402

from thetasol import RiemannTheta  # noqa: E402

try:
    import flint
    from flint import acb, acb_mat, arb
except ImportError:  # pragma: no cover
    flint = None


def make_tau(kind: str, g: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng([g, seed, 0 if kind == "well" else 1])
    Qm, _ = np.linalg.qr(rng.normal(size=(g, g)))
    if kind == "well":
        ev = rng.uniform(0.8, 2.0, g)
        X = rng.uniform(-0.5, 0.5, (g, g))
    else:
        ev = np.concatenate([[0.05], rng.uniform(0.3, 2.0, g - 1)])
        X = rng.uniform(-1, 1, (g, g))
    tau = X + 1j * ((Qm * ev) @ Qm.T)
    return 0.5 * (tau + tau.T)


def make_points(tau: np.ndarray, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    g = tau.shape[0]
    c = rng.uniform(-0.7, 0.7, (n, g))
    return rng.uniform(-1, 1, (n, g)) + 1j * (c @ tau.imag)


def cpu_best(f, reps: int) -> float:
    return best_of(f, reps, clock=time.process_time)[0]


def _acb_mat(a):
    a = np.atleast_2d(a)
    return acb_mat([[acb(float(x.real), float(x.imag)) for x in row] for row in a])


def flint_all(tau, z, prec, e=None):
    """All characteristics at one point; scaled by exp(-e) inside arb when e is given."""
    old = flint.ctx.prec
    flint.ctx.prec = prec
    try:
        th = _acb_mat(tau).theta(_acb_mat(np.asarray(z)[:, None]))
        s = (-arb(float(e))).exp() if e is not None else arb(1)
        return np.array([complex((th[0, i] * s).mid()) for i in range(th.ncols())])
    finally:
        flint.ctx.prec = old


def bench_case(g, kind, npts, nref, nflint, reps, tols):
    tau = make_tau(kind, g, 0)
    z = make_points(tau, npts, 1)
    rows = []
    # 128-bit reference on the first nref points, scaled by the exact-enough e of thetasol
    e_ref, _ = RiemannTheta(tau).separated(z[:nref])
    ref = np.array([flint_all(tau, z[p], 128, e_ref[p]) for p in range(nref)])
    scale = np.maximum(np.abs(ref), 1.0)
    for tol in tols:
        t_setup = cpu_best(lambda: RiemannTheta(tau, tol=tol)._table_all(), 1)
        th = RiemannTheta(tau, tol=tol)
        th(z[:2]), th(z[:2], char="all")  # warm the lattice and characteristic caches
        e1, v1 = th.separated(z[:nref])
        ea, va = th.separated(z[:nref], char="all")
        err1 = float(np.max(np.abs(v1 * np.exp(e1 - e_ref) - ref[:, 0]) / scale[:, 0]))
        erra = float(np.max(np.abs(va * np.exp(ea - e_ref)[:, None] - ref) / scale))
        t1 = cpu_best(lambda: th(z), reps) / npts
        ta = cpu_best(lambda: th(z, char="all"), max(1, reps // 2)) / npts
        tg = cpu_best(lambda: th.gradient(z), reps) / npts
        rows.append(dict(tol=tol, err1=err1, erra=erra, t1=t1, ta=ta, tg=tg, setup=t_setup))
    # FLINT at 53 bits: all characteristics per call
    fl = None
    if flint is not None and nflint:
        zz = z[:nflint]
        t0 = time.process_time()
        out = [flint_all(tau, zz[p], 53) for p in range(nflint)]
        tf = (time.process_time() - t0) / nflint
        k = min(nref, nflint)
        out = np.array(out[:k]) * np.exp(-e_ref[:k])[:, None]
        with np.errstate(invalid="ignore"):
            ef = float(np.max(np.abs(out - ref[:k]) / scale[:k]))
        fl = dict(t=tf, err=ef)
    return tau, rows, fl


def heavy_use_case(g, T=1000, S=20):
    """The theta rotation's pattern: z(t) + c_j for T times and S shifts, values and gradients."""
    tau = make_tau("ill", g, 3)
    rng = np.random.default_rng(4)
    th = RiemannTheta(tau)
    z0 = rng.uniform(-1, 1, g) + 0.3j * rng.normal(size=g)
    V = rng.normal(size=g) + 0.2j * rng.normal(size=g)
    c = rng.uniform(-1, 1, (S, g)) + 1j * rng.uniform(-2, 2, (S, g)) @ tau.imag
    t = np.linspace(0, 50, T)
    z = (z0 + t[:, None] * V)[:, None, :] + c[None, :, :]
    th.separated(z[:1])
    # |Im z| up to ~10 Im(tau): theta itself overflows float64, so use the separated form
    tv = cpu_best(lambda: th.separated(z), 2)
    tj = cpu_best(lambda: th.jet(z, order=1, separated=True), 2)
    return tv, tj


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--points", type=int, default=2000)
    ap.add_argument("--quick", action="store_true", help="fewer repetitions and reference points")
    ap.add_argument("--threads", action="store_true", help="leave BLAS threading alone")
    args = ap.parse_args()
    reps = 2 if args.quick else 5
    nref = 8 if args.quick else 20
    tols = (1e-8, 1e-12, 1e-14)
    lines = [f"Machine: {machine_info('flint')}.", "",
             f"Batch of {args.points} points per case (Im z = Im(tau) c, c uniform in [-0.7, 0.7]^g); "
             f"errors on {nref} points against acb_theta at 128 bits, relative to max(|theta|, exp(e)); "
             "CPU time per point, best of several runs.  FLINT computes all 2^(2g) characteristics "
             "in every call, so its time is the same for one and for all.", "",
             "| g | tau | tol | err (1 char) | us/pt (1 char) | us/pt (gradient) | err (all) | us/pt (all) "
             "| FLINT 53-bit us/pt | FLINT err | speed-up 1 char | speed-up all | setup ms |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    print("\n".join(lines), flush=True)
    for g in (1, 2, 3, 4):
        nflint = {1: 200, 2: 100, 3: 30, 4: 8}[g] // (4 if args.quick else 1)
        for kind in ("well", "ill"):
            tau, rows, fl = bench_case(g, kind, args.points, nref, max(nflint, nref), reps, tols)
            for r in rows:
                ft = f"{fl['t'] * 1e6:.0f}" if fl else "-"
                fe = f"{fl['err']:.1e}" if fl else "-"
                s1 = f"{fl['t'] / r['t1']:.0f}x" if fl else "-"
                sa = f"{fl['t'] / r['ta']:.0f}x" if fl else "-"
                line = (f"| {g} | {kind} | {r['tol']:.0e} | {r['err1']:.1e} | {r['t1'] * 1e6:.2f} | "
                        f"{r['tg'] * 1e6:.2f} | {r['erra']:.1e} | {r['ta'] * 1e6:.1f} | {ft} | {fe} | {s1} | {sa} "
                        f"| {r['setup'] * 1e3:.0f} |")
                lines.append(line)
                print(line, flush=True)
    lines += ["", "Trajectory pattern of the theta rotation (ill-conditioned tau, 1000 times x 20 shifts = 20000 "
              "points, one characteristic, exponent-separated output):", "", "| g | values ms | values + gradients ms |", "|---|---|---|"]
    for g in (3, 4):
        tv, tj = heavy_use_case(g)
        lines.append(f"| {g} | {tv * 1e3:.0f} | {tj * 1e3:.0f} |")
        print(lines[-1], flush=True)


if __name__ == "__main__":
    with docs_section(docs_page("docs/bench_theta.md"), "benchmarks/bench_theta.py"):
        main()
