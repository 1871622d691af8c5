"""The unsplit reference for coupled gyrostats: carriers and rotors as bodies on joints, maximal coordinates.

Nothing here uses Theorem 5 (no effective gyrostats, no rotor momenta, no Routh reduction): every
carrier with mass and every rotor is a rigid body with its own Newton-Euler equations (as in
:mod:`thetasol.integrators.multibody`),

    m_i xddot_i = -m_i (a x_i + b / 2) + joint forces,    I_i omegadot_i = -omega_i x I_i omega_i + Q_i^T tau_i + joint torques,

and the joints are holonomic constraints solved each step from the KKT system (Schur complement,
Baumgarte stabilization at rate ``alpha``):

* a spherical joint: ``x_i + Q_i rho_i - x_j - Q_j rho_j = 0`` (3 rows);
* a revolute joint (a rotor on its carrier): the spherical joint at a point of the axis plus the two
  rows ``(Q_C u_1) . (Q_R l) = (Q_C u_2) . (Q_R l) = 0`` (``u_1, u_2`` orthogonal to the axis ``l``);
* a universal joint (two rotors on a massless cross, CU^1, Corollary 9): the spherical joint at the
  point where their axes meet plus the one row ``(Q_1 l_1) . (Q_2 l_2) = l_1 . l_2`` (a Hooke joint).

A "dot" row ``g = (Q_i u) . (Q_j v) - c`` has ``gdot = (A x B) . (Q_i omega_i - Q_j omega_j)`` with
``A = Q_i u``, ``B = Q_j v``, and ``gddot = G acc + ((w_i x A) x B + A x (w_j x B)) . (w_i - w_j)``
(space-frame rates ``w = Q omega``).

Massless carriers are supported with exactly two rotors whose axes meet (the Hooke joint), as the root
of the tree or attached at that point; joints hanging from a massless carrier itself are refused.
"""
from __future__ import annotations

import time
from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import solve_ivp

from thetasol.core import validate as V
from thetasol.core.so3 import cross, hat, polar_orthonormalize, vee
from thetasol.core.threads import single_blas_thread
from thetasol.mechanics.rotors import GyrostatConfiguration, MasslessCarrier
from thetasol.mechanics.trajectories import Trajectories

__all__ = ["integrate_gyrostat_multibody", "relative_rotor_angles"]


def _hooke_point(gc: GyrostatConfiguration, n: str) -> np.ndarray:
    """The point (carrier frame) where the two rotor axes of the massless carrier ``n`` meet."""
    rs = [gc.rotors[r] for r in gc.rotors_of[n]]
    if len(rs) != 2:
        raise ValueError(f"massless carrier {n!r}: the reference handles exactly two rotors (a Hooke joint), "
                         f"got {len(rs)}")
    (p1, l1), (p2, l2) = (rs[0].point, rs[0].axis), (rs[1].point, rs[1].axis)
    Mx = np.column_stack([l1, -l2])
    s, *_ = np.linalg.lstsq(Mx, p2 - p1, rcond=None)
    x1, x2 = p1 + s[0] * l1, p2 + s[1] * l2
    size = max(np.linalg.norm(p1), np.linalg.norm(p2), np.linalg.norm(p1 - p2), 1e-300)
    if np.linalg.norm(x1 - x2) > 1e-12 * size or abs(abs(l1 @ l2) - 1) < 1e-12:
        raise ValueError(f"massless carrier {n!r}: the rotor axes must meet in one point (a Hooke joint)")
    return 0.5 * (x1 + x2)


class _Model:
    """Bodies and constraint rows of the unsplit system."""

    def __init__(self, gc: GyrostatConfiguration):
        names = gc.body_names
        self.names = names
        self.bodies = [gc.rotors[n].body if n in gc.rotors else gc.carriers[n] for n in names]
        self.idx = {n: i for i, n in enumerate(names)}
        self.points: list[tuple] = []   # (i, j, rho_i, rho_j)
        self.dots: list[tuple] = []     # (i, j, u, v, c)
        self._rows(gc)

    def _sph(self, bi: str, pi: np.ndarray, bj: str, pj: np.ndarray) -> None:
        i, j = self.idx[bi], self.idx[bj]
        self.points.append((i, j, pi - self.bodies[i].center, pj - self.bodies[j].center))

    def _rows(self, gc: GyrostatConfiguration) -> None:
        for n in gc.order:
            rs = [gc.rotors[r] for r in gc.rotors_of[n]]
            if isinstance(gc.carriers[n], MasslessCarrier):
                X = _hooke_point(gc, n)
                self._sph(rs[0].name, X, rs[1].name, X)
                self.dots.append((self.idx[rs[0].name], self.idx[rs[1].name], rs[0].axis, rs[1].axis,
                                  float(rs[0].axis @ rs[1].axis)))
            else:
                for r in rs:
                    self._sph(n, r.point, r.name, r.point)
                    k = int(np.argmin(np.abs(r.axis)))
                    e = np.zeros(3)
                    e[k] = 1.0
                    u1 = e - (e @ r.axis) * r.axis
                    u1 /= np.linalg.norm(u1)
                    for u in (u1, np.cross(r.axis, u1)):
                        self.dots.append((self.idx[n], self.idx[r.name], u, r.axis, 0.0))
            for ch in gc.children[n] + [k for r in rs for k in gc.children[r.name]]:
                j = gc.joints[ch]
                parent = j.parent
                if isinstance(gc.carriers.get(parent), MasslessCarrier):
                    raise ValueError(f"joint {parent!r} -> {ch!r}: joints on a massless carrier are not supported "
                                     "by the reference")
                child = ch
                if isinstance(gc.carriers[ch], MasslessCarrier):
                    X = _hooke_point(gc, ch)
                    if np.linalg.norm(j.child_point - X) > 1e-12 * max(np.linalg.norm(X), 1.0):
                        raise ValueError(f"joint -> massless {ch!r}: the reference needs it at the axes' meeting point")
                    child = gc.rotors_of[ch][0]
                self._sph(parent, j.parent_point, child, j.child_point)


class _System:
    """Right-hand side of the maximal-coordinate equations with spherical and dot rows."""

    def __init__(self, model: _Model, a, b, alpha, kappa):
        self.model = model
        bs = model.bodies
        self.N = N = len(bs)
        self.m = np.array([x.mass for x in bs])
        self.J = np.array([x.J for x in bs])
        self.I = np.array([x.I for x in bs])
        Minv = np.zeros((6 * N, 6 * N))
        for i in range(N):
            Minv[6 * i:6 * i + 3, 6 * i:6 * i + 3] = np.eye(3) / self.m[i]
            Minv[6 * i + 3:6 * i + 6, 6 * i + 3:6 * i + 6] = np.linalg.inv(self.I[i])
        self.Minv = Minv
        self.a, self.b, self.alpha, self.kappa = a, b, alpha, kappa
        self.nrows = 3 * len(model.points) + len(model.dots)
        self._index()

    def unpack(self, y):
        N, lead = self.N, y.shape[:-1]
        return (y[..., :3 * N].reshape(lead + (N, 3)), y[..., 3 * N:6 * N].reshape(lead + (N, 3)),
                y[..., 6 * N:15 * N].reshape(lead + (N, 3, 3)), y[..., 15 * N:].reshape(lead + (N, 3)))

    @staticmethod
    def pack(x, v, Q, w):
        return np.concatenate([x.ravel(), v.ravel(), Q.ravel(), w.ravel()])

    def _index(self):
        P, D = self.model.points, self.model.dots
        self.Pi = np.array([p[0] for p in P], dtype=int)
        self.Pj = np.array([p[1] for p in P], dtype=int)
        self.rho_i = np.array([p[2] for p in P]).reshape(-1, 3)
        self.rho_j = np.array([p[3] for p in P]).reshape(-1, 3)
        self.hat_i, self.hat_j = hat(self.rho_i), hat(self.rho_j)
        self.Di = np.array([d[0] for d in D], dtype=int)
        self.Dj = np.array([d[1] for d in D], dtype=int)
        self.U = np.array([d[2] for d in D]).reshape(-1, 3)
        self.Vd = np.array([d[3] for d in D]).reshape(-1, 3)
        self.c = np.array([d[4] for d in D])

    def rows(self, x, v, Q, w):
        """Jacobian ``G``, residuals ``g``, ``gdot`` and the velocity-product term ``gamma``."""
        N, K, nD = self.N, len(self.Pi), len(self.Di)
        Pi, Pj, Di, Dj = self.Pi, self.Pj, self.Di, self.Dj
        ks, ds = np.arange(K), np.arange(nD)
        G4 = np.zeros((K, 3, N, 6))
        G4[ks, :, Pi, :3] = np.eye(3)
        G4[ks, :, Pj, :3] = -np.eye(3)
        G4[ks, :, Pi, 3:] = -Q[Pi] @ self.hat_i
        G4[ks, :, Pj, 3:] = Q[Pj] @ self.hat_j
        rel = lambda Qs, u: np.einsum("kij,kj->ki", Qs, u)  # noqa: E731
        wi, wj = w[Pi], w[Pj]
        g1 = x[Pi] + rel(Q[Pi], self.rho_i) - x[Pj] - rel(Q[Pj], self.rho_j)
        gd1 = v[Pi] + rel(Q[Pi], cross(wi, self.rho_i)) - v[Pj] - rel(Q[Pj], cross(wj, self.rho_j))
        gam1 = rel(Q[Pi], cross(wi, cross(wi, self.rho_i))) - rel(Q[Pj], cross(wj, cross(wj, self.rho_j)))
        A, B = rel(Q[Di], self.U), rel(Q[Dj], self.Vd)
        Wi, Wj = rel(Q[Di], w[Di]), rel(Q[Dj], w[Dj])
        AB = cross(A, B)
        G5 = np.zeros((nD, N, 6))
        G5[ds, Di, 3:] = np.einsum("dk,dkj->dj", AB, Q[Di])
        G5[ds, Dj, 3:] = -np.einsum("dk,dkj->dj", AB, Q[Dj])
        g2 = np.sum(A * B, axis=-1) - self.c
        gd2 = np.sum(AB * (Wi - Wj), axis=-1)
        gam2 = np.sum((cross(cross(Wi, A), B) + cross(A, cross(Wj, B))) * (Wi - Wj), axis=-1)
        G = np.concatenate([G4.reshape(3 * K, 6 * N), G5.reshape(nD, 6 * N)])
        return G, np.concatenate([g1.ravel(), g2]), np.concatenate([gd1.ravel(), gd2]), \
            np.concatenate([gam1.ravel(), gam2])

    def __call__(self, _t, y):
        N = self.N
        x, v, Q, w = self.unpack(y)
        S = Q @ self.J @ np.swapaxes(Q, 1, 2)
        tau = vee(S @ self.a - self.a @ S)
        f = np.empty((N, 6))
        f[:, :3] = -self.m[:, None] * (x @ self.a + 0.5 * self.b)
        f[:, 3:] = np.einsum("nji,nj->ni", Q, tau) - cross(w, np.einsum("nij,nj->ni", self.I, w))
        acc = self.Minv @ f.ravel()
        if self.nrows:
            G, g, gd, gam = self.rows(x, v, Q, w)
            MG = self.Minv @ G.T
            rhs = -(gam + 2 * self.alpha * gd + self.alpha ** 2 * g)
            acc = acc + MG @ np.linalg.solve(G @ MG, rhs - G @ acc)
        acc = acc.reshape(N, 6)
        Qdot = Q @ hat(w) + 0.5 * self.kappa * Q @ (np.eye(3) - np.swapaxes(Q, 1, 2) @ Q)
        return self.pack(v, acc[:, :3], Qdot, acc[:, 3:])


@single_blas_thread
def integrate_gyrostat_multibody(config: GyrostatConfiguration, a: ArrayLike, b: ArrayLike, q0: ArrayLike,
                                 v0: ArrayLike, Q0: Mapping[str, ArrayLike], omega0: Mapping[str, ArrayLike],
                                 t: ArrayLike, *, rtol: float = 1e-12, atol: float | None = None,
                                 method: str = "DOP853", alpha: float | None = None) -> Trajectories:
    """Integrate carriers and rotors as one constrained multibody system in ``1/2 x^T a x + 1/2 b^T x``.

    Parameters
    ----------
    config : GyrostatConfiguration
        A CR^n (CU^n) tree; the initial state places the rotors at ``phi = 0`` with their ``spin``.
    a, b : array_like
        Potential (2.4).
    q0, v0 : array_like (3,)
        System mass centre and velocity at ``t = 0``.
    Q0, omega0 : mapping carrier -> (3, 3) / (3,)
        Carriers' attitudes and body angular velocities (identity and zero where missing), massless
        carriers included.
    t : array_like (T,)
        Increasing output times ``>= 0``.
    rtol, atol, method, alpha
        As for :func:`thetasol.integrators.multibody.integrate_multibody`.

    Returns
    -------
    Trajectories
        Every carrier with mass and every rotor (names root first, each carrier followed by its rotors);
        ``info`` has ``constraint_residual`` (max joint gap and axis misalignment), ``nfev``, ``seconds``.
    """
    a = V.symmetric_matrix(a, "a")
    b = V.vector3(b, "b")
    tt = V.times(t, "t")
    if tt.ndim != 1 or tt.size == 0 or tt[0] < 0 or np.any(np.diff(tt) < 0):
        raise ValueError("t must be a non-empty increasing 1-d array of times >= 0")
    model = _Model(config)
    Qc = {n: V.rotation_matrix(Q0.get(n, np.eye(3)), f"Q0[{n!r}]") for n in config.order}
    wc = {n: V.vector3(omega0.get(n, np.zeros(3)), f"omega0[{n!r}]") for n in config.order}
    zeros = {r: np.zeros(()) for r in config.rotors}
    spins = {r: np.array(config.rotors[r].spin) for r in config.rotors}
    placed = config.place(V.vector3(q0, "q0"), V.vector3(v0, "v0"), Qc, wc, zeros, spins)
    x, v, Q, w = (np.array([placed[n][k] for n in model.names]) for k in ("position", "velocity", "attitude", "omega"))
    if alpha is None:
        alpha = max(1.0, float(np.max(np.linalg.norm(w, axis=1))) + float(np.sqrt(np.max(np.abs(np.linalg.eigvalsh(a))))))
    sys = _System(model, a, b, float(alpha), float(alpha))
    y0 = sys.pack(x, v, Q, w)
    atol = 1e-3 * rtol if atol is None else float(atol)
    start = time.perf_counter()
    if tt[-1] > 0:
        sol = solve_ivp(sys, (0.0, float(tt[-1])), y0, method=method, t_eval=tt, rtol=rtol, atol=atol)
        if not sol.success:
            raise RuntimeError(f"multibody integration failed: {sol.message}")
        Y, nfev = sol.y.T, sol.nfev
    else:
        Y, nfev = np.tile(y0, (tt.size, 1)), 0
    seconds = time.perf_counter() - start
    X, Vel, Qs, W = sys.unpack(Y)
    resid = max((float(np.max(np.abs(sys.rows(*(z[k] for z in (X, Vel, Qs, W)))[1]))) for k in range(len(tt))),
                default=0.0) if sys.nrows else 0.0
    X, Vel, Qs, W = (np.moveaxis(z, 0, 1) for z in (X, Vel, Qs, W))
    Qs = polar_orthonormalize(Qs)
    mc = np.einsum("n,nti->ti", sys.m, X) / sys.m.sum()
    mcv = np.einsum("n,nti->ti", sys.m, Vel) / sys.m.sum()
    info = {"model": "multibody with rotors (maximal coordinates, KKT, Baumgarte)", "method": method, "rtol": rtol,
            "alpha": float(alpha), "nfev": int(nfev), "seconds": seconds, "constraint_residual": resid}
    return Trajectories(t=tt.copy(), names=tuple(model.names), position=X, velocity=Vel, attitude=Qs, omega=W,
                        mass_center=mc, mass_center_velocity=mcv, info=info)


def relative_rotor_angles(Q_carrier: np.ndarray, Q_rotor: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """The angle ``phi`` of ``Q_carrier^T Q_rotor = R_l(phi)`` along a time series, unwrapped (``phi(0)`` in
    ``(-pi, pi]``): the rotor angle of the unsplit reference."""
    R = np.swapaxes(Q_carrier, -1, -2) @ Q_rotor
    s = 0.5 * (vee(R - np.swapaxes(R, -1, -2)) @ axis)
    c = 0.5 * (np.trace(R, axis1=-2, axis2=-1) - axis @ R @ axis)   # the trace in the plane normal to the axis
    return np.unwrap(np.arctan2(s, c))
