"""Numerical references: the rotation ODEs of one body and the unsplit multibody system.

What the closed forms are checked against: :func:`~thetasol.integrators.rotation.integrate_rotation`
(DOP853, a symplectic splitting, heyoka when installed) and
:func:`~thetasol.integrators.multibody.integrate_multibody` (the constrained tree in maximal
coordinates, no split).
"""
