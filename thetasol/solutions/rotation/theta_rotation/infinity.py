"""The places of the spectral curve (4.12) over E = infinity and the flow velocity U there.

At the place ``inf_j`` (``w / E^2 -> J_j^2``) the Baker-Akhiezer function has its essential singularity
``exp(-J_j E t)``; the flow on the Jacobian has the velocity ``U = sum_j J_j omega(inf_j) / ds``
(``s = 1/E``), the residue theorem for the normalized second-kind differential with principal parts
``-J_j dE``.  Both are given here in closed form where the expansions at infinity lose accuracy.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from thetasol.curves.plane_curve import Numerator, Place
    from thetasol.curves.spectral import SpectralCurve

__all__ = ["infinity_data", "velocity_at_infinity"]


def infinity_data(curve: SpectralCurve, J2: np.ndarray, M: np.ndarray) -> tuple[list[Place], np.ndarray, np.ndarray]:
    """The places over E = infinity with J_j (w / E^2 -> J_j^2) and the eigenvector b_j of L there.

    b_j spans the eigenspace of J^2 for J_j^2 when it is simple (a coordinate axis); for a symmetric
    body the node at infinity has two branches w = J_1^2 E^2 + mu E + ..., and b_j is the eigenvector
    of M compressed to that eigenspace with eigenvalue mu ((e1 +- i e2) / sqrt 2).  B = [b_1 b_2 b_3]
    is unitary and the components of the Baker-Akhiezer function are taken in it, so that at inf_j
    only the j-th component survives.
    """
    places = list(curve.places_at_infinity())
    if len(places) != 3:
        raise RuntimeError(f"expected three places over E = infinity, found {len(places)}")
    if not curve.symmetric_body:
        # ordered by j with w / E^2 -> J2[j] (J2 ascending): the coordinate axes, exactly
        return [curve.place_at_infinity(j) for j in range(3)], np.sqrt(J2), np.eye(3, dtype=complex)
    Js, bs = [], []
    for Pl in places:
        k, c = Pl.series(order=4)
        lam0 = complex(c[k == -2][0]) if np.any(k == -2) else 0.0
        lam1 = complex(c[k == -1][0]) if np.any(k == -1) else 0.0
        idx = np.flatnonzero(np.abs(J2 - lam0.real) <= 1e-8 * J2.max())
        if len(idx) == 1:
            b = np.eye(3)[idx[0]].astype(complex)
        elif len(idx) == 2:
            W = np.eye(3)[:, idx]
            mu, V = np.linalg.eig(W.T @ M @ W)
            b = W @ V[:, int(np.argmin(np.abs(mu - lam1)))]
            b = b / np.linalg.norm(b)
        else:
            raise RuntimeError(f"cannot label the place at infinity with w / E^2 -> {lam0}")
        Js.append(np.sqrt(lam0.real))
        bs.append(b)
    B = np.column_stack(bs)
    if np.abs(B.conj().T @ B - np.eye(3)).max() > 1e-8:
        raise RuntimeError("eigenvectors at infinity are not orthonormal")
    return places, np.array(Js), B


def velocity_at_infinity(curve: SpectralCurve, nums: Sequence[Numerator]) -> np.ndarray:
    """sum_j J_j omega_i / ds at the places over E = infinity (s = 1/E), omega_i = g_i dE / f_w.

    Distinct J_j: in closed form.  f = lc prod_l (w - w_l) with w_l = x_l E^2 + O(E), x_l = J_l^2, so
    omega_i / ds (inf_j) = -h_i(x_j) / (lc prod_{l != j} (x_j - x_l)), where only the weight-2 part
    h_i(x) = alpha_i + beta_i x of g_i (its E^2 and w coefficients) survives at s = 0.  The sum over j
    weighted by J_j = sqrt(x_j) is the second divided difference of sqrt(x) h_i(x):

        sum_j J_j omega_i / ds (inf_j) = -(beta_i e2 - alpha_i) / (lc (J1 + J2)(J1 + J3)(J2 + J3)),

    e2 = J1 J2 + J1 J3 + J2 J3.  The terms of the sum grow like 1 / (J_1 - J_2) for a nearly
    symmetric body and cancel (the plain sum loses about log10(J_1 / (J_2 - J_1)) digits of U); the
    divided difference does not.

    Symmetric body (x_a = x_b = x_p at the node's two branches, x_s at the third place): the g_i
    have degree <= 1 in w, so by Euler-Jacobi sum_l g_i(E, w_l) / f_w(E, w_l) = 0 for every E and
    the t^0 coefficients at the three places add up to 0; the sum is (J_s - J_p) times the
    coefficient at inf_s, which has the closed form above:

        sum_j J_j omega_i / ds (inf_j) = -h_i(x_s) / (lc (J_s + J_p)(x_s - x_p)).

    The expansions at the node's branches are not used: their coefficients grow like spin^-k
    (branch points at |E| ~ 1 / spin, the axial spin), so the FFT would lose digits of the t^0 sum at
    small spins, a rate error of U.
    """
    lc = float(curve.coefficients[0, -1])               # the w^3 term of det(L(E) - w): -1, for every E
    x = np.asarray(curve.J2, float)                     # exact J_j^2 (snapped), not read off the places
    # the weight-2 part of each numerator: its E^2 and w coefficients (complex: on a symmetric body's
    # normalization the differentials come from the adjoint conditions)
    h = []
    for gnum in nums:
        if max(j for _, j in gnum.monomials) > 1:
            raise RuntimeError(f"holomorphic differential {gnum} of degree > 1 in w (internal error)")
        h.append((gnum.coefficient(2, 0), gnum.coefficient(0, 1)))
    if curve.symmetric_body:
        s_ = [i for i in range(3) if np.sum(x == x[i]) == 1]
        if len(s_) != 1:
            raise RuntimeError(f"symmetric body without a single distinct J^2 ({x}; internal error)")
        xs, xp = x[s_[0]], x[(s_[0] + 1) % 3]
        den = lc * (np.sqrt(xs) + np.sqrt(xp)) * (xs - xp)
        return np.array([-(alpha + beta * xs) / den for alpha, beta in h])
    J = np.sqrt(x)
    e2 = J[0] * J[1] + J[0] * J[2] + J[1] * J[2]
    den = lc * (J[0] + J[1]) * (J[0] + J[2]) * (J[1] + J[2])
    return np.array([-(beta.real * e2 - alpha.real) / den for alpha, beta in h])
