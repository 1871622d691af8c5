"""The generic gyrostat motion: the pencil parametrization inverted by Weierstrass' formula.

Three stages, each a frozen record built by one function (the method is described in
:mod:`thetasol.solutions.gyrostat`): :func:`elliptic_orbit` the orbit ``h(t)`` (:class:`EllipticOrbit`),
which :func:`reanchor` moves to a fast anchor; :func:`precession` the precession angle about a pole
(:class:`Precession`); :func:`elliptic_motion` the attitude and the error estimates
(:class:`EllipticMotion`, which evaluates ``omega`` and ``Q``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from thetasol.core.attitude import (
    angle_mod_2pi as _angle_mod_2pi,
    attitude_from_precession as _attitude,
    minimal_rotation as _minimal_rotation,
    norm3 as _norm,
    unit_rows as _unit,
)
from thetasol.core.dd import two_prod, two_sum
from thetasol.core.periodic import adaptive_series
from thetasol.solutions.gyrostat._algebra import mpq, orbit_algebra
from thetasol.solutions.gyrostat._forms import frame_with_e3
from thetasol.special.elliptic import ellipj_dd

__all__ = ["EllipticMotion", "EllipticOrbit", "OrbitConstants", "Precession", "elliptic_motion", "elliptic_orbit",
           "precession", "reanchor", "MIN_TORSION_RATIO"]

_EPS = np.finfo(float).eps
#: An anchor whose torsion rate is below this fraction of its maximum over the orbit is degenerate.
MIN_TORSION_RATIO = 1e-2


# -- the generic (elliptic) motion ------------------------------------------------------------

def _adaptive_series(coeffs, nmax, what, why=""):
    """:func:`thetasol.core.periodic.adaptive_series` for the series of ``psi'``."""
    return adaptive_series(coeffs, nmax, f"solve_gyrostat: the precession angle's {what} does not converge "
                                         f"(tail {{tail:.1e}}{why})")


def _cheb_nodes(n):
    return np.cos(np.pi * (np.arange(n) + 0.5) / n)


@dataclass(frozen=True, eq=False)
class OrbitConstants:
    """The algebraic constants of one orbit (:func:`~._algebra.orbit_algebra`): floats (and float
    vectors), and under ``mpc`` the same in mpmath.  ``kind`` 3 or 2 says which turning point of the
    Weierstrass cubic the inversion is based at; ``m``, ``mc``, ``scale``, ``T`` are the elliptic
    parameter, its complement, the rate of the elliptic argument and the period; ``va`` (+ ``va_lo``)
    the argument at the anchor; ``k``, ``qe``, ``p0``, ``p1``, ``cr``, ``sr``, ``s0`` the pencil's
    coefficients, turn and torsion rate at the anchor; ``polys``, ``tau``, ``e1``, ``e2`` the residual
    quadratic and the frame of the pencil; ``g2``, ``g3`` the invariants."""

    kind: int
    p1: float
    p0: float
    T: float
    m: float
    mc: float
    scale: float
    s0: float
    k: float
    qe: float
    g2: float
    g3: float
    cr: float
    sr: float
    va: float
    va_lo: float
    polys: tuple
    tau: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    mpc: dict


@dataclass(frozen=True, eq=False)
class EllipticOrbit:
    """h(t) of one orbit by the tangent-line pencil and Weierstrass' inversion based at a turning point;
    built by :func:`elliptic_orbit`.

    The state is carried as ``m = m0 + Delta(t)`` (``Delta`` the displacement of ``h`` from the anchor
    ``h(t_anchor) = m0 + n``), so that ``omega = a m`` keeps its relative accuracy when ``|m| << |N|``
    (fast rotors).  ``P`` maps the principal frame to the body frame; ``tr_hi + tr_lo`` is the time
    origin of the formula, ``t_anchor - v_a``, as a double-double.
    """

    Ip: np.ndarray
    a: np.ndarray
    n: np.ndarray
    m0: np.ndarray
    h0: np.ndarray
    P: np.ndarray
    G: float
    t_anchor: float
    Ip_exact: object
    c: OrbitConstants
    tr_hi: float
    tr_lo: float

    @property
    def separatrix(self) -> bool:
        """The orbit is a separatrix (``mc = 0``: no period, the saddle approached at both ends)."""
        return self.c.mc == 0.0

    @property
    def scale(self) -> float:
        """The rate of the elliptic argument."""
        return self.c.scale

    @property
    def T(self) -> float:
        """The period (inf on a separatrix)."""
        return self.c.T

    def orbit_times(self, n, off=None):
        """n times spread over the orbit: one period from the anchor, or on a separatrix
        ``tanh`` at Chebyshev nodes (the saddle approached at both ends); ``off`` shifts the
        grid by that fraction of its step."""
        if not self.separatrix:
            return self.t_anchor + (np.arange(n) + (off or 0.0)) * (self.T / n)
        s = np.cos(np.pi * (np.arange(n) + (0.5 if off is None else off)) / n)
        return self.tr_hi + np.arctanh(s) / self.scale

    def speed(self, t):
        """|hdot| = |h x omega| along the orbit."""
        d = self._dW(t)[0]
        return np.linalg.norm(np.cross(self.h0 + d, self.a * (self.m0 + d)), axis=-1)

    def anchor_candidates(self, n=64):
        """Times on the orbit for a new anchor: of a grid (offset by a generic fraction of its
        step, so that no point a symmetry of the orbit singles out is on it) the points not slower
        than a quarter of the fastest, by decreasing torsion rate |tau| |hdot| (the rate at which
        the pencil turns there)."""
        ts = self.orbit_times(n, off=0.313)
        d = self._dW(ts)[0]
        h, a = self.h0 + d, self.a
        w = a * (self.m0 + d)
        h1 = np.cross(h, w)
        w1 = a * h1
        h2 = np.cross(h1, w) + np.cross(h, w1)
        h3 = np.cross(h2, w) + 2 * np.cross(h1, w1) + np.cross(h, a * h2)
        b = np.cross(h1, h2)
        speed = np.linalg.norm(h1, axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            rate = np.abs(np.sum(b * h3, -1)) / np.sum(b * b, -1) * speed
        rate = np.where(np.isfinite(rate) & (speed >= 0.25 * np.nanmax(speed)), rate, -1.0)
        return ts[np.argsort(-rate)]

    def momentum_mp(self, t: float, near=None, as_mp=False, dps=None):
        """m(t) from the same closed form evaluated in mpmath (used to re-anchor exactly and
        to measure the float64 evaluation's error).

        With ``near`` given, of the two residual points for this ``z`` the one nearer to
        ``near`` is returned (where the two nearly coincide the sign test on ``B W`` is not
        decisive, and either is right to that accuracy)."""
        import mpmath as mp

        c = self.c.mpc
        with mp.workdps(dps or c["dps"]):
            sc = c["scale"]
            u = sc * (mp.mpf(t) - mp.mpf(self.t_anchor) + c["va"])
            sn, cn, dn = (mp.ellipfun(f, u, m=c["m"]) for f in ("sn", "cn", "dn"))
            if c["kind"] == 3:
                X, Xd = sn * sn, 2 * sn * cn * dn * sc
                Z0p = c["qe"] * X + c["p0"] * cn * cn
            else:
                X, Xd = 1 - cn, sc * sn * dn
                Z0p = c["qe"] * X + c["p0"] / 2 * (1 + cn)
            Z1p = c["k"] * X
            W = c["k"] * c["p0"] * Xd
            Z0 = c["cr"] * Z0p - c["sr"] * Z1p
            Z1 = c["sr"] * Z0p + c["cr"] * Z1p
            bSp, Ap, Bp, Cp = c["polys"]

            def hom(P):  # homogeneous evaluation of an ascending polynomial in z = Z1/Z0
                k = len(P) - 1
                return sum(P[i] * Z1 ** i * Z0 ** (k - i) for i in range(len(P)))

            bS, A, B, C = hom(bSp), hom(Ap), hom(Bp), hom(Cp)
            gS = Z0 * Z0 + Z1 * Z1
            mu = [Z1 * c["e1"][k] - Z0 * c["e2"][k] for k in range(3)]

            def point(Ws):
                if B * Ws > 0:
                    num, den = C, -B - Ws
                else:
                    num, den = Ws - B, A
                nrm = num * num + gS * den * den
                fac = -2 * bS / nrm if nrm != 0 else 0
                d = [fac * (num * den * c["tau"][k] + den * den * mu[k]) for k in range(3)]
                return [c["m0"][k] + d[k] for k in range(3)]

            p1 = point(W)
            if near is not None:
                p2 = point(-W)
                f1, f2 = (np.array([float(x) for x in p]) for p in (p1, p2))
                p1 = p1 if _norm(f1 - near) <= _norm(f2 - near) else p2
            return p1 if as_mp else np.array([float(x) for x in p1])

    def float_errors(self) -> tuple[float, float]:
        """Error of the float64 evaluation, relative to |m(0)|, and the phase error.

        Measured against the same closed form in mpmath at the data point and at the points
        of a dense grid over the orbit where the float64 result is least trustworthy: where it
        is slowest (turning points of the pencil, the approach to a saddle), where it is
        farthest from the invariant sphere and ellipsoid (rounding across the orbit shows there
        first), at the end of the period (the largest reduced argument), and a few others.
        To this the phase error is added: the argument ``scale (t - t_r)`` and the period
        carry the rounding of ``scale`` and ``K``, ``~2 eps`` per period in the phase."""
        n = 512
        ts = self.orbit_times(n, off=0.4137)
        d, W = self._dW(ts)
        h, m = self.h0 + d, self.m0 + d
        G2, E0 = self.G ** 2, np.sum(self.a * self.m0 ** 2)
        res = (np.abs(np.sum(h * h, -1) / G2 - 1)
               + np.abs(np.sum(self.a * m * m, -1) - E0) / (E0 + G2 * np.max(self.a)))
        hdot = np.linalg.norm(np.cross(h, self.a * m), axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            amp = np.nan_to_num(hdot / np.abs(W), nan=np.inf)  # |dh/dtheta|: rounding of theta
        pick = np.concatenate([[0.0, self.t_anchor], ts[np.argsort(-amp)[:6]],
                               ts[np.argsort(-res)[:4]], ts[n // 10::n // 5], ts[-2:]])
        mf = self.momentum(pick)
        scale = max(_norm(self.m0), 1e-300)
        # (twice the largest: the error between sampled points is rounding noise of that size)
        # (digits enough for float64 accuracy of m, mc; an exactly degenerate orbit is set up
        # at 2000 digits, which this comparison does not need)
        small = min(self.c.m, self.c.mc)
        dps = min(self.c.mpc["dps"], 50 + (int(-2 * np.log10(small)) if small > 0 else 0))
        float_error = 2 * max(_norm(mf[i] - self.momentum_mp(float(tp), near=mf[i], dps=dps))
                              for i, tp in enumerate(pick)) / scale
        if self.separatrix:
            u = np.abs(sum(self._u(ts)))
            return float_error, 2 * _EPS * np.max(u * hdot) / (self.scale * scale)
        return float_error, 4 * _EPS * self.T * np.max(hdot) / scale

    def reanchored(self, ta):
        """The same orbit with the pencil anchored at time ``ta``, at the point this closed form
        gives there in mpmath (not rounded: the curve stays the data's to the working precision)."""
        ma = self.momentum_mp(float(ta), as_mp=True)
        return elliptic_orbit(self.Ip, self.n, np.array([float(x) for x in ma]), self.P, t_anchor=float(ta),
                              m0_mp=ma, dps=self.c.mpc["dps"], Ip_exact=self.Ip_exact)

    def gives_back(self, mq) -> bool:
        """m(0) in mpmath equals the exact data ``mq`` to 1e-20 min(m, mc) (an exactly degenerate
        orbit: to the working precision less 40 digits)."""
        import mpmath as mp

        dps = self.c.mpc["dps"]
        with mp.workdps(dps):
            back = self.momentum_mp(0.0, as_mp=True)
            mis = max(abs(back[k] - mpq(mp, mq[k])) for k in range(3)) / max(abs(mpq(mp, x)) for x in mq)
            small = min(self.c.mpc["m"], self.c.mpc["mc"])
            return mis <= (mp.mpf(10) ** -20 * small if small > 0 else mp.mpf(10) ** (40 - dps))

    def anchor_is_slow(self) -> bool:
        """h(0) is much slower than the fast part of the orbit (next to a saddle)."""
        v0, v = self.speed(np.array([self.t_anchor]))[0], self.speed(self.orbit_times(64))
        return not (np.isfinite(v0) and np.all(np.isfinite(v))) or v0 < 0.25 * np.max(v)

    def torsion_ratio(self) -> float:
        """|dtheta/dt| at the anchor against its maximum over the orbit (0 when a value on the
        orbit is not finite: the formula is 0/0 somewhere)."""
        W = np.abs(self._dW(self.orbit_times(64))[1])
        return abs(self.c.s0) / np.max(W) if np.all(np.isfinite(W)) and np.max(W) > 0 else 0.0

    def anchor_is_degenerate(self) -> bool:
        """The orbit's torsion (nearly) vanishes at the anchor: dtheta_Z/dt = s0 ~ 0 there, and
        the pencil formula becomes 0/0 where the orbit meets the osculating plane again."""
        return self.torsion_ratio() < MIN_TORSION_RATIO

    # momentum --------------------------------------------------------------------------
    def h(self, t):
        """h(t) (principal frame) at flat times t."""
        return self.h0 + self._dW(t)[0]

    def momentum(self, t):
        """m(t) = I omega (principal frame) at flat times t."""
        return self.m0 + self._dW(t)[0]

    def displacement(self, t):
        """Delta(t) = h(t) - h(t_anchor) at flat times t."""
        return self._dW(t)[0]

    def displacement_at_argument(self, u):
        """Delta at the (float) elliptic arguments ``u = scale (t - t_r)``."""
        return self._dW_u(u, 0 * u)[0]

    def omega(self, t):
        """Body-frame omega at flat times t."""
        return (self.a * self.momentum(t)) @ self.P.T

    def _u(self, t):
        """The elliptic argument scale (t - t_r) as a double-double (hi, lo)."""
        d_hi, d_lo = two_sum(t, -self.tr_hi)
        hi, lo = two_prod(self.scale, d_hi)
        return hi, lo + self.scale * (d_lo - self.tr_lo)

    def _dW(self, t):
        """Delta(t) = h(t) - h(0) and the homogeneous W (unit (Z0, Z1)): dtheta_Z/dt = W."""
        return self._dW_u(*self._u(t))

    def _dW_u(self, hi, lo):
        """The state at the elliptic argument ``u = hi + lo = scale (t - t_r)``."""
        c = self.c
        sn, cn, dn, _ = ellipj_dd(hi, lo, np.full(hi.shape, c.m), np.full(hi.shape, c.mc))
        sc = self.scale
        # y = k / (wp - c) in the pencil turned by theta_r, wp = p1 + p0 / X, multiplied by X:
        # X (wp - c) = qe X + X (wp - e_top), the second term in a form free of cancellation
        # (next to a saddle wp - e_top is small and c nearly e_top: q1 X + p0 would cancel)
        if c.kind == 3:  # wp = e3 + (e1 - e3) / sn^2
            X = sn * sn
            Xd = 2 * sn * cn * dn * sc
            Z0p = c.qe * X + c.p0 * (cn * cn)
        else:  # wp = e2 + H (1 + cn) / (1 - cn), p0 = 2 H
            with np.errstate(divide="ignore", invalid="ignore"):
                X = np.where(cn > 0, sn * sn / (1 + cn), 1 - cn)
                Y = np.where(cn < 0, sn * sn / (1 - cn), 1 + cn)
            Xd = sc * sn * dn
            Z0p = c.qe * X + (0.5 * c.p0) * Y
        Z1p = c.k * X
        W = c.k * c.p0 * Xd  # the Wronskian Z0 Z1' - Z1 Z0' (invariant under the turn)
        Z0 = c.cr * Z0p - c.sr * Z1p
        Z1 = c.sr * Z0p + c.cr * Z1p
        nz = np.hypot(Z0, Z1)
        Z0, Z1, W = Z0 / nz, Z1 / nz, W / (nz * nz)
        return self._point(Z0, Z1, W), W

    def _point(self, Z0, Z1, W):
        tau, e1, e2 = self.c.tau, self.c.e1, self.c.e2
        mu = Z1[:, None] * e1 - Z0[:, None] * e2
        pb, pA, pB, pC = self.c.polys  # ascending powers of z = Z1/Z0, homogenized below
        bS = pb[0] * Z0 + pb[1] * Z1
        gS = Z0 * Z0 + Z1 * Z1
        At = [pA[0] * Z0, pA[1] * Z1]
        Bt = [pB[0] * Z0 * Z0, pB[1] * Z0 * Z1, pB[2] * Z1 * Z1]
        Ct = [pC[0] * Z0 * Z0 * Z0, pC[1] * Z0 * Z0 * Z1, pC[2] * Z0 * Z1 * Z1, pC[3] * Z1 * Z1 * Z1]
        A, B, C = sum(At), sum(Bt), sum(Ct)
        # the point's coordinate along the plane is the root w = (W - B)/A = C/(-B - W) of
        # A w^2 + 2 B w + C; of the two forms the one with the smaller rounding error bound is
        # used (not just "W - B cancels": next to a saddle B and C are small against their
        # terms, and C loses most of its digits)
        aA, aB = sum(np.abs(x) for x in At), sum(np.abs(x) for x in Bt) + np.abs(W)
        aC = sum(np.abs(x) for x in Ct)
        with np.errstate(divide="ignore", invalid="ignore"):
            err1 = (aB + np.abs(W - B) * aA / np.abs(A)) / np.abs(A)
            err2 = (aC + np.abs(C) * aB / np.abs(B + W)) / np.abs(B + W)
        second = np.nan_to_num(err2, nan=np.inf) < np.nan_to_num(err1, nan=np.inf)
        num = np.where(second, C, W - B)
        den = np.where(second, -B - W, A)
        nrm = num * num + gS * den * den
        with np.errstate(divide="ignore", invalid="ignore"):
            fac = np.where(nrm > 0, -2 * bS / nrm, 0.0)
        # at the anchor itself (the osculating plane, Z1 = 0) the formula is 0/0; the point
        # is the anchor
        fac = np.where(Z1 == 0, 0.0, fac)
        return fac[:, None] * ((num * den)[:, None] * tau + (den * den)[:, None] * mu)

    # the separatrix in s = tanh(u) (the saddle at s = +-1), for integrals along it ----------
    def separatrix_argument(self, t):
        """``s = tanh(u)``, ``u = scale (t - t_r)`` the elliptic argument, at flat times t."""
        return np.tanh(sum(self._u(t)))

    def omega_at_tanh(self, s):
        """Body-frame omega at the points ``s = tanh(u)`` in (-1, 1) of a separatrix."""
        u = np.arctanh(s)
        return (self.a * (self.m0 + self._dW_u(u, 0 * u)[0])) @ self.P.T



def elliptic_orbit(Ip, n, m0, Pbody, t_anchor=0.0, m0_mp=None, dps=34, Ip_exact=None) -> EllipticOrbit:
    """The :class:`EllipticOrbit` through ``h(t_anchor) = m0 + n`` (principal frame; ``Pbody`` principal
    -> body).  A re-anchoring point is passed in mpmath (``m0_mp``), and the exact inertia
    (``Ip_exact``), so that the curve stays the data's to the working precision: rounding it would move
    an orbit on a separatrix off it."""
    h0 = m0 + n
    Ip_exact = Ip if Ip_exact is None else Ip_exact
    c = OrbitConstants(**orbit_algebra(Ip_exact, n, m0 if m0_mp is None else m0_mp, dps))
    t_anchor = float(t_anchor)
    tr_hi, lo = two_sum(t_anchor, -c.va)
    return EllipticOrbit(Ip=Ip, a=1.0 / Ip, n=n, m0=m0, h0=h0, P=Pbody, G=_norm(h0), t_anchor=t_anchor,
                         Ip_exact=Ip_exact, c=c, tr_hi=tr_hi, tr_lo=lo - c.va_lo)


# -- the precession angle ----------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Precession:
    """The precession angle psi about the pole ``p`` (frame ``Pw``, its third axis ``p``): ``psi = nu t``
    plus a Fourier series in ``Om t`` (periodic orbit; coefficients ``d``, ``d_sum`` their sum) or a
    Chebyshev series in ``s = tanh(u)`` (separatrix, ``cheb``); ``tail`` is the series' tail (relative),
    ``nterms`` its length.  Built by :func:`precession`."""

    p: np.ndarray
    Pw: np.ndarray
    nu: float
    tail: float
    nterms: int
    Om: float = 0.0
    d: np.ndarray | None = None
    d_sum: complex = 0j
    cheb: np.ndarray | None = None

    def psi(self, orbit: EllipticOrbit, t):
        """psi at flat times t along ``orbit``."""
        if orbit.separatrix:
            C = np.polynomial.chebyshev
            s = orbit.separatrix_argument(t)
            s0 = orbit.separatrix_argument(np.zeros(1))
            per = C.chebval(s, self.cheb) - C.chebval(s0, self.cheb)
            return _angle_mod_2pi(self.nu, t, per)
        th = _angle_mod_2pi(self.Om, t, 0.0)
        z = np.exp(1j * th)
        s = np.zeros(t.shape, dtype=complex)
        for dk in self.d[::-1]:
            s = (s + dk) * z
        per = 2.0 * (s - self.d_sum).real
        return _angle_mod_2pi(self.nu, t, per)


def _pole(orbit: EllipticOrbit) -> np.ndarray:
    """Pole p maximizing min over the orbit of 1 + p.h/G (kept away from the orbit)."""
    ts = orbit.orbit_times(256)
    hs = orbit.h(ts) / orbit.G
    if orbit.separatrix:  # the saddle itself (u -> +-inf)
        big = np.array([40.0, -40.0])
        hs = np.concatenate([hs, (orbit.h0 + orbit.displacement_at_argument(big)) / orbit.G])
    cands = [np.eye(3)[i] * s for i in range(3) for s in (1, -1)]
    mean = hs.mean(axis=0)
    if np.linalg.norm(mean) > 1e-3:
        cands.append(mean / np.linalg.norm(mean))
    return max(cands, key=lambda p: np.min(1 + hs @ p))


def _psidot(orbit: EllipticOrbit, p: np.ndarray, d: np.ndarray) -> np.ndarray:
    """psi' at the displacements ``d`` (n, 3) of ``h`` from the anchor, about the pole ``p``."""
    h = orbit.h0 + d
    w = orbit.a * (orbit.m0 + d)
    hw = np.sum(h * w, -1)
    return (hw + orbit.G * (w @ p)) / (orbit.G + h @ p)


def _fourier(orbit: EllipticOrbit, p: np.ndarray) -> Precession:
    """Fourier coefficients of psi' over one period, doubling the sampling until the tail
    reaches round-off or stops decreasing (see :func:`_adaptive_series`)."""

    def coeffs(n):
        return np.fft.rfft(_psidot(orbit, p, orbit.displacement(np.arange(n) * (orbit.T / n)))) / n

    c, tail = _adaptive_series(coeffs, 2 ** 17, "Fourier series", "; orbit too close to a separatrix")
    Om = 2 * np.pi / orbit.T
    k = np.arange(1, len(c) - 1)
    d = c[1:-1] / (1j * Om * k)  # drop the Nyquist term
    return Precession(p=p, Pw=frame_with_e3(p), nu=c[0].real, tail=tail, nterms=len(d), Om=Om, d=d, d_sum=d.sum())


def _chebyshev(orbit: EllipticOrbit, p: np.ndarray) -> Precession:
    """On a separatrix: psi' is a rational function of s = tanh(u) (X = s^2, Xd is
    2 scale s (1 - s^2)) equal to the saddle's rate nu at s = +-1.  psi = nu t + phi(s) with
    phi' = (psi' - nu) / (scale (1 - s^2)): the Chebyshev interpolant of psi'(s) (to round-
    off, adaptive), less nu and its linear part at +-1 (the rounding of psi' at the saddle),
    is divided exactly by 1 - s^2 and integrated term by term."""
    C = np.polynomial.chebyshev

    def coeffs(n):
        u = np.arctanh(_cheb_nodes(n))
        return _dct2(_psidot(orbit, p, orbit.displacement_at_argument(u)))

    c, tail = _adaptive_series(coeffs, 2 ** 14, "Chebyshev series on the separatrix")
    p1, m1 = C.chebval(1.0, c), C.chebval(-1.0, c)
    nu = 0.5 * (p1 + m1)
    c[0] -= nu
    c[1] -= 0.5 * (p1 - m1)
    q, _ = C.chebdiv(c, [0.5, 0.0, -0.5])  # 1 - s^2 = (T0 - T2) / 2
    cheb = C.chebint(q) / orbit.scale
    return Precession(p=p, Pw=frame_with_e3(p), nu=nu, tail=tail, nterms=len(cheb), cheb=cheb)


def precession(orbit: EllipticOrbit) -> Precession:
    """The precession angle of ``orbit`` about the pole farthest from it (:func:`_pole`)."""
    p = _pole(orbit)
    return _chebyshev(orbit, p) if orbit.separatrix else _fourier(orbit, p)


# -- the motion --------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class EllipticMotion:
    """The generic gyrostat motion: the orbit ``h(t)``, the precession angle about a pole and the
    constant rotation ``S`` that puts ``Q_p(0) = Q0p``; ``float_error`` (relative, against mpmath and
    the data) and ``phase_error`` are the error estimates of its evaluation.  Built by
    :func:`elliptic_motion`."""

    orbit: EllipticOrbit
    prec: Precession
    S: np.ndarray
    float_error: float
    phase_error: float

    @property
    def separatrix(self) -> bool:
        return self.orbit.separatrix

    @property
    def scale(self) -> float:
        return self.orbit.scale

    @property
    def T(self) -> float:
        return self.orbit.T

    @property
    def nu(self) -> float:
        """The mean precession rate."""
        return self.prec.nu

    @property
    def fourier_tail(self) -> float:
        """The tail of the precession's series (relative)."""
        return self.prec.tail

    def psi(self, t):
        return self.prec.psi(self.orbit, t)

    def momentum(self, t):
        return self.orbit.momentum(t)

    def evaluate(self, t):
        o, Pw = self.orbit, self.prec.Pw
        d = o.displacement(t)
        w = o.a * (o.m0 + d)
        Qp = _attitude(self.S, self.psi(t), (o.h0 + d) @ Pw, Pw)
        return w @ o.P.T, Qp @ o.P.T

    def omega(self, t):
        return self.orbit.omega(t)

    def separatrix_argument(self, t):
        return self.orbit.separatrix_argument(t)

    def omega_at_tanh(self, s):
        return self.orbit.omega_at_tanh(s)


def elliptic_motion(orbit: EllipticOrbit, Q0p: np.ndarray, m_data: np.ndarray) -> EllipticMotion:
    """The motion along ``orbit`` with ``Q_p(0) = Q0p`` (principal -> space), and its errors: the
    float64 evaluation's against mpmath (:meth:`EllipticOrbit.float_errors`) and how far the formula's
    ``m(0)`` is from the data ``m_data`` (re-anchoring, rounding)."""
    prec = precession(orbit)
    h0w = prec.Pw.T @ orbit.h(np.zeros(1))[0]  # h(0) as the formula gives it
    S = Q0p @ prec.Pw @ _minimal_rotation(_unit(h0w)).T
    float_error, phase_error = orbit.float_errors()
    float_error = max(float_error, _norm(orbit.momentum(np.zeros(1))[0] - m_data) / max(_norm(m_data), 1e-300))
    return EllipticMotion(orbit=orbit, prec=prec, S=S, float_error=float_error, phase_error=phase_error)


def _dct2(f):
    """Chebyshev coefficients of the interpolant at the first-kind nodes (c_0 full weight)."""
    from scipy.fft import dct

    c = dct(f, type=2) / len(f)
    c[0] *= 0.5
    return c



def reanchor(impl, mq):
    """``impl`` (anchored at the data, ``mq`` exactly) re-anchored at a fast point of its orbit
    where the torsion does not vanish.

    Of the fastest candidates the first with a non-degenerate anchor is taken; on a nearly
    planar orbit (next to a separatrix of a nearly torque-free body, the torsion small
    everywhere) the least degenerate, and the error estimate says what is lost.  The new anchor
    came from the old pencil, whose mpmath evaluation loses digits where that pencil is
    degenerate (15-20 digits), and next to a separatrix the phase amplifies an error in the
    anchor by ~1/mc: unless the new pencil gives back the data at t = 0
    (:meth:`EllipticOrbit.gives_back`), both are redone with twice the digits."""
    best, best_ratio = None, -1.0
    for ta in impl.anchor_candidates()[:6]:
        new = impl.reanchored(ta)
        ratio = new.torsion_ratio()
        if ratio >= MIN_TORSION_RATIO:
            best = new
            break
        if ratio > best_ratio:
            best, best_ratio = new, ratio
    while not best.gives_back(mq) and best.c.mpc["dps"] <= 4000:
        first = elliptic_orbit(impl.Ip, impl.n, impl.m0, impl.P, m0_mp=mq, Ip_exact=impl.Ip_exact,
                               dps=2 * best.c.mpc["dps"])
        best = first.reanchored(best.t_anchor)
    return best

