"""Scalar root finders of the separated solutions, vectorized over many points.

* :func:`monotone_newton`: ``x`` with ``f(x) = y`` for an increasing ``f``, Newton safeguarded by
  bisection of a bracket, each point iterated only until it has converged;
* :func:`quadratic_roots`: the real roots of a quadratic without cancellation.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["monotone_newton", "quadratic_roots"]


def monotone_newton(fun: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]], y: np.ndarray, x: ArrayLike,
                    lo: ArrayLike, hi: ArrayLike, converged: Callable[[np.ndarray, np.ndarray], np.ndarray],
                    maxiter: int, polish: int) -> np.ndarray:
    """x with fun(x)[0] = y for an increasing fun (returning value and derivative; 1-d arrays):
    Newton steps, bisection of the bracket [lo, hi] where a step leaves it, each point until
    ``converged(new, old)`` (elementwise) holds for it (the others go on alone); then ``polish``
    plain steps on all (quadratic convergence reaches rounding)."""
    x = np.array(x, float)
    idx = np.arange(x.size)
    xa, ya = x, y
    lo, hi = np.broadcast_to(lo, x.shape), np.broadcast_to(hi, x.shape)
    for _ in range(maxiter):
        f, df = fun(xa)
        r = f - ya
        lo = np.where(r < 0, xa, lo)
        hi = np.where(r > 0, xa, hi)
        step = xa - r / df
        bad = (step < lo) | (step > hi) | ~np.isfinite(step)
        new = np.where(bad, 0.5 * (lo + hi), step)
        more = ~converged(new, xa)
        x[idx] = new
        if not more.any():
            break
        idx, xa, ya, lo, hi = idx[more], new[more], ya[more], lo[more], hi[more]
    for _ in range(polish):
        f, df = fun(x)
        x = x - (f - y) / df
    return x


def quadratic_roots(a2: float, a1: float, a0: float) -> np.ndarray:
    """Real roots (ascending) of a2 z^2 + a1 z + a0 without cancellation (discriminant clipped at 0)."""
    disc = max(a1 * a1 - 4.0 * a2 * a0, 0.0)
    q = -0.5 * (a1 + np.copysign(np.sqrt(disc), a1))
    if q == 0.0:
        return np.array([0.0, 0.0])
    r = np.array([q / a2, a0 / q])
    return np.sort(r)
