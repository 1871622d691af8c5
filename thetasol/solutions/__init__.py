"""Closed-form solutions, one module per physical model, and the dispatch between them.

* :mod:`~thetasol.solutions.mass_center`: the mass centre (3.2) in elementary functions;
* :mod:`~thetasol.solutions.rotation`: :func:`solve_rotation`, choosing among
  :mod:`~thetasol.solutions.euler_top` (Section 4 I), :mod:`~thetasol.solutions.pendulum`,
  :mod:`~thetasol.solutions.neumann_rotation` and :mod:`~thetasol.solutions.theta_rotation`
  (Section 4 II);
* :mod:`~thetasol.solutions.neumann`: :func:`solve_neumann`, the point on a sphere in a quadratic
  potential (Section 6, Theorem 3), whose models :mod:`~thetasol.solutions.neumann_rotation` reuses;
* :mod:`~thetasol.solutions.gyrostat`: the free gyrostat (8.39)-(8.40), with rotors (8.24)-(8.33);
* :mod:`~thetasol.solutions.heavy_top`: heavy tops about a fixed point (Section 5), dispatching to
  the Euler top and :mod:`~thetasol.solutions.lagrange_top` (Kovalevskaya's separated flow in
  :mod:`~thetasol.solutions.kovalevskaya_top`);
* :mod:`~thetasol.solutions.kepler` and :mod:`~thetasol.solutions.orbiting_rotation`: the orbit
  and the closed-form rotations in its gravity gradient (Section 7).
"""
