"""Homology of the Riemann surface from the lifted path graph, and a symplectic basis over Z.

Method.  The sheets continued along the edges of the planar path graph give the lifted graph: one
vertex (v, s) per graph vertex and sheet, one edge (e, s) per graph edge and sheet.  It is embedded
in the compact Riemann surface with every face a disc (a cell holds one critical value, whose
preimage is a union of discs in the normalization; the outside of the box is a disc around infinity),
so its cycle space maps onto H_1 and the kernel is the radical of the intersection form.  The lifted
vertex (v, s) inherits the counter-clockwise order of the edges at v, which makes the lifted graph a
ribbon graph; intersection numbers are computed vertex by vertex after pushing the second cycle off to
the left of every edge.  A symplectic basis is then extracted by integer symplectic Gram-Schmidt
(Euclid steps where no entry is +-1), and the rank must equal twice the genus from Riemann-Hurwitz.
Hand-written: the allowed dependencies have no integer symplectic reduction.
"""
from __future__ import annotations

from collections import deque

import numpy as np


class LiftedGraph:
    """Lifted graph of a planar graph with edge permutations.

    Parameters
    ----------
    nv : number of planar vertices;  edges : (ne, 2) (tail, head);  star : ccw half-edge lists
    perms : (ne, n) int, perms[e][s] = sheet at the head reached from sheet s at the tail
    n : number of sheets;  root : (vertex, sheet) of the base point
    """

    def __init__(self, nv, edges, star, perms, n, root):
        self.nv, self.n = nv, n
        self.edges = np.asarray(edges)
        self.perms = np.asarray(perms, dtype=int)
        ne = len(self.edges)
        self.ne = ne
        # lifted edge id: e * n + s; tail vertex id: tail * n + s; head: head * n + perms[e, s]
        self.ltail = (self.edges[:, 0][:, None] * n + np.arange(n)[None, :]).ravel()
        self.lhead = (self.edges[:, 1][:, None] * n + self.perms).ravel()
        nl = nv * n
        adj = [[] for _ in range(nl)]
        for le in range(ne * n):
            adj[self.ltail[le]].append((le, 1))
            adj[self.lhead[le]].append((le, -1))
        rootid = root[0] * n + root[1]
        self.root = rootid
        parent = np.full(nl, -2, dtype=int)  # lifted edge used to reach; -1 at root
        psign = np.zeros(nl, dtype=int)
        order = []
        parent[rootid] = -1
        dq = deque([rootid])
        while dq:
            u = dq.popleft()
            order.append(u)
            for le, sg in adj[u]:
                w = self.lhead[le] if sg == 1 else self.ltail[le]
                if parent[w] == -2:
                    parent[w] = le
                    psign[w] = sg
                    dq.append(w)
        self.connected = bool(np.all(parent != -2))
        self.n_components_hint = int(np.sum(parent == -2))
        self.parent, self.psign, self.order = parent, psign, order
        tree = np.zeros(ne * n, dtype=bool)
        tree[parent[parent >= 0]] = True
        self.tree = tree
        # ribbon structure: for each lifted vertex, its lifted half-edges in ccw order
        self.lstar = []
        for v in range(nv):
            for s in range(n):
                items = []
                for e, is_tail in star[v]:
                    if is_tail:
                        items.append((e * n + s, 1))
                    else:
                        sp = int(np.nonzero(self.perms[e] == s)[0][0])
                        items.append((e * n + sp, -1))
                self.lstar.append(items)

    def fundamental_cycles(self):
        """Integer matrix (m, ne*n): one cycle per non-tree lifted edge."""
        L = self.ne * self.n
        # potentials: tree path vectors for every vertex, in BFS order
        pot = {}
        pot[self.root] = np.zeros(L, dtype=np.int64)
        for u in self.order[1:]:
            le, sg = self.parent[u], self.psign[u]
            prev = self.ltail[le] if sg == 1 else self.lhead[le]
            v = pot[prev].copy()
            v[le] += sg
            pot[u] = v
        cyc = []
        for le in np.nonzero(~self.tree)[0]:
            a, b = self.ltail[le], self.lhead[le]
            v = pot[a].copy()
            v[le] += 1
            v -= pot[b]
            cyc.append(v)
        return np.array(cyc, dtype=np.int64).reshape(-1, L)

    def pairing_matrix(self):
        """G (L x L) with <alpha, beta> = alpha^T G beta for cycles alpha, beta (lifted edge vectors)."""
        L = self.ne * self.n
        G = np.zeros((L, L), dtype=np.int64)
        for items in self.lstar:
            d = len(items)
            for i in range(d):
                ei, si = items[i]
                for j in range(d):
                    ej, sj = items[j]
                    # beta's half-edge j is pushed to the left of its edge: ccw (+) at a tail,
                    # cw (-) at a head.
                    if i < j or (i == j and sj == 1):
                        G[ei, ej] += si * sj
        return G


def symplectic_basis(cycles, G, weights=None):
    """Integer symplectic reduction.

    Returns (a, b, rank) with a, b integer arrays (g, L) such that <a_i, b_j> = delta_ij,
    <a_i, a_j> = <b_i, b_j> = 0.  ``weights`` (length L, >0) ranks cycles by cost to prefer short ones.
    """
    C = [np.asarray(c, dtype=object) for c in cycles]
    Gd = G
    if weights is None:
        weights = np.ones(G.shape[0])

    def cost(u):
        return float(np.abs(np.asarray(u, dtype=float)) @ weights)

    A, B = [], []
    C = [c for c in C if np.any(c != 0)]
    while C:
        M = len(C)
        Cm = np.array(C, dtype=np.int64)
        if np.max(np.abs(Cm)) > 2**40:
            raise OverflowError("integer growth in symplectic reduction")
        S = Cm @ Gd @ Cm.T
        if not np.any(S):
            break
        # choose a pair with |S_ij| = 1 and minimal cost
        idx = np.argwhere(np.abs(S) == 1)
        if len(idx):
            cc = [cost(c) for c in C]
            costs = np.array([cc[i] + cc[j] for i, j in idx])
            i, j = idx[int(np.argmin(costs))]
        else:
            # Euclid on a row to create a unit entry
            i = int(np.argmax(np.any(S != 0, axis=1)))
            row = S[i].copy()
            while True:
                nz = np.nonzero(row)[0]
                if len(nz) == 0:
                    break
                j = nz[int(np.argmin(np.abs(row[nz])))]
                if abs(row[j]) == 1:
                    break
                done = True
                for k in nz:
                    if k == j:
                        continue
                    q = row[k] // row[j]
                    if q:
                        C[k] = C[k] - q * C[j]
                        row[k] -= q * row[j]
                        done = False
                if done:
                    raise ValueError(f"intersection form is not unimodular (gcd {abs(row[j])})")
            Cm = np.array(C, dtype=np.int64)
            S = Cm @ Gd @ Cm.T
            if abs(S[i, j]) != 1:
                continue
        a, b = C[i], C[j]
        if S[i, j] == -1:
            a, b = b, a
        A.append(a)
        B.append(b)
        # project the others: c -> c - <c, b> a + <c, a> b
        rest = []
        Cm = np.array(C, dtype=np.int64)
        CG = Cm @ Gd
        cbs, cas = CG @ np.asarray(b, dtype=np.int64), CG @ np.asarray(a, dtype=np.int64)
        for k in range(M):
            if k in (i, j):
                continue
            c = C[k] - int(cbs[k]) * a + int(cas[k]) * b
            if np.any(c != 0):
                rest.append(c)
        C = rest
    g = len(A)
    L = G.shape[0]
    Aa = np.array(A, dtype=np.int64).reshape(g, L)
    Bb = np.array(B, dtype=np.int64).reshape(g, L)
    return Aa, Bb, 2 * g
