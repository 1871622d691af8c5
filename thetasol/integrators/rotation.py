"""The numerical reference: rotation of one rigid body in a quadratic potential.

``integrate_rotation`` integrates the Euler equations (4.8) together with the attitude
equation ``Qdot = Q hat(omega)``.  Three methods:

``"DOP853"`` (default; any explicit :func:`scipy.integrate.solve_ivp` method name works)
    adaptive Runge-Kutta on ``(m, Q)``; ``Q`` is projected onto SO(3) at output only.
``"splitting"``
    a symplectic Lie-Poisson splitting (Touma & Wisdom 1994; Dullweber, Leimkuhler &
    McLachlan 1997): exact rotations about the principal axes alternate with exact kicks
    by the torque, composed to order 6 by Yoshida's triple jump.  ``Q`` stays in SO(3) to
    round-off and the energy error stays bounded over long times.
``"heyoka"``
    heyoka's Taylor integrator (optional extra ``thetasol[bench]``); ``fp_type=heyoka.real128`` or
    ``numpy.longdouble`` gives a quadruple/extended-precision reference.

The result, a :class:`NumericalRotation`, follows the :class:`~thetasol.protocol.RotationSolution`
protocol: the reference for bodies whose rotation has no closed form, and the check of those that have one.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.attitude import principal_frame
from thetasol.core.inertia import inertia
from thetasol.core.so3 import polar_orthonormalize
from thetasol.integrators._common import (
    SCIPY_METHODS,
    Settings,
    body_inertia,
    both_ways,
    extended_inertia,
    heyoka_and_type,
    heyoka_tol,
    settings,
    solve_ivp_mQ,
)
from thetasol.mechanics.equations import invariants_from_moments, rotation_rhs
from thetasol.protocol import RotationSolution

__all__ = ["integrate_rotation", "NumericalRotation", "rotation_expressions"]


def integrate_rotation(I: ArrayLike, a: ArrayLike, Q0: ArrayLike, omega0: ArrayLike, *, method: str = "DOP853",
                       rtol: float = 1e-12, atol: float | None = None, fp_type: Any = float,
                       step: float | None = None) -> NumericalRotation:
    """The rotation of a rigid body in the potential ``1/2 x^T a x``, integrated numerically.

    Parameters
    ----------
    I : array_like, shape (3,) or (3, 3)
        Inertia tensor of the body about its mass centre, body frame (principal values or a symmetric
        tensor); the paper's second moments ``J`` convert with :func:`thetasol.inertia`.
    a : array_like, shape (3, 3)
        Symmetric potential matrix, ``phi(x) = 1/2 x^T a x`` (the linear part of (2.4)
        exerts no torque about the mass centre).
    Q0 : array_like, shape (3, 3)
        Initial attitude, body to space (``x = Q r``); orthogonal to 1e-10.
    omega0 : array_like, shape (3,)
        Initial body-frame angular velocity (``Qdot = Q hat(omega)``).
    method : {"DOP853", "RK45", ..., "splitting", "heyoka"}
        A :func:`scipy.integrate.solve_ivp` method, the symplectic splitting or heyoka's Taylor integrator.
    rtol : float
        Relative tolerance of the adaptive methods and of heyoka.  For the splitting it sets the
        step: ``h = rtol**(1/6) / (2 (|omega0| + sqrt(|a|)))``.
    atol : float, optional
        Absolute tolerance of the solve_ivp methods (default ``1e-3 rtol``); refused with the others.
    fp_type : {float, numpy.longdouble, heyoka.real128}
        Floating type of ``"heyoka"`` (refused with the other methods).  In extended precision the
        inverse inertia and ``m0 = I omega0`` are those of the float64 ``I`` and ``omega0`` rounded
        once to that type (not the float64 inverse, another body one ulp away, which near an unstable
        relative equilibrium moves the trajectory far more than the data's conditioning).
    step : float, optional
        Fixed step of ``"splitting"`` (overrides the ``rtol`` rule; refused with the other methods).

    Returns
    -------
    NumericalRotation
        ``sol(t) -> (omega, Q)`` with shapes ``t.shape + (3,)`` and ``t.shape + (3, 3)`` for any
        shape of ``t`` (any order, negative allowed), one integration from ``t = 0`` per call;
        ``model`` is ``"rotation"``, ``method`` ``"numerical/<method>"``; ``invariants`` the first
        integrals at ``t = 0`` (``energy``, ``I2``, ``I3`` (4.13) and the spectral-curve coefficients
        ``curve`` (4.12)); ``diagnostics`` the integrator settings and ``error_estimate`` (its ``rtol``).

    Notes
    -----
    Implements the Euler equations (4.8) in the vector form ``mdot = m x omega + tau``,
    ``tau = vee([J, Q^T a Q])`` with ``J = tr(I)/2 1 - I`` (docs/conventions.md).  Its error grows with
    the horizon; tests/test_equations.py checks DOP853 against heyoka in 80-bit precision on generic data.
    """
    Im, Jm = body_inertia(I)
    am = V.symmetric_matrix(a, "a")
    Qm = V.rotation_matrix(Q0, "Q0")
    wm = V.vector3(omega0, "omega0")
    opts = settings(method, rtol, atol, fp_type, step, methods=(*SCIPY_METHODS, "splitting", "heyoka"))
    inv = invariants_from_moments(Jm, am, Qm, wm)
    first = {"energy": float(inv["energy"]), "I2": float(inv["I2"]), "I3": float(inv["I3"]), "curve": inv["curve"]}
    return NumericalRotation(J=Jm, a=am, Q0=Qm, omega0=wm, method=f"numerical/{opts.method}", invariants=first,
                             diagnostics=opts.diagnostics(), I_given=Im, settings=opts)


@dataclass(frozen=True, eq=False)
class NumericalRotation(RotationSolution):
    """The numerical rotation of :func:`integrate_rotation` behind the
    :class:`~thetasol.protocol.RotationSolution` protocol.

    ``sol(t)`` integrates on demand, once per call, from ``t = 0`` to every requested time (any
    shape, any order, negative allowed): no chunking, so a call costs one integration over
    ``[min(t, 0), max(t, 0)]`` and nothing is cached between calls.

    Attributes
    ----------
    I : ndarray, shape (3, 3)
        The inertia tensor as given (``J`` holds its second moments).
    settings : Settings
        The integrator and its tolerances.
    """

    settings: Settings = Settings()

    model: ClassVar[str] = "rotation"
    _AT_ONCE = True  # one integration over all requested times

    def _evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        s, Im, Jm, am, Q0, w0 = self.settings, self.I, self.J, self.a, self.Q0, self.omega0
        atol = 1e-3 * s.rtol if s.atol is None else s.atol
        I_inv = np.linalg.inv(Im)
        m0 = Im @ w0

        def run(grid):
            if s.method == "splitting":
                return _splitting(Jm, am, Q0, m0, grid, s.rtol, s.step, w0)
            if s.method == "heyoka":
                return _heyoka(Jm, Im, I_inv, am, Q0, m0, grid, s.rtol, s.fp_type, w0)
            return _solve_ivp(Jm, I_inv, am, Q0, m0, grid, s.rtol, atol, s.method)

        m_out, Q_out, inv = both_ways(t, m0, Q0, run)
        Q_out = polar_orthonormalize(Q_out)
        omega = np.linalg.solve(Im, m_out[..., None])[..., 0]
        return omega[inv], Q_out[inv]


def _solve_ivp(Jm, I_inv, am, Q0, m0, tgrid, rtol, atol, method):
    def rhs(_t, y):
        mdot, Qdot = rotation_rhs(Jm, I_inv, am, y[:3], y[3:].reshape(3, 3))
        return np.concatenate([mdot, Qdot.ravel()])

    return solve_ivp_mQ(rhs, m0, Q0, tgrid, rtol, atol, method)


# -- symplectic Lie-Poisson splitting -------------------------------------------------------

def _yoshida_weights(order: int) -> list[float]:
    """Weights of the symmetric Strang step in Yoshida's triple-jump composition."""
    w = [1.0]
    for p in range(2, order, 2):
        x1 = 1.0 / (2.0 - 2.0 ** (1.0 / (p + 1)))
        x0 = 1.0 - 2.0 * x1
        w = [x1 * c for c in w] + [x0 * c for c in w] + [x1 * c for c in w]
    return w


def _splitting(Jm, am, Q0, m0, tgrid, rtol, step, w0):
    # Work in the principal frame: J = P diag(Jp) P^T, Q' = Q P, m' = P^T m.
    Jp, P = principal_frame(Jm, ascending=True)  # right-handed: the flows use cross products
    Ip = inertia(Jp)
    Qp = Q0 @ P
    mp = P.T @ m0
    direction = 1.0 if tgrid[-1] >= 0 else -1.0
    if step is None:
        scale = np.linalg.norm(w0) + math.sqrt(np.max(np.abs(np.linalg.eigvalsh(am))))
        step = 0.5 * rtol ** (1.0 / 6.0) / max(scale, 1e-300)
    weights = _yoshida_weights(6)
    state = _SplitState(Jp, Ip, am, Qp, mp)
    m_out = np.empty((tgrid.size, 3))
    Q_out = np.empty((tgrid.size, 3, 3))
    t = 0.0
    for k, tk in enumerate(tgrid):
        span = abs(tk - t)
        n = int(math.ceil(span / step)) if span > 0 else 0
        if n:
            h = direction * span / n
            for _ in range(n):
                for w in weights:
                    state.strang(w * h)
        t = tk
        m_out[k] = P @ np.array(state.m)
        Q_out[k] = np.array(state.Q) @ P.T
    return m_out, Q_out


class _SplitState:
    """Scalar-arithmetic state for the splitting (Python floats: small ops, no array overhead)."""

    def __init__(self, Jp, Ip, a, Q, m):
        self.J = [float(x) for x in Jp]
        self.I = [float(x) for x in Ip]
        self.a = [[float(x) for x in row] for row in a]
        self.Q = [[float(x) for x in row] for row in Q]
        self.m = [float(x) for x in m]

    def kick(self, h):
        Q, a, J = self.Q, self.a, self.J
        aQ = [[sum(a[i][k] * Q[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
        ap = [[sum(Q[k][i] * aQ[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
        m = self.m
        m[0] += h * (J[2] - J[1]) * ap[2][1]
        m[1] += h * (J[0] - J[2]) * ap[0][2]
        m[2] += h * (J[1] - J[0]) * ap[1][0]

    def rotate(self, axis, h):
        # Exact flow of m_axis^2 / (2 I_axis): rotation about the body axis by th = h m_axis / I_axis.
        i, j = (axis + 1) % 3, (axis + 2) % 3
        m = self.m
        th = h * m[axis] / self.I[axis]
        c, s = math.cos(th), math.sin(th)
        mi, mj = m[i], m[j]
        # mdot = m x omega_axis e_axis: (m_i, m_j) rotate by -th in the (i, j) plane.
        m[i] = c * mi + s * mj
        m[j] = -s * mi + c * mj
        for row in self.Q:
            qi, qj = row[i], row[j]
            row[i] = c * qi + s * qj
            row[j] = -s * qi + c * qj

    def strang(self, h):
        half = 0.5 * h
        self.kick(half)
        self.rotate(0, half)
        self.rotate(1, half)
        self.rotate(2, h)
        self.rotate(1, half)
        self.rotate(0, half)
        self.kick(half)


# -- heyoka ----------------------------------------------------------------------------------

def rotation_expressions(m: list, Q: list, Iinv: list, J: list, A: list) -> list:
    """The right-hand side of (4.8) with ``Qdot = Q hat(omega)`` as expressions: ``mdot`` (3) then ``Qdot`` (9,
    row-major), for ``m`` (3) and ``Q`` (3 x 3 nested lists) of symbolic variables and ``I^-1``, ``J``, ``a``
    (3 x 3 nested lists of numbers or parameters).  The torque is ``vee([J, Q^T a Q])``.

    Written once for every heyoka model of the rotation (this module's reference and the benchmarks' compiled
    parametric integrators)."""
    w = [sum(Iinv[i][k] * m[k] for k in range(3)) for i in range(3)]
    aQ = [[sum(A[i][k] * Q[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    ap = [[sum(Q[k][i] * aQ[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    JA = [[sum(J[i][k] * ap[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    comm = [[JA[i][j] - JA[j][i] for j in range(3)] for i in range(3)]  # [J, ap] (ap symmetric)
    tau = [comm[2][1], comm[0][2], comm[1][0]]
    mdot = [m[1] * w[2] - m[2] * w[1] + tau[0], m[2] * w[0] - m[0] * w[2] + tau[1],
            m[0] * w[1] - m[1] * w[0] + tau[2]]
    W = [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]]
    return mdot + [sum(Q[i][k] * W[k][j] for k in range(3)) for i in range(3) for j in range(3)]


def _heyoka(Jm, Im, I_inv, am, Q0, m0, tgrid, rtol, fp_type, w0):
    hy, ft = heyoka_and_type(fp_type)
    names = [f"m{i}" for i in range(3)] + [f"q{i}{j}" for i in range(3) for j in range(3)]
    xs = hy.make_vars(*names)
    m = xs[:3]
    Q = [xs[3 + 3 * i: 6 + 3 * i] for i in range(3)]
    if ft is float:
        Iw, m0w = [[float(x) for x in row] for row in I_inv], [float(x) for x in m0]
    else:
        Iw, m0w = extended_inertia(Im, w0, ft)
    A = [[float(am[i, k]) for k in range(3)] for i in range(3)]
    J = [[float(Jm[i, k]) for k in range(3)] for i in range(3)]
    odes = list(zip(xs, rotation_expressions(m, Q, Iw, J, A), strict=True))
    # Q0 and the times are the float64 values themselves (real128(str(x)) would be another number)
    y0 = np.array(m0w + [ft(float(v)) for v in Q0.ravel()])
    grid = np.array([ft(float(v)) for v in np.concatenate([[0.0], tgrid])])
    tol = heyoka_tol(hy, ft, rtol)
    ta = hy.taylor_adaptive(odes, y0, tol=tol, fp_type=ft)
    res = ta.propagate_grid(grid)
    states = np.asarray(res[-1], dtype=float)[1:]
    return states[:, :3], states[:, 3:].reshape(-1, 3, 3)
