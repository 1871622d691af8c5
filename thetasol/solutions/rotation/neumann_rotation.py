"""A symmetric body without spin about its symmetry axis in a quadratic potential.

For ``J = diag(j, j, j3)`` (principal frame) the torque has no component along the symmetry axis,
so ``omega_3`` is an integral.  With ``omega_3 = 0`` the spectral curve (4.12) has a tacnode over
``E = infinity`` and the theta-function construction of :mod:`thetasol.solutions.rotation.theta_rotation` does not
apply.  The mechanics is solved directly instead (docs/neumann.md has the derivation and checks):

* ``gamma = Q e3`` (the symmetry axis in space) is a point on the unit sphere in C. Neumann's problem:
  mass ``I1 = j + j3``, potential ``1/2 (j3 - j) gamma^T a gamma``
  (``V = 1/2 tr(Q^T a Q J) = j/2 tr a + 1/2 (j3 - j) gamma^T a gamma``, ``T = 1/2 I1 |gammadot|^2``),
  i.e. the point model of :mod:`thetasol.solutions.points.neumann` with ``K = (j3 - j) a / I1``.
* The rest of the attitude: with ``omega_3 = 0`` the space angular velocity is
  ``gamma x gammadot`` and the body axis ``e1 = Q P e_1`` is parallel-transported along gamma.
  Its angle phi from the frame ``f1 = c x gamma / |c x gamma|``, ``f2 = gamma x f1`` (``c`` the
  eigen-axis of ``a`` the trajectory keeps farthest from) obeys
  ``phidot = -(gamma.c)(c.(gamma x gammadot)) / (1 - (gamma.c)^2)``: on the genus-2 torus a function
  sampled on a grid, transformed by FFT and integrated term by term along the linear flow
  (``phi = phi0 + <G> s + sum G_m e^{i m beta0} (e^{i m nu s} - 1) / (i m nu)``, the near-resonant
  terms in the form ``s sinc`` that keeps ``min(s, 1/|m nu|)`` as their amplification).  Only the
  real part is used, so the mode ``-m`` is folded onto ``m`` and the sum is a few matrix products
  of the coefficients with powers ``e^{i j alpha}``.  With a repeated eigenvalue the angle is a
  Fourier series on the one circle of the point model; on a great circle the body turns about its
  fixed normal.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from thetasol.core.attitude import principal_frame
from thetasol.core.periodic import eval_series, integrated, powers, refined_fft, sum_series
from thetasol.mechanics.equations import invariants_from_moments as _invariants
from thetasol.protocol import ROUNDOFF, ClosedFormUnavailable, RotationSolution
from thetasol.solutions._symmetry import (
    symmetric_without_spin,
)
from thetasol.solutions.points.neumann import (
    EllipticNeumann,
    LatitudeCircle,
    NeumannTorus,
    PlanarNeumann,
    neumann_model,
    series_or_unavailable,
)

__all__ = ["NeumannRotation", "solve_neumann_rotation"]

_EPS = np.finfo(float).eps
N_MAX_2D = 1024


# -- the angle of the parallel-transported frame ---------------------------------------------------

class _AngleSeries:
    """``phi(s) - phi(0) = int_0^s H ds`` for a function H on the torus ``beta in [0, 2 pi)^2`` that
    moves linearly, ``beta(s) = beta0 + nu s``: a 2-d FFT integrated term by term.

    ``H(a)`` returns the samples on the grid ``a x a`` of ``alpha = 2 beta`` in [0, 2 pi); ``parity``
    says in which direction H changes sign under ``alpha -> alpha + 2 pi``: there only odd beta
    harmonics occur, and ``H e^{-i p.alpha/2}`` is sampled on the alpha grid (half the points).
    """

    def __init__(self, H, beta0: np.ndarray, nu: np.ndarray, parity, what: str):
        p = np.asarray(parity, float)

        def transform(n):
            a = 2 * np.pi * np.arange(n) / n
            vals = H(a)
            twist = np.exp(-0.5j * (p[0] * a[:, None] + p[1] * a[None, :]))
            m = np.abs(np.rint(np.fft.fftfreq(n) * n).astype(int))
            band = (m[:, None] >= (3 * n) // 8) | (m[None, :] >= (3 * n) // 8)
            return np.fft.fft2(vals * twist) / (n * n), band, 8 * _EPS * np.abs(vals).max()

        self.n, c, keep = refined_fft(transform, what + " on the torus", 32, N_MAX_2D,
                                       terms=lambda n: f"{n}^2")
        m = np.rint(np.fft.fftfreq(self.n) * self.n).astype(int)
        i1, i2 = np.nonzero(keep)
        modes = np.stack([2 * m[i1] + int(p[0]), 2 * m[i2] + int(p[1])], -1)   # beta harmonics
        coef = c[i1, i2]
        zero = (modes[:, 0] == 0) & (modes[:, 1] == 0)
        self.mean = coef[zero].sum().real
        modes, coef = modes[~zero], coef[~zero]
        D = modes @ nu
        # near-resonant terms keep the form s e^{iDs/2} sinc: amplification min(s, 1/|D|)
        res = np.abs(D) < 1e-3 * nu.min()
        self.C_res = coef[res] * np.exp(1j * (modes[res] @ beta0))
        self.D_res = D[res]
        reg = modes[~res]
        C = coef[~res] / (1j * D[~res])
        self.const = (C * np.exp(1j * (reg @ beta0))).sum().real
        # only Re(sum) is needed: the mode -m is folded onto m (Re(c e^{-i m.b}) = Re(conj(c) e^{i m.b})),
        # so the box holds the half plane m1 > 0 or (m1 = 0, m2 > 0); and m = 2 j + p (the twist), so
        # it is indexed by the alpha harmonics j: a quarter of the beta box, half of it kept
        lower = (reg[:, 0] < 0) | ((reg[:, 0] == 0) & (reg[:, 1] < 0))
        reg = np.where(lower[:, None], -reg, reg)
        C = np.where(lower, C.conj(), C)
        self.p = p.astype(int)
        jj = (reg - self.p) // 2                                   # j1 >= 0
        self.col0 = None                                           # the column j2 = 0
        if reg.size:
            self.n1 = int(jj[:, 0].max())
            self.n2 = int(np.abs(jj[:, 1]).max())
            # columns j2 = 0, 1..n2 and -1..-n2 (conjugated: sum_k conj(b_{-k} e^{ikx}) = conj of a
            # product with the same powers)
            box = np.zeros((self.n1 + 1, 2 * self.n2 + 1), complex)
            col = np.where(jj[:, 1] >= 0, jj[:, 1], self.n2 - jj[:, 1])
            np.add.at(box, (jj[:, 0], col), np.where(jj[:, 1] >= 0, C, C.conj()))
            self.col0 = box[:, 0].copy()
            self.blocks = _row_blocks(box, self.n2)
        self.n_modes = int(keep.sum())

    def __call__(self, s: np.ndarray, beta: np.ndarray) -> np.ndarray:
        """int_0^s H, with beta = beta(s) given (shape (n, 2), any representative mod 2 pi)."""
        out = self.mean * s - self.const
        if self.col0 is not None:
            beta = np.remainder(beta, 2 * np.pi)
            a = np.remainder(2.0 * beta, 2 * np.pi)                # e^{i j alpha} = e^{2 i j beta}
            n1, n2 = self.n1, self.n2
            G = np.repeat(self.col0[:, None], s.size, 1)
            if n2:
                E2 = powers(a[:, 1], n2)
                for r0, r1, pos, neg in self.blocks:
                    w = pos.shape[1]
                    G[r0:r1] += pos @ E2[:w] + (neg @ E2[:w]).conj()
            val = G[0] + (np.einsum("jn,jn->n", G[1:], powers(a[:, 0], n1)) if n1 else 0.0)
            out = out + (np.exp(1j * (beta @ self.p)) * val).real
        for Cr, D in zip(self.C_res, self.D_res, strict=True):
            out = out + (Cr * s * np.exp(0.5j * D * s) * np.sinc(D * s / (2 * np.pi))).real
        return out


def _row_blocks(box: np.ndarray, n2: int, overhead: int = 256):
    """Split the rows of the angle box (columns 0, 1..n2, -1..-n2) into runs with their own column
    width w (rows far from j1 = 0 need few j2): (r0, r1, positive part, conjugated negative part),
    the runs chosen to minimize the entries multiplied plus ``overhead`` per run."""
    nz = box != 0
    cols = np.arange(1, n2 + 1)
    wr = np.array([max(cols[nz[r, 1:n2 + 1]].max(initial=0), cols[nz[r, n2 + 1:]].max(initial=0))
                   for r in range(box.shape[0])])
    R = wr.size
    best, cut = np.zeros(R + 1), np.zeros(R + 1, int)
    for r1 in range(1, R + 1):
        costs = [best[r0] + (r1 - r0) * 2 * wr[r0:r1].max() + overhead for r0 in range(r1)]
        cut[r1] = int(np.argmin(costs))
        best[r1] = costs[cut[r1]]
    blocks, r1 = [], R
    while r1 > 0:
        r0 = cut[r1]
        w = int(wr[r0:r1].max())
        if w:
            blocks.append((r0, r1, box[r0:r1, 1:w + 1].copy(), box[r0:r1, n2 + 1:n2 + 1 + w].copy()))
        r1 = r0
    return blocks[::-1]


def _frame(x: np.ndarray, c: int):
    """The reference frame f1 = e_c x x / |e_c x x|, f2 = x x f1 on the sphere."""
    e = np.zeros(3)
    e[c] = 1.0
    f1 = np.cross(e, x)
    f1 /= np.linalg.norm(f1, axis=-1, keepdims=True)
    return f1, np.cross(x, f1)


def _transported(x: np.ndarray, ref: int, phi: np.ndarray) -> np.ndarray:
    """The body's first axis at the angle phi from the reference frame of axis ref."""
    f1, f2 = _frame(x, ref)
    return np.cos(phi)[:, None] * f1 + np.sin(phi)[:, None] * f2


def _reference_axis(T: NeumannTorus):
    """Eigen-axis c of a farthest from the trajectory: max over the torus of x_c^2 is at a corner of
    the rectangle of (u1, u2); returns c and min(1 - x_c^2)."""
    best, margin = None, -1.0
    for i in range(3):
        mx = 1.0
        for kk, o in enumerate(T.osc):
            kind, g = T.role[i][kk]
            mx *= o.w if kind in ("lo", "hi") else g + o.w
        m = 1.0 - mx / T.norm[i] ** 2
        if m > margin:
            best, margin = i, m
    return best, margin


@dataclass(frozen=True, eq=False)
class NeumannRotation(RotationSolution):
    """Rotation of a symmetric body without axial spin: the axis in Neumann's problem, the body
    parallel-transported along it (see the module docstring).

    Attributes (besides :class:`thetasol.RotationSolution`'s)
    ----------------------------------------------------------
    k : ndarray, shape (3,)
        Eigenvalues of ``K = (j3 - j) a / (j + j3)`` (ascending): the potential of the axis per
        unit moment of inertia.
    frame : ndarray, shape (3, 3)
        Their eigenvectors (columns, right-handed, space frame).
    axis_model : object
        The point model of the axis in these eigen-coordinates
        (:func:`thetasol.solutions.points.neumann.neumann_model`).
    """

    k: np.ndarray = field(default=None, repr=False)
    frame: np.ndarray = field(default=None, repr=False)
    axis_model: object = field(default=None, repr=False)
    _c: dict = field(default=None, repr=False)

    def _evaluate(self, t: np.ndarray):
        c = self._c
        x, xd, E1 = c["axis_motion"](t)
        E2 = np.cross(x, E1)
        V, P = self.frame, c["P"]
        a1, a2, ax = c["axes"]
        Qp = np.empty(t.shape + (3, 3))
        Qp[..., :, a1] = E1 @ V.T
        Qp[..., :, a2] = E2 @ V.T
        Qp[..., :, ax] = x @ V.T
        wp = np.zeros(t.shape + (3,))
        wp[..., a1] = -np.einsum("ni,ni->n", xd, E2)
        wp[..., a2] = np.einsum("ni,ni->n", xd, E1)
        return wp @ P.T, Qp @ P.T


def _genus2_motion(T: NeumannTorus, e10: np.ndarray):
    """(axis_motion(t) -> (x, xdot, E1), info) on the genus-2 torus, the reference axis the eigen-axis
    farthest from the trajectory."""
    ref, margin = _reference_axis(T)
    o, p = [j for j in range(3) if j != ref]

    sgn = 1 if (o, p) in ((0, 1), (1, 2), (2, 0)) else -1

    def Hth(th1, th2):
        x, dx, _ = T.state(th1, th2)
        L = x[..., o] * dx[..., p] - x[..., p] * dx[..., o]
        return -sgn * x[..., ref] * L / (x[..., o] ** 2 + x[..., p] ** 2)

    def H(a):
        return Hth(T.osc[0].theta(a)[:, None], T.osc[1].theta(a)[None, :])

    # every reflection x_i -> -x_i changes the sign of H; theta_k -> theta_k + 2 pi reflects the x_i
    # whose k_i ends the k-th interval
    parity = [sum(T.role[i][kk][0] in ("lo", "hi") for i in range(3)) % 2 for kk in range(2)]
    beta0 = 0.5 * T.alpha0
    nu = 0.5 / T.fbar
    ang = _AngleSeries(H, beta0, nu, parity, "the frame's angular rate")
    x0, _, _ = T.state(T.th0[0], T.th0[1])
    f1, f2 = _frame(x0, ref)
    phi0 = np.arctan2(e10 @ f2, e10 @ f1)

    def motion(t):
        s, al, th = T.s_of_t(t)
        x, dx, gap = T.state(th[0], th[1])
        return x, dx / gap[:, None], _transported(x, ref, phi0 + ang(s, 0.5 * al.T))

    info = {"genus": 2, "reference_axis": ref, "angle_modes": ang.n_modes, "angle_grid": ang.n,
            "frequencies_s": nu.copy(), "time_drift": float(T.drift),
            "series_terms": [int(o_.B.size) for o_ in T.osc], "reference_margin": float(margin),
            "torus_dimension": 2}
    return motion, info



def _elliptic_motion(m: EllipticNeumann, x0: np.ndarray, e10: np.ndarray):
    """A repeated eigenvalue: the frame angle (reference c = n: ``phidot = -z ell / (1 - z^2)``) is one
    more Fourier series on the circle of z, summed with the point model's powers."""
    idx, fbar = m.ax.idx, m.fbar
    c_phi = m.series(lambda th: -m.osc.u(th) * m.ax.ell / m.rho2(th), "the frame's angular rate")
    P_phi = integrated(c_phi)
    Pp0 = eval_series(P_phi, m.al0)
    f1_0, f2_0 = _frame(x0, idx)
    phi0 = np.arctan2(e10 @ f2_0, e10 @ f1_0)

    def motion(t):
        al, E = m.angle(t, P_phi.size - 1)
        x, xd, _ = m.state(t, al, E)
        phi = phi0 + c_phi[0].real * t + fbar * (sum_series(E, P_phi) - Pp0)
        return x, xd, _transported(x, idx, phi)

    return motion, m.info()


def _latitude_motion(m: LatitudeCircle, x0: np.ndarray, e10: np.ndarray):
    """A circle of latitude: the frame turns at the constant rate ``-z0 ell / (1 - z0^2)``."""
    idx = m.ax.idx
    f1_0, f2_0 = _frame(x0, idx)
    phi0 = np.arctan2(e10 @ f2_0, e10 @ f1_0)

    def motion(t):
        x, xd = m.motion(t)
        return x, xd, _transported(x, idx, phi0 - m.ax.z0 * m.rate * t)

    return motion, m.info()


def _planar_motion(m: PlanarNeumann, e10: np.ndarray):
    """The axis on a great circle: the body turns about the fixed normal, so the first axis is e10
    turned by the same angle as the axis (Q stays orthogonal at far times)."""
    def motion(t):
        dv, vdot = m.angle(t)
        x, xd = m.state(dv, vdot)
        return x, xd, m.turn(e10, dv)

    return motion, m.info()


def _attitude_motion(model, x0: np.ndarray, e10: np.ndarray):
    """(axis_motion(t) -> (x, xdot, E1), info) for the point model of the axis."""
    if isinstance(model, NeumannTorus):
        return _genus2_motion(model, e10)
    if isinstance(model, EllipticNeumann):
        return _elliptic_motion(model, x0, e10)
    if isinstance(model, LatitudeCircle):
        return _latitude_motion(model, x0, e10)
    return _planar_motion(model, e10)


# -- set-up ----------------------------------------------------------------------------------------

@dataclass(frozen=True)
class _Reduced:
    """The body reduced to its axis: principal frame P, axes (a1, a2, ax), the eigen-decomposition
    K = V diag(k) V^T of the axis potential, the axis and its velocity (x0, y0) and the first body
    axis e10, all in the eigen-coordinates."""
    P: np.ndarray
    axes: tuple
    k: np.ndarray
    V: np.ndarray
    x0: np.ndarray
    y0: np.ndarray
    e10: np.ndarray


def _reduce(Jp, P, ax, a, Q0, omega0) -> _Reduced:
    """The axis gamma = Q e_ax and gammadot = Q (omega x e_ax) in the eigen-coordinates of K."""
    a1, a2 = (ax + 1) % 3, (ax + 2) % 3
    j, j3 = 0.5 * (Jp[a1] + Jp[a2]), Jp[ax]
    I1 = j + j3
    Q0p = Q0 @ P
    w0p = P.T @ omega0
    w0p[ax] = 0.0
    e_ax = np.zeros(3)
    e_ax[ax] = 1.0
    gamma0 = Q0p[:, ax]
    gdot0 = Q0p @ np.cross(w0p, e_ax)
    K = (j3 - j) / I1 * a
    k, V = principal_frame(K, ascending=True)
    x0 = V.T @ gamma0
    y0 = V.T @ gdot0
    x0 = x0 / np.linalg.norm(x0)
    y0 = y0 - x0 * (x0 @ y0)
    return _Reduced(P, (a1, a2, ax), k, V, x0, y0, V.T @ Q0p[:, a1])


def solve_neumann_rotation(J: np.ndarray, a: np.ndarray, Q0: np.ndarray, omega0: np.ndarray,
                           dps: int | None = None) -> NeumannRotation | None:
    """The Neumann branch of :func:`thetasol.solve_rotation` (None when it does not apply)."""
    found = symmetric_without_spin(J, a, omega0)
    if found is None:
        return None
    if dps is not None:
        raise ClosedFormUnavailable("dps= is not available for the Neumann solution (symmetric body "
                                    "without axial spin)")
    r = _reduce(*found, a, Q0, omega0)
    inv = {key: float(v) for key, v in _invariants(J, a, Q0, omega0).items() if key != "curve"}
    inv["k"] = r.k.copy()
    with series_or_unavailable("thetasol.integrate_rotation"):
        model = neumann_model(r.k, r.x0, r.y0)
        motion, info = _attitude_motion(model, r.x0, r.e10)
    inv.update(info)
    c = {"axis_motion": motion, "P": r.P, "axes": r.axes}
    diag = {"case": model.case, "error_estimate": max(ROUNDOFF, getattr(model, "fit_residual", 0.0))}
    return NeumannRotation(J=J, a=a, Q0=Q0, omega0=omega0, method=model.method, invariants=inv,
                           diagnostics=diag, k=r.k, frame=r.V, axis_model=model, _c=c)
