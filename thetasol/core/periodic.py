"""Periodic functions of one angle as truncated Fourier series, evaluated at many points.

The separated solutions (docs/neumann.md) describe every coordinate as a Fourier series in an angle
that moves linearly in time.  This module holds what they share:

* :func:`refined_fft`, :func:`fit_series`: the coefficients, the grid doubled until the outer band of
  the spectrum is below :data:`COEF_TOL` relative (or the noise of the samples);
* :func:`powers`: ``e^{ikx}`` for k = 1..n by doubling, at most log2(k) roundings (checked against
  mpmath, tests/test_neumann.py::test_powers_against_mpmath);
* :func:`sum_series`, :func:`sum_series_derivative`, :func:`eval_series`, :func:`grid_values` (on the
  uniform grid, by FFT), :func:`integrated`;
* :class:`HermiteTable`: a piecewise-cubic model of a series, cheap for the first Newton steps;
* :class:`TaylorTable`: local Taylor polynomials of a series, the series to rounding at a table's cost.

A series is stored as ``c_n`` (n = 0..N) with ``f(x) = Re(c_0 + 2 sum_{n >= 1} c_n e^{inx})``.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["COEF_TOL", "SeriesNotConverged", "refined_fft", "fit_series", "sum_series",
           "sum_series_derivative", "eval_series", "grid_values", "powers", "integrated", "HermiteTable",
           "TaylorTable", "adaptive_series"]

_EPS = np.finfo(float).eps

#: Fourier series are refined until their trailing coefficients fall below this (relative).
COEF_TOL = 2e-16


class SeriesNotConverged(ArithmeticError):
    """A Fourier series still had a large tail at the largest grid allowed (the message says which)."""


def refined_fft(transform: Callable[[int], tuple[np.ndarray, np.ndarray | slice, float]], what: str, n0: int, nmax: int,
                terms: Callable[[int], object] = str) -> tuple[int, np.ndarray, np.ndarray]:
    """Double the grid ``n`` from ``n0`` until the outer band of the spectrum is below ``COEF_TOL``
    times the largest coefficient or the absolute noise of the samples.

    ``transform(n)`` returns (coefficients, mask of the outer band, noise floor); the answer is
    ``(n, c, mask of the kept coefficients)``.  Raises :class:`SeriesNotConverged` past ``nmax``.
    """
    n = n0
    while True:
        c, band, floor = transform(n)
        scale = max(np.abs(c).max(), np.finfo(float).tiny)
        tail = np.abs(c[band]).max()
        if tail <= max(COEF_TOL * scale, floor):
            return n, c, np.abs(c) > 0.25 * max(COEF_TOL * scale, floor)
        if n >= nmax:
            raise SeriesNotConverged(f"the Fourier series of {what} has not converged with {terms(n)} "
                                     f"terms (tail {tail / scale:.1e} relative)")
        n *= 2


def fit_series(fun: Callable[[np.ndarray], np.ndarray], what: str, floor: float = 0.0,
               nmax: int = 2 ** 12) -> np.ndarray:
    """Coefficients ``c_n`` (n = 0..N/2) with ``fun(x) = Re(c_0 + 2 sum c_n e^{inx})``, N doubled
    until the upper quarter of the spectrum is below ``COEF_TOL`` times the largest coefficient or
    below ``floor`` (the absolute noise of the samples)."""
    def transform(n):
        c = np.fft.rfft(fun(2 * np.pi * np.arange(n) / n)) / n
        return c, slice((3 * n) // 8, None), floor

    _, c, keep = refined_fft(transform, what, 64, nmax)
    keep = np.flatnonzero(keep)
    return c[:keep.max() + 1 if keep.size else 1].copy()


def sum_series(E: np.ndarray, c: np.ndarray) -> np.ndarray:
    """``Re(c_0 + 2 sum c_n e^{inx})`` from the powers ``E = powers(x, >= c.size - 1)``."""
    return c[0].real + 2.0 * np.tensordot(c[1:], E[:c.size - 1], 1).real


def sum_series_derivative(E: np.ndarray, c: np.ndarray) -> np.ndarray:
    """The x-derivative of :func:`sum_series`, from the same powers."""
    return 2.0 * np.tensordot(1j * np.arange(1, c.size) * c[1:], E[:c.size - 1], 1).real


def eval_series(c: np.ndarray, x: np.ndarray, derivative: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """``Re(c_0 + 2 sum c_n e^{inx})`` (and its derivative) at real ``x`` (any shape)."""
    E = powers(x, c.size - 1)
    val = sum_series(E, c)
    if not derivative:
        return val
    return val, sum_series_derivative(E, c)


def grid_values(c: np.ndarray, n: int) -> np.ndarray:
    """``Re(c_0 + 2 sum c_m e^{imx})`` at the n points ``x_j = 2 pi j / n`` (the grid of :func:`fit_series`)
    by one inverse FFT: the coefficients are folded modulo n, so any n is exact."""
    folded = np.zeros(n, complex)
    m = np.arange(1, c.size) % n
    np.add.at(folded, m, c[1:])
    return c[0].real + 2.0 * n * np.fft.ifft(folded).real


def powers(x: np.ndarray, n: int) -> np.ndarray:
    """``e^{i k x}`` for k = 1..n, shape (n,) + x.shape (the points last: every product with them is
    one vectorized pass).  By doubling, ``e^{i(m + j)x} = e^{imx} e^{ijx}`` with ``e^{imx}`` (m a power
    of two) from cos/sin of the exact ``m x``: the k-th power carries at most log2(k) roundings, and
    the first k powers do not depend on n."""
    x = np.remainder(np.asarray(x, float), 2 * np.pi)
    E = np.empty((max(n, 1),) + x.shape, complex)
    E[0] = np.cos(x) + 1j * np.sin(x)
    m = 1
    while m < n:
        k = min(m, n - m)
        mx = m * x                                     # exact: m is a power of two
        E[m:m + k] = E[:k] * (np.cos(mx) + 1j * np.sin(mx))
        m += k
    return E[:n]


def integrated(c: np.ndarray) -> np.ndarray:
    """Coefficients of the zero-mean antiderivative of the periodic part of the series c."""
    out = np.zeros_like(c)
    n = np.arange(1, c.size)
    out[1:] = c[1:] / (1j * n)
    return out


class HermiteTable:
    """Piecewise-cubic Hermite interpolant of ``g(x) = Re(c_0 + 2 sum c_n e^{inx})`` on M uniform nodes
    (values and derivatives from one inverse FFT each), M doubled until the error at the midpoints is
    below ``tol``: a cheap model of a series for the first Newton steps (a gather and a Horner step
    per point instead of n complex powers).  ``error`` is the midpoint error reached."""

    def __init__(self, c: np.ndarray, tol: float, mmax: int = 2 ** 16):
        M = 8
        while M < 8 * c.size:
            M *= 2
        while True:
            self.coef, self.error, h = self._build(c, M)
            if self.error <= tol or M >= mmax:
                break
            M *= 2
        self.M, self.h = M, h

    @staticmethod
    def _build(c: np.ndarray, M: int):
        """(cubic coefficients per interval, midpoint error, node spacing) on M nodes."""
        n = np.arange(c.size)
        X = np.zeros(M + 1, complex)                     # samples at the nodes and the midpoints
        X[:c.size] = 2 * M * c
        X[0] = 2 * M * c[0].real
        dX = np.zeros(M + 1, complex)
        dX[:c.size] = 2 * M * 1j * n * c
        g, dg = np.fft.irfft(X, 2 * M), np.fft.irfft(dX, 2 * M)
        v, d = np.append(g[::2], g[0]), np.append(dg[::2], dg[0])
        h = 2 * np.pi / M
        d0, d1 = h * d[:-1], h * d[1:]
        dv = v[1:] - v[:-1]
        # g = v0 + u (d0 + u (a2 + u a3)), u in [0, 1] on each interval
        coef = np.stack([v[:-1], d0, 3 * dv - 2 * d0 - d1, d0 + d1 - 2 * dv], -1)
        mid = coef @ np.array([1.0, 0.5, 0.25, 0.125])
        return coef, float(np.abs(mid - g[1::2]).max()), h

    def __call__(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(g, dg/dx) at x."""
        y = np.remainder(x, 2 * np.pi) / self.h
        j = np.minimum(y.astype(np.intp), self.M - 1)
        u = y - j
        v0, d0, a2, a3 = self.coef[j].T
        return v0 + u * (d0 + u * (a2 + u * a3)), (d0 + u * (2.0 * a2 + 3.0 * u * a3)) / self.h


class TaylorTable:
    """Taylor polynomials of degree ``deg`` of ``g(x) = Re(c_0 + 2 sum c_n e^{inx})`` at M uniform nodes
    (the k-th derivatives from one inverse FFT each), M doubled until the polynomials reach the exact
    midpoint values (an FFT on 2M points) to ``tol`` (by default 4 eps sum |c|): the series to rounding at ~2 deg flops per point
    instead of n complex powers.  With ``M >= 4 n`` the step to the nearest node is ``h/2 <= pi / (4 n)``:
    the k-th term is below ``sum |c_m| (m h / 2)^k / k!``, so the rounding of the derivatives stays that
    of the series.  ``error`` is the midpoint error reached."""

    def __init__(self, c: np.ndarray, tol: float | None = None, deg: int = 10, mmax: int = 2 ** 16):
        if tol is None:                                  # the rounding of the series' own sum
            tol = 4 * _EPS * (abs(c[0]) + 2 * np.abs(c[1:]).sum())
        M = 16
        while M < 4 * c.size:
            M *= 2
        n = np.arange(c.size)
        while True:
            h = 2 * np.pi / M
            dk, fact, rows = c.astype(complex), 1.0, []
            for k in range(deg + 1):
                rows.append(grid_values(dk, M) * (h ** k / fact))
                dk, fact = dk * (1j * n), fact * (k + 1)
            self.coef = np.stack(rows, -1)
            mid = np.polynomial.polynomial.polyval(0.5, self.coef.T)
            self.error = float(np.abs(mid - grid_values(c, 2 * M)[1::2]).max())
            if self.error <= tol or M >= mmax:
                break
            M *= 2
        self.M, self.h = M, h

    def __call__(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(g, dg/dx) at x."""
        y = np.remainder(x, 2 * np.pi) / self.h
        j = np.rint(y)
        d = y - j
        C = self.coef[j.astype(np.intp) % self.M]
        v, dv = C[:, -1], np.zeros_like(d)
        for k in range(C.shape[1] - 2, -1, -1):
            dv = dv * d + v
            v = v * d + C[:, k]
        return v, dv / self.h


def adaptive_series(coeffs: Callable[[int], np.ndarray], nmax: int, failure: str
                    ) -> tuple[np.ndarray, float]:
    """Spectral coefficients ``coeffs(n)`` for ``n = 64, 128, ...`` until their tail (the last
    quarter) reaches round-off or stops decreasing (the samples' own rounding noise), at most
    ``nmax`` samples.

    Returns the coefficients and the tail relative to the largest (0 for all-zero coefficients).
    A tail above 1e-9 raises :class:`SeriesNotConverged` with ``failure`` followed by the tail (the
    solution layer turns it into :class:`~thetasol.protocol.ClosedFormUnavailable`).
    """
    n, prev = 64, np.inf
    while True:
        c = coeffs(n)
        scale = np.max(np.abs(c))
        if scale == 0:
            return c, 0.0
        tail = np.max(np.abs(c[3 * len(c) // 4:]))
        if tail <= 4 * _EPS * scale or (tail > 0.5 * prev and tail < 1e-11 * scale) or n >= nmax:
            break
        prev = tail
        n *= 2
    if tail / scale > 1e-9:
        raise SeriesNotConverged(failure.format(tail=tail / scale))
    return c, tail / scale
