"""Riemann theta with half characteristics on a 2-D grid of a real torus, as complex matrix products.

The points are ``z_ij = z0 + x_m + tau x_n`` with ``x = a_i k1 + b_j k2`` (``k1, k2`` real lattice coordinates,
``2g`` each: ``m + tau n`` for ``(m, n)``).  The grid is cut into blocks; a block with centre ``x_c`` is first
shifted by the integer lattice vector ``K = round(x_c)`` (the characteristics' signs ``(-1)^(2(alpha.K_m +
beta.K_n))`` kept, the quasi-periodicity factor common to all characteristics dropped, as
``KovalevskayaMotion.values_at`` does).  With ``zeta_c = xi + tau c`` the shifted centre (``xi, c`` real),
``n0 = -round(c)``, ``o = n0 + c`` (in the unit cube), ``nu = n + alpha - n0`` (in ``Z^g + alpha``),
``d = nu + o`` and the offsets ``delta = da u + db w`` (``u, w`` the complex directions of ``k1, k2``)::

    theta[alpha; beta](zeta_c + delta) = exp(L + 2 pi i n0.delta) sum_nu C_nu A[da, nu] B[nu, db],
        L = -pi i c.tau.c - 2 pi i c.xi,   C_nu = exp(pi i d.tau.d + 2 pi i d.xi + 2 pi i (n0 + nu).beta),
        A[da, nu] = exp(2 pi i da nu.u),   B[nu, db] = exp(2 pi i db nu.w).

The first factor is common to all characteristics; it is returned as the complex exponent ``e`` and not
applied.  A block's values are then one matrix product per characteristic (and per derivative: ``C_nu`` times
``2 pi i (n0 + nu).V``), with ``A`` shared by the blocks of a row and ``B`` by those of a column (one term set
per ``alpha``), all blocks of a column in one product.  All factors stay O(1): ``|C_nu| = exp(-pi d.Y.d)``
(``Y = Im tau``), ``|A| <= exp(2 pi |da| |nu|_Y |k1_n|_Y)`` with ``|da k1_n|_Y`` at most half of
``BLOCK_SPREAD`` (``|db k2_n|_Y``: ``BLOCK_SPREAD``), so an entry's exponent is at most ~20 and its relative
rounding ~2e-15.  The terms are ``|nu|_Y <= r + rho`` (``|v|_Y^2 = v.Y.v``): ``pi r^2 = log(1/tol) + 2 log 10``
is the ellipsoid criterion of :mod:`thetasol.theta.flow` (the terms outside every point's own ellipsoid are
left out), ``rho`` bounds ``|o + delta_n|_Y`` over the cube and the block (circumradii).  The sums run in
the frame of ``tau`` (no Siegel reduction): their cost grows as ``1/sqrt(det Im tau)`` and their error as
``cond(Im tau) eps`` (tests/test_theta_grid.py).

On the Kovalevskaya top's grids a point costs a small fraction of one of ``KovalevskayaMotion.values_at``
(``RiemannTheta.jet``), and the two agree to rounding relative to each point's largest value (values, and the
Wronskians ``val_i der_j - val_j der_i``); benchmarks/bench_theta_grid.py measures both.  The matrix products run
at the BLAS peak; the rest is elementwise work on the factors and a per-call overhead, which dominates the small
grids.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core.validate import finite_array
from thetasol.theta._checks import check_tau
from thetasol.theta.flow import ellipsoid_candidates, lower_factor

__all__ = ["ThetaGrid", "theta_grid"]

#: A block spans at most this length ``|da k1_n|_Y`` of the lattice along ``a`` and twice it along ``b``
#: (1 .. 128 points per axis): larger blocks spread over more lattice terms (the matrix products grow) and
#: larger factors, whose rounding grows; smaller ones cost more elementwise work per point, mostly along ``b``
#: (each block column forms its own left factors).
BLOCK_SPREAD = 1.0


def _block_size(a: np.ndarray, kn: np.ndarray, Y: np.ndarray, spread: float) -> int:
    if len(a) < 2:
        return 1
    step = (np.max(a) - np.min(a)) / (len(a) - 1) * math.sqrt(max(kn @ Y @ kn, 1e-300))
    return int(np.clip(2 ** math.floor(math.log2(max(spread / max(step, 1e-300), 1.0))), 1, 128))


@dataclass(frozen=True)
class ThetaGrid:
    """``sign * theta[chi](zeta_ij) = exp(e_ij) value_ij`` at ``zeta_ij = z_ij - shift_m - tau shift_n``.

    ``sign = (-1)^(2(alpha.shift_m + beta.shift_n))``, so ``value`` is ``theta[chi](z_ij)`` up to a factor
    common to all characteristics (the quasi-periodicity factor of ``shift``), as in
    ``KovalevskayaMotion.values_at``.  ``value``, ``derivative``: ``(n1, n2, nchar)`` (views of one array with the
    characteristics outermost); ``derivative`` is ``sign * D_V theta[chi](zeta_ij)`` in the same unit (None
    without a direction).  ``e``: ``(n1, n2)`` complex, common to all characteristics; ``Re e`` differs from
    ``pi Im(zeta).(Im tau)^-1.Im(zeta)`` by O(1), so ``|value|`` stays O(1).  ``shift``: ``(n1, n2, 2g)``
    integers (the block's lattice vector).  ``terms``: lattice terms summed per block and alpha.
    """

    e: np.ndarray
    value: np.ndarray
    derivative: np.ndarray | None
    shift: np.ndarray
    terms: int


@dataclass(frozen=True)
class _Blocks:
    """One axis cut into ``P`` blocks of ``size`` points: centres ``(P,)``, offsets ``(P, size)``."""

    n: int
    size: int
    centre: np.ndarray
    offset: np.ndarray


def _blocks(a: np.ndarray, block: int) -> _Blocks:
    n = len(a)
    size = min(block, n)
    P = -(-n // size)
    pad = np.concatenate([a, np.full(P * size - n, a[-1])]).reshape(P, size)
    centre = 0.5 * (pad.min(1) + pad.max(1))
    return _Blocks(n, size, centre, pad - centre[:, None])


def _chars(chars, g: int) -> tuple[np.ndarray, np.ndarray]:
    """``(alpha, beta)`` as integer arrays ``2 alpha, 2 beta`` of shape ``(nchar, g)``."""
    if isinstance(chars, str):
        if chars != "all":
            raise ValueError(f"chars must be 'all' or a sequence of (alpha, beta) or None, got {chars!r}")
        bits = (np.arange(1 << (2 * g))[:, None] >> np.arange(2 * g - 1, -1, -1)[None, :]) & 1
        return bits[:, :g], bits[:, g:]
    if len(chars) == 0:
        raise ValueError("no characteristic requested")
    try:
        ab = 2 * np.array([np.zeros((2, g)) if ch is None else np.asarray(ch, float).reshape(2, g) for ch in chars])
    except ValueError as exc:
        raise ValueError(f"characteristics must be pairs (alpha, beta) of length {g}, got {chars!r}") from exc
    if np.any(np.abs(ab - np.rint(ab)) > 1e-12):
        raise ValueError(f"characteristics must be half-integer, got {chars!r}")
    ab = np.mod(np.rint(ab), 2).astype(np.int64)
    return ab[:, 0], ab[:, 1]


def _radius(M: np.ndarray, k1n: np.ndarray, k2n: np.ndarray, A: _Blocks, B: _Blocks, tol: float) -> float:
    """``r + rho`` (see the module docstring): the terms kept are ``|nu|_Y <= r + rho`` (``Y = M^T M``)."""
    g = len(M)
    cube = (np.arange(1 << g)[:, None] >> np.arange(g)[None, :]) & 1
    rho = float(np.max(np.linalg.norm((cube - 0.5) @ M.T, axis=1)))
    ha, hb = np.max(np.abs(A.offset), 1), np.max(np.abs(B.offset), 1)
    spread = 0.0
    for s in (1.0, -1.0):
        v = ha[:, None, None] * k1n + s * hb[None, :, None] * k2n
        spread = max(spread, float(np.max(np.linalg.norm(v @ M.T, axis=-1))))
    return math.sqrt((math.log(1.0 / tol) + 2.0 * math.log(10.0)) / math.pi) + rho + spread


def _terms(Y: np.ndarray, M: np.ndarray, r: float, alphas: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per alpha the terms ``nu`` in ``Z^g + alpha`` with ``|nu|_Y <= r`` (``Y = M^T M``), padded to one length:
    ``nu`` (nalpha, S, g) and ``valid`` (nalpha, S)."""
    half = r * np.sqrt(np.diag(np.linalg.inv(Y)))
    box = [(math.floor(-h) - 1, math.ceil(h)) for h in half]
    if math.prod(hi - lo + 1 for lo, hi in box) <= 4096:   # small boxes: enumerating them is cheaper
        m = np.stack(np.meshgrid(*[np.arange(lo, hi + 1.0) for lo, hi in box], indexing="ij"), -1).reshape(-1, len(Y))
        sets = [m + al for al in alphas]
    else:
        sets = [ellipsoid_candidates(al, M, r * r, box) + al for al in alphas]
    sets = [nu[np.sum((nu @ M.T) ** 2, 1) <= r * r] for nu in sets]
    S = max(len(nu) for nu in sets)
    valid = np.arange(S)[None, :] < np.array([len(nu) for nu in sets])[:, None]
    nu = np.stack([np.concatenate([x, np.broadcast_to(x[:1], (S - len(x), len(Y)))]) for x in sets])
    return nu, valid


@dataclass(frozen=True)
class _Centres:
    """Per block ``(P, Q)``: the lattice shift ``K``, ``c``, ``xi`` and ``n0 = -round(c)``."""

    K: np.ndarray       # (P, Q, 2g)
    c: np.ndarray       # (P, Q, g)
    xi: np.ndarray      # (P, Q, g)
    n0: np.ndarray      # (P, Q, g)


def _centres(tau, z0, k1, k2, A: _Blocks, B: _Blocks) -> _Centres:
    g = len(tau)
    X, Y = tau.real, tau.imag
    xc = A.centre[:, None, None] * k1 + B.centre[None, :, None] * k2
    K = np.round(xc)
    f = xc - K
    c0 = np.linalg.solve(Y, z0.imag)
    c = c0 + f[..., g:]
    n0 = -np.round(c)
    return _Centres(K, c, (z0.real - X @ c0) + f[..., :g], n0)


def _coefficients(tau, cen: _Centres, nu, valid, al2, be2, ia, V):
    """``C`` (P, Q, nout, S): per characteristic the values' coefficients, then the derivatives' ones (``nu``,
    ``valid`` the terms of each alpha, ``ia`` the alpha of each characteristic)."""
    g = tau.shape[0]
    # -pi d.Y.d from d itself (summing the expanded form loses |nu.Y.nu| eps when Im tau is large)
    d = nu + (cen.n0 + cen.c)[:, :, None, None, :]                               # (P, Q, nal, S, g)
    X, Y = tau.real, tau.imag
    E = np.exp(np.pi * (1j * np.sum((d @ X) * d, -1) - np.sum((d @ Y) * d, -1))
               + 2j * np.pi * np.sum(d * cen.xi[:, :, None, None, :], -1)) * valid   # (P, Q, nal, S)
    # exp(2 pi i (n0 + nu).beta) exactly, and the block shift's signs (-1)^(2 (alpha.K_m + beta.K_n))
    K, n0 = np.rint(cen.K).astype(np.int64), np.rint(cen.n0).astype(np.int64)
    par = n0 @ be2.T + K[..., :g] @ al2.T + K[..., g:] @ be2.T                   # (P, Q, nch)
    quarter = np.einsum("csi,ci->cs", np.rint(2 * nu[ia]).astype(np.int64), be2)  # (nch, S)
    C = E[:, :, ia] * ((1 - 2 * np.mod(par, 2))[..., None] * np.array([1, 1j, -1, -1j])[np.mod(quarter, 4)])
    if V is None:
        return C
    w = 2j * np.pi * ((cen.n0 @ V)[..., None, None] + (nu @ V)[ia])             # (P, Q, nch, S)
    return np.concatenate([C, C * w], 2)


def _phases(offset: np.ndarray, nu: np.ndarray, al: np.ndarray, u: np.ndarray) -> np.ndarray:
    """``exp(2 pi i offset nu.u)`` as (nalpha, blocks, size, S): the product of ``exp(2 pi i offset alpha.u)`` and,
    per coordinate, ``exp(2 pi i offset m_i u_i)`` (``nu = m + alpha``) from tables over the range of ``m_i``
    (a third of the time of one exponential per entry); the blocks of a uniform grid share their offsets."""
    uniform = bool(np.all(offset == offset[:1]))
    off = offset[:1] if uniform else offset
    m = np.rint(nu - al[:, None, :]).astype(np.int64)
    lo = m.min(axis=(0, 1))
    out = np.exp((2j * np.pi) * off[None, :, :, None] * (al @ u)[:, None, None, None])   # (nal, P', s, 1)
    for i in range(len(u)):
        tab = np.exp((2j * np.pi) * u[i] * off[..., None] * np.arange(lo[i], m[..., i].max() + 1))  # (P', s, k)
        out = out * tab[:, :, m[..., i] - lo[i]].transpose(2, 0, 1, 3)
    return np.broadcast_to(out, (nu.shape[0],) + offset.shape + (nu.shape[1],)) if uniform else out


def _log_unit(tau, A: _Blocks, B: _Blocks, cen: _Centres, u, w) -> np.ndarray:
    """``e`` (P, sa, Q, sb): ``-pi i c.tau.c - 2 pi i c.xi + 2 pi i n0.delta`` (the factor common to all
    characteristics taken out of each block's sum)."""
    c = cen.c
    L = -1j * np.pi * (np.einsum("pqi,ij,pqj->pq", c, tau, c) + 2 * np.sum(c * cen.xi, -1))
    la, lb = 2j * np.pi * (cen.n0 @ u), 2j * np.pi * (cen.n0 @ w)               # (P, Q)
    return (L[:, None, :, None] + la[:, None, :, None] * A.offset[:, :, None, None]
            + lb[:, None, :, None] * B.offset[None, None, :, :])


def theta_grid(tau: ArrayLike, z0: ArrayLike, k1: ArrayLike, k2: ArrayLike, a: ArrayLike, b: ArrayLike,
               chars: str | Sequence = "all", direction: ArrayLike | None = None, tol: float = 1e-16,
               block: tuple[int, int] | None = None) -> ThetaGrid:
    """``theta[chi]`` and ``D_V theta[chi]`` at ``z0 + x_m + tau x_n``, ``x = a_i k1 + b_j k2``, on the grid ``(a, b)``.

    Parameters
    ----------
    tau : array_like, shape (g, g)
        Riemann matrix.
    z0 : array_like, shape (g,)
        Base point (complex); the cost assumes ``(Im tau)^-1 Im z0 = O(1)``.
    k1, k2 : array_like, shape (2g,)
        Real lattice coordinates of the two grid directions.
    a, b : array_like, shapes (n1,), (n2,)
        The grid's coordinates along ``k1`` and ``k2`` (any order: sorted internally; the blocks assume
        roughly uniform spacing).
    chars : "all" or sequence of (alpha, beta) or None
        Half characteristics (``"all"``: the ``4^g`` of :class:`thetasol.theta.riemann.RiemannTheta`'s order).
    direction : array_like, shape (g,), optional
        ``V`` of the derivative ``D_V theta = V . grad theta``.
    tol : float
        Truncation: the terms left out of every point's ellipsoid sum to about ``tol`` (relative to ``exp(e)``).
    block : (int, int), optional
        Points per block along ``a`` and ``b`` (default: ``BLOCK_SPREAD``).

    Returns
    -------
    ThetaGrid
    """
    tau = check_tau(tau)
    g = tau.shape[0]
    z0 = finite_array(z0, "z0", (g,), complex)
    k1, k2 = finite_array(k1, "k1", (2 * g,)), finite_array(k2, "k2", (2 * g,))
    a, b = finite_array(a, "a").ravel(), finite_array(b, "b").ravel()
    if not (len(a) and len(b)):
        raise ValueError(f"the grid is empty ({len(a)} x {len(b)} points)")
    V = None if direction is None else finite_array(direction, "direction", (g,), complex)
    oa, ob = np.argsort(a, kind="stable"), np.argsort(b, kind="stable")
    if np.any(np.diff(oa) != 1) or np.any(np.diff(ob) != 1):   # sorted axes keep the blocks' spread small
        G = theta_grid(tau, z0, k1, k2, a[oa], b[ob], chars, V, tol, block)
        ra, rb = np.argsort(oa)[:, None], np.argsort(ob)[None, :]
        return ThetaGrid(G.e[ra, rb], G.value[ra, rb], None if V is None else G.derivative[ra, rb],
                         G.shift[ra, rb], G.terms)
    al2, be2 = _chars(chars, g)
    nch = len(al2)
    if block is None:
        block = (_block_size(a, k1[g:], tau.imag, BLOCK_SPREAD), _block_size(b, k2[g:], tau.imag, 2 * BLOCK_SPREAD))
    A, B = _blocks(a, block[0]), _blocks(b, block[1])
    P, Q, sa, sb = len(A.centre), len(B.centre), A.size, B.size
    u, w = k1[:g] + tau @ k1[g:], k2[:g] + tau @ k2[g:]
    cen = _centres(tau, z0, k1, k2, A, B)
    nout = nch if V is None else 2 * nch
    out = np.empty((nout, P, sa, Q, sb), complex)
    M = lower_factor(tau.imag)
    r = _radius(M, k1[g:], k2[g:], A, B, tol)
    alphas, ia = np.unique(al2, axis=0, return_inverse=True)
    ia = ia.ravel()
    nu, valid = _terms(tau.imag, M, r, alphas / 2.0)
    C = _coefficients(tau, cen, nu, valid, al2, be2, ia, V)                    # (P, Q, nout, S)
    Am = _phases(A.offset, nu, alphas / 2.0, u)                                 # (nal, P, sa, S)
    Bm = _phases(B.offset, nu, alphas / 2.0, w).transpose(0, 1, 3, 2)           # (nal, Q, S, sb)
    groups = [np.nonzero(np.tile(ia, nout // nch) == i)[0] for i in range(len(alphas))]
    for q in range(Q):
        Cq = C[:, q].transpose(1, 0, 2)                                        # (nout, P, S)
        for i, rows in enumerate(groups):
            left = Am[i][None] * Cq[rows][:, :, None, :]                        # (nrow, P, sa, S)
            G = (left.reshape(-1, nu.shape[1]) @ Bm[i, q]).reshape(len(rows), P, sa, sb)
            for j, row in enumerate(rows):          # one slice each: a fancy-indexed assignment is much slower
                out[row, :, :, q, :] = G[j]
    out = out.reshape(nout, P * sa, Q * sb)[:, :A.n, :B.n]
    shift = np.broadcast_to(cen.K[:, None, :, None, :], (P, sa, Q, sb, 2 * g)).reshape(P * sa, Q * sb, 2 * g)
    e = _log_unit(tau, A, B, cen, u, w).reshape(P * sa, Q * sb)[:A.n, :B.n]
    val = np.moveaxis(out, 0, -1)
    return ThetaGrid(e, val[..., :nch], None if V is None else val[..., nch:], shift[:A.n, :B.n],
                     int(np.max(np.sum(valid, 1))))
