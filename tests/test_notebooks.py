"""The example notebooks of the documentation (docs/notebooks/*.md, MyST text notebooks) run without error.

Each is converted with jupytext and executed cell by cell with nbclient in a fresh kernel of this
interpreter (the equivalent of ``pytest --nbmake`` for text notebooks); the docs build executes them
too.  The two longest (the oracle sweeps several integrators and tolerances over a genus-4 motion, the
Kovalevskaya top builds its genus-2 theta functions) are marked slow (``python -m pytest -m slow``).
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

NOTEBOOKS = sorted((Path(__file__).resolve().parents[1] / "docs" / "notebooks").glob("*.md"))
SLOW = {"oracle", "kovalevskaya_top"}


def _kernel_manager():
    """A python3 kernel of this interpreter (not whatever 'python' is first on PATH)."""
    from jupyter_client.manager import KernelManager

    km = KernelManager(kernel_name="python3")
    km.kernel_spec.argv[0] = sys.executable
    return km


@pytest.mark.parametrize("path", [pytest.param(p, id=p.stem, marks=[pytest.mark.slow] if p.stem in SLOW else [])
                                  for p in NOTEBOOKS])
def test_notebook_runs(path, monkeypatch):
    jupytext = pytest.importorskip("jupytext")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    pytest.importorskip("matplotlib")
    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "1")
    # the kernel imports the thetasol these tests import (a checkout or the installed package)
    root = str(Path(__import__("thetasol").__file__).resolve().parents[1])
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([root] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
    nb = jupytext.read(path)
    assert any(c.cell_type == "code" for c in nb.cells), f"{path.name}: no code cells (not a MyST notebook?)"
    client = nbclient.NotebookClient(nb, km=_kernel_manager(), timeout=300,
                                     resources={"metadata": {"path": str(path.parent)}})  # as the docs build runs it
    client.execute()        # raises CellExecutionError naming the cell and its traceback
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", []) if o.output_type == "error"]
    assert errors == []
