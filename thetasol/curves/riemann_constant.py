"""The vector of Riemann constants: the half-period scan that picks it among its 2^(2g) candidates.

2K = -A(div dx) fixes K up to a half period (:meth:`PlaneCurve.canonical_divisor`); the half period
is the one with theta(K + A(D')) = 0 for effective divisors D' of degree g - 1
(:func:`choose_riemann_constant`).

:func:`half_period_scan` evaluates |theta| at all 4^g half periods around one point with one lattice
sum per b (a tailored trick the general evaluator does not offer): Im(tau) is LLL-reduced by a
unimodular change of the summation lattice (which leaves theta unchanged), and the sum runs over the
ellipsoid pi (n + c)^T Y (n + c) <= R^2.  The zero tests on single points use the library's theta
(:mod:`thetasol.theta.riemann`) through :func:`theta_normalized_abs`.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from thetasol.theta.lattice import lll_gram
from thetasol.theta.riemann import riemann_theta_separated


def ellipsoid_points(Y: np.ndarray, center: np.ndarray, R2: float) -> np.ndarray:
    """Integer points n with (n + center)^T Y (n + center) <= R2 (Fincke-Pohst, breadth first).

    Y symmetric positive definite (g x g); returns an int array (K, g).
    """
    g = Y.shape[0]
    L = np.linalg.cholesky(Y)  # Y = L L^T; use the upper factor U = L^T
    U = L.T
    c = np.asarray(center, dtype=float)
    # work from the last coordinate: q = sum_i (U_ii (n_i + c_i) + sum_{j>i} U_ij (n_j + c_j))^2
    pts = np.zeros((1, 0), dtype=np.int64)
    rem = np.array([R2])
    acc = np.zeros((1, g))  # partial sums sum_{j>i} U_ij (n_j + c_j) for each row i
    for i in range(g - 1, -1, -1):
        uii = U[i, i]
        shift = acc[:, i] / uii + c[i]  # (n_i + shift) * uii squared is the new term
        half = np.sqrt(np.maximum(rem, 0.0)) / uii
        lo = np.ceil(-half - shift).astype(np.int64)
        hi = np.floor(half - shift).astype(np.int64)
        cnt = np.maximum(hi - lo + 1, 0)
        if cnt.sum() == 0:
            return np.zeros((0, g), dtype=np.int64)
        rep = np.repeat(np.arange(len(cnt)), cnt)
        offs = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        ni = lo[rep] + offs
        term = (uii * (ni + shift[rep])) ** 2
        rem = rem[rep] - term
        acc = acc[rep] + np.outer(ni + c[i], U[:, i])
        pts = np.concatenate([ni[:, None], pts[rep]], axis=1)
    return pts


def theta_normalized_abs(z: ArrayLike, tau: np.ndarray, tol: float = 1e-14) -> np.ndarray:
    """|theta(z)| exp(-pi y^T Y^-1 y) for z of shape (N, g): lattice periodic, bounded; for zero tests."""
    tau = np.asarray(tau, dtype=complex)
    return np.abs(riemann_theta_separated(np.atleast_2d(np.asarray(z, dtype=complex)), 0.5 * (tau + tau.T),
                                          tol=tol)[1])


def half_period_scan(z0: np.ndarray, tau: np.ndarray, tol: float = 1e-9) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """|theta| exp(-pi y^T Y^-1 y) at all 4^g points z0 + (a + tau b)/2, a, b in {0, 1}^g.

    One lattice sum per b (grouped by n mod 2, then a sign transform over a) instead of 4^g sums.
    Returns (values (4^g,), a (4^g, g), b (4^g, g)) with a, b integer arrays.
    """
    z0 = np.asarray(z0, dtype=complex).ravel()
    tau = np.asarray(tau, dtype=complex)
    tau = 0.5 * (tau + tau.T)
    g = len(z0)
    U = lll_gram(tau.imag, delta=0.75).T  # columns: the reduced basis
    Uinv = np.rint(np.linalg.inv(U)).astype(np.int64)
    taup = U.T @ tau @ U
    zp = U.T @ z0
    Y, X = taup.imag, taup.real
    Yinv = np.linalg.inv(Y)
    m = np.rint(Yinv @ zp.imag)
    zp = zp - taup @ m  # lattice shift: same candidate set modulo the lattice
    c = Yinv @ zp.imag
    x0 = zp.real
    R2 = np.log(1.0 / tol) + 2.0 + g
    bits = np.array([[(i >> k) & 1 for k in range(g)] for i in range(2 ** g)], dtype=np.int64)
    sign = 1 - 2 * (np.mod(bits @ bits.T, 2))  # (-1)^{class . a}, indexed [class, a]
    vals = np.zeros((2 ** g, 2 ** g))  # [b, a]
    for ib, b in enumerate(bits):
        n = ellipsoid_points(Y, 0.5 * b + c, R2 / np.pi)
        par = np.mod(n, 2) @ (1 << np.arange(g))  # class of n mod 2
        nf = n.astype(float)
        mm = nf + 0.5 * b  # m_n = n + b/2
        ww = mm + c
        qq = ((ww @ Y) * ww).sum(axis=1)
        phase = np.pi * ((mm @ X) * mm).sum(axis=1) + 2 * np.pi * (nf @ x0)
        T = np.exp(1j * phase - np.pi * qq)
        S = np.bincount(par, weights=T.real, minlength=2 ** g) + 1j * np.bincount(
            par, weights=T.imag, minlength=2 ** g)
        vals[ib] = np.abs(S @ sign)
    # back to the original (a, b): a = U^-T a' (mod 2), b = U b' (mod 2)
    A_out, B_out, V_out = [], [], []
    for ib, bp in enumerate(bits):
        for ia, ap in enumerate(bits):
            A_out.append(np.mod(Uinv.T @ ap, 2))
            B_out.append(np.mod(U @ bp, 2))
            V_out.append(vals[ib, ia])
    return np.array(V_out), np.array(A_out, dtype=np.int64), np.array(B_out, dtype=np.int64)


def choose_riemann_constant(tau: np.ndarray, AC: np.ndarray, ADs: list) -> np.ndarray:
    """The Riemann constant K (normalized coordinates) from ``2K = -AC`` and the zero test.

    Parameters
    ----------
    tau : ndarray, shape (g, g)
        Riemann matrix.
    AC : ndarray, shape (g,)
        Abel image of a canonical divisor (the divisor of dx).
    ADs : list of ndarray, shape (g,)
        Abel images of random effective divisors D' of degree g - 1 (empty for genus 1).

    Returns
    -------
    ndarray, shape (g,)
        The half-period translate of ``-AC / 2`` at which theta vanishes at ``(g - 1)`` times the
        base point and at every ``D'``.

    Raises
    ------
    RuntimeError
        No candidate makes theta vanish unambiguously (a nearly degenerate curve).
    """
    g = tau.shape[0]
    K0 = -0.5 * AC
    vals, a_bits, b_bits = half_period_scan(K0, tau, tol=1e-12)
    cands = K0[None, :] + 0.5 * a_bits + 0.5 * (b_bits @ tau.T)
    # D' = (g - 1) * base point: theta(K) = 0; keep the few smallest, then the random D'
    keep = np.argsort(vals)[:min(len(vals), 8)]
    cands = cands[keep]
    score = vals[keep]
    if ADs:
        z = cands[None, :, :] + np.array(ADs)[:, None, :]  # one theta set-up for all D'
        score = np.maximum(score, theta_normalized_abs(z.reshape(-1, g), tau, tol=1e-15)
                           .reshape(len(ADs), -1).max(axis=0))
    order = np.argsort(score)
    best, second = score[order[0]], score[order[1]] if len(order) > 1 else np.inf
    # theta at the right candidate vanishes to rounding level; on a nearly degenerate curve
    # (a nearly pinched cycle, Im tau_ii large) a wrong candidate can be small too, but not
    # at rounding level
    if not (best < 1e-8 and second > 10 * best):
        raise RuntimeError(f"Riemann constant: no half-period candidate makes theta vanish "
                           f"unambiguously (best {best:.2g}, next {second:.2g}); nearly "
                           f"degenerate curve?")
    return cands[order[0]]
