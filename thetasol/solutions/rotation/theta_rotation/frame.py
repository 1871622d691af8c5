"""The principal frame of the data and the refusals made before the spectral curve is built.

The construction runs in the right-handed principal frame with ascending ``J``.  For a symmetric body
(two equal ``J_i``) the axial spin ``omega . e`` is an integral, and the construction runs in the frame
turning at ``-spin`` about the axis (``Q~ = Q R(t)``, ``omega~ = R^T omega - spin e``): there the Lax
equation (4.11) keeps its form and ``omega~`` has no axial part, so the Baker-Akhiezer function has no
third-kind singularity at the node over ``E = infinity`` (docs/theta_rotation.md).

Data that put branch points of the curve (4.12) out of the curve engine's reach are refused here, at
once, with :class:`~thetasol.ClosedFormUnavailable`; the limits are measured (docs/theta_rotation.md,
"Limits").
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from thetasol.core.attitude import principal_frame
from thetasol.core.inertia import inertia_from_moments
from thetasol.core.so3 import hat
from thetasol.curves.spectral import farthest_branch_point
from thetasol.protocol import ClosedFormUnavailable
from thetasol.solutions._symmetry import SNAP_TOL, symmetry_axis

__all__ = ["MIN_AXIAL_SPIN", "MIN_J_GAP", "MAX_FAR_BRANCH", "BodyFrame", "body_frame"]

#: A symmetric body's axial spin, relative to |omega0| + sqrt|a|, below which the data are refused: two
#: branch points sit near |E| ~ 1 / spin and below it the set-up grows to minutes (docs/theta_rotation.md,
#: "Limits").
MIN_AXIAL_SPIN = 3e-4
#: Relative gap of two principal second moments (over max J) below which the data are refused: branch
#: points near |E| ~ 1 / gap, beyond the curve engine's reach below it (docs/theta_rotation.md, "Limits").
MIN_J_GAP = 1e-7
#: A symmetric body whose farthest branch point lies beyond this, in units of sqrt(max |eig a|) / max J,
#: is refused (a nearly spherical body with a small spin, whose set-up would take seconds).
MAX_FAR_BRANCH = 2e4


@dataclass(frozen=True, eq=False)
class BodyFrame:
    """The data in the principal frame, and the turning frame of a symmetric body.

    Attributes
    ----------
    Jp : ndarray, shape (3,)
        Principal second moments, ascending.
    P : ndarray, shape (3, 3)
        Right-handed principal frame: ``J = P diag(Jp) P^T``.
    Q0p, w0p : ndarray
        Initial attitude ``Q0 P`` and angular velocity ``P^T omega0`` in that frame.
    M0, u0 : ndarray, shape (3, 3)
        The paper's ``M = hat(I omega0)`` and ``u = -Q0p^T a Q0p`` (4.5), (4.8).
    W0 : ndarray, shape (3, 3)
        ``hat(omega~0)``: the angular velocity in the turning frame (``hat(w0p)`` for distinct ``J``).
    spin : float
        Axial spin of a symmetric body (0.0 otherwise).
    axis : int or None
        Index of the symmetry axis, None for distinct ``J``.
    """

    Jp: np.ndarray
    P: np.ndarray
    Q0p: np.ndarray
    w0p: np.ndarray
    M0: np.ndarray
    u0: np.ndarray
    W0: np.ndarray
    spin: float
    axis: int | None


def _refuse_small_spin(Jp, a, w0p, spin, M0, u0) -> None:
    """Refuse a symmetric body near a tacnode over E = infinity (little axial spin, far branch points)."""
    sqrt_a = np.sqrt(np.abs(np.linalg.eigvalsh(a)).max())
    scale = np.linalg.norm(w0p) + sqrt_a
    if abs(spin) < MIN_AXIAL_SPIN * scale:
        # without spin the two places over E = infinity touch (a tacnode, genus 2: Neumann's problem,
        # dispatched before); a small spin puts two branch points near |E| ~ 1 / spin
        raise ClosedFormUnavailable(
            f"symmetric body with little spin (or none) about its symmetry axis ({abs(spin) / scale:.1e} of "
            f"|omega0| + sqrt|a|, below {MIN_AXIAL_SPIN:g}): the spectral curve is at or near a tacnode "
            "over E = infinity (the axis moves as in Neumann's problem, genus 2), which is not "
            "implemented; use thetasol.integrate_rotation")
    far = farthest_branch_point(np.diag(Jp), M0, u0) * (Jp[-1] / sqrt_a)
    if far > MAX_FAR_BRANCH:
        raise ClosedFormUnavailable(
            f"symmetric body with branch points of its spectral curve at |E| ~ {far:.1e} sqrt|a| / J "
            f"(above {MAX_FAR_BRANCH:g}; axial spin {abs(spin) / scale:.1e} of |omega0| + sqrt|a|): near a "
            "tacnode over E = infinity, out of the curve engine's reach; use thetasol.integrate_rotation")


def _snap_pair(Jp: np.ndarray) -> np.ndarray:
    """The two closest principal second moments replaced by their mean (as spectral_curve snaps them)."""
    Js = Jp.copy()
    i = int(np.argmin(np.diff(Js)))
    Js[i] = Js[i + 1] = 0.5 * (Js[i] + Js[i + 1])
    return Js


def _refuse_small_gap(Jp) -> None:
    """Refuse a nearly symmetric body: branch points near |E| ~ 1 / gap (numerically singular curve)."""
    gap = float(np.min(np.diff(Jp))) / Jp[-1]
    if gap < MIN_J_GAP:
        raise ClosedFormUnavailable(
            f"nearly symmetric body (two principal second moments {gap:.1e} apart relative, above the "
            f"snapping tolerance {SNAP_TOL:g} and below {MIN_J_GAP:g}): the spectral curve has branch "
            "points near |E| ~ 1 / gap, out of the curve engine's reach; use thetasol.integrate_rotation")


def body_frame(J: np.ndarray, a: np.ndarray, Q0: np.ndarray, omega0: np.ndarray) -> BodyFrame:
    """The data in the principal frame; raises ClosedFormUnavailable for data out of reach (module doc)."""
    Jp, P = principal_frame(J, ascending=True)
    Q0p = Q0 @ P
    w0p = P.T @ omega0
    spin, axis = 0.0, symmetry_axis(Jp)
    if axis is not None:
        # every stage (curve, eigenvector poles, frame) solves the exactly symmetric body
        Jp = _snap_pair(Jp)
    M0 = hat(inertia_from_moments(np.diag(Jp)) @ w0p)
    u0 = -(Q0p.T @ a @ Q0p)
    if axis is not None:
        spin = float(w0p[axis])
        _refuse_small_spin(Jp, a, w0p, spin, M0, u0)
        W0 = hat(w0p - spin * np.eye(3)[axis])
    else:
        _refuse_small_gap(Jp)
        W0 = hat(w0p)
    return BodyFrame(Jp=Jp, P=P, Q0p=Q0p, w0p=w0p, M0=M0, u0=u0, W0=W0, spin=spin, axis=axis)
