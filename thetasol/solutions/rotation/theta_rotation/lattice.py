"""Coordinates modulo the period lattice ``Z^g + tau Z^g`` of the Jacobian."""
from __future__ import annotations

import numpy as np

__all__ = ["lattice_coords", "reduce_lattice"]


def lattice_coords(z: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Real coordinates (x1, x2) with z = x1 + tau x2 (z of shape (..., g))."""
    Y = tau.imag
    x2 = np.linalg.solve(Y, z.imag.T).T if z.ndim > 1 else np.linalg.solve(Y, z.imag)
    x1 = z.real - x2 @ tau.real.T
    return x1, x2


def reduce_lattice(z: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """A representative of z modulo Z^g + tau Z^g with lattice coordinates in [-1/2, 1/2)."""
    x1, x2 = lattice_coords(z, tau)
    return z - np.round(x1) - np.round(x2) @ tau.T
