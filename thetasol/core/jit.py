"""Optional numba compilation of the few per-time kernels of the library's evaluations.

numba is not a dependency.  A :class:`Kernel` wraps a plain Python function written for numba's
nopython mode; :meth:`Kernel.get` returns it compiled, or None when numba is missing or switched off
(``THETASOL_NUMBA=0`` in the environment, read at the first call, or :data:`ENABLED` set to False),
and the caller then runs its numpy code, which computes the same quantities with the same formulas
(to rounding: the two paths are compared in tests/test_theta_evaluation.py).

Why compiled kernels at all: the evaluation of a few times is a few dozen numpy calls on arrays of a
handful of elements, each costing a fixed ~0.5-1 us, and the products of one-dimensional tables that
make the phases of a Fourier flow are gathers that numpy runs as separate passes.  Why lazily:
importing numba costs ~0.3 s and compiling a kernel ~1 s, so nothing happens at ``import thetasol``;
the first evaluation compiles (``cache=True``: later processes load the machine code from numba's
cache next to the module, or from ``NUMBA_CACHE_DIR``).  Cold start figures are in
benchmarks/bench_theta_rotation.py's docstring run notes (docs/bench_theta_rotation.md).
"""
from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

__all__ = ["ENABLED", "Kernel", "numba_available"]

#: Use numba when it is installed; ``None`` means: decide at the first call from ``THETASOL_NUMBA``.
ENABLED: bool | None = None

_state: dict[str, Any] = {"numba": None}


def numba_available() -> bool:
    """True when the compiled kernels are in use (numba importable and not switched off)."""
    if ENABLED is False:
        return False
    if ENABLED is None and os.environ.get("THETASOL_NUMBA", "").lower() in ("0", "off", "false", "no"):
        return False
    if _state["numba"] is None:
        try:
            import numba
        except ImportError:
            numba = False
        _state["numba"] = numba
    return _state["numba"] is not False


class Kernel:
    """A function compiled with ``numba.njit(cache=True)`` at its first use, if numba is available."""

    def __init__(self, fn: Callable[..., Any]):
        self.fn = fn
        self._compiled: Callable[..., Any] | None = None

    def get(self) -> Callable[..., Any] | None:
        """The compiled kernel, or None (numba missing or switched off: use the numpy path)."""
        if not numba_available():
            return None
        if self._compiled is None:
            self._compiled = _state["numba"].njit(cache=True, nogil=True)(self.fn)
        return self._compiled
