"""BLAS threads for the library's small-matrix work: one thread inside the library's entry points.

The library's linear algebra is on 3x3 .. 8x8 matrices and stacks of them, far below the size at
which a multi-threaded BLAS gains; with the BLAS's default threads (one per core) its calls pay the
threads' wake-up and synchronisation instead, and on a loaded machine a BLAS thread waits for a
busy core (benchmarks/bench_blas_threads.py measures both settings on the reference bodies).  The
guard's set and restore are a noticeable part of one far time of the theta-function rotation, whose
matrix-vector products OpenBLAS runs on one thread anyway: a closed form evaluated at one time skips
the guard (:meth:`thetasol.protocol.Solution._run`).

:func:`blas_threads` (a context manager) and :func:`single_blas_thread` (a decorator) set every
loaded BLAS to :data:`LIMIT` threads for the duration of the call, with threadpoolctl, and restore the
user's settings afterwards, also when the call raises.  Calls nest (only the outermost sets and
restores) and are safe from several Python threads at once (a process-wide count: the limit holds
while any thread is inside).  They do nothing without threadpoolctl, with ``LIMIT = None``, or with
``THETASOL_BLAS_THREADS=keep`` in the environment (read at the first call).  A BLAS already at
``LIMIT`` threads or fewer is left alone, so the cost is then one query per call.

OpenBLAS (tests/test_threads.py) ignores a setting made from a thread other than the
main one once the main thread has set one: called from worker threads of such a process, the library
runs with the BLAS as it finds it (Dask's worker processes start with ``OPENBLAS_NUM_THREADS=1``).
"""
from __future__ import annotations

import functools
import os
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, TypeVar

__all__ = ["LIMIT", "blas_threads", "single_blas_thread"]

#: Threads the library's BLAS calls run on; ``None`` leaves the BLAS as the user set it.
LIMIT: int | None = 1

F = TypeVar("F", bound=Callable[..., Any])

_lock = threading.Lock()
_state: dict[str, Any] = {"depth": 0, "saved": [], "controllers": None, "key": None}


def _blas_controllers() -> list:
    """(controller, its ``get_num_threads``) of the loaded BLAS libraries (numpy's, and scipy's once
    ``scipy.linalg`` is loaded), found once per state of ``scipy.linalg``.

    Importing ``scipy.linalg`` here to load its BLAS would slow the first call of a process,
    and the theta-function rotation makes no scipy call: a scipy BLAS first loaded inside a call is
    found at the next call."""
    key = "scipy.linalg" in sys.modules
    if _state["controllers"] is None or _state["key"] != key:
        _state["key"] = key
        if os.environ.get("THETASOL_BLAS_THREADS", "").lower() == "keep":
            _state["controllers"] = []
            return []
        try:
            from threadpoolctl import ThreadpoolController
        except ImportError:
            _state["controllers"] = []
            return []
        _state["controllers"] = [(c, c.get_num_threads) for c in ThreadpoolController().lib_controllers
                                 if c.user_api == "blas"]
    return _state["controllers"]


def _enter() -> None:
    with _lock:
        _state["depth"] += 1
        if _state["depth"] > 1 or LIMIT is None:
            return
        saved = []
        for c, get in _blas_controllers():
            n = get()                             # the bound method: no property lookup per call
            if n is not None and n > LIMIT:
                c.set_num_threads(LIMIT)
                saved.append((c, n))
        _state["saved"] = saved


def _exit() -> None:
    with _lock:
        _state["depth"] -= 1
        if _state["depth"] > 0 or not _state["saved"]:
            return
        for c, n in _state["saved"]:
            c.set_num_threads(n)
        _state["saved"] = []


@contextmanager
def blas_threads() -> Iterator[None]:
    """Run the block with every loaded BLAS on :data:`LIMIT` threads; the user's settings come back after.

    Examples
    --------
    >>> import numpy as np
    >>> with blas_threads():
    ...     x = np.linalg.solve(np.eye(3), np.ones(3))
    """
    _enter()
    try:
        yield
    finally:
        _exit()


def single_blas_thread(fun: F) -> F:
    """Decorator: ``fun`` runs inside :func:`blas_threads`."""
    @functools.wraps(fun)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        _enter()
        try:
            return fun(*args, **kwargs)
        finally:
            _exit()

    return wrapper  # type: ignore[return-value]
