"""Stage 1: the spectral curve (4.12) of the initial data and the homology basis adapted to the flow.

The curve ``det(J^2 E^2 + M E + u - w 1) = 0`` is built from the exact binary rationals of the data
(:func:`thetasol.curves.spectral.spectral_curve`).  Its periods are taken in a symplectic basis
adapted to the real Liouville torus (:func:`thetasol.curves.adapted_basis.real_flow_basis`): the
involutions ``sigma: (E, w) -> (-E, w)`` and complex conjugation act on homology by integer matrices,
and a basis whose first a-cycles span ``{x : S_sigma x = -x, S_c x = x}`` makes the flow velocity ``U``
real with only ``rdim`` non-zero coordinates (3, the Prym variety; 2 for a rank-one potential or a
symmetric body).  Theta along the trajectory is then a Fourier series in those phases.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from thetasol.curves.adapted_basis import real_flow_basis
from thetasol.curves.spectral import spectral_curve
from thetasol.solutions._symmetry import SNAP_TOL
from thetasol.solutions.rotation.theta_rotation.frame import BodyFrame
from thetasol.solutions.rotation.theta_rotation.infinity import infinity_data, velocity_at_infinity
from thetasol.solutions.rotation.theta_rotation.node import node_branch_slopes
from thetasol.theta.riemann import RiemannTheta

if TYPE_CHECKING:
    from thetasol.curves.plane_curve import Numerator, Place
    from thetasol.curves.spectral import SpectralCurve

__all__ = ["SpectralData", "spectral_data"]


@dataclass(frozen=True, eq=False)
class SpectralData:
    """The spectral curve (4.12), its adapted periods and its special places (stage 1).

    Attributes
    ----------
    frame : BodyFrame
        The data in the principal (and, for a symmetric body, turning) frame.
    curve : thetasol.curves.spectral.SpectralCurve
        The curve of ``J, M, u`` (snapped where degenerate to ``SNAP_TOL``).
    nums : tuple of Numerator
        Numerators ``g_i`` of the holomorphic differentials ``g_i dE / f_w`` (exact, no sympy).
    G : ndarray of int, shape (2g, 2g)
        The adapted symplectic basis, columns ``[a' | b']`` in the curve's own cycles.
    rdim : int
        Dimension of the real Liouville torus: ``U`` is zero beyond its first ``rdim`` coordinates.
    Ainv : ndarray, shape (g, g)
        Inverse a-periods in the adapted basis: raw Abel integrals -> normalized coordinates.
    tau : ndarray, shape (g, g)
        Riemann matrix in the adapted basis (symmetrized).
    theta : RiemannTheta
        Riemann theta of ``tau``.
    Pinf : tuple of Place
        The places ``inf_j`` over ``E = infinity``.
    Jinf : ndarray, shape (3,)
        ``J_j`` of each (``w / E^2 -> J_j^2``).
    B : ndarray, shape (3, 3)
        Unitary basis in which only the j-th component of the eigenvector survives at ``inf_j``.
    U : ndarray, shape (g,)
        Flow velocity on the Jacobian, ``A(D(t)) = A(D0) - t U``: real.
    P0 : tuple of Place
        The three places over ``E = 0`` (for a node at ``E = 0`` its two branches among them).
    slopes : tuple
        dw/dE at each of ``P0`` that is a branch of the node, None at a regular place.
    """

    frame: BodyFrame
    curve: object
    nums: tuple
    G: np.ndarray
    rdim: int
    Ainv: np.ndarray
    tau: np.ndarray
    theta: RiemannTheta
    Pinf: tuple
    Jinf: np.ndarray
    B: np.ndarray
    U: np.ndarray
    P0: tuple
    slopes: tuple

    @property
    def genus(self) -> int:
        return self.curve.genus

    @property
    def Bc(self) -> np.ndarray:
        """conj(B): eigenvector -> components of the Baker-Akhiezer function (``psi @ Bc``)."""
        return self.B.conj()

    def abel(self, points: Place | Sequence | Mapping) -> np.ndarray:
        """Abel map in the adapted normalized coordinates (see :meth:`thetasol.PlaneCurve.abel_map`)."""
        return self.curve.abel_map(points, normalized=False) @ self.Ainv.T


def parities(curve: SpectralCurve, nums: Sequence[Numerator]) -> np.ndarray:
    """Parity of each differential g dE / f_w under sigma: E^i w^j -> (-1)^(i+1)."""
    out = []
    for gn in nums:
        ps = {(-1) ** (i + 1) for i, _ in gn.monomials}
        if len(ps) != 1:
            raise RuntimeError(f"differential numerator {gn} has no definite parity under E -> -E")
        out.append(ps.pop())
    return np.array(out, float)


def adapted_periods(curve: SpectralCurve, nums: Sequence[Numerator]) -> tuple[np.ndarray, int, np.ndarray, np.ndarray]:
    """(G, rdim, Ainv, tau): the basis adapted to the real torus, its normalization and Riemann matrix."""
    g = curve.genus
    Pm = curve.period_matrix()
    G, rdim = real_flow_basis(Pm, parities(curve, nums))
    Pn = Pm @ G
    Ainv = np.linalg.inv(Pn[:, :g])
    tau = Ainv @ Pn[:, g:]
    return G, rdim, Ainv, 0.5 * (tau + tau.T)


def flow_velocity(curve: SpectralCurve, nums: Sequence[Numerator], Ainv: np.ndarray, rdim: int) -> np.ndarray:
    """U = A^-1 sum_j J_j omega(inf_j) / ds, checked real and zero beyond the torus (else inaccurate periods)."""
    g = curve.genus
    U = Ainv @ velocity_at_infinity(curve, nums)
    scaleU = np.abs(U).max()
    if np.abs(U.imag).max() > 1e-10 * scaleU or np.abs(U[rdim:]).max() > 1e-10 * scaleU:
        raise RuntimeError("the flow velocity is not real in the adapted basis: inaccurate periods")
    return np.concatenate([U[:rdim].real, np.zeros(g - rdim)])


def spectral_data(frame: BodyFrame) -> SpectralData:
    """Stage 1: the curve of the initial data, its adapted periods, ``U`` and the places over 0 and infinity."""
    curve = spectral_curve(np.diag(frame.Jp), frame.M0, frame.u0, tol=SNAP_TOL)
    nums = curve.holomorphic_numerators()
    G, rdim, Ainv, tau = adapted_periods(curve, nums)
    Pinf, Jinf, B = infinity_data(curve, curve.J2, curve.M)
    U = flow_velocity(curve, nums, Ainv, rdim)
    P0 = list(curve.places_over_zero())
    if len(P0) != 3:
        raise RuntimeError(f"expected three places over E = 0, found {len(P0)}")
    return SpectralData(frame=frame, curve=curve, nums=nums, G=G, rdim=rdim, Ainv=Ainv, tau=tau,
                        theta=RiemannTheta(tau), Pinf=tuple(Pinf), Jinf=Jinf, B=B, U=U, P0=tuple(P0),
                        slopes=node_branch_slopes(curve, P0))
