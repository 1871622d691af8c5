"""The free gyrostat (Zhukovsky-Volterra case): (8.39)-(8.40) in closed form.

A carrier with rotors of constant axial momentum (Section 8, Corollary 8): with the rotor
momentum ``N`` (constant in the body frame) and the body angular momentum ``m = I omega``
(the paper's ``M`` of (8.33), rotor inertia about the axes folded into ``I``), (8.39)
``Mdot = [M + N, omega]`` reads ``mdot = (m + N) x omega`` and conserves (8.40)
``T = 1/2 m . omega`` and ``|h|^2 = |m + N|^2``; the total momentum ``h = m + N`` is fixed in
space (``Q h`` constant).  The attitude obeys ``Qdot = Q hat(omega)``.

Method
------
``h(t)`` runs on the intersection of the sphere ``|h| = G`` with the ellipsoid
``(h - N) . I^{-1} (h - N) = 2T``, an elliptic curve (Volterra 1899; Basak 2009 gives its
sigma-function form).  We parametrize it by the pencil of planes through the tangent line of
the orbit at an anchor point ``h_a`` (normally ``h(0)``): each plane meets the curve in two
further points, which solve a quadratic whose discriminant ``Delta(z)`` is a quartic in the
pencil parameter ``z`` (``z = 0`` is the osculating plane).  ``dt`` is the holomorphic
differential: with our normalization ``dz / dt = W``, ``W^2 = Delta(z)`` exactly (checked to
50 digits, and by the tests).  ``z(t)`` oscillates between two real zeros of ``Delta`` (a real
component of the curve meets every plane of the pencil in an even number of points), and is
inverted by Weierstrass' formula based at such a zero ``z_r`` (Whittaker & Watson 20.6):
in the pencil turned so that ``z_r`` is at 0, ``y(t) = k / (wp(t - t_r) - c)`` with
``k = Delta'/4``, ``c = Delta''/24`` there and ``wp`` of the quartic's invariants ``g2, g3``,
written with our Jacobi functions (three real roots of ``4x^3 - g2 x - g3``:
``wp = e3 + (e1 - e3)/sn^2``; one real root: the ``cn`` form).  Multiplied through by ``sn^2``
(resp. ``1 - cn``), its homogeneous numerator and denominator never vanish together.  (The
formula based at a general point, the anchor, has a numerator and a denominator with two
common zeros per period; for some data, about 3 in 100 generic ones, they lie on the real orbit,
where float64 evaluation is 0/0: energy errors up to 1e-3 of its scale next to them.)  Of the
zeros bounding the orbit the steepest is taken (next to a separatrix the other can be one of a
nearly double pair, where ``wp - c`` would cancel), and ``t_r``, the time it is reached, comes
from ``wp(t_a - t_r)`` by Carlson's ``R_F``.  The point is rebuilt from ``z`` and ``W`` (a root
of the quadratic, in whichever of its two algebraic forms has the smaller rounding bound).
Argument reduction modulo the periods is as in the Euler top.

Attitude: as for the Euler top, ``Q = S R_3(psi) B(h)`` with ``B`` the minimal rotation
taking ``h/G`` to a pole ``p`` kept away from the orbit, and
``psi' = (h . omega + G p . omega) / (G + p . h)`` (an integral of the third kind).  Its
secular rate and periodic part are taken from the Fourier series of this closed-form
periodic integrand, the coefficients computed by FFT to round-off (the series converges
geometrically; the number of terms is chosen adaptively).

Separatrix: when the cubic has a double root the parameter is ``m = 1`` exactly (or ``m = 0``:
a regular orbit on a level set with a relative equilibrium elsewhere): ``sn = tanh``,
``cn = dn = sech`` and the orbit is homoclinic to the saddle ("gyrostat/separatrix", period
``inf``).  ``psi'`` is then a rational function of ``s = tanh(u)`` equal to the saddle's rate at
``s = +-1``; ``psi - nu t`` is the integral of a Chebyshev series in ``s`` (the interpolant of
``psi'``, less its values at ``+-1``, divided exactly by ``1 - s^2``).

Numerics: the few algebraic constants (the frame, the quartic, ``g2, g3``, the cubic's
roots, the turning point and ``t_r``, ``K``) are formed in mpmath from the data exactly
(``I_i = J_j + J_k`` and ``m = I omega0`` as rationals, a power-of-two scaling by ``|h|``):
``g2, g3`` cancel, near a separatrix the parameter amplifies that by ``1/mc``, and a float64
rounding of the data would move the period there by far more than round-off.  A discriminant
that vanishes to 2000 digits is taken as exactly zero.  The residual quadratic is evaluated from
exact-coefficient polynomials in ``z`` (so that small orbits about a relative equilibrium,
``|m| << |N|``, and nearly planar orbits of nearly axisymmetric dual-spin bodies keep their
relative accuracy); ``wp - c`` as ``(e_top - c) + (wp - e_top)``, each term free of
cancellation; ``m(t)`` is carried as ``m(h_a) + (h(t) - h_a)``.

The anchor: the pencil is re-anchored (at a point of the same orbit that the closed form gives
in mpmath, unrounded) when the torsion vanishes at ``h(0)`` (a point on a symmetry plane of the
orbit: ``N`` along a principal axis and ``omega0`` in a principal plane, say), where the
formula is 0/0 where the orbit meets the osculating plane again, and when ``h(0)`` is slow (next
to a saddle): its tangent line then passes close to the saddle, and the pencil resolves the
points around it, where the orbit lingers, only to ``eps / distance`` (2e-11 was seen).  The
new anchor is a fast point where the pencil turns fastest.

Degenerate cases are separate closed forms: ``N = 0`` (or below the rounding of ``m``) is the
Euler top (:mod:`thetasol.solutions.euler_top`), ``m = 0`` rest, ``h x omega = 0`` (to the rounding of the
data) steady rotation, a spherical carrier and an axisymmetric carrier with ``N`` along its
axis are trigonometric.

Error report: ``invariants["error_estimate"]`` is the float64 evaluation's error relative to
``|m|``, per period: twice the largest difference from the same closed form in mpmath at the
data point and at the points of a dense grid where the float64 result is least trustworthy
(largest ``|dh/dtheta|``, farthest from the invariant sphere and ellipsoid, the end of the
period, a few others), plus the phase error of the rounded period (``4 eps T max|hdot|``) and
the Fourier tail of ``psi'``; a :class:`RuntimeWarning` is issued above 1e-10.  Float64
round-off is reached everywhere except on nearly planar orbits (a rotor momentum small against
``|m|`` next to the Euler top's separatrix, where the torsion of the orbit is small everywhere
and every pencil of planes through a line meeting the curve twice degenerates): there the loss
grows like ``eps / torsion ratio`` and the estimate reports it (``J = (2, 0.25, 1)``,
``omega0 = (0, 0, 1)``, ``N = (0, n, 0)``, the error of ``m`` relative to ``max |m|`` on 4001
times of one period against quadruple heyoka: 3.4e-12 at ``n = 1e-3``, 3.6e-10 at ``1e-4``,
1.6e-6 at ``1e-6``; estimated 5.4e-12, 4.6e-10, 2.9e-6).  Orbits within 1e-307 (but not exactly
on) a separatrix, and motions within 1e-60 (relative) of a relative equilibrium, raise
:class:`NotImplementedError`.  There is no ``dps=`` path.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from thetasol.core import validate as V
from thetasol.special import elliptic as _el
from thetasol.core.attitude import (angle_mod_2pi as _angle_mod_2pi, attitude_from_precession as _attitude,
                                     minimal_rotation as _minimal_rotation, norm3 as _norm,
                                     principal_frame as _principal_frame, rotation_about_axis as _rot_about,
                                     uniform_rotation as _uniform_rotation, unit_rows as _unit)
from thetasol.solutions.rotation import RotationSolution, solve_rotation

__all__ = ["GyrostatSolution", "solve_gyrostat"]

_EPS = np.finfo(float).eps
#: An anchor whose torsion rate is below this fraction of its maximum over the orbit is degenerate.
_MIN_TORSION_RATIO = 1e-2


@dataclass(frozen=True, eq=False)
class GyrostatSolution(RotationSolution):
    """Closed-form motion of a free gyrostat; built by :func:`solve_gyrostat`.

    Besides the :class:`~thetasol.RotationSolution` protocol it has ``N`` (the rotor
    momentum, body frame) and ``h(t)`` (the total body momentum ``I omega + N``).
    """

    N: np.ndarray = None
    _impl: object = field(default=None, repr=False)

    def _evaluate(self, t):
        return self._impl.evaluate(t)

    def _omega(self, t):
        return self._impl.omega(t)

    def h(self, t):
        """Total angular momentum in the body frame, ``I omega + N``, shape ``t.shape + (3,)``."""
        return self.m(t) + self.N


# -- helpers ----------------------------------------------------------------------------------

def _frame_with_e3(p):
    """A rotation P with P e_3 = p (columns: an orthonormal frame ending with p)."""
    p = p / np.linalg.norm(p)
    k = int(np.argmin(np.abs(p)))
    e = np.zeros(3)
    e[k] = 1.0
    x = np.cross(e, p)
    x /= np.linalg.norm(x)
    y = np.cross(p, x)
    return np.stack([x, y, p], axis=1)


def _algebra(Ip, n, m0, dps=34):
    """See :func:`_algebra_at`; the precision is raised until the discriminant of the
    Weierstrass cubic is resolved (tiny orbits about a relative equilibrium make g2, g3
    nearly cancel).  A discriminant that vanishes to 2000 digits is taken as exactly zero:
    an orbit on a separatrix (or a regular orbit on a singular level set)."""
    while True:
        try:
            return _algebra_at(Ip, n, m0, dps, exact=dps > 2000)
        except _NeedDigits:
            dps *= 2


class _NeedDigits(Exception):
    pass


def _cubic_roots_mp(mp, g2, g3):
    """Real roots of 4x^3 - g2 x - g3 (three when g2^3 > 27 g3^2, else the one real root):
    trigonometric / Cardano forms, then two Newton steps (mpmath scalars)."""
    p, q = -g2 / 4, -g3 / 4  # x^3 + p x + q
    D = q * q / 4 + p ** 3 / 27
    if D < 0:
        r = 2 * mp.sqrt(-p / 3)
        phi = mp.acos(max(-1, min(1, (3 * q / (2 * p)) * mp.sqrt(-3 / p)))) / 3
        xs = [r * mp.cos(phi - 2 * mp.pi * k / 3) for k in range(3)]
    else:
        sD = mp.sqrt(D)
        u = mp.cbrt(-q / 2 + sD) if -q / 2 + sD >= 0 else -mp.cbrt(q / 2 - sD)
        v = mp.cbrt(-q / 2 - sD) if -q / 2 - sD >= 0 else -mp.cbrt(q / 2 + sD)
        xs = [u + v]
    out = []
    for x in xs:
        for _ in range(2):
            d = 12 * x * x - g2
            if d != 0:
                x = x - (4 * x ** 3 - g2 * x - g3) / d
        out.append(x)
    return out


def _mpq(mp, x):
    """An mpmath number from a float, an mpf or an exact Fraction (exact when the working
    precision holds it)."""
    if isinstance(x, Fraction):
        return mp.mpf(x.numerator) / x.denominator
    return mp.mpf(x)


def _pmul(p, q):
    r = [0] * (len(p) + len(q) - 1)
    for i, x in enumerate(p):
        for j, y in enumerate(q):
            r[i + j] += x * y
    return r


def _psub(p, q):
    L = max(len(p), len(q))
    p = list(p) + [0] * (L - len(p))
    q = list(q) + [0] * (L - len(q))
    return [x - y for x, y in zip(p, q)]


def _rotate_quartic(f, c, s):
    """Ascending coefficients in y of ``Dh(c - s y, s + c y)``, ``Dh(Z0, Z1) = sum f_k Z1^k Z0^(4-k)``
    the homogeneous form of the quartic ``f`` (ascending): the pencil turned by the angle
    ``(c, s) = (cos, sin)``."""
    out = [0] * 5
    for k in range(5):
        p = [f[k]]
        for _ in range(k):
            p = _pmul(p, [s, c])
        for _ in range(4 - k):
            p = _pmul(p, [c, -s])
        for i, x in enumerate(p):
            out[i] += x
    return out


def _turning_point(mp, f, s0, e_top, roots):
    """The pencil angle ``theta_r`` of a turning point of ``theta(t)`` next to the anchor
    (``theta = 0``), and the time from it to the anchor.

    ``theta(t)`` oscillates between the two real zeros of ``Dh(cos theta, sin theta)`` adjacent
    to 0 (the real orbit always has turning points: a real component of the curve meets every
    plane of the pencil in an even number of points).  The real zeros are tried by decreasing
    slope of ``Dh`` (next to a separatrix a zero can be one of a nearly double pair, where the
    formula below would cancel); a zero bounding the other real component is recognized by
    ``wp(t_a - t_r) < e_top`` and skipped.  In the pencil turned by ``theta_r`` the quartic has a root
    at 0 and (Whittaker & Watson 20.6, base point at a root)
    ``y(t) = k / (wp(t - t_r) - c)``, ``k = Dr'(0)/4``, ``c = Dr''(0)/24``: numerator and
    denominator never vanish together (the general base point of W&W's formula gives a
    numerator and a denominator with two common zeros per period, on the real orbit for some
    data, where float64 evaluation is 0/0).  The anchor ``y_a = -tan theta_r`` gives
    ``wp(t_a - t_r) = c + k / y_a``, inverted with Carlson's ``R_F``; the sign of ``t_a - t_r``
    is that of ``k dy/dt`` (``wp' < 0`` on the real half-period), ``dy/dt`` having the sign of
    ``dtheta/dt = s0`` at the anchor.
    """
    # zeros of Dh on the unit circle, located at moderate precision (in a turned pencil whose
    # leading coefficient is large; a double zero, on a separatrix, converges only linearly)
    # and polished by Newton's method at the working precision
    dps = mp.mp.dps
    with mp.workdps(min(dps, 50)):
        best = None
        for j in range(4):
            phi = mp.pi * j / 4
            fr = _rotate_quartic(f, mp.cos(phi), mp.sin(phi))
            if best is None or abs(fr[4]) > abs(best[1][4]):
                best = (phi, fr)
        phi, fr = best
        ys = mp.polyroots(fr[::-1], maxsteps=2000, extraprec=2 * mp.mp.prec)
        ths = [+((phi + mp.atan(mp.re(y))) % mp.pi) for y in ys if abs(mp.im(y)) <= 1e-20 * (1 + abs(y))]
        ths = [th - mp.pi if th > mp.pi / 2 else th for th in ths]
        slopes = [abs(_rotate_quartic(f, mp.cos(th), mp.sin(th))[1]) for th in ths]
    tol = mp.mpf(10) ** (-(dps // 2))

    def polish(th):  # Newton on Dh(cos th, sin th) = 0, doubling the precision each step
        prec = 40
        while True:
            prec = min(2 * prec, dps)
            with mp.workdps(prec + 10):
                c, s = mp.cos(th), mp.sin(th)
                v = sum(f[k] * s ** k * c ** (4 - k) for k in range(5))
                dv = sum(f[k] * (k * s ** (k - 1) * c ** (5 - k) if k else 0)
                         - f[k] * (4 - k) * s ** (k + 1) * c ** (3 - k) for k in range(5))
                if dv != 0:
                    th = th - v / dv
            if prec >= dps:
                return +th

    # every real zero is a turning point of this orbit or of the other real component (then the
    # anchor is not on its arc: wp(t_a - t_r) < e_top); the steepest of this orbit's is taken
    etol = tol * max(abs(x) for x in roots)
    for _, th in sorted(zip(slopes, ths), key=lambda x: -x[0]):
        th = polish(polish(th))
        dr = _rotate_quartic(f, mp.cos(th), mp.sin(th))
        k, c = dr[1] / 4, dr[2] / 12
        if k == 0:
            continue
        if abs(th) <= tol:  # the anchor is itself a turning point (zero torsion)
            return th, k, c, mp.mpf(0)
        Pa = c - k * mp.cos(th) / mp.sin(th)
        if Pa < e_top - etol:
            continue
        Pa = max(Pa, e_top)
        va = mp.re(mp.elliprf(Pa - roots[0], Pa - roots[1], Pa - roots[2]))
        if (k > 0) != (s0 > 0):
            va = -va
        return th, k, c, va
    raise RuntimeError("internal: the turning point of the pencil parameter was not found")


def _algebra_at(Ip, n, m0, dps, exact=False):
    """Frame, quartic, Weierstrass invariants, the turning point and the elliptic parameters,
    in mpmath.

    The invariants ``g2, g3`` are sums of products that cancel (they lose 2-3 digits) and
    the parameter ``mc`` of an orbit near a separatrix amplifies that loss by ``1/mc``; so
    these few scalars are formed at ``dps`` digits from the (exact) float data and rounded.
    With ``exact`` a discriminant below the working precision is taken as zero (a double
    root of the cubic: ``m = 1``, the separatrix, or ``m = 0``).
    Returns floats (and float vectors) and, under ``"mpc"``, the same in mpmath.
    """
    import mpmath as mp

    with mp.workdps(dps):
        # the data exactly (Ip and m0 as exact rationals from the float data, or an mpmath
        # re-anchoring point), not their float64 roundings: the curve, its period and a
        # separatrix are the data's
        A_ = [1 / _mpq(mp, x) for x in Ip]
        mm = [_mpq(mp, x) for x in m0]
        nn = [_mpq(mp, x) for x in n]
        h = [mm[k] + nn[k] for k in range(3)]  # exact: no loss of a small m against a large N

        def cross(u, v):
            return [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]

        def dot(u, v):
            return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]

        def lin(*terms):  # sum of c_i u_i
            return [sum(c * u[k] for c, u in terms) for k in range(3)]

        def av(u):
            return [A_[k] * u[k] for k in range(3)]

        w = av(mm)
        h1 = cross(h, w)
        h2 = lin((1, cross(h1, w)), (1, cross(h, av(h1))))
        n1 = mp.sqrt(dot(h1, h1))
        if n1 == 0:
            raise ValueError("internal: a steady state reached the elliptic branch")
        tau = [x / n1 for x in h1]
        e2 = lin((1, h2), (-dot(h2, tau), tau))
        e2 = [x / mp.sqrt(dot(e2, e2)) for x in e2]
        e1 = cross(e2, tau)
        alphaE = dot(tau, av(tau))
        mu0 = [-x for x in e2]
        mu1 = e1
        bS = [dot(h, mu0), dot(h, mu1)]
        bE = [dot(w, mu0), dot(w, mu1)]
        dE = [dot(tau, av(mu0)), dot(tau, av(mu1))]
        gS = [1, 0, 1]
        gE = [dot(mu0, av(mu0)), 2 * dot(mu0, av(mu1)), dot(mu1, av(mu1))]
        A = _psub(_pmul(bS, [alphaE]), bE)
        B = _pmul(bS, dE)
        C = _psub(_pmul(bS, gE), _pmul(bE, gS))
        D = _psub(_pmul(B, B), _pmul(A, C))
        f = (D + [0] * 5)[:5]
        # dz/dt = W with W^2 = Delta(z) = B^2 - A C (z = Z1/Z0 the pencil parameter, z = 0 the
        # osculating plane at h(0)): the constant in dt = kappa dz / W is exactly 1 for this
        # normalization (checked to 50 digits on random data, and by the tests against
        # integration), and zdot(0) = -B(0) (our point is the root of the quadratic that runs to
        # infinity on the osculating plane).
        zdot0 = -B[0]
        a4, a3, a2, a1, a0 = f[0], f[1] / 4, f[2] / 6, f[3] / 4, f[4]
        g2 = a0 * a4 - 4 * a1 * a3 + 3 * a2 ** 2
        g3 = a0 * a2 * a4 + 2 * a1 * a2 * a3 - a2 ** 3 - a0 * a3 ** 2 - a1 ** 2 * a4
        disc = g2 ** 3 - 27 * g3 ** 2
        if abs(disc) <= mp.mpf(10) ** (8 - dps) * (abs(g2) ** 3 + 27 * g3 ** 2):
            if not exact:
                raise _NeedDigits
            disc = 0
        out = {}
        if disc > 0:
            r = sorted(_cubic_roots_mp(mp, g2, g3), reverse=True)
        elif disc == 0:
            if g2 == 0:
                raise NotImplementedError("solve_gyrostat: a triple root of the Weierstrass cubic "
                                          "(degenerate orbit); not supported")
            ed = -3 * g3 / (2 * g2)  # 4x^3 - g2 x - g3 = 4 (x - ed)^2 (x + 2 ed)
            r = [ed, ed, -2 * ed] if ed > 0 else [-2 * ed, ed, ed]
        if disc >= 0:
            beta = r[0] - r[2]
            m, mc = (r[1] - r[2]) / beta, (r[0] - r[1]) / beta
            scale = mp.sqrt(beta)
            T = 2 * mp.ellipk(m) / scale if mc > 0 else mp.inf
            out.update(kind=3, p1=r[2], p0=beta, T=T)
            roots, e_top = r, r[0]
        else:
            e2r = _cubic_roots_mp(mp, g2, g3)[0]
            H = mp.sqrt(3 * e2r ** 2 - g2 / 4)
            m, mc = mp.mpf(1) / 2 - 3 * e2r / (4 * H), mp.mpf(1) / 2 + 3 * e2r / (4 * H)
            scale = 2 * mp.sqrt(H)
            out.update(kind=1, p1=e2r - H, p0=2 * H, T=4 * mp.ellipk(m) / scale)
            ei = mp.sqrt(3 * e2r ** 2 - g2) / 2
            roots, e_top = [mp.mpc(-e2r / 2, ei), e2r, mp.mpc(-e2r / 2, -ei)], e2r
        # next to a double root the cubic's close roots, hence m and mc, carry the rounding of
        # g2, g3 amplified by 1/min(m, mc)^2: work with enough digits for float64-accurate m, mc
        small = min(m, mc)
        if not exact and small > mp.mpf(2) ** -1020 and mp.mpf(10) ** -dps > mp.mpf(10) ** -20 * small ** 2:
            raise _NeedDigits
        if mc != 0 and (mc <= mp.mpf(2) ** -1020 or not mp.isfinite(out["T"])):
            raise NotImplementedError("solve_gyrostat: the orbit is within 1e-307 (mc = "
                                      f"{mp.nstr(mc, 3)}) of a separatrix of the gyrostat, "
                                      "closer than float64 resolves; not supported")
        th, k, cq, va = _turning_point(mp, f, zdot0, e_top, roots)
        # qe = e_top - c: wp - c = qe + (wp - e_top), both terms >= 0 unless y passes infinity
        out.update(m=m, mc=mc, scale=scale, s0=zdot0, k=k, qe=e_top - cq, g2=g2, g3=g3,
                   cr=mp.cos(th), sr=mp.sin(th), va=va)
        res = {k_: (int(v) if k_ == "kind" else float(v)) for k_, v in out.items()}
        res["va_lo"] = float(va - res["va"])
        # the residual quadratic's coefficients as exact-coefficient polynomials in z: evaluated
        # near their roots (a small orbit about a relative equilibrium, |m| << |N|) they keep
        # their relative accuracy, which dot products of O(|h|) vectors would not
        res["polys"] = tuple(np.array([float(x) for x in (P + [0] * 4)[:k_]])
                             for P, k_ in ((bS, 2), (A, 2), (B, 3), (C, 4)))
        res["tau"] = np.array([float(x) for x in tau])
        res["e1"] = np.array([float(x) for x in e1])
        res["e2"] = np.array([float(x) for x in e2])
        res["mpc"] = dict(out, polys=(bS, A, B, C), tau=tau, e1=e1, e2=e2, m0=mm, dps=dps)
        return res


# -- the generic (elliptic) motion ------------------------------------------------------------

def _adaptive_series(coeffs, nmax, what, why=""):
    """``coeffs(n)``, the series of ``psi'`` from ``n`` samples, for ``n = 64, 128, ...`` until
    its tail (the last quarter of the coefficients) reaches round-off or stops decreasing (the
    samples' own rounding noise), at most ``nmax`` samples.  Returns the coefficients and the
    tail relative to the largest; a tail above 1e-9 raises :class:`NotImplementedError`."""
    n, prev = 64, np.inf
    while True:
        c = coeffs(n)
        scale = np.max(np.abs(c))
        tail = np.max(np.abs(c[3 * len(c) // 4:]))
        if tail <= 4 * _EPS * scale or (tail > 0.5 * prev and tail < 1e-11 * scale) or n >= nmax:
            break
        prev = tail
        n *= 2
    if tail / scale > 1e-9:
        raise NotImplementedError(f"solve_gyrostat: the precession angle's {what} does not converge "
                                  f"(tail {tail / scale:.1e}{why})")
    return c, tail / scale


def _cheb_nodes(n):
    return np.cos(np.pi * (np.arange(n) + 0.5) / n)


class _Elliptic:
    """h(t) by the tangent-line pencil and Weierstrass' inversion based at a turning point;
    psi by Fourier series (periodic orbit) or by a Chebyshev series in ``tanh`` (separatrix)."""

    def __init__(self, Ip, n, m0, Pbody, t_anchor=0.0, m0_mp=None, dps=34, Ip_exact=None):
        # the state is carried as m = m0 + Delta(t) (Delta the displacement of h from the
        # anchor h(t_anchor) = m0 + N), so that omega = a m keeps its relative accuracy when
        # |m| << |N| (fast rotors)
        h0 = m0 + n
        self.Ip, self.a, self.n, self.m0, self.h0 = Ip, 1.0 / Ip, n, m0, h0
        self.P = Pbody  # principal -> body
        self.G = _norm(h0)
        self.t_anchor = float(t_anchor)
        # (a re-anchoring point is passed in mpmath, so that the curve stays the data's to the
        # working precision: rounding it would move an orbit on a separatrix off it)
        self.Ip_exact = Ip if Ip_exact is None else Ip_exact
        c = _algebra(self.Ip_exact, n, m0 if m0_mp is None else m0_mp, dps)
        for k, v in c.items():
            setattr(self, k, v)
        self.separatrix = self.mc == 0.0
        # the time origin of the formula, t_r = t_anchor - v_a, as a double-double
        self.tr_hi, lo = _el._two_sum(self.t_anchor, -self.va)
        self.tr_lo = lo - self.va_lo

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

        c = self.mpc
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

    def check_float_against_mp(self):
        """Error of the float64 evaluation, relative to |m(0)|.

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
        # (digits enough for float64 accuracy of m, mc; an exactly degenerate orbit was set up
        # at 2000 digits, which this comparison does not need)
        small = min(self.m, self.mc)
        dps = min(self.mpc["dps"], 50 + (int(-2 * np.log10(small)) if small > 0 else 0))
        self.float_error = 2 * max(_norm(mf[i] - self.momentum_mp(float(tp), near=mf[i], dps=dps))
                                   for i, tp in enumerate(pick)) / scale
        if self.separatrix:
            u = np.abs(sum(self._u(ts)))
            self.phase_error = 2 * _EPS * np.max(u * hdot) / (self.scale * scale)
        else:
            self.phase_error = 4 * _EPS * self.T * np.max(hdot) / scale

    def reanchored(self, ta):
        """The same orbit with the pencil anchored at time ``ta``, at the point this closed form
        gives there in mpmath (not rounded: the curve stays the data's to the working precision)."""
        ma = self.momentum_mp(float(ta), as_mp=True)
        return _Elliptic(self.Ip, self.n, np.array([float(x) for x in ma]), self.P, t_anchor=float(ta),
                         m0_mp=ma, dps=self.mpc["dps"], Ip_exact=self.Ip_exact)

    def gives_back(self, mq) -> bool:
        """m(0) in mpmath equals the exact data ``mq`` to 1e-20 min(m, mc) (an exactly degenerate
        orbit: to the working precision less 40 digits)."""
        import mpmath as mp

        dps = self.mpc["dps"]
        with mp.workdps(dps):
            back = self.momentum_mp(0.0, as_mp=True)
            mis = max(abs(back[k] - _mpq(mp, mq[k])) for k in range(3)) / max(abs(_mpq(mp, x)) for x in mq)
            small = min(self.mpc["m"], self.mpc["mc"])
            return mis <= (mp.mpf(10) ** -20 * small if small > 0 else mp.mpf(10) ** (40 - dps))

    def anchor_is_slow(self) -> bool:
        """h(0) is much slower than the fast part of the orbit (next to a saddle)."""
        v0, v = self.speed(np.array([self.t_anchor]))[0], self.speed(self.orbit_times(64))
        return not (np.isfinite(v0) and np.all(np.isfinite(v))) or v0 < 0.25 * np.max(v)

    def torsion_ratio(self) -> float:
        """|dtheta/dt| at the anchor against its maximum over the orbit (0 when a value on the
        orbit is not finite: the formula is 0/0 somewhere)."""
        W = np.abs(self._dW(self.orbit_times(64))[1])
        return abs(self.s0) / np.max(W) if np.all(np.isfinite(W)) and np.max(W) > 0 else 0.0

    def anchor_is_degenerate(self) -> bool:
        """The orbit's torsion (nearly) vanishes at the anchor: dtheta_Z/dt = s0 ~ 0 there, and
        the pencil formula becomes 0/0 where the orbit meets the osculating plane again."""
        return self.torsion_ratio() < _MIN_TORSION_RATIO

    def finish(self):
        self._pole()
        if self.separatrix:
            self._chebyshev()
        else:
            self._fourier()

    # momentum --------------------------------------------------------------------------
    def h(self, t):
        return self.h0 + self._dW(t)[0]

    def momentum(self, t):
        return self.m0 + self._dW(t)[0]

    def _u(self, t):
        """The elliptic argument scale (t - t_r) as a double-double (hi, lo)."""
        d_hi, d_lo = _el._two_sum(t, -self.tr_hi)
        hi, lo = _el._two_prod(self.scale, d_hi)
        return hi, lo + self.scale * (d_lo - self.tr_lo)

    def _dW(self, t):
        """Delta(t) = h(t) - h(0) and the homogeneous W (unit (Z0, Z1)): dtheta_Z/dt = W."""
        return self._dW_u(*self._u(t))

    def _dW_u(self, hi, lo):
        """The state at the elliptic argument ``u = hi + lo = scale (t - t_r)``."""
        sn, cn, dn, _ = _el._ellipj_reduced(hi, lo, np.full(hi.shape, self.m), np.full(hi.shape, self.mc))
        sc = self.scale
        # y = k / (wp - c) in the pencil turned by theta_r, wp = p1 + p0 / X, multiplied by X:
        # X (wp - c) = qe X + X (wp - e_top), the second term in a form free of cancellation
        # (next to a saddle wp - e_top is small and c nearly e_top: q1 X + p0 would cancel)
        if self.kind == 3:  # wp = e3 + (e1 - e3) / sn^2
            X = sn * sn
            Xd = 2 * sn * cn * dn * sc
            Z0p = self.qe * X + self.p0 * (cn * cn)
        else:  # wp = e2 + H (1 + cn) / (1 - cn), p0 = 2 H
            with np.errstate(divide="ignore", invalid="ignore"):
                X = np.where(cn > 0, sn * sn / (1 + cn), 1 - cn)
                Y = np.where(cn < 0, sn * sn / (1 - cn), 1 + cn)
            Xd = sc * sn * dn
            Z0p = self.qe * X + (0.5 * self.p0) * Y
        Z1p = self.k * X
        W = self.k * self.p0 * Xd  # the Wronskian Z0 Z1' - Z1 Z0' (invariant under the turn)
        Z0 = self.cr * Z0p - self.sr * Z1p
        Z1 = self.sr * Z0p + self.cr * Z1p
        nz = np.hypot(Z0, Z1)
        Z0, Z1, W = Z0 / nz, Z1 / nz, W / (nz * nz)
        return self._point(Z0, Z1, W), W

    def _point(self, Z0, Z1, W):
        tau, e1, e2 = self.tau, self.e1, self.e2
        mu = Z1[:, None] * e1 - Z0[:, None] * e2
        pb, pA, pB, pC = self.polys  # ascending powers of z = Z1/Z0, homogenized below
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

    # attitude --------------------------------------------------------------------------
    def _pole(self):
        """Pole p maximizing min over the orbit of 1 + p.h/G (kept away from the orbit)."""
        ts = self.orbit_times(256)
        hs = (self.h0 + self._dW(ts)[0]) / self.G
        if self.separatrix:  # the saddle itself (u -> +-inf)
            big = np.array([40.0, -40.0])
            hs = np.concatenate([hs, (self.h0 + self._dW_u(big, 0 * big)[0]) / self.G])
        cands = [np.eye(3)[i] * s for i in range(3) for s in (1, -1)]
        mean = hs.mean(axis=0)
        if np.linalg.norm(mean) > 1e-3:
            cands.append(mean / np.linalg.norm(mean))
        best = max(cands, key=lambda p: np.min(1 + hs @ p))
        self.p = best
        self.Pw = _frame_with_e3(best)

    def _psidot_d(self, d):
        h = self.h0 + d
        w = self.a * (self.m0 + d)
        hw = np.sum(h * w, -1)
        return (hw + self.G * (w @ self.p)) / (self.G + h @ self.p)

    def _fourier(self):
        """Fourier coefficients of psi' over one period, doubling the sampling until the tail
        reaches round-off or stops decreasing (see :func:`_adaptive_series`)."""

        def coeffs(n):
            return np.fft.rfft(self._psidot_d(self._dW(np.arange(n) * (self.T / n))[0])) / n

        c, self.fourier_tail = _adaptive_series(
            coeffs, 2 ** 17, "Fourier series", "; orbit too close to a separatrix")
        self.nu = c[0].real
        Om = 2 * np.pi / self.T
        k = np.arange(1, len(c) - 1)
        self.Om = Om
        self.d = c[1:-1] / (1j * Om * k)  # drop the Nyquist term
        self.d_sum = self.d.sum()
        self.nterms = len(self.d)

    def _chebyshev(self):
        """On a separatrix: psi' is a rational function of s = tanh(u) (X = s^2, Xd is
        2 scale s (1 - s^2)) equal to the saddle's rate nu at s = +-1.  psi = nu t + phi(s) with
        phi' = (psi' - nu) / (scale (1 - s^2)): the Chebyshev interpolant of psi'(s) (to round-
        off, adaptive), less nu and its linear part at +-1 (the rounding of psi' at the saddle),
        is divided exactly by 1 - s^2 and integrated term by term."""
        C = np.polynomial.chebyshev

        def coeffs(n):
            u = np.arctanh(_cheb_nodes(n))
            return _dct2(self._psidot_d(self._dW_u(u, 0 * u)[0]))

        c, self.fourier_tail = _adaptive_series(coeffs, 2 ** 14, "Chebyshev series on the separatrix")
        p1, m1 = C.chebval(1.0, c), C.chebval(-1.0, c)
        self.nu = 0.5 * (p1 + m1)
        c[0] -= self.nu
        c[1] -= 0.5 * (p1 - m1)
        q, _ = C.chebdiv(c, [0.5, 0.0, -0.5])  # 1 - s^2 = (T0 - T2) / 2
        self.cheb = C.chebint(q) / self.scale
        self.nterms = len(self.cheb)

    def psi(self, t):
        if self.separatrix:
            C = np.polynomial.chebyshev
            s = np.tanh(sum(self._u(t)))
            s0 = np.tanh(sum(self._u(np.zeros(1))))
            per = C.chebval(s, self.cheb) - C.chebval(s0, self.cheb)
            return _angle_mod_2pi(self.nu, t, per)
        th = _angle_mod_2pi(self.Om, t, 0.0)
        z = np.exp(1j * th)
        s = np.zeros(t.shape, dtype=complex)
        for dk in self.d[::-1]:
            s = (s + dk) * z
        per = 2.0 * (s - self.d_sum).real
        return _angle_mod_2pi(self.nu, t, per)

    def setup_attitude(self, Q0p):
        """S such that Q_p(0) = Q0p (principal -> space)."""
        h0w = self.Pw.T @ self.h(np.zeros(1))[0]  # h(0) as the formula gives it
        B0 = _minimal_rotation(_unit(h0w))
        self.S = Q0p @ self.Pw @ B0.T

    def evaluate(self, t):
        d = self._dW(t)[0]
        w = self.a * (self.m0 + d)
        Qp = _attitude(self.S, self.psi(t), (self.h0 + d) @ self.Pw, self.Pw)
        return w @ self.P.T, Qp @ self.P.T

    def omega(self, t):
        return (self.a * self.momentum(t)) @ self.P.T


def _dct2(f):
    """Chebyshev coefficients of the interpolant at the first-kind nodes (c_0 full weight)."""
    from scipy.fft import dct

    c = dct(f, type=2) / len(f)
    c[0] *= 0.5
    return c


class _Steady:
    def __init__(self, Q0, w0):
        self.Q0, self.w0 = Q0, w0

    def evaluate(self, t):
        return _uniform_rotation(self.Q0, self.w0, t)

    def omega(self, t):
        return np.broadcast_to(self.w0, (t.size, 3)).copy()


class _Sphere:
    """Spherical carrier: m rotates about N at rate |N|/I; Q = R(L, G t/I) Q0 R(N, -|N| t/I)."""

    def __init__(self, I, n, Q0, w0):
        self.I, self.n, self.Q0, self.w0 = I, n, Q0, w0
        m0 = I * w0
        h0 = m0 + n
        self.G = _norm(h0)
        self.L = Q0 @ h0 / self.G
        self.nn = _norm(n)
        self.nh = n / self.nn

    def evaluate(self, t):
        a1 = _angle_mod_2pi(self.nn / self.I, t, 0.0)
        E = _rot_about(self.nh, a1)
        w = np.einsum("nij,j->ni", E, self.w0)
        a2 = _angle_mod_2pi(self.G / self.I, t, 0.0)
        Q = _rot_about(self.L, a2) @ self.Q0 @ np.swapaxes(E, -1, -2)
        return w, Q

    def omega(self, t):
        return self.evaluate(t)[0]


class _Axisymmetric:
    """Carrier symmetric about principal axis c with N along it (dual-spin): trigonometric.

    ``m_c`` is constant, ``(m_a, m_b)`` turn at ``Omega = (m_c + N_c)/I_1 - m_c/I_c``; with the
    pole on the symmetry axis ``psi' = (h.omega + G omega_c)/(G + h_c)`` is constant.
    """

    def __init__(self, Ip, n, m, c, Q0p, P):
        a_, b_ = [i for i in range(3) if i != c]
        self.c, self.ab = c, (a_, b_)
        self.Ip, self.n, self.m0, self.P = Ip, n, m, P
        h0 = m + n
        self.G = _norm(h0)
        s = 1.0 if h0[c] >= 0 else -1.0
        pole = np.zeros(3)
        pole[c] = s
        self.pole = pole
        self.Pw = _frame_with_e3(pole)
        I1, Ic = Ip[a_], Ip[c]
        self.Om = (m[c] + n[c]) / I1 - m[c] / Ic
        w = m / Ip
        self.psidot = (h0 @ w + self.G * (w @ pole)) / (self.G + h0 @ pole)
        B0 = _minimal_rotation(_unit(self.Pw.T @ h0))
        self.S = Q0p @ self.Pw @ B0.T

    def _m(self, t):
        ang = _angle_mod_2pi(self.Om, t, 0.0)
        a_, b_ = self.ab
        # d/dt (m_a, m_b) = Omega (-m_b, m_a) when (a, b, c) is cyclic, the opposite otherwise
        sgn = 1.0 if (b_ - a_) % 3 == 1 else -1.0
        ca, sa = np.cos(ang), sgn * np.sin(ang)
        m = np.empty(t.shape + (3,))
        m[:, a_] = ca * self.m0[a_] - sa * self.m0[b_]
        m[:, b_] = sa * self.m0[a_] + ca * self.m0[b_]
        m[:, self.c] = self.m0[self.c]
        return m

    def evaluate(self, t):
        m = self._m(t)
        psi = _angle_mod_2pi(self.psidot, t, 0.0)
        Qp = _attitude(self.S, psi, (m + self.n) @ self.Pw, self.Pw)
        return (m / self.Ip) @ self.P.T, Qp @ self.P.T

    def omega(self, t):
        return (self._m(t) / self.Ip) @ self.P.T


class _Delegate:
    def __init__(self, sol):
        self.sol = sol

    def evaluate(self, t):
        return self.sol._evaluate(t)

    def omega(self, t):
        return self.sol._omega(t)


def _reanchor(impl, mq):
    """``impl`` (anchored at the data, ``mq`` exactly) re-anchored at a fast point of its orbit
    where the torsion does not vanish.

    Of the fastest candidates the first with a non-degenerate anchor is taken; on a nearly
    planar orbit (next to a separatrix of a nearly torque-free body, the torsion small
    everywhere) the least degenerate, and the error estimate says what is lost.  The new anchor
    came from the old pencil, whose mpmath evaluation loses digits where that pencil is
    degenerate (15-20 were seen), and next to a separatrix the phase amplifies an error in the
    anchor by ~1/mc: unless the new pencil gives back the data at t = 0
    (:meth:`_Elliptic.gives_back`), both are redone with twice the digits."""
    best, best_ratio = None, -1.0
    for ta in impl.anchor_candidates()[:6]:
        new = impl.reanchored(ta)
        ratio = new.torsion_ratio()
        if ratio >= _MIN_TORSION_RATIO:
            best = new
            break
        if ratio > best_ratio:
            best, best_ratio = new, ratio
    while not best.gives_back(mq) and best.mpc["dps"] <= 4000:
        first = _Elliptic(impl.Ip, impl.n, impl.m0, impl.P, m0_mp=mq, Ip_exact=impl.Ip_exact,
                          dps=2 * best.mpc["dps"])
        best = first.reanchored(best.t_anchor)
    return best


# -- entry point -------------------------------------------------------------------------------

def solve_gyrostat(J, N, Q0, omega0) -> GyrostatSolution:
    """Exact motion of a free gyrostat, (8.39)-(8.40) (Zhukovsky-Volterra case).

    Parameters
    ----------
    J : array_like, shape (3,) or (3, 3)
        Second moments of the gyrostat with its rotors locked (``I = tr(J) 1 - J`` is the
        inertia in ``m = I omega``, the paper's (8.33) with the rotor terms folded in).
    N : array_like, shape (3,)
        Constant rotor angular momentum in the body frame (the paper's ``N_k``).
    Q0 : array_like, shape (3, 3)
        Initial attitude, body to space.
    omega0 : array_like, shape (3,)
        Initial body angular velocity of the carrier.

    Returns
    -------
    GyrostatSolution
        The :class:`~thetasol.RotationSolution` protocol (``omega(t)``, ``Q(t)``, ``M(t)``,
        ``u(t)``, ``method``, ``invariants``) plus ``N`` and ``h(t)``.  ``invariants`` has
        ``energy`` (``1/2 m . omega``), ``H`` ((8.40): ``1/2 tr(M omega) = -2 energy``),
        ``H2`` ((8.40): ``tr (M + N)^2 = -2 |h|^2``), ``h2 = |h|^2``, ``period`` (of
        ``omega``; 0 when constant, ``inf`` on a separatrix), ``precession_rate`` (the mean
        rate; on a separatrix the saddle's) and ``error_estimate`` (relative error of
        ``m(t)`` per period, see the module notes).  ``method`` is one of
        ``gyrostat/elliptic``, ``gyrostat/separatrix``, ``gyrostat/steady``,
        ``gyrostat/sphere``, ``gyrostat/axisymmetric``, ``rest`` or the Euler top's.

    Raises
    ------
    ValueError
        Bad data (non-finite, wrong shapes, unphysical ``J``, ``Q0`` not a rotation).
    NotImplementedError
        An orbit within 1e-307 of a separatrix but not on it (the elliptic parameter is not
        representable), or a motion within 1e-60 of a relative equilibrium.

    Warns
    -----
    RuntimeWarning
        When ``error_estimate`` exceeds 1e-10 (nearly planar orbits, see the module notes).
    """
    Jm = V.second_moments(J, "J")
    n_body = V.vector3(N, "N")
    Q0m = V.rotation_matrix(Q0, "Q0")
    w0 = V.vector3(omega0, "omega0")
    I = np.trace(Jm) * np.eye(3) - Jm
    m_body = I @ w0
    h_body = m_body + n_body
    energy = 0.5 * float(w0 @ m_body)
    h2 = _norm(h_body) ** 2
    inv = {"energy": energy, "H": -2.0 * energy, "H2": -2.0 * h2, "h2": h2, "m2": _norm(m_body) ** 2}
    Z = np.zeros((3, 3))

    def make(method, impl, period=0.0, rate=0.0, err=_EPS):
        inv.update(period=float(period), precession_rate=float(rate), error_estimate=float(err))
        return GyrostatSolution(Jm, Z, Q0m, w0, method, inv, None, N=n_body, _impl=impl)

    if _norm(n_body) <= 0.25 * _EPS * _norm(m_body):
        # a rotor momentum below the rounding of m: the Euler top of the same data (exact
        # to rounding; the rotor term's effect stays below eps |m| omega t)
        sol = solve_rotation(Jm, Z, Q0m, w0)
        return make(sol.method, _Delegate(sol), sol.invariants["period"], sol.invariants["precession_rate"])
    if not np.any(m_body):
        return make("rest", _Steady(Q0m, np.zeros(3)))
    hdot0 = np.cross(m_body, w0) + np.cross(n_body, w0)
    if _norm(hdot0) <= 8 * _EPS * (_norm(m_body) + _norm(n_body)) * _norm(w0):
        # h x omega = 0 to the rounding of the data: a relative equilibrium (steady rotation)
        return make("gyrostat/steady", _Steady(Q0m, w0), rate=_norm(w0))
    Jp, R = _principal_frame(Jm)
    Ip = np.array([Jp[1] + Jp[2], Jp[0] + Jp[2], Jp[0] + Jp[1]])
    n = R.T @ n_body
    m = Ip * (R.T @ w0)
    Q0p = Q0m @ R
    if Jp[0] == Jp[1] == Jp[2]:
        impl = _Sphere(Ip[0], n, Q0p, w0 @ R)
        impl_body = _BodyMap(impl, R)
        return make("gyrostat/sphere", impl_body, period=2 * np.pi * Ip[0] / _norm(n),
                    rate=_norm(m + n) / Ip[0])
    for c in range(3):
        a_, b_ = [i for i in range(3) if i != c]
        # (a transverse rotor momentum below the rounding of N is the rounding of the data)
        if Jp[a_] == Jp[b_] and max(abs(n[a_]), abs(n[b_])) <= 0.25 * _EPS * _norm(n):
            n_ax = np.zeros(3)
            n_ax[c] = n[c]
            impl = _Axisymmetric(Ip, n_ax, m, c, Q0p, R)
            per = 2 * np.pi / abs(impl.Om) if impl.Om != 0 else 0.0
            return make("gyrostat/axisymmetric", impl, period=per, rate=impl.psidot)
    hdot = np.cross(m + n, m / Ip)
    if _norm(m) < 1e-60 * _norm(m + n) or _norm(hdot) < 1e-60 * _norm(m + n) * _norm(m / Ip):
        # the orbit is a loop of relative size < 1e-60 about a relative equilibrium (or the
        # carrier is at rest to 1e-60): its polynomial coefficients, powers of that size,
        # would underflow in float64
        raise NotImplementedError("solve_gyrostat: the motion is within 1e-60 (relative) of a "
                                  "relative equilibrium; not supported")
    # the motion scales with |h|: m(t) = G m1(G t) for the data divided by G (so that tiny or
    # huge momenta neither underflow nor overflow in the orbit's polynomial coefficients)
    # (a power of two near |h|: the scaled data are the data, exactly)
    Gs = 2.0 ** round(np.log2(_norm(m + n)))
    n, m = n / Gs, m / Gs
    # the exact data for the algebra: I_i = J_j + J_k and m = I omega0 (no rounding)
    wp = R.T @ w0
    Iq = [Fraction(float(Jp[1])) + Fraction(float(Jp[2])), Fraction(float(Jp[0])) + Fraction(float(Jp[2])),
          Fraction(float(Jp[0])) + Fraction(float(Jp[1]))]
    mq = [Iq[i] * Fraction(float(wp[i])) / Fraction(Gs) for i in range(3)]
    impl = _Elliptic(Ip, n, m, R, m0_mp=mq, Ip_exact=Iq)
    m_data = m
    if impl.anchor_is_degenerate() or impl.anchor_is_slow():
        # The pencil is anchored at h(0).  Two anchors are bad: zero torsion at h(0)
        # (typically a point on a symmetry plane of the orbit), where the formula is 0/0 where
        # the orbit meets the osculating plane again; and a slow point (next to a saddle),
        # whose tangent line passes close to the saddle, so that the pencil angle resolves the
        # points around the saddle, where the orbit lingers, only to eps / (distance), and the
        # Weierstrass form is based at a nearly double root.  Re-anchor at a fast point.
        impl = _reanchor(impl, mq)
    impl.finish()
    impl.setup_attitude(Q0p)
    impl.check_float_against_mp()
    # how far the formula's h(0) is from the data (re-anchoring, rounding)
    impl.float_error = max(impl.float_error,
                           _norm(impl.momentum(np.zeros(1))[0] - m_data) / max(_norm(m_data), 1e-300))
    # relative error: the float64 evaluation's (measured against mpmath at the worst-
    # conditioned points of the orbit) and the Fourier tail of psi' (per period)
    err = max(8 * _EPS, impl.float_error) + impl.phase_error + impl.fourier_tail
    if err > 1e-10:
        warnings.warn(f"solve_gyrostat: estimated relative error {err:.1e} per period of the "
                      "orbit (close to a separatrix); see "
                      "invariants['error_estimate']", RuntimeWarning, stacklevel=2)
    method = "gyrostat/separatrix" if impl.separatrix else "gyrostat/elliptic"
    return make(method, _Scaled(impl, Gs), period=impl.T / Gs, rate=impl.nu * Gs, err=err)


class _Scaled:
    """The motion of the data scaled by 1/G, at time G t, with omega scaled back by G."""

    def __init__(self, impl, G):
        self.impl, self.G = impl, G

    def evaluate(self, t):
        w, Q = self.impl.evaluate(self.G * t)
        return self.G * w, Q

    def omega(self, t):
        return self.G * self.impl.omega(self.G * t)

    def __getattr__(self, name):  # expose the elliptic details (T, m, kind, ...) for inspection
        return getattr(self.impl, name)


class _BodyMap:
    """Wraps a principal-frame implementation working with principal-frame Q0/omega."""

    def __init__(self, impl, R):
        self.impl, self.R = impl, R

    def evaluate(self, t):
        w, Q = self.impl.evaluate(t)
        return w @ self.R.T, Q @ self.R.T

    def omega(self, t):
        return self.impl.omega(t) @ self.R.T
