"""Kovalevskaya's top: the separating variables, the genus-2 curve, their motion by Jacobi inversion in theta
functions (:class:`SeparatedFlow`) and ``(omega, gamma)`` as quotients of theta functions with half-period
characteristics (:class:`KovalevskayaMotion`).  The attitude is :mod:`thetasol.solutions.tops.kovalevskaya_attitude`;
:func:`thetasol.solutions.tops.heavy_top.solve_heavy_top` puts them together (docs/heavy_top.md).  Checked along
80-bit heyoka trajectories (tests/test_heavy_top.py, tests/test_kovalevskaya_top.py).

Normalization of Kowalevski's memoir (S. Kowalevski, Acta Math. 12 (1889) 177-232): principal frame with ``I = diag(2, 2, 1) I3``, the mass centre
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
from numpy.typing import ArrayLike

from thetasol.core.dd import dd_mul
from thetasol.core.so3 import cross, rodrigues

__all__ = ["KovalevskayaFrame", "kovalevskaya_frame", "kovalevskaya_variables", "kovalevskaya_curve",
           "SeparatedFlow", "kovalevskaya_separated_flow", "KovalevskayaMotion", "kovalevskaya_motion"]


@dataclass(frozen=True)
class KovalevskayaFrame:
    """The memoir's frame: ``P`` (columns e1, e2, e3) maps it to the body frame; ``c0``."""

    P: np.ndarray
    I3: float
    c0: float


def kovalevskaya_frame(I: ArrayLike, center: ArrayLike, mass: float, gravity: ArrayLike) -> KovalevskayaFrame:
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


def kovalevskaya_variables(frame: KovalevskayaFrame, gravity: ArrayLike, omega: ArrayLike, Q: ArrayLike
                           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
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
    # s' = s - l1/2 are (R12 -+ root)/den; where R12 and root cancel (|s'_near| < |s'_far|/4) the near one comes
    # from the product s1' s2' = (R12^2 - R(x1) R(x2))/den^2 = F/(2 den), F free of the factor (x1 - x2)^2
    # (sympy): the cancelling form loses ~|s'_far|/|s'_near| relative, e.g. with q -> 0 (tests/test_kovalevskaya_top.py
    # checks both against mpmath)
    R12, pp = np.real(R12), p * p + q * q
    F = (c0 * c0 * (4 * l * l - 6 * l1 + 4 * p * p) + 8 * c0 * l * p * pp - 4 * k * k * p * p
         + 6 * l1 * (k * k + pp * pp))
    sg = np.where(R12 >= 0, 1.0, -1.0)
    far = (R12 + sg * root) / den
    near = (R12 - sg * root) / den
    near = np.where(4 * np.abs(near) < np.abs(far), F / (2 * den * np.where(far != 0, far, 1.0)), near)
    s1 = np.where(sg > 0, near, far) + l1 / 2
    s2 = np.where(sg > 0, far, near) + l1 / 2
    return s1, s2, l1, l, k


def kovalevskaya_curve(l1: float, l: float, k: float, c0: float) -> np.ndarray:
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
    ``d_i`` the derivative along ``V_i = N[:, i]`` (``N`` the normalization of ``s^(i-1) ds / y``), ``K`` the
    vector of Riemann constants; the constants ``c12, c22`` are fitted at ``t = 0``.
    """

    theta: object
    z0: np.ndarray
    V: np.ndarray       # (2, 2): columns V1, V2
    K: np.ndarray
    c: tuple            # (c12, c22)
    interval1: tuple    # the s-interval of s1 (s2 has the other one)

    def __call__(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
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


DEGENERATE_GAP = 1e-5   # branch points closer than this (relative): a degenerate torus, refused


@dataclass(frozen=True)
class _CurveSetup:
    frame: KovalevskayaFrame
    s: tuple
    l1: float
    l: float
    k: float
    curve: object
    theta: object
    z0: np.ndarray
    V: np.ndarray
    K: np.ndarray


def _branch_points(l1, l, k, c0):
    """The roots of ``R1``: ``e_a`` (the cubic's, Newton-polished) and ``k1,2 = (l1 +- k)/2``."""
    cub = np.array([4.0, 0.0, -(k * k - c0 * c0 + 3 * l1 * l1), -(l1 * (k * k - c0 * c0 - l1 * l1) + l * l * c0 * c0)])
    e = np.roots(cub).astype(complex)
    for _ in range(2):
        dp = np.polyval(np.polyder(cub), e)
        e = e - np.where(dp != 0, np.polyval(cub, e) / np.where(dp != 0, dp, 1), 0)
    return np.concatenate([e, [(l1 + k) / 2, (l1 - k) / 2]])


def _curve_setup(I, center, Q0, omega0, mass, gravity) -> _CurveSetup:
    """The curve of the data, its theta function and the Abel image ``z0`` of the initial divisor."""
    from thetasol.curves.hyperelliptic import HyperellipticCurve
    from thetasol.theta.riemann import RiemannTheta

    frame = kovalevskaya_frame(I, center, mass, gravity)
    Q0, omega0 = np.asarray(Q0, float), np.asarray(omega0, float)
    s1, s2, l1, l, k = (float(x) for x in kovalevskaya_variables(frame, gravity, omega0, Q0))
    coef = kovalevskaya_curve(l1, l, k, frame.c0)
    roots = _branch_points(l1, l, k, frame.c0)
    gap = np.min(np.where(np.eye(5, dtype=bool), np.inf, np.abs(roots[:, None] - roots[None, :])))
    if not np.isfinite(s1 * s2) or gap <= DEGENERATE_GAP * np.max(np.abs(roots)):
        raise RuntimeError(f"the curve is degenerate or the divisor at infinity (branch points {gap:.2g} apart, "
                           f"s = {s1:.6g}, {s2:.6g})")
    d1, d2 = _s_sign_derivative(frame, I, center, mass, gravity, omega0, Q0)
    y1 = d1 * np.sign(s1 - s2) * np.sqrt(max(np.polyval(coef, s1), 0.0))   # y = (s1 - s2) s1'
    y2 = -d2 * np.sign(s1 - s2) * np.sqrt(max(np.polyval(coef, s2), 0.0))
    curve = HyperellipticCurve.from_roots(roots, -4.0)
    theta = RiemannTheta(curve.riemann_matrix())
    z0 = curve.abel_map([(s1, y1), (s2, y2)]).sum(axis=0)
    # the curve's differentials are s^i ds / y = 2 s^i ds / f_y: V_i = N[:, i] / 2 in PlaneCurve's terms
    return _CurveSetup(frame, (s1, s2), l1, l, k, curve, theta, z0, curve.normalization(),
                       curve.riemann_constant(theta=theta))


def kovalevskaya_separated_flow(I: ArrayLike, center: ArrayLike, Q0: ArrayLike, omega0: ArrayLike, mass: float,
                                gravity: ArrayLike) -> SeparatedFlow:
    """Set up :class:`SeparatedFlow` from the data (the curve, its periods and Abel map)."""
    st = _curve_setup(I, center, Q0, omega0, mass, gravity)
    s1, s2 = st.s
    coef = kovalevskaya_curve(st.l1, st.l, st.k, st.frame.c0)
    roots = np.sort(np.real(np.roots(coef)[np.abs(np.imag(np.roots(coef))) < 1e-9 * np.max(np.abs(coef))]))
    lo = max([r for r in roots if r <= s1], default=-np.inf)
    hi = min([r for r in roots if r >= s1], default=np.inf)
    V1, V2 = st.V[:, 0], st.V[:, 1]
    _, v, gr, H = st.theta.jet(st.z0 + st.K, order=2, separated=True)
    Hl = H / v - np.outer(gr, gr) / v ** 2
    c22 = s1 + s2 - V2 @ Hl @ V2
    c12 = s1 * s2 + V1 @ Hl @ V2
    return SeparatedFlow(st.theta, st.z0, st.V, st.K, (c12, c22), (lo, hi))


# -- stage 3: (omega, gamma) from theta quotients -------------------------------------------------

TAYLOR_ORDER = 2   # Taylor coefficients at t = 0 matched by the fit of the constants (the theta jet's order)


def _conv(a, b, n):
    return sum(a[i] * b[n - i] for i in range(n + 1))


def _state_taylor(x, c0, order=TAYLOR_ORDER):
    """Taylor coefficients ``(order + 1, 6)`` of the memoir's state ``(p, q, r, g1, g2, g3)`` at one instant
    (the equations are quadratic: Cauchy products)."""
    X = [np.asarray(x, float)]
    for n in range(order):
        p, q, r, g1, g2, g3 = (np.array([X[i][j] for i in range(n + 1)]) for j in range(6))
        f = np.array([_conv(q, r, n) / 2, -(_conv(p, r, n) + c0 * g3[n]) / 2, c0 * g2[n],
                      _conv(r, g2, n) - _conv(q, g3, n), _conv(p, g3, n) - _conv(r, g1, n),
                      _conv(q, g1, n) - _conv(p, g2, n)])
        X.append(f / (n + 1))
    return np.stack(X)


def _series_div(a, b):
    c = []
    for n in range(len(a)):
        c.append((a[n] - sum(c[i] * b[n - i] for i in range(n))) / b[0])
    return np.stack(c)


def _series_mul(a, b):
    return np.stack([_conv(a, b, n) for n in range(len(a))])


@dataclass(frozen=True)
class KovalevskayaMotion:
    """``(omega, gamma_up)`` of Kovalevskaya's top from genus-2 theta functions with half-period characteristics.

    With ``T_chi(t) = theta[chi](z0 + K + V2 t)`` (``T_0`` without characteristic), ``chi_a`` the half
    characteristics of the branch points ``e_a`` (the roots of ``4 s^3 - g2 s - g3``) and ``chi_ab = chi_a + chi_b``:
    ``T_a/T_0 = kappa_a sqrt((s1 - e_a)(s2 - e_a))`` (the memoir's ``P_a``) and, in the memoir's frame,

        q = T_0/D,  p = N_p/D,  r = N_r/D,  g3 = N_3/D,  D = sum lambda_a T_a,  N_p = sum nu_a T_a,
        N_r = sum mu_ab T_ab,  N_3 = sum rho_ab T_ab,  g2 = rdot/c0,  2 c0 g1 = 2 (p^2 + q^2) + r^2 - 6 l1

    (memoir section 5: ``q = E/Delta``, ``p = -i (L1 P1 + ...)/Delta``, ``r = -i (L P23 + ...)/Delta``,
    ``c0 g3 = (L1 P23 + ...)/Delta``; the four constant triples are fitted to the Taylor coefficients of
    orders 0, 1, 2 of the state at ``t = 0``, which replaces the memoir's sigma constants and misprints).
    Every quantity is a quotient of entire functions: no square root, no sign to choose.
    """

    theta: object
    z0: np.ndarray
    V2: np.ndarray
    chars1: tuple
    chars2: tuple
    coef: np.ndarray    # (4, 3): lambda, nu, mu, rho
    c0: float
    l1: float
    P: np.ndarray
    w: tuple = None     # (hi, lo): V2 = w_m + tau w_n in lattice coordinates (lo = 0: float64 periods)
    fit_residual: float = 0.0
    V1: np.ndarray = None   # the other real flow of the torus (``sum_i ds_i/y_i``)

    def _jets(self, z, chars, order=1):
        # one pass over the lattice for all 16 half characteristics (the reduction of z done once): cheaper
        # than seven passes, most of all at few points
        e, v, gr, *H = self.theta.jet(z, char="all", order=max(order, 1), separated=True)
        dv = gr @ self.V2
        d2v = np.einsum("i,...cij,j->...c", self.V2, H[0], self.V2) if order == 2 else dv
        return [(e, v[..., i], dv[..., i], d2v[..., i]) for i in map(_char_index, chars)]

    def _values(self, t, order=0):
        """The seven theta values (and their t-derivatives) in a common unit.

        ``V2 t`` is reduced modulo the lattice in lattice coordinates with two-word products (the
        characteristics give each value the sign ``(-1)^(2 alpha.m + 2 beta.n)`` under a shift by ``m + tau n``)."""
        t = np.asarray(t, float)
        if self.w is None:
            return self.values_at(t[..., None] * self.lattice_velocity(), order, reduce=False)
        h, lo = dd_mul(t[..., None], 0.0, self.w[0], self.w[1])
        k = np.round(h)
        return self.values_at((h - k) + lo, order, k)

    def lattice_velocity(self) -> np.ndarray:
        """``w`` with ``V2 = w_m + tau w_n`` (``w`` real, lattice coordinates)."""
        if self.w is not None:
            return self.w[0]
        tau = self.theta.tau
        wn = np.linalg.solve(tau.imag, self.V2.imag)
        return np.concatenate([self.V2.real - tau.real @ wn, wn])

    def values_at(self, x: ArrayLike, order: int = 0, shift: np.ndarray | None = None, reduce: bool = True
                  ) -> np.ndarray | tuple[np.ndarray, ...]:
        """The seven theta values at ``z0 + x_m + tau x_n`` (``x`` real lattice coordinates, ``(..., 4)``), plus
        ``shift`` (integers, tracked only through the characteristics' signs); with ``order`` 1 or 2 also their
        first (and second) derivatives along ``V2``."""
        x = np.asarray(x, float)
        if reduce:
            k = np.round(x)
            x = x - k
            shift = k if shift is None else shift + k
        z = self.z0 + x[..., :2] + x[..., 2:] @ self.theta.tau.T
        chars = (None,) + self.chars1 + self.chars2
        jets = self._jets(z, chars, order)
        e = jets[0][0]
        sg = np.ones(x.shape[:-1] + (7,))
        if shift is not None:
            par = np.mod(shift, 2.0)
            for i, ch in enumerate(chars[1:], 1):
                sg[..., i] = 1 - 2 * np.mod(np.rint(par[..., :2] @ (2 * ch[0]) + par[..., 2:] @ (2 * ch[1])), 2)
        out = tuple(np.stack([np.exp(j[0] - e) * j[i] for j in jets], -1) * sg for i in range(1, order + 2))
        return out[0] if order == 0 else out

    def values_on_grid(self, k1: ArrayLike, k2: ArrayLike, a: ArrayLike, b: ArrayLike, order: int = 0
                       ) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
        """:meth:`values_at` on the grid ``x_ij = a_i k1 + b_j k2``, shape ``(len(a), len(b), 7)``, by
        :func:`thetasol.theta.grid.theta_grid` (matrix products; the common unit per point is another one)."""
        from thetasol.theta.grid import theta_grid

        G = theta_grid(self.theta.tau, self.z0, k1, k2, a, b, (None,) + self.chars1 + self.chars2,
                       self.V2 if order else None)
        return G.value if order == 0 else (G.value, G.derivative)

    def memoir_state(self, t: ArrayLike) -> tuple[np.ndarray, ...]:
        """``(p, q, r, g1, g2, g3)`` in the memoir's frame and normalization (downward ``g``)."""
        return _memoir_state(*self._values(t, 1), self.coef, self.c0, self.l1)

    def __call__(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        p, q, r, g1, g2, g3 = (np.real(x) for x in self.memoir_state(t))
        omega = np.stack([p, q, r], -1) @ self.P.T
        gamma_up = -np.stack([g1, g2, g3], -1) @ self.P.T
        return omega, gamma_up


def _memoir_state(val, der, coef, c0, l1):
    lam, nu, mu, rho = coef
    D, Dd = val[..., 1:4] @ lam, der[..., 1:4] @ lam
    Nr, Nrd = val[..., 4:7] @ mu, der[..., 4:7] @ mu
    Np = val[..., 1:4] @ nu
    q, p, r = val[..., 0] / D, Np / D, Nr / D
    g3 = val[..., 4:7] @ rho / D
    g2 = (Nrd * D - Nr * Dd) / (D * D) / c0
    g1 = (2 * (p * p + q * q) + r * r - 6 * l1) / (2 * c0)
    return p, q, r, g1, g2, g3


def _refine(coef, val, der, rows, c0, l1, l, k):
    """Gauss-Newton on the constants: Taylor rows at ``t = 0`` plus, at the sample points, reality, the
    integrals and the two equations of motion not used in the construction (``2 pdot = q r``,
    ``2 qdot = -p r - c0 g3``); the Taylor fit alone is not accurate enough (much less so where
    ``theta(z0 + K)`` is small), so its rows only pin the start (``TAYLOR_WEIGHT``).  The residuals of all
    central-difference steps are one batched evaluation (:func:`_fit_residuals`); the start is within the
    quadratic basin, so the iteration stops when a step no longer lowers the residual (2-4 steps)."""
    u = np.concatenate([coef.real.ravel(), coef.imag.ravel()])
    args = (val, der, rows, c0, l1, l, k)
    r = _fit_residuals(u[None], *args)[0]
    for _ in range(FIT_STEPS):
        h = 1e-6 * np.maximum(np.abs(u), 1e-3 * np.max(np.abs(u)))
        E = np.diag(h)
        rp = _fit_residuals(np.concatenate([u + E, u - E]), *args)
        Jac = ((rp[:len(u)] - rp[len(u):]) / (2 * h[:, None])).T
        step = np.linalg.lstsq(Jac, -r, rcond=None)[0]
        u_new = u + step
        r_new = _fit_residuals(u_new[None], *args)[0]
        if np.linalg.norm(r_new) >= np.linalg.norm(r):
            break
        u, r = u_new, r_new
    return (u[:12] + 1j * u[12:]).reshape(4, 3), float(np.max(np.abs(r)))


FIT_STEPS = 6   # Gauss-Newton steps at most (the fit converges in 2-4 from the Taylor constants)
# weight of the Taylor rows against the sample points' residuals in the Gauss-Newton fit: the rows only pin the
# start, the 40 sample points determine the constants.  The rows' matrices come from series divisions by
# theta(z0 + K), which is small when a point of the divisor is next to infinity (q(0) ~ 0): the rows are then
# inaccurate, and at a weight comparable to the points' they would pull the fitted state off the motion
TAYLOR_WEIGHT = 1e-4


def _fit_residuals(U, val, der, rows, c0, l1, l, k):
    """The residuals of :func:`_refine` for a batch of parameter vectors ``U`` (m, 24): (m, n)."""
    cf = (U[:, :12] + 1j * U[:, 12:]).reshape(-1, 4, 3)
    lam, nu, mu, rho = (np.moveaxis(cf[:, i], 0, -1) for i in range(4))     # (3, m)
    D, Dd = val[:, 1:4] @ lam, der[:, 1:4] @ lam                              # (P, m)
    Nr, Nrd = val[:, 4:7] @ mu, der[:, 4:7] @ mu
    Np, Npd = val[:, 1:4] @ nu, der[:, 1:4] @ nu
    v0, d0 = val[:, :1], der[:, :1]
    q, p, r = v0 / D, Np / D, Nr / D
    g3 = val[:, 4:7] @ rho / D
    g2 = (Nrd * D - Nr * Dd) / (D * D) / c0
    g1 = (2 * (p * p + q * q) + r * r - 6 * l1) / (2 * c0)
    pd = (Npd * D - Np * Dd) / (D * D)
    qd = (d0 * D - v0 * Dd) / (D * D)
    e1, e2 = 2 * pd - q * r, 2 * qd + p * r + c0 * g3
    out = [np.imag(np.concatenate([p, q, r, g2, g3])),
           np.real(2 * (p * g1 + q * g2) + r * g3 - 2 * l), np.real(g1 * g1 + g2 * g2 + g3 * g3 - 1),
           np.real((p * p - q * q + c0 * g1) ** 2 + (2 * p * q + c0 * g2) ** 2 - k * k) / max(k * k, c0 * c0),
           np.real(e1), np.imag(e1), np.real(e2), np.imag(e2)]
    for (A, b), x in zip(rows, np.moveaxis(cf, 1, 0), strict=True):
        w = TAYLOR_WEIGHT / np.linalg.norm(A, axis=1)
        res = (x @ A.T - b) * w                                                  # (m, rows)
        out += [np.real(res).T, np.imag(res).T]
    return np.concatenate(out).T


def _char_index(ch) -> int:
    """Position of the half characteristic ``ch = (alpha, beta)`` (None: zero) in ``RiemannTheta(..., char="all")``."""
    if ch is None:
        return 0
    bits = np.rint(2 * np.concatenate([ch[0], ch[1]])).astype(int)
    return int(bits @ (1 << np.arange(len(bits) - 1, -1, -1)))


def _half_characteristic(curve, tau, x):
    A = curve.branch_images()[np.argmin(np.abs(curve.branch_points - x))]
    al = np.linalg.solve(tau.imag, A.imag)
    be = np.real(A - tau @ al)
    return np.round(2 * al) / 2 % 1, np.round(2 * be) / 2 % 1


def kovalevskaya_motion(I: ArrayLike, center: ArrayLike, Q0: ArrayLike, omega0: ArrayLike, mass: float,
                        gravity: ArrayLike) -> KovalevskayaMotion:
    """Set up :class:`KovalevskayaMotion` from the data (the curve, its periods and Abel map)."""
    setup = _curve_setup(I, center, Q0, omega0, mass, gravity)
    curve, tau = setup.curve, setup.theta.tau
    c0, l1, l, k = setup.frame.c0, setup.l1, setup.l, setup.k
    cub = np.roots([4.0, 0.0, -(k * k - c0 * c0 + 3 * l1 * l1), -(l1 * (k * k - c0 * c0 - l1 * l1) + l * l * c0 * c0)])
    ch1 = tuple(_half_characteristic(curve, tau, x) for x in cub)
    ch2 = tuple(((ch1[a][0] + ch1[b][0]) % 1, (ch1[a][1] + ch1[b][1]) % 1) for a, b in ((1, 2), (0, 2), (0, 1)))
    z0 = setup.z0 + setup.K
    V2 = setup.V[:, 1]
    motion = KovalevskayaMotion(setup.theta, z0, V2, ch1, ch2, np.zeros((4, 3), complex), c0, l1, setup.frame.P)
    # one theta pass: the Taylor coefficients at t = 0 (the first point) and the fit's sample points
    tj = np.arange(1, 41) * (0.61803398875 / np.max(np.abs(V2)))
    val, der, der2 = motion.values_at(np.concatenate([np.zeros((1, 4)), tj[:, None] * motion.lattice_velocity()]),
                                      2, reduce=False)
    T = list(np.stack([val[0], der[0], der2[0] / 2], 1))
    val0, der0, val, der = val[:1], der[:1], val[1:], der[1:]
    g = np.asarray(gravity, float)
    x = np.concatenate([np.asarray(omega0, float) @ setup.frame.P,
                        (np.asarray(Q0, float).T @ (g / np.linalg.norm(g))) @ setup.frame.P])
    X = _state_taylor(x, c0)
    qB = [_series_mul(X[:, 1], _series_div(Tj, T[0])) for Tj in T[1:]]
    A1, A2 = np.stack(qB[:3], -1), np.stack(qB[3:], -1)
    rows = [(A1, np.eye(TAYLOR_ORDER + 1)[0]), (A1, X[:, 0]), (A2, X[:, 2]), (A2, X[:, 5])]
    coef = np.stack([np.linalg.solve(A, b + 0j) for A, b in rows])
    coef, resid = _refine(coef, val, der, rows, c0, l1, setup.l, k)
    # the fitted state at t = 0 against the data: flags a model (z0, periods) off the data, which the sample
    # points alone do not see (their residual can be far below the state's error against the numerical
    # reference)
    x0 = np.real(np.concatenate(_memoir_state(val0, der0, coef, c0, l1)))
    resid = max(resid, float(np.max(np.abs(x0 - x) / np.r_[[max(np.max(np.abs(x[:3])), np.sqrt(c0))] * 3, 1, 1, 1])))
    return KovalevskayaMotion(setup.theta, z0, V2, ch1, ch2, coef, c0, l1, setup.frame.P,
                              (motion.lattice_velocity(), np.zeros(4)), resid, setup.V[:, 0])
