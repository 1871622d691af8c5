"""Multiprecision evaluation for the curve engine (mpmath, private mp contexts only).

Two uses.  (1) Where float64 cannot separate the sheets (a node of the path lies so close to nearly
colliding branch points that the rounding error of a computed root is not small against the distance
between roots), the roots and derivatives at that node are recomputed with mpmath from the exact
coefficients and rounded back: the tracking and the quadrature then proceed in float64 with correct
values.  (2) The ``dps`` path: the sheet assignment found in float64 is kept, every quadrature node and
weight is recomputed at the requested precision, each root is polished by Newton's method in mpmath
and the integrals are summed in mpmath.  Nothing here changes mpmath's global precision: all work is
done inside ``mpmath.workdps``.
"""
from __future__ import annotations

from functools import cache

import mpmath
import numpy as np


class ExactEvaluator:
    """f and its derivatives at mp precision from the exact rational coefficients."""

    def __init__(self, poly):
        self.poly = poly
        self._cache = {}

    def coeffs(self, dps):
        """Coefficient table C[i][j] as mpc at precision dps (cached)."""
        if dps not in self._cache:
            with mpmath.workdps(dps):
                C = [[mpmath.mpc(0) for _ in range(self.poly.n + 1)] for _ in range(self.poly.dx + 1)]
                for (i, j), (re, im) in self.poly.exact.items():
                    C[i][j] = mpmath.mpc(mpmath.mpf(re.numerator) / re.denominator,
                                         mpmath.mpf(im.numerator) / im.denominator)
            self._cache[dps] = C
        return self._cache[dps]

    def ycoeffs(self, x, dps, deriv=False):
        """a_j(x) (and a_j'(x)) for one mp x."""
        C = self.coeffs(dps)
        n, dx = self.poly.n, self.poly.dx
        a = []
        da = []
        for j in range(n + 1):
            p = C[dx][j]
            dp = mpmath.mpc(0)
            for i in range(dx - 1, -1, -1):
                if deriv:
                    dp = dp * x + p
                p = p * x + C[i][j]
            a.append(p)
            da.append(dp)
        return (a, da) if deriv else a

    @staticmethod
    def horner(a, y):
        p = a[-1]
        dp = mpmath.mpc(0)
        for c in a[-2::-1]:
            dp = dp * y + p
            p = p * y + c
        return p, dp

    def roots_at(self, x, dps=40):
        """All roots in y, f_y and f_x at one float x (complex128 results, computed in mpmath).

        Float roots of the mp-evaluated polynomial seed the search; each cluster of nearly equal roots
        is resolved by re-expanding the polynomial (in mpmath) around the cluster centre, where its
        float roots are accurate relative to the cluster size; every root is then polished by
        Newton's method in mpmath.  mpmath.polyroots is the last resort.
        """
        with mpmath.workdps(dps):
            xm = mpmath.mpc(x)
            a, da = self.ycoeffs(xm, dps, deriv=True)
            if a[-1] == 0:
                raise ValueError(f"leading coefficient vanishes at x = {x}")
            roots = self._cluster_roots(a, dps)
            if roots is None:
                nn = len(a) - 1
                sig = max(abs(a[j] / a[nn]) ** (mpmath.mpf(1) / (nn - j)) for j in range(nn)) if nn else 1
                sig = sig if sig > 0 else mpmath.mpf(1)
                sc = [a[j] * sig**j for j in range(nn + 1)]
                try:
                    roots = [r * sig for r in mpmath.polyroots(sc[::-1], maxsteps=400, extraprec=2 * dps)]
                except mpmath.libmp.NoConvergence as exc:
                    raise ValueError(f"the curve is numerically singular near x = {x:.6g}: roots do not "
                                     f"separate at {dps} digits") from exc
            R, FY, FX = [], [], []
            for r in roots:
                p, dp = self.horner(a, r)
                px, _ = self.horner(da, r)
                R.append(complex(r))
                FY.append(complex(dp))
                FX.append(complex(px))
        return np.array(R), np.array(FY), np.array(FX)

    def _cluster_roots(self, a, dps):
        n = len(a) - 1
        ca = np.array([complex(c) for c in a])
        if not np.all(np.isfinite(ca)) or ca[-1] == 0:
            return None
        r = np.roots(ca[::-1])
        if len(r) != n:
            return None
        scale = np.max(np.abs(r)) + 1e-300
        # groups of roots closer than 1e-4 of the root scale
        groups = []
        used = np.zeros(n, bool)
        for i in range(n):
            if used[i]:
                continue
            g = [i]
            used[i] = True
            for j in range(n):
                if not used[j] and np.min(np.abs(r[j] - r[g])) < 1e-4 * scale:
                    g.append(j)
                    used[j] = True
            groups.append(g)
        out = []
        tol = mpmath.mpf(10) ** (-(dps - 6))
        for g in groups:
            if len(g) == 1:
                seeds = [mpmath.mpc(r[g[0]])]
            else:
                c = mpmath.mpc(complex(np.mean(r[g])))
                # Taylor shift p(c + eta) in mpmath (Horner scheme on the coefficient list)
                b = list(a)
                for k in range(n):
                    for j in range(n - 1, k - 1, -1):
                        b[j] = b[j] + c * b[j + 1]
                cb = np.array([complex(v) for v in b])
                eta = np.roots(cb[::-1])
                eta = eta[np.argsort(np.abs(eta))][:len(g)]
                seeds = [c + mpmath.mpc(complex(e)) for e in eta]
            for y in seeds:
                for _ in range(60):
                    f, d = self.horner(a, y)
                    if d == 0:
                        return None
                    step = f / d
                    y -= step
                    if abs(step) <= tol * (abs(y) + 1e-300) or step == 0:
                        break
                else:
                    return None
                out.append(y)
        # distinct roots?
        for i in range(n):
            for j in range(i):
                if abs(out[i] - out[j]) <= 1e3 * tol * (abs(out[i]) + 1e-300):
                    return None
        return out

    def fallback(self, xs, R_float):
        """Replacement (R, f_y, f_x) rows for the flagged nodes xs (float)."""
        R = np.empty((len(xs), self.poly.n), complex)
        FY = np.empty_like(R)
        FX = np.empty_like(R)
        for i, x in enumerate(xs):
            for dps in (30, 60):
                r, fy, fx = self.roots_at(complex(x), dps)
                sep = np.min(np.abs(r[:, None] - r[None, :]) + np.diag(np.full(len(r), np.inf))) \
                    if len(r) > 1 else np.inf
                if sep > 1e-13 * (np.max(np.abs(r)) + 1e-300):
                    break
            else:
                raise ValueError(f"the curve is numerically singular near x = {complex(x):.6g}: two sheets "
                                 "coincide to 80 digits (a singular point on the path?)")
            R[i], FY[i], FX[i] = r, fy, fx
        return R, FY, FX


@cache
def gauss_legendre_mp(N: int, dps: int):
    """Gauss-Legendre nodes and weights on [-1, 1] at dps digits (Newton on P_N from float seeds)."""
    t0, _ = np.polynomial.legendre.leggauss(N)
    with mpmath.workdps(dps + 10):
        ts, ws = [], []
        for x0 in t0:
            x = mpmath.mpf(x0)
            for _ in range(100):
                p0, p1 = mpmath.mpf(1), x
                for k in range(2, N + 1):
                    p0, p1 = p1, ((2 * k - 1) * x * p1 - (k - 1) * p0) / k
                dp = N * (x * p1 - p0) / (x * x - 1)
                dx = p1 / dp
                x -= dx
                if abs(dx) < mpmath.mpf(10) ** (-(dps + 8)):
                    break
            p0, p1 = mpmath.mpf(1), x
            for k in range(2, N + 1):
                p0, p1 = p1, ((2 * k - 1) * x * p1 - (k - 1) * p0) / k
            dp = N * (x * p1 - p0) / (x * x - 1)
            ts.append(x)
            ws.append(2 / ((1 - x * x) * dp * dp))
    return ts, ws


def piece_x_mp(pc, tau):
    a, b, e = mpmath.mpc(pc.a), mpmath.mpc(pc.b), pc.e
    if pc.kind == "line":
        return a + (b - a) * tau, (b - a)
    u = 1 - tau
    if pc.kind == "point":
        return b + (a - b) * u**e, -e * (a - b) * u ** (e - 1)
    return b + (a - b) / u**e, e * (a - b) / u ** (e + 1)


def numerators_mp(numer_exact, dps):
    """Numerator polynomials {(i, j): complex rational} -> lists of (i, j, mpc)."""
    out = []
    with mpmath.workdps(dps):
        for P in numer_exact:
            out.append([(i, j, mpmath.mpc(mpmath.mpf(re.numerator) / re.denominator,
                                          mpmath.mpf(im.numerator) / im.denominator))
                        for (i, j), (re, im) in P.items()])
    return out


def interval_mp(pc, lo, hi, N, seeds, ev, nums, dps):
    """mp Gauss-Legendre sum over [lo, hi] of one piece for every track.

    seeds: (m, N) float approximations of the roots at the (float) nodes, one row per track.
    Returns a list (per track) of lists (per numerator) of mpc.
    """
    m = seeds.shape[0]
    wdps = dps + 10
    tol = mpmath.mpf(10) ** (-(dps + 2))
    ts, ws = gauss_legendre_mp(N, dps)
    lo_m, hi_m = mpmath.mpf(lo), mpmath.mpf(hi)
    half = (hi_m - lo_m) / 2
    mid = (hi_m + lo_m) / 2
    acc = [[mpmath.mpc(0) for _ in nums] for _ in range(m)]
    for q, (t, w) in enumerate(zip(ts, ws)):
        tau = mid + half * t
        x, dxdt = piece_x_mp(pc, tau)
        a = ev.ycoeffs(x, wdps)
        for s in range(m):
            y0 = complex(seeds[s, q])
            y = mpmath.mpc(y0)
            prev = None
            for _ in range(60):
                f, fy = ev.horner(a, y)
                step = f / fy
                y -= step
                st = abs(step)
                if st <= tol * abs(y) or st == 0:
                    break
                if prev is not None and st >= prev and st <= 1e-6 * tol ** 0.5 * abs(y):
                    break  # stagnated at the rounding level of the working precision
                prev = st
            else:
                raise ValueError("Newton's method did not converge in the multiprecision quadrature")
            f, fy = ev.horner(a, y)
            if abs(complex(y) - y0) > 1e-4 * (abs(y0) + 1e-300) + 1e-300 and abs(complex(y) - y0) > 1e-6:
                raise ValueError("multiprecision quadrature: a root moved away from its sheet "
                                 "(numerically singular curve)")
            fac = w * half * dxdt / fy
            for d, terms in enumerate(nums):
                g = mpmath.mpc(0)
                for i, j, c in terms:
                    g += c * x**i * y**j
                acc[s][d] += g * fac
    return acc


def integrate_mp(tracked, ev, numer_exact, dps):
    """mp integrals along every track of a :class:`Tracked` (its pieces planned for this precision).

    Returns a list over pieces of lists (per track) of lists (per numerator) of mpc.
    """
    nodes = tracked.nodes
    wdps = dps + 10
    out = []
    with mpmath.workdps(wdps):
        nums = numerators_mp(numer_exact, wdps)
        pos = 0
        for p, pc in enumerate(tracked.pieces):
            m = len(pc.y0)
            L = nodes.offsets[p + 1] - nodes.offsets[p]
            ch = tracked.choice[pos:pos + m, :L]
            Rp = tracked.R[nodes.offsets[p]:nodes.offsets[p + 1]]
            acc = [[mpmath.mpc(0) for _ in nums] for _ in range(m)]
            k = 1  # node 0 is the start (weight 0)
            for lo, hi, N in nodes.plans[p]:
                seeds = Rp[np.arange(k, k + N)[None, :], ch[:, k:k + N]]
                part = interval_mp(pc, lo, hi, N, seeds, ev, nums, dps)
                for s in range(m):
                    for d in range(len(nums)):
                        acc[s][d] += part[s][d]
                k += N
            out.append(acc)
            pos += m
    return out


def cycle_sums_mp(res, cycles, nd: int, n: int, dps: int):
    """Periods (nd x len(cycles) mpmath matrix) from the per-edge, per-sheet integrals ``res[e][s][d]``
    and cycles given as integer coefficients on the lifted edges ``e * n + s``."""
    with mpmath.workdps(dps + 10):
        Pm = mpmath.matrix(nd, len(cycles))
        for col, cyc in enumerate(cycles):
            for le in np.nonzero(cyc)[0]:
                e, s_ = divmod(int(le), n)
                c = int(cyc[le])
                for d in range(nd):
                    Pm[d, col] += c * res[e][s_][d]
    return Pm
