"""Attitude helpers shared by the elliptic closed forms (Euler top, gyrostat).

Float64 kernels on rotations built from a precession angle and a unit momentum direction,
and angles reduced modulo 2 pi with an exact product so that far times keep their digits.
"""
from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core.dd import two_prod
from thetasol.core.so3 import hat, rotation_about

__all__ = ["TWO_PI_HI", "TWO_PI_LO", "norm3", "unit_rows", "minimal_rotation", "angle_mod_2pi",
           "rotation_about_axis", "uniform_rotation", "attitude_from_precession", "principal_frame"]


TWO_PI_HI = 6.283185307179586


TWO_PI_LO = 2.4492935982947064e-16


def norm3(v: ArrayLike) -> float:
    """Euclidean norm of one 3-vector without underflow or overflow of the squares."""
    return math.hypot(*(float(x) for x in v))


def unit_rows(v: np.ndarray) -> np.ndarray:
    """Rows of ``v`` (..., 3) normalized, scaled first so that tiny or huge vectors stay exact."""
    s = np.max(np.abs(v), axis=-1, keepdims=True)
    w = v / np.where(s > 0, s, 1.0)
    return w / np.linalg.norm(w, axis=-1, keepdims=True)


def minimal_rotation(nv: np.ndarray) -> np.ndarray:
    """B with B n = e_3 (rotation about n x e_3), for unit n with n_3 > -1; shape (..., 3, 3)."""
    n1, n2, n3 = nv[..., 0], nv[..., 1], nv[..., 2]
    q = 1.0 / (1.0 + n3)
    B = np.empty(nv.shape[:-1] + (3, 3))
    B[..., 0, 0] = 1.0 - n1 * n1 * q
    B[..., 0, 1] = -n1 * n2 * q
    B[..., 0, 2] = -n1
    B[..., 1, 0] = -n1 * n2 * q
    B[..., 1, 1] = 1.0 - n2 * n2 * q
    B[..., 1, 2] = -n2
    B[..., 2, 0] = n1
    B[..., 2, 1] = n2
    B[..., 2, 2] = n3
    return B


def angle_mod_2pi(rate: np.ndarray | float, t: np.ndarray | float, extra: np.ndarray | float) -> np.ndarray:
    """``rate * t + extra`` reduced modulo 2 pi with an exact product (float arrays)."""
    p, e = two_prod(rate, t)
    n = np.rint(p / TWO_PI_HI)
    q1, q1e = two_prod(n, TWO_PI_HI)
    r = ((p - q1) - q1e) + (e - n * TWO_PI_LO)
    return r + extra


def rotation_about_axis(axis: np.ndarray, ang: np.ndarray) -> np.ndarray:
    """Rotations about a fixed unit ``axis`` by the angles ``ang`` (n,) (Rodrigues), (n, 3, 3)."""
    K = hat(axis)
    return (np.eye(3) + np.sin(ang)[:, None, None] * K
            + (1.0 - np.cos(ang))[:, None, None] * (K @ K))


def uniform_rotation(Q0: np.ndarray, w0: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(omega, Q) of a constant body angular velocity ``w0`` (steady rotation or rest)."""
    n = t.size
    wn = norm3(w0)
    if wn == 0:
        return np.zeros((n, 3)), np.broadcast_to(Q0, (n, 3, 3)).copy()
    ang = angle_mod_2pi(wn, t, 0.0)
    return np.broadcast_to(w0, (n, 3)).copy(), Q0 @ rotation_about_axis(w0 / wn, ang)


def attitude_from_precession(S: np.ndarray, psi: np.ndarray, v: np.ndarray, P: np.ndarray) -> np.ndarray:
    """``S R_3(psi) B(v) P^T``: the attitude from the precession angle and the momentum ``v``
    (in the frame whose third axis is the pole), ``B`` the minimal rotation to ``e_3``."""
    return S @ rotation_about(2, psi) @ minimal_rotation(unit_rows(v)) @ P.T


def principal_frame(Jm: np.ndarray, *, ascending: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Principal values ``Jp`` and a right-handed principal frame ``R`` with ``Jm = R diag(Jp) R^T``.

    ``ascending=False``: a diagonal ``Jm`` keeps its own axes (``R = 1``, ``Jp`` in the body's order), so
    that principal data pass through unchanged; ``ascending=True``: always the eigen-decomposition, ``Jp``
    ascending (for models that number the axes by size).  Any other ``Jm`` (any symmetric matrix: second
    moments, a potential) is eigen-decomposed either way, with the third axis flipped if needed to make
    ``det R = 1``.
    """
    off = Jm - np.diag(np.diag(Jm))
    if not ascending and not np.any(off):
        return np.diag(Jm).copy(), np.eye(3)
    Jp, R = np.linalg.eigh(Jm)
    if np.linalg.det(R) < 0:
        R[:, 2] *= -1.0
    return Jp, R
