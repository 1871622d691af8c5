"""Rotation about a fixed principal axis: the planar pendulum (reducible spectral curve).

When the initial angular velocity lies along a principal axis ``e_i`` of the body and ``e_i`` is
an eigenvector of ``Q0^T a Q0``, the body keeps rotating about that axis: ``Q(t) = Q0 R_i(phi)``,
``omega = phidot e_i``.  Then ``J``, ``u`` and ``M`` share the invariant line ``e_i``, the spectral
curve (4.12) splits off the line ``w = J_i^2 E^2 + u_ii`` and what is left is the pendulum.  With
``B`` the block of ``Q0^T a Q0`` on the plane (j, k) (i, j, k cyclic) the torque (4.8) about ``e_i``
is ``(J_k - J_j) [ (B_kk - B_jj)/2 sin 2 phi + B_jk cos 2 phi ]``, so ``psi = 2 phi + delta`` (shifted
by pi where needed) obeys ``psidot^2 / 2 - nu^2 cos psi = const``: libration
``sin(psi/2) = k sn(nu t + u0 | k^2)``, circulation ``psi/2 = am(k nu t + u0 | 1/k^2)``, the
separatrix ``sin(psi/2) = tanh(nu t + u0)``, and uniform rotation when ``nu = 0`` (rest, or a
steady spin about an axis of symmetry of the body or of the potential).

Elliptic functions from :mod:`thetasol.special.elliptic` (accurate as m -> 1, arguments reduced modulo
the period, so far times cost what t = 1 costs).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from thetasol.core.attitude import principal_frame
from thetasol.core.inertia import inertia
from thetasol.core.so3 import rotation_about
from thetasol.mechanics.equations import invariants_from_moments as _invariants
from thetasol.protocol import RotationSolution

__all__ = ["PendulumRotation", "solve_pendulum"]

_EPS = np.finfo(float).eps


@dataclass(frozen=True, eq=False)
class PendulumRotation(RotationSolution):
    """Rotation about the fixed body axis ``axis_body`` (a principal axis) by the angle phi(t)."""

    axis_body: np.ndarray = field(default=None, repr=False)
    _c: dict = field(default=None, repr=False)

    def _evaluate(self, t: np.ndarray):
        c = self._c
        from thetasol.special.pendulum import pendulum_angle

        phi, phidot = pendulum_angle(c, t)
        Qp = c["Q0p"] @ rotation_about(c["i"], phi)
        wp = np.zeros(t.shape + (3,))
        wp[..., c["i"]] = phidot
        P = c["P"]
        return wp @ P.T, Qp @ P.T


def _axis_of(J, a, Q0, omega0):
    """The principal axis index i (in the principal frame) if the pendulum case applies, else None."""
    Jp, P = principal_frame(J, ascending=True)
    wp = P.T @ omega0
    Qp = Q0 @ P
    B = Qp.T @ a @ Qp
    scale_a = max(np.abs(np.linalg.eigvalsh(a)).max(), np.finfo(float).tiny)
    scale_w = np.linalg.norm(wp)
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        if scale_w > 0 and max(abs(wp[j]), abs(wp[k])) > 4 * _EPS * scale_w:
            continue
        if max(abs(B[i, j]), abs(B[i, k])) > 4 * _EPS * scale_a:
            continue
        return i, Jp, P, Qp, wp, B
    return None


def solve_pendulum(J: np.ndarray, a: np.ndarray, Q0: np.ndarray, omega0: np.ndarray,
                   dps: int | None = None) -> PendulumRotation | None:
    """The pendulum branch of :func:`thetasol.solve_rotation` (None when it does not apply)."""
    if dps is not None:
        return None
    found = _axis_of(J, a, Q0, omega0)
    if found is None:
        return None
    i, Jp, P, Qp, wp, B = found
    j, k = (i + 1) % 3, (i + 2) % 3
    Ii = inertia(Jp)[i]
    half = 0.5 * (B[k, k] - B[j, j])
    rho = np.hypot(half, B[j, k])
    kappa = 2.0 * (Jp[k] - Jp[j]) * rho / Ii          # psi'' = kappa sin(psi), psi = 2 phi + delta
    delta = np.arctan2(B[j, k], half)
    w0 = wp[i]
    c = {"i": i, "Q0p": Qp, "P": P, "phi0": 0.0, "w0": w0}
    inv = {key: float(v) for key, v in _invariants(J, a, Q0, omega0).items() if key != "curve"}
    scale = abs(w0) + np.sqrt(abs(kappa))
    # no torque now and no spin: an equilibrium, stable or not, is kept exactly
    at_rest = w0 == 0 and B[j, k] == 0
    if at_rest or abs(kappa) <= 4 * _EPS * max(scale, np.finfo(float).tiny) ** 2:
        c["kind"] = "uniform"
        case = "pendulum/uniform" if w0 != 0 else "rest"
        return PendulumRotation(J=J, a=a, Q0=Q0, omega0=omega0, method="elementary", invariants=inv,
                                diagnostics={"case": case}, axis_body=P[:, i], _c=c)
    # psi = 2 phi + delta - pi [kappa > 0] obeys psi'' = -nu^2 sin psi; phi(0) = 0
    psi0 = np.remainder(delta - (np.pi if kappa > 0 else 0.0) + np.pi, 2 * np.pi) - np.pi
    nu = np.sqrt(abs(kappa))
    # scipy.special (slow to import) only once the branch applies: solve_rotation tries it for every body
    from thetasol.special.elliptic import ellipk
    from thetasol.special.pendulum import pendulum_params

    params, m = pendulum_params(psi0, 2.0 * w0, nu)
    c.update(params)
    diag = {"pendulum_nu": float(nu), "pendulum_m": float(m)}
    if c["kind"] == "libration":
        diag["period"] = float(4.0 * ellipk(c["m"], c["mc"]) / nu)
    elif c["kind"] == "circulation":
        diag["period"] = float(2.0 * ellipk(c["m"], c["mc"]) / (c["k"] * nu))
    diag["case"] = "pendulum/" + c["kind"]
    return PendulumRotation(J=J, a=a, Q0=Q0, omega0=omega0, method="elliptic", invariants=inv,
                            diagnostics=diag, axis_body=P[:, i], _c=c)
