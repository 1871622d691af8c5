"""Compact Riemann surfaces of plane curves f(x, y) = 0: homology, periods, Abel map, Riemann constant.

Method (details and conventions in docs/curves.md).  The curve is a degree-n cover of the x-line.
Its finite critical values (roots of disc_y(f) * lc_y(f), found exactly with sympy, then
numerically) are separated by the edges of their Voronoi diagram clipped by a square
(:mod:`thetasol._paths`).  The n sheets are continued along every edge by vectorized root finding
with a Hermite matching test (:mod:`thetasol._curve_quad`); the lifted edges form a ribbon graph on
the surface, whose intersection form gives a symplectic basis of H_1 by integer reduction
(:mod:`thetasol._homology`).  The genus comes from Riemann-Hurwitz applied to the local monodromies
and is cross-checked against the rank of the intersection form and the number of holomorphic
differentials.  Periods are sums of Gauss-Legendre integrals along the edges (tolerance 1e-15 per
edge, rules chosen from the Bernstein ellipse of each interval); the ``dps`` path redoes the
quadrature on the same topology with mpmath from the exact coefficients.

Hand-written rather than wrapping a library: the reference implementations (Sage's
RiemannSurface, abelfunctions, Maple's algcurves) are not available as dependencies, and the
spectral curves of the rigid body need vectorized speed and an explicit treatment of nearly
degenerate curves.
"""
from __future__ import annotations

import numpy as np
import sympy as sp

from ._curve_poly import CurvePoly, polynomial_roots
from ._curve_quad import Piece, Tracker
from ._homology import LiftedGraph, symplectic_basis
from ._paths import CellGraph

__all__ = ["PlaneCurve", "Place"]

INF = complex("inf")


def _ncycles(perm):
    seen = np.zeros(len(perm), bool)
    c = 0
    for i in range(len(perm)):
        if not seen[i]:
            c += 1
            j = i
            while not seen[j]:
                seen[j] = True
                j = perm[j]
    return c


def _cycles(perm):
    seen = np.zeros(len(perm), bool)
    out = []
    for i in range(len(perm)):
        if not seen[i]:
            cyc = []
            j = i
            while not seen[j]:
                seen[j] = True
                cyc.append(int(j))
                j = perm[j]
            out.append(tuple(cyc))
    return out


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
        self._site = site
        self._ref = ref  # reference vertex of the path graph
        self._label = label  # reference sheet label at that vertex
        self._cycle = cycle
        self._y = y

    @property
    def y(self):
        if self._y is None and self.kind != "regular":
            self.curve._place_limits([self])
        return self._y

    @property
    def is_infinite(self) -> bool:
        return self.kind == "infinity"

    def _key(self):
        if self.kind == "regular":
            return ("regular", self.x, self._y)
        return (self.kind, self._site, self._cycle)

    def __eq__(self, other):
        return isinstance(other, Place) and other.curve is self.curve and other._key() == self._key()

    def __hash__(self):
        return hash((id(self.curve),) + tuple(map(str, self._key())))

    def __repr__(self):
        xs = "oo" if self.kind == "infinity" else f"{self.x:.6g}"
        ys = "?" if self._y is None else ("oo" if np.isinf(abs(self._y)) else f"{self._y:.6g}")
        return f"Place(x={xs}, y={ys}, e={self.e}, kind={self.kind!r})"

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

    def __init__(self, f, x, y, *, _extra_sites=None, _tol=1e-15):
        self._poly = CurvePoly(f, x, y)
        self.x, self.y = x, y
        self.n = self._poly.n
        if not self._poly.x_content_is_constant():
            raise ValueError("f is reducible: a polynomial in x alone divides it")
        F, disc_factors, disc = self._poly.critical_polynomial()
        self._disc_factors = disc_factors
        self._sites = polynomial_roots(F)
        self._graph = CellGraph(self._sites, _extra_sites)
        self._tracker = Tracker(self._poly, self._graph.allsites, tol=_tol)
        self._setup_sheets()
        self._cache = {}

    # ------------------------------------------------------------------ topology
    def _setup_sheets(self):
        G = self._graph
        poly = self._poly
        R, _ = poly.roots(G.V)
        order = np.lexsort((R.imag, R.real), axis=1) if R.shape[1] > 1 else np.zeros(R.shape, int)
        self._vroots = np.take_along_axis(R, order, axis=1)
        pieces = [Piece("line", G.V[a], G.V[b], self._vroots[a]) for a, b in G.edges]
        tr = self._tracker.track(pieces)
        self._edge_tracks = tr
        n = self.n
        perms = np.zeros((len(G.edges), n), dtype=int)
        for e, (a, b) in enumerate(G.edges):
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
        chi = -2 * n + sum(n - _ncycles(p) for p in self._site_perm) + (n - _ncycles(self._inf_perm))
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
    def base_point(self):
        """The default base point (x0, y0) of the Abel map: lower-left corner of the path box, sheet 0."""
        G = self._graph
        return complex(G.V[G.base]), complex(self._vroots[G.base][0])

    def sheets(self):
        """The base x0 and the n values of y over it, in the order used by :meth:`monodromy`."""
        G = self._graph
        return complex(G.V[G.base]), self._vroots[G.base].copy()

    def monodromy(self):
        """Local monodromy of every critical value, on the sheets of :meth:`sheets`.

        Returns (x0, y0, [(b, perm)]) with b a branch point (``inf`` last) and perm[i] = j when
        sheet i continued once counter-clockwise around b alone (along the tree path to its cell,
        around the cell, and back) ends on sheet j.
        """
        G = self._graph
        L = self._lifted
        n = self.n
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
            nv = len(G.V)
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

    # ------------------------------------------------------------------ differentials
    def _numerators(self, exprs):
        x, y = self.x, self.y
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
        for d, p in enumerate(polys):
            for (i, j), c in p.terms():
                P[d, i, j] = complex(c)
        return P

    def holomorphic_differentials(self) -> list:
        """Numerators g (sympy polynomials in x, y) of a basis of holomorphic differentials g dx / f_y.

        From the interior lattice points (i, j) of the Newton polygon, g = x^(i-1) y^(j-1), when
        their number equals the genus (f nondegenerate for its Newton polygon); otherwise the
        subspace of their span that satisfies the adjoint conditions at the singular points
        (computed numerically from Laurent coefficients at every place; see docs/curves.md).
        """
        if "holo" not in self._cache:
            pts = self._poly.interior_points()
            x, y = self.x, self.y
            g = self.genus
            if len(pts) == g:
                diffs = [x ** (i - 1) * y ** (j - 1) for i, j in pts]
            elif len(pts) > g:
                from ._curve_places import adjoint_subspace
                diffs = adjoint_subspace(self, [x ** (i - 1) * y ** (j - 1) for i, j in pts])
            else:
                raise RuntimeError(f"genus {g} exceeds the Newton polygon bound {len(pts)} (internal error)")
            self._cache["holo"] = diffs
        return list(self._cache["holo"])

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

    def homology_basis(self):
        """The symplectic basis as integer vectors over the lifted edges: (a, b), each (g, n_edges * n)."""
        a, b, _ = self._homology()
        return a.copy(), b.copy()

    def intersection_matrix(self):
        """Intersection matrix of (a_1..a_g, b_1..b_g): the standard [[0, 1], [-1, 0]] by construction."""
        a, b, G = self._homology()
        C = np.vstack([a, b])
        return C @ G @ C.T

    def _edge_integrals(self, P):
        ints = self._edge_tracks.integrate(P)
        return np.concatenate(ints, axis=0)  # (ne * n, nd), row e * n + s

    def period_matrix(self, differentials=None) -> np.ndarray:
        """Periods [A | B] (g x 2g complex) of the differentials g dx / f_y over the symplectic basis.

        Parameters
        ----------
        differentials : list of sympy polynomials, optional
            Numerators g; default :meth:`holomorphic_differentials`.  Any polynomial numerators are
            accepted (meromorphic differentials give their periods over the same cycles).
        """
        key = ("pm", None if differentials is None else tuple(map(str, differentials)))
        if key not in self._cache:
            diffs = self.holomorphic_differentials() if differentials is None else list(differentials)
            a, b, _ = self._homology()
            Iv = self._edge_integrals(self._numerators(diffs))
            PA = (a @ Iv).T
            PB = (b @ Iv).T
            self._cache[key] = np.hstack([PA, PB])
        return self._cache[key].copy()

    def riemann_matrix(self) -> np.ndarray:
        """tau = A^-1 B for the default holomorphic differentials; symmetric with Im tau > 0."""
        if "tau" not in self._cache:
            g = self.genus
            P = self.period_matrix()
            A, B = P[:, :g], P[:, g:]
            tau = np.linalg.solve(A, B)
            asym = np.max(np.abs(tau - tau.T)) / max(np.max(np.abs(tau)), 1e-300) if g else 0.0
            if asym > 1e-6:
                raise RuntimeError(f"tau is not symmetric (relative asymmetry {asym:.2g}): inaccurate periods")
            tau = 0.5 * (tau + tau.T)
            if g and np.min(np.linalg.eigvalsh(tau.imag)) <= 0:
                raise RuntimeError("Im tau is not positive definite (internal error)")
            self._cache["tau"] = tau
        return self._cache["tau"].copy()
