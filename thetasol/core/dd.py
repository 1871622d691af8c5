"""Double-double helpers for the few O(g^2)-per-point steps of :mod:`thetasol.theta.riemann` whose
float64 rounding is amplified: reduction of ``z`` modulo the period lattice (``z - tau k - j``
with integers ``k`` up to ~100 for large ``Im z``), the quasi-periodicity phase
``pi k.X.k`` taken modulo 2 pi, and the map ``u = M z`` into the reduced frame.  The
error-free transformations are shared with the compensated Horner scheme of the curve engine
(:mod:`thetasol.curves._poly`).

Error-free transformations (Knuth two-sum, Dekker/Veltkamp two-product), vectorized with numpy;
no FMA is assumed.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

_SPLIT = 134217729.0  # 2^27 + 1


def two_sum(a: np.ndarray | float, b: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def split(a: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """Veltkamp's split ``a = hi + lo`` into halves of 26 bits (``|a| < 1e150``: no overflow)."""
    t = _SPLIT * a
    hi = t - (t - a)
    return hi, a - hi


def two_prod(a: np.ndarray | float, b: np.ndarray | float, checked: bool = True,
             b_split: tuple | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``a*b = p + e`` exactly, for any finite a, b whose product does not overflow.

    Factors beyond 1e150 are first rebalanced by a power of two (``a 2^-s``, ``b 2^s``: the product
    is unchanged) so that Veltkamp's split cannot overflow (the elliptic argument reduction meets them).
    ``checked=False`` skips that test, for callers that have bounded both factors by 1e150 (the same
    result then, without two reductions per call).  ``b_split``: ``split(b)`` already computed, for a
    factor that enters many products (unchecked then).
    """
    p = a * b
    # (the method, not np.max: the test runs on every call, mostly on arrays of a few elements)
    if b_split is None and checked and (np.abs(a).max(initial=0.0) > 1e150 or np.abs(b).max(initial=0.0) > 1e150):
        sh = (np.frexp(a)[1] - np.frexp(b)[1]) // 2
        a, b = np.ldexp(a, -sh), np.ldexp(b, sh)
    ah, al = split(a)
    bh, bl = split(b) if b_split is None else b_split
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


class DD:
    """Unevaluated sum ``hi + lo`` of float arrays (real)."""

    __slots__ = ("hi", "lo")

    def __init__(self, hi, lo=None):
        self.hi = np.asarray(hi, dtype=float)
        self.lo = np.zeros_like(self.hi) if lo is None else np.asarray(lo, dtype=float)

    def __add__(self, other):
        if not isinstance(other, DD):
            other = DD(other)
        s, e = two_sum(self.hi, other.hi)
        e = e + self.lo + other.lo
        return DD(*two_sum(s, e))

    def __neg__(self):
        return DD(-self.hi, -self.lo)

    def __sub__(self, other):
        return self + (-other if isinstance(other, DD) else DD(-np.asarray(other, float)))

    def mul(self, b: ArrayLike) -> DD:
        """Product with a float array ``b`` (exact part by two-product)."""
        b = np.asarray(b, dtype=float)
        p, e = two_prod(self.hi, b)
        e = e + self.lo * b
        return DD(*two_sum(p, e))

    def mul_dd(self, other: DD) -> DD:
        return DD(*dd_mul(self.hi, self.lo, other.hi, other.lo))

    def frac(self) -> np.ndarray:
        """``self mod 1`` in [-1/2, 1/2] as a float (the rounding of hi is exact)."""
        n = np.rint(self.hi)
        return (self.hi - n) + self.lo

    def value(self) -> np.ndarray:
        return self.hi + self.lo


def dd_sum(x: DD) -> DD:
    """Sum over axis 0 by a pairwise tree of double-double additions.

    Layout convention of this module: the point axis is the LAST one (contiguous), summed
    axes come first, so every numpy loop runs over long contiguous rows.
    """
    hi = x.hi
    lo = x.lo if x.lo.shape == hi.shape else np.broadcast_to(x.lo, hi.shape)
    while hi.shape[0] > 1:
        n = hi.shape[0]
        h = n // 2
        s, e = two_sum(hi[:h], hi[h:2 * h])
        e = e + lo[:h] + lo[h:2 * h]
        s, e = two_sum(s, e)
        if n % 2:
            s, e = np.concatenate([s, hi[-1:]]), np.concatenate([e, lo[-1:]])
        hi, lo = s, e
    return DD(hi[0], lo[0])


def dd_prod(a: ArrayLike, b: ArrayLike) -> DD:
    """Exact product of two float arrays (broadcasting) as a DD."""
    return DD(*two_prod(np.asarray(a, float), np.asarray(b, float)))


def dd_split_mp(values: Sequence) -> tuple[np.ndarray, np.ndarray]:
    """Split mpmath reals (nested lists) into float hi + lo arrays."""
    hi = np.vectorize(lambda x: float(x))(values)
    lo = np.vectorize(lambda x, h: float(x - h))(values, hi)
    return hi.astype(float), lo.astype(float)


def dd_matvec(A_hi: np.ndarray, A_lo: np.ndarray, x: DD) -> DD:
    """``y_i = sum_j A_ij x_j`` for A = A_hi + A_lo (g, g) and x a DD of shape (g, P)."""
    xh = DD(x.hi[:, None, :], x.lo[:, None, :])  # [j, ., p]
    prod = xh.mul(A_hi.T[:, :, None]) + DD(x.hi[:, None, :] * A_lo.T[:, :, None])  # [j, i, p]
    return dd_sum(prod)


# ---------------------------------------------------------------------- double-double arithmetic on
# (hi, lo) float pairs and complex double-double 4-tuples (re_hi, re_lo, im_hi, im_lo); used by the
# curve engine's vectorized fallback quadrature (:mod:`thetasol.curves._dd`).  Errors ~2^-104 of the
# operands' magnitudes (IEEE-style addition, so cancellations stay accurate).
def quick_two_sum(a: np.ndarray | float, b: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """``a + b = s + e`` exactly when ``|a| >= |b|`` (or a = 0)."""
    s = a + b
    return s, b - (s - a)


def dd_add(ah: np.ndarray | float, al: np.ndarray | float, bh: np.ndarray | float,
           bl: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """Double-double sum of ``ah + al`` and ``bh + bl``."""
    s, e = two_sum(ah, bh)
    t, f = two_sum(al, bl)
    s, e = quick_two_sum(s, e + t)
    return quick_two_sum(s, e + f)


def dd_mul(ah: np.ndarray | float, al: np.ndarray | float, bh: np.ndarray | float,
           bl: np.ndarray | float, checked: bool = True, bh_split: tuple | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Double-double product of ``ah + al`` and ``bh + bl`` (``checked``, ``bh_split``: see :func:`two_prod`)."""
    p, e = two_prod(ah, bh, checked, bh_split)
    return quick_two_sum(p, e + (ah * bl + al * bh))


def dd_div(ah: np.ndarray | float, al: np.ndarray | float, bh: np.ndarray | float,
           bl: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """Double-double quotient ``(ah + al) / (bh + bl)`` (three float quotient digits)."""
    q1 = ah / bh
    ph, pl = dd_mul(bh, bl, q1, 0.0)
    rh, rl = dd_add(ah, al, -ph, -pl)
    q2 = rh / bh
    ph, pl = dd_mul(bh, bl, q2, 0.0)
    rh, rl = dd_add(rh, rl, -ph, -pl)
    q3 = rh / bh
    s, e = quick_two_sum(q1, q2)
    return dd_add(s, e, q3, 0.0)


def cdd(z: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Complex float array -> complex double-double 4-tuple."""
    z = np.asarray(z, dtype=complex)
    zero = np.zeros(z.shape)
    return (z.real.copy(), zero, z.imag.copy(), zero)


def cdd_value(a: Sequence[np.ndarray]) -> np.ndarray:
    """Complex double-double 4-tuple -> complex128 (rounded)."""
    return (a[0] + a[1]) + 1j * (a[2] + a[3])


def cdd_add(a: Sequence[np.ndarray], b: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    return dd_add(a[0], a[1], b[0], b[1]) + dd_add(a[2], a[3], b[2], b[3])


def cdd_sub(a: Sequence[np.ndarray], b: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    return dd_add(a[0], a[1], -b[0], -b[1]) + dd_add(a[2], a[3], -b[2], -b[3])


def cdd_mul(a: Sequence[np.ndarray], b: Sequence[np.ndarray],
            checked: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Complex double-double product (``checked``: see :func:`two_prod`)."""
    rh, rl = dd_add(*dd_mul(a[0], a[1], b[0], b[1], checked), *(-v for v in dd_mul(a[2], a[3], b[2], b[3], checked)))
    ih, il = dd_add(*dd_mul(a[0], a[1], b[2], b[3], checked), *dd_mul(a[2], a[3], b[0], b[1], checked))
    return rh, rl, ih, il


def cdd_scale(a: Sequence[np.ndarray], rh: np.ndarray | float,
              rl: np.ndarray | float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Complex double-double times the real double-double ``rh + rl``."""
    return dd_mul(a[0], a[1], rh, rl) + dd_mul(a[2], a[3], rh, rl)


def cdd_div(a: Sequence[np.ndarray], b: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Complex double-double quotient: float quotient, then two corrections from dd residuals."""
    bz = cdd_value(b)
    q = cdd(cdd_value(a) / bz)
    for _ in range(2):
        r = cdd_sub(a, cdd_mul(b, q))
        q = cdd_add(q, cdd(cdd_value(r) / bz))
    return q
