"""The planar pendulum ``psi'' = -nu^2 sin psi`` in Jacobi elliptic functions.

Libration ``sin(psi/2) = k sn(nu t + u0 | k^2)``, circulation ``psi/2 = am(k nu t + u0 | 1/k^2)``,
the separatrix ``sin(psi/2) = tanh(nu t + u0)`` and uniform rotation.  Shared by the rotation
about a fixed principal axis and by the planar motion of Neumann's problem.
"""
from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from thetasol.special.elliptic import ellipf, ellipj

__all__ = ["pendulum_angle", "pendulum_params"]


def pendulum_angle(c: Mapping[str, float | str], t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """phi(t), phidot(t) from the closed form chosen at set-up."""
    kind = c["kind"]
    if kind == "uniform":
        return c["phi0"] + c["w0"] * t, np.full_like(t, c["w0"])
    nu, m, mc, u0, sgn = c["nu"], c.get("m"), c.get("mc"), c["u0"], c["sign"]
    if kind == "libration":
        sn, cn, dn, _ = ellipj(nu * t + u0, m, mc)
        k = np.sqrt(m)
        psi = 2.0 * np.arctan2(k * sn, dn)            # sin(psi/2) = k sn, cos(psi/2) = dn
        psidot = 2.0 * k * nu * cn
    elif kind == "circulation":
        k = c["k"]
        sn, cn, dn, am = ellipj(k * nu * t + u0, m, mc)
        psi = sgn * 2.0 * am
        psidot = sgn * 2.0 * k * nu * dn
    else:  # separatrix: sin(psi/2) = sign tanh(s), cos(psi/2) = sech(s)
        s = nu * t + u0
        psi = sgn * 2.0 * np.arctan2(np.tanh(s), 1.0 / np.cosh(s))
        psidot = sgn * 2.0 * nu / np.cosh(s)
    return 0.5 * (psi - c["psi0"]), 0.5 * psidot


def pendulum_params(psi0: float, psidot0: float, nu: float) -> tuple[dict[str, float | str], float]:
    """Constants of :func:`pendulum_angle` for ``psi'' = -nu^2 sin psi`` (``nu > 0``) from ``psi0``
    in (-pi, pi] and ``psidot0``: libration, circulation (parameter 1/m) or the separatrix.

    Returns (dict with ``kind`` and its constants, ``m = k^2``, the energy parameter).
    """
    s2, c2 = np.sin(0.5 * psi0), np.cos(0.5 * psi0)
    # m = k^2 = psidot^2 / (4 nu^2) + sin^2(psi/2);  1 - m = cos^2(psi/2) - psidot^2 / (4 nu^2)
    x = psidot0 / (2.0 * nu)
    m = x * x + s2 * s2
    mc = (c2 - x) * (c2 + x)
    c = {"nu": nu, "psi0": psi0}
    if mc > 0:
        # sn(u0) = sin(psi0/2) / k, cn(u0) = psidot0 / (2 k nu)
        u0 = float(ellipf(np.arctan2(s2, x), m, mc)) if m > 0 else 0.0
        c.update(kind="libration", m=m, mc=mc, u0=u0, sign=1.0)
        return c, m
    sgn = 1.0 if psidot0 >= 0 else -1.0
    if mc < 0:
        mm, mmc = 1.0 / m, -mc / m
        c.update(kind="circulation", m=mm, mc=mmc, u0=float(ellipf(sgn * 0.5 * psi0, mm, mmc)),
                 k=np.sqrt(m), sign=sgn)
    else:
        c.update(kind="separatrix", u0=float(np.arctanh(np.clip(sgn * s2, -1.0, 1.0))), sign=sgn)
    return c, m
