"""Riemann theta functions: Siegel reduction, the summation engine, jets, and theta along a flow.

* :mod:`thetasol.theta.riemann`: :class:`RiemannTheta` and the functional API (float64 with error
  control, ``dps=`` through mpmath);
* :mod:`thetasol.theta.flow`: theta along a real linear flow as a Fourier series in time;
* private: the lattice (LLL, Siegel reduction), the summation core, the mpmath path.
"""
