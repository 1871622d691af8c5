"""The compiled core: the per-time evaluation of the theta-function rotation (src/kernels.cpp).

:class:`FlowKernel` evaluates theta along a real linear flow from the frozen tables of
:class:`thetasol.theta.flow.FlowTheta`; :class:`RotationKernel` the state ``(omega, Q)`` from those of
:class:`thetasol.solutions.rotation.theta_rotation.evaluator.FlowEvaluator`.  The Python side validates, builds the
tables and owns what a user sees; the kernels only compute (docs/architecture.md).

The extension ``_kernels`` is built by ``pip install`` (scikit-build-core, nanobind, the system C++17
compiler).  A source checkout imported ahead of an installed thetasol has no build of its own
(``python -m pytest`` from the checkout puts it first on ``sys.path``): it then loads the build of the
installed distribution, which ``pip install .`` made from the same sources.
"""
from __future__ import annotations

import importlib.machinery
import importlib.util
import sys

__all__ = ["FlowKernel", "RotationKernel"]

#: What a missing build says: how to make one.
NOT_BUILT = ("thetasol's compiled core (thetasol.core._kernels) is not built: install the package with "
             "`pip install .` (it compiles the extension; a C++17 compiler is needed), or for development "
             "`pip install --no-build-isolation -e .` (docs/architecture.md)")


def _load_installed():
    """The ``_kernels`` extension of the installed thetasol distribution, registered under its name, or
    ImportError saying how to build it."""
    import importlib.metadata  # here: its import costs more than the rest of the module's

    name = __name__.rpartition(".")[0] + "._kernels"
    try:
        files = importlib.metadata.distribution("thetasol").files or []
    except importlib.metadata.PackageNotFoundError:
        files = []
    for f in files:
        if (f.parent.as_posix() == "thetasol/core" and f.name.startswith("_kernels.")
                and f.name.endswith(tuple(importlib.machinery.EXTENSION_SUFFIXES))):
            spec = importlib.util.spec_from_file_location(name, f.locate())
            module = importlib.util.module_from_spec(spec)
            sys.modules[name] = module
            spec.loader.exec_module(module)
            return module
    raise ImportError(NOT_BUILT)


if importlib.util.find_spec(__name__.rpartition(".")[0] + "._kernels") is None:
    _kernels = _load_installed()
else:
    from thetasol.core import _kernels

FlowKernel = _kernels.FlowKernel
RotationKernel = _kernels.RotationKernel
