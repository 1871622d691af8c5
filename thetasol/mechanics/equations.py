"""Equations of motion and first integrals of one effective rigid body (Section 4).

Conventions (fixed once; docs/conventions.md, tested against point masses):

* ``J`` second moments ``sum m r r^T`` in the body frame, inertia ``I = tr(J) 1 - J``;
* ``Q`` maps body to space (``x = Q r + q``), ``omega`` is the body angular velocity,
  ``Qdot = Q hat(omega)``; the body angular momentum is ``m = I omega`` and
  ``M = J hat(omega) + hat(omega) J = hat(m)`` (4.5);
* the potential is ``phi(x) = 1/2 x^T a x + 1/2 b^T x`` (2.4); a body of second moments
  ``J`` has rotational potential energy ``V = 1/2 tr(Q^T a Q J)``;
* the paper's symmetric variable is ``u = -Q^T a Q`` (as in Section 7, (7.13)).  With this
  sign the printed equations (4.8) ``Mdot = [M, omega] + [u, J]``, ``udot = [u, omega]``, the
  Lax pair (4.11) and the curve (4.12) describe the motion in ``+phi``.  (With
  ``u = +Q^T a Q`` as printed under (4.8) they would describe the motion in ``-phi``.)
* (4.9) ``H = 1/2 tr(M omega) + tr(J u) = -2 (T + V)``: the paper's Hamiltonian is -2 times
  the physical energy in this convention.

All functions broadcast over leading axes of ``Q`` and ``omega``.
"""
from __future__ import annotations

import numpy as np

from thetasol.core import validate as V
from thetasol.core.inertia import inertia_from_moments, moments_from_inertia
from thetasol.core.so3 import cross, hat, vee

__all__ = [
    "torque",
    "torque_from_moments",
    "rotation_rhs",
    "paper_variables",
    "invariants",
    "invariants_from_moments",
    "spectral_coefficients",
    "spectral_coefficients_from_moments",
]


def torque(I: np.ndarray, a: np.ndarray, Q: np.ndarray) -> np.ndarray:  # noqa: E741 - the inertia tensor's usual name
    """Body-frame torque of the potential ``1/2 x^T a x`` on a body of inertia tensor ``I``.

    ``I`` is the inertia tensor in the body frame, three principal values or a symmetric 3x3; it is
    converted once to the paper's second moments ``J = tr(I)/2 1 - I`` (:func:`thetasol.second_moments`)
    and :func:`torque_from_moments` does the rest.  Shape ``Q.shape[:-2] + (3,)``.
    """
    return torque_from_moments(moments_from_inertia(V.inertia(I, "I")), a, Q)


def torque_from_moments(J: np.ndarray, a: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Body-frame torque of the potential ``1/2 x^T a x`` on a body with second moments ``J`` (3x3).

    ``tau = vee([J, Q^T a Q]) = vee([u, J])`` with ``u = -Q^T a Q``: the term ``[u, J]`` of (4.8).
    Shape ``Q.shape[:-2] + (3,)``.
    """
    Qt = np.swapaxes(Q, -1, -2)
    ap = Qt @ a @ Q
    return vee(J @ ap - ap @ J)


def rotation_rhs(J: np.ndarray, I_inv: np.ndarray, a: np.ndarray, m: np.ndarray,
                 Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Right-hand side of the Euler equations (4.8) in vector form and of ``Qdot = Q hat(omega)``.

    Returns ``(mdot, Qdot)`` where ``mdot = m x omega + tau`` and ``omega = I^{-1} m``.
    """
    omega = m @ I_inv.T
    mdot = cross(m, omega) + torque_from_moments(J, a, Q)
    return mdot, Q @ hat(omega)


def paper_variables(J: np.ndarray, a: np.ndarray, Q: np.ndarray,
                    omega: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The paper's matrices ``(M, u, omega_hat)`` of (4.5), (4.8) in the library convention.

    ``M = J hat(omega) + hat(omega) J`` and ``u = -Q^T a Q``.
    """
    W = hat(omega)
    M = J @ W + W @ J
    u = -(np.swapaxes(Q, -1, -2) @ a @ Q)
    return M, u, W


def _tr(X):
    return np.trace(X, axis1=-2, axis2=-1)


def invariants(I: np.ndarray, a: np.ndarray, Q: np.ndarray, omega: np.ndarray) -> dict:  # noqa: E741
    """First integrals of the rotation in a quadratic potential, of a body of inertia tensor ``I``.

    ``I`` is the inertia tensor in the body frame, three principal values (a list or a 1-D array) or a
    symmetric 3x3; ``a`` a 3x3 matrix.  ``I`` is converted once to the paper's second moments
    ``J = tr(I)/2 1 - I`` (:func:`thetasol.second_moments`), in which the integrals below are written,
    and :func:`invariants_from_moments` computes them (see there for the keys).
    """
    return invariants_from_moments(moments_from_inertia(V.inertia(I, "I")), a, Q, omega)


def invariants_from_moments(J: np.ndarray, a: np.ndarray, Q: np.ndarray, omega: np.ndarray) -> dict:
    """First integrals of the rotation in a quadratic potential, of a body of second moments ``J``.

    Returns a dict of arrays (shape ``omega.shape[:-1]``):

    ``energy``  physical energy ``T + V = 1/2 omega.I omega + 1/2 tr(Q^T a Q J)``;
    ``H``       (4.9) ``1/2 tr(M omega) + tr(J u)`` (equals ``-2 energy``);
    ``I2``      (4.13) ``tr(M^2 + 2 J^2 u)``;
    ``I3``      (4.13) ``tr(M^2 u + J^2 u^2)``;
    ``m2``      ``|m|^2 = -1/2 tr(M^2)`` ((4.7), conserved only when ``a`` is isotropic or zero);
    ``curve``   all coefficients of the spectral curve (4.12), see :func:`spectral_coefficients`.

    ``J`` is the paper's second moments, three principal values (a list or a 1-D array) or a 3x3 tensor;
    ``a`` a 3x3 matrix.
    """
    J = V.principal_or_tensor(J, "J")
    a = np.asarray(a, dtype=float)
    if a.shape != (3, 3):
        raise ValueError(f"a must be a 3x3 matrix, got shape {a.shape}")
    Q, omega = np.asarray(Q, dtype=float), np.asarray(omega, dtype=float)
    if Q.shape[-2:] != (3, 3) or omega.shape[-1:] != (3,):
        raise ValueError(f"Q must end in shape (3, 3) and omega in (3,), got {Q.shape} and {omega.shape}")
    M, u, W = paper_variables(J, a, Q, omega)
    J2 = J @ J
    M2 = M @ M
    return {
        "energy": 0.5 * np.einsum("...i,ij,...j->...", omega, inertia_from_moments(J), omega)
        - 0.5 * _tr(u @ J),
        "H": 0.5 * _tr(M @ W) + _tr(J @ u),
        "I2": _tr(M2 + 2 * J2 @ u),
        "I3": _tr(M2 @ u + J2 @ u @ u),
        "m2": -0.5 * _tr(M2),
        "curve": spectral_coefficients_from_moments(J, M, u),
    }


def _polymul(p, q):
    """Product of polynomials in E stored with the power as the LAST axis (ascending)."""
    n = p.shape[-1] + q.shape[-1] - 1
    out = np.zeros(np.broadcast_shapes(p.shape[:-1], q.shape[:-1]) + (n,), dtype=np.result_type(p, q))
    for i in range(p.shape[-1]):
        out[..., i : i + q.shape[-1]] += p[..., i : i + 1] * q
    return out


def spectral_coefficients(I: np.ndarray, M: np.ndarray, u: np.ndarray) -> np.ndarray:  # noqa: E741
    """Coefficients of the spectral curve (4.12) of a body of inertia tensor ``I`` at the paper's ``(M, u)``.

    ``I`` is the inertia tensor in the body frame, three principal values or a symmetric 3x3; the curve
    ``det(J^2 E^2 + M E + u - w 1)`` is written in the paper's second moments, so ``I`` is converted
    once to ``J = tr(I)/2 1 - I`` (:func:`thetasol.second_moments`) and
    :func:`spectral_coefficients_from_moments` does the rest (shape ``batch + (7, 4)``).
    """
    return spectral_coefficients_from_moments(moments_from_inertia(V.inertia(I, "I")), M, u)


def spectral_coefficients_from_moments(J: np.ndarray, M: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Coefficients of ``R(w, E) = det(J^2 E^2 + M E + u - w 1)`` (4.12), ``J`` the second moments (3x3).

    Returns ``C`` of shape ``batch + (7, 4)`` with ``R = sum_{k,l} C[k, l] E^k w^l``.
    Only even ``k`` are non-zero (the involution ``E -> -E``); every entry is a first
    integral of (4.8).
    """
    J = np.asarray(J, dtype=float)
    batch = np.broadcast_shapes(M.shape[:-2], u.shape[:-2])
    # L as a matrix polynomial in E: coefficient axis last, shape batch + (3, 3, 3).
    L = np.zeros(batch + (3, 3, 3), dtype=np.result_type(M, u, float))
    L[..., 0] = u
    L[..., 1] = M
    L[..., 2] = J @ J
    C = np.zeros(batch + (7, 4), dtype=L.dtype)
    # det(L - w) = -w^3 + tr(L) w^2 - c2(L) w + det(L)
    trL = L[..., 0, 0, :] + L[..., 1, 1, :] + L[..., 2, 2, :]
    c2 = np.zeros(batch + (5,), dtype=L.dtype)
    for i, j in ((0, 1), (0, 2), (1, 2)):
        c2 += _polymul(L[..., i, i, :], L[..., j, j, :]) - _polymul(L[..., i, j, :], L[..., j, i, :])
    det = np.zeros(batch + (7,), dtype=L.dtype)
    for (i, j, k), s in (((0, 1, 2), 1), ((1, 2, 0), 1), ((2, 0, 1), 1),
                         ((0, 2, 1), -1), ((2, 1, 0), -1), ((1, 0, 2), -1)):
        det += s * _polymul(_polymul(L[..., 0, i, :], L[..., 1, j, :]), L[..., 2, k, :])
    C[..., 0, 3] = -1.0
    C[..., :3, 2] = trL
    C[..., :5, 1] = -c2
    C[..., :, 0] = det
    return C
