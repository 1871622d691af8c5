"""Quadrature nodes of the path pieces of the curve engine (:mod:`thetasol.curves._quad`).

A piece's parameter interval [0, 1] is split until each interval sees its nearest singularity
(preimage of a critical value) outside the Bernstein ellipse of parameter rho >= 2.5, and each
interval gets the Gauss-Legendre rule whose error bound rho^(-2N) is below the tolerance.  The
splitting runs for all pieces of a batch at once, level by level (one vectorized evaluation of the
ellipse parameters per level instead of one per interval: the same arithmetic elementwise, so the
same intervals), and the nodes of all intervals are placed in one vectorized step.
"""
from __future__ import annotations

import numpy as np

from thetasol.core.panels import gauss_legendre

RHO_TARGET = 2.5


def n_nodes(rho: float, tol: float) -> int:
    if not np.isfinite(rho):
        return 4
    return int(max(4, min(80, np.ceil((np.log(1.0 / tol) + np.log(8.0)) / (2 * np.log(rho))))))


def ellipse_params(sings, lo, hi):
    """Parameter rho of the Bernstein ellipse of [lo, hi] through each singularity (broadcasting)."""
    t = (2 * sings - (lo + hi)) / (hi - lo)
    s = np.sqrt(t - 1) * np.sqrt(t + 1)
    return np.maximum(np.abs(t + s), np.abs(t - s))


def plan_pieces(pieces, sites, tol: float, rho_target: float = RHO_TARGET, max_intervals: int = 4000):
    """Intervals [lo, hi] of tau with their Gauss-Legendre order, for each piece without explicit
    nodes: lists of (lo, hi, N) sorted by lo ([] for the others)."""
    want = [p for p, pc in enumerate(pieces) if pc.taus is None]
    sings = [pieces[p].singularities(sites) for p in want]
    smax = max((len(s) for s in sings), default=0)
    SG = np.zeros((len(want), max(smax, 1)), complex)
    valid = np.zeros(SG.shape, bool)
    for r, s in enumerate(sings):
        SG[r, :len(s)], valid[r, :len(s)] = s, True
    out = [[] for _ in pieces]
    row, lo, hi = np.arange(len(want)), np.zeros(len(want)), np.ones(len(want))
    while len(row):
        with np.errstate(all="ignore"):
            ep = np.where(valid[row], ellipse_params(SG[row], lo[:, None], hi[:, None]), np.inf)
        rho = ep.min(axis=1)
        done = (rho >= rho_target) | (hi - lo < 1e-15)
        for r, a, b, q in zip(row[done].tolist(), lo[done].tolist(), hi[done].tolist(), rho[done].tolist()):
            out[want[r]].append((a, b, n_nodes(q, tol)))
            if len(out[want[r]]) > max_intervals:
                raise ValueError("path too close to a critical value (quadrature refinement exhausted)")
        # split at the projection of the nearest singularity, kept inside the middle half
        sp = ~done
        row, lo, hi, ep = row[sp], lo[sp], hi[sp], ep[sp]
        L = hi - lo
        z = SG[row, ep.argmin(axis=1)]
        m = np.minimum(np.maximum(z.real, lo + 0.25 * L), hi - 0.25 * L)
        row, lo, hi = np.concatenate([row, row]), np.concatenate([lo, m]), np.concatenate([m, hi])
    for iv in out:
        iv.sort()
    return out


class Nodes:
    """All tracking/quadrature nodes of a batch of pieces, flattened: ``tau``, weights ``w``, the
    points ``x`` and derivatives ``dx``, ``ddx``; ``offsets`` (per piece) and ``plans``."""

    def __init__(self, pieces, sites, tol):
        self.plans = plan_pieces(pieces, sites, tol)
        iv = [v for pv in self.plans for v in pv]
        lo, hi = np.array([v[0] for v in iv], float), np.array([v[1] for v in iv], float)
        Ns = [v[2] for v in iv]
        rules = [gauss_legendre(N) for N in Ns]
        mid, half = np.repeat(0.5 * (lo + hi), Ns), np.repeat(0.5 * (hi - lo), Ns)
        T = mid + half * np.concatenate([r[0] for r in rules]) if iv else np.zeros(0)
        W = half * np.concatenate([r[1] for r in rules]) if iv else np.zeros(0)
        taus, wts, self.offsets = [], [], [0]
        zero, one, k = np.zeros(1), np.ones(1), 0
        for pc, pv in zip(pieces, self.plans):
            if pc.taus is not None:
                tt, ww = [np.asarray(pc.taus, dtype=float)], [np.zeros(len(pc.taus))]
            else:
                n = sum(v[2] for v in pv)
                tt, ww = [zero, T[k:k + n]], [zero, W[k:k + n]]
                k += n
                if pc.kind == "line":
                    tt.append(one)
                    ww.append(zero)
            taus += tt
            wts += ww
            self.offsets.append(self.offsets[-1] + sum(len(t) for t in tt))
        self.tau = np.concatenate(taus) if taus else np.zeros(0)
        self.w = np.concatenate(wts) if wts else np.zeros(0)
        self.x, self.dx, self.ddx = _piece_values(pieces, self.tau, self.offsets)


def _piece_values(pieces, tau, offsets):
    """x, dx/dtau, d2x/dtau2 at the nodes of every piece."""
    if not pieces:
        return (np.zeros(0, complex),) * 3
    parts = [(pc.x(t), pc.dx(t), pc.ddx(t))
             for pc, t in ((pc, tau[offsets[p]:offsets[p + 1]]) for p, pc in enumerate(pieces))]
    return tuple(np.concatenate([v[c] for v in parts]) for c in range(3))
