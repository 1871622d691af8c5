"""Optional numba compilation of the few per-time kernels of the library's evaluations.

numba is not a dependency, and the kernels are opt-in: ``THETASOL_NUMBA=1`` in the environment (read
once, at the first call) or :data:`ENABLED` set to True.  A :class:`Kernel` wraps a plain Python
function written for numba's nopython mode; :meth:`Kernel.get` returns it compiled, or None when
numba is off or missing, and the caller then runs its numpy code, which computes the same quantities
with the same formulas (to rounding: the two paths are compared in tests/test_theta_evaluation.py).

Why compiled kernels at all: the evaluation of a few times is a few dozen numpy calls on arrays of a
handful of elements, each costing a fixed ~0.5-1 us, and the products of one-dimensional tables that
make the phases of a Fourier flow are gathers that numpy runs as separate passes.  One far time of
the theta-function rotation costs ~18 us of CPU time with the kernels and ~39 us without them (generic
body; ~15 and ~44 us on symmetric_oblate; tests/test_one_call.py checks the two paths agree); dense
evaluation gains 5-20%.

Why lazily, and the cost: nothing is imported or compiled at ``import thetasol`` nor in a set-up;
the first evaluation imports numba (~0.35 s) and compiles its kernels (``cache=True``: later processes
load the machine code from numba's cache next to the module, or from ``NUMBA_CACHE_DIR``).  Measured
(CPU time, this machine): a fresh process importing thetasol and solving the generic body takes
0.53-0.57 s with or without numba; its first evaluation then costs 0.67 s more with a warm cache, and
6.3 s more with an empty cache (compiling the two kernels, once per installation and source version).
That one-off cost is why they are opt-in: on by default, it lands in the first timed evaluation of
a program (``python -m thetasol demo`` reports the closed form's evaluation at 470 us per time
instead of 12 with a warm cache, and as never paying off while the kernels compile).
"""
from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

__all__ = ["ENABLED", "Kernel", "numba_available"]

#: Use numba (when installed): True, False, or ``None``: ``THETASOL_NUMBA`` decides (on for 1/on/true/yes).
ENABLED: bool | None = None

_state: dict[str, Any] = {"numba": None, "env_on": None}


def numba_available() -> bool:
    """True when the compiled kernels are in use (switched on and numba importable)."""
    if ENABLED is False:
        return False
    if ENABLED is None:
        if _state["env_on"] is None:
            _state["env_on"] = os.environ.get("THETASOL_NUMBA", "").lower() in ("1", "on", "true", "yes")
        if not _state["env_on"]:
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
