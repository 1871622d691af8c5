"""The Lagrange top (Section 5): a symmetric body, mass centre on the symmetry axis, full attitude.

In the principal frame at the fixed point (symmetry axis ``e3``, mass centre ``l e3`` with ``l > 0``)
and a space frame whose third axis is the upward vertical, ``I = diag(A, A, C)`` and
``u = cos theta = gamma_3``.  With ``a = M3/A``, ``b = Mz/A`` (``Mz = M.gamma``, the vertical
angular momentum), ``beta = 2 m g l / A`` and ``alpha = (2H - M3^2/C)/A``:

    udot^2 = f(u) = (1 - u^2)(alpha - beta u) - (b - a u)^2 = beta (u - u1)(u - u2)(u - u3)

(Goldstein section 5.7; Whittaker ch. VI), ``u = u1 + D sn^2(lambda (t - t1) | m)`` with
``D = u2 - u1``, ``m = D / (u3 - u1)``, ``lambda = sqrt(beta (u3 - u1)) / 2``.

The attitude is carried by the Cayley-Klein parameters (a unit quaternion)

    alpha_CK = cos(theta/2) e^{i chi+},   beta_CK = i sin(theta/2) e^{i chi-},
    q = (cos(theta/2) cos chi+, sin(theta/2) cos chi-, sin(theta/2) sin chi-, cos(theta/2) sin chi+),

``chi+- = (psi +- phi)/2`` for the zxz Euler angles ``Q = Rz(psi) Rx(theta) Rz(phi)``, with

    2 chi+' = kappa + (b + a)/(1 + u),    2 chi-' = -kappa + (b - a)/(1 - u),   kappa = a (A/C - 1).

No Euler angle is formed: ``cos^2(theta/2) = w/2`` and ``sin^2(theta/2) = v/2`` with
``w = 1 + u = w1 + D sn^2`` and ``v = 1 - u = v2 + D cn^2`` (sums of non-negative terms), and the two
phase integrals are Legendre integrals of the third kind written so that no term cancels:

* ``int dx / (w1 + D sn^2) = Pi(-D/w1; am x | m) / w1`` in the form, for ``n = -N < 0`` and ``mu = m/N``,
  ``Pi(n; phi | m) = (mu/3) s^3 R_J(c^2, d^2, 1, 1 + mu s^2) + atan2(p s, c d) / p``,
  ``p^2 = (1 + N)(1 + mu)`` (from the ``n <-> m/n`` relation, A&S 17.7.3-17.7.4 / DLMF 19.7.8-19.7.9, both
  terms positive).  Near the hanging position (``w1 -> 0``) the arctangent carries the jump of
  ``chi+`` by ``pi`` with its full relative accuracy.  The Legendre-Carlson form
  ``F + (n/3) s^3 R_J`` subtracts two O(1) numbers to get ``Pi ~ sqrt(w1/D)`` and multiplies by
  ``(b + a)/w1 ~ w1^(-1/2)``, so on a top near the hanging position its phase loses about half the
  digits, which this form keeps (tests/test_heavy_top.py::test_hanging_phase_against_mpmath);
* ``int dx / (v2 + D cn^2) = Pi(D/v1; am x | m) / v1``, ``v1 = 1 - u1``, with the Carlson form
  ``s R_F(c^2, d^2, 1) + (n/3) s^3 R_J(c^2, d^2, 1, (v2 + D c^2)/v1)`` (all terms positive).

The frames, ``A``, ``C``, the integrals and ``w1``, ``v2``, ``D`` (from the cubic written about the
initial point) are formed in 60-digit mpmath from the float64 data taken as exact; ``lambda``,
the initial argument, ``2K`` and the per-period phase increments are kept as two float64 words,
so that the error does not grow with ``t`` (one-word float64 frequencies would add a phase error
growing like ``eps t``; tests/test_heavy_top.py checks far times against 80-bit heyoka).  When the axis passes exactly through a pole (``b + a = 0``,
``w1 = 0``; ``b - a = 0``, ``v2 = 0``) the amplitude is taken signed, ``sqrt(D/2) sn`` (resp.
``sqrt(D/2) cn``), and the jump disappears.  Far times: the argument ``lambda (t - t1)`` is reduced
modulo ``2K`` with exact products, each phase is ``j Delta + (periodic part)`` with ``j Delta``
reduced modulo ``2 pi`` exactly (:func:`thetasol.core.attitude.angle_mod_2pi`).

The two constant phases (the symmetries ``Q -> Rz(dpsi) Q Rz(dphi)``) are fitted to ``Q0`` and
``omega0`` at ``t = 0``; the residual of the fit is ``diagnostics["fit_residual"]``.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import mpmath
import numpy as np
from scipy import special as sp

from thetasol.core.attitude import angle_mod_2pi
from thetasol.core.dd import two_prod
from thetasol.core.so3 import complete_frame
from thetasol.special.elliptic import ellipj

__all__ = ["lagrange_frame", "build_lagrange_top", "lagrange_state", "SYMMETRY_RTOL"]

#: Relative tolerance for recognizing I1 = I2 and the centre on the symmetry axis (a few ulps of
#: a tensor formed as R diag(I) R^T in float64; larger asymmetries are another body).
SYMMETRY_RTOL = 1e-13
_DPS = 60
#: The fit of the two constant phases to (Q0, omega0) leaves a few ulps;
#: more means the turning points or the initial argument are wrong.
FIT_WARN = 1e-12


# -- frames -------------------------------------------------------------------------------------

def lagrange_frame(I: np.ndarray, center: np.ndarray, rtol: float = SYMMETRY_RTOL
                   ) -> tuple[float, float, np.ndarray] | None:
    """``(A, C, P)`` when ``I`` is symmetric about the axis through ``center``, else None.

    ``P`` (columns) is a right-handed body frame whose third axis is ``center/|center|``:
    ``P^T I P = diag(A, A, C)`` up to ``rtol |I|``.
    """
    P = complete_frame(center / np.linalg.norm(center))
    Ip = P.T @ I @ P
    scale = np.max(np.abs(np.linalg.eigvalsh(I)))
    off = max(abs(Ip[0, 2]), abs(Ip[1, 2]), abs(Ip[0, 1]), 0.5 * abs(Ip[0, 0] - Ip[1, 1]))
    if off > rtol * scale:
        return None
    return 0.5 * (Ip[0, 0] + Ip[1, 1]), Ip[2, 2], P


# -- set-up: the cubic and its roots in mpmath ----------------------------------------------------

@dataclass(frozen=True)
class _Roots:
    """Turning points, elliptic parameters and rates (float64, each rounded once from 60 digits;
    the quantities that multiply t carry a second word ``*_lo``)."""

    w1: float      # 1 + u1
    v2: float      # 1 - u2
    D: float       # u2 - u1
    d31: float     # u3 - u1
    m: float
    mc: float
    lam: float     # lambda
    x0: float      # lambda (0 - t1), the initial argument
    s_minus: float  # b + a = (Mz + M3)/A
    s_plus: float   # b - a = (Mz - M3)/A
    a: float        # M3 / A
    omega3: float   # M3 / C
    kappa: float    # a (A/C - 1)
    K: float
    lam_lo: float
    x0_lo: float
    K2: tuple       # 2K as (hi, lo)
    rate_plus: tuple   # chi+ per period of x, (hi, lo)
    rate_minus: tuple  # chi- per period of x, (hi, lo)


def _hilo(x):
    hi = float(x)
    return hi, float(x - mpmath.mpf(hi))


def _bisect(p, lo, hi):
    """The root of ``p`` in ``[lo, hi]`` with ``p(lo) < 0 < p(hi)``, to the working precision
    (bisection: slow and certain)."""
    for _ in range(4 * mpmath.mp.dps):
        mid = (lo + hi) / 2
        if mid in (lo, hi):
            break
        if p(mid) < 0:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2


def _mp_roots(beta, c2, c1, c0, w0, v0, s_minus, s_plus):
    """Sorted roots xi1 <= xi2 <= xi3 of ``beta xi^3 + c2 xi^2 + c1 xi + c0`` (``xi = u - u0``)."""
    known = None
    if c0 == 0:
        known = mpmath.mpf(0)
    elif s_minus == 0:
        known = -w0
    elif s_plus == 0:
        known = v0
    if known is None:
        known = _bisect(lambda x: ((beta * x + c2) * x + c1) * x + c0, -w0, mpmath.mpf(0))
    b1 = c2 + known * beta
    b0 = c1 + known * b1
    disc = max(b1 * b1 - 4 * beta * b0, mpmath.mpf(0))
    sq = mpmath.sqrt(disc)
    q = -(b1 + mpmath.sign(b1) * sq) / 2 if b1 != 0 else -sq / 2
    ra = q / beta
    rb = b0 / q if q != 0 else mpmath.mpf(0)
    return sorted([known, ra, rb])


def _mp_frame(e3):
    """Orthonormal right-handed frame (list of 3 mp column vectors) with third column ``e3`` (mp, unit)."""
    k = min(range(3), key=lambda i: abs(e3[i]))
    t = [mpmath.mpf(int(i == k)) for i in range(3)]
    d = sum(t[i] * e3[i] for i in range(3))
    e1 = [t[i] - d * e3[i] for i in range(3)]
    n1 = mpmath.sqrt(sum(x * x for x in e1))
    e1 = [x / n1 for x in e1]
    e2 = [e3[1] * e1[2] - e3[2] * e1[1], e3[2] * e1[0] - e3[0] * e1[2], e3[0] * e1[1] - e3[1] * e1[0]]
    return [e1, e2, e3]


def _unit_mp(v):
    v = [mpmath.mpf(float(x)) for x in v]
    n = mpmath.sqrt(sum(x * x for x in v))
    return [x / n for x in v]


def _mp_data(I, center, Q0, omega0, mgl):
    """The principal-frame data in 60 digits from the float64 data taken as exact.

    Returns ``(P, S, A, C, beta, gamma, omega)``: frames as mp columns, ``gamma`` the unit upward
    vertical and ``omega`` the angular velocity in the principal frame.  ``Q0`` is orthogonal to a
    few ulps only; ``|Q0^T up|`` is kept as a factor of ``beta`` (the float64 equations of
    motion see ``Q^T gravity`` with that length).
    """
    mf = mpmath.mpf
    P = _mp_frame(_unit_mp(center))
    Im = [[mf(float(x)) for x in row] for row in I]
    quad = lambda u, v: sum(u[i] * Im[i][k] * v[k] for i in range(3) for k in range(3))  # noqa: E731
    A = (quad(P[0], P[0]) + quad(P[1], P[1])) / 2
    C = quad(P[2], P[2])
    Qm = [[mf(float(x)) for x in row] for row in Q0]
    up = mgl[1]
    g_body = [sum(Qm[k][i] * up[k] for k in range(3)) for i in range(3)]   # Q0^T up
    gamma = [sum(P[j][i] * g_body[i] for i in range(3)) for j in range(3)]
    nrm = mpmath.sqrt(sum(x * x for x in gamma))
    gamma = [x / nrm for x in gamma]
    w = [mf(float(x)) for x in omega0]
    omega = [sum(P[j][i] * w[i] for i in range(3)) for j in range(3)]
    beta = 2 * mgl[0] * nrm / A
    S = _mp_frame(up)
    return P, S, A, C, beta, gamma, omega


def _turning_points(A, C, B, g, w, lam=0) -> _Roots:
    """Roots of f about ``u0``, the elliptic parameters and the rates, all from the mp data.

    ``lam`` is the axial rotor momentum of a Lagrange gyrostat (``M3 = C omega3 + lam``); it changes
    ``a = M3 / A`` and ``kappa = omega3 - a`` (``phidot = omega3 - u psidot``), nothing else."""
    mf = mpmath.mpf
    g1, g2, g3 = g
    w1_, w2_, w3_ = w
    am = (C * w3_ + lam) / A
    wp2 = w1_ ** 2 + w2_ ** 2
    h = w1_ * g1 + w2_ * g2
    gp2 = g1 ** 2 + g2 ** 2
    u0 = g3
    w0 = 1 + g3 if g3 >= 0 else gp2 / (1 - g3)
    v0 = 1 - g3 if g3 <= 0 else gp2 / (1 + g3)
    udot0 = g1 * w2_ - g2 * w1_
    s_minus, s_plus = h + am * w0, h - am * v0
    # f(u0 + xi) = udot0^2 + c1 xi + c2 xi^2 + beta xi^3
    c1 = -2 * u0 * wp2 - B * gp2 + 2 * am * h
    c2 = -wp2 + 2 * B * u0 - am ** 2
    xi1, xi2, xi3 = _mp_roots(B, c2, c1, udot0 ** 2, w0, v0, s_minus, s_plus)
    xi1, xi2 = min(xi1, mf(0)), max(xi2, mf(0))
    w1 = mf(0) if s_minus == 0 else max(w0 + xi1, mf(0))
    v2 = mf(0) if (s_plus == 0 and wp2 - B * v0 > 0) else max(v0 - xi2, mf(0))
    D, d31, d32 = xi2 - xi1, xi3 - xi1, xi3 - xi2
    m, mc = D / d31, d32 / d31
    lam = mpmath.sqrt(B * d31) / 2
    x0 = mf(0)
    if D > 0:
        phi0 = mpmath.atan2(mpmath.sqrt(-xi1), mpmath.sqrt(xi2))
        x0 = mpmath.ellipf(phi0, m) * (1 if udot0 >= 0 else -1)
    kappa = am * (A / C - 1) if lam == 0 else w3_ - am
    K = mpmath.ellipk(m) if mc > 0 else mpmath.inf
    rp, rm = _mp_rates(kappa, K, lam, s_minus, s_plus, w1, v2, D, d31, mc)
    return _Roots(float(w1), float(v2), float(D), float(d31), float(m), float(mc), float(lam), float(x0),
                  float(s_minus), float(s_plus), float(am), float(w3_), float(kappa), float(K),
                  _hilo(lam)[1], _hilo(x0)[1], _hilo(2 * K) if mc > 0 else (math.inf, 0.0), rp, rm)


def _mp_rates(kappa, K, lam, s_minus, s_plus, w1, v2, D, d31, mc):
    """Increments of chi+ and chi- over one period ``2K`` of x (60 digits, as (hi, lo) pairs)."""
    if mc == 0:
        return (0.0, 0.0), (0.0, 0.0)
    with mpmath.workdps(36):   # two float64 words need 32 digits; R_J's cost grows with them
        return _mp_rates_at(kappa, K, lam, s_minus, s_plus, w1, v2, D, d31, mc)


def _mp_rates_at(kappa, K, lam, s_minus, s_plus, w1, v2, D, d31, mc):
    Gm = mpmath.mpf(0)
    if s_minus != 0 and w1 > 0:   # (b + a)/w1 Pi(-D/w1 | m), the cancellation-free form
        mu = w1 / d31
        Gm = s_minus / (3 * d31) * mpmath.elliprj(0, mc, 1, 1 + mu) \
            + s_minus / mpmath.sqrt(w1 * (w1 + D) * (1 + mu)) * mpmath.pi / 2
    Gp = mpmath.mpf(0)
    if s_plus != 0:               # (b - a)/v1 Pi(D/v1 | m)
        v1 = v2 + D
        Gp = s_plus / v1 * (K + D / v1 / 3 * mpmath.elliprj(0, mc, 1, v2 / v1))
    return _hilo((kappa * K + Gm) / lam), _hilo((-kappa * K + Gp) / lam)


# -- the third-kind integrals --------------------------------------------------------------------

@dataclass(frozen=True)
class _Phase:
    """One Cayley-Klein phase: ``2 chi = sign kappa (t - t1) + G(x)/lambda``, ``G`` of the third kind."""

    kind: str      # "minus" (1/(1+u), hanging side), "plus" (1/(1-u), upright side) or "none"
    k1: float
    k2: float
    mu: float      # "minus": m/N;  "plus": the characteristic n+
    p: float       # "minus": sqrt((1+N)(1+mu));  "plus": v1


def _phase_minus(R: _Roots) -> _Phase:
    """``G(x) = s- int_0^x dx / (w1 + D sn^2)``: the hanging side, the cancellation-free form."""
    s_minus = R.s_minus
    if s_minus == 0 or R.w1 == 0:
        return _Phase("none", 0.0, 0.0, 0.0, 0.0)
    w1, D = R.w1, R.D
    mu = w1 / R.d31
    k1 = s_minus / (3.0 * R.d31)
    k2 = s_minus / math.sqrt(w1 * (w1 + D) * (1.0 + mu))
    p = math.sqrt((w1 + D) * (1.0 + mu) / w1)
    return _Phase("minus", k1, k2, mu, p)


def _phase_plus(R: _Roots) -> _Phase:
    """``G(x) = s+ int_0^x dx / (v2 + D cn^2)``: the upright side, Carlson's form (no cancellation)."""
    if R.s_plus == 0:
        return _Phase("none", 0.0, 0.0, 0.0, 0.0)
    v1 = R.v2 + R.D
    return _Phase("plus", R.s_plus / v1, 0.0, R.D / v1, v1)


def _phase_G(ph: _Phase, r, s, c, d, R: _Roots):
    """``G`` at the reduced argument ``r`` (``s, c, d = sn, cn, dn``, ``|r| <= K``)."""
    if ph.kind == "none":
        return np.zeros_like(s)
    c2, d2 = c * c, d * d
    if ph.kind == "minus" and R.mc == 0:
        # separatrix (m = 1, sn = tanh): int dx/(w1 + D tanh^2) in elementary functions
        k = math.sqrt(R.D / R.w1)
        return R.s_minus / (R.w1 + R.D) * (r + k * np.arctan(k * s))
    if ph.kind == "minus":
        rj = sp.elliprj(c2, d2, 1.0, 1.0 + ph.mu * s * s)
        return ph.k1 * s ** 3 * rj + ph.k2 * np.arctan2(ph.p * s, c * d)
    rf = sp.elliprf(c2, d2, 1.0)
    rj = sp.elliprj(c2, d2, 1.0, (R.v2 + R.D * c2) / ph.p)
    return ph.k1 * (s * rf + ph.mu / 3.0 * s ** 3 * rj)


# -- the solution --------------------------------------------------------------------------------

@dataclass(frozen=True)
class _Constants:
    """Everything the evaluation needs (principal frame P, vertical frame S)."""

    P: np.ndarray
    S: np.ndarray
    R: _Roots
    minus: _Phase
    plus: _Phase
    limit_w: bool     # the axis passes exactly through the hanging position: signed sn amplitude
    limit_v: bool     # ... through the upright position: signed cn amplitude
    delta_plus: float
    delta_minus: float


def _reduce(c: _Constants, t):
    """``x = lambda t + x0 = 2 K j + r`` with exact products and the second words of ``lambda``,
    ``x0`` and ``2K``; returns (j, r)."""
    R = c.R
    p, e = two_prod(R.lam, t)
    e = e + (R.lam_lo * t + R.x0_lo)
    if math.isinf(R.K):  # on the separatrix (m = 1): no period
        return np.zeros_like(t), (p + R.x0) + e
    K2, K2_lo = R.K2
    j = np.rint((p + R.x0) / K2)
    q, qe = two_prod(j, K2)
    r = ((p - q) - qe) + ((e - j * K2_lo) + R.x0)
    return j, r


def _phases(c: _Constants, j, r, s, cn, dn):
    """The Cayley-Klein phases chi+ and chi- (radians, reduced modulo 2 pi)."""
    R = c.R
    Gm = _phase_G(c.minus, r, s, cn, dn, R)
    Gp = _phase_G(c.plus, r, s, cn, dn, R)
    tau = r / R.lam
    (rp, rp_lo), (rm, rm_lo) = R.rate_plus, R.rate_minus
    chi_p = angle_mod_2pi(rp, j, rp_lo * j + c.delta_plus + 0.5 * (R.kappa * tau + Gm / R.lam))
    chi_m = angle_mod_2pi(rm, j, rm_lo * j + c.delta_minus + 0.5 * (-R.kappa * tau + Gp / R.lam))
    return np.remainder(chi_p, 2.0 * math.pi), np.remainder(chi_m, 2.0 * math.pi)


def _state(c: _Constants, t):
    """(omega', Q') in the principal frame and the vertical frame."""
    R = c.R
    j, r = _reduce(c, t)
    s, cn, dn, _ = ellipj(r, R.m, R.mc)
    sign = np.where(np.mod(j, 2) == 0, 1.0, -1.0)   # sn(x) = sign sn(r), cn(x) = sign cn(r)
    w = R.w1 + R.D * s * s
    v = R.v2 + R.D * cn * cn
    chi_p, chi_m = _phases(c, j, r, s, cn, dn)
    half = math.sqrt(0.5 * R.D)
    amp_p = half * sign * s if c.limit_w else np.sqrt(0.5 * w)
    amp_m = half * sign * cn if c.limit_v else np.sqrt(0.5 * v)
    # omega_perp = (b - a u)/sin(theta) e_phi + udot/sin(theta) J e_phi, sin(theta) = 2 amp_p amp_m,
    # with the sn (cn) factor of a signed amplitude cancelled by hand.
    udot_red = 2.0 * R.lam * R.D * dn
    f_p, f_m = amp_p, amp_m
    if c.limit_w and c.limit_v:
        f_p, f_m, n1, n2 = half, half, 0.0 * s, udot_red
    elif c.limit_w:
        f_p, n1, n2 = half, -R.a * R.D * sign * s, udot_red * sign * cn
    elif c.limit_v:
        f_m, n1, n2 = half, R.a * R.D * sign * cn, udot_red * sign * s
    else:
        n1 = np.where(w <= v, R.s_minus - R.a * w, R.s_plus + R.a * v)
        n2 = udot_red * s * cn
    den = 2.0 * f_p * f_m
    with np.errstate(invalid="ignore", divide="ignore"):
        c1 = np.where(den > 0, n1 / den, 0.0)
        c2 = np.where(den > 0, n2 / den, 0.0)
    phi = chi_p - chi_m
    sp_, cp_ = np.sin(phi), np.cos(phi)
    omega = np.stack([c1 * sp_ - c2 * cp_, c1 * cp_ + c2 * sp_, np.full_like(s, R.omega3)], axis=-1)
    q = np.stack([amp_p * np.cos(chi_p), amp_m * np.cos(chi_m), amp_m * np.sin(chi_m),
                  amp_p * np.sin(chi_p)], axis=-1)
    return omega, _quat_to_matrix(q)


def _quat_to_matrix(q):
    q0, q1, q2, q3 = (q[..., k] for k in range(4))
    Q = np.empty(q.shape[:-1] + (3, 3))
    Q[..., 0, 0] = 1 - 2 * (q2 * q2 + q3 * q3)
    Q[..., 0, 1] = 2 * (q1 * q2 - q0 * q3)
    Q[..., 0, 2] = 2 * (q1 * q3 + q0 * q2)
    Q[..., 1, 0] = 2 * (q1 * q2 + q0 * q3)
    Q[..., 1, 1] = 1 - 2 * (q1 * q1 + q3 * q3)
    Q[..., 1, 2] = 2 * (q2 * q3 - q0 * q1)
    Q[..., 2, 0] = 2 * (q1 * q3 - q0 * q2)
    Q[..., 2, 1] = 2 * (q2 * q3 + q0 * q1)
    Q[..., 2, 2] = 1 - 2 * (q1 * q1 + q2 * q2)
    return Q


def _fit_offsets(c: _Constants, Qp0, wp0, beta):
    """The constant phases: ``Q' = Rz(dpsi) Q~ Rz(dphi)`` and ``omega' = Rz(-dphi) omega~`` at t = 0."""
    wt, Qt = _state(c, np.zeros(1))
    wt, Qt = wt[0], Qt[0]
    zg, zg_t = complex(Qp0[2, 0], Qp0[2, 1]), complex(Qt[2, 0], Qt[2, 1])
    scale = math.sqrt(wp0 @ wp0 + beta) or 1.0
    zw, zw_t = complex(wp0[0], wp0[1]) / scale, complex(wt[0], wt[1]) / scale
    prod = zg_t.conjugate() * zg + zw_t.conjugate() * zw   # ~ e^{-i dphi}
    dphi = -math.atan2(prod.imag, prod.real) if abs(prod) > 0 else 0.0
    cz, sz = math.cos(-dphi), math.sin(-dphi)
    Rm = np.array([[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]])
    M = Qp0 @ Rm @ Qt.T
    dpsi = math.atan2(M[1, 0] - M[0, 1], M[0, 0] + M[1, 1])
    cpsi, spsi = math.cos(dpsi), math.sin(dpsi)
    Rz = np.array([[cpsi, -spsi, 0.0], [spsi, cpsi, 0.0], [0.0, 0.0, 1.0]])
    resid = max(float(np.max(np.abs(M - Rz))), float(np.max(np.abs(Rm @ wt - wp0))) / scale)
    return 0.5 * (dpsi + dphi), 0.5 * (dpsi - dphi), resid


def build_lagrange_top(I: np.ndarray, center: np.ndarray, Q0: np.ndarray, omega0: np.ndarray, mgl: float,
                       up: np.ndarray, rotor_momentum: float = 0.0) -> tuple[_Constants, dict]:
    """The constants of the closed form (see the module docstring) for the inertia ``I`` symmetric
    about the axis of ``center`` (:func:`lagrange_frame`), ``mgl = mass |g| |center| > 0`` and ``up`` the
    upward vertical in space; the frames, moments, integrals, turning points and rates are formed in
    60-digit mpmath from the float64 data.

    ``rotor_momentum`` is ``lam`` of a Lagrange gyrostat: a rotor momentum ``lam center/|center|``
    along the axis (``I`` then excludes the rotor's axial moment); 0 for the top.

    Returns ``(constants, diagnostics)``; evaluate with :func:`lagrange_state`.
    """
    with mpmath.workdps(_DPS):
        Pm, Sm, A, C, B, g, w = _mp_data(I, center, Q0, omega0, (mpmath.mpf(float(mgl)), _unit_mp(up)))
        R = _turning_points(A, C, B, g, w, mpmath.mpf(float(rotor_momentum)))
        P = np.array([[float(Pm[j][i]) for j in range(3)] for i in range(3)])
        S = np.array([[float(Sm[j][i]) for j in range(3)] for i in range(3)])
        wp0 = np.array([float(x) for x in w])
        beta = float(B)
    Qp0 = S.T @ Q0 @ P
    limit_w = R.s_minus == 0 or R.w1 == 0
    limit_v = R.s_plus == 0 and R.v2 == 0
    c = _Constants(P, S, R, _phase_minus(R), _phase_plus(R), limit_w, limit_v, 0.0, 0.0)
    dp, dm, resid = _fit_offsets(c, Qp0, wp0, beta)
    if not resid < FIT_WARN:
        warnings.warn(f"Lagrange top: the closed form misses the initial state by {resid:.2g} "
                      "(expected a few ulps); errors of that size are to be expected", RuntimeWarning, stacklevel=3)
    c = _Constants(**{**c.__dict__, "delta_plus": dp, "delta_minus": dm})
    diag = {"period": 2.0 * R.K / R.lam if R.lam > 0 else math.inf, "K": R.K, "m": R.m, "mc": R.mc,
            "lambda": R.lam, "u1_plus_1": R.w1, "one_minus_u2": R.v2, "nutation_D": R.D, "fit_residual": resid,
            "passes_pole": {"hanging": limit_w, "upright": limit_v}}
    return c, diag


def lagrange_state(c: _Constants, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(omega, Q)`` in the user's body and space frames at the flat times ``t``."""
    wp, Qp = _state(c, np.asarray(t, float))
    return wp @ c.P.T, c.S @ Qp @ c.P.T
