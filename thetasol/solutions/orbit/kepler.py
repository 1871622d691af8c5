"""The Kepler orbit of the mass centre (7.7) in closed form: every conic by universal variables.

Section 7 splits the Lagrangian of an orbiting configuration (7.6) into the Kepler problem (7.7)
``qddot = -mu q / |q|^3`` of the mass centre and the rotations about it.  :class:`KeplerOrbit`
is the first part: position and velocity at any time from ``(mu, r0, v0)``, for elliptic,
parabolic and hyperbolic orbits alike.

Method (Battin, *An Introduction to the Mathematics and Methods of Astrodynamics*, ch. 4;
Vallado, *Fundamentals of Astrodynamics*, alg. 8).  With ``alpha = 2/|r0| - |v0|^2/mu`` (= 1/a),
``sigma0 = r0.v0 / sqrt(mu)``, the universal anomaly ``chi`` and the Stumpff functions
``c_k(z) = sum_j (-z)^j / (2j + k)!`` (:mod:`thetasol.special.stumpff`) of ``z = alpha chi^2``, put
``U_k = chi^k c_k(z)``.  Then

    sqrt(mu) dt = |r0| U1 + sigma0 U2 + U3              (the universal Kepler equation)
    r = |r0| U0 + sigma0 U1 + U2,
    f = 1 - U2/|r0|,  g = (|r0| U1 + sigma0 U2)/sqrt(mu),  fdot = -sqrt(mu) U1/(r |r0|),  gdot = 1 - U2/r,
    r(t) = f r0 + g v0,  v(t) = fdot r0 + gdot v0.

One formula for every conic, smooth through e = 1 (``c_k`` are entire in ``z``).  ``g`` is written
without ``dt`` so that it does not cancel.  The Kepler equation has derivative ``r > 0`` in ``chi``
and is solved by Laguerre's iteration (Conway, Celest. Mech. 39, 1986) inside a bracket that
always holds the root: ``|chi| <= sqrt(mu) |dt| / q`` (``q`` the periapsis distance, since the
derivative is ``r >= q``), and for ellipses ``|chi| <= sqrt(a) (n |dt| + 2 e)`` (``chi = sqrt(a) dE``,
``|dE - dM| <= 2 e``); a step leaving the bracket is replaced by bisection.

Many revolutions.  For ellipses ``dt`` is reduced modulo the period first, with ``alpha`` and the
period formed once in 40-digit mpmath from the float64 data and the period kept as two floats:
``t = 100`` periods costs what ``t = 1`` costs and keeps its digits.  (In float64, ``alpha`` of a
highly eccentric orbit started at periapsis loses bits to cancellation, a phase error that grows
with the revolutions.)  tests/test_kepler.py checks the orbit against 80-bit and quadruple-precision
heyoka integrations over many revolutions, against Kepler's equation in 50-digit mpmath at far times,
and on hyperbolic orbits; benchmarks/bench_orbiting_station.py measures the cost.

A radial orbit (zero angular momentum) is refused: its collision makes the closed form singular.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import mpmath
import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.dd import two_prod
from thetasol.protocol import ROUNDOFF, Solution
from thetasol.special.stumpff import stumpff, stumpff_float

__all__ = ["KeplerOrbit", "solve_kepler"]

_EPS = np.finfo(float).eps
_LAGUERRE_N = 5.0
_MAX_ITER = 200


@dataclass(frozen=True)
class _Setup:
    """Constants of the orbit formed once at construction (mpmath where float64 cancels)."""

    sqrtmu: float
    r0n: float
    sigma0: float
    alpha: float
    period_hi: float     # period = period_hi + period_lo (inf unless elliptic)
    period_lo: float
    q: float             # periapsis distance
    e: float


def _mp_constants(mu, r0, v0):
    """alpha = 2/|r0| - |v0|^2/mu, the period and the energy from the float64 data, at 40 digits."""
    with mpmath.workdps(40):
        m = mpmath.mpf(float(mu))
        r = mpmath.sqrt(mpmath.fsum(mpmath.mpf(float(x)) ** 2 for x in r0))
        v2 = mpmath.fsum(mpmath.mpf(float(x)) ** 2 for x in v0)
        alpha = 2 / r - v2 / m
        if alpha > 0:
            T = 2 * mpmath.pi / mpmath.sqrt(m * alpha ** 3)
            hi = float(T)
            lo = float(T - hi)
        else:
            hi, lo = np.inf, 0.0
        return float(alpha), hi, lo, float(-m * alpha / 2)


def _orbit_setup(mu: float, r0: np.ndarray, v0: np.ndarray) -> tuple[_Setup, dict, dict]:
    """The constants of the orbit through the validated ``(r0, v0)``, its first integrals (``energy``,
    ``h``, ``lrl``) and its diagnostics (kind and elements); radial orbits are refused."""
    r0n = float(np.linalg.norm(r0))
    if r0n == 0:
        raise ValueError("r0 is the origin: the attracting centre itself")
    h = np.cross(r0, v0)
    hn = float(np.linalg.norm(h))
    if hn <= 8 * _EPS * r0n * float(np.linalg.norm(v0)) or hn == 0:
        raise ValueError("radial orbit: r0 x v0 = 0 (zero angular momentum), the body falls into "
                         "the centre and the conic degenerates; no closed form here")
    alpha, T_hi, T_lo, energy = _mp_constants(mu, r0, v0)
    evec = np.cross(v0, h) / mu - r0 / r0n
    e = float(np.linalg.norm(evec))
    p = hn * hn / mu
    kind = "elliptic" if alpha > 0 else "hyperbolic" if alpha < 0 else "parabolic"
    i, raan, argp, nu0 = _elements(mu, r0, v0, h, evec)
    n = float(np.sqrt(mu * abs(alpha) ** 3)) if alpha != 0 else 0.0
    diag = {"kind": kind, "a": (1.0 / alpha) if alpha != 0 else np.inf, "e": e, "i": i,
            "raan": raan, "argp": argp, "nu0": nu0, "p": p, "periapsis": p / (1.0 + e),
            "period": T_hi, "mean_motion": n, "case": kind, "error_estimate": ROUNDOFF}
    setup = _Setup(np.sqrt(mu), r0n, float(r0 @ v0) / np.sqrt(mu), alpha, T_hi, T_lo, p / (1.0 + e), e)
    return setup, {"energy": energy, "h": h, "lrl": mu * evec}, diag


def _elements(mu, r0, v0, h, evec):
    """Classical elements (i, RAAN, argp, nu0) by atan2 in the orbit plane; conventions where undefined."""
    hn = np.linalg.norm(h)
    w = h / hn
    i = float(np.arctan2(np.hypot(w[0], w[1]), w[2]))
    node = np.array([-h[1], h[0], 0.0])            # e_z x h
    nn = np.linalg.norm(node)
    P = node / nn if nn > 1e-15 * hn else np.array([1.0, 0.0, 0.0])
    raan = float(np.arctan2(P[1], P[0])) % (2 * np.pi) if nn > 1e-15 * hn else 0.0
    Qv = np.cross(w, P)
    en = np.linalg.norm(evec)
    argp = float(np.arctan2(evec @ Qv, evec @ P)) % (2 * np.pi) if en > 1e-15 else 0.0
    u0 = float(np.arctan2(r0 @ Qv, r0 @ P))
    nu0 = (u0 - argp) % (2 * np.pi)
    return i, raan, argp, float(nu0)


@dataclass(frozen=True, eq=False)
class KeplerOrbit(Solution):
    """The two-body orbit ``qddot = -mu q / |q|^3`` (7.7) through ``(r0, v0)`` at ``t = 0``.

    Calling ``orbit(t)`` returns ``(r, v)`` of shapes ``t.shape + (3,)``; ``position(t)`` and
    ``velocity(t)`` return one of them.  ``period`` is ``inf`` unless the orbit is an ellipse.

    Parameters
    ----------
    mu : float
        Gravitational parameter ``G m0`` (> 0), in the user's units (e.g. 3.986004418e14 m^3/s^2).
    r0, v0 : array_like, shape (3,)
        Position and velocity at ``t = 0``; ``r0 x v0 != 0`` (radial orbits are refused).

    Attributes
    ----------
    invariants : dict
        First integrals: ``energy`` (per unit mass, ``|v|^2/2 - mu/|r|``), ``h`` (angular
        momentum per unit mass, ``r x v``), ``lrl`` (Laplace-Runge-Lenz vector ``v x h - mu r/|r|``).
    diagnostics : dict
        ``kind`` ("elliptic", "parabolic", "hyperbolic"), the elements ``a`` (inf if parabolic),
        ``e``, ``i``, ``raan``, ``argp``, ``nu0`` (radians; RAAN = 0 for equatorial orbits, argp = 0 for
        circular ones), ``p`` (semi-latus rectum), ``periapsis``, ``period``, ``mean_motion``, ``case``
        (the kind) and ``error_estimate`` (float64 rounding: the time of flight is solved to it).

    Examples
    --------
    >>> orb = KeplerOrbit(1.0, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    >>> r, v = orb(2 * np.pi)
    >>> bool(np.allclose(r, [1.0, 0.0, 0.0]))
    True
    """

    mu: float
    r0: np.ndarray
    v0: np.ndarray
    model = "kepler"

    method: str = field(default="elementary", init=False)
    invariants: dict = field(default=None, init=False, repr=False)
    diagnostics: dict = field(default=None, init=False, repr=False)
    _s: _Setup = field(default=None, init=False, repr=False)

    def __post_init__(self):
        # the inputs normalised (validated floats), and the orbit's constants, elements and first
        # integrals from them, each field assigned once (a frozen dataclass completing itself)
        mu = V.finite_array(self.mu, "mu", ())
        if not mu > 0:
            raise ValueError(f"mu must be positive, got {float(mu)!r}")
        mu = float(mu)
        r0 = V.vector3(self.r0, "r0")
        v0 = V.vector3(self.v0, "v0")
        setup, inv, diag = _orbit_setup(mu, r0, v0)
        object.__setattr__(self, "mu", mu)
        object.__setattr__(self, "r0", r0)
        object.__setattr__(self, "v0", v0)
        object.__setattr__(self, "invariants", inv)
        object.__setattr__(self, "diagnostics", diag)
        object.__setattr__(self, "_s", setup)

    # -- public views ------------------------------------------------------------------------
    def fastest_frequency(self) -> float:
        """The rate of the orbit's phase (the mean anomaly): the mean motion, ``sqrt(mu / p^3)`` for a
        parabola.  A time error moves the body along its orbit by that phase, whatever its speed."""
        n = self.diagnostics["mean_motion"]
        return n if n > 0 else math.sqrt(self.mu / self.diagnostics["p"] ** 3)

    @property
    def period(self) -> float:
        """Orbital period (``inf`` for parabolic and hyperbolic orbits)."""
        return self._s.period_hi

    @property
    def elements(self) -> dict:
        """The classical elements ``a, e, i, raan, argp, nu0`` (a copy of those diagnostics)."""
        return {k: self.diagnostics[k] for k in ("a", "e", "i", "raan", "argp", "nu0")}

    def position(self, t: ArrayLike) -> np.ndarray:
        """Position at times ``t``, shape ``t.shape + (3,)``."""
        return self(t)[0]

    def velocity(self, t: ArrayLike) -> np.ndarray:
        """Velocity at times ``t``, shape ``t.shape + (3,)``."""
        return self(t)[1]

    def state_at(self, t: float) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """``(r, v)`` at one time as tuples of Python floats: the same formulas on scalars, far
        cheaper per call than ``orbit(t)`` (for right-hand sides of ODE integrators)."""
        s = self._s
        t = float(t)
        if math.isfinite(s.period_hi):
            k = float(round(t / s.period_hi))
            p, pe = two_prod(k, s.period_hi)
            t = ((t - p) - pe) - k * s.period_lo
        chi = self._solve_chi_scalar(t)
        c0, c1, c2, _ = stumpff_float(s.alpha * chi * chi)
        U1, U2 = chi * c1, chi * chi * c2
        r = s.r0n * c0 + s.sigma0 * U1 + U2
        f, g = 1.0 - U2 / s.r0n, (s.r0n * U1 + s.sigma0 * U2) / s.sqrtmu
        fd, gd = -s.sqrtmu * U1 / (r * s.r0n), 1.0 - U2 / r
        (x0, x1, x2), (y0, y1, y2) = self.r0.tolist(), self.v0.tolist()
        return ((f * x0 + g * y0, f * x1 + g * y1, f * x2 + g * y2),
                (fd * x0 + gd * y0, fd * x1 + gd * y1, fd * x2 + gd * y2))

    # -- evaluation --------------------------------------------------------------------------
    def _reduced(self, t: np.ndarray) -> np.ndarray:
        """``t`` modulo the period (to [-T/2, T/2]) with the period in two floats; ``t`` otherwise."""
        s = self._s
        if not np.isfinite(s.period_hi):
            return t
        k = np.rint(t / s.period_hi)
        p, pe = two_prod(k, s.period_hi)
        return ((t - p) - pe) - k * s.period_lo

    def _bracket(self, dt):
        s = self._s
        span = s.sqrtmu * np.abs(dt) / s.q
        if s.alpha > 0:
            a = 1.0 / s.alpha
            span = np.minimum(span, np.sqrt(a) * (np.sqrt(s.alpha ** 3) * s.sqrtmu * np.abs(dt) + 2 * s.e))
        span = span * (1 + 1e-10) + np.finfo(float).tiny
        return np.where(dt >= 0, 0.0, -span), np.where(dt >= 0, span, 0.0)

    def _guess(self, dt):
        """Vallado's starting values: sqrt(a) dM for ellipses, the asymptotic log for hyperbolas."""
        s = self._s
        if s.alpha > 0:
            return s.sqrtmu * dt * s.alpha
        if s.alpha == 0:
            return np.zeros_like(dt)
        a = 1.0 / s.alpha
        sg = np.where(dt >= 0, 1.0, -1.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            arg = (-2 * s.sqrtmu ** 2 * s.alpha * dt) / (
                s.sigma0 * s.sqrtmu + sg * np.sqrt(-s.sqrtmu ** 2 * a) * (1 - s.r0n * s.alpha))
            g = sg * np.sqrt(-a) * np.log(arg)
        return np.where(np.isfinite(g), g, 0.0)

    def _solve_chi(self, dt: np.ndarray) -> np.ndarray:
        """The universal anomaly: Laguerre's iteration kept inside a bracket of the root."""
        s = self._s
        lo, hi = self._bracket(dt)
        chi = np.clip(self._guess(dt), lo, hi)
        target = s.sqrtmu * dt
        n = _LAGUERRE_N
        active = np.ones(dt.shape, dtype=bool)
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            for _ in range(_MAX_ITER):
                c0, c1, c2, c3 = stumpff(s.alpha * chi * chi)
                U1, U2, U3 = chi * c1, chi * chi * c2, chi ** 3 * c3
                F = s.r0n * U1 + s.sigma0 * U2 + U3 - target
                # overflow only far out on a hyperbola, where F has the sign of chi (F increases)
                F = np.where(np.isfinite(F), F, np.copysign(np.inf, chi))
                dF = s.r0n * c0 + s.sigma0 * U1 + U2
                d2F = s.sigma0 * c0 + (1.0 - s.alpha * s.r0n) * U1
                lo = np.where(F < 0, np.maximum(lo, chi), lo)
                hi = np.where(F > 0, np.minimum(hi, chi), hi)
                disc = np.sqrt(np.abs((n - 1) ** 2 * dF * dF - n * (n - 1) * F * d2F))
                new = chi - n * F / (dF + disc)
                bad = ~np.isfinite(new) | (new < lo) | (new > hi)
                new = np.where(bad, 0.5 * (lo + hi), new)
                step = np.abs(new - chi)
                # the residual at the rounding level of its terms, or the step or bracket at that of chi
                noise = 4 * _EPS * (s.r0n * np.abs(U1) + np.abs(s.sigma0 * U2) + np.abs(U3) + np.abs(target))
                done = (np.abs(F) <= noise) | (step <= 2 * _EPS * np.abs(new)) \
                    | (hi - lo <= 2 * _EPS * np.maximum(np.abs(lo), np.abs(hi)))
                chi = np.where(active, new, chi)
                active &= ~done
                if not active.any():
                    break
        return chi

    def _solve_chi_scalar(self, dt: float) -> float:
        """:meth:`_solve_chi` on one float (Python arithmetic)."""
        s = self._s
        span = s.sqrtmu * abs(dt) / s.q
        if s.alpha > 0:
            span = min(span, (s.sqrtmu * abs(dt) * s.alpha + 2 * s.e / math.sqrt(s.alpha)))
        span = span * (1 + 1e-10) + 1e-300
        lo, hi = (0.0, span) if dt >= 0 else (-span, 0.0)
        if s.alpha > 0:
            guess = s.sqrtmu * dt * s.alpha
        else:
            guess = float(self._guess(np.array([dt]))[0])
        chi = min(max(guess, lo), hi)
        target, n = s.sqrtmu * dt, _LAGUERRE_N
        for _ in range(_MAX_ITER):
            c0, c1, c2, c3 = stumpff_float(s.alpha * chi * chi)
            U1, U2, U3 = chi * c1, chi * chi * c2, chi * chi * chi * c3
            F = s.r0n * U1 + s.sigma0 * U2 + U3 - target
            if not math.isfinite(F):
                F = math.copysign(math.inf, chi)
            dF = s.r0n * c0 + s.sigma0 * U1 + U2
            d2F = s.sigma0 * c0 + (1.0 - s.alpha * s.r0n) * U1
            if F < 0:
                lo = max(lo, chi)
            elif F > 0:
                hi = min(hi, chi)
            noise = 4 * _EPS * (s.r0n * abs(U1) + abs(s.sigma0 * U2) + abs(U3) + abs(target))
            if abs(F) <= noise:
                return chi
            try:
                new = chi - n * F / (dF + math.sqrt(abs((n - 1) ** 2 * dF * dF - n * (n - 1) * F * d2F)))
            except (OverflowError, ZeroDivisionError, ValueError):
                new = math.nan
            if not (lo <= new <= hi):
                new = 0.5 * (lo + hi)
            if abs(new - chi) <= 2 * _EPS * abs(new) or hi - lo <= 2 * _EPS * max(abs(lo), abs(hi)):
                return new
            chi = new
        return chi

    def _evaluate(self, t: np.ndarray):
        s = self._s
        dt = self._reduced(np.asarray(t, dtype=float))
        chi = self._solve_chi(dt)
        c0, c1, c2, _ = stumpff(s.alpha * chi * chi)
        U1, U2 = chi * c1, chi * chi * c2
        r = s.r0n * c0 + s.sigma0 * U1 + U2
        f = 1.0 - U2 / s.r0n
        g = (s.r0n * U1 + s.sigma0 * U2) / s.sqrtmu
        fdot = -s.sqrtmu * U1 / (r * s.r0n)
        gdot = 1.0 - U2 / r
        if not (np.all(np.isfinite(f)) and np.all(np.isfinite(g))):
            raise OverflowError("the orbit overflows float64 at the requested times")
        pos = f[:, None] * self.r0 + g[:, None] * self.v0
        vel = fdot[:, None] * self.r0 + gdot[:, None] * self.v0
        return pos, vel


def solve_kepler(mu: float, r0: ArrayLike, v0: ArrayLike) -> KeplerOrbit:
    """The two-body orbit ``qddot = -mu q / |q|^3`` (7.7) through ``(r0, v0)`` at ``t = 0``.

    The entry point in the library's one pattern (the model's constant, then the initial state);
    it builds the same :class:`KeplerOrbit` as its constructor.

    Examples
    --------
    >>> r, v = solve_kepler(1.0, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])(np.pi)
    >>> np.round(r, 12).tolist()
    [-1.0, 0.0, 0.0]
    """
    return KeplerOrbit(mu, r0, v0)
