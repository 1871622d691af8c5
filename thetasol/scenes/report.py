"""The report of a scene: the split solution against the numerical references, in text.

:func:`run` solves a scene by the split (:mod:`thetasol.scenes.pipeline`) and reports the
effective bodies, the model of each part, and the exact parts against numerical references
that do not use them, each with its max deviation, a stated tolerance, the reference's own error
estimate and timings (the references and their error estimates: :mod:`thetasol.scenes.references`):

* the closed-form mass centre against DOP853 (on the sphere of a ``[constraint]`` (Theorem 3)
  Neumann's equation ``qddot = -a q + lambda q``, ``lambda = (q.aq - |qdot|^2) / |q|^2``, and
  ``|q| = R`` along the split);
* each closed-form rotation against :func:`thetasol.integrate_rotation` (80-bit heyoka where installed);
* the whole split against the unsplit multibody system of :mod:`thetasol.integrators.multibody`
  (tolerance ``10 check_rtol (1 + t) (1 + max |x|)``, docs/mechanics.md);
* with a ``[fixed_point]`` (Section 5): the main body's closed form about the pivot against the heavy
  top's integration in a uniform field (``a = 0``), else against
  :func:`thetasol.integrators.fixed_point.integrate_fixed_point` (no mass-centre check, the pivot
  fixes it), and the unsplit system with the pivot as a spherical joint to the ground.

A closed form's tolerance grows with the angle turned over the horizon (:func:`_check`); a check
beyond it says whether the closed form or the reference is off (:class:`~thetasol.scenes.checks.Check`).
Then the drift of the first integrals (4.9), (4.13), (4.12) along each rotation; then when the closed
form pays off: from this run's set-up, evaluation and integration times, the horizon beyond which the
split is cheaper than the multibody integration and each closed-form rotation cheaper than its
reference's integration (at the scene's output density and for one far time), and the accuracy argument.
"""
from __future__ import annotations

import importlib
import time
from collections.abc import Callable
from typing import TextIO

import numpy as np

from thetasol.integrators.fixed_point import fixed_point_energy
from thetasol.integrators.multibody import integrate_multibody
from thetasol.mechanics.equations import invariants_from_moments
from thetasol.mechanics.trajectories import Trajectories
from thetasol.protocol import describe
from thetasol.scenes.checks import Check, ReportText, verdict
from thetasol.scenes.fixed_point import pivoted_body
from thetasol.scenes.format import Scene
from thetasol.scenes.gyrostat_scene import GyrostatScene, run_gyrostat_scene
from thetasol.scenes.orbit_report import run_orbit
from thetasol.scenes.pipeline import ConfigurationSolution, rotation_kind
from thetasol.scenes.references import (
    ANNOUNCE_SECONDS,
    BUDGET_SECONDS,
    PER_RADIAN,
    Part,
    announce_fallbacks,
    horizon_tolerance,
    probe_rate,
    reference,
)

__all__ = ["Check", "run"]


def _fmt(x) -> str:
    x = np.where(np.abs(x) < 5e-7, 0.0, x) + 0.0  # no "-0." in the report
    return np.array2string(x, precision=6, suppress_small=True, floatmode="maxprec", separator=", ")


def _describe_scene(scene: Scene, say: ReportText) -> None:
    cfg, t = scene.config, scene.t
    say(f"scene: {scene.name or '(unnamed)'}" + (f"  -- {scene.description}" if scene.description else ""))
    viol = max((v.relative for v in cfg.violations()), default=0.0)
    say(f"{len(cfg)} bodies, root {cfg.root!r}, C^{cfg.depth}-central (max relative joint offset {viol:.2g}), "
        f"total mass {cfg.mass:.6g}" + ("; joints shifted to central positions" if scene.solver.get("make_central") else ""))
    if scene.constraint is not None:
        say(f"constraint: the system mass centre on the sphere |q| = {scene.constraint.radius:g} about the origin "
            "(Theorem 3, Neumann's problem)")
    if scene.fixed_point is not None:
        _describe_pivot(scene, say)
    say(f"output: {t.size} times in [{t[0]:g}, {t[-1]:g}]")
    say()
    say("effective bodies (2.15), (3.7), in each body's frame:")
    for n, e in cfg.effective_bodies().items():
        parent = cfg.parent(n)
        say(f"  {n}" + (f" (on {parent!r})" if parent else " (root)") + f": mass {e.mass:.6g}, centre {_fmt(e.center)}")
        say(f"      J principal {_fmt(e.principal_moments)}, I principal {_fmt(e.principal_inertia)}")
        say(f"      principal axes (columns) {_fmt(e.axes).replace(chr(10), ' ')}")
    say()


def _describe_pivot(scene: Scene, say: ReportText) -> None:
    """The fixed point and the main effective body about it, (5.1)-(5.3)."""
    p = scene.fixed_point
    pb = pivoted_body(scene.config, p, scene.a, scene.b)
    say(f"fixed point (Section 5): the point {_fmt(p.point)} of the main body {p.body!r} held at {_fmt(p.position)}")
    say(f"  main effective body about it: mass {pb.mass:.6g}, R (5.1) {_fmt(pb.R)}, "
        f"I (5.2) principal {_fmt(np.linalg.eigvalsh(pb.I))}")
    say(f"  potential about the pivot: a as given, b + 2 a x_P = {_fmt(pb.b)}; case: {pb.case}")


def _describe_models(sol: ConfigurationSolution, say: ReportText) -> None:
    say("models:")
    if "pivoted_body" in sol.diagnostics:
        say(f"  mass centre: {sol.diagnostics['models']['mass_center']}")
    elif sol.constraint is not None:
        say(f"  mass centre (6.1)-(6.2): {sol.diagnostics['models']['mass_center']}")
        if sol.diagnostics["mass_center_reason"]:
            say(f"    (no closed form: {sol.diagnostics['mass_center_reason']})")
    else:
        modes = sol.mass_center.describe()
        say(f"  mass centre (3.2): closed form, {modes[0]}")
        for line in modes[1:]:
            say(f"                                  {line}")
    rot = sol.diagnostics["rotations"]
    for n, r in rot.items():
        say(f"  rotation of {n}: {r['model']}")
    for reason in sorted({r["reason"] for r in rot.values() if not r["closed_form"] and r["reason"]}):
        say(f"    (no closed form: {reason})")
    say()


def _check(part: Part, closed: Callable, known: tuple, method: str, t: np.ndarray, closed_seconds: float,
           rate: float | None, note: Callable[[str], None] | None, body: str = "") -> Check:
    """The closed form's state (``known`` at the output times ``t``, else ``closed(times)``, in the order of
    ``part.state0``) against the reference of ``part``; ``body`` names the effective body whose rotation
    about its mass centre this is ("" for other parts).

    The tolerance grows with the angle turned over the checked horizon (:func:`horizon_tolerance`):
    of a rotation at its fastest angular rate, with angular velocities compared at ``max(1, |omega|)``;
    of the mass centre (``rate`` given) at the fastest frequency of the potential, relative to
    ``1 + max |q| + max |qdot|``.
    """
    ref = reference(part, t, note=note)
    mine = known if ref.t is t else closed(ref.t)
    dev = max(float(np.max(np.abs(np.asarray(m) - r))) for m, r in zip(mine, ref.state))
    horizon = float(ref.t[-1])
    if rate is None:
        fastest = float(np.max(np.linalg.norm(ref.state[0], axis=-1)))
        tol = horizon_tolerance(max(1.0, fastest), fastest, horizon)
    else:
        tol = horizon_tolerance(1.0 + max(float(np.max(np.abs(x))) for x in ref.state), rate, horizon)
    what = f"{part.what}: {method} vs {_INTEGRATOR[part.kind]} ({ref.label.split(';')[0]})"
    return Check(what, dev, tol, f"{closed_seconds * 1e3:.1f} ms vs {ref.seconds * 1e3:.1f} ms",
                 body=body, reference_seconds=ref.rate * horizon,
                 reference_error=ref.error, note=ref.note)


_INTEGRATOR = {"rotation": "integrate_rotation", "heavy_top": "integrate_heavy_top",
               "fixed_point": "integrate_fixed_point", "mass_center": "solve_ivp"}


def _reference_checks(scene: Scene, sol: ConfigurationSolution, traj: Trajectories,
                      note: Callable[[str], None] | None) -> list[Check]:
    """The closed-form mass centre and each closed-form rotation against their references."""
    t = scene.t
    if scene.fixed_point is not None:
        return _pivot_checks(scene, sol, traj, note)
    part = Part("mass centre", "mass_center", {"a": scene.a, "b": scene.b, "constraint": scene.constraint},
                (scene.q0, scene.v0))
    kind = "numerical fallback" if sol.diagnostics.get("mass_center_reason") else "closed form"
    rate = float(np.sqrt(np.max(np.abs(np.linalg.eigvalsh(scene.a)))))
    checks = [_check(part, sol.mass_center, (traj.mass_center, traj.mass_center_velocity), kind, t,
                     traj.info["mass_center_seconds"], rate, note)]
    if scene.constraint is not None:
        R = scene.constraint.radius
        gap = float(np.max(np.abs(scene.constraint.residual(traj.mass_center)))) / R
        # the models put the point on the unit sphere to rounding: measured 5.6e-16 (tests/test_constrained_scene.py)
        checks.append(Check(f"mass centre on |q| = {R:g}: max ||q| - R| / R", gap, 1e-13, "-"))
    return checks + _rotation_checks(scene, sol, traj, skip_root=False, note=note)


def _rotation_checks(scene: Scene, sol: ConfigurationSolution, traj: Trajectories, skip_root: bool,
                     note: Callable[[str], None] | None) -> list[Check]:
    """Each closed-form rotation of an effective body about its mass centre against its reference."""
    checks = []
    for i, n in enumerate(traj.names):
        r = traj.info["rotations"][n]
        if not r["closed_form"] or (skip_root and i == 0):
            continue
        e = scene.config.effective_body(n)
        part = Part(f"rotation of {n}", "rotation", {"I": e.I, "a": scene.a}, (scene.omega0[n], scene.Q0[n]))
        checks.append(_check(part, sol.rotations[n], (traj.omega[i], traj.attitude[i]), describe(sol.rotations[n], with_model=True),
                             scene.t, r["seconds"], None, note, body=n))
    return checks


def _pivot_checks(scene: Scene, sol: ConfigurationSolution, traj: Trajectories,
                  note: Callable[[str], None] | None) -> list[Check]:
    """The main body's closed form about the pivot against its reference; the others as usual.

    In a uniform field (``a = 0``) the reference is the heavy top's integration, else the fixed point's (5.3).
    """
    checks, n = [], traj.names[0]
    r = traj.info["rotations"][n]
    if r["closed_form"]:
        pb = sol.diagnostics["pivoted_body"]
        state0 = (scene.omega0[n], scene.Q0[n])
        if pb.case == "a = 0":
            part = Part(f"rotation of {n} about the pivot", "heavy_top",
                        {"I": pb.I, "center": pb.center, "mass": pb.mass, "gravity": -0.5 * pb.b}, state0)
        else:
            part = Part(f"rotation of {n} about the pivot", "fixed_point",
                        {"I": pb.I, "R": pb.R, "a": scene.a, "b": pb.b}, state0)
        checks.append(_check(part, sol.rotations[n], (traj.omega[0], traj.attitude[0]), describe(sol.rotations[n], with_model=True),
                             scene.t, r["seconds"], None, note))
    return checks + _rotation_checks(scene, sol, traj, skip_root=True, note=note)


def _drift(scene: Scene, traj: Trajectories, say: ReportText) -> None:
    say()
    say("first integrals of each effective rotation along the solution (max relative drift):")
    for i, n in enumerate(traj.names):
        if i == 0 and scene.fixed_point is not None:
            pb = pivoted_body(scene.config, scene.fixed_point, scene.a, scene.b)
            E = fixed_point_energy(pb.I, pb.R, scene.a, pb.b, traj.attitude[0], traj.omega[0])
            say(f"  {n} about the pivot: energy (5.3) {float(np.max(np.abs(E - E[0])) / max(abs(E[0]), 1e-300)):.1e}")
            continue
        e = scene.config.effective_body(n)
        inv = invariants_from_moments(e.J, scene.a, traj.attitude[i], traj.omega[i])
        drift = {}
        for k in ("energy", "I2", "I3"):
            x = inv[k]
            drift[k] = float(np.max(np.abs(x - x[0])) / max(abs(x[0]), 1e-300))
        curve = inv["curve"]
        cd = float(np.max(np.abs(curve - curve[0])) / np.max(np.abs(curve[0])))
        say(f"  {n}: energy {drift['energy']:.1e}, I2 {drift['I2']:.1e}, I3 {drift['I3']:.1e}, "
            f"spectral curve (4.12) {cd:.1e}")


#: Fewest times a multibody comparison samples: where the scene's output times are sparser on the checked
#: horizon (a far ``t_end``), the split is evaluated on this many evenly spaced times there instead.
MIN_CHECK_TIMES = 101


def _restricted(traj: Trajectories, tc: np.ndarray) -> Trajectories:
    """The first ``tc.size`` output times of ``traj`` (those are ``tc``)."""
    n = tc.size
    return Trajectories(t=tc, names=traj.names, position=traj.position[:, :n], velocity=traj.velocity[:, :n],
                        attitude=traj.attitude[:, :n], omega=traj.omega[:, :n], mass_center=traj.mass_center[:n],
                        mass_center_velocity=traj.mass_center_velocity[:n])


def _check_times(t: np.ndarray, t_end: float) -> np.ndarray:
    """The scene's output times up to ``t_end``, or :data:`MIN_CHECK_TIMES` even ones when they are fewer."""
    sel = t[t <= t_end]
    return sel if sel.size >= MIN_CHECK_TIMES else np.linspace(0.0, t_end, MIN_CHECK_TIMES)


def _multibody_check(scene: Scene, sol, traj: Trajectories, split_seconds: float, say: ReportText,
                     note: Callable[[str], None] | None = None) -> tuple[Check, float, float] | None:
    """The split against the unsplit multibody integration up to the scene's ``check_t_end``, or up to the
    output time it reaches in :data:`~thetasol.scenes.references.BUDGET_SECONDS` (from a timed probe;
    ``None`` when that is not even the second output time, and the report says why).

    Also returns the multibody integration's seconds and the end time it reached.
    """
    s, t = scene.solver, scene.t
    t_end = min(float(s.get("check_t_end", t[-1])), float(t[-1]))
    pivot = scene.fixed_point

    def unsplit(times):
        return integrate_multibody(scene.config, scene.a, scene.b, scene.q0, scene.v0, scene.Q0, scene.omega0, times,
                                   rtol=s.get("check_rtol", 1e-12),
                                   constraint=scene.constraint if pivot is None else pivot)

    rate = probe_rate(unsplit, t_end)
    cut = ""
    if rate * t_end > BUDGET_SECONDS:
        reach = BUDGET_SECONDS / rate
        cut = (f"checked on t <= {reach:.4g} only: to check_t_end = {t_end:g} it would take about "
               f"{rate * t_end:.2g} s (set check_t_end or --no-check)")
        t_end = reach
    if note is not None and rate * t_end > ANNOUNCE_SECONDS:
        note(f"to t = {t_end:g}, expected about {rate * t_end:.2g} s")
    tc = _check_times(t, t_end)
    say()
    say(f"the split against the unsplit multibody system (maximal coordinates, KKT, t <= {t_end:g}, "
        f"{tc.size} times" + (", the pivot a spherical joint to the ground):" if pivot is not None else "):"))
    mb = unsplit(tc)
    sub = _restricted(traj, tc) if tc.size <= t.size and np.array_equal(tc, t[:tc.size]) else sol.trajectories(tc)
    dv = sub.deviation(mb)
    size = 1.0 + float(np.max(np.abs(sub.position)))
    # The gap is the multibody integrator's error (it falls with check_rtol; docs/mechanics.md):
    # measured <= ~0.3 rtol (1 + t) |x|; a split that does not hold is off by ~ the joint offsets.
    tol = 10.0 * s.get("check_rtol", 1e-12) * (1.0 + t_end) * size
    say(f"  positions {dv['position']:.2e}, velocities {dv['velocity']:.2e}, attitudes {dv['attitude']:.2e}, "
        f"angular velocities {dv['omega']:.2e}")
    say(f"  multibody: {mb.info['nfev']} right-hand sides, max joint gap {mb.info['constraint_residual']:.1e}"
        + (f", max sphere gap ||q| - R| {mb.info['sphere_residual']:.1e}" if scene.constraint is not None else "")
        + (f", max pivot gap {mb.info['pivot_residual']:.1e}" if pivot is not None else ""))
    check = Check("split vs unsplit multibody: positions and attitudes", max(dv["position"], dv["attitude"]), tol,
                  f"split {split_seconds:.2f} s vs multibody {mb.info['seconds']:.2f} s", note=cut)
    say(check.line())
    return check, mb.info["seconds"], t_end


def _load_closed_forms(scene: Scene) -> float:
    """Import the theta-function machinery (and the mpmath it uses) once, if the scene needs it.

    Seconds spent: a one-off cost per process, reported apart from the split's time as the integrators'
    imports are from theirs.
    """
    if rotation_kind(scene.a) == "elliptic":
        return 0.0
    start = time.perf_counter()
    # (the set-up itself does not import sympy)
    for name in ("thetasol.solutions.rotation.dispatch", "thetasol.solutions.rotation.theta_rotation", "mpmath"):
        importlib.import_module(name)
    return time.perf_counter() - start


def _dur(seconds: float) -> str:
    """A duration in s, ms or us, three digits."""
    for unit, scale in (("s", 1.0), ("ms", 1e-3)):
        if seconds >= scale:
            return f"{seconds / scale:.3g} {unit}"
    return f"{seconds * 1e6:.3g} us"


def _break_even(setup: float, per_time: float, rate: float, density: float) -> str:
    """The horizon beyond which ``setup + per_time * density * T`` is below ``rate * T``."""
    gain = rate - per_time * density
    return f"T > {setup / gain:.3g}" if gain > 0 else "never at this output density"


#: The break-even above compares costs only; this line says why equal accuracy moves it further in the closed
#: form's favour (errors depend on the body, so the report names the page its benchmark writes them to).
_ACCURACY = ("accuracy: an integrator's error grows with the horizon and a closed form's stays near its set-up "
             "accuracy (docs/bench_theta_rotation.md); matching it over long horizons "
             "costs an integrator a tighter tolerance or extended precision, so at equal accuracy the closed form "
             "pays off before the horizons above")


def _pays_off(scene: Scene, sol: ConfigurationSolution, traj: Trajectories, ref_seconds: dict,
              multibody: tuple[float, float] | None, say: ReportText) -> None:
    """When the closed form pays off: set-up against horizon and accuracy, from this run's timings."""
    t = scene.t
    span = float(t[-1] - min(t[0], 0.0))
    if span <= 0 or not ref_seconds:
        return
    density = t.size / span
    d, ev = sol.diagnostics, traj.info["evaluation_seconds"]
    say()
    say(f"when the closed form pays off (this run's costs, taken as linear in the horizon T; output at "
        f"{density:.3g} times per unit time):")
    if multibody is not None:
        mb_seconds, mb_end = multibody
        rate, setup = mb_seconds / mb_end, d["setup_seconds"]
        per_time = sum(ev.values()) / t.size
        say(f"  the split against the unsplit multibody integration ({_dur(rate)} per unit time): set-up "
            f"{_dur(setup)}, evaluation {_dur(per_time)} per time: cheaper for "
            f"{_break_even(setup, per_time, rate, density)} (this scene: T = {span:g})")
    say("  each closed-form rotation against its reference's finer integration (its cost per unit time from this "
        "run's probe), for output at this density and for one time at T:")
    for n, ref in ref_seconds.items():
        setup, per_time, rate = d["rotations"][n]["setup_seconds"], ev[n] / t.size, ref / span
        say(f"    {n}: set-up {_dur(setup)}, {_dur(per_time)} per time against {_dur(rate)} per unit time: "
            f"{_break_even(setup, per_time, rate, density)}, one time {_break_even(setup, 0.0, rate, 1.0)}")
    say("  " + _ACCURACY)


def _fallbacks(sol: ConfigurationSolution) -> dict:
    """The split's own numerical integrations (rotations and mass centre where no closed form applies), by name."""
    runs = {f"rotation of {n}": sol.rotations[n] for n, r in sol.diagnostics["rotations"].items()
            if not r["closed_form"]}
    if sol.diagnostics.get("mass_center_reason"):
        runs["mass centre"] = sol.mass_center
    return runs


def _stepper(progress: Callable[[str, int, int], None] | None,
             parts: list[str]) -> tuple[Callable[[], None], Callable[[str], None]]:
    """``step()`` announces the next of ``parts`` as ``progress(label, k, n)`` before part ``k`` of ``n``
    starts, and the call after the last part sends ``progress("done", n, n)``; ``note(text)`` tells
    ``progress`` something about the running part (``"<label>: <text>"``, same ``k``)."""
    current = [-1]

    def step() -> None:
        current[0] += 1
        k = current[0]
        if progress is not None:
            progress(parts[k] if k < len(parts) else "done", k, len(parts))

    def note(text: str) -> None:
        if progress is not None and 0 <= current[0] < len(parts):
            progress(f"{parts[current[0]]}: {text}", current[0], len(parts))
    return step, note


def run(scene: Scene | GyrostatScene, check: bool = True, out: TextIO | None = None,
        progress: Callable[[str, int, int], None] | None = None, *,
        references: bool = True) -> tuple[Trajectories, str, list[Check]]:
    """Solve a scene by the split and compare its exact parts with the numerical references.

    Parameters
    ----------
    scene : Scene
    check : bool
        Also run the unsplit multibody reference (if the scene's ``check_multibody`` allows).
    out : text stream, optional
        Where to print the report as it is produced (besides returning it).
    progress : callable, optional
        ``progress(label, k, n)`` is called as part ``k`` of ``n`` starts (the split solution, the
        numerical references, the multibody reference), with ``"<label>: <detail>"`` while a long
        reference runs (its expected duration, then its segments), and as ``progress("done", n, n)``
        at the end.
    references : bool
        Compare the exact parts with their references (:mod:`thetasol.scenes.references`); with
        ``False`` (and ``check=False``) no integration runs but the split's own numerical fallbacks.

    Returns
    -------
    trajectories : Trajectories
        The split solution on the scene's times.
    report : str
    checks : list of Check
        Every comparison with its tolerance; ``all(c.ok for c in checks)`` is the verdict (an
        inconclusive check is not a failure: its line says why the reference cannot judge).
    """
    if isinstance(scene, GyrostatScene):
        multibody = check and scene.solver.get("check_multibody", True)
        step, note = _stepper(progress, ["split solution"] + (["unsplit multibody reference"] if multibody else []))
        step()
        traj, text, raw = run_gyrostat_scene(scene, check=check, out=out, note=note if progress is not None else None)
        step()
        if multibody:
            step()
        return traj, text, [Check(f"split (Theorem 5) vs unsplit multibody: {w}", d, tl, "-") for w, d, tl in raw]
    if scene.orbit is not None:
        return run_orbit(scene, check=check, out=out, references=references)
    say = ReportText(out)
    multibody = check and scene.solver.get("check_multibody", True)
    step, note = _stepper(progress, ["split solution"] + (["numerical references"] if references else [])
                          + (["unsplit multibody reference"] if multibody else []))
    _describe_scene(scene, say)
    import_seconds = _load_closed_forms(scene)
    step()
    start = time.perf_counter()
    sol = scene.solution()
    setup_seconds = time.perf_counter() - start
    announce_fallbacks(_fallbacks(sol), float(scene.t[-1]), note if progress is not None else None)
    start = time.perf_counter()
    traj = sol.trajectories(scene.t)
    split_seconds = setup_seconds + time.perf_counter() - start
    _describe_models(sol, say)

    checks = []
    if references:
        say("exact parts against the numerical references (max abs deviation):")
        step()
        checks = _reference_checks(scene, sol, traj, note)
        for c in checks:
            say(c.line())
        if not any(r["closed_form"] for r in traj.info["rotations"].values()):
            say("  rotations: no closed form applies to these data; they ARE the numerical reference")
        say(_TOLERANCES)
    else:
        say("exact parts: not checked against numerical references (--no-check)")
    _drift(scene, traj, say)
    mb_cost = None
    if multibody:
        step()
        result = _multibody_check(scene, sol, traj, split_seconds, say, note)
        if result is not None:
            mb_check, *mb_cost = result
            checks.append(mb_check)
    ref_seconds = {c.body: c.reference_seconds for c in checks if c.body and c.reference_seconds is not None}
    _pays_off(scene, sol, traj, ref_seconds, mb_cost, say)
    step()
    say()
    say(f"timings: split solution {split_seconds:.3f} s = set-up {setup_seconds:.3f} s + evaluation "
        f"{split_seconds - setup_seconds:.3f} s at {scene.t.size} times (mass centre "
        f"{traj.info['mass_center_seconds'] * 1e3:.2f} ms; "
        + ", ".join(f"{n} {r['seconds'] * 1e3:.0f} ms" for n, r in traj.info["rotations"].items()) + ")"
        + (f"; one-off imports of the closed-form machinery {import_seconds:.2f} s, not counted" if import_seconds
           else ""))
    say(verdict(checks))
    return traj, say.text(), checks


_TOLERANCES = ("  (each reference is run twice, and the difference of the runs is its own error estimate; a "
               f"tolerance is {PER_RADIAN:g} per radian turned over the horizon, docs/scene_format.md)")
