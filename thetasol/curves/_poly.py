"""Exact and numerical data of a plane curve f(x, y) = 0 (private to :mod:`thetasol.curves.plane_curve`).

The curve is kept twice: exactly (rational coefficients: a float coefficient is converted to
the rational number it represents in binary, so "the curve as given" is an exact object), and
as a complex128 coefficient array for the vectorized hot paths (roots in y by companion
eigenvalues plus a Newton polish, values and derivatives of f and of differential numerators).
The discriminant and its square-free part are exact (integer arithmetic for real curves of degree
<= 3 in y, :mod:`thetasol.curves._qpoly`; sympy otherwise), so that multiple critical values (nodes,
cusps, exactly degenerate spectral curves) are recognised exactly instead of appearing as clusters of
nearly equal floating roots.

The compensated (double-double) evaluations use the coefficients as hi + lo pairs of the exact
rationals, not their float64 roundings: next to two nearly colliding branch points (relative distance
d) a relative change eps of the coefficients moves them by ~eps / d and the differentials by
~eps / d^2 (large in the periods of a motion near a relative equilibrium, where d is small).
"""
from __future__ import annotations

from fractions import Fraction
from math import comb

import numpy as np

from thetasol.core.dd import split, two_prod, two_sum
from thetasol.curves._qpoly import (
    add,
    discriminant_in_y,
    has_common_factor,
    integer_coefficients,
    mul,
    square_free_part,
)

EPS = np.finfo(float).eps
_NOT_SQUARE_FREE = ("f is not square-free (its discriminant in y vanishes identically): it has a repeated "
                    "factor, so it is reducible")


def to_fraction_pair(c) -> tuple[Fraction, Fraction]:
    """Exact (real, imaginary) parts of a sympy number; floats are converted exactly."""
    import sympy as sp
    c = sp.sympify(c)
    if c.has(sp.nan, sp.zoo, sp.oo, -sp.oo):
        raise ValueError(f"coefficient {c} is not finite (NaN or infinity)")
    re, im = c.as_real_imag()
    out = []
    for part in (re, im):
        if not part.is_Number:
            # an exact irrational (sqrt(2), pi): use its float64 value
            try:
                part = sp.Float(float(sp.N(part, 30)))
            except (TypeError, ValueError) as exc:
                raise ValueError(f"coefficient {c} is not a number") from exc
        if part.is_Float:
            val = float(part)
            if not np.isfinite(val):
                raise ValueError(f"coefficient {c} is not finite (NaN or infinity)")
            out.append(Fraction(val))
        else:
            q = sp.Rational(part)
            out.append(Fraction(int(q.p), int(q.q)))
    return out[0], out[1]


def sympy_symbol(s):
    """``s`` if it is a sympy Symbol, else the Symbol named ``s``: curves built from exact coefficients
    (the spectral curves) name their coordinates, and sympy is imported when a symbol is first asked for."""
    if isinstance(s, str):
        import sympy as sp
        return sp.Symbol(s)
    return s


class CurvePoly:
    """f(x, y) = sum c[i, j] x^i y^j with exact and complex128 coefficients.

    Attributes
    ----------
    exact : dict {(i, j): (Fraction re, Fraction im)}
    C : complex array (dx + 1, n + 1)
    n : degree in y (number of sheets)
    """

    def __init__(self, f, x, y):
        import sympy as sp
        if not isinstance(x, sp.Symbol) or not isinstance(y, sp.Symbol):
            raise ValueError("x and y must be sympy Symbols")
        if x == y:
            raise ValueError("x and y must be different symbols")
        expr = f.as_expr() if isinstance(f, sp.Poly) else sp.sympify(f)
        if isinstance(expr, sp.Equality):
            expr = expr.lhs - expr.rhs
        if expr.has(sp.nan, sp.zoo, sp.oo, -sp.oo):
            raise ValueError("f has NaN or infinite coefficients")
        extra = expr.free_symbols - {x, y}
        if extra:
            raise ValueError(f"f must be a polynomial in {x}, {y} only; it also involves {sorted(map(str, extra))}")
        try:
            P = sp.Poly(sp.expand(expr), x, y)
        except sp.PolynomialError as exc:
            raise ValueError(f"f is not a polynomial in {x}, {y}: {exc}") from exc
        exact = {}
        for (i, j), c in P.terms():
            re, im = to_fraction_pair(c)
            if re != 0 or im != 0:
                exact[(int(i), int(j))] = (re, im)
        self._set_exact(exact, x, y)

    @classmethod
    def from_exact(cls, coef: dict, x, y) -> CurvePoly:
        """The curve ``sum coef[(i, j)] x^i y^j`` from exact real coefficients (Fractions), without sympy's
        parsing (slow, more so for a polynomial it has not seen): the spectral curves' path."""
        self = cls.__new__(cls)
        self._set_exact({k: (Fraction(v), Fraction(0)) for k, v in coef.items() if v != 0}, x, y)
        return self

    def _set_exact(self, exact: dict, x, y) -> None:
        if not exact:
            raise ValueError("f is the zero polynomial")
        n = max(j for _, j in exact)
        if n == 0:
            raise ValueError(f"f does not involve {y}: it does not define a cover of the {x}-line")
        dx = max(i for i, _ in exact)
        self._xy = (x, y)
        self.exact = exact
        self.n = n
        self.dx = dx
        self.is_real = all(im == 0 for _, im in exact.values())
        C = np.zeros((dx + 1, n + 1), dtype=complex)
        Clo = np.zeros_like(C)
        for (i, j), (re, im) in exact.items():
            # Clo: the rounding error of each coefficient.  The compensated evaluations use C + Clo (a
            # double-double copy of the exact curve); next to nearly colliding branch points the
            # float64-rounded curve alone moves them by ~eps |b|^2 / distance, i.e. relative errors of
            # ~eps |b| / distance^2 in the integrands (1e-9 near relative equilibria)
            C[i, j], Clo[i, j] = split_exact(re, im)
        if not np.all(np.isfinite(C)):
            raise ValueError("f has coefficients that overflow float64")
        self.C = C
        self.Clo = Clo
        self.absC = np.abs(C)
        self.Cx = C[1:, :] * np.arange(1, dx + 1)[:, None] if dx > 0 else np.zeros((1, n + 1), complex)
        self._sympy = None

    # ------------------------------------------------------------------ sympy / exact
    x = property(lambda self: sympy_symbol(self._xy[0]), doc="The first coordinate (sympy Symbol).")
    y = property(lambda self: sympy_symbol(self._xy[1]), doc="The second coordinate (sympy Symbol).")

    def sympy_expr(self):
        import sympy as sp
        I = sp.I
        return sum((sp.Rational(re.numerator, re.denominator) + I * sp.Rational(im.numerator, im.denominator))
                   * self.x**i * self.y**j for (i, j), (re, im) in self.exact.items())

    def sympy_poly(self):
        import sympy as sp
        if self._sympy is None:
            dom = "QQ" if self.is_real else "QQ_I"
            self._sympy = sp.Poly(self.sympy_expr(), self.x, self.y, domain=dom)
        return self._sympy

    def coeffs_in_y(self):
        """Exact univariate polynomials a_j(x) (sympy Poly in x) with f = sum a_j(x) y^j."""
        import sympy as sp
        P = self.sympy_poly()
        out = []
        for j in range(self.n + 1):
            terms = {(i,): c for (i, jj), c in P.terms() if jj == j}
            out.append(sp.Poly.from_dict(terms, self.x, domain=P.domain) if terms
                       else sp.Poly(0, self.x, domain=P.domain))
        return out

    def _coeff_lists(self) -> list:
        """The real parts of a_j(x) as ascending lists of Fractions, j = 0 .. n."""
        out = [[Fraction(0)] * (self.dx + 1) for _ in range(self.n + 1)]
        for (i, j), (re, _) in self.exact.items():
            out[j][i] = re
        return out

    def x_content_is_constant(self) -> bool:
        """Whether the a_j(x) have no common factor of positive degree (else f is reducible)."""
        if self.is_real:
            return not has_common_factor(integer_coefficients(self._coeff_lists())[0])
        a = [p for p in self.coeffs_in_y() if not p.is_zero]
        g = a[0]
        for p in a[1:]:
            g = g.gcd(p)
            if g.degree() == 0:
                return True
        return g.degree() <= 0

    def critical_polynomial(self) -> list:
        """Square-free exact polynomial whose roots are the finite critical x-values: the square-free part
        of ``P = disc_y(f) * lc_y(f)`` with the leading coefficient of ``P``, as exact (re, im) Fraction
        pairs in descending powers.

        Real curves of degree <= 3 in y by integer arithmetic (:mod:`thetasol.curves._qpoly`), others
        with sympy; the same polynomial either way, whatever sympy's ground types (tests/test_curves.py)."""
        if self.is_real and self.n <= 3:
            a, den = integer_coefficients(self._coeff_lists())
            disc = [1] if self.n == 1 else discriminant_in_y(a)
            if disc == [0]:
                raise ValueError(_NOT_SQUARE_FREE)
            prod = add((1, mul(disc, a[self.n])))
            # sympy's disc * lc over Q: disc is homogeneous of degree 2n - 2 in the coefficients
            lead = Fraction(prod[-1], den ** (2 * self.n - 1))
            F = square_free_part(prod, lead) if len(prod) > 1 else [lead]
            return [(c, Fraction(0)) for c in reversed(F)]
        return _poly_to_fracs(self._critical_polynomial_sympy())

    def _critical_polynomial_sympy(self):
        import sympy as sp
        P = self.sympy_poly()
        lc = self.coeffs_in_y()[self.n]
        if self.n == 1:
            disc = sp.Poly(1, self.x, domain=P.domain)
        else:
            disc = sp.Poly(sp.discriminant(P.as_expr(), self.y), self.x, domain=P.domain)
        if disc.is_zero:
            raise ValueError(_NOT_SQUARE_FREE)
        prod = disc * lc
        if prod.degree() <= 0:
            return prod
        # with prod's leading coefficient (sympy's sqf_part is monic with its python ground types)
        F = prod.sqf_part()
        return F * (prod.LC() / F.LC())

    # ------------------------------------------------------------------ numerics
    def coeff_polys(self, x):
        """a_j(x) for a 1-D complex array x: shape (K, n + 1)."""
        return _horner_x(self.C, np.asarray(x, dtype=complex))

    def coeff_polys_dx(self, x):
        x = np.asarray(x, dtype=complex)
        if self.dx == 0:
            return np.zeros(x.shape + (self.n + 1,), complex)
        return _horner_x(self.Cx, x)

    def abs_coeff_polys(self, ax):
        """sum_i |c_ij| |x|^i: for rounding-error bounds; ax = |x|."""
        return _horner_x(self.absC, ax)

    def roots(self, x, polish: int = 2, any_order: bool = False):
        """All n roots in y of f(x, y) at each x (1-D array): shape (K, n), unordered.

        Companion-matrix eigenvalues (backward stable), then ``polish`` vectorized Newton steps.
        ``any_order``: for callers that match the roots by value (the tracker), the roots of a cubic
        come from the closed form in another order than the eigenvalues' (far cheaper than the
        eigenvalues; rows where its backward error exceeds 1e-8 fall back to eigenvalues).
        Raises ValueError where the leading coefficient vanishes (a pole of y).
        """
        A = self.coeff_polys(x)
        return self.roots_from_coeffs(A, polish, any_order), A

    def roots_from_coeffs(self, A, polish: int = 2, any_order: bool = False):
        n = self.n
        lead = A[:, n]
        if np.any(lead == 0):
            raise ValueError("leading coefficient in y vanishes at a tracking point")
        if n == 1:
            return (-A[:, 0] / lead)[:, None]
        mon = A[:, :n] / lead[:, None]
        if n == 3 and any_order:
            Y = _cubic_roots(mon)
            bad = ~_accurate_cubic(mon, Y)
            if bad.any():
                Y[bad] = _companion_roots(mon[bad])
        else:
            Y = _companion_roots(mon)
        for _ in range(polish):
            p, dp = self.horner_y(A, Y)
            ok = dp != 0
            step = np.where(ok, p / np.where(ok, dp, 1), 0)
            # Newton only where it helps (clustered roots can make it wander).
            Y = np.where(np.abs(step) < 0.1 * (np.abs(Y) + 1e-300) + 1e-300, Y - step, Y)
        return Y

    @staticmethod
    def horner_y(A, Y):
        """p(Y), p'(Y) for p(y) = sum_j A[:, j] y^j, Y of shape (K, m)."""
        n = A.shape[1] - 1
        p = np.empty(Y.shape, A.dtype)   # (filled by broadcasting: cheaper than np.broadcast_to().copy())
        p[...] = A[:, n:n + 1]
        dp = np.zeros_like(p)
        for j in range(n - 1, -1, -1):
            dp = dp * Y + p
            p = p * Y + A[:, j:j + 1]
        return p, dp

    def fy_fx(self, x, Y, A=None):
        """f_y and f_x at (x[k], Y[k, s])."""
        if A is None:
            A = self.coeff_polys(x)
        _, fy = self.horner_y(A, Y)
        Ax = self.coeff_polys_dx(x)
        fx, _ = self.horner_y(Ax, Y)
        return fy, fx

    def root_error_bound(self, x, Y, fy):
        """First-order bound on the rounding error of each computed root: eps * sum|c||x|^i|y|^j / |f_y|."""
        absA = self.abs_coeff_polys(np.abs(x))
        aY = np.abs(Y)
        s = np.empty(Y.shape, absA.dtype)
        s[...] = absA[:, -1:]
        for j in range(self.n - 1, -1, -1):
            s = s * aY + absA[:, j:j + 1]
        return 4 * self.n * EPS * s / np.maximum(np.abs(fy), 1e-300)

    # ------------------------------------------------------------------ compensated (double-double)
    def coeff_polys_dd(self, x):
        """a_j(x) in double-double: (hi, lo) arrays (K, n + 1), x exact floats."""
        x = np.asarray(x, dtype=complex)
        C = self.C  # (dx + 1, n + 1): coefficient of x^i y^j
        # coefficients (1, n + 1, dx + 1), broadcast against the points inside comp_horner
        return comp_horner(C.T[None], self.Clo.T[None], np.broadcast_to(x[:, None], (len(x), self.n + 1)))

    def polish_dd(self, Ahi, Alo, Y, iters=4):
        """Newton steps on the roots Y (K, m) with compensated residuals; returns (Y, f_y)."""
        n = self.n
        jj = np.arange(1, n + 1)
        # derivative coefficients (j a_j) in double-double
        dhi, dlo = _two_prod_c(Ahi[:, 1:], jj)
        dlo = dlo + Alo[:, 1:] * jj
        Y, delta, step, fy, stale = _newton_dd(Ahi, Alo, dhi, dlo, Y, iters)
        # A close pair of roots far from y = 0 (two sheets 6 apart at |y| ~ 1e8, next to the far
        # branch points of a symmetric body with a small axial spin) can leave the companion matrix
        # a third of the gap off or more: 4 Newton steps then stop 1e-3..0.1 short, and more of them
        # can take both to the same root.  Those rows are finished by Ehrlich-Aberth steps (Newton
        # repelled by the other roots), with the same compensated residuals.
        m = Y.shape[1]
        close = np.zeros(Y.shape, bool)
        if m > 1:
            gaps = np.abs(Y[:, :, None] - Y[:, None, :])
            gaps[:, np.arange(m), np.arange(m)] = np.inf
            close = gaps.min(axis=2) <= 1e-13 * np.abs(Y)
        rows = np.nonzero((np.abs(step) > 1e-12 * np.abs(Y)).any(axis=1) | close.any(axis=1))[0]
        if rows.size and m == n:
            Y, delta = Y.copy(), delta.copy()
            Ys = Y[rows]
            # roots that coincide in float64 are pulled apart first (Aberth needs distinct iterates)
            Ys = np.where(close[rows], Ys * (1 + 1e-9 * np.exp(2j * np.arange(m)))[None, :], Ys)
            Y[rows], delta[rows], _, fy[rows], stale[rows] = _newton_dd(Ahi[rows], Alo[rows], dhi[rows], dlo[rows],
                                                                        Ys, 60, aberth=True)
        if stale.any():   # (the Newton pass has f_y at the final roots of the other rows, the same bits)
            fh, fl = comp_horner(dhi[stale][:, None, :], dlo[stale][:, None, :], Y[stale])
            fy[stale] = fh + fl
        # f_y at the exact root, not at its float64 rounding: where two sheets nearly coincide,
        # f_y changes by f_yy * delta, a relative eps |y| / gap (1e-12 next to close branch points)
        small = np.abs(delta) <= 1e-10 * (np.abs(Y) + 1e-300)
        if n > 1 and np.any(small & (delta != 0)):
            d2 = Ahi[:, 2:] * (jj[1:] * (jj[1:] - 1))
            fyy = np.empty(Y.shape, complex)
            fyy[...] = d2[:, -1:]
            for j in range(d2.shape[1] - 2, -1, -1):
                fyy = fyy * Y + d2[:, j:j + 1]
            fy = np.where(small, fy + fyy * delta, fy)
        return Y, fy

    def shifted_dd(self, b, b_lo=0.0):
        """Coefficients of F(xi, y) = f(b + b_lo + xi, y) in double-double: (hi, lo), arrays (dx + 1, n + 1).

        The shift is exact (rational arithmetic; b and b_lo are the exact binary values of floats), so F
        is evaluated accurately for small xi even where |b| is large against |xi| (a local chart at b;
        b_lo carries a critical value beyond float64, see :func:`root_corrections`).
        """
        b, b_lo = complex(b), complex(b_lo)
        br, bi = Fraction(b.real) + Fraction(b_lo.real), Fraction(b.imag) + Fraction(b_lo.imag)
        # powers of b as exact complex fractions
        pw = [(Fraction(1), Fraction(0))]
        for _ in range(self.dx):
            r, i = pw[-1]
            pw.append((r * br - i * bi, r * bi + i * br))
        hi = np.zeros((self.dx + 1, self.n + 1), complex)
        lo = np.zeros_like(hi)
        for j in range(self.n + 1):
            for i in range(self.dx + 1):
                sr, si = Fraction(0), Fraction(0)
                for k in range(i, self.dx + 1):
                    c = self.exact.get((k, j))
                    if c is None:
                        continue
                    cr, ci = c
                    pr, pi = pw[k - i]
                    m = comb(k, i)
                    sr += m * (cr * pr - ci * pi)
                    si += m * (cr * pi + ci * pr)
                hi[i, j], lo[i, j] = split_exact(sr, si)
        return hi, lo

    def coeff_polys_dd_local(self, xi, Chi, Clo):
        """a_j(b + xi) in double-double from the shifted coefficients of :meth:`shifted_dd`."""
        xi = np.asarray(xi, dtype=complex)
        K = len(xi)
        return comp_horner(Chi.T[None], Clo.T[None], np.broadcast_to(xi[:, None], (K, self.n + 1)))

    def second_derivatives(self, x, Y, A=None):
        """f_xx, f_xy, f_yy at (x[k], Y[k, s]) (plain float64; used only for step control).

        A: the coefficients a_j(x) (:meth:`coeff_polys`) when already at hand."""
        x = np.asarray(x, dtype=complex)
        n, dx = self.n, self.dx
        C = self.C
        ii = np.arange(dx + 1)
        A0 = self.coeff_polys(x) if A is None else A
        A1 = self.coeff_polys_dx(x)
        A2 = _horner_x((C * (ii * (ii - 1))[:, None])[2:], x) if dx >= 2 else np.zeros(x.shape + (n + 1,), complex)
        jj = np.arange(n + 1)
        fxx, _ = self.horner_y(A2, Y)
        fxy, _ = self.horner_y(A1[:, 1:] * jj[1:], Y) if n >= 1 else (np.zeros_like(Y), None)
        fyy, _ = self.horner_y(A0[:, 2:] * (jj[2:] * (jj[2:] - 1)), Y) if n >= 2 else (np.zeros_like(Y), None)
        return fxx, fxy, fyy

    # ------------------------------------------------------------------ Newton polygon
    def newton_polygon(self):
        pts = sorted(set(self.exact))
        return _convex_hull(pts)

    def interior_points(self):
        """Interior lattice points (i, j) of the Newton polygon, sorted by (j, i)."""
        hull = self.newton_polygon()
        if len(hull) < 3:
            return []
        xs = [p[0] for p in hull]
        ys = [p[1] for p in hull]
        out = []
        for j in range(min(ys) + 1, max(ys)):
            for i in range(min(xs) + 1, max(xs)):
                if all(_cross(hull[k], hull[(k + 1) % len(hull)], (i, j)) > 0 for k in range(len(hull))):
                    out.append((i, j))
        out.sort(key=lambda p: (p[1], p[0]))
        return out


_CUBE_ROOTS_OF_UNITY = np.exp(2j * np.pi * np.arange(3) / 3)


def _companion_roots(mon):
    """Roots of the monic polynomials y^n + sum_j mon[:, j] y^j: companion-matrix eigenvalues (K, n)."""
    K, n = mon.shape
    comp = np.zeros((K, n, n), dtype=complex)
    comp[:, 1:, :-1] = np.eye(n - 1)
    comp[:, :, -1] = -mon
    return np.linalg.eigvals(comp)


def _accurate_cubic(mon, Y):
    """Rows whose roots Y of the monic cubics are finite with backward error below 1e-8."""
    ay, am = np.abs(Y), np.abs(mon)[:, None, :]
    with np.errstate(all="ignore"):
        res = np.abs(((Y + mon[:, None, 2]) * Y + mon[:, None, 1]) * Y + mon[:, None, 0])
        bound = ((ay + am[..., 2]) * ay + am[..., 1]) * ay + am[..., 0]
        return (res <= 1e-8 * bound).all(axis=1)


def _cubic_roots(mon):
    """Roots of y^3 + a y^2 + b y + c for rows mon = [c, b, a] (K, 3): Cardano's formula, the cube
    root taken of the larger of -q/2 +- sqrt(q^2/4 + p^3/27) (no cancellation); not backward stable
    for every cubic (see :func:`_accurate_cubic`)."""
    c, b, a = mon[:, 0], mon[:, 1], mon[:, 2]
    with np.errstate(all="ignore"):   # overflows (roots beyond ~1e100) leave rows that the check rejects
        s = a / 3
        p = b - a * s                     # t^3 + p t + q, y = t - a/3
        q = c - b * s + 2 * s * s * s
        h = np.sqrt(0.25 * q * q + p * p * p / 27)
        w1, w2 = -0.5 * q + h, -0.5 * q - h
        w = np.where(np.abs(w1) >= np.abs(w2), w1, w2)
        C = w ** (1 / 3)
        Ck = C[:, None] * _CUBE_ROOTS_OF_UNITY
        t = Ck - p[:, None] / (3 * Ck)
    t = np.where(C[:, None] == 0, 0, t)
    return t - s[:, None]


def _horner_x(coef, x):
    """sum_i coef[i] x^i (coef rows indexed by the power of x) at every x: shape x.shape + coef.shape[1:]."""
    A = np.empty(x.shape + coef.shape[1:], coef.dtype)
    A[...] = coef[-1]
    for i in range(coef.shape[0] - 2, -1, -1):
        A *= x[..., None]
        A += coef[i]
    return A


def _cross(o, a, b):
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def _convex_hull(pts):
    """Counter-clockwise convex hull of integer points (monotone chain), collinear points dropped."""
    pts = sorted(set(pts))
    if len(pts) <= 2:
        return pts
    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and _cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and _cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


# ---------------------------------------------------------------------- univariate roots
def _poly_to_fracs(P):
    """Exact coefficients (descending) of a sympy univariate Poly over QQ or QQ_I as Fraction pairs."""
    return [to_fraction_pair(c) for c in P.all_coeffs()]


def split_exact(re: Fraction, im: Fraction) -> tuple[complex, complex]:
    """Exact complex ``re + i im`` -> (hi, lo): hi its float64 rounding, lo that of the remainder."""
    h = complex(float(re), float(im))
    return h, complex(float(re - Fraction(h.real)), float(im - Fraction(h.imag)))


def _split_coefs(coef) -> tuple[np.ndarray, np.ndarray]:
    """A list of exact (re, im) Fraction pairs -> complex double-double arrays (hi, lo)."""
    pairs = [split_exact(r, i) for r, i in coef]
    return np.array([h for h, _ in pairs], dtype=complex), np.array([l for _, l in pairs], dtype=complex)


def _scaled_fracs(coef):
    """Exact coefficients (descending (re, im) pairs) scaled by a power of 2 so the largest is ~1 (no float
    overflow)."""
    big = max(m for m in (max(abs(r), abs(i)) for r, i in coef) if m != 0)
    sh = big.numerator.bit_length() - big.denominator.bit_length()
    fac = Fraction(1, 2**sh) if sh >= 0 else Fraction(2**(-sh), 1)
    return [(r * fac, i * fac) for r, i in coef]


def polynomial_roots(P: list) -> np.ndarray:
    """All complex roots of a square-free exact univariate polynomial (descending (re, im) Fraction pairs).

    numpy's companion-matrix roots, polished by Newton's method; where roots are clustered
    (ill-conditioned in float64) they are recomputed with mpmath.polyroots at raised precision from
    the exact coefficients, so close but distinct critical values keep full relative accuracy.
    """
    deg = len(P) - 1
    if deg <= 0:
        return np.zeros(0, complex)
    coef = _scaled_fracs(P)
    c, c_lo = _split_coefs(coef)
    r = np.roots(c) if deg > 0 else np.zeros(0, complex)
    if len(r) != deg:
        # leading coefficient underflowed in float: fall back to mpmath entirely
        return _mp_polyroots(coef, deg)
    for _ in range(3):
        p = np.polyval(c, r)
        dp = np.polyval(np.polyder(c), r)
        step = np.where(dp != 0, p / np.where(dp != 0, dp, 1), 0)
        r = np.where(np.abs(step) < 0.1 * (np.abs(r) + 1), r - step, r)
    # Conditioning check: error bound vs distance to the nearest other root.
    ar = np.abs(r)
    absval = np.polyval(np.abs(c), ar)
    dp = np.abs(np.polyval(np.polyder(c), r))
    err = 8 * deg * EPS * absval / np.maximum(dp, 1e-300)
    if deg > 1:
        D = np.abs(r[:, None] - r[None, :]) + np.diag(np.full(deg, np.inf))
        sep = D.min(axis=1)
    else:
        sep = np.full(1, np.inf)
    if np.all(err < 1e-6 * sep) and np.all(np.isfinite(r)):
        # compensated Newton steps: the critical values to ~eps |r| (the local series at a branch
        # point are centred there; an offset delta shows up as spurious poles ~ delta / radius)
        hi, lo = c[::-1], c_lo[::-1]
        dc = np.polyder(c)
        for _ in range(2):
            ph, pl = comp_horner(hi, lo, r)
            d = np.polyval(dc, r)
            step = np.where(d != 0, (ph + pl) / np.where(d != 0, d, 1), 0)
            r = np.where(np.abs(step) < 1e-6 * (np.abs(r) + sep), r - step, r)
        return r
    return _mp_polyroots(coef, deg)


def root_corrections(P: list, r) -> np.ndarray:
    """r_true - r for float roots r of the exact polynomial P (descending (re, im) Fraction pairs): the low
    parts of the roots.

    A float64 root is off by up to eps |r| / 2 however well it is computed; next to another root at
    distance d the local series centred there then carry relative errors ~ eps |r| / d (1e-12 next to
    the close pairs of branch points of motions near relative equilibria).  One Newton step with a
    compensated residual (coefficients in double-double) gives the remainder to ~eps times the
    float root's own error bound; the local charts add it back.
    """
    r = np.asarray(r, dtype=complex)
    if len(r) == 0 or len(P) <= 1:
        return np.zeros(len(r), complex)
    hi, lo = _split_coefs(_scaled_fracs(P)[::-1])
    ph, pl = comp_horner(hi, lo, r)
    dh, dl = comp_horner(*_two_prod_c(hi[1:], np.arange(1, len(hi))), r)
    with np.errstate(divide="ignore", invalid="ignore"):
        d = -(ph + pl) / (dh + dl)
    # a correction is meaningful only at the rounding level of the float root
    ok = np.isfinite(d) & (np.abs(d) <= 1e-12 * (np.abs(r) + 1e-300))
    return np.where(ok, d, 0)


def _mp_polyroots(coef, deg):
    import mpmath
    dps = 40
    for _ in range(4):
        with mpmath.workdps(dps):
            cc = [mpmath.mpc(mpmath.mpf(rr.numerator) / rr.denominator, mpmath.mpf(ii.numerator) / ii.denominator)
                  for rr, ii in coef]
            try:
                roots = mpmath.polyroots(cc, maxsteps=200 + 20 * deg, extraprec=4 * dps)
            except mpmath.libmp.NoConvergence:
                dps *= 2
                continue
            return np.array([complex(z) for z in roots])
    raise ValueError("could not isolate the critical values of the curve (roots of the discriminant)")


# ---------------------------------------------------------------------- compensated arithmetic
# Error-free transformations (Dekker, Knuth) vectorized over numpy arrays, for compensated Horner
# schemes (Graillat, Langlois, Louvet 2005): a polynomial value computed as if in twice the working
# precision.  Used to polish the roots in y and to evaluate f_y where the sheets nearly coincide
# (close branch points, nearly symmetric bodies at large |E|), which plain float64 loses to
# cancellation; this avoids most multiprecision work.  The error-free transformations themselves
# are those of :mod:`thetasol.core.dd`.
def _cmul_eft(a, b):
    """a * b = p + e with p = fl(a * b) (complex) and e its rounding error to first order."""
    p1, e1 = two_prod(a.real, b.real)
    p2, e2 = two_prod(a.imag, b.imag)
    pr, e3 = two_sum(p1, -p2)
    p3, e4 = two_prod(a.real, b.imag)
    p4, e5 = two_prod(a.imag, b.real)
    pi, e6 = two_sum(p3, p4)
    return pr + 1j * pi, (e1 - e2 + e3) + 1j * (e4 + e5 + e6)


def _cadd_eft(a, b):
    sr, er = two_sum(a.real, b.real)
    si, ei = two_sum(a.imag, b.imag)
    return sr + 1j * si, er + 1j * ei


#: Points per block of :func:`comp_horner`: its ~15 temporaries of 4 x block doubles (64 kB) stay in
#: L2 and below the allocator's threshold for fresh mappings, and the blocks are few (smaller blocks
#: pay more per-call overhead, larger ones leave the cache).
_HORNER_BLOCK = 2048


def comp_horner(chi, clo, z):
    """Compensated Horner: sum_j (chi_j + clo_j) z^j as (hi, lo), coefficients along the last axis.

    chi, clo broadcast against z[..., None]; returns hi, lo with hi + lo accurate to about
    eps |value| + eps^2 sum |c_j| |z|^j.
    """
    n = chi.shape[-1] - 1
    z = np.asarray(z)
    if z.ndim and z.size > _HORNER_BLOCK and z.shape[0] > 1:
        # rows are independent: blocks that stay in cache (the stacked temporaries are 4x z)
        step = max(1, _HORNER_BLOCK * z.shape[0] // z.size)
        rows = lambda c, i: c[i:i + step] if c.ndim - 1 == z.ndim and c.shape[0] == z.shape[0] else c  # noqa: E731
        parts = [comp_horner(rows(chi, i), rows(clo, i), z[i:i + step]) for i in range(0, z.shape[0], step)]
        return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])
    # (filled by broadcasting assignment: np.broadcast_to's per-call overhead dominates on these small arrays)
    s = np.empty(z.shape, complex)
    s[...] = chi[..., n]
    comp = np.empty(z.shape, complex)
    comp[...] = clo[..., n]
    if n == 0:
        return _cadd_eft(s, comp)
    z = z.astype(complex, copy=False)
    # The operations of _cmul_eft / _cadd_eft on stacked real arrays (few numpy calls on these small
    # arrays): rows [Re s Re z, Re s Im z, Im s (-Im z), Im s Re z] are the four two-products (a
    # negated factor negates product and error exactly), summed pairwise as in _cmul_eft.
    ZZ = np.stack([z.real, z.imag, -z.imag, z.real])
    if _big(ZZ):
        return _comp_horner_general(chi, clo, z, s, comp, n)
    ZZh, ZZl = split(ZZ)
    CH = np.empty((2,) + z.shape + (n + 1,))
    CH[0], CH[1] = chi.real, chi.imag
    S = np.stack([s.real, s.imag])
    buf = np.empty(z.shape, complex)
    for j in range(n - 1, -1, -1):
        if _big(S):
            return _comp_horner_general(chi, clo, z, S[0] + 1j * S[1], comp, j + 1)
        SS = np.repeat(S, 2, axis=0)
        SSh, SSl = split(SS)
        Pr = SS * ZZ
        E = ((SSh * ZZh - Pr) + SSh * ZZl + SSl * ZZh) + SSl * ZZl
        p, e = two_sum(Pr[:2], Pr[2:])                  # [Re, Im] of fl(s z) and their errors
        pe = (E[:2] + E[2:]) + e
        S, se = two_sum(p, CH[..., j])
        T = pe + se
        buf.real, buf.imag = T[0], T[1]
        comp = comp * z + (buf + clo[..., j])
    hi, lo = _cadd_eft(S[0] + 1j * S[1], comp)
    return hi, lo


def _big(x: np.ndarray) -> bool:
    return bool(x.size and np.abs(x).max() > 1e150)


def _comp_horner_general(chi, clo, z, s, comp, n):
    """comp_horner's loop from the power n down, with the rescaling two-products (huge values)."""
    for j in range(n - 1, -1, -1):
        p, pe = _cmul_eft(s, z)
        s, se = _cadd_eft(p, np.broadcast_to(chi[..., j], z.shape))
        comp = comp * z + (pe + se + clo[..., j])
    hi, lo = _cadd_eft(s, comp)
    return hi, lo


def _two_prod_c(a, k):
    """Complex array a times small integers k (exact in a double-double pair)."""
    pr, er = two_prod(a.real, k * 1.0)
    pi, ei = two_prod(a.imag, k * 1.0)
    return pr + 1j * pi, er + 1j * ei


def _newton_dd(Ahi, Alo, dhi, dlo, Y, iters, aberth=False):
    """Up to ``iters`` Newton steps on the roots Y (K, m) with compensated residuals (see
    CurvePoly.polish_dd); returns (Y, delta, last step, f_y, stale).  f_y is the compensated value
    at the returned Y on the rows where ``stale`` is False (their last step left them unchanged),
    at the row's last iterate elsewhere.  ``aberth``: Y holds all the roots of each row and the
    steps are Ehrlich-Aberth's, N / (1 - N sum_j 1 / (y - y_j)) with N the Newton step."""
    delta = np.zeros_like(Y)
    step = np.zeros_like(Y)
    fyk = np.zeros_like(Y)
    stale = np.ones(Y.shape[0], bool)
    # f and f_y in one compensated Horner pass over [Y, Y]: f_y's coefficients get a leading zero,
    # whose first step leaves exactly f_y's own start (s = 0 z + c, compensation 0 z + c_lo)
    K, m = Y.shape
    n1 = Ahi.shape[1]
    Chi, Clo = np.zeros((K, 2 * m, n1), complex), np.zeros((K, 2 * m, n1), complex)
    Chi[:, :m], Chi[:, m:, :n1 - 1], Clo[:, :m], Clo[:, m:, :n1 - 1] = (
        Ahi[:, None, :], dhi[:, None, :], Alo[:, None, :], dlo[:, None, :])
    # A row whose steps all round away (Y - step == Y bit for bit) sits at a fixed point: every later
    # step repeats this one exactly, so it leaves the iteration ("act": the rows still moving).
    # Most rows get there after two steps; the last steps run on the few others.
    Y = Y.copy()
    ok = np.zeros(Y.shape, bool)
    act = np.arange(K)
    for _ in range(iters):
        Ya = Y[act]
        full = act.size == K
        hi, lo = comp_horner(Chi if full else Chi[act], Clo if full else Clo[act], np.concatenate([Ya, Ya], axis=1))
        rh, rl = hi[:, :m], lo[:, :m]
        fy = hi[:, m:] + lo[:, m:]
        with np.errstate(divide="ignore", invalid="ignore"):
            st = (rh + rl) / fy
            if aberth:
                diff = Ya[:, :, None] - Ya[:, None, :]
                diff[:, np.arange(m), np.arange(m)] = np.inf
                st = st / (1 - st * (1 / diff).sum(axis=2))
        oka = np.isfinite(st) & (np.abs(st) < 0.1 * (np.abs(Ya) + 1e-300) + 1e-300)
        st = np.where(oka, st, 0)
        Ynew = np.where(oka, Ya - st, Ya)
        # what the float64 root misses of the exact one: (Y - step) - fl(Y - step), exact
        # subtraction of nearby floats minus the (tiny, accurately known) step
        delta[act] = np.where(oka, (Ya - Ynew) - st, 0)
        step[act], ok[act], Y[act], fyk[act] = st, oka, Ynew, fy
        moving = (Ynew.view(np.uint64) != Ya.view(np.uint64)).any(axis=1)
        stale[act] = moving
        act = act[moving]
        if act.size == 0 or not np.any(ok & (np.abs(step) > 1e-17 * np.abs(Y))):
            break
    return Y, delta, step, fyk, stale
