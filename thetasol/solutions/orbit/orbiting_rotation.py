"""Closed forms of one body's rotation on a Kepler orbit (Section 7): the integrable special motions.

The rotation in the gravity-gradient torque (7.16) is not integrable in general (Boucher 2006 for a
circular orbit; chaotic on elliptic ones, Wisdom-Peale-Mignard 1984).  What is solved here in closed
form, with :func:`~thetasol.integrators.orbiting_rotation.integrate_orbiting_rotation` as the reference
for everything else (``sol.case`` names the motion; ``sol.method`` is ``"elementary"`` or, for the
pendulum's libration, circulation and separatrix, ``"elliptic"``):

``"relative-equilibrium"``
    circular orbit, principal axes along the orbit frame (radial, along-track, normal), turning with
    it: ``omega = n Q0^T e_n``, ``Q(t) = R_{e_n}(n t) Q0`` (24 attitudes; their linear stability is
    in ``diagnostics["stability"]``, :func:`~thetasol.mechanics.gravity_gradient.gravity_gradient_stability`).
``"pitch/libration"``, ``"pitch/circulation"``, ``"pitch/separatrix"``, ``"pitch/uniform"``
    circular orbit, a principal axis ``u`` along the orbit normal and ``omega0`` along it: the body
    stays in that plane.  With ``theta`` the angle from the radial to the body axis ``b_i``
    (``(b_i, b_j, u)`` right-handed) the torque about ``u`` is ``-(3/2) n^2 (I_j - I_i) sin 2 theta``,
    so ``psi = 2 theta`` (shifted by pi when ``I_j < I_i``) is a pendulum,

        theta'' = -(3/2) n^2 K sin 2 theta,    K = (I_j - I_i) / I_u,

    solved in Jacobi elliptic functions by :mod:`thetasol.special.pendulum` (libration
    ``sin(psi/2) = k sn(nu t + u0 | k^2)``, ``nu = n sqrt(3 |K|)``; circulation in ``am``; the
    separatrix in ``tanh``).  The attitude is ``Q(t) = R_{e_n}(n t + theta(t) - theta0) Q0``.
``"spherical"``
    a body with equal principal moments on any orbit: no torque, uniform rotation.

Angles are reduced modulo 2 pi with an exact product (:func:`thetasol.core.attitude.angle_mod_2pi`),
the elliptic functions modulo their periods: ``t = 1e6`` orbits costs what ``t = 1`` costs.
Accuracy is checked in tests/test_orbiting_rotation.py (LEO in SI units): the pitch angle and rate
against the pendulum equation and the attitude against the full 3-D equations, both integrated by
80-bit heyoka over many orbits (the attitude is less accurate where the planar motion is out-of-plane
sensitive, as the data's conditioning is); relative equilibria against DOP853; the pitch energy at
far times.

A circular orbit means ``e <= 1e-13`` (``KeplerOrbit.diagnostics["e"]``; data rounded from a
circular orbit give ~1e-16); the error that ``e`` leaves is of order ``e n t``, reported as
``diagnostics["error_estimate"]`` (at least float64 rounding) per unit time.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.attitude import angle_mod_2pi, principal_frame, uniform_rotation
from thetasol.core.inertia import inertia, second_moments
from thetasol.core.so3 import rotation_about
from thetasol.core.threads import single_blas_thread
from thetasol.mechanics.gravity_gradient import gravity_gradient_stability_from_moments, orbit_frame
from thetasol.protocol import ROUNDOFF, ClosedFormUnavailable, RotationSolution
from thetasol.solutions.orbit.kepler import KeplerOrbit
from thetasol.special.elliptic import ellipj, ellipk
from thetasol.special.pendulum import pendulum_angle, pendulum_params

__all__ = ["OrbitingRotation", "solve_orbiting_rotation"]

_EPS = np.finfo(float).eps
_CIRCULAR_E = 1e-13
_ALIGN = 16 * _EPS          # |Q0 u - e_n|, off-axis omega: rounding of exactly aligned data


@dataclass(frozen=True, eq=False)
class OrbitingRotation(RotationSolution):
    """A closed-form rotation on a Kepler orbit (module docstring); ``sol(t) -> (omega, Q)``.

    ``a`` is the tidal matrix (7.11) ``-3 mu g g^T / |r|^3`` at ``t = 0``; :meth:`u` uses the one at
    each time.  ``orbit`` is the :class:`KeplerOrbit`.
    """

    model = "orbiting-rotation"

    orbit: KeplerOrbit = field(default=None, repr=False)
    _c: dict = field(default=None, repr=False)

    def _evaluate(self, t: np.ndarray):
        c = self._c
        if c["kind"] == "spherical":
            return uniform_rotation(self.Q0, self.omega0, t)
        # the orbit's own angle (its period is exact to 40 digits): n t in float64 would drift from it
        # by n t eps, 6e-10 rad after 1e6 orbits
        r = self.orbit.position(t)
        F0 = c["F0"]
        nu = np.arctan2(r @ F0[:, 1], r @ F0[:, 0])
        if c["kind"] == "uniform":
            alpha = angle_mod_2pi(c["thetadot0"], t, nu)
            rate = np.full(t.shape, c["rate"])
        elif c["pend"]["kind"] == "circulation":
            # psi/2 = am(u) grows without bound: take it modulo 2 pi from (sn, cn), where the sum
            # am = reduced + j pi would lose 1e-9 rad of absolute precision at u ~ 1e7
            p = c["pend"]
            sn, cn, dn, _ = ellipj(p["k"] * p["nu"] * t + p["u0"], p["m"], p["mc"])
            alpha = nu + p["sign"] * np.arctan2(sn, cn) - 0.5 * p["psi0"]
            rate = c["n"] + p["sign"] * p["k"] * p["nu"] * dn
        else:
            dth, thdot = pendulum_angle(c["pend"], t)
            alpha = nu + dth
            rate = c["n"] + thdot
        Qp = c["Q0p"] @ rotation_about(c["k"], c["s"] * alpha)
        wp = np.zeros(t.shape + (3,))
        wp[:, c["k"]] = c["s"] * rate
        P = c["P"]
        return wp @ P.T, Qp @ P.T

    def u(self, t: ArrayLike) -> np.ndarray:
        """The paper's ``u = -Q^T a(t) Q`` with the tidal matrix (7.11) of the orbit at ``t``."""
        Q = self.Q(t)
        r = self.orbit.position(t)
        rn = np.linalg.norm(r, axis=-1)[..., None]
        rb = np.einsum("...ji,...j->...i", Q, r) / rn               # Q^T g
        return 3.0 * self.orbit.mu / rn[..., None] ** 3 * (rb[..., :, None] * rb[..., None, :])


def _tidal_matrix(orbit):
    r = orbit.r0
    rn = np.linalg.norm(r)
    g = r / rn
    return -3.0 * orbit.mu / rn ** 3 * np.outer(g, g)


def _jacobi(I, n, F0, Q0, w0):
    """(7.18): 1/2 (M, omega) + (3 n^2 / 2)(gamma, I gamma) - n (M, n_b), body-frame gamma, n_b."""
    g, nb = Q0.T @ F0[:, 0], Q0.T @ F0[:, 2]
    M = I @ w0
    return float(0.5 * M @ w0 + 1.5 * n * n * g @ I @ g - n * M @ nb)


def _pitch_axis(Qp, wp, en):
    """(k, s) with Q0p (s e_k) = e_n and omega along e_k, else None."""
    wn = np.linalg.norm(wp)
    for k in range(3):
        col = Qp[:, k]
        s = 1.0 if col @ en > 0 else -1.0
        if np.max(np.abs(s * col - en)) > _ALIGN:
            continue
        off = np.delete(wp, k)
        if wn > 0 and np.max(np.abs(off)) > _ALIGN * wn:
            continue
        return k, s
    return None


def _pitch_setup(Ip, k, s, Qp, wp, F0, n):
    """The constants of the planar motion: theta0, thetadot0, K and the pendulum's closed form."""
    i, j = ((k + 1) % 3, (k + 2) % 3) if s > 0 else ((k + 2) % 3, (k + 1) % 3)
    bi = Qp[:, i]
    th0 = math.atan2(float(bi @ F0[:, 1]), float(bi @ F0[:, 0]))
    thd0 = float(s * wp[k] - n)
    K = float((Ip[j] - Ip[i]) / Ip[k])
    c = {"k": k, "s": s, "n": n, "theta0": th0, "thetadot0": thd0, "K": K}
    scale = abs(thd0) + n * math.sqrt(3 * abs(K))
    at_equilibrium = abs(thd0) <= 8 * _EPS * n and abs(math.sin(2 * th0)) <= 8 * _EPS
    if at_equilibrium or abs(K) * n * n <= 4 * _EPS * scale * scale:
        c.update(kind="uniform", rate=n + thd0)
        return c, ("relative-equilibrium" if at_equilibrium else "pitch/uniform")
    nu = n * math.sqrt(3.0 * abs(K))
    psi0 = 2.0 * th0 - (0.0 if K > 0 else math.pi)
    psi0 = (psi0 + math.pi) % (2 * math.pi) - math.pi
    pend, m = pendulum_params(psi0, 2.0 * thd0, nu)
    c.update(kind="pendulum", pend=pend, nu=nu, m=float(m))
    if pend["kind"] == "libration":
        c["period"] = float(4.0 * ellipk(pend["m"], pend["mc"]) / nu)
    elif pend["kind"] == "circulation":
        c["period"] = float(2.0 * ellipk(pend["m"], pend["mc"]) / (pend["k"] * nu))
    return c, "pitch/" + pend["kind"]


@single_blas_thread
def solve_orbiting_rotation(I: ArrayLike, orbit: KeplerOrbit, Q0: ArrayLike, omega0: ArrayLike) -> OrbitingRotation:
    """The closed-form rotation about the mass centre on ``orbit`` where one exists.

    Parameters
    ----------
    I : array_like, shape (3,) or (3, 3)
        Inertia tensor about the mass centre in the body frame (second moments convert with
        :func:`thetasol.inertia`).
    orbit : KeplerOrbit
        The mass centre's orbit (7.7).
    Q0 : array_like, shape (3, 3)
        Attitude at ``t = 0``, body to space.
    omega0 : array_like, shape (3,)
        Body-frame angular velocity at ``t = 0``.

    Returns
    -------
    OrbitingRotation
        ``sol(t) -> (omega, Q)``; ``case`` names the motion (module docstring).

    Raises
    ------
    ClosedFormUnavailable
        Valid data outside the solved cases: use
        :func:`thetasol.integrators.orbiting_rotation.integrate_orbiting_rotation`.
    ValueError
        Bad data (non-physical ``I``, non-orthogonal ``Q0``, NaN).
    """
    if not isinstance(orbit, KeplerOrbit):
        raise TypeError(f"orbit must be a KeplerOrbit, got {type(orbit).__name__}")
    Im = V.inertia(I, "I")
    Jm = second_moments(Im)
    Q0 = V.rotation_matrix(Q0, "Q0")
    w0 = V.vector3(omega0, "omega0")
    Jp, P = principal_frame(Jm)
    Ip = inertia(Jp)
    base = dict(J=Jm, a=_tidal_matrix(orbit), Q0=Q0, omega0=w0, orbit=orbit, I_given=Im)
    if np.max(Ip) - np.min(Ip) <= 4 * _EPS * np.max(Ip):
        return OrbitingRotation(method="elementary", invariants={"m": Im @ w0},
                                diagnostics={"case": "spherical", "error_estimate": ROUNDOFF}, _c={"kind": "spherical"},
                                **base)
    d = orbit.diagnostics
    if d["kind"] != "elliptic" or d["e"] > _CIRCULAR_E:
        raise ClosedFormUnavailable(
            f"the orbit is not circular (e = {d['e']:.3g}): the rotation of a non-spherical body is then "
            "non-autonomous and not integrable; use thetasol.integrators.orbiting_rotation.integrate_orbiting_rotation")
    n = d["mean_motion"]
    F0 = orbit_frame(orbit.r0, orbit.v0)
    Qp, wp = Q0 @ P, P.T @ w0
    found = _pitch_axis(Qp, wp, F0[:, 2])
    if found is None:
        raise ClosedFormUnavailable(
            "no principal axis along the orbit normal with the angular velocity along it: the general "
            "rotation on a circular orbit is not integrable (Boucher 2006); use "
            "thetasol.integrators.orbiting_rotation.integrate_orbiting_rotation")
    k, s = found
    c, case = _pitch_setup(Ip, k, s, Qp, wp, F0, n)
    if case == "relative-equilibrium":
        c["thetadot0"] = 0.0
    c.update(Q0p=Qp, P=P, F0=F0)
    diag = {"orbit_e": d["e"], "mean_motion": n, "K": c["K"], "theta0": c["theta0"],
            "thetadot0": c["thetadot0"], "case": case, "error_estimate": max(ROUNDOFF, 4 * d["e"] * n)}
    if "period" in c:
        diag["period"] = c["period"]
    if case == "relative-equilibrium":
        order = [int(np.argmax(np.abs(Qp.T @ F0[:, a]))) for a in range(3)]   # principal axis per orbit axis
        st = gravity_gradient_stability_from_moments(Jp[order], n)
        diag.update(stability=st.region, stable=st.stable)
    inv = {"jacobi": _jacobi(Im, n, F0, Q0, w0)}
    if c["kind"] == "pendulum":
        inv["pitch_energy"] = 0.5 * c["thetadot0"] ** 2 - 0.75 * n * n * c["K"] * math.cos(2 * c["theta0"])
    method = "elementary" if case in ("relative-equilibrium", "pitch/uniform") else "elliptic"
    return OrbitingRotation(method=method, invariants=inv, diagnostics=diag, _c=c, **base)
