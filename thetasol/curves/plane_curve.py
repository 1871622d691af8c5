"""Compact Riemann surfaces of plane curves f(x, y) = 0: homology, periods, Abel map, Riemann constant.

Method (details and conventions in docs/curves.md).  The curve is a degree-n cover of the x-line.
Its finite critical values (roots of disc_y(f) * lc_y(f), found exactly with sympy, then
numerically) are separated by the edges of their Voronoi diagram clipped by a square
(:mod:`thetasol.curves._paths`).  The n sheets are continued along every edge by vectorized root finding
with a Hermite matching test (:mod:`thetasol.curves._quad`); the lifted edges form a ribbon graph on
the surface, whose intersection form gives a symplectic basis of H_1 by integer reduction
(:mod:`thetasol.curves._homology`).  The genus comes from Riemann-Hurwitz applied to the local monodromies
and is cross-checked against the rank of the intersection form and the number of holomorphic
differentials.  Periods are sums of Gauss-Legendre integrals along the edges (tolerance 1e-15 per
edge, rules chosen from the Bernstein ellipse of each interval, each interval summed in
double-double so that the many-edge sums keep float64 accuracy); the ``dps`` path redoes the
quadrature on the same topology with mpmath from the exact coefficients.

Hand-written rather than wrapping a library: the reference implementations (Sage's
RiemannSurface, abelfunctions, Maple's algcurves) are not available as dependencies, and the
spectral curves of the rigid body need vectorized speed and an explicit treatment of nearly
degenerate curves.
"""
from __future__ import annotations

import sys
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from thetasol.curves._homology import LiftedGraph, symplectic_basis
from thetasol.curves._numerators import Numerator
from thetasol.curves._paths import CellGraph
from thetasol.curves._places import (
    CurveEngine,
    expansion,
    holomorphic_basis,
    laurent,
    local_of,
    local_sites,
    near_site,
    noise_level,
    perm_cycles,
    place_series,
    prefetch_local,
    regular_samples,
    series_eval,
    series_integral,
)
from thetasol.curves._poly import CurvePoly, polynomial_roots, root_corrections
from thetasol.curves._quad import Piece, Tracker, shaped_integrals
from thetasol.curves.protocol import riemann_matrix_from_periods

if TYPE_CHECKING:
    import mpmath
    import sympy

    from thetasol.theta.riemann import RiemannTheta

__all__ = ["Numerator", "PlaneCurve", "Place"]

INF = complex("inf")


class Place:
    """A place of the curve: a point of its normalization (compact Riemann surface).

    Attributes
    ----------
    x : complex or ``inf``
        The x-coordinate (``complex('inf')`` for places over x = infinity).
    y : complex
        The limit of y at the place (``inf`` at a pole of y); ``None`` if not yet computed.
    e : int
        Ramification index over the x-line.  The local parameter is ``t`` with
        ``x = x0 + t**e`` (finite x0) or ``x = t**(-e)`` (x0 = infinity).
    kind : str
        'regular' (x not a critical value), 'critical' (over a finite critical value) or 'infinity'.
    """

    def __init__(self, curve, kind, x, e, site=-1, ref=None, label=None, cycle=None, y=None):
        self.curve = curve
        self.kind = kind
        self.x = complex(x)
        self.e = int(e)
        self.site = site  # the index of the critical value under a critical place (-1 otherwise)
        self._ref = ref  # reference vertex of the path graph
        self._label = label  # reference sheet label at that vertex
        self.cycle = cycle  # the cycle of sheets around that critical value or infinity (None if regular)
        self._y = y

    @property
    def y(self) -> complex:
        if self._y is None and self.kind != "regular":
            self.curve._place_limits([self])
        return self._y

    @property
    def is_infinite(self) -> bool:
        return self.kind == "infinity"

    def _key(self):
        if self.kind == "regular":
            return ("regular", self.x, self._y)
        return (self.kind, self.site, self.cycle)

    def __eq__(self, other):
        return isinstance(other, Place) and other.curve is self.curve and other._key() == self._key()

    def __hash__(self):
        return hash((id(self.curve),) + tuple(map(str, self._key())))

    def __repr__(self):
        xs = "oo" if self.kind == "infinity" else f"{self.x:.6g}"
        ys = "?" if self._y is None else ("oo" if np.isinf(abs(self._y)) else f"{self._y:.6g}")
        return f"Place(x={xs}, y={ys}, e={self.e}, kind={self.kind!r})"

    def series(self, order: int = 8) -> tuple[np.ndarray, np.ndarray]:
        """Laurent-Puiseux expansion of y at this place in the local parameter t.

        Returns (k, c): integer exponents (from the lowest significant one, negative at a pole of y)
        up to ``order``, and the coefficients, y = sum c_k t^k.  Computed by FFT from samples of the
        sheets on a circle (see docs/curves.md); coefficient k is accurate to about 1e-16 * 2^k
        relative to the largest term.
        """
        return expansion(self.curve, self, None, int(order), "y")

    def expand(self, numerator: str | sympy.Expr | Numerator, order: int = 8,
               differential: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Expansion of g(x, y) dx / f_y (differential=True) or of the function g(x, y) at this place.

        Returns (k, c) with g dx / f_y = sum c_k t^k dt (or g = sum c_k t^k) in the local parameter
        t of :meth:`local_parameter`; see :meth:`series`.
        """
        P = self.curve.engine.numerators([numerator])
        return expansion(self.curve, self, P, int(order), "differential" if differential else "function")

    @property
    def sampling_radius(self) -> float:
        """Radius ``|t|`` of the circle of the local parameter on which :meth:`series` and :meth:`expand`
        sample this place.

        The FFT coefficients are accurate relative to the largest term ``|c_k| r^k`` on that circle, not
        to the largest ``|c_k|``: a coefficient is significant when ``|c_k| r^k`` is.  Where the series
        converges only in a small disc (branch points close to the place) the ``c_k`` grow like
        ``r^-k`` and only the scaled comparison reads orders of vanishing correctly.
        """
        if self.kind == "regular":
            key = ("regsamples", self.x, self.y)
            if key not in self.curve._cache:
                self.curve._cache[key] = regular_samples(self.curve, self.x, self.y)
            return float(abs(self.curve._cache[key][0][0]))
        return float(abs(self.curve._place_data(self, None, None)[1]))

    def local_parameter(self) -> str:
        """The local parameter t, as text."""
        if self.kind == "infinity":
            return f"t with x = t**(-{self.e})" if self.e > 1 else "t = 1/x"
        return f"t with x = {self.x:.6g} + t**{self.e}" if self.e > 1 else f"t = x - ({self.x:.6g})"


class PlaneCurve:
    """The compact Riemann surface of an irreducible plane curve f(x, y) = 0, as a cover of the x-line.

    Parameters
    ----------
    f : sympy expression or Poly
        Irreducible polynomial in ``x`` and ``y`` with rational or floating-point coefficients
        (floats are taken as the exact binary rationals they represent).
    x, y : sympy Symbols
        The coordinates; the curve is viewed as an n-sheeted cover of the x-line, n = deg_y f.

    Notes
    -----
    All quantities refer to the normalization of the curve (its compact Riemann surface): for a
    singular curve, ``genus`` is the geometric genus.  Conventions (docs/curves.md): differentials are
    ``omega = g(x, y) dx / f_y``; the period matrix is ``[A | B]`` with ``A_ij`` the integral of
    ``omega_i`` over ``a_j``, the basis symplectic with ``a_i . b_j = delta_ij``; ``tau = A^-1 B``.
    """

    def __init__(self, f, x, y, *, _extra_sites=None, _tol=1e-15, _poly=None):
        # _poly: the curve already as a CurvePoly (a subclass with exact coefficients skips sympy's parsing;
        # its coordinates are the curve's)
        self._poly = CurvePoly(f, x, y) if _poly is None else _poly
        self.n = self._poly.n
        if not self._poly.x_content_is_constant():
            raise ValueError("f is reducible: a polynomial in x alone divides it")
        F = self._poly.critical_polynomial()
        self._sites = polynomial_roots(F)
        self._sites_lo = root_corrections(F, self._sites)  # exact critical value = _sites + _sites_lo
        self._graph = CellGraph(self._sites, _extra_sites)
        from thetasol.curves._mp import ExactEvaluator
        self._exact = ExactEvaluator(self._poly)
        self._tracker = Tracker(self._poly, self._graph.allsites, tol=_tol, mp_fallback=self._exact.fallback,
                                exact=self._exact)
        self._setup_sheets()
        self._cache = {}
        #: The numerical machinery the places and samples are computed with (:mod:`thetasol.curves._places`).
        self.engine = CurveEngine(poly=self._poly, sites=self._sites, sites_lo=self._sites_lo, graph=self._graph,
                                  exact=self._exact, tracker=self._tracker, vroots=self._vroots, cache=self._cache)

    # ------------------------------------------------------------------ topology
    def _setup_sheets(self):
        G = self._graph
        R = self._tracker._eval_nodes(G.V, np.zeros(len(G.V), complex))[0]
        order = np.lexsort((R.imag, R.real), axis=1) if R.shape[1] > 1 else np.zeros(R.shape, int)
        self._vroots = np.take_along_axis(R, order, axis=1)
        pieces = [Piece("line", G.V[a], G.V[b], self._vroots[a]) for a, b in G.edges]
        tr = self._tracker.track(pieces, precise=False)   # (their sums are all redone in double-double)
        self._edge_tracks = tr
        n = self.n
        perms = np.zeros((len(G.edges), n), dtype=int)
        for e, (_, b) in enumerate(G.edges):
            d = np.abs(tr.ends[e][:, None] - self._vroots[b][None, :])
            p = np.argmin(d, axis=1)
            if len(set(p.tolist())) != n:
                raise ValueError("sheet continuation along the path graph failed (numerically singular curve)")
            perms[e] = p
        self._perms = perms
        self._invperms = np.argsort(perms, axis=1)
        self._lifted = LiftedGraph(len(G.V), G.edges, G.star, perms, n, (G.base, 0))
        if not self._lifted.connected:
            raise ValueError("f is reducible over the complex numbers: its monodromy group is not transitive")
        # local monodromies
        self._site_perm = [self._walk(seq) for seq in G.cells]
        self._inf_perm = self._walk(G.outer)
        chi = -2 * n + sum(n - len(perm_cycles(p)) for p in self._site_perm + [self._inf_perm])
        if chi % 2:
            raise RuntimeError("Riemann-Hurwitz gives an odd Euler characteristic (internal error)")
        self._genus = chi // 2 + 1

    def _walk(self, seq):
        n = self.n
        out = np.arange(n)
        for e, sg in seq:
            out = self._perms[e][out] if sg == 1 else self._invperms[e][out]
        return out

    @property
    def genus(self) -> int:
        """Genus of the compact Riemann surface (geometric genus of the curve), from Riemann-Hurwitz."""
        return self._genus

    @property
    def arithmetic_genus(self) -> int:
        """Number of interior lattice points of the Newton polygon (Baker's bound on the genus)."""
        return len(self._poly.interior_points())

    @property
    def branch_points(self) -> np.ndarray:
        """Finite critical values of x (roots of disc_y(f) lc_y(f)), including those with trivial monodromy."""
        return self._sites.copy()

    @property
    def base_point(self) -> tuple[complex, complex]:
        """The default base point (x0, y0) of the Abel map: lower-left corner of the path box, sheet 0."""
        G = self._graph
        return complex(G.V[G.base]), complex(self._vroots[G.base][0])

    def sheets(self) -> tuple[complex, np.ndarray]:
        """The base x0 and the n values of y over it, in the order used by :meth:`monodromy`."""
        G = self._graph
        return complex(G.V[G.base]), self._vroots[G.base].copy()

    def monodromy(self) -> tuple[complex, np.ndarray, list[tuple[complex, np.ndarray]]]:
        """Local monodromy of every critical value, on the sheets of :meth:`sheets`.

        Returns (x0, y0, [(b, perm)]) with b a branch point (``inf`` last) and perm[i] = j when
        sheet i continued once counter-clockwise around b alone (along the tree path to its cell,
        around the cell, and back) ends on sheet j.
        """
        G = self._graph
        out = []
        for k, s in enumerate(self._sites):
            v = G.cell_vertices[k][0]
            out.append((complex(s), self._conj_perm(v, self._site_perm[k])))
        # infinity: the box boundary walked clockwise is a positive loop around infinity
        pinf = np.argsort(self._inf_perm)
        out.append((INF, pinf.copy()))
        return complex(G.V[G.base]), self._vroots[G.base].copy(), out

    def _tree_perm(self, v):
        """Map base sheet -> label at vertex v along the plane spanning tree path (BFS)."""
        if "tree" not in self._cache:
            G = self._graph
            parent = {G.base: None}
            order = [G.base]
            for u in order:
                for e, is_tail in G.star[u]:
                    a, b = G.edges[e]
                    w = b if is_tail else a
                    if w not in parent:
                        parent[w] = (u, e, 1 if is_tail else -1)
                        order.append(w)
            maps = {G.base: np.arange(self.n)}
            for u in order[1:]:
                pu, e, sg = parent[u]
                maps[u] = self._perms[e][maps[pu]] if sg == 1 else self._invperms[e][maps[pu]]
            self._cache["tree"] = maps
        return self._cache["tree"][v]

    def _conj_perm(self, v, perm_at_v):
        m = self._tree_perm(v)  # base sheet i -> label m[i] at v
        inv = np.argsort(m)
        return inv[perm_at_v[m]]

    x = property(lambda self: self._poly.x, doc="The coordinate x (sympy Symbol).")
    y = property(lambda self: self._poly.y, doc="The coordinate y (sympy Symbol).")

    # ------------------------------------------------------------------ differentials
    def polynomial(self) -> sympy.Expr:
        """The curve's polynomial f(x, y) as an exact sympy expression (rational coefficients)."""
        return self._poly.sympy_expr()

    def differential_values(self, numerators: Sequence[str | sympy.Expr | Numerator], x: ArrayLike, y: ArrayLike) -> np.ndarray:
        """Values ``g_d(x, y) / f_y(x, y)`` of the differentials ``g_d dx / f_y`` at points of the curve.

        Parameters
        ----------
        numerators : sequence of Numerator, sympy expressions or str
            Polynomials ``g_d`` in ``x``, ``y`` (e.g. :meth:`holomorphic_differentials`).
        x, y : array_like, same shape
            Points ``(x, y)`` on the curve (``y`` a root of ``f(x, .)``).

        Returns
        -------
        ndarray, shape ``(len(numerators),) + x.shape``
            Integrands with respect to ``x``: a quadrature rule in ``x`` applied to them integrates the
            differentials along a path on the sheet the ``y`` values follow.
        """
        P = np.asarray(self.engine.numerators(numerators))
        x = np.asarray(x, complex)
        y = np.asarray(y, complex)
        col = (slice(None),) + (None,) * x.ndim
        num = np.zeros(P.shape[:1] + x.shape, complex)
        for i in range(P.shape[1]):
            for j in range(P.shape[2]):
                if np.any(P[:, i, j]):
                    num += P[:, i, j][col] * (x ** i * y ** j)[None]
        fy, _ = self._poly.fy_fx(x.ravel(), y.ravel()[:, None])
        return num / fy.reshape(x.shape)[None]

    def holomorphic_differentials(self) -> list:
        """Numerators g (sympy polynomials in x, y) of a basis of holomorphic differentials g dx / f_y.

        From the interior lattice points (i, j) of the Newton polygon, g = x^(i-1) y^(j-1), when
        their number equals the genus (f nondegenerate for its Newton polygon); otherwise the
        subspace of their span that satisfies the adjoint conditions at the singular points
        (Laurent coefficients at every place, or at those a subclass knows to hold the singular points).
        The same numerators as exact :class:`Numerator` objects: :meth:`holomorphic_numerators`.
        """
        return [g.to_sympy(self.x, self.y) for g in self.holomorphic_numerators()]

    def holomorphic_numerators(self) -> tuple[Numerator, ...]:
        """:meth:`holomorphic_differentials` as :class:`Numerator` objects (exact coefficients; no sympy).

        Every method that takes numerators accepts them, and the engine's own default is this basis.
        """
        if "holo" not in self._cache:
            self._cache["holo"] = holomorphic_basis(self, self._poly.interior_points(), self._singular_sites())
        return self._cache["holo"]

    def _singular_sites(self):
        """Entries of the local data (-1: infinity) known to hold every singular point; None: unknown."""
        return None

    # ------------------------------------------------------------------ homology and periods
    def _homology(self):
        if "hom" not in self._cache:
            L = self._lifted
            cyc = L.fundamental_cycles()
            G = L.pairing_matrix()
            lens = np.abs(self._graph.V[self._graph.edges[:, 1]] - self._graph.V[self._graph.edges[:, 0]])
            w = np.repeat(lens / max(lens.max(), 1e-300), self.n) + 1e-3
            a, b, rank = symplectic_basis(cyc, G, weights=w)
            if rank != 2 * self.genus:
                raise RuntimeError(
                    f"rank of the intersection form {rank} != 2 * genus {2 * self.genus}: the sheet "
                    "continuation is inconsistent (numerically singular curve?)")
            self._cache["hom"] = (a, b, G)
        return self._cache["hom"]

    def homology_basis(self) -> tuple[np.ndarray, np.ndarray]:
        """The symplectic basis as integer vectors over the lifted edges: (a, b), each (g, n_edges * n)."""
        a, b, _ = self._homology()
        return a.copy(), b.copy()

    def intersection_matrix(self) -> np.ndarray:
        """Intersection matrix of (a_1..a_g, b_1..b_g): the standard [[0, 1], [-1, 0]] by construction."""
        a, b, G = self._homology()
        C = np.vstack([a, b])
        return C @ G @ C.T

    def _edge_integrals(self, P):
        # all in double-double (float64 sums over many edges lose digits); periods, potentials share it
        ck = ("edges", P.shape, P.tobytes(), repr(getattr(P, "exact", None)))
        if ck not in self._cache:    # rows e * n + s, one column per numerator
            self._cache[ck] = np.concatenate(self._edge_tracks.integrate(P, dd_all=True), axis=0)
        return self._cache[ck]

    def _period_matrix_mp(self, diffs, dps):
        from thetasol.curves._mp import cycle_sums_mp, integrate_mp
        key = ("pm_mp", tuple(map(str, diffs)), dps)
        if key in self._cache:
            return self._cache[key].copy()
        G = self._graph
        tr_mp = Tracker(self._poly, G.allsites, tol=10.0 ** (-(dps + 3)), mp_fallback=self._exact.fallback)
        pieces = [Piece("line", G.V[a], G.V[b], self._vroots[a]) for a, b in G.edges]
        tr = tr_mp.track(pieces)
        for e, (_, b) in enumerate(G.edges):
            p = np.argmin(np.abs(tr.ends[e][:, None] - self._vroots[b][None, :]), axis=1)
            if not np.array_equal(p, self._perms[e]):
                raise RuntimeError("the dps path found a different sheet permutation (internal error)")
        res = integrate_mp(tr, self._exact, self.engine.numerators(diffs).exact, dps)
        A, B, _ = self._homology()
        Pm = cycle_sums_mp(res, list(A) + list(B), len(diffs), self.n, dps)
        self._cache[key] = Pm
        return Pm.copy()

    def period_matrix(self, differentials: Sequence[str | sympy.Expr | Numerator] | None = None,
                      dps: int | None = None) -> np.ndarray | mpmath.matrix:
        """Periods [A | B] (g x 2g complex) of the differentials g dx / f_y over the symplectic basis.

        Parameters
        ----------
        differentials : sequence of Numerator or sympy polynomials, optional
            Numerators g; default :meth:`holomorphic_differentials`.  Any polynomial numerators are
            accepted (meromorphic differentials give their periods over the same cycles).
        dps : int, optional
            Decimal digits: return an ``mpmath.matrix`` computed at that precision (same cycles as the
            float64 result, quadrature and roots redone in mpmath from the exact coefficients).
        """
        if dps is not None:
            if int(dps) != dps or dps < 15:
                raise ValueError(f"dps must be an integer >= 15, got {dps}")
            diffs = self.holomorphic_numerators() if differentials is None else list(differentials)
            return self._period_matrix_mp(diffs, int(dps))
        key = ("pm", None if differentials is None else tuple(map(str, differentials)))
        if key not in self._cache:
            diffs = self.holomorphic_numerators() if differentials is None else list(differentials)
            a, b, _ = self._homology()
            Iv = self._edge_integrals(self.engine.numerators(diffs))
            PA = (a @ Iv).T
            PB = (b @ Iv).T
            self._cache[key] = np.hstack([PA, PB])
        return self._cache[key].copy()

    def riemann_matrix(self, dps: int | None = None) -> np.ndarray | mpmath.matrix:
        """tau = A^-1 B for the default holomorphic differentials; symmetric with Im tau > 0 (checked:
        :func:`thetasol.curves.protocol.riemann_matrix_from_periods`).

        With ``dps``: an ``mpmath.matrix`` at that precision.
        """
        if dps is not None:
            import mpmath
            P = self.period_matrix(dps=dps)
            g = self.genus
            with mpmath.workdps(int(dps) + 10):
                A = mpmath.matrix([[P[i, j] for j in range(g)] for i in range(g)])
                B = mpmath.matrix([[P[i, g + j] for j in range(g)] for i in range(g)])
                tau = mpmath.inverse(A) * B if g else mpmath.matrix(0, 0)
                tau = (tau + tau.T) / 2
            return tau
        if "tau" not in self._cache:
            self._cache["tau"] = riemann_matrix_from_periods(self.period_matrix())
        return self._cache["tau"].copy()

    # ------------------------------------------------------------------ places
    def _site_places(self, k):
        """The places over critical value k (over infinity for k = -1), one per cycle of the monodromy."""
        if ("places", k) not in self._cache:
            lds = local_sites(self)
            ld = lds[k if k >= 0 else len(lds) - 1]
            x, kind = (ld.center, "critical") if ld.kind == "critical" else (INF, "infinity")
            self._cache["places", k] = [Place(self, kind, x, len(cyc), site=ld.site, ref=ld.ref, label=cyc[0],
                                              cycle=cyc) for cyc in ld.cycles]
        return self._cache["places", k]

    def _place_limits(self, places):
        for P in places:
            ld = local_of(self, P)
            t, xs, ys = ld.place_samples(P.cycle)
            k, c, _ = laurent(t, ys)
            scale = np.max(np.abs(ys)) + 1e-300
            neg = np.abs(c[k < 0] * t[0] ** k[k < 0])
            P._y = INF if neg.size and neg.max() > 1e-8 * scale else complex(c[k == 0][0])

    def places_at_infinity(self) -> list:
        """The places over x = infinity (one per cycle of the monodromy at infinity)."""
        return list(self._site_places(-1))

    def places_over(self, x0: complex) -> list:
        """All places over x = x0 (a complex number or ``inf``)."""
        x0 = complex(x0)
        if not np.isfinite(x0):
            return self.places_at_infinity()
        k = self._site_index(x0)
        if k >= 0:
            return list(self._site_places(k))
        R, _ = self._poly.roots(np.array([x0]))
        return [Place(self, "regular", x0, 1, y=complex(v)) for v in R[0]]

    def _site_index(self, x0, rtol=1e-10):
        if len(self._sites) == 0:
            return -1
        d = np.abs(self._sites - x0)
        k = int(np.argmin(d))
        scale = max(abs(self._sites[k]), self._graph.min_sep, 1e-300)
        return k if d[k] <= rtol * scale else -1

    def place(self, x0: complex, y0: complex | None = None) -> Place:
        """The place over x0 (finite or ``inf``) with y-limit y0 (optional if it is unique)."""
        cands = self.places_over(x0)
        if y0 is None:
            if len(cands) == 1:
                return cands[0]
            raise ValueError(f"{len(cands)} places over x = {x0}: give y0 or pick one from places_over")
        y0 = complex(y0)
        ys = np.array([P.y for P in cands])
        if np.isinf(abs(y0)):
            hit = [P for P in cands if np.isinf(abs(P.y))]
        else:
            fin = np.isfinite(ys)
            d = np.where(fin, np.abs(ys - y0), np.inf)
            tol = 1e-6 * (1 + abs(y0))
            hit = [P for P, dd in zip(cands, d) if dd <= max(tol, 1e-6 * d.min())] if d.min() <= 1e-4 * (1 + abs(y0)) else []
            if not hit:
                raise ValueError(f"({x0}, {y0}) is not a point of the curve (nearest y over x0: "
                                 f"{ys[np.argmin(d)]:.8g})")
        if len(hit) != 1:
            raise ValueError(f"{len(hit)} places over ({x0}, {y0}) (a singular point): pick one from places_over")
        return hit[0]

    # ------------------------------------------------------------------ Abel map
    def _potentials(self, P, key):
        """Integral from the base (base vertex, sheet 0) to every lifted vertex along the lifted tree."""
        ck = ("phi", key)
        if ck not in self._cache:
            L = self._lifted
            Iv = self._edge_integrals(P)
            phi = np.zeros((L.nv * L.n, Iv.shape[1]), dtype=complex)
            for u in L.order[1:]:
                le, sg = L.parent[u], L.psign[u]
                prev = L.ltail[le] if sg == 1 else L.lhead[le]
                phi[u] = phi[prev] + sg * Iv[le]
            self._cache[ck] = phi
        return self._cache[ck]

    def _parse_targets(self, points):
        """Normalize the input of abel_map: returns (targets, weights, shape) where shape is
        'single', 'list' or 'divisor'."""
        # a sympy number can only be given once sympy is loaded: the test does not import it
        sp = sys.modules.get("sympy")

        def is_scalar(v):
            return isinstance(v, (int, float, complex, np.number)) or (
                sp is not None and isinstance(v, sp.Basic) and v.is_number)

        if isinstance(points, Place):
            return [points], None, "single"
        if isinstance(points, dict):
            items = list(points.items())
            return [self._as_target(p) for p, _ in items], np.array([m for _, m in items], dtype=float), "divisor"
        if isinstance(points, (tuple, list)) and len(points) == 2 and all(is_scalar(v) for v in points):
            return [self._as_target(tuple(points))], None, "single"
        arr = points
        if isinstance(arr, np.ndarray) and arr.ndim == 2 and arr.shape[1] == 2:
            return [self._as_target((a, b)) for a, b in arr], None, "list"
        return [self._as_target(p) for p in points], None, "list"

    def _as_target(self, p):
        if isinstance(p, Place):
            if p.curve is not self:
                raise ValueError("place belongs to another curve")
            return p
        try:
            x0, y0 = p
            x0, y0 = complex(x0), complex(y0)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"a point must be a Place or an (x, y) pair, got {p!r}") from exc
        if not (np.isfinite(x0) and np.isfinite(y0)):
            raise ValueError(f"point ({x0}, {y0}) is not finite: use places_at_infinity() for points at infinity")
        # on the curve?
        A = self._poly.coeff_polys(np.array([x0]))
        val, _ = self._poly.horner_y(A, np.array([[y0]]))
        absA = self._poly.abs_coeff_polys(np.array([abs(x0)]))
        sc, _ = self._poly.horner_y(absA, np.array([[abs(y0)]]))
        if abs(val[0, 0]) > 1e-8 * sc[0, 0]:
            raise ValueError(f"({x0}, {y0}) is not on the curve: |f| = {abs(val[0, 0]):.3g} "
                             f"(relative {abs(val[0, 0]) / sc[0, 0]:.3g})")
        k = self._site_index(x0, rtol=1e-14)
        if k >= 0:
            return self.place(self._sites[k], y0)
        return (x0, y0)

    def _local(self):
        return local_sites(self)

    def _place_data(self, place, P, key):
        """(k, t0, Fy, Fh) Laurent data of a critical or infinite place for numerators P."""
        ck = ("pser", key, place._key())
        if ck not in self._cache:
            self._cache[ck] = place_series(self, local_of(self, place), place.cycle, P)
        return self._cache[ck]

    def _series_integral(self, place, P, key, t):
        """Integral from the place to its local parameter t along its Laurent series."""
        k, t0, _, Fh = self._place_data(place, P, key)
        return series_integral(k, t0, Fh, t0 if t is None else t, noise=noise_level(local_of(self, place)))

    def _place_value(self, place, P, key):
        """Integral from the default base to a critical or infinite place."""
        ld = local_of(self, place)
        ck = ("lines", key)
        if ck not in self._cache:
            self._cache[ck] = local_sites(self).lines.integrate(P)
        lines = self._cache[ck]
        phi = self._potentials(P, key)
        # the approach line ends at the float x1 = b + xi0 exactly (xi0 is measured from the exact
        # critical value), so the series tail starts at the local parameter t0 of that very point
        tail = self._series_integral(place, P, key, None)
        return phi[ld.ref * self.n + place._label] + lines[ld.index][place._label] - tail

    def _near_place(self, x0, y0):
        """If (x0, y0) is inside the disc where a local series converges fast: (place, t)."""
        lds = self._local()
        k = near_site(lds, self._sites, x0)
        if k is None:
            return None
        ld = lds[k]
        cands = self._site_places(ld.site)
        best = []
        for P in cands:
            k, t0, Fy, _ = self._place_data(P, None, None)
            e = P.e
            base_t = x0 ** (-1.0 / e) if ld.kind == "infinity" else ((x0 - ld.center) - ld.center_lo) ** (1.0 / e)
            for j in range(e):
                t = base_t * np.exp(2j * np.pi * j / e)
                yv = series_eval(k, t0, Fy, t)
                best.append((abs(yv - y0), P, t))
        best.sort(key=lambda r: r[0])
        if best[0][0] > 1e-6 * (1 + abs(y0)) or (len(best) > 1 and best[1][0] < 10 * best[0][0]):
            raise ValueError(f"cannot identify the branch of ({x0}, {y0}) near a critical value "
                             "(not on the curve, or too close to a singular point): pass a Place")
        return best[0][1], best[0][2]

    def _abel_raw(self, targets, P, key):
        """Integrals of the numerators P from the default base point to every target: (N, nd)."""
        G = self._graph
        n = self.n
        phi = self._potentials(P, key)
        out = np.zeros((len(targets), P.shape[0]), dtype=complex)
        prefetch_local(self, targets)
        pts_idx, pieces1, starts = [], [], []
        for i, t in enumerate(targets):
            if isinstance(t, Place) and t.kind != "regular":
                out[i] = self._place_value(t, P, key)
                continue
            x0, yv = (t.x, t.y) if isinstance(t, Place) else t
            near = self._near_place(x0, yv)
            if near is not None:
                pl, tt = near
                out[i] = self._place_value(pl, P, key) + self._series_integral(pl, P, key, tt)
                continue
            kind, k, e, sg, q = G.locate(x0)
            a, b = G.edges[e]
            u = a if sg == 1 else b
            pts_idx.append(i)
            starts.append(u)
            pieces1.append(Piece("line", G.V[u], q, self._vroots[u]))
        if pieces1:
            tr1 = self._tracker.track(pieces1)
            pieces2 = [Piece("line", pc.b, (targets[i].x if isinstance(targets[i], Place) else targets[i][0]), y1)
                       for i, pc, y1 in zip(pts_idx, pieces1, tr1.ends)]
            tr2 = self._tracker.track(pieces2)
            I1 = tr1.integrate(P)
            I2 = tr2.integrate(P)
            for j, i in enumerate(pts_idx):
                t = targets[i]
                yv = t.y if isinstance(t, Place) else t[1]
                ends = tr2.ends[j]
                d = np.abs(ends - yv)
                ell = int(np.argmin(d))
                sep = np.partition(d, 1)[1] if n > 1 else np.inf
                if d[ell] > 1e-6 * (1 + abs(yv)) or d[ell] > 0.1 * sep:
                    raise ValueError(f"point ({t[0] if not isinstance(t, Place) else t.x}, {yv}) is not on "
                                     "the curve (or too close to a singular point to identify its sheet)")
                out[i] = phi[starts[j] * n + ell] + I1[j][ell] + I2[j][ell]
        return out

    def _holo_arrays(self):
        if "holoP" not in self._cache:
            self._cache["holoP"] = self.engine.numerators(self.holomorphic_numerators())
        return self._cache["holoP"]

    def normalization(self) -> np.ndarray:
        """A^-1 (g x g): multiplies holomorphic-differential integrals into normalized coordinates."""
        g = self.genus
        P = self.period_matrix()
        return np.linalg.inv(P[:, :g])

    def abel_map(self, points: Place | Sequence | Mapping, base: Place | tuple[complex, complex] | None = None, *,
                 normalized: bool = True) -> np.ndarray:
        """Abel map of points, places or divisors.

        Parameters
        ----------
        points : Place, (x, y) pair, sequence of these (or an array of pairs, shape (..., 2)), or dict
            {point or place: multiplicity}.  Finite points are (x, y) pairs on the curve; places over critical values and infinity come
            from :meth:`places_over` / :meth:`places_at_infinity` (an (x, y) pair at a critical value
            is accepted when it determines the place).
        base : Place or (x, y), optional
            Base point; default :attr:`base_point`.
        normalized : bool
            True (default): coordinates in which the period lattice is Z^g + tau Z^g
            (integrals of the normalized differentials A^-1 omega); False: integrals of the
            differentials of :meth:`holomorphic_differentials`, lattice = columns of period_matrix().

        Returns
        -------
        (g,) for one point or a divisor (sum of multiplicity * image), (N, g) for a sequence, ``(..., g)``
        for an array of pairs (the signature of :class:`~thetasol.curves.protocol.Curve`).
        Values are path integrals along the documented paths (docs/curves.md); they are defined modulo
        the lattice: another path adds a lattice vector.
        """
        if isinstance(points, np.ndarray) and points.ndim > 2 and points.shape[-1] == 2:    # pairs of any shape
            flat = self.abel_map(points.reshape(-1, 2), base, normalized=normalized)
            return flat.reshape(points.shape[:-1] + (self.genus,))
        targets, weights, shape = self._parse_targets(points)
        P = self._holo_arrays()
        raw = self._abel_raw(targets, P, "holo")
        if base is not None:
            braw = self._abel_raw([self._as_target(base)], P, "holo")[0]
            raw = raw - braw[None, :]
        if normalized:
            raw = raw @ self.normalization().T
        return shaped_integrals(raw, weights, shape)

    def integrate(self, numerators: Sequence[str | sympy.Expr | Numerator], points: Place | Sequence | Mapping,
                  base: Place | tuple[complex, complex] | None = None) -> np.ndarray:
        """Integrals of the differentials p dx / f_y (p polynomials) from the base to the points.

        Same paths as :meth:`abel_map` (use :meth:`period_matrix` with ``differentials=`` for the
        periods over the same cycles).  Poles of the differentials must not lie on the paths: a place
        where the differential has a pole cannot be a target (the integral diverges; regularization is
        left to the caller).  Returns (N, len(numerators)) or (len(numerators),) for a single point.
        """
        targets, weights, shape = self._parse_targets(points)
        P = self.engine.numerators(list(numerators))
        key = tuple(map(str, numerators))
        raw = self._abel_raw(targets, P, key)
        if base is not None:
            raw = raw - self._abel_raw([self._as_target(base)], P, key)[0]
        return shaped_integrals(raw, weights, shape)

    # ------------------------------------------------------------------ Riemann constant
    def canonical_divisor(self) -> dict:
        """The divisor of dx: finite ramification points (multiplicity e - 1) minus (e + 1) at infinity."""
        D = {P: P.e - 1 for k in range(len(self._sites)) for P in self._site_places(k) if P.e > 1}
        for P in self._site_places(-1):
            D[P] = D.get(P, 0) - (P.e + 1)
        return D

    def _test_divisor_images(self) -> np.ndarray:
        """Abel images of the three test divisors of degree g - 1, shape (3, g): the table's points in the path
        graph's box (:func:`~thetasol.curves.riemann_constant.test_abscissae`), off the critical values."""
        from thetasol.curves.riemann_constant import test_abscissae
        G, g = self._graph, self.genus
        xs, sheets = test_abscissae(G.center, 0.7 * G.H, g - 1)
        pts = []
        for x0, k in zip(xs.ravel(), sheets.ravel(), strict=True):
            if self._site_index(x0, rtol=1e-3) >= 0:
                x0 += 0.01 * G.H
            R, _ = self._poly.roots(np.array([x0]))
            pts.append((complex(x0), complex(R[0, k % self.n])))
        return self.abel_map(pts).reshape(3, g - 1, g).sum(axis=1)

    def riemann_constant(self, base: Place | tuple[complex, complex] | None = None, *,
                         theta: RiemannTheta | None = None) -> np.ndarray:
        """Vector of Riemann constants K (normalized coordinates, same base and paths as abel_map): for a generic
        effective divisor D of degree g, theta(A(P) - A(D) - K) vanishes exactly at the points of D.

        ``2K = -A(div dx)``; the half period by the library's one rule (:mod:`thetasol.curves.riemann_constant`)
        on ``(g - 1)`` times the base point and three divisors of the table of test points.  ``base``: another
        base point ``Q``, ``K_Q = K + (g - 1) A(Q)``; ``theta``: a RiemannTheta of :meth:`riemann_matrix` to reuse.
        """
        from thetasol.curves.riemann_constant import riemann_constant_vector
        g = self.genus
        if g == 0:
            return np.zeros(0, complex)
        if "K" not in self._cache:
            tau = self.riemann_matrix()
            AC = self.abel_map(self.canonical_divisor())
            ADs = np.zeros((1, g), complex)
            if g > 1:
                ADs = np.concatenate([ADs, self._test_divisor_images()])
            self._cache["K"] = riemann_constant_vector(tau, AC, ADs, theta=theta)
        K = self._cache["K"].copy()
        if base is not None:
            K = K + (g - 1) * self.abel_map(base)
        return K
