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

__all__ = []


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
    rows = [X[..., i, :] for i in range(3)]
    cands = np.stack([np.cross(rows[1], rows[2]), np.cross(rows[2], rows[0]), np.cross(rows[0], rows[1])], -2)
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
                             E: np.ndarray, w: np.ndarray, dps: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """The points of :func:`eigenvector_poles` polished by Newton's method in mpmath.

    ``np.roots`` leaves E a few ulps off; next to a tight pair of branch points (motion near a
    relative equilibrium) those ulps move the Abel image of the divisor by up to 6e-11.  Here
    ``(L(E) - w) v = 0`` with ``v = b1 + s b2`` (or ``s b1 + b2``) in the plane ``alpha^T v = 0``
    (bilinear; ``b1, b2`` two of ``alpha x e_i``, exactly in mpmath) is solved for
    ``(E, w, s)`` from the float values, with ``J^2`` taken exactly as the spectral curve takes it
    (the square of the binary J).  Returns ``(E, w)`` rounded to complex128.
    """
    import mpmath

    alpha = np.asarray(alpha)
    Eo, wo = np.array(E, dtype=complex), np.array(w, dtype=complex)
    with mpmath.workdps(dps):
        mpc = mpmath.mpc
        al = [mpc(complex(x)) for x in alpha]

        def cross(a, b):
            return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]

        # alpha x e_i is orthogonal to alpha (bilinearly, also for an isotropic alpha); take the
        # best-conditioned pair of the three as the basis of the plane
        cs = [cross(al, [mpc(int(i == k)) for i in range(3)]) for k in range(3)]
        cf = [np.array([complex(x) for x in c_]) for c_ in cs]
        i1, i2 = max(((0, 1), (0, 2), (1, 2)), key=lambda p: np.linalg.norm(np.cross(cf[p[0]], cf[p[1]])))
        b1, b2 = cs[i1], cs[i2]
        J2 = [mpmath.mpf(float(x)) ** 2 for x in J]
        Mm = [[mpmath.mpf(float(M[i, j])) for j in range(3)] for i in range(3)]
        Um = [[mpmath.mpf(float(u[i, j])) for j in range(3)] for i in range(3)]
        B = np.array([[complex(b1[i]), complex(b2[i])] for i in range(3)])
        tol = mpmath.mpf(10) ** (-(dps - 8))
        for n in range(len(Eo)):
            if not (np.isfinite(Eo[n]) and np.isfinite(wo[n])):
                continue
            v0 = right_eigenvector(lax_matrix(np.asarray(J, float), M, u, Eo[n]), wo[n])
            y0 = np.linalg.lstsq(B, v0, rcond=None)[0]
            free = 1 if abs(y0[0]) >= abs(y0[1]) else 0        # normalize the larger coefficient to 1
            x = [mpc(complex(Eo[n])), mpc(complex(wo[n])), mpc(complex(y0[free] / y0[1 - free]))]
            dv = b2 if free == 1 else b1
            for _ in range(8):
                e, ww, s = x
                y = [mpc(1), s] if free == 1 else [s, mpc(1)]
                v = [y[0] * b1[i] + y[1] * b2[i] for i in range(3)]
                L = [[Mm[i][j] * e + Um[i][j] for j in range(3)] for i in range(3)]
                for i in range(3):
                    L[i][i] += J2[i] * e * e - ww
                F = [mpmath.fsum(L[i][j] * v[j] for j in range(3)) for i in range(3)]
                dE = [mpmath.fsum((Mm[i][j] + (2 * J2[i] * e if i == j else 0)) * v[j] for j in range(3))
                      for i in range(3)]
                ds = [mpmath.fsum(L[i][j] * dv[j] for j in range(3)) for i in range(3)]
                step = _solve3([[dE[i], -v[i], ds[i]] for i in range(3)], F)
                x = [x[k] - step[k] for k in range(3)]
                if max(abs(step[0]), abs(step[1])) <= tol * (1 + abs(x[0]) + abs(x[1])):
                    break
            if abs(complex(x[0]) - Eo[n]) > 1e-6 * (1 + abs(Eo[n])):
                raise ValueError("polishing moved an eigenvector pole away from its float value")
            Eo[n], wo[n] = complex(x[0]), complex(x[1])
    return Eo, wo


def _solve3(A: list, b: list) -> list:
    """A x = b for a 3 x 3 system of mpmath numbers: Gaussian elimination with partial pivoting
    (at the working precision; the Newton steps of :func:`polish_eigenvector_poles` need no more)."""
    A = [row[:] + [bi] for row, bi in zip(A, b, strict=True)]
    for c in range(3):
        piv = max(range(c, 3), key=lambda r: abs(complex(A[r][c])))
        A[c], A[piv] = A[piv], A[c]
        for r in range(c + 1, 3):
            f = A[r][c] / A[c][c]
            A[r] = [A[r][k] - f * A[c][k] for k in range(4)]
    x = [0, 0, 0]
    for r in (2, 1, 0):
        x[r] = (A[r][3] - sum(A[r][k] * x[k] for k in range(r + 1, 3))) / A[r][r]
    return x
