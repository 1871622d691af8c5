"""Which kind of quadratic potential ``phi(x) = 1/2 x^T a x`` a body turns in (Section 4).

Only the eigenvalues of ``a`` matter, and only their differences: an isotropic part ``c 1`` exerts no
torque on any body.  Three kinds, each with its own closed form:

* ``"isotropic"``: ``a = c 1`` (zero included), no torque; the Euler top (Section 4 I);
* ``"rank-one"``: two equal eigenvalues, ``a = c 1 + d n n^T`` (a gravity gradient, a heavy top's
  field squared); the spectral curve (4.12) has a node and genus 3;
* ``"generic"``: three distinct eigenvalues; the spectral curve has genus 4 (Section 4 II).

:func:`potential_kind` is the one test of the library (the dispatcher of
:func:`thetasol.solve_rotation`, the scenes' report of which closed form a body needs).
"""
from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["EQUAL_TOL", "PotentialKind", "potential_kind"]

PotentialKind = Literal["isotropic", "rank-one", "generic"]

#: Two eigenvalues of ``a`` count as equal when they differ by at most this, relative to the larger of
#: their spread and the largest ``|eigenvalue|``: 8 ulps, the rounding of a symmetric eigen-decomposition,
#: so that data meant to be degenerate are read as such (the spectral curve snaps them the same way).
EQUAL_TOL = 8 * float(np.finfo(float).eps)


def potential_kind(a: ArrayLike) -> PotentialKind:
    """``"isotropic"``, ``"rank-one"`` or ``"generic"`` (module docstring) for a symmetric 3x3 ``a``.

    Raises
    ------
    ValueError
        ``a`` is not a finite 3x3 matrix.
    """
    a = np.asarray(a, dtype=float)
    if a.shape != (3, 3) or not np.all(np.isfinite(a)):
        raise ValueError(f"a must be a finite symmetric 3x3 matrix, got shape {a.shape}")
    lam = np.linalg.eigvalsh(a)
    spread = float(lam[-1] - lam[0])
    scale = max(spread, float(np.abs(lam).max()))
    if spread <= EQUAL_TOL * scale:
        return "isotropic"
    if float(np.min(np.diff(lam))) <= EQUAL_TOL * scale:
        return "rank-one"
    return "generic"
