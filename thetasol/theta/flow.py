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
"""
from __future__ import annotations

import math

import numpy as np

from thetasol.core.turns import rate_turns, split_rate
from thetasol.theta.lattice import unique_rows

__all__ = ["FlowTheta", "ellipsoid_candidates", "ellipsoid_candidates_many", "lower_factor", "row_sums"]

#: Bytes of phase products per block of times in :meth:`FlowTheta.__call__`, and the most times per
#: block: the real matrix (2 x phases, 4 x shifts) is read once per block, so larger blocks pay off until
#: the products leave the cache (benchmarks/bench_theta_rotation.py measures the dense evaluation).
BLOCK_BYTES = 1 << 22
BLOCK_CAP = 1024
#: Up to this many products (times x phases) :meth:`FlowTheta.phases` gathers all factors at once
#: instead of forming the products over prefixes of the modes (the same products in the same order):
#: fewer numpy calls, more multiplications, which pays off for a few times on a few hundred phases.
FEW_PRODUCTS = 512
#: From this many times on, :meth:`FlowTheta.tables` forms its powers along the times
#: (:meth:`FlowTheta.table_rows`, one numpy call per power) instead of by cumprod along short rows: the
#: same products, cheaper on long blocks of times and dearer on short ones.
COLUMN_POWERS = 128
#: From this many times on, and for up to :data:`ROWS_MAX_PHASES` phases, :meth:`FlowTheta.__call__`
#: forms the phases as rows, one per phase along the times (:meth:`FlowTheta.phase_rows`), and the matrix
#: product from their real and imaginary planes, in blocks of up to 1024 times: contiguous products instead
#: of gathers along short rows, which stop paying off when the rows of a block leave the cache.
ROWS_MIN = 64
ROWS_MAX_PHASES = 512
#: ``2 pi i``: the tables are ``exp(2 pi i k phi)``.
TWO_PI_I = 2j * math.pi


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


def _sorted_unique_rows(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(a, axis=0, return_inverse=True)`` for rows already in lexicographic order (runs of
    equal rows, no sort)."""
    new = np.concatenate([[True], (a[1:] != a[:-1]).any(axis=1)]) if len(a) else np.zeros(0, bool)
    return a[new], np.cumsum(new) - 1


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
        self.Dd = D * (2j * math.pi * (self.modes @ u))[None, :]
        self.u = u
        self.r = r
        self._u_pieces = (*split_rate(u), u)
        self._pair(self.modes, D, self.Dd)

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
        # the box holds k = 0 in every coordinate: the tables are powers outwards from it (:meth:`tables`)
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
        self._WT = np.ascontiguousarray(W.T)
        self._lo, self._span = lo, span
        self._k = [np.arange(span[i]) + lo[i] for i in range(len(span))]
        self._idx = [pm[:, i] - lo[i] for i in range(len(span))]
        # the products over the first r - 1 phases are formed once per distinct prefix of the modes
        # (fewer than the modes) and then gathered: the same products in the same order
        self._pre_inv, self._pre_idx = None, []
        r = len(span)
        if r > 1:
            pre, inv = _sorted_unique_rows(pm[:, :r - 1])
            self._pre_inv = inv.ravel()
            self._pre_idx = [pre[:, i] - lo[i] for i in range(r - 1)]
        self.n_phases = len(pm)
        self._runs = _runs(self._idx, self._pre_inv)
        self._k_all = np.concatenate(self._k).astype(float)
        self._k_owner = np.repeat(np.arange(r), span)
        ends = np.cumsum(span)
        self._k_slices = [slice(int(e - w), int(e)) for e, w in zip(ends, span, strict=True)]
        self._pm_rel = np.ascontiguousarray(pm - lo)
        # the few-times path gathers every factor from the one table at once: row i, column p holds
        # the column of the table of phase i that mode p multiplies
        self._gather = (self._pm_rel + (ends - span)[None, :]).T.ravel()
        self._blk = int(min(BLOCK_CAP, max(16, BLOCK_BYTES // (16 * max(1, self.n_phases)))))
        # per table: its slice and the column of k = 0
        self._zero_cols = [(sl, int(sl.start - lo[i])) for i, sl in enumerate(self._k_slices)]

    def phases(self, phi: np.ndarray, work: np.ndarray | None = None) -> np.ndarray:
        """``exp(2 pi i p.phi)`` (n, P) for the phases phi (n, r) reduced mod 1.  ``work``: a complex array
        (2, >= n, P) the products of many times are formed in (and the result is a view of);
        :meth:`__call__` passes one for all its blocks."""
        tab = self.tables(phi)
        n = phi.shape[0]
        if self.r > 1 and n * self.n_phases <= FEW_PRODUCTS:
            # every factor in one gather, multiplied in the order of the prefix products below (the
            # same values)
            g = tab.take(self._gather, axis=1).reshape(n, self.r, self.n_phases)
            return np.multiply.reduce(g, axis=1)
        X = None
        for i in range(self.r - 1):
            col = tab[:, self._k_slices[i]].take(self._pre_idx[i], axis=1)
            X = col if X is None else X * col
        last = tab[:, self._k_slices[-1]]
        if work is None:
            work = np.empty((2, n, self.n_phases), complex)
        out, other = work[0, :n], work[1, :n]
        # (mode="clip": the indices are in range, and take's default mode buffers an out= argument)
        last.take(self._idx[-1], axis=1, out=out, mode="clip")
        if X is None:
            return out
        X.take(self._pre_inv, axis=1, out=other, mode="clip")
        return np.multiply(other, out, out=out)

    def table_columns(self) -> tuple[np.ndarray, np.ndarray]:
        """``(i, k)`` of the columns of :meth:`tables`: column j holds ``exp(2 pi i k[j] phi_{i[j]})``."""
        return self._k_owner.copy(), self._k_all.copy()

    def tables(self, phi: np.ndarray) -> np.ndarray:
        """The r tables ``exp(2 pi i k phi_i)``, ``k = lo_i .. lo_i + span_i - 1``, side by side (n, sum span).

        Powers of ``exp(2 pi i phi_i)`` outwards from ``k = 0`` (``exp(-i x) = conj(exp(i x))``): one
        exponential per phase instead of one per entry, which cost as much as the flow's matrix product.
        The powers are also the more accurate: ``exp(2 pi i fl(k phi))`` carries the rounding of its
        argument, about ``|k phi| 2 pi eps``, which the powers do not (tests/test_theta_evaluation.py
        compares both with mpmath).  One time is formed as a block of one.
        """
        n = phi.shape[0]
        if n >= COLUMN_POWERS:     # the same products along the times (cumprod's rows are short)
            return self.table_rows(phi).T
        base = np.exp(TWO_PI_I * phi)                                   # (n, r)
        tab = np.empty((n, self._k_all.size), complex)
        for i, (sl, z) in enumerate(self._zero_cols):
            tab[:, z] = 1.0
            col = base[:, i:i + 1]
            if sl.stop > z + 1:
                np.cumprod(np.broadcast_to(col, (n, sl.stop - z - 1)), axis=1, out=tab[:, z + 1:sl.stop])
            if z > sl.start:
                tab[:, sl.start:z] = np.cumprod(np.broadcast_to(col.conj(), (n, z - sl.start)), axis=1)[:, ::-1]
        return tab

    def turns(self, t: np.ndarray) -> np.ndarray:
        """``t u`` modulo 1 (n, r) in ``[-1/2, 1/2]``, exact before its last roundings for ``|t| < 2^31``
        (:mod:`thetasol.core.turns`).  The plain product ``t u`` carries ``|t u| eps / 2`` into the
        phases, which the exponents of a theta quotient (reduced exactly the same way) then no longer
        match: the first integrals of the fast-spin bodies would drift far out (tests/test_one_call.py)."""
        x = np.ascontiguousarray(rate_turns(t, *self._u_pieces).T)
        x -= np.rint(x)
        return x

    def table_rows(self, phi: np.ndarray) -> np.ndarray:
        """:meth:`tables` transposed, formed as rows (sum span, n): each power one product along the times."""
        n = phi.shape[0]
        base = np.exp(TWO_PI_I * np.ascontiguousarray(phi.T))           # (r, n)
        tab = np.empty((self._k_all.size, n), complex)
        for i, (sl, z) in enumerate(self._zero_cols):
            tab[z] = 1.0
            for step, stop, e in ((1, sl.stop, base[i]), (-1, sl.start - 1, base[i].conj())):
                if stop != z + step:
                    tab[z + step] = e
                for k in range(z + 2 * step, stop, step):
                    np.multiply(tab[k - step], e, out=tab[k])
        return tab

    def phase_rows(self, phi: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """:meth:`phases` transposed (P, n), into ``out`` if given: the prefix products as rows, then one
        product of a prefix row with a block of the last table per run of modes (:func:`_runs`)."""
        tab = self.table_rows(phi)
        if out is None:
            out = np.empty((self.n_phases, phi.shape[0]), complex)
        X = None
        for i in range(self.r - 1):
            row = tab[self._k_slices[i]].take(self._pre_idx[i], axis=0)
            X = row if X is None else X * row
        last = tab[self._k_slices[-1]]
        for j, s, e, a in self._runs:
            if X is None:
                out[s:e] = last[a:a + e - s]
            else:
                np.multiply(X[j], last[a:a + e - s], out=out[s:e])
        return out

    def _by_rows(self, phi: np.ndarray) -> np.ndarray:
        """The float view of ``[v | dv]`` (n, 4S) from :meth:`phase_rows`, in blocks of times: each block's
        rows split into real and imaginary planes (2P, m), and ``W^T`` times them (4S, m)."""
        n, P = phi.shape[0], self.n_phases
        blk = min(n, BLOCK_CAP, max(ROWS_MIN, 4 * BLOCK_BYTES // (16 * P)))
        out = np.empty((n, self.W.shape[1]))
        # the rows and their planes in one workspace (MBs): separate fresh arrays of that size come from
        # mmap in a new process, and their page faults would cost more than the products
        work = np.empty(4 * P * blk)
        rows = work[:2 * P * blk].view(complex).reshape(P, blk)
        planes = work[2 * P * blk:].reshape(P, 2, blk)
        outT = np.empty((self.W.shape[1], blk))
        for a in range(0, n, blk):
            m = min(n, a + blk) - a
            R = self.phase_rows(phi[a:a + m], rows[:, :m])
            pl = planes[:, :, :m]
            np.copyto(pl, R.view(float).reshape(P, m, 2).transpose(0, 2, 1))
            np.matmul(self._WT, pl.reshape(2 * P, m), out=outT[:, :m])
            out[a:a + m] = outT[:, :m].T
        return out

    def __call__(self, t: np.ndarray, derivative: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """(e (S,), v (n, S), dv (n, S) or None): theta = exp(e) v, d/dt theta = exp(e) dv.

        Many times (:data:`ROWS_MIN`, up to :data:`ROWS_MAX_PHASES` phases) go through
        :meth:`phase_rows` in blocks of up to 1024 times; otherwise the phases are gathered per time, in
        blocks of :data:`BLOCK_BYTES` of phase products.  The derivative is computed in the same product
        whether asked or not (its columns cost a quarter of the product).
        """
        t = np.asarray(t, float)
        phi = self.turns(t)
        n, S = t.shape[0], self.D.shape[0]
        blk = self._blk
        if n >= ROWS_MIN and self.n_phases <= ROWS_MAX_PHASES:
            vd = self._by_rows(phi).view(complex)
            return self.e, vd[:, :S], (vd[:, S:] if derivative else None)
        if n <= blk:
            vd = np.matmul(self.phases(phi).view(float), self.W).view(complex)
            return self.e, vd[:, :S], (vd[:, S:] if derivative else None)
        out = np.empty((n, 4 * S))
        # the blocks' phase products (MBs) in one workspace: fresh arrays of that size come from mmap or
        # from the heap as glibc's adaptive threshold stands after the set-up, and from mmap their page
        # faults would cost as much as the products
        work = np.empty((2, blk, self.n_phases), complex)
        for a in range(0, n, blk):
            b = min(n, a + blk)
            np.matmul(self.phases(phi[a:b], work).view(float), self.W, out=out[a:b])
        vd = out.view(complex)
        return self.e, vd[:, :S], (vd[:, S:] if derivative else None)


def _runs(idx: list, pre_inv: np.ndarray | None) -> list[tuple[int, int, int, int]]:
    """The modes (lexicographic; ``idx[i]`` their table columns of phase i, ``pre_inv`` their prefix of the
    first r - 1 phases) as runs of consecutive last columns under one prefix:
    ``(prefix, first mode, end mode, first column)``.  An ellipsoid meets a line in an interval, so there
    are as many runs as prefixes, far fewer than the modes."""
    last = idx[-1]
    new = np.ones(len(last), bool)
    new[1:] = last[1:] != last[:-1] + 1
    if pre_inv is not None:
        new[1:] |= pre_inv[1:] != pre_inv[:-1]
    starts = np.flatnonzero(new)
    ends = np.append(starts[1:], len(last))
    pre = pre_inv[starts] if pre_inv is not None else np.zeros(len(starts), np.int64)
    return list(zip(pre.tolist(), starts.tolist(), ends.tolist(), last[starts].tolist(), strict=True))
