"""Stumpff's functions ``c_k(z) = sum_j (-z)^j / (2j + k)!``, ``k = 0..3``, for every sign of ``z``.

With ``s = sqrt(z)``: ``c0 = cos s``, ``c1 = sin s / s``, ``c2 = (1 - cos s) / s^2``, ``c3 = (s - sin s) / s^3``,
continued to ``z < 0`` by ``cosh``/``sinh``; entire in ``z``, so one formula covers the trigonometric,
parabolic and hyperbolic cases of the universal-variable Kepler problem (Battin, *An Introduction to the
Mathematics and Methods of Astrodynamics*, ch. 4) and of the modes of a quadratic potential
(``cos(sqrt(lam) t) = c0(lam t^2)``, ...).  Below ``|z| = 4`` the Maclaurin series (16 terms, Horner) is
used, because ``c3``'s direct form loses bits to cancellation there and ``c2``'s ``1 - cos s`` would;
above it the direct forms, with ``1 - cos s = 2 sin^2(s/2)``.

:func:`stumpff` takes arrays; :func:`stumpff_float` is the same series and forms on one Python float
(``c0``, ``c1`` from ``c2``, ``c3`` in the series range), for per-call code such as the scalar Kepler
solve inside an integrator's right-hand side, where numpy's per-call overhead would dominate.
"""
from __future__ import annotations

import math

import mpmath
import numpy as np
from numpy.typing import ArrayLike

__all__ = ["stumpff", "stumpff_float"]

#: |z| below which the series is summed (above it the direct forms have no cancellation).
SERIES_Z = 4.0
#: Terms of the series: the 16th, 4^16 / 32!, is 1.6e-26 of the first at |z| = 4.
SERIES_TERMS = 16


def _series_coeffs(k: int) -> np.ndarray:
    """Coefficients of c_k in powers of (-z): 1/(2j + k)!, highest first (for Horner)."""
    c = [1.0 / float(mpmath.factorial(2 * j + k)) for j in range(SERIES_TERMS)]
    return np.array(c[::-1])


_COEFFS = [_series_coeffs(k) for k in range(4)]
_FLOAT_SERIES = list(zip(_COEFFS[2].tolist(), _COEFFS[3].tolist(), strict=True))


def stumpff(z: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Stumpff's functions ``c0, c1, c2, c3`` of ``z`` (any sign), elementwise (module docstring).

    Parameters
    ----------
    z : array_like
        Arguments (float).

    Returns
    -------
    c0, c1, c2, c3 : ndarray
        Of the shape of ``z``; ``inf``/``nan`` where ``cosh`` overflows (``z`` below about ``-5e5``).
    """
    z = np.asarray(z, dtype=float)
    small = np.abs(z) < SERIES_Z
    w = -np.where(small, z, 0.0)
    ser = [np.polyval(c, w) for c in _COEFFS]
    zb = np.where(small, 1.0, z)
    pos = zb > 0
    s = np.sqrt(np.abs(zb))
    with np.errstate(over="ignore", invalid="ignore"):
        c0 = np.where(pos, np.cos(s), np.cosh(s))
        c1 = np.where(pos, np.sin(s), np.sinh(s)) / s
        half = np.where(pos, np.sin(0.5 * s), np.sinh(0.5 * s))
        c2 = 2.0 * half * half / np.abs(zb)
        c3 = np.where(pos, s - np.sin(s), np.sinh(s) - s) / (np.abs(zb) * s)
    out = [np.where(small, a, b) for a, b in zip(ser, (c0, c1, c2, c3), strict=True)]
    return out[0], out[1], out[2], out[3]


def stumpff_float(z: float) -> tuple[float, float, float, float]:
    """:func:`stumpff` on one float, in Python arithmetic."""
    if abs(z) < SERIES_Z:
        w = -z
        c2 = c3 = 0.0
        for a, b in _FLOAT_SERIES:
            c2 = c2 * w + a
            c3 = c3 * w + b
        return 1.0 - z * c2, 1.0 - z * c3, c2, c3
    s = math.sqrt(abs(z))
    if z > 0:
        h = math.sin(0.5 * s)
        return math.cos(s), math.sin(s) / s, 2.0 * h * h / z, (s - math.sin(s)) / (z * s)
    h = math.sinh(0.5 * s)
    return math.cosh(s), math.sinh(s) / s, 2.0 * h * h / -z, (math.sinh(s) - s) / (-z * s)
