"""Principal frames and the symmetry test shared by the rotation models in a potential.

The theta-function model and Neumann's model must agree on when a body counts as symmetric
(two principal second moments equal to ``SNAP_TOL`` relative) and on the frame they solve in.
"""
from __future__ import annotations

import numpy as np

from thetasol.solutions.base import ClosedFormUnavailable

__all__ = ["SNAP_TOL", "sorted_principal_frame", "symmetry_axis"]


#: Relative size below which a near-degeneracy of the data is snapped to an exact one.  At 1e-12
#: the change of the data moves the trajectory by less than the float64 conditioning at t ~ 1e3.
SNAP_TOL = 1e-12


def sorted_principal_frame(J: np.ndarray):
    """Right-handed principal frame with ascending principal values: J = P diag(Jp) P^T."""
    Jp, P = np.linalg.eigh(J)
    P[:, 2] *= np.sign(np.linalg.det(P))
    return Jp, P


def symmetry_axis(Jp: np.ndarray):
    """Index of the symmetry axis of a symmetric body (two equal ascending Jp), else None."""
    if np.min(np.diff(Jp)) > SNAP_TOL * Jp[-1]:
        return None
    if Jp[-1] - Jp[0] <= SNAP_TOL * Jp[-1]:
        raise ClosedFormUnavailable(f"nearly spherical body (principal second moments {Jp} equal to "
                                    f"{SNAP_TOL:g}): use thetasol.integrate_rotation")
    return 2 if Jp[1] - Jp[0] <= SNAP_TOL * Jp[-1] else 0
