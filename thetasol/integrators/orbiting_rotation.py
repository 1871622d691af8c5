"""The numerical reference of Section 7: one body's rotation about its mass centre on a Kepler orbit.

The mass centre follows a given orbit ``r(t)`` (:class:`~thetasol.mechanics.orbit.Orbit`, e.g. the
Kepler orbit (7.7) of :class:`thetasol.KeplerOrbit`); the body
turns in the gravity-gradient torque of (7.16) (:func:`~thetasol.mechanics.gravity_gradient.gravity_gradient_torque`)

    mdot = m x omega + 3 mu / |r|^5 (Q^T r) x I (Q^T r),    Qdot = Q hat(omega),    m = I omega,

in the conventions of :func:`thetasol.integrators.rotation.integrate_rotation` (``Q`` body to space,
``omega`` body frame).  On a circular orbit this is the autonomous system (7.16) written in the
inertial frame; on an elliptic one it is non-autonomous (Corollary 6).

Methods:

``"DOP853"`` (default; any explicit :func:`scipy.integrate.solve_ivp` method)
    adaptive Runge-Kutta on ``(m, Q)``; ``r(t)`` from the closed-form orbit
    (the orbit's ``state_at``) at every stage, ``Q`` projected onto SO(3) at output.
``"heyoka"``
    heyoka's Taylor integrator of the same equations with the orbit integrated alongside
    (``fp_type=numpy.longdouble``: 80-bit, ``heyoka.real128``: quadruple precision) -- the
    extended-precision reference; it integrates the Kepler orbit of ``orbit.mu``, ``orbit.r0``, ``orbit.v0``.

Accuracy (tests/test_orbiting_rotation.py): DOP853 is checked against 80-bit heyoka over many
orbits (circular, librating and tumbling), the Jacobi integral (7.18) on circular orbits, and a
centrally symmetric body of point masses in the exact 1/r field differs from it by ``16 (size / r)^2``
after two orbits, as the expansion (7.3) says.  Most of the cost of a right-hand side is the Kepler
solve (benchmarks/bench_orbiting_station.py measures it).  No symplectic splitting is offered here: the torque depends
on time through the orbit.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.so3 import polar_orthonormalize
from thetasol.integrators._common import (
    Settings,
    body_inertia,
    both_ways,
    extended_inertia,
    heyoka_and_type,
    heyoka_tol,
    settings,
    solve_ivp_mQ,
)
from thetasol.mechanics.orbit import Orbit, check_orbit
from thetasol.protocol import RotationSolution

__all__ = ["integrate_orbiting_rotation", "NumericalOrbitingRotation"]


def integrate_orbiting_rotation(I: ArrayLike, orbit: Orbit, Q0: ArrayLike, omega0: ArrayLike, *,  # noqa: E741
                                method: str = "DOP853", rtol: float = 1e-12, atol: float | None = None,
                                fp_type: Any = float) -> NumericalOrbitingRotation:
    """The rotation of a rigid body about its mass centre moving on ``orbit``, integrated numerically.

    Parameters
    ----------
    I : array_like, shape (3,) or (3, 3)
        Inertia tensor about the mass centre, body frame (principal values or a symmetric tensor).
    orbit : Orbit
        The mass centre's orbit (:class:`thetasol.KeplerOrbit`, or any object with the members of
        :class:`thetasol.mechanics.orbit.Orbit`); its ``mu`` sets the torque.
    Q0 : array_like, shape (3, 3)
        Attitude at ``t = 0`` (body to space).
    omega0 : array_like, shape (3,)
        Body-frame angular velocity at ``t = 0``.
    method : {"DOP853", "RK45", ..., "heyoka"}
    rtol, atol : float
        Tolerances (``atol`` defaults to ``1e-3 rtol`` times the scale of ``m0``; heyoka takes ``rtol``
        as its ``tol`` and refuses ``atol``).
    fp_type : {float, numpy.longdouble, heyoka.real128}
        Floating type of ``"heyoka"``.

    Returns
    -------
    NumericalOrbitingRotation
        ``sol(t) -> (omega, Q)`` with shapes ``t.shape + (3,)`` and ``t.shape + (3, 3)``, one
        integration from ``t = 0`` per call; ``model`` is ``"orbiting-rotation"``, ``method``
        ``"numerical/<method>"``; ``a`` the tidal matrix (7.11) at ``t = 0``; ``invariants`` the
        Jacobi integral (7.18) at ``t = 0`` when the orbit is circular (``e <= 1e-13``), else nothing
        (the rotation on an elliptic orbit has no known first integral); ``diagnostics`` the
        integrator settings and ``error_estimate`` (its ``rtol``).
    """
    orbit = check_orbit(orbit)
    Im, Jm = body_inertia(I)
    Qm = V.rotation_matrix(Q0, "Q0")
    wm = V.vector3(omega0, "omega0")
    opts = settings(method, rtol, atol, fp_type)
    r = np.asarray(orbit.r0, dtype=float)
    rn = float(np.linalg.norm(r))
    a = -3.0 * orbit.mu / rn ** 3 * np.outer(r, r) / rn ** 2
    d = orbit.diagnostics
    inv = {}
    if d["kind"] == "elliptic" and d["e"] <= 1e-13:
        n = d["mean_motion"]
        g, h = Qm.T @ (r / rn), np.cross(r, orbit.v0)
        nb = Qm.T @ (h / np.linalg.norm(h))
        M = Im @ wm
        inv["jacobi"] = float(0.5 * M @ wm + 1.5 * n * n * g @ Im @ g - n * M @ nb)
    return NumericalOrbitingRotation(J=Jm, a=a, Q0=Qm, omega0=wm, method=f"numerical/{opts.method}", invariants=inv,
                                     diagnostics=opts.diagnostics(), I_given=Im, orbit=orbit, settings=opts)


@dataclass(frozen=True, eq=False)
class NumericalOrbitingRotation(RotationSolution):
    """The rotation of :func:`integrate_orbiting_rotation` behind the
    :class:`~thetasol.protocol.RotationSolution` protocol.

    ``sol(t) -> (omega, Q)`` integrates on demand, once per call, from ``t = 0`` to every requested
    time (any shape and order); nothing is cached.  ``a`` is the tidal matrix (7.11) at ``t = 0``,
    ``I`` the inertia as given and ``J`` its second moments.
    """

    orbit: Orbit = field(default=None, repr=False)
    settings: Settings = Settings()

    model: ClassVar[str] = "orbiting-rotation"
    _AT_ONCE = True  # one integration over all requested times

    def _evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        s, Im, orbit, Q0, w0 = self.settings, self.I, self.orbit, self.Q0, self.omega0
        m0 = Im @ w0
        # scale of m: the spin or the orbital rate times the inertia, whichever is larger
        mscale = max(np.linalg.norm(m0), orbit.diagnostics["mean_motion"] * np.max(np.abs(Im)),
                     np.finfo(float).tiny)
        atol = 1e-3 * s.rtol * mscale if s.atol is None else s.atol

        def run(grid):
            if s.method == "heyoka":
                return _heyoka(Im, orbit, Q0, w0, grid, s.rtol, s.fp_type)
            return _solve_ivp(Im, orbit, Q0, m0, grid, s.rtol, atol, s.method)

        m_out, Q_out, inv = both_ways(t, m0, Q0, run)
        Q_out = polar_orthonormalize(Q_out)
        omega = np.linalg.solve(Im, m_out[..., None])[..., 0]
        return omega[inv], Q_out[inv]


def _solve_ivp(Im, orbit, Q0, m0, tgrid, rtol, atol, method):
    return solve_ivp_mQ(_make_rhs(Im, orbit), m0, Q0, tgrid, rtol, atol, method)


def _make_rhs(Im, orbit):
    """The right-hand side on Python floats: numpy's per-call overhead on 3-vectors would be several times the work.

    The same formulas as :func:`gravity_gradient_torque` (checked against it in the tests).
    """
    (i00, i01, i02), (i10, i11, i12), (i20, i21, i22) = Im.tolist()
    (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = np.linalg.inv(Im).tolist()
    mu3 = 3.0 * float(orbit.mu)
    state_at = orbit.state_at

    def rhs(time, y):
        m0, m1, m2, q00, q01, q02, q10, q11, q12, q20, q21, q22 = y.tolist()
        w0 = a00 * m0 + a01 * m1 + a02 * m2
        w1 = a10 * m0 + a11 * m1 + a12 * m2
        w2 = a20 * m0 + a21 * m1 + a22 * m2
        (x, yy, z), _ = state_at(time)
        r2 = x * x + yy * yy + z * z
        c = mu3 / (r2 * r2 * r2 ** 0.5)
        b0 = q00 * x + q10 * yy + q20 * z          # Q^T r
        b1 = q01 * x + q11 * yy + q21 * z
        b2 = q02 * x + q12 * yy + q22 * z
        e0 = i00 * b0 + i01 * b1 + i02 * b2        # I Q^T r
        e1 = i10 * b0 + i11 * b1 + i12 * b2
        e2 = i20 * b0 + i21 * b1 + i22 * b2
        return np.array([
            m1 * w2 - m2 * w1 + c * (b1 * e2 - b2 * e1),
            m2 * w0 - m0 * w2 + c * (b2 * e0 - b0 * e2),
            m0 * w1 - m1 * w0 + c * (b0 * e1 - b1 * e0),
            # Q hat(w), row by row
            q01 * w2 - q02 * w1, q02 * w0 - q00 * w2, q00 * w1 - q01 * w0,
            q11 * w2 - q12 * w1, q12 * w0 - q10 * w2, q10 * w1 - q11 * w0,
            q21 * w2 - q22 * w1, q22 * w0 - q20 * w2, q20 * w1 - q21 * w0])

    return rhs


def _heyoka(Im, orbit, Q0, w0, tgrid, rtol, fp_type):
    hy, ft = heyoka_and_type(fp_type)
    Iinv, m0 = extended_inertia(Im, w0, ft)  # I^-1 and m0 of the float64 data, rounded once to the working type
    Iw = [[ft(float(x)) for x in row] for row in Im]
    names = ["x", "y", "z", "vx", "vy", "vz"] + [f"m{i}" for i in range(3)] + [f"q{i}{j}" for i in range(3) for j in range(3)]
    xs = hy.make_vars(*names)
    pos, vel, m = xs[0:3], xs[3:6], xs[6:9]
    Q = [xs[9 + 3 * i: 12 + 3 * i] for i in range(3)]
    mu = float(orbit.mu)
    r2 = pos[0] ** 2 + pos[1] ** 2 + pos[2] ** 2
    acc = [-mu * p * r2 ** -1.5 for p in pos]
    w = [sum(Iinv[i][k] * m[k] for k in range(3)) for i in range(3)]
    rb = [sum(Q[k][i] * pos[k] for k in range(3)) for i in range(3)]        # Q^T r
    Irb = [sum(Iw[i][k] * rb[k] for k in range(3)) for i in range(3)]
    c = 3.0 * mu * r2 ** -2.5
    tau = [c * (rb[1] * Irb[2] - rb[2] * Irb[1]), c * (rb[2] * Irb[0] - rb[0] * Irb[2]),
           c * (rb[0] * Irb[1] - rb[1] * Irb[0])]
    mdot = [m[1] * w[2] - m[2] * w[1] + tau[0], m[2] * w[0] - m[0] * w[2] + tau[1],
            m[0] * w[1] - m[1] * w[0] + tau[2]]
    W = [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]]
    Qdot = [sum(Q[i][k] * W[k][j] for k in range(3)) for i in range(3) for j in range(3)]
    sys = list(zip(xs, list(vel) + acc + mdot + Qdot, strict=True))
    y0 = np.array([ft(float(v)) for v in list(orbit.r0) + list(orbit.v0)] + m0 + [ft(float(v)) for v in Q0.ravel()])
    grid = np.array([ft(float(v)) for v in np.concatenate([[0.0], tgrid])])
    tol = heyoka_tol(hy, ft, rtol)
    ta = hy.taylor_adaptive(sys, y0, tol=tol, fp_type=ft)
    states = np.asarray(ta.propagate_grid(grid)[-1], dtype=float)[1:]
    return states[:, 6:9], states[:, 9:].reshape(-1, 3, 3)
