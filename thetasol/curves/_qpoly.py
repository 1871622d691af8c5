"""Exact arithmetic on univariate polynomials with rational coefficients (private to the curve engine).

The plane-curve engine needs, once per curve, the discriminant of ``f`` in ``y`` and its square-free
part (the critical values of ``x``), and whether the coefficients ``a_j(x)`` share a factor.  For a real
curve of degree 2 or 3 in ``y`` (the spectral curves of the theta-function rotation, the hyperelliptic
curves) these are a few products of polynomials of degree <= 6 in ``x`` and one gcd: on integer
coefficient lists (the coefficients of a curve given in floats are dyadic rationals) that is an order
of magnitude cheaper than sympy's ``discriminant``, ``sqf_part`` and ``gcd``.  Other curves go through sympy (:meth:`thetasol.curves._poly.CurvePoly.critical_polynomial`).

Polynomials are lists of coefficients in ascending powers.  :func:`square_free_part` takes the leading
coefficient it is to have: the curve engine gives it that of ``disc * lc`` (as sympy's ``Poly.sqf_part``
over QQ does with python-flint's ground types; with its python ground types the part is monic), so the
critical values, which the float roots of these coefficients round, do not depend on sympy's backend.
"""
from __future__ import annotations

from fractions import Fraction
from math import gcd, lcm

__all__ = ["mul", "add", "integer_coefficients", "discriminant_in_y", "gcd_primitive", "has_common_factor",
           "square_free_part"]

#: A prime for the modular gcd test (2^61 - 1): a gcd of degree 0 modulo p is 1 over Q.
_P = (1 << 61) - 1


def _trim(a: list) -> list:
    while len(a) > 1 and a[-1] == 0:
        a = a[:-1]
    return a


def mul(a: list, b: list) -> list:
    """Product of two coefficient lists (ascending)."""
    out = [0] * (len(a) + len(b) - 1)
    for i, x in enumerate(a):
        if x:
            for j, y in enumerate(b):
                out[i + j] += x * y
    return out


def add(*terms: tuple) -> list:
    """``sum c * p`` over ``(c, p)`` pairs of an integer and a coefficient list."""
    out = [0] * max(len(p) for _, p in terms)
    for c, p in terms:
        for i, x in enumerate(p):
            out[i] += c * x
    return _trim(out)


def integer_coefficients(polys: list) -> tuple[list, int]:
    """The lists of Fractions ``polys`` times the least common denominator ``den`` of all their entries,
    as ints, and ``den``."""
    den = 1
    for p in polys:
        for c in p:
            den = lcm(den, Fraction(c).denominator)
    return [[int(Fraction(c) * den) for c in p] for p in polys], den


def discriminant_in_y(a: list) -> list | None:
    """The discriminant in ``y`` of ``sum a[j](x) y^j`` for degree 2 or 3 in ``y`` (coefficient lists of
    integers, or of Fractions as :func:`thetasol.curves.spectral.farthest_branch_point` gives them), up to
    a positive constant; None for other degrees."""
    if len(a) == 3:
        c, b, a2 = a
        return add((1, mul(b, b)), (-4, mul(a2, c)))
    if len(a) == 4:
        d, c, b, a3 = a
        bc = mul(b, c)
        return add((1, mul(bc, bc)), (-4, mul(a3, mul(c, mul(c, c)))), (-4, mul(mul(b, b), mul(b, d))),
                   (-27, mul(mul(a3, a3), mul(d, d))), (18, mul(mul(a3, d), bc)))
    return None


def _derivative(a: list) -> list:
    return _trim([i * a[i] for i in range(1, len(a))] or [0])


def _mod_gcd_degree(a: list, b: list) -> int:
    """Degree of gcd(a, b) modulo the prime ``_P`` (at least the degree over Q when ``_P`` divides neither
    leading coefficient)."""
    a = _trim([x % _P for x in a])
    b = _trim([x % _P for x in b])
    while b != [0]:
        inv = pow(b[-1], -1, _P)
        r = list(a)
        while len(r) >= len(b) and r != [0]:
            q = r[-1] * inv % _P
            s = len(r) - len(b)
            for i, y in enumerate(b):
                r[s + i] = (r[s + i] - q * y) % _P
            r = _trim(r[:-1]) if len(r) > 1 else [0]
        a, b = b, r
    return len(a) - 1


def _primitive(a: list) -> list:
    g = 0
    for x in a:
        g = gcd(g, x)
    return [x // g for x in a] if g > 1 else a


def _prem(a: list, b: list) -> list:
    """Pseudo-remainder of a by b (integer lists)."""
    r = list(a)
    lb = b[-1]
    while len(r) >= len(b) and r != [0]:
        lr = r[-1]
        s = len(r) - len(b)
        r = [x * lb for x in r]
        for i, y in enumerate(b):
            r[s + i] -= lr * y
        r = _trim(r[:-1]) if len(r) > 1 else [0]
    return r


def gcd_primitive(a: list, b: list) -> list:
    """A gcd over Q of two non-zero integer lists, primitive (primitive pseudo-remainder sequence), or
    ``[1]`` at once where their gcd modulo ``_P`` is constant (the usual case: coprime)."""
    a, b = _primitive(_trim(a)), _primitive(_trim(b))
    if len(a) == 1 or len(b) == 1 or (a[-1] % _P and b[-1] % _P and _mod_gcd_degree(a, b) == 0):
        return [1]
    if len(a) < len(b):
        a, b = b, a
    while b != [0]:
        a, b = b, _prem(a, b)
        if b != [0]:
            b = _primitive(b)
    return a


def _exact_quotient(a: list, b: list) -> list:
    """a / b over Q for b dividing a (Fraction coefficients)."""
    r = [Fraction(x) for x in a]
    q = [Fraction(0)] * (len(a) - len(b) + 1)
    for s in range(len(q) - 1, -1, -1):
        c = r[s + len(b) - 1] / b[-1]
        q[s] = c
        if c:
            for i, y in enumerate(b):
                r[s + i] -= c * y
    return q


def has_common_factor(polys: list) -> bool:
    """Whether the non-zero integer lists ``polys`` have a common factor of positive degree over Q."""
    polys = [_trim(p) for p in polys if any(p)]
    g = polys[0]
    for p in polys[1:]:
        g = gcd_primitive(g, p)
        if len(g) == 1:
            return False
    return len(g) > 1


def square_free_part(a: list, lead: Fraction) -> list[Fraction]:
    """The square-free part over Q of the non-constant integer list ``a`` with leading coefficient ``lead``
    (ascending Fractions)."""
    a = _trim(a)
    g = gcd_primitive(a, _derivative(a))
    q = _exact_quotient(a, g) if len(g) > 1 else [Fraction(x) for x in a]
    scale = lead / q[-1]
    return [c * scale for c in q]
