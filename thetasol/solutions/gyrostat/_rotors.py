"""The rotors of a gyrostat (Section 8): their data, the check of (8.33), and their angles.

A rotor ``k`` turns about the unit axis ``l_k`` fixed in the carrier, with axial moment ``A_k``
and transverse moment ``B_k``; its angle ``phi_k`` is cyclic, so its momentum (8.25)
``p_k = A_k (omega . l_k + phidot_k)`` is conserved (8.27), the carrier sees the constant
``N = sum_k p_k l_k`` (8.33) and the angle follows from (8.28),
``phidot_k = p_k / A_k - omega . l_k``: ``phi_k(t) = (p_k / A_k) t - int_0^t omega . l_k``.

The integral of ``omega . l_k`` over the closed-form motion: ``omega`` is a periodic function of
``t`` (period ``T`` of :func:`solve_gyrostat`'s diagnostics), analytic on the real line, so its
integral is ``nu_k t`` (the mean rate) plus a periodic function.  The periodic part is the term-by-
term integral of the Fourier series of the closed-form integrand, whose coefficients come from an
FFT of ``omega`` on one period (geometric convergence: the number of terms doubles until the tail
is at round-off, as for the precession angle).  The argument ``2 pi t / T`` is reduced modulo
``2 pi`` with an exact product, so a far time costs and loses what a near one does.  A constant
``omega`` (rest, steady rotation) integrates exactly.  On a separatrix of the gyrostat (period
``inf``) the integrand is a rational function of ``s = tanh(u)`` and its integral a Chebyshev
series in ``s`` (:class:`RotorAngles`); the Euler top's separatrix (rotors whose momenta cancel)
is refused.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from thetasol.core import validate as V
from thetasol.core.attitude import angle_mod_2pi as _angle_mod_2pi
from thetasol.core.periodic import adaptive_series
from thetasol.protocol import ClosedFormUnavailable

__all__ = ["Rotor", "parse_rotors", "RotorAngles", "rotor_angles", "AXIS_TOL", "N_RTOL"]

_EPS = np.finfo(float).eps
#: A rotor axis is accepted (and normalized) when its norm is within this of 1.
AXIS_TOL = 1e-12
#: ``N`` must equal ``sum p_k l_k`` to this relative tolerance (of ``|N| + sum |p_k|``).
N_RTOL = 1e-12


@dataclass(frozen=True)
class Rotor:
    """One rotor: unit axis ``axis`` in the carrier frame, axial moment ``A``, transverse moment
    ``B`` and conserved momentum ``p = A (omega . axis + phidot)`` (8.25)."""

    axis: np.ndarray
    A: float
    B: float
    p: float


def _scalar(x, what, positive=False, nonnegative=False):
    v = V.number(x, what)
    if positive and not v > 0:
        raise ValueError(f"{what} must be > 0, got {v}")
    if nonnegative and not v >= 0:
        raise ValueError(f"{what} must be >= 0, got {v}")
    return v


def _rotor(spec, k) -> Rotor:
    try:
        keys = set(spec)
        axis, A, B, p = spec["axis"], spec["A"], spec["B"], spec["p"]
    except (TypeError, KeyError):
        raise ValueError(f"rotors[{k}] must be a mapping with keys 'axis', 'A', 'B', 'p'") from None
    extra = keys - {"axis", "A", "B", "p"}
    if extra:
        raise ValueError(f"rotors[{k}] has unknown keys {sorted(extra)}")
    l = V.vector3(axis, f"rotors[{k}]['axis']")
    nl = float(np.linalg.norm(l))
    if not abs(nl - 1.0) <= AXIS_TOL:
        raise ValueError(f"rotors[{k}]['axis'] must be a unit vector (norm {nl!r})")
    return Rotor(axis=l / nl, A=_scalar(A, f"rotors[{k}]['A']", positive=True),
                 B=_scalar(B, f"rotors[{k}]['B']", nonnegative=True), p=_scalar(p, f"rotors[{k}]['p']"))


def parse_rotors(rotors, N) -> tuple[tuple[Rotor, ...], np.ndarray]:
    """The validated rotors and ``N``: ``N = sum p_k l_k`` (8.33) when ``N`` is None, else ``N``
    checked against that sum (relative tolerance :data:`N_RTOL`)."""
    if isinstance(rotors, dict) or not hasattr(rotors, "__len__"):
        raise ValueError("rotors must be a sequence of mappings with keys 'axis', 'A', 'B', 'p'")
    rs = tuple(_rotor(spec, k) for k, spec in enumerate(rotors))
    total = np.zeros(3)
    for r in rs:
        total = total + r.p * r.axis
    if N is None:
        return rs, total
    n = V.vector3(N, "N")
    scale = np.linalg.norm(n) + sum(abs(r.p) for r in rs)
    if np.linalg.norm(n - total) > N_RTOL * scale:
        raise ValueError(f"N = {n.tolist()} does not match the rotors' sum p_k l_k = {total.tolist()} "
                         f"(8.33) (difference {np.linalg.norm(n - total):.3e}, relative tolerance {N_RTOL})")
    return rs, n


def _fourier_series(f, T, nmax=2 ** 17):
    """Fourier coefficients of the periodic ``f(t)`` (values of shape (n, k)) on one period
    ``T``, the number of samples doubled from 64 until the tail is at round-off or stops
    decreasing (:func:`thetasol.core.periodic.adaptive_series`); returns the coefficients
    (trimmed) and the tail relative to the largest coefficient."""
    def coeffs(n):
        return np.fft.rfft(f(np.arange(n) * (T / n)), axis=0) / n

    c, tail = adaptive_series(coeffs, nmax, "solve_gyrostat: the rotor angles' Fourier series does not converge "
                                            "(tail {tail:.1e}; orbit too close to a separatrix)")
    return (c, 0.0) if tail == 0 and not np.any(c) else (_trim(c, np.max(np.abs(c))), tail)


def _trim(c, scale):
    """The coefficients up to the last one above eps/8 of the largest (the rest add nothing)."""
    big = np.nonzero(np.max(np.abs(c), axis=1) > 0.125 * _EPS * scale)[0]
    return c[:max(int(big[-1]) + 2, 2)] if len(big) else c[:2]


def _chebyshev_series(f, nmax=2 ** 14):
    """Chebyshev coefficients (n, k) of the interpolant of ``f(s)`` (values (n, k)) at the
    first-kind nodes, ``n`` doubled from 64 until the tail is at round-off or stops decreasing;
    returns them (trimmed) and the tail relative to the largest."""
    from scipy.fft import dct

    def coeffs(n):
        x = np.cos(np.pi * (np.arange(n) + 0.5) / n)
        c = dct(f(x), type=2, axis=0) / n
        c[0] *= 0.5
        return c

    c, tail = adaptive_series(coeffs, nmax, "solve_gyrostat: the rotor angles' Chebyshev series on the separatrix "
                                            "does not converge (tail {tail:.1e})")
    return (c, 0.0) if tail == 0 and not np.any(c) else (_trim(c, np.max(np.abs(c))), tail)


@dataclass(frozen=True, eq=False)
class RotorAngles:
    """``phi_k(t) = (p_k / A_k - nu_k) t - (S_k(t) - S_k(0))``: ``nu_k`` the mean of
    ``omega . l_k`` (on a separatrix its value at the saddle), ``S_k`` the integral of the rest.
    Built by :func:`rotor_angles`.

    ``impl`` is the motion (``omega(t)`` on flat times, body frame; on a separatrix also
    ``separatrix_argument(t)``), ``L`` the rotor axes (rows), ``rate`` the rotors' ``p_k / A_k``, ``drift`` the secular rate of
    each ``phi_k``.  Periodic motion: ``S_k`` is the Fourier series ``sum_j 2 Re d_j z^j`` in
    ``z = exp(i Om t)`` (``d_sum`` its value at ``t = 0``).  Separatrix: ``S_k`` is the Chebyshev series
    ``cheb`` in ``s = tanh(u)`` (``u`` the elliptic argument; ``s0`` its value at ``t = 0``)."""

    impl: object
    L: np.ndarray
    rate: np.ndarray
    nu: np.ndarray
    drift: np.ndarray
    Om: float = 0.0
    d: np.ndarray | None = None
    d_sum: np.ndarray | None = None
    cheb: np.ndarray | None = None
    s0: np.ndarray | None = None
    nterms: int = 0
    tail: float = 0.0

    def periodic(self, t):
        """``-(S_k(t) - S_k(0))``, shape (n, k)."""
        if self.cheb is not None:
            C = np.polynomial.chebyshev
            s = self.impl.separatrix_argument(t)
            return -(C.chebval(s, self.cheb).T - C.chebval(self.s0, self.cheb).T)
        if len(self.d) == 0:
            return np.zeros(t.shape + (len(self.rate),))
        th = _angle_mod_2pi(self.Om, t, 0.0)
        z = np.exp(1j * th)[:, None]
        s = np.zeros(t.shape + (len(self.rate),), dtype=complex)
        for dk in self.d[::-1]:
            s = (s + dk) * z
        return -2.0 * (s - self.d_sum).real

    def angles(self, t, wrap=False):
        """phi_k at flat times t, shape (n, k); with ``wrap`` reduced to (-pi, pi] modulo 2 pi
        with an exact product (the secular part of a far time loses nothing)."""
        per = self.periodic(t)
        if not wrap:
            return self.drift * t[:, None] + per
        out = np.empty_like(per)
        for k in range(per.shape[1]):
            a = _angle_mod_2pi(self.drift[k], t, per[:, k])
            out[:, k] = np.remainder(a + np.pi, 2 * np.pi) - np.pi
        return out

    def rates(self, omega_t):
        """phidot_k = p_k / A_k - omega . l_k (8.28) from omega at the times, shape (n, k)."""
        return self.rate - omega_t @ self.L.T


def rotor_angles(rotors, impl, period, omega0) -> RotorAngles:
    """The rotor angles of the motion ``impl`` of period ``period`` (0: constant ``omega``, ``inf``: a
    separatrix) from the body angular velocity ``omega0`` at ``t = 0`` (:class:`RotorAngles`).

    Periodic motion: ``omega . l_k`` as a Fourier series in ``2 pi t / T``, integrated term by term.
    Separatrix: in ``s = tanh(u)`` the integrand ``omega . l_k`` is a rational function equal to the
    saddle's value ``nu_k`` at ``s = +-1``, and ``S_k`` is the integral of ``(omega . l_k - nu_k) /
    (du/dt (1 - s^2))`` in ``s``: its Chebyshev interpolant, less its linear part at ``+-1`` (the
    rounding at the saddle), divided exactly by ``1 - s^2`` and integrated term by term (as for the
    precession angle).
    """
    L = np.array([r.axis for r in rotors]).reshape(-1, 3)
    rate = np.array([r.p / r.A for r in rotors])
    period = float(period)
    if period == np.inf:
        return _separatrix_angles(impl, L, rate)
    d = np.zeros((0, len(rate)), dtype=complex)
    tail, Om = 0.0, 0.0
    if period == 0.0:  # constant omega: the integral is exact
        nu = L @ np.asarray(omega0, dtype=float)
    else:
        c, tail = _fourier_series(lambda t: impl.omega(t) @ L.T, period)
        nu = c[0].real
        Om = 2 * np.pi / period
        k = np.arange(1, len(c) - 1)
        d = c[1:-1] / (1j * Om * k)[:, None]  # drop the Nyquist term
    # S(0) by the same Horner recursion as S(t) at z = 1: phi_k(0) = 0 exactly
    d_sum = np.zeros(len(rate), dtype=complex)
    for dk in d[::-1]:
        d_sum = d_sum + dk
    return RotorAngles(impl=impl, L=L, rate=rate, nu=nu, drift=rate - nu, Om=Om, d=d, d_sum=d_sum,
                       nterms=len(d), tail=tail)


def _separatrix_angles(impl, L, rate) -> RotorAngles:
    """:func:`rotor_angles` on a separatrix: the Chebyshev series of ``S_k`` in ``s = tanh(u)``."""
    if not hasattr(impl, "separatrix_argument"):
        raise ClosedFormUnavailable("solve_gyrostat: rotor angles on this separatrix (the Euler top's) "
                                    "are not supported; use thetasol.integrate_multibody")
    C = np.polynomial.chebyshev
    c, tail = _chebyshev_series(lambda s: impl.omega_at_tanh(s) @ L.T)
    p1, m1 = C.chebval(1.0, c), C.chebval(-1.0, c)
    nu = 0.5 * (p1 + m1)
    c[0] -= nu
    c[1] -= 0.5 * (p1 - m1)
    cheb = np.stack([C.chebint(C.chebdiv(c[:, j], [0.5, 0.0, -0.5])[0]) / impl.du_dt
                     for j in range(c.shape[1])], axis=1)
    return RotorAngles(impl=impl, L=L, rate=rate, nu=nu, drift=rate - nu, d=np.zeros((0, len(rate)), dtype=complex),
                       d_sum=np.zeros(len(rate), dtype=complex), cheb=cheb,
                       s0=impl.separatrix_argument(np.zeros(1)), nterms=len(cheb), tail=tail)
