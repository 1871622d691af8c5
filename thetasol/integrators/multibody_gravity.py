"""The unsplit station in the exact ``1/r`` field: the reference of Section 7 that truncates nothing.

Each body is a set of point masses ``m_k`` at body-frame points ``p_k``; the attracting centre
(``mu = G m0``, at the origin) pulls each with ``F_k = -mu m_k X_k / |X_k|^3``, ``X_k = x + Q (p_k - c)``
its position in space.  The body gets the sum of the ``F_k`` on its mass centre ``x`` and the torque
``sum Q (p_k - c) x F_k`` about it: no expansion (7.2)-(7.4), no tidal matrix, no split.  The tree of
bodies on spherical joints is integrated by :func:`~thetasol.integrators.multibody.integrate_multibody`
(maximal coordinates, KKT) with these loads (its quadratic potential set to zero), plus optional
pure control couples on each body.

The maximal coordinates are taken relative to the Kepler orbit ``q_K(t)`` of the initial system mass
centre (the caller's ``orbit``), a frame in free fall: each body then also feels the uniform fictitious force
``+mu m q_K / |q_K|^3``, which exerts no torque.  The field minus that force is formed without
cancellation (Battin's form, ``_tidal_force``), and the joints are evaluated on coordinates of the
station's size.  In absolute coordinates both carry rounding of relative size ``eps R / L`` (orbit
radius ``R``, station size ``L``), a noise in the right-hand side that the step-size control chases
with ever smaller steps; in these coordinates the step count does not depend on ``L/R``.  Nothing is expanded: each
point mass feels the exact ``-mu m_k X_k / |X_k|^3`` at ``X_k = q_K + x + Q (p_k - c)``.

Point-mass models of bodies that are not given as point masses (:func:`mass_points`):

* a homogeneous box: the 27 points of the 3-point Gauss-Legendre rule per axis, which integrate
  every monomial ``x^i y^j z^k`` with ``i, j, k <= 5`` exactly: all the box's moments up to order 5;
* a body given by its second moments only: six points ``c +- d_i a_i`` of mass ``m / 6`` on its
  principal axes ``a_i``, ``d_i = sqrt(3 J_i / m)``: mass, mass centre and second moments exact,
  third moments zero (as for any centrally symmetric body).  Its fourth moments are a choice the data
  do not fix; they enter the torque at ``(size / r)^2`` relative to the tidal one.
"""
from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.so3 import cross
from thetasol.core.threads import single_blas_thread
from thetasol.integrators.multibody import integrate_multibody
from thetasol.mechanics.bodies import Body
from thetasol.mechanics.configuration import Configuration
from thetasol.mechanics.orbit import Orbit, check_orbit
from thetasol.mechanics.trajectories import Trajectories

__all__ = ["box_mass_points", "mass_points", "PointMassGravity", "integrate_multibody_gravity"]

_GAUSS3_X = np.array([-np.sqrt(0.6), 0.0, np.sqrt(0.6)])
_GAUSS3_W = np.array([5.0, 8.0, 5.0]) / 18.0


def box_mass_points(mass: float, size: ArrayLike, center: ArrayLike = (0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """The 27 Gauss-Legendre points of a homogeneous box (module docstring): ``masses (27,), points (27, 3)``."""
    s = V.finite_array(size, "size", (3,))
    c = V.vector3(center, "center")
    g = np.meshgrid(_GAUSS3_X, _GAUSS3_X, _GAUSS3_X, indexing="ij")
    w = np.meshgrid(_GAUSS3_W, _GAUSS3_W, _GAUSS3_W, indexing="ij")
    pts = np.stack([g[i].ravel() * 0.5 * s[i] for i in range(3)], axis=1) + c
    return float(mass) * (w[0] * w[1] * w[2]).ravel(), pts


def mass_points(body: Body) -> tuple[np.ndarray, np.ndarray]:
    """Six point masses with the body's mass, mass centre and second moments (module docstring)."""
    vals, axes = body.principal()
    d = np.sqrt(np.maximum(3.0 * vals / body.mass, 0.0))
    offs = np.concatenate([(axes * d).T, -(axes * d).T])          # rows: +d_i a_i, then -d_i a_i
    return np.full(6, body.mass / 6.0), body.center + offs


class PointMassGravity:
    """The loads of the exact ``1/r`` field on point-mass bodies: ``forces(t, x, v, Q, omega) -> (N, 6)``.

    Parameters
    ----------
    config : Configuration
    mu : float
        Gravitational parameter of the attracting centre at the origin.
    points : mapping name -> (masses, points), optional
        Body-frame point masses per body; a body missing here is modelled by :func:`mass_points`.
        Each model must have the body's mass and mass centre (to 1e-12 relative).
    torques : callable, optional
        ``torques(t, q, qdot, Q, omega) -> (N, 3)`` body-frame control couples, from the system
        mass centre ``q, qdot`` and the attitudes and angular velocities of all bodies.
    frame : Orbit, optional
        Positions and velocities are relative to this orbit (a frame in free fall along it, e.g. a
        :class:`thetasol.KeplerOrbit` in the same field): the
        loads then include the uniform fictitious force ``+mu m q_K / |q_K|^3``, which exerts no
        torque, and ``torques`` still gets the absolute ``q, qdot``.
    """

    def __init__(self, config: Configuration, mu: float, points: Mapping | None = None,
                 torques: Callable | None = None, frame: Orbit | None = None):
        self.mu = float(V.finite_array(mu, "mu", ()))
        if not self.mu > 0:
            raise ValueError(f"mu must be positive, got {mu}")
        points = {} if points is None else dict(points)
        unknown = set(points) - set(config.order)
        if unknown:
            raise ValueError(f"points names unknown bodies {sorted(unknown)}")
        idx, mk, dk = [], [], []
        for i, n in enumerate(config.order):
            b = config.bodies[n]
            m, p = points[n] if n in points else mass_points(b)
            m = V.finite_array(m, f"masses of {n!r}")
            p = V.finite_array(p, f"points of {n!r}", (m.size, 3))
            scale = max(np.sqrt(np.trace(b.J) / b.mass), np.linalg.norm(b.center), np.finfo(float).tiny)
            if abs(m.sum() - b.mass) > 1e-12 * b.mass or np.max(np.abs(m @ p / m.sum() - b.center)) > 1e-12 * scale:
                raise ValueError(f"the point masses of {n!r} do not have the body's mass and mass centre")
            idx.append(np.full(m.size, i))
            mk.append(m)
            dk.append(p - b.center)
        self.N = len(config.order)
        self.idx, self.mk, self.dk = np.concatenate(idx), np.concatenate(mk), np.concatenate(dk)
        self.m = np.array([config.bodies[n].mass for n in config.order])
        self.torques = torques
        self.frame = frame

    def __call__(self, t: float, x: np.ndarray, v: np.ndarray, Q: np.ndarray, w: np.ndarray) -> np.ndarray:
        Qk = Q[self.idx]
        arm = np.einsum("kij,kj->ki", Qk, self.dk)                 # Q (p_k - c), space frame
        qk, vk = np.zeros(3), np.zeros(3)
        if self.frame is None:
            X = x[self.idx] + arm
            r2 = np.einsum("ki,ki->k", X, X)
            F = (-self.mu * self.mk / (r2 * np.sqrt(r2)))[:, None] * X
        else:
            r_, v_ = self.frame.state_at(t)
            qk, vk = np.array(r_), np.array(v_)
            F = _tidal_force(self.mu, self.mk, qk, x[self.idx] + arm)
        tau = np.einsum("kji,kj->ki", Qk, cross(arm, F))          # body frame
        out = np.zeros((self.N, 6))
        np.add.at(out[:, :3], self.idx, F)
        np.add.at(out[:, 3:], self.idx, tau)
        if self.torques is not None:
            M = self.m.sum()
            out[:, 3:] += self.torques(t, self.m @ x / M + qk, self.m @ v / M + vk, Q, w)
        return out


def _tidal_force(mu: float, m: np.ndarray, q: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``-mu m ((q + d)/|q + d|^3 - q/|q|^3)`` without cancellation (Battin's form): ``(K, 3)``.

    With ``u = d.(2q + d)/|q|^2 = |q + d|^2/|q|^2 - 1`` (no cancellation) and
    ``g = (1 + u)^(3/2) - 1 = expm1(1.5 log1p(u))`` the bracket is ``(d - g q) / |q + d|^3``: terms of
    the size of ``d``, so the tidal force keeps its relative precision however small ``|d| / |q|``.
    """
    q2 = float(q @ q)
    u = np.einsum("ki,ki->k", d, 2.0 * q + d) / q2
    g = np.expm1(1.5 * np.log1p(u))
    r3 = (q2 * (1.0 + u)) ** 1.5
    return (-mu * m / r3)[:, None] * (d - g[:, None] * q)


@single_blas_thread
def integrate_multibody_gravity(config: Configuration, orbit: Orbit, Q0: Mapping[str, ArrayLike],
                                omega0: Mapping[str, ArrayLike], t: ArrayLike, *,
                                points: Mapping | None = None, torques: Callable | None = None,
                                rtol: float = 1e-12, atol: float | None = None, method: str = "DOP853",
                                alpha: float | None = None) -> Trajectories:
    """Integrate a tree of point-mass bodies on spherical joints in the exact field ``-mu / |x|``.

    Parameters
    ----------
    config : Configuration
        Any tree of bodies (central or not).
    orbit : Orbit
        The Kepler orbit of the system mass centre's initial state, ``thetasol.KeplerOrbit(mu, q0, v0)``
        (or any :class:`thetasol.mechanics.orbit.Orbit` through that state in the field of ``orbit.mu``):
        its ``mu`` is the attracting centre's ``G m0``, its ``r0, v0`` the system mass centre's position
        and velocity at ``t = 0``, and it is the free-falling frame of the maximal coordinates.
    Q0, omega0 : mapping name -> (3, 3), (3,)
        Initial attitudes and body-frame angular velocities (identity, zero where missing).
    t : array_like (T,)
        Output times, increasing, ``>= 0``.
    points, torques
        As for :class:`PointMassGravity`.
    rtol, atol, method
        Passed to :func:`~thetasol.integrators.multibody.integrate_multibody`.
    alpha : float, optional
        Baumgarte rate; default the fastest initial rate, ``max(|omega0|, sqrt(mu / |r0|^3))``
        (unit-free, unlike the default of ``integrate_multibody``).

    Returns
    -------
    Trajectories
        As :func:`~thetasol.integrators.multibody.integrate_multibody`, ``info["model"]`` naming the field.
    """
    frame = check_orbit(orbit)
    q0v = V.vector3(frame.r0, "orbit.r0")
    if not np.linalg.norm(q0v) > 0:
        raise ValueError("orbit.r0 must not be the attracting centre")
    gravity = PointMassGravity(config, frame.mu, points, torques, frame=frame)
    if alpha is None:
        wmax = max((np.linalg.norm(V.vector3(w, "omega0")) for w in omega0.values()), default=0.0)
        alpha = max(wmax, np.sqrt(gravity.mu / np.linalg.norm(q0v) ** 3))
    rel = integrate_multibody(config, np.zeros((3, 3)), np.zeros(3), np.zeros(3), np.zeros(3), Q0, omega0, t,
                              rtol=rtol, atol=atol, method=method, alpha=float(alpha), forces=gravity)
    rK, vK = frame(rel.t)
    info = dict(rel.info, mu=gravity.mu,
                model="multibody in the exact 1/r field of point masses (maximal coordinates relative to the "
                      "Kepler orbit of the initial mass centre, KKT, Baumgarte)")
    return Trajectories(t=rel.t, names=rel.names, position=rel.position + rK, velocity=rel.velocity + vK,
                        attitude=rel.attitude, omega=rel.omega, mass_center=rel.mass_center + rK,
                        mass_center_velocity=rel.mass_center_velocity + vK, info=info)
