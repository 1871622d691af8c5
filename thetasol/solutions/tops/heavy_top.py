"""Heavy tops (Section 5): a rigid body turning about a fixed point in uniform gravity, in closed form.

:func:`solve_heavy_top` recognizes the integrable cases in any body frame and returns a
:class:`~thetasol.solutions.tops.heavy_top_base.HeavyTopSolution` (``sol(t) -> (omega, Q)``):

* mass centre at the fixed point, or no gravity: the Euler top, through
  :func:`thetasol.solutions.rotation.dispatch.solve_rotation` with ``a = 0`` (second moments
  ``J = tr(I)/2 1 - I``), still a heavy-top result (:class:`EulerHeavyTopSolution`, case ``"euler"``);
* Lagrange's top, ``I`` symmetric about the axis through the mass centre: the closed form of
  :mod:`thetasol.solutions.tops.lagrange_top` (``method = "elliptic"``);
* Kovalevskaya's top (``I1 = I2 = 2 I3``, centre in the equatorial plane, any body frame): genus-2 theta
  functions, :mod:`thetasol.solutions.tops.kovalevskaya_top` and :mod:`thetasol.solutions.tops.kovalevskaya_attitude`
  (``method = "theta/genus-2"``);
* anything else: :class:`~thetasol.protocol.ClosedFormUnavailable` naming
  :func:`thetasol.integrators.heavy_top.integrate_heavy_top`.

Conventions (:mod:`thetasol.mechanics.heavy_top`): ``I`` the inertia about the fixed point, ``center`` the
mass centre from the fixed point, both in the body frame; ``V = -mass gravity . (Q center)``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core.attitude import uniform_rotation
from thetasol.core.threads import single_blas_thread
from thetasol.mechanics.heavy_top import heavy_top_data, heavy_top_invariants, kovalevskaya_integral
from thetasol.protocol import ROUNDOFF, ClosedFormUnavailable, RotationSolution, quiet_far_times
from thetasol.solutions.rotation.dispatch import solve_rotation
from thetasol.solutions.tops.heavy_top_base import HeavyTopSolution
from thetasol.solutions.tops.lagrange_top import SYMMETRY_RTOL, build_lagrange_top, lagrange_frame, lagrange_state

__all__ = ["solve_heavy_top", "LagrangeTopSolution", "SteadyRotationSolution", "KovalevskayaTopSolution",
           "EulerHeavyTopSolution"]


@dataclass(frozen=True, eq=False)
class LagrangeTopSolution(HeavyTopSolution):
    """Lagrange's top in closed form (:mod:`thetasol.solutions.tops.lagrange_top`)."""

    constants: object = field(default=None, repr=False)

    def _evaluate(self, t):
        return lagrange_state(self.constants, t)


@dataclass(frozen=True, eq=False)
class SteadyRotationSolution(HeavyTopSolution):
    """Rotation about the vertical with the mass centre on it (a sleeping top, or rest)."""

    def _evaluate(self, t):
        return uniform_rotation(self.Q0, self.omega0, t)


@dataclass(frozen=True, eq=False)
class KovalevskayaTopSolution(HeavyTopSolution):
    """Kovalevskaya's top in genus-2 theta functions (:mod:`thetasol.solutions.tops.kovalevskaya_attitude`)."""

    constants: object = field(default=None, repr=False)

    def _evaluate(self, t):
        return self.constants(t)


@dataclass(frozen=True, eq=False)
class EulerHeavyTopSolution(HeavyTopSolution):
    """A heavy top without torque (centre at the pivot, no gravity or no mass): Euler's top, evaluated by
    the free rotation :attr:`rotation` of the same body (second moments ``J = tr(I)/2 1 - I``)."""

    rotation: RotationSolution = field(default=None, repr=False)

    _AT_ONCE = True  # the rotation chunks itself

    def _evaluate(self, t):
        return self.rotation(t)


def _euler(Im, c, Q0m, w0, mass, g):
    """The torque-free top: :func:`solve_rotation` of its inertia, as a heavy-top result."""
    rot = solve_rotation(Im, np.zeros((3, 3)), Q0m, w0)
    inv = {k: float(v) for k, v in heavy_top_invariants(Im, c, mass, g, w0, Q0m).items()}
    diag = {**rot.diagnostics, "case": "euler" + (f"/{rot.case}" if rot.case else "")}
    return EulerHeavyTopSolution(Im, c, mass, g, Q0m, w0, rot.method, inv, diag, rotation=quiet_far_times(rot))


def _kovalevskaya(Im, c, Q0m, w0, mass, g):
    from thetasol.solutions.tops.kovalevskaya_attitude import build_kovalevskaya_top

    try:
        att, diag = build_kovalevskaya_top(Im, c, Q0m, w0, mass, g)
    except (FloatingPointError, RuntimeError, ValueError, np.linalg.LinAlgError) as exc:
        raise ClosedFormUnavailable(f"heavy top: a Kovalevskaya top whose genus-2 construction does not apply "
                                    f"to these data ({exc}); use thetasol.integrators.heavy_top.integrate_heavy_top"
                                    ) from exc
    inv = heavy_top_invariants(Im, c, mass, g, w0, Q0m)
    inv = {"energy": float(inv["energy"]), "vertical_momentum": float(inv["vertical_momentum"]),
           "kovalevskaya_k2": float(kovalevskaya_integral(Im, c, mass, g, w0, Q0m))}
    diag = {**diag, "error_estimate": max(ROUNDOFF, diag["fit_residual"], diag["phase_tail"])}
    return KovalevskayaTopSolution(Im, c, mass, g, Q0m, w0, "theta/genus-2", inv, diag, att)


def _is_kovalevskaya(I, center, rtol=SYMMETRY_RTOL):
    ev = np.linalg.eigvalsh(I)
    scale = ev[-1]
    for k3, (i, j) in ((0, (1, 2)), (2, (0, 1))):
        if abs(ev[i] - ev[j]) <= rtol * scale and abs(ev[i] - 2 * ev[k3]) <= rtol * scale:
            axis = np.linalg.eigh(I)[1][:, k3]
            return abs(axis @ center) <= rtol * np.linalg.norm(center)
    return False


@single_blas_thread
def solve_heavy_top(I: ArrayLike, center: ArrayLike, Q0: ArrayLike, omega0: ArrayLike, *, mass: float = 1.0,
                    gravity: ArrayLike = (0.0, 0.0, -9.81)) -> HeavyTopSolution:
    """Exact motion of a heavy top (Section 5) when a closed form is known.

    Parameters
    ----------
    I : array_like, shape (3,) or (3, 3)
        Inertia about the fixed point in the body frame (principal values or a symmetric tensor).
    center : array_like, shape (3,)
        Mass centre seen from the fixed point, body frame.
    Q0 : array_like, shape (3, 3)
        Initial attitude, body to space.
    omega0 : array_like, shape (3,)
        Initial body angular velocity.
    mass : float
    gravity : array_like, shape (3,)
        Gravity vector in space.

    Returns
    -------
    HeavyTopSolution
        ``sol(t) -> (omega, Q)`` with shapes ``t.shape + (3,)`` and ``t.shape + (3, 3)``; ``model`` is
        ``"heavy-top"`` in every case, the centre at the pivot included.

    Raises
    ------
    ValueError
        Non-finite or wrongly shaped data, an inertia violating the triangle inequalities or not
        positive definite, a non-orthogonal ``Q0``, a negative mass.
    ClosedFormUnavailable
        No integrable case (the message names ``integrate_heavy_top``).

    Examples
    --------
    >>> import numpy as np
    >>> sol = solve_heavy_top([5.0, 5.0, 1.0], [0, 0, 1.0], np.eye(3), [0.3, 0, 50.0], mass=20, gravity=[0, 0, -1])
    >>> sol.model, sol.method
    ('heavy-top', 'elliptic')
    >>> sol(np.array([0.0, 1e6]))[1].shape
    (2, 3, 3)
    """
    Im, c, Q0m, w0, mass, g = heavy_top_data(I, center, Q0, omega0, mass, gravity)
    cn, gn = np.linalg.norm(c), np.linalg.norm(g)
    if cn == 0 or gn == 0 or mass == 0:
        return _euler(Im, c, Q0m, w0, mass, g)
    frame = lagrange_frame(Im, c)
    if frame is None:
        if _is_kovalevskaya(Im, c):
            return _kovalevskaya(Im, c, Q0m, w0, mass, g)
        raise ClosedFormUnavailable("heavy top: not an integrable case (Euler, Lagrange, Kovalevskaya); "
                                    "use thetasol.integrators.heavy_top.integrate_heavy_top")
    inv = {k: float(v) for k, v in heavy_top_invariants(Im, c, mass, g, w0, Q0m).items()}
    up = -g / gn
    axis = Q0m @ (c / cn)
    if abs(axis @ up) == 1.0 and np.all(np.cross(Q0m @ w0, up) == 0):
        # axis exactly vertical, turning about it: no torque ever (the unstable upright one included)
        return SteadyRotationSolution(Im, c, mass, g, Q0m, w0, "elementary", inv,
                                      {"case": "steady", "error_estimate": ROUNDOFF})
    consts, diag = build_lagrange_top(Im, c, Q0m, w0, mass * gn * cn, up)
    diag.update(case="separatrix" if diag["mc"] == 0 else "", error_estimate=max(ROUNDOFF, diag["fit_residual"]))
    return LagrangeTopSolution(Im, c, mass, g, Q0m, w0, "elliptic", inv, diag, consts)
