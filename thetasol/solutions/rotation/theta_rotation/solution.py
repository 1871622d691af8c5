"""The theta-function rotation as a :class:`~thetasol.RotationSolution`, and its set-up in stages.

:func:`solve_theta_rotation` (called by :func:`thetasol.solve_rotation`) runs the stages in order,
each a function returning a frozen dataclass:

0. :func:`~.frame.body_frame`: principal (and turning) frame, refusals of data out of reach;
1. :func:`~.spectral_data.spectral_data`: the curve (4.12), the basis adapted to the real torus, ``U``;
2. :func:`~.divisors.eigenvector_divisors`: the eigenvector's divisors and their Abel images;
3. :func:`~.riemann.theta_shifts`: the Riemann constant and the shifts of the theta quotients;
4. :func:`~.exponents.exponents`: the constants at ``t = 0`` (Cauchy means) and the exact exponents;
5. :func:`~.evaluator.flow_evaluator`: theta along the flow as a Fourier series, and the result.
"""
from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core.attitude import principal_frame
from thetasol.mechanics.equations import invariants_from_moments as first_integrals
from thetasol.protocol import ROUNDOFF, ClosedFormUnavailable, RotationSolution
from thetasol.solutions._symmetry import symmetry_axis
from thetasol.solutions.rotation.theta_rotation.divisors import eigenvector_divisors
from thetasol.solutions.rotation.theta_rotation.evaluator import FlowEvaluator, flow_evaluator
from thetasol.solutions.rotation.theta_rotation.exponents import exponents
from thetasol.solutions.rotation.theta_rotation.frame import body_frame
from thetasol.solutions.rotation.theta_rotation.riemann import theta_shifts
from thetasol.solutions.rotation.theta_rotation.spectral_data import spectral_data

if TYPE_CHECKING:
    from thetasol.curves.plane_curve import Place

__all__ = ["ThetaRotation", "solve_theta_rotation"]

#: |Im Phi(0, t)| at t = 1000 above which the set-up warns (accurate solutions stay well below it).
RESIDUAL_WARN = 1e-8


@dataclass(frozen=True, eq=False)
class ThetaRotation(RotationSolution):
    """Exact rotation in a quadratic potential in Riemann theta functions (Section 4 II).

    Built by :func:`thetasol.solve_rotation`; evaluates at any times in any order.  Besides the
    protocol of :class:`thetasol.RotationSolution` (``omega``, ``Q``, ``M``, ``u``, ``method``,
    ``invariants``, ``diagnostics``) it exposes the spectral data of the initial state.

    Attributes
    ----------
    curve : thetasol.curves.spectral.SpectralCurve
        The spectral curve (4.12) of the initial data (principal frame, ascending ``J``).
    basis : ndarray of int, shape (2g, 2g)
        The symplectic homology basis used, adapted to the real Liouville torus: its columns are
        the new cycles ``[a' | b']`` in the coordinates of ``curve``'s own basis.
    riemann_matrix : ndarray, shape (g, g)
        ``tau`` of the curve's normalization in that basis (g = 4 generic, 3 for a rank-one
        potential).
    U : ndarray, shape (g,)
        Velocity of the linear flow on the Jacobian: the Abel image of the eigenvector divisor
        moves as ``A(D(t)) = A(D(0)) - t U``.  Real, zero outside the first
        ``diagnostics['torus_dimension']`` coordinates.
    abel_divisor : ndarray, shape (g,)
        Abel image ``A(D0)`` of the pole divisor of the initial eigenvector (normalized by
        ``<alpha, psi> = 1``), see :meth:`abel_map`.
    alpha : ndarray, shape (3,)
        The normalization vector (principal frame).
    normalization : ndarray, shape (g, g)
        Inverse a-periods in that basis: raw Abel integrals of ``curve`` -> coordinates of ``tau``.
    evaluator : FlowEvaluator
        ``Phi(0, t)`` and the state from theta along the flow.
    """

    curve: object = field(default=None, repr=False)
    basis: np.ndarray = field(default=None, repr=False)
    riemann_matrix: np.ndarray = field(default=None, repr=False)
    U: np.ndarray = field(default=None, repr=False)
    abel_divisor: np.ndarray = field(default=None, repr=False)
    alpha: np.ndarray = field(default=None, repr=False)
    normalization: np.ndarray = field(default=None, repr=False)
    evaluator: FlowEvaluator = field(default=None, repr=False)

    def _evaluate(self, t: np.ndarray):
        return self.evaluator.evaluate(t)

    def abel_map(self, points: Place | Sequence | Mapping) -> np.ndarray:
        """Abel map in the coordinates of :attr:`riemann_matrix` and :attr:`U`.

        ``points`` as for :meth:`thetasol.PlaneCurve.abel_map` (points (E, w) of the spectral curve
        in the principal frame, places, divisors); values modulo ``Z^g + tau Z^g``.
        """
        return self.curve.abel_map(points, normalized=False) @ self.normalization.T

    def imaginary_residual(self, t: ArrayLike) -> np.ndarray:
        """max |Im Phi(0, t)|: the theta quotients are complex, their combination is real; the
        imaginary part left over measures the float64 error of the evaluation (shape ``t.shape``)."""
        tt, flat = self._times(t)
        return self.evaluator.imaginary_residual(flat).reshape(tt.shape)


def _build(J, a, Q0, omega0) -> ThetaRotation:
    """Run the stages (module docstring) and assemble the solution with its diagnostics."""
    frame = body_frame(J, a, Q0, omega0)
    sd = spectral_data(frame)
    dv = eigenvector_divisors(sd)
    ts = theta_shifts(sd, dv)
    ex = exponents(sd, dv, ts)
    ev, shift_correction = flow_evaluator(sd, dv, ts, ex)
    curve = sd.curve
    diagnostics = {
        "genus": curve.genus,
        "torus_dimension": sd.rdim,
        "fourier_modes": int(ev.flow.modes.shape[0]),
        "circle_radius": dv.radius,
        "nu_real_part": ex.nu_real_part,
        "nu_fit_residual": ex.nu_fit_residual,
        "node_gap_change": ex.node_gap_change,
        "nu_exact_change": ex.nu_exact_change,
        "rho_two_radii": ex.rho_two_radii,
        "X0_two_radii": ex.X0_two_radii,
        "shift_correction": shift_correction,
        # Phi(0, t) is real: its imaginary part at a far time bounds what the set-up lost
        "imaginary_residual_t1000": float(ev.imaginary_residual(np.array([1000.0]))[0]),
    }
    inv = {k: (float(v) if np.ndim(v) == 0 else v) for k, v in first_integrals(J, a, Q0, omega0).items()}
    kind = ("symmetric-" if frame.axis is not None else "") + ("nodal-" if curve.node is not None else "")
    diagnostics["case"] = kind.rstrip("-")
    # the imaginary part Phi(0, t) must not have, at a far time, bounds the error of the set-up
    diagnostics["error_estimate"] = max(ROUNDOFF, diagnostics["imaginary_residual_t1000"])
    return ThetaRotation(J=J, a=a, Q0=Q0, omega0=omega0, method=f"theta/genus-{curve.genus}",
                         invariants=inv, diagnostics=diagnostics, curve=curve, basis=sd.G,
                         riemann_matrix=sd.tau, U=sd.U, abel_divisor=dv.AD0, alpha=dv.alpha,
                         normalization=sd.Ainv, evaluator=ev)


def solve_theta_rotation(J: np.ndarray, a: np.ndarray, Q0: np.ndarray, omega0: np.ndarray,
                         dps: int | None = None) -> ThetaRotation:
    """Build the theta-function solution (called by :func:`thetasol.solve_rotation`)."""
    if dps is not None:
        raise ClosedFormUnavailable("dps= is not available for the theta-function solution")
    try:
        sol = _build(J, a, Q0, omega0)
    except ClosedFormUnavailable:
        raise
    except (ValueError, RuntimeError, np.linalg.LinAlgError) as exc:
        # the data were validated by solve_rotation: a failure here is the curve's, not the input's
        msg = f"theta-function solution unavailable for these data: {exc}"
        if symmetry_axis(principal_frame(J, ascending=True)[0]) is not None:
            msg += ("; a symmetric body with little spin about its symmetry axis has a spectral curve "
                    "near a tacnode over E = infinity (Neumann's problem), where the set-up fails")
        raise ClosedFormUnavailable(msg) from exc
    res = sol.diagnostics["imaginary_residual_t1000"]
    if res > RESIDUAL_WARN:
        warnings.warn(f"theta-function solution: |Im Phi(0, t)| = {res:.1g} at t = 1000; the set-up lost "
                      "accuracy (nearly degenerate spectral curve) and errors of that size are to be "
                      "expected; compare with thetasol.integrate_rotation", RuntimeWarning, stacklevel=3)
    return sol
