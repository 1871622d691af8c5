"""Input checks shared by every public entry point.

Every check raises ``ValueError`` with a message that names the argument and
says what is wrong; none of them silently repairs data beyond round-off.
"""
from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, DTypeLike

from thetasol.core.inertia import inertia_from_moments, moments_from_inertia
from thetasol.core.so3 import polar_orthonormalize

#: Relative tolerance on symmetry of a potential matrix or tensor.
SYM_RTOL = 1e-12
#: Absolute tolerance on ``Q^T Q - 1`` for an attitude matrix: round-off of a rotation composed in
#: float64 (~1e-15) passes and is snapped to SO(3); a matrix off by more is refused, not silently
#: changed by more than 1e-10.
ORTHO_TOL = 1e-10


def not_numbers(x: object) -> bool:
    """Whether ``x`` is text (a string or bytes, or an array of them) or an array of objects that are
    not numbers: numpy would turn ``"10"`` into ``10.0``, and a number typed as text is a mistake to
    name, not to repair."""
    if isinstance(x, str | bytes):
        return True
    if isinstance(x, int | float | complex):
        return False
    try:
        kind = np.asarray(x).dtype.kind
    except (TypeError, ValueError):            # ragged nests: the conversion's own error follows
        return False
    if kind == "O":
        return any(isinstance(v, str | bytes) for v in np.asarray(x, dtype=object).ravel())
    return kind in "USV"


def finite_array(x: ArrayLike, name: str, shape: Sequence[int] | None = None, dtype: DTypeLike = float) -> np.ndarray:
    """Convert to an array, checking that it holds numbers (not text), its shape and finiteness."""
    if not_numbers(x):
        raise ValueError(f"{name} must be numeric, got {x!r} (text is not read as a number)")
    try:
        arr = np.asarray(x, dtype=dtype)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric, got {x!r}") from exc
    if shape is not None and arr.shape != tuple(shape):
        raise ValueError(f"{name} must have shape {tuple(shape)}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or inf")
    return arr


def number(x: object, name: str) -> float:
    """A finite real number (a Python or numpy scalar, or a 0-d array), not text."""
    if not_numbers(x):
        raise ValueError(f"{name} must be numeric, got {x!r} (text is not read as a number)")
    try:
        v = float(np.asarray(x, dtype=float).reshape(()))
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {x!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {v}")
    return v


def symmetric_matrix(a: ArrayLike, name: str = "a", rtol: float = SYM_RTOL) -> np.ndarray:
    """A real symmetric 3x3 matrix; rejects asymmetry beyond ``rtol`` (relative to max |a_ij|)."""
    a = finite_array(a, name, (3, 3))
    scale = max(np.max(np.abs(a)), np.finfo(float).tiny)
    asym = np.max(np.abs(a - a.T)) / scale
    if asym > rtol:
        raise ValueError(f"{name} must be symmetric: max |{name} - {name}^T| / max|{name}| = {asym:.3g}")
    return 0.5 * (a + a.T)


def principal_or_tensor(x: ArrayLike, name: str) -> np.ndarray:
    """Three principal values or a symmetric 3x3 tensor (finite, numeric), as the 3x3 array."""
    arr = finite_array(x, name)
    if arr.shape == (3,):
        arr = np.diag(arr)
    elif arr.shape != (3, 3):
        raise ValueError(f"{name} must be 3 principal values or a 3x3 tensor, got shape {arr.shape}")
    return symmetric_matrix(arr, name)


def second_moments(J: ArrayLike, name: str = "J") -> np.ndarray:
    """Second-moment tensor ``J = sum m r r^T`` as a 3x3 array, checked to be physical.

    Accepts the three principal values or a symmetric 3x3 tensor.  A physical body has
    ``J`` positive semi-definite and inertia ``I = tr(J) 1 - J`` positive definite (the
    triangle inequalities ``I_i <= I_j + I_k``, a rod excluded); a flat plate (one
    ``J_i = 0``) is allowed.
    """
    arr = principal_or_tensor(J, name)
    ev = np.linalg.eigvalsh(arr)
    scale = max(ev[-1], np.finfo(float).tiny)
    if ev[-1] <= 0:
        raise ValueError(f"{name} must be positive semi-definite with a positive trace, eigenvalues {ev}")
    if ev[0] < -1e-12 * scale:
        raise ValueError(
            f"{name} is not physical: second moments must be >= 0 (eigenvalues {ev}); "
            "equivalently the inertia violates a triangle inequality I_i <= I_j + I_k"
        )
    if ev[1] <= 1e-12 * scale:
        raise ValueError(f"{name} describes a rod or a point (two zero second moments {ev}): the inertia is singular")
    return arr


#: Relative rounding margin of the triangle inequalities ``I_i <= I_j + I_k`` (of the largest principal
#: inertia): a flat plate (``I_3 = I_1 + I_2``) whose values were rounded to float64 passes.
TRIANGLE_RTOL = 1e-12


def inertia(I: ArrayLike, name: str = "I") -> np.ndarray:
    """An inertia tensor (3 principal values or a symmetric 3x3, body frame) as a 3x3 array, checked.

    It must be positive definite and satisfy the triangle inequalities ``I_i <= I_j + I_k`` up to
    :data:`TRIANGLE_RTOL` (a rod excluded).  Values that fail them but are valid second moments
    ``J = sum m r r^T`` (the paper's convention) are refused with a message naming that mix-up and
    its conversion, ``thetasol.inertia(J)``.
    """
    arr = principal_or_tensor(I, name)
    ev = np.linalg.eigvalsh(arr)
    if ev[0] <= TRIANGLE_RTOL * ev[2]:
        raise ValueError(f"inertia {name} must be positive definite (a rod or a point has a zero principal "
                         f"inertia), eigenvalues {ev}")
    if ev[2] > ev[0] + ev[1] + TRIANGLE_RTOL * ev[2]:
        hint = ""
        try:
            second_moments(arr, name)
            hint = ("; these look like second moments J = sum m r r^T (the paper's J), not an inertia: "
                    f"pass thetasol.inertia(J) = {_plain(inertia_from_moments(arr))}")
        except ValueError:
            pass
        raise ValueError(f"inertia {name} violates the triangle inequality I_i <= I_j + I_k (eigenvalues {ev}): "
                         f"no rigid body has it{hint}")
    return arr


def _plain(m: np.ndarray) -> str:
    """A 3x3 array for a message: its principal values when diagonal, else its rows (6 digits)."""
    rows = [np.diag(m)] if not np.any(m - np.diag(np.diag(m))) else m
    text = ["[" + ", ".join(f"{x:.6g}" for x in row) + "]" for row in rows]
    return text[0] if len(text) == 1 else "[" + ", ".join(text) + "]"


def inertia_to_moments(I: ArrayLike, name: str = "I") -> np.ndarray:
    """Second moments ``J = tr(I)/2 1 - I`` from an inertia tensor (principal values or 3x3)."""
    arr = principal_or_tensor(I, name)
    ev = np.linalg.eigvalsh(arr)
    if ev[0] <= 0:
        raise ValueError(f"inertia {name} must be positive definite, eigenvalues {ev}")
    J = moments_from_inertia(arr)
    return second_moments(J, f"second moments from {name}")


def rotation_matrix(Q: ArrayLike, name: str = "Q0", tol: float = ORTHO_TOL) -> np.ndarray:
    """A proper rotation; rejects ``|Q^T Q - 1| > tol`` or ``det Q < 0``, snaps round-off to SO(3)."""
    Q = finite_array(Q, name, (3, 3))
    err = np.max(np.abs(Q.T @ Q - np.eye(3)))
    if err > tol:
        raise ValueError(f"{name} is not orthogonal: max |{name}^T {name} - 1| = {err:.3g} > {tol:g}")
    if np.linalg.det(Q) < 0:
        raise ValueError(f"{name} is a reflection (det = -1), not a rotation")
    return polar_orthonormalize(Q)


def vector3(v: ArrayLike, name: str) -> np.ndarray:
    """A finite 3-vector."""
    return finite_array(v, name, (3,))


def times(t: ArrayLike, name: str = "t") -> np.ndarray:
    """Finite real times of any shape.

    A float64 array goes through as it is, checked by two ufunc calls, and a Python float is checked
    as a float: less fixed cost on a single time than :func:`finite_array` (its conversion and
    ``np.all`` wrapper).
    """
    if type(t) is np.ndarray and t.dtype == np.float64 and np.logical_and.reduce(np.isfinite(t), axis=None):
        return t
    if type(t) is float and math.isfinite(t):
        return np.array(t)
    return finite_array(t, name)
