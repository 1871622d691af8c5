"""Riemann theta along a real linear flow: theta(s_j + t u | tau) for fixed shifts s_j.

In a homology basis adapted to the real Liouville torus (:mod:`thetasol.curves.adapted_basis`) the
velocity ``u`` is real and vanishes outside the first r coordinates, so ``Im`` of the argument is
constant and, as a function of t, theta is the Fourier series in r phases::

    theta(s + t u) = exp(e_s) sum_{m' in Z^r} D_s(m') exp(2 pi i m'.phi(t)),  phi(t) = t u mod 1,
    D_s(m') = sum_{m''} exp(pi i m.tau.m + 2 pi i m.s - e_s),   m = (m', m''),

with ``e_s = pi y.(Im tau)^-1.y``, ``y = Im s``.  The coefficients D_s are summed once (all m in
the ellipsoid pi (m + c).Y.(m + c) <= R^2, c = Y^-1 y, outside which the terms are below ``tol``);
per time only the phases and one real matrix product remain.  The modes m' and -m' share one phase:
with ``p`` the modes up to sign, ``D(p) e^{i x} + D(-p) e^{-i x} = cos x (D(p) + D(-p)) +
sin x i (D(p) - D(-p))``, so the product runs over the float view ``(cos, sin)`` of
``exp(2 pi i p.phi)`` (products of one-dimensional tables) against one real matrix giving the values
and the t-derivatives of every shift together: half the phases and half the multiplications of the
complex series over m'.  Integer shifts of ``phi`` leave theta unchanged, so far times cost what t = 1 costs
and need no quasi-periodicity factors.

The per-time evaluation is compiled (:class:`thetasol.core.kernels.FlowKernel`, src/kernels.cpp): the turns
``t u`` reduced exactly (:mod:`thetasol.core.turns`), the tables ``exp(2 pi i k phi_i)`` as powers of
``exp(2 pi i phi_i)`` outwards from ``k = 0`` (one exponential per phase, and more accurate than
``exp(2 pi i fl(k phi))``), the products of the tables per mode and the real matrix product.  This module
sums the coefficients and builds the frozen tables it computes from.
"""
from __future__ import annotations

import math

import numpy as np

from thetasol.core.kernels import FlowKernel
from thetasol.core.turns import split_rate
from thetasol.theta.lattice import unique_rows

__all__ = ["FlowTheta", "ellipsoid_candidates", "ellipsoid_candidates_many", "lower_factor", "row_sums"]



def lower_factor(Y: np.ndarray) -> np.ndarray:
    """Lower triangular ``M`` with ``Y = M^T M`` (``Y`` symmetric positive definite)."""
    U = np.linalg.cholesky(Y[::-1, ::-1]).T          # upper, Y reversed = U^T U
    return U[::-1, ::-1]


def ellipsoid_candidates(c: np.ndarray, M: np.ndarray, bound: float, box: list) -> np.ndarray:
    """Integer points m of the box (per coordinate ``(lo, hi)``) that may satisfy
    ``(m + c).Y.(m + c) <= bound`` (``Y = M^T M``, M lower triangular), as floats in the box's
    lexicographic order (the order of ``np.meshgrid(..., indexing="ij")``).

    Coordinate by coordinate (Fincke-Pohst): row i of ``M (m + c)`` involves coordinates 0..i only,
    so the sum of the squares of the first rows bounds the range of the next coordinate.  The bound
    is widened by 1e-6 relative and every range by 1e-9 of its centre and half-width: more than the
    rounding of these sums (a few ulps relative), so a superset of the exact test's points (callers
    apply that test), and barely more: a widening by one integer per range would give several times as
    many.
    """
    return ellipsoid_candidates_many(np.asarray(c, float)[None, :], M, bound, [box])[0]


def ellipsoid_candidates_many(cs: np.ndarray, M: np.ndarray, bound: float,
                              boxes: list) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`ellipsoid_candidates` for several centres ``cs`` (S, g) and boxes at once: the points of
    all of them (n, g), grouped by centre, the centre of each (n,) and ``||M (m + c)||^2`` as summed
    row by row (n,).  The same operations per point as one centre at a time, in one pass over the
    coordinates (FlowTheta's ten shifts: one set of numpy calls instead of ten)."""
    S, g = cs.shape
    B = bound * (1 + 1e-6) + 1e-12
    bx = np.asarray(boxes, dtype=np.int64).reshape(S, g, 2)
    pts = np.zeros((S, 0))
    used = np.zeros(S)
    own = np.arange(S)
    for i in range(g):
        s_i = (pts + cs[own, :i]) @ M[i, :i] if i else np.zeros(len(pts))
        w = np.sqrt(np.maximum(B - used, 0.0)) / M[i, i]
        c_i = cs[own, i]
        ctr = -s_i / M[i, i] - c_i
        slack = 1e-9 * (1.0 + np.abs(ctr) + w)
        lo = np.maximum(np.ceil(ctr - w - slack), bx[own, i, 0]).astype(np.int64)
        hi = np.minimum(np.floor(ctr + w + slack), bx[own, i, 1]).astype(np.int64)
        # a prefix already beyond the bound has no continuation inside
        cnt = np.where(used > B, 0, np.maximum(hi - lo + 1, 0))
        owner = np.repeat(np.arange(len(pts)), cnt)
        start = np.cumsum(cnt) - cnt
        val = lo[owner] + (np.arange(owner.size) - start[owner])
        pts = np.concatenate([pts[owner], val[:, None].astype(float)], axis=1)
        row = M[i, i] * (val + c_i[owner]) + s_i[owner]
        used = used[owner] + row * row
        own = own[owner]
    return pts, own, used


def row_sums(P: np.ndarray) -> np.ndarray:
    """``P.sum(axis=1)`` bit for bit, for rows of up to 4 entries by columns (numpy's reduction over
    short rows costs more per row than the column additions): in numpy's order, left to right
    (pairwise ``(p0 + p1) + (p2 + p3)`` for 4 complex entries, whose 8 floats make one pairwise block)."""
    n = P.shape[1]
    if n > 4 or n == 0:
        return P.sum(axis=1)
    if n == 4 and np.iscomplexobj(P):
        return (P[:, 0] + P[:, 1]) + (P[:, 2] + P[:, 3])
    acc = P[:, 0]
    for i in range(1, n):
        acc = acc + P[:, i]
    return acc


def _surely_inside(Y: np.ndarray, bound: float) -> float:
    """A level below which ``||M (m + c)||^2`` as summed by :func:`ellipsoid_candidates_many` implies
    that FlowTheta's exact test ``pi (d.Y.d) <= pi bound`` (``d = m + c``, summed as ``(d @ Y) * d``)
    passes, or -1 (test every point).

    Both sums evaluate the same form of the same rounded ``d``; their relative difference is at most
    ``8 g eps (sqrt(tr Y / l) + ||Y||_F / l)`` (l the smallest eigenvalue of ``Y``: rounding of the
    rows of ``M d``, of ``d @ Y`` and of the sums, ``|d|^2 <= d.Y.d / l``), far below ``1e-6``.  Points
    ``1e-6`` inside are then inside for both, and only the candidates in that thin shell take the exact
    test.
    """
    g = len(Y)
    lam = float(np.linalg.eigvalsh(Y)[0])
    disc = 8 * g * np.finfo(float).eps * (math.sqrt(np.trace(Y) / lam) + np.linalg.norm(Y) / lam)
    return bound * (1 - 1e-6) if disc < 1e-7 else -1.0


def _quadratic_form(m: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """``row_sums((m @ tau) * m)`` for real points m (n, g): the same products from two real matrix
    products (the complex product of real m has the real products as its parts, and the complex
    multiplication by real m gives ``Re * m`` and ``Im * m``), summed in the order of the complex sum,
    without converting m to complex twice."""
    P = np.empty(m.shape, complex)
    P.real = (m @ tau.real) * m
    P.imag = (m @ tau.imag) * m
    return row_sums(P)


def _series_terms(tau: np.ndarray, shifts: np.ndarray, r: int, tol: float) -> tuple:
    """``(e (S,), keys, terms, rows)``: per shift s_j the exponent ``e_j``, and for the points m of its
    ellipsoid the mode ``m[:r]``, the term ``exp(pi i m.tau.m + 2 pi i m.s_j - e_j)`` and ``j``."""
    g, S = tau.shape[0], shifts.shape[0]
    Y = tau.imag
    Yinv = np.linalg.inv(Y)
    R2 = math.log(1.0 / tol) + 2.0 * math.log(10.0)
    e = np.empty(S)
    half = np.sqrt(R2 / math.pi * np.diag(Yinv))
    cs, boxes = [], []
    for j, s in enumerate(shifts):
        y = s.imag
        cs.append(Yinv @ y)
        e[j] = math.pi * y @ Yinv @ y
        boxes.append([(math.floor(-cs[j][i] - half[i]), math.ceil(-cs[j][i] + half[i])) for i in range(g)])
    pts, own, used = ellipsoid_candidates_many(np.array(cs), lower_factor(Y), R2 / math.pi, boxes)
    inner = _surely_inside(Y, R2 / math.pi)
    counts = np.bincount(own, minlength=S)
    ends = np.cumsum(counts)
    keys, terms, rows = [], [], []
    for j, s in enumerate(shifts):
        sl = slice(ends[j] - counts[j], ends[j])
        m = pts[sl]
        near = np.flatnonzero(used[sl] > inner)     # only these can fail the exact test
        if len(near):
            d = m[near] + cs[j]
            keep = np.ones(len(m), bool)
            keep[near] = math.pi * row_sums((d @ Y) * d) <= R2
            m = m[keep]
        expo = 1j * math.pi * _quadratic_form(m, tau) + 2j * math.pi * m @ s - e[j]
        keys.append(m[:, :r].astype(np.int64))
        terms.append(np.exp(expo))
        rows.append(np.full(len(m), j))
    return e, keys, terms, rows


class FlowTheta:
    """Values and u-derivatives of theta(s_j + t u) for shifts s_j (S, g) and real u (r,)."""

    def __init__(self, tau: np.ndarray, u: np.ndarray, shifts: np.ndarray, tol: float = 1e-16):
        tau = 0.5 * (tau + tau.T)
        u = np.asarray(u, float)
        r = u.size
        S = shifts.shape[0]
        self.e, keys, terms, rows = _series_terms(tau, shifts, r, tol)
        # group the terms by their first r indices (the Fourier mode), in one pass for all shifts
        # (np.unique over rows sorts structured records, slowly: rows coded as C-order flat indices in the
        # box lo .. lo + span - 1 keep the same lexicographic order)
        K = np.concatenate(keys)
        self.modes, inv = unique_rows(K)
        # np.add.at on the flat array: much cheaper than with the (shift, mode) index pair
        D = np.zeros(S * len(self.modes), complex)
        np.add.at(D, np.concatenate(rows) * len(self.modes) + inv, np.concatenate(terms))
        D = D.reshape(S, len(self.modes))
        self.D = D
        self.u = u
        self.r = r
        self._pair(self.modes, D, D * (2j * math.pi * (self.modes @ u))[None, :])    # D and its t-derivative

    def _pair(self, modes: np.ndarray, D: np.ndarray, Dd: np.ndarray) -> None:
        """The real form of the series: the modes m and -m share one phase (module docstring).

        ``p`` runs over the modes up to sign (first non-zero index positive); with
        ``c = cos 2 pi p.phi``, ``s = sin 2 pi p.phi``, a coefficient pair contributes
        ``c (D(p) + D(-p)) + s i (D(p) - D(-p))``.  ``self.W`` (2P, 4S) maps the columns
        ``(c_0, s_0, c_1, s_1, ...)`` (the float view of ``exp(2 pi i p.phi)``) to the float view of
        ``[v | dv]`` (n, 2S) complex.
        """
        S = D.shape[0]
        sign = np.zeros(len(modes), np.int64)
        for i in range(modes.shape[1] - 1, -1, -1):      # sign of the first non-zero index
            sign = np.where(modes[:, i] != 0, np.sign(modes[:, i]), sign)
        canon = modes * np.where(sign < 0, -1, 1)[:, None]
        # the box holds k = 0 in every coordinate: the tables are powers outwards from it (the kernel's tables)
        lo = np.minimum(canon.min(axis=0), 0)
        span = np.maximum(canon.max(axis=0), 0) - lo + 1
        pm, inv = unique_rows(canon, lo, span)
        C = np.concatenate([D, Dd]).T                    # (K, 2S): coefficients of exp(2 pi i m.phi)
        # each p has at most one mode of either sign, so the indices within a sign are distinct and the
        # buffered fancy additions give np.add.at's sums from zero (addition commutes)
        neg = sign < 0
        ip, ineg = inv[~neg], inv[neg]
        A = np.zeros((len(pm), 2 * S), complex)          # coefficient of cos
        A[ip] += C[~neg]
        A[ineg] += C[neg]
        Bs = np.zeros((len(pm), 2 * S), complex)         # coefficient of sin
        Bs[ip] += 1j * C[~neg]
        Bs[ineg] += -1j * C[neg]
        W = np.empty((2 * len(pm), 4 * S))
        W[0::2, 0::2], W[0::2, 1::2] = A.real, A.imag
        W[1::2, 0::2], W[1::2, 1::2] = Bs.real, Bs.imag
        self.W = W
        #: the modes up to sign
        self.n_phases = len(pm)
        #: the turn rates ``u`` as ``u1 + u2 + u3`` (:func:`thetasol.core.turns.split_rate`) and ``u``: (4, r)
        self.u_pieces = np.array([*split_rate(self.u), self.u]).reshape(4, len(span))
        self.lo, self.span = lo.astype(np.int64), span.astype(np.int64)
        #: per mode up to sign, its column in the table of each phase: ``k - lo`` (P, r)
        self.table_modes = np.ascontiguousarray(pm - lo, dtype=np.int64)
        self.kernel = FlowKernel(self.u_pieces, self.lo, self.span, self.table_modes, np.ascontiguousarray(W))

    def __call__(self, t: np.ndarray, derivative: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """(e (S,), v (n, S), dv (n, S) or None) at the flat times ``t``: theta = exp(e) v,
        d/dt theta = exp(e) dv (the compiled kernel; the derivative costs a quarter of the product and is
        formed whether asked or not)."""
        S = self.D.shape[0]
        vd = self.kernel(np.ascontiguousarray(t, dtype=float)).view(complex)
        return self.e, vd[:, :S], (vd[:, S:] if derivative else None)
