"""Differential numerators ``g(x, y)`` of the curve engine: parsed once per curve (the parsing is
private to :mod:`thetasol.curves.plane_curve`, which also exports :class:`Numerator`).

A numerator is given as a sympy expression, a string in ``x``, ``y``, or a :class:`Numerator` (exact
coefficients, no sympy: the holomorphic differentials of the engine and the numerators of the
theta-function rotation's set-up, which then runs without importing sympy, a large part of a
process's first set-up); the engine works with its complex coefficient array and, for the double-double and
mpmath sums, its exact rational form.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from thetasol.curves._poly import to_fraction_pair

__all__ = ["Numerator", "expanded_sum", "parse_numerators", "cached_numerators"]


@dataclass(frozen=True)
class Numerator:
    """An exact polynomial ``g(x, y) = sum c_ij x^i y^j``: the numerator of a differential ``g dx / f_y``.

    ``terms`` holds ``(i, j, re, im)`` with the parts of ``c_ij`` as Fractions (exact) or floats
    (a coefficient known only in floating point, taken as the binary rational it is, as the
    engine takes sympy's Floats), sorted by ``(i, j)``, zero coefficients left out.
    """

    terms: tuple

    @classmethod
    def monomial(cls, i: int, j: int) -> Numerator:
        """``x^i y^j``."""
        return cls.from_terms([(i, j, Fraction(1), Fraction(0))])

    @classmethod
    def from_terms(cls, terms) -> Numerator:
        """From ``(i, j, re, im)`` entries with distinct ``(i, j) >= 0`` (zero coefficients dropped)."""
        out = sorted((int(i), int(j), re, im) for i, j, re, im in terms if re != 0 or im != 0)
        keys = [(i, j) for i, j, _, _ in out]
        if len(set(keys)) != len(keys) or any(min(k) < 0 for k in keys):
            raise ValueError(f"numerator terms need distinct non-negative exponents (i, j), got {keys}")
        return cls(tuple(out))

    def coefficient(self, i: int, j: int) -> complex:
        """``c_ij`` as a complex float (0 for a monomial it lacks)."""
        for a, b, re, im in self.terms:
            if (a, b) == (i, j):
                return complex(float(re), float(im))
        return 0j

    @property
    def monomials(self) -> list[tuple[int, int]]:
        """The exponents ``(i, j)`` of its terms."""
        return [(i, j) for i, j, _, _ in self.terms]

    def to_sympy(self, x, y):
        """The polynomial as a sympy expression in the symbols ``x``, ``y`` (expanded, in sympy's canonical
        form: what ``sympy.expand`` gives for the sum of its terms)."""
        import sympy as sp

        def num(v):
            return sp.Float(v) if isinstance(v, float) else sp.Rational(v.numerator, v.denominator)

        terms = []
        for i, j, re, im in self.terms:
            for v, unit in ((re, sp.Integer(1)), (im, sp.I)):
                if v != 0:
                    terms.append(unit * num(v) * x ** i * y ** j)
        return expanded_sum(terms)

    def __str__(self) -> str:
        def num(re, im):
            return str(re) if im == 0 else f"({re} + {im}*I)" if re != 0 else f"{im}*I"
        parts = [f"{num(re, im)}*x**{i}*y**{j}" for i, j, re, im in self.terms]
        return " + ".join(parts) if parts else "0"


def expanded_sum(terms):
    """``sympy.expand(sympy.Add(*terms))`` for terms that are numbers times distinct monomials (distinct
    products of powers of symbols and ``I``): the same expression, built in Add's canonical order
    (the number first, the rest by ``Basic.compare``) without evaluating an Add, whose first
    evaluation in a process imports ``sympy.tensor.tensor`` (slow; tests/test_curves.py checks
    the identity)."""
    import sympy as sp
    numbers = [t for t in terms if t.is_Number]
    rest = sorted((t for t in terms if not t.is_Number), key=functools.cmp_to_key(sp.Basic.compare))
    args = ([sum(numbers[1:], numbers[0])] if numbers else []) + rest
    if not args:
        return sp.Integer(0)
    return args[0] if len(args) == 1 else sp.Add(*args, evaluate=False)


class _Numerators(np.ndarray):
    """Complex coefficient array (nd, I, J) of differential numerators carrying their exact form."""

    exact = None


def parse_numerators(exprs, symbols):
    """Differential numerators (:class:`Numerator`, sympy expressions or strings in ``x``, ``y``) as a
    complex coefficient array (nd, I, J) that carries their exact rational form in ``.exact``: each part
    of a coefficient correctly rounded in the array, exact in ``.exact`` (a Numerator's as it is, a sympy
    expression's as sympy's Poly over ``x, y`` holds it).  ``symbols()`` gives the sympy symbols
    ``(x, y)``; it is called only when a numerator is not a :class:`Numerator`."""
    xy = None
    nums = []
    for g in exprs:
        if not isinstance(g, Numerator):
            xy = xy or symbols()
            g = _from_sympy(g, *xy)
        nums.append(g)
    I = max([i for g in nums for i, _, _, _ in g.terms] + [0]) + 1
    J = max([j for g in nums for _, j, _, _ in g.terms] + [0]) + 1
    P = np.zeros((len(nums), I, J), dtype=complex)
    exact = []
    for d, g in enumerate(nums):
        ex = {}
        for i, j, re, im in reversed(g.terms):              # sympy's order of Poly.terms()
            P[d, i, j] = complex(float(re), float(im))
            ex[(i, j)] = (Fraction(re), Fraction(im))
        exact.append(ex)
    P = P.view(_Numerators)
    P.exact = exact
    return P


def _from_sympy(g, x, y) -> Numerator:
    """A sympy expression or string in ``x``, ``y`` as a :class:`Numerator` with the exact parts of
    sympy's coefficients (:func:`~thetasol.curves._poly.to_fraction_pair`)."""
    import sympy as sp
    g = sp.sympify(g)
    extra = g.free_symbols - {x, y}
    if extra:
        raise ValueError(f"differential numerator {g} involves {sorted(map(str, extra))}")
    return Numerator.from_terms((i, j, *to_fraction_pair(c)) for (i, j), c in sp.Poly(g, x, y).terms())


def cached_numerators(cache: dict, exprs, symbols):
    """:func:`parse_numerators` kept in ``cache`` (a curve's) per tuple of numerators, read-only: the callers
    share it (sympy's parsing is slow, and a set-up asks for the same numerators many times)."""
    exprs = tuple(exprs)
    key = ("parsed", exprs)
    try:
        P = cache.get(key)
    except TypeError:                                    # an unhashable numerator: parse it each time
        return parse_numerators(exprs, symbols)
    if P is None:
        P = parse_numerators(exprs, symbols)
        P.flags.writeable = False
        cache[key] = P
    return P
