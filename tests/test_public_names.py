"""What a user sees of the package: ``dir(thetasol)`` and ``dir(thetasol.reference)`` list the API
and nothing of the machinery that loads it lazily."""
import subprocess
import sys

import thetasol
from thetasol import reference


def test_dir_thetasol_is_the_api():
    names = dir(thetasol)
    assert names == sorted(thetasol.__all__)
    assert {"solve_rotation", "integrate_rotation", "Solution", "reference", "__version__"} <= set(names)
    assert not {"TYPE_CHECKING", "annotations", "importlib"} & set(names)
    assert [n for n in names if n.startswith("_")] == ["__version__"]


def test_every_listed_name_loads():
    """Each name of ``__all__`` resolves (the lazy table names a module that defines it)."""
    for name in thetasol.__all__:
        assert getattr(thetasol, name) is not None, name
    for name in reference.__all__:
        assert getattr(reference, name) is not None, name


def test_dir_reference_is_its_api():
    assert dir(reference) == sorted(reference.__all__)
    assert {"Case", "case", "cases", "names", "benchmark"} <= set(dir(reference))


def test_dir_is_the_api_in_a_fresh_interpreter():
    """Before any name is loaded (nothing cached in the module's globals yet), too."""
    code = "import thetasol; print(' '.join(dir(thetasol)))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)
    assert out.stdout.split() == sorted(thetasol.__all__)


def test_reference_names_are_not_shadowed_by_modules():
    """Whatever is loaded first, ``reference.benchmark`` is the function (no submodule of that name
    replaces it in the package), in a fresh interpreter."""
    code = ("import types; from thetasol import reference; reference.Table; import thetasol.reference._case; "
            "print(callable(reference.benchmark) and not isinstance(reference.benchmark, types.ModuleType))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)
    assert out.stdout.strip() == "True"
