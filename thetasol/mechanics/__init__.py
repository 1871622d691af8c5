"""Mechanics: rigid bodies, C^k-central configurations, the equations (4.8) and the Lax matrix (4.11).

Bodies and trees of bodies on spherical joints (Sections 2-3), effective bodies (2.15), (3.7), the
Euler equations of one effective body with their first integrals (4.9), (4.13), the Lax matrix
``L(E) = J^2 E^2 + M E + u`` and the per-body trajectory container.  No closed forms here.
"""
