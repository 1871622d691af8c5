"""Stage 5: the evaluator of Phi(0, t) = Q(t)^T Q0 along the real flow, and from it omega and Q.

At the three places ``P_s`` over ``E = 0`` the Baker-Akhiezer function gives the fundamental matrix
of ``Phidot = -A(0, t) Phi`` (4.11): ``Phi(0, t) X0 = B [Psi_k(P_s, t)]`` with ``X0`` the initial
eigenvectors, and ``Phi(0, t) = Q(t)^T Q0``.  Then ``Q = Q0 Phi^T`` and ``omega = vee(-Phidot Phi^T)``;
for a symmetric body ``Q = Q~ R(t)^T``, ``omega = R omega~ + spin e`` back from the turning frame.

The theta functions along the flow, ``theta(b_sk + t U)`` and ``theta(d_k + t U)``, are Fourier series
in the ``rdim`` real phases of ``U`` (:class:`thetasol.theta.flow.FlowTheta`): per time only the
phases and one matrix product remain, and a far time costs what ``t = 1`` costs.

The shifts ``b_sk = A(P_s) - e_k`` are sums of Abel images, known to ~1e-14; where ``psi_k(P_s)`` is
small or zero that error shows directly in ``Psi``.  Each ``b_sk`` is moved by the least amount that
makes the quotient reproduce ``psi_k(P_s)`` and its derivative ``-(omega0 x psi)_k`` at ``t = 0``
exactly (two linear conditions on the gradient and Hessian of theta): the shift lands on the theta
divisor where the component vanishes, and ``t = 0`` returns the initial data to round-off.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from thetasol.core.so3 import polar_orthonormalize, rotation_about, vee
from thetasol.solutions.theta_rotation.divisors import EigenvectorDivisors
from thetasol.solutions.theta_rotation.exponents import Exponents
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
        Theta at the 9 shifts ``b_sk`` and the 3 shifts ``d_k`` along ``t U``.
    nu : ndarray, shape (3, 3)
        Exponents: ``Psi_k(P_s, t)`` carries ``exp(i nu_sk t)``.
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
    amp: np.ndarray
    X0inv: np.ndarray
    B: np.ndarray
    Q0p: np.ndarray
    P: np.ndarray
    spin: float
    axis: int | None

    def phi0(self, t: np.ndarray, derivative: bool) -> tuple[np.ndarray, np.ndarray | None]:
        """Phi(0, t) (n, 3, 3) = Q'(t)^T Q'0 in the principal frame and, if asked, its derivative."""
        _, v, dv = self.flow(t, derivative)
        vb, vd = v[:, :9].reshape(-1, 3, 3), v[:, 9:]          # [n, s, k], [n, k]
        phase = np.exp(1j * np.multiply.outer(t, self.nu))      # [n, s, k]
        Psi = self.amp[None] * phase * vb / vd[:, None, :]      # Psi_k(P_s, t)
        B = self.B                                              # components -> principal frame
        Phi = B @ np.einsum("nsk,si->nki", Psi, self.X0inv)    # Phi X0 = B [Psi_c(P_s)]
        if not derivative:
            return Phi, None
        rate = 1j * self.nu[None] + dv[:, :9].reshape(-1, 3, 3) / vb - (dv[:, 9:] / vd)[:, None, :]
        return Phi, B @ np.einsum("nsk,si->nki", Psi * rate, self.X0inv)

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(omega, Q)`` at the flat times ``t``: shapes (n, 3), (n, 3, 3) in the body frame given."""
        Phi, Phidot = self.phi0(t, derivative=True)
        Phi_r = Phi.real
        Qp = polar_orthonormalize(self.Q0p @ np.swapaxes(Phi_r, -1, -2))
        wp = vee(-Phidot.real @ np.swapaxes(Phi_r, -1, -2))
        if self.axis is not None:
            # back from the frame turning at -spin about the symmetry axis: Q = Q~ R^T, omega = R omega~ + spin e
            ax, spin = self.axis, self.spin
            R = rotation_about(ax, -spin * t)                  # R(t) = exp(-spin t hat(e))
            Qp = Qp @ np.swapaxes(R, -1, -2)
            wp = np.einsum("nij,nj->ni", R, wp)
            wp[..., ax] += spin
        P = self.P
        return wp @ P.T, Qp @ P.T

    def imaginary_residual(self, t: np.ndarray) -> np.ndarray:
        """max |Im Phi(0, t)| at the flat times ``t`` (it must vanish: the error of the evaluation)."""
        Phi, _ = self.phi0(t, derivative=False)
        return np.abs(Phi.imag).max(axis=(-1, -2))


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
    flow = FlowTheta(sd.tau, sd.U[:sd.rdim], np.concatenate([b, ts.d]))
    eb = flow.e[:9].reshape(3, 3)
    amp = ex.means.rho * np.exp(eb - flow.e[9:][None, :])             # rho theta(d) exp(e_b - e_d)
    fr = sd.frame
    ev = FlowEvaluator(flow=flow, nu=ex.nu, amp=amp, X0inv=np.linalg.inv(sd.B @ ex.means.X0), B=sd.B,
                       Q0p=fr.Q0p, P=fr.P, spin=fr.spin, axis=fr.axis)
    return ev, shift_correction
