"""The output-time bookkeeping the rotation integrators share."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np


def both_ways(t: np.ndarray, m0: np.ndarray, Q0: np.ndarray,
              run: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Integrate once over the distinct times, forward for ``t > 0`` and backward for ``t < 0``.

    ``run(grid)`` integrates from ``t = 0`` through the monotone ``grid`` (all positive, or all
    negative and decreasing) and returns the momenta ``(k, 3)`` and attitudes ``(k, 3, 3)`` there.
    Returns ``(m, Q, inverse)`` over the sorted distinct times (the initial state at ``t = 0``) and
    the index that maps them back to ``t.ravel()``.
    """
    ts, inv = np.unique(t.ravel(), return_inverse=True)
    m_out = np.tile(m0, (ts.size, 1))
    Q_out = np.tile(Q0, (ts.size, 1, 1))
    for sel in (ts > 0, ts < 0):
        if not sel.any():
            continue
        idx = np.flatnonzero(sel)
        if ts[idx[0]] < 0:
            idx = idx[::-1]
        m_out[idx], Q_out[idx] = run(ts[idx])
    return m_out, Q_out, inv
