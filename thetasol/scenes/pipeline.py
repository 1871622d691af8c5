"""The split of Theorem 2 (3.1): a whole C^k-central configuration as one Solution.

:func:`solve_configuration` builds, once, every part of the split:

* the system mass centre ``q(t)`` in closed form (:class:`~thetasol.solutions.points.mass_center.MassCenterMotion`);
* one rotation per effective body (2.15), (3.7) in ``1/2 x^T a x`` (3.3), independent of ``q``
  and of each other: ``thetasol.solutions.rotation.dispatch.solve_rotation`` where a closed form exists
  (elliptic functions for ``a = c 1`` and pendulum motions, Neumann's separation for a
  symmetric body without axial spin, theta functions otherwise), else (data it refuses, e.g. a
  symmetric body with little but non-zero axial spin) a
  :class:`~thetasol.integrators.rotation.NumericalRotation`, which runs
  :func:`thetasol.integrate_rotation` on demand at the requested times.  Which one, and why, is
  recorded per body.

With ``constraint=Sphere(R)`` (Section 6, Theorem 3) the mass centre is held on ``|q| = R`` (a rod
on a spherical joint at the origin of the potential ``1/2 q^T a q``): it then moves as C. Neumann's
point, :func:`~thetasol.solutions.points.neumann.solve_neumann` with the same ``a`` (per unit mass: the
rod's force acts on the total mass; near a separatrix, where that closed form is refused,
:func:`~thetasol.integrators.neumann.integrate_neumann`), and the rotations are unchanged (the force is a uniform
acceleration field on the bodies: no torque about any mass centre).

The result, a :class:`ConfigurationSolution`, places every physical body down the tree
(:meth:`Configuration.place`) at any times it is asked for.
"""
from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.inertia import inertia
from thetasol.core.threads import single_blas_thread
from thetasol.integrators.neumann import NumericalNeumann, integrate_neumann
from thetasol.integrators.rotation import integrate_rotation
from thetasol.mechanics.configuration import Configuration, initial_attitudes
from thetasol.mechanics.constraints import Sphere
from thetasol.mechanics.equations import invariants_from_moments as rotation_invariants
from thetasol.mechanics.potential import potential_kind
from thetasol.mechanics.trajectories import Trajectories
from thetasol.protocol import ClosedFormUnavailable, Solution, describe, worst_error
from thetasol.solutions.points.mass_center import MassCenterMotion
from thetasol.solutions.points.neumann import NeumannSolution, solve_neumann

__all__ = ["ConfigurationSolution", "solve_configuration", "rotation_kind", "closed_form_rotation", "effective_rotations",
           "parts_text"]


def rotation_kind(a: ArrayLike) -> str:
    """Which closed form the rotation of a body in ``1/2 x^T a x`` needs (Sections 4 I and II).

    ``"elliptic"`` when ``a`` is isotropic (``a = c 1`` exerts no torque: the Euler top),
    ``"theta (rank-one a, genus-3 nodal curve)"`` for two equal eigenvalues (``a = c 1`` plus a
    rank-one matrix), else ``"theta"`` (the generic genus-4 spectral curve (4.12), Prym variety of
    dimension 3); the kinds of :func:`thetasol.mechanics.potential.potential_kind`.
    """
    kind = potential_kind(V.symmetric_matrix(a, "a"))
    return {"isotropic": "elliptic", "rank-one": "theta (rank-one a, genus-3 nodal curve)"}.get(kind, "theta")


def closed_form_rotation(J: ArrayLike, a: ArrayLike, Q0: ArrayLike, omega0: ArrayLike) -> tuple[Any, str]:
    """``solve_rotation(inertia(J), a, Q0, omega0)`` and ``""``, or ``None`` and the reason it refused the data
    (``J`` the second moments the split of the configuration gives)."""
    # imported here: scenes without a closed-form rotation never load the theta machinery
    from thetasol.solutions.rotation.dispatch import solve_rotation

    try:
        return solve_rotation(inertia(J), a, Q0, omega0), ""
    except NotImplementedError as exc:
        return None, str(exc) or "not implemented"


@dataclass(frozen=True, eq=False)
class ConfigurationSolution(Solution):
    """Every body of a C^k-central configuration, by the split (3.1), at any times.

    A :class:`~thetasol.protocol.Solution` like every other: ``sol(t)`` (alias :meth:`state`) takes
    times of any shape (any order, negative allowed) and returns the state with ``t.shape`` leading
    and the body axis next: ``(q, qdot, position, velocity, attitude, omega)``.  :meth:`trajectories`
    gives the same motion at 1-d times as a :class:`~thetasol.mechanics.trajectories.Trajectories`
    record (the layout of the multibody reference and of the output files).  Each part is evaluated
    once per call (the closed forms in their own chunks; a numerical rotation integrates from 0 to the
    requested times).

    Attributes
    ----------
    config : Configuration
    a, b : ndarray
        Potential (2.4).
    mass_center : MassCenterMotion, NeumannSolution or NumericalNeumann
        The system mass centre (3.2); on the sphere of ``constraint``, Neumann's point (6.1)-(6.2)
        (numerical where its closed form refuses the data).
    rotations : dict name -> Solution
        The rotation of every effective body (3.3), root first: a closed form of
        ``solve_rotation`` or a :class:`~thetasol.integrators.rotation.NumericalRotation`.
    model, method : str
        ``"configuration"`` and ``"split"``; ``diagnostics["parts"]`` says how each part is solved
        (the mass centre's model and method, then ``name=method`` per rotation).
    invariants : dict
        First integrals: ``energy`` (the whole system's, ``M E_q + sum_B E_B``),
        ``mass_center`` (per unit mass, the ``invariants`` of :attr:`mass_center`) and ``rotations``
        (name -> ``energy``, ``I2``, ``I3`` (4.13), ``curve`` (4.12) of each effective body).
    diagnostics : dict
        ``models`` (the mass-centre modes, or the Neumann model on the sphere, and a line per
        rotation), ``rotation_kind``,
        ``rotations`` (name -> ``model``, ``closed_form``, ``reason``, ``setup_seconds``),
        ``mass_center_setup_seconds``, ``mass_center_reason`` (why the mass centre is numerical,
        or ""), ``setup_seconds`` (all set-up), ``parts`` and ``error_estimate`` (the largest of the
        parts').
    constraint : Sphere or None
        The constraint on the system mass centre (Theorem 3), if any.
    """

    model = "configuration"

    config: Configuration
    a: np.ndarray
    b: np.ndarray
    mass_center: MassCenterMotion | NeumannSolution | NumericalNeumann
    rotations: dict
    method: str
    invariants: dict = field(repr=False)
    diagnostics: dict = field(default_factory=dict, repr=False)
    constraint: Sphere | None = None

    @property
    def names(self) -> tuple[str, ...]:
        """Body names, root first (the body axis of the outputs)."""
        return tuple(self.config.order)

    _AT_ONCE = True  # the parts chunk themselves; a numerical rotation integrates once

    def _parts(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, dict, dict, dict, dict]:
        """Mass centre, attitudes, angular velocities, placed bodies and seconds per part at 1-d ``t``."""
        seconds = {}
        start = time.perf_counter()
        q, qd = self.mass_center(t)
        seconds["mass_center"] = time.perf_counter() - start
        Qs, Ws = {}, {}
        for n, rot in self.rotations.items():
            start = time.perf_counter()
            Ws[n], Qs[n] = rot(t)
            seconds[n] = time.perf_counter() - start
        placed = self.config.place(q, qd, Qs, Ws, check_central=False)
        return q, qd, Qs, Ws, placed, seconds

    def _evaluate(self, t: np.ndarray) -> tuple[np.ndarray, ...]:
        q, qd, Qs, Ws, placed, _ = self._parts(t)
        names = self.names
        return (q, qd, np.stack([placed[n]["position"] for n in names], axis=1),
                np.stack([placed[n]["velocity"] for n in names], axis=1),
                np.stack([Qs[n] for n in names], axis=1), np.stack([Ws[n] for n in names], axis=1))

    def __call__(self, t: ArrayLike) -> tuple[np.ndarray, ...]:
        """The state at times ``t`` of any shape, ``t.shape`` leading and the body axis next.

        Returns
        -------
        q, qdot : ndarray, ``t.shape + (3,)``
            System mass centre and its velocity.
        position, velocity : ndarray, ``t.shape + (N, 3)``
            Each body's own mass centre and its velocity, bodies in ``names`` order.
        attitude : ndarray, ``t.shape + (N, 3, 3)``
        omega : ndarray, ``t.shape + (N, 3)``
            Body-frame angular velocities.
        """
        return super().__call__(t)

    def state(self, t: ArrayLike) -> tuple[np.ndarray, ...]:
        """Alias of ``sol(t)``: the state at times of any shape, time first."""
        return self(t)

    def fastest_frequency(self) -> float:
        """The fastest of the parts' frequencies."""
        parts = [self.mass_center, *self.rotations.values()]
        return max((p.fastest_frequency() for p in parts if isinstance(p, Solution)), default=0.0)

    @single_blas_thread
    def trajectories(self, t: ArrayLike) -> Trajectories:
        """:class:`Trajectories` of every body at the 1-d times ``t`` (body axis first, as the multibody
        reference and the output files have them).

        ``info`` holds ``models``, ``rotation_kind``, ``method``, ``parts`` and the seconds per part
        (``mass_center_seconds`` and ``rotations[name]["seconds"]``: set-up plus this
        evaluation; ``evaluation_seconds`` alone).
        """
        tt, _ = self._times(t)
        if tt.ndim != 1 or tt.size == 0:
            raise ValueError(f"t must be a non-empty 1-d array for Trajectories, got shape {tt.shape}; "
                             "sol(t) takes any shape")
        q, qd, Qs, Ws, placed, seconds = self._parts(tt)
        names = self.names
        d = self.diagnostics
        rot_info = {n: {"closed_form": r["closed_form"], "reason": r["reason"],
                        "seconds": r["setup_seconds"] + seconds[n]} for n, r in d["rotations"].items()}
        info = {"models": d["models"], "rotation_kind": d["rotation_kind"], "method": self.method, "parts": d["parts"],
                "rotations": rot_info, "evaluation_seconds": seconds,
                "mass_center_seconds": d["mass_center_setup_seconds"] + seconds["mass_center"]}
        return Trajectories(
            t=tt.copy(), names=names,
            position=np.array([placed[n]["position"] for n in names]),
            velocity=np.array([placed[n]["velocity"] for n in names]),
            attitude=np.array([Qs[n] for n in names]),
            omega=np.array([Ws[n] for n in names]),
            mass_center=q, mass_center_velocity=qd, info=info)


def parts_text(mass_center: Solution | None, rotations: Mapping[str, Solution]) -> str:
    """How each part of a split is solved: the mass centre's model and method (when it is a solution of
    its own), then ``name=method`` per rotation."""
    head = f"{mass_center.model}={describe(mass_center)}; " if mass_center is not None else ""
    return head + ", ".join(f"{n}={describe(r)}" for n, r in rotations.items())


def _check_arguments(config: Configuration, rotation: str, check_central: bool, constraint: Any) -> None:
    if not isinstance(config, Configuration):
        raise ValueError(f"config must be a Configuration, got {type(config).__name__}")
    if constraint is not None and not isinstance(constraint, Sphere):
        raise ValueError(f"constraint must be a Sphere or None, got {type(constraint).__name__}")
    if rotation not in ("auto", "numerical"):
        raise ValueError(f"rotation must be 'auto' or 'numerical', got {rotation!r}")
    if check_central:
        config.check_central()


def effective_rotations(config: Configuration, a: np.ndarray, Qa: np.ndarray, wa: np.ndarray, rotation: str,
                        rtol: float, method: str, kind: str, skip: tuple[str, ...] = ()) -> tuple[dict, dict]:
    """The rotation of every effective body (Theorem 2) but those in ``skip``, and its diagnostics.

    Each body gets its closed form when one applies (``rotation='auto'``), else ``integrate_rotation``;
    the diagnostics give per body the model, the reason a closed form was not used and the set-up seconds.
    """
    sols, diag = {}, {}
    for i, (n, e) in enumerate(config.effective_bodies().items()):
        if n in skip:
            continue
        start = time.perf_counter()
        sol, why = (None, "rotation='numerical'") if rotation == "numerical" else \
            closed_form_rotation(e.J, a, Qa[i], wa[i])
        closed = sol is not None
        if closed:
            model = f"{kind}: closed form {describe(sol)}"
        else:
            sol = integrate_rotation(e.I, a, Qa[i], wa[i], rtol=rtol, method=method)
            model = f"{kind}: numerical fallback (integrate_rotation {method}, rtol={rtol:g})"
        sols[n] = sol
        diag[n] = {"model": model, "closed_form": closed, "reason": why,
                   "setup_seconds": time.perf_counter() - start}
    return sols, diag


def _mass_center(a: np.ndarray, b: np.ndarray, q0: ArrayLike, v0: ArrayLike, constraint: Sphere | None,
                 rtol: float) -> tuple[MassCenterMotion | NeumannSolution | NumericalNeumann, Any, str, float]:
    """The mass-centre solution, its entry in ``models``, why it is numerical ("" if not), its set-up seconds."""
    start = time.perf_counter()
    why = ""
    if constraint is None:
        mc = MassCenterMotion(a, b, q0, v0)
        model = list(zip(mc.eigenvalues.tolist(), mc.kinds, strict=True))
    else:
        _, q0, v0 = constraint.check(b, q0, v0)
        head = f"Neumann's problem on |q| = {constraint.radius:g}: "
        try:
            mc = solve_neumann(a, q0, v0)
            model = head + f"closed form {describe(mc)}"
        except ClosedFormUnavailable as exc:
            why = str(exc)
            mc = integrate_neumann(a, q0, v0, rtol=rtol)
            model = head + f"numerical fallback (integrate_neumann DOP853, rtol={rtol:g})"
    return mc, model, why, time.perf_counter() - start


def _first_integrals(config: Configuration, a: np.ndarray, mc: Any, Qa: np.ndarray,
                     wa: np.ndarray) -> dict:
    rot = {}
    for i, (n, e) in enumerate(config.effective_bodies().items()):
        inv = rotation_invariants(e.J, a, Qa[i], wa[i])
        rot[n] = {"energy": float(inv["energy"]), "I2": float(inv["I2"]), "I3": float(inv["I3"]),
                  "curve": inv["curve"]}
    energy = config.mass * mc.invariants["energy"] + sum(r["energy"] for r in rot.values())
    return {"energy": float(energy), "mass_center": mc.invariants, "rotations": rot}


@single_blas_thread
def solve_configuration(config: Configuration, a: ArrayLike, b: ArrayLike, q0: ArrayLike, v0: ArrayLike,
                        Q0: Mapping[str, ArrayLike], omega0: Mapping[str, ArrayLike], *,
                        rotation: str = "auto", rtol: float = 1e-12, method: str = "DOP853",
                        check_central: bool = True, constraint: Sphere | None = None) -> ConfigurationSolution:
    """Every body of a C^k-central configuration by the split (3.1), as a solution to evaluate.

    Parameters
    ----------
    config : Configuration
        A central tree (else ValueError listing the joints to shift, unless
        ``check_central=False``, which evaluates the same formulas anyway: useful only to show
        that a non-central tree does not split).
    a, b : array_like
        Potential ``phi(x) = 1/2 x^T a x + 1/2 b^T x`` (2.4).
    q0, v0 : array_like (3,)
        System mass centre and its velocity at ``t = 0``.
    Q0 : mapping name -> (3, 3)
        Attitudes (identity where missing).
    omega0 : mapping name -> (3,)
        Body-frame angular velocities (zero where missing).
    rotation : {"auto", "numerical"}
        ``"auto"`` uses ``thetasol.solutions.rotation.dispatch.solve_rotation`` where it has a closed form
        and :func:`~thetasol.integrate_rotation` (on demand) elsewhere; ``"numerical"`` always
        integrates.
    rtol, method : float, str
        Passed to :func:`~thetasol.integrate_rotation` for the numerical rotations.
    constraint : Sphere, optional
        Hold the system mass centre on the sphere ``|q| = constraint.radius`` about the origin
        (Theorem 3): it then moves by :func:`~thetasol.solutions.points.neumann.solve_neumann` with the
        same ``a``; the rotations are unchanged.  Needs ``b = 0``, ``|q0| = radius`` and ``v0``
        tangent, to 1e-12 relative (else ``ValueError``).  Where ``solve_neumann`` builds no closed
        form (near a separatrix) the mass centre is a
        :class:`~thetasol.integrators.neumann.NumericalNeumann` at ``rtol`` and
        ``diagnostics["mass_center_reason"]`` says why.

    Returns
    -------
    ConfigurationSolution
        ``sol(t)`` the state arrays at times of any shape (time first); ``sol.trajectories(t)`` the
        :class:`Trajectories` at 1-d times ``t``.

    Examples
    --------
    >>> from thetasol.mechanics.bodies import Body
    >>> cfg = Configuration([Body(mass=1.0, J=[1.0, 2.0, 3.0], name="solo")])
    >>> sol = solve_configuration(cfg, np.diag([1.0, 2.0, 3.0]), [0, 0, 0], [1, 0, 0], [0, 0, 0],
    ...                           {}, {}, rotation="numerical")
    >>> sol([0.0, 1.0])[2].shape
    (2, 1, 3)
    >>> sol.trajectories([0.0, 1.0]).position.shape
    (1, 2, 3)
    """
    _check_arguments(config, rotation, check_central, constraint)
    a = V.symmetric_matrix(a, "a")
    b = V.vector3(b, "b")
    Qa, wa = initial_attitudes(config, Q0, omega0)
    mc, mc_model, mc_why, mc_seconds = _mass_center(a, b, q0, v0, constraint, rtol)
    kind = rotation_kind(a)
    rots, rot_diag = effective_rotations(config, a, Qa, wa, rotation, rtol, method, kind)
    models = {"mass_center": mc_model, "rotations": {n: r["model"] for n, r in rot_diag.items()}}
    diagnostics = {"models": models, "rotation_kind": kind, "rotations": rot_diag, "mass_center_reason": mc_why,
                   "mass_center_setup_seconds": mc_seconds,
                   "setup_seconds": mc_seconds + sum(r["setup_seconds"] for r in rot_diag.values())}
    diagnostics.update(parts=parts_text(mc, rots), error_estimate=worst_error([mc, *rots.values()]))
    return ConfigurationSolution(config=config, a=a, b=b, mass_center=mc, rotations=rots, method="split",
                                 invariants=_first_integrals(config, a, mc, Qa, wa), diagnostics=diagnostics,
                                 constraint=constraint)
