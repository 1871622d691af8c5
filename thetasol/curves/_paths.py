"""The path graph on the x-line: Voronoi cells of the critical values clipped by a square.

Method.  The critical x-values (sites) are separated by the edges of their Voronoi diagram,
clipped by a square box around them.  Every cell is convex and contains exactly one site; the
outside of the box contains only x = infinity.  Every point of an edge is at least as far from
all sites as from the two it separates, so edges keep the largest possible distance from the
singularities of the integrands; quadrature is refined where two sites are close.  The diagram is
computed here by half-plane clipping (O(m^2) for m sites) rather than with scipy's Qhull, because
Qhull rejects collinear sites (all critical values real is common) and the clipping keeps exact
track of which face lies on each side of an edge, which the intersection pairing needs.

Paths (documented in docs/curves.md):
* the graph's vertices and edges are the corners and sides of the clipped cells;
* a point x inside the box lies in the cell of its nearest site s; its path leaves the graph at
  the point q where the ray from s through x exits the cell, then runs straight from q to x;
* a point outside the box is reached by the ray from the box centre: q is where it leaves the box;
* a place over a site s is reached straight from the cell's first vertex;
* a place over infinity is reached along the ray from the box centre through the base vertex
  (the lower-left corner of the box).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def _clip(poly, labels, mid, d, lab, tol):
    """Clip a convex ccw polygon by {z : Re((z - mid) conj(d)) <= 0}; labels[i] names edge i->i+1."""
    h = ((poly - mid) * np.conj(d)).real / abs(d)
    N = len(poly)
    out, outl = [], []
    for i in range(N):
        j = (i + 1) % N
        P, Q, L = poly[i], poly[j], labels[i]
        hp, hq = h[i], h[j]
        if hp <= tol:
            out.append(P)
            outl.append(L)
            if hq > tol:
                t = hp / (hp - hq)
                out.append(P + t * (Q - P))
                outl.append(lab)
        elif hq <= tol:
            t = hp / (hp - hq)
            out.append(P + t * (Q - P))
            outl.append(L)
    # remove zero-length edges (keep the label of the later vertex)
    changed = True
    while changed and len(out) > 2:
        changed = False
        for i in range(len(out)):
            j = (i + 1) % len(out)
            if abs(out[i] - out[j]) <= tol:
                del out[i]
                del outl[i]
                changed = True
                break
    return np.array(out, dtype=complex), outl


class CellGraph:
    """Planar graph of clipped Voronoi cells of ``sites``.

    Attributes
    ----------
    sites : (m,) complex
    center, H : box centre and half-width
    V : (nv,) complex vertices;  edges : (ne, 2) int (tail, head)
    cells : list over sites of [(edge, sign)] ccw around the site (sign +1: tail -> head)
    cell_vertices : list over sites of vertex indices (ccw, first = the reference vertex)
    outer : [(edge, sign)] ccw around the box starting at the base vertex
    base : index of the base vertex (lower-left box corner)
    star : list over vertices of [(edge, is_tail)] sorted counter-clockwise by direction
    """

    def __init__(self, sites, extra_sites=None):
        sites = np.asarray(sites, dtype=complex).ravel()
        self.sites = sites
        allsites = sites if extra_sites is None else np.concatenate([sites, np.asarray(extra_sites, complex)])
        m = len(allsites)
        bx = _box(allsites)
        self.center, self.H, self.min_sep, self.tol = bx.center, bx.H, bx.min_sep, bx.tol
        cells_poly = _clipped_cells(allsites, bx)
        self.V, cell_vids = _merge_vertices(cells_poly, allsites, bx)
        top = _topology(cells_poly, cell_vids)
        self.edges = np.asarray(top.edges, dtype=int).reshape(-1, 2)
        self.base, self.outer = _outer_walk(self.V, bx.box, top)
        _check_graph(len(self.V), len(top.edges), top, self.outer)
        self.cells = top.cells[:len(sites)] if m else []
        self.extra_cells = top.cells[len(sites):] if m else top.cells
        self.cell_vertices = top.cell_vertices[:len(sites)] if m else []
        self.cells_poly = [p for p, _ in cells_poly[:len(sites)]] if m else []
        self.allsites = allsites
        self.box = bx.box
        self.star = _stars(self.V, self.edges)

    # ------------------------------------------------------------------ point location
    def locate(self, x):
        """Where the path to x leaves the graph.

        Returns (kind, k, edge, sign, q): kind 'cell' (x in the cell of site k) or 'outer'; the
        graph path ends at the tail (in the walk direction ``sign``) of ``edge``, then follows the
        edge to q, then runs straight from q to x.
        """
        x = complex(x)
        c, H = self.center, self.H
        if abs((x - c).real) >= H or abs((x - c).imag) >= H or len(self.allsites) == 0:
            d = x - c if x != c else 1.0
            return ("outer", -1) + self._exit(self.outer, c, d, x)
        k = int(np.argmin(np.abs(self.allsites - x)))
        seq = self.cells[k] if k < len(self.sites) else self.extra_cells[k - len(self.sites)]
        s = self.allsites[k]
        if x == s:
            raise ValueError("point at a critical value: pass a place")
        return ("cell", k) + self._exit(seq, s, x - s, x)

    def _exit(self, seq, s, d, x):
        best = None
        for e, sg in seq:
            a, b = self.edges[e]
            if sg < 0:
                a, b = b, a
            A, B = self.V[a], self.V[b]
            # s + t d = A + u (B - A)
            M = np.array([[d.real, -(B - A).real], [d.imag, -(B - A).imag]])
            rhs = np.array([(A - s).real, (A - s).imag])
            det = np.linalg.det(M)
            if abs(det) < 1e-300:
                continue
            t, u = np.linalg.solve(M, rhs)
            if t > 0 and -1e-12 <= u <= 1 + 1e-12:
                if best is None or t < best[0]:
                    best = (t, e, sg, A + min(max(u, 0.0), 1.0) * (B - A))
        if best is None:
            raise RuntimeError("ray does not leave its Voronoi cell (internal error)")
        return best[1], best[2], best[3]


def _line_intersection(p1, d1, p2, d2):
    """Intersection of the lines p1 + s d1 and p2 + t d2 (complex numbers as plane vectors)."""
    den = (d1.conjugate() * d2).imag
    if den == 0:
        return None
    s = ((p2 - p1).conjugate() * d2).imag / den
    return p1 + s * d1


def _vertex_position(keys, pts, sites, box):
    """Coordinates of a Voronoi vertex from the best-conditioned pair of lines defining it."""
    lines = []
    for key in keys:
        ss = sorted(j for kind, j in key if kind == "site")
        bb = sorted(j for kind, j in key if kind == "box")
        for a in range(len(ss)):
            for b in range(a + 1, len(ss)):
                p, q = sites[ss[a]], sites[ss[b]]
                lines.append((0.5 * (p + q), 1j * (q - p)))
        for i in bb:
            A, B = box[i], box[(i + 1) % 4]
            lines.append((A, B - A))
    best, bestang = None, -1.0
    for i in range(len(lines)):
        for j in range(i + 1, len(lines)):
            (p1, d1), (p2, d2) = lines[i], lines[j]
            ang = abs((d1.conjugate() * d2).imag) / (abs(d1) * abs(d2))
            if ang > bestang:
                z = _line_intersection(p1, d1, p2, d2)
                if z is not None:
                    best, bestang = z, ang
    if best is None or bestang < 1e-3:
        return complex(np.mean(pts))
    return complex(best)


# -- the stages of CellGraph's construction -------------------------------------------------------

@dataclass(frozen=True)
class _Box:
    """The square box around the sites: centre, half-width, corners (ccw from the lower left),
    the smallest site separation and the clipping tolerance."""

    center: complex
    H: float
    box: np.ndarray
    min_sep: float
    tol: float


def _box(allsites) -> _Box:
    m = len(allsites)
    if m:
        lo = np.array([allsites.real.min(), allsites.imag.min()])
        hi = np.array([allsites.real.max(), allsites.imag.max()])
        c = complex(*(0.5 * (lo + hi)))
        R = float(np.max(np.abs(allsites - c)))
    else:
        c, R = 0j, 0.0
    H = 1.5 * R if R > 0 else max(1.0, abs(c))
    H = max(H, 1e-12 * max(abs(c), 1.0))
    if m > 1:
        D = np.abs(allsites[:, None] - allsites[None, :]) + np.diag(np.full(m, np.inf))
        min_sep = float(D.min())
    else:
        min_sep = H
    # clipping decisions are only as good as float rounding at the scale of the box
    tol = 8 * np.finfo(float).eps * (abs(c) + 2 * H)
    box = c + H * np.array([-1 - 1j, 1 - 1j, 1 + 1j, -1 + 1j])
    return _Box(center=c, H=H, box=box, min_sep=min_sep, tol=tol)


def _clipped_cells(allsites, bx: _Box):
    """Per site its cell (the box clipped by the bisectors, nearest sites first) and the labels
    of the cell's edges (``("box", i)`` or ``("site", j)``)."""
    m, tol = len(allsites), bx.tol
    cells_poly = []
    for k in range(max(m, 1)):
        poly = bx.box.copy()
        labels = [("box", i) for i in range(4)]
        if m:
            sk = allsites[k]
            order = np.argsort(np.abs(allsites - sk))
            for j in order:
                if j == k:
                    continue
                d = allsites[j] - sk
                # skip sites that cannot cut the current polygon
                hmax = np.max(((poly - 0.5 * (sk + allsites[j])) * np.conj(d)).real) / abs(d)
                if hmax <= tol:
                    continue
                poly, labels = _clip(poly, labels, 0.5 * (sk + allsites[j]), d, ("site", int(j)), tol)
        cells_poly.append((poly, labels))
    return cells_poly


def _merge_vertices(cells_poly, allsites, bx: _Box):
    """Merge the corners of the cells into graph vertices; returns the vertices and, per cell,
    the vertex index of each corner.

    A Voronoi vertex is identified by the sites (and box sides) it is equidistant to, read off the
    labels of the two cell edges meeting there; this is exact even where two nearly parallel
    bisectors make its coordinates ill-conditioned.  Rounding-level geometric proximity merges
    the corners of co-circular (degenerate) configurations.
    """
    m, tol, H = len(allsites), bx.tol, bx.H
    keys, pts = [], []
    for k, (poly, labels) in enumerate(cells_poly):
        for i in range(len(poly)):
            key = frozenset([("site", k), labels[i - 1], labels[i]]) if m else frozenset([labels[i - 1], labels[i]])
            keys.append(key)
            pts.append(complex(poly[i]))
    parent = list(range(len(keys)))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    first = {}
    for i, key in enumerate(keys):
        if key in first:
            parent[find(i)] = find(first[key])
        else:
            first[key] = i
    P = np.asarray(pts)
    # corners closer than the rounding tolerance, all pairs j < i at once
    dsite = np.abs(allsites[None, :] - P[:, None]).min(axis=1) if m else np.full(len(P), H)
    near = np.abs(P[None, :] - P[:, None]) <= np.maximum(2 * tol, 1e-9 * dsite)[:, None]
    for i, j in zip(*np.nonzero(np.tril(near, -1))):
        parent[find(int(i))] = find(int(j))
    groups = {}
    for i in range(len(keys)):
        groups.setdefault(find(i), []).append(i)
    Vlist = []
    gid = {}
    for r, members in groups.items():
        gid[r] = len(Vlist)
        Vlist.append(_vertex_position([keys[i] for i in members], [pts[i] for i in members], allsites, bx.box))
    cell_vids = []
    pos = 0
    for poly, _ in cells_poly:
        cell_vids.append([gid[find(pos + i)] for i in range(len(poly))])
        pos += len(poly)
    return np.asarray(Vlist, dtype=complex), cell_vids


@dataclass(frozen=True)
class _Topology:
    """Edges (tail, head) with their multiplicities, each cell's (edge, sign) cycle and vertex
    list, and the box edges by their tail vertex: ``{tail: (edge, sign, head)}``."""

    edges: list
    count: dict
    cells: list
    cell_vertices: list
    box_directed: dict


def _topology(cells_poly, cell_vids) -> _Topology:
    edge_index: dict[tuple[int, int], int] = {}
    edges: list[tuple[int, int]] = []
    count: dict[int, int] = {}
    cells = []
    cell_vertices = []
    box_directed = {}
    for (_, labels), vids in zip(cells_poly, cell_vids, strict=True):
        seq = []
        verts = []
        N = len(vids)
        for i in range(N):
            a, b = vids[i], vids[(i + 1) % N]
            if a == b:
                continue
            verts.append(a)
            key = (min(a, b), max(a, b))
            if key not in edge_index:
                edge_index[key] = len(edges)
                edges.append(key)
            e = edge_index[key]
            count[e] = count.get(e, 0) + 1
            seq.append((e, 1 if (a, b) == key else -1))
            if labels[i][0] == "box":
                box_directed[a] = (e, 1 if (a, b) == key else -1, b)
        cells.append(seq)
        cell_vertices.append(verts)
    if any(count[e] > 2 for e in range(len(edges))):
        raise RuntimeError("inconsistent Voronoi graph (an edge borders more than two cells)")
    return _Topology(edges=edges, count=count, cells=cells, cell_vertices=cell_vertices,
                     box_directed=box_directed)


def _outer_walk(V, box, top: _Topology):
    """The base vertex (the lower-left corner) and the box boundary walked ccw from it."""
    box_directed = top.box_directed
    nbox = len(box_directed)
    base = int(np.argmin(np.abs(V - box[0])))
    outer = []
    v = base
    for _ in range(nbox + 1):
        if v not in box_directed:
            raise RuntimeError("the box boundary of the Voronoi graph is not closed")
        e, s, w = box_directed[v]
        outer.append((e, s))
        v = w
        if v == base:
            break
    else:
        raise RuntimeError("the box boundary of the Voronoi graph is not closed")
    if len(outer) != nbox:
        raise RuntimeError("the box boundary of the Voronoi graph is not a single cycle")
    return base, outer


def _check_graph(nv, ne, top: _Topology, outer):
    """Every interior edge twice, every box edge once, and Euler's formula."""
    on_box = {e for e, _ in outer}
    for e in range(ne):
        want = 1 if e in on_box else 2
        if top.count[e] != want:
            raise RuntimeError("inconsistent Voronoi graph (edge multiplicities)")
    F = len(top.cells) + 1
    if nv - ne + F != 2:
        raise RuntimeError(f"Voronoi graph fails Euler's formula: V - E + F = {nv - ne + F}")


def _stars(V, edges):
    """Counter-clockwise star of each vertex: [(edge, is_tail)] sorted by direction."""
    nv = len(V)
    star = [[] for _ in range(nv)]
    for e, (a, b) in enumerate(edges):
        star[a].append((e, True))
        star[b].append((e, False))
    for v in range(nv):
        def ang(item, v=v):
            e, is_tail = item
            a, b = edges[e]
            other = b if is_tail else a
            return np.angle(V[other] - V[v])
        star[v].sort(key=ang)
    return star
