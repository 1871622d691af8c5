"""A symplectic homology basis adapted to the real Liouville torus of a spectral curve.

For real data the spectral curve carries two commuting involutions: sigma (E, w) -> (-E, w)
and complex conjugation c.  On H_1(Gamma, Z) = Z^2g (coordinates in a symplectic basis [a | b])
they act by integer matrices S_sigma, S_c, read off the period matrix P (g x 2g) of
differentials g_i dE / f_w with parity eps_i under sigma and real coefficients::

    P S_sigma = diag(eps) P,        P S_c = conj(P).

The flow of a real trajectory is tangent to W = {x : S_sigma x = -x, S_c x = x} (the real part
of the Prym variety).  W is isotropic for the intersection form because c reverses it, so a
Z-basis of W n Z^2g extends to a symplectic basis whose first a-cycles span W.  In that basis the
velocity of the linear flow is real and vanishes outside those coordinates: Im z(t) is constant
and the theta series is a Fourier series in as many phases as the torus has dimensions.

Integer linear algebra on matrices of size 2g <= 8 with Python integers (exact).
"""
from __future__ import annotations

from fractions import Fraction
from math import gcd, lcm

import numpy as np

__all__ = ["involution_matrix", "saturated_kernel", "symplectic_completion", "real_flow_basis"]


def involution_matrix(P: np.ndarray, image: np.ndarray, what: str) -> np.ndarray:
    """Integer S with P S = image (both g x 2g complex), checked to be integral."""
    R = np.vstack([P.real, P.imag])
    Rimg = np.vstack([image.real, image.imag])
    S = np.linalg.solve(R, Rimg)
    Si = np.rint(S)
    if np.max(np.abs(S - Si)) > 1e-6:
        raise ValueError(f"the action of {what} on homology is not integral (max deviation "
                         f"{np.max(np.abs(S - Si)):.2g}): periods too inaccurate")
    return Si.astype(np.int64)


def _hnf_transform(B: list[list[int]]):
    """Unimodular U (list of rows) with U B upper triangular (row echelon), B an n x r integer matrix."""
    n = len(B)
    r = len(B[0]) if n else 0
    A = [row[:] for row in B]
    U = [[int(i == j) for j in range(n)] for i in range(n)]
    row = 0
    for col in range(r):
        if row >= n:
            break
        # Euclid on the column below `row`
        while True:
            nz = [i for i in range(row, n) if A[i][col] != 0]
            if not nz:
                break
            piv = min(nz, key=lambda i: abs(A[i][col]))
            A[row], A[piv] = A[piv], A[row]
            U[row], U[piv] = U[piv], U[row]
            done = True
            for i in range(row + 1, n):
                if A[i][col]:
                    q = A[i][col] // A[row][col]
                    A[i] = [x - q * y for x, y in zip(A[i], A[row])]
                    U[i] = [x - q * y for x, y in zip(U[i], U[row])]
                    if A[i][col]:
                        done = False
            if done:
                break
        if any(A[i][col] for i in range(row, n)):
            row += 1
    return U, A


def _echelon(A: list[list[int]]) -> tuple[list[list[int]], list[int]]:
    """Fraction-free Gauss-Jordan on integer rows: rows whose division by their pivot (``pivots[i]`` the
    column of row i's) is the reduced row echelon form over Q, and the pivot columns."""
    A = [list(r) for r in A]
    m, n = len(A), len(A[0]) if A else 0
    pivots, row = [], 0
    for col in range(n):
        piv = next((i for i in range(row, m) if A[i][col] != 0), None)
        if piv is None:
            continue
        A[row], A[piv] = A[piv], A[row]
        p = A[row][col]
        for i in range(m):
            a = A[i][col]
            if i != row and a != 0:
                r = [x * p - y * a for x, y in zip(A[i], A[row], strict=True)]
                d = 0
                for x in r:
                    d = gcd(d, x)
                A[i] = [x // d for x in r] if d > 1 else r
        pivots.append(col)
        row += 1
        if row == m:
            break
    return A, pivots


def _inverse_unimodular(U: list[list[int]]) -> list[list[int]]:
    n = len(U)
    R, piv = _echelon([list(row) + [int(i == j) for j in range(n)] for i, row in enumerate(U)])
    out = []
    for i in range(n):
        p = R[i][piv[i]]
        if any(x % p for x in R[i][n:]):
            raise ValueError("the matrix is not unimodular (internal error)")
        out.append([x // p for x in R[i][n:]])
    return out


def _nullspace(M: list[list[int]]) -> list[list[Fraction]]:
    """A basis of the rational kernel of M: one vector per free column (1 there), as sympy's nullspace."""
    n = len(M[0])
    R, pivots = _echelon(M)
    out = []
    for free in (c for c in range(n) if c not in pivots):
        v = [Fraction(0)] * n
        v[free] = Fraction(1)
        for i, pc in enumerate(pivots):
            v[pc] = Fraction(-R[i][free], R[i][pc])
        out.append(v)
    return out


def saturated_kernel(M: np.ndarray) -> np.ndarray:
    """Z-basis (columns) of {x in Z^n : M x = 0} for an integer matrix M."""
    ns = _nullspace(M.astype(np.int64).tolist())
    if not ns:
        return np.zeros((M.shape[1], 0), dtype=np.int64)
    cols = []
    for v in ns:
        den = lcm(*[x.denominator for x in v])
        cols.append([int(x * den) for x in v])
    B = [list(r) for r in zip(*cols)]                 # n x r
    U, _ = _hnf_transform(B)
    Ui = _inverse_unimodular(U)
    r = len(cols)
    # U B is echelon with r nonzero rows, so span_Q(B) n Z^n = first r columns of U^-1.
    return np.array([[Ui[i][j] for j in range(r)] for i in range(len(B))], dtype=np.int64)


def _omega(x, y, g):
    return sum(x[i] * y[g + i] - x[g + i] * y[i] for i in range(g))


def _project(x, pairs, g):
    """Remove the components of x along the symplectic pairs (a, b), Omega(a, b) = 1."""
    x = list(x)
    for a, b in pairs:
        ob, oa = _omega(x, b, g), _omega(x, a, g)
        x = [xi - ob * ai + oa * bi for xi, ai, bi in zip(x, a, b)]
    return x


def _primitive(x):
    d = 0
    for v in x:
        d = gcd(d, int(v))
    return [v // d for v in x] if d > 1 else list(x)


def _partner(a, pairs, g):
    """b in the complement of ``pairs`` with Omega(a, b) = 1 (a primitive there)."""
    # Omega(a, x) = c . x with c = (-a_b, a_a); solve c . x = 1 by extended Euclid.
    c = [-a[g + i] for i in range(g)] + [a[i] for i in range(g)]
    x = [0] * (2 * g)
    idx = [i for i, v in enumerate(c) if v]
    d, coeffs = c[idx[0]], {idx[0]: 1}
    for i in idx[1:]:
        # extended gcd of d and c[i]
        old_r, r_ = d, c[i]
        old_s, s_ = 1, 0
        old_t, t_ = 0, 1
        while r_:
            q = old_r // r_
            old_r, r_ = r_, old_r - q * r_
            old_s, s_ = s_, old_s - q * s_
            old_t, t_ = t_, old_t - q * t_
        coeffs = {k: v * old_s for k, v in coeffs.items()}
        coeffs[i] = old_t
        d = old_r
    if abs(d) != 1:
        raise ValueError("vector is not primitive: no symplectic partner")
    for k, v in coeffs.items():
        x[k] = v * d  # d = +-1
    b = _project(x, pairs, g)
    if _omega(a, b, g) != 1:
        raise AssertionError("symplectic completion failed")
    return b


def symplectic_completion(W: np.ndarray) -> np.ndarray:
    """G in Sp(2g, Z) (columns [a'_1..a'_g | b'_1..b'_g] in old coordinates) whose first
    a-cycles span the primitive isotropic sublattice spanned by the columns of W."""
    n, r = W.shape
    g = n // 2
    ws = [[int(v) for v in W[:, j]] for j in range(r)]
    for i in range(r):
        for j in range(i):
            if _omega(ws[i], ws[j], g) != 0:
                raise ValueError("the sublattice is not isotropic")
    pairs = []
    for w in ws:
        a = _primitive(_project(w, pairs, g))
        pairs.append((a, _partner(a, pairs, g)))
    # complete the remaining symplectic complement
    while len(pairs) < g:
        for j in range(n):
            e = [int(i == j) for i in range(n)]
            x = _project(e, pairs, g)
            if any(x):
                a = _primitive(x)
                try:
                    pairs.append((a, _partner(a, pairs, g)))
                    break
                except ValueError:
                    continue
    G = np.array([p[0] for p in pairs] + [p[1] for p in pairs], dtype=np.int64).T
    Jm = np.block([[np.zeros((g, g), np.int64), np.eye(g, dtype=np.int64)],
                   [-np.eye(g, dtype=np.int64), np.zeros((g, g), np.int64)]])
    if not np.array_equal(G.T @ Jm @ G, Jm):
        raise AssertionError("completion is not symplectic")
    return G


def real_flow_basis(P: np.ndarray, parities: np.ndarray) -> tuple[np.ndarray, int]:
    """Symplectic change of basis G making the real flow direction span the first a-cycles.

    Parameters
    ----------
    P : (g, 2g) period matrix of differentials with sigma-parities ``parities`` (+-1) and real
        coefficients.

    Returns
    -------
    G : (2g, 2g) integer symplectic matrix (new basis cycles as columns in old coordinates)
    r : dimension of the real torus W (3 for a generic spectral curve, 2 for a nodal one)
    """
    g = P.shape[0]
    S_sig = involution_matrix(P, parities[:, None] * P, "sigma")
    S_c = involution_matrix(P, P.conj(), "complex conjugation")
    I = np.eye(2 * g, dtype=np.int64)
    Wb = saturated_kernel(np.vstack([S_sig + I, S_c - I]))
    G = symplectic_completion(Wb)
    return G, Wb.shape[1]
