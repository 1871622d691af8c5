"""Right-hand sides, first integrals and state layouts of the models, written from the physics.

Each model's ODE is the textbook one on a flat state (body angular velocity ``omega`` first, then
the attitude ``Q`` row-major, then whatever else the model carries); nothing here calls a closed
form, so a case's ``rhs`` and its ``exact`` are independent.
"""
from __future__ import annotations

import numpy as np

from thetasol.core.inertia import inertia_from_moments
from thetasol.core.so3 import cross, hat
from thetasol.mechanics.equations import invariants_from_moments, rotation_rhs
from thetasol.mechanics.heavy_top import heavy_top_invariants
from thetasol.reference._case import Group

__all__ = ["ROTATION_COLUMNS", "rotation_groups", "rotation_system", "free_top_integrals",
           "gyrostat_system", "heavy_top_system", "neumann_system", "kepler_system",
           "orbiting_system", "mass_center_system", "split_rotation"]

ROTATION_COLUMNS = ("omega_1", "omega_2", "omega_3") + tuple(f"Q_{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3))


def rotation_groups() -> tuple[Group, ...]:
    return (Group("omega", 0, 3), Group("Q", 3, 12, 1.0))


def split_rotation(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(omega, Q)`` views of states ``(..., >= 12)``."""
    return y[..., 0:3], y[..., 3:12].reshape(y.shape[:-1] + (3, 3))


def _orthogonality(Q: np.ndarray):
    d = np.abs(np.swapaxes(Q, -1, -2) @ Q - np.eye(3)).max(axis=(-2, -1))
    return d, np.ones_like(d)


def _momentum(I: np.ndarray, omega: np.ndarray, Q: np.ndarray, N=0.0) -> np.ndarray:
    """Space-frame angular momentum ``Q (I omega + N)``."""
    return (Q @ (omega @ I.T + N)[..., None])[..., 0]


def rotation_system(J: np.ndarray, a: np.ndarray):
    """(4.8) in vector form, ``I omegadot = m x omega + tau``, ``Qdot = Q hat(omega)``, and its integrals."""
    I = inertia_from_moments(J)
    I_inv = np.linalg.inv(I)

    def rhs(_t, y):
        w, Q = split_rotation(y)
        mdot, Qdot = rotation_rhs(J, I_inv, a, I @ w, Q)
        return np.concatenate([I_inv @ mdot, Qdot.ravel()])

    def integrals(y):
        w, Q = split_rotation(y)
        inv = invariants_from_moments(J, a, Q, w)
        kin = 0.5 * np.einsum("...i,ij,...j->...", w, I, w)
        u = -(np.swapaxes(Q, -1, -2) @ a @ Q)
        pot = 0.5 * np.abs(np.trace(u @ J, axis1=-2, axis2=-1))
        M2 = np.abs(np.sum((w @ I.T) ** 2, axis=-1))
        J2u = np.abs(np.trace(J @ J @ u, axis1=-2, axis2=-1))
        J2u2 = np.abs(np.trace(J @ J @ u @ u, axis1=-2, axis2=-1))
        out = {"energy": (inv["energy"], kin + pot), "orthogonality": _orthogonality(Q)}
        if np.any(a != 0):
            M2u = np.abs(np.trace(hat(w @ I.T) @ hat(w @ I.T) @ u, axis1=-2, axis2=-1))
            out["I2"] = (inv["I2"], 2 * M2 + 2 * J2u)
            out["I3"] = (inv["I3"], M2u + J2u2)
        return out

    return rhs, integrals


def free_top_integrals(J: np.ndarray):
    """Energy, ``|m|^2`` and the space angular momentum of a free body, with the orthogonality of ``Q``."""
    I = inertia_from_moments(J)

    def integrals(y):
        w, Q = split_rotation(y)
        e = 0.5 * np.einsum("...i,ij,...j->...", w, I, w)
        m2 = np.sum((w @ I.T) ** 2, axis=-1)
        L = _momentum(I, w, Q)
        return {"energy": (e, e), "m2": (m2, m2), "momentum": (L, np.sqrt(m2)), "orthogonality": _orthogonality(Q)}

    return integrals


def gyrostat_system(J: np.ndarray, N: np.ndarray, rotors: list | None = None):
    """(8.39): ``I omegadot = (I omega + N) x omega``, ``Qdot = Q hat(omega)``; with rotors also
    ``phidot_k = p_k / A_k - omega . l_k`` ((8.25)) after ``Q``."""
    I = inertia_from_moments(J)
    I_inv = np.linalg.inv(I)
    axes = np.array([r["axis"] for r in rotors or []], dtype=float).reshape(-1, 3)
    rates = np.array([r["p"] / r["A"] for r in rotors or []], dtype=float)

    def rhs(_t, y):
        w, Q = split_rotation(y)
        wdot = I_inv @ cross(I @ w + N, w)
        return np.concatenate([wdot, (Q @ hat(w)).ravel(), rates - axes @ w])

    def integrals(y):
        w, Q = split_rotation(y)
        e = 0.5 * np.einsum("...i,ij,...j->...", w, I, w)
        h = _momentum(I, w, Q, N)
        hn = np.linalg.norm(h, axis=-1)
        return {"energy": (e, e), "h": (h, hn), "orthogonality": _orthogonality(Q)}

    return rhs, integrals


def heavy_top_system(I: np.ndarray, center: np.ndarray, mass: float, gravity: np.ndarray):
    """Section 5, ``I omegadot = m x omega + c x (Q^T mass g)``, ``Qdot = Q hat(omega)``."""
    I_inv = np.linalg.inv(I)
    F = mass * gravity

    def rhs(_t, y):
        w, Q = split_rotation(y)
        m = I @ w
        mdot = cross(m, w) + cross(center, Q.T @ F)
        return np.concatenate([I_inv @ mdot, (Q @ hat(w)).ravel()])

    def integrals(y):
        w, Q = split_rotation(y)
        inv = heavy_top_invariants(I, center, mass, gravity, w, Q)
        kin = 0.5 * np.einsum("...i,ij,...j->...", w, I, w)
        pot = np.abs(mass * np.linalg.norm(gravity) * np.linalg.norm(center)) * np.ones_like(kin)
        mn = np.linalg.norm(w @ I.T, axis=-1)
        return {"energy": (inv["energy"], kin + pot), "vertical_momentum": (inv["vertical_momentum"], mn),
                "axial_momentum": (inv["axial_momentum"], mn), "orthogonality": _orthogonality(Q)}

    return rhs, integrals


def neumann_system(k: np.ndarray):
    """(6.1)-(6.2) per unit mass for ``a = diag(k)``: ``qddot = -a q + lambda q``,
    ``lambda = (q.aq - |qdot|^2) / |q|^2``; integrals: energy, radius, ``q.v`` and Uhlenbeck's ``F``."""

    def rhs(_t, y):
        q, v = y[0:3], y[3:6]
        lam = (q @ (k * q) - v @ v) / (q @ q)
        return np.concatenate([v, -k * q + lam * q])

    def integrals(y):
        q, v = y[..., 0:3], y[..., 3:6]
        R2 = np.sum(q * q, axis=-1)
        kin, pot = 0.5 * np.sum(v * v, axis=-1), 0.5 * np.sum(k * q * q, axis=-1)
        x, yy = q / np.sqrt(R2)[..., None], v / np.sqrt(R2)[..., None]
        F = x * x
        for i in range(3):
            for j in range(3):
                if i != j:
                    F[..., i] += (x[..., i] * yy[..., j] - x[..., j] * yy[..., i]) ** 2 / (k[i] - k[j])
        one = np.ones_like(R2)
        return {"energy": (kin + pot, kin + np.abs(pot)), "radius2": (R2, R2),
                "q.v": (np.sum(q * v, axis=-1), np.sqrt(R2 * 2 * kin)), "F": (F, one)}

    return rhs, integrals


def kepler_system(mu: float):
    """(7.7): ``rdot = v``, ``vdot = -mu r / |r|^3``; integrals: energy, ``h = r x v``, Laplace-Runge-Lenz."""

    def rhs(_t, y):
        r, v = y[0:3], y[3:6]
        return np.concatenate([v, -mu * r / (r @ r) ** 1.5])

    def integrals(y):
        r, v = y[..., 0:3], y[..., 3:6]
        rn = np.linalg.norm(r, axis=-1)
        kin = 0.5 * np.sum(v * v, axis=-1)
        h = cross(r, v)
        lrl = cross(v, h) - mu * r / rn[..., None]
        return {"energy": (kin - mu / rn, kin + mu / rn), "h": (h, np.linalg.norm(h, axis=-1)),
                "lrl": (lrl, mu * np.ones_like(rn))}

    return rhs, integrals


def orbiting_system(J: np.ndarray, mu: float):
    """(7.16) with the orbit (7.7) alongside: state ``omega, Q, r, v``.

    ``I omegadot = m x omega + 3 mu / |r|^5 (Q^T r) x I (Q^T r)``; on a circular orbit the Jacobi
    integral ``T - n e_n . (Q m) + 3 mu / (2 |r|^3) gamma . I gamma`` (``gamma = Q^T r / |r|``) is conserved.
    """
    I = inertia_from_moments(J)
    I_inv = np.linalg.inv(I)
    krhs, kint = kepler_system(mu)

    def rhs(t, y):
        w, Q = split_rotation(y)
        r = y[12:15]
        b = Q.T @ r
        tau = 3.0 * mu / (r @ r) ** 2.5 * cross(b, I @ b)
        wdot = I_inv @ (cross(I @ w, w) + tau)
        return np.concatenate([wdot, (Q @ hat(w)).ravel(), krhs(t, y[12:18])])

    def integrals(y):
        w, Q = split_rotation(y)
        r, v = y[..., 12:15], y[..., 15:18]
        h = cross(r, v)
        hn = np.linalg.norm(h, axis=-1)
        rn = np.linalg.norm(r, axis=-1)
        n = hn / rn ** 2                                   # circular orbit: the mean motion
        g = (np.swapaxes(Q, -1, -2) @ (r / rn[..., None])[..., None])[..., 0]
        kin = 0.5 * np.einsum("...i,ij,...j->...", w, I, w)
        spin = n * np.sum(h / hn[..., None] * _momentum(I, w, Q), axis=-1)
        pot = 1.5 * mu / rn ** 3 * np.einsum("...i,ij,...j->...", g, I, g)
        out = {"jacobi": (kin - spin + pot, kin + np.abs(spin) + pot), "orthogonality": _orthogonality(Q)}
        out.update({f"orbit_{k}": val for k, val in kint(y[..., 12:18]).items()})
        return out

    return rhs, integrals


def mass_center_system(a: np.ndarray, b: np.ndarray):
    """(3.2): ``qddot = -grad phi = -(a q + b / 2)``; integral: the energy ``|v|^2/2 + phi(q)``."""

    def rhs(_t, y):
        q, v = y[0:3], y[3:6]
        return np.concatenate([v, -(a @ q) - 0.5 * b])

    def integrals(y):
        q, v = y[..., 0:3], y[..., 3:6]
        kin = 0.5 * np.sum(v * v, axis=-1)
        pot = 0.5 * np.einsum("...i,ij,...j->...", q, a, q) + 0.5 * q @ b
        aq = np.abs(q)
        scale = kin + 0.5 * np.einsum("...i,ij,...j->...", aq, np.abs(a), aq) + 0.5 * aq @ np.abs(b)
        return {"energy": (kin + pot, scale)}

    return rhs, integrals
