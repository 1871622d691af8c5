"""Argument checks of the Riemann theta functions (shared by the float64 and the mpmath paths)."""
from __future__ import annotations

import math

import numpy as np

from thetasol.core.validate import finite_array
from thetasol.theta.lattice import MAX_GENUS

#: Relative tolerance on the symmetry of tau: rounding of a computed period matrix passes and is
#: symmetrized (FLINT returns NaN for tau symmetric only up to rounding); anything larger is refused.
TAU_SYM_RTOL = 1e-12


#: Largest derivative order accepted.
MAX_ORDER = 8


# ----------------------------------------------------------------------------------------
# Validation
# ----------------------------------------------------------------------------------------
def check_tau(tau) -> np.ndarray:
    t = finite_array(tau, "tau", dtype=complex)
    if t.ndim != 2 or t.shape[0] != t.shape[1] or t.shape[0] < 1:
        raise ValueError(f"tau must be a square g x g matrix, got shape {t.shape}")
    g = t.shape[0]
    if g > MAX_GENUS:
        raise ValueError(f"genus g = {g} is not supported (g <= {MAX_GENUS})")
    scale = max(float(np.max(np.abs(t))), np.finfo(float).tiny)
    asym = float(np.max(np.abs(t - t.T))) / scale
    if asym > TAU_SYM_RTOL:
        raise ValueError(f"tau must be symmetric: max|tau - tau^T| / max|tau| = {asym:.3g} > {TAU_SYM_RTOL:g}")
    t = 0.5 * (t + t.T)
    ev = np.linalg.eigvalsh(t.imag)
    if not ev[0] > 0:
        raise ValueError(f"Im(tau) must be positive definite, its eigenvalues are {ev}")
    try:
        np.linalg.cholesky(t.imag)
    except np.linalg.LinAlgError as exc:  # pragma: no cover - eigvalsh said > 0
        raise ValueError(f"Im(tau) is numerically not positive definite (eigenvalues {ev})") from exc
    return t


def check_z(z, g: int) -> np.ndarray:
    zz = finite_array(z, "z", dtype=complex)
    if zz.ndim < 1 or zz.shape[-1] != g:
        raise ValueError(f"z must have shape (..., {g}) for genus {g}, got {zz.shape}")
    return zz


def check_char(char, g: int):
    """None -> zero characteristic; "all" -> the 2^(2g) half-integer ones; (alpha, beta)."""
    if char is None:
        return np.zeros((1, g)), np.zeros((1, g)), False
    if isinstance(char, str):
        if char != "all":
            raise ValueError(f"char must be None, 'all' or a pair (alpha, beta), got {char!r}")
        if g > 6:
            raise ValueError(f"char='all' is limited to g <= 6 (4^g characteristics), got g = {g}")
        idx = np.arange(4 ** g)
        bits = (idx[:, None] >> np.arange(2 * g - 1, -1, -1)[None, :]) & 1
        return bits[:, :g] / 2.0, bits[:, g:] / 2.0, True
    try:
        alpha, beta = char
    except (TypeError, ValueError) as exc:
        raise ValueError(f"char must be None, 'all' or a pair (alpha, beta), got {char!r}") from exc
    alpha = finite_array(alpha, "char alpha", (g,))
    beta = finite_array(beta, "char beta", (g,))
    return alpha[None, :], beta[None, :], False


def check_dirs(derivs, g: int) -> np.ndarray:
    if derivs is None:
        derivs = ()
    try:
        V = [finite_array(v, f"derivs[{i}]", (g,), dtype=complex) for i, v in enumerate(derivs)]
    except TypeError as exc:
        raise ValueError("derivs must be a sequence of direction vectors of length g") from exc
    if len(V) > MAX_ORDER:
        raise ValueError(f"derivative order {len(V)} > {MAX_ORDER} is not supported")
    return np.array(V, dtype=complex).reshape(len(V), g)


def check_tol(tol) -> float:
    try:
        tol = float(tol)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"tol must be a positive float, got {tol!r}") from exc
    if not (0.0 < tol <= 0.1) or math.isnan(tol):
        raise ValueError(f"tol must be in (0, 0.1], got {tol}")
    return tol
