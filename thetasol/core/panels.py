"""The running integral of a positive periodic function with complex singularities close to the real
axis, and its inverse, by Gauss-Legendre panels graded toward the singularities.

A Fourier series of such a function needs ~36 / d terms (d the distance of the nearest singularity
from the real axis): thousands near a separatrix of a separated solution (docs/neumann.md).  Panels
bisected until every singularity lies outside the Bernstein ellipse of parameter :data:`RHO` of its
panel need only ~log2(1/d) panels per singularity, and :data:`NODES` Gauss-Legendre nodes integrate
each to ``RHO^(-2 NODES)`` relative, below float64 rounding.
"""
from __future__ import annotations

from collections.abc import Callable
from functools import cache

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core.roots import monotone_newton

__all__ = ["NODES", "RHO", "PeriodicIntegral", "bernstein_rho", "gauss_legendre"]

#: Gauss-Legendre nodes per panel.
NODES = 16
#: Smallest Bernstein-ellipse parameter of a singularity relative to its panel.
RHO = 4.0


@cache
def gauss_legendre(N: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on [-1, 1] of order N (numpy's ``leggauss``, computed once
    per order and kept): shared, not to be written into."""
    return np.polynomial.legendre.leggauss(N)


_X, _W = gauss_legendre(NODES)


def _integration_matrix() -> np.ndarray:
    """S with (S f)_i = int_{-1}^{X_i} p, p the polynomial through (X_j, f_j) (Legendre basis)."""
    L = np.polynomial.legendre
    inv = np.linalg.inv(L.legvander(_X, NODES - 1))
    return np.stack([L.legval(_X, L.legint(inv[:, j], lbnd=-1)) for j in range(NODES)], -1)


_S = _integration_matrix()
_MAX_PANELS = 4096


def bernstein_rho(z: np.ndarray, a: float, b: float) -> float:
    """The smallest parameter rho of the Bernstein ellipses (foci a, b) through the points z."""
    if z.size == 0:
        return np.inf
    w = (2.0 * z - (a + b)) / (b - a)
    return float(np.abs(w + np.sqrt(w - 1.0) * np.sqrt(w + 1.0)).min())


class PeriodicIntegral:
    """``F(x) = int_0^x f`` for a positive ``f`` of period ``2 pi`` analytic off the points
    ``singularities`` (complex; their periodic images are added here), for any real x:
    ``F(x + 2 pi) = F(x) + total``.

    Attributes: ``edges`` (panel ends in ``[0, 2 pi]``), ``cum`` (F at the edges), ``total``, ``nodes``
    (the quadrature nodes, dense where f varies fast).
    """

    def __init__(self, f: Callable[[np.ndarray], np.ndarray], singularities: ArrayLike):
        s = np.asarray(singularities, complex).ravel()
        s = np.concatenate([s + 2 * np.pi * m for m in (-1, 0, 1)])
        self.f = f
        edges = [0.0]
        todo = [(0.5 * np.pi * j, 0.5 * np.pi * (j + 1)) for j in range(4)][::-1]
        while todo:
            a, b = todo.pop()
            if bernstein_rho(s, a, b) < RHO and len(edges) < _MAX_PANELS:
                c = 0.5 * (a + b)
                todo += [(c, b), (a, c)]
            else:
                edges.append(b)
        self.edges = np.array(edges)
        a, b = self.edges[:-1], self.edges[1:]
        h = 0.5 * (b - a)
        nodes = (a + h)[:, None] + h[:, None] * _X
        vals = f(nodes)
        self.cum = np.r_[0.0, np.cumsum((vals @ _W) * h)]
        self.total = float(self.cum[-1])
        # per panel, x as a polynomial in F through the nodes and the ends: the start of the inversion
        self.nodes = nodes.ravel()
        self._px = np.concatenate([a[:, None], nodes, b[:, None]], 1)
        self._pF = np.concatenate([self.cum[:-1, None], self.cum[:-1, None] + (vals @ _S.T) * h[:, None],
                                   self.cum[1:, None]], 1)
        diff = self._pF[:, :, None] - self._pF[:, None, :]
        np.einsum("pii->pi", diff)[...] = 1.0
        self._pw = 1.0 / diff.prod(-1)                  # barycentric weights

    def __call__(self, x: ArrayLike) -> np.ndarray:
        """F(x) (any real x, any shape): the panel's running value plus Gauss-Legendre from its start."""
        x = np.asarray(x, float)
        turns = np.floor(x / (2 * np.pi))
        r = np.clip(x - 2 * np.pi * turns, 0.0, 2 * np.pi)
        j = np.clip(np.searchsorted(self.edges, r, "right") - 1, 0, self.edges.size - 2)
        a = self.edges[j]
        h = 0.5 * (r - a)
        part = (self.f((a + h)[..., None] + h[..., None] * _X) @ _W) * h
        return turns * self.total + self.cum[j] + part

    def inverse(self, y: ArrayLike) -> np.ndarray:
        """x with F(x) = y (1-d y): Newton from the polynomial x(F) through the panel's nodes
        (barycentric form), safeguarded by the panel's ends (F is increasing), then one plain step."""
        y = np.asarray(y, float)
        turns = np.floor(y / self.total)
        r = y - turns * self.total
        j = np.clip(np.searchsorted(self.cum, r, "right") - 1, 0, self.edges.size - 2)
        shift = 2 * np.pi * turns
        a, b = self.edges[j] + shift, self.edges[j + 1] + shift
        dF = r[:, None] - self._pF[j]
        hit = dF == 0.0
        dF[hit] = 1.0
        q = self._pw[j] / dF
        x0 = np.where(hit.any(-1), (self._px[j] * hit).sum(-1), (q * self._px[j]).sum(-1) / q.sum(-1))
        x0 = np.clip(x0 + shift, a, b)

        def fun(x):
            return self(x), self.f(x)

        # the start is ~RHO^-(NODES + 2) of the panel away: one step is at rounding, one more polishes
        return monotone_newton(fun, y, x0, a, b, lambda new, x: np.abs(new - x) <= 1e-9, 100, 1)
