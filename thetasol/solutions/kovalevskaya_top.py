"""Kovalevskaya's top, stages 1 and 2 of its closed form: the separating variables, the genus-2 curve
and their motion by Jacobi inversion in theta functions.

Not yet a solution of the motion: :func:`thetasol.solutions.heavy_top.solve_heavy_top` recognizes
the top and raises ``ClosedFormUnavailable``; ``(omega, Q)`` from ``s1, s2`` is what is left
(docs/heavy_top.md).  What is here is checked along 80-bit heyoka trajectories (tests/test_heavy_top.py).

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

from thetasol.core.so3 import cross, rodrigues

__all__ = ["KovalevskayaFrame", "kovalevskaya_frame", "kovalevskaya_variables", "kovalevskaya_curve",
           "SeparatedFlow", "kovalevskaya_separated_flow"]


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


# -- stage 2: the separating variables in theta functions ----------------------------------------

@dataclass(frozen=True)
class SeparatedFlow:
    """``s1(t), s2(t)`` of Kovalevskaya's top from the genus-2 theta function (Jacobi inversion).

    ``s1 + s2 = d_2 d_2 log theta(z + K) + c22`` and ``s1 s2 = -d_1 d_2 log theta(z + K) + c12``
    (the Kleinian functions wp_22, wp_12 of the curve up to constants), ``z = z0 + V2 t`` the
    normalized Abel image of the divisor ``{(s1, y1), (s2, y2)}`` from the branch point at infinity,
    ``d_i`` the derivative along ``V_i = N[:, i]/2`` (``N`` the normalization, ``f_y = 2 y``), ``K`` the
    vector of Riemann constants; the constants ``c12, c22`` are fitted at ``t = 0``.
    """

    theta: object
    z0: np.ndarray
    V: np.ndarray       # (2, 2): columns V1, V2
    K: np.ndarray
    c: tuple            # (c12, c22)
    interval1: tuple    # the s-interval of s1 (s2 has the other one)

    def __call__(self, t):
        t = np.asarray(t, float)
        V1, V2 = self.V[:, 0], self.V[:, 1]
        z = self.z0 + t[..., None] * V2 + self.K
        _, v, gr, H = self.theta.jet(z, order=2, separated=True)   # log-derivatives: exp(e) cancels
        Hl = H / v[..., None, None] - gr[..., :, None] * gr[..., None, :] / v[..., None, None] ** 2
        G22 = np.einsum("i,...ij,j->...", V2, Hl, V2)
        G12 = np.einsum("i,...ij,j->...", V1, Hl, V2)
        ssum = np.real(G22 + self.c[1])
        sprod = np.real(-G12 + self.c[0])
        disc = np.sqrt(np.maximum(ssum * ssum - 4 * sprod, 0.0))
        big = 0.5 * (ssum + np.where(ssum >= 0, disc, -disc))
        small = np.where(big != 0, sprod / np.where(big != 0, big, 1.0), 0.0)
        lo, hi = self.interval1
        first = (big >= lo) & (big <= hi)
        return np.where(first, big, small), np.where(first, small, big)


def _s_sign_derivative(frame, I, center, mass, gravity, omega, Q, h=1e-7):
    """Signs of ``s1', s2'`` at one state from a central difference along the equations of motion."""
    I = np.asarray(I, float)
    M = I @ omega
    wdot = np.linalg.solve(I, cross(M, omega) + cross(np.asarray(center, float), Q.T @ (mass * np.asarray(gravity))))
    out = []
    for sgn in (1.0, -1.0):
        out.append(kovalevskaya_variables(frame, gravity, omega + sgn * h * wdot, Q @ rodrigues(sgn * h * omega))[:2])
    return np.sign(out[0][0] - out[1][0]), np.sign(out[0][1] - out[1][1])


def kovalevskaya_separated_flow(I, center, Q0, omega0, mass, gravity) -> SeparatedFlow:
    """Set up :class:`SeparatedFlow` from the data (the curve, its periods and Abel map: ~0.1 s)."""
    import sympy

    from thetasol.curves.plane_curve import PlaneCurve
    from thetasol.theta.riemann import RiemannTheta

    frame = kovalevskaya_frame(I, center, mass, gravity)
    Q0, omega0 = np.asarray(Q0, float), np.asarray(omega0, float)
    s1, s2, l1, l, k = (float(x) for x in kovalevskaya_variables(frame, gravity, omega0, Q0))
    coef = kovalevskaya_curve(l1, l, k, frame.c0)
    d1, d2 = _s_sign_derivative(frame, I, center, mass, gravity, omega0, Q0)
    y1 = d1 * np.sign(s1 - s2) * np.sqrt(max(np.polyval(coef, s1), 0.0))   # y = (s1 - s2) s1'
    y2 = -d2 * np.sign(s1 - s2) * np.sqrt(max(np.polyval(coef, s2), 0.0))
    S, Y = sympy.symbols("s y")
    curve = PlaneCurve(Y ** 2 - sum(sympy.Float(float(cf), 30) * S ** (5 - i) for i, cf in enumerate(coef)), S, Y)
    inf = curve.places_at_infinity()[0]
    N = curve.normalization()
    z0 = curve.abel_map([(complex(s1), complex(y1)), (complex(s2), complex(y2))], base=inf).sum(axis=0)
    K = curve.riemann_constant(base=inf)
    flow = SeparatedFlow(RiemannTheta(curve.riemann_matrix()), z0, N / 2, K, (0.0, 0.0), (0.0, 0.0))
    roots = np.sort(np.real(np.roots(coef)[np.abs(np.imag(np.roots(coef))) < 1e-9 * np.max(np.abs(coef))]))
    lo = max([r for r in roots if r <= s1], default=-np.inf)
    hi = min([r for r in roots if r >= s1], default=np.inf)
    V1, V2 = N[:, 0] / 2, N[:, 1] / 2
    _, v, gr, H = flow.theta.jet(z0 + K, order=2, separated=True)
    Hl = H / v - np.outer(gr, gr) / v ** 2
    c22 = s1 + s2 - V2 @ Hl @ V2
    c12 = s1 * s2 + V1 @ Hl @ V2
    return SeparatedFlow(flow.theta, z0, N / 2, K, (c12, c22), (lo, hi))
