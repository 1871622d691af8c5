"""The numerical reference: a rigid body turning about a fixed point in a quadratic potential (5.3).

With the fixed point ``P0`` at the origin of space and of the body frame, the Lagrangian (5.3) is

    L = 1/2 omega.I omega - 1/2 tr(Q^T a Q J) - 1/2 b.(Q R),

``I`` the inertia about ``P0`` and ``J = tr(I)/2 1 - I`` its second moments, ``R`` the first moment
(5.1) (the mass times the mass centre seen from ``P0``), ``phi(y) = 1/2 y^T a y + 1/2 b.y`` the
potential with ``y`` measured from ``P0``.  The body angular momentum ``m = I omega`` obeys

    mdot = m x omega + vee([J, Q^T a Q]) + R x (Q^T (-b/2)),      Qdot = Q hat(omega):

the torque of the quadratic part as in (4.8) (:func:`thetasol.mechanics.equations.torque`) and the
torque of the uniform force ``-b/2`` per unit mass.  ``b = 0`` or ``R = 0`` is the problem of
:func:`~thetasol.integrators.rotation.integrate_rotation` with ``I`` about ``P0`` (Corollary 2);
``a = 0`` is the heavy top of :func:`~thetasol.integrators.heavy_top.integrate_heavy_top` with
``center = R / mass`` and ``gravity = -b / 2`` (Corollary 3).  The general case has no known closed form: this module is its reference.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.inertia import second_moments
from thetasol.core.so3 import cross, hat, polar_orthonormalize
from thetasol.integrators._common import SCIPY_METHODS, Settings, body_inertia, both_ways, settings, solve_ivp_mQ
from thetasol.mechanics.equations import torque_from_moments
from thetasol.protocol import RotationSolution

__all__ = ["integrate_fixed_point", "fixed_point_energy", "NumericalFixedPoint"]


def fixed_point_energy(I: ArrayLike, R: ArrayLike, a: ArrayLike, b: ArrayLike, Q: ArrayLike,  # noqa: E741
                       omega: ArrayLike) -> np.ndarray:
    """Energy ``1/2 omega.I omega + 1/2 tr(Q^T a Q J) + 1/2 b.(Q R)`` of (5.3) (leading axes broadcast), for
    the inertia ``I`` about the fixed point (principal values or a tensor) and its second moments ``J``."""
    Im = np.asarray(I, dtype=float)
    Im = np.diag(Im) if Im.shape == (3,) else Im
    J = second_moments(Im)
    Q, w = np.asarray(Q, dtype=float), np.asarray(omega, dtype=float)
    kin = 0.5 * np.einsum("...i,ij,...j->...", w, Im, w)
    quad = 0.5 * np.trace(np.swapaxes(Q, -1, -2) @ np.asarray(a, float) @ Q @ J, axis1=-2, axis2=-1)
    return kin + quad + 0.5 * (Q @ np.asarray(R, float)) @ np.asarray(b, float)


def integrate_fixed_point(I: ArrayLike, R: ArrayLike, a: ArrayLike, b: ArrayLike, Q0: ArrayLike,  # noqa: E741
                          omega0: ArrayLike, *, method: str = "DOP853", rtol: float = 1e-12,
                          atol: float | None = None) -> NumericalFixedPoint:
    """The rotation (5.3) of a body about a fixed point in ``1/2 y^T a y + 1/2 b.y``, integrated numerically.

    Parameters
    ----------
    I : array_like, shape (3,) or (3, 3)
        Inertia about the fixed point, body frame (principal values or a symmetric tensor); the
        paper's second moments about it (5.2) convert with :func:`thetasol.inertia`.
    R : array_like, shape (3,)
        First moment about the fixed point (5.1): mass times the mass centre seen from it.
    a, b : array_like
        The potential, ``y`` measured from the fixed point.
    Q0, omega0 : array_like
        Initial attitude (body to space) and body angular velocity.
    method : str
        Any :func:`scipy.integrate.solve_ivp` method.
    rtol, atol : float
        Tolerances of :func:`scipy.integrate.solve_ivp` (``atol`` defaults to ``1e-3 rtol``).

    Returns
    -------
    NumericalFixedPoint
        ``sol(t) -> (omega, Q)`` with shapes ``t.shape + (3,)`` and ``t.shape + (3, 3)``, one
        integration from ``t = 0`` per call; ``model`` is ``"fixed-point"``, ``method``
        ``"numerical/<method>"``; ``invariants`` the ``energy`` at ``t = 0`` (:func:`fixed_point_energy`);
        ``diagnostics`` the integrator settings and ``error_estimate`` (its ``rtol``).
    """
    Im, Jm = body_inertia(I)
    Rv = V.vector3(R, "R")
    am = V.symmetric_matrix(a, "a")
    bv = V.vector3(b, "b")
    Qm = V.rotation_matrix(Q0, "Q0")
    w0 = V.vector3(omega0, "omega0")
    opts = settings(method, rtol, atol, methods=SCIPY_METHODS)
    energy = float(fixed_point_energy(Im, Rv, am, bv, Qm, w0))
    return NumericalFixedPoint(J=Jm, a=am, Q0=Qm, omega0=w0, method=f"numerical/{opts.method}",
                               invariants={"energy": energy}, diagnostics=opts.diagnostics(),
                               I_given=Im, R=Rv, b=bv, settings=opts)


@dataclass(frozen=True, eq=False)
class NumericalFixedPoint(RotationSolution):
    """The rotation of :func:`integrate_fixed_point` behind the :class:`~thetasol.protocol.RotationSolution`
    protocol: ``sol(t)`` integrates on demand, once per call, from ``t = 0`` to every requested time.

    ``I`` is the inertia about the fixed point as given, ``J`` its second moments.
    """

    R: np.ndarray = field(default_factory=lambda: np.zeros(3))
    b: np.ndarray = field(default_factory=lambda: np.zeros(3))
    settings: Settings = Settings()

    model: ClassVar[str] = "fixed-point"
    _AT_ONCE = True  # one integration over all requested times

    def _evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        s, Im, Jm, Rv, am, Qm, w0 = self.settings, self.I, self.J, self.R, self.a, self.Q0, self.omega0
        atol = 1e-3 * s.rtol if s.atol is None else s.atol
        I_inv = np.linalg.inv(Im)
        F = -0.5 * self.b  # the uniform force per unit mass, space frame

        def rhs(_t, y):
            m, Q = y[:3], y[3:].reshape(3, 3)
            w = I_inv @ m
            mdot = cross(m, w) + torque_from_moments(Jm, am, Q) + cross(Rv, Q.T @ F)
            return np.concatenate([mdot, (Q @ hat(w)).ravel()])

        m0 = Im @ w0
        m_out, Q_out, inv = both_ways(t, m0, Qm, lambda grid: solve_ivp_mQ(rhs, m0, Qm, grid, s.rtol, atol, s.method))
        Q_out = polar_orthonormalize(Q_out)
        omega = np.linalg.solve(Im, m_out[..., None])[..., 0]
        return omega[inv], Q_out[inv]
