"""Constraints: the system mass centre on a sphere (Section 6 (6.1), Theorem 3), a body point fixed in space (Section 5).

:class:`Sphere` holds the mass centre ``q`` of a whole configuration on ``|q| = R`` about the
origin of the potential (physically: a massless rod of length ``R`` from a spherical joint at the
origin to the mass centre).  Its force ``mu q`` acts on the total mass; spread over the bodies in
proportion to their masses it is a uniform acceleration field, which exerts no torque about any
mass centre, so the rotations of the effective bodies are those of Theorem 2 and only the mass
centre changes: per unit mass it obeys C. Neumann's problem ``qddot = -a q + lambda q`` in
``phi = 1/2 q^T a q`` (6.2).  That needs ``b = 0``: a linear term would make the mass centre's
problem a different one (not Neumann's), so :meth:`Sphere.check` refuses it.

:class:`Pivot` holds one point of one body fixed in space (an ideal spherical joint to the ground):
the fixed point ``P0`` of Section 5.  It fixes the system mass centre's motion through the
attitude of the body that carries the pivot (:func:`pivot_mass_center`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V

__all__ = ["Sphere", "SPHERE_TOL", "Pivot", "pivot_mass_center", "point_on_sphere"]

#: Relative tolerance on ``|q0| = R`` and on ``q0 . v0 = 0`` (the initial state must satisfy the constraint).
SPHERE_TOL = 1e-12


@dataclass(frozen=True)
class Sphere:
    """The system mass centre on the sphere ``|q| = radius`` about the origin (6.1), Theorem 3.

    Parameters
    ----------
    radius : float
        Positive and finite (the length of the rod).

    Examples
    --------
    >>> Sphere(2.0).radius
    2.0
    """

    radius: float

    def __post_init__(self) -> None:
        r = self.radius
        if isinstance(r, bool) or not isinstance(r, (int, float, np.floating, np.integer)):
            raise ValueError(f"sphere radius must be a number, got {r!r}")
        r = float(r)
        if not np.isfinite(r) or r <= 0:
            raise ValueError(f"sphere radius must be positive and finite, got {r!r}")
        object.__setattr__(self, "radius", r)

    def check(self, b: ArrayLike, q0: ArrayLike, v0: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(b, q0, v0)`` validated for this constraint.

        Raises
        ------
        ValueError
            ``b != 0`` (Neumann's problem has the homogeneous potential (6.2) only), ``|q0|`` not
            ``radius`` to ``SPHERE_TOL`` relative, or ``v0`` not tangent (``|q0.v0| >
            SPHERE_TOL |q0| |v0|``).
        """
        b = V.vector3(b, "b")
        q0 = V.vector3(q0, "q0")
        v0 = V.vector3(v0, "v0")
        if np.any(b != 0):
            raise ValueError(f"b must be 0 with the sphere constraint (Theorem 3 needs the homogeneous "
                             f"potential 1/2 q^T a q (6.2)), got b = {b.tolist()}")
        R = self.radius
        rq = float(np.linalg.norm(q0))
        if abs(rq - R) > SPHERE_TOL * R:
            raise ValueError(f"q0 must be on the sphere |q| = {R:g}: |q0| = {rq!r}, relative offset "
                             f"{(rq - R) / R:.3g} (tolerance {SPHERE_TOL:g})")
        vn = float(np.linalg.norm(v0))
        if abs(q0 @ v0) > SPHERE_TOL * rq * vn:
            raise ValueError(f"v0 must be tangent to the sphere |q| = {R:g}: q0.v0 / (|q0| |v0|) = "
                             f"{(q0 @ v0) / (rq * vn):.3g} (tolerance {SPHERE_TOL:g})")
        return b, q0, v0

    def residual(self, q: ArrayLike) -> np.ndarray:
        """``|q| - radius`` over the last axis of ``q``."""
        return np.linalg.norm(np.asarray(q, dtype=float), axis=-1) - self.radius


@dataclass(frozen=True, eq=False)
class Pivot:
    """The point ``point`` of body ``body`` (its frame) held at ``position`` in space: Section 5's ``P0``.

    Parameters
    ----------
    body : str
        Name of the body carrying the pivot.
    point : array_like (3,)
        The pivot in that body's frame.
    position : array_like (3,), optional
        Where it is held in space (default the origin of the potential).

    Examples
    --------
    >>> Pivot("core", [0.0, 0.0, -1.0]).position.tolist()
    [0.0, 0.0, 0.0]
    """

    body: str
    point: np.ndarray
    position: np.ndarray = None  # type: ignore[assignment]

    def __post_init__(self) -> None:
        if not isinstance(self.body, str) or not self.body:
            raise ValueError(f"pivot body must be a non-empty body name, got {self.body!r}")
        pos = np.zeros(3) if self.position is None else self.position
        for attr, val in (("point", self.point), ("position", pos)):
            v = V.vector3(val, f"pivot {attr}").copy()
            v.flags.writeable = False
            object.__setattr__(self, attr, v)

    def __eq__(self, other: object) -> bool:
        return (isinstance(other, Pivot) and other.body == self.body and bool(np.all(other.point == self.point))
                and bool(np.all(other.position == self.position)))

    __hash__ = None  # type: ignore[assignment]


def pivot_mass_center(pivot: Pivot, center: ArrayLike, Q: ArrayLike, omega: ArrayLike
                      ) -> tuple[np.ndarray, np.ndarray]:
    """System mass centre and its velocity when the body carrying ``pivot`` is the main body.

    ``q = x_P + Q (c - r_P)``, ``qdot = Q (omega x (c - r_P))``: ``c`` the mass centre of the main
    body's effective body (2.15), (3.7) (the system mass centre of a central tree), ``r_P`` the
    pivot, both in the main body's frame; ``Q``, ``omega`` its attitude and body angular velocity
    (leading axes broadcast).
    """
    d = np.asarray(center, dtype=float) - pivot.point
    Q = np.asarray(Q, dtype=float)
    w = np.asarray(omega, dtype=float)
    return pivot.position + Q @ d, (Q @ np.cross(w, d)[..., None])[..., 0]


def point_on_sphere(a: ArrayLike, q0: ArrayLike, v0: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """``(a, q0, v0, radius)`` of Neumann's problem checked: ``a`` symmetric, ``q0`` and ``v0`` finite
    3-vectors, ``q0 != 0`` (it fixes the radius ``|q0|``); ``ValueError`` naming the problem otherwise.
    Tangency of ``v0`` is the caller's rule (the closed form refuses, the integrator projects)."""
    a = V.symmetric_matrix(a, "a")
    q0 = V.vector3(q0, "q0")
    v0 = V.vector3(v0, "v0")
    R = float(np.linalg.norm(q0))
    if R == 0.0:
        raise ValueError("q0 must be non-zero: it fixes the radius of the sphere")
    return a, q0, v0, R
