"""Closed-form rotation of one effective rigid body: the entry point and the result protocol.

:func:`solve_rotation` takes the data of :func:`thetasol.integrate_rotation` (inertia
tensor ``I``, potential matrix ``a``, initial attitude ``Q0``, initial body angular
velocity ``omega0``; the paper's second moments ``J = tr(I)/2 1 - I`` are formed once, inside)
and returns a :class:`RotationSolution`, an immutable object that
evaluates the motion at any times, in any order, at the cost of a few elementary and
elliptic function evaluations per time (no time stepping).

Dispatch (one small function per branch, tried in order, see ``_BRANCHES``):

* ``a = c 1`` (zero or isotropic) or a spherical body (no torque, Section 4 I): the Euler top of
  :mod:`thetasol.solutions.rotation.euler_top` in Jacobi elliptic functions;
* angular velocity along a principal axis that is also an eigenvector of ``Q0^T a Q0``: the
  body keeps turning about that axis, a planar pendulum in elliptic functions
  (:mod:`thetasol.solutions.rotation.pendulum`; the spectral curve is reducible), uniform rotation or rest included;
* a symmetric body with no spin about its symmetry axis: the axis moves as in C. Neumann's problem
  and the body is parallel-transported along it (:mod:`thetasol.solutions.rotation.neumann_rotation`);
* any other ``a`` (Section 4 II): the Baker-Akhiezer theta-function solution of
  :mod:`thetasol.solutions.rotation.theta_rotation` (genus 4; genus 3 for a potential with a repeated eigenvalue
  or for a symmetric body, genus 2 for both).

Units: the data are first put in units where ``max J`` and the larger of ``|omega0|`` and
``sqrt|a - c 1|`` are of order one, by exact powers of two, and an isotropic part ``c 1`` of ``a``
that dominates is removed (it exerts no torque); the solution is returned in the user's units
(:mod:`thetasol.solutions.rotation._scaling`, docs/units.md).  A potential too weak against the spin for the
theta-function set-up (``MIN_POTENTIAL``) is refused at once.

The free gyrostat (8.39)-(8.40) has its own entry point, :func:`thetasol.solve_gyrostat`,
and returns an object with the same protocol.
"""
from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.attitude import principal_frame
from thetasol.core.inertia import second_moments
from thetasol.core.threads import single_blas_thread
from thetasol.mechanics.potential import potential_kind
from thetasol.protocol import ROUNDOFF, ClosedFormUnavailable, RotationSolution
from thetasol.solutions._symmetry import SNAP_TOL, symmetric_without_spin, symmetry_axis
from thetasol.solutions.rotation._scaling import choose_scales, dimensionless_data, scaled_solution

__all__ = ["ClosedFormUnavailable", "RotationSolution", "solve_rotation"]


# -- dispatcher --------------------------------------------------------------------------------

def _free_branch(J, a, Q0, omega0, dps):
    # a spherical body feels no torque either ([u, J] = 0): the same eigenvalue test on J
    if not (potential_kind(a) == "isotropic" or potential_kind(J) == "isotropic"):
        return None
    from thetasol.solutions.rotation.euler_top import solve_euler_top

    return solve_euler_top(J, a, Q0, omega0, dps=dps)


def _pendulum_branch(J, a, Q0, omega0, dps):
    from thetasol.solutions.rotation.pendulum import solve_pendulum

    return solve_pendulum(J, a, Q0, omega0, dps)


def _neumann_branch(J, a, Q0, omega0, dps):
    # symmetric body without axial spin: the axis moves as in Neumann's problem (tacnode of (4.12));
    # other bodies do not import its modules
    if symmetric_without_spin(J, a, omega0) is None:
        return None
    from thetasol.solutions.rotation.neumann_rotation import solve_neumann_rotation

    return solve_neumann_rotation(J, a, Q0, omega0, dps)


#: Smallest potential the theta-function set-up is given, as ``|a - c 1| / (|omega0|^2 + |a - c 1|)``
#: (eigenvalue norms; J of order one after the change of units): below it the spectral curve is within
#: a few digits of the free top's and the set-up fails or loses accuracy.  Each value is the smallest at
#: which that kind of body still keeps its accuracy against 80-bit heyoka at far times (tests/test_units.py
#: checks bodies on both sides; benchmarks/bench_units_sweep.py sweeps random data).
MIN_POTENTIAL = {"generic": 1e-10, "rank-one": 1e-5, "symmetric": 1e-6}
#: Two eigenvalues of ``a`` closer than this (relative to their spread) but not within ``SNAP_TOL``: the
#: spectral curve is near the node of a rank-one potential and is refused at once: below it the error
#: grows as the gap shrinks, without a warning, and smaller gaps are refused by the set-up only after a
#: long computation.
MIN_A_GAP = 1e-7


def _body_kind(J: np.ndarray, a_kind: str) -> str:
    """The key of :data:`MIN_POTENTIAL`: a symmetric body, else the kind of ``a`` (not isotropic here)."""
    if symmetry_axis(principal_frame(J, ascending=True)[0]) is not None:
        return "symmetric"
    return a_kind


def _check_potential_size(J, a, omega0):
    """Refuse at once a potential too weak for the theta-function set-up (:data:`MIN_POTENTIAL`)."""
    lam = np.linalg.eigvalsh(a - np.trace(a) / 3.0 * np.eye(3))
    dev = float(np.abs(lam).max())
    rel = dev / (float(omega0 @ omega0) + dev)
    full = np.linalg.eigvalsh(a)
    gap = float(np.min(np.diff(full))) / float(full[-1] - full[0])
    a_kind = potential_kind(a)
    if a_kind != "rank-one" and gap < MIN_A_GAP:     # rank-one: snapped by the spectral curve
        raise ClosedFormUnavailable(
            f"nearly rank-one potential (two eigenvalues of a {gap:.1e} apart relative to their spread, "
            f"above the snapping tolerance {SNAP_TOL:g} and below {MIN_A_GAP:g}): the spectral curve is near "
            "the node of the rank-one case, out of the curve engine's reach; use thetasol.integrate_rotation")
    kind = _body_kind(J, a_kind)
    if rel < MIN_POTENTIAL[kind]:
        raise ClosedFormUnavailable(
            f"the potential is weak against the spin (|a - c 1| = {rel:.1e} of |omega0|^2; below {MIN_POTENTIAL[kind]:g} for a {kind} body): its spectral curve is within "
            "rounding of the free top's, out of the theta-function set-up's reach; use "
            "thetasol.integrate_rotation (or the free top, solve_rotation with a = 0, when the torque's "
            "effect over your horizon is below your tolerance)")


def _potential_branch(J, a, Q0, omega0, dps):
    _check_potential_size(J, a, omega0)
    from thetasol.solutions.rotation.theta_rotation import solve_theta_rotation

    return solve_theta_rotation(J, a, Q0, omega0, dps=dps)


#: Tried in order; each returns a RotationSolution or None (not its case).
_BRANCHES: list[Callable] = [_free_branch, _pendulum_branch, _neumann_branch, _potential_branch]


@single_blas_thread
def solve_rotation(I: ArrayLike, a: ArrayLike, Q0: ArrayLike, omega0: ArrayLike, *,
                   dps: int | None = None) -> RotationSolution:
    """Exact rotation of a rigid body in the potential ``phi = 1/2 x^T a x`` (closed form).

    Parameters
    ----------
    I : array_like, shape (3,) or (3, 3)
        Inertia tensor about the mass centre in the body frame: principal values or a symmetric
        tensor (then a right-handed principal frame is used internally and results are mapped
        back).  Positive definite with ``I_i <= I_j + I_k``; second moments ``J = sum m r r^T``
        convert with :func:`thetasol.inertia`.
    a : array_like, shape (3, 3)
        Symmetric potential matrix.  ``a = 0`` or ``a = c 1`` (no torque) gives the Euler
        top; any other ``a`` the theta-function solution (4.8)-(4.12).
    Q0 : array_like, shape (3, 3)
        Initial attitude, body to space (``x = Q r``).
    omega0 : array_like, shape (3,)
        Initial body-frame angular velocity (``Qdot = Q hat(omega)``).
    dps : int, optional
        Compute with mpmath at ``dps`` decimal digits (the float data taken as exact);
        ``omega``/``Q`` then return object arrays of ``mpmath.mpf``.

    Returns
    -------
    RotationSolution
        ``sol(t) -> (omega, Q)``, ``sol.omega(t)``, ``sol.Q(t)``, ``sol.M(t)``, ``sol.u(t)``,
        ``sol.model`` (``"rotation"``), ``sol.method`` (``"elliptic"``, ``"elementary"``, ``"theta/genus-4"``,
        ...; docs/results.md), ``sol.invariants`` (first integrals), ``sol.diagnostics`` (self-checks,
        ``error_estimate`` among them), ``sol.check()``.  Data
        of order one (scales within ``2^+-4`` of 1, no dominant isotropic part) get the branch's own
        solution object; others a :class:`~thetasol.solutions.rotation._scaling.ScaledRotation` around the
        solution of the dimensionless problem (``sol.diagnostics["scales"]``), with the user's body
        (``sol.I``; the paper's second moments ``sol.J``), ``a`` and first integrals.

    Raises
    ------
    ValueError
        Non-finite, wrongly shaped or unphysical data; an ``I`` that violates a triangle
        inequality but reads as second moments ``J`` says so (pass ``thetasol.inertia(J)``).
    ClosedFormUnavailable
        (a ``NotImplementedError``) A symmetric body (two equal principal moments) with little
        (but not zero) spin about its symmetry axis in a potential with torque, a Neumann torus
        too close to a separatrix or too thin, ``dps`` with a potential, a potential far weaker
        than the spin (``|a - c 1|`` below ``MIN_POTENTIAL`` of ``|omega0|^2``),
        or nearly degenerate data for which the curve computations cannot reach the solution's
        accuracy; the message says which.

    Warns
    -----
    RuntimeWarning
        The theta-function set-up lost accuracy (``|Im Phi(0, t)|`` above 1e-8 at ``t = 1000``,
        the size is stated): errors of that size are to be expected.  The check cannot see an
        error of the torus position along the real torus: cross-check motion near an unstable
        relative equilibrium with :func:`thetasol.integrate_rotation` (docs/theta_rotation.md, Limits).

    Examples
    --------
    >>> import numpy as np
    >>> sol = solve_rotation([5.5, 4.5, 3.0], np.zeros((3, 3)), np.eye(3), [0.1, 1.0, 0.2])
    >>> sol.model, sol.method
    ('rotation', 'elliptic')
    >>> sol.omega(np.array([0.0, 1e6])).shape
    (2, 3)
    """
    Im = V.inertia(I, "I")
    Jm = second_moments(Im)
    am = V.symmetric_matrix(a, "a")
    Q0m = V.rotation_matrix(Q0, "Q0")
    w0 = V.vector3(omega0, "omega0")
    if dps is not None and (not isinstance(dps, (int, np.integer)) or dps < 15):
        raise ValueError(f"dps must be an integer >= 15, got {dps!r}")
    # no torque from an isotropic a: its units are those of the Euler top (J and omega0 only)
    am_solve = np.zeros((3, 3)) if potential_kind(am) == "isotropic" else am
    sc = choose_scales(Jm, am_solve, w0)
    if sc.trivial:
        sol = _dispatch(Jm, am, Q0m, w0, dps)
    else:
        Js, as_, ws = dimensionless_data(Jm, am_solve, w0, sc)
        sol = scaled_solution(_dispatch(Js, as_, Q0m, ws, dps), Jm, am, Q0m, w0, sc)
    return dataclasses.replace(sol, I_given=Im)   # sol.I is the body as given, not tr(J) 1 - J again


def _dispatch(J, a, Q0, omega0, dps) -> RotationSolution:
    for branch in _BRANCHES:
        sol = branch(J, a, Q0, omega0, dps)
        if sol is not None:
            return _with_error_estimate(sol)
    raise AssertionError("unreachable: the last branch always answers")  # pragma: no cover


def _with_error_estimate(sol: RotationSolution) -> RotationSolution:
    """``sol`` with ``diagnostics["error_estimate"]`` when its branch has no check of its own (the Euler
    top, the pendulum): the data reproduced at ``t = 0``, at least the rounding of the arithmetic
    (float64, or a few units in the last of ``dps`` digits)."""
    if "error_estimate" in sol.diagnostics:
        return sol
    floor = ROUNDOFF if sol.dps is None else 10.0 ** (1 - sol.dps)
    est = floor if sol.dps is not None else max(floor, sol.initial_residual())
    return dataclasses.replace(sol, diagnostics={**sol.diagnostics, "error_estimate": est})
