"""What a numerical reference needs of a mass centre's orbit: a structural protocol.

The references of Sections 7 and 8 turn a body in the gravity-gradient torque along a given orbit
``r(t)`` of its mass centre about a centre of attraction ``mu``.  They take the orbit as an input and
use only the members listed in :class:`Orbit`, so any object with them serves: the closed-form
:class:`thetasol.KeplerOrbit`, or a user's tabulated or perturbed orbit.  The references therefore
import no closed form.
"""
from __future__ import annotations

from collections.abc import Mapping
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["Orbit", "check_orbit"]


@runtime_checkable
class Orbit(Protocol):
    """A mass centre's orbit about a centre of attraction at the origin, as the numerical references use it.

    Attributes
    ----------
    mu : float
        Gravitational parameter of the attracting centre (> 0).
    r0, v0 : ndarray, shape (3,)
        Position and velocity at ``t = 0`` (the initial state of heyoka's integration of the orbit).
    diagnostics : mapping
        ``"kind"`` (``"elliptic"``, ``"parabolic"`` or ``"hyperbolic"``), the eccentricity ``"e"`` and
        the ``"mean_motion"`` (the orbital rate, which scales the default absolute tolerance).
    """

    mu: float
    r0: np.ndarray
    v0: np.ndarray
    diagnostics: Mapping

    def state_at(self, t: float) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """Position and velocity at one time, as tuples of Python floats (called by right-hand sides)."""

    def __call__(self, t: ArrayLike) -> tuple[np.ndarray, ...]:
        """Position and velocity at times ``t`` (any shape), shapes ``t.shape + (3,)``."""


def check_orbit(orbit: object, name: str = "orbit") -> Orbit:
    """``orbit`` if it has the members of :class:`Orbit`; a ``TypeError`` naming the missing ones otherwise."""
    if not isinstance(orbit, Orbit):
        missing = [m for m in ("mu", "r0", "v0", "diagnostics", "state_at", "__call__") if not hasattr(orbit, m)]
        raise TypeError(f"{name} must be an orbit (e.g. thetasol.KeplerOrbit) with mu, r0, v0, diagnostics, "
                        f"state_at(t) and __call__(t); {type(orbit).__name__} lacks {', '.join(missing)}")
    return orbit
