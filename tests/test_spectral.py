"""spectral_curve: the curve (4.12), its involution, special places and degenerations.

References: sympy's exact determinant, Sage period matrices at 212 bits (tests/data/curves), and
identities (sigma acts on the holomorphic differentials {1, E, E^2, w} dE/f_w by -1, +1, -1, -1).
"""
import numpy as np
import pytest
import sympy as sp
from test_curves import assert_same_lattice, load_ref

from thetasol.core.so3 import hat
from thetasol.curves.spectral import spectral_curve

E, w = sp.symbols("E w")


def generic_data(seed=3):
    rng = np.random.default_rng(seed)
    J = np.array([1.0, 1.7, 2.9])
    m = rng.normal(size=3)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    a = rng.normal(size=(3, 3))
    a = a + a.T
    return J, hat(m), -Q.T @ a @ Q, Q


def test_polynomial_is_the_determinant():
    J, M, u, _ = generic_data()
    C = spectral_curve(J, M, u)
    Jm = sp.diag(*[sp.Rational(v) for v in J])
    Mm = sp.Matrix(3, 3, [sp.Rational(v) for v in M.ravel()])
    Um = sp.Matrix(3, 3, [sp.Rational(v) for v in u.ravel()])
    det = sp.Poly((Jm**2 * E**2 + Mm * E + Um - w * sp.eye(3)).det(), E, w)
    ours = sp.Poly(C._poly.sympy_expr(), E, w)
    for (i, j), c in det.terms():
        c2 = ours.coeff_monomial(E**i * w**j)
        assert abs(float(c - c2)) <= 1e-14 * max(1.0, abs(float(c))), (i, j)


def test_generic_curve_structure():
    J, M, u, _ = generic_data()
    C = spectral_curve(J, M, u)
    assert C.genus == 4 and C.arithmetic_genus == 4 and C.degeneracy == [] and C.node is None
    b = np.sort_complex(C.branch_points)
    assert len(b) == 12
    assert np.allclose(np.sort_complex(-b), b, atol=1e-12)
    assert [str(g) for g in C.holomorphic_differentials()] == ["1", "E", "E**2", "w"]
    assert [str(g) for g in C.prym_differentials()] == ["1", "E**2", "w"]
    # w / E^2 at the places at infinity: the coefficient of t^(-2e) of w's series there (x = t^(-e))
    lims = [c[k == -2 * P.e][0] for P in C.places_at_infinity() for k, c in [P.series(4)]]
    assert np.allclose(lims, J**2, atol=1e-12)
    assert all(P.e == 1 for P in C.places_at_infinity())
    ys = np.sort([P.y.real for P in C.places_over_zero()])
    assert np.allclose(ys, np.linalg.eigvalsh(u), atol=1e-12)


def test_involution_on_the_jacobian():
    """A(sigma P) = diag(-1, 1, -1, -1) A(P) + const modulo the lattice (raw coordinates)."""
    J, M, u, _ = generic_data()
    C = spectral_curve(J, M, u)
    P = C.period_matrix()
    s = np.array([-1, 1, -1, -1])
    rng = np.random.default_rng(1)
    vals = []
    for _ in range(3):
        E0 = complex(rng.normal(), rng.normal())
        R, _ = C._poly.roots(np.array([E0]))
        p = (E0, R[0, 0])
        A = C.abel_map([p, C.involution(p)], normalized=False)
        vals.append(A[1] - s * A[0])
    for v in vals[1:]:
        d = v - vals[0]
        T = np.linalg.solve(np.vstack([P.real, P.imag]), np.concatenate([d.real, d.imag]))
        assert np.max(np.abs(T - np.rint(T))) < 1e-10
    for Pl in C.places_at_infinity() + C.places_over_zero():
        assert C.involution(Pl) == Pl


def test_generic_periods_match_sage():
    d, f, diffs, Pref = load_ref("spectral_g4")
    J = np.array([1, 1.7, 2.9])
    m = np.array([0.3, -0.7, 1.1])
    u = np.array([[-1.2, 0.3, 0.1], [0.3, 0.5, -0.4], [0.1, -0.4, 0.9]])
    C = spectral_curve(J, hat(m), u)
    P = C.period_matrix([g.subs({sp.Symbol("x"): E, sp.Symbol("y"): w}) for g in diffs])
    assert_same_lattice(P, Pref, tol=1e-12)


def test_rank_one_potential_is_nodal_and_matches_sage():
    _, _, diffs, Pref = load_ref("spectral_nodal_g3")
    J = np.array([1, 1.7, 2.9])
    m = np.array([0.3, -0.7, 1.1])
    v = np.array([2.0, -1.0, 2.0]) / 3
    u = 0.2 * np.eye(3) - (1 / 3) * np.outer(v, v)
    C = spectral_curve(J, hat(m), u)
    assert C.genus == 3 and C.arithmetic_genus == 4
    assert C.node is not None and abs(C.node[1] - 0.2) < 1e-15
    assert any("rank-one" in s for s in C.degeneracy)
    P = C.period_matrix([g.subs({sp.Symbol("x"): E, sp.Symbol("y"): w}) for g in diffs])
    assert_same_lattice(P, Pref, tol=1e-12)
    prym = C.prym_differentials()
    assert len(prym) == 2
    assert all(abs(complex(g.subs({E: 0, w: C.node[1]}))) < 1e-12 for g in prym)  # adjoint at the node
    b1, b2 = C.node_branches()
    assert C.involution(b1) == b2 and C.involution(b2) == b1
    assert b1 != b2 and b1.e == b2.e == 1
    # the node's branches are distinct points of the Jacobian, exchanged by sigma
    A = C.abel_map([b1, b2])
    assert np.max(np.abs(A[0] - A[1])) > 1e-3


def test_near_rank_one_within_tolerance_is_snapped():
    J, M, _, Q = generic_data()
    gam = np.array([0.3, -1.2, 0.8])
    a = 2.0 * np.outer(gam, gam) + 1e-12 * np.diag([1.0, 2.0, 3.0])
    C = spectral_curve(J, M, -Q.T @ a @ Q)
    assert C.genus == 3 and C.node is not None
    assert "changed by" in C.degeneracy[0]


def test_symmetric_body_matches_sage():
    _, _, diffs, Pref = load_ref("spectral_symmetric")
    J = np.array([1, 1, 2.9])
    m = np.array([0.3, -0.7, 1.1])
    u = np.array([[-1.2, 0.3, 0.1], [0.3, 0.5, -0.4], [0.1, -0.4, 0.9]])
    C = spectral_curve(J, hat(m), u)
    assert C.symmetric_body and C.genus == 3
    P = C.period_matrix([g.subs({sp.Symbol("x"): E, sp.Symbol("y"): w}) for g in diffs])
    assert_same_lattice(P, Pref, tol=1e-12)
    with pytest.raises(ValueError, match="symmetric body"):
        C.place_at_infinity(0)


def test_bad_input():
    J, M, u, _ = generic_data()
    with pytest.raises(ValueError, match="triple eigenvalue"):
        spectral_curve(J, M, 0.7 * np.eye(3))
    with pytest.raises(ValueError, match="NaN"):
        spectral_curve(J, M, np.full((3, 3), np.nan))
    with pytest.raises(ValueError, match="skew"):
        spectral_curve(J, M + np.eye(3), u)
    with pytest.raises(ValueError, match="symmetric"):
        spectral_curve(J, M, u + np.triu(np.ones((3, 3)), 1))
    with pytest.raises(ValueError, match="reducible"):
        spectral_curve(J, np.zeros((3, 3)), np.diag([0.1, 0.5, 0.9]))


# ---------------------------------------------------------------------- nearly degenerate data
from thetasol.curves.plane_curve import PlaneCurve  # noqa: E402


def _near_rank_one(eps, seed=3):
    J, M, _, Q = generic_data(seed)
    gam = np.array([0.3, -1.2, 0.8])
    a = 2.0 * np.outer(gam, gam) + eps * np.diag([1.0, 2.0, 3.0])
    return J, M, -Q.T @ a @ Q


def _same_basis_close(P1, P2, tol):
    return np.max(np.abs(P1 - P2)) / np.max(np.abs(P2)) <= tol


@pytest.mark.parametrize("eps", [1e-6, 1e-8])
def test_near_rank_one_above_tolerance_against_multiprecision(eps):
    """Branch points ~eps apart: float64 result equals the mpmath quadrature (20 digits at every node,
    same cycles) and a different path graph gives the same lattice."""
    J, M, u = _near_rank_one(eps)
    C = spectral_curve(J, M, u, tol=1e-12)
    assert C.genus == 4 and C.node is None
    b = C.branch_points
    D = np.abs(b[:, None] - b[None, :]) + np.eye(len(b))
    assert D.min() < 10 * eps
    P = C.period_matrix()
    Pm = np.array(C.period_matrix(dps=20).tolist(), dtype=complex)
    assert _same_basis_close(P, Pm, 1e-12)
    C2 = PlaneCurve(C._poly.sympy_expr(), C.x, C.y, _extra_sites=[0.05 + 0.031j, -0.2 + 0.11j])
    assert_same_lattice(C2.period_matrix(), P, tol=1e-12)
    tau = C.riemann_matrix()
    assert np.min(np.linalg.eigvalsh(tau.imag)) > 0


def test_nearly_symmetric_body_path_independent():
    """J2/J1 = 1 + 1e-4: two branch points near E ~ 4e3, sheets nearly equal at large E."""
    J, M, u, _ = generic_data()
    C = spectral_curve([1.0, 1.0 + 1e-4, 2.9], M, u, tol=1e-12)
    assert C.genus == 4 and not C.symmetric_body
    assert np.abs(C.branch_points).max() > 1e3
    P = C.period_matrix()
    C2 = PlaneCurve(C._poly.sympy_expr(), C.x, C.y, _extra_sites=[0.05 + 0.031j, 30.0 - 20.0j])
    assert_same_lattice(C2.period_matrix(), P, tol=1e-12)
    K = C.riemann_constant()
    assert K.shape == (4,)


def test_nearly_reducible_data_are_handled_or_refused():
    """M ~ 1e-7, u diagonal in the J frame: the curve is irreducible but within 1e-7 of reducible."""
    J = np.array([1.0, 1.7, 2.9])
    M = 1e-7 * hat([1.0, 2.0, 3.0])
    u = np.diag([0.1, 0.5, 0.9])
    C = spectral_curve(J, M, u, tol=1e-12)
    assert C.genus == 4
    P = C.period_matrix()
    tau = C.riemann_matrix()
    assert np.min(np.linalg.eigvalsh(tau.imag)) > 0
    C2 = PlaneCurve(C._poly.sympy_expr(), C.x, C.y, _extra_sites=[0.05 + 0.031j, -0.2 + 0.11j])
    assert_same_lattice(C2.period_matrix(), P, tol=1e-11)
    with pytest.raises(ValueError, match="reducible"):
        spectral_curve(J, 1e-11 * hat([1.0, 2.0, 3.0]), u)  # within the tolerance: refused as reducible


@pytest.mark.slow
def test_random_physical_spectral_curves():
    """60 random bodies and potentials (every 5th a rank-one gravity-gradient potential): genus,
    Riemann bilinear relations, path independence, Jacobi inversion with the Riemann constant."""
    from thetasol.curves.riemann_constant import theta_normalized_abs
    for seed in range(60):
        rng = np.random.default_rng(1000 + seed)
        J = np.sort(rng.uniform(0.2, 3.0, 3))
        m = rng.normal(size=3) * rng.uniform(0.1, 5)
        Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        a = rng.normal(size=(3, 3)) * rng.uniform(0.1, 5)
        a = a + a.T
        if seed % 5 == 0:
            gam = rng.normal(size=3)
            a = 3 * np.outer(gam, gam)
        C = spectral_curve(J, hat(m), -Q.T @ a @ Q)
        assert C.genus == (3 if seed % 5 == 0 else 4)
        tau = C.riemann_matrix()
        assert np.min(np.linalg.eigvalsh(tau.imag)) > 0
        K = C.riemann_constant()
        pts = []
        for i in range(C.genus):
            E0 = complex(rng.normal(), rng.normal())
            R, _ = C._poly.roots(np.array([E0]))
            pts.append((E0, R[0, i % 3]))
        A = C.abel_map(pts)
        assert theta_normalized_abs(A - A.sum(axis=0) - K, tau).max() < 1e-9
        if seed % 6 == 0:
            C2 = PlaneCurve(C._poly.sympy_expr(), C.x, C.y, _extra_sites=[0.05 + 0.031j, -0.2 + 0.11j])
            assert_same_lattice(C2.period_matrix(), C.period_matrix(), tol=1e-12)


def test_very_nearly_symmetric_body_consistent():
    """J2/J1 = 1 + 1e-6: branch points near |E| ~ 1e6 (second-order tracking keeps it cheap)."""
    J, M, u, _ = generic_data()
    C = spectral_curve([1.0, 1.0 + 1e-6, 1.7], M, u, tol=1e-12)
    assert C.genus == 4 and np.abs(C.branch_points).max() > 1e5
    K = C.riemann_constant()
    assert K.shape == (4,)
    P = C.period_matrix()
    C2 = PlaneCurve(C._poly.sympy_expr(), C.x, C.y, _extra_sites=[0.05 + 0.031j, 3e5 + 1e5j])
    assert_same_lattice(C2.period_matrix(), P, tol=1e-12)
