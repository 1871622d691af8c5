"""What the numerical references share: output-time bookkeeping, the solve_ivp run on the state
(m, Q), the checked options, the body's inertia and that of an extended-precision reference."""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import solve_ivp

from thetasol.core import validate as V
from thetasol.core.inertia import second_moments


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


def extended_inertia(Im: np.ndarray, w0: np.ndarray, fp: type) -> tuple[list, list]:
    """``I^-1`` and ``m0 = I omega0`` of the float64 inertia ``Im`` (3x3) and ``w0`` as lists of ``fp`` numbers
    (np.longdouble, heyoka.real128), for an extended-precision reference.

    Both are formed in mpmath at 60 digits and rounded once to ``fp`` as the sum of the float64 triple-word
    split: the float64 inverse of the float64 inertia is another body, about one ulp away, and next to an
    unstable relative equilibrium that ulp moves the trajectory far more than the data's own conditioning
    (tests/test_equations.py).
    """
    import mpmath

    with mpmath.workdps(60):
        def to_fp(x):
            parts = []
            for _ in range(3):
                parts.append(float(x))
                x = x - mpmath.mpf(parts[-1])
            return (fp(parts[0]) + fp(parts[1])) + fp(parts[2])

        Imp = mpmath.matrix([[mpmath.mpf(float(x)) for x in row] for row in Im])
        Iinv = Imp ** -1
        m0 = Imp * mpmath.matrix([mpmath.mpf(float(x)) for x in w0])
        return [[to_fp(Iinv[i, k]) for k in range(3)] for i in range(3)], [to_fp(m0[i]) for i in range(3)]


#: The explicit methods of :func:`scipy.integrate.solve_ivp` (the implicit ones need no other data here either).
SCIPY_METHODS = ("RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA")


@dataclass(frozen=True)
class Settings:
    """The checked options of one numerical reference: its integrator and tolerances.

    ``method`` is a :data:`SCIPY_METHODS` name, ``"splitting"`` or ``"heyoka"``; ``atol`` None means the
    reference's own default (a fraction of ``rtol`` times the state's scale); ``fp_type`` the floating
    type of heyoka's arithmetic; ``step`` the fixed step of the splitting.
    """

    method: str = "DOP853"
    rtol: float = 1e-12
    atol: float | None = None
    fp_type: Any = float
    step: float | None = None

    def diagnostics(self) -> dict:
        """The settings as diagnostics; ``error_estimate`` is the integrator's relative tolerance (the
        error it controls per step, not a bound on the global error)."""
        return {"error_estimate": self.rtol, "integrator": self.method, "rtol": self.rtol, "atol": self.atol,
                "fp_type": getattr(self.fp_type, "__name__", str(self.fp_type)), "step": self.step}


def settings(method: str, rtol: float, atol: float | None, fp_type: Any = float, step: float | None = None, *,
             methods: tuple[str, ...] = (*SCIPY_METHODS, "heyoka")) -> Settings:
    """Check the options scipy-style: an unknown method, a tolerance outside (0, 1) or an option that the
    chosen method would ignore (``step`` without the splitting, ``atol`` with heyoka or the splitting,
    ``fp_type`` other than float without heyoka) is a ``ValueError`` naming it."""
    if not isinstance(method, str) or method not in methods:
        raise ValueError(f"method must be one of {', '.join(methods)}; got {method!r}")
    if isinstance(rtol, bool) or not isinstance(rtol, (int, float, np.floating)) or not 0 < rtol < 1:
        raise ValueError(f"rtol must be in (0, 1), got {rtol!r}")
    if step is not None and method != "splitting":
        raise ValueError(f"step= is an option of method='splitting'; method={method!r} ignores it")
    if step is not None and not (isinstance(step, (int, float, np.floating)) and np.isfinite(step) and step > 0):
        raise ValueError(f"step must be a positive number, got {step!r}")
    if atol is not None and method in ("heyoka", "splitting"):
        raise ValueError(f"atol= is an option of the solve_ivp methods; method={method!r} ignores it (rtol sets "
                         "its accuracy)")
    if atol is not None and not (isinstance(atol, (int, float, np.floating)) and atol > 0):
        raise ValueError(f"atol must be a positive number, got {atol!r}")
    if fp_type is np.float64:
        fp_type = float
    if fp_type is not float and method != "heyoka":
        raise ValueError(f"fp_type= other than float is an option of method='heyoka'; method={method!r} computes in "
                         "float64")
    return Settings(method, float(rtol), None if atol is None else float(atol), fp_type,
                    None if step is None else float(step))


def heyoka_and_type(fp_type: Any) -> tuple[Any, type]:
    """The heyoka module and ``fp_type`` (float, numpy.longdouble or heyoka.real128) for method='heyoka'.

    heyoka is optional: its absence is an ImportError naming the extra; another type a ValueError.
    """
    try:
        import heyoka as hy
    except ImportError as exc:  # pragma: no cover - exercised only without the extra
        raise ImportError("method='heyoka' needs the optional extra: pip install 'thetasol[bench]'") from exc
    if fp_type not in (float, np.longdouble, hy.real128):
        raise ValueError(f"fp_type must be float, numpy.longdouble or heyoka.real128, got {fp_type!r}")
    return hy, fp_type


def heyoka_tol(hy: Any, fp_type: Any, rtol: float) -> Any:
    """heyoka's tolerance ``rtol`` in ``fp_type`` (for real128 through its decimal string, as given)."""
    return hy.real128(str(rtol)) if fp_type is hy.real128 else fp_type(rtol)


def body_inertia(I: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The checked inertia ``I`` (principal values or a symmetric tensor) as a 3x3 array, and its second
    moments ``J = tr(I)/2 1 - I`` (the form the torque of a quadratic potential takes)."""
    Im = V.inertia(I, "I")
    return Im, second_moments(Im)
