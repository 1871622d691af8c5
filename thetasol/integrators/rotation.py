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
    heyoka's Taylor integrator (optional extra ``thetasol[bench]``); ``dtype="f128"`` or
    ``"ldbl"`` gives a quadruple/extended-precision reference.

:class:`NumericalRotation` wraps it in the :class:`~thetasol.protocol.RotationSolution`
protocol, for bodies whose rotation has no closed form.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.attitude import principal_frame
from thetasol.core.so3 import polar_orthonormalize
from thetasol.core.threads import single_blas_thread
from thetasol.integrators._common import both_ways, extended_inertia, heyoka_and_type, solve_ivp_mQ
from thetasol.mechanics.equations import inertia_from_moments, invariants, rotation_rhs
from thetasol.protocol import RotationSolution

__all__ = ["integrate_rotation", "NumericalRotation", "numerical_rotation", "rotation_expressions"]


def _prepare(J, a, Q0, omega0, t) -> tuple[np.ndarray, ...]:
    Jm = V.second_moments(J, "J")
    am = V.symmetric_matrix(a, "a")
    Q0 = V.rotation_matrix(Q0, "Q0")
    w0 = V.vector3(omega0, "omega0")
    tt = V.times(t, "t")
    return Jm, am, Q0, w0, tt


@single_blas_thread
def integrate_rotation(J: ArrayLike, a: ArrayLike, Q0: ArrayLike, omega0: ArrayLike, t: ArrayLike, rtol: float = 1e-12, atol: float | None = None,
                       method: str = "DOP853", step: float | None = None,
                       dtype: str = "dbl") -> tuple[np.ndarray, np.ndarray]:
    """Integrate the rotation of a rigid body in the potential ``1/2 x^T a x`` numerically.

    Parameters
    ----------
    J : array_like, shape (3,) or (3, 3)
        Second moments ``sum m r r^T`` of the body in its body frame (principal values or
        a symmetric tensor).  Inertia is ``I = tr(J) 1 - J``.
    a : array_like, shape (3, 3)
        Symmetric potential matrix, ``phi(x) = 1/2 x^T a x`` (the linear part of (2.4)
        exerts no torque about the mass centre).
    Q0 : array_like, shape (3, 3)
        Initial attitude, body to space (``x = Q r``); orthogonal to 1e-10.
    omega0 : array_like, shape (3,)
        Initial body-frame angular velocity (``Qdot = Q hat(omega)``).
    t : array_like
        Output times (any shape, any order, negative allowed); integration starts at 0.
    rtol, atol : float
        Tolerances for the adaptive methods (``atol`` defaults to ``1e-3 rtol``).  For the
        splitting method ``rtol`` sets the step: ``h = rtol**(1/6) / (2 (|omega0| + sqrt(|a|)))``.
    method : {"DOP853", "RK45", ..., "splitting", "heyoka"}
    step : float, optional
        Fixed step for ``"splitting"`` (overrides the ``rtol`` rule).
    dtype : {"dbl", "ldbl", "f128"}
        Floating type for ``"heyoka"``.  With ``"ldbl"`` and ``"f128"`` the inverse inertia and
        ``m0 = I omega0`` are those of the float64 ``J`` and ``omega0`` rounded once to that type
        (not the float64 inverse, another body one ulp away: near an unstable relative equilibrium
        that body's trajectory parts from the data's, tests/test_equations.py::
        test_extended_precision_reference_next_to_an_unstable_equilibrium_matches_the_closed_form).

    Returns
    -------
    omega : ndarray, shape ``t.shape + (3,)``
    Q : ndarray, shape ``t.shape + (3, 3)``

    Notes
    -----
    Implements the Euler equations (4.8) in the vector form ``mdot = m x omega + tau``,
    ``tau = vee([J, Q^T a Q])`` (docs/conventions.md).  Its error grows with the horizon;
    tests/test_equations.py checks DOP853 against heyoka in 80-bit precision on generic data.
    """
    Jm, am, Q0, w0, tt = _prepare(J, a, Q0, omega0, t)
    if not (0 < rtol < 1):
        raise ValueError(f"rtol must be in (0, 1), got {rtol}")
    atol = 1e-3 * rtol if atol is None else float(atol)
    Im = inertia_from_moments(Jm)
    I_inv = np.linalg.inv(Im)
    m0 = Im @ w0
    # Integrate once over the distinct times, forward for t > 0 and backward for t < 0.
    def run(grid):
        if method == "splitting":
            return _splitting(Jm, am, Q0, m0, grid, rtol, step, w0)
        if method == "heyoka":
            return _heyoka(Jm, I_inv, am, Q0, m0, grid, rtol, dtype, w0)
        return _solve_ivp(Jm, I_inv, am, Q0, m0, grid, rtol, atol, method)

    m_out, Q_out, inv = both_ways(tt, m0, Q0, run)
    Q_out = polar_orthonormalize(Q_out)
    omega = np.linalg.solve(Im, m_out[..., None])[..., 0]
    return omega[inv].reshape(tt.shape + (3,)), Q_out[inv].reshape(tt.shape + (3, 3))


@dataclass(frozen=True, eq=False)
class NumericalRotation(RotationSolution):
    """:func:`integrate_rotation` behind the :class:`~thetasol.protocol.RotationSolution` protocol.

    ``sol(t)`` integrates on demand, once per call, from ``t = 0`` to every requested time (any
    shape, any order, negative allowed): no chunking, so a call costs one integration over
    ``[min(t, 0), max(t, 0)]`` and nothing is cached between calls.  Build it with
    :func:`numerical_rotation`.

    Attributes
    ----------
    rtol : float
        Relative tolerance passed to :func:`integrate_rotation`.
    integrator : str
        Its ``method`` (``"DOP853"``, ``"splitting"``, ``"heyoka"``, ...).
    """

    rtol: float = 1e-12
    integrator: str = "DOP853"

    _AT_ONCE = True  # one integration over all requested times

    def _evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return integrate_rotation(self.J, self.a, self.Q0, self.omega0, t, rtol=self.rtol, method=self.integrator)


def numerical_rotation(J: ArrayLike, a: ArrayLike, Q0: ArrayLike, omega0: ArrayLike, rtol: float = 1e-12,
                       method: str = "DOP853") -> NumericalRotation:
    """The rotation of one body in ``1/2 x^T a x`` as a solution evaluated by :func:`integrate_rotation`.

    Parameters
    ----------
    J, a, Q0, omega0
        As for :func:`integrate_rotation` (validated here).
    rtol : float
        Relative tolerance of the integration.
    method : str
        Integration method of :func:`integrate_rotation`.

    Returns
    -------
    NumericalRotation
        ``method`` is ``"numerical/<method>"``; ``invariants`` the first integrals at ``t = 0``
        (``energy``, ``I2``, ``I3`` (4.13) and the spectral-curve coefficients ``curve`` (4.12));
        ``diagnostics`` the integrator and its tolerance.
    """
    Jm = V.second_moments(J, "J")
    am = V.symmetric_matrix(a, "a")
    Qm = V.rotation_matrix(Q0, "Q0")
    wm = V.vector3(omega0, "omega0")
    if not (0 < rtol < 1):
        raise ValueError(f"rtol must be in (0, 1), got {rtol}")
    inv = invariants(Jm, am, Qm, wm)
    first = {"energy": float(inv["energy"]), "I2": float(inv["I2"]), "I3": float(inv["I3"]), "curve": inv["curve"]}
    # Q0 is kept as given (checked above): integrate_rotation projects it onto SO(3) itself, and a
    # second projection could move its last bits.
    Qg = np.array(Q0, dtype=float)
    return NumericalRotation(J=Jm, a=am, Q0=Qg, omega0=wm, method=f"numerical/{method}", invariants=first,
                             diagnostics={"integrator": "integrate_rotation", "method": method, "rtol": rtol},
                             rtol=float(rtol), integrator=method)


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
    Ip = Jp.sum() - Jp
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


def _heyoka(Jm, I_inv, am, Q0, m0, tgrid, rtol, dtype, w0):
    hy, ft = heyoka_and_type(dtype)
    names = [f"m{i}" for i in range(3)] + [f"q{i}{j}" for i in range(3) for j in range(3)]
    xs = hy.make_vars(*names)
    m = xs[:3]
    Q = [xs[3 + 3 * i: 6 + 3 * i] for i in range(3)]
    if dtype == "dbl":
        Iw, m0w = [[float(x) for x in row] for row in I_inv], [float(x) for x in m0]
    else:
        Iw, m0w = extended_inertia(Jm, w0, ft, from_moments=True)
    A = [[float(am[i, k]) for k in range(3)] for i in range(3)]
    J = [[float(Jm[i, k]) for k in range(3)] for i in range(3)]
    odes = list(zip(xs, rotation_expressions(m, Q, Iw, J, A), strict=True))
    # Q0 and the times are the float64 values themselves (real128(str(x)) would be another number)
    y0 = np.array(m0w + [ft(float(v)) for v in Q0.ravel()])
    grid = np.array([ft(float(v)) for v in np.concatenate([[0.0], tgrid])])
    tol = hy.real128(str(rtol)) if dtype == "f128" else ft(rtol)
    ta = hy.taylor_adaptive(odes, y0, tol=tol, fp_type=ft)
    res = ta.propagate_grid(grid)
    states = np.asarray(res[-1], dtype=float)[1:]
    return states[:, :3], states[:, 3:].reshape(-1, 3, 3)
