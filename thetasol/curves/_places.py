"""Places over the critical values and infinity; local expansions; adjoint conditions.

Method.  Around each critical value b (and around x = infinity) the sheets are continued from the
reference vertex of b's cell to a circle of radius r (half the distance to the nearest other critical
value) and once around it, sampled at M equispaced points.  The cycles of the resulting permutation
are the places over b; concatenating the samples of the sheets of a cycle of length e gives the
values on a circle |t| = r^(1/e) in the local parameter t (x = b + t^e, or x = t^(-e) at infinity),
and an FFT gives Laurent-Puiseux coefficients of any function or differential there.  This one
numerical tool replaces symbolic Puiseux expansions: it gives the limits of y at every place, the
local expansions the Baker-Akhiezer construction needs, and the adjoint conditions (no negative
powers of t in g/f_y dx/dt) that select the holomorphic differentials of a singular curve.

Accuracy next to close critical values (motions near relative equilibria: pairs 1e-4 apart relative
to their size).  The chart is centred at the exact critical value (its float64 value plus the low part
from :func:`~thetasol.curves._poly.root_corrections`), the samples are evaluated through the exactly
shifted polynomial, and f_y is taken at the exact roots (:meth:`CurvePoly.polish_dd`): each of these
three roundings alone would move the series by ~eps |b| / r, large next to a pair.  M = 128 samples
per turn keep the truncation of the series at the sampling circle, where tails of Abel integrals into
places are summed, below float64 rounding (~2^(-M/2) of the largest term).
"""
from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from thetasol.curves._numerators import Numerator, cached_numerators
from thetasol.curves._quad import Piece

# samples per turn.  The circle has radius half the distance to the next critical value, so in the
# local parameter the series converges like 2^(-k/e) there and the FFT keeps e M / 2 terms: the
# truncation is ~2^(-M/2) of the largest term.  That is what tails into places are summed with
# (at t0 itself); M = 128 puts it below float64 rounding, fewer samples would not.
M_SITE = 128
M_INF = 128


@dataclass(frozen=True, eq=False)
class CurveEngine:
    """The numerical machinery of a plane curve that its places and samples are computed with, built
    once by :class:`~thetasol.curves.plane_curve.PlaneCurve` (its ``engine``).

    Attributes
    ----------
    poly : CurvePoly
        The polynomial (:mod:`thetasol.curves._poly`).
    sites, sites_lo : ndarray
        The finite critical values and the low parts of their exact values (or None).
    graph : CellGraph
        The path graph between the critical values (:mod:`thetasol.curves._paths`).
    exact : ExactEvaluator
        The mpmath evaluator of the exact coefficients (:mod:`thetasol.curves._mp`).
    tracker : Tracker
        Sheet continuation along lines and circles (:mod:`thetasol.curves._quad`).
    vroots : ndarray
        The sheets' values at the graph's vertices, in label order.
    cache : dict
        The curve's cache of computed results (shared with the curve).
    """

    poly: Any
    sites: np.ndarray
    sites_lo: np.ndarray | None
    graph: Any
    exact: Any
    tracker: Any
    vroots: np.ndarray
    cache: dict

    def numerators(self, exprs) -> Any:
        """The exact numerators of the differentials ``exprs`` (cached)."""
        return cached_numerators(self.cache, exprs, lambda: (self.poly.x, self.poly.y))


class LocalData:
    """Samples of all sheets on a circle around a critical value or infinity."""

    def __init__(self, kind, site, center, ref, x1, xs, ys, perm):
        self.kind = kind  # 'critical' | 'infinity'
        self.index = None  # position in the list of local data (= piece index of the approach line)
        self.site = site
        self.center = center  # b, or 0 for infinity
        self.ref = ref
        self.x1 = x1
        self.xs = xs  # (M,)
        self.ys = ys  # (n, M) indexed by reference labels
        self.perm = perm
        self.cycles = perm_cycles(perm)
        self.center_lo = 0j  # the exact critical value is center + center_lo
        self.xi0 = x1 - center  # first sample minus the exact critical value

    def place_samples(self, cycle):
        """(t samples, x samples, y samples) of length e*M for the place of this cycle."""
        e = len(cycle)
        M = self.xs.shape[0]
        y = np.concatenate([self.ys[c] for c in cycle])
        x = np.tile(self.xs, e)
        m = np.arange(e * M)
        if self.kind == "infinity":
            t0 = self.x1 ** (-1.0 / e)
        else:
            t0 = self.xi0 ** (1.0 / e)
        t = t0 * np.exp(2j * np.pi * m / (e * M))
        return t, x, y


def perm_cycles(perm):
    """Cycles of a permutation (array perm[i] = image of i), as tuples in order of first element."""
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


def local_data(curve):
    """LocalData for every site (in order) and for infinity (last), all computed."""
    lds = local_sites(curve)
    lds.compute_all()
    return lds


def local_sites(curve):
    """The :class:`LocalSites` of the curve: each entry computed on first use."""
    if "local" not in curve.engine.cache:
        curve.engine.cache["local"] = LocalSites(curve)
    return curve.engine.cache["local"]


class LocalSites:
    """The circles around every critical value (in order) and around infinity (last).

    The approach lines from the reference vertices are tracked for all of them at once (the Abel
    images of places add their integrals), but the turn around a circle and its compensated samples
    (128 per turn, the larger part of the cost) only for the entries that are used: a curve's Abel
    map at the places at infinity needs the circle at infinity alone.  Indexing an entry computes it
    (with every other entry not yet computed when iterating).
    """

    def __init__(self, curve):
        self._curve = curve
        G = curve.engine.graph
        sites = curve.engine.sites
        allsites = G.allsites
        pieces1 = []
        meta = []
        for k, b in enumerate(sites):
            ref = G.cell_vertices[k][0]
            others = np.abs(allsites - b)
            others = others[others > 0]
            dmin = others.min() if len(others) else G.H
            v = G.V[ref]
            r = min(0.5 * dmin, 0.5 * abs(v - b))
            x1 = b + r * (v - b) / abs(v - b)
            pieces1.append(Piece("line", v, x1, curve.engine.vroots[ref]))
            meta.append(("critical", k, b, ref, x1, M_SITE, 1))
        # infinity: out along the ray from the box centre through the base vertex
        vb = G.V[G.base]
        c = G.center
        # the circle |x| = |x1| encloses every critical value with a margin of 2 (the Laurent series in
        # t = x^(-1/e) converges for |x| > max |site|): coefficients lose at most ~2^k in accuracy
        Rfar = 2.0 * (np.abs(allsites).max() if len(allsites) else max(abs(c), 1.0))
        d = vb - c
        # smallest lam >= 1 with |c + lam d| >= Rfar (the ray beyond the base corner stays outside the box)
        qa, qb, qc = abs(d) ** 2, 2 * (np.conj(c) * d).real, abs(c) ** 2 - Rfar**2
        disc = max(qb * qb - 4 * qa * qc, 0.0)
        lam = max(1.0, (-qb + np.sqrt(disc)) / (2 * qa))
        x1 = c + lam * d
        pieces1.append(Piece("line", vb, x1, curve.engine.vroots[G.base]))
        meta.append(("infinity", -1, 0j, G.base, x1, M_INF, -1))
        self._meta = meta
        #: the approach lines, tracked together (piece p ends at the circle of entry p)
        self.lines = curve.engine.tracker.track(pieces1)
        self._data = [None] * len(meta)

    def __len__(self):
        return len(self._meta)

    def x1(self, p):
        """The first sample (end of the approach line) of entry p, without computing the circle."""
        return self._meta[p][4]

    def __getitem__(self, p):
        p = range(len(self._meta))[p]
        if self._data[p] is None:
            self._compute([p])
        return self._data[p]

    def __iter__(self):
        self.compute_all()
        return iter(self._data)

    def prefetch(self, which):
        """Compute the entries of ``which`` not yet computed, in one batch."""
        missing = sorted({range(len(self._meta))[p] for p in which} - {p for p, ld in enumerate(self._data)
                                                                        if ld is not None})
        if missing:
            self._compute(missing)

    def compute_all(self):
        """Compute every entry not yet computed (one tracking call for all of them)."""
        missing = [p for p, ld in enumerate(self._data) if ld is None]
        if missing:
            self._compute(missing)

    def _compute(self, which):
        curve = self._curve
        tr1 = self.lines
        pieces2 = []
        for p in which:
            _, _, b, _, x1, M, d = self._meta[p]
            pieces2.append(Piece("circle", x1, b, tr1.ends[p], e=d, taus=np.arange(M + 1) / M))
        tr2 = curve.engine.tracker.track(pieces2)
        for q, p in enumerate(which):
            self._data[p] = _local_entry(curve, self._meta[p], p, tr1.ends[p], tr2, q)


def _local_entry(curve, meta, p, y1, tr2, q):
    """The LocalData of entry p from piece q of the tracked circles tr2."""
    kind, k, b, ref, x1, M, _ = meta
    xs, ys = tr2.values(q)
    end = ys[:, -1]
    dd = np.abs(end[:, None] - y1[None, :])
    perm = np.argmin(dd, axis=1)
    if len(set(perm.tolist())) != curve.n:
        raise ValueError("sheet continuation around a critical value failed (numerically singular curve)")
    ld = LocalData(kind, k, b, ref, x1, xs[:M], ys[:, :M], perm)
    ld.index = p
    rel = tr2.rel[tr2.nodes.offsets[q]:tr2.nodes.offsets[q] + M] if tr2.rel is not None else None
    xi = None
    blo = 0j
    if kind == "critical":
        # the FFT assumes samples exactly at b + xi_m, xi_m = xi_0 exp(2 pi i m / M), b the exact
        # critical value (float b plus its low part: the float alone is off by ~eps |b|, which a
        # close neighbour at distance d turns into errors ~eps |b| / d in the series)
        blo = complex(curve.engine.sites_lo[k]) if curve.engine.sites_lo is not None else 0j
        ld.center_lo = blo
        ld.xi0 = (x1 - b) - blo
        xi = ld.xi0 * np.exp(2j * np.pi * np.arange(M) / M)
        ld.xs = b + (blo + xi)
    ld.ys, ld.fys = _accurate_samples(curve, ld.xs, ld.ys, rel, center=b if kind == "critical" else None,
                                      xi=xi, center_lo=blo)
    return ld


def prefetch_local(curve, targets):
    """Compute in one batch the local data that the Abel map of ``targets`` (places and (x, y)
    pairs) will read: the circles under critical and infinite places, and those of :func:`near_site`
    (the rule PlaneCurve._near_place uses) for a point close to a critical value or far out."""
    lds = local_sites(curve)
    sites = curve.engine.sites
    which = []
    for t in targets:
        kind = getattr(t, "kind", None)
        if kind in ("critical", "infinity"):
            which.append(t.site if kind == "critical" else -1)
            continue
        k = near_site(lds, sites, t.x if kind == "regular" else t[0])
        if k is not None:
            which.append(k)
    lds.prefetch(which)


def near_site(lds, sites: np.ndarray, x0: complex) -> int | None:
    """The site whose local series serve a point over ``x0``: the nearest critical value when ``x0`` is
    within a quarter of its series' approach distance, -1 (infinity) far out, else None."""
    if len(sites):
        kk = int(np.argmin(np.abs(sites - x0)))
        if abs(x0 - sites[kk]) < 0.25 * abs(lds.x1(kk) - sites[kk]):
            return kk
    if abs(x0) > 4 * abs(lds.x1(len(lds) - 1)):
        return -1
    return None


def local_of(curve, place):
    """The :class:`LocalData` of the critical value or of infinity under a (non-regular) place."""
    lds = local_sites(curve)
    return lds[place.site] if place.kind == "critical" else lds[-1]


def _accurate_samples(curve, xs, ys, rel, center=None, xi=None, center_lo=0j):
    """Sample values and f_y at them, with compensated (double-double) Newton steps.

    With ``center`` b, the samples are taken at exactly b + (xs - b) evaluated through the exactly
    shifted polynomial f(b + xi, y) when the circle is small against |b| (otherwise rounding x to
    float64 would jitter the samples by eps |b| / radius of the circle, which the FFT turns into
    spurious negative powers).  Where even the compensated residual loses digits (its second-order
    error above the float64 rounding of the root), the samples are polished in mpmath.
    """
    poly = curve.engine.poly
    if center is not None:
        # (float sample positions b + xi are off by eps |b|: spurious terms ~eps |b| / |xi| in the series)
        if np.finfo(float).eps * abs(center) > 1e-15 * np.min(np.abs(xi)):
            Chi, Clo = poly.shifted_dd(center, center_lo)
            Ahi, Alo = poly.coeff_polys_dd_local(xi, Chi, Clo)
            Y, fy = poly.polish_dd(Ahi, Alo, ys.T.copy())
            return Y.T.copy(), fy.T.copy()
    Ahi, Alo = poly.coeff_polys_dd(xs)
    Y, fy = poly.polish_dd(Ahi, Alo, ys.T.copy())
    ys, fys = Y.T.copy(), fy.T.copy()
    if rel is None or np.max(rel) <= 1e-11:
        return ys, fys
    # The tracker's rel includes the float64 rounding of the roots themselves (eps |y| / gap), which no
    # polish can improve on; what mpmath can improve is the second-order error of the compensated
    # residual, 4n eps times the float64 bound, where it exceeds that rounding.
    err2 = 4 * poly.n * np.finfo(float).eps * poly.root_error_bound(xs, Y, fy)
    rel = np.where((err2 > np.finfo(float).eps * np.abs(Y)).any(axis=1), rel, 0.0)
    if np.max(rel) <= 1e-11:
        return ys, fys
    import mpmath
    ev = curve.engine.exact
    ys = ys.copy()
    fys = fys.copy()
    with mpmath.workdps(40):
        tol = mpmath.mpf(10) ** -32
        for q in np.nonzero(rel > 1e-11)[0]:
            a = ev.ycoeffs(mpmath.mpc(complex(xs[q])), 40)
            for s in range(ys.shape[0]):
                y = mpmath.mpc(complex(ys[s, q]))
                for _ in range(50):
                    f, d = ev.horner(a, y)
                    step = f / d
                    y -= step
                    if abs(step) <= tol * abs(y):
                        break
                f, d = ev.horner(a, y)
                ys[s, q] = complex(y)
                fys[s, q] = complex(d)
    return ys, fys


def place_series(curve, ld, cycle, P):
    """FFT Laurent data of the place (ld, cycle): (k, t0, Fy, Fh) with Fh (nd, N) for numerators P.

    Coefficients are stored scaled: c_k t0^k = F[k], so that sums over (t / t0)^k are stable.
    """
    t, x, y = ld.place_samples(cycle)
    N = len(t)
    k = np.fft.fftfreq(N, 1.0 / N).astype(int)
    Fy = np.fft.fft(y) / N
    Fh = None
    if P is not None:
        _, h = differential_samples(curve, ld, cycle, P)
        Fh = np.fft.fft(h, axis=1) / N
    return k, t[0], Fy, Fh


def series_eval(k, t0, F, t):
    """sum_k F[k] (t / t0)^k for arrays F (..., N); t scalar."""
    r = t / t0
    scale = np.max(np.abs(F)) + 1e-300
    # negative powers only where the coefficient is significant (a pole), never rounding noise
    keep = (k >= 0) | ((k > -len(k) // 4) & (np.abs(F) > 1e-9 * scale).reshape(-1, len(k)).any(axis=0))
    return (F[..., keep] * r ** k[keep]).sum(axis=-1)


def noise_level(ld):
    """Threshold for spurious negative Laurent coefficients at this circle (pole test of tails).

    1e-9, raised to 100 eps |b| / radius for circles tiny against |b|, where rounding of the
    centre or of the sample positions (~eps |b|) would show up as ~eps |b| / radius.  The charts
    are centred on the exact critical value with exactly shifted samples (:func:`local_data`), so
    that rounding does not occur, and the raise applies only when |b| / radius > 4.5e4 (1e-9 /
    (100 eps))."""
    if ld.kind != "critical":
        return 1e-9
    return max(1e-9, 100 * np.finfo(float).eps * abs(ld.center) / abs(ld.x1 - ld.center))


def series_integral(k, t0, Fh, t, what="differential", noise=1e-9):
    """Integral from the place (t = 0) to t of h(t) dt from its scaled Laurent data Fh (nd, N)."""
    scale = np.max(np.abs(Fh), axis=-1, keepdims=True) + 1e-300
    neg = (k < 0) & (k > -len(k) // 4)
    if np.any(np.abs(Fh[..., neg]) > noise * scale):
        raise ValueError(f"the {what} has a pole at this place: its integral to the place diverges")
    pos = k >= 0
    kk = k[pos]
    r = t / t0
    return (Fh[..., pos] * r ** kk / (kk + 1)).sum(axis=-1) * t


def laurent(t, h):
    """Laurent coefficients c_k (k = -K..K-1) of samples h(t) on a circle t = t0 * exp(2 pi i m / N)."""
    N = len(t)
    F = np.fft.fft(h) / N
    k = np.fft.fftfreq(N, 1.0 / N).astype(int)
    t0 = t[0]
    with np.errstate(over="ignore", invalid="ignore"):
        c = F / t0 ** k
    order = np.argsort(k)
    return k[order], c[order], F[order]


def differential_samples(curve, ld, cycle, P):
    """h(t) samples of g/f_y dx/dt for numerator arrays P (nd, I, J): shape (nd, e*M)."""
    t, x, y = ld.place_samples(cycle)
    e = len(cycle)
    fy = np.concatenate([ld.fys[c] for c in cycle])
    Xp = x[:, None] ** np.arange(P.shape[1])[None, :]
    Yp = y[:, None] ** np.arange(P.shape[2])[None, :]
    g = np.einsum("ki,kj,dij->dk", Xp, Yp, P)
    if ld.kind == "infinity":
        dxdt = -e * t ** (-e - 1)
    else:
        dxdt = e * t ** (e - 1)
    return t, g / fy * dxdt


def holomorphic_basis(curve, pts, sites=None) -> tuple:
    """Numerators of a basis of holomorphic differentials: the monomials ``x^(i-1) y^(j-1)`` of the
    interior points ``pts`` of the Newton polygon when they are as many as the genus, else the
    subspace of their span that :func:`adjoint_subspace` selects (``sites`` as there)."""
    g = curve.genus
    cands = tuple(Numerator.monomial(i - 1, j - 1) for i, j in pts)
    if len(pts) == g:
        return cands
    if len(pts) < g:
        raise RuntimeError(f"genus {g} exceeds the Newton polygon bound {len(pts)} (internal error)")
    return tuple(adjoint_subspace(curve, cands, sites))


def adjoint_subspace(curve, candidates, sites=None):
    """Combinations of the candidate numerators whose differentials are holomorphic at every place.

    ``sites``: the entries of :func:`local_sites` (-1: infinity) that hold every singular point of
    the curve, when the caller knows them (elsewhere the candidates are holomorphic by the Newton
    polygon, and those places only add rows of rounding noise); default all of them."""
    P = curve.engine.numerators(candidates)
    rows = []
    if sites is None:
        lds = local_data(curve)
    else:
        local_sites(curve).prefetch(sites)
        lds = [local_sites(curve)[p] for p in sites]
    for ld in lds:
        for cyc in ld.cycles:
            t, h = differential_samples(curve, ld, cyc, P)
            N = h.shape[1]
            F = np.fft.fft(h, axis=1) / N
            k = np.fft.fftfreq(N, 1.0 / N).astype(int)
            neg = F[:, (k < 0) & (k > -N // 2 + 2)]  # (ncand, nneg), coefficients c_k t0^k
            scale = np.max(np.abs(h)) + 1e-300
            rows.append(neg.T / scale)
    Cm = np.vstack(rows) if rows else np.zeros((0, len(candidates)))
    g = curve.genus
    if Cm.shape[0] == 0:
        N = np.eye(len(candidates))
    else:
        if Cm.shape[0] < Cm.shape[1]:
            Cm = np.vstack([Cm, np.zeros((Cm.shape[1] - Cm.shape[0], Cm.shape[1]))])
        U, s, Vh = np.linalg.svd(Cm, full_matrices=False)
        s_full = np.zeros(len(candidates))
        s_full[:len(s)] = s
        null = np.nonzero(s_full <= 1e-7 * max(s_full.max(), 1e-300))[0]
        if len(null) != g:
            raise RuntimeError(
                f"adjoint conditions give {len(null)} holomorphic differentials, genus is {g} "
                f"(singular values {np.array2string(s_full, precision=2)}): numerically singular curve")
        gap = s_full[s_full > 1e-7 * s_full.max()].min() / max(s_full[null].max(), 1e-300) if len(null) < len(s_full) else np.inf
        if gap < 1e4:
            raise RuntimeError("adjoint conditions are numerically ambiguous (singular value gap "
                               f"{gap:.2g}): the curve is nearly singular")
        N = Vh.conj().T[:, null]  # (ncand, g)
    return _nice_basis(N, candidates)


def _nice_basis(N, candidates):
    """Reduced row echelon form of the null space, cleaned to rationals where possible: Numerators
    (the candidates are monomials)."""
    B = N.T.copy()  # (g, ncand)
    g, m = B.shape
    piv_row = 0
    for col in range(m):
        if piv_row >= g:
            break
        r = piv_row + int(np.argmax(np.abs(B[piv_row:, col])))
        if abs(B[r, col]) < 1e-8:
            continue
        B[[piv_row, r]] = B[[r, piv_row]]
        B[piv_row] /= B[piv_row, col]
        for rr in range(g):
            if rr != piv_row:
                B[rr] -= B[rr, col] * B[piv_row]
        piv_row += 1
    out = []
    for row in B:
        terms = []
        for c, cand in zip(row, candidates):
            if abs(c) < 1e-10:
                continue
            (i, j, _, _), = cand.terms
            terms.append((i, j, _nice_number(c.real), _nice_number(c.imag)))
        out.append(Numerator.from_terms(terms))
    return out


def _nice_number(v: float) -> Fraction | float:
    """``v`` as a Fraction of denominator <= 10000 within 1e-11 relative, else the float; 0 below 1e-10."""
    if abs(v) < 1e-10:
        return Fraction(0)
    fr = Fraction(v).limit_denominator(10000)
    return fr if abs(float(fr) - v) < 1e-11 * max(1.0, abs(v)) else float(v)


def regular_samples(curve, x0, y0, M=M_SITE):
    """(t, x, y, f_y) on a circle t = x - x0 around a regular point, on the sheet through y0."""
    sites = curve.engine.graph.allsites
    d = np.abs(sites - x0).min() if len(sites) else 1.0
    r = 0.5 * d
    x1 = x0 + r
    tr1 = curve.engine.tracker.track([Piece("line", x0, x1, [y0])])
    tr2 = curve.engine.tracker.track([Piece("circle", x1, x0, tr1.ends[0], e=1, taus=np.arange(M) / M)])
    xs, ys = tr2.values(0)
    rel = tr2.rel
    ys2, fys = _accurate_samples(curve, xs, ys, rel)
    t = xs - x0
    return t, xs, ys2[0], fys[0]


def expansion(curve, place, numer, order, mode):
    """Laurent-Puiseux coefficients at a place in its local parameter t.

    mode 'y': y(t);  'function': g(x, y) for the single numerator array numer (1, I, J);
    'differential': h(t) with g dx / f_y = h(t) dt.
    Returns (k, c): exponents from the lowest significant one to ``order`` and coefficients.
    """
    if place.kind == "regular":
        key = ("regsamples", place.x, place.y)
        if key not in curve.engine.cache:
            curve.engine.cache[key] = regular_samples(curve, place.x, place.y)
        t, x, y, fy = curve.engine.cache[key]
        e = 1
    else:
        ld = local_of(curve, place)
        t, x, y = ld.place_samples(place.cycle)
        fy = np.concatenate([ld.fys[c] for c in place.cycle])
        e = place.e
    if mode == "y":
        h = y
    else:
        P = np.asarray(numer)
        Xp = x[:, None] ** np.arange(P.shape[1])[None, :]
        Yp = y[:, None] ** np.arange(P.shape[2])[None, :]
        h = np.einsum("ki,kj,ij->k", Xp, Yp, P[0])
        if mode == "differential":
            if place.kind == "infinity":
                dxdt = -e * t ** (-e - 1)
            else:
                dxdt = e * t ** (e - 1)
            h = h / fy * dxdt
    N = len(t)
    F = np.fft.fft(h) / N
    k = np.fft.fftfreq(N, 1.0 / N).astype(int)
    order_idx = np.argsort(k)
    k, F = k[order_idx], F[order_idx]
    scale = np.max(np.abs(F)) + 1e-300
    sig = (np.abs(F) > 1e-9 * scale) & (k > -N // 4)
    kmin = int(k[sig].min()) if np.any(sig) else 0
    kmin = min(kmin, 0) if np.any(sig & (k < 0)) else max(kmin, 0) if mode != "y" else kmin
    if not np.any(sig & (k < 0)):
        kmin = 0 if not np.any(sig) else max(0, min(kmin, int(k[sig].min())))
    if order >= N // 2 - 1:
        raise ValueError(f"order {order} too high for the {N} samples of this place")
    keep = (k >= kmin) & (k <= order)
    t0 = t[0]
    c = F[keep] / t0 ** k[keep]
    return k[keep], c
