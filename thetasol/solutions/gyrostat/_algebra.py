"""The algebraic constants of a Zhukovsky-Volterra orbit, formed in mpmath from the exact data.

The tangent-line pencil at the anchor, its quartic, the Weierstrass invariants ``g2, g3``, the
cubic's roots, the elliptic parameter and period, and the turning point the inversion is based at
(see :mod:`thetasol.solutions.gyrostat`).  :func:`orbit_algebra` returns them as floats and, under
``"mpc"``, in mpmath.
"""
from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from thetasol.protocol import ClosedFormUnavailable

__all__ = ["orbit_algebra", "mpq"]


def orbit_algebra(Ip, n, m0, dps=34):
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


def mpq(mp, x):
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
    return [x - y for x, y in zip(p, q, strict=True)]


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
    for _, th in sorted(zip(slopes, ths, strict=True), key=lambda x: -x[0]):
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


@dataclass(frozen=True)
class _Pencil:
    """The pencil of planes through the tangent line at the anchor, in mpmath.

    ``tau`` is the unit tangent, ``(e1, e2)`` complete the frame; a plane of the pencil meets the
    orbit in two further points, the roots of ``A w^2 + 2 B w + C`` (``bS, A, B, C`` are the
    ascending coefficient lists in the pencil parameter ``z``), and ``f`` is the quartic
    ``Delta(z) = B^2 - A C`` (ascending).  ``zdot0 = dz/dt`` at the anchor, ``mm`` the anchor's
    momentum."""

    tau: list
    e1: list
    e2: list
    bS: list
    A: list
    B: list
    C: list
    f: list
    zdot0: object
    mm: list


def _pencil(mp, Ip, n, m0) -> _Pencil:
    """The tangent-line pencil at ``h(0) = m0 + n`` of the orbit ``I^{-1} = diag(1/Ip)``."""
    # the data exactly (Ip and m0 as exact rationals from the float data, or an mpmath
    # re-anchoring point), not their float64 roundings: the curve, its period and a
    # separatrix are the data's
    A_ = [1 / mpq(mp, x) for x in Ip]
    mm = [mpq(mp, x) for x in m0]
    nn = [mpq(mp, x) for x in n]
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
    return _Pencil(tau=tau, e1=e1, e2=e2, bS=bS, A=A, B=B, C=C, f=f, zdot0=-B[0], mm=mm)


def _weierstrass(mp, f, dps, exact):
    """The invariants ``g2, g3`` of the quartic ``f`` and the discriminant of the cubic
    ``4x^3 - g2 x - g3``; a discriminant below the working precision needs more digits or,
    with ``exact``, is zero."""
    a4, a3, a2, a1, a0 = f[0], f[1] / 4, f[2] / 6, f[3] / 4, f[4]
    g2 = a0 * a4 - 4 * a1 * a3 + 3 * a2 ** 2
    g3 = a0 * a2 * a4 + 2 * a1 * a2 * a3 - a2 ** 3 - a0 * a3 ** 2 - a1 ** 2 * a4
    disc = g2 ** 3 - 27 * g3 ** 2
    if abs(disc) <= mp.mpf(10) ** (8 - dps) * (abs(g2) ** 3 + 27 * g3 ** 2):
        if not exact:
            raise _NeedDigits
        disc = 0
    return g2, g3, disc


@dataclass(frozen=True)
class _Cubic:
    """The elliptic parametrization from the roots of ``4x^3 - g2 x - g3``: ``kind`` 3 (three
    real roots, ``wp = p1 + p0 / sn^2``) or 1 (one real root, the ``cn`` form), the parameter
    ``m``, ``mc = 1 - m``, the argument ``scale``, the period ``T`` (``inf`` on a separatrix),
    the roots and the top real root ``e_top``."""

    kind: int
    p1: object
    p0: object
    T: object
    m: object
    mc: object
    scale: object
    roots: list
    e_top: object


def _cubic(mp, g2, g3, disc) -> _Cubic:
    """Roots, parameter and period of the Weierstrass cubic with discriminant ``disc``."""
    if disc > 0:
        r = sorted(_cubic_roots_mp(mp, g2, g3), reverse=True)
    elif disc == 0:
        if g2 == 0:
            raise ClosedFormUnavailable("solve_gyrostat: a triple root of the Weierstrass cubic "
                                      "(degenerate orbit); not supported")
        ed = -3 * g3 / (2 * g2)  # 4x^3 - g2 x - g3 = 4 (x - ed)^2 (x + 2 ed)
        r = [ed, ed, -2 * ed] if ed > 0 else [-2 * ed, ed, ed]
    if disc >= 0:
        beta = r[0] - r[2]
        m, mc = (r[1] - r[2]) / beta, (r[0] - r[1]) / beta
        scale = mp.sqrt(beta)
        T = 2 * mp.ellipk(m) / scale if mc > 0 else mp.inf
        return _Cubic(kind=3, p1=r[2], p0=beta, T=T, m=m, mc=mc, scale=scale, roots=r, e_top=r[0])
    e2r = _cubic_roots_mp(mp, g2, g3)[0]
    H = mp.sqrt(3 * e2r ** 2 - g2 / 4)
    m, mc = mp.mpf(1) / 2 - 3 * e2r / (4 * H), mp.mpf(1) / 2 + 3 * e2r / (4 * H)
    scale = 2 * mp.sqrt(H)
    T = 4 * mp.ellipk(m) / scale
    ei = mp.sqrt(3 * e2r ** 2 - g2) / 2
    roots = [mp.mpc(-e2r / 2, ei), e2r, mp.mpc(-e2r / 2, -ei)]
    return _Cubic(kind=1, p1=e2r - H, p0=2 * H, T=T, m=m, mc=mc, scale=scale, roots=roots, e_top=e2r)


def _check_resolution(mp, cub: _Cubic, dps, exact):
    """Next to a double root the cubic's close roots, hence m and mc, carry the rounding of
    g2, g3 amplified by 1/min(m, mc)^2: more digits until m, mc are float64-accurate; an ``mc``
    below float64's range is refused."""
    m, mc = cub.m, cub.mc
    small = min(m, mc)
    if not exact and small > mp.mpf(2) ** -1020 and mp.mpf(10) ** -dps > mp.mpf(10) ** -20 * small ** 2:
        raise _NeedDigits
    if mc != 0 and (mc <= mp.mpf(2) ** -1020 or not mp.isfinite(cub.T)):
        raise ClosedFormUnavailable("solve_gyrostat: the orbit is within 1e-307 (mc = "
                                  f"{mp.nstr(mc, 3)}) of a separatrix of the gyrostat, "
                                  "closer than float64 resolves; not supported")


def _pack(mp, pen: _Pencil, cub: _Cubic, turn, g2, g3, dps):
    """The constants as floats (and float vectors) and, under ``"mpc"``, in mpmath."""
    th, k, cq, va = turn
    # qe = e_top - c: wp - c = qe + (wp - e_top), both terms >= 0 unless y passes infinity
    out = dict(kind=cub.kind, p1=cub.p1, p0=cub.p0, T=cub.T, m=cub.m, mc=cub.mc, scale=cub.scale,
               s0=pen.zdot0, k=k, qe=cub.e_top - cq, g2=g2, g3=g3, cr=mp.cos(th), sr=mp.sin(th), va=va)
    res = {k_: (int(v) if k_ == "kind" else float(v)) for k_, v in out.items()}
    res["va_lo"] = float(va - res["va"])
    # the residual quadratic's coefficients as exact-coefficient polynomials in z: evaluated
    # near their roots (a small orbit about a relative equilibrium, |m| << |N|) they keep
    # their relative accuracy, which dot products of O(|h|) vectors would not
    polys = (pen.bS, pen.A, pen.B, pen.C)
    res["polys"] = tuple(np.array([float(x) for x in (P + [0] * 4)[:k_]])
                         for P, k_ in zip(polys, (2, 2, 3, 4), strict=True))
    res["tau"] = np.array([float(x) for x in pen.tau])
    res["e1"] = np.array([float(x) for x in pen.e1])
    res["e2"] = np.array([float(x) for x in pen.e2])
    res["mpc"] = dict(out, polys=polys, tau=pen.tau, e1=pen.e1, e2=pen.e2, m0=pen.mm, dps=dps)
    return res


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
        pen = _pencil(mp, Ip, n, m0)
        g2, g3, disc = _weierstrass(mp, pen.f, dps, exact)
        cub = _cubic(mp, g2, g3, disc)
        _check_resolution(mp, cub, dps, exact)
        turn = _turning_point(mp, pen.f, pen.zdot0, cub.e_top, cub.roots)
        return _pack(mp, pen, cub, turn, g2, g3, dps)
