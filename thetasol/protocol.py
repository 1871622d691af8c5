"""The Solution protocol every result follows (closed forms and numerical references), and the
exceptions they share.

A solution is an immutable object built once from the data (the set-up) and evaluated at any
times afterwards, in any order, without time stepping:

* ``sol(t)`` (alias ``sol.evaluate(t)``) returns the model's state arrays, each with ``t.shape``
  leading; long time arrays are evaluated in chunks so memory stays bounded;
* ``sol.model`` names the physical system (:data:`MODELS`) and ``sol.method`` the technique that
  solves it (:data:`METHODS`, or ``"numerical/<integrator>"`` for a numerical reference);
  ``sol.case`` the special case within the method (``"separatrix"``, ``"nodal"``, ...), if any;
* ``sol.invariants`` holds the first integrals of the motion (energy, momenta, Casimirs);
* ``sol.diagnostics`` says how the solution checked itself; it always holds ``error_estimate``:
  the estimated relative error of the state the solution returns, on its validated horizon, from
  its own self-check (rounding of the evaluation, the data reproduced at ``t = 0``, the tail of a
  series, a residual that must vanish, or a numerical integrator's tolerance);
* ``sol.check()`` reads that estimate against :data:`CHECK_TOL` (or a given tolerance, and far
  times) and says ok or not, and why, in one sentence.

Evaluation runs with the BLAS on one thread (:mod:`thetasol.core.threads`; the user's setting is
restored after the call), except the evaluation of a closed form at one time, whose products are
matrix-vector products that the BLAS runs on one thread anyway (:meth:`Solution._run`).

Times are checked on every call: text and non-finite times are refused, and so are times so far
from 0 that float64 keeps no digit of the motion's phase (:data:`PHASE_LIMIT`); times whose float64
spacing alone makes the state less accurate than ``error_estimate`` and :data:`CHECK_TOL` warn, once per
solution.

``ClosedFormUnavailable`` is raised for valid data outside the closed forms (its message names the
numerical reference to use instead); ``ValueError`` for bad data, naming the problem.
"""
from __future__ import annotations

import math
import os
import sys
import warnings
import weakref
from collections.abc import Iterable
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.inertia import inertia_from_moments
from thetasol.core.so3 import hat
from thetasol.core.threads import blas_threads

__all__ = ["ClosedFormUnavailable", "Solution", "RotationSolution", "SelfCheck", "CHUNK", "MODELS", "METHODS",
           "NUMERICAL", "CHECK_TOL", "ROUNDOFF", "PHASE_LIMIT", "vocabulary_problem", "describe", "worst_error",
           "quiet_far_times"]

#: Times evaluated per chunk by :meth:`Solution.__call__` (bounded memory on long time arrays).
CHUNK = 4096

#: The physical systems a solution describes (``sol.model``), each with the paper's section.
MODELS = MappingProxyType({
    "rotation": "one rigid body turning about its mass centre in a quadratic potential, the free "
                "body included (Section 4)",
    "heavy-top": "a rigid body turning about a fixed point in uniform gravity (Section 5)",
    "gyrostat": "a rigid body carrying rotors, free or in a field (Section 8)",
    "neumann": "a point on a sphere in a quadratic potential, Neumann's problem (Sections 3 and 6)",
    "mass-center": "the mass centre of a configuration in a quadratic potential (Section 3)",
    "kepler": "the orbit of a mass centre about an attracting centre (Section 7)",
    "orbiting-rotation": "a rigid body on a circular orbit in the gravity gradient (Section 7)",
    "fixed-point": "a rigid body turning about a fixed point in a quadratic potential (Section 5)",
    "configuration": "every body of a configuration, split into its mass centre and rotations "
                     "(Theorems 1-5)",
})

#: The techniques (``sol.method``); a numerical reference's is ``NUMERICAL + <integrator>``.
METHODS = MappingProxyType({
    "elementary": "exponential, trigonometric or polynomial functions of t (rest, steady rotations, "
                  "spherical and symmetric bodies, Kepler's universal variables)",
    "elliptic": "Jacobi elliptic functions and integrals, their separatrix limits included",
    "theta/genus-2": "Riemann theta functions of a genus-2 curve",
    "theta/genus-3": "Riemann theta functions of a genus-3 curve (a symmetric body or a rank-one "
                     "potential)",
    "theta/genus-4": "Riemann theta functions of the generic genus-4 spectral curve (4.12)",
    "fourier/genus-2": "Fourier series on the real torus of a genus-2 curve",
    "split": "a configuration's parts, each solved by its own method (``diagnostics['parts']``)",
})

#: Prefix of a numerical reference's method, followed by the integrator's name (``numerical/DOP853``).
NUMERICAL = "numerical/"

#: :meth:`Solution.check`'s default bound on ``error_estimate``: a closed form is evaluated to a few
#: units of float64 rounding, and one whose own check is above this lost digits to nearby degenerate
#: data (the gyrostat's and the theta functions' warnings use the same bound).
CHECK_TOL = 1e-10

#: The least error a float64 evaluation can claim: a few units of rounding (eps = 2.2e-16).
ROUNDOFF = 8 * np.finfo(float).eps

#: A time whose float64 spacing moves the phase of the fastest motion by more than this (radians) keeps
#: no significant digit of the state: it is refused.
PHASE_LIMIT = 1.0

_EPS = np.finfo(float).eps
#: Solutions that already warned about far times, by id (once per solution; kept beside them, not in
#: them, and dropped with them).
_FAR_WARNED: dict[int, weakref.ref] = {}


def _first_far_warning(sol: object) -> bool:
    """True the first time ``sol`` asks (it is then remembered until it is collected)."""
    key = id(sol)
    ref = _FAR_WARNED.get(key)
    if ref is not None and ref() is sol:
        return False
    _FAR_WARNED[key] = weakref.ref(sol, lambda _r, key=key: _FAR_WARNED.pop(key, None))
    return True


def quiet_far_times(part: Solution) -> Solution:
    """``part``, marked as evaluated only through a composite solution (a heavy top with its centre at
    the pivot around its free rotation, a rescaled rotation around the dimensionless one) that checks
    the times and warns about far times itself, so that the user gets that warning once, in the
    composite's name.  Times past :data:`PHASE_LIMIT` are still refused by both."""
    _first_far_warning(part)
    return part


def _user_stacklevel() -> int:
    """The ``stacklevel`` of a warning that points at the first caller outside the package."""
    here, level, frame = os.path.dirname(os.path.abspath(__file__)), 1, sys._getframe(1)
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(here):
        frame, level = frame.f_back, level + 1
    return level


def vocabulary_problem(model: object, method: object) -> str:
    """What is wrong with a (model, method) pair, or ``""`` when both are in the vocabulary."""
    if model not in MODELS:
        return f"model {model!r} is not one of {sorted(MODELS)}"
    if not isinstance(method, str) or not (method in METHODS or (method.startswith(NUMERICAL)
                                                                and len(method) > len(NUMERICAL))):
        return f"method {method!r} is not one of {sorted(METHODS)} nor {NUMERICAL}<integrator>"
    return ""


def describe(sol: Solution, *, with_model: bool = False) -> str:
    """How one part of a composite was solved: its ``method``, the case in parentheses if any, and with
    ``with_model`` the model first (``"heavy-top by elliptic (lagrange)"``), for a line read on its own."""
    text = sol.method + (f" ({sol.case})" if sol.case else "")
    return f"{sol.model} by {text}" if with_model else text


def worst_error(parts: Iterable[Solution]) -> float:
    """A composite's error estimate: the largest of its parts' (``inf`` for a part that reports none)."""
    return max((float(p.diagnostics.get("error_estimate", math.inf)) for p in parts), default=ROUNDOFF)


@dataclass(frozen=True)
class SelfCheck:
    """The verdict of :meth:`Solution.check`: true when the expected error is within the tolerance.

    Attributes
    ----------
    ok : bool
    reason : str
        One sentence: what was compared and why it is ok or not.
    estimate : float
        The expected relative error: ``error_estimate``, or the far-time error when it is larger.
    threshold : float
        The tolerance it was compared with.
    """

    ok: bool
    reason: str
    estimate: float
    threshold: float

    def __bool__(self) -> bool:
        return self.ok

    def __str__(self) -> str:
        return ("ok: " if self.ok else "NOT ok: ") + self.reason


class Solution:
    """Base of every solution: chunked, shape-preserving evaluation, vocabulary and self-check.

    Subclasses are frozen dataclasses with the fields ``method``, ``invariants`` and
    ``diagnostics`` (holding ``error_estimate``), a ``model`` (a class attribute or a field) and
    implement ``_evaluate(t)`` for a flat float array ``t`` of length ``n``, returning a tuple of
    arrays of shapes ``(n,) + state_shape``.
    """

    #: The physical system, one of :data:`MODELS` (set by every subclass).
    model: str = ""

    def _diagnostics(self) -> dict:
        """``diagnostics``, or an empty dict for a minimal subclass without them."""
        d = getattr(self, "diagnostics", None)
        return d if isinstance(d, dict) else {}

    @property
    def case(self) -> str:
        """The special case within the method (``diagnostics["case"]``), ``""`` for the generic one."""
        return str(self._diagnostics().get("case", ""))

    def fastest_frequency(self) -> float:
        """The fastest angular frequency of the motion (rad per unit time): the rate at which a time
        error becomes a state error.  Default ``2 pi / period`` from ``diagnostics``; models with a
        faster rate (a spin) override it."""
        period = self._diagnostics().get("period", 0.0)
        return 2 * math.pi / period if period and math.isfinite(period) and period > 0 else 0.0

    def far_time_error(self, t: ArrayLike) -> float:
        """The relative state error float64 times alone cause at ``t``: ``max|t| eps`` times the fastest
        frequency (the spacing of float64 numbers near ``t`` moves the phase by that much)."""
        tt = V.times(t, "t")
        return float(np.max(np.abs(tt), initial=0.0)) * _EPS * self.fastest_frequency()

    def check(self, tol: float = CHECK_TOL, t: ArrayLike | None = None) -> SelfCheck:
        """Whether the solution's own error estimate (and, given ``t``, the far-time error at ``t``) is
        within ``tol``; ``str()`` of the answer says it in one sentence, ``bool()`` is the verdict."""
        tol = float(V.finite_array(tol, "tol", ()))
        est = self._diagnostics().get("error_estimate")
        if est is None or not math.isfinite(est):
            return SelfCheck(False, f"{self.model} by {self.method} reports no finite error_estimate", math.inf, tol)
        est, what = float(est), "its own check estimates a relative error of"
        if t is not None:
            far = self.far_time_error(t)
            if far > est:
                est, what = far, "float64 times up to the latest requested give a relative error of"
        ok = bool(est <= tol)
        reason = f"{self.model} by {self.method}: {what} {est:.1e}, {'within' if ok else 'above'} the tolerance {tol:.1e}"
        return SelfCheck(ok, reason, est, tol)

    def _evaluate(self, t: np.ndarray) -> tuple[np.ndarray, ...]:  # pragma: no cover - abstract
        raise NotImplementedError

    #: Evaluate all requested times in one call (a numerical reference integrates once over them, a
    #: composite solution lets its parts chunk themselves) instead of in chunks of ``_chunk_size()``.
    _AT_ONCE = False

    def _chunk_size(self) -> int:
        """Times per chunk; models whose evaluation needs much memory per time lower it."""
        return CHUNK

    def _times(self, t):
        tt = V.times(t, "t")
        if tt.size:
            self._far_times(float(np.max(np.abs(tt))))
        return tt, tt.ravel()

    def _far_times(self, latest: float) -> None:
        """Refuse times with no digit of the phase left; warn once when float64 spacing alone makes the
        state inaccurate: less accurate than the solution's own estimate and than :data:`CHECK_TOL`
        (every time loses ``|t| eps`` of phase, so the estimate alone would warn from a few periods on)."""
        far = latest * _EPS * self.fastest_frequency()
        if far <= CHECK_TOL:
            return
        if far > PHASE_LIMIT:
            raise ValueError(f"t = {latest:.3g} is too far for float64: its spacing moves the phase of the "
                             f"motion by {far:.1e} rad, no significant digit of the state is left")
        est = self._diagnostics().get("error_estimate", math.inf)
        if far > est and _first_far_warning(self):
            warnings.warn(f"{self.model}: at |t| = {latest:.3g} the float64 spacing of t alone gives a relative "
                          f"error of about {far:.1e} (the solution's own estimate is {est:.1e}); shift the "
                          "time origin (solve from a later state) for better accuracy", RuntimeWarning,
                          stacklevel=_user_stacklevel())

    def _chunked(self, fn, flat: np.ndarray):
        n = flat.size
        if self._AT_ONCE:
            return fn(flat)
        step = max(1, int(self._chunk_size()))
        if n <= step:
            return fn(flat)
        parts = [fn(flat[i:i + step]) for i in range(0, n, step)]
        if isinstance(parts[0], tuple):
            return tuple(np.concatenate(p, axis=0) for p in zip(*parts))
        return np.concatenate(parts, axis=0)

    def _run(self, fn, flat: np.ndarray):
        """``fn`` on the flat times in chunks, inside :func:`~thetasol.core.threads.blas_threads` unless it is
        one time of a closed form: one time makes matrix-vector products only, which the BLAS runs on one
        thread whatever its setting, so the guard's set and restore would only add to the call
        (tests/test_threads.py checks the bits are the same either way)."""
        if flat.size == 1 and not self._AT_ONCE:
            return fn(flat)
        with blas_threads():
            return self._chunked(fn, flat)

    def __call__(self, t: ArrayLike) -> tuple[np.ndarray, ...]:
        """The state at times ``t`` (any shape): a tuple of arrays with ``t.shape`` leading."""
        tt, flat = self._times(t)
        out = self._run(self._evaluate, flat)
        if tt.ndim == 1:                                   # the shapes are already t.shape + state
            return tuple(out)
        return tuple(x.reshape(tt.shape + x.shape[1:]) for x in out)

    def evaluate(self, t: ArrayLike) -> tuple[np.ndarray, ...]:
        """Alias of ``sol(t)`` (the name diffrax users expect)."""
        return self(t)


class ClosedFormUnavailable(NotImplementedError):
    """No closed form could be built for these (valid) data; the message says why.

    Raised for the cases a closed form does not cover (a symmetric body with little but non-zero
    spin about its axis in a potential) and where the curve computations cannot reach the accuracy
    the solution promises (for example data within rounding of a degeneration).
    :func:`thetasol.integrate_rotation` always applies.
    """


@dataclass(frozen=True, eq=False)
class RotationSolution(Solution):
    """The motion ``t -> (omega(t), Q(t))`` of one body, in the conventions of ``integrate_rotation``.

    Subclasses implement ``_evaluate(t) -> (omega, Q)`` for a flat float array ``t``
    (shapes ``(n, 3)``, ``(n, 3, 3)``) and may override ``_omega`` when the angular
    velocity alone is cheaper.  Everything else (shapes, validation, ``M``, ``u``) is here.

    Attributes
    ----------
    J : ndarray, shape (3, 3)
        The paper's second moments in the body frame, ``J = tr(I)/2 1 - I`` (the property ``I`` gives the
        inertia tensor the entry points take).
    a : ndarray, shape (3, 3)
        Potential matrix, ``phi = 1/2 x^T a x``.
    Q0 : ndarray (3, 3)
        Initial attitude, the rotation from the body frame to the space frame.
    omega0 : ndarray (3,)
        Initial angular velocity in the body frame.
    model : str
        ``"rotation"`` (subclasses for other systems override it), see :data:`MODELS`.
    method : str
        The technique, e.g. ``"elliptic"`` or ``"theta/genus-4"`` (:data:`METHODS`).
    invariants : dict
        First integrals (energy, ``m2 = |m|^2``, the coefficients of the spectral curve, ...).
    dps : int or None
        When set, values are computed with mpmath at ``dps`` digits and returned as object
        arrays of ``mpmath.mpf``.
    diagnostics : dict
        How the solution checked itself: error estimates, periods and the characteristic
        constants of the closed form, and ``error_estimate`` (see the module docstring).
    I_given : ndarray, shape (3, 3), or None
        The inertia tensor as the entry point received it (checked, principal values as a diagonal);
        the property ``I`` returns it.
    """

    model = "rotation"

    J: np.ndarray
    a: np.ndarray
    Q0: np.ndarray
    omega0: np.ndarray
    method: str
    invariants: dict = field(repr=False)
    dps: int | None = None
    diagnostics: dict = field(default_factory=dict, repr=False)
    I_given: np.ndarray | None = field(default=None, repr=False)

    # -- to implement ------------------------------------------------------------------------
    def _evaluate(self, t: np.ndarray):  # pragma: no cover - abstract
        raise NotImplementedError

    def _omega(self, t: np.ndarray) -> np.ndarray:
        return self._evaluate(t)[0]

    def initial_residual(self) -> float:
        """How far the solution at ``t = 0`` is from its data: ``|omega(0) - omega0|`` relative to
        ``|omega0|`` and ``max |Q(0) - Q0|``, the larger; a self-check for closed forms without one of
        their own."""
        w, Q = self._evaluate(np.zeros(1))
        w, Q = np.asarray(w, dtype=float)[0], np.asarray(Q, dtype=float)[0]
        scale = float(np.linalg.norm(self.omega0))
        dw = float(np.linalg.norm(w - self.omega0))
        return max(dw / scale if scale > 0 else dw, float(np.abs(Q - self.Q0).max()))

    def fastest_frequency(self) -> float:
        """The largest of the spin ``|omega0|``, ``2 pi / period`` and the potential's rate
        ``sqrt(|a| |J| / I_min)`` (the angular acceleration a unit tilt gets), rad per unit time."""
        w, J = self.omega0, self.J
        spin = math.sqrt(float(w @ w))
        pull = float(np.abs(self.a).max()) * float(np.abs(J).max())
        i_min = float(np.trace(J)) - float(np.abs(J).max())     # the smallest I for principal values
        pot = math.sqrt(pull / i_min) if pull > 0 and i_min > 0 else 0.0
        return max(spin, pot, super().fastest_frequency())

    # -- protocol ----------------------------------------------------------------------------
    def __call__(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """``(omega(t), Q(t))`` with shapes ``t.shape + (3,)`` and ``t.shape + (3, 3)``."""
        return super().__call__(t)

    def omega(self, t: ArrayLike) -> np.ndarray:
        """Body angular velocity, shape ``t.shape + (3,)``."""
        tt, flat = self._times(t)
        return self._run(self._omega, flat).reshape(tt.shape + (3,))

    def Q(self, t: ArrayLike) -> np.ndarray:
        """Attitude (body to space), shape ``t.shape + (3, 3)``."""
        return self(t)[1]

    @property
    def I(self) -> np.ndarray:
        """Inertia tensor in the body frame, shape (3, 3): the body as every entry point takes it, so that
        results of different models compare.  The inertia the entry point was given (``I_given``) when
        it stored it, else ``tr(J) 1 - J`` (the round trip through ``J`` may differ from it by an ulp)."""
        return self.I_given if self.I_given is not None else inertia_from_moments(self.J)

    def m(self, t: ArrayLike) -> np.ndarray:
        """Body angular momentum ``m = I omega``, shape ``t.shape + (3,)``."""
        return self.omega(t) @ self.I.T

    def M(self, t: ArrayLike) -> np.ndarray:
        """The paper's skew matrix ``M = J hat(omega) + hat(omega) J = hat(I omega)`` (4.5)."""
        return hat(self.m(t))

    def u(self, t: ArrayLike) -> np.ndarray:
        """The paper's ``u = -Q^T a Q`` (sign of (7.13), docs/conventions.md), ``t.shape + (3, 3)``."""
        Q = self.Q(t)
        return -(np.swapaxes(Q, -1, -2) @ self.a @ Q)
