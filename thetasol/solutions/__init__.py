"""Closed-form solutions, one subpackage per system of the paper, each with its entry points.

* :mod:`~thetasol.solutions.rotation` (Section 4): :func:`solve_rotation` in
  :mod:`~thetasol.solutions.rotation.dispatch`, choosing among
  :mod:`~thetasol.solutions.rotation.euler_top` (Section 4 I), :mod:`~thetasol.solutions.rotation.pendulum`,
  :mod:`~thetasol.solutions.rotation.neumann_rotation` and :mod:`~thetasol.solutions.rotation.theta_rotation`
  (Section 4 II);
* :mod:`~thetasol.solutions.tops` (Section 5): :mod:`~thetasol.solutions.tops.heavy_top`, heavy tops about a
  fixed point, dispatching to the Euler top and :mod:`~thetasol.solutions.tops.lagrange_top` (Kovalevskaya's
  separated flow in :mod:`~thetasol.solutions.tops.kovalevskaya_top`), and the Lagrange gyrostat;
* :mod:`~thetasol.solutions.points` (Sections 3 and 6): :mod:`~thetasol.solutions.points.mass_center`, the
  mass centre (3.2) in elementary functions, and :mod:`~thetasol.solutions.points.neumann`,
  :func:`solve_neumann`, the point on a sphere in a quadratic potential (Section 6, Theorem 3), whose
  models :mod:`~thetasol.solutions.rotation.neumann_rotation` reuses;
* :mod:`~thetasol.solutions.orbit` (Section 7): :mod:`~thetasol.solutions.orbit.kepler` and
  :mod:`~thetasol.solutions.orbit.orbiting_rotation`, the orbit and the closed-form rotations in its
  gravity gradient;
* :mod:`~thetasol.solutions.gyrostat` (Section 8): the free gyrostat (8.39)-(8.40), with rotors (8.24)-(8.33).

:mod:`~thetasol.solutions._symmetry` holds the symmetry test and the snapping tolerance that the
rotation models and Neumann's point share, so it sits here, above both subpackages.
"""
