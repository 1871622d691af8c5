"""Differential numerators ``g(x, y)`` of the curve engine: parsed once per curve (private to
:mod:`thetasol.curves.plane_curve`).

A numerator is given as a sympy expression or a string in ``x``, ``y``; the engine works with its
complex coefficient array and, for the double-double and mpmath sums, its exact rational form.
"""
from __future__ import annotations

import numpy as np

from thetasol.curves._poly import to_fraction_pair

__all__ = []


class _Numerators(np.ndarray):
    """Complex coefficient array (nd, I, J) of differential numerators carrying their exact form."""

    exact = None


def parse_numerators(exprs, x, y):
    """Differential numerators (sympy expressions or strings in ``x``, ``y``) as a complex coefficient
    array (nd, I, J) that carries their exact rational form in ``.exact``."""
    import sympy as sp
    polys = []
    for g in exprs:
        g = sp.sympify(g)
        extra = g.free_symbols - {x, y}
        if extra:
            raise ValueError(f"differential numerator {g} involves {sorted(map(str, extra))}")
        polys.append(sp.Poly(g, x, y))
    I = max([p.degree(x) for p in polys] + [0]) + 1
    J = max([p.degree(y) for p in polys] + [0]) + 1
    P = np.zeros((len(polys), I, J), dtype=complex)
    exact = []
    for d, p in enumerate(polys):
        ex = {}
        for (i, j), c in p.terms():
            P[d, i, j] = complex(c)
            ex[(int(i), int(j))] = to_fraction_pair(c)
        exact.append(ex)
    P = P.view(_Numerators)
    P.exact = exact
    return P


def cached_numerators(cache: dict, exprs, x, y):
    """:func:`parse_numerators` kept in ``cache`` (a curve's) per tuple of numerators, read-only: the callers
    share it (sympy's parsing costs ~0.3 ms a numerator, and a set-up asks for the same ones many times)."""
    exprs = tuple(exprs)
    key = ("parsed", exprs)
    try:
        P = cache.get(key)
    except TypeError:                                    # an unhashable numerator: parse it each time
        return parse_numerators(exprs, x, y)
    if P is None:
        P = parse_numerators(exprs, x, y)
        P.flags.writeable = False
        cache[key] = P
    return P
