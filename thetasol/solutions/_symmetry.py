"""The symmetry test shared by the rotation models in a potential.

The theta-function model and Neumann's model must agree on when a body counts as symmetric
(two principal second moments equal to ``SNAP_TOL`` relative) and on the frame they solve in
(:func:`thetasol.core.attitude.principal_frame` with ascending principal values).
"""
from __future__ import annotations

import numpy as np

from thetasol.core.attitude import principal_frame
from thetasol.mechanics.potential import potential_kind
from thetasol.protocol import ClosedFormUnavailable

__all__ = ["SNAP_TOL", "symmetric_without_spin", "symmetry_axis"]


#: Relative size below which a near-degeneracy of the data is snapped to an exact one: 8 ulps, the
#: rounding of an eigen-decomposition.  Snapping a gap d moves the trajectory by about d / eps times
#: the float64 conditioning (error and conditioning both grow like t; benchmarks/bench_snapping.py
#: measures it), so only gaps at the level of rounding are snapped.  Gaps above it and below the
#: engines' own limits are refused.
SNAP_TOL = 8 * float(np.finfo(float).eps)


def symmetry_axis(Jp: np.ndarray):
    """Index of the symmetry axis of a symmetric body (two equal ascending Jp), else None."""
    if np.min(np.diff(Jp)) > SNAP_TOL * Jp[-1]:
        return None
    if Jp[-1] - Jp[0] <= SNAP_TOL * Jp[-1]:
        raise ClosedFormUnavailable(f"nearly spherical body (principal second moments {Jp} equal to "
                                    f"{SNAP_TOL:g}): use thetasol.integrate_rotation")
    return 2 if Jp[1] - Jp[0] <= SNAP_TOL * Jp[-1] else 0


def symmetric_without_spin(J: np.ndarray, a: np.ndarray, omega0: np.ndarray):
    """``(Jp, P, axis)`` when the body is symmetric, ``a`` is not isotropic and ``omega0`` has no axial
    part (relative to ``|omega0| + sqrt|a|``, within :data:`SNAP_TOL`): Neumann's case of
    :func:`thetasol.solve_rotation`; else None.  Here, apart from the Neumann model, so that the
    dispatcher imports that model's modules only for the bodies it solves."""
    Jp, P = principal_frame(J, ascending=True)
    if Jp[-1] - Jp[0] <= SNAP_TOL * Jp[-1]:
        return None                                    # spherical: no torque
    axis = symmetry_axis(Jp)
    if axis is None:
        return None
    if potential_kind(a) == "isotropic":
        return None                                    # no torque
    ev = np.linalg.eigvalsh(a)
    w0p = P.T @ omega0
    scale = np.linalg.norm(w0p) + np.sqrt(np.abs(ev).max())
    if abs(w0p[axis]) > SNAP_TOL * scale:
        return None
    return Jp, P, axis
