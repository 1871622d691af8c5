"""Section 4: the rotation of one effective rigid body in a quadratic potential.

* :mod:`~thetasol.solutions.rotation.dispatch`: :func:`~thetasol.solutions.rotation.dispatch.solve_rotation`,
  the entry point, choosing among the models below and putting the data in units of their own
  (:mod:`~thetasol.solutions.rotation._scaling`);
* :mod:`~thetasol.solutions.rotation.euler_top`: the free body (Section 4 I) in Jacobi elliptic functions;
* :mod:`~thetasol.solutions.rotation.pendulum`: rotation about a principal axis (a reducible spectral curve);
* :mod:`~thetasol.solutions.rotation.neumann_rotation`: a symmetric body without axial spin, whose axis
  moves as a point of Neumann's problem (:mod:`~thetasol.solutions.points.neumann`);
* :mod:`~thetasol.solutions.rotation.theta_rotation`: the general case (Section 4 II) in Riemann theta
  functions of the spectral curve (4.12).
"""
