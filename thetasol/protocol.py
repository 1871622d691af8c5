"""The Solution protocol every closed form follows, and the exceptions they share.

A solution is an immutable object built once from the data (the set-up) and evaluated at any
times afterwards, in any order, without time stepping:

* ``sol(t)`` (alias ``sol.evaluate(t)``) returns the model's state arrays, each with ``t.shape``
  leading; long time arrays are evaluated in chunks so memory stays bounded;
* ``sol.method`` names the closed form used, e.g. ``"theta/genus-4"``;
* ``sol.invariants`` holds the first integrals of the motion (energy, momenta, Casimirs);
* ``sol.diagnostics`` says how the solution checked itself: error estimates, periods, the
  characteristic constants of the closed form.

Evaluation runs with the BLAS on one thread (:mod:`thetasol.core.threads`; the user's setting is
restored after the call), except the evaluation of a closed form at one time, whose products are
matrix-vector products that the BLAS runs on one thread anyway (:meth:`Solution._run`).

``ClosedFormUnavailable`` is raised for valid data outside the closed forms (its message names the
numerical reference to use instead); ``ValueError`` for bad data, naming the problem.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.so3 import hat
from thetasol.core.threads import blas_threads
from thetasol.mechanics.equations import inertia_from_moments

__all__ = ["ClosedFormUnavailable", "Solution", "RotationSolution", "CHUNK"]

#: Times evaluated per chunk by :meth:`Solution.__call__` (bounded memory on long time arrays).
CHUNK = 4096


class Solution:
    """Base of every closed-form solution: chunked, shape-preserving evaluation.

    Subclasses are frozen dataclasses with the fields ``method``, ``invariants`` and
    ``diagnostics`` and implement ``_evaluate(t)`` for a flat float array ``t`` of length
    ``n``, returning a tuple of arrays of shapes ``(n,) + state_shape``.
    """

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
        return tt, tt.ravel()

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
        one time of a closed form.  One time makes matrix-vector products only (the theta-function
        rotation's largest: 2836 x 40), which OpenBLAS runs on one thread whatever its setting (0.3.31:
        CPU time equals wall time on 2 threads); the guard's set and restore would add 6-9 us to a
        35-50 us call when the BLAS is on 2 threads (one far time of the generic reference body, many
        repetitions; tests/test_threads.py checks the bits are the same either way)."""
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
    Q0, omega0 : ndarray
        Initial attitude (body to space) and body angular velocity.
    method : str
        Short name of the closed form used, e.g. ``"euler-top/elliptic"``.
    invariants : dict
        First integrals (energy, ``m2 = |m|^2``, the coefficients of the spectral curve, ...).
    dps : int or None
        When set, values are computed with mpmath at ``dps`` digits and returned as object
        arrays of ``mpmath.mpf``.
    diagnostics : dict
        How the solution checked itself: error estimates, periods and the characteristic
        constants of the closed form.
    """

    J: np.ndarray
    a: np.ndarray
    Q0: np.ndarray
    omega0: np.ndarray
    method: str
    invariants: dict = field(repr=False)
    dps: int | None = None
    diagnostics: dict = field(default_factory=dict, repr=False)

    # -- to implement ------------------------------------------------------------------------
    def _evaluate(self, t: np.ndarray):  # pragma: no cover - abstract
        raise NotImplementedError

    def _omega(self, t: np.ndarray) -> np.ndarray:
        return self._evaluate(t)[0]

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
        """Inertia tensor ``I = tr(J) 1 - J`` in the body frame, shape (3, 3): the body as every entry
        point takes it, so that results of different models compare."""
        return inertia_from_moments(self.J)

    def m(self, t: ArrayLike) -> np.ndarray:
        """Body angular momentum ``m = I omega``, shape ``t.shape + (3,)``."""
        return self.omega(t) @ inertia_from_moments(self.J).T

    def M(self, t: ArrayLike) -> np.ndarray:
        """The paper's skew matrix ``M = J hat(omega) + hat(omega) J = hat(I omega)`` (4.5)."""
        return hat(self.m(t))

    def u(self, t: ArrayLike) -> np.ndarray:
        """The paper's ``u = -Q^T a Q`` (sign of (7.13), docs/conventions.md), ``t.shape + (3, 3)``."""
        Q = self.Q(t)
        return -(np.swapaxes(Q, -1, -2) @ self.a @ Q)
