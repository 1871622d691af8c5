"""Small, vectorized helpers on so(3) and SO(3) shared by every module.

Conventions (docs/conventions.md): ``hat(v) @ w == np.cross(v, w)``; ``vee`` is
its inverse on skew matrices.  All functions broadcast over leading axes.
"""
from __future__ import annotations

import numpy as np

__all__ = ["hat", "vee", "cross", "rotation_about", "rodrigues", "polar_orthonormalize", "polar_near_orthogonal",
           "NEWTON_SCHULZ_MAX", "complete_frame"]


def hat(v: np.ndarray) -> np.ndarray:
    """Skew matrix of a vector: ``hat(v) @ w = v x w``; shape ``(..., 3) -> (..., 3, 3)``."""
    v = np.asarray(v)
    x, y, w = v[..., 0], v[..., 1], v[..., 2]
    # filled in place: nested np.stack costs several times more on the single vectors of right-hand sides
    S = np.zeros(v.shape[:-1] + (3, 3), dtype=v.dtype)
    S[..., 0, 1], S[..., 0, 2] = -w, y
    S[..., 1, 0], S[..., 1, 2] = w, -x
    S[..., 2, 0], S[..., 2, 1] = -y, x
    return S


def vee(S: np.ndarray) -> np.ndarray:
    """Inverse of :func:`hat` (antisymmetrizing first); shape ``(..., 3, 3) -> (..., 3)``."""
    S = np.asarray(S)
    return 0.5 * np.stack(
        [S[..., 2, 1] - S[..., 1, 2], S[..., 0, 2] - S[..., 2, 0], S[..., 1, 0] - S[..., 0, 1]], -1
    )


def cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``np.cross`` of ``(..., 3)`` arrays with the same floating-point operations, minus its axis
    handling (which dominates the cost for the few vectors of a right-hand side)."""
    u0, u1, u2 = u[..., 0], u[..., 1], u[..., 2]
    v0, v1, v2 = v[..., 0], v[..., 1], v[..., 2]
    return np.stack([u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0], -1)


def rodrigues(phi: np.ndarray) -> np.ndarray:
    """Rotation matrix ``exp(hat(phi))`` for rotation vectors ``phi`` of shape ``(..., 3)``."""
    phi = np.asarray(phi, dtype=float)
    th = np.linalg.norm(phi, axis=-1)[..., None, None]
    K = hat(phi)
    small = th < 1e-4
    th2 = th * th
    # Taylor series where th is small keeps full relative accuracy.
    with np.errstate(invalid="ignore", divide="ignore"):
        a = np.where(small, 1 - th2 / 6 * (1 - th2 / 20), np.sin(th) / np.where(small, 1, th))
        b = np.where(small, 0.5 * (1 - th2 / 12 * (1 - th2 / 30)),
                     (1 - np.cos(th)) / np.where(small, 1, th2))
    return np.eye(3) + a * K + b * (K @ K)


def rotation_about(axis: int, angle: np.ndarray) -> np.ndarray:
    """Rotation by ``angle`` about coordinate axis ``axis`` (0, 1 or 2); shape ``angle.shape + (3, 3)``."""
    angle = np.asarray(angle, dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    R = np.zeros(angle.shape + (3, 3))
    i, j = (axis + 1) % 3, (axis + 2) % 3
    R[..., axis, axis] = 1.0
    R[..., i, i] = c
    R[..., j, j] = c
    R[..., j, i] = s
    R[..., i, j] = -s
    return R


def polar_orthonormalize(Q: np.ndarray) -> np.ndarray:
    """Nearest rotation matrix (polar factor) of nearly orthogonal matrices ``(..., 3, 3)``."""
    U, _, Vt = np.linalg.svd(Q)
    return U @ Vt


#: max |X^T X - I| up to which one Newton-Schulz step gives the polar factor to rounding (module docstring
#: of :func:`polar_near_orthogonal`); beyond it the rows take the SVD.
NEWTON_SCHULZ_MAX = 1e-8


def polar_near_orthogonal(X: np.ndarray) -> np.ndarray:
    """Polar factor of nearly orthogonal 3x3 matrices stored as component rows ``X[r, c, n]``.

    One Newton-Schulz step ``X (3 - X^T X) / 2``: with ``X = R (1 + S)``, ``S`` symmetric, it returns
    ``R (1 - 3 S^2 / 2 + ...)``, so for ``|X^T X - 1| <= 1e-8`` (``|S| <= 5e-9``) the result is the
    polar factor to rounding; columns beyond that take the SVD.  Elementwise over ``n`` (the same
    operations for every column, whatever ``n``), much cheaper than a batched SVD.
    """
    D = np.add.reduce(X[:, :, None] * X[:, None, :], axis=0)        # X^T X, (3, 3, n)
    D -= _EYE
    # 1 - D / 2 = 3/2 - X^T X / 2 exactly: X^T X - 1 is exact on the diagonal (Sterbenz) wherever the
    # step applies, so both round the same real number once
    H = _EYE - 0.5 * D
    out = np.add.reduce(X[:, :, None] * H[None], axis=1)
    np.abs(D, out=D)
    if np.maximum.reduce(D, axis=None, initial=0.0) > NEWTON_SCHULZ_MAX:
        bad = np.maximum.reduce(D, axis=(0, 1)) > NEWTON_SCHULZ_MAX
        out[:, :, bad] = polar_orthonormalize(X[:, :, bad].transpose(2, 0, 1)).transpose(1, 2, 0)
    return out


_EYE = np.eye(3)[:, :, None]


def complete_frame(e3: np.ndarray) -> np.ndarray:
    """Right-handed orthonormal frame (columns) whose third column is the unit vector ``e3``.

    The first column is the coordinate axis least aligned with ``e3``, made orthogonal to it.
    """
    k = int(np.argmin(np.abs(e3)))
    t = np.zeros(3)
    t[k] = 1.0
    e1 = t - (t @ e3) * e3
    e1 /= np.linalg.norm(e1)
    return np.column_stack([e1, np.cross(e3, e1), e3])
