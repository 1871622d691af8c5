"""Sections 3 and 6: the motion of a point, the system's mass centre, unconstrained or on a sphere.

* :mod:`~thetasol.solutions.points.mass_center`: the mass centre (3.2) in elementary functions;
* :mod:`~thetasol.solutions.points.neumann`: :func:`~thetasol.solutions.points.neumann.solve_neumann`, the
  point on a sphere in a quadratic potential (Section 6, Theorem 3), on the Liouville tori of
  :mod:`~thetasol.solutions.points._neumann_torus`.
"""
