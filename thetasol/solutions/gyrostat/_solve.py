"""The entry point :func:`solve_gyrostat` and the solution object :class:`GyrostatSolution`.

The set-up runs in named stages: the data (:func:`_data`), the first integrals, then the closed
form (:func:`_degenerate_form` for the trigonometric and limiting cases, else
:func:`_elliptic_form`), each returning a small frozen record.
"""
from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.attitude import norm3 as _norm, principal_frame as _principal_frame
from thetasol.core.inertia import second_moments
from thetasol.core.periodic import SeriesNotConverged
from thetasol.core.threads import single_blas_thread
from thetasol.protocol import ClosedFormUnavailable
from thetasol.solutions.gyrostat._elliptic import elliptic_motion, elliptic_orbit, reanchor
from thetasol.solutions.gyrostat._forms import Axisymmetric, BodyMap, Delegate, Scaled, Sphere, Steady
from thetasol.solutions.gyrostat._rotors import RotorAngles, parse_rotors, rotor_angles
from thetasol.solutions.rotation.dispatch import RotationSolution, solve_rotation

__all__ = ["GyrostatSolution", "solve_gyrostat"]

_EPS = np.finfo(float).eps


@dataclass(frozen=True, eq=False)
class GyrostatSolution(RotationSolution):
    """Closed-form motion of a free gyrostat; built by :func:`solve_gyrostat`.

    Besides the :class:`~thetasol.RotationSolution` protocol it has ``N`` (the rotor
    momentum (8.33), body frame) and ``h(t)`` (the total body momentum ``I omega + N``); built
    with ``rotors``, also ``rotors`` (the :class:`Rotor` data: axis, ``A``, ``B`` and the
    conserved ``p`` of (8.25)), ``rotor_angles(t)`` and ``rotor_rates(t)``.
    """

    model = "gyrostat"

    N: np.ndarray = None
    rotors: tuple = ()
    _impl: object = field(default=None, repr=False)
    _rotor_angles: object = field(default=None, repr=False)

    def _evaluate(self, t):
        return self._impl.evaluate(t)

    def _omega(self, t):
        return self._impl.omega(t)

    def h(self, t):
        """Total angular momentum in the body frame, ``I omega + N``, shape ``t.shape + (3,)``."""
        return self.m(t) + self.N

    def _rotor_impl(self) -> RotorAngles:
        if self._rotor_angles is None:
            raise ValueError("this gyrostat was built without rotors (pass rotors= to solve_gyrostat)")
        return self._rotor_angles

    def rotor_angles(self, t, wrap: bool = False) -> np.ndarray:
        """Rotor angles ``phi_k(t)`` relative to the carrier, ``phi_k(0) = 0``, shape
        ``t.shape + (n_rotors,)``: ``phidot_k = p_k / A_k - omega . l_k`` (8.28) integrated in
        closed form (module :mod:`thetasol.solutions.gyrostat._rotors`).  Unwrapped by default;
        ``wrap=True`` reduces them to ``(-pi, pi]`` with an exact product (far times)."""
        ra = self._rotor_impl()
        tt, flat = self._times(t)
        out = self._run(lambda x: ra.angles(x, wrap), flat)
        return out.reshape(tt.shape + (len(self.rotors),))

    def rotor_rates(self, t) -> np.ndarray:
        """Rotor rates ``phidot_k(t) = p_k / A_k - omega . l_k`` (8.28), shape ``t.shape + (n_rotors,)``."""
        ra = self._rotor_impl()
        return ra.rates(self.omega(t))


# -- stages ------------------------------------------------------------------------------------

@dataclass(frozen=True)
class _Data:
    """The validated data: second moments, rotor momentum, attitude, angular velocity, and the
    carrier's inertia and momentum ``m = I omega0`` (body frame)."""

    J: np.ndarray
    N: np.ndarray
    Q0: np.ndarray
    omega0: np.ndarray
    I: np.ndarray
    m: np.ndarray


@dataclass(frozen=True)
class _Form:
    """A closed form: its method and case, the implementation (``evaluate(t)``, ``omega(t)``), the
    period of ``omega`` (0 when constant, ``inf`` on a separatrix), the mean precession rate and
    the relative error estimate of ``m(t)`` per period."""

    method: str
    case: str
    impl: object
    period: float = 0.0
    rate: float = 0.0
    err: float = _EPS


def _data(I, N, Q0, omega0) -> _Data:
    Im = V.inertia(I, "I")
    n_body = V.vector3(N, "N")
    Q0m = V.rotation_matrix(Q0, "Q0")
    w0 = V.vector3(omega0, "omega0")
    return _Data(J=second_moments(Im), N=n_body, Q0=Q0m, omega0=w0, I=Im, m=Im @ w0)


def _first_integrals(d: _Data) -> dict:
    """(8.40): ``energy = 1/2 m . omega``, ``H = -2 energy``, ``H2 = -2 |h|^2``, ``h2``, ``m2``."""
    h_body = d.m + d.N
    energy = 0.5 * float(d.omega0 @ d.m)
    h2 = _norm(h_body) ** 2
    return {"energy": energy, "H": -2.0 * energy, "H2": -2.0 * h2, "h2": h2, "m2": _norm(d.m) ** 2}


def _degenerate_form(d: _Data) -> _Form | None:
    """The Euler top (``N`` below the rounding of ``m``), rest, steady rotation, a spherical
    carrier, an axisymmetric carrier with ``N`` along its axis; None for the generic motion."""
    m_body, n_body, w0, Q0m = d.m, d.N, d.omega0, d.Q0
    if _norm(n_body) <= 0.25 * _EPS * _norm(m_body):
        # a rotor momentum below the rounding of m: the Euler top of the same data (exact
        # to rounding; the rotor term's effect stays below eps |m| omega t)
        sol = solve_rotation(d.I, np.zeros((3, 3)), Q0m, w0)
        return _Form(sol.method, sol.case, Delegate(sol), sol.diagnostics["period"], sol.diagnostics["precession_rate"],
                     err=sol.diagnostics["error_estimate"])
    if not np.any(m_body):
        return _Form("elementary", "rest", Steady(Q0m, np.zeros(3)))
    hdot0 = np.cross(m_body, w0) + np.cross(n_body, w0)
    if _norm(hdot0) <= 8 * _EPS * (_norm(m_body) + _norm(n_body)) * _norm(w0):
        # h x omega = 0 to the rounding of the data: a relative equilibrium (steady rotation)
        return _Form("elementary", "steady", Steady(Q0m, w0), rate=_norm(w0))
    Jp, R = _principal_frame(d.J)
    Ip = np.array([Jp[1] + Jp[2], Jp[0] + Jp[2], Jp[0] + Jp[1]])
    n = R.T @ n_body
    m = Ip * (R.T @ w0)
    Q0p = Q0m @ R
    if Jp[0] == Jp[1] == Jp[2]:
        impl = BodyMap(Sphere(Ip[0], n, Q0p, w0 @ R), R)
        return _Form("elementary", "spherical", impl, period=2 * np.pi * Ip[0] / _norm(n), rate=_norm(m + n) / Ip[0])
    for c in range(3):
        a_, b_ = [i for i in range(3) if i != c]
        # (a transverse rotor momentum below the rounding of N is the rounding of the data)
        if Jp[a_] == Jp[b_] and max(abs(n[a_]), abs(n[b_])) <= 0.25 * _EPS * _norm(n):
            n_ax = np.zeros(3)
            n_ax[c] = n[c]
            impl = Axisymmetric(Ip, n_ax, m, c, Q0p, R)
            per = 2 * np.pi / abs(impl.Om) if impl.Om != 0 else 0.0
            return _Form("elementary", "axisymmetric", impl, period=per, rate=impl.psidot)
    return None


def _elliptic_form(d: _Data) -> _Form:
    """The generic motion: :func:`elliptic_motion` of the data scaled by a power of two near
    ``|h|``, re-anchored where the anchor is degenerate or slow, with its error estimate."""
    Jp, R = _principal_frame(d.J)
    diagonal = not np.any(d.I - np.diag(np.diag(d.I)))
    # the user's principal inertia as given (R = 1 then); else from the principal second moments
    Ip = np.diag(d.I).copy() if diagonal else np.array([Jp[1] + Jp[2], Jp[0] + Jp[2], Jp[0] + Jp[1]])
    n = R.T @ d.N
    m = Ip * (R.T @ d.omega0)
    hdot = np.cross(m + n, m / Ip)
    if _norm(m) < 1e-60 * _norm(m + n) or _norm(hdot) < 1e-60 * _norm(m + n) * _norm(m / Ip):
        # the orbit is a loop of relative size < 1e-60 about a relative equilibrium (or the
        # carrier is at rest to 1e-60): its polynomial coefficients, powers of that size,
        # would underflow in float64
        raise ClosedFormUnavailable("solve_gyrostat: the motion is within 1e-60 (relative) of a "
                                  "relative equilibrium; not supported")
    # the motion scales with |h|: m(t) = G m1(G t) for the data divided by G (so that tiny or
    # huge momenta neither underflow nor overflow in the orbit's polynomial coefficients)
    # (a power of two near |h|: the scaled data are the data, exactly)
    Gs = 2.0 ** round(np.log2(_norm(m + n)))
    n, m = n / Gs, m / Gs
    # the exact data for the algebra: the principal inertia (the user's, or I_i = J_j + J_k) and
    # m = I omega0 (no rounding)
    wp = R.T @ d.omega0
    Iq = ([Fraction(float(x)) for x in Ip] if diagonal else
          [Fraction(float(Jp[1])) + Fraction(float(Jp[2])), Fraction(float(Jp[0])) + Fraction(float(Jp[2])),
           Fraction(float(Jp[0])) + Fraction(float(Jp[1]))])
    mq = [Iq[i] * Fraction(float(wp[i])) / Fraction(Gs) for i in range(3)]
    orbit = elliptic_orbit(Ip, n, m, R, m0_mp=mq, Ip_exact=Iq)
    if orbit.anchor_is_degenerate() or orbit.anchor_is_slow():
        # Zero torsion at h(0) (a point on a symmetry plane of the orbit: the formula is 0/0
        # where the orbit meets the osculating plane again) or a slow h(0) (next to a saddle:
        # the pencil resolves the points around the saddle only to eps / distance).
        orbit = reanchor(orbit, mq)
    impl = elliptic_motion(orbit, d.Q0 @ R, m)
    # relative error: the float64 evaluation's (measured against mpmath at the worst-
    # conditioned points of the orbit) and the Fourier tail of psi' (per period)
    err = max(8 * _EPS, impl.float_error) + impl.phase_error + impl.fourier_tail
    if err > 1e-10:
        warnings.warn(f"solve_gyrostat: estimated relative error {err:.1e} per period of the "
                      "orbit (close to a separatrix); see "
                      "diagnostics['error_estimate']", RuntimeWarning, stacklevel=3)
    return _Form("elliptic", "separatrix" if impl.separatrix else "", Scaled(impl, Gs), period=impl.T / Gs, rate=impl.nu * Gs, err=err)


def _closed_form(d: _Data, rs) -> tuple[_Form, RotorAngles | None]:
    """The carrier's form and the rotors' angles; a series that does not converge (an orbit too
    close to a separatrix) puts the data outside the closed form."""
    try:
        form = _degenerate_form(d) or _elliptic_form(d)
        return form, (rotor_angles(rs, form.impl, form.period, d.omega0) if rs else None)
    except SeriesNotConverged as exc:
        raise ClosedFormUnavailable(f"{exc}; use thetasol.integrators.gyrostat.integrate_gyrostat") from exc


# -- entry point -------------------------------------------------------------------------------

@single_blas_thread
def solve_gyrostat(I: ArrayLike, N: ArrayLike | None, Q0: ArrayLike, omega0: ArrayLike, *,
                   rotors: Sequence[Mapping] | None = None) -> GyrostatSolution:
    """Exact motion of a free gyrostat, (8.39)-(8.40) (Zhukovsky-Volterra case), with the
    angles of its rotors when they are given.

    The carrier obeys ``I omega_dot = (I omega + N) x omega`` with a constant ``N``, and
    ``Qdot = Q hat(omega)``.

    Parameters
    ----------
    I : array_like, shape (3,) or (3, 3)
        Inertia tensor of the carrier INCLUDING the rotors' masses and transverse moments but
        NOT the rotors' axial moments ``A_k``: the paper's (8.33) inertia of the effective
        carrier.  (Equivalently, without ``rotors``: ``I`` with the rotors locked, axial moments
        included, when the rotors spin at constant rates relative to the carrier and
        ``N = sum A_k phidot_k l_k``.)  Second moments convert with :func:`thetasol.inertia`.
    N : array_like, shape (3,), or None
        Constant rotor angular momentum in the body frame, ``N = sum_k p_k l_k`` (8.33).  With
        ``rotors`` it is checked against that sum (relative tolerance 1e-12 of
        ``|N| + sum |p_k|``, else :class:`ValueError`); None takes the sum.
    Q0 : array_like, shape (3, 3)
        Initial attitude, body to space.
    omega0 : array_like, shape (3,)
        Initial body angular velocity of the carrier.
    rotors : sequence of mappings, optional
        One mapping per rotor with keys ``axis`` (its unit axis ``l_k`` in the carrier frame;
        a norm off 1 by more than 1e-12 is refused, else it is normalized), ``A`` (axial moment,
        > 0), ``B`` (transverse moment, >= 0; already part of ``I``, kept for inspection) and
        ``p`` (the conserved rotor momentum ``p_k = A_k (omega . l_k + phidot_k)``, (8.25)).
        The rotor angles start at ``phi_k(0) = 0``.

    Returns
    -------
    GyrostatSolution
        The :class:`~thetasol.RotationSolution` protocol (``omega(t)``, ``Q(t)``, ``M(t)``,
        ``u(t)``, ``method``, ``invariants``, ``diagnostics``) plus ``N`` and ``h(t)``; with
        ``rotors``, also ``rotors``, ``rotor_angles(t)`` and ``rotor_rates(t)``.
        ``invariants`` (first integrals) has ``energy`` (``1/2 m . omega``), ``H`` ((8.40):
        ``1/2 tr(M omega) = -2 energy``), ``H2`` ((8.40): ``tr (M + N)^2 = -2 |h|^2``),
        ``h2 = |h|^2``, ``m2 = |m|^2`` and with rotors ``rotor_momenta`` (the ``p_k``).
        ``diagnostics`` has ``period`` (of ``omega``; 0 when constant, ``inf`` on a separatrix),
        ``precession_rate`` (the mean rate; on a separatrix the saddle's) and
        ``error_estimate`` (relative error of ``m(t)`` per period, see the package notes); with
        rotors ``rotor_mean_rates`` (the secular rates of ``phi_k``), ``rotor_series_terms`` and
        ``rotor_series_tail`` (the Fourier series of ``omega . l_k``).  ``model`` is
        ``"gyrostat"``; ``method`` ``"elliptic"`` (``case`` ``""`` or ``"separatrix"``) or
        ``"elementary"`` (``case`` ``"steady"``, ``"spherical"``, ``"axisymmetric"`` or ``"rest"``), or
        the Euler top's when ``N`` is below the rounding of ``m``.

    Raises
    ------
    ValueError
        Bad data (non-finite, wrong shapes, unphysical ``I``, ``Q0`` not a rotation, a rotor
        with a non-unit axis, ``A <= 0``, ``B < 0``, or ``N`` not ``sum p_k l_k``).
    ClosedFormUnavailable
        An orbit within 1e-307 of a separatrix but not on it (the elliptic parameter is not
        representable), a motion within 1e-60 of a relative equilibrium, rotor angles on the
        Euler top's separatrix (rotors whose momenta cancel), or a Fourier series of the precession
        or of the rotor angles that does not converge.

    Warns
    -----
    RuntimeWarning
        When ``error_estimate`` exceeds 1e-10 (nearly planar orbits, see the package notes).
    """
    rs = ()
    if rotors is not None:
        rs, N = parse_rotors(rotors, N)
    elif N is None:
        raise ValueError("N is required without rotors")
    d = _data(I, N, Q0, omega0)
    inv = _first_integrals(d)
    form, angles = _closed_form(d, rs)
    diag = {"period": float(form.period), "precession_rate": float(form.rate),
            "case": form.case, "error_estimate": float(form.err)}
    if rs:
        inv["rotor_momenta"] = np.array([r.p for r in rs])
        diag.update(rotor_mean_rates=angles.drift.copy(), rotor_series_terms=int(angles.nterms),
                    rotor_series_tail=float(angles.tail))
    return GyrostatSolution(d.J, np.zeros((3, 3)), d.Q0, d.omega0, form.method, inv, None,
                            diag, I_given=d.I, N=d.N, rotors=rs, _impl=form.impl, _rotor_angles=angles)
