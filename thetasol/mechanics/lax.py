"""Algebra of the Lax matrix L(E) = J^2 E^2 + M E + u of (4.11) at t = 0.

Everything the Baker-Akhiezer reconstruction needs that does not involve periods:
eigenvectors at places and the pole divisor of the normalized eigenvector.  J is diagonal
(principal frame).

The pole divisor.  With psi(P) the eigenvector of L(E) at P = (E, w) normalized by
<alpha, psi> = 1, its poles are the points where alpha^T v(P) = 0 for the right eigenvector
v.  With B2 a basis of {v : alpha^T v = 0}, v = B2 y and the conditions
alpha^T L B2 y = 0 and B2^H (L - w) B2 y = 0 say that y is (bilinearly) orthogonal to
r(E) = B2^T L(E)^T alpha and an eigenvector of L22(E) = B2^H L(E) B2.  In two dimensions
y = rot90(r), so the E-coordinates are the roots of the degree-6 polynomial det[L22(E) y(E), y(E)];
w is the eigenvalue of L22 on y.  This avoids resultants of the
degree-24 system and gives each point once.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core.dd import cdd, cdd_add, cdd_mul, cdd_scale, cdd_sub, cdd_value, two_prod
from thetasol.core.so3 import cross

__all__ = ["lax_matrix", "right_eigenvector", "eigenvector_poles", "polish_eigenvector_poles"]


def lax_matrix(J: np.ndarray, M: np.ndarray, u: np.ndarray, E: ArrayLike) -> np.ndarray:
    """L(E) = J^2 E^2 + M E + u (4.11) for J the principal values; shape ``E.shape + (3, 3)``."""
    E = np.asarray(E)[..., None, None]
    return np.diag(J * J) * E**2 + M * E + u


def right_eigenvector(L: np.ndarray, w: ArrayLike) -> np.ndarray:
    """Unit null vector of ``L - w`` (batched): the right eigenvector at a smooth point.

    Taken from a row pair's cross product (the largest one), exact where ``w`` is a simple
    eigenvalue; shape ``L.shape[:-1]``.
    """
    X = L - np.asarray(w)[..., None, None] * np.eye(3)
    r0, r1, r2 = X[..., 0, :], X[..., 1, :], X[..., 2, :]
    cands = np.stack([cross(r1, r2), cross(r2, r0), cross(r0, r1)], -2)
    norms = np.linalg.norm(cands, axis=-1)
    best = np.argmax(norms, axis=-1)
    v = np.take_along_axis(cands, best[..., None, None], axis=-2)[..., 0, :]
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _polymatmul(A: list, B: list) -> list:
    out = [None] * (len(A) + len(B) - 1)
    for i, x in enumerate(A):
        for j, y in enumerate(B):
            out[i + j] = x @ y if out[i + j] is None else out[i + j] + x @ y
    return out


def eigenvector_poles(J: np.ndarray, M: np.ndarray, u: np.ndarray, alpha: np.ndarray,
                      left: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Points (E, w) where alpha^T v = 0, v the right (``left=True``: left) eigenvector.

    Returns ``(E, w)`` arrays of the finite points (6 for generic alpha, with multiplicity; fewer
    when alpha is orthogonal to an eigenvector of J^2, whose place at infinity then takes the rest).
    """
    alpha = np.asarray(alpha)
    alpha = alpha / np.linalg.norm(alpha)
    # basis of {v : alpha^T v = 0} (bilinear: alpha may be complex, e.g. (e1 - i e2)/sqrt(2))
    B2 = np.linalg.svd(alpha[None, :])[2][1:].conj().T
    if np.isrealobj(alpha):
        B2 = B2.real
    Lc = [u, M, np.diag(J * J)]
    if left:
        Lc = [X.T for X in Lc]
    # The row alpha^T of (L - w) B2 y = 0 drops w (alpha^T B2 = 0): y is bilinearly orthogonal to
    # r = B2^T L^T alpha.  The other two rows are taken with B2^H: [alpha, conj(B2)] is invertible
    # even for an isotropic alpha (alpha^T alpha = 0, e.g. (e1 - i e2)/sqrt(2)), and B2^H B2 = 1.
    L22 = [B2.conj().T @ X @ B2 for X in Lc]
    y = [np.array([-r[1], r[0]]) for r in (B2.T @ X.T @ alpha for X in Lc)]
    Ly = _polymatmul(L22, [v[:, None] for v in y])
    p = np.zeros(7, dtype=np.result_type(M, u, B2, float))
    for i, A in enumerate(Ly):
        for j, v in enumerate(y):
            p[i + j] += A[0, 0] * v[1] - A[1, 0] * v[0]
    # With alpha along an axis the degree drops (those zeros sit at the places over E = infinity):
    # leading coefficients that vanish to rounding are dropped, not turned into huge roots.
    scale = np.abs(p).max()
    deg = 6
    while deg > 0 and abs(p[deg]) <= 1e-13 * scale:
        deg -= 1
    E = np.roots(p[: deg + 1][::-1])
    yy = sum(c * E[:, None] ** k for k, c in enumerate(y))
    Lyy = sum(c[:, 0] * E[:, None] ** k for k, c in enumerate(Ly))
    num = np.einsum("ni,ni->n", yy.conj(), Lyy)
    den = np.einsum("ni,ni->n", yy.conj(), yy)
    # y = 0 where r(E) vanishes (alpha orthogonal to two eigenvectors there): E is a genuine zero,
    # but its w is not given by the reduction; it is left NaN (callers needing w avoid such alpha).
    w = np.full(E.shape, np.nan, dtype=complex)
    ok = np.abs(den) > 0
    w[ok] = num[ok] / den[ok]
    return E, w


def polish_eigenvector_poles(J: np.ndarray, M: np.ndarray, u: np.ndarray, alpha: np.ndarray,
                             E: np.ndarray, w: np.ndarray, iters: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """The points of :func:`eigenvector_poles` polished by Newton's method in double-double.

    ``np.roots`` leaves E a few ulps off; next to a tight pair of branch points (motion near a
    relative equilibrium) those ulps move the Abel image of the divisor by many more.  Here
    ``(L(E) - w) v = 0`` with ``v = b1 + s b2`` (or ``s b1 + b2``) in the plane ``alpha^T v = 0``
    (bilinear; ``b1, b2`` two of ``alpha x e_i``, whose entries are entries of alpha: exact) is solved
    for ``(E, w, s)`` from the float values, with ``J^2`` taken exactly as the spectral curve takes it
    (the square of the binary J), all points at once.  The residual is computed in double-double
    (errors ~1e-32 of its terms), the Jacobian in float64: each step multiplies the error by about
    eps times the Jacobian's condition, so ``iters = 3`` steps from np.roots' few ulps end at the
    double-double limit, and the points rounded to complex128 are the correctly rounded roots (checked
    against a 40-digit mpmath Newton; points at E = 0, where the node is, may differ in the low word).
    Returns ``(E, w)``.
    """
    Eo, wo = np.array(E, dtype=complex), np.array(w, dtype=complex)
    idx = np.nonzero(np.isfinite(Eo) & np.isfinite(wo))[0]
    if idx.size == 0:
        return Eo, wo
    al = np.asarray(alpha).astype(complex)
    # alpha x e_i is orthogonal to alpha (bilinearly, also for an isotropic alpha); take the
    # best-conditioned pair of the three as the basis of the plane
    cs = [np.cross(al, np.eye(3)[k]) for k in range(3)]
    i1, i2 = max(((0, 1), (0, 2), (1, 2)), key=lambda p: np.linalg.norm(np.cross(cs[p[0]], cs[p[1]])))
    b1, b2 = cs[i1], cs[i2]
    B = np.column_stack([b1, b2])
    Jf = np.asarray(J, float)
    free = np.empty(idx.size, bool)
    s0 = np.empty(idx.size, complex)
    V0 = right_eigenvector(lax_matrix(Jf, M, u, Eo[idx]), wo[idx])
    for q, v0 in enumerate(V0):
        y0 = np.linalg.lstsq(B, v0, rcond=None)[0]
        free[q] = abs(y0[0]) >= abs(y0[1])                 # normalize the larger coefficient to 1
        s0[q] = y0[1] / y0[0] if free[q] else y0[0] / y0[1]
    X = [cdd(Eo[idx]), cdd(wo[idx]), cdd(s0)]
    J2 = two_prod(Jf, Jf)                                  # J^2 exactly, as a double-double
    dv = np.where(free[:, None], b2[None, :], b1[None, :])
    one = cdd(np.ones(idx.size))
    eye = np.eye(3)
    b1_dd, b2_dd, u_dd = cdd(b1[None, :]), cdd(b2[None, :]), cdd(u[None].astype(complex))
    for _ in range(iters):
        e, ww, sv = X
        y1 = tuple(np.where(free, a, b) for a, b in zip(one, sv, strict=True))
        y2 = tuple(np.where(free, b, a) for a, b in zip(one, sv, strict=True))
        v = cdd_add(cdd_mul(_col(y1), b1_dd), cdd_mul(_col(y2), b2_dd))                        # (m, 3)
        diag = cdd_sub(cdd_scale(_col(cdd_mul(e, e)), J2[0][None, :], J2[1][None, :]), _col(ww))
        L = cdd_add(cdd_scale(tuple(c[:, None, None] for c in e), M[None]), u_dd)
        L = cdd_add(L, tuple(c[:, :, None] * eye for c in diag))                              # (m, 3, 3)
        P = cdd_mul(L, tuple(c[:, None, :] for c in v))
        F = cdd_value(cdd_add(cdd_add(tuple(c[..., 0] for c in P), tuple(c[..., 1] for c in P)),
                              tuple(c[..., 2] for c in P)))
        Lf, vf, ef = cdd_value(L), cdd_value(v), cdd_value(e)
        dE = vf @ M.T + 2 * (Jf * Jf)[None, :] * ef[:, None] * vf
        jac = np.stack([dE, -vf, np.einsum("mij,mj->mi", Lf, dv)], axis=-1)
        step = np.linalg.solve(jac, F[:, :, None])[:, :, 0]
        X = [cdd_sub(x, cdd(step[:, k])) for k, x in enumerate(X)]
    En, wn = cdd_value(X[0]), cdd_value(X[1])
    if np.any(np.abs(En - Eo[idx]) > 1e-6 * (1 + np.abs(Eo[idx]))):
        raise ValueError("polishing moved an eigenvector pole away from its float value")
    Eo[idx], wo[idx] = En, wn
    return Eo, wo


def _col(a):
    """A complex double-double vector (m,) as a column (m, 1)."""
    return tuple(c[:, None] for c in a)
