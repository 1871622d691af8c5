"""Special functions: Jacobi elliptic functions, Legendre integrals, the planar pendulum, Stumpff's functions.

Vectorized float64 kernels accurate as the parameter tends to 1, arguments reduced modulo the
periods so far times cost what t = 1 costs.  Depends only on :mod:`thetasol.core`.
"""
