"""The genus-2 model of Neumann's problem (distinct eigenvalues): sphero-conical coordinates on the
curve ``y^2 = -4 A(z) B(z)``, each a separated :class:`Oscillator`, on the torus of
:class:`NeumannTorus`.  Private to :mod:`thetasol.solutions.points.neumann` (which exports both);
docs/neumann.md has the derivation and the checks.
"""
from __future__ import annotations

import numpy as np

from thetasol.core.panels import PeriodicIntegral
from thetasol.core.periodic import (
    HermiteTable,
    TaylorTable,
    eval_series,
    fit_series,
    grid_values,
    integrated,
)
from thetasol.core.roots import monotone_newton, quadratic_roots
from thetasol.protocol import ClosedFormUnavailable

__all__ = ["MIN_WIDTH", "DegenerateTorus", "Oscillator", "NeumannTorus"]

_EPS = np.finfo(float).eps
#: Thinnest interval of a sphero-conical coordinate (relative to k3 - k1) that is accepted.
MIN_WIDTH = 1e-14


class DegenerateTorus(ArithmeticError):
    """The torus is too thin for the separated coordinates (the message says why); turned into
    :class:`ClosedFormUnavailable` naming the caller's numerical reference by
    :func:`series_or_unavailable`."""



# -- one separated coordinate ----------------------------------------------------------------------

class Oscillator:
    """``u = lo + w sin^2(theta/2)`` on ``[lo, hi]`` with ``dtheta/dtau = sqrt(C prod_r |u - r|)``.

    ``below``/``above``: gaps ``lo - r`` / ``r - hi`` to the other real roots (given accurately by the
    caller); ``complex_roots``: the others.  ``alpha`` (the angle linear in tau, ``alpha = tau / fbar``
    + const) is the running integral of ``1 / rate`` on panels graded toward the complex theta where
    ``u`` meets another root (:class:`thetasol.core.panels.PeriodicIntegral`: a root at ``g`` from an
    end puts them ~``2 sqrt(g / w)`` from the real axis, where a Fourier series in theta would need
    ~``18 sqrt(w / g)`` terms); its inverse ``theta = alpha + B(alpha)`` is a Fourier series (analytic in
    a strip of width ~``1 / log(w / g)``: tens to hundreds of terms).
    """

    def __init__(self, lo, hi, C, below=(), above=(), complex_roots=(), name="u", w=None):
        self.lo, self.hi, self.w = float(lo), float(hi), float(hi - lo if w is None else w)
        self.C = float(C)
        self.below = np.asarray(below, float)
        self.above = np.asarray(above, float)
        self.cplx = np.asarray(complex_roots, complex)
        self.F = PeriodicIntegral(lambda th: 1.0 / self.rate(th), self.singularities())
        self.fbar = self.F.total / (2 * np.pi)
        # theta is known to eps * 2 pi at best: that is the noise floor of its series
        self.B = fit_series(lambda al: self.F.inverse(al * self.fbar) - al, f"the inverse angle of {name}",
                            floor=2 * np.pi * _EPS)

    def singularities(self) -> np.ndarray:
        """The complex theta (one per root and sign) where u(theta) meets another root: a root of the
        rate.  Below lo: sin^2(theta/2) = -g/w; above hi: cos^2(theta/2) = -g/w; complex r: (r - lo)/w."""
        sb = 2j * np.arcsinh(np.sqrt(self.below / self.w))
        sa = np.pi + 2j * np.arcsinh(np.sqrt(self.above / self.w))
        sc = 2.0 * np.arcsin(np.sqrt((self.cplx - self.lo) / self.w + 0j))
        s = np.concatenate([sb, sa, sc])
        return np.concatenate([s, -s, s.conj(), -s.conj()])

    def parts(self, th: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(u - lo, hi - u, sin(th/2), cos(th/2))``, each accurate near its zero."""
        s, c = np.sin(0.5 * th), np.cos(0.5 * th)
        return self.w * s * s, self.w * c * c, s, c

    def u(self, th: np.ndarray) -> np.ndarray:
        dlo, dhi, _, _ = self.parts(th)
        return np.where(dlo <= dhi, self.lo + dlo, self.hi - dhi)

    def dists(self, th: np.ndarray) -> np.ndarray:
        """|u - r| for every other root, shape th.shape + (n_roots,)."""
        dlo, dhi, _, _ = self.parts(th)
        out = [d + dlo for d in self.below] + [d + dhi for d in self.above]
        if self.cplx.size:
            u = self.u(th)
            out += [np.abs(u - r) for r in self.cplx]
        return np.stack(out, -1)

    def rate(self, th: np.ndarray) -> np.ndarray:
        return np.sqrt(self.C * np.prod(self.dists(th), -1))

    def theta(self, al: np.ndarray) -> np.ndarray:
        return al + eval_series(self.B, al)

    def theta_grid(self, n: int) -> np.ndarray:
        """theta at alpha = 2 pi j / n, j < n (the grid of :func:`thetasol.core.periodic.fit_series`)."""
        return 2 * np.pi * np.arange(n) / n + grid_values(self.B, n)

    def alpha(self, th: np.ndarray) -> np.ndarray:
        return self.F(th) / self.fbar


# -- the genus-2 torus (distinct eigenvalues) ------------------------------------------------------

_JL = [(1, 2), (0, 2), (0, 1)]                      # the other two indices of each eigenvalue


def _anchored(d, x2, L2, a2, z):
    """The roots z of ``N(z) + sum_m L2_m (z - d_m)`` (``N = sum_i x2_i prod_{j != i} (z - d_j)``) as
    ``(i, offset)``, ``z = d_i + offset`` for the nearest d_i: the offset is a root of the polynomial
    shifted to d_i, whose coefficients ``N(d_i) + ...`` and ``N'(d_i) + ...`` are sums of products of
    the data with differences of the d (no cancellation against d_i: near an equilibrium the gaps are
    ~x_i^2, known to their relative rounding, not to eps (k3 - k1))."""
    out = []
    for zz in z:
        i = int(np.argmin(np.abs(zz - d)))
        j, l = _JL[i]
        dj, dl = d[i] - d[j], d[i] - d[l]
        p0 = x2[i] * dj * dl + L2[j] * dj + L2[l] * dl
        p1 = x2[i] * (dj + dl) + x2[j] * dl + x2[l] * dj + L2.sum()
        zeta = quadratic_roots(a2, p1, p0)
        out.append((i, float(zeta[np.argmin(np.abs(zeta - (zz - d[i])))])))
    return out


class NeumannTorus:
    """Neumann's problem ``xddot = -k x + (x.kx - |xdot|^2) x`` on the unit sphere (k ascending,
    distinct) from ``(x0, y0)``: the separated solution ``x(t)``, ``xdot(t)``.

    Public state read by the rotation: ``osc`` (the two :class:`Oscillator`), ``role[i][kk]`` (how
    ``k_i`` sits in the interval of ``u_kk``: ``'lo'``/``'hi'`` endpoint or ``'below'``/``'above'`` with
    its gap), ``norm``, ``th0``, ``alpha0``, ``fbar``, ``drift``, :meth:`state`, :meth:`s_of_t`.
    """

    method, case = "fourier/genus-2", ""

    def __init__(self, k: np.ndarray, x0: np.ndarray, y0: np.ndarray):
        self._separation(k, x0, y0)
        self._oscillators()
        self._roles()
        self._initial_angles(x0, y0)
        self._signs(x0, y0)
        self._time_series()

    # -- set-up stages -----------------------------------------------------------------------------
    def _separation(self, k, x0, y0):
        """The sphero-conical coordinates (u1, u2) and the roots of A B, shifted to k2, each also as
        ``(i, offset)`` from its nearest k_i (:func:`_anchored`): their differences are accurate."""
        d = k - k[1]
        x2 = x0 * x0
        a2 = x2.sum()
        a1 = -sum(x2[i] * (d[j] + d[l]) for i, (j, l) in enumerate(_JL))
        a0 = sum(x2[i] * d[j] * d[l] for i, (j, l) in enumerate(_JL))
        zu = quadratic_roots(a2, a1, a0)              # u1 <= k2 <= u2 (shifted)
        L2 = np.cross(x0, y0) ** 2
        zb = quadratic_roots(a2, a1 + L2.sum(), a0 - (L2 * d).sum())
        self.d = d
        self.zu = _anchored(d, x2, np.zeros(3), a2, zu)
        zb_a = _anchored(d, x2, L2, a2, zb)
        roots = sorted([(d[i], "k", i, (i, 0.0)) for i in range(3)]
                       + [(d[p[0]] + p[1], "b", j, p) for j, p in enumerate(zb_a)], key=lambda r: r[0])
        vals = np.array([r[0] for r in roots])
        scale = max(abs(d[0]), abs(d[2]))
        tol = 1e-9 * scale
        if not (vals[1] - tol <= zu[0] <= vals[2] + tol and vals[3] - tol <= zu[1] <= vals[4] + tol):
            raise ClosedFormUnavailable(f"Neumann solution: the sphero-conical coordinates {zu} are not in "
                                        f"their oscillation intervals {vals} (internal inconsistency)")
        self.zb, self.roots, self.vals, self.scale = zb, roots, vals, scale
        self.anc = [r[3] for r in roots]
        self.ivals = [(1, 2), (3, 4)]
        self.gap12 = self._gap(self.anc[3], self.anc[2])

    def _gap(self, p, q):
        """p - q for anchored values ``(i, offset)`` (value ``d_i + offset``)."""
        return (self.d[p[0]] - self.d[q[0]]) + (p[1] - q[1])

    def _oscillators(self):
        """One :class:`Oscillator` per coordinate; thin intervals bounded by a root of B are refused."""
        vals, roots, scale, anc = self.vals, self.roots, self.scale, self.anc
        self.osc = []
        for kk, (i_lo, i_hi) in enumerate(self.ivals):
            w = self._gap(anc[i_hi], anc[i_lo])
            below = [self._gap(anc[i_lo], anc[m]) for m in range(i_lo)]
            above = [self._gap(anc[m], anc[i_hi]) for m in range(i_hi + 1, 5)]
            if min(below + above, default=1.0) <= 0.0:
                # two roots of A B equal within rounding: the motion is on a separatrix (asymptotic to
                # an equilibrium), the period infinite
                raise DegenerateTorus("Neumann solution: the torus is on a separatrix within rounding "
                                      f"(two branch points {min(below + above) / scale:.1e} apart, relative)")
            if w <= MIN_WIDTH * scale and "b" in (roots[i_lo][1], roots[i_hi][1]):
                # the widths are accurate (roots anchored at the k_i), but a thin torus next to a
                # separatrix (released at rest near a saddle) loses far more than the data's conditioning
                raise DegenerateTorus(
                    f"Neumann solution: nearly degenerate torus (a sphero-conical coordinate stays within "
                    f"{max(w, 0.0) / scale:.1e} of the span of k: the point within ~{np.sqrt(max(w, 0.0) / scale):.0e} "
                    "rad of an invariant great circle); the separated coordinates lose accuracy there")
            self.osc.append(Oscillator(vals[i_lo], vals[i_hi], 4.0,
                                       below=below, above=above,
                                       name=f"u{kk + 1}", w=w))

    def _roles(self):
        """The role of each k_i in each interval: 'lo', 'hi' endpoint or a gap to the nearer endpoint."""
        d, vals, roots, anc = self.d, self.vals, self.roots, self.anc
        self.role = []
        for i in range(3):
            row = []
            for i_lo, i_hi in self.ivals:
                if roots[i_lo][1:3] == ("k", i):
                    row.append(("lo", 0.0))
                elif roots[i_hi][1:3] == ("k", i):
                    row.append(("hi", 0.0))
                elif d[i] < vals[i_lo]:
                    row.append(("below", self._gap(anc[i_lo], (i, 0.0))))
                else:
                    row.append(("above", self._gap((i, 0.0), anc[i_hi])))
            self.role.append(row)
        self.norm = np.array([np.sqrt(abs((d[i] - d[j]) * (d[i] - d[l]))) for i, (j, l) in enumerate(_JL)])

    def _initial_angles(self, x0, y0):
        """theta_k at t = 0: cos from the position, sin from the velocity (both absolutely accurate):
        du/ds = (u2 - u1) du/dt = (w/2) sin(theta) dtheta/ds = w sin(theta) sqrt(prod_others |u - r|),
        du/dt from N_t(u) + N'(u) du/dt = 0, N'(u_k) = a2 (u_k - u_other)."""
        gap0 = self._gap(self.zu[1], self.zu[0])
        a2 = (x0 * x0).sum()
        th0 = []
        for kk, o in enumerate(self.osc):
            z = self.zu[kk]
            i_lo, i_hi = self.ivals[kk]
            udot = -sum(2.0 * x0[i] * y0[i] * self._gap(z, (j, 0.0)) * self._gap(z, (l, 0.0))
                        for i, (j, l) in enumerate(_JL)) / (a2 * (gap0 if kk else -gap0))
            cos_th = (self._gap(self.anc[i_hi], z) - self._gap(z, self.anc[i_lo])) / o.w
            dist = [abs(self._gap(z, self.anc[m])) for m in range(5) if m not in self.ivals[kk]]
            sin_th = gap0 * udot / (o.w * np.sqrt(np.prod(dist)))
            th0.append(np.arctan2(sin_th, cos_th))
        self.th0 = np.array(th0)

    def _signs(self, x0, y0):
        """The constant signs sigma_i of x_i fitted at t = 0, and how well the data are reproduced."""
        self.sigma = np.ones(3)
        xm, dxm, gm = self.state(self.th0[0], self.th0[1])
        tau2 = 1.0 / self.scale
        self.sigma = np.where(x0 * xm + tau2 * y0 * dxm / gm >= 0, 1.0, -1.0)
        xm, dxm, gm = self.state(self.th0[0], self.th0[1])
        self.fit_residual = float(max(np.abs(xm - x0).max(), np.sqrt(tau2) * np.abs(dxm / gm - y0).max()))

    def _time_series(self):
        """The time along the torus, t(s) = <u2 - u1> s + bounded: Taylor tables of the bounded parts
        and of theta(alpha) (to the rounding of their series), and cheaper Hermite tables of the
        bounded parts (to 1e-12 of the time scale 1/drift) for the first Newton steps."""
        self.alpha0 = np.array([o.alpha(th) for o, th in zip(self.osc, self.th0, strict=True)])
        self.cu = [fit_series(lambda al, o=o: o.u(o.theta_grid(al.size)), f"u{kk + 1}(alpha)",
                              floor=4 * _EPS * self.scale)
                   for kk, o in enumerate(self.osc)]
        self.P = [integrated(c) for c in self.cu]
        self.fbar = np.array([o.fbar for o in self.osc])
        self.drift = self.cu[1][0].real - self.cu[0][0].real
        self.Pspan = sum(2 * f * np.abs(P).sum() for f, P in zip(self.fbar, self.P, strict=True)) * 2
        self.taylor = [(TaylorTable(P), TaylorTable(o.B)) for o, P in zip(self.osc, self.P, strict=True)]
        self.P0 = np.array([tab[0](self.alpha0[kk:kk + 1])[0][0] for kk, tab in enumerate(self.taylor)])
        self.tables = [HermiteTable(f * P, 1e-12 / self.drift) for f, P in zip(self.fbar, self.P, strict=True)]
        self.table0 = [tab(a)[0] for tab, a in zip(self.tables, self.alpha0, strict=True)]

    # -- the state on the torus --------------------------------------------------------------------
    def _rho(self, i, kk, th):
        """Signed smooth sqrt|k_i - u_kk| and its theta-derivative."""
        o = self.osc[kk]
        kind, g = self.role[i][kk]
        s, c = np.sin(0.5 * th), np.cos(0.5 * th)
        rw = np.sqrt(o.w)
        if kind == "lo":
            return rw * s, 0.5 * rw * c
        if kind == "hi":
            return rw * c, -0.5 * rw * s
        if kind == "below":
            r = np.sqrt(g + o.w * s * s)
            return r, o.w * s * c / (2.0 * r)
        r = np.sqrt(g + o.w * c * c)
        return r, -o.w * s * c / (2.0 * r)

    def state(self, th1: np.ndarray, th2: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """x, dx/ds and u2 - u1 at the angles (th1, th2) (broadcast: a grid costs two 1-d passes)."""
        th1, th2 = np.asarray(th1, float), np.asarray(th2, float)
        r1 = self.osc[0].rate(th1)
        r2 = self.osc[1].rate(th2)
        xs, dxs = [], []
        for i in range(3):
            p1, q1 = self._rho(i, 0, th1)
            p2, q2 = self._rho(i, 1, th2)
            xs.append(self.sigma[i] / self.norm[i] * p1 * p2)
            dxs.append(self.sigma[i] / self.norm[i] * ((q1 * r1) * p2 + p1 * (q2 * r2)))
        o1, o2 = self.osc
        # u2 - u1 from the gap between the intervals (no cancellation)
        gap = (self.gap12 + o1.parts(th1)[1]) + o2.parts(th2)[0]
        return np.stack(np.broadcast_arrays(*xs), -1), np.stack(np.broadcast_arrays(*dxs), -1), gap

    def motion(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(x, xdot) at the times t (1-d)."""
        _, _, th = self.s_of_t(t)
        x, dx, gap = self.state(th[0], th[1])
        return x, dx / gap[:, None]

    # -- time -> s ---------------------------------------------------------------------------------
    def _alpha(self, s):
        """The two angles alpha_k(s), linear in s: shape (2, s.size)."""
        return self.alpha0[:, None] + s[None, :] / self.fbar[:, None]

    def time_of_s(self, s: np.ndarray, angles: bool = False) -> tuple[np.ndarray, ...]:
        """t(s) and dt/ds = u2 - u1 at s (the series of t and theta from their Taylor tables, to
        rounding); with ``angles`` also theta_k(alpha_k(s)) and dtheta_k/dalpha_k."""
        al = self._alpha(s)
        t = self.drift * s
        u, th, dth = [], [], []
        for kk, (o, (tab_P, tab_B)) in enumerate(zip(self.osc, self.taylor, strict=True)):
            t = t + (1 if kk else -1) * self.fbar[kk] * (tab_P(al[kk])[0] - self.P0[kk])
            b, db = tab_B(al[kk])
            th.append(al[kk] + b)
            u.append(o.u(th[-1]))
            dth.append(1.0 + db)
        if angles:
            return t, u[1] - u[0], np.array(th), np.array(dth)
        return t, u[1] - u[0]

    def _time_model(self, s):
        """t(s) and dt/ds from the Hermite tables of the bounded parts."""
        t, dt = self.drift * s, self.drift
        for kk, (tab, f, a0) in enumerate(zip(self.tables, self.fbar, self.alpha0, strict=True)):
            g, dg = tab(a0 + s / f)
            sgn = 1 if kk else -1
            t, dt = t + sgn * (g - self.table0[kk]), dt + sgn * dg / f
        return t, dt

    def s_of_t(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """s with t(s) = t (t(s) is increasing) and alpha(s), theta(s): safeguarded Newton on the
        tables of t(s), then one Newton step on the series; if a step is above 1e-9 / drift and the
        rounding of s (64 eps |s|), a table was poor (it stopped at its node limit) and the
        safeguarded Newton goes on on the series."""
        lo, hi = (t - self.Pspan) / self.drift, (t + self.Pspan) / self.drift
        unit = 1.0 / self.drift

        def close(tol):
            return lambda new, s: np.abs(new - s) <= np.maximum(tol * unit, 64 * _EPS * np.abs(s))

        s0 = monotone_newton(self._time_model, t, t / self.drift, lo, hi, close(1e-10), 200, 0)
        # the tables are good to 1e-12 unit: one series step lands at rounding (the step after it
        # would be ~1e-24 unit), and theta follows to first order (the second is ~1e-24 too)
        t0, dt0, th0, dth0 = self.time_of_s(s0, angles=True)
        step = (t - t0) / dt0
        s = s0 + step
        if np.all(close(1e-9)(s, s0)):
            return s, self._alpha(s), th0 + dth0 * (step / self.fbar[:, None])
        s = monotone_newton(self.time_of_s, t, s0, lo, hi, close(1e-9), 200, 1)     # a poor table
        al = self._alpha(s)
        return s, al, np.array([o.theta(a) for o, a in zip(self.osc, al, strict=True)])

    def info(self) -> dict:
        """Periods and sizes of the series (for diagnostics)."""
        return {"genus": 2, "torus_dimension": 2, "frequencies_s": 1.0 / self.fbar,
                "time_drift": float(self.drift), "series_terms": [int(o.B.size) for o in self.osc],
                "quadrature_panels": [int(o.F.edges.size - 1) for o in self.osc]}


