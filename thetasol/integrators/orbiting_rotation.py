"""The numerical reference of Section 7: one body's rotation about its mass centre on a Kepler orbit.

The mass centre follows a :class:`~thetasol.solutions.kepler.KeplerOrbit` ``r(t)`` (7.7); the body
turns in the gravity-gradient torque of (7.16) (:func:`~thetasol.mechanics.gravity_gradient.gravity_gradient_torque`)

    mdot = m x omega + 3 mu / |r|^5 (Q^T r) x I (Q^T r),    Qdot = Q hat(omega),    m = I omega,

in the conventions of :func:`thetasol.integrators.rotation.integrate_rotation` (``Q`` body to space,
``omega`` body frame).  On a circular orbit this is the autonomous system (7.16) written in the
inertial frame; on an elliptic one it is non-autonomous (Corollary 6).

Methods:

``"DOP853"`` (default; any explicit :func:`scipy.integrate.solve_ivp` method)
    adaptive Runge-Kutta on ``(m, Q)``; ``r(t)`` from the closed-form orbit
    (:meth:`KeplerOrbit.state_at`) at every stage, ``Q`` projected onto SO(3) at output.
``"heyoka"``
    heyoka's Taylor integrator of the same equations with the orbit integrated alongside
    (``dtype="ldbl"``: 80-bit, ``"f128"``: quadruple precision) -- the extended-precision reference.

Accuracy (tests/test_orbiting_rotation.py): DOP853 is checked against 80-bit heyoka over many
orbits (circular, librating and tumbling), the Jacobi integral (7.18) on circular orbits, and a
centrally symmetric body of point masses in the exact 1/r field differs from it by ``16 (size / r)^2``
after two orbits, as the expansion (7.3) says.  Most of the cost of a right-hand side is the Kepler
solve (benchmarks/bench_orbiting_station.py measures it).  No symplectic splitting is offered here: the torque depends
on time through the orbit.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.so3 import polar_orthonormalize
from thetasol.core.threads import single_blas_thread
from thetasol.integrators._common import both_ways, heyoka_and_type, solve_ivp_mQ
from thetasol.protocol import RotationSolution
from thetasol.solutions.kepler import KeplerOrbit

__all__ = ["integrate_orbiting_rotation", "NumericalOrbitingRotation", "numerical_orbiting_rotation"]


@single_blas_thread
def integrate_orbiting_rotation(J: ArrayLike, orbit: KeplerOrbit, Q0: ArrayLike, omega0: ArrayLike, t: ArrayLike, *,
                                rtol: float = 1e-12, atol: float | None = None, method: str = "DOP853",
                                dtype: str = "dbl") -> tuple[np.ndarray, np.ndarray]:
    """Integrate the rotation of a rigid body about its mass centre moving on ``orbit``.

    Parameters
    ----------
    J : array_like, shape (3,) or (3, 3)
        Second moments ``sum m r r^T`` in the body frame (``I = tr(J) 1 - J``).
    orbit : KeplerOrbit
        The mass centre's orbit; its ``mu`` sets the torque.
    Q0 : array_like, shape (3, 3)
        Attitude at ``t = 0`` (body to space).
    omega0 : array_like, shape (3,)
        Body-frame angular velocity at ``t = 0``.
    t : array_like
        Output times (any shape and order; negative allowed).
    rtol, atol : float
        Tolerances (``atol`` defaults to ``1e-3 rtol`` times the scale of ``m0``; for heyoka
        ``rtol`` is its ``tol``).
    method : {"DOP853", "RK45", ..., "heyoka"}
    dtype : {"dbl", "ldbl", "f128"}
        Floating type for ``"heyoka"``.

    Returns
    -------
    omega : ndarray, shape ``t.shape + (3,)``
    Q : ndarray, shape ``t.shape + (3, 3)``
    """
    if not isinstance(orbit, KeplerOrbit):
        raise TypeError(f"orbit must be a KeplerOrbit, got {type(orbit).__name__}")
    Jm = V.second_moments(J, "J")
    Q0 = V.rotation_matrix(Q0, "Q0")
    w0 = V.vector3(omega0, "omega0")
    tt = V.times(t, "t")
    if not (0 < rtol < 1):
        raise ValueError(f"rtol must be in (0, 1), got {rtol}")
    Im = np.trace(Jm) * np.eye(3) - Jm
    m0 = Im @ w0
    # scale of m: the spin or the orbital rate times the inertia, whichever is larger
    mscale = max(np.linalg.norm(m0), orbit.diagnostics["mean_motion"] * np.max(np.abs(Im)),
                 np.finfo(float).tiny)
    atol = 1e-3 * rtol * mscale if atol is None else float(atol)
    def run(grid):
        if method == "heyoka":
            return _heyoka(Jm, orbit, Q0, w0, grid, rtol, dtype)
        return _solve_ivp(Jm, Im, orbit, Q0, m0, grid, rtol, atol, method)

    m_out, Q_out, inv = both_ways(tt, m0, Q0, run)
    Q_out = polar_orthonormalize(Q_out)
    omega = np.linalg.solve(Im, m_out[..., None])[..., 0]
    return omega[inv].reshape(tt.shape + (3,)), Q_out[inv].reshape(tt.shape + (3, 3))


def _solve_ivp(Jm, Im, orbit, Q0, m0, tgrid, rtol, atol, method):
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


def _to_fp(x, fp, mpmath):
    """An mpmath number rounded to ``fp`` as the sum of its float64 triple-word split."""
    parts = []
    for _ in range(3):
        parts.append(float(x))
        x = x - mpmath.mpf(parts[-1])
    return (fp(parts[0]) + fp(parts[1])) + fp(parts[2])


def _heyoka(Jm, orbit, Q0, w0, tgrid, rtol, dtype):
    import mpmath

    hy, ft = heyoka_and_type(dtype)
    with mpmath.workdps(60):     # I^-1 and m0 of the float64 data, rounded once to the working type
        Jmp = mpmath.matrix([[mpmath.mpf(float(x)) for x in row] for row in Jm])
        Imp = (Jmp[0, 0] + Jmp[1, 1] + Jmp[2, 2]) * mpmath.eye(3) - Jmp
        Iinv_mp, m0_mp = Imp ** -1, Imp * mpmath.matrix([mpmath.mpf(float(x)) for x in w0])
        Iinv = [[_to_fp(Iinv_mp[i, k], ft, mpmath) for k in range(3)] for i in range(3)]
        Iw = [[_to_fp(Imp[i, k], ft, mpmath) for k in range(3)] for i in range(3)]
        m0 = [_to_fp(m0_mp[i], ft, mpmath) for i in range(3)]
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
    tol = hy.real128(str(rtol)) if dtype == "f128" else ft(rtol)
    ta = hy.taylor_adaptive(sys, y0, tol=tol, fp_type=ft)
    states = np.asarray(ta.propagate_grid(grid)[-1], dtype=float)[1:]
    return states[:, 6:9], states[:, 9:].reshape(-1, 3, 3)


@dataclass(frozen=True, eq=False)
class NumericalOrbitingRotation(RotationSolution):
    """:func:`integrate_orbiting_rotation` behind the :class:`~thetasol.protocol.RotationSolution` protocol.

    ``sol(t) -> (omega, Q)`` integrates on demand, once per call, from ``t = 0`` to every requested
    time (any shape and order); nothing is cached.  ``a`` is the tidal matrix (7.11) at ``t = 0``.
    Build it with :func:`numerical_orbiting_rotation`.
    """

    orbit: KeplerOrbit = field(default=None, repr=False)
    rtol: float = 1e-12
    integrator: str = "DOP853"

    _AT_ONCE = True  # one integration over all requested times

    def _evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return integrate_orbiting_rotation(self.J, self.orbit, self.Q0, self.omega0, t, rtol=self.rtol,
                                           method=self.integrator)


def numerical_orbiting_rotation(J: ArrayLike, orbit: KeplerOrbit, Q0: ArrayLike, omega0: ArrayLike, *,
                                rtol: float = 1e-12, method: str = "DOP853") -> NumericalOrbitingRotation:
    """One body's rotation on ``orbit`` as a solution evaluated by :func:`integrate_orbiting_rotation`.

    Returns
    -------
    NumericalOrbitingRotation
        ``method`` is ``"numerical/<method>"``; ``invariants`` holds the Jacobi integral (7.18) at
        ``t = 0`` when the orbit is circular (``e <= 1e-13``), else nothing (the rotation on an
        elliptic orbit has no known first integral).
    """
    if not isinstance(orbit, KeplerOrbit):
        raise TypeError(f"orbit must be a KeplerOrbit, got {type(orbit).__name__}")
    Jm = V.second_moments(J, "J")
    Qm = V.rotation_matrix(Q0, "Q0")
    wm = V.vector3(omega0, "omega0")
    if not (0 < rtol < 1):
        raise ValueError(f"rtol must be in (0, 1), got {rtol}")
    r = orbit.r0
    rn = float(np.linalg.norm(r))
    a = -3.0 * orbit.mu / rn ** 3 * np.outer(r, r) / rn ** 2
    d = orbit.diagnostics
    inv = {}
    if d["kind"] == "elliptic" and d["e"] <= 1e-13:
        n = d["mean_motion"]
        Im = np.trace(Jm) * np.eye(3) - Jm
        g, h = Qm.T @ (r / rn), np.cross(r, orbit.v0)
        nb = Qm.T @ (h / np.linalg.norm(h))
        M = Im @ wm
        inv["jacobi"] = float(0.5 * M @ wm + 1.5 * n * n * g @ Im @ g - n * M @ nb)
    return NumericalOrbitingRotation(J=Jm, a=a, Q0=np.array(Q0, dtype=float), omega0=wm, method=f"numerical/{method}",
                                     invariants=inv, diagnostics={"integrator": "integrate_orbiting_rotation",
                                                                  "method": method, "rtol": rtol},
                                     orbit=orbit, rtol=float(rtol), integrator=method)
