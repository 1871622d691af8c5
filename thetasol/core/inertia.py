"""The two descriptions of a rigid body's mass distribution and the conversions between them.

The paper works with the second moments ``J = sum m r r^T`` (Bogoyavlenskij 1992, (4.5)); engineering
codes and every public entry point of thetasol take the inertia tensor ``I = tr(J) 1 - J``, whose
inverse is ``J = tr(I)/2 1 - I``.  These are the only places the conversions are written, so that
every layer rounds them the same way.  No checks here: :mod:`thetasol.core.validate` checks bodies.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["inertia", "second_moments", "inertia_from_moments", "moments_from_inertia"]


def inertia_from_moments(J: np.ndarray) -> np.ndarray:
    """Inertia tensor ``I = tr(J) 1 - J`` (4.5) of second-moment tensors ``J`` (shape ``(..., 3, 3)``)."""
    return np.trace(J, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) - J


def moments_from_inertia(I: np.ndarray) -> np.ndarray:  # noqa: E741 - the inertia tensor's usual name
    """Second moments ``J = tr(I)/2 1 - I`` of inertia tensors ``I`` (shape ``(..., 3, 3)``)."""
    return 0.5 * np.trace(I, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) - I


def _principal_or_tensor(x: ArrayLike, name: str) -> np.ndarray:
    arr = np.asarray(x, dtype=float)
    if arr.shape not in ((3,), (3, 3)):
        raise ValueError(f"{name} must be 3 principal values or a 3x3 tensor, got shape {arr.shape}")
    return arr


def inertia(J: ArrayLike) -> np.ndarray:
    """The inertia tensor ``I = tr(J) 1 - J`` of second moments ``J = sum m r r^T`` (the paper's (4.5)).

    Principal values give principal values (shape (3,)), a 3x3 tensor a 3x3 tensor.  Every public
    entry point of thetasol takes ``I``; this converts the paper's second moments to it.
    """
    arr = _principal_or_tensor(J, "J")
    if arr.ndim == 1:
        return arr.sum() - arr
    return inertia_from_moments(arr)


def second_moments(I: ArrayLike) -> np.ndarray:  # noqa: E741 - the inertia tensor's usual name
    """The second moments ``J = tr(I)/2 1 - I`` (the paper's ``J``) of an inertia tensor ``I``.

    The inverse of :func:`inertia`, with the same shapes.
    """
    arr = _principal_or_tensor(I, "I")
    if arr.ndim == 1:
        return 0.5 * arr.sum() - arr
    return moments_from_inertia(arr)
