"""The numerical references of a scene's checks: one integration per exact part, with its own error estimated.

:func:`reference` is the one place where a scene's checks call the integrators.  A closed form can
only be judged against a reference whose own error over the horizon is known to be smaller, so every
reference is run twice and the difference of the two runs is its error estimate:

* a rotation about the mass centre (in a fixed potential or on an orbit), and a heavy top about a
  pivot in a uniform field (``a = 0``):
  heyoka's Taylor integrator in 80-bit precision (``np.longdouble``) at tolerance 1e-19 where
  heyoka is installed (the ``test`` and ``bench`` extras bring it), checked against the same
  integration in float64 at tolerance 1e-15;
* otherwise (no heyoka, a body about a pivot in a non-uniform field, the mass centre, an orbit):
  DOP853 at rtol 1e-13, checked against DOP853 at rtol 1e-11.

The difference of the two runs is mostly the coarser run's error, so it over-estimates the finer
run's: a verdict built on it blames the closed form only when the difference from the reference
exceeds the tolerance by more than the reference's own error (:class:`~thetasol.scenes.checks.Check`).

Long horizons: before integrating, a short timed probe of each run is extrapolated linearly to the
horizon.  An expected cost above :data:`ANNOUNCE_SECONDS` is announced (through ``note``) and the
integration runs in segments, each announced as it ends; a reference that would take longer than
:data:`BUDGET_SECONDS` is run only up to the time it reaches in that budget, and the check says so.
"""
from __future__ import annotations

import importlib.util
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from thetasol.integrators.fixed_point import integrate_fixed_point
from thetasol.integrators.heavy_top import integrate_heavy_top
from thetasol.integrators.orbiting_rotation import integrate_orbiting_rotation
from thetasol.integrators.rotation import integrate_rotation

__all__ = ["Part", "Reference", "reference", "horizon_tolerance", "probe_rate", "announce_fallbacks", "ANNOUNCE_SECONDS",
           "BUDGET_SECONDS", "PER_RADIAN"]

#: Expected seconds of a reference above which the command line is told how long it will take.
ANNOUNCE_SECONDS = 2.0
#: Seconds one reference may take: a longer one checks the horizon it reaches in that time (a reference of
#: hours would hold back the report of a solution computed in milliseconds).
BUDGET_SECONDS = 30.0
#: Wall time of the timed probe that measures a run's cost per unit time (long enough to be timed
#: to a few per cent, short beside the run it predicts).
PROBE_SECONDS = 0.05
#: The closed forms' error budget per radian of motion: an exact solution in float64 drifts in phase by
#: the rounding of its frequencies times the angle turned; 1e-11 per radian allows a conditioning of the
#: frequencies of about 4.5e4 (1e-11 / eps), beside a fixed 1e-11 for the set-up.
PER_RADIAN = 1e-11


def horizon_tolerance(scale: float, rate: float, horizon: float) -> float:
    """``PER_RADIAN * scale * (1 + rate * horizon)``: the tolerance of a closed form over ``[0, horizon]``.

    ``rate`` is the fastest angular rate (or frequency) of the motion, so ``rate * horizon`` is the
    angle turned; ``scale`` the size of the compared quantities (1 for attitudes; ``max(1, |omega|)``
    when angular velocities are compared too).
    """
    return PER_RADIAN * scale * (1.0 + rate * horizon)


@dataclass(frozen=True, eq=False)
class Part:
    """One exact part of a scene, as the references integrate it.

    Attributes
    ----------
    what : str
        Its name in the report (``"rotation of cap"``).
    kind : str
        ``"rotation"`` (``I``, ``a``), ``"orbiting_rotation"`` (``I``, ``orbit``), ``"heavy_top"`` (``I``,
        ``center``, ``mass``, ``gravity``), ``"fixed_point"`` (``I``, ``R``, ``a``, ``b``), ``"mass_center"``
        (``a``, ``b``, ``constraint``) or ``"kepler"`` (``mu``).
    data : dict
        The model's data, by those names.
    state0 : tuple of ndarray
        The state at ``t = 0``: ``(omega0, Q0)``, or ``(q0, v0)`` for the mass centre and an orbit.
    """

    what: str
    kind: str
    data: dict
    state0: tuple


@dataclass(frozen=True, eq=False)
class Reference:
    """A reference run on the checked times, with its own error estimate.

    Attributes
    ----------
    t : ndarray
        The checked times: the output times, or up to where the budget reached (see ``note``).
    state : tuple of ndarray
        The finer run's state there, time first.
    error : float
        Max abs difference of the two runs over ``t``: the reference's own error estimate.
    label : str
        Which integrations (``"heyoka 80-bit, tol 1e-19"``) and how the error was estimated.
    seconds : float
        Wall time of both runs, probe included.
    rate : float
        Seconds per unit time of the finer run alone, from the probe (model compilation excluded).
    note : str
        Why fewer times were checked than the scene's, or "".
    """

    t: np.ndarray
    state: tuple
    error: float
    label: str
    seconds: float
    rate: float = 0.0
    note: str = ""


def _heyoka_installed() -> bool:
    """heyoka can be imported, and ``np.longdouble`` is wider than float64 here (80-bit on x86; on platforms
    where it is float64 the extended-precision reference would not be one)."""
    extended = np.finfo(np.longdouble).eps < np.finfo(float).eps
    return extended and importlib.util.find_spec("heyoka") is not None


def _runs(kind: str) -> tuple[dict, dict, str]:
    """The finer and the coarser run of a part's reference, and the label of the pair."""
    if kind in ("rotation", "orbiting_rotation", "heavy_top") and _heyoka_installed():
        return ({"method": "heyoka", "fp_type": np.longdouble, "rtol": 1e-19}, {"method": "heyoka", "rtol": 1e-15},
                "heyoka 80-bit, tol 1e-19; its error: the difference from float64 heyoka at tol 1e-15")
    return ({"method": "DOP853", "rtol": 1e-13}, {"method": "DOP853", "rtol": 1e-11},
            "DOP853, rtol 1e-13; its error: the difference from rtol 1e-11")


def _mass_center(a, b, constraint, q0, v0, t, rtol) -> tuple[np.ndarray, np.ndarray]:
    """The mass centre (3.2) in ``1/2 q.aq + 1/2 b.q``, or on the sphere of ``constraint`` Neumann's
    equation ``qddot = -a q + lambda q``, ``lambda = (q.aq - |qdot|^2) / |q|^2``, by DOP853."""
    def rhs(_t, y):
        return np.concatenate([y[3:], -(a @ y[:3] + 0.5 * b)])

    def rhs_sphere(_t, y):
        q, v = y[:3], y[3:]
        aq = a @ q
        return np.concatenate([v, -aq + (q @ aq - v @ v) / (q @ q) * q])

    sol = solve_ivp(rhs if constraint is None else rhs_sphere, (0.0, float(t[-1])), np.concatenate([q0, v0]),
                    t_eval=t, method="DOP853", rtol=rtol, atol=1e-2 * rtol)
    if not sol.success:
        raise RuntimeError(f"mass-centre reference failed: {sol.message}")
    return sol.y[:3].T, sol.y[3:].T


def _kepler(mu, q0, v0, t, rtol) -> tuple[np.ndarray, np.ndarray]:
    """A point in the field ``-mu / |q|`` (7.7), by DOP853 (``atol`` relative to ``|q0|``)."""
    def rhs(_t, y):
        q = y[:3]
        return np.concatenate([y[3:], -mu * q / np.dot(q, q) ** 1.5])

    sol = solve_ivp(rhs, (0.0, float(t[-1])), np.concatenate([q0, v0]), t_eval=t, method="DOP853", rtol=rtol,
                    atol=1e-3 * rtol * float(np.linalg.norm(q0)))
    if not sol.success:
        raise RuntimeError(f"orbit reference failed: {sol.message}")
    return sol.y[:3].T, sol.y[3:].T


def _integrate(part: Part, t: np.ndarray, state0: tuple, run: dict) -> tuple[np.ndarray, np.ndarray]:
    """One run of ``part``'s equations from ``state0`` at ``t = 0`` through the times ``t >= 0``."""
    d = part.data
    if part.kind == "mass_center":
        return _mass_center(d["a"], d["b"], d["constraint"], *state0, t, run["rtol"])
    if part.kind == "kepler":
        return _kepler(d["mu"], *state0, t, run["rtol"])
    w0, Q0 = state0
    if part.kind == "rotation":
        ref = integrate_rotation(d["I"], d["a"], Q0, w0, **run)
    elif part.kind == "orbiting_rotation":
        ref = integrate_orbiting_rotation(d["I"], d["orbit"], Q0, w0, **run)
    elif part.kind == "heavy_top":
        ref = integrate_heavy_top(d["I"], d["center"], Q0, w0, mass=d["mass"], gravity=d["gravity"], **run)
    else:
        ref = integrate_fixed_point(d["I"], d["R"], d["a"], d["b"], Q0, w0, **run)
    return ref(t)


def probe_rate(run: Callable[[np.ndarray], Any], horizon: float) -> float:
    """Seconds per unit time of ``run(times)`` (an integration from 0 through ``times``), from timed probes
    after a warm-up (which compiles heyoka's model).

    The probe's horizon grows eightfold until it takes :data:`PROBE_SECONDS` or reaches ``horizon``;
    the cost of a run over a tiny horizon (building the integrator) is subtracted.
    """
    if horizon <= 0:
        return 0.0
    tiny = np.array([0.0, min(horizon, 1e-3)])
    run(tiny)
    start = time.perf_counter()
    run(tiny)
    overhead = time.perf_counter() - start
    span = min(horizon, 1.0)
    while True:
        start = time.perf_counter()
        run(np.array([0.0, span]))
        seconds = time.perf_counter() - start
        if seconds >= PROBE_SECONDS or span >= horizon:
            return max(seconds - overhead, 0.0) / span
        span = min(horizon, 8.0 * span)


def announce_fallbacks(runs: dict[str, Callable[[np.ndarray], Any]], horizon: float,
                       note: Callable[[str], None] | None) -> None:
    """Tell ``note`` how long each of a split's own numerical integrations (``what -> run(times)``) will take
    to reach ``horizon``, when more than :data:`ANNOUNCE_SECONDS` (from :func:`probe_rate`); nothing without
    ``note``."""
    if note is None:
        return
    for what, run in runs.items():
        expected = probe_rate(run, horizon) * horizon
        if expected > ANNOUNCE_SECONDS:
            note(f"{what}: numerical fallback to t = {horizon:g}, expected about {expected:.2g} s")


def _rate(part: Part, run: dict, horizon: float) -> float:
    """Seconds per unit time of one run of ``part``'s reference (:func:`probe_rate`)."""
    return probe_rate(lambda times: _integrate(part, times, part.state0, run), horizon)


def _segmented(part: Part, t: np.ndarray, runs: tuple[dict, ...], edges: np.ndarray,
               tick: Callable[[int], None]) -> list[tuple[np.ndarray, ...]]:
    """Each run through the times ``t`` in segments ``t[edges[k]:edges[k + 1]]``, each segment from the run's
    own end state of the one before (at its last time); ``tick(k)`` as segment ``k`` ends."""
    pieces = [[] for _ in runs]
    states, start = [part.state0] * len(runs), 0.0
    for k in range(edges.size - 1):
        seg = t[edges[k]:edges[k + 1]]
        for i, run in enumerate(runs):
            out = _integrate(part, seg - start, states[i], run)
            pieces[i].append(out)
            states[i] = tuple(x[-1] for x in out)
        start = float(seg[-1])
        tick(k)
    return [tuple(np.concatenate([p[j] for p in ps]) for j in range(len(ps[0]))) for ps in pieces]


def _checked_times(t: np.ndarray, rate: float, budget: float) -> tuple[np.ndarray, str]:
    """The output times the budget reaches (101 equally spaced times when fewer than 11 of them fit)."""
    horizon = float(t[-1])
    if rate * horizon <= budget:
        return t, ""
    reach = budget / rate
    tc = t[t <= reach]
    if tc.size < 11:
        tc = np.linspace(0.0, reach, 101)
    return tc, (f"checked on t <= {tc[-1]:.4g} only: the reference to t = {horizon:g} would take about "
                f"{rate * horizon:.2g} s (a shorter --t-end checks it all; --no-check skips the references)")


def reference(part: Part, t: np.ndarray, *, note: Callable[[str], None] | None = None,
              budget: float = BUDGET_SECONDS) -> Reference:
    """The reference of ``part`` on the increasing times ``t >= 0``, with its error estimate.

    Parameters
    ----------
    part : Part
    t : ndarray
        Output times of the scene.
    note : callable, optional
        Told the expected duration of a long reference and its progress, one line each.
    budget : float
        Seconds the reference may take; beyond, it checks the horizon the budget reaches.
    """
    start = time.perf_counter()
    fine, coarse, label = _runs(part.kind)
    horizon = float(t[-1])
    fine_rate = _rate(part, fine, horizon)
    rate = fine_rate + _rate(part, coarse, horizon)
    tc, cut = _checked_times(t, rate, budget)
    expected = rate * float(tc[-1])
    segments = 1
    if expected > ANNOUNCE_SECONDS and note is not None:
        # a rotation on an orbit depends on t itself (the orbit's phase): it cannot restart at a segment's start
        # segments of about ANNOUNCE_SECONDS each, at most 50 progress lines
        if part.kind != "orbiting_rotation":
            segments = int(min(50, tc.size, np.ceil(expected / ANNOUNCE_SECONDS)))
        note(f"{part.what}: {label.split(';')[0]} to t = {tc[-1]:g}, expected about {expected:.2g} s")
    edges = np.linspace(0, tc.size, segments + 1).round().astype(int)

    def tick(k: int) -> None:
        if note is not None and segments > 1:
            note(f"{part.what}: {k + 1}/{segments} segments")

    ref, other = _segmented(part, tc, (fine, coarse), edges, tick)
    error = max(float(np.max(np.abs(x - y))) for x, y in zip(ref, other))
    return Reference(t=tc, state=ref, error=error, label=label, seconds=time.perf_counter() - start, rate=fine_rate,
                     note=cut)

