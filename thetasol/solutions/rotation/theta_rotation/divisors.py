"""Stage 2: the divisors of the eigenvector and of its components, and their Abel images.

For a point ``P = (E, w)`` of the curve (4.12) let ``psi(P)`` be the eigenvector of ``L(E, 0)`` with
``<alpha, psi> = 1``.  Its poles form a divisor ``D0`` of degree ``g + 2``; the component ``psi_k``
vanishes at ``inf_j`` (``j != k``) and at ``g`` finite points ``Z_k`` (the zeros of the k-th component
of the unnormalized eigenvector ``v``), so ``div(psi_k) = Z_k + sum_{j != k} inf_j - D0``.  The theta
shifts of stage 3 need ``A(D0)``, ``A(Z_k)`` and the Abel images ``A(P_s)`` of the places over
``E = 0``; these are computed here in one Abel-map call, whose paths are planned together.

``A(D0)`` does not depend on ``alpha`` (pole divisors for two normalizations differ by the divisor of
``<alpha', v> / <alpha, v>``): it is taken for the normalization whose divisor keeps farthest from the
branch points and from infinity, where Abel images lose accuracy.  The divisor points come from
``np.roots`` a few ulps off and are polished by Newton steps (next to a tight pair of branch points the
unpolished points moved the Abel images by up to 6e-11).  At a node over ``E = 0`` every ``<alpha, v>``
vanishes (a base point): on the normalization it cancels in ``psi_k = v_k / <alpha, v>`` and is dropped.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from thetasol.mechanics.lax import eigenvector_poles, lax_matrix, polish_eigenvector_poles, right_eigenvector
from thetasol.solutions.rotation.theta_rotation._directions import ALPHA_CANDIDATES, DIVISOR_CANDIDATES
from thetasol.solutions.rotation.theta_rotation.lattice import reduce_lattice
from thetasol.solutions.rotation.theta_rotation.spectral_data import SpectralData

if TYPE_CHECKING:
    from thetasol.curves.spectral import SpectralCurve

__all__ = ["EigenvectorDivisors", "auxiliary_places", "eigenvector_divisors"]


@dataclass(frozen=True, eq=False)
class EigenvectorDivisors:
    """Abel images of the eigenvector's divisors (stage 2).

    Attributes
    ----------
    alpha : ndarray, shape (3,)
        The normalization vector of ``psi`` (principal frame).
    AD0 : ndarray, shape (g,)
        ``A(D0)``, the Abel image of the pole divisor of ``psi`` (any normalization: see the module).
    AP0 : ndarray, shape (3, g)
        ``A(P_s)`` of the places over ``E = 0``, reduced modulo the lattice.
    AZ : tuple of (ndarray or None)
        ``A(Z_k)``; None where a zero of ``v_k`` runs off towards infinity or has no ``w`` of its own
        (stage 3 then uses ``div(E)`` and ``A(inf_k)``).
    radius : float
        Radius of the Cauchy circles of stage 4 (:func:`circle_radius`).
    AP0_raw : ndarray, shape (3, g)
        ``A(P_s)`` as computed (not reduced): the canonical divisor of stage 3 is made of these.
    A_points : ndarray, shape (n, g)
        The Abel images of the single points of ``D0`` and of the ``Z_k`` used: stage 3 tests the
        Riemann constant on divisors made of them.
    aux_places : tuple of ndarray
        ``(E, w)`` of the auxiliary points of stage 4 (:func:`auxiliary_places`).
    A_aux : ndarray, shape (n, g)
        Their Abel images (in the same call as the divisors': cheaper than a call of their own).
    """

    alpha: np.ndarray
    AD0: np.ndarray
    AP0: np.ndarray
    AZ: tuple
    radius: float
    AP0_raw: np.ndarray
    A_points: np.ndarray
    aux_places: tuple
    A_aux: np.ndarray


def choose_alpha(X: np.ndarray) -> np.ndarray:
    """A normalization vector far from orthogonal to the columns of X and to the axes."""
    best, score = None, -1.0
    cands = [np.array([1.0, 2 ** 0.5, 3 ** 0.5])] + [np.array(c) for c in ALPHA_CANDIDATES]
    Xn = X / np.linalg.norm(X, axis=0, keepdims=True)
    for c in cands:
        c = c / np.linalg.norm(c)
        sc = min(np.min(np.abs(c)), np.min(np.abs(c @ Xn)))
        if sc > score:
            best, score = c, sc
    return best


def abel_friendly_divisor(Jp: np.ndarray, M: np.ndarray, u: np.ndarray, alpha: np.ndarray, bp: np.ndarray,
                          degree: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pole divisor (E, w, alpha') of the eigenvector for the normalization vector alpha', among alpha
    and fixed ones (:mod:`._directions`), whose points are farthest from the branch points and all within 10 |bp|max of E = 0."""
    R = float(np.abs(bp).max())
    best, score = None, -np.inf
    for c in [alpha] + [np.array(c) for c in DIVISOR_CANDIDATES]:
        E, w = eigenvector_poles(Jp, M, u, c)
        if len(E) != degree or not np.all(np.isfinite(w)):
            continue
        sc = np.min(np.abs(E[:, None] - bp[None, :])) / R if np.abs(E).max() <= 10.0 * R else -1.0
        if sc > score:
            best, score = (E, w, c), sc
    if best is None:
        raise RuntimeError("no normalization vector gives a finite eigenvector divisor")
    return best


def drop_node_point(Ez: np.ndarray, wz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The points of an eigenvector divisor on the normalization: the one at the node E = 0 removed."""
    k = int(np.argmin(np.abs(Ez)))
    if abs(Ez[k]) > 1e-8 * (1 + np.abs(Ez).max()):
        raise RuntimeError("expected the eigenvector divisor to pass through the node")
    return np.delete(Ez, k), np.delete(wz, k)


def circle_radius(curve: SpectralCurve, E_poles: np.ndarray, E_zeros: np.ndarray) -> float:
    """Radius of the Cauchy circles around E = 0.

    The poles of rho_k (the divisor D0) and the branch points must lie outside, with margin 3
    (trapezoidal error ~ 3^-N); the zeros of the eigenvector components, whose poles cancel only to
    rounding between the two terms of the mean, must not lie near the circle.  Among radii
    r_max 2^-j the one farthest (in log scale) from those zeros is taken.  The node's eigenvectors
    (:func:`~thetasol.solutions.rotation.theta_rotation.node.node_branch`) are accurate at every radius.
    """
    bp = np.abs(np.asarray(curve.branch_points))
    far = np.concatenate([bp[bp > 0], np.abs(E_poles[np.abs(E_poles) > 0])])
    r_max = float(far.min()) / 3.0
    zeros = np.abs(E_zeros[np.isfinite(E_zeros)])
    zeros = zeros[zeros > 0]
    best, margin = r_max, -np.inf
    for j in range(8):
        r = r_max * 2.0 ** -j
        m = np.min(np.abs(np.log(zeros / r))) if zeros.size else np.inf
        if m > margin + 0.3:           # prefer larger radii unless clearly better placed
            best, margin = r, m
    return best


def _pole_divisors(sd: SpectralData):
    """(alpha, poles E of psi, the divisor D0 (E, w, alpha') whose Abel image is taken)."""
    curve, Jp, g = sd.curve, sd.frame.Jp, sd.genus
    M, u = curve.M, curve.u
    Xtmp = np.column_stack([right_eigenvector(u, Pl.y) if slope is None else np.ones(3)
                            for Pl, slope in zip(sd.P0, sd.slopes, strict=True)])
    alpha = choose_alpha(Xtmp)
    Ed, wd = eigenvector_poles(Jp, M, u, alpha)
    if curve.node is not None:
        Ed, wd = drop_node_point(Ed, wd)
    if len(Ed) != g + 2:
        raise RuntimeError(f"eigenvector divisor of degree {len(Ed)}, expected g + 2 = {g + 2}")
    if curve.node is None:
        D0 = abel_friendly_divisor(Jp, M, u, alpha, np.asarray(curve.branch_points), g + 2)
    else:
        D0 = (Ed, wd, alpha)
    return alpha, Ed, D0


def _component_zeros(sd: SpectralData, Ed: np.ndarray):
    """(zeros (E, w) of each component v_k, whether A(Z_k) is used, the Cauchy radius)."""
    curve, Jp, g = sd.curve, sd.frame.Jp, sd.genus
    M, u = curve.M, curve.u
    # components in B (alpha = conj(b_k)) for a symmetric body, the axes otherwise
    comp_alpha = [sd.Bc[:, k] if curve.symmetric_body else np.eye(3)[k] for k in range(3)]
    comp_zeros = [eigenvector_poles(Jp, M, u, al) for al in comp_alpha]
    r = circle_radius(curve, Ed, np.concatenate([Ez for Ez, _ in comp_zeros]))
    if curve.node is not None:
        comp_zeros = [drop_node_point(Ez, wz) for Ez, wz in comp_zeros]   # Z_k keeps g points
    R = float(np.abs(curve.branch_points).max())
    # A zero without a w (NaN) is where v_k vanishes on two sheets at once: the axis e_k is an
    # eigenvector of u, and the zeros sit at places over E = 0
    use_zeros = [len(Ez) == g and np.abs(Ez).max() <= 10.0 * R and np.all(np.isfinite(wz))
                 for Ez, wz in comp_zeros]
    for k in range(3):
        if use_zeros[k]:
            comp_zeros[k] = polish_eigenvector_poles(Jp, M, u, comp_alpha[k], *comp_zeros[k])
    return comp_zeros, use_zeros, r


def auxiliary_places(sd: SpectralData) -> tuple[np.ndarray, np.ndarray]:
    """``(E, w)`` (n,): points near the branch points where eigenvectors mix, one per pair of components
    (the largest second-largest component among trial points), for the auxiliary rows of stage 4
    (:func:`~.cauchy.auxiliary_nu`).  Chosen here so that their Abel images come with the divisors'
    in one Abel-map call."""
    curve, Bc = sd.curve, sd.Bc
    Jp, M, u = sd.frame.Jp, curve.M, curve.u
    bp = np.asarray(curve.branch_points)
    scale = float(np.abs(bp).max())
    R = float(np.abs(bp)[np.abs(bp) > 1e-8 * scale].min())   # a branch point may sit at E = 0 (rank-one a)
    trial = [0.35 * R * np.exp(1j * ang) for ang in (0.3, 1.1, 1.9, 2.7)]
    # Far branch points (|E| ~ 1/(J_2 - J_1) for nearly symmetric bodies) are where L ~ J^2 E^2 and
    # eigenvectors lose accuracy: use the core of the set only.
    # (the median as np.median computes it, without its import of numpy.ma, a cost on a first set-up)
    r = np.sort(np.abs(bp))
    med = r[len(r) // 2] if len(r) % 2 else (r[len(r) // 2 - 1] + r[len(r) // 2]) / 2
    core = bp[np.abs(bp) <= 10.0 * med]
    for b in core:
        sep = np.abs(bp - b)
        sep = min(sep[sep > 0].min(), abs(b))
        if sep <= 1e-8 * scale:
            continue                        # a branch point at E = 0 (rank-one a): a singular point
        trial += [b + 0.25 * sep * np.exp(1j * ang) for ang in (0.4, 2.5, 4.6)]
    cands = {}
    # every eigenvector of every trial point in one batched call (the same operations per point)
    Et = np.array(trial)
    Lt = lax_matrix(Jp, M, u, Et)
    Wt = np.linalg.eigvals(Lt)
    Vt = right_eigenvector(np.broadcast_to(Lt[:, None], (len(Et), 3, 3, 3)), Wt)
    for E, ws, vs in zip(trial, Wt, Vt, strict=True):
        for w, v in zip(ws, vs, strict=True):
            v = v @ Bc
            h = np.abs(v) / np.linalg.norm(v)
            order = np.argsort(h)
            pair = tuple(sorted(order[1:]))
            if h[order[1]] > cands.get(pair, (0.0,))[0]:
                cands[pair] = (h[order[1]], E, w)
    pts = sorted(cands.values(), key=lambda c: -c[0])
    E = np.array([c[1] for c in pts])
    w = np.array([c[2] for c in pts])
    return E, w


def eigenvector_divisors(sd: SpectralData) -> EigenvectorDivisors:
    """Stage 2: ``alpha``, ``A(D0)``, ``A(P_s)`` and ``A(Z_k)`` (module docstring)."""
    curve, g = sd.curve, sd.genus
    alpha, Ed, (D_E, D_w, D_alpha) = _pole_divisors(sd)
    comp_zeros, use_zeros, r = _component_zeros(sd, Ed)
    D_E, D_w = polish_eigenvector_poles(sd.frame.Jp, curve.M, curve.u, D_alpha, D_E, D_w)
    batch = [(complex(x), complex(y)) for x, y in zip(D_E, D_w, strict=True)] + list(sd.P0)
    for (Ez, wz), use in zip(comp_zeros, use_zeros, strict=True):
        if use:
            batch += [(complex(x), complex(y)) for x, y in zip(Ez, wz, strict=True)]
    E_aux, w_aux = auxiliary_places(sd)
    batch += [(complex(a_), complex(b_)) for a_, b_ in zip(E_aux, w_aux, strict=True)]
    A_all = sd.abel(batch)
    A_aux, A_all = A_all[len(A_all) - len(E_aux):], A_all[:len(A_all) - len(E_aux)]
    nD = len(D_E)
    AD0 = A_all[:nD].sum(axis=0)
    AP0 = np.array([reduce_lattice(v, sd.tau) for v in A_all[nD:nD + 3]])
    AZ, pos = [None] * 3, nD + 3
    for k, use in enumerate(use_zeros):
        if use:
            AZ[k], pos = A_all[pos:pos + g].sum(axis=0), pos + g
    return EigenvectorDivisors(alpha=alpha, AD0=AD0, AP0=AP0, AZ=tuple(AZ), radius=r,
                               AP0_raw=A_all[nD:nD + 3], A_points=np.concatenate([A_all[:nD], A_all[nD + 3:]]),
                               aux_places=(E_aux, w_aux), A_aux=A_aux)
