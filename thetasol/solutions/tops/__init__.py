"""Section 5: heavy tops about a fixed point, and the Lagrange top carrying a rotor on its axis.

* :mod:`~thetasol.solutions.tops.heavy_top`: :func:`~thetasol.solutions.tops.heavy_top.solve_heavy_top`,
  the entry point, dispatching to the Euler top, the Lagrange top and the Kovalevskaya top;
* :mod:`~thetasol.solutions.tops.heavy_top_base`: :class:`HeavyTopSolution`, the result they share;
* :mod:`~thetasol.solutions.tops.lagrange_top`: the symmetric top in elliptic functions and Legendre
  integrals of the third kind;
* :mod:`~thetasol.solutions.tops.kovalevskaya_top` (the separated flow in genus-2 theta functions) and
  :mod:`~thetasol.solutions.tops.kovalevskaya_attitude` (the attitude);
* :mod:`~thetasol.solutions.tops.lagrange_gyrostat`: the Lagrange top with a rotor on its axis (Section 8
  on a pivot), whose closed form is the Lagrange top's with one changed constant.
"""
