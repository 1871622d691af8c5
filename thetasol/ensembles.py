"""Ensembles: many bodies or scenes solved at once, on local processes or on a Dask cluster.

:func:`solve_many` solves a list of independent problems (the rotations of many bodies, many
scenes) and returns the results in input order.  Each item is solved where it lands, by the same
entry points as one at a time (:func:`thetasol.solve_rotation` or any solver given, a scene's
:meth:`~thetasol.scenes.format.Scene.solution`), so the results are bit-identical to a loop.

Where it runs:

* by default, a local pool of processes (``concurrent.futures.ProcessPoolExecutor``, ``spawn``
  start method: the calling script needs the ``if __name__ == "__main__":`` guard), one per core,
  started for the call and shut down after (its start-up, mostly the workers' imports, is timed
  apart by benchmarks/bench_ensemble.py: for repeated calls pass your own executor as ``client``);
* ``workers=1``: in this process, no pool (the baseline, and the way to debug);
* ``client=``: a ``dask.distributed.Client`` (Dask is an optional extra, ``thetasol[dask]``),
  ``"dask"`` for the current default client, or any ``concurrent.futures.Executor``.

A theta-function solution pickles large (its lattice tables): to bring back only states, give
``t`` and each worker returns ``sol(t)`` instead of ``sol``.  Throughput and scaling are measured in
benchmarks/bench_ensemble.py (docs/ensembles.md).
"""
from __future__ import annotations

import concurrent.futures as cf
import math
import multiprocessing
import os
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from thetasol.protocol import ClosedFormUnavailable
from thetasol.scenes.format import Scene, load_scene

__all__ = ["solve_many", "EXPECTED_ERRORS"]

#: Per-item outcomes of valid and invalid data (the Solution protocol's two exceptions): returned in
#: place with ``errors="return"``.  Any other exception is a fault, raised in every mode.
EXPECTED_ERRORS: tuple[type[BaseException], ...] = (ClosedFormUnavailable, ValueError)

#: Items at or above which ``progress=None`` shows a bar (when tqdm is installed).
PROGRESS_MIN_ITEMS = 50


# -- work units (run in the workers: module-level, picklable) ------------------------------------

@dataclass(frozen=True)
class _Task:
    """One item, ready to solve: ``kind`` is "call" (solver(*args, **kwargs)), "scene" or "path"."""

    index: int
    kind: str
    payload: Any
    args: tuple = ()
    kwargs: Mapping | None = None


@dataclass(frozen=True)
class _Outcome:
    index: int
    value: Any = None
    error: BaseException | None = None
    warned: tuple = ()          # (category, message) of every warning the item raised


def _solve_one(task: _Task, t: np.ndarray | None) -> Any:
    if task.kind == "call":
        sol = task.payload(*task.args, **(task.kwargs or {}))
    else:
        scene = load_scene(task.payload) if task.kind == "path" else task.payload
        sol = scene.solution()
        return sol if t is None else sol.trajectories(t)
    return sol if t is None else sol(t)


def _run_chunk(tasks: Sequence[_Task], t: np.ndarray | None) -> list[_Outcome]:
    """Solve a chunk of items; expected errors come back as values, faults are raised with the item named."""
    out = []
    for task in tasks:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                value, error = _solve_one(task, t), None
            except EXPECTED_ERRORS as exc:
                value, error = None, exc
            except Exception as exc:
                exc.add_note(f"solve_many: raised while solving item {task.index}")
                raise
        out.append(_Outcome(task.index, value, error, tuple((w.category, str(w.message)) for w in caught)))
    return out


# -- the items -----------------------------------------------------------------------------------

def _task(index: int, item: Any, solver: Callable | None) -> _Task:
    if isinstance(item, Scene):
        return _Task(index, "scene", item)
    if isinstance(item, (str, os.PathLike)):
        return _Task(index, "path", Path(item))
    if solver is None:
        from thetasol.solutions.rotation.dispatch import solve_rotation

        solver = solve_rotation
    if isinstance(item, Mapping):
        return _Task(index, "call", solver, kwargs=dict(item))
    if isinstance(item, tuple | list):
        return _Task(index, "call", solver, args=tuple(item))
    raise TypeError(f"solve_many: item {index} is a {type(item).__name__}; expected a mapping of the solver's "
                    "keyword arguments (by default solve_rotation's I, a, Q0, omega0), a tuple of its positional "
                    "arguments, a Scene or the path of a scene file")


def _chunks(tasks: list[_Task], size: int) -> list[list[_Task]]:
    return [tasks[i:i + size] for i in range(0, len(tasks), size)]


# -- progress ------------------------------------------------------------------------------------

class _Progress:
    """Counts finished items into a tqdm bar, a user callable ``progress(done, total)``, or nothing."""

    def __init__(self, progress: Any, total: int):
        self.total, self.done, self.bar, self.callback = total, 0, None, None
        if callable(progress):
            self.callback = progress
        elif progress or (progress is None and total >= PROGRESS_MIN_ITEMS):
            try:
                from tqdm.auto import tqdm
            except ImportError:
                if progress:
                    raise ImportError("solve_many(progress=True) needs tqdm: pip install 'thetasol[progress]' "
                                      "(or pass progress=None to show a bar only when tqdm is installed)") from None
                return
            self.bar = tqdm(total=total, desc="solve_many", unit="item")

    def advance(self, n: int) -> None:
        self.done += n
        if self.bar is not None:
            self.bar.update(n)
        if self.callback is not None:
            self.callback(self.done, self.total)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


# -- engines: each yields the outcome lists of finished chunks -----------------------------------

def _serial(chunks, t):
    for chunk in chunks:
        yield _run_chunk(chunk, t)


def _executor(executor: cf.Executor | Callable[[], cf.Executor], chunks, t, own: bool):
    """Chunks on an executor; ``own``: ``executor`` is a factory, the pool lives for this call only."""
    pool = executor() if own else executor
    futures = []
    try:
        futures = [pool.submit(_run_chunk, chunk, t) for chunk in chunks]
        for fut in cf.as_completed(futures):
            yield fut.result()
    finally:
        for fut in futures:
            fut.cancel()
        if own:
            pool.shutdown(wait=True, cancel_futures=True)


def _dask(client, chunks, t):
    from distributed import as_completed

    futures = client.map(_run_chunk, chunks, t=t, pure=False)
    try:
        for fut in as_completed(futures):
            yield fut.result()
    finally:
        client.cancel(futures)


def _is_dask_client(client: Any) -> bool:
    return type(client).__module__.split(".")[0] == "distributed" and hasattr(client, "gather")


def _dask_default_client():
    try:
        from distributed import get_client
    except ImportError:
        raise ImportError("solve_many(client='dask') needs dask.distributed: pip install 'thetasol[dask]'") from None
    try:
        return get_client()
    except ValueError:
        raise ValueError("solve_many(client='dask'): no Dask client is running; create one first "
                         "(dask.distributed.Client(...)) or pass it as client=") from None


def _engine(client, workers, n_chunks, chunks, t, mp_context):
    if client is None:
        n = min(workers or _cpu_count(), n_chunks)
        if n <= 1:
            return _serial(chunks, t)
        ctx = multiprocessing.get_context(mp_context or "spawn")
        return _executor(lambda: cf.ProcessPoolExecutor(max_workers=n, mp_context=ctx), chunks, t, own=True)
    if isinstance(client, str):
        if client != "dask":
            raise ValueError(f"solve_many: client must be a dask.distributed.Client, 'dask' or a "
                             f"concurrent.futures.Executor, got {client!r}")
        client = _dask_default_client()
    if _is_dask_client(client):
        return _dask(client, chunks, t)
    if isinstance(client, cf.Executor):
        return _executor(client, chunks, t, own=False)
    raise TypeError(f"solve_many: client must be a dask.distributed.Client, 'dask' or a concurrent.futures.Executor, "
                    f"got {type(client).__name__}")


def _cpu_count() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        return os.cpu_count() or 1


def _parallelism(client, workers) -> int:
    if client is None:
        return workers or _cpu_count()
    if _is_dask_client(client):
        return max(1, sum(client.nthreads().values()))
    return getattr(client, "_max_workers", None) or _cpu_count()


# -- the entry point -----------------------------------------------------------------------------

def solve_many(items: Iterable[Any], *, t: Any = None, solver: Callable | None = None, client: Any = None,
               workers: int | None = None, errors: str = "raise", progress: Any = None,
               chunksize: int | None = None, mp_context: str | None = None) -> list[Any]:
    """Solve many independent bodies or scenes, in parallel; results in input order.

    Parameters
    ----------
    items : iterable
        Each one of: a mapping of the solver's keyword arguments (by default
        :func:`~thetasol.solve_rotation`'s ``I, a, Q0, omega0``, optionally ``dps``); a tuple of its
        positional arguments; a :class:`~thetasol.scenes.format.Scene` or the path of a scene file
        (solved by ``scene.solution()``, the split of Theorem 2).
    t : array_like, optional
        Evaluate each solution at ``t`` where it is solved and return ``sol(t)`` (tuples of state
        arrays; :class:`~thetasol.mechanics.trajectories.Trajectories` for scenes) instead of the
        solution objects, which are larger to send back (a theta-function rotation ~1 MB).
    solver : callable, optional
        What mappings and tuples are passed to, e.g. :func:`thetasol.solve_gyrostat` or
        ``functools.partial(solve_rotation, dps=30)``; it must be picklable (defined at module
        level) for a pool or a cluster.  Default :func:`~thetasol.solve_rotation`.
    client : dask.distributed.Client, "dask" or concurrent.futures.Executor, optional
        Where to run: a Dask cluster (``"dask"``: the current default client; Dask is the optional
        extra ``thetasol[dask]``), or an executor you own (kept open: reuse it across calls to pay the
        workers' start-up once).  Default: a local process pool for this call.
    workers : int, optional
        Processes of the local pool (default: the cores this process may use); ``1`` solves in this
        process, without a pool.  Ignored with ``client``.
    errors : {"raise", "return"}
        What an item whose solver raises :data:`EXPECTED_ERRORS` (``ClosedFormUnavailable`` for valid
        data outside the closed forms, ``ValueError`` for bad data) does: ``"raise"`` re-raises the
        first such error to arrive (with a note naming the item) and cancels the rest;
        ``"return"`` puts the exception object in that item's place and carries on.  Any other
        exception is a fault and is raised in both modes, naming the item.
    progress : bool, callable or None
        ``None``: a tqdm bar when tqdm is installed and there are at least ``PROGRESS_MIN_ITEMS`` items;
        ``True``: a bar (ImportError naming the extra ``thetasol[progress]`` without tqdm); ``False``:
        none; a callable is called as ``progress(done, total)`` after every finished chunk.
    chunksize : int, optional
        Items per task sent to a worker (default: enough tasks for 8 per worker, at most 16 items
        each; larger chunks pay less overhead per item, smaller ones balance uneven set-ups better).
    mp_context : str, optional
        Start method of the local pool (default ``"spawn"``, safe with threads and on every platform).

    Returns
    -------
    list
        One entry per item, in input order: the solution (or ``sol(t)``), or with ``errors="return"``
        the ``ClosedFormUnavailable`` / ``ValueError`` instance of an item without one.

    Warns
    -----
    Every warning an item raised where it was solved is re-issued here, its message prefixed with
    ``item i:`` (e.g. the theta set-up's RuntimeWarning on lost accuracy).

    Raises
    ------
    ValueError
        Bad arguments of ``solve_many`` itself (``errors``, ``workers``, ``chunksize``, ``client``), or
        (``errors="raise"``) an item's ``ValueError``.
    TypeError
        An item of none of the kinds above, or a ``client`` of none of the kinds above.
    ClosedFormUnavailable
        (``errors="raise"``) the first item without a closed form.

    Examples
    --------
    >>> import numpy as np
    >>> bodies = [dict(I=[5.5, 4.5, 3.0], a=np.zeros((3, 3)), Q0=np.eye(3), omega0=[0.1, 1.0, w])
    ...           for w in (0.2, 0.3)]
    >>> [(s.model, s.method) for s in solve_many(bodies, workers=1)]
    [('rotation', 'elliptic'), ('rotation', 'elliptic')]
    """
    if errors not in ("raise", "return"):
        raise ValueError(f"errors must be 'raise' or 'return', got {errors!r}")
    for name, v in (("workers", workers), ("chunksize", chunksize)):
        if v is not None and (not isinstance(v, (int, np.integer)) or v < 1):
            raise ValueError(f"{name} must be a positive integer or None, got {v!r}")
    tasks = [_task(i, item, solver) for i, item in enumerate(items)]
    if not tasks:
        return []
    tt = None if t is None else np.asarray(t, dtype=float)
    size = chunksize or max(1, min(16, math.ceil(len(tasks) / (8 * _parallelism(client, workers)))))
    chunks = _chunks(tasks, size)
    results: list[Any] = [None] * len(tasks)
    bar = _Progress(progress, len(tasks))
    finished = _engine(client, workers, len(chunks), chunks, tt, mp_context)
    try:
        for outcomes in finished:
            for o in outcomes:
                for category, message in o.warned:
                    warnings.warn(f"item {o.index}: {message}", category, stacklevel=2)
                if o.error is not None and errors == "raise":
                    o.error.add_note(f"solve_many: item {o.index} of {len(tasks)}")
                    raise o.error
                results[o.index] = o.error if o.error is not None else o.value
            bar.advance(len(outcomes))
    finally:
        finished.close()   # stops the pool or cancels the cluster's tasks now, also on an error
        bar.close()
    return results
