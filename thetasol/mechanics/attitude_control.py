"""Corollary 5 made concrete: an LQR attitude controller for one effective body on a circular orbit.

By Theorem 4 every effective body ``T_a`` of an orbiting C^k-central station turns on its own in the
tidal field (7.11); Corollary 5 concludes that its rotation can be stabilized on its own.  A pure
couple ``u`` on the physical body ``T_a`` (thruster pair, magnetic torquer, the reaction of a wheel)
does no work in a virtual translation and its virtual work ``u . dphi_a`` involves only the attitude
``Q_a``, which the effective body shares: it enters the rotation equation (7.16) of ``T_a`` alone,
leaving the mass centre and every other rotation untouched.  So a controller designed on ``T_a`` alone
(its effective second moments, the orbit's mean motion) is applied as a couple on the physical body
(docs/orbiting_station.md, tests/test_station_control.py).

Linearization.  Target: the body's axes ``B0`` (body-frame columns: the axes to hold along the
radial, along-track and normal directions, right-handed) along the orbit frame ``F(t)``
(:func:`~thetasol.mechanics.gravity_gradient.orbit_frame`), turning at the mean motion ``n``.  With
``Q B0 = F R``, ``R = exp(hat(theta))`` and ``omega_a = B0^T omega = theta' + n R^T e3`` to first
order, the equations of :mod:`thetasol.mechanics.gravity_gradient` with a control couple ``u``
(components along ``B0``) read

    I1 theta1'' + (I3 - I1 - I2) n theta2' + (I3 - I2) n^2 theta1 = u1
    I2 theta2'' + (I1 + I2 - I3) n theta1' + 4 (I3 - I1) n^2 theta2 = u2
    I3 theta3'' + 3 (I2 - I1) n^2 theta3 = u3

with ``I`` the principal moments in the order of ``B0``.  The controller minimizes
``int x^T Qw x + u^T Rw u`` over ``x = (theta, theta')`` (``scipy.linalg.solve_continuous_are``),
``u = -K x``; by default ``Qw = diag(1, 1, 1, 1/n^2, 1/n^2, 1/n^2)`` and ``Rw = diag(1 / (n^2 I_i)^2)``
(each axis's couple in units of its own gravity-gradient scale ``n^2 I_i``), which makes the design
independent of the units and keeps every closed-loop rate of order ``n`` even for a body with one
small moment (no stiff mode for the integrator).  Measured state: ``theta`` the rotation vector of
``R = F^T Q B0`` and ``theta' = omega_a - n R^T e3`` (exact: ``vee(R^T R')``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import solve_continuous_are
from scipy.spatial.transform import Rotation

from thetasol.core import validate as V
from thetasol.core.inertia import moments_from_inertia
from thetasol.mechanics.configuration import Configuration
from thetasol.mechanics.gravity_gradient import (
    GravityGradientStability,
    gravity_gradient_stability,
    gravity_gradient_stability_from_moments,
    orbit_frame,
)

__all__ = ["gravity_gradient_linearization", "AttitudeLQR", "lqr_attitude_controller", "StationController",
           "station_controller"]


def gravity_gradient_linearization(I: ArrayLike, mean_motion: float) -> tuple[np.ndarray, np.ndarray]:  # noqa: E741
    """``(A, B)`` of ``x' = A x + B u``, ``x = (theta, theta')``, about the orbit-aligned attitude.

    Parameters
    ----------
    I : array_like, shape (3,)
        Principal moments of inertia in the order radial, along-track, normal (as for
        :func:`~thetasol.mechanics.gravity_gradient.gravity_gradient_stability`).
    mean_motion : float
        ``n`` of the circular orbit.

    Returns
    -------
    A : ndarray (6, 6)
    B : ndarray (6, 3)
        ``u`` the control couple along the same axes.
    """
    return _linearization(gravity_gradient_stability(I, mean_motion))


def _linearization(st: GravityGradientStability) -> tuple[np.ndarray, np.ndarray]:
    """The ``(A, B)`` of :func:`gravity_gradient_linearization` from the body's stability record."""
    I1, I2, I3 = st.inertia
    n = st.mean_motion
    A = np.zeros((6, 6))
    A[:3, 3:] = np.eye(3)
    A[3, 0], A[3, 4] = -(I3 - I2) * n * n / I1, -(I3 - I1 - I2) * n / I1
    A[4, 1], A[4, 3] = -4.0 * (I3 - I1) * n * n / I2, -(I1 + I2 - I3) * n / I2
    A[5, 2] = -3.0 * (I2 - I1) * n * n / I3
    B = np.zeros((6, 3))
    B[3:] = np.diag(1.0 / st.inertia)
    return A, B


@dataclass(frozen=True, eq=False)
class AttitudeLQR:
    """An LQR attitude controller of one body about its orbit-aligned attitude (module docstring).

    Attributes
    ----------
    alignment : ndarray (3, 3)
        ``B0``: body-frame principal axes (columns) held along radial, along-track, normal.
    inertia : ndarray (3,)
        Principal moments in that order.
    mean_motion : float
    A, B, K, P : ndarray
        The linear model, the gain ``u = -K x`` (3, 6) and the Riccati solution.
    closed_loop_eigenvalues : ndarray (6,)
        Eigenvalues of ``A - B K``.
    open_loop : GravityGradientStability
        The uncontrolled linear stability of that attitude.
    """

    alignment: np.ndarray
    inertia: np.ndarray
    mean_motion: float
    A: np.ndarray
    B: np.ndarray
    K: np.ndarray
    P: np.ndarray
    closed_loop_eigenvalues: np.ndarray
    open_loop: GravityGradientStability

    def error(self, Q: ArrayLike, omega: ArrayLike, F: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """``theta`` and ``theta'`` (shape ``(..., 3)`` each) of attitudes ``Q`` with body rates ``omega`` in the orbit frame ``F``."""
        Q, w, F = (np.asarray(x, dtype=float) for x in (Q, omega, F))
        R = np.swapaxes(F, -1, -2) @ Q @ self.alignment
        lead = R.shape[:-2]
        theta = Rotation.from_matrix(R.reshape(-1, 3, 3)).as_rotvec().reshape(lead + (3,))
        wa = w @ self.alignment
        rate = wa - self.mean_motion * R[..., 2, :]              # omega_a - n R^T e3
        return theta, rate

    def torque(self, Q: ArrayLike, omega: ArrayLike, F: ArrayLike) -> np.ndarray:
        """Body-frame control couple ``B0 (-K x)``, shape ``(..., 3)``."""
        theta, rate = self.error(Q, omega, F)
        u = -np.concatenate([theta, rate], axis=-1) @ self.K.T
        return u @ self.alignment.T


def lqr_attitude_controller(I: ArrayLike, mean_motion: float, Qw: ArrayLike | None = None,  # noqa: E741
                            Rw: ArrayLike | None = None, alignment: ArrayLike | None = None) -> AttitudeLQR:
    """LQR controller holding a body's principal axes along the orbit frame on a circular orbit.

    Parameters
    ----------
    I : array_like, shape (3,) or (3, 3)
        Inertia tensor: principal values in the order radial, along-track, normal (then
        ``alignment`` defaults to the identity), or the body-frame tensor (then ``alignment`` is
        required).
    mean_motion : float
        ``n`` of the circular orbit.
    Qw : array_like (6, 6) or (6,), optional
        State weight on ``(theta, theta')`` (default ``diag(1, 1, 1, n^-2, n^-2, n^-2)``).
    Rw : array_like (3, 3) or (3,), optional
        Control weight (default ``diag(1 / (n^2 I_i)^2)``).
    alignment : array_like (3, 3), optional
        Body-frame axes (columns, right-handed, principal axes of ``I``) to hold along radial,
        along-track and normal.

    Returns
    -------
    AttitudeLQR

    Examples
    --------
    >>> c = lqr_attitude_controller([1.75, 0.75, 2.0], 1.0)     # unstable alone
    >>> c.open_loop.region, bool(np.all(c.closed_loop_eigenvalues.real < 0))
    ('unstable', True)
    """
    principal = np.shape(I) == (3,)
    Jm = moments_from_inertia(V.inertia(I, "I"))
    return _lqr(np.diag(Jm) if principal else Jm, mean_motion, Qw, Rw, alignment)


def _lqr(J: np.ndarray, mean_motion: float, Qw, Rw, alignment) -> AttitudeLQR:
    """:func:`lqr_attitude_controller` of a body given by its second moments ``J`` (principal or tensor)."""
    Jm = np.asarray(J, dtype=float)
    if Jm.shape == (3,):
        B0 = np.eye(3) if alignment is None else V.rotation_matrix(alignment, "alignment")
        Jb = B0 @ np.diag(V.finite_array(Jm, "J", (3,))) @ B0.T
    else:
        if alignment is None:
            raise ValueError("a body-frame J (3, 3) needs the alignment: the axes to hold along the orbit frame")
        Jb = V.second_moments(Jm, "J")
        B0 = V.rotation_matrix(alignment, "alignment")
    Ja = B0.T @ Jb @ B0
    off = np.max(np.abs(Ja - np.diag(np.diag(Ja))))
    if off > 1e-10 * np.max(np.abs(Ja)):
        raise ValueError(f"the alignment's axes are not principal axes of J (off-diagonal {off:.3g})")
    st = gravity_gradient_stability_from_moments(np.diag(Ja), mean_motion)
    A, B = _linearization(st)
    n = st.mean_motion
    Qm = np.diag(np.r_[np.ones(3), np.full(3, n ** -2)]) if Qw is None else _weight(Qw, 6, "Qw")
    Rm = np.diag((n * n * st.inertia) ** -2.0) if Rw is None else _weight(Rw, 3, "Rw")
    P = solve_continuous_are(A, B, Qm, Rm)
    K = np.linalg.solve(Rm, B.T @ P)
    return AttitudeLQR(alignment=B0, inertia=st.inertia, mean_motion=n, A=A, B=B, K=K, P=P,
                       closed_loop_eigenvalues=np.linalg.eigvals(A - B @ K), open_loop=st)


class StationController:
    """One :class:`AttitudeLQR` per effective body, applied as pure couples on the physical bodies.

    ``ctrl(t, q, qdot, Q, omega) -> (N, 3)``: the body-frame couple on each body (``config.order``),
    from the orbit frame of the measured system mass centre ``q, qdot`` and each body's own attitude
    ``Q[i]`` and rate ``omega[i]``, nothing else: the controllers are the separate designs of
    Corollary 5.  Bodies without a controller get zero.  This is the ``torques`` argument of
    :class:`thetasol.integrators.multibody_gravity.PointMassGravity`.

    Attributes
    ----------
    names : tuple of str
        ``config.order``.
    controllers : dict name -> AttitudeLQR
    """

    def __init__(self, names: tuple, controllers: dict):
        self.names = tuple(names)
        self.controllers = dict(controllers)

    def __call__(self, t: float, q: np.ndarray, qdot: np.ndarray, Q: np.ndarray, omega: np.ndarray) -> np.ndarray:
        F = orbit_frame(q, qdot)
        out = np.zeros((len(self.names), 3))
        for i, n in enumerate(self.names):
            c = self.controllers.get(n)
            if c is not None:
                out[i] = c.torque(Q[i], omega[i], F)
        return out


def station_controller(config: Configuration, mean_motion: float, alignments: dict, Qw: ArrayLike | None = None,
                       Rw: ArrayLike | None = None) -> StationController:
    """An LQR per effective body, each designed on that body alone (Corollary 5).

    Parameters
    ----------
    config : Configuration
        A central tree; each controller uses its body's effective second moments (2.15), (3.7).
    mean_motion : float
        ``n`` of the circular orbit.
    alignments : mapping name -> (3, 3)
        Per controlled body, the body-frame principal axes (columns) to hold along radial,
        along-track, normal (:func:`lqr_attitude_controller`).  Other bodies are left free.
    Qw, Rw : optional
        Weights, the same for every body (defaults of :func:`lqr_attitude_controller`).
    """
    unknown = set(alignments) - set(config.order)
    if unknown:
        raise ValueError(f"alignments name unknown bodies {sorted(unknown)}")
    ctrl = {n: _lqr(config.effective_body(n).J, mean_motion, Qw, Rw, B0)
            for n, B0 in alignments.items()}
    return StationController(config.order, ctrl)


def _weight(W: ArrayLike, k: int, name: str) -> np.ndarray:
    W = np.asarray(W, dtype=float)
    W = np.diag(W) if W.shape == (k,) else W
    W = V.finite_array(W, name, (k, k))
    return 0.5 * (W + W.T)
