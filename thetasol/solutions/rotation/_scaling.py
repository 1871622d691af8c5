"""Units of the rotation problem: solve in units where the data are of order one.

Multiplying ``J`` by a constant, rescaling time, or adding ``c 1`` to ``a`` changes nothing
physical: with ``J = s_J J'``, ``t = T t'``, ``omega = omega' / T`` and ``a = c 1 + a' / T^2`` the
equations (4.8) for ``(J', a', omega')`` are those for ``(J, a, omega)`` (the torque ``[J, Q^T a Q]``
scales with ``J`` and does not see ``c 1``) and ``Q(t) = Q'(t / T)``.  :func:`choose_scales`
picks ``s_J`` and ``T`` as exact powers of two, so the change of units is exact in floating point,
and :class:`ScaledRotation` maps the dimensionless solution back to the user's units.

The isotropic part is removed with ``c`` equal to the middle diagonal entry of ``a``: where ``c``
dominates, every ``a_ii - c`` is then exact (Sterbenz), so the deviatoric part carries all the digits
the data have.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from thetasol.mechanics.equations import invariants_from_moments as _invariants
from thetasol.protocol import RotationSolution, quiet_far_times

__all__ = ["Scales", "choose_scales", "dimensionless_data", "ScaledRotation", "scaled_solution"]

#: Data whose scale lies within 2^+-ORDER_ONE of 1 are left in the user's units (bit-identical results).
ORDER_ONE = 4
EPS = np.finfo(float).eps


@dataclass(frozen=True)
class Scales:
    """The change of units: ``J = J_unit J'``, ``t = time_unit t'``, ``a = isotropic 1 + a' / time_unit^2``."""

    J_unit: float
    time_unit: float
    isotropic: float

    @property
    def trivial(self) -> bool:
        return self.J_unit == 1.0 and self.time_unit == 1.0 and self.isotropic == 0.0

    def as_dict(self) -> dict:
        return {"J_unit": self.J_unit, "time_unit": self.time_unit, "isotropic_part": self.isotropic}


def _power_of_two(x: float) -> float:
    """2^k nearest to x (in log scale); 1 when x is within 2^+-ORDER_ONE of 1 or not positive."""
    if not (x > 0 and math.isfinite(x)):
        return 1.0
    k = round(math.log2(x))
    return 1.0 if abs(k) <= ORDER_ONE else math.ldexp(1.0, k)


def _spread(a: np.ndarray) -> float:
    """max |eigenvalue| of the trace-free part of a."""
    c = np.trace(a) / 3.0
    return float(np.abs(np.linalg.eigvalsh(a - c * np.eye(3))).max())


def choose_scales(J: np.ndarray, a: np.ndarray, omega0: np.ndarray) -> Scales:
    """Units in which ``max J``, and the larger of ``|omega0|`` and ``sqrt|a - c 1|``, are of order one.

    The isotropic part ``c`` is removed only where it dominates (``|c|`` above the spread of the
    eigenvalues of ``a``): below that it costs at most a factor 2 in the relative tolerances of the
    curve computations, and keeping it keeps results on order-one data bit-identical.
    """
    sJ = _power_of_two(float(np.linalg.eigvalsh(J)[-1]))
    spread = _spread(a)
    c_mean = np.trace(a) / 3.0
    # the median of the three diagonal entries (np.median's value; it would import numpy.ma)
    c = float(np.sort(np.diag(a))[1]) if abs(c_mean) > spread else 0.0
    rate = max(float(np.linalg.norm(omega0)), math.sqrt(spread))
    T = 1.0 / _power_of_two(rate)
    return Scales(J_unit=sJ, time_unit=T, isotropic=c)


def _snap_double_eigenvalue(a_dev: np.ndarray, rounding: float) -> np.ndarray:
    """a_dev with two eigenvalues closer than ``rounding`` (the user's a cannot tell them apart) made equal."""
    lam, V = np.linalg.eigh(a_dev)
    k = int(np.argmin(np.diff(lam)))
    if not 0.0 < lam[k + 1] - lam[k] <= rounding:
        return a_dev
    lam[k] = lam[k + 1] = 0.5 * (lam[k] + lam[k + 1])
    out = (V * lam) @ V.T
    return 0.5 * (out + out.T)


def dimensionless_data(J, a, omega0, sc: Scales):
    """``(J', a', omega0')`` of the data in the units ``sc`` (exact but for ``a - c 1``).

    With a dominant isotropic part the user's ``a`` fixes the trace-free part only to
    ``eps max|a_ij|``: a double eigenvalue split by less than that (a gravity gradient plus a large
    ``c 1``) is made exact, as the curve computations expect of a rank-one potential.
    """
    T = sc.time_unit
    a_dev = a
    if sc.isotropic != 0.0:
        a_dev = _snap_double_eigenvalue(a - sc.isotropic * np.eye(3), 16 * EPS * float(np.abs(a).max()))
    return J / sc.J_unit, (a_dev * T) * T, omega0 * T


@dataclass(frozen=True, eq=False)
class ScaledRotation(RotationSolution):
    """A solution of the dimensionless problem seen in the user's units.

    ``omega(t) = omega'(t / T) / T`` and ``Q(t) = Q'(t / T)`` with ``T = scales.time_unit`` (a power of
    two: both maps are exact).  ``J``, ``a``, ``Q0``, ``omega0`` and ``invariants`` are the user's;
    ``method`` is the inner solution's; ``diagnostics`` holds the inner solution's diagnostics in the
    user's units, the scales, and the inner invariants (times there in units of ``T``, rates in
    units of ``1 / T``).
    """

    inner: RotationSolution = field(default=None, repr=False)
    scales: Scales = field(default=None)

    def _per_time(self, w: np.ndarray) -> np.ndarray:
        """w / T, exact: mpf values (dps=) are shifted by the exponent, not rounded to mpmath's precision."""
        T = self.scales.time_unit
        if w.dtype != object:
            return w / T
        import mpmath

        k = -(math.frexp(T)[1] - 1)
        return np.vectorize(lambda x: mpmath.ldexp(x, k), otypes=[object])(w)

    def _evaluate(self, t: np.ndarray):
        w, Q = self.inner(t / self.scales.time_unit)
        return self._per_time(w), Q

    def _omega(self, t: np.ndarray) -> np.ndarray:
        return self._per_time(self.inner.omega(t / self.scales.time_unit))


#: Entries of the branches' ``invariants`` that carry units: a time, a rate, a rate squared (Neumann's
#: ``k``, eigenvalues of a multiple of ``a``: meaningful in the user's units only without isotropic shift).
_TIMES = ("period",)
_RATES = ("precession_rate", "pendulum_nu")


def _in_user_units(entries: dict, sc: Scales) -> dict:
    """A branch's ``invariants`` or ``diagnostics`` with times, rates and ``k`` in the user's units."""
    T = sc.time_unit
    out = dict(entries)
    for key in _TIMES:
        if key in out:
            out[key] = out[key] * T
    for key in _RATES:
        if key in out:
            out[key] = out[key] / T
    if "k" in out:
        if sc.isotropic == 0.0:
            out["k"] = out["k"] / T**2
        else:
            del out["k"]                         # shifted by the isotropic part: see dimensionless_invariants
    return out


def _user_invariants(inner: RotationSolution, J, a, Q0, omega0, sc: Scales) -> dict:
    """The inner solution's entries in the user's units; the first integrals from the user's data."""
    inv = _in_user_units(inner.invariants, sc)
    first = _invariants(J, a, Q0, omega0)
    inv.update({k: (float(v) if np.ndim(v) == 0 else v) for k, v in first.items()})
    return inv


def scaled_solution(inner: RotationSolution, J, a, Q0, omega0, sc: Scales) -> ScaledRotation:
    """Wrap ``inner`` (the solution for :func:`dimensionless_data`) in the user's units."""
    inv = _user_invariants(inner, J, a, Q0, omega0, sc)
    diag = _in_user_units(inner.diagnostics, sc)
    diag.update(scales=sc.as_dict(), dimensionless_invariants=inner.invariants)
    return ScaledRotation(J=J, a=a, Q0=Q0, omega0=omega0, method=inner.method, invariants=inv,
                          dps=inner.dps, diagnostics=diag, inner=quiet_far_times(inner), scales=sc)
