"""A point on a sphere in a quadratic potential: C. Neumann's problem (Section 6, Theorem 3).

The mass centre constrained to the sphere ``|q| = R`` (6.1) in the potential ``phi = 1/2 q^T a q`` (6.2)
moves, per unit mass, by ``qddot = -a q + lambda q`` with ``lambda = (q.aq - |qdot|^2) / |q|^2`` (the
multiplier that keeps ``d^2 |q|^2 / dt^2 = 0``).  :func:`solve_neumann` returns its exact solution;
the rotation of a symmetric body without axial spin (:mod:`thetasol.solutions.rotation.neumann_rotation`) uses
the same models for the body's axis.  docs/neumann.md has the derivation and the checks.

Units.  With ``a = V diag(k) V^T``, ``x = V^T q / R`` is on the unit sphere and the eigenvalues are
scaled by ``sigma``, a power of 4 near ``k3 - k1`` (exact in binary, so is ``sqrt(sigma)``): the models
below see ``x'' = -k x / sigma + ...`` in the time ``sqrt(sigma) t`` and never the user's units.

The models (``method``, and ``case`` where it is not the generic one), docs/neumann.md has the table:

* ``fourier/genus-2`` (distinct eigenvalues): sphero-conical coordinates ``u1 < u2``
  (``sum x_i^2 / (z - k_i) = (z - u1)(z - u2) / A(z)``, ``A = prod (z - k_i)``) separate with the time
  ``ds = dt / (u2 - u1)``: ``(du_k / ds)^2 = -4 A(u_k) B(u_k)``, ``B(z) = N(z) + sum_m L_m^2 (z - k_m)``,
  ``N(z) = sum_i x_i^2 prod_{j != i} (z - k_j)``, ``L = x cross xdot`` (Uhlenbeck's integrals
  ``sum F_i / (z - k_i) = B / A`` without their divisors ``k_i - k_j``): the curve ``y^2 = -4 A B``.
  With ``u = lo + (hi - lo) sin^2(theta / 2)`` between neighbouring roots of ``A B`` (kept as offsets
  from the nearest ``k_i``), ``s(theta)`` is a running integral on graded Gauss-Legendre panels, its
  inverse and ``t(s) = int (u2 - u1) ds`` are linear terms plus Fourier series, and
  ``x_i = prod_k sqrt(k_i - u_k) / sqrt(prod_{j != i} (k_i - k_j))`` (square roots smooth in theta).
  A time is mapped to ``s`` by safeguarded Newton: a far time costs what ``t = 1`` costs.  The model
  lives in :mod:`thetasol.solutions.points._neumann_torus` (:class:`NeumannTorus`, :class:`Oscillator`).
* ``elliptic``, ``elementary`` with case ``latitude`` (a repeated eigenvalue): ``z = x.n`` in a quartic well,
  the azimuth about ``n`` a quadrature on the same circle, or a uniform circle of latitude.
* case ``planar-*`` (an invariant great circle, or an isotropic ``a``): a pendulum in twice the
  angle, in Jacobi functions (:mod:`thetasol.special.pendulum`).

Hand-written because no library has Neumann's problem in real time (the theta-function form of
Moser and Mumford's Tata lectures II needs the same curve and degenerates in the same places).
"""
from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core.panels import PeriodicIntegral
from thetasol.core.periodic import (
    SeriesNotConverged,
    eval_series,
    fit_series,
    integrated,
    powers,
    refined_fft,
    sum_series,
)
from thetasol.core.roots import quadratic_roots
from thetasol.core.threads import single_blas_thread
from thetasol.mechanics.constraints import point_on_sphere
from thetasol.protocol import ROUNDOFF, ClosedFormUnavailable, Solution
from thetasol.solutions._symmetry import SNAP_TOL
from thetasol.solutions.points._neumann_torus import MIN_WIDTH, DegenerateTorus, NeumannTorus, Oscillator

__all__ = ["NeumannSolution", "solve_neumann", "NeumannTorus", "Oscillator", "EllipticNeumann",
           "LatitudeCircle", "PlanarNeumann", "neumann_model", "series_or_unavailable",
           "MIN_WIDTH", "PLANAR_TOL"]

_EPS = np.finfo(float).eps
#: Out-of-plane size (|x_i|, |xdot_i| / sqrt(k3 - k1)) below which the point is put on the great circle.
PLANAR_TOL = 64 * _EPS
#: Relative tolerance on q0 . v0 (the velocity must be tangent to the sphere).
TANGENT_TOL = 1e-12
#: The numerical reference named where no closed form is built.
_REFERENCE = "thetasol.integrate_neumann (qddot = -a q + lambda q, lambda = (q.aq - |qdot|^2) / |q|^2)"


@contextmanager
def series_or_unavailable(reference: str) -> Iterator[None]:
    """Turn a Fourier series that did not converge, or a torus refused as nearly degenerate, into
    :class:`ClosedFormUnavailable` naming ``reference``, the numerical integrator to use instead."""
    try:
        yield
    except DegenerateTorus as err:
        raise ClosedFormUnavailable(f"{err}; use {reference}") from None
    except SeriesNotConverged as err:
        raise ClosedFormUnavailable(
            f"Neumann solution: {err}: the torus is too close to a separatrix or the trajectory too close "
            f"to the reference axis; use {reference}") from None


# -- a repeated eigenvalue: an axis of symmetry n --------------------------------------------------

def _axes_of_symmetry(idx: int):
    """The indices (o1, o2) of the other two eigen-axes with (m1, m2, n) right-handed."""
    o1, o2 = [j for j in range(3) if j != idx]
    if (o1, o2) not in ((0, 1), (1, 2), (2, 0)):
        o1, o2 = o2, o1
    return o1, o2


def _latitude_roots(kappa: float, h: float, ell: float):
    """The roots in z of zdot^2 = kappa z^4 - (kappa + 2h) z^2 + 2h - ell^2, as (root, 1 - |root| for a
    real root): z^2 = 1 - v with kappa v^2 + (2h - kappa) v - ell^2 = 0 (v, and so 1 - |z| = v / (1 + |z|),
    accurate near the poles)."""
    v = quadratic_roots(kappa, 2.0 * h - kappa, -ell * ell)
    roots = []
    for vv in v:
        w = 1.0 - vv
        if w >= 0:
            rt = np.sqrt(w)
            roots += [(rt, vv / (1.0 + rt)), (-rt, vv / (1.0 + rt))]
        else:
            roots += [(1j * np.sqrt(-w), None), (-1j * np.sqrt(-w), None)]
    return roots


def _turning_points(roots, z0: float):
    """The two real roots around z0 (the oscillation interval of z)."""
    real = sorted([r for r in roots if np.isreal(r[0])], key=lambda r: r[0].real)
    below = [r for r in real if r[0].real <= z0]
    above = [r for r in real if r[0].real > z0]
    if not below or not above:
        # z0 at a turning point within rounding: take the nearest pair around it
        zs = np.array([r[0].real for r in real])
        i = int(np.argmin(np.abs(zs - z0)))
        below, above = (real[:i + 1], real[i + 1:]) if i + 1 < len(real) and z0 >= zs[i] else (real[:i], real[i:])
    return below[-1], above[0]


@dataclass(frozen=True)
class _Axial:
    """The data of a motion about the symmetry axis n = e_idx: the frame (m1, m2, n), the height
    z0 = x0.n, the angular momentum ell about n, the energy h and the anisotropy kappa."""
    idx: int
    o1: int
    o2: int
    kappa: float
    z0: float
    ell: float
    h: float
    lam0: float

    @classmethod
    def of(cls, k, x0, y0, idx):
        o1, o2 = _axes_of_symmetry(idx)
        kperp = 0.5 * (k[o1] + k[o2])
        kappa = k[idx] - kperp
        z0 = x0[idx]
        ell = x0[o1] * y0[o2] - x0[o2] * y0[o1]
        h = 0.5 * (y0 @ y0) + 0.5 * kappa * z0 * z0
        return cls(idx, o1, o2, kappa, z0, ell, h, np.arctan2(x0[o2], x0[o1]))

    def basis(self):
        return np.eye(3)[self.o1], np.eye(3)[self.o2], np.eye(3)[self.idx]


class LatitudeCircle:
    """A circle of latitude z0 about the symmetry axis run at a constant rate (a relative equilibrium)."""

    method, case = "elementary", "latitude"

    def __init__(self, ax: _Axial, x0: np.ndarray):
        self.ax = ax
        self.rho0 = np.hypot(x0[ax.o1], x0[ax.o2])
        self.rate = ax.ell / self.rho0 ** 2

    def motion(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        ax = self.ax
        m1, m2, n = ax.basis()
        lam = ax.lam0 + self.rate * t
        cl, sl = np.cos(lam)[:, None], np.sin(lam)[:, None]
        x = ax.z0 * n + self.rho0 * (cl * m1 + sl * m2)
        xd = ax.ell / self.rho0 * (-sl * m1 + cl * m2)
        return x, xd

    def info(self) -> dict:
        return {"torus_dimension": 1, "reference_axis": self.ax.idx, "azimuth_drift": float(self.rate)}


class EllipticNeumann:
    """a with a repeated eigenvalue: ``K = k_perp + kappa n n^T`` with ``n = e_idx``.  ``z = x.n``
    oscillates in a quartic well, ``zdot^2 = kappa z^4 - (kappa + 2h) z^2 + 2h - ell^2``; the azimuth
    ``int ell / (1 - z^2) dt`` is a Fourier series on the same circle.  Where that series does not
    converge (a small ``ell`` near a pole: the azimuth turns by ~pi in a short time) the horizontal
    part ``rho e^{i lambda}``, smooth through the pole, is one instead (:meth:`_cartesian`)."""

    method, case = "elliptic", ""

    def __init__(self, ax: _Axial, roots, lo, hi, y0: np.ndarray):
        self.ax = ax
        zlo, zhi = float(lo[0].real), float(hi[0].real)
        # 1 - z_hi and 1 + z_lo from 1 - |z| where they are small (a turning point near a pole)
        self.one_minus_hi = hi[1] if zhi > 0 else 1.0 - zhi
        self.one_plus_lo = lo[1] if zlo < 0 else 1.0 + zlo
        others = [r[0] for r in roots if r is not lo and r is not hi]
        self.osc = osc = Oscillator(zlo, zhi, abs(ax.kappa),
                                    below=[zlo - r.real for r in others if np.isreal(r) and r.real < zlo],
                                    above=[r.real - zhi for r in others if np.isreal(r) and r.real >= zhi],
                                    complex_roots=[r for r in others if not np.isreal(r)], name="z")
        # initial angle theta0: cos from the position, sin from zdot = (w/2) sin(theta) rate
        z0, zd0 = ax.z0, y0[ax.idx]
        cos0 = ((zhi - z0) - (z0 - zlo)) / osc.w
        sin0 = 2.0 * zd0 / (osc.w * np.sqrt(osc.C * np.prod(np.abs(np.array(others) - z0))))
        th0 = np.arctan2(sin0, cos0)
        self.al0 = osc.alpha(th0)
        self.fbar = osc.fbar
        try:
            self.c_lam = self.series(lambda th: ax.ell / self.rho2(th), "the azimuth rate")
        except SeriesNotConverged:
            self.c_lam = None
            self._cartesian(th0)
            return
        self.P_lam = integrated(self.c_lam)
        self.Pl0 = eval_series(self.P_lam, self.al0)
        self.n_pow = max(osc.B.size, self.P_lam.size) - 1

    def _cartesian(self, th0: float) -> None:
        """``W~(alpha) = rho e^{i (lambda - nu alpha)}`` as a complex Fourier series (``Wp``: m >= 0,
        ``Wn``: m = -1, -2, ...), ``nu`` the azimuth's advance per unit alpha.  lambda on the grid is the
        running integral of ``dlambda/dtheta = ell / ((1 - z^2) rate)`` on panels graded toward the
        zeros of ``1 - z^2`` (``theta = pi +- 2i asinh sqrt((1 - z_hi) / w)``, ``+-2i asinh sqrt((1 + z_lo)
        / w)``) and of the rate."""
        ax, osc = self.ax, self.osc
        poles = [np.pi + 2j * np.arcsinh(np.sqrt(self.one_minus_hi / osc.w)),
                 2j * np.arcsinh(np.sqrt(self.one_plus_lo / osc.w))]
        poles = np.array(poles + [p.conjugate() for p in poles])
        lam = PeriodicIntegral(lambda th: ax.ell / (self.rho2(th) * osc.rate(th)),
                               np.concatenate([osc.singularities(), poles, -poles]))
        self.nu = lam.total / (2 * np.pi)
        lam_start = ax.lam0 - lam(th0)
        floor = 8 * _EPS * (1.0 + 2 * np.pi * abs(self.nu))

        def transform(n):
            al = 2 * np.pi * np.arange(n) / n
            th = osc.theta_grid(n)
            W = np.sqrt(self.rho2(th)) * np.exp(1j * (lam_start + lam(th) - self.nu * al))
            return np.fft.fft(W) / n, slice((3 * n) // 8, (5 * n) // 8 + 1), floor

        n, c, keep = refined_fft(transform, "the horizontal motion", 64, 2 ** 13)
        m = np.abs(np.fft.fftfreq(n, 1.0 / n)[keep]).max() if keep.any() else 0
        m = int(max(m, 1))
        self.Wp, self.Wn = c[:m + 1].copy(), c[n - m:][::-1].copy()
        self.n_pow = max(osc.B.size - 1, m)

    def _horizontal(self, al: np.ndarray, E: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """rho e^{i lambda} and its time derivative from the Cartesian series (:meth:`_cartesian`)."""
        m = self.Wp.size - 1
        Ep, En = E[:m], E[:m].conj()
        j = np.arange(1, m + 1)
        Wt = self.Wp[0] + self.Wp[1:] @ Ep + self.Wn @ En
        dWt = (1j * j * self.Wp[1:]) @ Ep - (1j * j * self.Wn) @ En
        rot = np.exp(1j * self.nu * al)
        return Wt * rot, (dWt + 1j * self.nu * Wt) * rot / self.fbar

    def rho2(self, th: np.ndarray) -> np.ndarray:
        """1 - z^2 without cancellation."""
        dlo, dhi, _, _ = self.osc.parts(th)
        return (self.one_minus_hi + dhi) * (self.one_plus_lo + dlo)

    def series(self, g: Callable[[np.ndarray], np.ndarray], what: str) -> np.ndarray:
        """The Fourier series in alpha of g(theta(alpha)).  Noise floor: the rounding of g (from ell) and
        that of theta (2 pi eps) times the largest |dg/dtheta|, by differences at the quadrature nodes
        of the oscillator (dense where g is steep: near a pole with small ell, 1 / (1 - z^2) is)."""
        th, h = self.osc.F.nodes, 1e-8
        slope = np.abs(g(th + h) - g(th - h)).max() / (2 * h)
        return fit_series(lambda al: g(self.osc.theta_grid(al.size)), what,
                          floor=4 * _EPS * (abs(self.ax.ell) + 1.0) + 4 * np.pi * _EPS * slope)

    def angle(self, t: np.ndarray, n_pow: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """alpha(t) and its powers e^{ij alpha}, j = 1..max(self.n_pow, n_pow) (shared by the series)."""
        al = self.al0 + t / self.fbar
        return al, powers(al, max(self.n_pow, n_pow))

    def state(self, t: np.ndarray, al: np.ndarray, E: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x, xdot, theta) at the times t from alpha(t) and its powers (:meth:`angle`)."""
        ax, osc = self.ax, self.osc
        m1, m2, n = ax.basis()
        th = al + sum_series(E, osc.B)
        z = osc.u(th)
        zd = 0.5 * osc.w * np.sin(th) * osc.rate(th)
        if self.c_lam is None:
            # the direction of W, its modulus from z (|x| = 1 to rounding at any t); the velocity
            # made tangent (the series' error has a normal part)
            W, dW = self._horizontal(al, E)
            aW = np.abs(W)
            W = np.sqrt(self.rho2(th)) * np.where(aW > 0, W / np.where(aW > 0, aW, 1.0), 1.0)
            x = z[:, None] * n + W.real[:, None] * m1 + W.imag[:, None] * m2
            xd = zd[:, None] * n + dW.real[:, None] * m1 + dW.imag[:, None] * m2
            return x, xd - x * np.einsum("ij,ij->i", x, xd)[:, None], th
        rho = np.sqrt(self.rho2(th))
        lam = ax.lam0 + self.c_lam[0].real * t + self.fbar * (sum_series(E, self.P_lam) - self.Pl0)
        cl, sl = np.cos(lam)[:, None], np.sin(lam)[:, None]
        radial = cl * m1 + sl * m2
        east = -sl * m1 + cl * m2
        x = z[:, None] * n + rho[:, None] * radial
        xd = zd[:, None] * n - (z * zd / rho)[:, None] * radial + (ax.ell / rho)[:, None] * east
        return x, xd, th

    def motion(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        al, E = self.angle(t)
        x, xd, _ = self.state(t, al, E)
        return x, xd

    def info(self) -> dict:
        return {"torus_dimension": 1, "reference_axis": self.ax.idx, "period": float(2 * np.pi * self.fbar),
                "azimuth_drift": float(self.c_lam[0].real if self.c_lam is not None else self.nu / self.fbar),
                "series_terms": [int(self.osc.B.size),
                                 int(self.c_lam.size if self.c_lam is not None else self.Wp.size)]}


def _repeated_model(k, x0, y0, idx):
    """The motion for a repeated eigenvalue (the other one at idx): a latitude circle or the
    elliptic model."""
    ax = _Axial.of(k, x0, y0, idx)
    roots = _latitude_roots(ax.kappa, ax.h, ax.ell)
    lo, hi = _turning_points(roots, ax.z0)
    if float(hi[0].real) - float(lo[0].real) <= 64 * _EPS:
        return LatitudeCircle(ax, x0)
    return EllipticNeumann(ax, roots, lo, hi, y0)


# -- the point on an invariant great circle --------------------------------------------------------

def _rotate(v: np.ndarray, n: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """v turned by ``angle`` (array) about the unit vector n (Rodrigues), shape angle.shape + (3,)."""
    c, s = np.cos(angle)[..., None], np.sin(angle)[..., None]
    return c * v + s * np.cross(n, v) + (1.0 - c) * (n @ v) * n


def _pendulum(psi0: float, psidot0: float, nu: float):
    """psi'' = -nu^2 sin psi from (psi0 in (-pi, pi], psidot0): the constants of
    :func:`thetasol.special.pendulum.pendulum_angle` (which returns half of ``psi(t) - psi0`` and
    ``psidot(t)``) and the kind of motion."""
    if nu == 0.0 or (psidot0 == 0.0 and (np.sin(psi0) == 0.0 or abs(psi0) == np.pi)):     # at rest on an axis
        return {"kind": "uniform", "phi0": 0.0, "w0": 0.5 * psidot0}, ("uniform" if psidot0 else "rest")
    # scipy.special (slow to import) only once a pendulum is needed: solve_rotation imports this module
    from thetasol.special.pendulum import pendulum_params

    c, _ = pendulum_params(psi0, psidot0, nu)
    return c, c["kind"]


class PlanarNeumann:
    """The point on the invariant great circle with the unit normal ``normal`` (an eigenvector of k,
    eigen-coordinates): ``x = cos v p + sin v q``, ``psi = 2 v`` a pendulum of frequency
    ``sqrt(k_q - k_p)``; :meth:`angle` gives ``v - v0`` and ``vdot``."""

    def __init__(self, k, x0, y0, normal, isotropic: bool = False):
        n = normal / np.linalg.norm(normal)
        # p, q: an orthonormal eigenbasis of k in the plane, p the lower eigenvalue
        Pn = np.eye(3) - np.outer(n, n)
        B = Pn @ np.diag(k) @ Pn
        ev, W = np.linalg.eigh(B + 10.0 * (np.abs(k).max() + 1.0) * np.outer(n, n))
        p, q = W[:, 0], W[:, 1]
        if np.cross(p, q) @ n < 0:
            q = -q
        v0 = np.arctan2(x0 @ q, x0 @ p)
        vdot0 = y0 @ np.cross(n, x0)
        psi0 = np.remainder(2.0 * v0 + np.pi, 2.0 * np.pi) - np.pi
        nu2 = ev[1] - ev[0]
        scale = abs(vdot0) + np.sqrt(np.abs(k).max())
        self.nu = 0.0 if isotropic or nu2 <= 4 * _EPS * scale ** 2 else float(np.sqrt(nu2))
        self.pend, self.kind = _pendulum(psi0, 2.0 * vdot0, self.nu)
        self.method = "elementary" if self.kind in ("rest", "uniform") else "elliptic"
        self.case = f"planar-{self.kind}"
        x0n = x0 - (x0 @ n) * n
        self.x0n = x0n / np.linalg.norm(x0n)
        self.n = n

    def angle(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(v(t) - v0, vdot(t)): v - v0 = (psi - psi0) / 2."""
        from thetasol.special.pendulum import pendulum_angle

        return pendulum_angle(self.pend, t)

    def state(self, dv: np.ndarray, vdot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(x, xdot) at the angles dv from x0 (turned about the fixed normal: |x| = 1 at far times)."""
        x = _rotate(self.x0n, self.n, dv)
        return x, vdot[:, None] * np.cross(self.n, x)

    def turn(self, v: np.ndarray, dv: np.ndarray) -> np.ndarray:
        """v turned about the normal by the angles dv, shape dv.shape + (3,)."""
        return _rotate(v, self.n, dv)

    def motion(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self.state(*self.angle(t))

    def info(self) -> dict:
        return {"torus_dimension": 1 if self.nu else 0, "pendulum_nu": self.nu, "plane_normal": self.n}


def _great_circle_normal(x0, y0, fallback: int):
    """The normal of the great circle through x0 along y0 (for y0 = 0, one through e_fallback)."""
    if np.linalg.norm(y0) > 0.0:
        return np.cross(x0, y0)
    normal = np.cross(x0, np.eye(3)[fallback])
    if np.linalg.norm(normal) <= PLANAR_TOL:
        normal = np.cross(x0, np.eye(3)[(fallback + 1) % 3])
    return normal


def neumann_model(k: np.ndarray, x0: np.ndarray,
                  y0: np.ndarray) -> NeumannTorus | EllipticNeumann | LatitudeCircle | PlanarNeumann:
    """The model of Neumann's problem ``xddot = -k x + (x.kx - |xdot|^2) x`` (k ascending, |x0| = 1,
    y0 tangent), chosen from the data: an object with ``method``, ``motion(t) -> (x, xdot)`` and
    ``info()``: :class:`NeumannTorus`, :class:`EllipticNeumann`, :class:`LatitudeCircle` or
    :class:`PlanarNeumann`.  Raises :class:`ClosedFormUnavailable` where the models lose accuracy."""
    span = k[2] - k[0]
    if span <= 8 * _EPS * np.abs(k).max():
        return PlanarNeumann(k, x0, y0, _great_circle_normal(x0, y0, int(np.argmin(np.abs(x0)))), isotropic=True)
    wscale = np.sqrt(span)
    gaps = np.diff(k)
    if gaps.min() <= SNAP_TOL * span:
        idx = 0 if gaps[1] <= gaps[0] else 2                # the eigenvalue that is not repeated
        n = np.eye(3)[idx]
        ell = np.cross(x0, y0) @ n
        if abs(ell) <= PLANAR_TOL * (np.linalg.norm(y0) + wscale):
            normal = np.cross(x0, y0) if np.linalg.norm(y0) > PLANAR_TOL * wscale else np.cross(x0, n)
            if np.linalg.norm(normal) <= PLANAR_TOL:
                normal = np.cross(x0, np.eye(3)[(idx + 1) % 3])   # the point on n at rest
            return PlanarNeumann(k, x0, y0, normal)
        return _repeated_model(k, x0, y0, idx)
    for i in range(3):
        if max(abs(x0[i]), abs(y0[i]) / wscale) <= PLANAR_TOL:
            return PlanarNeumann(k, x0, y0, np.eye(3)[i])
    T = NeumannTorus(k, x0, y0)
    if T.fit_residual > 1e-9:
        raise DegenerateTorus(f"Neumann solution: the initial state is reproduced only to "
                              f"{T.fit_residual:.1e} (nearly degenerate torus)")
    return T


# -- the public solution ---------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class NeumannSolution(Solution):
    """The motion ``t -> (q(t), v(t))`` of a point on the sphere ``|q| = |q0|`` in ``phi = 1/2 q^T a q``
    (per unit mass), from :func:`solve_neumann`.

    Attributes
    ----------
    a : ndarray, shape (3, 3)
        The potential matrix (symmetrized).
    q0, v0 : ndarray, shape (3,)
        The initial position and (tangent) velocity.
    model : str
        ``"neumann"``.
    method : str
        ``"fourier/genus-2"``, ``"elliptic"`` or ``"elementary"``; ``diagnostics["case"]`` is ``"latitude"``
        or ``"planar-<kind>"`` for those models, ``""`` otherwise.
    invariants : dict
        ``energy`` (``1/2 |v|^2 + 1/2 q.aq``) and Uhlenbeck's integrals in the eigenbasis of ``a``
        (ascending eigenvalues), ``F_k = x_k^2 + sum_{j != k} (x_k y_j - x_j y_k)^2 / (a_k - a_j)`` with
        ``x = q / R``, ``y = v / R`` (``sum F_k = 1``): ``F`` (distinct eigenvalues), ``F_axis`` and
        ``L_axis`` (a repeated eigenvalue: ``F`` of the other axis and the angular momentum ``q x v``
        about it) or ``L`` (isotropic ``a``: the angular momentum).
    diagnostics : dict
        ``eigenvalues``, ``axes`` (columns, right-handed), ``radius``, ``time_scale`` (the unit of time
        of the models, ``1 / sqrt(sigma)``), ``branch_points`` of the genus-2 curve, the model's
        periods and series sizes, ``fit_residual`` (the data reproduced at t = 0, unit sphere) and
        ``error_estimate`` (that residual, at least float64 rounding).
    """

    model = "neumann"

    a: np.ndarray
    q0: np.ndarray
    v0: np.ndarray
    method: str
    invariants: dict = field(repr=False)
    diagnostics: dict = field(default_factory=dict, repr=False)
    _model: object = field(default=None, repr=False)
    _units: tuple = field(default=None, repr=False)

    def fastest_frequency(self) -> float:
        """The larger of the speed ``|v0| / R`` and the potential's rate ``sqrt(max |a_i - a_j|)``."""
        ev = self.diagnostics["eigenvalues"]
        return max(float(np.linalg.norm(self.v0)) / self.diagnostics["radius"], math.sqrt(float(ev.max() - ev.min())))

    def __call__(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """``(q(t), v(t))``, each of shape ``t.shape + (3,)``."""
        return super().__call__(t)

    def _evaluate(self, t: np.ndarray):
        R, rate, axes = self._units
        x, xd = self._model.motion(t * rate)             # rate is a power of 2: exact
        return R * (x @ axes.T), (R * rate) * (xd @ axes.T)


def _uhlenbeck(k: np.ndarray, x: np.ndarray, y: np.ndarray, R: float, snapped: bool, isotropic: bool) -> dict:
    """Uhlenbeck's integrals F_k = x_k^2 + sum_{j != k} (x_k y_j - x_j y_k)^2 / (a_k - a_j) of the
    unit sphere (x = q / R, y = v / R in the eigenbasis; sum F_k = 1, sum a_k F_k = 2 H / R^2) where
    their divisors are not zero, and the angular momenta q x v that replace them."""
    L = np.cross(x, y)
    if isotropic:
        return {"L": L * R * R}
    F = x * x
    gaps = np.diff(k)
    idx = 0 if gaps[1] <= gaps[0] else 2
    for i in range(3):
        for j in range(3):
            if j != i and not (snapped and idx not in (i, j)):
                F[i] += L[3 - i - j] ** 2 / (k[i] - k[j])
    if snapped:
        return {"F_axis": float(F[idx]), "L_axis": float(L[idx] * R * R)}
    return {"F": F}


def _validated(a, q0, v0):
    """(a, q0, v0, radius) checked: a symmetric, q0 != 0, v0 tangent within TANGENT_TOL relative."""
    a, q0, v0, R = point_on_sphere(a, q0, v0)
    vn = float(np.linalg.norm(v0))
    if abs(q0 @ v0) > TANGENT_TOL * R * vn:
        raise ValueError(f"v0 must be tangent to the sphere |q| = |q0|: q0.v0 / (|q0| |v0|) = "
                         f"{(q0 @ v0) / (R * vn):.3g} (tolerance {TANGENT_TOL:g})")
    return a, q0, v0, R


@single_blas_thread
def solve_neumann(a: ArrayLike, q0: ArrayLike, v0: ArrayLike) -> NeumannSolution:
    """Exact motion of a point on the sphere ``|q| = |q0|`` in the potential ``phi = 1/2 q^T a q``
    (Section 6, (6.1)-(6.2); Theorem 3: the mass centre of the configuration).

    Per unit mass ``qddot = -a q + lambda q``, ``lambda = (q.aq - |qdot|^2) / |q|^2``.  Any symmetric
    ``a`` (definite, indefinite, repeated eigenvalues); the radius and the scale of ``a`` do not matter.

    Parameters
    ----------
    a : array_like, shape (3, 3)
        Symmetric potential matrix.
    q0 : array_like, shape (3,)
        Initial position (non-zero; its length is the radius of the sphere).
    v0 : array_like, shape (3,)
        Initial velocity, tangent to the sphere (``|q0.v0| <= 1e-12 |q0| |v0|``; projected exactly).

    Returns
    -------
    NeumannSolution
        ``sol(t) -> (q, v)`` with shapes ``t.shape + (3,)``.

    Raises
    ------
    ValueError
        ``a`` not symmetric, NaN or inf in the data, ``q0 = 0``, ``v0`` not tangent.
    ClosedFormUnavailable
        The torus on a separatrix within rounding (two branch points equal), thinner than
        ``MIN_WIDTH`` (within ~1e-7 rad of an invariant great circle without being on it), or a
        Fourier series that would need more terms than its limit: the message names the numerical
        reference to use instead, :func:`thetasol.integrate_neumann`.
    """
    a, q0, v0, R = _validated(a, q0, v0)
    k, axes = np.linalg.eigh(a)
    axes[:, 2] *= np.sign(np.linalg.det(axes))
    span = k[2] - k[0]
    isotropic = bool(span <= 8 * _EPS * np.abs(k).max())
    # sigma = 4^m near the span: k / sigma, sqrt(sigma) t and v / sqrt(sigma) are exact scalings
    rate = 1.0 if isotropic else float(2.0 ** np.round(0.5 * np.log2(span)))
    ks = np.zeros(3) if isotropic else (k - k[1]) / (rate * rate)
    x0 = axes.T @ q0 / R
    y0 = axes.T @ v0 / (R * rate)
    x0 = x0 / np.linalg.norm(x0)
    y0 = y0 - x0 * (x0 @ y0)
    with series_or_unavailable(_REFERENCE):
        model = neumann_model(ks, x0, y0)
    gaps = np.diff(ks)
    snapped = not isotropic and bool(gaps.min() <= SNAP_TOL * (ks[2] - ks[0]))
    inv = {"energy": float(0.5 * (v0 @ v0) + 0.5 * (q0 @ a @ q0))}
    inv.update(_uhlenbeck(k, x0, rate * y0, R, snapped, isotropic))
    diag = {"eigenvalues": k, "axes": axes, "radius": R, "time_scale": 1.0 / rate}
    diag.update(model.info())
    if isinstance(model, NeumannTorus):
        diag["fit_residual"] = model.fit_residual
        diag["branch_points"] = np.sort(np.r_[k, model.zb * rate * rate + k[1]])
    diag["case"] = model.case
    diag["error_estimate"] = max(ROUNDOFF, diag.get("fit_residual", 0.0))
    return NeumannSolution(a=a, q0=q0, v0=v0, method=model.method, invariants=inv, diagnostics=diag,
                           _model=model, _units=(R, rate, axes))
