"""Riemann theta functions: Siegel reduction, the summation engine, jets, and theta along a flow.

* :mod:`thetasol.theta.riemann`: :class:`RiemannTheta` and the functional API (float64 with error
  control, ``dps=`` through mpmath);
* :mod:`thetasol.theta.flow`: theta along a real linear flow as a Fourier series in time;
* :mod:`thetasol.theta.grid`: theta with half characteristics and a directional derivative on a 2-D grid of
  a real torus, as matrix products per block;
* private: the lattice (LLL, Siegel reduction), the summation core, the mpmath path.
"""
