"""The numerical reference: a heavy top, a rigid body turning about a fixed point in uniform gravity.

``integrate_heavy_top`` integrates the Euler-Poisson equations of Section 5 in the body frame,

    m = I omega,   mdot = m x omega + c x (Q^T mass g),   Qdot = Q hat(omega),

where ``I`` is the inertia about the fixed point, ``c`` the mass centre seen from the fixed point
(body frame) and ``g`` the gravity vector in space.  The potential is
``V = -mass g . (Q c)``; with ``gamma = -Q^T g / |g|`` (the upward vertical in the body) the torque is
``mass |g| gamma x c``, the form ``dM/dt = M x omega + m g gamma x R`` of the paper.

Two methods, as in :mod:`thetasol.integrators.rotation`:

``"DOP853"`` (default; any explicit :func:`scipy.integrate.solve_ivp` method name works)
    adaptive Runge-Kutta on ``(m, Q)``; ``Q`` is projected onto SO(3) at output only.
``"heyoka"``
    heyoka's Taylor integrator (optional extra ``thetasol[bench]``); ``fp_type=numpy.longdouble``
    (80-bit) or ``heyoka.real128`` gives an extended-precision reference.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core.inertia import second_moments
from thetasol.core.so3 import cross, hat, polar_orthonormalize
from thetasol.integrators._common import (
    Settings,
    both_ways,
    extended_inertia,
    heyoka_and_type,
    heyoka_tol,
    settings,
    solve_ivp_mQ,
)
from thetasol.mechanics.heavy_top import heavy_top_data, heavy_top_invariants
from thetasol.protocol import RotationSolution

__all__ = ["integrate_heavy_top", "NumericalHeavyTop"]


def integrate_heavy_top(I: ArrayLike, center: ArrayLike, Q0: ArrayLike, omega0: ArrayLike, *,
                        mass: float = 1.0, gravity: ArrayLike = (0.0, 0.0, -9.81), method: str = "DOP853",
                        rtol: float = 1e-12, atol: float | None = None, fp_type: Any = float) -> NumericalHeavyTop:
    """The heavy top (Section 5), integrated numerically.

    Parameters
    ----------
    I : array_like, shape (3,) or (3, 3)
        Inertia about the fixed point in the body frame (principal values or a symmetric tensor).
    center : array_like, shape (3,)
        Mass centre seen from the fixed point, body frame.
    Q0 : array_like, shape (3, 3)
        Initial attitude, body to space (orthogonal to 1e-10).
    omega0 : array_like, shape (3,)
        Initial body-frame angular velocity (``Qdot = Q hat(omega)``).
    mass : float
        Mass of the body.
    gravity : array_like, shape (3,)
        Gravity acceleration in space; the potential is ``V = -mass gravity . (Q center)``.
    method : {"DOP853", "RK45", ..., "heyoka"}
    rtol, atol : float
        Tolerances (``atol`` defaults to ``1e-3 rtol``; heyoka takes ``rtol`` only and refuses ``atol``).
    fp_type : {float, numpy.longdouble, heyoka.real128}
        Floating type of ``"heyoka"``: ``numpy.longdouble`` is 80-bit extended precision.

    Returns
    -------
    NumericalHeavyTop
        ``sol(t) -> (omega, Q)`` with shapes ``t.shape + (3,)`` and ``t.shape + (3, 3)``, one
        integration from ``t = 0`` per call; ``model`` is ``"heavy-top"``, ``method``
        ``"numerical/<method>"``; ``invariants`` the ``energy``, ``vertical_momentum`` and
        ``axial_momentum`` at ``t = 0`` (:func:`thetasol.heavy_top_invariants`); ``diagnostics`` the
        integrator settings and ``error_estimate`` (its ``rtol``).

    Notes
    -----
    DOP853's error against 80-bit heyoka grows with t and the spin, and its cost with the spin:
    on fast tops (Simo-Wong's, Bruls-Cardona's) heyoka is both more accurate and much cheaper
    (tests/test_heavy_top.py; benchmarks/bench_heavy_top.py measures both).
    """
    Im, c, Q0m, w0, mass, g = heavy_top_data(I, center, Q0, omega0, mass, gravity)
    opts = settings(method, rtol, atol, fp_type)
    first = {k: float(v) for k, v in heavy_top_invariants(Im, c, mass, g, w0, Q0m).items()}
    return NumericalHeavyTop(J=second_moments(Im), a=np.zeros((3, 3)), Q0=Q0m, omega0=w0,
                             method=f"numerical/{opts.method}", invariants=first, diagnostics=opts.diagnostics(),
                             I_given=Im, center=c, mass=mass, gravity=g, settings=opts)


@dataclass(frozen=True, eq=False)
class NumericalHeavyTop(RotationSolution):
    """The heavy top of :func:`integrate_heavy_top` behind the :class:`~thetasol.protocol.RotationSolution`
    protocol: ``sol(t)`` integrates on demand, once per call, from ``t = 0`` to every requested time.

    ``I`` is the inertia about the fixed point as given (``J`` its second moments, ``a`` zero: the
    field is the uniform ``gravity``), ``center`` the mass centre seen from the fixed point.
    """

    center: np.ndarray = None
    mass: float = 1.0
    gravity: np.ndarray = None
    settings: Settings = Settings()

    model: ClassVar[str] = "heavy-top"
    _AT_ONCE = True  # one integration over all requested times

    def _evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        s, Im, c, Q0m, w0 = self.settings, self.I, self.center, self.Q0, self.omega0
        atol = 1e-3 * s.rtol if s.atol is None else s.atol
        F = self.mass * self.gravity  # the weight, space frame
        m0 = Im @ w0

        def run(grid):
            if s.method == "heyoka":
                return _heyoka(Im, c, F, Q0m, w0, grid, s.rtol, s.fp_type)
            return _solve_ivp(Im, c, F, Q0m, m0, grid, s.rtol, atol, s.method)

        m_out, Q_out, inv = both_ways(t, m0, Q0m, run)
        Q_out = polar_orthonormalize(Q_out)
        omega = np.linalg.solve(Im, m_out[..., None])[..., 0]
        return omega[inv], Q_out[inv]


def _solve_ivp(Im, c, F, Q0, m0, grid, rtol, atol, method):
    I_inv = np.linalg.inv(Im)

    def rhs(_t, y):
        m, Q = y[:3], y[3:].reshape(3, 3)
        w = I_inv @ m
        mdot = cross(m, w) + cross(c, Q.T @ F)
        return np.concatenate([mdot, (Q @ hat(w)).ravel()])

    return solve_ivp_mQ(rhs, m0, Q0, grid, rtol, atol, method)


def _heyoka(Im, c, F, Q0, w0, grid, rtol, fp_type):
    hy, ft = heyoka_and_type(fp_type)
    names = [f"m{i}" for i in range(3)] + [f"q{i}{j}" for i in range(3) for j in range(3)]
    xs = hy.make_vars(*names)
    m = xs[:3]
    Q = [xs[3 + 3 * i: 6 + 3 * i] for i in range(3)]
    if ft is float:
        Iw, m0w = [[float(x) for x in row] for row in np.linalg.inv(Im)], [float(x) for x in Im @ w0]
    else:
        Iw, m0w = extended_inertia(Im, w0, ft)
    w = [sum(Iw[i][k] * m[k] for k in range(3)) for i in range(3)]
    Fb = [sum(Q[k][i] * float(F[k]) for k in range(3)) for i in range(3)]  # Q^T F
    cf = [float(x) for x in c]
    tau = [cf[1] * Fb[2] - cf[2] * Fb[1], cf[2] * Fb[0] - cf[0] * Fb[2], cf[0] * Fb[1] - cf[1] * Fb[0]]
    mdot = [m[1] * w[2] - m[2] * w[1] + tau[0], m[2] * w[0] - m[0] * w[2] + tau[1],
            m[0] * w[1] - m[1] * w[0] + tau[2]]
    W = [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]]
    Qdot = [sum(Q[i][k] * W[k][j] for k in range(3)) for i in range(3) for j in range(3)]
    y0 = np.array(m0w + [ft(float(v)) for v in Q0.ravel()])
    tgrid = np.array([ft(float(v)) for v in np.concatenate([[0.0], grid])])
    tol = heyoka_tol(hy, ft, rtol)
    ta = hy.taylor_adaptive(list(zip(xs, mdot + Qdot, strict=True)), y0, tol=tol, fp_type=ft)
    res = ta.propagate_grid(tgrid)
    states = np.asarray(res[-1], dtype=float)[1:]
    return states[:, :3], states[:, 3:].reshape(-1, 3, 3)
