"""Turns ``c t`` of rates ``c`` modulo 1, exact before their last roundings for ``|t| < 2^31``.

A phase ``c t`` computed as a rounded product carries ``|c t| 1.1e-16`` turns of error: at ``t = 1e9``
that is 1e-7, and where several phases must keep exact relations (the exponents and the flow of a
theta-function solution) the first integrals drift with ``t``.  Here ``t = t1 + t2`` (``t1 = rint(t)``,
both exact) and a rate is given as ``c1 + c2 + c3`` with ``c1``, ``c2`` of 22 significant bits (so
``t1 c1``, ``t1 c2`` are exact and their integer parts drop exactly) and ``c3`` small; ``c`` is the
rate's float value, multiplied by ``|t2| <= 1/2``.  For ``|t| >= 2^31`` the integer part is not split off
(``t1 = 0``): the plain product.

:func:`rate_turns` forms these turns for any number of times.  The result is not reduced: a caller
reduces it, or first takes integer combinations of several rates' turns.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["TURNS_EXACT", "split_rate", "split_rate_exact", "rate_turns"]

#: Below this ``|t|`` the products of ``rint(t)`` with 22-bit pieces are exact (22 + 31 bits).
TURNS_EXACT = 2.0 ** 31


def split_rate(u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``u = u1 + u2 + u3`` exactly for float rates, ``u1`` and ``u2`` with 22 significant bits, ``u3`` with
    at most 9 (a rate known beyond float64: :func:`split_rate_exact`)."""
    def top22(x):
        e = np.frexp(x)[1]
        return np.ldexp(np.rint(np.ldexp(x, 21 - e)), e - 21)
    u1 = top22(u)
    u2 = top22(u - u1)
    return u1, u2, (u - u1) - u2


def split_rate_exact(x) -> tuple[float, float, float]:
    """:func:`split_rate` of one rate known beyond float64 (an mpmath number, or a float): ``c1`` and ``c2``
    with 22 significant bits taken off its exact value in turn, ``c3`` the float of the rest."""
    pieces = []
    rest = x
    for _ in range(2):
        piece = 0.0
        if rest != 0:
            k = 21 - math.frexp(float(rest))[1]
            piece = math.ldexp(round(math.ldexp(float(rest), k)), -k)
            rest = rest - piece
        pieces.append(piece)
    return pieces[0], pieces[1], float(rest)


def rate_turns(t: np.ndarray, c1: np.ndarray, c2: np.ndarray, c3: np.ndarray, c: np.ndarray) -> np.ndarray:
    """The turns ``c t`` (rates, n) of the rates ``c1 + c2 + c3`` (each (rates,)) at the times ``t`` (n,),
    up to integers (module docstring)."""
    t1 = np.rint(t)
    t1[np.abs(t1) >= TURNS_EXACT] = 0.0
    t2 = t - t1
    x = np.multiply.outer(c1, t1)
    x -= np.rint(x)
    y = np.multiply.outer(c2, t1)
    y -= np.rint(y)
    x += y
    x += np.multiply.outer(c3, t1)
    x += np.multiply.outer(c, t2)
    return x
