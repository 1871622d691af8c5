"""Stage 4a: the constants rho_k and the exponents c_k at t = 0, as Cauchy means.

At ``t = 0`` the theta quotient must give ``Psi_k(P, 0) = psi_k(P)``: this fixes
``rho_k(P) = psi_k(P) / theta(A(P) - e_k)``, and its t-derivative, ``psidot = -A(E, 0) psi`` (4.11),
fixes ``c_k(P)``.  At the places ``P_s`` over ``E = 0`` both are taken as means over a circle ``|E| = r``
around the place (``N_CIRCLE`` points; the Abel map there from the place along the radii by
``N_RAY``-point Gauss-Legendre): a component of the initial eigenvector that vanishes at ``P_s`` (a
removable 0/0, data aligned with principal axes) costs no accuracy.  The means at two radii are
compared in the diagnostics.  :func:`auxiliary_nu` adds exponents at points near the branch points,
where eigenvectors mix, for the fit of stage 4b.  The points (:func:`circle_rows`,
:func:`auxiliary_points`) and the means from theta's jets there (:func:`means_from_theta`,
:func:`auxiliary_nu`) are separate steps: stage 4 evaluates theta on all the points at once
(:func:`~.exponents._cauchy_data`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from thetasol.core.panels import gauss_legendre
from thetasol.mechanics.lax import lax_matrix, right_eigenvector
from thetasol.solutions.rotation.theta_rotation.divisors import EigenvectorDivisors
from thetasol.solutions.rotation.theta_rotation.node import lax_eigenvalues, local_branch, node_branch
from thetasol.solutions.rotation.theta_rotation.spectral_data import SpectralData

__all__ = ["N_CIRCLE", "N_RAY", "CauchyMeans", "auxiliary_points", "auxiliary_nu", "circle_points", "circle_rows",
           "means_from_theta"]

#: Points on the circles of the Cauchy means, and Gauss-Legendre nodes on their radii.
N_CIRCLE = 32
N_RAY = 16


@dataclass(frozen=True, eq=False)
class CauchyMeans:
    """Means over the circle ``|E| = radius`` around each place ``P_s`` over ``E = 0``.

    Attributes
    ----------
    X0 : ndarray, shape (3, 3)
        ``psi_k(P_s)`` as ``[k, s]``: the initial eigenvectors in the components of ``B``.
    rho : ndarray, shape (3, 3)
        ``rho_k(P_s) theta(d_k)`` as ``[s, k]``.
    nu : ndarray, shape (3, 3)
        The exponents' constants ``c_k(P_s)`` as ``[s, k]`` (imaginary for consistent data).
    """

    X0: np.ndarray
    rho: np.ndarray
    nu: np.ndarray


def circle_points(radius: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Ec (N,), Eq (N, n), wg (n,)): the points of a circle |E| = radius, the Gauss-Legendre nodes
    on its radii and their weights."""
    phis = 2 * np.pi * np.arange(N_CIRCLE) / N_CIRCLE
    Ec = radius * np.exp(1j * phis)
    xg, wg = gauss_legendre(N_RAY)
    return Ec, Ec[:, None] * (0.5 * (xg + 1))[None, :], wg.copy()


def circle_data(sd: SpectralData, s_: int, radius: float,
                eig: tuple | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points on a circle |E| = radius around the place P_s (over E = 0), their w, and the local
    Abel integrals from the place along the radii (Gauss-Legendre).  ``eig``: the eigenvalues of
    L at the nodes and at the points (:func:`circle_points`), which the three places share."""
    curve, place, slope = sd.curve, sd.P0[s_], sd.slopes[s_]
    Ec, Eq, wg = circle_points(radius)
    Wq, Wc = eig if eig is not None else (None, None)
    wq = local_branch(curve, place, slope, Eq, Wq)
    vals = curve.differential_values(sd.nums, Eq, wq)                # g dE / f_w over dE, (d, N, n)
    local = 0.5 * np.einsum("dnq,q->nd", vals * Ec[None, :, None], wg)   # (N, g_raw)
    wc = local_branch(curve, place, slope, Ec, Wc)
    return Ec, wc, local


def circle_rows(sd: SpectralData, dv: EigenvectorDivisors, radii) -> list[tuple]:
    """``(psi, dpsi, A)`` per radius and place ``P_s`` (``3 i + s``): eigenvector (components of ``B``),
    its t-derivative and the Abel images on the circle, (N_CIRCLE, 3) twice and (N_CIRCLE, g)."""
    curve = sd.curve
    Jp, M, u = sd.frame.Jp, curve.M, curve.u
    circles = []
    for radius in radii:
        Ec, Eq, _ = circle_points(radius)
        eig = (lax_eigenvalues(curve, Eq), lax_eigenvalues(curve, Ec))
        for s_ in range(3):
            Ec, wc, local = circle_data(sd, s_, radius, eig)
            if sd.slopes[s_] is not None:
                v = node_branch(curve, sd.slopes[s_], Ec, eig[1])[1]
            else:
                v = right_eigenvector(lax_matrix(Jp, M, u, Ec), wc)
            psi, dpsi = _normalized(sd, dv.alpha, Ec, v)
            circles.append((psi, dpsi, dv.AP0[s_][None, :] + local @ sd.Ainv.T))
    return circles


def means_from_theta(circles: list[tuple], jets: tuple, theta_d: tuple, U: np.ndarray) -> list[CauchyMeans]:
    """X0, rho and the exponents' constants at the places over E = 0 (module docstring), one
    :class:`CauchyMeans` per radius, from the circles (:func:`circle_rows`) and the separated jets
    ``(e, v, gradient)`` of theta at ``A - e_k`` on all of them, (n, 3) and (n, 3, g).
    ``theta_d = (ed, vd, dlog_d)``: theta at ``d_k`` (exponent, value) and its log-derivative along U."""
    ed_, vd_, dlog_d = theta_d
    eb_all, vb_all, gb_all = jets
    out, pos = [], 0
    for i in range(len(circles) // 3):
        X0 = np.zeros((3, 3), complex)
        rho = np.zeros((3, 3), complex)                  # rho_k(P_s) theta(d_k), [s, k]
        cst = np.zeros((3, 3), complex)
        for s_ in range(3):
            psi, dpsi, A_loc = circles[3 * i + s_]
            sl = slice(pos, pos + len(A_loc))
            pos += len(A_loc)
            eb, vb, gb = eb_all[sl], vb_all[sl], gb_all[sl]
            X0[:, s_] = psi.mean(axis=0)
            rho[s_] = (psi / vb * np.exp(ed_[None, :] - eb)).mean(axis=0) * vd_
            cst[s_] = (dpsi / psi - (gb @ U) / vb).mean(axis=0) + dlog_d
        out.append(CauchyMeans(X0=X0, rho=rho, nu=cst))
    return out


def auxiliary_points(sd: SpectralData, dv: EigenvectorDivisors) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The points of :func:`auxiliary_nu` (:func:`~.divisors.auxiliary_places`, Abel images from stage
    2): ``(psi, dpsi, A)``, eigenvector (components of ``B``), its t-derivative, (n, 3), and the Abel
    images (n, g)."""
    curve = sd.curve
    E, w = dv.aux_places
    Jp, M, u = sd.frame.Jp, curve.M, curve.u
    return (*_normalized(sd, dv.alpha, E, right_eigenvector(lax_matrix(Jp, M, u, E), w)), dv.A_aux)


def _normalized(sd: SpectralData, alpha: np.ndarray, E: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``psi = v / <alpha, v>`` and its t-derivative ``-(J E + W0) psi`` (4.11) at the points E, both in
    the components of ``B``."""
    psi = v / (v @ alpha)[:, None]
    dpsi = -np.einsum("nij,nj->ni", np.diag(sd.frame.Jp)[None] * E[:, None, None] + sd.frame.W0[None], psi) @ sd.Bc
    return psi @ sd.Bc, dpsi


def auxiliary_nu(rows: tuple, jets: tuple, U: np.ndarray, dlog_d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exponent constants nu(P, k) at points P where eigenvectors mix (near branch points), from the
    points of :func:`auxiliary_points` and the separated jets ``(e, v, gradient)`` of theta at
    ``A - e_k`` there, (n, 3) and (n, 3, g).  Returns (nu (n, 3), relative component sizes
    |psi_k| / |psi| (n, 3))."""
    psi, dpsi, _ = rows
    _, vb, gb = jets
    nu = dpsi / psi - (gb @ U) / vb + dlog_d[None, :]
    return nu, np.abs(psi) / np.linalg.norm(psi, axis=1, keepdims=True)
