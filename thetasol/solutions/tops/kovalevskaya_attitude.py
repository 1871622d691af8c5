"""Kovalevskaya's top, the attitude: the angle about the vertical as a Fourier series on the invariant torus.

Given ``(omega, gamma)`` of :class:`thetasol.solutions.tops.kovalevskaya_top.KovalevskayaMotion`, the attitude is
``Q = E S(phi) B^T`` with ``B = [u_b, gamma x u_b, gamma]`` (body frame), ``u_b`` the unit horizontal part of a
reference vector ``b`` (among ``M = I omega``, the body axes and their combinations, the one whose rate series
converges fastest on the first grid), ``E`` a space frame with third axis up and ``S(phi)`` the rotation by ``phi`` about it.
The azimuth of ``Q b`` obeys

    phidot = (b x bdot_space) . gamma / (|b|^2 - (b . gamma)^2),   bdot_space = omega x b (body axis),
    = (M x tau) . gamma / (|M|^2 - (M . gamma)^2),  tau = mass |g| gamma x center   (b = M),

a function on the real torus ``z0 + a V1 + b V2`` (an abelian integral of the third kind along the flow).  It is
sampled on an ``n1 x n2`` grid of the torus angles (each axis doubled from 32 until the integrated Fourier
coefficients on its edge are below ``PHASE_TOL``; the grid predicted from the first grid's decay is sampled in
one call, a doubling beyond it samples only the new rows or columns), its Fourier
coefficients taken by FFT, and integrated term by term:
``phi(t) = phi0 + c_00 t + sum c_jk (exp(2 pi i (j nu1 + k nu2) t) - 1)/(2 pi i (j nu1 + k nu2))``, the torus
angles ``nu t`` reduced modulo 1 and ``c_00 t`` modulo ``2 pi`` with two-word products.  The series is kept as
a dense box of modes ``|j| <= J, |k| <= K`` (the smallest outside which the coefficients sum to at most
``PHASE_DROP``, less where the edge leaves less room below ``PHASE_TOL``) and evaluated as a matrix product.  The truncation (the largest coefficient on the grid's edge
plus the dropped sum) is ``diagnostics["phase_tail"]``.

The samples come from :meth:`KovalevskayaMotion.values_on_grid` (:func:`thetasol.theta.grid.theta_grid`: the
theta functions on the grid as matrix products), which gives the seven theta values and derivatives in another
common unit per point than :meth:`KovalevskayaMotion.values_at`; the rate, a quotient, is the same to rounding
(tests/test_theta_grid.py), and the grid is much cheaper than ``values_at`` at every point
(benchmarks/bench_theta_grid.py measures both).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core.dd import dd_mul
from thetasol.solutions.tops.kovalevskaya_top import KovalevskayaMotion

__all__ = ["Reference", "KovalevskayaAttitude", "kovalevskaya_attitude", "build_kovalevskaya_top"]


def _lattice_coords(motion, V):
    tau = motion.theta.tau
    wn = np.linalg.solve(tau.imag, V.imag)
    return np.concatenate([V.real - tau.real @ wn, wn])


def _torus_lattice(motion, box=4):
    """Two integer vectors ``k1, k2`` (lattice coordinates) spanning the periods of the state on the real torus."""
    W = np.stack([_lattice_coords(motion, motion.V1), motion.lattice_velocity()], 1)   # (4, 2)
    Qw, _ = np.linalg.qr(W)
    k = np.indices((2 * box + 1,) * 4).reshape(4, -1).T - float(box)   # the box in lexicographic order
    k = k[np.any(k != 0, 1)]
    k = k[np.linalg.norm(k - (k @ Qw) @ Qw.T, axis=1) <= 1e-6 * np.linalg.norm(k, axis=1)]
    for a, b in motion.chars1 + motion.chars2:
        k = k[np.rint(k[:, :2] @ (2 * a) + k[:, 2:] @ (2 * b)) % 2 == 0]
    if len(k) < 2:
        raise RuntimeError("no period lattice of the real torus found")
    ab = np.linalg.lstsq(W, k.T, rcond=None)[0].T          # (n, 2): the periods in the flows' times
    order = np.argsort(np.linalg.norm(ab, axis=1), kind="stable")
    k, ab = k[order], ab[order]
    cross = np.abs(ab[0, 0] * ab[:, 1] - ab[0, 1] * ab[:, 0])
    indep = np.nonzero(cross > 1e-6 * np.linalg.norm(ab[0]) * np.linalg.norm(ab, axis=1))[0]
    if len(indep):
        return k[0], k[indep[0]]
    raise RuntimeError("the real torus has no two independent periods in the search box")


@dataclass(frozen=True)
class Reference:
    """The reference vector ``b = mu M + lam e_axis`` (body frame; ``M = I omega``, ``e_axis`` a column of the
    memoir's frame; ``axis = -1``: none).  In space ``d(Q b)/dt = Q (mu tau + lam omega x e_axis)``."""

    mu: float
    lam: float
    axis: int

    def vector(self, P: np.ndarray, I: np.ndarray, omega: np.ndarray) -> np.ndarray:
        """``b`` in body coordinates along the angular velocities ``omega``."""
        b = np.zeros_like(omega)
        if self.mu:
            b = b + self.mu * (omega @ I.T)
        if self.lam:
            b = b + self.lam * P[:, self.axis]
        return b

    def __str__(self) -> str:
        if not self.lam:
            return "angular momentum"
        axis = f"body axis e{self.axis + 1}"
        return axis if not self.mu else f"M/|M(0)| {'+' if self.lam > 0 else '-'} {abs(self.lam):g} {axis}"


def _references(I: np.ndarray, omega0: np.ndarray) -> list[Reference]:
    """The candidates: ``M``, the three body axes, and ``M/|M(0)| + lam e_k`` for ``|lam|`` in 1/2, 1, 2 (a
    combination keeps its horizontal part, and the rate's series converges faster, where ``M`` and the axes
    pass near the vertical: its box of significant modes is smaller than for the one of ``M`` and the axes
    farthest from the vertical)."""
    refs = [Reference(0.0, 1.0, k) for k in range(3)]
    m0 = float(np.linalg.norm(I @ omega0))
    if m0 > 0:
        refs.insert(0, Reference(1.0, 0.0, -1))
        refs += [Reference(1 / m0, lam, k) for k in range(3) for lam in (-2.0, -1.0, -0.5, 0.5, 1.0, 2.0)]
    return refs


@dataclass(frozen=True)
class KovalevskayaAttitude:
    """``(omega, Q)`` of Kovalevskaya's top; see the module docstring."""

    motion: KovalevskayaMotion
    I: np.ndarray
    center: np.ndarray
    mg: float
    E: np.ndarray        # space frame, third column up
    ref: Reference
    nu: tuple            # torus frequencies (hi, lo)
    modes: tuple         # (j, k): the integer modes of the two torus angles (rows, columns of coef)
    coef: np.ndarray     # (len(j), len(k)): coefficients divided by 2 pi i (j nu1 + k nu2)
    rate: tuple          # c_00 (hi, lo)
    phi0: float
    tail: float
    grid: tuple          # (n1, n2) samples of the torus angles

    @property
    def _coef_sum(self) -> float:
        return float(np.real(np.sum(self.coef)))

    def phase(self, t: ArrayLike) -> np.ndarray:
        t = np.asarray(t, float)
        h, lo = dd_mul(t[..., None], 0.0, self.nu[0], self.nu[1])
        th = (h - np.round(h)) + lo
        # the dense mode box as a matrix product: one complex exponential per mode index and axis
        e1 = np.exp((2j * np.pi) * th[..., :1] * self.modes[0])
        e2 = np.exp((2j * np.pi) * th[..., 1:] * self.modes[1])
        per = np.real(np.sum(e1 * (e2 @ self.coef.T), -1)) - self._coef_sum
        rh, rl = dd_mul(t, 0.0, self.rate[0], self.rate[1])
        lin = np.mod(rh, 2 * np.pi) + rl
        return self.phi0 + lin + per

    def __call__(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        t = np.asarray(t, float)
        omega, gamma = self.motion(t)
        b = self.ref.vector(self.motion.P, self.I, omega)
        u = b - np.sum(b * gamma, -1)[..., None] * gamma
        u /= np.linalg.norm(u, axis=-1)[..., None]
        B = np.stack([u, np.cross(gamma, u), gamma], -1)
        phi = self.phase(t)
        c, s = np.cos(phi), np.sin(phi)
        S = np.zeros(t.shape + (3, 3))
        S[..., 0, 0], S[..., 0, 1], S[..., 1, 0], S[..., 1, 1], S[..., 2, 2] = c, -s, s, c, 1.0
        return omega, self.E @ S @ np.swapaxes(B, -1, -2)


def _grid_state(motion, val, der):
    """``omega`` and ``gamma`` (body frame, up) as ``(3, N)`` arrays from the seven theta values and derivatives on
    the grid (:func:`thetasol.solutions.tops.kovalevskaya_top.KovalevskayaMotion.memoir_state`'s formulas on
    contiguous planes, one complex reciprocal per point)."""
    V = np.moveaxis(val, -1, 0).reshape(7, -1)
    Dv = np.moveaxis(der, -1, 0).reshape(7, -1)
    lam, nu, mu, rho = motion.coef
    D, Np = np.array([lam, nu]) @ V[1:4]
    Nr, G3 = np.array([mu, rho]) @ V[4:7]
    iD = 1.0 / D
    rc = Nr * iD
    p, q, r = np.real(Np * iD), np.real(V[0] * iD), np.real(rc)
    g2 = np.real((mu @ Dv[4:7] - rc * (lam @ Dv[1:4])) * iD) / motion.c0
    g1 = (2 * (p * p + q * q) + r * r - 6 * motion.l1) / (2 * motion.c0)
    return motion.P @ np.stack([p, q, r]), motion.P @ -np.stack([g1, g2, np.real(G3 * iD)])


def _rate_on_grid(motion, I, center, mg, grid, refs):
    """``phidot`` on the grid ``(k1, k2, a, b)`` of lattice coordinates ``a_i k1 + b_j k2``, per reference.

    With ``b = mu M + lam d`` (``d`` a unit column of the memoir's frame), ``tau = mg gamma x center`` and
    ``K = tau x gamma``, the numerator ``(b x bdot) . gamma`` is ``mu^2 M.K + mu lam ((M.d)(omega.gamma) -
    (M.omega)(d.gamma) + d.K) + lam^2 ((omega.gamma) - (d.omega)(d.gamma))``: a few dot products per point shared
    by all the candidates."""
    val, der = motion.values_on_grid(*grid, 1)
    omega, gamma = _grid_state(motion, val, der)
    M = I @ omega
    tau = mg * np.stack([gamma[1] * center[2] - gamma[2] * center[1], gamma[2] * center[0] - gamma[0] * center[2],
                         gamma[0] * center[1] - gamma[1] * center[0]])
    K = np.stack([tau[1] * gamma[2] - tau[2] * gamma[1], tau[2] * gamma[0] - tau[0] * gamma[2],
                  tau[0] * gamma[1] - tau[1] * gamma[0]])
    MM, MK, Mg, Mw, wg = (np.einsum("in,in->n", x, y) for x, y in
                          ((M, M), (M, K), (M, gamma), (M, omega), (omega, gamma)))
    Pt = motion.P.T
    Md, dg, dw, dK = Pt @ M, Pt @ gamma, Pt @ omega, Pt @ K
    dd = np.sum(motion.P * motion.P, 0)
    shape = val.shape[:-1]
    out = []
    for rf in refs:
        mu, lam, k = rf.mu, rf.lam, rf.axis
        num, bb, bg = mu * mu * MK, mu * mu * MM, mu * Mg
        if lam:
            num = num + (mu * lam) * (Md[k] * wg - Mw * dg[k] + dK[k]) + (lam * lam) * (dd[k] * wg - dw[k] * dg[k])
            bb = bb + (2 * mu * lam) * Md[k] + (lam * lam) * dd[k]
            bg = bg + lam * dg[k]
        out.append((num / (bb - bg * bg)).reshape(shape))
    return out


def _phase_series(rate, nu):
    """Integrated Fourier coefficients of the rate on an ``n1 x n2`` grid: the mode box ``(j, k)`` and its dense
    coefficient matrix, the largest integrated coefficient on each axis' edge, the sum of the dropped ones
    (a bound on the phase error they leave), the mean rate."""
    n1, n2 = rate.shape
    j, k, C, mean = _integrated(rate, nu)
    tails = (float(np.max(np.abs(C[np.abs(j) >= n1 // 2 - 1]))), float(np.max(np.abs(C[:, np.abs(k) >= n2 // 2 - 1]))))
    # the dropped modes' budget leaves the truncation below PHASE_TOL where the edge allows
    budget = min(PHASE_DROP, max(0.0, 0.99 * PHASE_TOL - max(tails)))
    rows, cols, dropped = _mode_box(np.abs(C), np.abs(j), np.abs(k), budget)
    return (j[rows], k[cols]), C[np.ix_(rows, cols)], tails, dropped, mean


def _integrated(rate, nu):
    """The modes ``j, k``, the rate's integrated Fourier coefficients ``C`` (``C[0, 0] = 0``) and its mean."""
    n1, n2 = rate.shape
    F = np.fft.fft2(rate) / (n1 * n2)
    j, k = np.fft.fftfreq(n1, 1 / n1), np.fft.fftfreq(n2, 1 / n2)
    div = 2j * np.pi * (j[:, None] * nu[0] + k[None, :] * nu[1])
    div[0, 0] = 1.0
    C = F / div
    C[0, 0] = 0.0
    return j, k, C, float(np.real(F[0, 0]))


def _edge_tails(rates, nu):
    """The largest integrated coefficient on either edge of each rate's series (``rates`` (nref, n1, n2), one
    batched FFT): ``max(_phase_series(rate, nu)[2])`` per rate."""
    _, n1, n2 = rates.shape
    F = np.abs(np.fft.fft2(rates) / (n1 * n2))
    j, k = np.fft.fftfreq(n1, 1 / n1), np.fft.fftfreq(n2, 1 / n2)
    div = np.abs(2 * np.pi * (j[:, None] * nu[0] + k[None, :] * nu[1]))
    div[0, 0] = np.inf
    C = F / div
    edge = (np.abs(j)[:, None] >= n1 // 2 - 1) | (np.abs(k)[None, :] >= n2 // 2 - 1)
    return np.max(C[:, edge], 1)


def _mode_box(A, aj, ak, budget):
    """The smallest box ``|j| <= J, |k| <= K`` (shrunk greedily, the cheaper row or column first) outside which
    the coefficients sum to at most ``budget``: the evaluation costs ``(2J + 1)(2K + 1)`` products."""
    nj, nk = int(aj.max()) + 1, int(ak.max()) + 1
    idx = aj.astype(int)[:, None] * nk + ak.astype(int)[None, :]
    M = np.bincount(idx.ravel(), A.ravel(), nj * nk).reshape(nj, nk)   # mass per (|j|, |k|)
    J, K, dropped = M.shape[0] - 1, M.shape[1] - 1, 0.0
    while J > 0 or K > 0:
        rj = M[J, :K + 1].sum() if J > 0 else np.inf
        ck = M[:J + 1, K].sum() if K > 0 else np.inf
        if min(rj, ck) + dropped > budget:
            break
        if rj / (2 * K + 1) <= ck / (2 * J + 1):   # per product saved
            dropped, J = dropped + rj, J - 1
        else:
            dropped, K = dropped + ck, K - 1
    return aj <= J, ak <= K, dropped


PHASE_DROP = 5e-16     # radians: the integrated Fourier coefficients dropped sum to at most this
PHASE_TOL = 1e-15      # an axis of the grid doubles (32 .. 512) until the coefficients on its edge are below
GRID_START, GRID_MAX = 32, 512
PHASE_REFUSE = 1e-12   # radians: a larger truncation at GRID_MAX is refused (the mean rate's error grows with t)


def _predicted_grid(rate, nu):
    """The grid ``(n1, n2)`` (powers of two, ``GRID_START .. GRID_MAX / 2``) at which the edge coefficients of the
    rate's series on the first grid would fall below ``PHASE_TOL``, extrapolating each axis' geometric decay
    between ``|j| = n/4`` and its edge.  An underestimate costs one more doubling, an overestimate samples points
    the doubling test leaves unused (hence the cap: the early decay is often the slower one, so an uncapped
    extrapolation overshoots)."""
    j, k, C, _ = _integrated(rate, nu)
    out = []
    for A, m in ((np.abs(C), np.abs(j)), (np.abs(C).T, np.abs(k))):
        n = len(m)
        prof = np.zeros(n // 2 + 1)
        np.maximum.at(prof, m.astype(int), A.max(1))
        edge, mid = float(prof[n // 2 - 1:].max()), float(prof[n // 4])
        size = n
        if edge >= PHASE_TOL and mid > edge:
            per_mode = (np.log(mid) - np.log(edge)) / (n // 2 - 1 - n // 4)
            while size < GRID_MAX // 2 and np.log(edge) - per_mode * (size - n) / 2 >= np.log(PHASE_TOL):
                size *= 2
        elif edge >= PHASE_TOL:
            size = min(2 * n, GRID_MAX)
        out.append(size)
    return out


def _phase_grid(motion, I, center, mg, k1, k2, nu, refs):
    """The reference vector and the rate's Fourier series on a grid refined per axis: each axis doubles until its
    edge coefficients are below ``PHASE_TOL``.  The grid predicted from the first grid's decay is sampled in one
    call (a call has a fixed cost besides its points), the doublings take their samples from it; beyond it a
    doubling samples only the new (odd) rows or columns."""
    def sample(i1, n1, i2, n2, refs):
        return _rate_on_grid(motion, I, center, mg, (k1, k2, i1 / n1, i2 / n2), refs)

    n = [GRID_START, GRID_START]
    ar = np.arange(GRID_START)
    rates = sample(ar, GRID_START, ar, GRID_START, refs)
    # the reference whose rate's series converges fastest on the first grid (the largest edge coefficient);
    # the distance from the vertical alone is a poor proxy: the rate's size also varies with the numerator
    best = int(np.argmin(_edge_tails(np.stack(rates), nu)))
    ref, rate = refs[best], rates[best]
    big = _predicted_grid(rate, nu)
    full = sample(np.arange(big[0]), big[0], np.arange(big[1]), big[1], (ref,))[0] if big != n else None
    if full is not None:
        rate = full[::big[0] // n[0], ::big[1] // n[1]]
    while True:
        modes, coef, tails, dropped, mean = _phase_series(rate, nu)
        grow = [a for a in (0, 1) if tails[a] >= PHASE_TOL and n[a] < GRID_MAX]
        if not grow:
            return ref, modes, coef, max(tails) + dropped, mean, tuple(n)
        for a in grow:
            m = list(n)
            m[a] *= 2
            if full is not None and m[0] <= big[0] and m[1] <= big[1]:
                rate, n = full[::big[0] // m[0], ::big[1] // m[1]], m
                continue
            odd = np.arange(1, 2 * n[a], 2)
            other = np.arange(n[1 - a])
            new = (sample(odd, 2 * n[0], other, n[1], (ref,)) if a == 0
                   else sample(other, n[0], odd, 2 * n[1], (ref,)))[0]
            out = np.empty(m)
            idx = [slice(None), slice(None)]
            idx[a] = slice(0, None, 2)
            out[tuple(idx)] = rate
            idx[a] = slice(1, None, 2)
            out[tuple(idx)] = new
            rate, n = out, m


def kovalevskaya_attitude(motion: KovalevskayaMotion, I: ArrayLike, center: ArrayLike, Q0: ArrayLike,
                          omega0: ArrayLike, mass: float, gravity: ArrayLike) -> KovalevskayaAttitude:
    """Set up :class:`KovalevskayaAttitude` (the torus lattice, the FFT of the precession rate)."""
    I, center, Q0 = np.asarray(I, float), np.asarray(center, float), np.asarray(Q0, float)
    g = np.asarray(gravity, float)
    mg = mass * np.linalg.norm(g)
    k1, k2 = _torus_lattice(motion)
    nu = np.linalg.lstsq(np.stack([k1, k2], 1), motion.lattice_velocity(), rcond=None)[0]
    ref, modes, coef, tail, mean, n = _phase_grid(motion, I, center, mg, k1, k2, nu, _references(I, omega0))
    if tail > PHASE_REFUSE:
        raise RuntimeError(f"the precession rate's Fourier series has not converged on the {n[0]} x {n[1]} grid "
                           f"(truncation {tail:.1e} rad)")
    up = -g / np.linalg.norm(g)
    e1 = np.cross(up, [1.0, 0.0, 0.0]) if abs(up[0]) < 0.9 else np.cross(up, [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    E = np.stack([e1, np.cross(up, e1), up], 1)
    gam0 = Q0.T @ up
    b0 = ref.vector(motion.P, I, np.asarray(omega0, float))
    u0 = b0 - (b0 @ gam0) * gam0
    us = E.T @ (Q0 @ (u0 / np.linalg.norm(u0)))
    return KovalevskayaAttitude(motion, I, center, mg, E, ref, (nu, np.zeros(2)), modes, coef, (mean, 0.0),
                                float(np.arctan2(us[1], us[0])), tail, n)


def build_kovalevskaya_top(I: ArrayLike, center: ArrayLike, Q0: ArrayLike, omega0: ArrayLike, mass: float,
                           gravity: ArrayLike) -> tuple[KovalevskayaAttitude, dict]:
    """The closed form of Kovalevskaya's top: ``(KovalevskayaAttitude, diagnostics)``.

    Raises ``FloatingPointError`` or ``RuntimeError`` when the construction does not apply to the data
    (an initial state on the curve's branch point at infinity, ``q(0) = 0``; a degenerate curve).
    """
    from thetasol.solutions.tops.kovalevskaya_top import kovalevskaya_motion

    with np.errstate(divide="raise", invalid="raise", over="raise"):
        motion = kovalevskaya_motion(I, center, Q0, omega0, mass, gravity)
    att = kovalevskaya_attitude(motion, I, center, Q0, omega0, mass, gravity)
    tau = motion.theta.tau
    diag = {"riemann_matrix": tau.copy(), "flow_direction": motion.V2.copy(), "torus_frequencies": att.nu[0].copy(),
            "fit_residual": motion.fit_residual, "phase_tail": att.tail, "phase_grid": att.grid,
            "phase_modes": int(np.count_nonzero(att.coef)), "precession_rate": att.rate[0],
            "phase_reference": str(att.ref),
            "c0": motion.c0, "l1": motion.l1}
    return att, diag
