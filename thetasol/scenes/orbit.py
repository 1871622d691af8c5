"""The ``[orbit]`` entry of scene files: a C^k-central station on a Kepler orbit, split by Theorem 4.

With ``[orbit]`` (``mu``, and the system mass centre's ``r0``, ``v0`` relative to the attracting
centre) a scene has no ``[potential]``: the field is ``-mu / |x|``, and Theorem 4 splits the motion
(to the order of (7.4)) into

* the system mass centre on the Kepler orbit (7.7), :class:`~thetasol.solutions.orbit.kepler.KeplerOrbit`
  (closed form, every conic);
* one rotation per effective body (7.10) in the tidal field (7.11) of that orbit, independent of the
  others: :func:`~thetasol.solutions.orbit.orbiting_rotation.solve_orbiting_rotation` where a closed form
  applies (relative equilibria and planar pitch motions on a circular orbit, spherical bodies), else
  :func:`~thetasol.integrators.orbiting_rotation.integrate_orbiting_rotation` on demand;

and every body is placed from these down the tree (:meth:`Configuration.place`).  On a circular
orbit each effective body also gets the linear stability of the orbit-aligned attitude nearest its
initial one (:func:`station_stability`).

The bodies' point-mass models (given ``masses``/``points``, 27 Gauss points of a ``box``, six points
otherwise: :mod:`thetasol.integrators.multibody_gravity`) are kept for the report's unsplit check in
the exact ``1/r`` field.
"""
from __future__ import annotations

import itertools
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core.inertia import inertia
from thetasol.core.threads import single_blas_thread
from thetasol.integrators.multibody_gravity import box_mass_points
from thetasol.integrators.orbiting_rotation import integrate_orbiting_rotation
from thetasol.mechanics.configuration import Configuration, initial_attitudes
from thetasol.mechanics.gravity_gradient import (
    GravityGradientStability,
    gravity_gradient_stability_from_moments,
    orbit_frame,
)
from thetasol.protocol import ClosedFormUnavailable, describe, worst_error
from thetasol.scenes.pipeline import ConfigurationSolution, parts_text
from thetasol.scenes.values import numeric_array
from thetasol.solutions.orbit.kepler import KeplerOrbit
from thetasol.solutions.orbit.orbiting_rotation import solve_orbiting_rotation

__all__ = ["OrbitEntry", "orbit_entry", "BodyStability", "station_stability", "OrbitingConfigurationSolution",
           "solve_orbiting_configuration"]

_ORBIT_KEYS = {"mu", "r0", "v0"}
_CIRCULAR_E = 1e-13


def _tidal_matrix(mu: float, r: np.ndarray) -> np.ndarray:
    rn = float(np.linalg.norm(r))
    return -3.0 * mu / rn ** 3 * np.outer(r, r) / rn ** 2


@dataclass(frozen=True, eq=False)
class OrbitEntry:
    """The ``[orbit]`` of a scene: the Kepler orbit of the system mass centre and the bodies' point masses.

    Attributes
    ----------
    orbit : KeplerOrbit
        ``KeplerOrbit(mu, r0, v0)``.
    points : dict name -> (masses, points)
        Body-frame point masses of the bodies given as ``masses``/``points`` or ``box``; the
        others are modelled by :func:`~thetasol.integrators.multibody_gravity.mass_points`.
    """

    orbit: KeplerOrbit
    points: dict = field(default_factory=dict)

    @property
    def mu(self) -> float:
        return self.orbit.mu

    def tidal_matrix(self) -> np.ndarray:
        """(7.11) at ``t = 0``: ``-3 mu g g^T / |r0|^3``."""
        return _tidal_matrix(self.orbit.mu, self.orbit.r0)


def _vec(x: Any, where: str) -> np.ndarray:
    return numeric_array(x, where, (3,))


def _body_points(raw_bodies: list) -> dict:
    pts = {}
    for b in raw_bodies:
        if "masses" in b:
            pts[b["name"]] = (np.array(b["masses"], dtype=float), np.array(b["points"], dtype=float))
        elif "box" in b:
            pts[b["name"]] = box_mass_points(float(b["mass"]), b["box"], b.get("center", (0.0, 0.0, 0.0)))
    return pts


def orbit_entry(d: Mapping) -> OrbitEntry | None:
    """The ``[orbit]`` of a parsed scene table (after its bodies were validated), or None without one.

    Raises ``ValueError`` for unknown keys, a missing or non-positive ``mu``, a radial orbit,
    ``solver.method = "splitting"``, and entries that contradict it: ``[potential]``, ``[constraint]``, ``initial.q`` or ``initial.v``
    (the orbit gives the system mass centre's state; one source of truth).
    """
    if "orbit" not in d:
        return None
    o = d["orbit"]
    if not isinstance(o, dict):
        raise ValueError(f"[orbit] must be a table, got {type(o).__name__}")
    extra = set(o) - _ORBIT_KEYS
    if extra:
        raise ValueError(f"[orbit]: unknown key(s) {sorted(extra)}; allowed: {sorted(_ORBIT_KEYS)}")
    for k in sorted(_ORBIT_KEYS):
        if k not in o:
            raise ValueError(f"[orbit] needs '{k}'")
    for clash in ("potential", "constraint"):
        if clash in d:
            raise ValueError(f"[orbit] and [{clash}] exclude each other: the field of an orbit is -mu/|x|")
    solver = d.get("solver", {})
    if isinstance(solver, dict) and solver.get("method") == "splitting":
        raise ValueError("solver.method = \"splitting\" is not offered on an orbit (the torque depends on time "
                         "through the orbit): use DOP853, RK45, RK23 or heyoka")
    ini = d.get("initial", {})
    if isinstance(ini, dict) and set(ini) & {"q", "v"}:
        raise ValueError("with [orbit], the system mass centre's state is orbit.r0 and orbit.v0: "
                         "remove initial.q and initial.v")
    mu = o["mu"]
    if isinstance(mu, bool) or not isinstance(mu, (int, float)) or not np.isfinite(mu) or mu <= 0:
        raise ValueError(f"orbit.mu must be a positive number, got {mu!r}")
    try:
        orbit = KeplerOrbit(float(mu), _vec(o["r0"], "orbit.r0"), _vec(o["v0"], "orbit.v0"))
    except ValueError as exc:
        raise ValueError(f"[orbit]: {exc}") from exc
    return OrbitEntry(orbit=orbit, points=_body_points(d["bodies"]))


@dataclass(frozen=True)
class BodyStability:
    """Linear stability of one effective body at the orbit-aligned attitude nearest its initial one.

    Attributes
    ----------
    alignment : ndarray (3, 3)
        Body-frame principal axes (columns) along radial, along-track, normal at that attitude.
    angle : float
        Rotation angle (rad) from that attitude to the initial one.
    stability : GravityGradientStability
    lagrange_alignment : ndarray (3, 3)
        The axes of the Lagrange (energy-minimum) attitude: least inertia radial, greatest normal.
    """

    alignment: np.ndarray
    angle: float
    stability: GravityGradientStability
    lagrange_alignment: np.ndarray


def _nearest_alignment(F: np.ndarray, Qb: np.ndarray, axes: np.ndarray) -> tuple[np.ndarray, float]:
    """Signed permutation ``B0`` of the principal ``axes`` nearest ``F`` (``Q B0 ~ F``) and the angle between."""
    C = F.T @ Qb @ axes                                     # C[k, j] = cos(orbit axis k, principal axis j)
    perm = max(itertools.permutations(range(3)), key=lambda p: sum(abs(C[k, p[k]]) for k in range(3)))
    B0 = axes[:, list(perm)] * np.sign([C[k, perm[k]] or 1.0 for k in range(3)])
    if np.linalg.det(B0) < 0:
        B0[:, 2] = -B0[:, 2]
    R = F.T @ Qb @ B0
    angle = float(np.arccos(np.clip(0.5 * (np.trace(R) - 1.0), -1.0, 1.0)))
    return B0, angle


def station_stability(config: Configuration, orbit: KeplerOrbit, Q0: Mapping[str, ArrayLike]) -> dict[str, BodyStability]:
    """Per effective body, the linear stability of the orbit-aligned attitude nearest ``Q0`` (circular orbits)."""
    d = orbit.diagnostics
    if d["kind"] != "elliptic" or d["e"] > _CIRCULAR_E:
        return {}
    n = d["mean_motion"]
    F = orbit_frame(orbit.r0, orbit.v0)
    Qa, _ = initial_attitudes(config, Q0, {})
    out = {}
    for i, (name, e) in enumerate(config.effective_bodies().items()):
        B0, angle = _nearest_alignment(F, Qa[i], e.axes)
        Jal = np.maximum(np.diag(B0.T @ e.J @ B0), 0.0)    # a flat body's zero moment may round below 0
        lag = e.axes[:, [2, 1, 0]].copy()                   # J descending: I ascending radial -> normal
        if np.linalg.det(lag) < 0:
            lag[:, 2] = -lag[:, 2]
        out[name] = BodyStability(alignment=B0, angle=angle, stability=gravity_gradient_stability_from_moments(Jal, n),
                                  lagrange_alignment=lag)
    return out


@dataclass(frozen=True, eq=False)
class OrbitingConfigurationSolution(ConfigurationSolution):
    """A C^k-central station on a Kepler orbit, split by Theorem 4 (module docstring).

    As :class:`~thetasol.scenes.pipeline.ConfigurationSolution` (``sol(t)`` the state at any shape of
    ``t``, ``sol.trajectories(t)`` -> Trajectories), with ``mass_center`` the :class:`KeplerOrbit`, ``a`` the tidal
    matrix (7.11) at ``t = 0`` and ``b = 0``.  ``invariants``: ``orbit`` (Kepler's first integrals)
    and ``rotations`` (name -> the rotation's first integrals: the Jacobi integral (7.18) on a
    circular orbit).  ``stability``: name -> :class:`BodyStability` (empty unless circular).
    """

    orbit: KeplerOrbit = field(default=None, repr=False)
    stability: dict = field(default_factory=dict, repr=False)


def _orbiting_rotation(J, orbit, Q0, w0, rotation, rtol, method):
    """(solution, closed?, reason) of one effective body."""
    if rotation != "numerical":
        try:
            return solve_orbiting_rotation(inertia(J), orbit, Q0, w0), True, ""
        except ClosedFormUnavailable as exc:
            why = str(exc)
    else:
        why = "rotation='numerical'"
    return integrate_orbiting_rotation(inertia(J), orbit, Q0, w0, rtol=rtol, method=method), False, why


@single_blas_thread
def solve_orbiting_configuration(config: Configuration, orbit: KeplerOrbit, Q0: Mapping[str, ArrayLike],
                                 omega0: Mapping[str, ArrayLike], *, rotation: str = "auto", rtol: float = 1e-12,
                                 method: str = "DOP853") -> OrbitingConfigurationSolution:
    """Every body of a C^k-central station whose mass centre follows ``orbit`` (Theorem 4).

    Parameters
    ----------
    config : Configuration
        A central tree (else ``ValueError``).
    orbit : KeplerOrbit
        The system mass centre's orbit (its ``r0, v0`` are the mass centre's state at ``t = 0``).
    Q0, omega0 : mapping name -> (3, 3), (3,)
        Attitudes and body-frame angular velocities (identity, zero where missing).
    rotation : {"auto", "numerical"}
        ``"auto"``: the closed forms of ``solve_orbiting_rotation`` where they apply, else
        ``integrate_orbiting_rotation``; ``"numerical"``: always integrate.
    rtol, method
        Of the numerical rotations.

    Returns
    -------
    OrbitingConfigurationSolution
    """
    if not isinstance(config, Configuration):
        raise ValueError(f"config must be a Configuration, got {type(config).__name__}")
    if not isinstance(orbit, KeplerOrbit):
        raise ValueError(f"orbit must be a KeplerOrbit, got {type(orbit).__name__}")
    if rotation not in ("auto", "numerical"):
        raise ValueError(f"rotation must be 'auto' or 'numerical', got {rotation!r}")
    config.check_central()
    Qa, wa = initial_attitudes(config, Q0, omega0)
    d = orbit.diagnostics
    mc_model = f"Kepler orbit (7.7): closed form (universal variables), {d['kind']}, e = {d['e']:.3g}"
    sols, rot_diag = {}, {}
    for i, (n, e) in enumerate(config.effective_bodies().items()):
        start = time.perf_counter()
        sol, closed, why = _orbiting_rotation(e.J, orbit, Qa[i], wa[i], rotation, rtol, method)
        model = (f"gravity gradient (7.11): closed form {describe(sol)}" if closed else
                 f"gravity gradient (7.11): numerical (integrate_orbiting_rotation {method}, rtol={rtol:g})")
        sols[n] = sol
        rot_diag[n] = {"model": model, "closed_form": closed, "reason": why,
                       "setup_seconds": time.perf_counter() - start}
    diagnostics = {"models": {"mass_center": mc_model, "rotations": {n: r["model"] for n, r in rot_diag.items()}},
                   "rotation_kind": "gravity gradient (7.11), time-dependent", "rotations": rot_diag,
                   "mass_center_reason": "", "mass_center_setup_seconds": 0.0,
                   "setup_seconds": sum(r["setup_seconds"] for r in rot_diag.values())}
    diagnostics.update(parts="Theorem 4: " + parts_text(orbit, sols), error_estimate=worst_error([orbit, *sols.values()]))
    invariants = {"orbit": orbit.invariants, "rotations": {n: s.invariants for n, s in sols.items()}}
    return OrbitingConfigurationSolution(
        config=config, a=_tidal_matrix(orbit.mu, orbit.r0), b=np.zeros(3), mass_center=orbit, rotations=sols,
        method="split", invariants=invariants, diagnostics=diagnostics, orbit=orbit,
        stability=station_stability(config, orbit, dict(zip(config.order, Qa, strict=True))))
