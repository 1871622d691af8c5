"""Lattice machinery behind :mod:`thetasol.theta.riemann`: LLL, Siegel reduction, error bounds, point sets.

Everything here works on the quadratic form ``Y = Im tau = T^T T`` (``T`` upper triangular, so
``(T n)_g = T_gg n_g`` and lattice points are enumerated from the last coordinate to the first,
the first being innermost).  Hand-written because it is small, because no allowed dependency
has an LLL for a real Gram matrix, and because the evaluator needs the exact composition of the
elementary symplectic steps (not only the reduced ``tau``) to map points and characteristics.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from thetasol.core.panels import gauss_legendre

__all__ = ["MAX_GENUS", "lll_gram", "Reduction", "siegel_reduction", "dense_unique", "unique_rows", "shortest_vector",
           "tail_bound", "radius_for", "union_set", "babai"]

#: Largest genus accepted (the union sets grow like R^g; 6 is slow but works).
MAX_GENUS = 8


# ----------------------------------------------------------------------------------------
# LLL reduction of a positive definite Gram matrix
# ----------------------------------------------------------------------------------------
def _ldl(H: np.ndarray):
    """``H = L diag(d) L^T`` with ``L`` unit lower triangular (small dense H)."""
    C = np.linalg.cholesky(H)
    d = np.diag(C) ** 2
    L = C / np.diag(C)[None, :]
    return L, d


def lll_gram(G: np.ndarray, delta: float = 0.99) -> np.ndarray:
    """Unimodular integer ``U`` such that ``U G U^T`` is LLL-reduced (rows of ``U`` = new basis).

    Float arithmetic on the Gram matrix; ``U G U^T`` is recomputed from the integer ``U`` at
    every step, so round-off does not accumulate.
    """
    g = G.shape[0]
    U = np.eye(g, dtype=np.int64)
    k = 1
    it = 0
    while k < g:
        it += 1
        if it > 10000:  # pragma: no cover - LLL terminates; this guards against NaN input
            raise ValueError("LLL reduction of Im(tau) did not terminate")
        for j in range(k - 1, -1, -1):
            H = U @ G @ U.T
            L, _ = _ldl(H)
            q = round(L[k, j])
            if q:
                U[k] -= q * U[j]
        H = U @ G @ U.T
        L, d = _ldl(H)
        if d[k] >= (delta - L[k, k - 1] ** 2) * d[k - 1]:
            k += 1
        else:
            U[[k - 1, k]] = U[[k, k - 1]]
            k = max(k - 1, 1)
    return U


# ----------------------------------------------------------------------------------------
# Siegel reduction as a composition of elementary symplectic steps
# ----------------------------------------------------------------------------------------
@dataclass
class Reduction:
    """Result of :func:`siegel_reduction` for ``tau0`` (a g x g complex symmetric matrix).

    With ``tau = tau_red`` and the zero characteristic it holds, for every ``w`` in C^g,

        theta(w | tau0) = exp(c0 + 2 pi i l.w + pi i w.Q w) theta(M w + tau a_s + b_s | tau)

    where ``a_s, b_s`` are half-integer vectors.  ``gamma = [[A, B], [C, D]]`` in Sp(2g, Z)
    satisfies ``tau = (A tau0 + B)(C tau0 + D)^{-1}`` and ``M = (C tau0 + D)^{-T}``; the
    lattice map ``(a, b) -> gamma^{-T} (a, b)`` sends ``tau0 a + b`` to ``tau a' + b'`` under ``M``.
    """

    tau0: np.ndarray
    tau: np.ndarray
    gamma: np.ndarray
    M: np.ndarray
    Q: np.ndarray
    l: np.ndarray
    c0: complex
    a_s: np.ndarray
    b_s: np.ndarray
    steps: list = field(default_factory=list)
    mp: dict = field(default_factory=dict)

    @property
    def lattice_map(self) -> np.ndarray:
        """``gamma^{-T} = [[D, -C], [-B, A]]`` as an integer matrix."""
        g = self.tau.shape[0]
        A, B = self.gamma[:g, :g], self.gamma[:g, g:]
        C, D = self.gamma[g:, :g], self.gamma[g:, g:]
        return np.block([[D, -C], [-B, A]])


def siegel_reduction(tau0: np.ndarray, max_iter: int = 500, dps: int = 40) -> Reduction:
    """Frauendiener-Jaber-Klein (2019) reduction: LLL on Im tau, |Re tau| <= 1/2, then invert
    ``tau_11`` while ``|tau_11| < 1``.

    The integer steps are chosen in float64, then replayed with mpmath at ``dps`` digits: the
    transformation constants (``c0``, ``Q``, ``l``) carry phases of size ~100 that would otherwise
    cost about 100 eps of accuracy.  The float fields are the correctly rounded mp results; the mp
    values are kept in ``mp`` for the characteristic tables.

    Ties (``Re tau_ij = +-1/2``, LLL coefficients ``+-1/2``, ``|tau_11| = 1``) are common for
    bases adapted to a real structure; either choice is valid provided every step is exactly
    symplectic: the float ``tau`` is kept exactly symmetric and ``B`` is symmetric by
    construction, and ``gamma`` is checked (``gamma^T J gamma = J``) after the replay.
    """
    g = tau0.shape[0]
    tau0 = 0.5 * (tau0 + tau0.T)  # exact no-op for symmetric input
    tau = tau0.copy()
    I = np.eye(g, dtype=np.int64)
    steps: list = []
    for _ in range(max_iter):
        U = lll_gram(tau.imag)
        if not np.array_equal(U, I):
            # U tau U^T is symmetric only up to rounding: keep tau exactly symmetric, or the
            # rounding of Re tau_ij = +-1/2 (a tie, common for real-structure bases) differs
            # between (i, j) and (j, i) and B below is not symmetric (gamma not symplectic)
            tau = U @ tau @ U.T
            tau = 0.5 * (tau + tau.T)
            steps.append(("U", U))
        B = _symmetric_shift(tau.real)
        if np.any(B):
            tau = tau + B
            steps.append(("B", B))
        t11 = tau[0, 0]
        if abs(t11) >= 1.0 - 1e-12:
            break
        tnew = tau.copy()
        tnew[0, 0] = -1.0 / t11
        tnew[0, 1:] = tau[0, 1:] / t11
        tnew[1:, 0] = tau[1:, 0] / t11
        tnew[1:, 1:] = tau[1:, 1:] - np.outer(tau[1:, 0], tau[0, 1:]) / t11
        tau = 0.5 * (tnew + tnew.T)
        steps.append(("S", None))
    else:  # pragma: no cover - det Im tau grows at every inversion, so this needs absurd input
        raise ValueError(f"Siegel reduction of tau did not converge in {max_iter} steps")
    return _replay(tau0, steps, dps)


def _symmetric_shift(X: np.ndarray) -> np.ndarray:
    """Symmetric integer ``B`` with ``|X + B|_ij <= 1/2``, rounded from the upper triangle only.

    ``tau -> tau + B`` is symplectic only for symmetric ``B``; rounding both triangles of a
    matrix that is symmetric up to an ulp breaks that at the ties ``X_ij = +-1/2``.
    """
    R = np.triu(-np.rint(X)).astype(np.int64)
    return R + np.triu(R, 1).T


def _check_steps(steps: list, gamma: np.ndarray) -> None:
    """Every elementary step and their composition must be exactly symplectic (integer check)."""
    g = gamma.shape[0] // 2
    for kind, data in steps:
        if kind == "B" and not np.array_equal(data, data.T):  # pragma: no cover - guarded above
            raise RuntimeError(f"internal error: Siegel reduction shift B is not symmetric:\n{data}")
        if kind == "U" and abs(round(np.linalg.det(data))) != 1:  # pragma: no cover
            raise RuntimeError(f"internal error: Siegel reduction step U is not unimodular:\n{data}")
    J = np.block([[np.zeros((g, g), np.int64), np.eye(g, dtype=np.int64)],
                  [-np.eye(g, dtype=np.int64), np.zeros((g, g), np.int64)]])
    if not np.array_equal(gamma.T @ J @ gamma, J):  # pragma: no cover - would be a broken step
        raise RuntimeError(f"internal error: Siegel reduction gamma is not symplectic:\n{gamma}")


def _replay(tau0: np.ndarray, steps: list, dps: int) -> Reduction:
    """Apply the elementary steps to tau and to the transformation data, in mpmath."""
    import mpmath
    g = tau0.shape[0]
    ctx = mpmath.mp.clone()
    ctx.dps = dps
    mpc, pi = ctx.mpc, ctx.pi
    tau = [[mpc(complex(tau0[i, j])) for j in range(g)] for i in range(g)]
    M = [[mpc(1 if i == j else 0) for j in range(g)] for i in range(g)]
    Q = [[mpc(0)] * g for _ in range(g)]
    l = [mpc(0)] * g
    c0 = mpc(0)
    a_s = np.zeros(g)
    b_s = np.zeros(g)
    gamma = np.eye(2 * g, dtype=np.int64)
    I = np.eye(g, dtype=np.int64)
    Z = np.zeros((g, g), np.int64)

    def matmul(A, Bm):  # A integer nested list, Bm nested list
        # the zero entries of the unimodular A are skipped: fsum adds exactly and drops zeros anyway
        return [[ctx.fsum(a * Bm[k][j] for k, a in nz) for j in range(g)] for nz in
                ([(k, a) for k, a in enumerate(row) if a] for row in A)]

    for kind, data in steps:
        if kind == "U":
            U = data
            Uinv_T = np.rint(np.linalg.inv(U)).astype(np.int64).T
            if not np.array_equal(U @ Uinv_T.T, I):  # pragma: no cover - huge U entries only
                raise RuntimeError(f"internal error: inverse of the LLL step is not exact:\n{U}")
            Ul = U.tolist()
            tau = matmul(Ul, [list(r) for r in zip(*matmul(Ul, [list(r) for r in zip(*tau)]))])
            tau = [[(tau[i][j] + tau[j][i]) / 2 for j in range(g)] for i in range(g)]
            M = matmul(Ul, M)
            a_s, b_s = Uinv_T @ a_s, U @ b_s
            gamma = np.block([[U, Z], [Z, Uinv_T]]) @ gamma
        elif kind == "B":
            B = data
            tau = [[tau[i][j] + int(B[i, j]) for j in range(g)] for i in range(g)]
            b_s = b_s - B @ a_s - np.diag(B) / 2.0
            gamma = np.block([[I, B], [Z, I]]) @ gamma
        else:
            t11 = tau[0][0]
            # u_1 = M_1 w + s_1 with s = tau a_s + b_s (exact halves times tau)
            s1 = ctx.fsum(tau[0][j] * ctx.mpf(a_s[j]) for j in range(g)) + ctx.mpf(b_s[0])
            M1 = list(M[0])
            # one reciprocal, then products (cheaper than ~3 g^2 mpmath divisions, as accurate); the
            # products a_i a_j first, so that Q and tau stay exactly symmetric
            r11 = 1 / t11
            M1r = [x * r11 for x in M1]
            Q = [[Q[i][j] - (M1[i] * M1[j]) * r11 for j in range(g)] for i in range(g)]
            l = [l[i] - s1 * M1r[i] for i in range(g)]
            c0 = c0 - 1j * pi * s1 * s1 * r11 - ctx.log(-1j * t11) / 2
            newM = [M1r]
            for i in range(1, g):
                newM.append([M[i][j] - tau[i][0] * M1r[j] for j in range(g)])
            M = newM
            tn = [[None] * g for _ in range(g)]
            tn[0][0] = -r11
            for j in range(1, g):
                tn[0][j] = tn[j][0] = tau[0][j] * r11
            for i in range(1, g):
                for j in range(1, g):
                    tn[i][j] = tau[i][j] - (tau[i][0] * tau[0][j]) * r11
            tau = tn
            E = np.zeros((g, g), np.int64)
            E[0, 0] = 1
            Id = I - E
            a_s, b_s = Id @ a_s - E @ b_s, E @ a_s + Id @ b_s
            gamma = np.block([[Id, -E], [E, Id]]) @ gamma
    _check_steps(steps, gamma)
    tofl = lambda A: np.array([[complex(x) for x in row] for row in A])
    taur = tofl(tau)
    red = Reduction(tau0=tau0, tau=0.5 * (taur + taur.T), gamma=gamma, M=tofl(M), Q=tofl(Q),
                    l=np.array([complex(x) for x in l]), c0=complex(c0), a_s=a_s, b_s=b_s, steps=steps)
    red.mp = {"ctx": ctx, "tau0": [[mpc(complex(tau0[i, j])) for j in range(g)] for i in range(g)],
              "tau": tau, "M": M, "Q": Q, "l": l, "c0": c0}
    return red


def dense_unique(codes: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(codes, return_inverse=True)`` for integers in ``0 .. size - 1``, by marking a table
    instead of sorting (the flow terms of a body fall into tables far smaller than their count, where
    marking is an order of magnitude cheaper than the sort)."""
    if size > 4 * codes.size + 4096:
        codes, inv = np.unique(codes, return_inverse=True)
        return codes, np.asarray(inv).reshape(-1)
    present = np.zeros(size, bool)
    present[codes] = True
    rank = np.cumsum(present) - 1
    return np.flatnonzero(present), rank[codes]


def unique_rows(a: np.ndarray, lo: np.ndarray | None = None,
                span: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(a, axis=0, return_inverse=True)`` for integer rows (N, c): the distinct rows in
    lexicographic order and the index of each row, through one mixed-radix code per row in the box
    ``lo .. lo + span - 1`` (default: the rows' own box; a larger box gives the same result) and
    :func:`dense_unique` (cheaper than numpy's sort of the rows)."""
    if a.shape[0] == 0 or a.shape[1] == 0:
        rows, inv = np.unique(a, axis=0, return_inverse=True)
        return rows, np.asarray(inv).reshape(-1)
    if lo is None:   # column by column: numpy's integer min/max over axis 0 of (N, c) is slower here
        lo = np.array([a[:, i].min() for i in range(a.shape[1])], dtype=np.int64)
        span = np.array([a[:, i].max() for i in range(a.shape[1])], dtype=np.int64) - lo + 1
    codes, inv = dense_unique(np.ravel_multi_index(tuple((a - lo).T), span), int(np.prod(span)))
    rows = (lo + np.stack(np.unravel_index(codes, span), axis=-1)).astype(a.dtype, copy=False)
    return rows, inv


# ----------------------------------------------------------------------------------------
# Error bounds (Deconinck et al. 2004, Thm 2, generalized to polynomial weights)
# ----------------------------------------------------------------------------------------
def shortest_vector(T: np.ndarray) -> float:
    """Length of the shortest nonzero vector ``min ||T n||`` (Fincke-Pohst on the union-free set)."""
    g = T.shape[0]
    best = float(min(np.linalg.norm(T[:, j]) for j in range(g)))
    pts = _enumerate(T, best * (1 + 1e-12), box=False)
    norms = np.linalg.norm(pts @ T.T, axis=1)
    norms = norms[norms > 0]
    return float(min(best, norms.min())) if norms.size else best


def tail_bound(R: float, rho: float, g: int, order: int = 0, a: float = 1.0) -> float:
    """Upper bound of ``sum_{||T(m+f)|| >= R} (1 + a t)^order exp(-pi t^2)``, t = ||T(m+f)||.

    Disjoint balls of radius rho/2 around the points give ``#{t_m <= t} <= (2 t/rho + 1)^g``;
    a Stieltjes integration by parts then bounds the tail by
    ``int_R^inf (2t/rho + 1)^g (-h'(t)) dt`` for the decreasing weight h (Deconinck et al.).

    ``-h'`` is negative below ``t* = _weight_turn(order, a)`` (the bound counts it as 0) and a polynomial
    times ``exp(-pi t^2)`` beyond: composite Gauss-Legendre (32 panels of 20 nodes) on
    ``[max(R, t*), R + 12]``, to rounding against scipy's adaptive quadrature
    (tests/test_setup_kernels.py), without importing scipy.integrate (slow at its first use).
    """
    t0 = max(R, _weight_turn(order, a)) if order else R
    if t0 >= R + 12.0:
        return 0.0
    x, wq = _panels(t0, R + 12.0)
    w = 1.0 + a * x
    hp = ((2 * math.pi * x * w - order * a) * w ** (order - 1) if order else 2 * math.pi * x) * np.exp(-math.pi * x * x)
    return float(np.dot(wq, (2.0 * x / rho + 1.0) ** g * np.maximum(hp, 0.0)))


def _weight_turn(order: int, a: float) -> float:
    """The positive root of ``2 pi t (1 + a t) - order a``, where ``-h'`` turns positive."""
    return (-2 * math.pi + math.sqrt(4 * math.pi ** 2 + 8 * math.pi * a * a * order)) / (4 * math.pi * a)


def _panels(lo: float, hi: float, n: int = 32) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights of n Gauss-Legendre panels of 20 nodes on [lo, hi]."""
    t, w = gauss_legendre(20)
    h = (hi - lo) / n
    mid = lo + h * (np.arange(n) + 0.5)
    return (mid[:, None] + 0.5 * h * t[None, :]).ravel(), np.tile(0.5 * h * w, n)


def _polymul(p: list, q: list) -> list:
    out = [0.0] * (len(p) + len(q) - 1)
    for i, x in enumerate(p):
        for j, y in enumerate(q):
            out[i + j] += x * y
    return out


def _tail_closed(R: float, rho: float, g: int, order: int, a: float) -> float | None:
    """:func:`tail_bound` in closed form, or None where the weight's derivative changes sign beyond R.

    The integrand is a polynomial in t times exp(-pi t^2) (no clipping where the polynomial is
    positive on [R, inf): beyond the positive root of 2 pi t (1 + a t) - order a); with
    ``I_k = int_R^inf t^k exp(-pi t^2) dt = (R^(k-1) exp(-pi R^2) + (k-1) I_(k-2)) / (2 pi)``.
    The quadrature's upper limit R + 12 drops ``exp(-pi (R + 12)^2)``, far below double precision.
    """
    h = [0.0, 2 * math.pi]
    if order:
        t_star = _weight_turn(order, a)
        if R <= 1.01 * t_star:
            return None
        w = [1.0, a]
        h = _polymul(w, h)
        h[0] -= order * a
        for _ in range(order - 1):
            h = _polymul(h, w)
    c = h
    for _ in range(g):
        c = _polymul(c, [1.0, 2.0 / rho])
    ex = math.exp(-math.pi * R * R)
    I = [0.5 * math.erfc(math.sqrt(math.pi) * R), ex / (2 * math.pi)]
    for k in range(2, len(c)):
        I.append((R ** (k - 1) * ex + (k - 1) * I[k - 2]) / (2 * math.pi))
    return sum(ck * Ik for ck, Ik in zip(c, I))


def _tail_above(R: float, tol: float, rho: float, g: int, order: int, a: float) -> bool:
    """``tail_bound(R) > tol``, decided by the closed form where it is clear by a factor 1 +- 1e-4
    (far beyond the quadrature's 1e-6), else by the quadrature: the same decisions, far cheaper."""
    v = _tail_closed(R, rho, g, order, a)
    if v is not None and math.isfinite(v):
        if v > tol * (1 + 1e-4):
            return True
        if v < tol * (1 - 1e-4):
            return False
    return tail_bound(R, rho, g, order, a) > tol


def radius_for(tol: float, rho: float, g: int, order: int = 0, a: float = 1.0) -> float:
    """Smallest R (to 1e-3) with ``tail_bound(R) <= tol``."""
    lo, hi = 0.5, 2.0
    while _tail_above(hi, tol, rho, g, order, a):
        lo, hi = hi, hi * 1.5
    while hi - lo > 1e-3:
        mid = 0.5 * (lo + hi)
        if _tail_above(mid, tol, rho, g, order, a):
            lo = mid
        else:
            hi = mid
    return hi


# ----------------------------------------------------------------------------------------
# Lattice point sets and Babai rounding
# ----------------------------------------------------------------------------------------
def _enumerate(T: np.ndarray, R: float, box: bool = True) -> np.ndarray:
    """Integer points ``m`` with ``sum_i dist((T m)_i, [-T_ii/2, T_ii/2])^2 < R^2`` (box=True):
    the union over the Babai cell of the ellipsoids ``||T(m + f)|| < R``; box=False gives the
    plain ellipsoid ``||T m|| < R``.  Level-wise (vectorized) enumeration from the last coordinate.
    """
    g = T.shape[0]
    half = 0.5 * np.diag(T) if box else np.zeros(g)
    pts = np.zeros((1, 0), dtype=np.int64)
    rem = np.array([R * R])
    for i in range(g - 1, -1, -1):
        tii = T[i, i]
        s = pts @ T[i, i + 1:] if pts.shape[1] else np.zeros(len(pts))
        r = np.sqrt(np.maximum(rem, 0.0)) + half[i]
        lo = np.ceil((-s - r) / tii - 1e-12).astype(np.int64)
        hi = np.floor((-s + r) / tii + 1e-12).astype(np.int64)
        cnt = np.maximum(hi - lo + 1, 0)
        rep = np.repeat(np.arange(len(pts)), cnt)
        offs = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        mi = lo[rep] + offs
        d = np.maximum(np.abs(tii * mi + s[rep]) - half[i], 0.0)
        newrem = rem[rep] - d * d
        keep = newrem > 0
        pts = np.concatenate([mi[keep, None], pts[rep][keep]], axis=1)
        rem = newrem[keep]
    return pts


def union_set(T: np.ndarray, R: float) -> np.ndarray:
    """Lattice points needed by every point whose Babai remainder lies in the cell (int64, (N, g))."""
    return _enumerate(T, R, box=True)


def babai(c: np.ndarray, T: np.ndarray) -> np.ndarray:
    """Nearest-plane rounding: integer ``k`` with ``(T(c - k))_i`` in ``[-T_ii/2, T_ii/2]``.

    ``c`` has shape (..., g); returns float array of integers (same shape).
    """
    g = T.shape[0]
    k = np.empty_like(c)
    f = np.empty_like(c)
    for i in range(g - 1, -1, -1):
        acc = c[..., i] + (f[..., i + 1:] @ T[i, i + 1:]) / T[i, i] if i < g - 1 else c[..., i].copy()
        k[..., i] = np.rint(acc)
        f[..., i] = c[..., i] - k[..., i]
    return k
