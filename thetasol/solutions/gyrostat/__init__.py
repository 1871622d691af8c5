"""The free gyrostat (Zhukovsky-Volterra case): (8.39)-(8.40) in closed form.

A carrier with rotors of constant axial momentum (Section 8, Corollary 8): with the rotor
momentum ``N = sum p_k l_k`` (8.33) (constant in the body frame) and the body angular momentum
``m = I omega`` (the paper's ``M`` of (8.33); ``I`` is the carrier's inertia with the rotors'
masses and transverse moments, without their axial moments), (8.39)
``Mdot = [M + N, omega]`` reads ``mdot = (m + N) x omega`` and conserves (8.40)
``T = 1/2 m . omega`` and ``|h|^2 = |m + N|^2``; the total momentum ``h = m + N`` is fixed in
space (``Q h`` constant).  The attitude obeys ``Qdot = Q hat(omega)``.  Given the rotors (axis
``l_k``, moments ``A_k, B_k``, the conserved ``p_k`` of (8.25)), the rotor angles follow from
(8.28), ``phidot_k = p_k / A_k - omega . l_k`` (:mod:`thetasol.solutions.gyrostat._rotors`,
docs/gyrostat.md).

Method
------
``h(t)`` runs on the intersection of the sphere ``|h| = G`` with the ellipsoid
``(h - N) . I^{-1} (h - N) = 2T``, an elliptic curve (Volterra 1899; Basak 2009 gives its
sigma-function form).  We parametrize it by the pencil of planes through the tangent line of
the orbit at an anchor point ``h_a`` (normally ``h(0)``): each plane meets the curve in two
further points, which solve a quadratic whose discriminant ``Delta(z)`` is a quartic in the
pencil parameter ``z`` (``z = 0`` is the osculating plane).  ``dt`` is the holomorphic
differential: with our normalization ``dz / dt = W``, ``W^2 = Delta(z)`` exactly (checked to
50 digits, and by the tests).  ``z(t)`` oscillates between two real zeros of ``Delta`` (a real
component of the curve meets every plane of the pencil in an even number of points), and is
inverted by Weierstrass' formula based at such a zero ``z_r`` (Whittaker & Watson 20.6):
in the pencil turned so that ``z_r`` is at 0, ``y(t) = k / (wp(t - t_r) - c)`` with
``k = Delta'/4``, ``c = Delta''/24`` there and ``wp`` of the quartic's invariants ``g2, g3``,
written with our Jacobi functions (three real roots of ``4x^3 - g2 x - g3``:
``wp = e3 + (e1 - e3)/sn^2``; one real root: the ``cn`` form).  Multiplied through by ``sn^2``
(resp. ``1 - cn``), its homogeneous numerator and denominator never vanish together.  (The
formula based at a general point, the anchor, has a numerator and a denominator with two
common zeros per period; for some generic data they lie on the real orbit, where float64
evaluation is 0/0: large energy errors next to them.)  Of the
zeros bounding the orbit the steepest is taken (next to a separatrix the other can be one of a
nearly double pair, where ``wp - c`` would cancel), and ``t_r``, the time it is reached, comes
from ``wp(t_a - t_r)`` by Carlson's ``R_F``.  The point is rebuilt from ``z`` and ``W`` (a root
of the quadratic, in whichever of its two algebraic forms has the smaller rounding bound).
Argument reduction modulo the periods is as in the Euler top.

Attitude: as for the Euler top, ``Q = S R_3(psi) B(h)`` with ``B`` the minimal rotation
taking ``h/G`` to a pole ``p`` kept away from the orbit, and
``psi' = (h . omega + G p . omega) / (G + p . h)`` (an integral of the third kind).  Its
secular rate and periodic part are taken from the Fourier series of this closed-form
periodic integrand, the coefficients computed by FFT to round-off (the series converges
geometrically; the number of terms is chosen adaptively).

Separatrix: when the cubic has a double root the parameter is ``m = 1`` exactly (or ``m = 0``:
a regular orbit on a level set with a relative equilibrium elsewhere): ``sn = tanh``,
``cn = dn = sech`` and the orbit is homoclinic to the saddle (method "elliptic", case "separatrix", period
``inf``).  ``psi'`` is then a rational function of ``s = tanh(u)`` equal to the saddle's rate at
``s = +-1``; ``psi - nu t`` is the integral of a Chebyshev series in ``s`` (the interpolant of
``psi'``, less its values at ``+-1``, divided exactly by ``1 - s^2``).

Numerics: the few algebraic constants (the frame, the quartic, ``g2, g3``, the cubic's
roots, the turning point and ``t_r``, ``K``) are formed in mpmath from the data exactly
(``I_i = J_j + J_k`` and ``m = I omega0`` as rationals, a power-of-two scaling by ``|h|``):
``g2, g3`` cancel, near a separatrix the parameter amplifies that by ``1/mc``, and a float64
rounding of the data would move the period there by far more than round-off.  A discriminant
that vanishes to 2000 digits is taken as exactly zero.  The residual quadratic is evaluated from
exact-coefficient polynomials in ``z`` (so that small orbits about a relative equilibrium,
``|m| << |N|``, and nearly planar orbits of nearly axisymmetric dual-spin bodies keep their
relative accuracy); ``wp - c`` as ``(e_top - c) + (wp - e_top)``, each term free of
cancellation; ``m(t)`` is carried as ``m(h_a) + (h(t) - h_a)``.

The anchor: the pencil is re-anchored (at a point of the same orbit that the closed form gives
in mpmath, unrounded) when the torsion vanishes at ``h(0)`` (a point on a symmetry plane of the
orbit: ``N`` along a principal axis and ``omega0`` in a principal plane, say), where the
formula is 0/0 where the orbit meets the osculating plane again, and when ``h(0)`` is slow (next
to a saddle): its tangent line then passes close to the saddle, and the pencil resolves the
points around it, where the orbit lingers, only to ``eps / distance``.  The
new anchor is a fast point where the pencil turns fastest.

Degenerate cases are separate closed forms: ``N = 0`` (or below the rounding of ``m``) is the
Euler top (:mod:`thetasol.solutions.rotation.euler_top`), ``m = 0`` rest, ``h x omega = 0`` (to the rounding of the
data) steady rotation, a spherical carrier and an axisymmetric carrier with ``N`` along its
axis are trigonometric.

Error report: ``diagnostics["error_estimate"]`` is the float64 evaluation's error relative to
``|m|``, per period: twice the largest difference from the same closed form in mpmath at the
data point and at the points of a dense grid where the float64 result is least trustworthy
(largest ``|dh/dtheta|``, farthest from the invariant sphere and ellipsoid, the end of the
period, a few others), plus the phase error of the rounded period (``4 eps T max|hdot|``) and
the Fourier tail of ``psi'``; a :class:`RuntimeWarning` is issued above 1e-10.  Float64
round-off is reached everywhere except on nearly planar orbits (a rotor momentum small against
``|m|`` next to the Euler top's separatrix, where the torsion of the orbit is small everywhere
and every pencil of planes through a line meeting the curve twice degenerates): there the loss
grows like ``eps / torsion ratio`` and the estimate reports it (checked against quadruple heyoka in
``test_nearly_planar_orbits_report_their_loss``).  Orbits within 1e-307 (but not exactly
on) a separatrix, and motions within 1e-60 (relative) of a relative equilibrium, raise
:class:`~thetasol.protocol.ClosedFormUnavailable`.  There is no ``dps=`` path.
"""
from __future__ import annotations

from thetasol.solutions.gyrostat._rotors import Rotor
from thetasol.solutions.gyrostat._solve import GyrostatSolution, solve_gyrostat

__all__ = ["GyrostatSolution", "Rotor", "solve_gyrostat"]
