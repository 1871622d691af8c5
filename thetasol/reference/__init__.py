"""Exact reference cases for testing numerical integrators (``thetasol.reference``).

Every model thetasol solves in closed form gives a few named initial-value problems: the model's
ODE ``y' = rhs(t, y)`` on a flat float state in :func:`scipy.integrate.solve_ivp`'s signature and
its exact solution ``exact(t)``, with ``score`` and ``report`` to measure a user's numerical states
against it, and ``export`` to CSV/JSON for other languages.  docs/reference_cases.md lists them.

>>> from scipy.integrate import solve_ivp
>>> from thetasol import reference
>>> c = reference.case("free_top_long_axis")
>>> sol = solve_ivp(c.rhs, c.t_span, c.y0, method="DOP853", rtol=1e-10, atol=1e-10, t_eval=c.times(21))
>>> c.score(sol.t, sol.y).worst < 1e-7
True

The names load on first use: the pytest plugin (:mod:`thetasol.reference.pytest_plugin`) is a
submodule that every pytest session in the environment imports, and importing this package must
not pull in numpy and the closed forms for the sessions that never ask for a case.  (The modules
behind the names are private: a submodule named like a function, once imported, would shadow it.)
"""
from __future__ import annotations

import importlib as _importlib
from typing import TYPE_CHECKING

#: public name -> module that defines it
_API = {"Case": "_case", "Group": "_case", "Report": "_case", "Score": "_case",
        "Table": "_benchmark", "benchmark": "_benchmark",
        "case": "catalogue", "cases": "catalogue", "names": "catalogue"}

__all__ = ["Case", "Group", "Report", "Score", "Table", "benchmark", "case", "cases", "names"]


def __getattr__(name: str):
    try:
        module = _API[name]
    except KeyError:
        raise AttributeError(f"module 'thetasol.reference' has no attribute {name!r}") from None
    value = getattr(_importlib.import_module(f"thetasol.reference.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)


if TYPE_CHECKING:
    from thetasol.reference._benchmark import Table, benchmark
    from thetasol.reference._case import Case, Group, Report, Score
    from thetasol.reference.catalogue import case, cases, names
