"""Throughput of solve_many on random bodies of every regime: Dask LocalCluster of 1 and 2 workers,
the local process pool, and one process.

    python benchmarks/bench_ensemble.py [--n 1000] [--seed 0] [--times 101] [--skip serial,...]

The bodies are those of benchmarks/bench_units_sweep.py (eleven regimes in turn: generic, nearly
symmetric, symmetric, rank-one, rank-two, nearly isotropic, tiny a, huge a, fast spin, zero spin,
near relative equilibrium; units of order one), solved by solve_rotation and evaluated where they
are solved at ``--times`` times on [0, 100] (``errors="return"``: a refusal counts as done).  Each
engine gets the same list; the wall time includes starting its workers (each worker's first theta
set-up included), the cluster's start-up is timed apart.  Output: a markdown table (docs/ensembles.md
holds a recorded run).
"""
from __future__ import annotations

import argparse
import logging
import os
import time
import warnings

import numpy as np
from _common import docs_page, docs_section, machine_info
from bench_units_sweep import REGIMES, _body

from thetasol.ensembles import solve_many
from thetasol.protocol import ClosedFormUnavailable


def bodies(n: int, seed: int) -> list[dict]:
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        J, a, Q0, w0 = _body(REGIMES[i % len(REGIMES)], rng)
        out.append(dict(J=J, a=a, Q0=Q0, omega0=w0))
    return out


def _run(items, t, **kw):
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        out = solve_many(items, t=t, errors="return", progress=False, **kw)
    return time.perf_counter() - start, out


def _dask(items, t, n_workers):
    import distributed

    start = time.perf_counter()
    cluster = distributed.LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                                       dashboard_address=None, silence_logs=logging.CRITICAL)
    with cluster, distributed.Client(cluster) as client:
        client.wait_for_workers(n_workers)
        boot = time.perf_counter() - start
        seconds, out = _run(items, t, client=client)
    return boot, seconds, out


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=1000, help="bodies (default 1000)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--times", type=int, default=101, help="output times per body on [0, 100]")
    ap.add_argument("--skip", default="", help="comma-separated engines to leave out: dask1,dask2,pool,serial")
    args = ap.parse_args(argv)
    skip = set(filter(None, args.skip.split(",")))
    items, t = bodies(args.n, args.seed), np.linspace(0.0, 100.0, args.times)
    print(f"machine: {machine_info('heyoka', 'dask', 'distributed')}")
    print(f"{args.n} bodies (seed {args.seed}, {len(REGIMES)} regimes in turn), {args.times} times each, "
          f"cores usable: {len(os.sched_getaffinity(0))}, load average at start {os.getloadavg()[0]:.1f}\n")
    rows, ref = [], None
    engines = [("serial", "one process (workers=1)", lambda: (0.0, *_run(items, t, workers=1))),
               ("pool", "local process pool, 2 workers", lambda: (0.0, *_run(items, t, workers=2))),
               ("dask1", "Dask LocalCluster, 1 worker", lambda: _dask(items, t, 1)),
               ("dask2", "Dask LocalCluster, 2 workers", lambda: _dask(items, t, 2))]
    for key, label, fn in engines:
        if key in skip:
            continue
        boot, seconds, out = fn()
        refused = sum(isinstance(o, ClosedFormUnavailable) for o in out)
        other = sum(isinstance(o, Exception) and not isinstance(o, ClosedFormUnavailable) for o in out)
        if ref is None:
            ref = out
        same = all(isinstance(a, Exception) == isinstance(b, Exception) and
                   (isinstance(a, Exception) or all(np.array_equal(x, y) for x, y in zip(a, b)))
                   for a, b in zip(out, ref))
        rows.append((key, label, boot, seconds, refused, other, same))
        print(f"  {label}: {seconds:.1f} s", flush=True)
    base = {k: s for k, _, _, s, *_ in rows}
    print("\n| engine | cluster start-up (s) | wall time (s) | bodies / s | speed-up vs 1 worker | refused | "
          "other errors | same bits as the first engine |")
    print("|---|---|---|---|---|---|---|---|")
    for key, label, boot, seconds, refused, other, same in rows:
        one = base.get("dask1") if key.startswith("dask") else base.get("serial")
        speed = f"{one / seconds:.2f}" if one else "-"
        print(f"| {label} | {boot:.1f} | {seconds:.1f} | {args.n / seconds:.2f} | {speed} | {refused} | {other} | "
              f"{'yes' if same else 'NO'} |")


if __name__ == "__main__":
    with docs_section(docs_page("docs/ensembles.md"), "benchmarks/bench_ensemble.py"):
        main()
