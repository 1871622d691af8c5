"""Riemann theta with half characteristics on a 2-D grid of a real torus, as complex matrix products.

The points are ``z_ij = z0 + x_m + tau x_n`` with ``x = a_i k1 + b_j k2`` (``k1, k2`` real lattice coordinates,
``2g`` each: ``m + tau n`` for ``(m, n)``).  The grid is cut into blocks; a block with centre ``x_c`` is first
shifted by the integer lattice vector ``K = round(x_c)`` (the characteristics' signs ``(-1)^(2(alpha.K_m +
beta.K_n))`` kept, the common quasi-periodicity factor dropped), and with ``zeta_c = xi + tau c`` its reduced
centre (``xi, c`` real), ``d = n + alpha + c = m + o`` (``n0 = n - m = -round(c + alpha)``, ``o`` in the unit
cube) and the offsets ``delta = da u + db w`` (``u, w`` the complex directions of ``k1, k2``)::

    theta[alpha; beta](zeta_c + delta) = exp(-pi i c.tau.c - 2 pi i c.xi) exp(2 pi i (n0 + alpha).delta)
        sum_m C_m A[da, m] B[m, db],   C_m = exp(pi i d.tau.d + 2 pi i d.xi + 2 pi i (n + alpha).beta),
        A[da, m] = exp(2 pi i da m.u),  B[m, db] = exp(2 pi i db m.w).

So a block's values are one matrix product per characteristic (and per derivative: ``C_m`` times
``2 pi i (n + alpha).V``), ``A`` shared by the blocks of a row and ``B`` by those of a column.  All factors
stay O(1): ``|C_m| = exp(-pi d.Y.d)``, ``|A| <= exp(2 pi |da| |m.Y.k1_n|)`` with ``da`` half a block.  The
terms are ``|m|_Y <= r + rho`` (``|v|_Y^2 = v.Y.v``, ``Y = Im tau``): ``pi r^2 = log(1/tol) + 2 log 10`` is the
ellipsoid criterion of :mod:`thetasol.theta.flow` (the terms left out of every point's own ellipsoid are below
``tol``), ``rho`` bounds ``|o + delta_n|_Y`` over the cube and the block (circumradii).  The result is
exponent-separated, ``theta = exp(e) v`` with ``e = pi Im(zeta).Y^-1.Im(zeta)`` at the shifted point ``zeta``.

Cost: genus 2, 7 characteristics with their derivative along ``V`` (the Kovalevskaya top,
benchmarks/bench_theta_grid.py), ~0.2 us per point on a 128 x 128 grid against ~16 us per point of
:meth:`thetasol.theta.riemann.RiemannTheta.jet` (``char="all"``, order 1); the values agree to ~1e-15
relative to each point's largest value (tests/test_theta_grid.py).
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from thetasol.theta._checks import check_tau
from thetasol.theta.flow import ellipsoid_candidates, lower_factor

__all__ = ["ThetaGrid", "theta_grid"]

#: Points per block and axis: larger blocks spread over more lattice terms, smaller ones cost more
#: per-block work (benchmarks/bench_theta_grid.py).
BLOCK = 16


@dataclass(frozen=True)
class ThetaGrid:
    """``theta[chi](zeta_ij) = exp(e_ij) sign * value_ij`` at ``zeta_ij = z_ij - shift_m - tau shift_n``.

    ``value`` and ``derivative`` are ``(n1, n2, nchar)`` with the sign ``(-1)^(2(alpha.shift_m +
    beta.shift_n))`` included, i.e. the values at ``z_ij`` up to a factor common to all characteristics;
    ``derivative`` is ``D_V theta`` at ``zeta_ij`` in the same unit (None without a direction); ``e``
    ``(n1, n2)``; ``shift`` ``(n1, n2, 2g)`` integers (the block's lattice vector); ``terms`` the lattice
    terms summed per block.
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
    al, be = [], []
    for ch in chars:
        ab = np.zeros((2, g)) if ch is None else 2 * np.asarray(ch, float).reshape(2, g)
        if np.any(np.abs(ab - np.rint(ab)) > 1e-12):
            raise ValueError(f"characteristics must be half-integer, got {ch!r}")
        ab = np.mod(np.rint(ab), 2).astype(np.int64)
        al.append(ab[0])
        be.append(ab[1])
    if not al:
        raise ValueError("no characteristic requested")
    return np.array(al), np.array(be)


def _terms(Y: np.ndarray, k1n: np.ndarray, k2n: np.ndarray, A: _Blocks, B: _Blocks, tol: float) -> np.ndarray:
    """The lattice terms ``m`` (S, g) with ``|m|_Y <= r + rho`` (see the module docstring)."""
    g = len(Y)
    M = lower_factor(Y)
    cube = (np.arange(1 << g)[:, None] >> np.arange(g)[None, :]) & 1
    rho = float(np.max(np.linalg.norm((cube - 0.5) @ M.T, axis=1)))
    ha, hb = np.max(np.abs(A.offset), 1), np.max(np.abs(B.offset), 1)
    spread = 0.0
    for s in (1.0, -1.0):
        v = ha[:, None, None] * k1n + s * hb[None, :, None] * k2n
        spread = max(spread, float(np.max(np.linalg.norm(v @ M.T, axis=-1))))
    r = math.sqrt((math.log(1.0 / tol) + 2.0 * math.log(10.0)) / math.pi) + rho + spread
    half = r * np.sqrt(np.diag(np.linalg.inv(Y)))
    box = [(math.floor(-h), math.ceil(h)) for h in half]
    m = ellipsoid_candidates(np.zeros(g), M, r * r, box)
    return m[np.sum((m @ M.T) ** 2, 1) <= r * r]


@dataclass(frozen=True)
class _Centres:
    """Per block ``(P, Q)``: the lattice shift ``K``, ``c``, ``xi``, ``n0`` and ``o`` per distinct alpha."""

    K: np.ndarray       # (P, Q, 2g)
    c: np.ndarray       # (P, Q, g)
    xi: np.ndarray      # (P, Q, g)
    n0: np.ndarray      # (P, Q, nalpha, g)
    o: np.ndarray       # (P, Q, nalpha, g)


def _centres(tau, z0, k1, k2, A: _Blocks, B: _Blocks, alphas: np.ndarray) -> _Centres:
    g = len(tau)
    X, Y = tau.real, tau.imag
    xc = A.centre[:, None, None] * k1 + B.centre[None, :, None] * k2
    K = np.round(xc)
    f = xc - K
    c0 = np.linalg.solve(Y, z0.imag)
    c = c0 + f[..., g:]
    xi = (z0.real - X @ c0) + f[..., :g]
    al = alphas / 2.0
    n0 = -np.round(c[:, :, None, :] + al)
    return _Centres(K, c, xi, n0, n0 + al + c[:, :, None, :])


def _coefficients(tau, cen: _Centres, m, al2, be2, ia, V):
    """``C`` (P, Q, nout, S): per characteristic the values' coefficients, then the derivatives' ones."""
    d = m[None, None, None, :, :] + cen.o[:, :, :, None, :]                    # (P, Q, nal, S, g)
    ex = np.pi * np.einsum("...i,ij,...j->...", d, tau, d) + 2 * np.pi * np.einsum("...i,...i->...", d,
                                                                                      cen.xi[:, :, None, None, :])
    E = np.exp(1j * ex)[:, :, ia]                                                # (P, Q, nch, S)
    n = cen.n0[:, :, ia, None, :] + m                                            # (P, Q, nch, S, g)
    Kp = np.rint(cen.K).astype(np.int64)
    g = tau.shape[0]
    par = np.einsum("pqcsi,ci->pqcs", n.astype(np.int64), be2) + (Kp[..., :g] @ al2.T + Kp[..., g:] @ be2.T)[..., None]
    unit = np.array([1, 1j, -1, -1j])[np.mod(np.sum(al2 * be2, 1), 4)][:, None]   # exp(2 pi i alpha.beta)
    C = E * (1 - 2 * np.mod(par, 2)) * unit
    if V is None:
        return C
    w = 2j * np.pi * ((n + al2[:, None, :] / 2.0) @ V)
    return np.concatenate([C, C * w], 2)


def _correction(tau, k1, k2, A: _Blocks, B: _Blocks, cen: _Centres, u, w):
    """``F`` (P, Q, nal, size_a, size_b): ``exp(-pi i c.tau.c - 2 pi i c.xi + 2 pi i (n0 + alpha).delta - (e(zeta)
    - pi c.Y.c))``, the factor from the block's sum to ``exp(-e) theta``; and ``e`` (P, Q, size_a, size_b)."""
    g = tau.shape[0]
    X, Y = tau.real, tau.imag
    k1n, k2n = k1[g:], k2[g:]
    c, xi = cen.c, cen.xi
    ph = np.exp(-1j * np.pi * (np.einsum("pqi,ij,pqj->pq", c, X, c) + 2 * np.sum(c * xi, -1)))
    na = cen.o - c[:, :, None, :]                                               # n0 + alpha
    ra = 2j * np.pi * (na @ u.real) - 2 * np.pi * (cen.o @ (Y @ k1n))           # (P, Q, nal)
    rb = 2j * np.pi * (na @ w.real) - 2 * np.pi * (cen.o @ (Y @ k2n))
    da, db = A.offset[:, None, None, :], B.offset[None, :, None, :]              # (P, 1, 1, sa), (1, Q, 1, sb)
    row = np.exp(ra[..., None] * da - np.pi * (k1n @ Y @ k1n) * da * da) * ph[..., None, None]
    col = np.exp(rb[..., None] * db - np.pi * (k2n @ Y @ k2n) * db * db)
    cross = np.exp(-2 * np.pi * (k1n @ Y @ k2n) * A.offset[:, None, :, None] * B.offset[None, :, None, :])
    F = row[..., :, None] * col[..., None, :] * cross[:, :, None]
    cy = c @ Y
    e = (np.pi * np.sum(cy * c, -1)[..., None, None]
         + 2 * np.pi * ((cy @ k1n)[..., None, None] * da[:, :, 0, :, None] + (cy @ k2n)[..., None, None]
                        * db[:, :, 0, None, :])
         + np.pi * ((k1n @ Y @ k1n) * da[:, :, 0, :, None] ** 2 + (k2n @ Y @ k2n) * db[:, :, 0, None, :] ** 2)
         + 2 * np.pi * (k1n @ Y @ k2n) * da[:, :, 0, :, None] * db[:, :, 0, None, :])
    return F, e


def theta_grid(tau: ArrayLike, z0: ArrayLike, k1: ArrayLike, k2: ArrayLike, a: ArrayLike, b: ArrayLike,
               chars: str | Sequence = "all", direction: ArrayLike | None = None, tol: float = 1e-16,
               block: int = BLOCK) -> ThetaGrid:
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
        The grid's coordinates along ``k1`` and ``k2`` (any order; sorted ones make small blocks).
    chars : "all" or sequence of (alpha, beta) or None
        Half characteristics (``"all"``: the ``4^g`` of :class:`thetasol.theta.riemann.RiemannTheta`'s order).
    direction : array_like, shape (g,), optional
        ``V`` of the derivative ``D_V theta = V . grad theta``.
    tol : float
        Truncation: the terms left out of every point's ellipsoid sum to about ``tol`` (relative to ``exp(e)``).
    block : int
        Points per block and axis.

    Returns
    -------
    ThetaGrid
    """
    tau = check_tau(tau)
    g = tau.shape[0]
    z0 = np.asarray(z0, complex).reshape(g)
    k1, k2 = np.asarray(k1, float).reshape(2 * g), np.asarray(k2, float).reshape(2 * g)
    a, b = np.asarray(a, float).ravel(), np.asarray(b, float).ravel()
    V = None if direction is None else np.asarray(direction, complex).reshape(g)
    al2, be2 = _chars(chars, g)
    alphas, ia = np.unique(al2, axis=0, return_inverse=True)
    ia = ia.ravel()
    A, B = _blocks(a, block), _blocks(b, block)
    u, w = k1[:g] + tau @ k1[g:], k2[:g] + tau @ k2[g:]
    m = _terms(tau.imag, k1[g:], k2[g:], A, B, tol)
    cen = _centres(tau, z0, k1, k2, A, B, alphas)
    C = _coefficients(tau, cen, m, al2, be2, ia, V)                              # (P, Q, nout, S)
    Am = np.exp((2j * np.pi) * A.offset[..., None] * (m @ u))                    # (P, sa, S)
    Bm = np.exp((2j * np.pi) * B.offset[:, None, :] * (m @ w)[None, :, None])   # (Q, S, sb)
    F, e = _correction(tau, k1, k2, A, B, cen, u, w)
    P, Q, nout = C.shape[0], C.shape[1], C.shape[2]
    sa, sb, nch = A.size, B.size, len(ia)
    out = np.empty((P, sa, Q, sb, nout), complex)
    for q in range(Q):
        left = Am[:, None, :, :] * C[:, q, :, None, :]                          # (P, nout, sa, S)
        G = (left.reshape(-1, len(m)) @ Bm[q]).reshape(P, nout, sa, sb)
        for k in range(nout):
            np.multiply(G[:, k], F[:, q, ia[k % nch]], out=out[:, :, q, :, k])
    out = out.reshape(P * sa, Q * sb, nout)[:A.n, :B.n]
    shift = np.broadcast_to(cen.K[:, None, :, None, :], (P, sa, Q, sb, 2 * g)).reshape(P * sa, Q * sb, 2 * g)
    return ThetaGrid(e.transpose(0, 2, 1, 3).reshape(P * sa, Q * sb)[:A.n, :B.n], out[..., :nch],
                     None if V is None else out[..., nch:], shift[:A.n, :B.n], len(m))
