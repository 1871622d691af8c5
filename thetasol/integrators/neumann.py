"""Numerical reference for C. Neumann's problem: a point on the sphere ``|q| = R`` in ``1/2 q^T a q``.

Per unit mass ``qddot = -a q + lambda q`` (Section 6, (6.1)-(6.2)), integrated by
:func:`scipy.integrate.solve_ivp` with the multiplier

    lambda = (q.aq - |qdot|^2 - 2 alpha q.qdot - alpha^2 (|q|^2 - R^2) / 2) / |q|^2,

which makes ``c = (|q|^2 - R^2) / 2`` obey ``cddot + 2 alpha cdot + alpha^2 c = 0`` (Baumgarte,
critically damped; ``alpha = sqrt(max |eig a|) + |v0| / R``, the fastest natural rate; the sign of
``2 alpha`` follows the direction of integration, so that backward in time it damps too): on the
sphere it is Neumann's multiplier, off it the drift of the integrator decays instead of growing.
Used where :func:`~thetasol.solutions.points.neumann.solve_neumann` builds no closed form (within ~1e-4 of
a separatrix) and by the split of a scene with the sphere constraint in that case.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import solve_ivp

from thetasol.integrators._common import SCIPY_METHODS, Settings, settings
from thetasol.mechanics.constraints import point_on_sphere
from thetasol.protocol import Solution

__all__ = ["integrate_neumann", "NumericalNeumann"]


def integrate_neumann(a: ArrayLike, q0: ArrayLike, v0: ArrayLike, *, method: str = "DOP853",
                      rtol: float = 1e-12) -> NumericalNeumann:
    """Neumann's problem on ``|q| = |q0|``, integrated numerically (module docstring).

    Parameters
    ----------
    a : array_like (3, 3)
        Symmetric potential matrix.
    q0, v0 : array_like (3,)
        Initial point (non-zero) and velocity (its normal part is removed).
    method : str
        Any :func:`scipy.integrate.solve_ivp` method.
    rtol : float
        Relative tolerance (``atol = 1e-3 rtol`` times the scale ``|q0| (1 + alpha)``).

    Returns
    -------
    NumericalNeumann
        ``sol(t) -> (q, v)``, each ``t.shape + (3,)`` and projected onto the sphere and its tangent
        plane at output, for any shape of ``t`` (any order, negative allowed), one integration from
        ``t = 0`` per call; ``model`` is ``"neumann"``, ``method`` ``"numerical/<method>"``;
        ``invariants`` the energy per unit mass ``1/2 |v0|^2 + 1/2 q0.a q0``; ``diagnostics`` the
        integrator settings, ``error_estimate`` (its ``rtol``) and the ``radius``.
    """
    a, q0, v0, R = point_on_sphere(a, q0, v0)
    opts = settings(method, rtol, None, methods=SCIPY_METHODS)
    inv = {"energy": float(0.5 * (v0 @ v0) + 0.5 * (q0 @ a @ q0))}
    return NumericalNeumann(a=a, q0=q0, v0=v0, method=f"numerical/{opts.method}", invariants=inv,
                            diagnostics={**opts.diagnostics(), "radius": R}, settings=opts)


@dataclass(frozen=True, eq=False)
class NumericalNeumann(Solution):
    """Neumann's problem of :func:`integrate_neumann` behind the Solution protocol: ``sol(t) -> (q, v)``,
    integrated on demand, once per call, over ``[min(t, 0), max(t, 0)]`` (nothing cached)."""

    a: np.ndarray
    q0: np.ndarray
    v0: np.ndarray
    method: str
    invariants: dict = field(repr=False)
    diagnostics: dict = field(default_factory=dict, repr=False)
    settings: Settings = Settings()

    model: ClassVar[str] = "neumann"
    _AT_ONCE = True  # one integration over all requested times

    def _evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        a, q0, rtol, method = self.a, self.q0, self.settings.rtol, self.settings.method
        R = float(np.linalg.norm(q0))
        v0 = self.v0 - q0 * (q0 @ self.v0) / (R * R)
        alpha = float(np.sqrt(np.max(np.abs(np.linalg.eigvalsh(a))))) + float(np.linalg.norm(v0)) / R

        def rhs(_t, y, damping):
            q, v = y[:3], y[3:]
            aq = a @ q
            qq = q @ q
            lam = (q @ aq - v @ v - damping * (q @ v) - 0.5 * alpha ** 2 * (qq - R * R)) / qq
            return np.concatenate([v, -aq + lam * q])

        ts, inv = np.unique(t, return_inverse=True)
        Y = np.tile(np.concatenate([q0, v0]), (ts.size, 1))
        scale = R * (1.0 + alpha)
        for sel in (ts > 0, ts < 0):
            idx = np.flatnonzero(sel)
            if idx.size == 0:
                continue
            backward = ts[idx[0]] < 0
            if backward:
                idx = idx[::-1]
            # damped in the direction of integration (backward in time the damping term changes sign)
            sol = solve_ivp(rhs, (0.0, float(ts[idx[-1]])), Y[0], method=method, t_eval=ts[idx], rtol=rtol,
                            atol=1e-3 * rtol * scale, args=(-2 * alpha if backward else 2 * alpha,))
            if not sol.success:
                raise RuntimeError(f"Neumann integration failed: {sol.message}")
            Y[idx] = sol.y.T
        q, v = Y[:, :3], Y[:, 3:]
        q = q * (R / np.linalg.norm(q, axis=1))[:, None]
        v = v - q * (np.einsum("ti,ti->t", q, v) / (R * R))[:, None]
        return q[inv], v[inv]
