"""Numbers in scene files: what TOML gives must already be a number; a string is never read as one.

The API refuses strings where it takes numbers, and so do scene files: ``top = [0.5, 0.0, "12"]``
is a ``ValueError`` naming the entry (and :func:`~thetasol.scenes.format.load_scene` adds the file),
not the number 12.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from thetasol.core import validate as V

__all__ = ["number", "numeric_array"]


def _non_number(x: Any) -> Any:
    """The first entry of the (nested) list ``x`` that is not an int or a float (bools are not numbers), or None."""
    if isinstance(x, (list, tuple)):
        for item in x:
            bad = _non_number(item)
            if bad is not None:
                return bad
        return None
    if isinstance(x, bool) or not isinstance(x, (int, float, np.integer, np.floating)):
        return x
    return None


def number(x: Any, where: str, positive: bool = False) -> float:
    """``x`` as a float: a finite int or float (positive if asked), else ``ValueError`` naming ``where``."""
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        raise ValueError(f"{where} must be a number, got {x!r}" + (" (a string, not a number)" if isinstance(x, str)
                                                                   else ""))
    x = float(x)
    if not np.isfinite(x):
        raise ValueError(f"{where} must be finite, got {x!r}")
    if positive and x <= 0:
        raise ValueError(f"{where} must be positive, got {x!r}")
    return x


def numeric_array(x: Any, where: str, shape: tuple | None = None) -> np.ndarray:
    """``x``, a number or a (nested) list of numbers, as a finite float array (of ``shape`` if given)."""
    if isinstance(x, np.ndarray) and x.dtype.kind in "fiu":
        return V.finite_array(x, where, shape)
    bad = _non_number(x)
    if bad is not None:
        kind = "a string" if isinstance(bad, str) else type(bad).__name__
        raise ValueError(f"{where} must be numbers, got {bad!r} ({kind}, not a number) in {x!r}")
    try:
        arr = np.array(x, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where} must be a (nested) list of numbers, got {x!r}") from exc
    return V.finite_array(arr, where, shape)
