"""pytest plugin: the fixture ``thetasol_case``, one test per exact reference case.

Installed thetasol registers this module as the ``pytest11`` entry point ``thetasol``, so any
project's tests can ask for the fixture; without the install, load it with
``pytest -p thetasol.reference.pytest_plugin`` (not both: pytest refuses to register the module
twice).  A test that takes ``thetasol_case`` runs once per case of :func:`thetasol.reference.cases`
(test ids are the case names)::

    def test_my_integrator(thetasol_case):
        sol = my_solve_ivp(thetasol_case.rhs, thetasol_case.t_span, thetasol_case.y0, t_eval=thetasol_case.times())
        assert thetasol_case.score(sol.t, sol.y).worst < 1e-8

``--thetasol-cases=NAME,NAME`` restricts the cases, ``--thetasol-model=MODEL`` to one model; an
unknown name is a usage error that lists the known ones.

Every pytest session in an environment where thetasol is installed loads this module, so it imports
only pytest at load time; the catalogue (numpy and the closed forms) is imported when a test asks
for the fixture or an option names a case.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    from thetasol.reference._case import Case


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("thetasol", "thetasol exact reference cases")
    group.addoption("--thetasol-cases", default=None,
                    help="comma-separated case names for the thetasol_case fixture (default: all)")
    group.addoption("--thetasol-model", default=None,
                    help="only the cases of this model (e.g. 'heavy top')")


def _requested(config: pytest.Config) -> list[str] | None:
    """The case names of ``--thetasol-cases`` (None: all cases)."""
    names = config.getoption("--thetasol-cases")
    return [n.strip() for n in names.split(",") if n.strip()] if names else None


def pytest_configure(config: pytest.Config) -> None:
    """Refuse unknown case or model names before collection, as a usage error naming the known ones
    (not as an error inside the user's test file)."""
    names, model = _requested(config), config.getoption("--thetasol-model")
    if names is None and model is None:
        return
    from thetasol.reference import cases

    known = cases()
    unknown = [n for n in names or () if n not in {c.name for c in known}]
    if unknown:
        raise pytest.UsageError(f"--thetasol-cases: unknown reference case(s) {', '.join(unknown)}; "
                                f"known: {', '.join(c.name for c in known)}")
    models = list(dict.fromkeys(c.model for c in known))
    if model is not None and model not in models:
        raise pytest.UsageError(f"--thetasol-model: unknown model {model!r}; known: {', '.join(models)}")


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    if "thetasol_case" not in metafunc.fixturenames:
        return
    from thetasol.reference import cases

    selected = cases(_requested(metafunc.config), model=metafunc.config.getoption("--thetasol-model"))
    metafunc.parametrize("thetasol_case", selected, ids=[c.name for c in selected], indirect=True)


@pytest.fixture
def thetasol_case(request: pytest.FixtureRequest) -> Case:
    """One :class:`thetasol.reference.Case` (the test runs once per case of the catalogue)."""
    return request.param
