"""Scenes with rotors (Section 8): coupled gyrostats split by Theorem 5 and checked against the unsplit system.

A scene file with ``[[rotors]]`` entries (docs/gyrostat.md, "Scenes with rotors") describes a CR^n- (or
CU^n-) central :class:`~thetasol.mechanics.rotors.GyrostatConfiguration` in the potential (2.4):

* ``[[bodies]]`` carriers: ``name`` and ``mass`` with ``box``, ``J`` or ``I`` (and ``center``), or
  ``massless = true`` (the cross of a universal joint);
* ``[[rotors]]``: ``name``, ``carrier``, ``axis`` and ``point`` (carrier frame), ``mass`` and either
  ``A`` (axial) and ``B`` (transverse moment of inertia, about the mass centre at ``point``) or ``J``
  (second moments, rotor frame = carrier frame at ``phi = 0``) with ``center``; ``spin`` the initial
  relative rate.  A rotor violating (8.12) is refused with the reason;
* ``[[joints]]``: ``parent`` (a carrier or a rotor), ``child`` (a carrier), ``parent_point``,
  ``child_point`` (3 numbers or ``"central"``);
* ``[potential]``, ``[initial]`` (``q``, ``v``, ``[initial.attitude]``, ``[initial.omega]`` of the
  carriers), ``[output]`` and ``[solver]`` (``rtol``, ``check_multibody``, ``check_rtol``,
  ``check_t_end``) as in docs/scene_format.md.

:func:`solve_gyrostat_configuration` is the split: the system mass centre in closed form, and per
carrier its effective gyrostat (8.17), (8.23) turning by (8.32) with ``N_k`` (8.33): in closed form by
:func:`thetasol.solve_gyrostat` (rotor angles included) when ``a`` is isotropic (free motion), by
:func:`~thetasol.integrators.gyrostat.integrate_gyrostat` otherwise; a carrier without rotors by the
rigid-body rotation of :mod:`thetasol.scenes.pipeline`.  :func:`run_gyrostat_scene` reports it against
:func:`~thetasol.integrators.multibody_rotors.integrate_gyrostat_multibody`.
"""
from __future__ import annotations

import time
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

import numpy as np

from thetasol.core import validate as V
from thetasol.core.inertia import inertia
from thetasol.core.so3 import rodrigues
from thetasol.core.threads import single_blas_thread
from thetasol.integrators.gyrostat import integrate_gyrostat
from thetasol.integrators.multibody_rotors import integrate_gyrostat_multibody, relative_rotor_angles
from thetasol.integrators.rotation import integrate_rotation
from thetasol.mechanics.bodies import Body
from thetasol.mechanics.configuration import Joint
from thetasol.mechanics.rotors import (
    GyrostatConfiguration,
    MasslessCarrier,
    Rotor,
    axis_rotation,
    gyrostat_energy_from_moments,
)
from thetasol.mechanics.trajectories import Trajectories
from thetasol.protocol import Solution, describe, worst_error
from thetasol.scenes.checks import ReportText
from thetasol.scenes.pipeline import closed_form_rotation, parts_text, rotation_kind
from thetasol.scenes.references import announce_fallbacks
from thetasol.scenes.values import number, numeric_array
from thetasol.solutions.gyrostat import solve_gyrostat
from thetasol.solutions.points.mass_center import MassCenterMotion

__all__ = ["GyrostatScene", "GyrostatSplit", "solve_gyrostat_configuration", "gyrostat_scene_from_dict",
           "load_gyrostat_scene", "run_gyrostat_scene"]


# -- the split of Theorem 5 --------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class _Part:
    """One carrier's rotation: ``kind`` ("closed", "numerical", "rigid"), the object, rotor data."""

    kind: str
    sol: Any
    model: str
    axes: np.ndarray
    A: np.ndarray
    p: np.ndarray
    specs: list = field(default_factory=list)

    def __call__(self, t):
        """``(omega, Q, phi, phidot)`` at the 1-d times ``t``."""
        if self.kind == "numerical":
            w, Q, phi = self.sol.evaluate_with_angles(t)
        else:
            w, Q = self.sol(t)
            phi = self.sol.rotor_angles(t) if (self.kind == "closed" and len(self.A)) else np.zeros(t.shape + (0,))
        phidot = (self.p / self.A)[None, :] - w @ self.axes.T
        return w, Q, phi, phidot


@dataclass(frozen=True, eq=False)
class GyrostatSplit(Solution):
    """A CR^n-central configuration by the split of Theorem 5.

    ``sol(t)`` takes times of any shape and returns the state of every body with mass
    (:attr:`GyrostatConfiguration.body_names`) and the rotor angles, time first; :meth:`trajectories`
    gives :class:`Trajectories` at 1-d times, with ``info["rotor_angles"]`` (rotor -> ``phi(t)``) and
    ``info["carrier_attitudes"]`` (massless carriers included).

    Attributes
    ----------
    config : GyrostatConfiguration
    a, b : ndarray
    mass_center : MassCenterMotion
    parts : dict carrier -> the rotation of its effective gyrostat
    model, method : str
        ``"configuration"`` and ``"split"``.
    invariants : dict
        First integrals: ``rotor_momenta`` (carrier -> the conserved ``p_ka`` (8.25)), ``energies``
        (carrier -> (8.34) as a physical energy, :func:`~thetasol.mechanics.rotors.gyrostat_energy`) and
        ``mass_center`` (per unit mass).
    diagnostics : dict
        ``models`` (carrier -> which method turns its effective gyrostat), ``parts`` (Theorem 5's split
        in one line) and ``error_estimate`` (the largest of the parts').
    rtol : float
        Tolerance of the numerical rotations.
    """

    model = "configuration"

    config: GyrostatConfiguration
    a: np.ndarray
    b: np.ndarray
    mass_center: MassCenterMotion
    parts: dict
    method: str
    invariants: dict = field(repr=False)
    diagnostics: dict = field(default_factory=dict, repr=False)
    rtol: float = 1e-12

    @property
    def momenta(self) -> dict:
        """Carrier -> the conserved rotor momenta ``p_ka`` (8.25)."""
        return self.invariants["rotor_momenta"]

    @property
    def models(self) -> dict:
        """Carrier -> the method of its effective gyrostat."""
        return self.diagnostics["models"]

    _AT_ONCE = True   # the parts chunk themselves; a numerical one integrates once

    def evaluate_parts(self, t: np.ndarray) -> tuple[dict, dict, dict, dict]:
        """Per carrier ``omega``, ``Q`` and per rotor ``phi``, ``phidot`` at the flat times ``t``."""
        W, Qs, phi, phid = {}, {}, {}, {}
        for n, part in self.parts.items():
            W[n], Qs[n], ph, phd = part(t)
            for i, r in enumerate(self.config.rotors_of[n]):
                phi[r], phid[r] = ph[..., i], phd[..., i]
        return W, Qs, phi, phid

    def _evaluate(self, t: np.ndarray) -> tuple[np.ndarray, ...]:
        q, qd = self.mass_center(t)
        W, Qs, phi, phid = self.evaluate_parts(t)
        placed = self.config.place(q, qd, Qs, W, phi, phid)
        names = self.config.body_names
        rot = list(self.config.rotors)
        return (q, qd, *(np.stack([placed[n][k] for n in names], axis=1)
                         for k in ("position", "velocity", "attitude", "omega")),
                np.stack([phi[r] for r in rot], axis=1) if rot else np.zeros((t.size, 0)))

    def __call__(self, t: Any) -> tuple[np.ndarray, ...]:
        """``(q, qdot, position, velocity, attitude, omega, rotor_angles)`` at times of any shape: ``t.shape``
        leading, then the body axis (``body_names``) or the rotor axis (``config.rotors`` order)."""
        return super().__call__(t)

    def state(self, t: Any) -> tuple[np.ndarray, ...]:
        """Alias of ``sol(t)``: the state at times of any shape, time first."""
        return self(t)

    def fastest_frequency(self) -> float:
        """The fastest of the parts' frequencies."""
        return max([self.mass_center.fastest_frequency(), *(p.sol.fastest_frequency() for p in self.parts.values())])

    def trajectories(self, t: Any) -> Trajectories:
        """:class:`Trajectories` of every body with mass at the 1-d times ``t`` (body axis first), with
        ``info["rotor_angles"]`` (rotor -> ``phi(t)``) and ``info["carrier_attitudes"]``."""
        tt, _ = self._times(t)
        if tt.ndim != 1 or tt.size == 0:
            raise ValueError(f"t must be a non-empty 1-d array for Trajectories, got shape {tt.shape}; "
                             "sol(t) takes any shape")
        start = time.perf_counter()
        q, qd = self.mass_center(tt)
        W, Qs, phi, phid = self.evaluate_parts(tt)
        placed = self.config.place(q, qd, Qs, W, phi, phid)
        names = tuple(self.config.body_names)
        info = {"models": dict(self.models), "seconds": time.perf_counter() - start,
                "rotor_angles": phi, "carrier_attitudes": Qs, "carrier_omegas": W}
        return Trajectories(t=tt.copy(), names=names, position=np.array([placed[n]["position"] for n in names]),
                            velocity=np.array([placed[n]["velocity"] for n in names]),
                            attitude=np.array([placed[n]["attitude"] for n in names]),
                            omega=np.array([placed[n]["omega"] for n in names]),
                            mass_center=q, mass_center_velocity=qd, info=info)


def _part(e, a, Q0, w0, p, rotation, rtol) -> _Part:
    axes = np.array([r.axis for r in e.rotors]).reshape(-1, 3)
    A = np.array([r.A for r in e.rotors])
    if not e.rotors:
        sol, why = (None, "rotation='numerical'") if rotation == "numerical" else closed_form_rotation(e.J, a, Q0, w0)
        if sol is None:
            sol = integrate_rotation(inertia(e.J), a, Q0, w0, rtol=rtol)
            return _Part("rigid", sol, f"rigid body: numerical (integrate_rotation, rtol={rtol:g}); no closed form: {why}",
                         axes, A, p)
        return _Part("rigid", sol, f"rigid body: closed form {describe(sol)}", axes, A, p)
    specs = e.rotor_specs(p)
    if rotation_kind(a) == "elliptic" and rotation != "numerical":
        sol = solve_gyrostat(e.I_gyro, None, Q0, w0, rotors=specs)
        return _Part("closed", sol, f"gyrostat (8.39): closed form {describe(sol)}", axes, A, p, specs)
    sol = integrate_gyrostat(e.I_gyro, None, Q0, w0, rotors=specs, a=a, rtol=rtol)
    why = ("rotation='numerical'" if rotation == "numerical" else
           "the potential is not isotropic, and Section 8 gives a gyrostat's closed form (8.39) only for a = c 1")
    return _Part("numerical", sol, f"gyrostat (8.32): integrate_gyrostat (DOP853, rtol={rtol:g}); no closed form: {why}",
                 axes, A, p, specs)


@single_blas_thread
def solve_gyrostat_configuration(config: GyrostatConfiguration, a: Any, b: Any, q0: Any, v0: Any,
                                 Q0: Mapping[str, Any], omega0: Mapping[str, Any], *, rotation: str = "auto",
                                 rtol: float = 1e-12) -> GyrostatSplit:
    """The split of Theorem 5 for a CR^n-central configuration (see the module docstring).

    ``Q0``, ``omega0`` give the carriers' attitudes and body rates (identity and zero where missing); the
    rotors start at ``phi = 0`` with their ``spin``.  ``rotation="numerical"`` integrates every
    effective gyrostat (8.32).  Raises ``ValueError`` for a non-central tree.
    """
    if not isinstance(config, GyrostatConfiguration):
        raise ValueError(f"config must be a GyrostatConfiguration, got {type(config).__name__}")
    if rotation not in ("auto", "numerical"):
        raise ValueError(f"rotation must be 'auto' or 'numerical', got {rotation!r}")
    config.check_central()
    a, b = V.symmetric_matrix(a, "a"), V.vector3(b, "b")
    mc = MassCenterMotion(a, b, V.vector3(q0, "q0"), V.vector3(v0, "v0"))
    momenta = config.initial_momenta(omega0)
    parts, models, energies = {}, {}, {}
    for n, e in config.effective_gyrostats().items():
        Q0n = V.rotation_matrix(Q0.get(n, np.eye(3)), f"Q0[{n!r}]")
        w0n = V.vector3(omega0.get(n, np.zeros(3)), f"omega0[{n!r}]")
        parts[n] = _part(e, a, Q0n, w0n, momenta[n], rotation, rtol)
        models[n] = parts[n].model
        energies[n] = float(gyrostat_energy_from_moments(e.J, e.J_gyro, a, Q0n, w0n))
    inv = {"rotor_momenta": momenta, "energies": energies, "mass_center": mc.invariants}
    diag = {"models": models, "parts": "Theorem 5: " + parts_text(mc, {n: p.sol for n, p in parts.items()}),
            "error_estimate": worst_error([mc, *(p.sol for p in parts.values())])}
    return GyrostatSplit(config, a, b, mc, parts, "split", inv, diag, rtol)


# -- scene files ---------------------------------------------------------------------------------------

_TOP = {"name", "description", "bodies", "rotors", "joints", "potential", "initial", "output", "solver"}
_SOLVER = {"rtol", "rotation", "check_multibody", "check_rtol", "check_t_end"}


@dataclass(frozen=True, eq=False)
class GyrostatScene:
    """A scene with rotors: configuration, potential, initial state, output times, solver options."""

    model = "configuration"

    config: GyrostatConfiguration
    a: np.ndarray
    b: np.ndarray
    q0: np.ndarray
    v0: np.ndarray
    Q0: dict
    omega0: dict
    t: np.ndarray
    name: str = ""
    description: str = ""
    solver: dict = field(default_factory=dict)

    def solution(self, rotation: str | None = None) -> GyrostatSplit:
        """The split of Theorem 5 with the scene's options."""
        s = self.solver
        return solve_gyrostat_configuration(self.config, self.a, self.b, self.q0, self.v0, self.Q0, self.omega0,
                                            rotation=rotation or s.get("rotation", "auto"), rtol=s.get("rtol", 1e-12))

    def solve(self, rotation: str | None = None) -> Trajectories:
        """The split on the output times (:meth:`GyrostatSplit.trajectories`)."""
        return self.solution(rotation).trajectories(self.t)


def _arr(x, where, shape=None):
    return numeric_array(x, where, shape)


def _keys(d, allowed, where):
    if not isinstance(d, Mapping):
        raise ValueError(f"{where} must be a table")
    extra = set(d) - allowed
    if extra:
        raise ValueError(f"{where}: unknown key(s) {sorted(extra)}; allowed: {sorted(allowed)}")


def _carrier(d, i):
    _keys(d, {"name", "mass", "J", "I", "center", "box", "massless"}, f"bodies[{i}]")
    name = d.get("name")
    if not isinstance(name, str) or not name:
        raise ValueError(f"bodies[{i}]: 'name' must be a non-empty string")
    if d.get("massless", False) is True:
        if set(d) - {"name", "massless"}:
            raise ValueError(f"body {name!r}: a massless carrier has only 'name' and 'massless'")
        return MasslessCarrier(name)
    if "mass" not in d:
        raise ValueError(f"body {name!r}: missing 'mass' (or massless = true)")
    center = _arr(d.get("center", [0.0, 0.0, 0.0]), f"body {name!r}: center", (3,))
    given = [k for k in ("J", "I", "box") if k in d]
    if len(given) != 1:
        raise ValueError(f"body {name!r}: give exactly one of 'J', 'I' or 'box'")
    k = given[0]
    if k == "box":
        return Body.box(number(d["mass"], f"body {name!r}: mass"), _arr(d["box"], f"body {name!r}: box", (3,)),
                        center=center, name=name)
    return Body(mass=number(d["mass"], f"body {name!r}: mass"), center=center, name=name, **{k: _arr(d[k], f"body {name!r}: {k}")})


def _rotor(d, i):
    _keys(d, {"name", "carrier", "axis", "point", "mass", "A", "B", "J", "center", "spin"}, f"rotors[{i}]")
    for k in ("name", "carrier", "axis", "point", "mass"):
        if k not in d:
            raise ValueError(f"rotors[{i}]: missing '{k}'")
    name, w = d["name"], f"rotor {d['name']!r}"
    axis, point = _arr(d["axis"], f"{w}: axis", (3,)), _arr(d["point"], f"{w}: point", (3,))
    spin = float(_arr(d.get("spin", 0.0), f"{w}: spin", ()))
    if "J" in d:
        if "A" in d or "B" in d:
            raise ValueError(f"{w}: give 'A' and 'B', or 'J' (and 'center'), not both")
        body = Body(mass=number(d["mass"], f"{w}: mass"), J=_arr(d["J"], f"{w}: J"),
                    center=_arr(d.get("center", point), f"{w}: center", (3,)), name=name)
        return Rotor(name, d["carrier"], axis, point, body, spin)
    if "A" not in d or "B" not in d or "center" in d:
        raise ValueError(f"{w}: give 'A' and 'B' (mass centre at 'point'), or 'J' and 'center'")
    return Rotor.symmetric(name, d["carrier"], axis, point, number(d["mass"], f"{w}: mass"), number(d["A"], f"{w}: A"),
                           number(d["B"], f"{w}: B"), spin)


def _config(d) -> GyrostatConfiguration:
    carriers = [_carrier(b, i) for i, b in enumerate(d.get("bodies", []))]
    rotors = [_rotor(r, i) for i, r in enumerate(d.get("rotors", []))]
    raw = []
    for i, j in enumerate(d.get("joints", [])):
        _keys(j, {"parent", "child", "parent_point", "child_point"}, f"joints[{i}]")
        if not {"parent", "child", "parent_point", "child_point"} <= set(j):
            raise ValueError(f"joints[{i}]: needs parent, child, parent_point, child_point")
        cp = j["child_point"]
        if isinstance(cp, str) and cp != "central":
            raise ValueError(f"joints[{i}]: child_point must be 3 numbers or \"central\"")
        raw.append((j["parent"], j["child"], _arr(j["parent_point"], f"joints[{i}]: parent_point", (3,)),
                    cp if isinstance(cp, str) else _arr(cp, f"joints[{i}]: child_point", (3,))))
    gc = GyrostatConfiguration(carriers, rotors, [Joint(p, c, pp, np.zeros(3) if isinstance(cp, str) else cp)
                                                  for p, c, pp, cp in raw])
    if any(isinstance(cp, str) for *_, cp in raw):
        gc = GyrostatConfiguration(carriers, rotors, [
            Joint(p, c, pp, gc.effective_gyrostat(c).center if isinstance(cp, str) else cp) for p, c, pp, cp in raw])
    gc.check_central()
    return gc


def _initial(d, names):
    ini = d.get("initial", {})
    _keys(ini, {"q", "v", "attitude", "omega"}, "[initial]")
    Q0, w0 = {}, {}
    for key, dest in (("attitude", Q0), ("omega", w0)):
        tab = ini.get(key, {})
        _keys(tab, set(names), f"[initial.{key}]")
        for n, val in tab.items():
            x = _arr(val, f"initial.{key}.{n}")
            dest[n] = (rodrigues(x) if x.shape == (3,) else V.rotation_matrix(x, f"initial.{key}.{n}")) \
                if key == "attitude" else V.vector3(x, f"initial.{key}.{n}")
    return (_arr(ini.get("q", [0.0] * 3), "initial.q", (3,)), _arr(ini.get("v", [0.0] * 3), "initial.v", (3,)),
            {n: Q0.get(n, np.eye(3)) for n in names}, {n: w0.get(n, np.zeros(3)) for n in names})


def _times(d):
    out = d.get("output", {})
    _keys(out, {"t_end", "samples", "times"}, "[output]")
    if "times" in out:
        t = _arr(out["times"], "output.times")
    else:
        if "t_end" not in out:
            raise ValueError("[output] needs 't_end' (and 'samples') or 'times'")
        n = out.get("samples", 201)
        if isinstance(n, bool) or not isinstance(n, int) or not 2 <= n <= 10**7:
            raise ValueError(f"output.samples must be an integer in [2, 1e7], got {n!r}")
        t = np.linspace(0.0, number(out["t_end"], "output.t_end", positive=True), n)
    if t.ndim != 1 or t.size == 0 or t[0] < 0 or np.any(np.diff(t) <= 0):
        raise ValueError("output times must be >= 0 and strictly increasing")
    return t


def gyrostat_scene_from_dict(d: Mapping[str, Any], source: str = "scene") -> GyrostatScene:
    """Build and validate a scene with rotors from its parsed TOML table (the module docstring)."""
    try:
        _keys(d, _TOP, "top level")
        gc = _config(d)
        pot = d.get("potential", {})
        _keys(pot, {"a", "b"}, "[potential]")
        a = V.symmetric_matrix(_arr(pot.get("a", np.zeros((3, 3))), "potential.a", (3, 3)), "potential.a")
        b = _arr(pot.get("b", [0.0] * 3), "potential.b", (3,))
        q0, v0, Q0, w0 = _initial(d, list(gc.order))
        t = _times(d)
        solver = d.get("solver", {})
        _keys(solver, _SOLVER, "[solver]")
        solver = {k: number(v, f"solver.{k}", positive=True) if k in ("rtol", "check_rtol", "check_t_end") else v
                  for k, v in solver.items()}
        s = {"rtol": 1e-12, "rotation": "auto", "check_multibody": True, "check_rtol": 1e-13,
             "check_t_end": float(t[-1]), **solver}
        return GyrostatScene(gc, a, b, q0, v0, Q0, w0, t, str(d.get("name", "")), str(d.get("description", "")), s)
    except ValueError as exc:
        raise ValueError(f"{source}: {exc}") from exc


def load_gyrostat_scene(path: str | Path) -> GyrostatScene:
    """Read a scene file with rotors (TOML)."""
    path = Path(path)
    try:
        d = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise ValueError(f"{path}: cannot read the scene: {exc}") from exc
    return gyrostat_scene_from_dict(d, str(path))


# -- the report ------------------------------------------------------------------------------------------

def _describe(scene: GyrostatScene, sol: GyrostatSplit, say) -> None:
    gc = scene.config
    say(f"scene: {scene.name or '(unnamed)'}" + (f"  -- {scene.description}" if scene.description else ""))
    say(f"{len(gc.carriers)} carriers, {len(gc.rotors)} rotors, root {gc.root!r}, CR^n-central, "
        f"total mass {gc.mass:.6g}; {scene.t.size} times in [{scene.t[0]:g}, {scene.t[-1]:g}]")
    say("effective gyrostats (8.17), (8.23) and the constants (8.15)-(8.16), (8.25), (8.33):")
    for n, e in gc.effective_gyrostats().items():
        N = e.N(sol.momenta[n]) if e.rotors else np.zeros(3)
        say(f"  {n}: mass {e.mass:.6g}, centre {np.round(e.center, 6).tolist()}, "
            f"J_gyro eigenvalues {np.round(np.linalg.eigvalsh(e.J_gyro), 6).tolist()}, N {np.round(N, 6).tolist()}")
        for r, p in zip(e.rotors, sol.momenta[n], strict=True):
            say(f"      rotor {r.name}: axis {np.round(r.axis, 6).tolist()}, mass {r.mass:.6g}, A {r.A:.6g}, "
                f"B (8.15) {r.B:.6g}, p {p:.6g}")
        say(f"      model: {sol.models[n]}")


def _rotor_angle_gap(scene: GyrostatScene, traj: Trajectories, mb: Trajectories) -> float:
    """Max difference of the split's rotor angles from the reference's: on a carrier with mass the angle of
    ``Q_carrier^T Q_rotor``; on a massless carrier (absent from the reference) the carrier attitude rebuilt
    from the reference rotor and the split's angle, ``Q_rotor R_l(-phi)``, against the split's carrier."""
    gap, k = 0.0, mb.t.size
    for rn, r in scene.config.rotors.items():
        phi = traj.info["rotor_angles"][rn][:k]
        ir = mb.names.index(rn)
        if isinstance(scene.config.carriers[r.carrier], MasslessCarrier):
            Qc = mb.attitude[ir] @ axis_rotation(r.axis, -phi)
            gap = max(gap, float(np.max(np.abs(Qc - traj.info["carrier_attitudes"][r.carrier][:k]))))
            continue
        ref = relative_rotor_angles(mb.attitude[mb.names.index(r.carrier)], mb.attitude[ir], r.axis)
        gap = max(gap, float(np.max(np.abs(np.angle(np.exp(1j * (phi - ref)))))))
    return gap


def _drift(scene: GyrostatScene, sol: GyrostatSplit, traj: Trajectories, say) -> None:
    """Relative drift of (8.34) of every effective gyrostat along the split, and of (8.40) ``|m + N|^2``
    where the potential is isotropic."""
    say("first integrals along the split (max relative drift): (8.34) energy" +
        ("; (8.40) |m + N|^2" if rotation_kind(scene.a) == "elliptic" else ""))
    for n, e in scene.config.effective_gyrostats().items():
        Q, W = traj.info["carrier_attitudes"][n], traj.info["carrier_omegas"][n]
        E = gyrostat_energy_from_moments(e.J, e.J_gyro, scene.a, Q, W)
        ref = sol.invariants["energies"][n]
        line = f"  {n}: {float(np.max(np.abs(E - ref))) / max(abs(ref), 1e-300):.1e}"
        if rotation_kind(scene.a) == "elliptic":
            h = W @ e.I_gyro + (e.N(sol.momenta[n]) if e.rotors else 0.0)
            h2 = np.sum(h * h, axis=-1)
            line += f", {float(np.max(np.abs(h2 - h2[0]))) / max(h2[0], 1e-300):.1e}"
        say(line)


def run_gyrostat_scene(scene: GyrostatScene, check: bool = True, out: TextIO | None = None,
                       note: Callable[[str], None] | None = None
                       ) -> tuple[Trajectories, str, list[tuple[str, float, float]]]:
    """Solve a scene with rotors by the split and compare it with the unsplit multibody system.

    Returns the split's trajectories, the report text and the checks ``(what, deviation, tolerance)``.
    The tolerance of the comparison is ``10 check_rtol (1 + t_end) (1 + max |x|)``, the reference's
    own error (docs/gyrostat.md).  ``note`` is told how long the carriers integrated numerically will take,
    when long.
    """
    say = ReportText(out)

    start = time.perf_counter()
    sol = scene.solution()
    setup_seconds = time.perf_counter() - start
    announce_fallbacks({f"rotation of {n}": part for n, part in sol.parts.items()
                        if part.kind == "numerical" or "numerical" in part.model},
                       float(scene.t[-1]), note)
    start = time.perf_counter()
    traj = sol.trajectories(scene.t)
    split_seconds = setup_seconds + time.perf_counter() - start
    _describe(scene, sol, say)
    _drift(scene, sol, traj, say)
    checks = []
    s = scene.solver
    if check and s.get("check_multibody", True):
        sel = scene.t <= s.get("check_t_end", scene.t[-1])
        mb = integrate_gyrostat_multibody(scene.config, scene.a, scene.b, scene.q0, scene.v0, scene.Q0,
                                          scene.omega0, scene.t[sel], rtol=s.get("check_rtol", 1e-13))
        size = 1.0 + float(np.max(np.abs(traj.position)))
        tol = 10.0 * s.get("check_rtol", 1e-13) * (1.0 + float(scene.t[sel][-1])) * size
        dp = float(np.max(np.abs(traj.position[:, sel] - mb.position)))
        dq = float(np.max(np.abs(traj.attitude[:, sel] - mb.attitude)))
        da = _rotor_angle_gap(scene, traj, mb)
        checks += [("positions", dp, tol), ("attitudes", dq, tol), ("rotor angles", da, tol)]
        say(f"the split against the unsplit multibody system (rotors on revolute joints, t <= {scene.t[sel][-1]:g}, "
            f"{mb.info['nfev']} right-hand sides, max joint gap {mb.info['constraint_residual']:.1e}):")
        for what, dev, tl in checks:
            say(f"  {what}: {dev:.2e} (tolerance {tl:.1e})  {'ok' if dev <= tl else 'FAILED'}")
        say(f"timings: split {split_seconds:.3f} s, multibody {mb.info['seconds']:.2f} s")
    say("verdict: " + ("all checks passed" if all(d <= t for _, d, t in checks) else "FAILED"))
    return traj, say.text(), checks
