"""Summation engine of :mod:`thetasol.theta.riemann` in the Siegel-reduced frame.

Notation: ``tau = X + i Y`` is reduced, ``Y = T^T T``.  For points ``w`` the engine returns the
exponent-separated lattice sums (Deconinck et al. 2004, eq. (4) with the Babai shift)

    v_0(w + b/2) = exp(-pi c.Y c) theta(w + b/2 | tau),   c = Y^{-1} Im w,

and their directional derivatives, for all sign patterns ``b`` at once (the factor
``(-1)^{n.b}`` is a column of the right-hand side of one matrix product).

Derivatives are carried as *subset jets*: for directions ``v_1..v_r`` and maximal order ``o``
a jet holds ``D_S f`` for every subset ``S`` of ``{1..r}`` with ``|S| <= o``
(``D_S = prod_{i in S} D_{v_i}``).  Multiplying by ``exp(q(z))`` with ``q`` quadratic is a
Leibniz rule on jets (:meth:`Jet.leibniz`); this is how shifts, characteristics and the
modular transformation act on derivatives.

Two engines compute the same sums:

* ``direct``: one complex exponential per (point, lattice point), exponents by a BLAS product;
* ``split``: factorizes ``exp(2 pi i n.w)`` as ``exp(2 pi i n_1 w_1) exp(2 pi i k.w_rest)``,
  ``n = (n_1, k)``, so the sum over ``n_1`` becomes a complex matrix product
  ``W_1 (P x N_1) @ Q (N_1 x |K|)`` and only ``N_1 + |K|`` exponentials per point remain
  (``|K|`` = number of distinct tails ``k``).  Magnitudes are bounded before use; if a factor
  could overflow the engine falls back to ``direct``.
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from thetasol.core.dd import DD, dd_sum, two_prod
from thetasol.theta.lattice import babai, radius_for, shortest_vector, union_set, unique_rows

TWO_PI_I = 2j * math.pi
#: Largest |log| of a factor the split engine accepts (float64 overflows at ~709).
_LOG_SAFE = 600.0
#: Target size (complex entries) of the per-chunk work arrays.
_CHUNK_ENTRIES = 1 << 20
#: The same for the split engine, whose several (points x tails) arrays are each read once or twice:
#: 1 MB arrays stay in cache, where larger ones would not.
_SPLIT_CHUNK_ENTRIES = 1 << 16


# ----------------------------------------------------------------------------------------
# Subset jets
# ----------------------------------------------------------------------------------------
class Jet:
    """Index bookkeeping for subset jets of ``r`` directions up to order ``o``."""

    def __init__(self, r: int, o: int):
        self.r, self.o = r, o
        masks = [m for m in range(1 << r) if bin(m).count("1") <= o]
        masks.sort(key=lambda m: (bin(m).count("1"), m))
        self.masks = masks
        self.index = {m: i for i, m in enumerate(masks)}
        self.size = len(masks)
        self.popcount = np.array([bin(m).count("1") for m in masks])
        # Leibniz pairs: out[S] += f[T] * g[S \ T] for T subset of S
        s_idx, t_idx, u_idx = [], [], []
        for m in masks:
            t = m
            while True:
                s_idx.append(self.index[m])
                t_idx.append(self.index[t])
                u_idx.append(self.index[m ^ t])
                if t == 0:
                    break
                t = (t - 1) & m
        self.pairs = (np.array(s_idx), np.array(t_idx), np.array(u_idx))

    def factor(self, ell: np.ndarray, q: np.ndarray | None) -> np.ndarray:
        """``D_T exp(phi) / exp(phi)`` for all T, with ``D_{v_i} phi = ell[..., i]`` and
        ``D_{v_i} D_{v_j} phi = q[i, j]`` (phi quadratic; ``q=None`` means linear)."""
        f = np.empty(ell.shape[:-1] + (self.size,), dtype=complex)
        f[..., 0] = 1.0
        for pos in range(1, self.size):
            m = self.masks[pos]
            t = (m & -m).bit_length() - 1
            rest = m ^ (1 << t)
            acc = ell[..., t] * f[..., self.index[rest]]
            if q is not None:
                u_bits = rest
                while u_bits:
                    u = (u_bits & -u_bits).bit_length() - 1
                    u_bits ^= 1 << u
                    acc = acc + q[t, u] * f[..., self.index[rest ^ (1 << u)]]
            f[..., pos] = acc
        return f

    def leibniz(self, f: np.ndarray, g: np.ndarray) -> np.ndarray:
        """Jet of a product from the jets of its factors (broadcasting over leading axes)."""
        s, t, u = self.pairs
        shape = np.broadcast_shapes(f.shape[:-1], g.shape[:-1]) + (self.size,)
        out = np.zeros(shape, dtype=complex)
        prod = f[..., t] * g[..., u]
        # accumulate: pairs are grouped by s in increasing order
        bounds = np.flatnonzero(np.diff(s)) + 1
        out[...] = np.add.reduceat(prod, np.concatenate([[0], bounds]), axis=-1)
        return out

    def weights(self, V: np.ndarray, m: np.ndarray) -> np.ndarray:
        """``prod_{i in S} (v_i . m)`` for all lattice points m (rows) and subsets S: (N, size)."""
        vm = m @ V.T  # (N, r)
        W = np.empty((m.shape[0], self.size), dtype=complex)
        W[:, 0] = 1.0
        for pos in range(1, self.size):
            mask = self.masks[pos]
            t = (mask & -mask).bit_length() - 1
            W[:, pos] = vm[:, t] * W[:, self.index[mask ^ (1 << t)]]
        return W


@lru_cache(maxsize=64)
def jet_layout(r: int, o: int) -> Jet:
    return Jet(r, o)


def sign_matrix(bits: np.ndarray, m: np.ndarray) -> np.ndarray:
    """``(-1)^{m.b}`` for lattice points m (N, g) and bit patterns b (nb, g): (N, nb)."""
    return 1.0 - 2.0 * ((m @ bits.T) & 1)


# ----------------------------------------------------------------------------------------
# Reduced-frame lattice data
# ----------------------------------------------------------------------------------------
class ReducedLattice:
    """Cholesky factor, shortest vector and cached union sets of a reduced ``tau``."""

    def __init__(self, tau: np.ndarray, tau_lo: np.ndarray | None = None):
        self.tau = tau
        self.g = tau.shape[0]
        self.X = tau.real.copy()
        self.Y = tau.imag.copy()
        # tau = (X + X_lo) + i (Y + Y_lo) to double-double accuracy (from the mp replay): the
        # Babai shift by tau k must not add the rounding of tau times |k|
        lo = np.zeros_like(tau) if tau_lo is None else tau_lo
        self.X_lo, self.Y_lo = lo.real.copy(), lo.imag.copy()
        self.T = np.linalg.cholesky(self.Y).T  # upper triangular, Y = T^T T
        self.Yinv = np.linalg.inv(self.Y)
        self.Tinv = np.linalg.inv(self.T)
        self.rho = shortest_vector(self.T)
        self._sets: dict = {}
        self._radii: dict = {}

    def radius(self, tol: float, order: int, a: float) -> float:
        """R such that the truncated tail of the order-``order`` moments is <= tol.

        Derivative weights obey ``prod_i |2 pi v_i.(m + delta)| <= (2 pi)^o prod_i (1 + b_i)
        (1 + a t)^o`` with ``t = ||T(m + f)||``, ``a >= max_i ||T^{-T} v_i|| / |v_i|`` and
        ``b_i = |v_i.(c - alpha)|`` (the natural size of the derivative), so the bound is
        applied to ``(1 + a t)^o exp(-pi t^2)`` with tolerance ``tol / (2 pi)^o``.
        """
        key = (float(tol), int(order), math.ceil(max(a, 1.0) * 100) / 100)
        if key not in self._radii:
            self._radii[key] = radius_for(tol / (2 * math.pi) ** order, self.rho, self.g, order, key[2])
        return self._radii[key]

    def _half_form(self, mf: np.ndarray) -> np.ndarray:
        """``m.X.m / 2`` modulo 1 for integer points m (N, g), from exact products summed in double-double
        (X up to 1/2 but m.X.m up to ~100).  X is symmetric (the reduction keeps it so): the g (g + 1) / 2
        products ``X_ij m_i m_j`` (halved on the diagonal) in one call and one pairwise sum, cheaper
        than g^2 sequential additions."""
        g = self.g
        if np.array_equal(self.X, self.X.T):
            i, j = np.triu_indices(g)
            w = np.where(i == j, 0.5, 1.0) * self.X[i, j]
        else:  # pragma: no cover - the reduced tau is exactly symmetric
            i, j = (x.ravel() for x in np.indices((g, g)))
            w = 0.5 * self.X[i, j]
        mm = mf.T[i] * mf.T[j]  # exact: small integers
        return dd_sum(DD(*two_prod(np.broadcast_to(w[:, None], mm.shape), mm))).frac()

    def points(self, R: float):
        """Union set for radius R (rounded up to a 0.05 grid so nearby requests share it)."""
        Rq = math.ceil(R * 20.0) / 20.0
        if Rq not in self._sets:
            m = union_set(self.T, Rq)
            mf = m.astype(float)
            Tm = mf @ self.T.T
            self._sets[Rq] = {
                "m": m,
                "mf": mf,
                "Tm": Tm,
                # -pi ||T m||^2 + i pi m.X.m: the point-independent part of the exponent
                "a": -math.pi * np.einsum("ni,ni->n", Tm, Tm) + 2j * math.pi * self._half_form(mf),
                "split": None,
            }
        return self._sets[Rq]


# ----------------------------------------------------------------------------------------
# One characteristic group: v'[alpha; beta_base + b/2](u) for sign patterns b
# ----------------------------------------------------------------------------------------
def group_jets(lat: ReducedLattice, lset: dict, u: np.ndarray, alpha: np.ndarray, beta: np.ndarray,
               bits: np.ndarray, jet: Jet, V: np.ndarray, engine: str = "auto",
               u_lo: np.ndarray | None = None) -> np.ndarray:
    """Exponent-separated jets ``exp(-pi Im(u) Y^{-1} Im(u)) D_S theta[alpha; beta + b/2](u | tau)``.

    u: (P, g) points (``u + u_lo`` in double-double if given), alpha/beta: real (g,),
    bits: (nb, g) 0/1 patterns, V: (r, g) directions.  Returns (P, nb, jet.size).
    """
    P, g = u.shape
    X, Y, T = lat.X, lat.Y, lat.T
    if u_lo is None:
        u_lo = np.zeros_like(u)
    W = u + lat.tau @ alpha + beta  # (P, g)
    k = babai(W.imag @ lat.Yinv, T)
    d = alpha[None, :] - k
    # Wr = u + tau d + beta, d = alpha - k, in double-double: |Y k| can be ~100 for elongated Y
    # while Im Wr = Y f is small, and the Gaussian weights need Im Wr to full relative accuracy
    # double-double work in the (g, P) layout of riemann.py (point axis last)
    # (real and imaginary parts stacked: one call each, the same operations per entry)
    dT = d.T
    XY = np.stack([X.T, Y.T], axis=1)[:, :, :, None]  # [j, re/im, i, 1]
    dXY = dd_sum(DD(*two_prod(dT[:, None, None, :], XY))) + DD(np.stack([lat.X_lo @ dT, lat.Y_lo @ dT]))
    Wr = (DD(np.stack([u.real.T, u.imag.T])) + DD(np.stack([u_lo.real.T + beta[:, None], u_lo.imag.T])) + dXY).value()
    Wr_re, Wr_im = Wr[0].T, Wr[1].T
    Wr_re -= np.rint(Wr_re)  # the m-sum is 1-periodic in Re Wr
    s_T = _solve_transposed_upper(T, Wr_im)  # T f, with T^T (T f) = Im Wr
    # moments G[p, b, T] = sum_m (-1)^{m.b} prod_{i in T} (v_i . m) E[p, m]
    if engine == "auto":
        engine = "split" if _split_ok(lat, lset, s_T, Wr_im) else "direct"
    if engine == "split":
        G = _moments_split(lat, lset, Wr_re, Wr_im, s_T, bits, jet, V)
    else:
        G = _moments_direct(lat, lset, Wr_re, s_T, bits, jet, V)
    # derivative weights prod 2 pi i v.(m + delta), delta = alpha - k  (n + alpha = m - k + alpha)
    G = G * (TWO_PI_I ** jet.popcount)
    delta = alpha[None, :] - k
    ell = TWO_PI_I * (delta @ V.T)  # (P, r)
    if jet.size > 1:
        G = jet.leibniz(jet.factor(ell[:, None, :], None), G)
    # phase of the characteristic prefactor and of the shift by tau k, combined:
    # pi d.X.d + 2 pi d.(Re u + beta) + pi d.b   (mod 2 pi, double-double)
    ure = DD(u.real.T) + DD(u_lo.real.T + beta[:, None])  # Re u + beta, (g, P)
    dd_ = (dT[:, None, :] * dT[None, :, :]).reshape(g * g, P)  # exact: small integers and halves
    acc = dd_sum(ure.mul(dT)) + dd_sum(DD(*two_prod(dd_, 0.5 * X.reshape(-1, 1)))) \
        + DD((0.5 * lat.X_lo.reshape(-1)) @ dd_)
    ph = 2 * math.pi * acc.frac()[:, None] + math.pi * (d @ bits.T.astype(float))
    return G * np.exp(1j * ph)[:, :, None]


def _solve_transposed_upper(T: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Rows ``x`` with ``T^T x = b`` for the rows ``b`` of ``B`` (P, g), ``T`` upper triangular (g, g).

    Forward substitution over the g coordinates, vectorized over the points: scipy.linalg's
    ``solve_triangular`` would cost its slow import at the first set-up of a process, and its bits
    depend on the BLAS kernel (OpenBLAS's dtrsm rounds with FMA), these do not.
    """
    X = np.empty(B.shape)
    for i in range(T.shape[0]):
        acc = B[:, i].copy()
        for k in range(i):
            acc -= T[k, i] * X[:, k]
        X[:, i] = acc / T[i, i]
    return X


def _moments_direct(lat, lset, Wr_re, s_T, bits, jet, V):
    """E[p, m] = exp(-pi ||T m + s_p||^2 + i pi m.X.m + 2 pi i m.Re Wr_p), then E @ rhs."""
    m, mf, a, Tm = lset["m"], lset["mf"], lset["a"], lset["Tm"]
    N = len(m)
    rhs = (sign_matrix(bits, m)[:, :, None] * jet.weights(V, mf)[:, None, :]).reshape(N, -1)
    P = len(Wr_re)
    out = np.empty((P, rhs.shape[1]), dtype=complex)
    ss = np.einsum("pi,pi->p", s_T, s_T)
    step = max(1, _CHUNK_ENTRIES // max(N, 1))
    for s in range(0, P, step):
        sl = slice(s, s + step)
        ex = np.empty((len(Wr_re[sl]), N), dtype=complex)
        ex.real = (-2 * math.pi) * (s_T[sl] @ Tm.T)
        ex.real -= math.pi * ss[sl, None]
        ex.imag = (2 * math.pi) * (Wr_re[sl] @ mf.T)
        ex += a[None, :]
        np.exp(ex, out=ex)
        out[sl] = ex @ rhs
    return out.reshape(P, len(bits), jet.size)


def _split_data(lset: dict) -> dict:
    """Factor the set as n = (n_1, k): tails k, the n_1 range, and Q[n_1, k] = exp(a_n)."""
    if lset["split"] is None:
        m = lset["m"]
        tails, kidx = unique_rows(m[:, 1:])
        lo, hi = int(m[:, 0].min()), int(m[:, 0].max())
        Qm = np.zeros((hi - lo + 1, len(tails)), dtype=complex)
        Qm[m[:, 0] - lo, kidx] = np.exp(lset["a"])
        tail_index = [(int(tails[:, j].min()), tails[:, j] - tails[:, j].min()) for j in range(tails.shape[1])]
        lset["split"] = {"tails": tails.astype(float), "lo": lo, "n1": np.arange(lo, hi + 1, dtype=float),
                         "Q": Qm, "tail_index": tail_index, "fold": _tail_fold(tail_index, len(tails))}
    return lset["split"]


def _tail_fold(tail_index: list, nK: int) -> tuple[int, np.ndarray | None]:
    """``(f, index)``: the first ``f`` tail coordinates whose box of powers (the product of their ranges)
    has at most ``nK`` entries, and each tail's row-major position in that box."""
    f, size, index = 0, 1, None
    for _, kidx in tail_index:
        span = int(kidx.max()) + 1
        if size * span > nK:
            break
        index = kidx if index is None else index * span + kidx
        f, size = f + 1, size * span
    return f, index


def _tail_factors(sp: dict, w: np.ndarray, s_T: np.ndarray) -> np.ndarray:
    """``Wk[p, k] = exp(-pi ||T f_p||^2) prod_j w_pj^{k_j}`` (P, |K|) for the tail coordinates ``w``
    (P, g - 1), multiplied left to right.

    Power tables per coordinate (a few ns per entry instead of a ~20 ns complex exponential); the
    first coordinates are multiplied out on their box (81 entries for the 393 tails of the generic
    body's order-1 set) and gathered once, the rest gathered and multiplied per tail: the same
    products in the same order as gathering every coordinate.
    """
    f, index = sp["fold"]
    tab = np.exp(-math.pi * np.einsum("pi,pi->p", s_T, s_T))[:, None]
    P = len(w)
    for jj in range(f):
        klo, kidx = sp["tail_index"][jj]
        pj = _powers(w[:, jj], klo, int(kidx.max()) + 1)
        tab = (tab[:, :, None] * pj[:, None, :]).reshape(P, -1)
    Wk = tab[:, index] if f else np.repeat(tab, len(sp["tails"]), axis=1)
    for jj in range(f, len(sp["tail_index"])):
        klo, kidx = sp["tail_index"][jj]
        Wk *= _powers(w[:, jj], klo, int(kidx.max()) + 1)[:, kidx]
    return Wk


def _powers(w: np.ndarray, lo: int, count: int) -> np.ndarray:
    """``exp(2 pi i n w)`` for n = lo .. lo+count-1 (P, count): two exponentials, then products."""
    pw = np.empty((len(w), count), dtype=complex)
    pw[:, 0] = np.exp(TWO_PI_I * lo * w)
    if count > 1:
        pw[:, 1:] = np.exp(TWO_PI_I * w)[:, None]
        np.cumprod(pw, axis=1, out=pw)
    return pw


def _split_ok(lat, lset, s_T, Wr_im) -> bool:
    """Use the factorized sum when it saves exponentials and no factor can overflow."""
    sp = _split_data(lset)
    N, nK = len(lset["m"]), len(sp["tails"])
    if lat.g > 1 and nK > 0.6 * N:
        return False
    if len(Wr_im) == 0:
        return True
    amax = np.max(np.abs(Wr_im), axis=0)
    log1 = 2 * math.pi * np.max(np.abs(sp["n1"])) * amax[0]
    logk = 2 * math.pi * float(np.max(np.abs(sp["tails"]), axis=0, initial=0.0) @ amax[1:]) if lat.g > 1 else 0.0
    logk += math.pi * float(np.max(np.einsum("pi,pi->p", s_T, s_T)))
    return max(log1, logk) < _LOG_SAFE


def _tail_polynomials(jet: Jet, V: np.ndarray, tails: np.ndarray, o: int) -> np.ndarray:
    """Tail polynomials ``H[j, k, T] = sum_{A subset T, |A| = j} prod_{i in A} v_i1 prod_{i in T \\ A} (v_i,rest . k)``
    of :func:`_moments_split`, (o + 1, |K|, jet.size).

    Up to order 2 a term has at most two factors and an entry at most two terms, so the entries are
    written directly, with the operands in the order of the general loop (the same values, in one
    numpy call per kind of subset instead of about ten per subset); higher orders run the general loop.
    """
    nK = len(tails)
    vk = tails @ V[:, 1:].T if jet.r else np.zeros((nK, 0))  # (nK, r)
    H = np.zeros((o + 1, nK, jet.size), dtype=complex)
    if o > 2:
        return _tail_polynomials_loop(jet, V, vk, H)
    masks, pc = jet.masks, jet.popcount
    one_c = np.ones((nK, 1), dtype=complex)  # the loop's products start from ones, its sums from zero
    H[0, :, 0] += one_c[:, 0]
    one = np.flatnonzero(pc == 1)
    if len(one):
        t = np.array([masks[p].bit_length() - 1 for p in one])
        H[0][:, one] += one_c * vk[:, t]
        H[1][:, one] += one_c * V[t, 0][None, :]
    two = np.flatnonzero(pc == 2)
    if len(two):
        lo = np.array([(masks[p] & -masks[p]).bit_length() - 1 for p in two])
        hi = np.array([masks[p].bit_length() - 1 for p in two])
        H[2][:, two] += (one_c * V[lo, 0][None, :]) * V[hi, 0][None, :]
        # the subsets in the loop's order: {hi} (term vk_lo v_hi), then {lo} (term v_lo vk_hi)
        H[1][:, two] += (one_c * vk[:, lo]) * V[hi, 0][None, :]
        H[1][:, two] += (one_c * V[lo, 0][None, :]) * vk[:, hi]
        H[0][:, two] += (one_c * vk[:, lo]) * vk[:, hi]
    return H


def _tail_polynomials_loop(jet: Jet, V: np.ndarray, vk: np.ndarray, H: np.ndarray) -> np.ndarray:
    """:func:`_tail_polynomials` by the general loop over subsets (any order)."""
    nK = len(vk)
    for pos, mask in enumerate(jet.masks):
        A = mask
        while True:
            j = bin(A).count("1")
            term = np.ones(nK, dtype=complex)
            for i in range(jet.r):
                if mask >> i & 1:
                    term = term * (V[i, 0] if A >> i & 1 else vk[:, i])
            H[j, :, pos] += term
            if A == 0:
                break
            A = (A - 1) & mask
    return H


def _moments_split(lat, lset, Wr_re, Wr_im, s_T, bits, jet, V):
    """Same moments as :func:`_moments_direct`, with E[p, (n_1, k)] = W1[p, n_1] Q[n_1, k] Wk[p, k].

    W1 = exp(2 pi i n_1 Wr_1) by powers (two exponentials per point), Wk = exp(2 pi i k.Wr_rest
    - pi ||T f||^2) (|K| exponentials), and the n_1 sum is one complex matrix product with Q.
    Signs (-1)^{n.b} and derivative weights prod (v_i . n) split the same way:
    (-1)^{n_1 b_1} and powers n_1^j go with W1, (-1)^{k.b'} and polynomials in k with the tails.
    """
    sp = _split_data(lset)
    tails, n1, Qm = sp["tails"], sp["n1"], sp["Q"]
    P, g = Wr_re.shape
    N1, nK = Qm.shape
    o = jet.o if jet.r else 0
    b1_vals = np.unique(bits[:, 0], return_inverse=True)[0]      # (the sorted path: no import of numpy.ma)
    rest = bits[:, 1:]
    rest_u, rest_idx = np.unique(rest, axis=0, return_inverse=True)
    rest_idx = np.asarray(rest_idx).reshape(-1)
    H = _tail_polynomials(jet, V, tails, o)
    sgn_rest = sign_matrix(rest_u, tails.astype(np.int64)) if g > 1 else np.ones((nK, 1))  # (nK, nr)
    R = (sgn_rest[None, :, :, None] * H[:, :, None, :]).reshape(o + 1, nK, -1)  # (o+1, nK, nr*size)
    out = np.zeros((P, len(b1_vals), len(rest_u), jet.size), dtype=complex)
    step = max(1, _SPLIT_CHUNK_ENTRIES // max(nK * (o + 1) * len(b1_vals), N1, 1))
    for s0 in range(0, P, step):
        sl = slice(s0, s0 + step)
        pw = _powers(Wr_re[sl, 0] + 1j * Wr_im[sl, 0], sp["lo"], N1)
        lhs = []  # rows (p, b1, j)
        for b1 in b1_vals:
            base = pw * ((-1.0) ** n1)[None, :] if b1 else pw
            for j in range(o + 1):
                lhs.append(base * (n1 ** j)[None, :] if j else base)
        L = np.stack(lhs, axis=1)  # (p, nb1*(o+1), N1)
        Pn = L.shape[0]
        A = (L.reshape(-1, N1) @ Qm).reshape(Pn, len(b1_vals), o + 1, nK)
        Wk = _tail_factors(sp, Wr_re[sl, 1:] + 1j * Wr_im[sl, 1:], s_T[sl])[:, None, :]
        acc = np.zeros((Pn, len(b1_vals), len(rest_u) * jet.size), dtype=complex)
        for j in range(o + 1):  # A * Wk formed per j, contiguous for the product
            acc += ((A[:, :, j, :] * Wk).reshape(-1, nK) @ R[j]).reshape(Pn, len(b1_vals), -1)
        out[sl] = acc.reshape(Pn, len(b1_vals), len(rest_u), jet.size)
    b1_pos = np.searchsorted(b1_vals, bits[:, 0])
    return out[:, b1_pos, rest_idx, :]
