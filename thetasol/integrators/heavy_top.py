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
    heyoka's Taylor integrator (optional extra ``thetasol[bench]``); ``dtype="ldbl"`` (80-bit)
    or ``"f128"`` gives an extended-precision reference.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.so3 import cross, hat, polar_orthonormalize
from thetasol.core.threads import single_blas_thread
from thetasol.integrators._common import both_ways, extended_inertia, heyoka_and_type, solve_ivp_mQ
from thetasol.mechanics.heavy_top import heavy_top_data

__all__ = ["integrate_heavy_top"]


@single_blas_thread
def integrate_heavy_top(I: ArrayLike, center: ArrayLike, Q0: ArrayLike, omega0: ArrayLike, t: ArrayLike, *,
                        mass: float = 1.0, gravity: ArrayLike = (0.0, 0.0, -9.81),
                        rtol: float = 1e-12, atol: float | None = None, method: str = "DOP853",
                        dtype: str = "dbl") -> tuple[np.ndarray, np.ndarray]:
    """Integrate the heavy top (Section 5) numerically.

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
    t : array_like
        Output times (any shape, any order, negative allowed); integration starts at 0.
    mass : float
        Mass of the body.
    gravity : array_like, shape (3,)
        Gravity acceleration in space; the potential is ``V = -mass gravity . (Q center)``.
    rtol, atol : float
        Tolerances (``atol`` defaults to ``1e-3 rtol``; heyoka uses ``rtol`` only).
    method : {"DOP853", "RK45", ..., "heyoka"}
    dtype : {"dbl", "ldbl", "f128"}
        Floating type for ``"heyoka"``: ``"ldbl"`` is 80-bit extended precision.

    Returns
    -------
    omega : ndarray, shape ``t.shape + (3,)``
    Q : ndarray, shape ``t.shape + (3, 3)``

    Notes
    -----
    DOP853's error against 80-bit heyoka grows with t and the spin, and its cost with the spin:
    on fast tops (Simo-Wong's, Bruls-Cardona's) heyoka is both more accurate and much cheaper
    (tests/test_heavy_top.py; benchmarks/bench_heavy_top.py measures both).
    """
    Im, c, Q0m, w0, mass, g = heavy_top_data(I, center, Q0, omega0, mass, gravity)
    tt = V.times(t, "t")
    if not (0 < rtol < 1):
        raise ValueError(f"rtol must be in (0, 1), got {rtol}")
    atol = 1e-3 * rtol if atol is None else float(atol)
    F = mass * g  # the weight, space frame
    m0 = Im @ w0
    def run(grid):
        if method == "heyoka":
            return _heyoka(Im, c, F, Q0m, w0, grid, rtol, dtype)
        return _solve_ivp(Im, c, F, Q0m, m0, grid, rtol, atol, method)

    m_out, Q_out, inv = both_ways(tt, m0, Q0m, run)
    Q_out = polar_orthonormalize(Q_out)
    omega = np.linalg.solve(Im, m_out[..., None])[..., 0]
    return omega[inv].reshape(tt.shape + (3,)), Q_out[inv].reshape(tt.shape + (3, 3))


def _solve_ivp(Im, c, F, Q0, m0, grid, rtol, atol, method):
    I_inv = np.linalg.inv(Im)

    def rhs(_t, y):
        m, Q = y[:3], y[3:].reshape(3, 3)
        w = I_inv @ m
        mdot = cross(m, w) + cross(c, Q.T @ F)
        return np.concatenate([mdot, (Q @ hat(w)).ravel()])

    return solve_ivp_mQ(rhs, m0, Q0, grid, rtol, atol, method)


def _heyoka(Im, c, F, Q0, w0, grid, rtol, dtype):
    hy, ft = heyoka_and_type(dtype)
    names = [f"m{i}" for i in range(3)] + [f"q{i}{j}" for i in range(3) for j in range(3)]
    xs = hy.make_vars(*names)
    m = xs[:3]
    Q = [xs[3 + 3 * i: 6 + 3 * i] for i in range(3)]
    if dtype == "dbl":
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
    tol = hy.real128(str(rtol)) if dtype == "f128" else ft(rtol)
    ta = hy.taylor_adaptive(list(zip(xs, mdot + Qdot, strict=True)), y0, tol=tol, fp_type=ft)
    res = ta.propagate_grid(tgrid)
    states = np.asarray(res[-1], dtype=float)[1:]
    return states[:, :3], states[:, 3:].reshape(-1, 3, 3)
