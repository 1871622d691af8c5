"""What the rotation integrators share: output-time bookkeeping, the solve_ivp run on the state
(m, Q), and the inertia of an extended-precision reference."""
from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp


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


def solve_ivp_mQ(rhs: Callable, m0: np.ndarray, Q0: np.ndarray, grid: np.ndarray, rtol: float, atol: float,
                 method: str) -> tuple[np.ndarray, np.ndarray]:
    """scipy's ``solve_ivp`` on the flat state ``(m, Q)`` from ``t = 0`` through ``grid``: the momenta
    ``(k, 3)`` and attitudes ``(k, 3, 3)`` there; a failed integration raises ``RuntimeError``."""
    y0 = np.concatenate([m0, Q0.ravel()])
    sol = solve_ivp(rhs, (0.0, grid[-1]), y0, method=method, t_eval=grid, rtol=rtol, atol=atol)
    if not sol.success:
        raise RuntimeError(f"integration failed: {sol.message}")
    y = sol.y.T
    return y[:, :3], y[:, 3:].reshape(-1, 3, 3)


def extended_inertia(M: np.ndarray, w0: np.ndarray, fp: type, *, from_moments: bool = False
                     ) -> tuple[list, list]:
    """``I^-1`` and ``m0 = I omega0`` of the float64 data as lists of ``fp`` numbers (np.longdouble,
    heyoka.real128), for an extended-precision reference.

    ``M`` is the inertia ``I``, or with ``from_moments`` the second moments ``J`` (then
    ``I = tr(J) 1 - J`` is formed exactly).  Everything is formed in mpmath at 60 digits and rounded
    once to ``fp`` as the sum of the float64 triple-word split: the float64 inverse of the float64
    inertia is another body, about one ulp away, and next to an unstable relative equilibrium that
    ulp moves the trajectory far more than the data's conditioning (tests/test_equations.py).
    """
    import mpmath

    with mpmath.workdps(60):
        def to_fp(x):
            parts = []
            for _ in range(3):
                parts.append(float(x))
                x = x - mpmath.mpf(parts[-1])
            return (fp(parts[0]) + fp(parts[1])) + fp(parts[2])

        Mmp = mpmath.matrix([[mpmath.mpf(float(x)) for x in row] for row in M])
        Imp = (Mmp[0, 0] + Mmp[1, 1] + Mmp[2, 2]) * mpmath.eye(3) - Mmp if from_moments else Mmp
        Iinv = Imp ** -1
        m0 = Imp * mpmath.matrix([mpmath.mpf(float(x)) for x in w0])
        return [[to_fp(Iinv[i, k]) for k in range(3)] for i in range(3)], [to_fp(m0[i]) for i in range(3)]


def heyoka_and_type(dtype: str) -> tuple[Any, type]:
    """The heyoka module and the float type of ``dtype`` ('dbl', 'ldbl' or 'f128') for method='heyoka'.

    heyoka is optional: its absence is an ImportError naming the extra; a wrong ``dtype`` a ValueError.
    """
    try:
        import heyoka as hy
    except ImportError as exc:  # pragma: no cover - exercised only without the extra
        raise ImportError("method='heyoka' needs the optional extra: pip install 'thetasol[bench]'") from exc
    fp = {"dbl": float, "ldbl": np.longdouble, "f128": hy.real128}
    if dtype not in fp:
        raise ValueError(f"dtype must be 'dbl', 'ldbl' or 'f128', got {dtype!r}")
    return hy, fp[dtype]
