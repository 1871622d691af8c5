"""Snapping near-degenerate data: how far it moves the trajectory, against heyoka in 80 bits.

    python benchmarks/bench_snapping.py

solve_rotation snaps two principal second moments, or two eigenvalues of ``a``, closer than
``SNAP_TOL`` (relative) to exactly equal ones and solves the degenerate model; gaps above it and below
the engines' limits (``MIN_J_GAP``, ``MIN_A_GAP``) are refused.  For a family of bodies with a gap d in
J (``J = (0.7, 0.7 (1 + d), 1.3)``, axial spin 0.3) and in the eigenvalues of a rank-one-like ``a``
(``V diag(-1.3, 0, 1.3 d) V^T``), the table gives the outcome, the refusal or set-up time, the largest
error over t = 0.7 .. 4002 and the data's conditioning (the reference's spread under a change of the
data of a few ulps).  The last two columns solve the exactly degenerate model (the pair of J replaced by
its mean, the small eigenvalue of a by 0) for every gap, snapped or not, against the reference of the
true data: snapping a gap d would move the answer by about d / eps times the conditioning.
"""
from __future__ import annotations

import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from _common import docs_page, docs_section, machine_info  # noqa: E402
from bench_units_sweep import heyoka_rotation  # noqa: E402

from thetasol import (
    inertia,
    solve_rotation,  # noqa: E402
)
from thetasol.core.so3 import rodrigues  # noqa: E402
from thetasol.solutions._symmetry import SNAP_TOL  # noqa: E402

EPS = np.finfo(float).eps
T = np.array([0.7, 3.1, 17.3, 102.0, 997.0, 4002.0])
A0 = np.array([[0.3, -0.2, 0.1], [-0.2, -0.4, 0.25], [0.1, 0.25, 0.6]])
Q0 = rodrigues(np.array([0.3, -0.5, 0.2]))
W0 = np.array([0.3, -0.6, 0.45])
GAMMA = np.array([0.47, -0.87, 0.105]) / np.linalg.norm([0.47, -0.87, 0.105])
V = np.linalg.qr(np.column_stack([GAMMA, [1.0, 0.2, 0.3], [0.1, 1.0, -0.4]]))[0]
S = np.array([[0.3, -0.7, 0.2], [-0.7, 0.5, 1.0], [0.2, 1.0, -0.9]])
GAPS = [1e-6, 1e-9, 1e-12, 1e-13, 1e-14, 1e-15, 3e-16, 0.0]


def _spread(J, a, w0, ref, J2, a2, w2):
    wp, Qp = heyoka_rotation(J2, a2, Q0, w2, T)
    return max(np.abs(wp - ref[0]).max() / np.abs(ref[0]).max(), np.abs(Qp - ref[1]).max())


def _error(sol, ref):
    w, Q = sol(T)
    return max(np.abs(w - ref[0]).max() / np.abs(ref[0]).max(), np.abs(Q - ref[1]).max())


def _row(kind, d, J, a, w0, J2, a2, w2, Js, as_):
    """One table row; ``Js, as_`` the exactly degenerate data a snap would solve instead."""
    J, J2 = np.diag(J), np.diag(J2)
    ref = heyoka_rotation(J, a, Q0, w0, T)
    cond = _spread(J, a, w0, ref, J2, a2, w2)
    snapped = _error(solve_rotation(inertia(Js), as_, Q0, w0), ref)
    t0 = time.perf_counter()
    try:
        sol = solve_rotation(inertia(np.diag(J)), a, Q0, w0)
        err = _error(sol, ref)
        out = f"{sol.method} | {err:.1e} | {err / cond:.1f}"
    except Exception as ex:  # noqa: BLE001 (the table reports every outcome)
        out = f"refused ({type(ex).__name__}) | - | -"
    dt = time.perf_counter() - t0
    print(f"| {kind} | {d:.0e} | {out} | {cond:.1e} | {dt:.2f} | {snapped:.1e} | {snapped / cond:.1f} |",
          flush=True)


def main():
    print(machine_info())
    print(f"\nSNAP_TOL = {SNAP_TOL:.2e}\n")
    print("| gap in | d | outcome | max error t <= 4002 | error / conditioning | conditioning | time (s) "
          "| degenerate model's error | its error / conditioning |")
    print("|---|---|---|---|---|---|---|---|---|")
    w0 = W0 + np.array([0.0, 0.0, 0.3])
    for d in GAPS:
        J = np.array([0.7, 0.7 * (1 + d), 1.3])
        Js = np.diag([0.7, 0.7 * (1 + d / 2), 1.3])
        Js[0, 0] = Js[1, 1]                                    # the pair replaced by its mean
        _row("J", d, J, A0, w0, J * [1, 1 + 4 * EPS, 1], A0, w0 * (1 + 2 * EPS), Js, A0)
    for d in GAPS:
        a = V @ np.diag([-1.3, 0.0, 1.3 * d]) @ V.T
        J = np.array([0.6, 1.0, 1.7])
        _row("a", d, J, a, W0, J, a + EPS * np.abs(a).max() * S, W0, np.diag(J), V @ np.diag([-1.3, 0.0, 0.0]) @ V.T)


if __name__ == "__main__":
    with docs_section(docs_page("docs/units.md"), "benchmarks/bench_snapping.py"):
        main()
