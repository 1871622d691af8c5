"""pytest plugin: the fixture ``thetasol_case``, one test per exact reference case.

Installed thetasol registers this module as the ``pytest11`` entry point ``thetasol``, so any
project's tests can ask for the fixture; without the install, load it with
``pytest -p thetasol.reference.pytest_plugin`` (not both: pytest refuses to register the module
twice).  A test that takes ``thetasol_case`` runs once per case of :func:`thetasol.reference.cases`
(test ids are the case names)::

    def test_my_integrator(thetasol_case):
        sol = my_solve_ivp(thetasol_case.rhs, thetasol_case.t_span, thetasol_case.y0, t_eval=thetasol_case.times())
        assert thetasol_case.score(sol.t, sol.y).worst < 1e-8

``--thetasol-cases=NAME,NAME`` restricts the cases, ``--thetasol-model=MODEL`` to one model.
"""
from __future__ import annotations

import pytest

from thetasol.reference._case import Case


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("thetasol", "thetasol exact reference cases")
    group.addoption("--thetasol-cases", default=None,
                    help="comma-separated case names for the thetasol_case fixture (default: all)")
    group.addoption("--thetasol-model", default=None,
                    help="only the cases of this model (e.g. 'heavy top')")


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    if "thetasol_case" not in metafunc.fixturenames:
        return
    from thetasol.reference import cases

    opt = metafunc.config.getoption
    names = opt("--thetasol-cases")
    selected = cases([n.strip() for n in names.split(",") if n.strip()] if names else None,
                     model=opt("--thetasol-model"))
    metafunc.parametrize("thetasol_case", selected, ids=[c.name for c in selected], indirect=True)


@pytest.fixture
def thetasol_case(request: pytest.FixtureRequest) -> Case:
    """One :class:`thetasol.reference.Case` (the test runs once per case of the catalogue)."""
    return request.param
