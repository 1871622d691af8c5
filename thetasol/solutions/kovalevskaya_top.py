"""Kovalevskaya's top, stage 1 of its closed form: the separating variables and the genus-2 curve.

Not yet a solution: :func:`thetasol.solutions.heavy_top.solve_heavy_top` recognizes the top and
raises ``ClosedFormUnavailable``.  What is here is checked along 80-bit heyoka trajectories
(tests/test_heavy_top.py) and is the input of the Abel-Jacobi inversion (docs/heavy_top.md, the plan).

Normalization of Kowalevski's memoir (Acta Math. 12 (1889) 177-232; transcribed in
/work/shared/SECTIONS_5_8.md A.5): principal frame with ``I = diag(2, 2, 1) I3``, the mass centre
``x0 e1``, ``c0 = m |g| x0 / I3``, ``g`` the DOWNWARD vertical in the body frame (``-gamma`` of the
paper's Section 5) and the physical time:

    2 pdot = q r,  2 qdot = -p r - c0 g3,  rdot = c0 g2,
    2 (p^2 + q^2) + r^2 = 2 c0 g1 + 6 l1,   2 (p g1 + q g2) + r g3 = 2 l,
    k^2 = |(p + i q)^2 + c0 (g1 + i g2)|^2.

Kowalevski's variables ``x1,2 = p +- i q`` and

    R(x) = -x^4 + 6 l1 x^2 + 4 l c0 x + c0^2 - k^2,
    R(x1, x2) = -x1^2 x2^2 + 6 l1 x1 x2 + 2 l c0 (x1 + x2) + c0^2 - k^2,
    s1,2 = [R(x1, x2) -+ sqrt(R(x1) R(x2))] / (2 (x1 - x2)^2) + l1/2,

separate the motion on the genus-2 curve ``y^2 = R1(s) = -4 (s - e1)(s - e2)(s - e3)(s - k1)(s - k2)``,
``4 s^3 - g2 s - g3 = 4 (s - e1)(s - e2)(s - e3)``, ``g2 = k^2 - c0^2 + 3 l1^2``,
``g3 = l1 (k^2 - c0^2 - l1^2) + l^2 c0^2``, ``k1,2 = (l1 +- k)/2``:

    (s1 - s2) s1dot = sqrt(R1(s1)),   (s1 - s2) s2dot = -sqrt(R1(s2)).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["KovalevskayaFrame", "kovalevskaya_frame", "kovalevskaya_variables", "kovalevskaya_curve"]


@dataclass(frozen=True)
class KovalevskayaFrame:
    """The memoir's frame: ``P`` (columns e1, e2, e3) maps it to the body frame; ``c0``."""

    P: np.ndarray
    I3: float
    c0: float


def kovalevskaya_frame(I, center, mass, gravity) -> KovalevskayaFrame:
    """The frame ``e1 = center/|center|``, ``e3`` the axis of the smallest moment, ``e2 = e3 x e1``."""
    I = np.asarray(I, float)
    ev, vec = np.linalg.eigh(I)
    e3 = vec[:, 0]
    x0 = float(np.linalg.norm(center))
    e1 = np.asarray(center, float) / x0
    e1 = e1 - (e1 @ e3) * e3
    e1 /= np.linalg.norm(e1)
    P = np.column_stack([e1, np.cross(e3, e1), e3])
    return KovalevskayaFrame(P, float(ev[0]), mass * float(np.linalg.norm(gravity)) * x0 / float(ev[0]))


def kovalevskaya_variables(frame: KovalevskayaFrame, gravity, omega, Q):
    """``(s1, s2, l1, l, k)`` along states ``(omega, Q)`` (leading axes broadcast)."""
    g = np.asarray(gravity, float)
    pqr = omega @ frame.P
    gd = (np.swapaxes(Q, -1, -2) @ (g / np.linalg.norm(g))) @ frame.P
    p, q, r = pqr[..., 0], pqr[..., 1], pqr[..., 2]
    g1, g2, g3 = gd[..., 0], gd[..., 1], gd[..., 2]
    c0 = frame.c0
    l1 = (2 * (p * p + q * q) + r * r - 2 * c0 * g1) / 6
    l = ((p * g1 + q * g2) + r * g3 / 2)
    x1 = p + 1j * q
    k = np.abs(x1 ** 2 + c0 * (g1 + 1j * g2))
    x2 = np.conj(x1)
    Rx = lambda x: -x ** 4 + 6 * l1 * x ** 2 + 4 * l * c0 * x + c0 ** 2 - k ** 2  # noqa: E731
    R12 = -(x1 * x2) ** 2 + 6 * l1 * x1 * x2 + 2 * l * c0 * (x1 + x2) + c0 ** 2 - k ** 2
    root = np.sqrt(np.real(Rx(x1) * Rx(x2)))
    den = np.real(2 * (x1 - x2) ** 2)   # = -8 q^2
    s1 = (np.real(R12) - root) / den + l1 / 2
    s2 = (np.real(R12) + root) / den + l1 / 2
    return s1, s2, l1, l, k


def kovalevskaya_curve(l1, l, k, c0):
    """Coefficients (highest first) of ``R1(s) = -(4 s^3 - g2 s - g3)(s - k1)(s - k2)``."""
    g2 = k * k - c0 * c0 + 3 * l1 * l1
    g3 = l1 * (k * k - c0 * c0 - l1 * l1) + l * l * c0 * c0
    k1, k2 = (l1 + k) / 2, (l1 - k) / 2
    return -np.polymul([4.0, 0.0, -g2, -g3], np.poly([k1, k2]))
