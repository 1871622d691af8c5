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
the orbit at ``h(0)``: each plane meets the curve in two further points, which solve a
quadratic whose discriminant ``Delta(z)`` is a quartic in the pencil parameter ``z`` (``z = 0``
is the osculating plane).  ``dt`` is the holomorphic differential: with our normalization
``dz / dt = W``, ``W^2 = Delta(z)`` exactly (checked to 50 digits, and by the tests), so
``z(t)`` is given by Weierstrass' addition formula for the
inversion of a quartic (Whittaker & Watson 20.6) with ``wp`` of the quartic's invariants
``g2, g3``; ``wp`` is written with our Jacobi functions (three real roots of
``4x^3 - g2 x - g3``: ``wp = e3 + (e1 - e3)/sn^2``; one real root: the ``cn`` form), and the
whole formula is multiplied through by ``sn^4`` (resp. ``(1 - cn)^2``) so that nothing is
infinite at ``t = 0``.  The point is then rebuilt from ``z`` and the sign of ``W`` (a stable
root of the quadratic).  Argument reduction modulo the periods is as in the Euler top.

Attitude: as for the Euler top, ``Q = S R_3(psi) B(h)`` with ``B`` the minimal rotation
taking ``h/G`` to a pole ``p`` kept away from the orbit, and
``psi' = (h . omega + G p . omega) / (G + p . h)`` (an integral of the third kind).  Its
secular rate and periodic part are taken from the Fourier series of this closed-form
periodic integrand, the coefficients computed by FFT to round-off (the series converges
geometrically; the number of terms is chosen adaptively).

Numerics: the few algebraic constants (the frame, the quartic, ``g2, g3``, the cubic's
roots, ``K``) are formed in mpmath from the exact float data (``g2, g3`` cancel, and near a
separatrix the parameter amplifies that by ``1/mc``); the residual quadratic is evaluated from
exact-coefficient polynomials in ``z`` (so that small orbits about a relative equilibrium,
``|m| << |N|``, and nearly planar orbits of nearly axisymmetric dual-spin bodies keep their
relative accuracy); ``m(t)`` is carried as ``m(0) + (h(t) - h(0))``.  Where the torsion of the
orbit vanishes at ``h(0)`` (a point on a symmetry plane of the orbit: ``N`` along a principal
axis and ``omega0`` in a principal plane, say) the formula is 0/0 where the orbit meets the
osculating plane again: the parametrization is then re-anchored a little later on the same
orbit, at the point the closed form gives there in mpmath.

Degenerate cases are separate closed forms: ``N = 0`` (or below the rounding of ``m``) is the
Euler top (:mod:`thetasol.euler_top`), ``m = 0`` rest, ``h x omega = 0`` (to the rounding of the
data) steady rotation, a spherical carrier and an axisymmetric carrier with ``N`` along its
axis are trigonometric.

Error report: ``invariants["error_estimate"]`` is the float64 evaluation's relative error
measured against the same closed form in mpmath at the orbit's worst-conditioned points (where
it is slowest, near a saddle it can reach ~1e-12) and at ``t = 0``, plus the Fourier tail of
``psi'`` per period; a :class:`RuntimeWarning` is issued above 1e-10.  Orbits exactly on a
separatrix of the gyrostat (infinite period) and motions within 1e-60 (relative) of a relative
equilibrium raise :class:`NotImplementedError`.  There is no ``dps=`` path.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from . import _validate as V
from . import elliptic as _el
from .euler_top import _angle_mod_2pi, _minimal_rotation, _norm, _principal_frame, _unit
from .rotation import RotationSolution, solve_rotation

__all__ = ["GyrostatSolution", "solve_gyrostat"]

_EPS = np.finfo(float).eps


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

def _rot_about(axis, ang):
    """Rotation matrices about a fixed unit axis by angles ``ang`` (n,), shape (n, 3, 3)."""
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return (np.eye(3) + np.sin(ang)[:, None, None] * K
            + (1.0 - np.cos(ang))[:, None, None] * (K @ K))


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


def _algebra(a, n, m0, dps=34):
    """See :func:`_algebra_at`; the precision is raised until the discriminant of the
    Weierstrass cubic is resolved (tiny orbits about a relative equilibrium make g2, g3
    nearly cancel)."""
    while True:
        try:
            return _algebra_at(a, n, m0, dps)
        except _NeedDigits:
            if dps > 2000:
                raise NotImplementedError("solve_gyrostat: the orbit is (within 2000 digits) "
                                          "a separatrix of the gyrostat") from None
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


def _algebra_at(a, n, m0, dps):
    """Frame, quartic, Weierstrass invariants and the elliptic parameters, in mpmath.

    The invariants ``g2, g3`` are sums of products that cancel (they lose 2-3 digits) and
    the parameter ``mc`` of an orbit near a separatrix amplifies that loss by ``1/mc``; so
    these few scalars are formed at ``dps`` digits from the (exact) float data and rounded.
    Returns floats (and float vectors) only.
    """
    import mpmath as mp

    with mp.workdps(dps):
        A_ = [mp.mpf(float(x)) for x in a]
        mm = [mp.mpf(float(x)) for x in m0]
        nn = [mp.mpf(float(x)) for x in n]
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

        def pmul(p, q):
            r = [0] * (len(p) + len(q) - 1)
            for i, x in enumerate(p):
                for j, y in enumerate(q):
                    r[i + j] += x * y
            return r

        def psub(p, q):
            L = max(len(p), len(q))
            p = list(p) + [0] * (L - len(p))
            q = list(q) + [0] * (L - len(q))
            return [x - y for x, y in zip(p, q)]

        A = psub(pmul(bS, [alphaE]), bE)
        B = pmul(bS, dE)
        C = psub(pmul(bS, gE), pmul(bE, gS))
        D = psub(pmul(B, B), pmul(A, C))
        D = (D + [0] * 5)[:5]
        # dz/dt = W with W^2 = Delta(z) = B^2 - A C: the constant kappa in dt = kappa dz / W is
        # exactly 1 for this normalization (checked to 50 digits on random data, and by the
        # tests against integration), so zdot(0) = W(0) = -B(0) (our point is the root of the
        # quadratic that runs to infinity on the osculating plane z = 0).  This needs no third
        # derivative and stays valid where the torsion of the orbit vanishes at h(0).
        kappa = mp.mpf(1)
        zdot0 = -B[0]
        f = D
        a4, a3, a2, a1, a0 = f[0], f[1] / 4, f[2] / 6, f[3] / 4, f[4]
        g2 = a0 * a4 - 4 * a1 * a3 + 3 * a2 ** 2
        g3 = a0 * a2 * a4 + 2 * a1 * a2 * a3 - a2 ** 3 - a0 * a3 ** 2 - a1 ** 2 * a4
        disc = g2 ** 3 - 27 * g3 ** 2
        if abs(disc) <= mp.mpf(10) ** (8 - dps) * (abs(g2) ** 3 + 27 * g3 ** 2):
            raise _NeedDigits
        out = {}
        if disc > 0:
            r = sorted(_cubic_roots_mp(mp, g2, g3), reverse=True)
            beta = r[0] - r[2]
            m, mc = (r[1] - r[2]) / beta, (r[0] - r[1]) / beta
            scale = mp.sqrt(beta)
            out.update(kind=3, p1=r[2], p0=beta, kwp=-2 * beta ** 1.5, T=2 * mp.ellipk(m) / scale)
        elif disc < 0:
            e2r = _cubic_roots_mp(mp, g2, g3)[0]
            H = mp.sqrt(3 * e2r ** 2 - g2 / 4)
            m, mc = mp.mpf(1) / 2 - 3 * e2r / (4 * H), mp.mpf(1) / 2 + 3 * e2r / (4 * H)
            scale = 2 * mp.sqrt(H)
            out.update(kind=1, p1=e2r - H, p0=2 * H, kwp=-4 * H ** 1.5, T=4 * mp.ellipk(m) / scale)
        else:
            m = mc = scale = None
        if m is None or mc <= mp.mpf(2) ** -1020 or not mp.isfinite(out.get("T", mp.inf)):
            raise NotImplementedError("solve_gyrostat: the orbit is (within float range) a separatrix "
                                      "of the gyrostat: infinite period")
        out.update(m=m, mc=mc, scale=scale, q1=out["p1"] - a2 / 2, kappa=kappa, s0=zdot0,
                   g2=g2, g3=g3, alphaE=alphaE, loss=mp.sqrt(dot(h, h) * dot(w, w)) / n1)
        res = {k: (int(v) if k == "kind" else float(v)) for k, v in out.items()}
        res["wc"] = tuple(float(x) for x in (a0, a1, a2, a3, a4))
        # the residual quadratic's coefficients as exact-coefficient polynomials in z: evaluated
        # near their roots (a small orbit about a relative equilibrium, |m| << |N|) they keep
        # their relative accuracy, which dot products of O(|h|) vectors would not
        res["polys"] = tuple(np.array([float(x) for x in (P + [0] * 4)[:k]])
                             for P, k in ((bS, 2), (A, 2), (B, 3), (C, 4)))
        res["tau"] = np.array([float(x) for x in tau])
        res["e1"] = np.array([float(x) for x in e1])
        res["e2"] = np.array([float(x) for x in e2])
        res["mpc"] = dict(out, wc=(a0, a1, a2, a3, a4), polys=(bS, A, B, C), tau=tau, e1=e1, e2=e2,
                          m0=mm, dps=dps)
        return res


# -- the generic (elliptic) motion ------------------------------------------------------------

class _Elliptic:
    """h(t) by the tangent-line pencil and Weierstrass' inversion; psi by Fourier series."""

    def __init__(self, a, n, m0, Pbody, t_anchor=0.0):
        # the state is carried as m = m0 + Delta(t) (Delta the displacement of h from the
        # anchor h(t_anchor) = m0 + N), so that omega = a m keeps its relative accuracy when
        # |m| << |N| (fast rotors)
        h0 = m0 + n
        self.a, self.n, self.m0, self.h0 = a, n, m0, h0
        self.P = Pbody  # principal -> body
        self.G = _norm(h0)
        self.w0 = a * m0
        self.t_anchor = float(t_anchor)
        c = _algebra(a, n, m0)
        for k, v in c.items():
            setattr(self, k, v)

    def momentum_mp(self, t: float, near=None) -> np.ndarray:
        """m(t) from the same closed form evaluated in mpmath (used to re-anchor exactly).

        With ``near`` given, of the two residual points for this ``z`` the one nearer to
        ``near`` is returned (where the two nearly coincide the sign test on ``B W`` is not
        decisive, and either is right to that accuracy)."""
        import mpmath as mp

        c = self.mpc
        with mp.workdps(c["dps"]):
            a0, a1, a2, a3, a4 = c["wc"]
            sc = c["scale"]
            u = sc * (mp.mpf(t) - mp.mpf(self.t_anchor))
            sn, cn, dn = (mp.ellipfun(f, u, m=c["m"]) for f in ("sn", "cn", "dn"))
            if c["kind"] == 3:
                X, Y = sn * sn, cn * dn * sn
                Xd, Yd = 2 * sn * cn * dn * sc, sc * (cn * cn * dn * dn - sn * sn * dn * dn - c["m"] * sn * sn * cn * cn)
            else:
                X, Y = 1 - cn, sn * dn
                Xd, Yd = sc * sn * dn, sc * cn * (dn * dn - c["m"] * sn * sn)
            q1, p0, s0, kw = c["q1"], c["p0"], c["s0"], c["kwp"]
            Pq = q1 * X + p0
            Z1 = -s0 * kw * Y + 2 * a3 * Pq * X + a1 * a4 * X * X
            Z0 = 2 * Pq * Pq - a0 * a4 * X * X / 2
            Z1d = -s0 * kw * Yd + 2 * a3 * (2 * q1 * X + p0) * Xd + 2 * a1 * a4 * X * Xd
            Z0d = (4 * q1 * Pq - a0 * a4 * X) * Xd
            W = Z0 * Z1d - Z1 * Z0d
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
                return np.array([float(c["m0"][k] + d[k]) for k in range(3)])

            p1 = point(W)
            if near is None:
                return p1
            p2 = point(-W)
            return p1 if _norm(p1 - near) <= _norm(p2 - near) else p2

    def check_float_against_mp(self, n=12):
        """Empirical error of the float64 evaluation: float vs mpmath (same closed form) at the
        points of the orbit where it is slowest (|dtheta_Z/dt| smallest, near a saddle the
        parametrization is worst conditioned) and at a few others."""
        ts = np.arange(128) * (self.T / 128)
        W = np.abs(self._dW(ts)[1])
        # t = 0 (the data point, always evaluated) is included
        pick = np.concatenate([[0.0], ts[np.argsort(W)[: n - 4]], ts[:: 32]])
        mf = self.momentum(pick)
        scale = max(_norm(self.m0), 1e-300)
        self.float_error = max(_norm(mf[i] - self.momentum_mp(float(tp), near=mf[i]))
                               for i, tp in enumerate(pick)) / scale

    def anchor_is_degenerate(self) -> bool:
        """The orbit's torsion (nearly) vanishes at the anchor: dtheta_Z/dt = -B(0) ~ 0 there, and
        the pencil formula becomes 0/0 where the orbit meets the osculating plane again."""
        _, W = self._dW(np.arange(64) * (self.T / 64) + self.t_anchor)
        return abs(self.s0) < 1e-2 * np.max(np.abs(W))

    def finish(self):
        self._pole()
        self._fourier()

    # momentum --------------------------------------------------------------------------
    def h(self, t):
        return self.h0 + self._dW(t)[0]

    def momentum(self, t):
        return self.m0 + self._dW(t)[0]

    def _dW(self, t):
        """Delta(t) = h(t) - h(0) and the homogeneous W (unit (Z0, Z1)): dtheta_Z/dt = W."""
        a0, a1, a2, a3, a4 = self.wc
        if self.t_anchor:
            d_hi, d_lo = _el._two_sum(t, -self.t_anchor)
            hi, lo = _el._two_prod(self.scale, d_hi)
            lo = lo + self.scale * d_lo
        else:
            hi, lo = _el._two_prod(self.scale, t)
        sn, cn, dn, _ = _el._ellipj_reduced(hi, lo, np.full(t.shape, self.m), np.full(t.shape, self.mc))
        sc = self.scale
        if self.kind == 3:
            X = sn * sn
            Y = cn * dn * sn
            Xd = 2 * sn * cn * dn * sc
            Yd = sc * (cn * cn * dn * dn - sn * sn * dn * dn - self.m * sn * sn * cn * cn)
        else:
            with np.errstate(divide="ignore", invalid="ignore"):
                X = np.where(cn > 0, sn * sn / (1 + cn), 1 - cn)
            Y = sn * dn
            Xd = sc * sn * dn
            Yd = sc * cn * (dn * dn - self.m * sn * sn)
        q1, p0 = self.q1, self.p0
        Pq = q1 * X + p0
        # W&W's "sqrt f(x0)" is -zdot(0) with wp' ~ -2/t^3 (checked against integration)
        Z1 = -self.s0 * self.kwp * Y + 2 * a3 * Pq * X + a1 * a4 * X * X
        Z0 = 2 * Pq * Pq - 0.5 * a0 * a4 * X * X
        Z1d = -self.s0 * self.kwp * Yd + 2 * a3 * (2 * q1 * X + p0) * Xd + 2 * a1 * a4 * X * Xd
        Z0d = (4 * q1 * Pq - a0 * a4 * X) * Xd
        nz = np.hypot(Z0, Z1)
        Z0, Z1, Z0d, Z1d = Z0 / nz, Z1 / nz, Z0d / nz, Z1d / nz
        W = self.kappa * (Z0 * Z1d - Z1 * Z0d)
        return self._point(Z0, Z1, W), W

    def _point(self, Z0, Z1, W):
        tau, e1, e2 = self.tau, self.e1, self.e2
        mu = Z1[:, None] * e1 - Z0[:, None] * e2
        pb, pA, pB, pC = self.polys  # ascending powers of z = Z1/Z0, homogenized below
        bS = pb[0] * Z0 + pb[1] * Z1
        gS = Z0 * Z0 + Z1 * Z1
        A = pA[0] * Z0 + pA[1] * Z1
        B = (pB[0] * Z0 + pB[1] * Z1) * Z0 + pB[2] * Z1 * Z1
        C = ((pC[0] * Z0 + pC[1] * Z1) * Z0 + pC[2] * Z1 * Z1) * Z0 + pC[3] * Z1 * Z1 * Z1
        same = B * W > 0
        num = np.where(same, C, W - B)
        den = np.where(same, -B - W, A)
        nrm = num * num + gS * den * den
        with np.errstate(divide="ignore", invalid="ignore"):
            fac = np.where(nrm > 0, -2 * bS / nrm, 0.0)
        # at the anchor itself (t - t_anchor a multiple of the period: Z1 = 0 exactly) the
        # formula is 0/0; the point is the anchor
        fac = np.where(Z1 == 0, 0.0, fac)
        return fac[:, None] * ((num * den)[:, None] * tau + (den * den)[:, None] * mu)

    # attitude --------------------------------------------------------------------------
    def _pole(self):
        """Pole p maximizing min over the orbit of 1 + p.h/G (kept away from the orbit)."""
        ts = np.linspace(0.0, self.T, 257)[:-1]
        hs = (self.h0 + self._dW(ts)[0]) / self.G
        cands = [np.eye(3)[i] * s for i in range(3) for s in (1, -1)]
        mean = hs.mean(axis=0)
        if np.linalg.norm(mean) > 1e-3:
            cands.append(mean / np.linalg.norm(mean))
        best = max(cands, key=lambda p: np.min(1 + hs @ p))
        self.p = best
        self.Pw = _frame_with_e3(best)

    def _psidot(self, t):
        d = self._dW(t)[0]
        h = self.h0 + d
        w = self.a * (self.m0 + d)
        hw = np.sum(h * w, -1)
        return (hw + self.G * (w @ self.p)) / (self.G + h @ self.p), h

    def _fourier(self):
        """Fourier coefficients of psi' over one period, doubling the sampling until the tail
        reaches round-off or stops decreasing (the samples' own rounding noise)."""
        n, prev = 64, np.inf
        while True:
            ts = np.arange(n) * (self.T / n)
            f, _ = self._psidot(ts)
            c = np.fft.rfft(f) / n
            scale = np.max(np.abs(c))
            tail = np.max(np.abs(c[3 * len(c) // 4:]))
            if tail <= 4 * _EPS * scale or (n >= 256 and tail > 0.5 * prev) or n >= 2 ** 17:
                break
            prev = tail
            n *= 2
        self.fourier_tail = tail / scale
        if self.fourier_tail > 1e-9:
            raise NotImplementedError("solve_gyrostat: the precession angle's Fourier series does not "
                                      f"converge (tail {self.fourier_tail:.1e}; orbit too close to a separatrix)")
        self.nu = c[0].real
        Om = 2 * np.pi / self.T
        k = np.arange(1, len(c) - 1)
        self.Om = Om
        self.d = c[1:-1] / (1j * Om * k)  # drop the Nyquist term
        self.d_sum = self.d.sum()
        self.nterms = len(self.d)

    def psi(self, t):
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
        h = self.h0 + d
        w = self.a * (self.m0 + d)
        psi = self.psi(t)
        B = _minimal_rotation(_unit(h @ self.Pw))
        R3 = np.zeros(t.shape + (3, 3))
        cp, sp = np.cos(psi), np.sin(psi)
        R3[..., 0, 0] = cp
        R3[..., 0, 1] = -sp
        R3[..., 1, 0] = sp
        R3[..., 1, 1] = cp
        R3[..., 2, 2] = 1.0
        Qp = self.S @ R3 @ B @ self.Pw.T
        return w @ self.P.T, Qp @ self.P.T

    def omega(self, t):
        return (self.a * self.momentum(t)) @ self.P.T


class _Steady:
    def __init__(self, Q0, w0):
        self.Q0, self.w0 = Q0, w0

    def evaluate(self, t):
        n = t.size
        wn = _norm(self.w0)
        if wn == 0:
            return np.zeros((n, 3)), np.broadcast_to(self.Q0, (n, 3, 3)).copy()
        ang = _angle_mod_2pi(wn, t, 0.0)
        return np.broadcast_to(self.w0, (n, 3)).copy(), self.Q0 @ _rot_about(self.w0 / wn, ang)

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
        h = m + self.n
        psi = _angle_mod_2pi(self.psidot, t, 0.0)
        B = _minimal_rotation(_unit(h @ self.Pw))
        R3 = np.zeros(t.shape + (3, 3))
        cp, sp = np.cos(psi), np.sin(psi)
        R3[..., 0, 0] = cp
        R3[..., 0, 1] = -sp
        R3[..., 1, 0] = sp
        R3[..., 1, 1] = cp
        R3[..., 2, 2] = 1.0
        Qp = self.S @ R3 @ B @ self.Pw.T
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
        ``omega``; 0 when constant), ``precession_rate`` and ``error_estimate``.

    Raises
    ------
    ValueError
        Bad data (non-finite, wrong shapes, unphysical ``J``, ``Q0`` not a rotation).
    NotImplementedError
        An orbit exactly on a separatrix of the gyrostat (infinite period).
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
        inv.update({k: sol.invariants[k] for k in ("period", "precession_rate")})
        inv["error_estimate"] = _EPS
        return GyrostatSolution(Jm, Z, Q0m, w0, sol.method, inv, None, N=n_body, _impl=_Delegate(sol))
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
    Gs = _norm(m + n)
    n, m = n / Gs, m / Gs
    impl = _Elliptic(1.0 / Ip, n, m, R)
    m_data = m
    for frac in (0.0313, 0.0517, 0.1):
        if not impl.anchor_is_degenerate():
            break
        # zero torsion at h(0) (typically a point on a symmetry plane of the orbit): the
        # formula is 0/0 where the orbit meets the osculating plane again.  Re-anchor a little
        # later, at a generic point (not a fraction of the period a symmetry could single
        # out), given there by the closed form evaluated in mpmath; rounding it perturbs the
        # data by ~1e-16, which the motion carries back to t = 0 (measured below)
        ta = frac * impl.T
        impl = _Elliptic(1.0 / Ip, n, impl.momentum_mp(ta), R, t_anchor=ta)
    impl.finish()
    impl.setup_attitude(Q0p)
    impl.check_float_against_mp()
    # how far the formula's h(0) is from the data (re-anchoring, rounding)
    impl.float_error = max(impl.float_error,
                           _norm(impl.momentum(np.zeros(1))[0] - m_data) / max(_norm(m_data), 1e-300))
    # relative error: the float64 evaluation's (measured against mpmath at the worst-
    # conditioned points of the orbit) and the Fourier tail of psi' (per period)
    err = max(8 * _EPS, impl.float_error) + impl.fourier_tail
    if err > 1e-10:
        warnings.warn(f"solve_gyrostat: estimated relative error {err:.1e} per period of the "
                      "orbit (close to a separatrix); see "
                      "invariants['error_estimate']", RuntimeWarning, stacklevel=2)
    return make("gyrostat/elliptic", _Scaled(impl, Gs), period=impl.T / Gs, rate=impl.nu * Gs, err=err)


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
