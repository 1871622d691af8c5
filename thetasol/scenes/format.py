"""Scene files: a configuration in a quadratic potential with its initial state and output times.

A scene (TOML, read with the standard library's :mod:`tomllib`; format in
docs/scene_format.md) gives bodies, joints, the potential (2.4), the initial state and the
output times, and optionally a ``[constraint]`` on the system mass centre (the sphere of
Theorem 3) or a ``[fixed_point]``: a point of the main body held fixed in space (Section 5).  :func:`load_scene` reads and validates one; every error is a ``ValueError``
naming the file and the entry.  Unknown keys are errors: a typo must not change the physics.
"""
from __future__ import annotations

import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from thetasol.core import validate as V
from thetasol.core.so3 import rodrigues
from thetasol.mechanics.bodies import Body
from thetasol.mechanics.configuration import Configuration, Joint
from thetasol.mechanics.constraints import Pivot, Sphere, pivot_mass_center
from thetasol.mechanics.trajectories import Trajectories
from thetasol.scenes.fixed_point import solve_fixed_point
from thetasol.scenes.gyrostat_scene import GyrostatScene, gyrostat_scene_from_dict
from thetasol.scenes.orbit import OrbitEntry, orbit_entry, solve_orbiting_configuration
from thetasol.scenes.pipeline import ConfigurationSolution, solve_configuration
from thetasol.scenes.values import number, numeric_array

__all__ = ["Scene", "load_scene", "demo_scene_path", "with_times"]

_TOP_KEYS = {"name", "description", "bodies", "joints", "potential", "initial", "output", "solver", "constraint",
             "fixed_point", "orbit"}
_BODY_KEYS = {"name", "mass", "J", "I", "center", "box", "masses", "points"}
_JOINT_KEYS = {"parent", "child", "parent_point", "child_point"}
_SOLVER_KEYS = {"rtol", "method", "rotation", "make_central", "check_multibody", "check_t_end", "check_rtol"}
_METHODS = ("DOP853", "RK45", "RK23", "splitting", "heyoka")


@dataclass(frozen=True, eq=False)
class Scene:
    """A configuration in a quadratic potential with its initial state and output times.

    Attributes
    ----------
    config : Configuration
    a, b : ndarray
        Potential (2.4).
    q0, v0 : ndarray (3,)
        System mass centre and velocity at ``t = 0``.
    Q0, omega0 : dict name -> ndarray
        Attitudes and body angular velocities at ``t = 0`` (every body present).
    t : ndarray (T,)
        Output times, increasing, ``>= 0``.
    name, description : str
    solver : dict
        ``rtol``, ``method``, ``rotation``, ``check_multibody``, ``check_t_end``, ``check_rtol``,
        ``make_central``.
    constraint : Sphere or None
        The system mass centre held on a sphere about the origin (Theorem 3), if any.
    fixed_point : Pivot or None
        A point of the main body (the root) held fixed in space (Section 5), if any; ``q0`` and
        ``v0`` are then the ones it implies.
    orbit : OrbitEntry or None
        The ``[orbit]`` (Theorem 4): then ``q0, v0`` are its ``r0, v0``, ``a`` the tidal matrix
        (7.11) at ``t = 0`` and ``b = 0`` (:mod:`thetasol.scenes.orbit`).
    """

    config: Configuration
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
    constraint: Sphere | None = None
    fixed_point: Pivot | None = None
    orbit: OrbitEntry | None = None

    def solution(self, rotation: str | None = None) -> ConfigurationSolution:
        """The split solution with the scene's options: :func:`~thetasol.scenes.pipeline.solve_configuration`,
        or with an ``[orbit]`` :func:`~thetasol.scenes.orbit.solve_orbiting_configuration` (Theorem 4)."""
        s = self.solver
        if self.fixed_point is not None:
            return solve_fixed_point(self.config, self.a, self.b, self.fixed_point, self.Q0, self.omega0,
                                     rotation=rotation or s.get("rotation", "auto"), rtol=s.get("rtol", 1e-12),
                                     method=s.get("method", "DOP853"))
        if self.orbit is not None:
            return solve_orbiting_configuration(self.config, self.orbit.orbit, self.Q0, self.omega0,
                                                rotation=rotation or s.get("rotation", "auto"),
                                                rtol=s.get("rtol", 1e-12), method=s.get("method", "DOP853"))
        return solve_configuration(self.config, self.a, self.b, self.q0, self.v0, self.Q0, self.omega0,
                                   rotation=rotation or s.get("rotation", "auto"), rtol=s.get("rtol", 1e-12),
                                   method=s.get("method", "DOP853"), constraint=self.constraint)

    def solve(self, rotation: str | None = None) -> Trajectories:
        """The split solution on the output times: ``self.solution(rotation).trajectories(self.t)``."""
        return self.solution(rotation).trajectories(self.t)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], source: str = "scene") -> Scene:
        """Build and validate a scene from the parsed TOML table (docs/scene_format.md)."""
        return _scene_from_dict(d, source)


def load_scene(path: str | Path) -> Scene | GyrostatScene:
    """Read and validate a scene file (TOML); a file with ``[[rotors]]`` gives a
    :class:`~thetasol.scenes.gyrostat_scene.GyrostatScene` (Section 8).

    Raises
    ------
    ValueError
        Unreadable or malformed TOML, unknown keys, missing or non-physical data; the
        message names the file and the entry.
    """
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ValueError(f"cannot read scene file {str(path)!r}: {exc.strerror or exc}") from exc
    try:
        d = tomllib.loads(data.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: not UTF-8 text ({exc})") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: malformed TOML: {exc}") from exc
    return _scene_from_dict(d, str(path))


def with_times(scene: Scene | GyrostatScene, t_end: float | None = None,
               samples: int | None = None) -> Scene | GyrostatScene:
    """The scene with ``samples`` equally spaced output times on ``[0, t_end]`` (each defaulting to the scene's
    own number of times and last time); the rest, ``check_t_end`` included, unchanged.

    Raises ``ValueError`` for a ``t_end`` that is not a positive finite number or ``samples`` outside [2, 1e7].
    """
    if t_end is None and samples is None:
        return scene
    t_end = float(scene.t[-1]) if t_end is None else _number(t_end, "t_end", positive=True)
    n = scene.t.size if samples is None else samples
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 2 <= n <= 10**7:
        raise ValueError(f"the number of output times must be an integer in [2, 1e7], got {n!r}")
    return replace(scene, t=np.linspace(0.0, t_end, int(n)))


def demo_scene_path() -> Path:
    """Path of the bundled demo scene (a C^2-central space-station-like configuration)."""
    return Path(__file__).with_name("data") / "station.toml"


# -- values ----------------------------------------------------------------------------------------

def _table(d: Mapping, key: str, required: bool = True) -> dict:
    if key not in d:
        if required:
            raise ValueError(f"missing [{key}]")
        return {}
    v = d[key]
    if not isinstance(v, dict):
        raise ValueError(f"[{key}] must be a table, got {type(v).__name__}")
    return v


def _unknown(d: Mapping, allowed: set, where: str) -> None:
    extra = set(d) - allowed
    if extra:
        raise ValueError(f"{where}: unknown key(s) {sorted(extra)}; allowed: {sorted(allowed)}")


def _number(x: Any, where: str, positive: bool = False) -> float:
    return number(x, where, positive)


def _array(x: Any, where: str, shape: tuple | None = None) -> np.ndarray:
    return numeric_array(x, where, shape)


def _attitude(x: Any, where: str) -> np.ndarray:
    arr = _array(x, where)
    if arr.shape == (3,):
        return rodrigues(arr)
    if arr.shape == (3, 3):
        return V.rotation_matrix(arr, where)
    raise ValueError(f"{where} must be a rotation vector (3 numbers) or a 3x3 matrix, got shape {arr.shape}")


# -- the stages of a scene -------------------------------------------------------------------------

def _body(d: Any, i: int) -> Body:
    where = f"bodies[{i}]"
    if not isinstance(d, dict):
        raise ValueError(f"{where} must be a table")
    _unknown(d, _BODY_KEYS, where)
    name = d.get("name")
    if not isinstance(name, str) or not name:
        raise ValueError(f"{where}: 'name' must be a non-empty string")
    where = f"body {name!r}"
    if "masses" in d or "points" in d:
        if not ({"masses", "points"} <= set(d)) or set(d) & {"mass", "J", "I", "box", "center"}:
            raise ValueError(f"{where}: a point-mass body gives exactly 'masses' and 'points'")
        return Body.from_point_masses(_array(d["masses"], f"{where}: masses"), _array(d["points"], f"{where}: points"),
                                      name=name)
    if "mass" not in d:
        raise ValueError(f"{where}: missing 'mass'")
    mass = _number(d["mass"], f"{where}: mass", positive=True)
    center = _array(d.get("center", [0.0, 0.0, 0.0]), f"{where}: center", (3,))
    given = [k for k in ("J", "I", "box") if k in d]
    if len(given) != 1:
        raise ValueError(f"{where}: give exactly one of 'J' (second moments), 'I' (inertia) or 'box' (edge lengths)")
    k = given[0]
    if k == "box":
        return Body.box(mass, _array(d["box"], f"{where}: box", (3,)), center=center, name=name)
    val = _array(d[k], f"{where}: {k}")
    return Body(mass=mass, center=center, name=name, **{k: val})


def _bodies(d: Mapping) -> dict[str, Body]:
    """The ``[[bodies]]``, by name, in file order."""
    bl = d.get("bodies")
    if not isinstance(bl, list) or not bl:
        raise ValueError("needs at least one [[bodies]] entry")
    bodies = [_body(b, i) for i, b in enumerate(bl)]
    byname = {}
    for b in bodies:
        if b.name in byname:
            raise ValueError(f"duplicate body name {b.name!r}")
        byname[b.name] = b
    return byname


def _joint(j: Any, i: int, byname: Mapping[str, Body]) -> tuple:
    """``(parent, child, parent_point, child_point)``; ``child_point`` may be the string "central"."""
    where = f"joints[{i}]"
    if not isinstance(j, dict):
        raise ValueError(f"{where} must be a table")
    _unknown(j, _JOINT_KEYS, where)
    for k in _JOINT_KEYS:
        if k not in j:
            raise ValueError(f"{where}: missing '{k}'")
    for k in ("parent", "child"):
        if not isinstance(j[k], str):
            raise ValueError(f"{where}: '{k}' must be a body name (string)")
        if j[k] not in byname:
            raise ValueError(f"{where}: unknown {k} {j[k]!r}; bodies are {list(byname)}")
    pp = _array(j["parent_point"], f"{where}: parent_point", (3,))
    cp = j["child_point"]
    if isinstance(cp, str):
        if cp != "central":
            raise ValueError(f"{where}: child_point must be 3 numbers or \"central\", got {cp!r}")
    else:
        cp = _array(cp, f"{where}: child_point", (3,))
    return j["parent"], j["child"], pp, cp


def _configuration(bodies: list[Body], raw_joints: list[tuple], make_central: Any) -> Configuration:
    """The tree, "central" child points filled in, shifted to central if asked, checked central."""
    # "central" child points need the effective bodies: build once with zeros, then fill in.
    joints = [Joint(p, c, pp, np.zeros(3) if isinstance(cp, str) else cp) for p, c, pp, cp in raw_joints]
    config = Configuration(bodies, joints)
    if any(isinstance(cp, str) for *_, cp in raw_joints):
        joints = [Joint(p, c, pp, config.effective_body(c).center if isinstance(cp, str) else cp)
                  for p, c, pp, cp in raw_joints]
        config = Configuration(bodies, joints)
    if not isinstance(make_central, bool):
        raise ValueError("[solver] make_central must be true or false")
    if make_central:
        config = config.make_central()
    config.check_central()
    return config


def _potential(d: Mapping) -> tuple[np.ndarray, np.ndarray]:
    pot = _table(d, "potential")
    _unknown(pot, {"a", "b"}, "[potential]")
    if "a" not in pot:
        raise ValueError("[potential] needs 'a' (3x3 symmetric)")
    a = V.symmetric_matrix(_array(pot["a"], "potential.a", (3, 3)), "potential.a")
    b = _array(pot.get("b", [0.0, 0.0, 0.0]), "potential.b", (3,))
    return a, b


def _initial(d: Mapping, order: list[str]) -> tuple[np.ndarray, np.ndarray, dict, dict]:
    """``q0, v0`` and per-body attitudes and angular velocities (identity and zero where not given)."""
    ini = _table(d, "initial", required=False)
    _unknown(ini, {"q", "v", "attitude", "omega"}, "[initial]")
    q0 = _array(ini.get("q", [0.0, 0.0, 0.0]), "initial.q", (3,))
    v0 = _array(ini.get("v", [0.0, 0.0, 0.0]), "initial.v", (3,))
    Q0, w0 = {}, {}
    for key, dest in (("attitude", Q0), ("omega", w0)):
        tab = ini.get(key, {})
        if not isinstance(tab, dict):
            raise ValueError(f"[initial.{key}] must be a table of body names")
        for n, val in tab.items():
            if n not in order:
                raise ValueError(f"initial.{key} names unknown body {n!r}")
            w = f"initial.{key}.{n}"
            dest[n] = _attitude(val, w) if key == "attitude" else _array(val, w, (3,))
    Q0 = {n: Q0.get(n, np.eye(3)) for n in order}
    w0 = {n: w0.get(n, np.zeros(3)) for n in order}
    return q0, v0, Q0, w0


def _constraint(d: Mapping, b: np.ndarray, q0: np.ndarray, v0: np.ndarray) -> Sphere | None:
    """The ``[constraint]`` (``type = "sphere"``, ``radius``), checked against the potential and ``q0, v0``."""
    if "constraint" not in d:
        return None
    c = _table(d, "constraint")
    _unknown(c, {"type", "radius"}, "[constraint]")
    if c.get("type") != "sphere":
        raise ValueError(f"constraint.type must be \"sphere\", got {c.get('type')!r}")
    if "radius" not in c:
        raise ValueError("[constraint] needs 'radius'")
    sphere = Sphere(_number(c["radius"], "constraint.radius", positive=True))
    try:
        sphere.check(b, q0, v0)
    except ValueError as exc:
        msg = str(exc)
        for name, entry in (("b", "potential.b"), ("q0", "initial.q"), ("v0", "initial.v")):
            msg = msg.replace(f"{name} must", f"{entry} must", 1)
        raise ValueError(f"[constraint] sphere: {msg}") from exc
    return sphere


def _fixed_point(d: Mapping, config: Configuration) -> Pivot | None:
    """The ``[fixed_point]`` (``body``, ``point``, ``position``): a point of the main body fixed in space."""
    if "fixed_point" not in d:
        return None
    f = _table(d, "fixed_point")
    _unknown(f, {"body", "point", "position"}, "[fixed_point]")
    for k in ("body", "point"):
        if k not in f:
            raise ValueError(f"[fixed_point] needs '{k}'")
    body = f["body"]
    if not isinstance(body, str) or body not in config.bodies:
        raise ValueError(f"fixed_point.body: unknown body {body!r}; bodies are {config.order}")
    if body != config.root:
        raise ValueError(f"fixed_point.body {body!r} is not the main body (the root of the joint tree, "
                         f"{config.root!r}): Section 5 fixes a point of the main body, and a pivot in another "
                         f"body ties the rotations on its path to the root together; write the joints with "
                         f"{body!r} as the root")
    if "constraint" in d:
        raise ValueError("[fixed_point] and [constraint] together: with a fixed point the system mass centre "
                         "already stays at the fixed distance |c - r_P| from the pivot, so a sphere either "
                         "repeats that (drop [constraint]) or over-constrains the configuration")
    ini = d.get("initial", {})
    given = [k for k in ("q", "v") if isinstance(ini, dict) and k in ini]
    if given:
        raise ValueError(f"initial.{given[0]}: with [fixed_point] the system mass centre and its velocity follow "
                         "from the pivot and the main body's attitude and angular velocity; omit "
                         + " and ".join(f"initial.{k}" for k in given))
    point = _array(f["point"], "fixed_point.point", (3,))
    position = _array(f.get("position", [0.0, 0.0, 0.0]), "fixed_point.position", (3,))
    return Pivot(body, point, position)


def _output(d: Mapping) -> np.ndarray:
    """The output times: ``times``, or ``samples`` points on ``[0, t_end]``."""
    out = _table(d, "output")
    _unknown(out, {"t_end", "samples", "times"}, "[output]")
    if "times" in out:
        if set(out) & {"t_end", "samples"}:
            raise ValueError("[output] gives either 'times' or 't_end' and 'samples'")
        t = _array(out["times"], "output.times")
        if t.ndim != 1 or t.size == 0:
            raise ValueError("output.times must be a non-empty list of numbers")
    else:
        if "t_end" not in out:
            raise ValueError("[output] needs 't_end' (and optionally 'samples') or 'times'")
        t_end = _number(out["t_end"], "output.t_end", positive=True)
        n = out.get("samples", 201)
        if isinstance(n, bool) or not isinstance(n, int) or not 2 <= n <= 10**7:
            raise ValueError(f"output.samples must be an integer in [2, 1e7], got {n!r}")
        t = np.linspace(0.0, t_end, n)
    if t[0] < 0 or np.any(np.diff(t) <= 0):
        raise ValueError("output times must be >= 0 and strictly increasing")
    return t


def _solver_options(solver: Mapping, t: np.ndarray, make_central: bool) -> dict:
    """The ``[solver]`` options with their defaults."""
    s = {"rtol": 1e-12, "method": "DOP853", "rotation": "auto", "check_multibody": True,
         "check_t_end": float(t[-1]), "check_rtol": 1e-12}
    for k in ("rtol", "check_rtol"):
        if k in solver:
            s[k] = _number(solver[k], f"solver.{k}", positive=True)
            if s[k] >= 1:
                raise ValueError(f"solver.{k} must be below 1")
    if "check_t_end" in solver:
        s["check_t_end"] = _number(solver["check_t_end"], "solver.check_t_end", positive=True)
    if "method" in solver:
        if solver["method"] not in _METHODS:
            raise ValueError("solver.method must be DOP853, RK45, RK23, splitting or heyoka")
        s["method"] = solver["method"]
    if "rotation" in solver:
        if solver["rotation"] not in ("auto", "numerical"):
            raise ValueError("solver.rotation must be 'auto' or 'numerical'")
        s["rotation"] = solver["rotation"]
    if "check_multibody" in solver:
        if not isinstance(solver["check_multibody"], bool):
            raise ValueError("solver.check_multibody must be true or false")
        s["check_multibody"] = solver["check_multibody"]
    s["make_central"] = make_central
    return s


def _scene_from_dict(d: Any, source: str) -> Scene | GyrostatScene:
    if isinstance(d, Mapping) and "rotors" in d:
        # rotors: the split of Theorem 5 (thetasol.scenes.gyrostat_scene)
        return gyrostat_scene_from_dict(d, source)
    try:
        return _build_scene(d)
    except ValueError as exc:
        raise ValueError(f"{source}: {exc}") from exc


def _build_scene(d: Any) -> Scene:
    if not isinstance(d, Mapping):
        raise ValueError("a scene must be a table")
    _unknown(d, _TOP_KEYS, "top level")
    name = d.get("name", "")
    desc = d.get("description", "")
    if not isinstance(name, str) or not isinstance(desc, str):
        raise ValueError("'name' and 'description' must be strings")
    byname = _bodies(d)
    jl = d.get("joints", [])
    if not isinstance(jl, list):
        raise ValueError("'joints' must be an array of tables [[joints]]")
    raw_joints = [_joint(j, i, byname) for i, j in enumerate(jl)]
    solver = dict(_table(d, "solver", required=False))
    _unknown(solver, _SOLVER_KEYS, "[solver]")
    make_central = solver.get("make_central", False)
    config = _configuration(list(byname.values()), raw_joints, make_central)
    orbit = orbit_entry(d)
    a, b = _potential(d) if orbit is None else (orbit.tidal_matrix(), np.zeros(3))
    q0, v0, Q0, w0 = _initial(d, config.order)
    pivot = _fixed_point(d, config)
    if pivot is not None and orbit is not None:
        raise ValueError("scene: [fixed_point] and [orbit] exclude each other (a pivot fixed in space "
                         "cannot follow an orbit)")
    if pivot is not None:
        q0, v0 = pivot_mass_center(pivot, config.effective_body(config.root).center, Q0[config.root],
                                   w0[config.root])
    if orbit is not None:
        q0, v0 = orbit.orbit.r0.copy(), orbit.orbit.v0.copy()
    constraint = _constraint(d, b, q0, v0)
    t = _output(d)
    return Scene(config=config, a=a, b=b, q0=q0, v0=v0, Q0=Q0, omega0=w0, t=t, name=name, description=desc,
                 solver=_solver_options(solver, t, make_central), constraint=constraint, fixed_point=pivot,
                 orbit=orbit)
