"""The curve methods the theta-function rotation reads: values of differentials, the farthest branch
point without the surface, the exact polynomial and the sampling radius of a place's expansions.

References: sympy's exact discriminant (mpmath roots) and sympy-lambdified g / f_w at eigenvalues of
L(E) from numpy."""
import mpmath
import numpy as np
import sympy as sp

from thetasol.core.so3 import hat
from thetasol.curves.spectral import farthest_branch_point, spectral_curve

J = np.array([0.6, 1.0, 1.7])
M = hat(np.array([0.3, -0.7, 0.45]))
U = np.array([[0.4, -0.3, 0.2], [-0.3, -0.9, 0.5], [0.2, 0.5, 1.1]])


def _exact_det(J=J, M=M, U=U):
    E, w = sp.symbols("E w")
    R = lambda x: sp.Rational(*float(x).as_integer_ratio())  # noqa: E731
    L = sp.Matrix(3, 3, lambda i, j: (R(J[i]) ** 2 * E ** 2 if i == j else 0) + R(M[i, j]) * E + R(U[i, j])
                  - (w if i == j else 0))
    return sp.expand(L.det()), E, w


def _farthest_exact(J, M, U):
    """max |E| over the roots of sympy's square-free discriminant, in 40-digit mpmath."""
    f, E, w = _exact_det(J, M, U)
    disc = sp.Poly(sp.discriminant(f, w), E).sqf_part()
    with mpmath.workdps(40):
        roots = mpmath.polyroots([mpmath.mpf(sp.Rational(c).p) / sp.Rational(c).q for c in disc.all_coeffs()],
                                 maxsteps=200, extraprec=200)
        return float(max(abs(r) for r in roots))


def test_farthest_branch_point_against_the_exact_discriminant():
    got = farthest_branch_point(np.diag(J), M, U)
    # measured 2.1e-15 relative (np.roots on the float64 coefficients of the exact discriminant)
    assert abs(got - _farthest_exact(J, M, U)) <= 2e-14 * got


def test_farthest_branch_point_of_a_symmetric_body():
    """A symmetric body with a small axial spin: branch points far out (|E| ~ 1 / spin) and a node, whose
    double root of the discriminant np.roots takes to ~sqrt(eps).  Measured: the farthest within 1.9e-15
    relative at spins 1e-1 .. 1e-4 (a simple root); bound 1e-13."""
    Js = np.array([0.8, 0.8, 1.5])
    for spin in (1e-1, 1e-2, 1e-4):
        w0 = np.array([0.7, -0.4, spin])
        Ms = hat(np.diag(Js.sum() - Js) @ w0)
        got = farthest_branch_point(np.diag(Js), Ms, U)
        assert abs(got - _farthest_exact(Js, Ms, U)) <= 1e-13 * got


def test_polynomial_and_differential_values_against_sympy():
    C = spectral_curve(J, M, U, tol=1e-12)
    f, E, w = _exact_det()
    assert sp.expand(C.polynomial().subs({C.x: E, C.y: w}) - f) == 0
    nums = C.holomorphic_differentials()
    Es = np.array([[0.3 + 0.2j, -1.1 + 0.4j], [2.0 - 0.7j, 0.05j]])
    L = np.diag(J ** 2)[None, None] * Es[..., None, None] ** 2 + M * Es[..., None, None] + U
    Ws = np.linalg.eigvals(L)[..., 1]
    got = C.differential_values(nums, Es, Ws)
    assert got.shape == (len(nums),) + Es.shape
    fw = sp.diff(C.polynomial(), C.y)
    for d, g in enumerate(nums):
        h = sp.lambdify((C.x, C.y), sp.sympify(g) / fw)
        ref = np.vectorize(lambda x, y, h=h: complex(h(x, y)))(Es, Ws)
        # measured 1.3e-16 .. 4.8e-16 relative
        assert np.abs(got[d] - ref).max() <= 5e-15 * np.abs(ref).max()


def test_sampling_radius_is_inside_the_disc_of_convergence():
    """The series of y at a place, summed at |t| = r / 2 (r = sampling_radius, t = 1/E at infinity,
    t = E over E = 0), is an eigenvalue of L(E): the expansions are sampled where they converge.
    Measured <= 5.6e-11 relative (truncation at order 12); at |t| = 2 r the sums miss by up to 4.8e-3."""
    C = spectral_curve(J, M, U, tol=1e-12)
    for P in list(C.places_at_infinity()) + list(C.places_over_zero()):
        r = P.sampling_radius
        k, c = P.series(order=12)
        t = 0.5 * r * np.exp(0.3j)
        y = (c * t ** k.astype(float)).sum()
        E = 1 / t if P.is_infinite else t
        W = np.linalg.eigvals(np.diag(J ** 2) * E ** 2 + M * E + U)
        assert np.min(np.abs(W - y)) <= 1e-10 * abs(y), (P, np.min(np.abs(W - y)) / abs(y))
