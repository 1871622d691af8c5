"""Rotation of a rigid body in a quadratic potential in Riemann theta functions (Section 4 II).

The method (derivation, accuracy and limits in docs/theta_rotation.md)
----------------------------------------------------------------------
The Lax pair (4.11) ``L(E) = J^2 E^2 + M E + u``, ``A(E) = J E + omega``, ``Ldot = [L, A]``
is solved by the fundamental matrix ``Phi(E, t)`` of ``Phidot = -A(E, t) Phi``: then
``L(E, t) = Phi L(E, 0) Phi^{-1}`` and, at ``E = 0``, ``Phi(0, t) = Q(t)^T Q0``: the attitude
itself.  For a point ``P = (E, w)`` of the spectral curve (4.12) let ``psi(P)`` be the eigenvector
of ``L(E, 0)`` normalized by ``<alpha, psi> = 1``.  The vector Baker-Akhiezer function
``Psi(P, t) = Phi(E, t) psi(P)`` has the poles of ``psi`` (a divisor ``D0`` of degree g + 2),
the essential singularity ``exp(-J_j E t)`` at the place ``inf_j`` over ``E = infinity`` and
``Psi_k exp(J_j E t) -> delta_kj / alpha_j`` there.  Its components are theta quotients::

    Psi_k(P, t) = rho_k(P) exp(c_k(P) t) theta(A(P) + t U - e_k) theta(A(inf_k) - e_k)
                                        / theta(A(inf_k) + t U - e_k)
    e_k = A(D0) - sum_{j != k} A(inf_j) + K,     U = sum_j J_j omega(inf_j) / ds  (s = 1/E).

Evaluating at the three places over ``E = 0`` gives ``Phi(0, t)``, hence ``Q(t)`` and
``omega = vee(-Phidot Phi^T)``.  Everything is computed in a homology basis adapted to the real
Liouville torus, where ``U`` is real with as many non-zero coordinates as the torus has dimensions,
so theta along the trajectory is a Fourier series and a far time costs what t = 1 costs.

The set-up is a sequence of stages, one module each, each returning a frozen dataclass
(:mod:`.solution` runs them):

* :mod:`.frame` -- the principal frame; a symmetric body's turning frame; refusals;
* :mod:`.spectral_data` -- stage 1: the curve, the adapted basis, ``tau``, ``U``, the special places
  (closed forms at infinity in :mod:`.infinity`, the node over ``E = 0`` in :mod:`.node`);
* :mod:`.divisors` -- stage 2: the eigenvector divisors and their Abel images;
* :mod:`.riemann` -- stage 3: the Riemann constant ``K`` and the shifts ``e_k``, ``d_k``;
* :mod:`.cauchy`, :mod:`.exponents` -- stage 4: the constants at ``t = 0`` and the exact exponents;
* :mod:`.evaluator` -- stage 5: theta along the flow and ``omega``, ``Q``; :mod:`.solution` the result.

Degenerate data: ``a`` with a repeated eigenvalue gives a node at ``E = 0`` and the construction runs
on the genus-3 normalization; a symmetric body runs in the frame turning with its axial spin, on the
normalization of the node over ``E = infinity``.  A symmetric body with little axial spin (below
``MIN_AXIAL_SPIN``) or far branch points (beyond ``MAX_FAR_BRANCH``), and a nearly symmetric one (gap
below ``MIN_J_GAP``), are refused at once (ClosedFormUnavailable).
"""
from __future__ import annotations

from thetasol.solutions.rotation.theta_rotation.cauchy import N_CIRCLE, N_RAY
from thetasol.solutions.rotation.theta_rotation.frame import MAX_FAR_BRANCH, MIN_AXIAL_SPIN, MIN_J_GAP

# the entry point of the dispatcher in thetasol.solutions.rotation.dispatch
from thetasol.solutions.rotation.theta_rotation.solution import (
    ThetaRotation,
    solve_theta_rotation as solve_theta_rotation,
)

__all__ = ["ThetaRotation", "solve_theta_rotation", "MIN_AXIAL_SPIN", "MIN_J_GAP", "MAX_FAR_BRANCH", "N_CIRCLE", "N_RAY"]
