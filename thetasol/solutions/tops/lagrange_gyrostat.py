"""The Lagrange gyrostat (Section 8 on a pivot): a symmetric carrier with a rotor on its axis, in gravity.

A heavy top whose inertia about the fixed point is symmetric about the axis through its mass centre
and that carries rotors whose momentum ``N = lam e3`` lies along that axis (``e3 = center / |center|``)
obeys ``mdot = (m + N) x omega + mass |g| gamma x center`` with ``m = I omega``, ``I`` without the
rotors' axial moments.  The axial momentum ``M3 = C omega3 + lam`` and the vertical momentum
``(m + N) . gamma`` are conserved, ``omega3`` is constant, and the nutation ``u = gamma . e3`` obeys the
Lagrange top's cubic with ``a = M3 / A`` (the total axial momentum); the spin angle obeys
``phidot = omega3 - u psidot`` with ``omega3 = (M3 - lam) / C``.  So the closed form of
:mod:`thetasol.solutions.tops.lagrange_top` holds with one changed constant: the phase rate
``kappa = a (A / C - 1)`` becomes ``omega3 - a`` (from the spin equation above); everything else (turning
points, Legendre integrals of the third kind, far-time reduction) is the top's.

Checked against :func:`thetasol.integrators.gyrostat.integrate_heavy_gyrostat` (80-bit heyoka) in
tests/test_gyrostat_potential.py.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.threads import single_blas_thread
from thetasol.mechanics.heavy_top import heavy_top_data, heavy_top_invariants
from thetasol.protocol import ROUNDOFF, ClosedFormUnavailable, quiet_far_times
from thetasol.solutions.gyrostat import solve_gyrostat
from thetasol.solutions.tops.heavy_top import (
    EulerHeavyTopSolution,
    LagrangeTopSolution,
    SteadyRotationSolution,
    solve_heavy_top,
)
from thetasol.solutions.tops.heavy_top_base import HeavyTopSolution
from thetasol.solutions.tops.lagrange_top import SYMMETRY_RTOL, build_lagrange_top, lagrange_frame

__all__ = ["solve_lagrange_gyrostat"]

_REFERENCE = "thetasol.integrators.gyrostat.integrate_heavy_gyrostat"


def _invariants(Im, c, N, mass, g, w0, Q0) -> dict:
    base = heavy_top_invariants(Im, c, mass, g, w0, Q0)
    gn, cn = np.linalg.norm(g), np.linalg.norm(c)
    up = -g / gn if gn > 0 else np.array([0.0, 0.0, 1.0])      # heavy_top_invariants' conventions without
    h = Im @ w0 + N                                              # gravity or with the centre at the pivot
    return {"energy": float(base["energy"]), "vertical_momentum": float((Q0 @ h) @ up),
            "axial_momentum": float(h @ (c / cn)) if cn > 0 else 0.0}


def _torque_free(Im, c, Nv, Q0m, w0, mass, g) -> EulerHeavyTopSolution:
    """No gravity torque (centre at the pivot, no gravity or no mass): the free gyrostat of the same body,
    as a heavy-top result like every other answer of :func:`solve_lagrange_gyrostat`."""
    gyro = solve_gyrostat(Im, Nv, Q0m, w0)
    diag = {**gyro.diagnostics, "case": "gyrostat" + (f"/{gyro.case}" if gyro.case else "")}
    return EulerHeavyTopSolution(Im, c, mass, g, Q0m, w0, gyro.method, _invariants(Im, c, Nv, mass, g, w0, Q0m),
                                 diag, rotation=quiet_far_times(gyro))


@single_blas_thread
def solve_lagrange_gyrostat(I: ArrayLike, center: ArrayLike, Q0: ArrayLike, omega0: ArrayLike, *, N: ArrayLike,
                            mass: float = 1.0, gravity: ArrayLike = (0.0, 0.0, -9.81)
                            ) -> HeavyTopSolution:
    """Exact motion of a Lagrange gyrostat on a fixed point in uniform gravity.

    Parameters
    ----------
    I : array_like, shape (3,) or (3, 3)
        Inertia about the fixed point, body frame, WITHOUT the rotors' axial moments (rotor masses and
        transverse moments included): ``m = I omega``.
    center : array_like (3,)
        Mass centre seen from the fixed point, body frame.
    Q0, omega0 : array_like
        Initial attitude and body angular velocity of the carrier.
    N : array_like (3,)
        Constant rotor momentum ``sum p_k l_k`` (8.33), body frame; must lie along ``center``
        (keyword-only: the field of the top is its ``center``).
    mass : float
    gravity : array_like (3,)

    Returns
    -------
    HeavyTopSolution
        ``sol(t) -> (omega, Q)``; model ``"heavy-top"``, method ``"elliptic"`` (case ``""`` or
        ``"separatrix"``; ``"elementary"`` with case ``"steady"``) and ``diagnostics["rotor_momentum"]``;
        ``N = 0`` is :func:`thetasol.solutions.tops.heavy_top.solve_heavy_top`; no gravity or the centre at
        the pivot the free gyrostat of :func:`thetasol.solve_gyrostat` (case ``"gyrostat"``), as a heavy-top
        result.  ``invariants``: ``energy``
        (``1/2 omega . I omega - mass g . Q center``), ``vertical_momentum`` (``Q (m + N) . up``),
        ``axial_momentum`` (``(m + N) . e3``).

    Raises
    ------
    ValueError
        Bad data (as :func:`solve_heavy_top`).
    ClosedFormUnavailable
        ``I`` not symmetric about the axis of ``center`` or ``N`` not along it (the message names
        :func:`~thetasol.integrators.gyrostat.integrate_heavy_gyrostat`).
    """
    Im, c, Q0m, w0, mass, g = heavy_top_data(I, center, Q0, omega0, mass, gravity)
    Nv = V.vector3(N, "N")
    cn, gn = np.linalg.norm(c), np.linalg.norm(g)
    if not np.any(Nv):
        return solve_heavy_top(Im, c, Q0m, w0, mass=mass, gravity=g)
    if cn == 0 or gn == 0 or mass == 0:
        return _torque_free(Im, c, Nv, Q0m, w0, mass, g)
    frame = lagrange_frame(Im, c)
    e3 = c / cn
    lam = float(Nv @ e3)
    if frame is None or np.linalg.norm(Nv - lam * e3) > SYMMETRY_RTOL * np.linalg.norm(Nv):
        raise ClosedFormUnavailable("heavy gyrostat: not a Lagrange gyrostat (inertia symmetric about the axis "
                                    f"of the mass centre, rotor momentum along it); use {_REFERENCE}")
    inv = _invariants(Im, c, Nv, mass, g, w0, Q0m)
    up = -g / gn
    if abs((Q0m @ e3) @ up) == 1.0 and np.all(np.cross(Q0m @ w0, up) == 0):
        return SteadyRotationSolution(Im, c, mass, g, Q0m, w0, "elementary", inv,
                                      {"case": "steady", "rotor_momentum": lam, "error_estimate": ROUNDOFF})
    consts, diag = build_lagrange_top(Im, c, Q0m, w0, mass * gn * cn, up, rotor_momentum=lam)
    diag["rotor_momentum"] = lam
    diag.update(case="separatrix" if diag["mc"] == 0 else "", error_estimate=max(ROUNDOFF, diag["fit_residual"]))
    return LagrangeTopSolution(Im, c, mass, g, Q0m, w0, "elliptic", inv, diag, consts)
