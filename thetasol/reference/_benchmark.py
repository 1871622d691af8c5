"""Work-precision benchmark of a user's integrator over the reference cases."""
from __future__ import annotations

import time
from collections.abc import Callable, Sequence

import numpy as np

from thetasol.reference._case import Case

__all__ = ["Table", "benchmark"]

_COLUMNS = ("case", "model", "rtol", "error", "nfev", "seconds", "success", "message")


class Table(list):
    """A list of dict rows (one per case and tolerance) that prints as a fixed-width table."""

    def __str__(self) -> str:
        head = f"{'case':<26s} {'rtol':>8s} {'error':>10s} {'nfev':>8s} {'seconds':>9s}  ok"
        lines = [head, "-" * len(head)]
        for r in self:
            lines.append(f"{r['case']:<26s} {r['rtol']:8.0e} {r['error']:10.2e} {r['nfev']:8d} "
                         f"{r['seconds']:9.4f}  {'yes' if r['success'] else 'NO'}")
        return "\n".join(lines)


def _figure(table: Table):
    """Error against right-hand-side evaluations, one line per case; None without matplotlib."""
    try:
        from matplotlib.figure import Figure
    except ImportError:
        return None
    fig = Figure(figsize=(7, 5))
    ax = fig.add_subplot()
    for i, name in enumerate(dict.fromkeys(r["case"] for r in table)):
        rows = [r for r in table if r["case"] == name and r["success"] and np.isfinite(r["error"])]
        if rows:                      # ten colours per line style
            ax.loglog([max(r["error"], 1e-17) for r in rows], [r["nfev"] for r in rows], marker="o",
                      ls=("-", "--", ":")[(i // 10) % 3], label=name, ms=3)
    ax.set_xlabel("max relative error (worst component group)")
    ax.set_ylabel("right-hand-side evaluations")
    ax.set_title("work-precision on the thetasol reference cases")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=6, ncol=2)
    return fig


def benchmark(solver: Callable, cases: Sequence[Case] | None = None,
              rtols: Sequence[float] = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12), *, n_eval: int = 101,
              atol_factor: float = 1.0, plot: bool = True) -> tuple[Table, object | None]:
    """Run ``solver`` over the cases at each tolerance and score it against the exact solutions.

    Parameters
    ----------
    solver : callable
        ``solver(fun, t_span, y0, t_eval=..., rtol=..., atol=...)`` returning an object with
        ``t``, ``y`` (``(n, len(t))``) and optionally ``nfev`` and ``success``, as
        :func:`scipy.integrate.solve_ivp` does (e.g. ``functools.partial(solve_ivp, method="RK45")``).
    cases : sequence of Case, optional
        Default: the whole catalogue (:func:`thetasol.reference.cases`).
    rtols : sequence of float
        Relative tolerances; ``atol = atol_factor * rtol`` (the states are of order one).
    n_eval : int
        Output times per case (``case.times(n_eval)``), where the error is measured.
    plot : bool
        Build the work-precision figure (needs matplotlib; None when absent or ``plot=False``).

    Returns
    -------
    table : Table
        Rows ``{"case", "model", "rtol", "error", "nfev", "seconds", "success"}``; ``error`` is
        ``case.score(...).worst`` (NaN when the solver failed); prints as a table.
    figure : matplotlib.figure.Figure or None
        Error against right-hand-side evaluations (log-log), one line per case.
    """
    if cases is None:
        from thetasol.reference.catalogue import cases as _all
        cases = _all()
    table = Table()
    for c in cases:
        t_eval = c.times(n_eval)
        c.exact(t_eval)                          # build the closed form outside the timing
        for rtol in rtols:
            start = time.perf_counter()
            try:
                res = solver(c.rhs, c.t_span, c.y0, t_eval=t_eval, rtol=rtol, atol=atol_factor * rtol)
                ok = bool(getattr(res, "success", True))
            except Exception as exc:  # a failing integrator is a result, not an error of the benchmark
                res, ok = None, False
                err_msg = f"{type(exc).__name__}: {exc}"
            else:
                err_msg = ""
            secs = time.perf_counter() - start
            err = float("nan")
            if res is not None and ok and np.shape(res.y)[-1] == t_eval.size:
                err = c.score(res.t, res.y).worst
            table.append({"case": c.name, "model": c.model, "rtol": float(rtol), "error": err,
                          "nfev": int(getattr(res, "nfev", -1)) if res is not None else -1,
                          "seconds": secs, "success": ok and np.isfinite(err), "message": err_msg})
    return table, (_figure(table) if plot else None)
