"""Double-double quadrature of the critical intervals of the curve engine.

Where the float64 Gauss-Legendre sum of an interval is not accurate enough (node positions next to
close critical values, roots that float64 cannot separate well, see
:meth:`thetasol.curves._quad.Tracked.critical_intervals`), the interval is re-summed in double-double
arithmetic (~32 digits): the exact rational coefficients of the curve and of the numerators rounded
to double-double pairs, Gauss-Legendre nodes and weights (a stored table of mpmath's values), the
piece's parametrization x(tau), dx/dtau, Newton polishing of all roots from the float seeds, and the
integrand p(x, y) / f_y dx/dtau, all in double-double and vectorized over every node of every
critical interval and every track at once.  Only the sum of each interval is rounded to complex128.

Why by hand: the same computation in mpmath (:func:`thetasol.curves._mp.interval_mp`, kept for the
``dps=`` path and as the reference of the tests) runs a scalar Python Newton loop per node and per
track and dominated the set-up time of the theta solutions; no allowed dependency offers vectorized
double-double arithmetic.  The primitives are those of :mod:`thetasol.core.dd`.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from thetasol.core.dd import (
    DD,
    cdd,
    cdd_add,
    cdd_div,
    cdd_mul,
    cdd_scale,
    cdd_sub,
    cdd_value,
    dd_add,
    dd_div,
    dd_mul,
    dd_split_mp,
    dd_sum,
    split,
)
from thetasol.curves._mp import gauss_legendre_mp
from thetasol.curves._poly import split_exact

_NEWTON_MAX = 12
_REL_DONE = 2.0 ** -104   # a Newton step this small (relative) changes nothing in double-double
_REL_STALL = 1e-26        # steps stagnating below this are rounding noise of an ill-conditioned root


def exact_to_cdd(exact: dict, shape: tuple[int, int]):
    """{(i, j): (Fraction re, Fraction im)} -> complex double-double arrays of ``shape`` indexed [j, i]."""
    hi, lo = np.zeros(shape, complex), np.zeros(shape, complex)
    for (i, j), (re, im) in exact.items():
        hi[j, i], lo[j, i] = split_exact(re, im)
    return hi.real, lo.real, hi.imag, lo.imag


def curve_to_cdd(poly):
    """The curve's coefficients (:class:`CurvePoly` C + Clo) as complex double-double arrays indexed [j, i]."""
    return poly.C.T.real, poly.Clo.T.real, poly.C.T.imag, poly.Clo.T.imag


def numerators_to_cdd(numer_exact):
    """List of exact numerators -> complex double-double arrays (ndiff, J, I) (coefficient of x^i y^j)."""
    I = 1 + max((i for P in numer_exact for i, _ in P), default=0)
    J = 1 + max((j for P in numer_exact for _, j in P), default=0)
    parts = [exact_to_cdd(P, (J, I)) for P in numer_exact]
    return tuple(np.stack([p[c] for p in parts]) for c in range(4))


#: The stored orders of :func:`gauss_legendre_dd`: those of :func:`thetasol.curves._nodes.n_nodes`.
TABLE_ORDERS = range(4, 81)
_TABLE = Path(__file__).with_name("data") / "gauss_legendre_dd.npz"


@cache
def gauss_legendre_dd(N: int):
    """Gauss-Legendre nodes and weights on [-1, 1] as double-double pairs (t_hi, t_lo, w_hi, w_lo).

    Orders in :data:`TABLE_ORDERS` are read from a table of the values of
    :func:`gauss_legendre_dd_mp` (curves/data/gauss_legendre_dd.npz, written by
    :func:`write_gauss_legendre_table`; tests/test_curve_dd.py checks it bit for bit): reading it
    is far cheaper than computing the orders a set-up needs, which would be paid once per process.
    """
    if N in TABLE_ORDERS:
        offsets, nodes = _table()
        k = offsets[N - TABLE_ORDERS.start]
        return tuple(nodes[i, k:k + N] for i in range(4))
    return gauss_legendre_dd_mp(N)


@cache
def _table() -> tuple[np.ndarray, np.ndarray]:
    with np.load(_TABLE) as f:
        return f["offsets"], f["nodes"]


def gauss_legendre_dd_mp(N: int):
    """:func:`gauss_legendre_dd` computed: mpmath at 34 digits, split into double-double pairs."""
    import mpmath
    ts, ws = gauss_legendre_mp(N, 24)
    with mpmath.workdps(40):
        return (*dd_split_mp(ts), *dd_split_mp(ws))


def write_gauss_legendre_table(path: Path = _TABLE) -> None:
    """Write the table of :func:`gauss_legendre_dd` for :data:`TABLE_ORDERS` (in mpmath: slow, run by hand)."""
    parts = [np.stack(gauss_legendre_dd_mp(N)) for N in TABLE_ORDERS]
    offsets = np.cumsum([0] + [p.shape[1] for p in parts])[:-1]
    np.savez_compressed(path, offsets=offsets, nodes=np.concatenate(parts, axis=1))


def _horner(C, z, deriv=False):
    """sum_k C[..., k] z^k in complex double-double (coefficients along the last axis), and its z-derivative.

    The partial sums are carried stacked, hi and lo arrays (s, 2, ...) of [Re, Im] (s = 2 with the
    derivative's sum first), and a Horner step is one broadcast double-double product against the
    factors [[Re z, Im z], [-Im z, Re z]] and two sums: the elementwise operations of
    :func:`thetasol.core.dd.cdd_mul` and ``cdd_add`` (the same bits), with z split once per call and
    each partial sum once per step (``cdd_mul`` splits every part once per product it enters): fewer
    passes over the arrays, and a quarter of the numpy calls (the stacking pays over several steps,
    not for a single one).
    """
    n = C[0].shape[-1] - 1
    # Every factor of the products (partial sums of the value and the derivative, parts of z) is
    # below 4 (n + 1)^2 max|c| max(1, 4 max|z|)^n: where that is below 1e140 the two-products need
    # not test for huge factors (the same results, without two reductions in each of them).
    cmax = max(np.abs(c).max(initial=0.0) for c in C)
    zmax = max(np.abs(v).max(initial=0.0) for v in z)
    with np.errstate(over="ignore", invalid="ignore"):
        bound = cmax * 4.0 * (n + 1) ** 2 * np.maximum(1.0, 4.0 * zmax) ** max(n, 0)
    checked = not bound <= 1e140
    shape = np.broadcast_shapes(C[0].shape[:-1], z[0].shape)
    lead = (1,) * (len(shape) + 1 - C[0].ndim)
    CH = np.stack([C[0], C[2]]).reshape((2,) + lead + C[0].shape)
    CL = np.stack([C[1], C[3]]).reshape(CH.shape)
    H, L = np.empty((1, 2) + shape), np.empty((1, 2) + shape)
    H[...], L[...] = CH[..., n], CL[..., n]
    # factors [c, 1, a]: the part c of a sum times them gives the products summed into part a
    # (full-shape copies: the broadcasts then run over the leading axes only, with contiguous inner loops)
    zf = []
    for v, w in ((z[0], z[2]), (z[1], z[3])):
        f = np.empty((2, 1, 2) + shape)
        f[0, 0, 0], f[0, 0, 1], f[1, 0, 0], f[1, 0, 1] = v, w, -w, v
        zf.append(f)
    zs = None if checked else split(zf[0])
    for k in range(n - 1, -1, -1):
        if deriv and H.shape[0] == 2:
            AH, AL = np.empty(H.shape), np.empty(H.shape)
            AH[0], AH[1], AL[0], AL[1] = H[1], CH[..., k], L[1], CL[..., k]
        else:
            AH, AL = CH[..., k], CL[..., k]
        if deriv and k == n - 1:     # the derivative's sum starts at the value's leading coefficient
            H1, L1 = _horner_step(H, L, zf, zs, AH, AL, checked)
            H, L = np.concatenate([H, H1]), np.concatenate([L, L1])
        else:
            H, L = _horner_step(H, L, zf, zs, AH, AL, checked)
    p = (H[-1, 0], L[-1, 0], H[-1, 1], L[-1, 1])
    if deriv:
        return p, (np.zeros(shape),) * 4 if n == 0 else (H[0, 0], L[0, 0], H[0, 1], L[0, 1])
    return p


def _horner_step(H, L, zf, zs, AH, AL, checked):
    """(H + L) z + (AH + AL) for stacked complex double-doubles (s, 2, ...) (see :func:`_horner`)."""
    ah, al = H.swapaxes(0, 1)[:, :, None], L.swapaxes(0, 1)[:, :, None]    # [c, s, 1]
    ph, pl = dd_mul(ah, al, zf[0], zf[1], checked, zs)       # (zs: z's split, once per call, or None)
    # [c = Re, Im] products summed: [Re Re z + Im (-Im z), Re Im z + Im Re z] = [Re, Im] of the product
    sh, sl = dd_add(ph[0], pl[0], ph[1], pl[1])
    return dd_add(sh, sl, AH, AL)


def _pow_dd(uh, ul, e):
    """(uh + ul)^e for an integer e >= 0 (double-double)."""
    ph, pl = np.ones_like(uh), np.zeros_like(uh)
    for _ in range(e):
        ph, pl = dd_mul(ph, pl, uh, ul)
    return ph, pl


def piece_x_dd(kind, a, b, e, tau):
    """x(tau) and dx/dtau of a path piece in complex double-double (see :class:`thetasol.curves._quad.Piece`).

    a, b: complex arrays (per node), e: int, tau: real double-double (hi, lo) per node.
    """
    th, tl = tau
    if kind == "line":
        d = cdd_sub(cdd(b), cdd(a))
        return cdd_add(cdd(a), cdd_scale(d, th, tl)), d
    if kind not in ("point", "inf"):
        raise ValueError(f"no double-double parametrization for a {kind!r} piece")
    d = cdd_sub(cdd(a), cdd(b))
    uh, ul = dd_add(np.ones_like(th), 0.0 * th, -th, -tl)
    if kind == "point":
        xh = cdd_add(cdd(b), cdd_scale(d, *_pow_dd(uh, ul, e)))
        return xh, cdd_scale(d, *dd_mul(*_pow_dd(uh, ul, e - 1), np.full_like(th, -float(e)), 0.0))
    ph, pl = _pow_dd(uh, ul, e)
    inv_h, inv_l = dd_div(np.ones_like(th), 0.0 * th, ph, pl)
    x = cdd_add(cdd(b), cdd_scale(d, inv_h, inv_l))
    inv2_h, inv2_l = dd_div(inv_h, inv_l, uh, ul)
    return x, cdd_scale(d, *dd_mul(inv2_h, inv2_l, np.full_like(th, float(e)), 0.0))


def _nodes_dd(pieces, crit):
    """Gauss-Legendre nodes of every interval on its piece, in double-double: the points
    ``X`` (complex double-double), ``w dx/dtau`` per node, and the interval of each node."""
    # every node of every interval at once (elementwise: the same operations as interval by interval)
    Ns = np.array([N for _, _, (_, _, N) in crit])
    nint = np.repeat(np.arange(len(crit)), Ns)
    lo = np.array([lo_ for _, _, (lo_, _, _) in crit], dtype=float)[nint]
    hi = np.array([hi_ for _, _, (_, hi_, _) in crit], dtype=float)[nint]
    th_, tl_, wh_, wl_ = (np.concatenate(v) for v in zip(*(gauss_legendre_dd(int(N)) for N in Ns)))
    mh, ml = dd_add(lo, 0.0, hi, 0.0)
    hh, hl = dd_add(hi, 0.0, -lo, 0.0)
    mh, ml, hh, hl = 0.5 * mh, 0.5 * ml, 0.5 * hh, 0.5 * hl   # exact halvings
    tau_h, tau_l = dd_add(mh, ml, *dd_mul(th_, tl_, hh, hl))
    w_h, w_l = dd_mul(wh_, wl_, hh, hl)
    K = len(tau_h)
    X = [np.zeros(K) for _ in range(4)]
    DX = [np.zeros(K) for _ in range(4)]
    pidx = np.array([crit[c][0] for c in range(len(crit))])[nint]
    groups = {}
    for node, p in enumerate(pidx.tolist()):
        pc = pieces[p]
        groups.setdefault((pc.kind, pc.e), []).append(node)
    for (kind, e), sel in groups.items():
        sel = np.asarray(sel)
        a = np.array([pieces[p].a for p in pidx[sel]])
        b = np.array([pieces[p].b for p in pidx[sel]])
        x, dx = piece_x_dd(kind, a, b, e, (tau_h[sel], tau_l[sel]))
        for c in range(4):
            X[c][sel] = x[c]
            DX[c][sel] = dx[c]
    return tuple(X), cdd_scale(tuple(DX), w_h, w_l)


@dataclass(frozen=True)
class _Pairs:
    """The (node, track) pairs, interval by interval: each pair's node, float seed, quadrature
    index ``q`` and group (interval, track) ``grp``; ``gstart`` the first group of each interval."""

    node: np.ndarray
    seed: np.ndarray
    q: np.ndarray
    grp: np.ndarray
    gstart: np.ndarray


def _pairs(crit, seeds) -> _Pairs:
    Ns = np.array([N for _, _, (_, _, N) in crit], dtype=np.int64)
    ms = np.array([s.shape[0] for s in seeds], dtype=np.int64)
    base = np.cumsum(np.concatenate([[0], Ns]))
    gstart = np.cumsum(np.concatenate([[0], ms]))
    # interval by interval, track-major: pair r of interval c is node r % N of track r // N
    cnt = ms * Ns
    ic = np.repeat(np.arange(len(crit)), cnt)
    r = np.arange(int(cnt.sum())) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    q = r % Ns[ic]
    return _Pairs(node=base[ic] + q, seed=np.concatenate([np.asarray(s, dtype=complex).ravel() for s in seeds]),
                  q=q, grp=gstart[ic] + r // Ns[ic], gstart=gstart)


def _newton_dd(Ap, y0):
    """Newton's method on all roots at once, from the float seeds ``y0``; returns the roots
    (complex double-double) and ``f_y`` there.

    Steps in float (they are small corrections).  A root is done when its step is below the
    rounding bound of the double-double residual, 2^-104 (n + 1) sum |a_j| |y|^j / |f_y|
    (ill-conditioned roots near colliding sheets), or when its steps stop decreasing below
    1e-26 relative; it then leaves the iteration with its y and f_y (the ill-conditioned roots still
    step after the others are done)."""
    y = tuple(np.array(v) for v in cdd(y0))       # (four arrays: updated in place below)
    fy = tuple(np.zeros(len(y0)) for _ in range(4))
    prev = np.full(len(y0), np.inf)
    absA = np.abs(Ap[0] + 1j * Ap[2])
    act = np.arange(len(y0))       # the roots not done yet: a done root keeps its y and f_y
    for _ in range(_NEWTON_MAX):
        ya = tuple(v[act] for v in y)
        f, fya = _horner(tuple(v[act] for v in Ap), ya, deriv=True)
        for c in range(4):
            fy[c][act] = fya[c]
        with np.errstate(divide="ignore", invalid="ignore"):
            step = cdd_value(f) / cdd_value(fya)
            rel = np.abs(step) / np.abs(cdd_value(ya))
        if not np.all(np.isfinite(step)):
            raise ValueError("double-double quadrature: f_y vanishes at a node (numerically singular curve)")
        ay = np.abs(cdd_value(ya))
        S = absA[act, -1]
        for j in range(absA.shape[1] - 2, -1, -1):
            S = S * ay + absA[act, j]
        with np.errstate(divide="ignore", invalid="ignore"):
            noise = _REL_DONE * absA.shape[1] * S / np.abs(cdd_value(fya)) / ay
        done = (rel <= np.maximum(_REL_DONE, noise)) | ((rel >= prev[act]) & (rel <= _REL_STALL)) | (step == 0)
        prev[act] = rel
        act, step = act[~done], step[~done]
        if not len(act):
            break
        ynew = cdd_sub(tuple(v[act] for v in y), cdd(step))
        for c in range(4):
            y[c][act] = ynew[c]
    else:
        raise ValueError("Newton's method did not converge in the double-double quadrature")
    yz = cdd_value(y)
    moved = np.abs(yz - y0)
    if np.any((moved > 1e-4 * (np.abs(y0) + 1e-300) + 1e-300) & (moved > 1e-6)):
        raise ValueError("multiprecision quadrature: a root moved away from its sheet "
                         "(numerically singular curve)")
    return y, fy


def _interval_sums(term, pr: _Pairs, crit, rounded):
    """Sums per (interval, track) in double-double: padded (node, group, ndiff) layout."""
    gstart = pr.gstart
    G = int(gstart[-1])
    Nmax = int(max(N for _, _, (_, _, N) in crit))
    nd = term[0].shape[1]
    sums = []
    for c in range(4):
        buf = np.zeros((Nmax, G, nd))
        buf[pr.q, pr.grp] = term[c]
        sums.append(buf)
    re = dd_sum(DD(sums[0], sums[1]))
    im = dd_sum(DD(sums[2], sums[3]))
    if not rounded:
        return [(re.hi[gstart[c]:gstart[c + 1]], re.lo[gstart[c]:gstart[c + 1]],
                 im.hi[gstart[c]:gstart[c + 1]], im.lo[gstart[c]:gstart[c + 1]]) for c in range(len(crit))]
    tot = (re.hi + re.lo) + 1j * (im.hi + im.lo)                       # (G, ndiff)
    return [tot[gstart[c]:gstart[c + 1]] for c in range(len(crit))]


@dataclass(frozen=True)
class IntervalRoots:
    """What :func:`intervals_dd` computes before any numerator: the nodes ``X`` (complex double-double),
    the (node, track) pairs, the polished roots ``y`` and ``w dx/dtau / f_y`` per pair.  The curve engine
    keeps it per set of intervals, so further differentials over the same cycles (the third-kind periods
    of the theta-function rotation) pay only for their numerators."""

    X: tuple
    pairs: _Pairs
    y: tuple
    fac: tuple


def interval_roots_dd(pieces, crit, seeds, curve_cdd) -> IntervalRoots:
    """The numerator-free stage of :func:`intervals_dd` (same parameters)."""
    X, wdx = _nodes_dd(pieces, crit)                                   # weight * dx/dtau per node
    A = _horner(curve_cdd, tuple(v[:, None] for v in X))              # (K, n + 1): a_j(x) at every node
    pr = _pairs(crit, seeds)
    pn = pr.node
    y, fy = _newton_dd(tuple(v[pn] for v in A), pr.seed)
    fac = cdd_div(tuple(v[pn] for v in wdx), fy)                      # w dx/dtau / f_y per pair
    return IntervalRoots(X=X, pairs=pr, y=y, fac=fac)


def interval_sums_dd(roots: IntervalRoots, crit, numer_cdd, rounded=True):
    """The sums of :func:`intervals_dd` from its numerator-free stage ``roots`` (same ``crit``)."""
    B = _horner(numer_cdd, tuple(v[:, None, None] for v in roots.X))  # (K, ndiff, J): b_dj(x) at every node
    Bp = tuple(v[roots.pairs.node] for v in B)                         # (P, ndiff, J)
    g = _horner(Bp, tuple(v[:, None] for v in roots.y))                # (P, ndiff)
    term = cdd_mul(g, tuple(v[:, None] for v in roots.fac))
    return _interval_sums(term, roots.pairs, crit, rounded)


def intervals_dd(pieces, crit, seeds, curve_cdd, numer_cdd, rounded=True):
    """Double-double Gauss-Legendre sums over critical intervals, for every track.

    Parameters
    ----------
    pieces : list of :class:`thetasol.curves._quad.Piece`
    crit : list of (piece index, first node, (lo, hi, N)) as from ``Tracked.critical_intervals``.
    seeds : list (per interval) of complex arrays (m, N): float roots at the float nodes, one row per track.
    curve_cdd : complex double-double coefficients of f, arrays (n + 1, dx + 1) indexed [j, i].
    numer_cdd : complex double-double numerator coefficients, arrays (ndiff, J, I).
    rounded : if False, return the unrounded sums as complex double-double 4-tuples (for tests).

    Returns
    -------
    list (per interval) of complex arrays (m, ndiff), each the interval's sum rounded to complex128.
    """
    if not crit:
        return []
    return interval_sums_dd(interval_roots_dd(pieces, crit, seeds, curve_cdd), crit, numer_cdd, rounded)
