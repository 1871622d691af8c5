"""Sphinx configuration: the user guide (docs/*.md), the API reference (docs/api/) and the
executed example notebooks (docs/notebooks/*.md, MyST text notebooks without outputs).

Build: ``python -m sphinx -W -b html docs docs/_build/html`` (needs the ``docs`` extra).
"""
from __future__ import annotations

import os
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# the thetasol of this checkout, for autodoc and for the notebook kernels
sys.path.insert(0, str(ROOT))
os.environ["PYTHONPATH"] = os.pathsep.join(
    [str(ROOT)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p])
# the kernels show figures inline whatever backend the caller's environment names
os.environ["MPLBACKEND"] = "module://matplotlib_inline.backend_inline"
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import thetasol  # noqa: E402

project = "thetasol"
author = "thetasol contributors"
copyright = "thetasol contributors"
release = thetasol.__version__
version = release

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
]

# README.md and the build output are not pages; nothing else is excluded
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "**/.ipynb_checkpoints", "jupyter_execute"]
source_suffix = {".md": "myst-nb", ".ipynb": "myst-nb", ".rst": "restructuredtext"}

# MyST: $...$ maths, anchors for links such as [x](page.md#section)
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# notebooks: executed on every build, cached by their source (a changed cell re-runs the notebook)
nb_execution_mode = "cache"
nb_execution_timeout = 120
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_merge_streams = True

# API reference from the numpydoc docstrings
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_typehints_description_target = "documented"   # no second, undocumented parameter list
autodoc_default_options = {"members": True, "show-inheritance": True}
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_ivar = True          # "Attributes" sections as fields: no duplicate object descriptions
napoleon_use_rtype = False
napoleon_preprocess_types = False

html_theme = "furo"
html_title = f"thetasol {release}"
html_static_path: list[str] = []



def _check_api_coverage(app) -> None:
    """Warn (an error under -W) for a public name of thetasol that no API page documents."""
    from sphinx.util import logging
    logger = logging.getLogger(__name__)
    text = "".join(p.read_text() for p in (Path(app.srcdir) / "api").glob("*.md"))
    for name in sorted(set(thetasol.__all__) - {"__version__"}):
        if f"thetasol.{name}\n" not in text:
            logger.warning(f"thetasol.{name} is exported by thetasol/__init__.py but documented on no "
                           f"docs/api/*.md page: add it to the page of its concept")


_SECTION = re.compile(r"^\s*-{3,}\s*$")
_GROUPED = re.compile(r"^(\s*)([A-Za-z_]\w*(?:\s*,\s*[A-Za-z_]\w*)+)\s*:(.*)$")


def _split_grouped_attributes(app, what, name, obj, options, lines) -> None:
    """``a, b : type`` in an "Attributes" section becomes one entry per name (napoleon's fields
    take one name each; Parameters sections it splits itself)."""
    out, in_attributes, i = [], False, 0
    while i < len(lines):
        line = lines[i]
        if i + 1 < len(lines) and _SECTION.match(lines[i + 1]) and line.strip():
            in_attributes = line.strip() == "Attributes"
        match = _GROUPED.match(line) if in_attributes else None
        if match is None:
            out.append(line)
            i += 1
            continue
        indent, names, rest = match.groups()
        body = []
        i += 1
        while i < len(lines) and (not lines[i].strip() or
                                  len(lines[i]) - len(lines[i].lstrip()) > len(indent)):
            body.append(lines[i])
            i += 1
        for n in names.split(","):
            out += [f"{indent}{n.strip()} :{rest}"] + body
    lines[:] = out


def setup(app):
    app.connect("builder-inited", _check_api_coverage)
    # before napoleon (priority 500) turns the sections into fields
    app.connect("autodoc-process-docstring", _split_grouped_attributes, priority=400)
