"""The protocol every compact Riemann surface of the library satisfies, and the one check of its tau.

:class:`~thetasol.curves.plane_curve.PlaneCurve` (any plane curve, with sympy) and
:class:`~thetasol.curves.hyperelliptic.HyperellipticCurve` (``y^2 = f(x)`` from its branch points alone)
answer the same questions with the same signatures, so that code written for one runs on the other:
the genus, the periods of a basis of holomorphic differentials over a symplectic homology basis, the
Riemann matrix, the normalization, the Abel map of points ``(x, y)`` (and of divisors) from a base point,
and the vector of Riemann constants for that base (docs/curves.md, Conventions).
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

if TYPE_CHECKING:
    from thetasol.curves._numerators import Numerator
    from thetasol.theta.riemann import RiemannTheta

__all__ = ["TAU_SYMMETRY_TOL", "Curve", "riemann_matrix_from_periods"]

#: Largest relative asymmetry of ``tau = A^-1 B`` accepted from computed periods.  Riemann's bilinear
#: relations make ``tau`` symmetric; a wrong sheet or cycle breaks them at order one, while accurate
#: periods leave rounding (1e-15 .. 1e-10 on nearly degenerate curves, whose accuracy the callers' own
#: checks judge): this catches the first without refusing the second.
TAU_SYMMETRY_TOL = 1e-6


def riemann_matrix_from_periods(P: np.ndarray) -> np.ndarray:
    """``tau = A^-1 B`` from the period matrix ``[A | B]`` (g x 2g), symmetrized.

    Raises
    ------
    RuntimeError
        ``tau`` is not symmetric to :data:`TAU_SYMMETRY_TOL` (inaccurate periods) or ``Im tau`` is not
        positive definite (wrong intersection signs).
    """
    g = P.shape[0]
    if g == 0:
        return np.zeros((0, 0), complex)
    tau = np.linalg.solve(P[:, :g], P[:, g:])
    asym = np.max(np.abs(tau - tau.T)) / max(np.max(np.abs(tau)), 1e-300)
    if asym > TAU_SYMMETRY_TOL:
        raise RuntimeError(f"tau is not symmetric (relative asymmetry {asym:.2g}): inaccurate periods")
    tau = 0.5 * (tau + tau.T)
    if np.min(np.linalg.eigvalsh(tau.imag)) <= 0:
        raise RuntimeError("Im tau is not positive definite (internal error in the intersection signs)")
    return tau


@runtime_checkable
class Curve(Protocol):
    """A compact Riemann surface with its periods, Abel map and Riemann constant.

    Conventions: holomorphic differentials ``omega_i = g_i(x, y) dx / f_y`` (:meth:`holomorphic_numerators`
    gives the ``g_i``), period matrix ``[A | B]`` with ``A_ij`` the integral of ``omega_i`` over ``a_j``,
    ``a_i . b_j = delta_ij``, ``tau = A^-1 B``, normalized coordinates ``A^-1 int omega`` (lattice
    ``Z^g + tau Z^g``).
    """

    @property
    def genus(self) -> int:
        """The genus of the compact surface."""
        ...

    def holomorphic_numerators(self) -> tuple[Numerator, ...]:
        """Exact numerators ``g_i`` of the basis ``g_i dx / f_y`` of holomorphic differentials."""
        ...

    def period_matrix(self) -> np.ndarray:
        """``[A | B]``, shape (g, 2g)."""
        ...

    def riemann_matrix(self) -> np.ndarray:
        """``tau = A^-1 B`` (:func:`riemann_matrix_from_periods`)."""
        ...

    def normalization(self) -> np.ndarray:
        """``A^-1``: integrals of the differentials into normalized coordinates."""
        ...

    def abel_map(self, points: Any | Sequence | Mapping, base: Any | None = None, *,
                 normalized: bool = True) -> np.ndarray:
        """Abel map from ``base`` (default: the curve's base point) of one point ``(x, y)`` (shape (g,)), of
        a sequence or array of points (shape ``(..., g)``) or of a divisor ``{point: multiplicity}`` (shape (g,))."""
        ...

    def riemann_constant(self, base: Any | None = None, *, theta: RiemannTheta | None = None) -> np.ndarray:
        """The vector of Riemann constants for ``base`` (default: the curve's base point), normalized."""
        ...
