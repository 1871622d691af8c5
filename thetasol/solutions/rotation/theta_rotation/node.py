"""The node of a rank-one potential over E = 0: its branches, their slopes and eigenvectors.

For ``a`` with a repeated eigenvalue ``lam`` (the gravity gradient of Section 7) the curve (4.12) has a
node at ``(E, w) = (0, lam)``; its two branches ``w = lam + mu E + ...`` are two of the three places over
``E = 0`` on the genus-3 normalization.  There ``L(E) - w`` has two rows parallel to ``O(E)``, so the
float64 eigenvalue and eigenvector of ``L(E)`` lose ``eps / |E|``; :func:`node_branch` solves a scaled
eigenproblem accurate to eps instead.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from thetasol.mechanics.lax import lax_matrix, right_eigenvector

if TYPE_CHECKING:
    from thetasol.curves.plane_curve import Place
    from thetasol.curves.spectral import SpectralCurve

__all__ = ["node_branch", "lax_eigenvalues", "nearest_eigenvalue", "node_slopes", "local_branch", "node_branch_slopes"]


def node_branch(curve: SpectralCurve, slope: complex, Es: np.ndarray,
                W: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(w, unit right eigenvector) on the node branch of slope ``slope`` at the small values Es
    (``W``: :func:`lax_eigenvalues` at Es if already known).

    There L(E) - w = (u - lam) + E (M - (w - lam) / E) + E^2 J^2 has two rows parallel to O(E): its
    null vector and eigenvalue taken from L(E) in float64 carry ~eps |L| / (|mu_1 - mu_2| |E|) (1e-13
    on circles of radius 1e-2 around the node).  In the frame T = [k_1, k_2, n] of u (u - lam = lam_n n n^T)
    with v = T (y_1, y_2, E y_3) and w = lam + E x the rows divided by E are O(1):
    X(x) = [[M' + E J2' - x]_kk, E (M' + E J2')_kn; (M' + E J2')_nk, lam_n + E (M' - x + E J2')_nn],
    whose root x (Newton on det X from the float64 eigenvalue) and null vector y are accurate to eps.
    """
    lam, V = np.linalg.eigh(curve.u)
    lb = curve.node[1]
    order = np.argsort(np.abs(lam - lb))
    T = V[:, order]
    lam_n = lam[order[2]] - lb
    Mp = T.T @ curve.M @ T
    J2p = T.T @ np.diag(np.asarray(curve.J2, float)) @ T
    Ev = np.asarray(Es, complex)
    A = Mp + Ev[..., None, None] * J2p                                 # (..., 3, 3)
    X0 = A.copy()
    X0[..., :2, 2] *= Ev[..., None]
    X0[..., 2, 2] = lam_n + Ev * A[..., 2, 2]
    dX = -np.stack([np.ones_like(Ev), np.ones_like(Ev), Ev], -1)          # d X / dx, diagonal
    x = (nearest_eigenvalue(curve, Ev, lb + slope * Ev, W) - lb) / Ev    # the branch, to ~eps / |E|
    for _ in range(8):
        X = X0 + dX[..., :, None] * np.eye(3) * x[..., None, None]
        minors = np.stack([X[..., 1, 1] * X[..., 2, 2] - X[..., 1, 2] * X[..., 2, 1],
                           X[..., 0, 0] * X[..., 2, 2] - X[..., 0, 2] * X[..., 2, 0],
                           X[..., 0, 0] * X[..., 1, 1] - X[..., 0, 1] * X[..., 1, 0]], -1)
        step = np.linalg.det(X) / (minors * dX).sum(-1)
        x = x - step
        if np.all(np.abs(step) <= 4 * np.finfo(float).eps * (1 + np.abs(x))):
            break
    X = X0 + dX[..., :, None] * np.eye(3) * x[..., None, None]
    y = right_eigenvector(X, np.zeros(x.shape))
    v = np.einsum("ij,...j->...i", T, y * np.stack([np.ones_like(Ev), np.ones_like(Ev), Ev], -1))
    return lb + Ev * x, v / np.linalg.norm(v, axis=-1, keepdims=True)


def lax_eigenvalues(curve: SpectralCurve, Es: np.ndarray) -> np.ndarray:
    """The eigenvalues of L(Es) (float64; shape ``Es.shape + (3,)``)."""
    return np.linalg.eigvals(lax_matrix(np.sqrt(curve.J2), curve.M, curve.u, Es))


def nearest_eigenvalue(curve: SpectralCurve, Es: np.ndarray, target: np.ndarray,
                       W: np.ndarray | None = None) -> np.ndarray:
    """The eigenvalue of L(Es) nearest to ``target`` (float64; same shape as Es); ``W`` the
    eigenvalues (:func:`lax_eigenvalues`) if already known."""
    W = lax_eigenvalues(curve, Es) if W is None else W
    idx = np.argmin(np.abs(W - target[..., None]), axis=-1)
    return np.take_along_axis(W, idx[..., None], axis=-1)[..., 0]


def node_slopes(curve: SpectralCurve) -> np.ndarray:
    """dw/dE on the node's two branches: the eigenvalues of M compressed to the 2D eigenspace of u."""
    lam, V = np.linalg.eigh(curve.u)
    lb = curve.node[1]
    idx = np.argsort(np.abs(lam - lb))[:2]
    W2 = V[:, idx]
    mu = np.linalg.eigvals(W2.T @ curve.M @ W2)
    return mu


def local_branch(curve: SpectralCurve, place: Place, slope: complex | None, Es: np.ndarray,
                 W: np.ndarray | None = None) -> np.ndarray:
    """w on the branch of ``place`` (over E = 0) at the small values Es (same shape).

    ``slope`` is dw/dE at a node's branch (:func:`node_slopes`; the scaled eigenproblem of
    :func:`node_branch`), None at a regular place (the eigenvalue of L(E) nearest to its w).
    ``W``: :func:`lax_eigenvalues` at Es if already known (the three places share the points).
    """
    if slope is not None:
        return node_branch(curve, slope, Es, W)[0]
    return nearest_eigenvalue(curve, Es, np.full(np.shape(Es), complex(place.y)), W)


def node_branch_slopes(curve: SpectralCurve, places: Sequence[Place]) -> tuple:
    """dw/dE for each of ``places`` (over E = 0): the slope at a branch of the node, None elsewhere.

    The node's two branches are told apart by the first-order coefficient of their series
    ``w = lambda + mu E + ...``, matched to the eigenvalues ``mu`` of :func:`node_slopes`.
    """
    if curve.node is None:
        return tuple(None for _ in places)
    lb = curve.node[1]
    branches = [i for i, Pl in enumerate(places) if abs(Pl.y - lb) <= 1e-6 * (1 + abs(lb))]
    if len(branches) != 2:
        raise RuntimeError(f"expected two branches over the node, found {len(branches)}")
    out = [None] * len(places)
    for m in node_slopes(curve):
        best = None
        for i in branches:
            if out[i] is not None:
                continue
            k, c = places[i].series(order=2)
            c1 = c[k == 1][0] if np.any(k == 1) else 0.0
            dist = abs(c1 - m)
            if best is None or dist < best[0]:
                best = (dist, i)
        out[best[1]] = m
    return tuple(out)
