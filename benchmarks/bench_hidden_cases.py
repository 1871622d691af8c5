"""Random bodies of every kind the theta rotation covers, against heyoka: error at t <= 4002 and set-up cost.

Usage: ``python benchmarks/bench_hidden_cases.py [seed [count]]`` (defaults 2026, 45: five of each
kind).  Needs heyoka (``pip install .[bench]``); the references are 80-bit Taylor integrations
(``--f128`` re-runs the worst in quadruple precision, a slow integration, to tell the reference's error from
the solution's).  Results of the default run: docs/theta_rotation.md ("Accuracy and cost", random data).
"""
from __future__ import annotations

import sys
import time
import warnings

import numpy as np
from _common import docs_page, docs_section, machine_info

import thetasol as ts
from thetasol.core.inertia import inertia
from thetasol.core.so3 import rodrigues

T = np.array([0.7, 3.1, 17.3, 102.0, 997.0, 4002.0])
KINDS = ["generic", "saddle", "fast", "slow", "nearly-symmetric", "rank-one", "near-eq", "symmetric",
         "symmetric-rank-one"]


def _rank_one(rng):
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    return rng.uniform(0.3, 3) * rng.choice([-1, 1]) * np.outer(n, n)


def case(rng, kind):
    """(J principal values, a, Q0, omega0) of one random body of the given kind."""
    J = np.sort(rng.uniform(0.2, 2, 3))
    Q0 = rodrigues(rng.normal(size=3))
    a = rng.normal(size=(3, 3))
    a = (a + a.T) / 2
    sa = np.sqrt(np.abs(np.linalg.eigvalsh(a)).max())
    w0 = rng.normal(size=3) * sa
    if kind == "saddle":
        lam, V = np.linalg.eigh(a)
        a = V @ np.diag(np.abs(lam) * np.array([-1, 1, rng.choice([-1, 1])])) @ V.T
    elif kind == "fast":
        w0 = rng.normal(size=3) * 8 * sa
    elif kind == "slow":
        w0 = rng.normal(size=3) * 0.01 * sa
    elif kind == "nearly-symmetric":
        d = 10 ** rng.uniform(-7, -3)
        j = rng.uniform(0.3, 1.5)
        J = np.sort([j, j * (1 + d), rng.uniform(0.2, 2)])
    elif kind == "rank-one":
        a = _rank_one(rng)
    elif kind == "near-eq":
        # a principal frame of a in random order, turned by 1e-3: stable or unstable relative equilibria
        lam, V = np.linalg.eigh(a)
        V[:, 2] *= np.linalg.det(V)
        P = np.eye(3)[:, rng.permutation(3)]
        P[:, 2] *= np.linalg.det(P)
        Q0 = V @ P @ rodrigues(1e-3 * rng.normal(size=3))
        w0 = 1e-3 * rng.normal(size=3)
    elif kind in ("symmetric", "symmetric-rank-one"):
        j = rng.uniform(0.3, 1.5)
        J = np.array([j, j, rng.uniform(0.2, 2)])
        if kind == "symmetric-rank-one":
            a = _rank_one(rng)
            sa = np.sqrt(np.abs(np.linalg.eigvalsh(a)).max())
        rel = 10 ** rng.uniform(-3, -0.5)                   # axial spin relative to |omega0| + sqrt|a|
        wp = rng.normal(size=2) * sa
        s = rel * (np.linalg.norm(wp) + sa) / (1 - rel)
        w0 = np.array([*wp, rng.choice([-1, 1]) * s])
    return J, a, Q0, w0


def main(seed: int = 2026, count: int = 45, f128: bool = False) -> None:
    print(machine_info("heyoka"))
    print(f"\nseed {seed}, {count} bodies; error: max over omega and Q at t = {', '.join(f'{x:g}' for x in T)}\n")
    print("| body | kind | method | set-up (s CPU) | warnings | error at each time |")
    print("|---|---|---|---|---|---|")
    rng = np.random.default_rng(seed)
    worst, rows, setups, warned = {}, [], [], 0
    for i in range(count):
        kind = KINDS[i % len(KINDS)]
        J, a, Q0, w0 = case(rng, kind)
        with warnings.catch_warnings(record=True) as W:
            warnings.simplefilter("always")
            try:
                t0 = time.process_time()
                sol = ts.solve_rotation(ts.inertia(J), a, Q0, w0)
                setup = time.process_time() - t0
            except ts.ClosedFormUnavailable as exc:
                print(f"| {i} | {kind} | refused: {exc} | | | |")
                continue
        w, Q = sol(T)
        wr, Qr = ts.integrate_rotation(inertia(J), a, Q0, w0, method="heyoka", fp_type=np.longdouble, rtol=1e-19)(T)
        err = np.maximum(np.abs(w - wr).max(axis=1), np.abs(Q - Qr).max(axis=(1, 2)))
        rows.append((err.max(), i, kind, J, a, Q0, w0))
        worst[kind] = max(worst.get(kind, 0.0), err.max())
        setups.append(setup)
        warned += bool(W)
        print(f"| {i} | {kind} | {sol.method} | {setup:.2f} | {len(W)} | " + " ".join(f"{e:.1e}" for e in err) + " |",
              flush=True)
    if setups:
        print(f"\nsolved {len(setups)} of {count}, {warned} with a warning; set-up {min(setups):.2f} .. "
              f"{max(setups):.2f} s CPU, median {np.median(setups):.2f} s (single runs, each body new to the process)")
    print("\nworst per kind against 80-bit heyoka: " + ", ".join(f"{k} {v:.1e}" for k, v in worst.items()))
    if f128 and rows:
        import heyoka as hy

        e, i, kind, J, a, Q0, w0 = max(rows, key=lambda r: r[0])
        w, Q = ts.solve_rotation(inertia(J), a, Q0, w0)(T)
        wr, Qr = ts.integrate_rotation(inertia(J), a, Q0, w0, method="heyoka", fp_type=hy.real128, rtol=1e-32)(T)
        err = np.maximum(np.abs(w - wr).max(axis=1), np.abs(Q - Qr).max(axis=(1, 2)))
        print(f"\nworst body ({i}, {kind}) against quadruple-precision heyoka: " + " ".join(f"{x:.1e}" for x in err))


if __name__ == "__main__":
    with docs_section(docs_page("docs/theta_rotation.md"), "benchmarks/bench_hidden_cases.py"):
        args = [x for x in sys.argv[1:] if not x.startswith("--")]
        main(*(int(x) for x in args), f128="--f128" in sys.argv)
