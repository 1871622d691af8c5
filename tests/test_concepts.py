"""One implementation of each concept: the principal frame, the Stumpff functions, the potential
classifier and the Curve protocol, checked against independent definitions."""
from __future__ import annotations

import mpmath
import numpy as np
import pytest

from thetasol.core.attitude import principal_frame
from thetasol.core.so3 import rodrigues
from thetasol.curves.hyperelliptic import HyperellipticCurve
from thetasol.curves.protocol import Curve
from thetasol.curves.riemann_constant import theta_normalized_abs
from thetasol.curves.spectral import spectral_curve
from thetasol.mechanics.potential import potential_kind
from thetasol.special.stumpff import stumpff, stumpff_float

# -- principal frame ---------------------------------------------------------------------------

@pytest.mark.parametrize("ascending", [False, True])
def test_principal_frame_diagonalizes_right_handed(ascending):
    rng = np.random.default_rng(3)
    A = rng.normal(size=(3, 3))
    J = A @ A.T + np.eye(3)
    Jp, R = principal_frame(J, ascending=ascending)
    assert np.allclose(R.T @ R, np.eye(3), atol=1e-14)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-14)
    assert np.allclose(R @ np.diag(Jp) @ R.T, J, atol=1e-13)
    assert np.all(np.diff(Jp) > 0)


def test_principal_frame_of_principal_data():
    J = np.diag([3.0, 1.0, 2.0])
    Jp, R = principal_frame(J)
    assert np.array_equal(Jp, [3.0, 1.0, 2.0]) and np.array_equal(R, np.eye(3))   # the body's own axes
    Jp, R = principal_frame(J, ascending=True)
    assert np.array_equal(Jp, [1.0, 2.0, 3.0])
    assert np.allclose(R @ np.diag(Jp) @ R.T, J, atol=1e-15) and np.linalg.det(R) == pytest.approx(1.0)


# -- Stumpff functions -------------------------------------------------------------------------

_Z = np.concatenate([-np.logspace(-20, 2.5, 60), [0.0], np.logspace(-20, 2.5, 60), [3.999, 4.0, 4.001]])


def _closed_form(k, z):
    """c_k(z) from cos/sin (cosh/sinh for z < 0) in mpmath, or the series' first term at z = 0."""
    if z == 0:
        return 1 / mpmath.factorial(k)
    s = mpmath.sqrt(abs(z))
    c, sn = (mpmath.cos(s), mpmath.sin(s)) if z > 0 else (mpmath.cosh(s), mpmath.sinh(s))
    return [c, sn / s, (1 - c) / z, (s - sn) / (z * s) if z > 0 else (sn - s) / (-z * s)][k]


def test_stumpff_against_the_series_and_the_closed_forms():
    c = stumpff(_Z)
    worst_series = worst_closed = 0.0
    with mpmath.workdps(60):    # the closed forms cancel near z = 0: 60 digits keep 20 at z = 1e-20
        for i, zz in enumerate(_Z):
            x = mpmath.mpf(float(zz))
            for k in range(4):
                ref = mpmath.nsum(lambda j, x=x, k=k: (-x) ** j / mpmath.factorial(2 * j + k), [0, mpmath.inf])
                worst_series = max(worst_series, float(abs(c[k][i] - ref) / abs(ref)))
                worst_closed = max(worst_closed, float(abs(c[k][i] - _closed_form(k, x)) / abs(ref)))
    assert worst_series < 1e-14
    assert worst_closed < 1e-14


def test_stumpff_float_is_the_same_functions():
    c = stumpff(_Z)
    for i, zz in enumerate(_Z):
        f = stumpff_float(float(zz))
        for k in range(4):
            assert f[k] == pytest.approx(float(c[k][i]), rel=4e-16, abs=0.0)


def test_stumpff_modes_of_a_quadratic_potential():
    # c0, c1, c2 of z = lam t^2 are cos(x), sin(x)/x, (1 - cos x)/x^2 with x = sqrt(lam) t
    lam, t = np.array([4.0, -4.0, 0.0, 1e-30]), 0.5
    C, S, P, _ = stumpff(lam * t * t)
    assert np.allclose(C, [np.cos(1), np.cosh(1), 1, 1], rtol=1e-15)
    assert np.allclose(S, [np.sin(1), np.sinh(1), 1, 1], rtol=1e-15)
    assert np.allclose(P, [1 - np.cos(1), np.cosh(1) - 1, 0.5, 0.5], rtol=1e-15)
    # no cancellation in c2 for small arguments (1 - cos x loses everything at x = 1e-9)
    assert stumpff(1e-18)[2] == 0.5


# -- the potential classifier ------------------------------------------------------------------

def _turned(d):
    """``Q diag(d) Q^T`` for a generic rotation: the kind must survive the rounding of the rotation."""
    Q = rodrigues(np.array([0.3, -0.5, 0.8]))
    return Q @ np.diag(d) @ Q.T


@pytest.mark.parametrize("a, kind", [
    (np.zeros((3, 3)), "isotropic"),
    (2.0 * np.eye(3), "isotropic"),
    (_turned([-5.0, -5.0, -5.0]), "isotropic"),
    (3.0 * np.outer([0.6, 0.0, 0.8], [0.6, 0.0, 0.8]), "rank-one"),
    (_turned([1.0, 1.0, 3.0]), "rank-one"),
    (_turned([1e6, 1e6, 1e6 + 1.0]), "rank-one"),     # a large isotropic part does not hide the pair
    (np.diag([1.0, 2.0, 3.0]), "generic"),
    (_turned([1.0, 1.0 + 1e-12, 3.0]), "generic"),
])
def test_potential_kind(a, kind):
    assert potential_kind(a) == kind


@pytest.mark.parametrize("d, genus", [([1.0, 1.0, 3.0], 3), ([1.0, 2.0, 3.5], 4)])
def test_potential_kind_agrees_with_the_genus_of_the_spectral_curve(d, genus):
    # (4.12): a rank-one potential gives a nodal curve of geometric genus 3, a generic one genus 4
    a = _turned(d)
    C = spectral_curve([1.0, 1.7, 2.4], [0.3, -0.2, 0.5], -a)
    assert C.genus == genus
    assert potential_kind(a) == ("rank-one" if genus == 3 else "generic")


def test_potential_kind_refuses_what_is_not_a_matrix():
    with pytest.raises(ValueError, match="3x3"):
        potential_kind(np.ones(3))


# -- one Curve protocol ------------------------------------------------------------------------

_J2 = np.block([[np.zeros((2, 2)), np.eye(2)], [-np.eye(2), np.zeros((2, 2))]])


def _protocol_checks(C, pts: np.ndarray) -> None:
    """The same code for any Curve: shapes, tau, Jacobi inversion with K, another base point, divisors."""
    assert isinstance(C, Curve)
    g = C.genus
    P, tau = C.period_matrix(), C.riemann_matrix()
    assert P.shape == (g, 2 * g) and len(C.holomorphic_numerators()) == g
    assert np.allclose(tau, np.linalg.solve(P[:, :g], P[:, g:]), rtol=0, atol=1e-13 * np.abs(tau).max())
    assert np.array_equal(tau, tau.T) and np.min(np.linalg.eigvalsh(tau.imag)) > 0
    assert np.allclose(C.normalization() @ P[:, :g], np.eye(g), atol=1e-13)
    D = pts[:g]
    A = C.abel_map(D)
    assert A.shape == (g, g) and C.abel_map(tuple(D[0])).shape == (g,)
    assert C.abel_map(np.stack([D, D])).shape == (2, g, g)
    assert np.allclose(C.abel_map({tuple(p): 1 for p in D}), A.sum(axis=0), atol=1e-13)
    # theta(A(P) - A(D) - K) vanishes at the g points of D (Riemann's vanishing theorem) and not elsewhere
    K = C.riemann_constant()
    assert theta_normalized_abs(A - A.sum(axis=0) - K, tau).max() < 1e-9
    assert theta_normalized_abs(C.abel_map(pts[g:]) - A.sum(axis=0) - K, tau).min() > 1e-4
    # the same from another base point Q: K_Q = K + (g - 1) A(Q)
    Q = tuple(pts[-1])
    AQ = C.abel_map(D, base=Q)
    assert theta_normalized_abs(AQ - AQ.sum(axis=0) - C.riemann_constant(base=Q), tau).max() < 1e-9


def test_both_curve_classes_satisfy_one_protocol():
    """y^2 = f(x) of genus 2 written as a PlaneCurve and as a HyperellipticCurve: the same code runs on
    both, the lattices agree up to an integer symplectic change of basis (PlaneCurve's differentials
    x^i dx / f_y are half of x^i dx / y), and the numerators differ by that factor 2."""
    sympy = pytest.importorskip("sympy")
    from thetasol.curves.plane_curve import PlaneCurve

    coef = np.real(-2.0 * np.poly([-2.1, -0.6, 0.4, 1.3, 2.7]))
    X, Y = sympy.symbols("x y")
    pc = PlaneCurve(Y ** 2 - sum(sympy.Float(float(c), 30) * X ** (5 - i) for i, c in enumerate(coef)), X, Y)
    hc = HyperellipticCurve.from_coefficients(coef)
    x = np.array([0.3 + 0.8j, -1.2 + 0.4j, 1.9 - 0.7j, -0.4 - 1.1j, 0.9 + 1.5j])
    pts = np.stack([x, np.sqrt(hc.f(x)) * np.array([1, -1, 1, 1, -1])], axis=-1)
    for C in (pc, hc):
        _protocol_checks(C, pts)
    S = np.linalg.solve(np.vstack([hc.period_matrix().real, hc.period_matrix().imag]),
                        np.vstack([2 * pc.period_matrix().real, 2 * pc.period_matrix().imag]))
    assert np.max(np.abs(S - np.rint(S))) < 1e-10
    S = np.rint(S)
    assert np.array_equal(S.T @ _J2 @ S, _J2)
    for i, (n_pc, n_hc) in enumerate(zip(pc.holomorphic_numerators(), hc.holomorphic_numerators(), strict=True)):
        assert n_pc.monomials == n_hc.monomials == [(i, 0)]
        assert n_hc.coefficient(i, 0) == 2 * n_pc.coefficient(i, 0)


@pytest.mark.parametrize("roots", [[-2.1, -0.6, 0.4, 1.3, 2.7],                                # genus 2
                                   [-2.1, -0.7 + 0.5j, -0.7 - 0.5j, 0.9, 2.4],                 # genus 2, complex pair
                                   [-2.3, -1.1, -0.2, 0.5, 1.4, 2.2, 3.1]])                    # genus 3
def test_one_theta_call_chooses_as_the_pruned_two(roots, monkeypatch):
    """The chooser scores few points (candidates x test divisors) in one theta call and many in two (the
    second only for the candidates that vanish at the first divisor): the same K either way, bit for bit."""
    import thetasol.curves.riemann_constant as R

    def K(fold):
        monkeypatch.setattr(R, "FOLD_POINTS", fold)
        return HyperellipticCurve.from_roots(np.array(roots, complex), -4.0).riemann_constant()

    assert np.array_equal(K(0), K(10 ** 6))
