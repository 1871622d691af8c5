"""One reference case: an initial-value problem with its exact solution, scoring and export.

A :class:`Case` is an ODE ``y' = rhs(t, y)`` on a flat float state (the model's own equations,
written from the physics) together with the closed form of :mod:`thetasol.solutions` that solves
it exactly.  The closed form is built on the first call of :meth:`Case.exact` and kept.
"""
from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["Case", "Group", "Score", "Report"]


@dataclass(frozen=True)
class Group:
    """A block of state components scored together.

    ``scale`` is the unit its error is divided by: a number (1 for an attitude matrix or an
    angle: absolute error) or None (the largest ``|component|`` of the exact states on the times
    scored: relative error).
    """

    name: str
    start: int
    stop: int
    scale: float | None = None


class Score(dict):
    """Max relative error per component group (``{group: error}``); ``worst`` is the largest."""

    @property
    def worst(self) -> float:
        return max(self.values())

    def __float__(self) -> float:
        return self.worst


@dataclass(frozen=True)
class Report:
    """Errors against time per group and the drift of the first integrals.

    ``errors[g][i]`` is the error of group ``g`` at ``t[i]`` (relative as in :meth:`Case.score`);
    ``drift[name][i]`` is ``|I(y(t_i)) - I(y0)| / scale`` (``scale`` the larger of the integral's
    natural size at ``t0`` and at ``t_i``, e.g. kinetic plus absolute potential energy) for each
    first integral (and constraint, such as ``orthogonality = max |Q^T Q - 1|``) of the case.
    """

    name: str
    t: np.ndarray
    errors: dict
    drift: dict

    def __str__(self) -> str:
        lines = [f"{self.name}: {self.t.size} times in [{self.t.min():.6g}, {self.t.max():.6g}]",
                 "  error (max over t)"]
        lines += [f"    {g:<22s} {float(np.max(e)):.3e}" for g, e in self.errors.items()]
        lines.append("  drift of the first integrals (max over t)")
        lines += [f"    {k:<22s} {float(np.max(d)):.3e}" for k, d in self.drift.items()]
        return "\n".join(lines)


def _norm(x: np.ndarray) -> np.ndarray:
    """Euclidean norm over the trailing axes beyond the time axes (scalars: absolute value)."""
    return np.abs(x) if x.ndim <= 1 else np.sqrt(np.sum(x.reshape(x.shape[0], -1) ** 2, axis=1))


class Case:
    """An initial-value problem with a closed-form solution (see the package docstring).

    Attributes
    ----------
    name, model, description : str
        Identifier, the model (e.g. ``"free rigid body"``) and what the case exercises.
    equations, units : str
        The ODE in words and formulas, and the units of the state (for the JSON export).
    t_span : tuple of float
        The interval the case is meant to be integrated over.
    y0 : ndarray, shape (n,)
        Flat initial state; ``columns`` names its components, ``groups`` blocks them.
    method : str
        The closed form behind :meth:`exact` (known after the first call).
    """

    def __init__(self, *, name: str, model: str, description: str, equations: str, units: str,
                 t_span: tuple[float, float], y0, columns: tuple[str, ...], groups: tuple[Group, ...],
                 rhs: Callable, build: Callable, integrals: Callable):
        self.name, self.model, self.description = name, model, description
        self.equations, self.units = equations, units
        self.t_span = (float(t_span[0]), float(t_span[1]))
        self._y0 = np.array(y0, dtype=float)
        self._y0.setflags(write=False)
        if len(columns) != self._y0.size:
            raise ValueError(f"{name}: {len(columns)} column names for {self._y0.size} components")
        self.columns, self.groups = tuple(columns), tuple(groups)
        self._rhs, self._build, self._integrals = rhs, build, integrals
        self._exact = None          # (solution object, states function), built on first use

    def __repr__(self) -> str:
        return f"Case({self.name!r}, model={self.model!r}, t_span={self.t_span})"

    @property
    def y0(self) -> np.ndarray:
        """The initial state (a copy)."""
        return self._y0.copy()

    def rhs(self, t, y):
        """The model's ODE right-hand side, ``solve_ivp``'s signature (``y`` of shape (n,) or (n, k))."""
        y = np.asarray(y, dtype=float)
        if y.ndim == 2:      # vectorized=True layout: columns are states
            return np.stack([self._rhs(t, y[:, j]) for j in range(y.shape[1])], axis=1)
        return self._rhs(t, y)

    def _solution(self):
        if self._exact is None:
            self._exact = self._build()
        return self._exact

    @property
    def solution(self):
        """The closed-form solution object of :mod:`thetasol.solutions` (built on first use)."""
        return self._solution()[0]

    @property
    def method(self) -> str:
        return str(self.solution.method)

    def exact(self, t) -> np.ndarray:
        """Exact states at times ``t`` (any shape): an array of shape ``t.shape + y0.shape``."""
        tt = np.asarray(t, dtype=float)
        flat = tt.ravel()
        out = np.asarray(self._solution()[1](flat), dtype=float).reshape(flat.size, self._y0.size)
        return out.reshape(tt.shape + self._y0.shape)

    def times(self, n: int = 101) -> np.ndarray:
        """``n`` equally spaced times over ``t_span`` (a ``t_eval`` for ``solve_ivp``)."""
        return np.linspace(self.t_span[0], self.t_span[1], int(n))

    def _states(self, t, y) -> tuple[np.ndarray, np.ndarray]:
        tt = np.atleast_1d(np.asarray(t, dtype=float)).ravel()
        yy = np.asarray(y, dtype=float)
        n = self._y0.size
        if yy.shape == (tt.size, n):
            return tt, yy
        if yy.shape == (n, tt.size):            # solve_ivp's sol.y
            return tt, yy.T
        if yy.size == tt.size * n and yy.shape[-1] == n:
            return tt, yy.reshape(tt.size, n)
        raise ValueError(f"{self.name}: states of shape {yy.shape} do not match {tt.size} times of "
                         f"{n} components (expected t.shape + ({n},) or solve_ivp's ({n}, len(t)))")

    def _errors(self, t, y) -> dict:
        tt, yy = self._states(t, y)
        ex = self.exact(tt)
        errs = {}
        for g in self.groups:
            d = np.abs(yy[:, g.start:g.stop] - ex[:, g.start:g.stop]).max(axis=1)
            scale = g.scale if g.scale is not None else float(np.abs(ex[:, g.start:g.stop]).max())
            errs[g.name] = d / max(scale, np.finfo(float).tiny)
        return errs

    def score(self, t, y) -> Score:
        """Max over ``t`` of the error of the states ``y`` per component group.

        Parameters
        ----------
        t : array_like, shape (k,)
            Times.
        y : array_like
            States at those times, shape ``(k, n)`` (``sol.y.T``) or solve_ivp's ``(n, k)``.

        Returns
        -------
        Score
            ``{group: max_t |y_g - exact_g| / scale_g}`` (``scale_g`` as in :class:`Group`), with
            ``.worst`` the largest.  NaN states give NaN.
        """
        return Score({g: float(np.max(e)) for g, e in self._errors(t, y).items()})

    def integrals(self, y) -> dict:
        """First integrals (and constraints) of states ``y`` (..., n): ``{name: (value, scale)}``."""
        return self._integrals(np.asarray(y, dtype=float))

    def report(self, t, y) -> Report:
        """Error against time per group and drift of the first integrals along ``y``."""
        tt, yy = self._states(t, y)
        ref = self.integrals(self._y0[None, :])
        now = self.integrals(yy)
        drift = {}
        for k, (v0, s0) in ref.items():
            # the integral's natural size, now or at t0 (states may grow, e.g. a hyperbolic mode)
            scale = np.maximum(float(np.max(np.abs(s0))), _norm(np.asarray(now[k][1], dtype=float)))
            drift[k] = _norm(now[k][0] - v0) / np.maximum(scale, np.finfo(float).tiny)
        return Report(self.name, tt, self._errors(tt, yy), drift)

    def metadata(self) -> dict:
        """Name, model, description, equations, units, columns and the closed form's method."""
        return {"name": self.name, "model": self.model, "description": self.description,
                "equations": self.equations, "units": self.units, "method": self.method,
                "t_span": list(self.t_span), "columns": ["t", *self.columns]}

    def export(self, path, t=None) -> Path:
        """Write the exact states at ``t`` (default ``times(101)``) to ``.csv`` or ``.json``.

        The CSV has a header line naming the columns (``t`` first) and each value in the
        shortest form that reads back to the same float64 (Python's ``repr``); the JSON holds
        :meth:`metadata` plus ``t`` and ``states`` (a list of rows).
        """
        p = Path(path)
        tt = self.times() if t is None else np.atleast_1d(np.asarray(t, dtype=float)).ravel()
        ys = self.exact(tt)
        suffix = p.suffix.lower()
        if suffix == ".csv":
            text = ",".join(["t", *self.columns]) + "\n" + "\n".join(
                ",".join(_g17(x) for x in (ti, *row)) for ti, row in zip(tt, ys, strict=True)) + "\n"
        elif suffix == ".json":
            # metadata indented, one state per line
            head = json.dumps({**self.metadata(), "t": tt.tolist()}, indent=1)[:-2]
            rows = ",\n  ".join(json.dumps(row) for row in ys.tolist())
            text = f'{head},\n "states": [\n  {rows}\n ]\n}}\n'
        else:
            raise ValueError(f"export: file must end in .csv or .json, got {str(path)!r}")
        tmp = p.with_name(p.name + ".tmp")
        tmp.write_text(text)
        tmp.replace(p)
        return p


def _g17(x: float) -> str:
    x = float(x)
    return repr(x) if math.isfinite(x) else str(x)
