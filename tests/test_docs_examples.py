"""The code the user guide shows runs, and the signatures it lists are the library's.

The quick start and the README are not executed by the docs build (only the notebooks are), so this
runs their ``python`` blocks in order, each page in one namespace as a reader would paste them; the
example test of the pytest plugin is called with a case of the catalogue.  The ``>>>`` examples of
docs/results.md run as doctests.  The entry-point tables of docs/api_conventions.md are compared with
``inspect.signature`` of the public functions: the parameters they name, in order, with ``*`` where
the keyword-only ones begin and the defaults they state.
"""
from __future__ import annotations

import doctest
import inspect
import re
from pathlib import Path

import numpy as np
import pytest

import thetasol

ROOT = Path(__file__).resolve().parents[1]
PYTHON_BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)
# `name(arguments)` inside backticks, for a public function of thetasol
CALL = re.compile(r"`((?:solve|integrate)_\w+)\(([^`]*)\)`")


def python_blocks(page: str) -> list[str]:
    return PYTHON_BLOCK.findall((ROOT / page).read_text())


@pytest.mark.parametrize("page", ["docs/quickstart.md", "README.md"])
def test_page_code_runs(page, monkeypatch):
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "1")
    blocks = python_blocks(page)
    assert blocks, f"{page}: no python blocks"
    namespace: dict = {}
    for block in blocks:
        exec(compile(block, page, "exec"), namespace)    # noqa: S102 - the page's own example code
    for name, value in list(namespace.items()):
        if name.startswith("test_") and callable(value):
            value(thetasol.reference.case("kepler_ellipse"))


def test_quickstart_shows_what_it_says():
    """The values the quick start's comments state: the method, the shapes, a passing check."""
    namespace: dict = {}
    for block in python_blocks("docs/quickstart.md")[:3]:
        exec(compile(block, "docs/quickstart.md", "exec"), namespace)  # noqa: S102
    sol, omega, Q = namespace["sol"], namespace["omega"], namespace["Q"]
    assert (sol.model, sol.method) == ("rotation", "theta/genus-4")
    assert omega.shape == (2001, 3) and Q.shape == (2001, 3, 3)
    assert sol.check().ok


def test_quickstart_case_names_exist():
    text = (ROOT / "docs/quickstart.md").read_text()
    named = re.findall(r"--thetasol-cases=([\w,]+)", text)
    assert named
    known = set(thetasol.reference.names())
    for group in named:
        assert set(group.split(",")) <= known, group


def test_results_doctest():
    text = "\n".join(block for block in python_blocks("docs/results.md") if ">>>" in block)
    parser = doctest.DocTestParser()
    test = parser.get_doctest(text, {"np": np, "thetasol": thetasol}, "docs/results.md", "docs/results.md", 0)
    assert test.examples
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    runner.run(test)
    assert runner.failures == 0


def documented_calls() -> list[tuple[str, str]]:
    text = (ROOT / "docs/api_conventions.md").read_text()
    return sorted({(name, args) for name, args in CALL.findall(text) if name in thetasol.__all__})


def test_api_conventions_lists_every_entry_point():
    names = {name for name, _ in documented_calls()}
    public = {n for n in thetasol.__all__ if n.startswith(("solve_", "integrate_"))}
    assert public - names == set()


@pytest.mark.parametrize("name, args", documented_calls(), ids=[name for name, _ in documented_calls()])
def test_api_conventions_signature(name, args):
    """The parameters the table names are the function's, in order (``...`` leaves out the rest)."""
    params = list(inspect.signature(getattr(thetasol, name)).parameters.values())
    expected: list[str] = []
    keyword_only_marked = False
    for p in params:
        if p.kind is p.KEYWORD_ONLY and not keyword_only_marked:
            expected.append("*")
            keyword_only_marked = True
        expected.append(p.name)
    tokens = [tok.strip() for tok in re.split(r",(?![^()]*\))", args) if tok.strip()]
    shown = [tok.split("=")[0].strip() for tok in tokens]
    if "..." in shown:
        shown = shown[:shown.index("...")]
        expected = expected[:len(shown)]
    assert shown == expected, f"{name}: docs/api_conventions.md shows ({args})"
    defaults = {p.name: p.default for p in params}
    for tok in tokens:
        if "=" in tok:
            key, value = (s.strip() for s in tok.split("=", 1))
            assert eval(value, {"float": float}) == defaults[key], f"{name}: default of {key}"  # noqa: S307


def test_reference_cases_page_lists_the_catalogue():
    """The generated case table of docs/reference_cases.md names every case with its method and case
    (benchmarks/bench_reference_cases.py rewrites it; a catalogue change without a rerun fails here)."""
    text = (ROOT / "docs/reference_cases.md").read_text()
    rows: dict = {}
    for line in text.splitlines():
        if line.startswith("| `"):
            rows.setdefault(line.split("|")[1].strip(" `"), line)       # the case table comes first
    for c in thetasol.reference.cases():
        method = f"`{c.method}`" + (f" ({c.solution.case})" if c.solution.case else "")
        assert c.name in rows and f"| {method} |" in rows[c.name], c.name


def test_every_public_name_has_an_api_page():
    """What docs/conf.py checks at build time (a warning, an error under ``sphinx -W``), without a build:
    every name of ``thetasol.__all__`` is documented by an ``auto...:: thetasol.<name>`` line of docs/api."""
    text = "".join(p.read_text() for p in (ROOT / "docs" / "api").glob("*.md"))
    documented = set(re.findall(r"^\.\. auto\w+:: thetasol\.(\w+)\s*$", text, re.M))
    assert set(thetasol.__all__) - {"__version__"} - documented == set()
