"""Hyperelliptic curves ``y^2 = f(x)``, ``deg f = 2g + 1``: periods, Riemann matrix, Abel map from the
branch point at infinity, Riemann constant, from the branch points alone (no sympy, no path graph).

Method (after Molin & Neurohr, Math. Comp. 88 (2019) 847-888, written here from the mathematics).  For
``y^2 = f(x)`` the sheets are ``+-y``, so nothing has to be tracked: every integral runs along a straight
segment that starts or ends at a branch point, with the square root's singularity taken into the
quadrature weight (or a substitution) and the rest analytic in an ellipse whose size is known from the
branch points; the node count follows from it in advance, the cost is that of a few hundred
evaluations of a product, and no path graph, sympy or sheet matching (as in PlaneCurve) is needed.

* **Cycles.**  The finite branch points are sorted by ``(Re, Im)`` into a chain ``e_1, ..., e_{2g+1}``;
  the polyline through them is x-monotone, so its segments meet only at shared ends and no other
  branch point lies in the vertical strip of a segment.  ``gamma_k`` is the segment ``[e_k, e_{k+1}]``
  lifted on a fixed branch ``y_k`` and back on ``-y_k``; these 2g cycles generate H_1.  Two cycles meet
  only at a shared end, where ``y`` is a local coordinate: there each cycle is a straight line through
  ``y = 0`` and ``gamma_k . gamma_{k+1}`` is the sign of the angle between the two lines, read from the
  branches ``y_k, y_{k+1}`` at the vertex.  Integer symplectic reduction of this tridiagonal form
  gives ``a_1..a_g, b_1..b_g`` with ``a_i . b_j = delta_ij``, then changed (integer symplectic steps on the
  cycles) until ``tau`` is Siegel-reduced, so that theta sums and lattice reductions of callers see short
  periods (which keeps Kovalevskaya's top closer to its numerical reference than the chain's basis does).
* **Periods.**  On ``x = m + h cos(th)`` the branch is ``y = C_k sin(th) P_k(th)``, ``P_k`` the product of
  ``sqrt((x - e_j)/(m - e_j))`` over the other branch points (principal roots: continuous because no
  ``e_j`` lies on the segment), so ``int x^i dx / y = (h / C_k) int_0^pi x^i / P_k dth``: the square-root
  end singularities are absorbed (Gauss-Chebyshev, i.e. the midpoint rule in ``th``).  The number of
  nodes comes from the Bernstein ellipse through the nearest other branch point (Gauss error
  ``rho^(-2N)``); past 64 nodes (another branch point closer than ~2e-3 of the segment length to
  its end) a tanh-sinh rule in ``th`` is used instead, its step halved until two levels agree, because
  its nodes cluster at the ends where the near singularity is.  ``x - e_j`` near an end is formed as
  ``(e_end - e_j) -+ 2 h sin^2(.)``, so close pairs keep their relative accuracy.
* **Abel map** of ``(X, Y)``: from the nearest branch point ``e`` along the straight segment (no other
  branch point in the disc of radius ``|X - e|`` about ``X``), with ``x = e + (X - e) s^2`` so that the
  integrand is analytic in ``s`` (Gauss-Legendre, tanh-sinh past 64 nodes); the branch ends at ``Y``.
  The images of the branch points from infinity are half periods: the chain gives their
  differences and ``div y = sum e_j - (2g + 1) inf`` gives ``sum_j A(e_j) = 0``, hence ``A(e_1)``.
* **Riemann constant** (base infinity, a Weierstrass point: ``div(dx / y) = (2g - 2) inf``, so ``K`` is a half
  period): the library's one rule (:func:`thetasol.curves.riemann_constant.riemann_constant_vector`) on the
  effective divisors ``(g - 1) inf`` and three of the fixed table of test points, one theta call for all.

Everything is built from differences of branch points, so nothing depends on the units of ``x``.
Checked in tests/test_hyperelliptic.py: periods against mpmath ``quad`` at 30 digits, also with close
branch points; against :class:`~thetasol.curves.plane_curve.PlaneCurve` the bases differ by an integer
symplectic matrix (integrals and Abel maps equal modulo the lattice); tau symmetric; Jacobi inversion
(Kleinian functions from theta give back ``x1 + x2``, ``x1 x2``).  Three branch points close together
(a cusp forming) lose digits in proportion to the size of the vanishing-cycle periods.  The cost is a
small fraction of a PlaneCurve's on the same curve (benchmarks/bench_curves.py, docs/bench_curves.md).
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from fractions import Fraction
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core.panels import gauss_legendre
from thetasol.curves._numerators import Numerator
from thetasol.curves.protocol import riemann_matrix_from_periods
from thetasol.curves.riemann_constant import riemann_constant_vector, test_abscissae
from thetasol.theta.lattice import lll_gram
from thetasol.theta.riemann import RiemannTheta

__all__ = ["HyperellipticCurve"]

GAUSS_MAX = 64          # nodes of a Gauss rule before tanh-sinh takes over
DE_T = 4.0              # tanh-sinh truncation: weights below 1e-37 beyond
DE_LEVELS = (3, 11)     # steps 2^-3 .. 2^-10 (65 .. 8193 nodes)
EPS = 1e-16


@lru_cache(maxsize=16)
def _tanh_sinh(level: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nodes of the tanh-sinh rule on [-1, 1] as the complements ``1 + u``, ``1 - u`` and weights."""
    h = 2.0 ** -level
    t = np.arange(-DE_T, DE_T + h / 2, h)
    a = 0.5 * np.pi * np.sinh(t)
    lo = 2.0 / (1.0 + np.exp(-2.0 * a))    # 1 + u
    hi = 2.0 / (1.0 + np.exp(2.0 * a))     # 1 - u
    w = h * 0.5 * np.pi * np.cosh(t) / np.cosh(a) ** 2
    return lo, hi, w


def _bernstein_rho(z: np.ndarray) -> np.ndarray:
    """The Bernstein-ellipse parameter of [-1, 1] through the points z."""
    w = z + np.sqrt(z * z - 1 + 0j)
    r = np.abs(w)
    return np.maximum(r, 1 / np.where(r > 0, r, 1.0))


def _gauss_nodes(rho: float) -> int:
    """Gauss nodes for the error ``rho^(-2N)`` below EPS (0: too many, use tanh-sinh)."""
    if rho <= 1.0:
        return 0
    n = int(np.ceil(np.log(1 / EPS) / (2 * np.log(rho)))) + 2
    return max(8, -(-n // 8) * 8) if n <= GAUSS_MAX else 0


def _adaptive(rule):
    """tanh-sinh: the rule evaluated at levels 3, 4, ... until two levels agree to 1e-8 (the error of the
    finer one is then about the square, 1e-16) relative to the integral of |integrand|."""
    prev = None
    for level in range(*DE_LEVELS):
        val, size = rule(*_tanh_sinh(level))
        if prev is not None and np.all(np.abs(val - prev) <= 1e-8 * np.maximum(size, 1e-300)):
            return val
        prev = val
    raise RuntimeError("tanh-sinh quadrature did not converge (branch points too close?)")


def _symplectic_reduction(J0: np.ndarray) -> np.ndarray:
    """Integer ``M`` (rows a_1..a_g, b_1..b_g) with ``M J0 M^T = [[0, 1], [-1, 0]]``, for a unimodular J0 in
    which a pairing ``+-1`` is available at every step (true for the chain's tridiagonal form)."""
    vecs = list(np.eye(len(J0), dtype=np.int64))
    A, B = [], []
    while vecs:
        a = vecs.pop(0)
        p = [int(a @ J0 @ v) for v in vecs]
        j = next((j for j, x in enumerate(p) if abs(x) == 1), None)
        if j is None:
            raise RuntimeError("the intersection form of the chain is not unimodular (internal error)")
        b = vecs.pop(j) * p[j]            # <a, b> = 1
        vecs = [u - int(u @ J0 @ b) * a + int(u @ J0 @ a) * b for u in vecs]
        A.append(a)
        B.append(b)
    return np.array(A + B)


def _siegel_basis(Om: np.ndarray, M: np.ndarray, max_iter: int = 100) -> np.ndarray:
    """The symplectic basis ``M`` changed so that ``tau`` is Siegel-reduced (Frauendiener, Jaber & Klein 2019:
    LLL on ``Im tau``, ``|Re tau_ij| <= 1/2``, ``a_1 <-> b_1`` while ``|tau_11| < 1``): the theta sums and the
    lattice reductions of the callers then see short periods."""
    g = len(M) // 2
    for _ in range(max_iter):
        P = Om @ M.T
        tau = np.linalg.solve(P[:, :g], P[:, g:])
        U = lll_gram(0.5 * (tau.imag + tau.imag.T))          # tau -> U tau U^T
        Ma = np.rint(np.linalg.inv(U)).astype(np.int64).T @ M[:g]
        M = np.concatenate([Ma, U @ M[g:]])
        tau = U @ tau @ U.T
        S = -np.rint(0.5 * (tau.real + tau.real.T)).astype(np.int64)    # tau -> tau + S
        M = np.concatenate([M[:g], M[g:] + S.T @ M[:g]])
        t11 = tau[0, 0] + S[0, 0]
        if abs(t11) >= 1.0 - 1e-12:
            return M
        M = M.copy()
        M[[0, g]] = np.stack([M[g], -M[0]])
    raise RuntimeError("Siegel reduction did not terminate (internal error)")


@dataclass(frozen=True)
class _Segment:
    """``int_{e_a}^{e_b} x^i dx / y_k`` (i < g) on the branch ``y_k`` of the segment, and the unit directions
    of ``y_k`` as it leaves ``e_a`` and as it reaches ``e_b`` (``y`` is a local coordinate at a branch point)."""

    integrals: np.ndarray
    leave: complex
    reach: complex


def _segment(e: np.ndarray, k: int, lead: complex, g: int) -> _Segment:
    ea, eb = e[k], e[k + 1]
    m, h = (ea + eb) / 2, (eb - ea) / 2
    oth = np.delete(e, [k, k + 1])
    d = m - oth
    C = h * np.sqrt(-lead + 0j) * np.prod(np.sqrt(d))      # y = C sin(th) P(th)
    leave = C * np.prod(np.sqrt((ea - oth) / d))
    reach = C * np.prod(np.sqrt((eb - oth) / d))
    powers = np.arange(g)[:, None]

    def rule(lo, hi, w):    # lo = th, hi = pi - th, both accurate near their ends
        near_b = lo < hi
        s2 = 2 * np.sin(np.where(near_b, lo, hi) / 2) ** 2          # 1 -+ cos(th)
        xe = np.where(near_b[:, None], (eb - oth)[None, :] - h * s2[:, None], (ea - oth)[None, :] + h * s2[:, None])
        x = np.where(near_b, eb - h * s2, ea + h * s2)
        F = x[None, :] ** powers / np.prod(np.sqrt(xe / d[None, :]), axis=1)[None, :]
        return F @ w, np.abs(F) @ w

    n = _gauss_nodes(float(np.min(_bernstein_rho(-d / h)))) if len(oth) else 8
    if n:
        th = (np.arange(n) + 0.5) * (np.pi / n)
        val = rule(th, np.pi - th, np.full(n, np.pi / n))[0]
    else:
        val = _adaptive(lambda lo, hi, w: rule(0.5 * np.pi * lo, 0.5 * np.pi * hi, 0.5 * np.pi * w))
    return _Segment(h / C * val, complex(leave / abs(leave)), complex(reach / abs(reach)))


@dataclass(frozen=True, eq=False)
class HyperellipticCurve:
    """The compact Riemann surface of ``y^2 = lead * prod_j (x - e_j)``, ``2g + 1`` distinct finite branch
    points ``e_j`` (real or complex) and one at infinity.

    Conventions as :class:`~thetasol.curves.plane_curve.PlaneCurve` with the differentials
    ``omega_i = x^i dx / y`` (``i = 0..g-1``; PlaneCurve's ``x^i dx / f_y`` are half of them): the period
    matrix is ``[A | B]``, ``A_ij`` the integral of ``omega_i`` over ``a_j``, ``a_i . b_j = delta_ij``,
    ``tau = A^-1 B``, normalized coordinates ``A^-1 int omega``.  The base of the Abel map is the place
    at infinity.  Build with :meth:`from_roots` or :meth:`from_coefficients`.

    Attributes
    ----------
    branch_points : ndarray, shape (2g + 1,)
        The finite branch points in the order of the chain of cycles (sorted by real, then imaginary part).
    lead : complex
        Leading coefficient of ``f``.
    genus : int
    """

    branch_points: np.ndarray
    lead: complex
    genus: int
    chain_periods: np.ndarray = field(repr=False)    # (g, 2g): omega_i over gamma_k
    chain_intersections: np.ndarray = field(repr=False)   # (2g, 2g): gamma_k . gamma_l
    cycles: np.ndarray = field(repr=False)           # (2g, 2g) integer: a_1..a_g, b_1..b_g over gamma_k
    _branch_raw: np.ndarray = field(repr=False)      # (2g + 1, g): int_inf^{e_j} omega
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    @classmethod
    def from_roots(cls, roots: ArrayLike, lead: complex = 1.0) -> HyperellipticCurve:
        """The curve ``y^2 = lead * prod (x - roots)`` (odd number ``2g + 1 >= 3`` of distinct roots)."""
        e = np.asarray(roots, complex).ravel()
        if len(e) < 3 or len(e) % 2 == 0 or not np.all(np.isfinite(e)) or lead == 0 or not np.isfinite(lead):
            raise ValueError(f"need an odd number >= 3 of finite roots and a finite nonzero lead, got {len(e)} roots")
        e = e[np.lexsort((e.imag, e.real))]
        g = (len(e) - 1) // 2
        gap = np.min(np.abs(np.diff(e))) if len(e) > 1 else np.inf
        spread = np.max(np.abs(e - e[0]))
        if not np.min(np.abs(e[:, None] - e[None, :]) + np.eye(len(e)) * spread) > 1e-13 * spread:
            raise ValueError(f"repeated branch points (closest {gap:.2g} apart, spread {spread:.2g}): singular curve")
        segs = [_segment(e, k, complex(lead), g) for k in range(2 * g)]
        J0 = np.zeros((2 * g, 2 * g), np.int64)
        for k in range(2 * g - 1):
            # at e_{k+1}: gamma_k moves along -reach_k, gamma_{k+1} along leave_{k+1}; +1 if counterclockwise
            s = int(np.sign((np.conj(-segs[k].reach) * segs[k + 1].leave).imag))
            J0[k, k + 1], J0[k + 1, k] = s, -s
        Om = 2 * np.stack([s.integrals for s in segs], 1)
        M = _siegel_basis(Om, _symplectic_reduction(J0))
        D = np.concatenate([np.zeros((1, g), complex), np.cumsum([s.integrals for s in segs], axis=0)])
        return cls(e, complex(lead), g, Om, J0, M, D - D.sum(axis=0))

    @classmethod
    def from_coefficients(cls, coef: ArrayLike) -> HyperellipticCurve:
        """The curve ``y^2 = f(x)``, ``f`` given by its coefficients, highest first (degree ``2g + 1``)."""
        c = np.trim_zeros(np.asarray(coef, complex), "f")
        r = np.roots(c)
        for _ in range(2):   # Newton: np.roots' eigenvalues to the last bit where the roots are simple
            dp = np.polyval(np.polyder(c), r)
            r = r - np.where(dp != 0, np.polyval(c, r) / np.where(dp != 0, dp, 1), 0)
        return cls.from_roots(r, complex(c[0]))

    def f(self, x: ArrayLike) -> np.ndarray:
        """``f(x) = lead * prod (x - e_j)``."""
        x = np.asarray(x, complex)
        return self.lead * np.prod(x[..., None] - self.branch_points, axis=-1)

    def period_matrix(self) -> np.ndarray:
        """``[A | B]`` (g x 2g): the integrals of ``x^i dx / y`` over ``a_1..a_g, b_1..b_g``."""
        return self.chain_periods @ self.cycles.T

    def riemann_matrix(self) -> np.ndarray:
        """``tau = A^-1 B``, symmetric with ``Im tau`` positive definite (checked:
        :func:`thetasol.curves.protocol.riemann_matrix_from_periods`)."""
        if "tau" not in self._cache:
            self._cache["tau"] = riemann_matrix_from_periods(self.period_matrix())
        return self._cache["tau"].copy()

    def normalization(self) -> np.ndarray:
        """``A^-1`` (g x g): integrals of ``x^i dx / y`` into normalized coordinates (lattice ``Z^g + tau Z^g``)."""
        return np.linalg.inv(self.period_matrix()[:, :self.genus])

    def branch_images(self, normalized: bool = True) -> np.ndarray:
        """Abel images from infinity of :attr:`branch_points` (half periods), shape (2g + 1, g)."""
        return self._branch_raw @ self.normalization().T if normalized else self._branch_raw.copy()

    def holomorphic_numerators(self) -> tuple[Numerator, ...]:
        """The numerators ``2 x^i`` (``i < g``) of the basis ``x^i dx / y = 2 x^i dx / f_y`` of holomorphic
        differentials, ``f = y^2 - lead prod (x - e_j)`` (:class:`~thetasol.curves.protocol.Curve`)."""
        return tuple(Numerator.from_terms([(i, 0, Fraction(2), Fraction(0))]) for i in range(self.genus))

    def abel_map(self, points: ArrayLike | Mapping, base: ArrayLike | None = None, *,
                 normalized: bool = True) -> np.ndarray:
        """Abel map from ``base`` (default: the place at infinity) of points ``(x, y)`` on the curve.

        ``points``: one pair ``(x, y)`` (result shape (g,)), an array of pairs of shape ``(..., 2)`` (result
        ``(..., g)``), or a divisor ``{(x, y): multiplicity}`` (result (g,)); ``base`` a pair ``(x, y)``.
        Signature of :class:`~thetasol.curves.protocol.Curve`.

        Raises
        ------
        ValueError
            A point is not on the curve, or ``points`` is not made of pairs.
        """
        if isinstance(points, Mapping):
            pts = np.array([[complex(p[0]), complex(p[1])] for p in points], complex).reshape(-1, 2)
            weights = np.array([float(m) for m in points.values()])
            out = weights @ self._abel_xy(pts[:, 0], pts[:, 1], normalized)
        else:
            pts = np.asarray(points, complex)
            if pts.ndim == 0 or pts.shape[-1] != 2:
                raise ValueError(f"points must be (x, y) pairs (an array of shape (..., 2)), got shape {pts.shape}")
            out = self._abel_xy(pts[..., 0], pts[..., 1], normalized)
        if base is not None:
            out = out - self.abel_map(base, normalized=normalized)
        return out

    def _abel_xy(self, x: ArrayLike, y: ArrayLike, normalized: bool) -> np.ndarray:
        """Abel map from the place at infinity of the finite points ``(x, y)`` (broadcast), shape ``x.shape + (g,)``.

        The path runs from the branch point nearest to ``x`` along the straight segment, on the sheet
        ending at ``y``; the value is defined modulo the lattice.  ``y`` must satisfy ``y^2 = f(x)``
        (checked to 1e-8 relative to the size of ``f`` near the branch points; at a branch point
        either sign).

        Raises
        ------
        ValueError
            A point is not on the curve.
        """
        X, Y = np.broadcast_arrays(np.asarray(x, complex), np.asarray(y, complex))
        shape = X.shape
        X, Y = X.ravel(), Y.ravel()
        e, c, g = self.branch_points, self.lead, self.genus
        if X.size == 0:
            return np.zeros(shape + (g,), complex)
        near = np.argmin(np.abs(X[:, None] - e[None, :]), axis=1)
        en, dX = e[near], X - e[near]
        other = np.arange(len(e))[None, :] != near[:, None]
        Xe = X[:, None] - e[None, :]
        sq = np.prod(np.where(other, np.sqrt(Xe), 1.0), axis=1)            # prod_{j != near} sqrt(X - e_j)
        Y0 = np.sqrt(c) * np.sqrt(dX) * sq
        spread = np.max(np.abs(e - e[0]))
        size = np.abs(c) * np.prod(np.abs(Xe) + spread, axis=1)
        bad = np.abs(Y * Y - Y0 * Y0) > 1e-8 * (size + np.abs(Y) ** 2)
        if np.any(bad) or not np.all(np.isfinite(X)):
            i = int(np.argmax(bad))
            raise ValueError(f"point ({X[i]}, {Y[i]}) is not on the curve: y^2 - f(x) = {Y[i] ** 2 - Y0[i] ** 2:.3g}")
        sign = np.where((Y * np.conj(Y0)).real < 0, -1.0, 1.0)
        pref = 2 * np.sqrt(dX) / (sign * np.sqrt(c) * sq)
        safe = np.where(dX != 0, dX, 1.0)
        sj = np.sqrt((e[None, :] - en[:, None]) / safe[:, None])
        rho = np.where(other & (dX != 0)[:, None], _bernstein_rho(sj), np.inf)
        powers = np.arange(g)

        def rule(s, w):   # int_0^1 x^i / prod sqrt(r_j) ds, r_j = (x - e_j)/(X - e_j), x = e + (X - e) s^2
            s2 = s * s
            num = (en[:, None, None] - e[None, None, :]) + dX[:, None, None] * s2[None, :, None]
            r = np.where(other[:, None, :], num / np.where(other, Xe, 1.0)[:, None, :], 1.0)
            xs = en[:, None] + dX[:, None] * s2[None, :]
            F = xs[..., None] ** powers / np.prod(np.sqrt(r), axis=2)[..., None]
            return np.einsum("mnk,n->mk", F, w), np.einsum("mnk,n->mk", np.abs(F), w)

        n = _gauss_nodes(float(np.min(rho))) if np.isfinite(np.min(rho)) else 8
        if n:
            s, w = gauss_legendre(n)
            val = rule(s, 0.5 * w)[0]
        else:
            val = _adaptive(lambda lo, hi, w: rule(0.5 * lo, 0.5 * w))
        raw = self._branch_raw[near] + pref[:, None] * val
        out = raw @ self.normalization().T if normalized else raw
        return out.reshape(shape + (g,))

    def riemann_constant(self, base: ArrayLike | None = None, *, theta: RiemannTheta | None = None) -> np.ndarray:
        """Vector of Riemann constants (normalized coordinates) with base at infinity, or at ``base``
        (a pair ``(x, y)``: ``K + (g - 1) A(base)``).

        A half period (module docstring), chosen by the library's one rule
        (:func:`thetasol.curves.riemann_constant.riemann_constant_vector`).  With it ``theta(A(P) - A(D) - K)``
        vanishes exactly at the points of a generic effective divisor ``D`` of degree g.  ``theta``: a
        :class:`~thetasol.theta.riemann.RiemannTheta` of :meth:`riemann_matrix` to reuse (its set-up is
        most of the cost).

        Raises
        ------
        RuntimeError
            No candidate makes theta vanish unambiguously (nearly degenerate curve).
        """
        g = self.genus
        if "K" not in self._cache:
            e = self.branch_points
            center = np.mean(e)
            x, sheet = test_abscissae(center, float(np.max(np.abs(e - center))), g - 1)
            y = np.sqrt(self.f(x)) * np.where(sheet % 2 == 1, -1.0, 1.0)
            D = np.concatenate([np.zeros((1, g), complex), self._abel_xy(x, y, True).sum(axis=1)])
            self._cache["K"] = riemann_constant_vector(self.riemann_matrix(), np.zeros(g, complex), D, theta=theta)
        K = self._cache["K"].copy()
        if base is not None:
            K = K + (g - 1) * self.abel_map(base)
        return K
