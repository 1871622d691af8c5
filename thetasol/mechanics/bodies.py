"""Rigid bodies: mass, mass centre and second moments in the body's own frame.

A :class:`Body` stores what the Lagrangian of Sections 2 and 3 needs from a rigid body:
its mass ``m``, the position ``c`` of its mass centre in its own (body) frame and its
second-moment tensor ``J = int rho (r - c)(r - c)^T`` about that mass centre ((2.9); the
inertia tensor is ``I = tr(J) 1 - J``).  The body frame is arbitrary: it need not be
centred at the mass centre nor principal, because joint points are given in it.

Bodies made of point masses (:meth:`Body.from_point_masses`) are exact, cheap test
objects: every formula in thetasol can be checked against them by brute force.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.inertia import inertia_from_moments

__all__ = ["Body", "principal_axes"]


def principal_axes(J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Principal second moments and a right-handed principal frame of a symmetric 3x3 tensor.

    Parameters
    ----------
    J : ndarray, shape (3, 3)
        Symmetric tensor (second moments or inertia).

    Returns
    -------
    values : ndarray, shape (3,)
        Eigenvalues in ascending order.
    axes : ndarray, shape (3, 3)
        Orthonormal eigenvectors as COLUMNS with ``det(axes) = +1``, so that
        ``J = axes @ diag(values) @ axes.T``.  Each column's sign is fixed so that its
        largest component is positive (then the last column is flipped if needed to be
        right-handed): the result does not depend on LAPACK's sign choices.
    """
    J = np.asarray(J, dtype=float)
    values, axes = np.linalg.eigh(0.5 * (J + J.T))
    for k in range(3):
        col = axes[:, k]
        if col[np.argmax(np.abs(col))] < 0:
            axes[:, k] = -col
    if np.linalg.det(axes) < 0:
        axes[:, 2] = -axes[:, 2]
    return values, axes


@dataclass(frozen=True, eq=False)
class Body:
    """A rigid body in its own frame.

    Parameters
    ----------
    mass : float
        Positive mass.
    J : array_like, shape (3,) or (3, 3), optional
        Second moments ``int rho (r - c)(r - c)^T`` about the mass centre, in the body frame
        (principal values if a 3-vector).  Give exactly one of ``J`` and ``I``.
    I : array_like, shape (3,) or (3, 3), optional
        Inertia tensor about the mass centre, ``I = tr(J) 1 - J``.
    center : array_like, shape (3,)
        Mass centre in the body frame (default the origin).
    name : str
        Label used by configurations and scene files.

    Raises
    ------
    ValueError
        Non-positive or non-finite mass, NaN/inf, a non-symmetric tensor, a non-physical
        inertia (negative second moment, i.e. a violated triangle inequality
        ``I_i <= I_j + I_k``) or a rod/point (singular inertia).

    Notes
    -----
    Attributes ``mass``, ``center`` and ``J`` (always a 3x3 array) are read-only; ``I`` is
    derived.  Arrays are copies flagged read-only, so a body cannot change under a
    configuration that uses it.
    """

    mass: float
    J: np.ndarray | None = None
    I: np.ndarray | None = field(default=None, repr=False)
    center: np.ndarray = field(default_factory=lambda: np.zeros(3))
    name: str = ""

    def __post_init__(self):
        label = f"body {self.name!r}" if self.name else "body"
        m = V.finite_array(self.mass, f"mass of {label}")
        if m.shape != () or not m > 0:
            raise ValueError(f"mass of {label} must be a positive number, got {self.mass!r}")
        if (self.J is None) == (self.I is None):
            raise ValueError(f"{label}: give exactly one of J (second moments) and I (inertia)")
        if self.J is not None:
            J = V.second_moments(self.J, f"J of {label}")
        else:
            J = V.inertia_to_moments(self.I, f"I of {label}")
        c = V.vector3(self.center, f"center of {label}")
        J = J.copy()
        J.flags.writeable = False
        c = c.copy()
        c.flags.writeable = False
        object.__setattr__(self, "mass", float(m))
        object.__setattr__(self, "J", J)
        object.__setattr__(self, "center", c)
        Imat = inertia_from_moments(J)
        Imat.flags.writeable = False
        object.__setattr__(self, "I", Imat)
        object.__setattr__(self, "name", str(self.name))

    @classmethod
    def from_point_masses(cls, masses: ArrayLike, points: ArrayLike, name: str = "") -> Body:
        """A body made of point masses ``masses[k]`` at body-frame points ``points[k]``.

        Parameters
        ----------
        masses : array_like, shape (n,)
            Positive masses.
        points : array_like, shape (n, 3)
            Their positions in the body frame.
        name : str
            Label.

        Returns
        -------
        Body
            With ``mass = sum m_k``, ``center = sum m_k r_k / m`` and
            ``J = sum m_k (r_k - c)(r_k - c)^T``.  The points must not be collinear.
        """
        mk = V.finite_array(masses, "masses")
        if mk.ndim != 1 or mk.size == 0 or np.any(mk <= 0):
            raise ValueError(f"masses must be a non-empty 1-d array of positive numbers, got {masses!r}")
        pts = V.finite_array(points, "points", (mk.size, 3))
        m = mk.sum()
        c = mk @ pts / m
        d = pts - c
        J = np.einsum("k,ki,kj->ij", mk, d, d)
        return cls(mass=m, J=J, center=c, name=name)

    @classmethod
    def box(cls, mass: float, size: ArrayLike, center: ArrayLike = (0.0, 0.0, 0.0), name: str = "") -> Body:
        """A homogeneous box with edge lengths ``size`` along the body axes, centred at ``center``.

        Its second moments are ``J_i = m size_i^2 / 12``.
        """
        s = V.finite_array(size, "size", (3,))
        if np.any(s < 0):
            raise ValueError(f"box size must be non-negative, got {size!r}")
        return cls(mass=mass, J=float(mass) * s**2 / 12.0, center=center, name=name)

    def principal(self) -> tuple[np.ndarray, np.ndarray]:
        """Principal second moments (ascending) and right-handed principal axes (columns)."""
        return principal_axes(self.J)

    def second_moments_about(self, point: ArrayLike) -> np.ndarray:
        """Second moments ``int rho (r - p)(r - p)^T`` about a body-frame point ``p`` (parallel axes)."""
        d = V.vector3(point, "point") - self.center
        return self.J + self.mass * np.outer(d, d)

    def renamed(self, name: str) -> Body:
        """A copy with another name."""
        return Body(mass=self.mass, J=self.J, center=self.center, name=name)

    def __repr__(self) -> str:
        Jp = np.linalg.eigvalsh(self.J)
        return (f"Body(name={self.name!r}, mass={self.mass:.6g}, center={np.round(self.center, 6).tolist()}, "
                f"J principal={np.round(Jp, 6).tolist()})")
