"""The numerical reference: a rigid body turning about a fixed point in a quadratic potential (5.3).

With the fixed point ``P0`` at the origin of space and of the body frame, the Lagrangian (5.3) is

    L = 1/2 omega.I omega - 1/2 tr(Q^T a Q J) - 1/2 b.(Q R),

``J`` the second moments and ``I = tr(J) 1 - J`` the inertia about ``P0``, ``R`` the first moment
(5.1) (the mass times the mass centre seen from ``P0``), ``phi(y) = 1/2 y^T a y + 1/2 b.y`` the
potential with ``y`` measured from ``P0``.  The body angular momentum ``m = I omega`` obeys

    mdot = m x omega + vee([J, Q^T a Q]) + R x (Q^T (-b/2)),      Qdot = Q hat(omega):

the torque of the quadratic part as in (4.8) (:func:`thetasol.mechanics.equations.torque`) and the
torque of the uniform force ``-b/2`` per unit mass.  ``b = 0`` or ``R = 0`` is the problem of
:func:`~thetasol.integrators.rotation.integrate_rotation` with ``J`` about ``P0`` (Corollary 2);
``a = 0`` is the heavy top of :func:`~thetasol.integrators.heavy_top.integrate_heavy_top` with
``center = R / mass`` and ``gravity = -b / 2`` (Corollary 3).  The general case has no known closed form: this module is its reference.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.so3 import cross, hat, polar_orthonormalize
from thetasol.core.threads import single_blas_thread
from thetasol.integrators._common import both_ways, solve_ivp_mQ
from thetasol.mechanics.equations import inertia_from_moments, torque
from thetasol.protocol import RotationSolution

__all__ = ["integrate_fixed_point", "fixed_point_energy", "NumericalFixedPoint", "numerical_fixed_point"]


def _data(J, R, a, b, Q0, omega0):
    Jm = V.second_moments(J, "J")
    Rv = V.vector3(R, "R")
    am = V.symmetric_matrix(a, "a")
    bv = V.vector3(b, "b")
    Qm = V.rotation_matrix(Q0, "Q0")
    w0 = V.vector3(omega0, "omega0")
    return Jm, Rv, am, bv, Qm, w0


def fixed_point_energy(J: ArrayLike, R: ArrayLike, a: ArrayLike, b: ArrayLike, Q: ArrayLike,
                       omega: ArrayLike) -> np.ndarray:
    """Energy ``1/2 omega.I omega + 1/2 tr(Q^T a Q J) + 1/2 b.(Q R)`` of (5.3) (leading axes broadcast)."""
    J = np.asarray(J, dtype=float)
    J = np.diag(J) if J.shape == (3,) else J
    Q, w = np.asarray(Q, dtype=float), np.asarray(omega, dtype=float)
    kin = 0.5 * np.einsum("...i,ij,...j->...", w, inertia_from_moments(J), w)
    quad = 0.5 * np.trace(np.swapaxes(Q, -1, -2) @ np.asarray(a, float) @ Q @ J, axis1=-2, axis2=-1)
    return kin + quad + 0.5 * (Q @ np.asarray(R, float)) @ np.asarray(b, float)


@single_blas_thread
def integrate_fixed_point(J: ArrayLike, R: ArrayLike, a: ArrayLike, b: ArrayLike, Q0: ArrayLike,
                          omega0: ArrayLike, t: ArrayLike, *, rtol: float = 1e-12, atol: float | None = None,
                          method: str = "DOP853") -> tuple[np.ndarray, np.ndarray]:
    """Integrate the rotation (5.3) of a body about a fixed point in ``1/2 y^T a y + 1/2 b.y``.

    Parameters
    ----------
    J : array_like, shape (3,) or (3, 3)
        Second moments about the fixed point (5.2), body frame.
    R : array_like, shape (3,)
        First moment about the fixed point (5.1): mass times the mass centre seen from it.
    a, b : array_like
        The potential, ``y`` measured from the fixed point.
    Q0, omega0 : array_like
        Initial attitude (body to space) and body angular velocity.
    t : array_like
        Output times (any shape, any order, negative allowed); integration starts at 0.
    rtol, atol : float
        Tolerances of :func:`scipy.integrate.solve_ivp` (``atol`` defaults to ``1e-3 rtol``).
    method : str
        Any explicit solve_ivp method.

    Returns
    -------
    omega : ndarray, ``t.shape + (3,)``
    Q : ndarray, ``t.shape + (3, 3)``
    """
    Jm, Rv, am, bv, Qm, w0 = _data(J, R, a, b, Q0, omega0)
    tt = V.times(t, "t")
    if not (0 < rtol < 1):
        raise ValueError(f"rtol must be in (0, 1), got {rtol}")
    atol = 1e-3 * rtol if atol is None else float(atol)
    Im = inertia_from_moments(Jm)
    I_inv = np.linalg.inv(Im)
    F = -0.5 * bv  # the uniform force per unit mass, space frame

    def rhs(_t, y):
        m, Q = y[:3], y[3:].reshape(3, 3)
        w = I_inv @ m
        mdot = cross(m, w) + torque(Jm, am, Q) + cross(Rv, Q.T @ F)
        return np.concatenate([mdot, (Q @ hat(w)).ravel()])

    m_out, Q_out, inv = both_ways(tt, Im @ w0, Qm, lambda grid: solve_ivp_mQ(rhs, Im @ w0, Qm, grid, rtol, atol,
                                                                             method))
    Q_out = polar_orthonormalize(Q_out)
    omega = np.linalg.solve(Im, m_out[..., None])[..., 0]
    return omega[inv].reshape(tt.shape + (3,)), Q_out[inv].reshape(tt.shape + (3, 3))


@dataclass(frozen=True, eq=False)
class NumericalFixedPoint(RotationSolution):
    """:func:`integrate_fixed_point` behind the :class:`~thetasol.protocol.RotationSolution` protocol.

    ``J`` are the second moments about the fixed point; ``sol(t)`` integrates on demand, once per
    call, from ``t = 0`` to every requested time.  Build it with :func:`numerical_fixed_point`.
    """

    R: np.ndarray = field(default_factory=lambda: np.zeros(3))
    b: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rtol: float = 1e-12
    integrator: str = "DOP853"

    _AT_ONCE = True  # one integration over all requested times

    def _evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return integrate_fixed_point(self.J, self.R, self.a, self.b, self.Q0, self.omega0, t, rtol=self.rtol,
                                     method=self.integrator)


def numerical_fixed_point(J: ArrayLike, R: ArrayLike, a: ArrayLike, b: ArrayLike, Q0: ArrayLike,
                          omega0: ArrayLike, *, rtol: float = 1e-12, method: str = "DOP853"
                          ) -> NumericalFixedPoint:
    """The rotation (5.3) as a solution evaluated by :func:`integrate_fixed_point`.

    Returns
    -------
    NumericalFixedPoint
        ``method`` is ``"numerical/<method>"``; ``invariants`` the ``energy`` at ``t = 0``
        (:func:`fixed_point_energy`); ``diagnostics`` the integrator and its tolerance.
    """
    Jm, Rv, am, bv, Qm, w0 = _data(J, R, a, b, Q0, omega0)
    if not (0 < rtol < 1):
        raise ValueError(f"rtol must be in (0, 1), got {rtol}")
    energy = float(fixed_point_energy(Jm, Rv, am, bv, Qm, w0))
    return NumericalFixedPoint(J=Jm, a=am, Q0=np.array(Q0, dtype=float), omega0=w0, method=f"numerical/{method}",
                               invariants={"energy": energy},
                               diagnostics={"integrator": "integrate_fixed_point", "method": method, "rtol": rtol},
                               R=Rv, b=bv, rtol=float(rtol), integrator=method)
