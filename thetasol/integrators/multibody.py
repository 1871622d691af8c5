"""The unsplit reference: a tree of rigid bodies integrated as one constrained multibody system.

Nothing here uses the split of Theorem 2 (no effective bodies, no system mass centre in the
equations): every body has its own Newton-Euler equations in maximal coordinates,

    m_i xddot_i   = -m_i (a x_i + b / 2)                  + sum of joint forces,
    I_i omegadot_i = -omega_i x I_i omega_i + Q_i^T tau_i  + sum of joint torques,
    Qdot_i        = Q_i hat(omega_i),

with ``x_i`` the body's own mass centre and ``tau_i = vee(S_i a - a S_i)`` the space-frame
torque of the quadratic potential on the second moments ``S_i = Q_i J_i Q_i^T`` (the linear
part of ``phi`` exerts no torque about the mass centre).  A joint between parent ``P`` and
child ``C`` is the holonomic constraint

    g = x_P + Q_P rho_P - x_C - Q_C rho_C = 0,      rho = (joint point) - (mass centre),

whose force ``lambda`` (on ``P``; ``-lambda`` on ``C``) is solved each step from the KKT
system in Schur-complement form ``(G M^-1 G^T) lambda = -gamma - G M^-1 f - 2 alpha gdot -
alpha^2 g`` (Baumgarte stabilization, critically damped at rate ``alpha``).  ``Q`` is kept
orthogonal by the term ``Q (1 - Q^T Q) kappa / 2`` added to ``Qdot`` (zero on SO(3)).

With ``constraint=Sphere(R)`` (Section 6, Theorem 3) the system mass centre
``q = sum m_i x_i / M`` is held on ``|q| = R`` by one more holonomic constraint,
``g = (|q|^2 - R^2) / (2 R) = 0`` (a length, like the joint gaps).  Its gradient in ``x_i`` is
``(m_i / M) q / R``, so its multiplier ``mu`` pushes every body with the force
``mu (m_i / M) q / R``: in proportion to its mass, the same acceleration ``mu q / (M R)`` for all,
and no torque.  The row joins the joint rows of the same KKT system with
``gdot = q.qdot / R`` and ``gamma = |qdot|^2 / R`` (``gddot = G acc + gamma``).  This models the
rod of the paper without choosing a material attachment point (the mass centre is none).

With ``constraint=Pivot(body, point, position)`` (Section 5) the point ``point`` of ``body`` is
held at ``position`` in space by a spherical joint to the ground: three more rows
``g = x_B + Q_B rho - position = 0``, ``rho = point - c_B``, the joint rows with the ground as the
other body (``G = [1, -Q_B hat(rho)]``, ``gamma = Q_B (omega x (omega x rho))``).  Nothing else
changes: no effective body, no pivot inertia.  The initial state is the joints' one moved so that
the pivot sits at ``position`` with zero velocity (``q0`` and ``v0`` follow; given ones must agree).

The ODE is integrated by :func:`scipy.integrate.solve_ivp` (DOP853 by default).  Dense
maximal coordinates are slow compared with the split (it is a reference, not the product),
but they are transparent, and the code is short enough to audit.  It also serves users as
a check that a configuration really splits, or to measure how far a non-central one
departs from the split.
"""
from __future__ import annotations

import time
from collections.abc import Callable, Mapping

import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import solve_ivp

from thetasol.core import validate as V
from thetasol.core.so3 import cross, hat, polar_orthonormalize, vee
from thetasol.core.threads import single_blas_thread
from thetasol.mechanics.configuration import Configuration, initial_attitudes
from thetasol.mechanics.constraints import Pivot, Sphere
from thetasol.mechanics.trajectories import Trajectories

__all__ = ["initial_state", "pivot_initial_state", "integrate_multibody"]


def initial_state(config: Configuration, q0: ArrayLike, v0: ArrayLike, Q0: Mapping[str, ArrayLike],
                  omega0: Mapping[str, ArrayLike]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Maximal coordinates (mass centres and their velocities) of every body, joints satisfied.

    Parameters
    ----------
    config : Configuration
        Any tree (central or not).
    q0, v0 : array_like (3,)
        Position and velocity of the SYSTEM mass centre.
    Q0 : dict name -> (3, 3)
        Attitudes (body to space), orthogonal to 1e-10.
    omega0 : dict name -> (3,)
        Body-frame angular velocities.

    Returns
    -------
    x, v : ndarray (N, 3)
        Mass centre and velocity of each body in ``config.order``.
    Q, w : ndarray (N, 3, 3), (N, 3)
        Validated attitudes and angular velocities in the same order.
    """
    q0 = V.vector3(q0, "q0")
    v0 = V.vector3(v0, "v0")
    Q0, w0 = initial_attitudes(config, Q0, omega0)
    idx = {n: i for i, n in enumerate(config.order)}
    N = len(config.order)
    O = np.zeros((N, 3))  # frame origins, root origin at 0 for now
    Od = np.zeros((N, 3))
    for n in config.order[1:]:
        j = config.joints[n]
        p, c = idx[j.parent], idx[n]
        O[c] = O[p] + Q0[p] @ j.parent_point - Q0[c] @ j.child_point
        Od[c] = Od[p] + Q0[p] @ np.cross(w0[p], j.parent_point) - Q0[c] @ np.cross(w0[c], j.child_point)
    centers = np.array([config.bodies[n].center for n in config.order])
    masses = np.array([config.bodies[n].mass for n in config.order])
    x = O + np.einsum("nij,nj->ni", Q0, centers)
    v = Od + np.einsum("nij,nj->ni", Q0, np.cross(w0, centers))
    x += q0 - masses @ x / masses.sum()
    v += v0 - masses @ v / masses.sum()
    return x, v, Q0, w0


def pivot_initial_state(config: Configuration, pivot: Pivot, q0: ArrayLike | None, v0: ArrayLike | None,
                        Q0: Mapping[str, ArrayLike], omega0: Mapping[str, ArrayLike]
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`initial_state` with the pivot at its place and at rest; ``q0``, ``v0`` (if given) checked.

    Raises
    ------
    ValueError
        The pivot's body is not in ``config``, or a given ``q0`` / ``v0`` differs from the one the
        pivot implies by more than 1e-12 of the configuration's size and speed.
    """
    if not isinstance(pivot, Pivot):
        raise ValueError(f"pivot must be a Pivot, got {type(pivot).__name__}")
    if pivot.body not in config.bodies:
        raise ValueError(f"pivot body {pivot.body!r} is not in the configuration; bodies are {config.order}")
    x, v, Q, w = initial_state(config, np.zeros(3), np.zeros(3), Q0, omega0)
    i = config.order.index(pivot.body)
    rho = pivot.point - config.bodies[pivot.body].center
    x += pivot.position - (x[i] + Q[i] @ rho)
    v -= v[i] + Q[i] @ np.cross(w[i], rho)
    m = np.array([config.bodies[n].mass for n in config.order])
    q, qd = m @ x / m.sum(), m @ v / m.sum()
    size = 1.0 + float(np.max(np.abs(x - pivot.position)))
    speed = 1e-300 + float(np.max(np.abs(v)))
    for given, implied, scale, what in ((q0, q, size, "q0"), (v0, qd, speed, "v0")):
        if given is not None and np.max(np.abs(V.vector3(given, what) - implied)) > 1e-12 * scale:
            raise ValueError(f"{what} = {np.asarray(given, float).tolist()} disagrees with the pivot, which puts "
                             f"it at {implied.tolist()}; pass None")
    return x, v, Q, w


class _System:
    """Right-hand side of the maximal-coordinate equations (module docstring)."""

    def __init__(self, config, a, b, alpha, kappa, radius=None, pivot=None, forces=None):
        self.radius = radius  # of the sphere constraint on the system mass centre, or None
        self.forces = forces  # extra applied forces and body-frame torques, or None
        self.names = config.order
        idx = {n: i for i, n in enumerate(self.names)}
        self.pivot = None if pivot is None else (idx[pivot.body], pivot.point - config.bodies[pivot.body].center,
                                                 pivot.position)
        bodies = [config.bodies[n] for n in self.names]
        self.N = N = len(bodies)
        self.m = np.array([b_.mass for b_ in bodies])
        self.J = np.array([b_.J for b_ in bodies])
        self.I = np.array([b_.I for b_ in bodies])
        self.Iinv = np.linalg.inv(self.I)
        self.a, self.b = a, b
        self.alpha, self.kappa = alpha, kappa
        js = [config.joints[n] for n in self.names[1:]]
        self.K = len(js)
        self.P = np.array([idx[j.parent] for j in js], dtype=int)
        self.C = np.array([idx[j.child] for j in js], dtype=int)
        self.rhoP = np.array([j.parent_point - config.bodies[j.parent].center for j in js]).reshape(-1, 3)
        self.rhoC = np.array([j.child_point - config.bodies[j.child].center for j in js]).reshape(-1, 3)
        # Generalized inverse mass as a dense (6N, 6N) block-diagonal matrix.
        Minv = np.zeros((6 * N, 6 * N))
        for i in range(N):
            Minv[6 * i:6 * i + 3, 6 * i:6 * i + 3] = np.eye(3) / self.m[i]
            Minv[6 * i + 3:6 * i + 6, 6 * i + 3:6 * i + 6] = self.Iinv[i]
        self.Minv = Minv
        # Constraint Jacobian G (3K, 6N) as (K, 3, N, 6): the translation blocks +-1 are constant,
        # the rotation blocks are filled per call at (k, :, P[k], 3:) and (k, :, C[k], 3:).
        G0 = np.zeros((self.K, 3, N, 6))
        ks = np.arange(self.K)
        G0[ks, :, self.P, :3] = np.eye(3)
        G0[ks, :, self.C, :3] = -np.eye(3)
        self._G0, self._ks = G0, ks
        self._hatP, self._hatC = hat(self.rhoP), hat(self.rhoC)

    def unpack(self, y):
        """``(x, v, Q, w)`` from the state vector(s) ``y`` of shape ``(..., 18 N)``."""
        N, lead = self.N, y.shape[:-1]
        x = y[..., :3 * N].reshape(lead + (N, 3))
        v = y[..., 3 * N:6 * N].reshape(lead + (N, 3))
        Q = y[..., 6 * N:15 * N].reshape(lead + (N, 3, 3))
        w = y[..., 15 * N:].reshape(lead + (N, 3))
        return x, v, Q, w

    @staticmethod
    def pack(x, v, Q, w):
        return np.concatenate([x.ravel(), v.ravel(), Q.ravel(), w.ravel()])

    def constraint(self, x, v, Q, w):
        """Joint residuals g and gdot, shape (..., K, 3), of the states (..., N, ...) of :meth:`unpack`."""
        P, C = self.P, self.C
        QP, QC, wP, wC = Q[..., P, :, :], Q[..., C, :, :], w[..., P, :], w[..., C, :]
        rP = np.einsum("...kij,kj->...ki", QP, self.rhoP)
        rC = np.einsum("...kij,kj->...ki", QC, self.rhoC)
        g = x[..., P, :] + rP - x[..., C, :] - rC
        gd = (v[..., P, :] + np.einsum("...kij,...kj->...ki", QP, cross(wP, self.rhoP))
              - v[..., C, :] - np.einsum("...kij,...kj->...ki", QC, cross(wC, self.rhoC)))
        return g, gd

    def _joint_rows(self, x, v, Q, w):
        """Jacobian ``G`` (3K, 6N) of the joints and the right-hand side of ``G acc = rhs``."""
        N, K = self.N, self.K
        P, C, ks = self.P, self.C, self._ks
        QP, QC = Q[P], Q[C]
        G4 = self._G0.copy()
        G4[ks, :, P, 3:] = -QP @ self._hatP
        G4[ks, :, C, 3:] = QC @ self._hatC
        G = G4.reshape(3 * K, 6 * N)
        wP, wC = w[P], w[C]
        gamma = (np.einsum("kij,kj->ki", QP, cross(wP, cross(wP, self.rhoP)))
                 - np.einsum("kij,kj->ki", QC, cross(wC, cross(wC, self.rhoC))))
        g, gd = self.constraint(x, v, Q, w)
        return G, -(gamma + 2 * self.alpha * gd + self.alpha ** 2 * g).ravel()

    def _sphere_row(self, x, v):
        """The row (1, 6N) of ``g = (|q|^2 - R^2) / (2R)`` and its right-hand side (module docstring)."""
        R, M = self.radius, self.m.sum()
        q, qd = self.m @ x / M, self.m @ v / M
        G = np.zeros((self.N, 6))
        G[:, :3] = (self.m / (M * R))[:, None] * q
        rq = float(np.linalg.norm(q))
        g = (rq - R) * (rq + R) / (2 * R)
        rhs = -(qd @ qd / R + 2 * self.alpha * (q @ qd) / R + self.alpha ** 2 * g)
        return G.reshape(1, 6 * self.N), np.array([rhs])

    def _pivot_rows(self, x, v, Q, w):
        """The rows (3, 6N) of ``g = x_B + Q_B rho - position`` and their right-hand side (module docstring)."""
        i, rho, pos = self.pivot
        G = np.zeros((3, self.N, 6))
        G[:, i, :3] = np.eye(3)
        G[:, i, 3:] = -Q[i] @ hat(rho)
        wr = np.cross(w[i], rho)
        g = x[i] + Q[i] @ rho - pos
        gd = v[i] + Q[i] @ wr
        gamma = Q[i] @ np.cross(w[i], wr)
        return G.reshape(3, 6 * self.N), -(gamma + 2 * self.alpha * gd + self.alpha ** 2 * g)

    def pivot_residual(self, x, Q):
        """``|x_B + Q_B rho - position|`` of the states (..., N, ...) of :meth:`unpack`."""
        i, rho, pos = self.pivot
        return np.linalg.norm(x[..., i, :] + Q[..., i, :, :] @ rho - pos, axis=-1)

    def __call__(self, _t, y):
        N, K = self.N, self.K
        x, v, Q, w = self.unpack(y)
        a = self.a
        S = Q @ self.J @ np.swapaxes(Q, 1, 2)
        tau_space = vee(S @ a - a @ S)
        Iw = np.einsum("nij,nj->ni", self.I, w)
        f = np.empty((N, 6))
        f[:, :3] = -self.m[:, None] * (x @ a + 0.5 * self.b)
        f[:, 3:] = np.einsum("nji,nj->ni", Q, tau_space) - cross(w, Iw)
        if self.forces is not None:
            f += self.forces(_t, x, v, Q, w)
        f = f.ravel()
        if K or self.radius is not None or self.pivot is not None:
            G, rhs = self._joint_rows(x, v, Q, w)
            extra = [] if self.radius is None else [self._sphere_row(x, v)]
            extra += [] if self.pivot is None else [self._pivot_rows(x, v, Q, w)]
            for Gs, rs in extra:
                G, rhs = np.concatenate([G, Gs]), np.concatenate([rhs, rs])
            MG = self.Minv @ G.T
            acc = self.Minv @ f
            lam = np.linalg.solve(G @ MG, rhs - G @ acc)
            acc = acc + MG @ lam
        else:
            acc = self.Minv @ f
        acc = acc.reshape(N, 6)
        Qt = np.swapaxes(Q, 1, 2)
        Qdot = Q @ hat(w) + 0.5 * self.kappa * Q @ (np.eye(3) - Qt @ Q)
        return self.pack(v, acc[:, :3], Qdot, acc[:, 3:])


@single_blas_thread
def integrate_multibody(config: Configuration, a: ArrayLike, b: ArrayLike, q0: ArrayLike, v0: ArrayLike,
                        Q0: Mapping[str, ArrayLike], omega0: Mapping[str, ArrayLike], t: ArrayLike,
                        rtol: float = 1e-12, atol: float | None = None, method: str = "DOP853",
                        alpha: float | None = None, kappa: float | None = None,
                        constraint: Sphere | Pivot | None = None, forces: Callable | None = None) -> Trajectories:
    """Integrate a tree of rigid bodies on spherical joints in ``phi(x) = 1/2 x^T a x + 1/2 b^T x``.

    Parameters
    ----------
    config : Configuration
        Any tree of bodies (central or not).
    a : array_like (3, 3)
        Symmetric potential matrix.
    b : array_like (3,)
        Linear part of (2.4).
    q0, v0 : array_like (3,)
        Initial system mass centre and its velocity.
    Q0 : dict name -> (3, 3)
        Initial attitudes (identity where missing).
    omega0 : dict name -> (3,)
        Initial body-frame angular velocities (zero where missing).
    t : array_like (T,)
        Output times, increasing, ``t[0] >= 0``; the integration starts at 0.
    rtol, atol : float
        Tolerances of :func:`scipy.integrate.solve_ivp` (``atol`` defaults to ``1e-3 rtol``).
    method : str
        Any explicit solve_ivp method.
    alpha : float, optional
        Baumgarte rate of the joint constraints (default: the system's fastest natural rate,
        ``|omega0|_max + sqrt(|a|)``, at least 1).
    kappa : float, optional
        Rate pulling ``Q`` back to SO(3) (default ``alpha``).
    constraint : Sphere, optional
        Hold the system mass centre on ``|q| = constraint.radius`` (Theorem 3; module
        docstring).  Needs ``b = 0``, ``|q0| = radius`` and ``v0`` tangent
        (:meth:`Sphere.check`, else ``ValueError``).  A :class:`Pivot` holds one point of any body
        fixed in space (Section 5); ``q0`` and ``v0`` then follow from the attitudes and may be
        ``None`` (given ones must agree to 1e-12 relative, else ``ValueError``).
    forces : callable, optional
        Further applied loads ``forces(t, x, v, Q, omega) -> (N, 6)``: per body (``config.order``)
        the force on its mass centre (space frame) and the torque about it (body frame), from
        the states ``x, v (N, 3)``, ``Q (N, 3, 3)``, ``omega (N, 3)``.  Used for the exact
        ``1/r`` field and control torques (:mod:`thetasol.integrators.multibody_gravity`).

    Returns
    -------
    Trajectories
        ``info`` holds ``"constraint_residual"`` (max joint gap), ``"orthogonality"``
        (max ``|Q^T Q - 1|`` before the output projection), ``"nfev"``, ``"seconds"``; with a
        sphere also ``"sphere_residual"`` (max ``| |q| - radius |``), with a pivot
        ``"pivot_residual"`` (max distance of the pivot from its place).

    Notes
    -----
    Equations derived independently of the split (module docstring).  Cost is dominated
    by Python overhead per right-hand side (dense ``(6N, 6N)`` algebra; docs/bench_mechanics.md,
    section 2, written by benchmarks/bench_mechanics.py).
    """
    if not isinstance(config, Configuration):
        raise ValueError(f"config must be a Configuration, got {type(config).__name__}")
    a = V.symmetric_matrix(a, "a")
    b = V.vector3(b, "b")
    tt = V.times(t, "t")
    if tt.ndim != 1 or tt.size == 0 or tt[0] < 0 or np.any(np.diff(tt) < 0):
        raise ValueError("t must be a non-empty increasing 1-d array of times >= 0")
    if not (0 < rtol < 1):
        raise ValueError(f"rtol must be in (0, 1), got {rtol}")
    atol = 1e-3 * rtol if atol is None else float(atol)
    if isinstance(constraint, Pivot):
        x, v, Q, w = pivot_initial_state(config, constraint, q0, v0, Q0, omega0)
    else:
        if constraint is not None:
            if not isinstance(constraint, Sphere):
                raise ValueError(f"constraint must be a Sphere, a Pivot or None, got {type(constraint).__name__}")
            b, q0, v0 = constraint.check(b, q0, v0)
        x, v, Q, w = initial_state(config, q0, v0, Q0, omega0)
    if alpha is None:
        alpha = max(1.0, float(np.max(np.linalg.norm(w, axis=1))) + float(np.sqrt(np.max(np.abs(np.linalg.eigvalsh(a))))))
    kappa = alpha if kappa is None else float(kappa)
    sys = _System(config, a, b, float(alpha), kappa, constraint.radius if isinstance(constraint, Sphere) else None,
                  constraint if isinstance(constraint, Pivot) else None, forces)
    y0 = sys.pack(x, v, Q, w)
    start = time.perf_counter()
    if tt[-1] > 0:
        sol = solve_ivp(sys, (0.0, float(tt[-1])), y0, method=method, t_eval=tt, rtol=rtol, atol=atol)
        if not sol.success:
            raise RuntimeError(f"multibody integration failed: {sol.message}")
        Y = sol.y.T
        nfev = sol.nfev
    else:
        Y = np.tile(y0, (tt.size, 1))
        nfev = 0
    seconds = time.perf_counter() - start
    states = sys.unpack(Y)  # (T, N, ...)
    resid = float(np.max(np.abs(sys.constraint(*states)[0]), initial=0.0))
    X, Vel, Qs, W = (np.moveaxis(z, 0, 1) for z in states)  # body axis first: (N, T, ...)
    ortho = float(np.max(np.abs(np.swapaxes(Qs, -1, -2) @ Qs - np.eye(3))))
    Qs = polar_orthonormalize(Qs)
    mc = np.einsum("n,nti->ti", sys.m, X) / sys.m.sum()
    mcv = np.einsum("n,nti->ti", sys.m, Vel) / sys.m.sum()
    info = {"model": "multibody (maximal coordinates, KKT, Baumgarte)", "method": method, "rtol": rtol,
            "atol": atol, "alpha": float(alpha), "kappa": kappa, "nfev": int(nfev), "seconds": seconds,
            "constraint_residual": resid, "orthogonality": ortho}
    if isinstance(constraint, Sphere):
        info["sphere_residual"] = float(np.max(np.abs(constraint.residual(mc))))
    if isinstance(constraint, Pivot):
        info["pivot_residual"] = float(np.max(sys.pivot_residual(states[0], states[2])))
    return Trajectories(t=tt.copy(), names=tuple(sys.names), position=X, velocity=Vel, attitude=Qs, omega=W,
                        mass_center=mc, mass_center_velocity=mcv, info=info)
