"""Analytic continuation of the sheets along paths, and quadrature of differentials.

Method.  A path piece is a map x(tau), tau in [0, 1]: a straight segment, a segment into a
critical value s written in the local parameter (x = s + (v - s)(1 - tau)^e), or a ray to
infinity (x = c + (v - c)(1 - tau)^(-e)).  In tau every integrand g/f_y dx/dtau of a holomorphic
differential is analytic on [0, 1]; its singularities are the preimages of the critical values.
[0, 1] is split until each interval sees its nearest singularity outside the Bernstein ellipse of
parameter rho >= 2.5, and each interval gets the Gauss-Legendre rule whose error bound rho^(-2N) is
below the tolerance (the classical a-priori estimate; geometric refinement appears by itself next to
close critical values).

The sheets are continued through the quadrature nodes: all roots in y are computed at once
(companion eigenvalues, vectorized over every node of every piece, then Newton steps with
compensated double-double residuals), then matched node to node with a Hermite test (the tangents
from both ends must meet at the midpoint far closer than the roots are to each other), a
gap-closing-time test and a tangent-turn test.  Where sheets turn together, gaps a small fraction of
their common motion (large circles, far branch points of nearly symmetric bodies), the Hermite test on
y would need steps ~ gap^(1/3); it is also tried on log y, and on the mean and half-difference of a
tight pair of sheets, either of which matches such steps safely (far fewer nodes per circle for
nearly symmetric bodies).  Steps that fail every test are subdivided in vectorized rounds;
roots that float64 cannot separate are recomputed with mpmath from the exact coefficients, and
intervals whose float64 sum is not accurate enough are re-summed in double-double from the exact
coefficients (:mod:`thetasol.curves._dd`, vectorized over all nodes and tracks; nearly singular curves).
This is written by hand rather than with a homotopy-continuation library because none of the
allowed dependencies offers vectorized polynomial root tracking.
"""
from __future__ import annotations

import numpy as np

from thetasol.curves._nodes import Nodes
from thetasol.curves._walk import walk_safe

EPS = np.finfo(float).eps
SAFETY = 0.25
MOVE = 0.5
FLAG = 1e-4
JITTER = 1e-13
REL = 1e-11


class Piece:
    """A path piece x(tau), tau in [0, 1], with the sheet values to continue from tau = 0.

    kind 'line': x = a + (b - a) tau;  'point': x = b + (a - b)(1 - tau)^e (ends at the critical
    value b);  'inf': x = b + (a - b)(1 - tau)^(-e) (ends at infinity; b the centre).
    """

    __slots__ = ("kind", "a", "b", "e", "y0", "taus")

    def __init__(self, kind, a, b, y0, e=1, taus=None):
        self.kind = kind
        self.a = complex(a)
        self.b = complex(b)
        self.e = int(e)
        self.y0 = np.atleast_1d(np.asarray(y0, dtype=complex))
        self.taus = taus  # explicit tracking nodes (no quadrature) if given

    def x(self, tau):
        tau = np.asarray(tau, dtype=float)
        if self.kind == "line":
            # the end exactly b: a + (b - a) is off by ~eps |a|, which a line from a far vertex
            # (nearly symmetric body) next to a branch point magnifies in y
            return np.where(tau == 1.0, self.b, self.a + (self.b - self.a) * tau)
        if self.kind == "circle":  # around b, starting at a; e = +1 ccw, -1 cw
            return self.b + (self.a - self.b) * np.exp(2j * np.pi * self.e * tau)
        u = 1.0 - tau
        if self.kind == "point":
            return self.b + (self.a - self.b) * u**self.e
        return self.b + (self.a - self.b) / u**self.e

    def dx(self, tau):
        tau = np.asarray(tau, dtype=float)
        if self.kind == "line":
            return np.full(tau.shape, self.b - self.a, dtype=complex)
        if self.kind == "circle":
            return 2j * np.pi * self.e * (self.x(tau) - self.b)
        u = 1.0 - tau
        e = self.e
        if self.kind == "point":
            return -e * (self.a - self.b) * u ** (e - 1) + 0j
        return e * (self.a - self.b) / u ** (e + 1) + 0j

    def ddx(self, tau):
        tau = np.asarray(tau, dtype=float)
        if self.kind == "line":
            return np.zeros(tau.shape, dtype=complex)
        if self.kind == "circle":
            return (2j * np.pi * self.e) ** 2 * (self.x(tau) - self.b)
        u = 1.0 - tau
        e = self.e
        if self.kind == "point":
            return e * (e - 1) * (self.a - self.b) * u ** (e - 2) + 0j if e > 1 else np.zeros(tau.shape, complex)
        return e * (e + 1) * (self.a - self.b) / u ** (e + 2) + 0j

    def singularities(self, sites):
        """Preimages in the tau-plane of the critical values ``sites``."""
        sites = np.asarray(sites, dtype=complex)
        if self.kind == "line":
            d = self.b - self.a
            if d == 0:
                return np.zeros(0, complex)
            return (sites - self.a) / d
        e = self.e
        if self.kind == "point":
            sites = sites[sites != self.b]
            w = (sites - self.b) / (self.a - self.b)
        else:
            with np.errstate(divide="ignore", invalid="ignore"):
                w = (self.a - self.b) / (sites - self.b)
            w = w[np.isfinite(w)]
        if len(w) == 0:
            return np.zeros(0, complex)
        r = np.abs(w) ** (1.0 / e)
        th = np.angle(w) / e
        k = np.arange(e)
        roots = r[:, None] * np.exp(1j * (th[:, None] + 2 * np.pi * k[None, :] / e))
        return (1.0 - roots).ravel()


def _collision_times(R, Dt, sep):
    """sep / |d(gap)/dtau| for the nearest other root of every root (inf where the gap is constant)."""
    if R.shape[1] == 1:
        return np.full(R.shape, np.inf)
    nn = np.argmin(_gaps(R), axis=2)
    rate = np.abs(Dt - np.take_along_axis(Dt, nn, axis=1))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(rate > 0, sep / rate, np.inf)


def _log_hermite(y, yd, y2, R, D, D2, dt, h2):
    """The Hermite matching test of :meth:`Tracker._match_pass` on log y, for steps that fail it on y.

    y, yd, y2 (m,): value and tau-derivatives at the previous node; R, D, D2 (m, n) at the next one.
    Returns (index of the matching root, safe).  Safe also needs |dt (log y)'| <= MOVE at both ends
    (y neither changes by more than e^MOVE nor turns by more than MOVE radians over the step), which
    keeps log y away from its branch point y = 0.
    """
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        lp = yd / y
        l2p = y2 / y - lp * lp
        ln = D / R
        l2n = D2 / R - ln * ln
        lr = np.log(R / y[:, None])
        dd = np.abs(lr - 0.5 * dt[:, None] * ln + h2[:, None] * l2n - (0.5 * dt * lp + h2 * l2p)[:, None])
        dd = np.where(np.isfinite(dd), dd, np.inf)
        i = np.argmin(dd, axis=1)
        ar = np.arange(len(y))
        d1 = dd[ar, i]
        d2 = np.partition(dd, 1, axis=1)[:, 1]
        # log-gap of the chosen root to the others at the next node
        gl = np.abs(np.log(R / R[ar, i][:, None]))
        gl[ar, i] = np.inf
        sep = gl.min(axis=1)
        turn = np.abs(dt * dt * (l2n[ar, i] - l2p))
        adt = np.abs(dt)
        ok = ((d1 <= SAFETY * d2) & (d1 <= SAFETY * sep) & (turn <= SAFETY * sep)
              & (adt * np.abs(lp) <= MOVE) & (adt * np.abs(ln[ar, i]) <= MOVE))
    return i, ok


def _pair_hermite(P, Pd, P2, ip, R, D, D2, dt, h2):
    """The Hermite test for a track in a tight pair of sheets whose common motion is large against
    their gap (a far branch point: the test on y then needs steps ~ gap^(1/3)).

    The pair {ip, nearest neighbour} at the previous node is matched to a pair at the next node by
    the test on the pair's mean (analytic while the pair stays apart from the other sheets, tested
    against their distance), and the track inside the pair by the test on the half-difference
    (tested against the pair's gap).  P, Pd, P2 (m, n): roots and tau-derivatives at the previous
    node, ip (m,) the track's root there; R, D, D2 at the next node.  Returns (index, safe).
    """
    m, n = R.shape
    ar = np.arange(m)

    nnP, nnR = np.argmin(_gaps(P), axis=2), np.argmin(_gaps(R), axis=2)
    kp = nnP[ar, ip]
    # midpoint predictions of the mean and half-difference from the previous node
    Mp = 0.5 * (P[ar, ip] + P[ar, kp]) + 0.25 * dt * (Pd[ar, ip] + Pd[ar, kp]) + 0.5 * h2 * (P2[ar, ip] + P2[ar, kp])
    Zp = 0.5 * (P[ar, ip] - P[ar, kp]) + 0.25 * dt * (Pd[ar, ip] - Pd[ar, kp]) + 0.5 * h2 * (P2[ar, ip] - P2[ar, kp])
    m2p = 0.5 * (P2[ar, ip] + P2[ar, kp])
    z2p = 0.5 * (P2[ar, ip] - P2[ar, kp])
    # the same from the next node, for the pair of every root there
    Rn, Dn, D2n = (np.take_along_axis(V, nnR, axis=1) for V in (R, D, D2))
    Mc = 0.5 * (R + Rn) - 0.25 * dt[:, None] * (D + Dn) + 0.5 * h2[:, None] * (D2 + D2n)
    j = np.argmin(np.abs(Mc - Mp[:, None]), axis=1)
    l = nnR[ar, j]
    mean = 0.5 * (R[ar, j] + R[ar, l])
    out = np.abs(R - mean[:, None])
    out[ar, j] = np.inf
    out[ar, l] = np.inf
    sepM = out.min(axis=1) if n > 2 else np.full(m, np.inf)
    dM = np.abs(Mc[ar, j] - Mp)
    turnM = np.abs(dt * dt * (0.5 * (D2[ar, j] + D2[ar, l]) - m2p))
    Zc = 0.5 * (R[ar, j] - R[ar, l]) - 0.25 * dt * (D[ar, j] - D[ar, l]) + 0.5 * h2 * (D2[ar, j] - D2[ar, l])
    z2c = 0.5 * (D2[ar, j] - D2[ar, l])
    dp, dm = np.abs(Zc - Zp), np.abs(Zc + Zp)
    pick = np.where(dp <= dm, j, l)
    d1, d2 = np.minimum(dp, dm), np.maximum(dp, dm)
    sepZ = np.abs(R[ar, j] - R[ar, l])
    turnZ = np.abs(dt * dt * (np.where(dp <= dm, z2c, -z2c) - z2p))
    ok = ((nnP[ar, kp] == ip) & (nnR[ar, l] == j)            # mutual nearest neighbours at both ends
          & (sepZ <= SAFETY * sepM)                          # a pair apart from the rest
          & (dM <= SAFETY * sepM) & (turnM <= SAFETY * sepM)
          & (d1 <= SAFETY * d2) & (d1 <= SAFETY * sepZ) & (turnZ <= SAFETY * sepZ))
    return pick, ok


def _step_tests(c, prev, node, dt, h2, mc, pool):
    """The matching tests of the steps prev -> node for a track holding root ``c`` at ``prev``.

    Hermite test on y (second-order midpoint predictions from both ends), else on log y, else on a
    tight pair; safe also needs the step within MOVE of both ends' scales.  Returns the root index
    ``i``, ``safe`` (before the test for duplicates) and what :func:`_subdivisions` needs.
    """
    Rp, Dp, Sp, Tc, D2p = pool["R"], pool["Dt"], pool["sep"], pool["tc"], pool["D2"]
    n = Rp.shape[1]
    ycur, ydcur, tccur, y2cur = Rp[prev, c], Dp[prev, c], Tc[prev, c], D2p[prev, c]
    with np.errstate(all="ignore"):
        mp_ = ycur + 0.5 * dt * ydcur + h2 * y2cur
        dd = np.abs(mc - mp_[:, None])
        i = np.argmin(dd, axis=1)
        ar = np.arange(len(i))
        d1 = dd[ar, i]
        d2 = np.partition(dd, 1, axis=1)[:, 1] if n > 1 else np.full(len(i), np.inf)
        sepi = Sp[node, i]
        turn = np.abs(dt * dt * (D2p[node, i] - y2cur))
        adt = np.abs(dt)
        # the tangent may turn by no more than a fraction of the gap over the step (curvature),
        # otherwise the Hermite discrepancy is not a reliable error measure
        herm = (d1 <= SAFETY * d2) & (d1 <= SAFETY * sepi) & (turn <= SAFETY * sepi)
        if not herm.all():
            # the same test on log y: sheets that turn together (y ~ c_j x^p on a large circle,
            # gaps a small fraction of |y|) fail it in y at steps ~ gap^(1/3) but pass it in log y
            w = np.nonzero(~herm)[0]
            il, ok = _log_hermite(ycur[w], ydcur[w], y2cur[w], Rp[node[w]], Dp[node[w]],
                                  D2p[node[w]], dt[w], h2[w])
            i[w] = np.where(ok, il, i[w])
            herm[w] = ok
            w = w[~ok]
            if len(w) and n > 1:
                # a tight pair of sheets riding on a common motion (near a far branch point): the
                # test on the pair's mean and on its half-difference
                ip, ok = _pair_hermite(Rp[prev[w]], Dp[prev[w]], D2p[prev[w]], np.full(len(w), c),
                                       Rp[node[w]], Dp[node[w]], D2p[node[w]], dt[w], h2[w])
                i[w] = np.where(ok, ip, i[w])
                herm[w] = ok
        Tci = Tc[node, i]
        safe = herm & (adt <= MOVE * tccur) & (adt <= MOVE * Tci)
    return {"i": i, "safe": safe, "d1": d1, "d2": d2, "sepi": sepi, "turn": turn, "adt": adt,
            "tccur": tccur, "Tci": Tci}


def _subdivisions(tests, c, e):
    """Number of parts for each unsafe step (entries ``e`` of :func:`_step_tests` for roots ``c``):
    from how far the step failed each test (the tests scale as the step to the powers used)."""
    g = {name: np.array([tests[ci][name][ei] for ci, ei in zip(c, e)])
         for name in ("d1", "d2", "sepi", "turn", "adt", "tccur", "Tci")}
    d1, d2, sepi, turn, adt, tca, Tci = (g[k] for k in ("d1", "d2", "sepi", "turn", "adt", "tccur", "Tci"))
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.maximum.reduce([
            np.where(sepi > 0, (d1 / (SAFETY * sepi)) ** (1 / 4), 4.0),
            np.where(tca > 0, adt / (MOVE * tca), 4.0),
            np.where(Tci > 0, adt / (MOVE * Tci), 4.0),
            np.where(sepi > 0, (turn / (SAFETY * sepi)) ** (1 / 3), 4.0),
            np.where(d2 > 0, (d1 / (SAFETY * d2)) ** (1 / 4), 4.0)])
    return np.clip(np.ceil(1.5 * np.nan_to_num(r, nan=4.0, posinf=64.0)), 2, 64).astype(int)


def _gaps(R):
    """|R_i - R_j| for the roots of every row (K, n, n), infinite on the diagonal."""
    n = R.shape[1]
    G = np.abs(R[:, :, None] - R[:, None, :])
    G[:, np.arange(n), np.arange(n)] = np.inf
    return G


def _separations(R):
    if R.shape[1] == 1:
        return np.full(R.shape, np.inf)
    return _gaps(R).min(axis=2)


class Tracker:
    """Continue sheets along pieces and integrate differentials g dx / f_y along them."""

    def __init__(self, poly, sites, tol=1e-15, mp_fallback=None, exact=None):
        self.poly = poly
        self.exact = exact
        self.sites = np.asarray(sites, dtype=complex)
        self.tol = tol
        self.mp_fallback = mp_fallback
        self.n_refined_steps = 0
        self.n_mp_nodes = 0

    # -------------------------------------------------------------- node evaluation
    def _polish_nodes(self, x, R, A):
        """Compensated (double-double) Newton polish and f_y: roots accurate to ~eps |y| even where the
        sheets nearly coincide; the plain float64 bound enters at second order only.
        Returns (R, f_y, f_x, error bound of R)."""
        poly = self.poly
        Ahi, Alo = poly.coeff_polys_dd(x)
        R, fy = poly.polish_dd(Ahi, Alo, R)
        _, fx = poly.fy_fx(x, R, A)
        return R, fy, fx, EPS * np.abs(R) + 4 * poly.n * EPS * poly.root_error_bound(x, R, fy)

    def _eval_nodes(self, x, dx, precise=True, ddx=None):
        poly = self.poly
        R, A = poly.roots(x, any_order=True)
        if precise:
            R, fy, fx, err = self._polish_nodes(x, R, A)
        else:  # tracking-only points (refinement): plain float64 is enough to match sheets
            fy, fx = poly.fy_fx(x, R, A)
        with np.errstate(divide="ignore", invalid="ignore"):
            D = -fx / fy
        sep = _separations(R)
        if not precise:
            err = poly.root_error_bound(x, R, fy)
            weak = (err > 1e-8 * sep).any(axis=1)
            if np.any(weak):
                # compensated polish where plain float64 is not clearly enough (still cheap)
                w = np.nonzero(weak)[0]
                R[w], fy[w], fx[w], err[w] = self._polish_nodes(x[w], R[w], A[w])
                with np.errstate(divide="ignore", invalid="ignore"):
                    D[w] = -fx[w] / fy[w]
                sep[w] = _separations(R[w])
        self._last_rel = None
        # float64 roots whose rounding error is not negligible against the gaps between sheets
        # (nearly colliding branch points) are recomputed in mpmath
        bad = ~(err <= FLAG * sep) | ~np.isfinite(D).all(axis=1)[:, None]
        bad = bad.any(axis=1)
        if np.any(bad):
            if self.mp_fallback is None:
                raise ValueError(
                    "the curve is numerically singular near x = "
                    f"{complex(x[np.argmax(bad)]):.6g}: two sheets are closer than float64 can separate")
            idx = np.nonzero(bad)[0]
            R2, fy2, fx2 = self.mp_fallback(x[idx], R[idx])
            R[idx], fy[idx], fx[idx] = R2, fy2, fx2
            D[idx] = -fx2 / fy2
            sep[idx] = _separations(R2)
            err[idx] = 0.0
            self.n_mp_nodes += len(idx)
        Dt = D * dx[:, None]
        # second derivative in tau: y_xx x_tau^2 + y_x x_tautau, y_xx = -(f_xx + 2 f_xy y' + f_yy y'^2) / f_y
        fxx, fxy, fyy = poly.second_derivatives(x, R, A)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            Dxx = -(fxx + 2 * fxy * D + fyy * D * D) / fy
            D2 = Dxx * (dx * dx)[:, None] + (D * ddx[:, None] if ddx is not None else 0)
        D2 = np.where(np.isfinite(D2), D2, 0)
        # time (in tau) until the gap to the nearest other root closes at its current rate
        tc = _collision_times(R, Dt, sep)
        with np.errstate(divide="ignore", invalid="ignore"):
            self._last_rel = np.where(sep > 0, err / sep, np.inf).max(axis=1)
        self._last_D2 = D2
        return R, A, fy, Dt, sep, tc

    # -------------------------------------------------------------- matching
    @staticmethod
    def _match(yp, ydp, dt, roots, rootd, sep, tc, tcp, y2p=0.0, root2=0.0):
        """Index of the root continuing yp and whether the step is safe.

        Safe: each root moves by less than half its distance to the others (the linear model of the
        step is valid) and the tangents from both ends meet at the midpoint much closer than the
        roots are to each other (Hermite test).
        """
        h2 = 0.125 * dt * dt
        mp = yp + 0.5 * dt * ydp + h2 * y2p
        mc = roots - 0.5 * dt * rootd + h2 * root2
        d = np.abs(mc - mp)
        i = int(np.argmin(d))
        d1 = d[i]
        d2 = np.partition(d, 1)[1] if len(d) > 1 else np.inf
        r2 = root2[i] if np.ndim(root2) else root2
        safe = bool(d1 <= SAFETY * d2 and d1 <= SAFETY * sep[i]
                    and abs(dt) <= MOVE * tcp and abs(dt) <= MOVE * tc[i]
                    and abs(dt * dt * (r2 - y2p)) <= SAFETY * sep[i])
        return i, safe

    def _refine(self, pc, t0, y0, yd0, t1, roots1, rootd1, sep1, tc1, tc0, y20, root21, depth=0):
        """Subdivide the step t0 -> t1 until matching is safe; return the root index at t1.

        The step is cut into m equal parts at once (m from how far the safety tests failed), all new
        points are evaluated in one vectorized call, and any sub-step still unsafe recurses.
        """
        self.n_refined_steps += 1
        if depth > 40 or abs(t1 - t0) < 1e-15:
            x0 = complex(pc.x(t0))
            raise ValueError(f"cannot continue the sheets near x = {x0:.6g}: the curve is numerically singular there")
        dt = t1 - t0
        h2 = 0.125 * dt * dt
        d = np.abs(roots1 - 0.5 * dt * rootd1 + h2 * root21 - (y0 + 0.5 * dt * yd0 + h2 * y20))
        i = int(np.argmin(d))
        r = max((d[i] / (SAFETY * sep1[i])) ** (1 / 4) if sep1[i] > 0 else 4.0,
                abs(dt) / (MOVE * tc0) if tc0 > 0 else 4.0,
                abs(dt) / (MOVE * tc1[i]) if tc1[i] > 0 else 4.0,
                (abs(dt * dt * (root21[i] - y20)) / (SAFETY * sep1[i])) ** (1 / 3) if sep1[i] > 0 else 4.0)
        m = int(min(64, max(2, np.ceil(1.5 * r))))
        ts = t0 + (t1 - t0) * np.arange(1, m) / m
        Rm, _, _, Dm, sepm, tcm = self._eval_nodes(np.atleast_1d(pc.x(ts)), np.atleast_1d(pc.dx(ts)),
                                                   precise=False, ddx=np.atleast_1d(pc.ddx(ts)))
        D2m = self._last_D2
        seq = list(zip(Rm, Dm, sepm, tcm, D2m, ts)) + [(roots1, rootd1, sep1, tc1, root21, t1)]
        yc, ydc, tcc, y2c, tc_ = y0, yd0, tc0, y20, t0
        j = -1
        for Rq, Dq, sq, tq, D2q, tauq in seq:
            j, safe = self._match(yc, ydc, tauq - tc_, Rq, Dq, sq, tq, tcc, y2c, D2q)
            if not safe:
                j = self._refine(pc, tc_, yc, ydc, tauq, Rq, Dq, sq, tq, tcc, y2c, D2q, depth + 1)
            yc, ydc, tcc, y2c, tc_ = Rq[j], Dq[j], tq[j], D2q[j], tauq
        return j

    # -------------------------------------------------------------- main entry
    def track(self, pieces, precise: bool = True):
        """Continue every piece's starting values; returns a :class:`Tracked` (integrate later).

        Matching runs node to node, vectorized over all tracks; steps that fail the safety tests are
        subdivided for all pieces at once (one vectorized evaluation per round), and the matching is
        rerun until every step is safe (scalar recursive subdivision as a last resort).
        """
        nodes = Nodes(pieces, self.sites, self.tol)
        if not pieces:
            return Tracked(self, pieces, nodes, None, None, None, [], np.zeros(0, int), np.zeros((0, 0), int))
        R, A, fy, Dt, sep, tc = self._eval_nodes(nodes.x, nodes.dx, precise, ddx=nodes.ddx)
        rel = self._last_rel
        D2 = self._last_D2
        off = nodes.offsets
        N0 = len(nodes.tau)
        tp, ty = [], []
        for p, pc in enumerate(pieces):
            tp.extend([p] * len(pc.y0))
            ty.extend(pc.y0)
        tp = np.asarray(tp, dtype=int)
        T = len(tp)
        y0 = np.asarray(ty, dtype=complex)
        k0 = np.asarray(off[:-1])[tp]
        d = np.abs(R[k0] - y0[:, None])
        c0 = np.argmin(d, axis=1)
        dmin = d[np.arange(T), c0]
        scale = 1e-7 * (np.abs(y0) + np.where(np.isfinite(sep[k0, c0]), sep[k0, c0], 0) + 1e-300)
        if np.any(dmin > scale):
            bad = int(np.argmax(dmin > scale))
            raise ValueError(f"starting value y = {y0[bad]:.6g} is not a root of f at x = {nodes.x[k0[bad]]:.6g}")
        pool = {"tau": nodes.tau.copy(), "R": R, "Dt": Dt, "sep": sep, "tc": tc, "D2": D2}
        seqs = [np.arange(off[p], off[p + 1]) for p in range(len(pieces))]
        for _round in range(12):
            choice_seq, unsafe = self._match_pass(pieces, seqs, pool, tp, c0, scalar=False)
            if not unsafe:
                break
            new_tau, new_piece = [], []
            for p, k, m in unsafe:
                t0, t1 = pool["tau"][seqs[p][k - 1]], pool["tau"][seqs[p][k]]
                ts = t0 + (t1 - t0) * np.arange(1, m) / m
                new_tau.append(ts)
                new_piece.append(np.full(m - 1, p))
            new_tau = np.concatenate(new_tau)
            new_piece = np.concatenate(new_piece)
            xs = np.empty(len(new_tau), complex)
            dxs = np.empty(len(new_tau), complex)
            ddxs = np.empty(len(new_tau), complex)
            for p in np.unique(new_piece):
                sel = new_piece == p
                xs[sel] = pieces[p].x(new_tau[sel])
                dxs[sel] = pieces[p].dx(new_tau[sel])
                ddxs[sel] = pieces[p].ddx(new_tau[sel])
            Rn, _, _, Dn, sn, tn = self._eval_nodes(xs, dxs, precise=False, ddx=ddxs)
            D2n = self._last_D2
            self.n_refined_steps += len(unsafe)
            base = len(pool["tau"])
            pool["tau"] = np.concatenate([pool["tau"], new_tau])
            pool["R"] = np.concatenate([pool["R"], Rn])
            pool["Dt"] = np.concatenate([pool["Dt"], Dn])
            pool["sep"] = np.concatenate([pool["sep"], sn])
            pool["tc"] = np.concatenate([pool["tc"], tn])
            pool["D2"] = np.concatenate([pool["D2"], D2n])
            idx = base + np.arange(len(new_tau))
            for p in np.unique(new_piece):
                merged = np.concatenate([seqs[p], idx[new_piece == p]])
                seqs[p] = merged[np.argsort(pool["tau"][merged], kind="stable")]
        else:
            choice_seq, _ = self._match_pass(pieces, seqs, pool, tp, c0, scalar=True, pieces_obj=pieces)
        # choices at the quadrature nodes (the original pool entries, in order)
        lens = np.diff(off)
        choice = np.full((T, int(lens.max())), -1, dtype=int)
        for t in range(T):
            p = tp[t]
            sq = seqs[p]
            keep = sq < N0
            choice[t, :lens[p]] = choice_seq[t, :len(sq)][keep]
        ends = []
        pos = 0
        for p, pc in enumerate(pieces):
            m = len(pc.y0)
            last = choice[pos:pos + m, lens[p] - 1]
            if len(set(last.tolist())) != m:
                raise ValueError(f"sheet continuation is not injective along the path from x = {pc.a:.6g} "
                                 "(numerically singular curve)")
            ends.append(R[off[p] + lens[p] - 1, last])
            pos += m
        tr = Tracked(self, pieces, nodes, R, fy, A, ends, tp, choice)
        tr.rel = rel
        return tr

    def _match_pass(self, pieces, seqs, pool, tp, c0, scalar, pieces_obj=None):
        """Match along every sequence; returns (choices (T, Lmax), unsafe steps [(piece, k, m)]).

        With scalar=True unsafe steps are resolved by :meth:`_refine` instead of being reported.
        A step's tests depend on the matching only through the root the track holds at the previous
        node: they are done for every step and every such root at once (:func:`_step_tests`), and the
        walk along the tracks only picks the entries.
        """
        Rp, Dp, Sp, Tc, tau, D2p = pool["R"], pool["Dt"], pool["sep"], pool["tc"], pool["tau"], pool["D2"]
        T = len(tp)
        L = np.array([len(sq) for sq in seqs])
        Lmax = int(L.max())
        S = np.full((len(seqs), Lmax), -1, dtype=int)
        for p, sq in enumerate(seqs):
            S[p, :len(sq)] = sq
        n = Rp.shape[1]
        # tracks by decreasing length: the tracks still active at step k are a prefix
        perm = np.argsort(-L[tp], kind="stable")
        tq = tp[perm]
        Lq = L[tq]
        choice = np.full((T, Lmax), -1, dtype=int)
        choice[:, 0] = c0[perm]
        NODE = S[tq]
        tt, kk = np.nonzero(Lq[:, None] > np.arange(1, Lmax)[None, :])   # every step k = kk + 1
        pos = np.zeros((T, Lmax), dtype=int)
        pos[tt, kk + 1] = np.arange(len(tt))
        prev, node = NODE[tt, kk], NODE[tt, kk + 1]
        dt = tau[node] - tau[prev]
        h2 = 0.125 * dt * dt
        with np.errstate(all="ignore"):
            mc = Rp[node] - 0.5 * dt[:, None] * Dp[node] + h2[:, None] * D2p[node]
        tests = [_step_tests(c, prev, node, dt, h2, mc, pool) for c in range(n)]
        I = np.stack([t_["i"] for t_ in tests])
        SAFE = np.stack([t_["safe"] for t_ in tests])
        nact = np.searchsorted(-Lq, -np.arange(Lmax), side="left")   # tracks with length > k
        unsafe = {}
        # the step-by-step loop below only where the fast walk meets a step that fails a test
        fast = not scalar and walk_safe(choice, I, SAFE, pos, nact, tt, kk, tq, n)
        for k in range(1, 1 if fast else Lmax):
            na = int(nact[k])
            if na == 0:
                break
            c = choice[:na, k - 1]
            e = pos[:na, k]
            i = I[c, e]
            # two tracks of one piece may not pick the same root
            key = tq[:na] * (n + 1) + i
            safe = SAFE[c, e] & (np.bincount(key)[key] == 1)
            bad = np.nonzero(~safe)[0]
            if len(bad):
                bad = bad[np.argsort(perm[bad])]          # in the tracks' own order
                if scalar:
                    for q in bad:
                        pv, nd, cq = prev[e[q]], node[e[q]], c[q]
                        i[q] = self._refine(pieces_obj[tq[q]], tau[pv], Rp[pv, cq], Dp[pv, cq], tau[nd],
                                            Rp[nd], Dp[nd], Sp[nd], Tc[nd], Tc[pv, cq], D2p[pv, cq], D2p[nd])
                else:
                    for q, mq in zip(bad, _subdivisions(tests, c[bad], e[bad])):
                        key2 = (int(tq[q]), k)
                        unsafe[key2] = max(unsafe.get(key2, 2), int(mq))
            choice[:na, k] = i
        out = np.empty_like(choice)
        out[perm] = choice
        return out, [(p, k, m) for (p, k), m in unsafe.items()]


class Tracked:
    """Result of :meth:`Tracker.track`: node values on every track; integrate any numerators."""

    def __init__(self, tracker, pieces, nodes, R, fy, A, ends, tp, choice):
        self.tracker = tracker
        self.pieces = pieces
        self.nodes = nodes
        self.R, self.fy, self.A = R, fy, A
        self.ends = ends
        self.tp = tp
        self.choice = choice
        self.rel = None
        # the numerator-free double-double stage per set of critical intervals (keys: their (piece, node))
        self._dd_roots = {}

    def values(self, p):
        """(x nodes, y values (m, L)) of the tracks of piece p."""
        off = self.nodes.offsets
        L = off[p + 1] - off[p]
        pos = int(np.searchsorted(self.tp, p))
        m = len(self.pieces[p].y0)
        rows = off[p] + np.arange(L)
        ch = self.choice[pos:pos + m, :L]
        return self.nodes.x[rows], self.R[rows[None, :], ch]

    def critical_intervals(self, mass, dd_all: bool = False):
        """Intervals whose float64 sum is not accurate enough, as (piece, first node, (lo, hi, N)).

        Two error sources are estimated per interval, relative to its absolute mass (sum of
        |weight * integrand|): the rounding of the node positions (relative jitter eps |x| / length,
        large for intervals shorter than ~1e-3 |x| next to close critical values) and the remaining
        error of the (compensated) roots relative to the gap between sheets (at least the rounding of
        y to float64, eps |y| / gap).  An interval is re-summed in double-double when the first exceeds 1e-14,
        or the second 1e-13, of the largest piece mass.  With ``dd_all``, every interval of non-zero length.
        """
        offs, out = self.nodes.offsets, []
        thr = 1e-14 * max((float(mass[offs[p]:offs[p + 1]].sum()) for p in range(len(self.pieces))), default=0.0)
        for p, pc in enumerate(self.pieces):
            if not self.nodes.plans[p]:
                continue
            # the piece's ends and node rounding, all intervals at once (elementwise: the same values)
            lo, hi, N = (np.array(v) for v in zip(*self.nodes.plans[p]))
            xl, xh, mid = pc.x(lo), pc.x(hi), 0.5 * (lo + hi)
            ell = np.abs(xh - xl)
            jit = EPS * (np.abs(pc.dx(mid)) * np.abs(mid) + np.maximum(np.abs(xl), np.abs(xh)))
            ks = offs[p] + 1 + np.cumsum(N) - N
            rel = np.maximum.reduceat(self.rel[:ks[-1] + N[-1]], ks) if self.rel is not None else np.zeros(len(N))
            for c, k in enumerate(ks.tolist()):
                m_int = float(mass[k:k + N[c]].sum())
                if ell[c] > 0 and (dd_all or jit[c] / ell[c] * m_int > thr or rel[c] * m_int > 10 * thr):
                    out.append((p, k, self.nodes.plans[p][c]))
        return out

    def integrate(self, numerators, exact=None, dd_all: bool = False):
        """Integrals of p(x, y) dx / f_y along every track.

        numerators: complex array (ndiff, I, J), p = sum P[i, j] x^i y^j.
        exact: the same numerators as exact dicts {(i, j): (Fraction, Fraction)} (default: the
        ``exact`` attribute of ``numerators``); when available, intervals whose float64 sum is not
        accurate enough (:meth:`critical_intervals`) are re-summed in double-double at exact node
        positions (:meth:`_add_dd`); ``dd_all`` re-sums every interval (periods: float64 sums of many
        intervals leave a few ulps).
        Returns a list over pieces of arrays (len(y0), ndiff).
        """
        if not self.pieces:
            return []
        if exact is None:
            exact = getattr(numerators, "exact", None)
        P = np.asarray(numerators, dtype=complex).view(np.ndarray)
        if P.shape[0] == 0:
            return [np.zeros((len(pc.y0), 0), complex) for pc in self.pieces]
        nodes = self.nodes
        R = self.R
        Xp = nodes.x[:, None] ** np.arange(P.shape[1])[None, :]
        Yp = R[:, :, None] ** np.arange(P.shape[2])[None, None, :]
        G = np.einsum("ki,ksj,dij->ksd", Xp, Yp, P)
        with np.errstate(divide="ignore", invalid="ignore"):
            W = G / self.fy[:, :, None] * (nodes.dx * nodes.w)[:, None, None]
        W = np.where(nodes.w[:, None, None] == 0, 0, W)
        crit = []
        if exact is not None and self.tracker.exact is not None:
            mass = np.abs(W).max(axis=(1, 2))
            crit = self.critical_intervals(mass, dd_all)
            for _, k, (_, _, N) in crit:
                W[k:k + N] = 0.0
        lens = np.diff(nodes.offsets)
        start = nodes.offsets[:-1]
        out = []
        pos = 0
        for p, pc in enumerate(self.pieces):
            m = len(pc.y0)
            L = lens[p]
            rows = start[p] + np.arange(L)
            ch = self.choice[pos:pos + m, :L]
            out.append(W[rows[None, :], ch].sum(axis=1))
            pos += m
        if crit:
            out = self._add_dd(out, exact, crit)
        return out

    def _add_dd(self, out, exact, crit):
        """Add the double-double sums of the critical intervals (:mod:`thetasol.curves._dd`)."""
        from thetasol.curves._dd import curve_to_cdd, interval_roots_dd, interval_sums_dd, numerators_to_cdd
        circ = [c for c in crit if self.pieces[c[0]].kind not in ("line", "point", "inf")]
        if circ:  # no double-double parametrization (never planned for quadrature so far)
            out = self._add_mp(out, exact, circ)
            crit = [c for c in crit if c not in circ]
        if not crit:
            return out
        key = tuple((p, k) for p, k, _ in crit)
        if key not in self._dd_roots:
            self._dd_roots[key] = interval_roots_dd(self.pieces, crit, self.interval_seeds(crit),
                                                    curve_to_cdd(self.tracker.poly))
        parts = interval_sums_dd(self._dd_roots[key], crit, numerators_to_cdd(exact))
        for (p, _, _), part in zip(crit, parts):
            out[p] = out[p] + part
        return out

    def interval_seeds(self, crit) -> list:
        """Float roots at the nodes of each critical interval, one row per track: (m, N) arrays."""
        tstart = np.concatenate([[0], np.cumsum([len(pc.y0) for pc in self.pieces])])
        seeds = []
        for p, k, (_, _, N) in crit:
            m = len(self.pieces[p].y0)
            rows = np.arange(k, k + N)
            ch = self.choice[tstart[p]:tstart[p] + m, rows - self.nodes.offsets[p]]
            seeds.append(self.R[rows[None, :], ch])
        return seeds

    def _add_mp(self, out, exact, crit):
        """mpmath (20 digits) version of :meth:`_add_dd`: the reference of tests and benchmarks."""
        import mpmath

        from thetasol.curves._mp import interval_mp, numerators_mp
        ev = self.tracker.exact
        dps = 20
        with mpmath.workdps(dps + 10):
            nums = numerators_mp(exact, dps + 10)
            for (p, _, (lo, hi, N)), seeds in zip(crit, self.interval_seeds(crit)):
                part = interval_mp(self.pieces[p], lo, hi, N, seeds, ev, nums, dps)
                out[p] = out[p] + np.array([[complex(v) for v in row] for row in part])
        return out


def shaped_integrals(raw: np.ndarray, weights: np.ndarray | None, shape: str) -> np.ndarray:
    """Rows of integrals (N, nd) in the form the input had (see PlaneCurve._parse_targets)."""
    if shape == "single":
        return raw[0]
    if shape == "divisor":
        return weights @ raw
    return raw
