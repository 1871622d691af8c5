"""Closed-form solutions, one module per physical model, and the dispatch between them.

* :mod:`~thetasol.solutions.base`: the :class:`Solution` protocol and :class:`ClosedFormUnavailable`;
* :mod:`~thetasol.solutions.mass_center`: the mass centre (3.2) in elementary functions;
* :mod:`~thetasol.solutions.rotation`: :func:`solve_rotation`, choosing among
  :mod:`~thetasol.solutions.euler_top` (Section 4 I), :mod:`~thetasol.solutions.pendulum`,
  :mod:`~thetasol.solutions.neumann_rotation` and :mod:`~thetasol.solutions.theta_rotation`
  (Section 4 II);
* :mod:`~thetasol.solutions.neumann`: :func:`solve_neumann`, the point on a sphere in a quadratic
  potential (Section 6, Theorem 3), whose models :mod:`~thetasol.solutions.neumann_rotation` reuses;
* :mod:`~thetasol.solutions.gyrostat`: the free gyrostat (8.39)-(8.40).

New models go here as their own modules: heavy tops (Section 5), the orbit and its rotations
(Section 7), gyrostats with rotors (Section 8).
"""
