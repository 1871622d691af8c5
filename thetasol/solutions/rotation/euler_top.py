"""The free rigid body (Euler top) with full attitude, in Jacobi elliptic functions.

Inertial rotation (Section 4 I, (4.5)-(4.7); the a = 0 case of every effective body): the
body angular momentum ``m = I omega`` obeys ``mdot = m x omega`` ((4.6) in vector form) and
conserves ``|m|^2`` and ``2T = m . I^{-1} m`` (4.7).

Angular momentum
    Let ``c`` be the principal axis the momentum circles (the axis of largest inertia if
    ``G^2 > 2T I_mid``, of smallest inertia if ``G^2 < 2T I_mid``), ``b`` the middle axis
    and ``a`` the third one.  In a right-handed *working frame* (a signed permutation of the
    principal axes) in which ``m_c > 0``::

        m_a = G A_a cn(tau),  m_b = G A_b sn(tau),  m_c = G A_c dn(tau),  tau = lam t + u0,

    with amplitudes, parameter and frequency computed from sums of positive terms (only the
    distance to the separatrix, ``mc = k'^2``, is a difference, and it is the problem's own
    conditioning).  Exactly on the separatrix (``G^2 = 2T I_mid``) ``cn, dn -> sech`` and
    ``sn -> tanh`` (method "elliptic", case "separatrix"); with two equal moments ``k = 0`` and
    the functions are trigonometric ("elementary", case "symmetric"); a momentum along a principal
    axis, or a sphere, gives a steady rotation ("elementary", "steady"); ``m = 0`` is "rest".

Attitude
    As in Celledoni, Fasso, Safstrom & Zanna (SIAM J. Sci. Comput. 30, 2008) with the
    corrections of Principia's documentation/Celledoni.tex: ``Q(t) = S R_3(psi(t)) B(m(t))``
    where ``B(m)`` is the minimal rotation taking ``m/G`` to ``e_3`` (in the working frame;
    singular only at ``m = -G e_3``, which ``m_c > 0`` keeps away: there is no singularity
    where ``mdot = 0``), ``S`` is constant and the precession angle obeys
    ``psi' = G/I_c + (2T - G^2/I_c) / (G + m_c)``.  The published formulas have a sign error
    in lambda (case i), a wrong separatrix solution, a wrong characteristic of Pi and a frame
    singular where mdot = 0; all are avoided here by the construction above, and every formula
    below is derived anew and tested against numerical integration.

    ``int dtau / (G + A dn tau)`` is an integral of the third kind.  The textbook
    decomposition into ``Pi(n; am tau | m)`` and an arctangent (Principia's (integraldn))
    cancels catastrophically near steady rotation (both terms grow like ``1/A_a^2``).  Here the
    Gauss (descending Landen) transformation ``k1 = (1 - k')/(1 + k')``,
    ``dn(tau, k) = (1 - k1 s^2)/(1 + k1 s^2)``, ``s = sn(tau/(1 + k1), k1) = (1 + k') sn/(1 + dn)``
    turns it into ``int dv (1 + k1 s^2)/(1 - N s^2) = v + ((k1 + N)/3) s^3 R_J(c^2, 1 - k1^2 s^2,
    1, 1 - N s^2)`` (``c^2 = cos^2 am(v, k1)``, formed from ``cn``) with
    ``N = -k1 (G - A)/(G + A) <= 0`` and ``k1 + N = 2 A k1/(G + A) >= 0``: every term is
    positive and nothing cancels, from steady rotation to the separatrix.  The
    angle is split into a secular part ``nu t`` (``nu`` the mean precession rate) and a
    periodic part evaluated on the argument reduced modulo ``2K``; ``lam t``, ``nu t`` are
    formed as exact products and reduced with compensated arithmetic, so a far time costs and
    loses nothing more than a near one.

Precision: ``dps=`` evaluates the same closed form with mpmath at ``dps`` digits.  Data whose
``k'^2`` underflows float64 (a momentum within ~1e-160 of the unstable axis) are served by that
path too (rounded to float64; slow but exact).  See docs/euler_top.md.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import special as _sp

from thetasol.core.attitude import (
    angle_mod_2pi as _angle_mod_2pi,
    attitude_from_precession as _attitude,
    minimal_rotation as _minimal_rotation,
    norm3 as _norm,
    principal_frame as _principal_frame,
    uniform_rotation as _uniform_rotation,
    unit_rows as _unit,
)
from thetasol.core.dd import two_prod, two_sum
from thetasol.core.inertia import inertia_from_moments
from thetasol.protocol import RotationSolution
from thetasol.special.elliptic import reduce_period, sncndn_quarter

__all__ = ["EulerTopSolution", "solve_euler_top"]



# -- scalar arithmetic, float or mpmath --------------------------------------------------------

class _OutOfRange(Exception):
    """The distance to the separatrix is below what the current arithmetic represents."""


class _FloatOps:
    """Scalar operations for the float64 setup."""

    pi = math.pi
    exact_m = False  # the float kernels use mc, not m = 1 - mc
    tiny = 2.2250738585072014e-308  # a subnormal mc would carry only a few bits

    @staticmethod
    def num(x):
        return float(x)

    sqrt = staticmethod(math.sqrt)
    hypot = staticmethod(math.hypot)
    norm3 = staticmethod(math.hypot)  # n-argument hypot: no underflow of the squares
    asinh = staticmethod(math.asinh)
    atan = staticmethod(math.atan)
    tanh = staticmethod(math.tanh)

    @staticmethod
    def K(mc):
        return float(_sp.ellipkm1(mc))

    @staticmethod
    def RF(x, y, z):
        return float(_sp.elliprf(x, y, z))

    @staticmethod
    def RJ(x, y, z, p):
        return float(_sp.elliprj(x, y, z, p))


class _MpOps:
    """Scalar operations for the mpmath setup (used inside ``mpmath.workdps``)."""

    exact_m = True  # mpmath.ellipfun takes m: 1 - mc must not round to 1
    tiny = 0

    def __init__(self):
        import mpmath

        self.mp = mpmath
        self.pi = mpmath.pi
        self.sqrt = mpmath.sqrt
        self.hypot = mpmath.hypot
        self.asinh = mpmath.asinh
        self.atan = mpmath.atan
        self.tanh = mpmath.tanh

    def num(self, x):
        return self.mp.mpf(x)

    def norm3(self, a, b, c):
        return self.mp.sqrt(a * a + b * b + c * c)

    def K(self, mc):
        return self.mp.ellipk(1 - mc)

    def RF(self, x, y, z):
        return self.mp.elliprf(x, y, z)

    def RJ(self, x, y, z, p):
        return self.mp.elliprj(x, y, z, p)


def _F_sc(X, s, c, mc, K):
    """F(phi | 1 - mc) from sin(phi) = s, cos(phi) = c, phi in [-pi, pi] (scalar).

    Near phi = +-pi/2 (where F is near K and ``c^2`` may underflow) the complementary
    amplitude is used: ``F(phi) = K - F(phi')`` with ``tan phi' = cot(phi) / k'``.
    """
    if c * c >= 0.5:
        f = abs(s) * X.RF(c * c, c * c + mc * s * s, 1)
        if c < 0:
            f = 2 * K - f
    else:
        kps = X.sqrt(mc) * abs(s)
        h = X.hypot(abs(c), kps)
        sp, cp = abs(c) / h, kps / h
        v = sp * X.RF(cp * cp, cp * cp + mc * sp * sp, 1)
        f = K - v if c >= 0 else K + v
    return -f if s < 0 else f


# -- the constants of one motion ---------------------------------------------------------------

@dataclass
class _Consts:
    kind: str                 # rest | steady | elliptic | separatrix
    G: object = 0.0           # |m|
    W: np.ndarray = None      # working frame -> principal frame (signed permutation)
    Iw: tuple = ()            # inertias along the working axes a, b, c
    A: tuple = ()             # unit amplitudes (A_a, A_b, A_c)
    m: object = 0.0           # parameter k^2
    mc: object = 1.0          # k'^2
    K: object = 0.0
    lam: object = 0.0         # dtau/dt
    u0: object = 0.0
    nu: object = 0.0          # mean precession rate
    kappa: object = 0.0       # coefficient of the periodic part of psi
    kp: object = 1.0          # k'
    k1p2: object = 0.0        # 1 - k1^2 of the Gauss transformation
    N: object = 0.0           # characteristic of the transformed third-kind integral
    RJc: object = 0.0         # complete R_J of the periodic part
    rho: object = 0.0         # separatrix: A_a / (1 + A_c)
    period: object = 0.0
    symmetric: bool = False
    P0: object = 0.0          # periodic part of psi at t = 0


@dataclass(frozen=True)
class _Axes:
    """Which principal axis the momentum circles (``c``), the middle axis ``b`` and the third
    ``a``; ``sep`` on the separatrix; ``hi`` the axis of largest inertia."""

    a: int
    b: int
    c: int
    sep: bool
    hi: int
    rho4: object


def _axes(J, Ip, n, dI) -> _Axes:
    """Order by the exact second moments (I ascending = J descending), not by rounded inertias,
    and classify the orbit by the sign of ``G^2 - 2T I_mid``."""
    lo, mid, hi = sorted(range(3), key=lambda i: (-J[i], i))
    sep = False
    rho4 = None
    if dI(mid, lo) == 0:
        c, a = hi, lo
    elif dI(hi, mid) == 0:
        c, a = lo, hi
    else:
        rho4 = dI(mid, lo) * Ip[hi] / (dI(hi, mid) * Ip[lo])
        # sign of G^2 - 2T I_mid; scaled so that tiny components do not underflow to "0"
        sc_ = max(abs(n[hi]), abs(n[lo]))
        num = (n[hi] / sc_) ** 2 - rho4 * (n[lo] / sc_) ** 2 if sc_ > 0 else 0 * sc_
        if num > 0:
            c, a = hi, lo
        elif num < 0:
            c, a = lo, hi
        else:
            c, a, sep = hi, lo, True
    return _Axes(a=a, b=mid, c=c, sep=sep, hi=hi, rho4=rho4)


@dataclass(frozen=True)
class _Amplitudes:
    """Unit amplitudes ``A_a, A_b, A_c``, the parameter ``m = k^2`` and ``mc = k'^2``, the
    inertia differences ``|I_c - I_b|``, ``|I_c - I_a|`` and ``sg`` = sign of ``I_c - I_b``."""

    Aa: object
    Ab: object
    Ac: object
    m: object
    mc: object
    dcb: object
    dca: object
    sg: int
    symmetric: bool


def _amplitudes(X, Ip, n, dI, ax: _Axes) -> _Amplitudes:
    a, b, c = ax.a, ax.b, ax.c
    Ia, Ib, Ic = Ip[a], Ip[b], Ip[c]
    dcb, dca, dba = abs(dI(c, b)), abs(dI(c, a)), abs(dI(b, a))
    sg = 1 if c == ax.hi else -1  # sign of I_c - I_b (from J, not from rounded inertias)
    symmetric = dba == 0
    rho1 = dcb * Ia / (dca * Ib)
    rho2 = dca * Ib / (dcb * Ia)
    rho3 = dba * Ic / (Ib * dca)
    # unit amplitudes: sums of squares (hypot: no underflow), independent of the signs
    Aa = X.hypot(n[a], n[b] * X.sqrt(rho1))
    Ab = X.hypot(n[b], n[a] * X.sqrt(rho2))
    Ac = X.hypot(n[c], n[b] * X.sqrt(rho3))
    if symmetric:
        m_par, mc = 0 * Aa, 1 + 0 * Aa
    elif ax.sep:
        m_par, mc = 1 + 0 * Aa, 0 * Aa
    else:
        m_dir = rho3 * (Ab / Ac) ** 2
        if m_dir < 0.5:
            m_par, mc = m_dir, 1 - m_dir
        else:
            # mc = (n_c^2 - rho n_a^2) / A_c^2, formed from ratios
            rho = ax.rho4 if c == ax.hi else 1 / ax.rho4
            mc = (n[c] / Ac) ** 2 - rho * (n[a] / Ac) ** 2
            if not mc > X.tiny or (X.exact_m and 1 - mc == 1):
                # closer to the separatrix than this arithmetic resolves: more digits needed
                raise _OutOfRange
            m_par = 1 - mc
    return _Amplitudes(Aa=Aa, Ab=Ab, Ac=Ac, m=m_par, mc=mc, dcb=dcb, dca=dca, sg=sg, symmetric=symmetric)


def _working_frame(n, ax: _Axes):
    """The right-handed working frame (a signed permutation of the principal axes) with
    ``n_c >= 0`` (and ``n_a >= 0`` on the separatrix), and the unit momentum in it."""
    a, b, c = ax.a, ax.b, ax.c
    sc = -1 if n[c] < 0 else 1
    sa = (-1 if n[a] < 0 else 1) if ax.sep else 1
    P = np.zeros((3, 3))
    P[a, 0] = P[b, 1] = P[c, 2] = 1.0
    sb = sa * sc * int(round(np.linalg.det(P)))
    W = P * np.array([sa, sb, sc], dtype=float)
    return W, (sa * n[a], sb * n[b], sc * n[c])


def _separatrix_consts(X, out: _Consts, G, am: _Amplitudes, nw, Ic, lam1, C1) -> _Consts:
    """Phase, precession rate and the coefficient of the arctangent on the separatrix."""
    na, nb, _ = nw
    Aa, Ab, Ac = am.Aa, am.Ab, am.Ac
    out.u0 = X.asinh((nb / Ab) / (na / Aa))
    out.nu = G * (1 / Ic + C1)
    out.kappa = C1 * 2 * Ac / (lam1 * Aa)
    out.rho = Aa / (1 + Ac)
    out.A = (Aa, 1 + 0 * Aa, Ac)  # A_b = 1 on the separatrix (m -> G e_b)
    out.period = math.inf
    return out


def _elliptic_consts(X, out: _Consts, G, am: _Amplitudes, nw, Ic, lam1, C1) -> _Consts:
    """K, the phase, the Gauss transformation's constants, the mean precession rate and the
    period of a periodic orbit."""
    na, nb, _ = nw
    Aa, Ab, Ac, mc = am.Aa, am.Ab, am.Ac, am.mc
    K = X.K(mc)
    kp = X.sqrt(mc)
    k1 = (1 - kp) / (1 + kp)
    k1p2 = 4 * kp / ((1 + kp) * (1 + kp))
    N = -k1 * Aa * Aa / ((1 + Ac) * (1 + Ac))  # -k1 (1 - A_c)/(1 + A_c), 1 - A_c^2 = A_a^2
    Gam = (1 + k1) * 2 * Ac * k1 / (3 * (1 + Ac) * (1 + Ac))
    RJc = X.RJ(0 * K, k1p2, 1, 1 - N) if k1 != 0 else 0 * K
    Ibar1 = 1 / (1 + Ac) + Gam * RJc / K  # G times the mean of 1/(G + m_c)
    s0, c0 = nb / Ab, na / Aa
    r0 = X.hypot(s0, c0)
    out.u0 = _F_sc(X, s0 / r0, c0 / r0, mc, K)
    out.K, out.kp, out.k1p2, out.N, out.RJc = K, kp, k1p2, N, RJc
    out.nu = G * (1 / Ic + C1 * Ibar1)
    out.kappa = C1 * Gam / lam1
    out.period = 4 * K / abs(out.lam)  # cn, sn have period 4K (dn alone 2K)
    return out


def _setup(Jp, mvec, X) -> _Consts:
    """Constants of the motion from principal second moments ``Jp`` and momentum ``mvec``.

    ``X`` supplies scalar arithmetic (float64 or mpmath); differences of inertia are formed
    from the second moments (``I_i - I_j = J_j - J_i``), never as differences of inertias.
    """
    J = [X.num(v) for v in Jp]
    mv = [X.num(v) for v in mvec]
    Ip = [J[1] + J[2], J[0] + J[2], J[0] + J[1]]

    def dI(i, j):  # I_i - I_j
        return J[j] - J[i]

    G = X.norm3(mv[0], mv[1], mv[2])
    if G == 0:
        return _Consts(kind="rest")
    # steady rotation: m x omega vanishes exactly (m along a principal axis, or a sphere)
    # (a logical test: the product m_j m_k (I_j - I_k) could underflow for tiny data)
    steady = all(mv[j] == 0 or mv[k] == 0 or dI(j, k) == 0 for j, k in ((1, 2), (2, 0), (0, 1)))
    if steady:
        return _Consts(kind="steady", G=G)
    n = [v / G for v in mv]
    ax = _axes(J, Ip, n, dI)
    Ia, Ib, Ic = Ip[ax.a], Ip[ax.b], Ip[ax.c]
    am = _amplitudes(X, Ip, n, dI, ax)
    W, nw = _working_frame(n, ax)
    na, nb, _ = nw
    # rates per unit |m| (then scaled by G: no underflow of G^2 for tiny momenta)
    lam1 = am.sg * am.Ac * X.sqrt(am.dcb * am.dca / (Ia * Ib)) / Ic
    if lam1 == 0:  # underflow (a momentum within 1e-300 of an axis of a symmetric body)
        raise _OutOfRange
    # C1 = (2T - G^2/I_c) / G^2 as a sum of terms of one sign
    C1 = am.sg * (na * na * am.dca / (Ia * Ic) + nb * nb * am.dcb / (Ib * Ic))
    out = _Consts(kind="separatrix" if ax.sep else "elliptic", G=G, W=W, Iw=(Ia, Ib, Ic),
                  A=(am.Aa, am.Ab, am.Ac), m=am.m, mc=am.mc, lam=G * lam1, symmetric=am.symmetric)
    if ax.sep:
        return _separatrix_consts(X, out, G, am, nw, Ic, lam1, C1)
    return _elliptic_consts(X, out, G, am, nw, Ic, lam1, C1)


# -- float64 evaluation ------------------------------------------------------------------------



def _momentum_float(c: _Consts, t):
    """Working-frame momentum (n, 3) at flat times t (float64), and what the precession angle
    needs: ``tau`` on the separatrix, else ``(x, sn, cn, dn, sgn)`` at the reduced argument."""
    G = c.G
    Aa, Ab, Ac = c.A
    p, e = two_prod(c.lam, t)
    hi, e2 = two_sum(p, c.u0)
    if c.kind == "separatrix":
        tau = hi + (e2 + e)
        with np.errstate(over="ignore"):
            sech = 1.0 / np.cosh(tau)
        return G * np.stack([Aa * sech, np.tanh(tau), Ac * sech], -1), tau
    r, nper = reduce_period(hi, e + e2, 2.0 * c.K)
    r = np.clip(r, -c.K, c.K)
    x = np.abs(r)
    sn, cn, dn = sncndn_quarter(x, c.m, c.mc, c.K)
    sgn = np.where(r < 0, -1.0, 1.0)
    par = np.where(np.fmod(np.abs(nper), 2.0) == 1.0, -1.0, 1.0)
    mw = G * np.stack([Aa * par * cn, Ab * par * sgn * sn, Ac * dn], -1)
    return mw, (x, sn, cn, dn, sgn)


def _eval_float(c: _Consts, t):
    """Working-frame momentum (n, 3) and precession angle (n,) at flat times t (float64)."""
    mw, aux = _momentum_float(c, t)
    if c.kind == "separatrix":
        tau = aux
        per = np.arctan(c.rho * np.tanh(0.5 * tau)) - math.atan(c.rho * math.tanh(0.5 * c.u0))
        return mw, _angle_mod_2pi(c.nu, t, -c.kappa * per)
    x, sn, cn, dn, sgn = aux
    per = _periodic(c, x, sn, cn, dn) * sgn
    return mw, _angle_mod_2pi(c.nu, t, c.kappa * (per - c.P0))


def _periodic(c: _Consts, x, sn, cn, dn):
    """Periodic part of the third-kind integral on 0 <= x <= K (Gauss transformation + R_J)."""
    if c.N == 0 or c.symmetric:
        return np.zeros_like(x)
    kp = c.kp
    s1 = (1.0 + kp) * sn / (1.0 + dn)
    s1 = np.minimum(s1, 1.0)
    xx = 2.0 * (1.0 + kp) * cn * cn / ((1.0 + dn) * (dn + kp))
    yy = xx + c.k1p2 * s1 * s1
    pp = 1.0 - c.N * s1 * s1
    return s1 ** 3 * _sp.elliprj(xx, yy, 1.0, pp) - x * (c.RJc / c.K)


# -- mpmath evaluation -------------------------------------------------------------------------

def _momentum_mp(c: _Consts, t, mp):
    """:func:`_momentum_float` at one mpmath time (mpmath)."""
    G = c.G
    Aa, Ab, Ac = c.A
    tau = c.lam * t + c.u0
    if c.kind == "separatrix":
        sech = mp.sech(tau)
        return [G * Aa * sech, G * mp.tanh(tau), G * Ac * sech], tau
    nper = mp.nint(tau / (2 * c.K))
    r = tau - 2 * c.K * nper
    x = abs(r)
    sn = mp.ellipfun("sn", x, m=c.m)
    cn = mp.ellipfun("cn", x, m=c.m)
    dn = mp.ellipfun("dn", x, m=c.m)
    sgn = -1 if r < 0 else 1
    par = -1 if int(nper) % 2 else 1
    return [G * Aa * par * cn, G * Ab * par * sgn * sn, G * Ac * dn], (x, sn, cn, dn, sgn)


def _periodic_mp(c: _Consts, x, sn, cn, dn, sgn, mp):
    """:func:`_periodic` (times the sign of the reduced argument) in mpmath."""
    if c.N == 0 or c.symmetric:
        return 0
    kp = c.kp
    s1 = min((1 + kp) * sn / (1 + dn), mp.mpf(1))
    xx = 2 * (1 + kp) * cn * cn / ((1 + dn) * (dn + kp))
    yy = xx + c.k1p2 * s1 * s1
    return sgn * (s1 ** 3 * mp.elliprj(xx, yy, 1, 1 - c.N * s1 * s1) - x * c.RJc / c.K)


def _eval_mp(c: _Consts, tval, mp):
    """Working-frame momentum (3 mpf) and precession angle at one time (mpmath)."""
    t = mp.mpf(tval)
    mw, aux = _momentum_mp(c, t, mp)
    if c.kind == "separatrix":
        tau = aux
        per = mp.atan(c.rho * mp.tanh(tau / 2)) - mp.atan(c.rho * mp.tanh(c.u0 / 2))
        return mw, c.nu * t - c.kappa * per
    return mw, c.nu * t + c.kappa * (_periodic_mp(c, *aux, mp) - c.P0)


def _mp_minimal_rotation(nv, mp):
    n1, n2, n3 = nv
    q = 1 / (1 + n3)
    return mp.matrix([[1 - n1 * n1 * q, -n1 * n2 * q, -n1],
                      [-n1 * n2 * q, 1 - n2 * n2 * q, -n2],
                      [n1, n2, n3]])


# -- the solution object -----------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class EulerTopSolution(RotationSolution):
    """Closed-form free rotation (see the module docstring); built by :func:`thetasol.solve_rotation`."""

    _c: _Consts = field(default=None, repr=False)
    _P: np.ndarray = field(default=None, repr=False)   # working frame -> body frame
    _S: np.ndarray = field(default=None, repr=False)   # Q = S R3(psi) B(m) P^T
    _Iw: np.ndarray = field(default=None, repr=False)
    _mp: object = field(default=None, repr=False)

    # float64 ------------------------------------------------------------------------------
    def _evaluate(self, t):
        if self._mp is not None:
            om, Q = self._evaluate_mp(t)
            if self.dps is None:  # float64 API served by the mpmath path (extreme data)
                return om.astype(float), Q.astype(float)
            return om, Q
        c = self._c
        if c.kind in ("rest", "steady"):
            return _uniform_rotation(self.Q0, self.omega0 if c.kind == "steady" else np.zeros(3), t)
        mw, psi = _eval_float(c, t)
        return (mw / self._Iw) @ self._P.T, _attitude(self._S, psi, mw, self._P)

    def _omega(self, t):
        if self._mp is not None or self._c.kind in ("rest", "steady"):
            return self._evaluate(t)[0]
        mw, _ = _momentum_float(self._c, t)
        return (mw / self._Iw) @ self._P.T

    # mpmath -------------------------------------------------------------------------------
    def _evaluate_mp(self, t):
        import mpmath as mp

        c = self._c
        n = t.size
        om = np.empty((n, 3), dtype=object)
        Qo = np.empty((n, 3, 3), dtype=object)
        with mp.workdps(self._mp["wdps"]):
            P = self._mp.get("P")
            S = self._mp.get("S")
            Q0 = self._mp["Q0"]
            w0 = self._mp["w0"]
            for i, tv in enumerate(t):
                if c.kind == "rest":
                    w, Q = mp.matrix(3, 1), Q0
                elif c.kind == "steady":
                    tt = mp.mpf(tv)
                    wn = mp.norm(w0)
                    ax = w0 / wn
                    Kx = mp.matrix([[0, -ax[2], ax[1]], [ax[2], 0, -ax[0]], [-ax[1], ax[0], 0]])
                    ang = wn * tt
                    Q = Q0 * (mp.eye(3) + mp.sin(ang) * Kx + (1 - mp.cos(ang)) * Kx * Kx)
                    w = w0
                else:
                    mw, psi = _eval_mp(c, tv, mp)
                    G = mp.sqrt(mw[0] ** 2 + mw[1] ** 2 + mw[2] ** 2)
                    B = _mp_minimal_rotation([v / G for v in mw], mp)
                    R3 = mp.matrix([[mp.cos(psi), -mp.sin(psi), 0], [mp.sin(psi), mp.cos(psi), 0], [0, 0, 1]])
                    Q = S * R3 * B * P.T
                    w = P * mp.matrix([mw[k] / self._mp["Iw"][k] for k in range(3)])
                for k in range(3):
                    om[i, k] = +w[k]
                    for j in range(3):
                        Qo[i, k, j] = +Q[k, j]
        return om, Qo


def _basic_invariants(Jm, am, omega0) -> dict:
    """energy = T + V (V = c tr(J)/2 is constant for a = c 1), H = -2 energy (4.9), m2 = |m|^2."""
    I = inertia_from_moments(Jm)
    m = I @ omega0
    energy = 0.5 * float(omega0 @ m) + 0.5 * float(np.trace(am) / 3.0 * np.trace(Jm))
    return {"energy": energy, "H": -2.0 * energy, "m2": _norm(m) ** 2}


def _steady_rate(c, omega0):
    return _norm(omega0) if c.kind == "steady" else 0.0


def _method(c) -> tuple[str, str]:
    """(method, case): rest, steady rotations and the symmetric top are elementary, the rest elliptic."""
    if c.kind in ("rest", "steady"):
        return "elementary", c.kind
    if c.kind == "separatrix":
        return "elliptic", "separatrix"
    return ("elementary", "symmetric") if c.symmetric else ("elliptic", "")


def solve_euler_top(Jm: np.ndarray, am: np.ndarray, Q0: np.ndarray, omega0: np.ndarray,
                    dps: int | None = None) -> EulerTopSolution:
    """Build the Euler-top solution from validated data (``a`` isotropic or zero)."""
    inv = _basic_invariants(Jm, am, omega0)
    if dps is not None:
        return _solve_mp(Jm, am, Q0, omega0, dps, inv)
    Jp, R = _principal_frame(Jm)
    Ip = np.array([Jp[1] + Jp[2], Jp[0] + Jp[2], Jp[0] + Jp[1]])
    try:
        c = _setup(Jp, Ip * (R.T @ omega0), _FloatOps)
    except _OutOfRange:
        # k'^2 underflows (momentum within ~1e-160 of the unstable axis): same closed form
        # in mpmath, results rounded to float64
        return _solve_mp(Jm, am, Q0, omega0, 30, inv, float_output=True)
    method, case = _method(c)
    if c.kind in ("rest", "steady"):
        diag = dict(period=0.0, precession_rate=_steady_rate(c, omega0), m=0.0, case=case)
        return EulerTopSolution(Jm, am, Q0, omega0, method, inv, None, diag, _c=c)
    diag = dict(period=float(c.period), precession_rate=float(c.nu), m=float(c.m), case=case)
    P = R @ c.W
    Iw = np.array([float(v) for v in c.Iw])
    mw0, aux = _momentum_float(c, np.zeros(1))
    if c.kind == "elliptic":
        x0, sn, cn, dn, sgn = aux
        c.P0 = float(_periodic(c, x0, sn, cn, dn)[0] * sgn[0])
    n0 = _unit(mw0)[0]
    S = Q0 @ P @ _minimal_rotation(n0).T
    return EulerTopSolution(Jm, am, Q0, omega0, method, inv, None, diag, _c=c, _P=P, _S=S, _Iw=Iw)


def _setup_mp(Jm, omega0, mp):
    """Principal frame (mpmath eigensolver unless J is diagonal) and the constants, in mpmath."""
    X = _MpOps()
    Jmp = mp.matrix([[mp.mpf(float(v)) for v in row] for row in Jm])
    if not np.any(Jm - np.diag(np.diag(Jm))):
        Jp = [Jmp[i, i] for i in range(3)]
        R = mp.eye(3)
    else:
        ev, R = mp.eigsy(Jmp)
        Jp = [ev[i] for i in range(3)]
        if mp.det(R) < 0:
            for i in range(3):
                R[i, 2] = -R[i, 2]
    Ip = [Jp[1] + Jp[2], Jp[0] + Jp[2], Jp[0] + Jp[1]]
    wp = R.T * mp.matrix([mp.mpf(float(v)) for v in omega0])
    return _setup(Jp, [Ip[i] * wp[i] for i in range(3)], X), R


def _solve_mp(Jm, am, Q0, omega0, dps, inv, float_output=False):
    import mpmath as mp

    wdps = dps + 10
    while True:
        with mp.workdps(wdps):
            try:
                c, R = _setup_mp(Jm, omega0, mp)
                break
            except _OutOfRange:
                if wdps > 20000:
                    raise ValueError("the momentum is too close to the separatrix to resolve "
                                     "(k'^2 below 1e-20000)") from None
                wdps *= 2
    with mp.workdps(wdps):
        Q0m = mp.matrix([[mp.mpf(float(v)) for v in row] for row in Q0])
        w0 = mp.matrix([mp.mpf(float(v)) for v in omega0])
        store = {"Q0": Q0m, "w0": w0, "wdps": wdps}
        dps = None if float_output else dps
        method, case = _method(c)
        if c.kind in ("rest", "steady"):
            diag = dict(period=0.0, precession_rate=_steady_rate(c, omega0), m=0.0, case=case)
            return EulerTopSolution(Jm, am, Q0, omega0, method, inv, dps, diag, _c=c, _mp=store)
        diag = dict(period=float(c.period), precession_rate=float(c.nu), m=float(c.m), case=case)
        Wm = mp.matrix(c.W.tolist())
        P = R * Wm
        mw0, aux = _momentum_mp(c, mp.mpf(0), mp)
        c.P0 = _periodic_mp(c, *aux, mp) if c.kind == "elliptic" else 0
        G = mp.sqrt(mw0[0] ** 2 + mw0[1] ** 2 + mw0[2] ** 2)
        B0 = _mp_minimal_rotation([v / G for v in mw0], mp)
        S = Q0m * P * B0.T
        store.update(P=P, S=S, Iw=list(c.Iw))
        return EulerTopSolution(Jm, am, Q0, omega0, method, inv, dps, diag, _c=c, _mp=store)
