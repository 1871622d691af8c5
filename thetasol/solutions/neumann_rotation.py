"""A symmetric body with no spin about its symmetry axis in a quadratic potential: Neumann's problem.

Why a separate model
--------------------
For ``J = diag(j, j, j3)`` (principal frame) the torque has no component along the symmetry axis,
so ``omega_3`` is an integral.  With ``omega_3 = 0`` the spectral curve (4.12) has a tacnode over
``E = infinity`` and the theta-function construction of :mod:`thetasol.solutions.theta_rotation` does not
apply.  The mechanics is solved directly instead (docs/neumann.md has the derivation and checks):

* ``gamma = Q e3`` (the symmetry axis in space) obeys C. Neumann's problem: a particle of mass
  ``I1 = j + j3`` on the unit sphere in the potential ``1/2 (j3 - j) gamma^T a gamma``
  (``V = 1/2 tr(Q^T a Q J) = j/2 tr a + 1/2 (j3 - j) gamma^T a gamma``, ``T = 1/2 I1 |gammadot|^2``).
  With ``K = (j3 - j) a / I1 = V diag(k) V^T`` and ``x = V^T gamma`` it separates in the sphero-
  conical coordinates ``u1 < u2`` (``sum x_i^2 / (z - k_i) = (z - u1)(z - u2) / A(z)``,
  ``A = prod (z - k_i)``): with the time ``ds = dt / (u2 - u1)`` each coordinate moves on its own,
  ``(du_k / ds)^2 = -4 A(u_k) B(u_k)``, ``B(z) = N(z) + sum_m L_m^2 (z - k_m)`` with
  ``N(z) = sum_i x_i^2 prod_{j != i} (z - k_j)`` and ``L = x cross xdot`` (the Uhlenbeck integrals
  summed without their small divisors ``k_i - k_j``).  This is the genus-2 curve
  ``y^2 = -4 A(z) B(z)``; the real torus is the product of the two ovals.
* Each ``u_k`` oscillates between two neighbouring roots ``lo, hi`` of ``A B``; with
  ``u = lo + (hi - lo) sin^2(theta / 2)`` the rate ``dtheta / ds = 2 sqrt(prod_others |u - r|)`` is
  analytic and positive, so ``s(theta)`` is ``theta`` times a mean plus a Fourier series (FFT to
  float64, trailing coefficients below 2e-16 relative or the sample noise).  Its inverse, the time
  ``t(s) = int (u2 - u1) ds`` and
  ``x_i = prod_k sqrt(k_i - u_k) / sqrt(prod_{j != i} (k_i - k_j))`` (signed square roots that are
  smooth in theta) follow.  A time ``t`` is mapped to ``s`` by a safeguarded Newton solve of the
  monotone ``t(s) = <u2 - u1> s + bounded`` on cubic Hermite tables of the two bounded parts, then
  one Newton step on the series: a far time costs what ``t = 1`` costs.
* The rest of the attitude: with ``omega_3 = 0`` the space angular velocity is
  ``gamma x gammadot`` and the body axis ``e1 = Q P e_1`` is parallel-transported along gamma.
  Its angle phi from the frame ``f1 = c x gamma / |c x gamma|``, ``f2 = gamma x f1`` (``c`` the
  eigen-axis of ``a`` the trajectory keeps farthest from) obeys
  ``phidot = -(gamma.c)(c.(gamma x gammadot)) / (1 - (gamma.c)^2)``: a function on the real torus,
  sampled on a grid, transformed by FFT and integrated term by term along the linear flow
  (``phi = phi0 + <G> s + sum G_m e^{i m beta0} (e^{i m nu s} - 1) / (i m nu)``, the near-resonant
  terms in the form ``s sinc`` that keeps ``min(s, 1/|m nu|)`` as their amplification).  Only the
  real part is used, so the mode ``-m`` is folded onto ``m`` and the sum is a few matrix products
  of the coefficients with powers ``e^{i j alpha}`` (computed by doubling).

Hand-written because no library has Neumann's problem; the theta-function solution (Moser,
Mumford's Tata lectures II) would need the same quadrature for the angle and its genus-2 curve
degenerates in the same places, so the separated form is used for both.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from thetasol.mechanics.equations import invariants as _invariants
from thetasol.special.pendulum import pendulum_angle as _pendulum_angle, pendulum_params as _pendulum_params
from thetasol.solutions.base import ClosedFormUnavailable, RotationSolution
from thetasol.solutions._symmetry import SNAP_TOL, sorted_principal_frame as _principal_frame, symmetry_axis as _symmetry_axis

__all__ = ["NeumannRotation"]

_EPS = np.finfo(float).eps
#: Fourier series are refined until their trailing coefficients fall below this (relative).
COEF_TOL = 2e-16
N_MAX_1D = 2 ** 12
N_MAX_2D = 1024
#: Thinnest interval of a sphero-conical coordinate (relative to k3 - k1) that is accepted.
MIN_WIDTH = 1e-8


# -- Fourier series on the circle ----------------------------------------------------------------

def _refined_fft(transform, what: str, n0: int, nmax: int, terms=str):
    """Double the grid ``n`` from ``n0`` until the outer band of the spectrum is below ``COEF_TOL``
    times the largest coefficient or the absolute noise of the samples.  ``transform(n)`` returns
    (coefficients, mask of the outer band, noise floor); the answer is (n, c, mask of the kept)."""
    n = n0
    while True:
        c, band, floor = transform(n)
        scale = max(np.abs(c).max(), np.finfo(float).tiny)
        tail = np.abs(c[band]).max()
        if tail <= max(COEF_TOL * scale, floor):
            return n, c, np.abs(c) > 0.25 * max(COEF_TOL * scale, floor)
        if n >= nmax:
            raise ClosedFormUnavailable(
                f"Neumann solution: the Fourier series of {what} has not converged with {terms(n)} terms "
                f"(tail {tail / scale:.1e} relative): the torus is too close to a separatrix or the "
                "trajectory too close to the reference axis; use thetasol.integrate_rotation")
        n *= 2


def _fit_series(fun, what: str, floor: float = 0.0):
    """Coefficients ``c_n`` (n = 0..N/2) with ``fun(x) = Re(c_0 + 2 sum c_n e^{inx})``, N doubled
    until the upper quarter of the spectrum is below ``COEF_TOL`` times the largest coefficient or
    below ``floor`` (the absolute noise of the samples)."""
    def transform(n):
        c = np.fft.rfft(fun(2 * np.pi * np.arange(n) / n)) / n
        return c, slice((3 * n) // 8, None), floor

    _, c, keep = _refined_fft(transform, what, 64, N_MAX_1D)
    keep = np.flatnonzero(keep)
    return c[:keep.max() + 1 if keep.size else 1].copy()


def _sum_series(E: np.ndarray, c: np.ndarray):
    """``Re(c_0 + 2 sum c_n e^{inx})`` from the powers ``E = _powers(x, >= c.size - 1)``."""
    return c[0].real + 2.0 * np.tensordot(c[1:], E[:c.size - 1], 1).real


def _sum_series_derivative(E: np.ndarray, c: np.ndarray):
    """The x-derivative of :func:`_sum_series`, from the same powers."""
    return 2.0 * np.tensordot(1j * np.arange(1, c.size) * c[1:], E[:c.size - 1], 1).real


def _eval_series(c: np.ndarray, x: np.ndarray, derivative: bool = False):
    """``Re(c_0 + 2 sum c_n e^{inx})`` (and its derivative) at real ``x`` (any shape)."""
    E = _powers(x, c.size - 1)
    val = _sum_series(E, c)
    if not derivative:
        return val
    return val, _sum_series_derivative(E, c)


def _powers(x: np.ndarray, n: int) -> np.ndarray:
    """``e^{i k x}`` for k = 1..n, shape (n,) + x.shape (the times last: every product below is one
    vectorized pass).  By doubling, ``e^{i(m + j)x} = e^{imx} e^{ijx}`` with ``e^{imx}`` (m a power of
    two) from cos/sin of the exact ``m x``: the k-th power carries at most log2(k) roundings."""
    x = np.remainder(np.asarray(x, float), 2 * np.pi)
    E = np.empty((max(n, 1),) + x.shape, complex)
    E[0] = np.cos(x) + 1j * np.sin(x)
    m = 1
    while m < n:
        k = min(m, n - m)
        mx = m * x                                     # exact: m is a power of two
        E[m:m + k] = E[:k] * (np.cos(mx) + 1j * np.sin(mx))
        m += k
    return E[:n]


def _integrated(c: np.ndarray) -> np.ndarray:
    """Coefficients of the zero-mean antiderivative of the periodic part of the series c."""
    out = np.zeros_like(c)
    n = np.arange(1, c.size)
    out[1:] = c[1:] / (1j * n)
    return out


class _HermiteTable:
    """Piecewise-cubic Hermite interpolant of ``g(x) = Re(c_0 + 2 sum c_n e^{inx})`` on M uniform nodes
    (values and derivatives from one inverse FFT each), M doubled until the error at the midpoints is
    below ``tol``: a cheap model of a series for the first Newton steps (a gather and a Horner step
    per point instead of n complex powers)."""

    def __init__(self, c: np.ndarray, tol: float, mmax: int = 2 ** 16):
        n = np.arange(c.size)
        M = 8
        while M < 8 * c.size:
            M *= 2
        while True:
            X = np.zeros(M + 1, complex)                     # samples at the nodes and the midpoints
            X[:c.size] = 2 * M * c
            X[0] = 2 * M * c[0].real
            dX = np.zeros(M + 1, complex)
            dX[:c.size] = 2 * M * 1j * n * c
            g, dg = np.fft.irfft(X, 2 * M), np.fft.irfft(dX, 2 * M)
            v, d = np.append(g[::2], g[0]), np.append(dg[::2], dg[0])
            h = 2 * np.pi / M
            d0, d1 = h * d[:-1], h * d[1:]
            dv = v[1:] - v[:-1]
            # g = v0 + u (d0 + u (a2 + u a3)), u in [0, 1] on each interval
            self.coef = np.stack([v[:-1], d0, 3 * dv - 2 * d0 - d1, d0 + d1 - 2 * dv], -1)
            mid = self.coef @ np.array([1.0, 0.5, 0.25, 0.125])
            self.error = float(np.abs(mid - g[1::2]).max())
            if self.error <= tol or M >= mmax:
                break
            M *= 2
        self.M, self.h = M, h

    def __call__(self, x: np.ndarray):
        """(g, dg/dx) at x."""
        y = np.remainder(x, 2 * np.pi) / self.h
        j = np.minimum(y.astype(np.intp), self.M - 1)
        u = y - j
        v0, d0, a2, a3 = self.coef[j].T
        return v0 + u * (d0 + u * (a2 + u * a3)), (d0 + u * (2.0 * a2 + 3.0 * u * a3)) / self.h


# -- one separated coordinate ----------------------------------------------------------------------

class _Oscillator:
    """``u = lo + w sin^2(theta/2)`` on ``[lo, hi]`` with ``dtheta/dtau = sqrt(C prod_r |u - r|)``.

    ``below``/``above``: gaps ``lo - r`` / ``r - hi`` to the other real roots (given accurately by the
    caller); ``complex_roots``: the others.  ``alpha`` (the angle linear in tau, ``alpha = tau / fbar``
    + const) and its inverse ``theta = alpha + B(alpha)`` are Fourier series.
    """

    def __init__(self, lo, hi, C, below=(), above=(), complex_roots=(), name="u"):
        self.lo, self.hi, self.w = float(lo), float(hi), float(hi - lo)
        self.C = float(C)
        self.below = np.asarray(below, float)
        self.above = np.asarray(above, float)
        self.cplx = np.asarray(complex_roots, complex)
        self.f = _fit_series(lambda th: 1.0 / self.rate(th), f"d{name}/rate")
        self.fbar = self.f[0].real
        self.A = _integrated(self.f) / self.fbar            # alpha = theta + A(theta)
        # theta is known to eps * 2 pi at best: that is the noise floor of its series
        self.B = _fit_series(lambda al: self._invert(al) - al, f"the inverse angle of {name}",
                             floor=2 * np.pi * _EPS)

    # theta-functions of the coordinate
    def parts(self, th):
        """``(u - lo, hi - u, sin(th/2), cos(th/2))``, each accurate near its zero."""
        s, c = np.sin(0.5 * th), np.cos(0.5 * th)
        return self.w * s * s, self.w * c * c, s, c

    def u(self, th):
        dlo, dhi, _, _ = self.parts(th)
        return np.where(dlo <= dhi, self.lo + dlo, self.hi - dhi)

    def dists(self, th):
        """|u - r| for every other root, shape th.shape + (n_roots,)."""
        dlo, dhi, _, _ = self.parts(th)
        out = [d + dlo for d in self.below] + [d + dhi for d in self.above]
        if self.cplx.size:
            u = self.u(th)
            out += [np.abs(u - r) for r in self.cplx]
        return np.stack(out, -1)

    def rate(self, th):
        return np.sqrt(self.C * np.prod(self.dists(th), -1))

    def _invert(self, al):
        """theta with theta + A(theta) = al (safeguarded Newton; the map is increasing)."""
        def fun(th):
            g, dg = _eval_series(self.A, th, derivative=True)
            return th + g, 1.0 + dg

        span = 2.0 * np.abs(self.A[1:]).sum() + 1e-300
        return _monotone_newton(fun, al, al.copy(), al - span, al + span,
                                lambda new, th: np.abs(new - th) <= 1e-9, 100, 2)

    def theta(self, al):
        return al + _eval_series(self.B, al)

    def alpha(self, th):
        return th + _eval_series(self.A, th)


def _monotone_newton(fun, y, x, lo, hi, converged, maxiter: int, polish: int):
    """x with fun(x)[0] = y for an increasing fun (returning value and derivative; 1-d arrays):
    Newton steps, bisection of the bracket [lo, hi] where a step leaves it, each point until
    ``converged(new, old)`` (elementwise) holds for it (the others go on alone); then ``polish``
    plain steps on all (quadratic convergence reaches rounding)."""
    x = np.array(x, float)
    idx = np.arange(x.size)
    xa, ya = x, y
    lo, hi = np.broadcast_to(lo, x.shape), np.broadcast_to(hi, x.shape)
    for _ in range(maxiter):
        f, df = fun(xa)
        r = f - ya
        lo = np.where(r < 0, xa, lo)
        hi = np.where(r > 0, xa, hi)
        step = xa - r / df
        bad = (step < lo) | (step > hi) | ~np.isfinite(step)
        new = np.where(bad, 0.5 * (lo + hi), step)
        more = ~converged(new, xa)
        x[idx] = new
        if not more.any():
            break
        idx, xa, ya, lo, hi = idx[more], new[more], ya[more], lo[more], hi[more]
    for _ in range(polish):
        f, df = fun(x)
        x = x - (f - y) / df
    return x


def _quadratic_roots(a2: float, a1: float, a0: float):
    """Real roots (ascending) of a2 z^2 + a1 z + a0 without cancellation (discriminant clipped at 0)."""
    disc = max(a1 * a1 - 4.0 * a2 * a0, 0.0)
    q = -0.5 * (a1 + np.copysign(np.sqrt(disc), a1))
    if q == 0.0:
        return np.array([0.0, 0.0])
    r = np.array([q / a2, a0 / q])
    return np.sort(r)


# -- the genus-2 torus (distinct eigenvalues of a) -------------------------------------------------

class _NeumannTorus:
    """Neumann's problem ``xddot = -k x + (x.kx - |xdot|^2) x`` on the unit sphere (k ascending,
    distinct) from ``(x0, y0)``: the separated solution ``x(t)``, ``xdot(t)``."""

    def __init__(self, k: np.ndarray, x0: np.ndarray, y0: np.ndarray):
        d = k - k[1]                                   # shifted to the middle eigenvalue (exact)
        L = np.cross(x0, y0)
        x2 = x0 * x0
        jl = [(1, 2), (0, 2), (0, 1)]
        a2 = x2.sum()
        a1 = -sum(x2[i] * (d[j] + d[l]) for i, (j, l) in enumerate(jl))
        a0 = sum(x2[i] * d[j] * d[l] for i, (j, l) in enumerate(jl))
        zu = _quadratic_roots(a2, a1, a0)              # u1 <= k2 <= u2 (shifted)
        L2 = L * L
        zb = _quadratic_roots(a2, a1 + L2.sum(), a0 - (L2 * d).sum())
        roots = sorted([(d[i], "k", i) for i in range(3)] + [(zb[j], "b", j) for j in range(2)],
                       key=lambda r: r[0])
        vals = np.array([r[0] for r in roots])
        scale = max(abs(d[0]), abs(d[2]))
        tol = 1e-9 * scale
        ivals = [(1, 2), (3, 4)]
        if not (vals[1] - tol <= zu[0] <= vals[2] + tol and vals[3] - tol <= zu[1] <= vals[4] + tol):
            raise ClosedFormUnavailable(f"Neumann solution: the sphero-conical coordinates {zu} are not in "
                                        f"their oscillation intervals {vals} (internal inconsistency)")
        self.osc = []
        for kk, (i_lo, i_hi) in enumerate(ivals):
            lo, hi = vals[i_lo], vals[i_hi]
            if hi - lo <= MIN_WIDTH * scale and "b" in (roots[i_lo][1], roots[i_hi][1]):
                # the width is a difference with a root of B known to eps * scale: the angle on a
                # thin torus is known to ~eps / width (measured 5e-12 at width 1e-10, t = 40); an
                # interval [k_i, k_j] (nearly repeated eigenvalues) is exact and kept
                raise ClosedFormUnavailable(
                    f"Neumann solution: nearly degenerate torus (a sphero-conical coordinate stays within "
                    f"{(hi - lo) / scale:.1e} of the span of k: the axis within ~{np.sqrt((hi - lo) / scale):.0e} "
                    "of an invariant great circle, or of a periodic orbit); the separated coordinates lose "
                    "accuracy there (nearly planar motion is not handled); use thetasol.integrate_rotation")
            others = [vals[m] for m in range(5) if m not in (i_lo, i_hi)]
            self.osc.append(_Oscillator(lo, hi, 4.0, below=[lo - r for r in others if r < lo],
                                        above=[r - hi for r in others if r >= hi], name=f"u{kk + 1}"))
        # the role of each k_i in each interval: 'lo', 'hi' endpoint or a gap to the nearer endpoint
        self.role = []
        for i in range(3):
            row = []
            for kk, (i_lo, i_hi) in enumerate(ivals):
                if roots[i_lo][1:] == ("k", i):
                    row.append(("lo", 0.0))
                elif roots[i_hi][1:] == ("k", i):
                    row.append(("hi", 0.0))
                elif d[i] < vals[i_lo]:
                    row.append(("below", vals[i_lo] - d[i]))
                else:
                    row.append(("above", d[i] - vals[i_hi]))
            self.role.append(row)
        self.norm = np.array([np.sqrt(abs((d[i] - d[j]) * (d[i] - d[l]))) for i, (j, l) in enumerate(jl)])
        # initial angles: cos theta from the position, sin theta from the velocity (both absolute-accurate):
        # du/ds = (u2 - u1) du/dt = (w/2) sin(theta) dtheta/ds = w sin(theta) sqrt(prod_others |u - r|)
        th0 = []
        gap0 = zu[1] - zu[0]
        for kk, o in enumerate(self.osc):
            z = zu[kk]
            udot = -sum(2.0 * x0[i] * y0[i] * (z - d[j]) * (z - d[l])
                        for i, (j, l) in enumerate(jl)) / (2.0 * a2 * z + a1)
            cos_th = ((o.hi - z) - (z - o.lo)) / o.w
            dist = [abs(z - vals[m]) for m in range(5) if m not in ivals[kk]]
            sin_th = gap0 * udot / (o.w * np.sqrt(np.prod(dist)))
            th0.append(np.arctan2(sin_th, cos_th))
        self.th0 = np.array(th0)
        self.sigma = np.ones(3)
        xm, dxm, gm = self.state(self.th0[0], self.th0[1])
        tau2 = 1.0 / scale
        self.sigma = np.where(x0 * xm + tau2 * y0 * dxm / gm >= 0, 1.0, -1.0)
        xm, dxm, gm = self.state(self.th0[0], self.th0[1])
        self.fit_residual = float(max(np.abs(xm - x0).max(), np.sqrt(tau2) * np.abs(dxm / gm - y0).max()))
        # the time along the torus: t(s) = <u2 - u1> s + bounded
        self.alpha0 = np.array([o.alpha(th) for o, th in zip(self.osc, self.th0)])
        self.cu = [_fit_series(lambda al, o=o: o.u(o.theta(al)), f"u{kk + 1}(alpha)",
                               floor=4 * _EPS * scale)
                   for kk, o in enumerate(self.osc)]
        self.P = [_integrated(c) for c in self.cu]
        self.fbar = np.array([o.fbar for o in self.osc])
        self.drift = self.cu[1][0].real - self.cu[0][0].real
        self.P0 = np.array([_eval_series(P, a) for P, a in zip(self.P, self.alpha0)])
        self.Pspan = sum(2 * f * np.abs(P).sum() for f, P in zip(self.fbar, self.P)) * 2
        # cheap models of the two bounded parts of t(s) (to 1e-12 of the time scale 1/drift): Newton
        # on them, then one step on the series
        self.tables = [_HermiteTable(f * P, 1e-12 / self.drift) for f, P in zip(self.fbar, self.P)]
        self.table0 = [tab(a)[0] for tab, a in zip(self.tables, self.alpha0)]

    # -- the state on the torus ------------------------------------------------------------------
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

    def state(self, th1, th2):
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
        gap = ((o2.lo - o1.hi) + o1.parts(th1)[1]) + o2.parts(th2)[0]
        return np.stack(np.broadcast_arrays(*xs), -1), np.stack(np.broadcast_arrays(*dxs), -1), gap

    # -- time -> s ---------------------------------------------------------------------------------
    def _alpha(self, s):
        """The two angles alpha_k(s), linear in s: shape (2, s.size)."""
        return self.alpha0[:, None] + s[None, :] / self.fbar[:, None]

    def _time(self, s, angles: bool = False):
        """t(s) and dt/ds = u2 - u1 at s (one set of powers e^{i n alpha} per coordinate); with
        ``angles`` also theta_k(alpha_k(s)) and dtheta_k/dalpha_k."""
        al = self._alpha(s)
        t = self.drift * s
        u, th, dth = [], [], []
        for kk, (o, P) in enumerate(zip(self.osc, self.P)):
            E = _powers(al[kk], max(P.size, o.B.size) - 1)
            t = t + (1 if kk else -1) * self.fbar[kk] * (_sum_series(E, P) - self.P0[kk])
            th.append(al[kk] + _sum_series(E, o.B))
            u.append(o.u(th[-1]))
            if angles:
                dth.append(1.0 + _sum_series_derivative(E, o.B))
        if angles:
            return t, u[1] - u[0], np.array(th), np.array(dth)
        return t, u[1] - u[0]

    def _time_model(self, s):
        """t(s) and dt/ds from the Hermite tables of the bounded parts."""
        t, dt = self.drift * s, self.drift
        for kk, (tab, f, a0) in enumerate(zip(self.tables, self.fbar, self.alpha0)):
            g, dg = tab(a0 + s / f)
            sgn = 1 if kk else -1
            t, dt = t + sgn * (g - self.table0[kk]), dt + sgn * dg / f
        return t, dt

    def s_of_t(self, t: np.ndarray):
        """s with t(s) = t (t(s) is increasing) and alpha(s), theta(s): safeguarded Newton on the
        tables of t(s), then one Newton step on the series; if a step is above 1e-9 / drift and the
        rounding of s (64 eps |s|), a table was poor (it stopped at its node limit) and the
        safeguarded Newton goes on on the series."""
        lo, hi = (t - self.Pspan) / self.drift, (t + self.Pspan) / self.drift
        unit = 1.0 / self.drift

        def close(tol):
            return lambda new, s: np.abs(new - s) <= np.maximum(tol * unit, 64 * _EPS * np.abs(s))

        s0 = _monotone_newton(self._time_model, t, t / self.drift, lo, hi, close(1e-10), 200, 0)
        # the tables are good to 1e-12 unit: one series step lands at rounding (the step after it
        # would be ~1e-24 unit), and theta follows to first order (the second is ~1e-24 too)
        t0, dt0, th0, dth0 = self._time(s0, angles=True)
        step = (t - t0) / dt0
        s = s0 + step
        if np.all(close(1e-9)(s, s0)):
            return s, self._alpha(s), th0 + dth0 * (step / self.fbar[:, None])
        s = _monotone_newton(self._time, t, s0, lo, hi, close(1e-9), 200, 1)     # a poor table
        al = self._alpha(s)
        return s, al, np.array([o.theta(a) for o, a in zip(self.osc, al)])


# -- the angle of the parallel-transported frame ---------------------------------------------------

class _AngleSeries:
    """``phi(s) - phi(0) = int_0^s H ds`` for a function H on the torus ``beta in [0, 2 pi)^2`` that
    moves linearly, ``beta(s) = beta0 + nu s``: a 2-d FFT integrated term by term.

    ``H(a)`` returns the samples on the grid ``a x a`` of ``alpha = 2 beta`` in [0, 2 pi); ``parity``
    says in which direction H changes sign under ``alpha -> alpha + 2 pi``: there only odd beta
    harmonics occur, and ``H e^{-i p.alpha/2}`` is sampled on the alpha grid (half the points).
    """

    def __init__(self, H, beta0: np.ndarray, nu: np.ndarray, parity, what: str):
        p = np.asarray(parity, float)

        def transform(n):
            a = 2 * np.pi * np.arange(n) / n
            vals = H(a)
            twist = np.exp(-0.5j * (p[0] * a[:, None] + p[1] * a[None, :]))
            m = np.abs(np.rint(np.fft.fftfreq(n) * n).astype(int))
            band = (m[:, None] >= (3 * n) // 8) | (m[None, :] >= (3 * n) // 8)
            return np.fft.fft2(vals * twist) / (n * n), band, 8 * _EPS * np.abs(vals).max()

        self.n, c, keep = _refined_fft(transform, what + " on the torus", 32, N_MAX_2D,
                                       terms=lambda n: f"{n}^2")
        m = np.rint(np.fft.fftfreq(self.n) * self.n).astype(int)
        i1, i2 = np.nonzero(keep)
        modes = np.stack([2 * m[i1] + int(p[0]), 2 * m[i2] + int(p[1])], -1)   # beta harmonics
        coef = c[i1, i2]
        zero = (modes[:, 0] == 0) & (modes[:, 1] == 0)
        self.mean = coef[zero].sum().real
        modes, coef = modes[~zero], coef[~zero]
        D = modes @ nu
        # near-resonant terms keep the form s e^{iDs/2} sinc: amplification min(s, 1/|D|)
        res = np.abs(D) < 1e-3 * nu.min()
        self.C_res = coef[res] * np.exp(1j * (modes[res] @ beta0))
        self.D_res = D[res]
        reg = modes[~res]
        C = coef[~res] / (1j * D[~res])
        self.const = (C * np.exp(1j * (reg @ beta0))).sum().real
        # only Re(sum) is needed: the mode -m is folded onto m (Re(c e^{-i m.b}) = Re(conj(c) e^{i m.b})),
        # so the box holds the half plane m1 > 0 or (m1 = 0, m2 > 0); and m = 2 j + p (the twist), so
        # it is indexed by the alpha harmonics j: a quarter of the beta box, half of it kept
        lower = (reg[:, 0] < 0) | ((reg[:, 0] == 0) & (reg[:, 1] < 0))
        reg = np.where(lower[:, None], -reg, reg)
        C = np.where(lower, C.conj(), C)
        self.p = p.astype(int)
        jj = (reg - self.p) // 2                                   # j1 >= 0
        self.col0 = None                                           # the column j2 = 0
        if reg.size:
            self.n1 = int(jj[:, 0].max())
            self.n2 = int(np.abs(jj[:, 1]).max())
            # columns j2 = 0, 1..n2 and -1..-n2 (conjugated: sum_k conj(b_{-k} e^{ikx}) = conj of a
            # product with the same powers)
            box = np.zeros((self.n1 + 1, 2 * self.n2 + 1), complex)
            col = np.where(jj[:, 1] >= 0, jj[:, 1], self.n2 - jj[:, 1])
            np.add.at(box, (jj[:, 0], col), np.where(jj[:, 1] >= 0, C, C.conj()))
            self.col0 = box[:, 0].copy()
            self.blocks = _row_blocks(box, self.n2)
        self.n_modes = int(keep.sum())

    def __call__(self, s: np.ndarray, beta: np.ndarray) -> np.ndarray:
        """int_0^s H, with beta = beta(s) given (shape (n, 2), any representative mod 2 pi)."""
        out = self.mean * s - self.const
        if self.col0 is not None:
            beta = np.remainder(beta, 2 * np.pi)
            a = np.remainder(2.0 * beta, 2 * np.pi)                # e^{i j alpha} = e^{2 i j beta}
            n1, n2 = self.n1, self.n2
            G = np.repeat(self.col0[:, None], s.size, 1)
            if n2:
                E2 = _powers(a[:, 1], n2)
                for r0, r1, pos, neg in self.blocks:
                    w = pos.shape[1]
                    G[r0:r1] += pos @ E2[:w] + (neg @ E2[:w]).conj()
            val = G[0] + (np.einsum("jn,jn->n", G[1:], _powers(a[:, 0], n1)) if n1 else 0.0)
            out = out + (np.exp(1j * (beta @ self.p)) * val).real
        for Cr, D in zip(self.C_res, self.D_res):
            out = out + (Cr * s * np.exp(0.5j * D * s) * np.sinc(D * s / (2 * np.pi))).real
        return out


def _row_blocks(box: np.ndarray, n2: int, overhead: int = 256):
    """Split the rows of the angle box (columns 0, 1..n2, -1..-n2) into runs with their own column
    width w (rows far from j1 = 0 need few j2): (r0, r1, positive part, conjugated negative part),
    the runs chosen to minimize the entries multiplied plus ``overhead`` per run."""
    nz = box != 0
    cols = np.arange(1, n2 + 1)
    wr = np.array([max(cols[nz[r, 1:n2 + 1]].max(initial=0), cols[nz[r, n2 + 1:]].max(initial=0))
                   for r in range(box.shape[0])])
    R = wr.size
    best, cut = np.zeros(R + 1), np.zeros(R + 1, int)
    for r1 in range(1, R + 1):
        costs = [best[r0] + (r1 - r0) * 2 * wr[r0:r1].max() + overhead for r0 in range(r1)]
        cut[r1] = int(np.argmin(costs))
        best[r1] = costs[cut[r1]]
    blocks, r1 = [], R
    while r1 > 0:
        r0 = cut[r1]
        w = int(wr[r0:r1].max())
        if w:
            blocks.append((r0, r1, box[r0:r1, 1:w + 1].copy(), box[r0:r1, n2 + 1:n2 + 1 + w].copy()))
        r1 = r0
    return blocks[::-1]


def _frame(x: np.ndarray, c: int):
    """The reference frame f1 = e_c x x / |e_c x x|, f2 = x x f1 on the sphere."""
    e = np.zeros(3)
    e[c] = 1.0
    f1 = np.cross(e, x)
    f1 /= np.linalg.norm(f1, axis=-1, keepdims=True)
    return f1, np.cross(x, f1)


def _transported(x: np.ndarray, ref: int, phi: np.ndarray) -> np.ndarray:
    """The body's first axis at the angle phi from the reference frame of axis ref."""
    f1, f2 = _frame(x, ref)
    return np.cos(phi)[:, None] * f1 + np.sin(phi)[:, None] * f2


def _reference_axis(T: _NeumannTorus):
    """Eigen-axis c of a farthest from the trajectory: max over the torus of x_c^2 is at a corner of
    the rectangle of (u1, u2); returns c and min(1 - x_c^2)."""
    best, margin = None, -1.0
    for i in range(3):
        mx = 1.0
        for kk, o in enumerate(T.osc):
            kind, g = T.role[i][kk]
            mx *= o.w if kind in ("lo", "hi") else g + o.w
        m = 1.0 - mx / T.norm[i] ** 2
        if m > margin:
            best, margin = i, m
    return best, margin


@dataclass(frozen=True, eq=False)
class NeumannRotation(RotationSolution):
    """Rotation of a symmetric body without axial spin: the axis in Neumann's problem, the body
    parallel-transported along it (see the module docstring).

    Attributes (besides :class:`thetasol.RotationSolution`'s)
    ----------------------------------------------------------
    k : ndarray, shape (3,)
        Eigenvalues of ``K = (j3 - j) a / (j + j3)`` (ascending): the potential of the axis per
        unit moment of inertia.
    frame : ndarray, shape (3, 3)
        Their eigenvectors (columns, right-handed, space frame).
    """

    k: np.ndarray = field(default=None, repr=False)
    frame: np.ndarray = field(default=None, repr=False)
    _c: dict = field(default=None, repr=False)

    def _evaluate(self, t: np.ndarray):
        c = self._c
        x, xd, E1 = c["axis_motion"](t)
        E2 = np.cross(x, E1)
        V, P = self.frame, c["P"]
        a1, a2, ax = c["axes"]
        Qp = np.empty(t.shape + (3, 3))
        Qp[..., :, a1] = E1 @ V.T
        Qp[..., :, a2] = E2 @ V.T
        Qp[..., :, ax] = x @ V.T
        wp = np.zeros(t.shape + (3,))
        wp[..., a1] = -np.einsum("ni,ni->n", xd, E2)
        wp[..., a2] = np.einsum("ni,ni->n", xd, E1)
        return wp @ P.T, Qp @ P.T


def _genus2_motion(T: _NeumannTorus, ref: int, e10: np.ndarray):
    """(axis_motion(t) -> (x, xdot, E1), invariants) on the genus-2 torus with reference axis ref."""
    o, p = [j for j in range(3) if j != ref]

    sgn = 1 if (o, p) in ((0, 1), (1, 2), (2, 0)) else -1

    def Hth(th1, th2):
        x, dx, _ = T.state(th1, th2)
        L = x[..., o] * dx[..., p] - x[..., p] * dx[..., o]
        return -sgn * x[..., ref] * L / (x[..., o] ** 2 + x[..., p] ** 2)

    def H(a):
        return Hth(T.osc[0].theta(a)[:, None], T.osc[1].theta(a)[None, :])

    # every reflection x_i -> -x_i changes the sign of H; theta_k -> theta_k + 2 pi reflects the x_i
    # whose k_i ends the k-th interval
    parity = [sum(T.role[i][kk][0] in ("lo", "hi") for i in range(3)) % 2 for kk in range(2)]
    beta0 = 0.5 * T.alpha0
    nu = 0.5 / T.fbar
    ang = _AngleSeries(H, beta0, nu, parity, "the frame's angular rate")
    x0, _, _ = T.state(T.th0[0], T.th0[1])
    f1, f2 = _frame(x0, ref)
    phi0 = np.arctan2(e10 @ f2, e10 @ f1)

    def motion(t):
        s, al, th = T.s_of_t(t)
        x, dx, gap = T.state(th[0], th[1])
        return x, dx / gap[:, None], _transported(x, ref, phi0 + ang(s, 0.5 * al.T))

    motion.torus = T                                   # for the tests of the time map
    info = {"genus": 2, "reference_axis": ref, "angle_modes": ang.n_modes, "angle_grid": ang.n,
            "frequencies_s": nu.copy(), "time_drift": float(T.drift),
            "series_terms": [int(o_.f.size) for o_ in T.osc]}
    return motion, info


# -- set-up ----------------------------------------------------------------------------------------

def _symmetric_no_spin(J: np.ndarray, a: np.ndarray, omega0: np.ndarray):
    """(Jp, P, axis) when the body is symmetric, a is not isotropic and omega0 has no axial part
    (relative to |omega0| + sqrt|a|, within theta_rotation's SNAP_TOL); else None."""
    Jp, P = _principal_frame(J)
    if Jp[-1] - Jp[0] <= SNAP_TOL * Jp[-1]:
        return None                                    # spherical: no torque
    axis = _symmetry_axis(Jp)
    if axis is None:
        return None
    ev = np.linalg.eigvalsh(a)
    if ev[-1] - ev[0] <= 8 * _EPS * np.abs(ev).max():
        return None                                    # isotropic a: no torque
    w0p = P.T @ omega0
    scale = np.linalg.norm(w0p) + np.sqrt(np.abs(ev).max())
    if abs(w0p[axis]) > SNAP_TOL * scale:
        return None
    return Jp, P, axis


def _solve_neumann_rotation(J, a, Q0, omega0, dps=None):
    """The Neumann branch of :func:`thetasol.solve_rotation` (None when it does not apply)."""
    found = _symmetric_no_spin(J, a, omega0)
    if found is None:
        return None
    if dps is not None:
        raise ClosedFormUnavailable("dps= is not available for the Neumann solution (symmetric body "
                                    "without axial spin)")
    Jp, P, ax = found
    a1, a2 = (ax + 1) % 3, (ax + 2) % 3
    j, j3 = 0.5 * (Jp[a1] + Jp[a2]), Jp[ax]
    I1 = j + j3
    Q0p = Q0 @ P
    w0p = P.T @ omega0
    w0p[ax] = 0.0
    e_ax = np.zeros(3)
    e_ax[ax] = 1.0
    gamma0 = Q0p[:, ax]
    gdot0 = Q0p @ np.cross(w0p, e_ax)
    K = (j3 - j) / I1 * a
    k, V = np.linalg.eigh(K)
    V[:, 2] *= np.sign(np.linalg.det(V))
    x0 = V.T @ gamma0
    y0 = V.T @ gdot0
    x0 = x0 / np.linalg.norm(x0)
    y0 = y0 - x0 * (x0 @ y0)
    e10 = V.T @ Q0p[:, a1]
    inv = {key: float(v) for key, v in _invariants(J, a, Q0, omega0).items() if key != "curve"}
    inv["k"] = k.copy()
    motion, info, method = _axis_model(k, x0, y0, e10)
    inv.update(info)
    c = {"axis_motion": motion, "P": P, "axes": (a1, a2, ax)}
    return NeumannRotation(J=J, a=a, Q0=Q0, omega0=omega0, method=method, invariants=inv,
                           k=k, frame=V, _c=c)


# -- degenerate tori: a great circle, a potential with an axis of symmetry -------------------------

def _rotate(v: np.ndarray, n: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """v turned by ``angle`` (array) about the unit vector n (Rodrigues), shape angle.shape + (3,)."""
    c, s = np.cos(angle)[..., None], np.sin(angle)[..., None]
    return c * v + s * np.cross(n, v) + (1.0 - c) * (n @ v) * n


def _pendulum(psi0: float, psidot0: float, nu: float):
    """psi'' = -nu^2 sin psi from (psi0 in (-pi, pi], psidot0): the parameters of
    :func:`thetasol.solutions.pendulum._pendulum_angle` (which returns half of ``psi(t) - psi0``, ``psidot(t)``)
    and the kind of motion."""
    if nu == 0.0 or (psidot0 == 0.0 and np.sin(psi0) == 0.0):
        return {"kind": "uniform", "phi0": 0.0, "w0": 0.5 * psidot0}, ("uniform" if psidot0 else "rest")
    c, _ = _pendulum_params(psi0, psidot0, nu)
    return c, c["kind"]


def _planar_motion(k, x0, y0, e10, normal):
    """The axis on the invariant great circle with the unit normal ``normal`` (an eigenvector of K,
    eigen-coordinates): gamma = cos v p + sin v q, ``psi = 2 v`` a pendulum; the body turns about the
    fixed normal, so the first axis is e10 turned by v - v0."""
    n = normal / np.linalg.norm(normal)
    # p, q: an orthonormal eigenbasis of K in the plane, p the lower eigenvalue
    Pn = np.eye(3) - np.outer(n, n)
    B = Pn @ np.diag(k) @ Pn
    ev, W = np.linalg.eigh(B + 10.0 * (np.abs(k).max() + 1.0) * np.outer(n, n))
    p, q = W[:, 0], W[:, 1]
    if np.cross(p, q) @ n < 0:
        q = -q
    kp, kq = ev[0], ev[1]
    v0 = np.arctan2(x0 @ q, x0 @ p)
    vdot0 = y0 @ np.cross(n, x0)
    psi0 = np.remainder(2.0 * v0 + np.pi, 2.0 * np.pi) - np.pi
    nu2 = kq - kp
    scale = abs(vdot0) + np.sqrt(np.abs(k).max())
    nu = 0.0 if nu2 <= 4 * _EPS * scale ** 2 else float(np.sqrt(nu2))
    pend, kind = _pendulum(psi0, 2.0 * vdot0, nu)

    x0n = x0 - (x0 @ n) * n
    x0n /= np.linalg.norm(x0n)

    def motion(t):
        dv, vdot = _pendulum_angle(pend, t)                 # v - v0 = (psi - psi0) / 2
        # the axis and the body's first axis turned by the same angle: Q stays orthogonal at far times
        x = _rotate(x0n, n, dv)
        xd = vdot[:, None] * np.cross(n, x)
        return x, xd, _rotate(e10, n, dv)

    return motion, {"torus_dimension": 1 if nu else 0, "pendulum_nu": nu, "plane_normal": n}, kind


def _repeated_motion(k, x0, y0, e10, idx):
    """a with a repeated eigenvalue: K = k_perp + kappa n n^T with n = e_idx.  z = x.n oscillates in
    an elliptic-type well, the azimuth and the frame angle are quadratures in z: all on one circle."""
    o1, o2 = [j for j in range(3) if j != idx]
    if (o1, o2) not in ((0, 1), (1, 2), (2, 0)):
        o1, o2 = o2, o1                                     # (m1, m2, n) right-handed
    kperp = 0.5 * (k[o1] + k[o2])
    kappa = k[idx] - kperp
    z0 = x0[idx]
    ell = x0[o1] * y0[o2] - x0[o2] * y0[o1]
    h = 0.5 * (y0 @ y0) + 0.5 * kappa * z0 * z0
    # z^2 = w = 1 - v with kappa v^2 + (2h - kappa) v - ell^2 = 0 (v accurate near the poles)
    v = _quadratic_roots(kappa, 2.0 * h - kappa, -ell * ell)
    roots = []
    for vv in v:
        w = 1.0 - vv
        if w >= 0:
            rt = np.sqrt(w)
            roots += [(rt, vv / (1.0 + rt)), (-rt, None)]      # (root, 1 - root when accurate)
        else:
            roots += [(1j * np.sqrt(-w), None), (-1j * np.sqrt(-w), None)]
    real = sorted([r for r in roots if np.isreal(r[0])], key=lambda r: r[0].real)
    below = [r for r in real if r[0].real <= z0]
    above = [r for r in real if r[0].real > z0]
    if not below or not above:
        # z0 at a turning point within rounding: take the nearest pair around it
        zs = np.array([r[0].real for r in real])
        i = int(np.argmin(np.abs(zs - z0)))
        below, above = (real[:i + 1], real[i + 1:]) if i + 1 < len(real) and z0 >= zs[i] else (real[:i], real[i:])
    lo, hi = below[-1], above[0]
    zlo, zhi = float(lo[0].real), float(hi[0].real)
    m1, m2, n = np.eye(3)[o1], np.eye(3)[o2], np.eye(3)[idx]
    lam0 = np.arctan2(x0[o2], x0[o1])
    f1_0, f2_0 = _frame(x0, idx)
    phi0 = np.arctan2(e10 @ f2_0, e10 @ f1_0)
    if zhi - zlo <= 64 * _EPS:
        # a circle of latitude z0 run at a constant rate (a relative equilibrium)
        rho0 = np.hypot(x0[o1], x0[o2])
        rate = ell / rho0 ** 2

        def steady(t):
            lam = lam0 + rate * t
            cl, sl = np.cos(lam)[:, None], np.sin(lam)[:, None]
            x = z0 * n + rho0 * (cl * m1 + sl * m2)
            xd = ell / rho0 * (-sl * m1 + cl * m2)
            return x, xd, _transported(x, idx, phi0 - z0 * rate * t)

        return steady, {"torus_dimension": 1, "reference_axis": idx, "azimuth_drift": float(rate)}
    one_minus_hi = hi[1] if hi[1] is not None else 1.0 - zhi
    one_plus_lo = 1.0 + zlo
    others = [r[0] for r in roots if r is not lo and r is not hi]
    osc = _Oscillator(zlo, zhi, abs(kappa),
                      below=[zlo - r.real for r in others if np.isreal(r) and r.real < zlo],
                      above=[r.real - zhi for r in others if np.isreal(r) and r.real >= zhi],
                      complex_roots=[r for r in others if not np.isreal(r)], name="z")

    def rho2(th):
        dlo, dhi, _, _ = osc.parts(th)
        return (one_minus_hi + dhi) * (one_plus_lo + dlo)          # 1 - z^2 without cancellation

    def series(g, what):
        return _fit_series(lambda al: g(osc.theta(al)), what, floor=4 * _EPS * (abs(ell) + 1.0))

    c_lam = series(lambda th: ell / rho2(th), "the azimuth rate")
    c_phi = series(lambda th: -osc.u(th) * ell / rho2(th), "the frame's angular rate")
    # initial angle theta0: cos from the position, sin from zdot = (w/2) sin(theta) rate
    zd0 = y0[idx]
    cos0 = ((zhi - z0) - (z0 - zlo)) / osc.w
    sin0 = 2.0 * zd0 / (osc.w * np.sqrt(osc.C * np.prod(np.abs(np.array(others) - z0))))
    th0 = np.arctan2(sin0, cos0)
    al0 = osc.alpha(th0)
    fbar = osc.fbar
    P_lam, P_phi = _integrated(c_lam), _integrated(c_phi)
    Pl0, Pp0 = _eval_series(P_lam, al0), _eval_series(P_phi, al0)

    n_pow = max(osc.B.size, P_lam.size, P_phi.size) - 1

    def motion(t):
        al = al0 + t / fbar
        E = _powers(al, n_pow)                                      # shared by the three series
        th = al + _sum_series(E, osc.B)
        z = osc.u(th)
        r2 = rho2(th)
        rho = np.sqrt(r2)
        lam = lam0 + c_lam[0].real * t + fbar * (_sum_series(E, P_lam) - Pl0)
        phi = phi0 + c_phi[0].real * t + fbar * (_sum_series(E, P_phi) - Pp0)
        zd = 0.5 * osc.w * np.sin(th) * osc.rate(th)
        cl, sl = np.cos(lam)[:, None], np.sin(lam)[:, None]
        radial = cl * m1 + sl * m2
        east = -sl * m1 + cl * m2
        x = z[:, None] * n + rho[:, None] * radial
        xd = zd[:, None] * n - (z * zd / rho)[:, None] * radial + (ell / rho)[:, None] * east
        return x, xd, _transported(x, idx, phi)

    info = {"torus_dimension": 1, "reference_axis": idx, "period": float(2 * np.pi * fbar),
            "azimuth_drift": float(c_lam[0].real), "series_terms": [int(osc.f.size), int(c_lam.size)]}
    return motion, info


#: Out-of-plane size (|x_i|, |xdot_i| / sqrt(k3 - k1)) below which the axis is put on the great circle.
PLANAR_TOL = 64 * _EPS


def _axis_model(k, x0, y0, e10):
    """Choose the model of the axis motion: (motion, info, method)."""
    span = k[2] - k[0]
    wscale = np.sqrt(span)
    gaps = np.diff(k)
    if gaps.min() <= SNAP_TOL * span:
        idx = 0 if gaps[1] <= gaps[0] else 2                # the eigenvalue that is not repeated
        n = np.eye(3)[idx]
        ell = np.cross(x0, y0) @ n
        if abs(ell) <= PLANAR_TOL * (np.linalg.norm(y0) + wscale):
            normal = np.cross(x0, y0) if np.linalg.norm(y0) > PLANAR_TOL * wscale else np.cross(x0, n)
            if np.linalg.norm(normal) <= PLANAR_TOL:
                normal = np.cross(x0, np.eye(3)[(idx + 1) % 3])   # the axis on n at rest
            motion, info, kind = _planar_motion(k, x0, y0, e10, normal)
            return motion, info, f"neumann/planar-{kind}"
        motion, info = _repeated_motion(k, x0, y0, e10, idx)
        return motion, info, "neumann/elliptic"
    for i in range(3):
        if max(abs(x0[i]), abs(y0[i]) / wscale) <= PLANAR_TOL:
            motion, info, kind = _planar_motion(k, x0, y0, e10, np.eye(3)[i])
            return motion, info, f"neumann/planar-{kind}"
    T = _NeumannTorus(k, x0, y0)
    if T.fit_residual > 1e-9:
        raise ClosedFormUnavailable(f"Neumann solution: the initial state is reproduced only to "
                                    f"{T.fit_residual:.1e} (nearly degenerate torus)")
    ref, margin = _reference_axis(T)
    motion, info = _genus2_motion(T, ref, e10)
    info["reference_margin"] = float(margin)
    info["torus_dimension"] = 2
    return motion, info, "neumann/genus-2"
