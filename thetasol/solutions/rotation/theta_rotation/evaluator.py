"""Stage 5: the evaluator of Phi(0, t) = Q(t)^T Q0 along the real flow, and from it omega and Q.

At the three places ``P_s`` over ``E = 0`` the Baker-Akhiezer function gives the fundamental matrix
of ``Phidot = -A(0, t) Phi`` (4.11): ``Phi(0, t) X0 = B [Psi_k(P_s, t)]`` with ``X0`` the initial
eigenvectors, and ``Phi(0, t) = Q(t)^T Q0``.  Then ``Q = Q0 Phi^T`` and ``omega = vee(-Phidot Phi^T)``;
for a symmetric body ``Q = Q~ R(t)^T``, ``omega = R omega~ + spin e`` back from the turning frame.

The theta functions along the flow, ``theta(b_sk + t U)`` and ``theta(d_k + t U)``, are Fourier series
in the ``rdim`` real phases of ``U`` (:class:`thetasol.theta.flow.FlowTheta`): per time only the
phases and one real matrix product remain, and a far time costs what ``t = 1`` costs.  The exponents
``exp(i nu_sk t)`` take ``nu t / 2 pi`` modulo 1 exactly for ``|t| < 2^31`` (:class:`PhaseTurns`), as
the integer combinations of a few rates' turns that the exponents are exactly
(:class:`~.exponents.PhaseRates`): rounded products ``nu t``, and the rounded floats ``nu_sk`` (whose
exact relations hold only to about one ulp), would make the first integrals drift with ``t``; with the
combinations, and the flow's phases ``t u`` reduced as exactly
(:func:`thetasol.core.turns.rate_turns`), the drift far out stays at the level of ``t = 0``
(tests/test_one_call.py).  After the flow ``Psi`` and its derivative go through one more real product
(9x9 complex maps folded with ``B``, ``X0^-1``, ``Q0`` and the principal frame, :func:`linear_map`) and
the 3x3 algebra follows: the polar factor by one Newton-Schulz step (as
:func:`thetasol.core.so3.polar_near_orthogonal`, closer to the long-double polar factor than the SVD's,
tests/test_theta_evaluation.py).  The per-time evaluation is compiled
(:class:`thetasol.core.kernels.RotationKernel`, src/kernels.cpp): one call for many times, and one time
is a batch of one.  Working memory is a few KB per call, so the default chunk of
:class:`thetasol.protocol.Solution` applies.

The shifts ``b_sk = A(P_s) - e_k`` are sums of Abel images, known to about 1e-14; where ``psi_k(P_s)``
is small or zero that error shows directly in ``Psi``.  Each ``b_sk`` is moved by the least amount that
makes the quotient reproduce ``psi_k(P_s)`` and its derivative ``-(omega0 x psi)_k`` at ``t = 0``
exactly (two linear conditions on the gradient and Hessian of theta): the shift lands on the theta
divisor where the component vanishes, and ``t = 0`` returns the initial data to round-off.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import mpmath
import numpy as np

from thetasol.core.kernels import RotationKernel
from thetasol.core.so3 import NEWTON_SCHULZ_MAX, polar_orthonormalize
from thetasol.core.turns import rate_turns, split_rate_exact
from thetasol.solutions.rotation.theta_rotation.divisors import EigenvectorDivisors
from thetasol.solutions.rotation.theta_rotation.exponents import Exponents, PhaseRates
from thetasol.solutions.rotation.theta_rotation.riemann import ThetaShifts
from thetasol.solutions.rotation.theta_rotation.spectral_data import SpectralData
from thetasol.theta.flow import FlowTheta

__all__ = ["FlowEvaluator", "PhaseTurns", "build_evaluator", "flow_evaluator", "linear_map", "phase_turns",
           "rotation_kernel"]

#: ``2 pi i``: ``exp(2 pi i x)`` of the turns ``x``.
TWO_PI_I = 2j * math.pi


@dataclass(frozen=True, eq=False)
class PhaseTurns:
    """The turns ``nu_sk t / (2 pi)`` modulo 1 of the nine exponents, from their exact rates.

    The exponents are exact integer combinations of a few rates (:class:`.exponents.PhaseRates`); each
    rate's turns are reduced modulo 1 exactly (:mod:`thetasol.core.turns`), and the turns of ``nu_sk``
    are the integer combinations of these, formed once per distinct row of coefficients (exponents
    alike by symmetry share one).  Built by :func:`phase_turns`.

    Attributes
    ----------
    phase : PhaseRates
        The rates and their integer coefficients.
    pieces : tuple of 4 ndarrays, each (rates,)
        ``c1``, ``c2``, ``c3``, ``c`` of every rate (:func:`thetasol.core.turns.rate_turns`).
    coef : ndarray, shape (rows, rates)
        The distinct rows of the integer coefficients (as floats), in the order ``row_of`` indexes.
    row_of : ndarray of int, shape (9,)
        The distinct row of each exponent ``m = 3 s + k``.
    """

    phase: PhaseRates
    pieces: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
    coef: np.ndarray
    row_of: np.ndarray

    def rows(self, t: np.ndarray) -> np.ndarray:
        """The distinct rows of the turns (rows, n) at the flat times ``t``, not reduced: integer
        combinations of :func:`thetasol.core.turns.rate_turns` (coefficients in rate order)."""
        x = rate_turns(t, *self.pieces)                                  # (rates, n): rows contiguous
        rows = np.zeros((self.coef.shape[0], t.shape[0]))
        for acc, row in zip(rows, self.coef, strict=True):
            for j in np.flatnonzero(row):                                # zero coefficients skipped
                acc += x[j] * row[j]
        return rows

    def __call__(self, t: np.ndarray) -> np.ndarray:
        """The turns (n, 3, 3) at the flat times ``t``, ``[n, s, k]``, up to integers."""
        return self.rows(t).T.take(self.row_of, axis=1).reshape(-1, 3, 3)


def phase_turns(phase: PhaseRates) -> PhaseTurns:
    """The :class:`PhaseTurns` of ``phase``: the rates ``U / 2`` and ``gaps / 2 pi`` split into exact
    pieces (:func:`turn_rates`) and the distinct rows of the coefficients ``[n | e]``."""
    coef = np.hstack([phase.n, phase.e]).astype(float)                  # (9, rates)
    rows, idx = np.unique(coef, axis=0, return_inverse=True)
    return PhaseTurns(phase=phase, pieces=turn_rates(phase), coef=np.ascontiguousarray(rows), row_of=idx.ravel())


def turn_rates(phase: PhaseRates) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The turn rates ``U / 2`` and ``gaps / 2 pi`` of ``phase`` (r + g,) as ``c1 + c2 + c3`` to the
    rounding of ``c3`` (about 2^-97 relative), ``c1`` and ``c2`` with 22 significant bits each
    (:func:`thetasol.core.turns.split_rate_exact`), and ``c`` their float64 values.  Then ``t1 c1`` and
    ``t1 c2`` are exact for integers ``|t1| < 2^31`` and the rounding of ``t1 c3`` is about
    ``|t c| 2^-97``: two pieces would leave ``|t c| 2^-75``, which the first integrals of the fast-spin
    bodies show as a drift far out."""
    with mpmath.workdps(50):
        rates = ([mpmath.mpf(float(u)) / 2 for u in phase.lattice]
                 + [mpmath.mpf(float(g)) / (2 * mpmath.pi) for g in phase.gaps])
        out = np.array([(*split_rate_exact(x), float(x)) for x in rates]).reshape(-1, 4).T
    return out[0], out[1], out[2], out[3]


def linear_map(B: np.ndarray, X0inv: np.ndarray, Q0p: np.ndarray, P: np.ndarray, axis: int | None) -> np.ndarray:
    """L (45, 36): the float view of ``[Psi | Psi rate]`` (n, 18 complex) -> the real parts of
    ``G = Q0p Phi^T Pf^T``, ``F = Pf Phi`` with its rows cycled by 2 and by 1, and ``Fd / 2``
    (``Fd = Pf Phidot``) with its rows cycled by 1 and by 2 (9 each, row-major): then
    ``vee(F Fd^T)`` is two products and a sum.  ``Pf = P`` for distinct ``J`` (the output frame
    folded in), the identity for a symmetric body (``axis`` not None)."""
    Pf = P if axis is None else np.eye(3)
    T = np.einsum("jk,si->skji", B, X0inv).reshape(9, 3, 3)              # Phi[j, i] per Psi[s, k]
    TG = np.einsum("mji,ai,bj->mab", T, Q0p, Pf).reshape(9, 9)
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


@dataclass(frozen=True, eq=False)
class FlowEvaluator:
    """``Phi(0, t)``, ``omega(t)`` and ``Q(t)`` from theta along the flow (stage 5); built by
    :func:`build_evaluator`, which derives ``turns`` and ``lin`` from the others.

    Attributes
    ----------
    flow : FlowTheta
        Theta at the 9 shifts ``b_sk`` and at ``d`` along ``t U`` (the three ``d_k`` are equal,
        :class:`~.riemann.ThetaShifts`: one denominator serves the three components).
    nu : ndarray, shape (3, 3)
        Exponents: ``Psi_k(P_s, t)`` carries ``exp(i nu_sk t)``.
    turns : PhaseTurns
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
    lin : ndarray, shape (45, 36)
        :func:`linear_map` of ``B``, ``X0inv``, ``Q0p``, ``P``, ``axis``.
    kernel : RotationKernel
        The compiled evaluation of :meth:`evaluate`, built from the arrays above.
    """

    flow: FlowTheta
    nu: np.ndarray
    turns: PhaseTurns
    amp: np.ndarray
    X0inv: np.ndarray
    B: np.ndarray
    Q0p: np.ndarray
    P: np.ndarray
    spin: float
    axis: int | None
    lin: np.ndarray
    kernel: RotationKernel

    @property
    def phase(self) -> PhaseRates:
        """The exponents' rates and integer coefficients (:class:`~.exponents.PhaseRates`)."""
        return self.turns.phase

    def phi0(self, t: np.ndarray, derivative: bool) -> tuple[np.ndarray, np.ndarray | None]:
        """Phi(0, t) (n, 3, 3) = Q'(t)^T Q'0 in the principal frame and, if asked, its derivative: the
        definition, used by the set-up's check (``imaginary_residual``) and by the tests of
        :meth:`evaluate`."""
        _, v, dv = self.flow(t, derivative)
        vb, vd = v[:, :9].reshape(-1, 3, 3), v[:, 9:]          # [n, s, k], [n, 1]
        phase = np.exp(self.turns(t) * TWO_PI_I)                # [n, s, k]: exp(i nu t)
        Psi = self.amp[None] * phase * vb / vd[:, None, :]      # Psi_k(P_s, t)
        B = self.B                                              # components -> principal frame
        Phi = B @ np.einsum("nsk,si->nki", Psi, self.X0inv)    # Phi X0 = B [Psi_c(P_s)]
        if not derivative:
            return Phi, None
        rate = 1j * self.nu[None] + dv[:, :9].reshape(-1, 3, 3) / vb - (dv[:, 9:] / vd)[:, None, :]
        return Phi, B @ np.einsum("nsk,si->nki", Psi * rate, self.X0inv)

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(omega, Q)`` at the flat times ``t``: shapes (n, 3), (n, 3, 3) in the body frame given.

        The compiled kernel (:class:`thetasol.core.kernels.RotationKernel`): ``Psi`` and
        ``Psidot = Psi rate`` (rate without dividing by ``vb``, which vanishes where a component does) go
        through one real matrix product to ``G = Q0 Phi^T P^T`` (polar factor: ``Q``) and
        ``F, Fd = P Phi, P Phidot`` (``omega = vee(F Fd^T)``).  Times where ``G`` is too far from
        orthogonal for one Newton-Schulz step (:data:`thetasol.core.so3.NEWTON_SCHULZ_MAX`) come back
        unprojected and take the SVD here; the polar factor commutes with the orthogonal output frame.
        """
        w, Q, projected = self.kernel(np.ascontiguousarray(t, dtype=float))
        if not projected.all():
            Q[~projected] = polar_orthonormalize(Q[~projected])
        return w, Q

    def imaginary_residual(self, t: np.ndarray) -> np.ndarray:
        """max |Im Phi(0, t)| at the flat times ``t`` (it must vanish: the error of the evaluation)."""
        Phi, _ = self.phi0(t, derivative=False)
        return np.abs(Phi.imag).max(axis=(-1, -2))


def build_evaluator(flow: FlowTheta, nu: np.ndarray, phase: PhaseRates, amp: np.ndarray, X0inv: np.ndarray,
                    B: np.ndarray, Q0p: np.ndarray, P: np.ndarray, spin: float, axis: int | None) -> FlowEvaluator:
    """The :class:`FlowEvaluator` of these data, with its turns (:func:`phase_turns`), its folded
    linear map (:func:`linear_map`) and its compiled kernel (:func:`rotation_kernel`)."""
    turns, lin = phase_turns(phase), linear_map(B, X0inv, Q0p, P, axis)
    kernel = rotation_kernel(flow, turns, amp, nu, lin, P, spin, axis)
    return FlowEvaluator(flow=flow, nu=nu, turns=turns, amp=amp, X0inv=X0inv, B=B, Q0p=Q0p, P=P,
                         spin=spin, axis=axis, lin=lin, kernel=kernel)


def rotation_kernel(flow: FlowTheta, turns: PhaseTurns, amp: np.ndarray, nu: np.ndarray, lin: np.ndarray,
                    P: np.ndarray, spin: float, axis: int | None) -> RotationKernel:
    """The compiled evaluation of these frozen arrays: the turns' pieces and their integer rows (dense,
    zeros skipped by the kernel), the amplitudes as floats (9, 2), ``axis`` -1 for distinct ``J``."""
    f64 = np.ascontiguousarray
    return RotationKernel(flow.kernel, f64(np.stack(turns.pieces)), turns.coef, f64(turns.row_of, dtype=np.int64),
                          f64(np.asarray(amp, complex).reshape(9)).view(float).reshape(9, 2), f64(nu, dtype=float),
                          f64(lin), f64(P, dtype=float), float(spin), -1 if axis is None else int(axis),
                          NEWTON_SCHULZ_MAX)


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
    ev = build_evaluator(flow=flow, nu=ex.nu, phase=ex.phase, amp=amp, X0inv=np.linalg.inv(sd.B @ ex.means.X0),
                         B=sd.B, Q0p=fr.Q0p, P=fr.P, spin=fr.spin, axis=fr.axis)
    return ev, shift_correction
