"""The result protocol of the heavy-top closed forms: ``sol(t) -> (omega, Q)``.

A :class:`HeavyTopSolution` follows :class:`~thetasol.protocol.Solution` with the state of
:func:`thetasol.integrators.heavy_top.integrate_heavy_top`: the body angular velocity ``omega``
(shape ``t.shape + (3,)``) and the attitude ``Q`` (body to space, ``t.shape + (3, 3)``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from thetasol.protocol import Solution

__all__ = ["HeavyTopSolution"]


@dataclass(frozen=True, eq=False)
class HeavyTopSolution(Solution):
    """The motion of a heavy top, ``t -> (omega(t), Q(t))``.

    Attributes
    ----------
    I : ndarray, shape (3, 3)
        Inertia about the fixed point, body frame.
    center : ndarray, shape (3,)
        Mass centre seen from the fixed point, body frame.
    mass : float
    gravity : ndarray, shape (3,)
        Gravity vector in space; potential ``V = -mass gravity . (Q center)``.
    Q0, omega0 : ndarray
        Initial attitude (body to space) and body angular velocity.
    model : str
        ``"heavy-top"`` (rotors along the axis of a Lagrange gyrostat included).
    method : str
        ``"elliptic"`` (Lagrange's top, and Euler's when the centre is at the pivot), ``"theta/genus-2"``
        (Kovalevskaya's top) or ``"elementary"`` (steady rotations, the symmetric Euler top, rest);
        ``diagnostics["case"]`` names the special case (``"separatrix"``, ``"steady"``, ``"euler"``, ...).
    invariants : dict
        ``energy``, ``vertical_momentum``, ``axial_momentum`` (see
        :func:`thetasol.mechanics.heavy_top.heavy_top_invariants`).
    diagnostics : dict
        Periods, the elliptic parameters, the turning points, the fit residual at ``t = 0`` and
        ``error_estimate``.
    """

    model = "heavy-top"

    I: np.ndarray
    center: np.ndarray
    mass: float
    gravity: np.ndarray
    Q0: np.ndarray
    omega0: np.ndarray
    method: str
    invariants: dict = field(repr=False)
    diagnostics: dict = field(default_factory=dict, repr=False)

    def _evaluate(self, t: np.ndarray):  # pragma: no cover - abstract
        raise NotImplementedError

    def omega(self, t: ArrayLike) -> np.ndarray:
        """Body angular velocity, shape ``t.shape + (3,)``."""
        return self(t)[0]

    def Q(self, t: ArrayLike) -> np.ndarray:
        """Attitude (body to space), shape ``t.shape + (3, 3)``."""
        return self(t)[1]

    def m(self, t: ArrayLike) -> np.ndarray:
        """Body angular momentum about the fixed point ``I omega``, shape ``t.shape + (3,)``."""
        return self.omega(t) @ self.I.T

    def fastest_frequency(self) -> float:
        """The largest of the spin ``|omega0|``, ``2 pi / period`` and the pendulum rate of gravity
        ``sqrt(mass |g| |center| / I_d)`` (``I_d`` the smallest diagonal moment), rad per unit time."""
        pull = self.mass * float(np.linalg.norm(self.gravity)) * float(np.linalg.norm(self.center))
        swing = math.sqrt(pull / float(np.diag(self.I).min())) if pull > 0 else 0.0
        return max(float(np.linalg.norm(self.omega0)), swing, super().fastest_frequency())
