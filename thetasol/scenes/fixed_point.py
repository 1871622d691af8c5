"""Section 5: a C^k-central configuration turning about a point of its main body fixed in space.

The main body ``T_0k`` is the root of the tree; the pivot ``P0`` is a point ``r_P`` of it (its
frame) held at ``x_P`` in space (:class:`~thetasol.mechanics.constraints.Pivot`).  The split (3.8)
``L = L_{T_k} + sum_alpha L_{2 alpha}`` is an identity in ``(q, Q_0, Q_alpha)`` for a central tree,
so the pivot, which ties only ``q`` to ``Q_0`` (``q = x_P + Q_0 (c - r_P)``, ``c`` the mass centre
of the root's effective body), changes ``L_{T_k}`` alone (Corollary 1): every other effective body
turns about its own (now moving) mass centre as in Theorem 2, and the main effective body turns
about the pivot with the Lagrangian (5.3),

    L = 1/2 omega.I_P omega - 1/2 tr(Q^T a Q J_P) - 1/2 b_P.(Q R),

* ``R = m (c - r_P)`` the first moment (5.1) of the effective body about the pivot (``m`` the
  whole mass: the effective root body carries every subtree at its joint);
* ``J_P = J + m (c - r_P)(c - r_P)^T`` its second moments about the pivot (5.2), ``I_P = tr(J_P) - J_P``;
* ``b_P = b + 2 a x_P``: the paper puts the pivot at the origin of space; about a pivot at ``x_P``,
  ``phi(x_P + y) = phi(x_P) + 1/2 y^T a y + 1/2 b_P.y``, so the linear term that matters is twice
  the force per unit mass at the pivot, not ``b``.

The cheapest exact form (Corollaries 2-4), chosen by :func:`main_rotation`:

* ``R = 0`` or ``b_P = 0`` (Corollary 2): the Section 4 problem with ``J_P``, by
  :func:`thetasol.solutions.rotation.dispatch.solve_rotation`;
* ``a`` isotropic (zero included: a uniform field, Corollary 3; ``a = s 1`` exerts no torque): a
  heavy top, :func:`thetasol.solutions.tops.heavy_top.solve_heavy_top` with ``I_P``, centre
  ``c - r_P``, mass ``m`` and gravity ``-b_P / 2`` (Euler, Lagrange, Kovalevskaya);
* otherwise no closed form is known (Corollary 4): the numerical reference
  :func:`thetasol.integrators.fixed_point.integrate_fixed_point`, and the diagnostics say why.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.inertia import inertia_from_moments
from thetasol.core.threads import single_blas_thread
from thetasol.integrators.fixed_point import fixed_point_energy, integrate_fixed_point
from thetasol.mechanics.configuration import Configuration, initial_attitudes
from thetasol.mechanics.constraints import Pivot, pivot_mass_center
from thetasol.mechanics.equations import invariants_from_moments as rotation_invariants
from thetasol.protocol import ClosedFormUnavailable, describe, worst_error
from thetasol.scenes.pipeline import (
    ConfigurationSolution,
    closed_form_rotation,
    effective_rotations,
    parts_text,
    rotation_kind,
)

__all__ = ["PivotedBody", "pivoted_body", "main_rotation", "FixedPointSolution", "solve_fixed_point",
           "ZERO_RTOL"]

#: Relative size below which ``R`` (against the body's size) and ``b_P`` (against ``|b| + 2|a||x_P|``) count as 0.
ZERO_RTOL = 1e-13


@dataclass(frozen=True, eq=False)
class PivotedBody:
    """The main effective body about the pivot, (5.1)-(5.3), in the main body's frame.

    Attributes
    ----------
    name : str
        The main body (the root).
    mass : float
        The whole configuration's mass.
    center : ndarray (3,)
        Mass centre seen from the pivot, ``c - r_P``.
    R : ndarray (3,)
        First moment (5.1), ``mass * center``.
    J, I : ndarray (3, 3)
        Second moments (5.2) and inertia about the pivot.
    b : ndarray (3,)
        Linear term of the potential about the pivot, ``b + 2 a x_P``.
    case : str
        ``"R = 0"``, ``"b = 0"`` (Corollary 2), ``"a = 0"`` or ``"a isotropic"`` (Corollary 3), or
        ``"general"``.
    """

    name: str
    mass: float
    center: np.ndarray
    R: np.ndarray
    J: np.ndarray
    I: np.ndarray
    b: np.ndarray
    case: str


def pivoted_body(config: Configuration, pivot: Pivot, a: ArrayLike, b: ArrayLike) -> PivotedBody:
    """The effective body of ``config``'s root about ``pivot`` and the case of Corollaries 2-3.

    Raises
    ------
    ValueError
        The pivot is not in the root (the main body ``T_0k``; a pivot elsewhere ties the rotations
        on the path to the root together and the split does not hold).
    """
    if not isinstance(pivot, Pivot):
        raise ValueError(f"pivot must be a Pivot, got {type(pivot).__name__}")
    if pivot.body != config.root:
        known = "" if pivot.body in config.bodies else f" (no body of that name; bodies are {config.order})"
        raise ValueError(f"the pivot must be in the main body (the root of the joint tree, {config.root!r}), "
                         f"got {pivot.body!r}{known}")
    a = V.symmetric_matrix(a, "a")
    b = V.vector3(b, "b")
    e = config.effective_body(config.root)
    d = e.center - pivot.point
    J = e.J + e.mass * np.outer(d, d)
    J = 0.5 * (J + J.T)
    bP = b + 2.0 * (a @ pivot.position)
    size = max(float(np.sqrt(np.trace(e.J) / e.mass)), float(np.linalg.norm(e.center)),
               float(np.linalg.norm(pivot.point)))
    bscale = float(np.linalg.norm(b)) + 2.0 * float(np.linalg.norm(a, 2)) * float(np.linalg.norm(pivot.position))
    if np.linalg.norm(d) <= ZERO_RTOL * size:
        case = "R = 0"
    elif np.linalg.norm(bP) <= ZERO_RTOL * bscale:
        case = "b = 0"
    elif rotation_kind(a) == "elliptic":
        case = "a = 0" if not np.any(a) else "a isotropic"
    else:
        case = "general"
    return PivotedBody(name=config.root, mass=e.mass, center=d, R=e.mass * d, J=J, I=inertia_from_moments(J),
                       b=bP, case=case)


def _heavy_top(pb: PivotedBody, Q0: np.ndarray, w0: np.ndarray) -> Any:
    from thetasol.solutions.tops.heavy_top import solve_heavy_top  # loads the elliptic and theta machinery

    return solve_heavy_top(pb.I, pb.center, Q0, w0, mass=pb.mass, gravity=-0.5 * pb.b)


def main_rotation(pb: PivotedBody, a: np.ndarray, Q0: np.ndarray, omega0: np.ndarray, *, rotation: str = "auto",
                  rtol: float = 1e-12, method: str = "DOP853") -> tuple[Any, str, bool, str]:
    """The rotation of the main effective body about the pivot in its cheapest exact form.

    Returns
    -------
    sol, model, closed_form, reason
        ``sol(t) -> (omega, Q)``; ``model`` the report's line; ``reason`` why the rotation is
        numerical ("" when it is a closed form).
    """
    why = "rotation='numerical'" if rotation == "numerical" else ""
    sol, head = None, ""
    if pb.case in ("R = 0", "b = 0"):
        head = f"Corollary 2 ({pb.case} about the pivot): Section 4 with J about the pivot"
        if not why:
            sol, why = closed_form_rotation(pb.J, a, Q0, omega0)
    elif pb.case in ("a = 0", "a isotropic"):
        head = f"Corollary 3 ({pb.case}: a uniform field about the pivot): heavy top"
        if not why:
            try:
                sol = _heavy_top(pb, Q0, omega0)
            except ClosedFormUnavailable as exc:
                why = str(exc)
    else:
        head = "Corollary 4 (a and b about the pivot both act, R != 0)"
        why = why or ("no closed form is known for a body about a fixed point in a quadratic potential with a "
                      "linear part (a not isotropic, b + 2 a x_P != 0, mass centre off the pivot)")
    if sol is not None:
        return sol, f"{head}: closed form {describe(sol)}", True, ""
    sol = integrate_fixed_point(pb.I, pb.R, a, pb.b, Q0, omega0, rtol=rtol, method=method)
    return sol, f"{head}: numerical (integrate_fixed_point {method}, rtol={rtol:g})", False, why


@dataclass(frozen=True, eq=False)
class FixedPointSolution(ConfigurationSolution):
    """Every body of a C^k-central configuration turning about a fixed point of its main body.

    As :class:`~thetasol.scenes.pipeline.ConfigurationSolution`, with ``mass_center`` the
    :class:`PivotedBody` (the system mass centre is ``x_P + Q_root (c - r_P)``, not a motion of its
    own) and ``pivot`` the :class:`~thetasol.mechanics.constraints.Pivot`.
    """

    pivot: Pivot | None = field(default=None)

    def _parts(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, dict, dict, dict, dict]:
        seconds, Qs, Ws = {}, {}, {}
        for n, rot in self.rotations.items():
            start = time.perf_counter()
            Ws[n], Qs[n] = rot(t)
            seconds[n] = time.perf_counter() - start
        start = time.perf_counter()
        root = self.config.root
        q, qd = pivot_mass_center(self.pivot, self.config.effective_body(root).center, Qs[root], Ws[root])
        seconds["mass_center"] = time.perf_counter() - start
        placed = self.config.place(q, qd, Qs, Ws, check_central=False)
        return q, qd, Qs, Ws, placed, seconds


def _invariants(config: Configuration, pb: PivotedBody, a: np.ndarray, b: np.ndarray, pivot: Pivot,
                Qa: np.ndarray, wa: np.ndarray) -> dict:
    rot = {config.root: {"energy": float(fixed_point_energy(pb.I, pb.R, a, pb.b, Qa[0], wa[0]))}}
    for i, (n, e) in enumerate(list(config.effective_bodies().items())[1:], start=1):
        inv = rotation_invariants(e.J, a, Qa[i], wa[i])
        rot[n] = {"energy": float(inv["energy"]), "I2": float(inv["I2"]), "I3": float(inv["I3"]),
                  "curve": inv["curve"]}
    x = pivot.position
    at_pivot = 0.5 * x @ a @ x + 0.5 * b @ x
    return {"energy": float(config.mass * at_pivot + sum(r["energy"] for r in rot.values())),
            "mass_center": {}, "rotations": rot}


@single_blas_thread
def solve_fixed_point(config: Configuration, a: ArrayLike, b: ArrayLike, pivot: Pivot,
                      Q0: dict, omega0: dict, *, rotation: str = "auto", rtol: float = 1e-12,
                      method: str = "DOP853", check_central: bool = True) -> FixedPointSolution:
    """Every body of a C^k-central configuration about a fixed point of its main body (Section 5).

    Parameters
    ----------
    config : Configuration
        A central tree whose root (the main body ``T_0k``) carries the pivot.
    a, b : array_like
        Potential ``phi(x) = 1/2 x^T a x + 1/2 b^T x`` (2.4), ``x`` from the origin of space.
    pivot : Pivot
        The point of the root held fixed in space.
    Q0, omega0 : mapping name -> array
        Attitudes and body angular velocities (identity and zero where missing).
    rotation : {"auto", "numerical"}
        ``"auto"``: the main body by :func:`main_rotation`, the others by ``solve_rotation`` where
        it has a closed form; ``"numerical"``: everything integrated.
    rtol, method : float, str
        Of the numerical rotations.

    Returns
    -------
    FixedPointSolution
        ``diagnostics`` as for ``solve_configuration`` plus ``pivoted_body`` (the
        :class:`PivotedBody`); ``models["mass_center"]`` says how ``q`` follows from the pivot.
    """
    if not isinstance(config, Configuration):
        raise ValueError(f"config must be a Configuration, got {type(config).__name__}")
    if rotation not in ("auto", "numerical"):
        raise ValueError(f"rotation must be 'auto' or 'numerical', got {rotation!r}")
    if check_central:
        config.check_central()
    a = V.symmetric_matrix(a, "a")
    b = V.vector3(b, "b")
    pb = pivoted_body(config, pivot, a, b)
    Qa, wa = initial_attitudes(config, Q0, omega0)
    kind = rotation_kind(a)
    start = time.perf_counter()
    root_sol, model, closed, why = main_rotation(pb, a, Qa[0], wa[0], rotation=rotation, rtol=rtol, method=method)
    rots = {config.root: root_sol}
    rot_diag = {config.root: {"model": model, "closed_form": closed, "reason": why,
                              "setup_seconds": time.perf_counter() - start}}
    # Corollary 1: the other effective bodies turn as in Theorem 2
    others, other_diag = effective_rotations(config, a, Qa, wa, rotation, rtol, method, kind,
                                             skip=(next(iter(config.effective_bodies())),))
    rots.update(others)
    rot_diag.update(other_diag)
    models = {"mass_center": "fixed by the pivot: q = x_P + Q (c - r_P), Q the main body's attitude",
              "rotations": {n: r["model"] for n, r in rot_diag.items()}}
    diagnostics = {"models": models, "rotation_kind": kind, "rotations": rot_diag, "mass_center_reason": "",
                   "mass_center_setup_seconds": 0.0, "pivoted_body": pb,
                   "setup_seconds": sum(r["setup_seconds"] for r in rot_diag.values())}
    diagnostics.update(parts="about a fixed point: " + parts_text(None, rots), error_estimate=worst_error(rots.values()))
    return FixedPointSolution(config=config, a=a, b=b, mass_center=pb, rotations=rots, method="split",
                              invariants=_invariants(config, pb, a, b, pivot, Qa, wa), diagnostics=diagnostics,
                              constraint=None, pivot=pivot)
