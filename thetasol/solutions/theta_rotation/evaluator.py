"""Stage 5: the evaluator of Phi(0, t) = Q(t)^T Q0 along the real flow, and from it omega and Q.

At the three places ``P_s`` over ``E = 0`` the Baker-Akhiezer function gives the fundamental matrix
of ``Phidot = -A(0, t) Phi`` (4.11): ``Phi(0, t) X0 = B [Psi_k(P_s, t)]`` with ``X0`` the initial
eigenvectors, and ``Phi(0, t) = Q(t)^T Q0``.  Then ``Q = Q0 Phi^T`` and ``omega = vee(-Phidot Phi^T)``;
for a symmetric body ``Q = Q~ R(t)^T``, ``omega = R omega~ + spin e`` back from the turning frame.

The theta functions along the flow, ``theta(b_sk + t U)`` and ``theta(d_k + t U)``, are Fourier series
in the ``rdim`` real phases of ``U`` (:class:`thetasol.theta.flow.FlowTheta`): per time only the
phases and one real matrix product remain, and a far time costs what ``t = 1`` costs.  The exponents
``exp(i nu_sk t)`` take ``nu t / 2 pi`` modulo 1 exactly for ``|t| < 2^31`` (:meth:`FlowEvaluator._turns`),
as the integer combinations of a few rates' turns that the exponents are exactly
(:class:`~.exponents.PhaseRates`): rounded products ``nu t`` make the first integrals drift with ``t``
(4e-11 at ``t = 1e6`` on the rank-one bodies), and so do the rounded floats ``nu_sk``, whose exact
relations hold only to ~1e-16 (symmetric_oblate 1.9e-11 at ``t = 1e6``, 1.9e-8 at ``1e9``); with the
combinations, and the flow's phases ``t u`` reduced as exactly (:meth:`thetasol.theta.flow.FlowTheta.turns`), the
drift on ``[T, T + 100]`` stays at the level of ``T = 0`` up to ``T = 1e9`` (<= 3.0e-14 on six bodies, the
fast-spin ones included, tests/test_one_call.py).  After the flow ``Psi`` and its derivative go through one
more real product (9x9 complex maps folded with ``B``, ``X0^-1``, ``Q0`` and the principal frame) and
the 3x3 algebra runs on component rows: the polar factor by one Newton-Schulz step
(:func:`thetasol.core.so3.polar_near_orthogonal`, 20x closer to the long-double polar factor than the
SVD's, tests/test_theta_evaluation.py).  One time takes that state on Python complex numbers and
floats around the one matrix product (:meth:`FlowEvaluator._state_one`): numpy's fixed cost per call
exceeds the arithmetic on nine elements.  One far time then costs 25-48 us of CPU time, 65 near the
unstable equilibrium (best of 7 x 100 calls on a shared 2-core machine, benchmarks/bench_theta_rotation.py,
docs/bench_theta_rotation.md): 6-62 dense points.  With the numba kernels switched on (``THETASOL_NUMBA=1``,
:mod:`thetasol.core.jit`) the state is one compiled kernel per chunk of times.
Working memory is ~2.5 KB per time (the flow's phases go in bounded blocks), so the default chunk of
:class:`thetasol.protocol.Solution` applies.

The shifts ``b_sk = A(P_s) - e_k`` are sums of Abel images, known to ~1e-14; where ``psi_k(P_s)`` is
small or zero that error shows directly in ``Psi``.  Each ``b_sk`` is moved by the least amount that
makes the quotient reproduce ``psi_k(P_s)`` and its derivative ``-(omega0 x psi)_k`` at ``t = 0``
exactly (two linear conditions on the gradient and Hessian of theta): the shift lands on the theta
divisor where the component vanishes, and ``t = 0`` returns the initial data to round-off.
"""
from __future__ import annotations

import cmath
import math
from dataclasses import dataclass

import mpmath
import numpy as np

from thetasol.core.jit import Kernel
from thetasol.core.so3 import NEWTON_SCHULZ_MAX, polar_near_orthogonal, polar_near_orthogonal_one
from thetasol.core.turns import TURNS_EXACT, rate_turns, rate_turns_one, split_rate_exact
from thetasol.solutions.theta_rotation.divisors import EigenvectorDivisors
from thetasol.solutions.theta_rotation.exponents import Exponents, PhaseRates
from thetasol.solutions.theta_rotation.riemann import ThetaShifts
from thetasol.solutions.theta_rotation.spectral_data import SpectralData
from thetasol.theta.flow import FlowTheta

__all__ = ["FlowEvaluator", "flow_evaluator"]


@dataclass(frozen=True, eq=False)
class FlowEvaluator:
    """``Phi(0, t)``, ``omega(t)`` and ``Q(t)`` from theta along the flow (stage 5).

    Attributes
    ----------
    flow : FlowTheta
        Theta at the 9 shifts ``b_sk`` and at ``d`` along ``t U`` (the three ``d_k`` are equal,
        :class:`~.riemann.ThetaShifts`: one denominator serves the three components).
    nu : ndarray, shape (3, 3)
        Exponents: ``Psi_k(P_s, t)`` carries ``exp(i nu_sk t)``.
    phase : PhaseRates
        The exponents as exact integer combinations of rates: the phases ``nu_sk t`` come from these.
    amp : ndarray, shape (3, 3)
        ``rho_k(P_s) theta(d_k)`` times the separated exponents of the flow's theta values.
    X0inv : ndarray, shape (3, 3)
        ``(B X0)^-1``: from the components at the places to ``Phi(0, t)``.
    B : ndarray, shape (3, 3)
        Components -> principal frame.
    Q0p, P : ndarray, shape (3, 3)
        Initial attitude in the principal frame, and that frame.
    spin : float
        Axial spin of a symmetric body (0.0 otherwise).
    axis : int or None
        Its symmetry axis, None for distinct ``J``.
    """

    flow: FlowTheta
    nu: np.ndarray
    phase: PhaseRates
    amp: np.ndarray
    X0inv: np.ndarray
    B: np.ndarray
    Q0p: np.ndarray
    P: np.ndarray
    spin: float
    axis: int | None

    def phi0(self, t: np.ndarray, derivative: bool) -> tuple[np.ndarray, np.ndarray | None]:
        """Phi(0, t) (n, 3, 3) = Q'(t)^T Q'0 in the principal frame and, if asked, its derivative.

        numpy only: the set-up's check at one time (``imaginary_residual``) would otherwise import
        numba (~0.35 s) inside ``solve_rotation``; the first evaluation pays that instead."""
        _, v, dv = self.flow(t, derivative, compiled=False)
        vb, vd = v[:, :9].reshape(-1, 3, 3), v[:, 9:]          # [n, s, k], [n, 1]
        phase = np.exp(self._turns(t) * TWO_PI_I)               # [n, s, k]: exp(i nu t)
        Psi = self.amp[None] * phase * vb / vd[:, None, :]      # Psi_k(P_s, t)
        B = self.B                                              # components -> principal frame
        Phi = B @ np.einsum("nsk,si->nki", Psi, self.X0inv)    # Phi X0 = B [Psi_c(P_s)]
        if not derivative:
            return Phi, None
        rate = 1j * self.nu[None] + dv[:, :9].reshape(-1, 3, 3) / vb - (dv[:, 9:] / vd)[:, None, :]
        return Phi, B @ np.einsum("nsk,si->nki", Psi * rate, self.X0inv)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_lin", self._linear_map())
        object.__setattr__(self, "_inu", 1j * self.nu)
        object.__setattr__(self, "_inu_flat", self._inu.astype(complex).ravel())
        object.__setattr__(self, "_amp_flat", self.amp.astype(complex).ravel())
        object.__setattr__(self, "_P_rows", np.asarray(self.P, float).tolist())
        pieces = _turn_rates(self.phase)                                          # c1, c2, c3, c
        coef = np.hstack([self.phase.n, self.phase.e]).astype(float)             # (9, rates)
        object.__setattr__(self, "_pieces", pieces)
        object.__setattr__(self, "_rates", list(zip(*(x.tolist() for x in pieces), strict=True)))
        object.__setattr__(self, "_coef", coef)
        rows, idx = np.unique(coef, axis=0, return_inverse=True)                 # entries alike by symmetry
        object.__setattr__(self, "_row_terms", [[(j, float(a)) for j, a in enumerate(row) if a != 0] for row in rows])
        object.__setattr__(self, "_row_of", idx.ravel())
        object.__setattr__(self, "_row_of_list", idx.ravel().tolist())
        for name, x in (("_inu_list", self._inu_flat), ("_amp_list", self._amp_flat)):
            object.__setattr__(self, name, x.ravel().tolist())

    def _linear_map(self) -> np.ndarray:
        """L (45, 36): the float view of ``[Psi | Psi rate]`` (n, 18 complex) -> the real parts of
        ``G = Q0p Phi^T Pf^T``, ``F = Pf Phi`` with its rows cycled by 2 and by 1, and ``Fd / 2``
        (``Fd = Pf Phidot``) with its rows cycled by 1 and by 2 (9 each, row-major): then
        ``vee(F Fd^T)`` is two products and a sum.  ``Pf = P`` for distinct ``J`` (the output frame
        folded in), the identity for a symmetric body."""
        Pf = self.P if self.axis is None else np.eye(3)
        T = np.einsum("jk,si->skji", self.B, self.X0inv).reshape(9, 3, 3)     # Phi[j, i] per Psi[s, k]
        TG = np.einsum("mji,ai,bj->mab", T, self.Q0p, Pf).reshape(9, 9)
        TF = np.einsum("mji,aj->mai", T, Pf)
        up, down = [1, 2, 0], [2, 0, 1]
        blocks = ((0, TG), (0, TF[:, down].reshape(9, 9)), (0, TF[:, up].reshape(9, 9)),
                  (18, 0.5 * TF[:, up].reshape(9, 9)), (18, 0.5 * TF[:, down].reshape(9, 9)))
        L = np.zeros((45, 36))
        for i, (col, M) in enumerate(blocks):
            blk = np.empty((18, 9))
            blk[0::2], blk[1::2] = M.real, -M.imag                  # Re(z M) = Re z Re M - Im z Im M
            L[9 * i: 9 * i + 9, col: col + 18] = blk.T
        return L

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(omega, Q)`` at the flat times ``t``: shapes (n, 3), (n, 3, 3) in the body frame given.

        ``Psi`` and ``Psidot = Psi rate`` (rate without dividing by ``vb``, which vanishes where a
        component does) go through one real matrix product to ``G = Q0 Phi^T P^T`` (polar factor:
        ``Q``) and ``F, Fd = P Phi, P Phidot`` (``omega = vee(F Fd^T)``); the 3x3 algebra after it
        runs on component rows (9, n).
        """
        _, v, dv = self.flow(t, True)
        kern = _STATE.get()
        if kern is None:
            return self._state(t, v, dv)
        n = t.shape[0]
        w, Q, bad = np.empty((n, 3)), np.empty((n, 3, 3)), np.zeros(n, bool)
        kern(t, v, dv, self._inu_flat, self._amp_flat, *self._pieces, self._coef, self._lin,
             self.P, -1 if self.axis is None else self.axis, float(self.spin), NEWTON_SCHULZ_MAX,
             w, Q, bad)
        if bad.any():                                                # the polar factor needs the SVD
            w[bad], Q[bad] = self._state(t[bad], v[bad], dv[bad])
        return w, Q

    def _state(self, t: np.ndarray, v: np.ndarray, dv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """numpy path of :meth:`evaluate` from the flow's values (its compiled twin: ``_state_kernel``)."""
        n = t.shape[0]
        if n == 1:
            one = self._state_one(t, v, dv)
            if one is not None:
                return one
        vb, vd = v[:, :9].reshape(n, 3, 3), v[:, 9:]              # [n, s, k], [n, 1]
        ivd = 1.0 / vd
        # exp(i nu t) on the distinct rows of turns only (4-9 of the 9 exponents), then spread (for one
        # time too: the numpy rows are the Python floats' turns bit for bit, tests/test_one_call.py)
        q = np.exp(self._turn_rows(t).T * TWO_PI_I).take(self._row_of, axis=1).reshape(n, 3, 3)
        q *= self.amp
        q *= ivd[:, None, :]
        Z = np.empty((n, 2, 3, 3), complex)
        np.multiply(q, vb, out=Z[:, 0])
        rate = self._inu - (dv[:, 9:] * ivd)[:, None, :]
        rate *= vb
        rate += dv[:, :9].reshape(n, 3, 3)
        np.multiply(q, rate, out=Z[:, 1])
        Y = self._lin @ Z.reshape(n, 18).view(float).T             # (45, n)
        Q = polar_near_orthogonal(Y[:9].reshape(3, 3, n))
        w = np.add.reduce((Y[27:36] * Y[9:18] - Y[36:45] * Y[18:27]).reshape(3, 3, n), axis=1)   # vee(F Fd^T)
        if self.axis is not None:
            Q, w = self._from_turning_frame(t, Q, w)
        return np.ascontiguousarray(w.T), np.ascontiguousarray(Q.transpose(2, 0, 1))

    def _turns(self, t: np.ndarray) -> np.ndarray:
        """``nu t / (2 pi)`` modulo 1 (n, 3, 3), exact before its last roundings for ``|t| < 2^31``.

        The exponents are exact integer combinations of a few rates (:class:`.exponents.PhaseRates`);
        each rate's turns are reduced modulo 1 exactly (:mod:`thetasol.core.turns`, the pieces from
        :func:`_turn_rates`), and the turns of ``nu_sk`` are the integer combinations of these
        (coefficients in order, the same in every path).  The plain product ``nu t`` would carry an error
        of ``|nu t| 1.1e-16`` into the phase (1e-10 at ``t = 1e6``), and the rounded floats ``nu_sk``
        keep their exact relations (the form ``F_s - G_k``, the lattice rate ``U``) only to ~1e-16:
        either way the nine exponents would no longer combine into an orthogonal ``Phi(0, t)`` and the
        first integrals drift with ``t`` (benchmarks/bench_theta_rotation.py, drift far;
        tests/test_one_call.py).  One time: on Python floats, cheaper than numpy."""
        if t.shape[0] == 1:
            return np.array(self._turns_one(t.item())).reshape(1, 3, 3)
        return self._turn_rows(t).T.take(self._row_of, axis=1).reshape(-1, 3, 3)

    def _turn_rows(self, t: np.ndarray) -> np.ndarray:
        """The distinct rows of :meth:`_turns` (rows, n): ``_turns`` is ``rows.T`` spread by ``_row_of``."""
        x = rate_turns(t, *self._pieces)                                 # (rates, n): rows contiguous
        rows = np.zeros((len(self._row_terms), t.shape[0]))
        for acc, terms in zip(rows, self._row_terms, strict=True):
            for j, a in terms:
                acc += x[j] * a
        return rows

    def _turns_one(self, x: float) -> list[float]:
        """:meth:`_turns` of one time on Python floats, the same operations: the nine turns in the order
        ``3 s + k``."""
        p = rate_turns_one(x, self._rates)
        rows = []
        for terms in self._row_terms:
            acc = 0.0
            for j, a in terms:
                acc += p[j] * a
            rows.append(acc)
        return [rows[i] for i in self._row_of_list]

    def _state_one(self, t: np.ndarray, v: np.ndarray, dv: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """:meth:`_state` for one time on Python complex numbers and floats, around the one matrix product
        (numpy's calls cost more than their arithmetic on nine elements: one far time 8-12 us cheaper,
        tests/test_one_call.py); the same formulas, to rounding (complex products round differently
        from numpy's).  None when the polar factor needs the SVD: the numpy rows then apply."""
        x = t.item()
        vl, dl, inu, amp = v[0].tolist(), dv[0].tolist(), self._inu_list, self._amp_list
        Z = [0j] * 18
        ivd = 1.0 / vl[9]
        rd = dl[9] * ivd
        for m, turn in enumerate(self._turns_one(x)):
            q = cmath.exp(complex(0.0, TWO_PI * turn)) * amp[m] * ivd
            Z[m] = q * vl[m]
            Z[9 + m] = q * ((inu[m] - rd) * vl[m] + dl[m])
        y = (self._lin @ np.array(Z).view(float)).tolist()
        Q = polar_near_orthogonal_one(y[:9])
        if Q is None:
            return None
        w = [(y[27 + k] * y[9 + k] - y[36 + k] * y[18 + k]) + (y[28 + k] * y[10 + k] - y[37 + k] * y[19 + k])
             + (y[29 + k] * y[11 + k] - y[38 + k] * y[20 + k]) for k in (0, 3, 6)]
        if self.axis is not None:
            Q, w = self._from_turning_frame_one(x, Q, w)
        return np.array([w]), np.array([[Q[0:3], Q[3:6], Q[6:9]]])

    def _from_turning_frame_one(self, t: float, Q: list[float], w: list[float]) -> tuple[list, list]:
        """:meth:`_from_turning_frame` at one time ``t``, on ``Q`` (9 floats, row-major) and ``w`` (3 floats)."""
        ax, spin, P = self.axis, self.spin, self._P_rows
        i, j = (ax + 1) % 3, (ax + 2) % 3
        x = -spin * t
        c, s = math.cos(x), math.sin(x)
        Qr = list(Q)
        wr = list(w)
        for r in (0, 3, 6):
            Qr[r + i], Qr[r + j] = c * Q[r + i] - s * Q[r + j], s * Q[r + i] + c * Q[r + j]
        wr[ax] = w[ax] + spin
        wr[i], wr[j] = c * w[i] - s * w[j], s * w[i] + c * w[j]
        Qo = [Qr[r] * p[0] + Qr[r + 1] * p[1] + Qr[r + 2] * p[2] for r in (0, 3, 6) for p in P]
        wo = [p[0] * wr[0] + p[1] * wr[1] + p[2] * wr[2] for p in P]
        return Qo, wo

    def _from_turning_frame(self, t: np.ndarray, Q: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Symmetric body: ``Q = Q~ R^T P^T``, ``omega = P (R omega~ + spin e)``, ``R = exp(-spin t hat(e))``
        (component rows (3, 3, n), (3, n))."""
        ax, spin, P = self.axis, self.spin, self.P
        i, j = (ax + 1) % 3, (ax + 2) % 3
        c, s = np.cos(-spin * t), np.sin(-spin * t)
        Qr = np.empty_like(Q)
        Qr[:, ax] = Q[:, ax]
        Qr[:, i] = c * Q[:, i] - s * Q[:, j]
        Qr[:, j] = s * Q[:, i] + c * Q[:, j]
        wr = np.empty_like(w)
        wr[ax] = w[ax] + spin
        wr[i] = c * w[i] - s * w[j]
        wr[j] = s * w[i] + c * w[j]
        # Q~ R^T P^T row by row, and P omega: matrix products on the component rows (5 ns per time
        # against 43 for the broadcast sums, on blocks of 1024 times)
        return np.matmul(P, Qr), P @ wr

    def imaginary_residual(self, t: np.ndarray) -> np.ndarray:
        """max |Im Phi(0, t)| at the flat times ``t`` (it must vanish: the error of the evaluation)."""
        Phi, _ = self.phi0(t, derivative=False)
        return np.abs(Phi.imag).max(axis=(-1, -2))


#: ``2 pi`` and ``2 pi i``: ``exp(2 pi i x)`` of the turns ``x``.
TWO_PI = 2.0 * math.pi
TWO_PI_I = 2j * math.pi


def _turn_rates(phase: PhaseRates) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The turn rates ``U / 2`` and ``gaps / 2 pi`` of ``phase`` (r + g,) as ``c1 + c2 + c3`` to the
    rounding of ``c3``, ~2^-97 relative (tests/test_one_call.py), ``c1`` and ``c2`` with 22 significant
    bits each (:func:`thetasol.core.turns.split_rate_exact`), and ``c`` their float64 values.  Then
    ``t1 c1`` and ``t1 c2`` are exact for integers ``|t1| < 2^31`` and the rounding of ``t1 c3`` is
    ~``|t c| 2^-97``; two pieces would leave ``|t c| 2^-75``, a drift of the first integrals of 5e-13 at
    ``t = 1e9`` on the fast-spin bodies."""
    with mpmath.workdps(50):
        rates = ([mpmath.mpf(float(u)) / 2 for u in phase.lattice]
                 + [mpmath.mpf(float(g)) / (2 * mpmath.pi) for g in phase.gaps])
        out = np.array([(*split_rate_exact(x), float(x)) for x in rates]).reshape(-1, 4).T
    return out[0], out[1], out[2], out[3]


def _state_kernel(t, v, dv, inu, amp, rc1, rc2, rc3, rc, coef, L, P, axis, spin, tol, w_out, Q_out,
                  bad):  # pragma: no cover
    """Compiled :meth:`FlowEvaluator._state` (numba), time by time, with the same formulas in the same
    order; ``bad[a]`` marks a time whose polar factor needs the SVD (``|G^T G - 1| > tol``)."""
    Zf, Y, p = np.empty(36), np.empty(45), np.empty(rc1.shape[0])
    G, H = np.empty((3, 3)), np.empty((3, 3))
    Q, w = np.empty((3, 3)), np.empty(3)
    for a in range(t.shape[0]):
        t1 = np.rint(t[a])
        if not abs(t1) < TURNS_EXACT:
            t1 = 0.0
        t2 = t[a] - t1
        for j in range(p.shape[0]):                              # the turns of core.turns.rate_turns
            x = t1 * rc1[j]
            x -= np.rint(x)
            y = t1 * rc2[j]
            y -= np.rint(y)
            x += y
            x += t1 * rc3[j]
            x += t2 * rc[j]
            p[j] = x
        ivd = 1.0 / v[a, 9]
        rd = dv[a, 9] * ivd
        for k in range(3):
            for s in range(3):
                m = 3 * s + k
                x = 0.0
                for j in range(p.shape[0]):
                    x += p[j] * coef[m, j]
                q = np.exp(x * TWO_PI_I) * amp[m] * ivd
                z = q * v[a, m]
                zd = q * ((inu[m] - rd) * v[a, m] + dv[a, m])
                Zf[2 * m], Zf[2 * m + 1], Zf[18 + 2 * m], Zf[19 + 2 * m] = z.real, z.imag, zd.real, zd.imag
        for i in range(45):
            acc = 0.0
            for j in range(36):
                acc += L[i, j] * Zf[j]
            Y[i] = acc
        err = 0.0
        for i in range(3):
            for j in range(3):
                G[i, j] = Y[3 * i + j]
        for i in range(3):
            for j in range(3):
                x = G[0, i] * G[0, j] + G[1, i] * G[1, j] + G[2, i] * G[2, j]
                err = max(err, abs(x - (1.0 if i == j else 0.0)))
                H[i, j] = (1.5 if i == j else 0.0) - 0.5 * x
        bad[a] = err > tol
        for i in range(3):
            for j in range(3):
                Q[i, j] = G[i, 0] * H[0, j] + G[i, 1] * H[1, j] + G[i, 2] * H[2, j]
            w[i] = 0.0
            for k in range(3):
                w[i] += Y[27 + 3 * i + k] * Y[9 + 3 * i + k] - Y[36 + 3 * i + k] * Y[18 + 3 * i + k]
        if axis < 0:
            Q_out[a], w_out[a] = Q, w
            continue
        # the turning frame of a symmetric body, as in FlowEvaluator._from_turning_frame
        i, j = (axis + 1) % 3, (axis + 2) % 3
        c, s = np.cos(-spin * t[a]), np.sin(-spin * t[a])
        G[:, :] = Q                                               # the polar factor, before turning
        for r in range(3):
            Q[r, i], Q[r, j] = c * G[r, i] - s * G[r, j], s * G[r, i] + c * G[r, j]
        wa, wi, wj = w[axis] + spin, c * w[i] - s * w[j], s * w[i] + c * w[j]
        w[axis], w[i], w[j] = wa, wi, wj
        for r in range(3):
            for b in range(3):
                Q_out[a, r, b] = Q[r, 0] * P[b, 0] + Q[r, 1] * P[b, 1] + Q[r, 2] * P[b, 2]
            w_out[a, r] = P[r, 0] * w[0] + P[r, 1] * w[1] + P[r, 2] * w[2]


_STATE = Kernel(_state_kernel)


def corrected_shifts(sd: SpectralData, dv: EigenvectorDivisors, ts: ThetaShifts,
                     ex: Exponents) -> tuple[np.ndarray, float]:
    """The shifts b_sk moved onto the initial data (module docstring): (b (9, g), size of the move)."""
    th, U, B, g = sd.theta, sd.U, sd.B, sd.genus
    X0, rho = ex.means.X0, ex.means.rho
    ed_, vd_, dlog_d = ex.theta_d
    b = (dv.AP0[:, None, :] - ts.e[None, :, :]).reshape(9, g)
    eb_, vb_, gb_, hb_ = th.jet(b, order=2, separated=True)
    scale_b = np.exp(eb_)
    rho_k = (rho / (np.exp(ed_) * vd_)[None, :]).ravel()               # rho_k(P_s), [s*3+k]
    h = X0.T.ravel()                                                     # psi_k(P_s)
    hdot = (-(B.conj().T @ sd.frame.W0 @ B @ X0)).T.ravel()              # d/dt Psi_k(P_s) at t = 0
    dlogd = np.tile(dlog_d, 3)
    nu_rows = 1j * ex.nu.ravel()
    theta_b = scale_b * vb_
    val_target = h / rho_k
    der_target = hdot / rho_k - nu_rows * val_target + val_target * dlogd
    A = np.stack([scale_b[:, None] * gb_, scale_b[:, None] * (hb_ @ U)], axis=1)   # (9, 2, g)
    rhs = np.stack([val_target - theta_b, der_target - scale_b * (gb_ @ U)], axis=1)
    AAH = np.einsum("nig,njg->nij", A, A.conj())
    db = np.einsum("nig,ni->ng", A.conj(), np.linalg.solve(AAH, rhs[..., None])[..., 0])
    shift_correction = float(np.abs(db).max())
    if shift_correction > 1e-6:
        raise RuntimeError(f"theta quotients inconsistent with the initial eigenvectors (shift correction "
                           f"{shift_correction:.2g}): inaccurate Abel images")
    return b + db, shift_correction


def flow_evaluator(sd: SpectralData, dv: EigenvectorDivisors, ts: ThetaShifts,
                   ex: Exponents) -> tuple[FlowEvaluator, float]:
    """Stage 5: the evaluator, and the size of the shift correction (module docstring)."""
    b, shift_correction = corrected_shifts(sd, dv, ts, ex)
    flow = FlowTheta(sd.tau, sd.U[:sd.rdim], np.concatenate([b, ts.d[None, :]]))
    eb = flow.e[:9].reshape(3, 3)
    amp = ex.means.rho * np.exp(eb - flow.e[9:][None, :])             # rho theta(d) exp(e_b - e_d)
    fr = sd.frame
    ev = FlowEvaluator(flow=flow, nu=ex.nu, phase=ex.phase, amp=amp, X0inv=np.linalg.inv(sd.B @ ex.means.X0), B=sd.B,
                       Q0p=fr.Q0p, P=fr.P, spin=fr.spin, axis=fr.axis)
    return ev, shift_correction
