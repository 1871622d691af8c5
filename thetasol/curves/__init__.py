"""Compact Riemann surfaces of plane curves and the spectral curve (4.12).

One module per concept, after abelfunctions: polynomial data (``_poly``), the path graph
(``_paths``), analytic continuation and quadrature (``_quad``), places and local expansions
(``_places``), homology (``_homology``), the curve object with differentials, periods, Abel map
and Riemann constant (:mod:`thetasol.curves.plane_curve`), the one rule that picks the Riemann constant
(:mod:`thetasol.curves.riemann_constant`), the :class:`~thetasol.curves.protocol.Curve` protocol both curve
classes satisfy (:mod:`thetasol.curves.protocol`), the real homology basis of a Liouville torus
(:mod:`thetasol.curves.adapted_basis`), the spectral curve of a body in a quadratic potential
(:mod:`thetasol.curves.spectral`), and hyperelliptic curves ``y^2 = f(x)`` of odd degree built from their
branch points alone, much faster than the general path (:mod:`thetasol.curves.hyperelliptic`).  Depends on :mod:`thetasol.theta` and below.
"""
