"""Small, vectorized helpers on so(3) and SO(3) shared by every module.

Conventions (docs/conventions.md): ``hat(v) @ w == np.cross(v, w)``; ``vee`` is
its inverse on skew matrices.  All functions broadcast over leading axes.
"""
from __future__ import annotations

import numpy as np

__all__ = ["hat", "vee", "rotation_about", "rodrigues", "polar_orthonormalize"]


def hat(v: np.ndarray) -> np.ndarray:
    """Skew matrix of a vector: ``hat(v) @ w = v x w``; shape ``(..., 3) -> (..., 3, 3)``."""
    v = np.asarray(v)
    z = np.zeros_like(v[..., 0])
    x, y, w = v[..., 0], v[..., 1], v[..., 2]
    return np.stack(
        [np.stack([z, -w, y], -1), np.stack([w, z, -x], -1), np.stack([-y, x, z], -1)], -2
    )


def vee(S: np.ndarray) -> np.ndarray:
    """Inverse of :func:`hat` (antisymmetrizing first); shape ``(..., 3, 3) -> (..., 3)``."""
    S = np.asarray(S)
    return 0.5 * np.stack(
        [S[..., 2, 1] - S[..., 1, 2], S[..., 0, 2] - S[..., 2, 0], S[..., 1, 0] - S[..., 0, 1]], -1
    )


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
