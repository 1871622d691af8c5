"""Data and first integrals of a heavy top (Section 5): a body turning about a fixed point in uniform gravity.

Conventions: ``I`` is the inertia about the fixed point in the body frame, ``center`` the mass
centre seen from the fixed point (body frame), ``gravity`` the gravity vector in space, ``Q`` maps
body to space and ``omega`` is the body angular velocity.  The potential is
``V = -mass gravity . (Q center)``, the body angular momentum ``M = I omega`` obeys

    Mdot = M x omega + center x (Q^T mass gravity) = M x omega + mass |g| gamma x center,

with ``gamma = -Q^T gravity / |gravity|`` the UPWARD vertical in the body frame (the paper's
``dM/dt = M x omega + m g gamma x R``).
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V

__all__ = ["heavy_top_data", "heavy_top_invariants", "kovalevskaya_integral"]


def heavy_top_data(I: ArrayLike, center: ArrayLike, Q0: ArrayLike, omega0: ArrayLike, mass: float = 1.0,
                   gravity: ArrayLike = (0.0, 0.0, -9.81)
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, np.ndarray]:
    """Checked heavy-top data ``(I, center, Q0, omega0, mass, gravity)`` as float arrays.

    ``I`` (3 principal values or a symmetric 3x3 tensor) must be positive definite and satisfy the
    triangle inequalities ``I_i <= I_j + I_k``; ``Q0`` must be a rotation; ``mass >= 0``; every
    entry finite.  Raises ``ValueError`` naming the argument otherwise.
    """
    Im = V.inertia(I, "I")  # positive definite, triangle inequalities (naming a second-moment mix-up), symmetry
    c = V.vector3(center, "center")
    Q0m = V.rotation_matrix(Q0, "Q0")
    w0 = V.vector3(omega0, "omega0")
    g = V.vector3(gravity, "gravity")
    mass = float(V.finite_array(mass, "mass", ()))
    if mass < 0:
        raise ValueError(f"mass must be >= 0, got {mass}")
    return Im, c, Q0m, w0, mass, g


def heavy_top_invariants(I: ArrayLike, center: ArrayLike, mass: float, gravity: ArrayLike, omega: ArrayLike,
                         Q: ArrayLike) -> dict:
    """First integrals along ``(omega, Q)`` (leading axes broadcast).

    Returns ``energy = 1/2 omega.I omega - mass gravity.(Q center)``, ``vertical_momentum = (Q I omega).up``
    (``up = -gravity/|gravity|``; the space angular momentum about the fixed point along the
    vertical) and ``axial_momentum = (I omega).center/|center|`` (a first integral of the Lagrange
    top only).
    """
    I = np.asarray(I, float)
    c = np.asarray(center, float)
    g = np.asarray(gravity, float)
    M = np.asarray(omega, float) @ I.T
    energy = 0.5 * np.sum(M * omega, axis=-1) - mass * ((Q @ c) @ g)
    gn = np.linalg.norm(g)
    up = -g / gn if gn > 0 else np.array([0.0, 0.0, 1.0])
    vert = (Q @ M[..., None])[..., 0] @ up
    cn = np.linalg.norm(c)
    axial = M @ (c / cn) if cn > 0 else np.zeros(M.shape[:-1])
    return {"energy": energy, "vertical_momentum": vert, "axial_momentum": axial}


def kovalevskaya_integral(I: ArrayLike, center: ArrayLike, mass: float, gravity: ArrayLike, omega: ArrayLike,
                          Q: ArrayLike) -> np.ndarray:
    """Kovalevskaya's integral ``k^2 = |(p + i q)^2 + c0 (g1 + i g2)|^2`` (leading axes broadcast).

    For ``I = diag(2, 2, 1) I3`` in a principal frame ``(e1, e2, e3)`` with the mass centre
    ``x0 e1``: ``p, q`` the components of ``omega`` along ``e1, e2``, ``c0 = mass |g| x0 / I3`` and
    ``g = Q^T gravity / |gravity|`` the DOWNWARD vertical in the body frame (Kowalevski's memoir,
    Acta Math. 12 (1889): ``2 pdot = q r``, ``2 qdot = -p r - c0 g3``, ``rdot = c0 g2``).  A first
    integral only for those bodies; ``e3`` is the eigenvector of the smallest moment.
    """
    I = np.asarray(I, float)
    c = np.asarray(center, float)
    g = np.asarray(gravity, float)
    ev, vec = np.linalg.eigh(I)
    e3 = vec[:, 0]
    x0 = np.linalg.norm(c)
    e1 = c / x0
    e2 = np.cross(e3, e1)
    c0 = mass * np.linalg.norm(g) * x0 / ev[0]
    gd = np.swapaxes(Q, -1, -2) @ (g / np.linalg.norm(g))
    z = (omega @ e1 + 1j * (omega @ e2)) ** 2 + c0 * (gd @ e1 + 1j * (gd @ e2))
    return np.abs(z) ** 2
