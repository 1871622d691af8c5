"""Scene files and the solve pipeline of a C^k-central configuration.

A scene (TOML, read with the standard library's :mod:`tomllib`; format in
docs/scene_format.md) gives bodies, joints, the potential (2.4), the initial state and the
output times.  :func:`solve_configuration` applies Theorem 2 (3.1):

* the system mass centre ``q(t)`` in closed form (:mod:`thetasol.solutions.mass_center`);
* every effective body (2.15), (3.7) rotates independently in ``1/2 x^T a x`` (3.3):
  ``thetasol.solutions.rotation.solve_rotation`` where a closed form exists (elliptic functions for
  ``a = c 1`` and pendulum motions, Neumann's separation for a symmetric body without axial spin,
  theta functions otherwise), else (data it refuses, e.g. a symmetric body with little but non-zero
  axial spin) the numerical reference :func:`thetasol.integrate_rotation`.
  Which one was used, and why, is recorded per body;
* every physical body follows down the tree (:meth:`Configuration.place`).

:func:`run` adds the report: effective bodies, models, and the exact parts against the
numerical references (the mass centre against DOP853, closed-form rotations against
``integrate_rotation``, the whole split against the unsplit multibody system of
:mod:`thetasol.integrators.multibody`) with max deviations and timings.

Output files are written atomically (temporary file in the same directory, then
``os.replace``): an error leaves no partial file behind.
"""
from __future__ import annotations

import io
import os
import tempfile
import time
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np
from scipy.integrate import solve_ivp

from thetasol.core import validate as V
from thetasol.core.so3 import rodrigues
from thetasol.mechanics.bodies import Body
from thetasol.mechanics.configuration import Configuration, Joint, initial_attitudes
from thetasol.mechanics.trajectories import Trajectories, write_trajectories
from thetasol.mechanics.equations import invariants
from thetasol.integrators.rotation import integrate_rotation
from thetasol.solutions.mass_center import MassCenterMotion

__all__ = ["Scene", "load_scene", "solve_configuration", "run", "write_trajectories", "demo_scene_path",
           "rotation_kind"]

# -- the split solution --------------------------------------------------------------------------


def rotation_kind(a) -> str:
    """Which closed form the rotation of a body in ``1/2 x^T a x`` needs (Sections 4 I and II).

    ``"elliptic"`` when ``a`` is isotropic (``a = c 1`` exerts no torque: the Euler top),
    ``"theta (rank-one a, genus-3 nodal curve)"`` for ``a`` of rank one, else ``"theta"``
    (the generic genus-4 spectral curve (4.12), Prym variety of dimension 3).
    """
    a = V.symmetric_matrix(a, "a")
    ev = np.linalg.eigvalsh(a)
    scale = max(np.max(np.abs(ev)), np.finfo(float).tiny)
    if ev[-1] - ev[0] <= 1e-14 * scale:
        return "elliptic"
    if np.sum(np.abs(ev) > 1e-14 * scale) == 1:
        return "theta (rank-one a, genus-3 nodal curve)"
    return "theta"


def _closed_form_rotation(J, a, Q0, w0):
    """``solve_rotation`` result, or None and the reason when no closed form applies to these data."""
    from thetasol.solutions.rotation import solve_rotation  # lazy: the theta machinery is not needed for numerical scenes

    try:
        return solve_rotation(J, a, Q0, w0), ""
    except NotImplementedError as exc:
        return None, str(exc) or "not implemented"


def solve_configuration(config: Configuration, a, b, q0, v0, Q0: Mapping, omega0: Mapping, t,
                        rotation: str = "auto", rtol: float = 1e-12, method: str = "DOP853",
                        check_central: bool = True) -> Trajectories:
    """Trajectories of every body of a C^k-central configuration by the split (3.1).

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
    t : array_like (T,)
        Output times (1-d).
    rotation : {"auto", "numerical"}
        ``"auto"`` uses ``thetasol.solutions.rotation.solve_rotation`` where it has a closed form and
        :func:`~thetasol.integrate_rotation` elsewhere; ``"numerical"`` always integrates.
    rtol, method : float, str
        Passed to :func:`~thetasol.integrate_rotation` for the numerical rotations.

    Returns
    -------
    Trajectories
        ``info["models"]`` names the model of the mass centre (per mode) and of every
        rotation; ``info["rotations"]`` holds per-body seconds.
    """
    if not isinstance(config, Configuration):
        raise ValueError(f"config must be a Configuration, got {type(config).__name__}")
    if rotation not in ("auto", "numerical"):
        raise ValueError(f"rotation must be 'auto' or 'numerical', got {rotation!r}")
    if check_central:
        config.check_central()

    a = V.symmetric_matrix(a, "a")
    b = V.vector3(b, "b")
    tt = V.times(t, "t")
    if tt.ndim != 1 or tt.size == 0:
        raise ValueError(f"t must be a non-empty 1-d array, got shape {tt.shape}")
    Qa, wa = initial_attitudes(config, Q0, omega0)
    start = time.perf_counter()
    mc = MassCenterMotion(a, b, q0, v0)
    q, qd = mc(tt)
    mc_seconds = time.perf_counter() - start
    kind = rotation_kind(a)
    Qs, Ws, rot_models, rot_info = {}, {}, {}, {}
    for i, (n, e) in enumerate(config.effective_bodies().items()):
        start = time.perf_counter()
        sol, why = (None, "rotation='numerical'") if rotation == "numerical" else _closed_form_rotation(e.J, a, Qa[i], wa[i])
        if sol is not None:
            Ws[n], Qs[n] = sol(tt)
            rot_models[n] = f"{kind}: closed form {sol.method}"
        else:
            Ws[n], Qs[n] = integrate_rotation(e.J, a, Qa[i], wa[i], tt, rtol=rtol, method=method)
            rot_models[n] = f"{kind}: numerical fallback (integrate_rotation {method}, rtol={rtol:g})"
        rot_info[n] = {"seconds": time.perf_counter() - start, "closed_form": sol is not None, "reason": why,
                       "solution": sol}
    placed = config.place(q, qd, Qs, Ws, check_central=False)
    names = tuple(config.order)
    info = {"models": {"mass_center": list(zip(mc.eigenvalues.tolist(), mc.kinds)), "rotations": rot_models},
            "rotations": rot_info, "mass_center_seconds": mc_seconds, "mass_center_motion": mc,
            "rotation_kind": kind}
    return Trajectories(
        t=tt.copy(), names=names,
        position=np.array([placed[n]["position"] for n in names]),
        velocity=np.array([placed[n]["velocity"] for n in names]),
        attitude=np.array([Qs[n] for n in names]),
        omega=np.array([Ws[n] for n in names]),
        mass_center=q, mass_center_velocity=qd, info=info)


# -- scenes -----------------------------------------------------------------------------------------

_TOP_KEYS = {"name", "description", "bodies", "joints", "potential", "initial", "output", "solver"}
_BODY_KEYS = {"name", "mass", "J", "I", "center", "box", "masses", "points"}
_JOINT_KEYS = {"parent", "child", "parent_point", "child_point"}
_SOLVER_KEYS = {"rtol", "method", "rotation", "make_central", "check_multibody", "check_t_end", "check_rtol"}


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
        ``rtol``, ``method``, ``rotation``, ``check_multibody``, ``check_t_end``, ``check_rtol``.
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

    def solve(self, rotation: str | None = None) -> Trajectories:
        """The split solution on the output times (:func:`solve_configuration`)."""
        s = self.solver
        return solve_configuration(self.config, self.a, self.b, self.q0, self.v0, self.Q0, self.omega0, self.t,
                                   rotation=rotation or s.get("rotation", "auto"), rtol=s.get("rtol", 1e-12),
                                   method=s.get("method", "DOP853"))

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], source: str = "scene") -> "Scene":
        """Build and validate a scene from the parsed TOML table (docs/scene_format.md)."""
        return _scene_from_dict(d, source)


def load_scene(path) -> Scene:
    """Read and validate a scene file (TOML).

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


def demo_scene_path() -> Path:
    """Path of the bundled demo scene (a C^2-central space-station-like configuration)."""
    return Path(__file__).with_name("data") / "station.toml"


def _table(d, key, required=True):
    if key not in d:
        if required:
            raise ValueError(f"missing [{key}]")
        return {}
    v = d[key]
    if not isinstance(v, dict):
        raise ValueError(f"[{key}] must be a table, got {type(v).__name__}")
    return v


def _unknown(d, allowed, where):
    extra = set(d) - allowed
    if extra:
        raise ValueError(f"{where}: unknown key(s) {sorted(extra)}; allowed: {sorted(allowed)}")


def _number(x, where, positive=False):
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        raise ValueError(f"{where} must be a number, got {x!r}")
    x = float(x)
    if not np.isfinite(x):
        raise ValueError(f"{where} must be finite, got {x!r}")
    if positive and x <= 0:
        raise ValueError(f"{where} must be positive, got {x!r}")
    return x


def _array(x, where, shape=None):
    if isinstance(x, (str, bool, dict)):
        raise ValueError(f"{where} must be numeric, got {x!r}")
    try:
        arr = np.array(x, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where} must be a (nested) list of numbers, got {x!r}") from exc
    return V.finite_array(arr, where, shape)


def _body(d, i):
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


def _attitude(x, where):
    arr = _array(x, where)
    if arr.shape == (3,):
        return rodrigues(arr)
    if arr.shape == (3, 3):
        return V.rotation_matrix(arr, where)
    raise ValueError(f"{where} must be a rotation vector (3 numbers) or a 3x3 matrix, got shape {arr.shape}")


def _scene_from_dict(d, source):
    try:
        return _build_scene(d)
    except ValueError as exc:
        raise ValueError(f"{source}: {exc}") from exc


def _build_scene(d):
    if not isinstance(d, Mapping):
        raise ValueError("a scene must be a table")
    _unknown(d, _TOP_KEYS, "top level")
    name = d.get("name", "")
    desc = d.get("description", "")
    if not isinstance(name, str) or not isinstance(desc, str):
        raise ValueError("'name' and 'description' must be strings")
    bl = d.get("bodies")
    if not isinstance(bl, list) or not bl:
        raise ValueError("needs at least one [[bodies]] entry")
    bodies = [_body(b, i) for i, b in enumerate(bl)]
    byname = {}
    for b in bodies:
        if b.name in byname:
            raise ValueError(f"duplicate body name {b.name!r}")
        byname[b.name] = b
    jl = d.get("joints", [])
    if not isinstance(jl, list):
        raise ValueError("'joints' must be an array of tables [[joints]]")
    raw_joints = []
    for i, j in enumerate(jl):
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
        raw_joints.append((j["parent"], j["child"], pp, cp))
    solver = dict(_table(d, "solver", required=False))
    _unknown(solver, _SOLVER_KEYS, "[solver]")
    # "central" child points need the effective bodies: build once with zeros, then fill in.
    joints = [Joint(p, c, pp, np.zeros(3) if isinstance(cp, str) else cp) for p, c, pp, cp in raw_joints]
    config = Configuration(bodies, joints)
    if any(isinstance(cp, str) for *_, cp in raw_joints):
        joints = [Joint(p, c, pp, config.effective_body(c).center if isinstance(cp, str) else cp)
                  for p, c, pp, cp in raw_joints]
        config = Configuration(bodies, joints)
    make_central = solver.get("make_central", False)
    if not isinstance(make_central, bool):
        raise ValueError("[solver] make_central must be true or false")
    if make_central:
        config = config.make_central()
    config.check_central()

    pot = _table(d, "potential")
    _unknown(pot, {"a", "b"}, "[potential]")
    if "a" not in pot:
        raise ValueError("[potential] needs 'a' (3x3 symmetric)")
    a = V.symmetric_matrix(_array(pot["a"], "potential.a", (3, 3)), "potential.a")
    b = _array(pot.get("b", [0.0, 0.0, 0.0]), "potential.b", (3,))

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
            if n not in byname:
                raise ValueError(f"initial.{key} names unknown body {n!r}")
            w = f"initial.{key}.{n}"
            dest[n] = _attitude(val, w) if key == "attitude" else _array(val, w, (3,))
    Q0 = {n: Q0.get(n, np.eye(3)) for n in config.order}
    w0 = {n: w0.get(n, np.zeros(3)) for n in config.order}

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
        if solver["method"] not in ("DOP853", "RK45", "RK23", "splitting", "heyoka"):
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
    return Scene(config=config, a=a, b=b, q0=q0, v0=v0, Q0=Q0, omega0=w0, t=t, name=name, description=desc,
                 solver=s)


# -- the report ----------------------------------------------------------------------------------------

def _mass_center_numerical(a, b, q0, v0, t):
    def rhs(_t, y):
        return np.concatenate([y[3:], -(a @ y[:3] + 0.5 * b)])

    sol = solve_ivp(rhs, (0.0, float(t[-1])), np.concatenate([q0, v0]), t_eval=t, method="DOP853",
                    rtol=1e-13, atol=1e-15)
    if not sol.success:
        raise RuntimeError(f"mass-centre reference failed: {sol.message}")
    return sol.y[:3].T, sol.y[3:].T


def _fmt(x):
    x = np.where(np.abs(x) < 5e-7, 0.0, x) + 0.0  # no "-0." in the report
    return np.array2string(x, precision=6, suppress_small=True, floatmode="maxprec", separator=", ")


@dataclass
class Check:
    """One comparison of the report: a max deviation against a stated tolerance."""

    what: str
    deviation: float
    tolerance: float
    seconds: str

    @property
    def ok(self) -> bool:
        return bool(self.deviation <= self.tolerance)


def run(scene: Scene, check: bool = True, out=None) -> tuple[Trajectories, str, list[Check]]:
    """Solve a scene by the split and compare its exact parts with the numerical references.

    Parameters
    ----------
    scene : Scene
    check : bool
        Also run the unsplit multibody reference (if the scene's ``check_multibody`` allows).
    out : text stream, optional
        Where to print the report as it is produced (besides returning it).

    Returns
    -------
    trajectories : Trajectories
        The split solution on the scene's times.
    report : str
    checks : list of Check
        Every comparison with its tolerance; ``all(c.ok for c in checks)`` is the verdict.
    """
    buf = io.StringIO()

    def say(line=""):
        buf.write(line + "\n")
        if out is not None:
            print(line, file=out, flush=True)

    cfg, s = scene.config, scene.solver
    t = scene.t
    say(f"scene: {scene.name or '(unnamed)'}" + (f"  -- {scene.description}" if scene.description else ""))
    viol = max((v.relative for v in cfg.violations()), default=0.0)
    say(f"{len(cfg)} bodies, root {cfg.root!r}, C^{cfg.depth}-central (max relative joint offset {viol:.2g}), "
        f"total mass {cfg.mass:.6g}" + ("; joints shifted to central positions" if s.get("make_central") else ""))
    say(f"output: {t.size} times in [{t[0]:g}, {t[-1]:g}]")
    say()
    say("effective bodies (2.15), (3.7), in each body's frame:")
    for n, e in cfg.effective_bodies().items():
        parent = cfg.parent(n)
        say(f"  {n}" + (f" (on {parent!r})" if parent else " (root)") + f": mass {e.mass:.6g}, centre {_fmt(e.center)}")
        say(f"      J principal {_fmt(e.principal_moments)}, I principal {_fmt(e.principal_inertia)}")
        say(f"      principal axes (columns) {_fmt(e.axes).replace(chr(10), ' ')}")
    say()

    start = time.perf_counter()
    traj = scene.solve()
    split_seconds = time.perf_counter() - start
    mc: MassCenterMotion = traj.info["mass_center_motion"]
    say("models:")
    say(f"  mass centre (3.2): closed form, {mc.describe()[0]}")
    for line in mc.describe()[1:]:
        say(f"                                  {line}")
    for n, m in traj.info["models"]["rotations"].items():
        say(f"  rotation of {n}: {m}")
    reasons = {r["reason"] for r in traj.info["rotations"].values() if not r["closed_form"] and r["reason"]}
    for r in sorted(reasons):
        say(f"    (no closed form: {r})")
    say()

    checks: list[Check] = []
    say("exact parts against the numerical references (max abs deviation):")
    start = time.perf_counter()
    qn, vn = _mass_center_numerical(scene.a, scene.b, scene.q0, scene.v0, t)
    ref_seconds = time.perf_counter() - start
    scale = 1.0 + float(np.max(np.abs(qn))) + float(np.max(np.abs(vn)))
    dev = max(float(np.max(np.abs(qn - traj.mass_center))), float(np.max(np.abs(vn - traj.mass_center_velocity))))
    checks.append(Check("mass centre: closed form vs DOP853 (rtol 1e-13)", dev, 1e-9 * scale,
                        f"{traj.info['mass_center_seconds'] * 1e3:.2f} ms vs {ref_seconds * 1e3:.1f} ms"))
    for i, n in enumerate(traj.names):
        r = traj.info["rotations"][n]
        if not r["closed_form"]:
            continue
        e = cfg.effective_body(n)
        start = time.perf_counter()
        wn, Qn = integrate_rotation(e.J, scene.a, scene.Q0[n], scene.omega0[n], t, rtol=1e-13)
        ref_seconds = time.perf_counter() - start
        dev = max(float(np.max(np.abs(Qn - traj.attitude[i]))), float(np.max(np.abs(wn - traj.omega[i]))))
        checks.append(Check(f"rotation of {n}: {r['solution'].method} vs integrate_rotation (DOP853, rtol 1e-13)",
                            dev, 1e-8, f"{r['seconds'] * 1e3:.1f} ms vs {ref_seconds * 1e3:.1f} ms"))
    for c in checks:
        say(f"  {c.what}: {c.deviation:.2e} (tolerance {c.tolerance:.1e}) [{c.seconds}]  {'ok' if c.ok else 'FAILED'}")
    if not any(r["closed_form"] for r in traj.info["rotations"].values()):
        say("  rotations: no closed form applies to these data; they ARE the numerical reference")

    say()
    say("first integrals of each effective rotation along the solution (max relative drift):")
    for i, n in enumerate(traj.names):
        e = cfg.effective_body(n)
        inv = invariants(e.J, scene.a, traj.attitude[i], traj.omega[i])
        drift = {}
        for k in ("energy", "I2", "I3"):
            x = inv[k]
            drift[k] = float(np.max(np.abs(x - x[0])) / max(abs(x[0]), 1e-300))
        curve = inv["curve"]
        cd = float(np.max(np.abs(curve - curve[0])) / np.max(np.abs(curve[0])))
        say(f"  {n}: energy {drift['energy']:.1e}, I2 {drift['I2']:.1e}, I3 {drift['I3']:.1e}, "
            f"spectral curve (4.12) {cd:.1e}")

    if check and s.get("check_multibody", True):
        from thetasol.integrators.multibody import integrate_multibody

        t_end = min(float(s.get("check_t_end", t[-1])), float(t[-1]))
        sel = t <= t_end
        say()
        say(f"the split against the unsplit multibody system (maximal coordinates, KKT, t <= {t_end:g}):")
        mb = integrate_multibody(cfg, scene.a, scene.b, scene.q0, scene.v0, scene.Q0, scene.omega0, t[sel],
                                 rtol=s.get("check_rtol", 1e-12))
        sub = Trajectories(t=t[sel], names=traj.names, position=traj.position[:, sel],
                           velocity=traj.velocity[:, sel], attitude=traj.attitude[:, sel], omega=traj.omega[:, sel],
                           mass_center=traj.mass_center[sel], mass_center_velocity=traj.mass_center_velocity[sel])
        dv = sub.deviation(mb)
        size = 1.0 + float(np.max(np.abs(traj.position[:, sel])))
        # The gap is the multibody integrator's error (it falls with check_rtol; docs/mechanics.md):
        # measured <= ~0.3 rtol (1 + t) |x|; a split that does not hold is off by ~ the joint offsets.
        tol = 10.0 * s.get("check_rtol", 1e-12) * (1.0 + t_end) * size
        say(f"  positions {dv['position']:.2e}, velocities {dv['velocity']:.2e}, attitudes {dv['attitude']:.2e}, "
            f"angular velocities {dv['omega']:.2e}")
        say(f"  multibody: {mb.info['nfev']} right-hand sides, max joint gap {mb.info['constraint_residual']:.1e}")
        checks.append(Check("split vs unsplit multibody: positions and attitudes",
                            max(dv["position"], dv["attitude"]), tol,
                            f"split {split_seconds:.2f} s vs multibody {mb.info['seconds']:.2f} s"))
        c = checks[-1]
        say(f"  {c.what}: {c.deviation:.2e} (tolerance {c.tolerance:.1e}) [{c.seconds}]  {'ok' if c.ok else 'FAILED'}")
    say()
    say(f"timings: split solution {split_seconds:.3f} s (mass centre {traj.info['mass_center_seconds'] * 1e3:.2f} ms; "
        + ", ".join(f"{n} {r['seconds'] * 1e3:.0f} ms" for n, r in traj.info["rotations"].items()) + ")")
    say("verdict: " + ("all checks passed" if all(c.ok for c in checks) else
                       "FAILED: " + "; ".join(c.what for c in checks if not c.ok)))
    return traj, buf.getvalue(), checks


# -- output files ------------------------------------------------------------------------------------



