"""Stage 3: the Riemann constant and the shifts of the theta quotients.

The components of the Baker-Akhiezer function are theta quotients (docs/theta_rotation.md)::

    Psi_k(P, t) = rho_k(P) exp(c_k(P) t) theta(A(P) + t U - e_k) theta(d_k) / theta(d_k + t U),
    e_k = A(D0) - sum_{j != k} A(inf_j) + K,        d_k = A(inf_k) - e_k.

For distinct ``J`` no Abel image at infinity is used (for a nearly symmetric body ``inf_1``, ``inf_2``
sit in a cluster of branch points): ``div(psi_k)`` gives ``e_k = A(Z_k) + K`` and ``div(E) = sum_s P_s -
sum_j inf_j`` gives ``d_k = sum_s A(P_s) - A(D0) - K``.  ``K`` comes from a canonical divisor made of
regular places: ``2 (P_1 + P_2 + P_3)``, the divisor of ``E^2 dE / f_w``, when there is no node, else
that of ``E dE / f_w`` (the regular places over ``E = 0`` and the places at infinity), with Riemann's
vanishing theorem choosing among the half-period candidates (the library's one rule,
:mod:`thetasol.curves.riemann_constant`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from thetasol.curves.plane_curve import Numerator
from thetasol.curves.riemann_constant import riemann_constant_vector, test_abscissae
from thetasol.mechanics.lax import lax_matrix
from thetasol.solutions.rotation.theta_rotation.divisors import EigenvectorDivisors
from thetasol.solutions.rotation.theta_rotation.lattice import reduce_lattice
from thetasol.solutions.rotation.theta_rotation.spectral_data import SpectralData

if TYPE_CHECKING:
    from thetasol.curves.plane_curve import Place

__all__ = ["ThetaShifts", "theta_shifts"]

@dataclass(frozen=True, eq=False)
class ThetaShifts:
    """The Riemann constant and the shifts of the theta quotients (stage 3).

    Attributes
    ----------
    K : ndarray, shape (g,)
        Vector of Riemann constants (adapted normalized coordinates, the curve's base point).
    canonical_degree : int
        Degree of the canonical divisor used (``2g - 2``).
    e : ndarray, shape (3, g)
        ``e_k`` reduced modulo the lattice: the numerators are ``theta(A(P) + t U - e_k)``.
    d : ndarray, shape (g,)
        ``d_k = A(inf_k) - e_k`` reduced, the same for every k (``sum_s A(P_s) - A(D0) - K``, module
        docstring): the denominators are ``theta(d + t U)``.
    """

    K: np.ndarray
    canonical_degree: int
    e: np.ndarray
    d: np.ndarray


def zero_order(Pl: Place, numerator: Numerator) -> int:
    """Order of vanishing of numerator dE / f_w at the place (from its expansion).

    A coefficient is significant against the largest term c_k t0^k on the sampling circle
    |t| = |t0| (:attr:`thetasol.curves.plane_curve.Place.sampling_radius`), not against the largest
    c_k: near a tacnode (a symmetric body with little axial spin) two branch points sit at
    |E| ~ 1 / spin, the series in t = 1/E converges only for |t| < ~spin and c_k grows like spin^-k.
    """
    k, c = Pl.expand(numerator, order=4)
    t0 = Pl.sampling_radius
    F = np.abs(c) * t0 ** k.astype(float)
    sig = F > 1e-10 * F.max()
    return int(k[np.argmax(sig)])


def canonical_divisor(sd: SpectralData) -> dict:
    """A canonical divisor {place: order} made of places away from branch-point clusters (module doc).

    Orders 0 (the node's branches over infinity of a symmetric body, whose series carry the noise of
    ``E^2 - w / J_1^2`` cancelling on ``w ~ J_1^2 E^2``) are left out: no Abel image is needed there.
    """
    curve, g = sd.curve, sd.genus
    P0_reg = [Pl for Pl, slope in zip(sd.P0, sd.slopes, strict=True) if slope is None]
    if curve.node is None and not curve.symmetric_body:
        canon = {Pl: 2 for Pl in P0_reg}
    else:
        # E dE / f_w: simple zeros at the regular places over E = 0 (none at the node's branches)
        # and at the places at infinity (simple for distinct J; at a node read off the expansion)
        canon = {Pl: 1 for Pl in P0_reg}
        for Pl in sd.Pinf:
            canon[Pl] = 1 if not curve.symmetric_body else zero_order(Pl, Numerator.monomial(1, 0))   # E
    if sum(canon.values()) != 2 * g - 2:
        raise RuntimeError(f"canonical divisor of E dE / f_w of degree {sum(canon.values())} on genus {g} "
                           "(orders read off the expansions at infinity; internal error)")
    return {Pl: m for Pl, m in canon.items() if m != 0}


def riemann_constant(sd: SpectralData, canon: dict, dv: EigenvectorDivisors | None = None) -> np.ndarray:
    """Vector of Riemann constants K in the adapted normalized coordinates, the curve's base point.

    2K = -A(C) for the canonical divisor C (``canon``, place -> order, :func:`canonical_divisor`), and the
    half period by the rule of :func:`thetasol.curves.riemann_constant.riemann_constant_vector`.  With
    ``dv`` the test divisors are first made of the points of stage 2 (the poles ``D0`` and zeros ``Z_k``,
    whose Abel images are known) and the places over ``E = 0`` reuse stage 2's images; when they do not
    decide, three divisors of the fixed table of test points do (:func:`_table_divisor_constant`).  Only
    regular places are involved, so clustered branch points do not matter.
    """
    g = sd.genus
    if dv is None or g < 2 or len(dv.A_points) < 2 * (g - 1):
        return _table_divisor_constant(sd, canon)
    known = {Pl: i for i, Pl in enumerate(sd.P0)}
    rest = [Pl for Pl in canon if Pl not in known]
    A_rest = iter(sd.abel(rest)) if rest else iter(())
    rows = np.array([dv.AP0_raw[known[Pl]] if Pl in known else next(A_rest) for Pl in canon])
    AC = np.array([canon[P] for P in canon], float) @ rows
    n = min(3, len(dv.A_points) // (g - 1))
    K = riemann_constant_vector(sd.theta.tau, AC, dv.A_points[:n * (g - 1)].reshape(n, g - 1, g).sum(axis=1),
                                theta=sd.theta, final=False)
    return _table_divisor_constant(sd, canon) if K is None else K


def _table_divisor_constant(sd: SpectralData, canon: dict) -> np.ndarray:
    """:func:`riemann_constant` tested on three effective divisors of degree g - 1 in general position
    (:func:`thetasol.curves.riemann_constant.test_abscissae`, each ``E`` lifted to the eigenvalue ``w`` of
    the listed index)."""
    th, curve = sd.theta, sd.curve
    Jp, M, u = sd.frame.Jp, curve.M, curve.u
    g = th.g
    places = list(canon)
    scale = float(np.abs(np.asarray(curve.branch_points)).max())
    E, sheet = test_abscissae(0.0, scale, g - 1)
    pts = [(e, np.linalg.eigvals(lax_matrix(Jp, M, u, e))[k]) for e, k in zip(E.ravel(), sheet.ravel(), strict=True)]
    A_all = sd.abel(places + pts)                       # one call: the paths are planned together
    AC = np.array([canon[P] for P in places], float) @ A_all[:len(places)]
    return riemann_constant_vector(th.tau, AC, A_all[len(places):].reshape(3, g - 1, g).sum(axis=1), theta=th)


def theta_shifts(sd: SpectralData, dv: EigenvectorDivisors) -> ThetaShifts:
    """Stage 3: ``K``, ``e_k`` and ``d_k`` (module docstring).

    Where a zero of ``v_k`` runs off towards infinity (``v_3`` of a nearly symmetric body has one at
    ``E ~ 1 / (J_2 - J_1)``) or sits at a place over ``E = 0``, ``e_k = A(D0) - sum_s A(P_s) + A(inf_k)
    + K`` is used instead: ``inf_k`` is then the place away from the cluster.
    """
    canon = canonical_divisor(sd)
    K = riemann_constant(sd, canon, dv)
    tau, g = sd.tau, sd.genus
    e = np.empty((3, g), complex)
    for k in range(3):
        if dv.AZ[k] is not None:
            e[k] = reduce_lattice(dv.AZ[k] + K, tau)
        else:
            e[k] = reduce_lattice(dv.AD0 - dv.AP0.sum(axis=0) + sd.abel([sd.Pinf[k]])[0] + K, tau)
    d = reduce_lattice(dv.AP0.sum(axis=0) - dv.AD0 - K, tau)
    return ThetaShifts(K=K, canonical_degree=int(sum(canon.values())), e=e, d=d)
