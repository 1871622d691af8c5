"""Theta-function rotation in a quadratic potential: every stage and the whole solution.

References nobody here wrote: long extended-precision Taylor integrations (heyoka, 80-bit, tol
1e-19, checked against quadruple precision; tests/data/rotation/make_refs.py), scipy's DOP853, and
the conserved integrals (4.9), (4.13) of the paper.
"""
import json
import pathlib

import numpy as np
import pytest
from conftest import label

from thetasol import ClosedFormUnavailable, inertia, integrate_rotation, invariants, solve_rotation
from thetasol.core.so3 import hat
from thetasol.mechanics.lax import eigenvector_poles
from thetasol.solutions.rotation.theta_rotation import ThetaRotation
from thetasol.solutions.rotation.theta_rotation.lattice import lattice_coords as _lattice_coords

REFS = json.loads((pathlib.Path(__file__).parent / "data" / "rotation" / "refs.json").read_text())
# Measured (max over the six times, largest at t = 4002): 7.4e-15 (near the stable equilibrium) to
# 7.8e-13 on most cases; fast spin 4.0e-11, symmetric fast spin 2.7e-11, near the unstable equilibrium
# 1.2e-11 (its reference is itself good to 4e-11 there, make_refs.py).  The references form the inverse
# inertia in quadruple precision: the float64 inverse of the float64 inertia is a body one ulp away, not
# integrable, and moves the near-unstable case by ~1e-9.  The symmetric fast spin needs the exact
# exponents' difference at the node (test_node_exponent_gap_is_exact_and_used): with the fitted one it
# drifts to 4.2e-9.


def _case(name):
    r = REFS[name]
    return np.diag(r["J"]), np.array(r["a"]), np.array(r["Q0"]), np.array(r["omega0"]), r


@pytest.mark.parametrize("name", [n for n in REFS])
def test_against_long_high_accuracy_integration(name):
    """Max error in omega and Q <= 1e-9 at t in {0.7, 3.1, 17.3, 102, 997, 4002}."""
    J, a, Q0, w0, r = _case(name)
    sol = solve_rotation(inertia(J), a, Q0, w0)
    assert isinstance(sol, ThetaRotation)
    t = np.array(r["t"])
    w, Q = sol(t)
    err = np.maximum(np.abs(w - np.array(r["omega"])).max(axis=1), np.abs(Q - np.array(r["Q"])).max(axis=(1, 2)))
    assert np.all(err <= 1e-9), err
    assert np.abs(np.swapaxes(Q, -1, -2) @ Q - np.eye(3)).max() < 1e-14


@pytest.mark.parametrize("name", [n for n in REFS if n.startswith("symmetric")])
def test_node_exponent_gap_is_exact_and_used(name):
    """The exponents' difference at the node over infinity (the turn about the symmetry axis) from the
    third-kind differential E^2 dE / f_w agrees with the fit from theta derivatives (to its ~1e-13
    accuracy, modulo 2 pi n.U) and replaces it: without it the fast spin drifted 1.2e-13 per unit time."""
    J, a, Q0, w0, _ = _case(name)
    sol = solve_rotation(inertia(J), a, Q0, w0)
    change = sol.diagnostics["node_gap_change"]
    assert change is not None and abs(change) <= 1e-12, change


@pytest.mark.parametrize("name", ["generic", "rank_one", "saddle"])
def test_reconstruction_at_zero_returns_the_initial_data(name):
    J, a, Q0, w0, _ = _case(name)
    sol = solve_rotation(inertia(J), a, Q0, w0)
    w, Q = sol(0.0)
    assert np.abs(Q - Q0).max() <= 1e-13 and np.abs(w - w0).max() <= 1e-13
    M, u = sol.M(0.0), sol.u(0.0)
    assert np.abs(M - hat(np.diag(np.trace(J) - np.diag(J)) @ w0)).max() <= 1e-13
    assert np.abs(u + Q0.T @ a @ Q0).max() <= 1e-13


@pytest.mark.parametrize("name", ["generic", "fast_spin", "rank_one"])
def test_integrals_4_13_are_constant_on_the_theta_solution(name):
    J, a, Q0, w0, _ = _case(name)
    sol = solve_rotation(inertia(J), a, Q0, w0)
    t = np.concatenate([np.linspace(0, 50, 401), [997.0, 4002.0, 1e5, 1e6]])
    w, Q = sol(t)
    inv = invariants(inertia(J), a, Q, w)
    # measured 2.8e-14 (generic), 3.1e-14 (fast spin), 1.4e-12 (rank one, at t = 1e6: its conjugate
    # places' phases exp(i nu t) are rounded independently) relative (the phases t u are reduced mod 1
    # before theta is summed)
    for key in ("energy", "I2", "I3"):
        v = inv[key]
        assert np.abs(v - v[0]).max() <= 1e-10 * (1 + abs(v[0])), key
    C = inv["curve"]
    assert np.abs(C - C[0]).max() <= 1e-10 * (1 + np.abs(C[0]).max())


def test_linear_flow_velocity_is_the_drift_of_the_eigenvector_divisor():
    """A(D(t)) = A(D(0)) - t U: U from the expansions at infinity, D(t) from numerically integrated L."""
    J, a, Q0, w0, _ = _case("generic")
    sol = solve_rotation(inertia(J), a, Q0, w0)
    curve, tau, U, alpha = sol.curve, sol.riemann_matrix, sol.U, sol.alpha
    Jp = np.sqrt(curve.J2)
    Pf = sol.evaluator.P
    # the documented basis: the curve's periods times sol.basis give tau
    g = curve.genus
    Pn = curve.period_matrix() @ sol.basis
    assert np.abs(np.linalg.solve(Pn[:, :g], Pn[:, g:]) - tau).max() < 1e-12

    def abel_D(M, u):
        E, w = eigenvector_poles(Jp, M, u, alpha)
        return sol.abel_map([(complex(x), complex(y)) for x, y in zip(E, w)]).sum(0)

    A0 = abel_D(curve.M, curve.u)
    # abel_divisor may come from another normalization (linearly equivalent divisor): equal mod lattice
    x1, x2 = _lattice_coords(A0 - sol.abel_divisor, tau)
    x = np.concatenate([x1, x2])
    assert np.abs(x - np.round(x)).max() < 1e-11
    for t in (0.4, 1.7):
        w, Q = integrate_rotation(inertia(J), a, Q0, w0, rtol=1e-13)(np.array([t]))
        wp, Qp = Pf.T @ w[0], Q[0] @ Pf
        M = hat(np.diag(Jp.sum() - Jp) @ wp)
        u = -(Qp.T @ a @ Qp)
        drift = abel_D(M, u) - A0 + t * U
        x1, x2 = _lattice_coords(drift, tau)
        x = np.concatenate([x1, x2])
        assert np.abs(x - np.round(x)).max() < 1e-9


def test_adapted_basis_makes_the_flow_real_on_the_prym():
    J, a, Q0, w0, _ = _case("generic")
    sol = solve_rotation(inertia(J), a, Q0, w0)
    assert sol.diagnostics["torus_dimension"] == 3          # the Prym variety of the genus-4 curve
    assert np.all(np.isreal(sol.U)) and sol.U[3] == 0
    tau = sol.riemann_matrix
    assert np.abs(tau - tau.T).max() < 1e-14 and np.linalg.eigvalsh(tau.imag).min() > 0
    J1, a1, Q01, w01, _ = _case("rank_one")
    sol1 = solve_rotation(inertia(J1), a1, Q01, w01)
    assert sol1.diagnostics["torus_dimension"] == 2 and sol1.curve.genus == 3


def test_baker_akhiezer_function_at_generic_points():
    """The vector BA function Phi(E, t) psi(P) at points over E = 0.3 against DOP853.

    Phi(0, t) = Q(t)^T Q0 is what the solution evaluates; this checks the same theta quotients
    at other points of the curve, where the places over E = 0 play no role.
    """
    J, a, Q0, w0, _ = _case("saddle")
    sol = solve_rotation(inertia(J), a, Q0, w0)
    c = sol.evaluator
    t = np.array([0.5, 2.0, 6.0])
    w, Q = integrate_rotation(inertia(J), a, Q0, w0, rtol=1e-13)(t)
    Pf = c.P
    Phi_num = np.swapaxes(Q @ Pf, -1, -2) @ c.Q0p
    Phi, _ = sol.evaluator.phi0(t, derivative=False)
    assert np.abs(Phi.imag).max() < 1e-11
    assert np.abs(Phi.real - Phi_num).max() < 1e-11


def test_far_times_cost_nothing_extra_and_stay_on_the_invariant_torus():
    J, a, Q0, w0, _ = _case("generic")
    sol = solve_rotation(inertia(J), a, Q0, w0)
    t = np.array([1.0, 1e6, 1e6 + 1.0, 3.3e7])
    w, Q = sol(t)
    assert np.all(np.isfinite(w)) and np.abs(np.swapaxes(Q, -1, -2) @ Q - np.eye(3)).max() < 1e-14
    inv = invariants(inertia(J), a, Q, w)
    assert np.abs(inv["energy"] - inv["energy"][0]).max() < 1e-9
    # Im Phi(0, t) must vanish; it grows linearly with the accuracy of the precession frequencies
    # (measured ~1.3e-13 per unit time, dominated by small eigenvector components; the error of Q
    # itself at t = 4002 is 2e-12, see the reference test)
    assert np.all(sol.imaginary_residual(t) <= 1e-12 * (1 + t))


def test_general_body_frame_and_shapes():
    """J given as a non-principal tensor: the principal frame is internal, results map back."""
    rng = np.random.default_rng(4)
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    R *= np.linalg.det(R)
    J = R @ np.diag([0.6, 1.0, 1.7]) @ R.T
    a = rng.normal(size=(3, 3))
    a = a + a.T
    Q0 = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    Q0 *= np.linalg.det(Q0)
    w0 = rng.normal(size=3)
    sol = solve_rotation(inertia(J), a, Q0, w0)
    t = np.array([[0.3, 1.1], [7.0, 20.0]])
    w, Q = sol(t)
    assert w.shape == (2, 2, 3) and Q.shape == (2, 2, 3, 3) and sol.M(t).shape == (2, 2, 3, 3)
    wr, Qr = integrate_rotation(inertia(J), a, Q0, w0, rtol=1e-13)(t)
    assert np.abs(Q - Qr).max() < 1e-10 and np.abs(w - wr).max() < 1e-10


def test_symmetric_body_with_little_axial_spin_says_what_is_missing():
    """No axial spin goes to Neumann's problem (tests/test_neumann.py); a little spin (a curve near
    a tacnode, branch points near |E| ~ 1 / spin) is refused at once, naming the cause."""
    J, a = [0.5, 0.5, 1.2], np.diag([1.0, 2.0, 3.0])
    sol = solve_rotation(inertia(J), a, np.eye(3), [0.1, 0.2, 0.0])
    assert type(getattr(sol, "inner", sol)).__name__ == "NeumannRotation"
    with pytest.raises(ClosedFormUnavailable, match="tacnode"):
        solve_rotation(inertia(J), a, np.eye(3), [0.1, 0.2, 1e-5])


def test_symmetric_body_as_a_tensor_against_dop853():
    """A symmetric body given by a non-diagonal J (symmetry axis off the coordinate axes): the
    turning frame is built in the principal frame and mapped back."""
    R = np.linalg.qr(np.random.default_rng(5).normal(size=(3, 3)))[0]
    J = R @ np.diag([0.9, 0.5, 0.9]) @ R.T
    a = np.array([[0.3, -0.2, 0.1], [-0.2, -0.4, 0.25], [0.1, 0.25, 0.6]])
    Q0, w0 = R.T, np.array([0.3, -0.6, 0.45])
    sol = solve_rotation(inertia(J), a, Q0, w0)
    assert label(sol) == "theta/genus-3:symmetric"
    t = np.array([0.0, 2.5, 40.0])
    w, Q = sol(t)
    wr, Qr = integrate_rotation(inertia(J), a, Q0, w0, rtol=1e-13)(t)
    assert np.abs(w[0] - w0).max() <= 1e-13 and np.abs(Q[0] - Q0).max() <= 1e-13
    assert max(np.abs(w - wr).max(), np.abs(Q - Qr).max()) <= 1e-10


def test_symmetric_body_conserves_its_axial_spin():
    J, a, Q0, w0, _ = _case("symmetric_oblate")
    w = solve_rotation(inertia(J), a, Q0, w0).omega(np.linspace(0.0, 500.0, 41))
    assert np.abs(w[:, 2] - w0[2]).max() <= 1e-12


def test_splitting_integrator_agrees():
    """Independent check with the symplectic splitting (structure preserving) over a few periods."""
    J, a, Q0, w0, _ = _case("saddle")
    sol = solve_rotation(inertia(J), a, Q0, w0)
    t = np.array([5.0, 20.0])
    w, Q = sol(t)
    wr, Qr = integrate_rotation(inertia(J), a, Q0, w0, method="splitting", step=2e-3)(t)
    assert np.abs(Q - Qr).max() < 1e-9


def test_spectral_coefficients_are_exact_for_the_floats_given():
    # near an equilibrium |M|^2 ~ 1e-6 rides on O(1) terms: float64 coefficients lose it (U 3e-11 off)
    from fractions import Fraction

    import sympy as sp

    from thetasol.curves.spectral import spectral_curve
    rng = np.random.default_rng(11)
    J = np.array([0.6, 1.0, 1.7])
    M = hat(1e-3 * rng.normal(size=3))
    u = rng.normal(size=(3, 3))
    u = 0.5 * (u + u.T)
    C = spectral_curve(J, M, u, tol=1e-12)
    E, w = sp.symbols("E w")
    R = lambda x: sp.Rational(*Fraction(float(x)).as_integer_ratio())  # noqa: E731
    L = sp.Matrix(3, 3, lambda i, j: (R(J[i]) ** 2 * E ** 2 if i == j else 0) + R(M[i, j]) * E + R(u[i, j])
                  - (w if i == j else 0))
    exact = sp.Poly(sp.expand(L.det()), E, w)
    got = sp.Poly(C.polynomial(), E, w)
    for (k, l), c in exact.terms():
        if k % 2 == 0:
            assert got.coeff_monomial(E ** k * w ** l) == c


def test_flow_velocity_divided_difference_equals_the_sum_over_the_places():
    # the closed form of sum_j J_j omega_i / ds (inf_j) against the plain sum of the per-place values
    # -h_i(x_j) / (lc prod_{l != j} (x_j - x_l)), well conditioned for well separated J
    import sympy as sp

    from thetasol.curves.spectral import spectral_curve
    from thetasol.solutions.rotation.theta_rotation.infinity import (
        infinity_data as _infinity_data,
        velocity_at_infinity as _velocity_at_infinity,
    )
    J, a, Q0, w0, _ = _case("generic")
    C = spectral_curve(J, hat(J @ w0), -(Q0.T @ a @ Q0), tol=1e-12)
    nums = C.holomorphic_differentials()
    Pinf, Jinf, _ = _infinity_data(C, C.J2, C.M)
    x = Jinf ** 2
    lc = float(sp.Poly(C.polynomial(), C.y).LC())
    direct = np.zeros(len(nums))
    for i, gn in enumerate(nums):
        terms = sp.Poly(sp.sympify(gn), C.x, C.y).terms()
        for j in range(3):
            h = sum(float(cf) * x[j] ** mw for (me, mw), cf in terms if me + 2 * mw == 2)
            direct[i] += -Jinf[j] * h / (lc * np.prod([x[j] - x[l] for l in range(3) if l != j]))
    closed = _velocity_at_infinity(C, C.holomorphic_numerators())
    assert np.abs(closed - direct).max() <= 1e-12 * np.abs(direct).max()


def test_nearly_symmetric_bodies_down_to_the_refusal_limit():
    # J2 / J1 = 1 + 1e-3 .. 1 + 2e-7 on these data: accurate and silent (measured 8.7e-12 .. 8e-13 at
    # t = 997 against heyoka).  The small gap puts branch points in tight clusters: an error in the
    # curve engine's cluster handling shows here as ~1e-7 or a refusal.  A relative gap below 1e-7 (of
    # max J) is refused at once: from 3e-8 down random bodies stop in the set-up or run for minutes.
    import warnings

    from thetasol.core.so3 import rodrigues
    rng = np.random.default_rng(3)
    a = rng.normal(size=(3, 3))
    a = 0.5 * (a + a.T)
    Q0, w0 = rodrigues(np.array([0.3, -0.5, 0.2])), np.array([0.4, -0.7, 0.5])
    t = np.array([3.1, 102.0])
    for dl in (1e-3, 1e-5, 2e-7):
        J = np.array([0.8, 0.8 * (1 + dl), 1.5])
        with warnings.catch_warnings(record=True) as rec:
            warnings.simplefilter("always")
            sol = solve_rotation(inertia(J), a, Q0, w0)
        assert not [r for r in rec if "set-up lost accuracy" in str(r.message)]
        w, Q = sol(t)
        wr, Qr = integrate_rotation(inertia(J), a, Q0, w0, rtol=1e-13)(t)
        assert max(np.abs(w - wr).max(), np.abs(Q - Qr).max()) <= 1e-9
    with pytest.raises(ClosedFormUnavailable, match="nearly symmetric body"):
        solve_rotation(inertia(np.array([0.8, 0.8 * (1 + 1e-7), 1.5])), a, Q0, w0)


def test_nearly_symmetric_body_with_far_cell_vertices_against_dop853():
    """J gap 2.3e-7 relative (a random body of the hidden-case sweep, seed 7): the cells of the critical
    values next to E = +-1.2 have vertices at |E| ~ 1e7.  A line from there computed as a + (b - a) ends
    ~eps |a| = 2e-9 off the circle's start b next to a branch point, where y is then 2e-7 off and the
    set-up stops ('starting value ... is not a root'); lines end exactly at b.  Measured 2.8e-12 at
    t = 4002 against heyoka 80-bit."""
    J = np.array([0.44747052264601117, 0.44747052264601117 * (1 + 1e-6), 1.940866823715262])
    a = np.array([[-1.1140671431510563, 0.5773031540758372, 0.11239990014646231],
                  [0.5773031540758372, 0.6530885027011638, -0.18200658236154083],
                  [0.11239990014646231, -0.18200658236154083, 1.052126358426947]])
    Q0 = np.array([[0.9736408255636728, 0.17051144044330785, -0.15149056562584304],
                   [-0.21246648833665566, 0.9195823062716068, -0.33049413508575726],
                   [0.08295501268506533, 0.35396925102350524, 0.9315708428242478]])
    w0 = np.array([-0.0061489657274877, 0.6643499943849732, -1.4700563260729687])
    _check_against_dop853(J, a, Q0, w0, "theta/genus-4", [0.0, 3.1, 17.3], 1e-12)       # measured 1.2e-13


def test_symmetric_body_with_little_axial_spin_is_refused_at_once(monkeypatch):
    # below MIN_AXIAL_SPIN (relative) the curve engine's set-up grows to minutes: refused before the curve
    # (the message of a failed set-up also says "little spin": the curve must not be built at all)
    import thetasol.solutions.rotation.theta_rotation.spectral_data as tr
    from thetasol.solutions.rotation.theta_rotation import MIN_AXIAL_SPIN

    def no_curve(*args, **kwargs):
        raise AssertionError("the spectral curve was built")

    monkeypatch.setattr(tr, "spectral_curve", no_curve)
    scale = np.linalg.norm([0.3, 0.2]) + 3.0 ** 0.5
    with pytest.raises(ClosedFormUnavailable, match="little spin"):
        solve_rotation(inertia([0.5, 0.5, 1.2]), np.diag([1.0, 2.0, 3.0]), np.eye(3), [0.3, 0.2, 0.5 * MIN_AXIAL_SPIN * scale])


def test_nearly_spherical_symmetric_body_with_small_spin_is_refused_at_once(monkeypatch):
    """J gap 0.25 %, axial spin 1e-3 relative: branch points at |E| ~ 4.2e4 sqrt|a| / J (with the guard
    lifted the set-up takes 4.8 s CPU; at spin 3e-4, 1.4e5, the curve alone takes 114 s): refused
    before the curve is built."""
    import thetasol.solutions.rotation.theta_rotation.spectral_data as tr

    def no_curve(*args, **kwargs):
        raise AssertionError("the spectral curve was built")

    monkeypatch.setattr(tr, "spectral_curve", no_curve)
    a = np.array([[0.84, 0.58, 1.74], [0.58, -1.57, 1.02], [1.74, 1.02, -2.47]])
    with pytest.raises(ClosedFormUnavailable, match="branch points of its spectral curve"):
        solve_rotation(inertia([1.0, 1.0025, 1.0]), a, np.eye(3), [-0.9, 0.003, -0.6])


def _small_spin_body(spin):
    from thetasol.core.so3 import rodrigues

    r = np.random.default_rng(6).normal(size=(3, 3))
    return np.diag([0.6, 0.6, 1.1]), r + r.T, rodrigues(np.array([0.3, -0.5, 0.2])), np.array([0.3, 0.2, spin])


@pytest.mark.parametrize("spin", [3e-3, 1e-3])
def test_symmetric_body_with_small_axial_spin_against_heyoka(spin):
    """Axial spin 1.2e-3 and 4.1e-4 of |omega0| + sqrt|a|, branch points at |E| ~ 750 and 2250.  The
    orders of the canonical divisor at the node's branches are read off scaled Laurent coefficients
    (unscaled ones grow like spin^-k and give a divisor of degree 8: the set-up stops); U and the
    exponent gap come from the exact relations (from the expansions at the node the second body is
    1.5e-8 off at t = 4002; with fitted exponents and float64 periods 1.7e-11 and 8.9e-12).  Measured
    1.4e-13 and 2.5e-13 against heyoka 80-bit."""
    _check_against_heyoka(*_small_spin_body(spin), "theta/genus-3:symmetric", 2e-12)


def _check_against_heyoka(J, a, Q0, w0, method, tol):
    """max error in omega and Q at t in {0.7, ..., 4002} against heyoka 80-bit at most tol."""
    pytest.importorskip("heyoka")
    sol = solve_rotation(inertia(J), a, Q0, w0)
    assert label(sol) == method
    t = np.array([0.7, 3.1, 17.3, 102.0, 997.0, 4002.0])
    wr, Qr = integrate_rotation(inertia(J), a, Q0, w0, rtol=1e-19, method="heyoka", fp_type=np.longdouble)(t)
    w, Q = sol(t)
    err = np.maximum(np.abs(w - wr).max(axis=1), np.abs(Q - Qr).max(axis=(1, 2)))
    assert np.all(err <= tol), err


def _rank_one_symmetric_body(spin):
    from thetasol.core.so3 import rodrigues

    n = np.array([0.47, -0.87, 0.105])
    n /= np.linalg.norm(n)
    return np.diag([1.17, 1.17, 0.52]), -1.3 * np.outer(n, n), rodrigues(np.array([0.7, -0.2, 0.4])), \
        np.array([-0.93, -0.49, spin])


@pytest.mark.parametrize("name", ["generic", "fast_spin", "rank_one", "symmetric_oblate", "symmetric_rank_one",
                                  "spin 1.5e-3"])
def test_exponents_obey_the_exact_relations(name):
    """The exponents nu_sk = F_s - G_k are fixed by sigma: (E, w) -> (-E, w) (nu_{sigma s, sigma k} =
    -nu_sk modulo 2 pi n.U; without nodes every one is a half lattice rate) and by the third-kind rates of
    the nodes.  The least-squares fit from theta derivatives, independent of those relations, must agree
    with them to its accuracy; the exact values then replace it.  Measured changes 1.0e-15 .. 2.1e-13
    (the small-spin body; fast spin 3.9e-14, 4.8e-13 with float64 periods)."""
    J, a, Q0, w0 = _rank_one_symmetric_body(1.5e-3) if name == "spin 1.5e-3" else _case(name)[:4]
    sol = solve_rotation(inertia(J), a, Q0, w0)
    change = sol.diagnostics["nu_exact_change"]
    assert change is not None and change <= 2e-11, change
    nu = sol.evaluator.nu
    assert np.abs(nu - nu[:, :1] - nu[:1, :] + nu[0, 0]).max() <= 1e-14 * np.abs(nu).max()


def test_symmetric_rank_one_small_axial_spin_against_heyoka():
    """Rank-one a, axial spin 3.3e-4 of |omega0| + sqrt|a|.  With the exponents fitted from theta
    derivatives (circle means at the node's branches biased by ~1e-12) the attitude drifts linearly,
    2.1e-9 at t = 4002 against heyoka 80-bit; with the exact relations but float64 periods 1.6e-11.
    Measured (exact relations, periods summed in double-double) 4.0e-12."""
    _check_against_heyoka(*_rank_one_symmetric_body(7.3e-4), "theta/genus-2:symmetric-nodal", 8e-12)


def test_node_velocity_closed_form_against_a_contour_integral():
    """sum_j J_j (g_i dE / f_w) / dt at the places over E = infinity (t = 1/E) for a symmetric body with
    axial spin 1e-3: the closed form (Euler-Jacobi) against the t^0 coefficient of the sum over the
    node's two sheets, a function single-valued and holomorphic outside the core branch points (the far
    pair at |E| ~ 2e3 only swaps the two sheets), integrated on |E| = 3 max|core|.  FFT expansions at
    the node's branches lose 5e-12 of it."""
    import sympy as sp

    from thetasol.core.inertia import inertia_from_moments
    from thetasol.curves.spectral import spectral_curve
    from thetasol.solutions.rotation.theta_rotation.infinity import (
        infinity_data as _infinity_data,
        velocity_at_infinity as _velocity_at_infinity,
    )

    J, a, Q0, w0 = _small_spin_body(1e-3)
    C = spectral_curve(J, hat(inertia_from_moments(J) @ w0), -(Q0.T @ a @ Q0), tol=1e-12)
    nums = C.holomorphic_differentials()
    Pinf, Jinf, _ = _infinity_data(C, C.J2, C.M)
    closed = _velocity_at_infinity(C, C.holomorphic_numerators())
    bp = np.sort(np.abs(C.branch_points))
    assert bp[-1] > 300 * bp[-3]                      # the far pair
    E = 3 * bp[-3] * np.exp(2j * np.pi * np.arange(64) / 64)
    W = np.linalg.eigvals(np.diag(C.J2)[None] * E[:, None, None] ** 2 + C.M[None] * E[:, None, None] + C.u[None])
    x = C.J2
    fw = sp.lambdify((C.x, C.y), sp.diff(C.polynomial(), C.y))
    direct = np.zeros(len(nums), complex)
    for i, gn in enumerate(nums):
        g = sp.lambdify((C.x, C.y), sp.sympify(gn))
        h = g(E[:, None], W) / fw(E[:, None], W) * (-E[:, None] ** 2)      # g dE / f_w = h dt
        Jw = np.sqrt(x[np.argmin(np.abs(W[..., None] / E[:, None, None] ** 2 - x), axis=-1)])
        direct[i] = (Jw * h).sum(axis=1).mean()
    assert np.abs(direct.imag).max() <= 1e-13
    assert np.abs(closed - direct.real).max() <= 1e-13 * np.abs(closed).max()


@pytest.mark.parametrize("seed", range(4))
def test_random_symmetric_bodies_against_dop853(seed):
    """Random symmetric bodies (either axis, random a, attitude, spin).  Measured on these four at
    t <= 40: 7.5e-14..1.2e-12 from DOP853 at rtol 1e-13, 1.5e-14..1.7e-13 from heyoka 80-bit (and
    worst 3.7e-11 from DOP853 on 16 other random cases)."""
    from thetasol.core.so3 import rodrigues

    rng = np.random.default_rng([2026, seed])
    j = rng.uniform(0.3, 1.5, 2)
    J = np.array([j[0], j[0], j[1]])[rng.permutation(3)]
    r = rng.normal(size=(3, 3))
    a = (r + r.T) * rng.uniform(0.2, 2.0)
    Q0, w0 = rodrigues(rng.normal(size=3)), rng.normal(size=3) * rng.uniform(0.2, 3.0)
    sol = solve_rotation(inertia(J), a, Q0, w0)
    assert label(sol) == "theta/genus-3:symmetric"
    t = np.array([0.0, 1.3, 7.7, 40.0])
    w, Q = sol(t)
    wr, Qr = integrate_rotation(inertia(J), a, Q0, w0, rtol=1e-13)(t)
    assert max(np.abs(w - wr).max(), np.abs(Q - Qr).max()) <= 1e-10


@pytest.mark.parametrize("turn", [None, (2, 0.7), (0, -1.1)])
def test_principal_axes_along_eigenvectors_of_a(turn):
    """J and a diagonal, Q0 = 1 or a turn about one axis: some e_k is an eigenvector of u, the zeros of
    v_k sit at places over E = 0 with no w of their own.  These are the README's example data: the
    set-up must handle those zeros, not refuse the data (ClosedFormUnavailable).  Measured against
    heyoka 80-bit at t <= 4002: 5.3e-13, 6.3e-13, 7.4e-12."""
    from thetasol.core.so3 import rotation_about

    J, a, w0 = [0.6, 1.0, 1.7], np.diag([-1.0, 0.4, 1.5]), np.array([0.5, -0.8, 0.6])
    Q0 = np.eye(3) if turn is None else rotation_about(*turn)
    _check_against_dop853(J, a, Q0, w0, "theta/genus-4", [0.0, 3.1, 40.0], 1e-10)


def _check_against_dop853(J, a, Q0, w0, method, t, tol):
    sol = solve_rotation(inertia(J), a, Q0, w0)
    assert label(sol) == method
    w, Q = sol(np.array(t))
    wr, Qr = integrate_rotation(inertia(J), a, Q0, w0, rtol=1e-13)(np.array(t))
    assert max(np.abs(w - wr).max(), np.abs(Q - Qr).max()) <= tol


# rank-one a whose node at E = 0 has branch points at |E| = 0.031 (a random body of the hidden-case sweep)
_NODE_NEAR_BRANCH = (
    np.array([0.29082610749882637, 0.5294277466977709, 1.7154120507534654]),
    np.array([[-0.1517545567491876, 0.3465694865962838, -0.5134987996262976],
              [0.3465694865962838, -0.7914781052546861, 1.1727029432692584],
              [-0.5134987996262976, 1.1727029432692584, -1.7375492562865669]]),
    np.array([[-0.9829870525000257, -0.17178036248650932, -0.06502277817284462],
              [0.15726593164040023, -0.9700344426196177, 0.18520423018096602],
              [-0.09488878417699563, 0.17182749254892463, 0.9805464963181302]]),
    np.array([-2.681202624341547, -0.9878231959234417, -1.598377742050736]))


def test_node_branch_eigenvectors_against_mpmath():
    """On the node's branches over E = 0, L(E) - w has two rows parallel to O(E): the float64 null vector
    of L(E) carries ~eps |L| / |E|.  The scaled eigenproblem of _node_branch is accurate to eps.  Reference:
    mpmath (40 digits) with u exactly lam 1 + lam_n n n^T (the snapped rank-one structure; the float64
    entries of u alone split the node by ~eps), at |E| = 1e-2 .. 1e-6; the plain float64 eigenvector is
    the foil."""
    import mpmath

    from thetasol.mechanics.lax import lax_matrix, right_eigenvector
    from thetasol.solutions.rotation.theta_rotation.node import node_branch as _node_branch, node_slopes as _node_slopes

    curve = solve_rotation(inertia(_NODE_NEAR_BRANCH[0]), *_NODE_NEAR_BRANCH[1:]).curve
    lb = curve.node[1]
    lam, V = np.linalg.eigh(curve.u)
    k = int(np.argmax(np.abs(lam - lb)))
    Es = np.array([1e-2, 1e-4, 1e-6]) * np.exp(0.7j)
    L = lax_matrix(np.sqrt(curve.J2), curve.M, curve.u, Es)
    worst_node, worst_plain, worst_w = 0.0, 0.0, 0.0
    with mpmath.workdps(40):
        n = mpmath.matrix(V[:, k].tolist())
        n = n / mpmath.norm(n)
        u = float(lb) * mpmath.eye(3) + float(lam[k] - lb) * (n * n.T)
        for mu in _node_slopes(curve):
            w, v = _node_branch(curve, mu, Es)
            for i, E in enumerate(Es):
                Em = mpmath.mpc(complex(E))
                Lm = u + Em * mpmath.matrix(curve.M.tolist()) + Em**2 * mpmath.diag([float(x) for x in curve.J2])
                ev, X = mpmath.eig(Lm)
                j = min(range(3), key=lambda q: abs(complex(ev[q]) - w[i]))
                x = np.array([complex(X[q, j]) for q in range(3)])
                x /= np.linalg.norm(x)
                worst_w = max(worst_w, abs(complex(ev[j]) - w[i]) / abs(E))
                for y, node in ((v[i], True), (right_eigenvector(L[i], w[i]), False)):
                    ph = (y @ x.conj()) / abs(y @ x.conj())
                    err = np.abs(y - ph * x).max()
                    worst_node, worst_plain = (max(worst_node, err), worst_plain) if node else \
                        (worst_node, max(worst_plain, err))
    # measured: w to 3.3e-16 |E|, eigenvector 4.6e-16; the plain float64 eigenvector 2.3e-10 (|E| = 1e-6)
    assert worst_w <= 1e-14 and worst_node <= 1e-14 < 1e-12 < worst_plain, (worst_w, worst_node, worst_plain)


def test_rank_one_node_next_to_branch_points_against_dop853():
    """The Cauchy circles around the places over E = 0 are small here (r = 8e-5: every zero of the
    eigenvector components lies outside the largest admissible radius), where plain float64
    eigenvectors on the node's branches lose eps / r: 1.9e-11 at t = 17.3 and 3.7e-9 at t = 4002
    against heyoka 80-bit.  With the node's scaled eigenproblem (and the exact exponents) measured
    1.6e-14 and 1.5e-12.  DOP853 at rtol 1e-13 is itself 3.5e-13 off here."""
    _check_against_dop853(*_NODE_NEAR_BRANCH, "theta/genus-3:nodal", [0.0, 3.1, 17.3], 1e-12)


@pytest.mark.parametrize("name", ["generic", "nearly_symmetric", "near_unstable_equilibrium", "rank_one",
                                  "symmetric_oblate", "symmetric_rank_one"])
def test_riemann_constant_from_stage_two_divisors_matches_the_fallback_divisors(name, monkeypatch):
    """Riemann's vanishing theorem on the divisors made of stage 2's points (poles and component zeros)
    picks the same half-period candidate as on the three divisors of the fixed table of test points, and
    decides on its own (without the table's divisors)."""
    from thetasol.solutions.rotation.theta_rotation import riemann as stage3
    from thetasol.solutions.rotation.theta_rotation.divisors import eigenvector_divisors
    from thetasol.solutions.rotation.theta_rotation.frame import body_frame
    from thetasol.solutions.rotation.theta_rotation.spectral_data import spectral_data

    J, a, Q0, w0, _ = _case(name)
    sd = spectral_data(body_frame(J, a, Q0, w0))
    dv = eigenvector_divisors(sd)
    canon = stage3.canonical_divisor(sd)
    K_table = stage3.riemann_constant(sd, canon)            # no stage 2 data: the table's divisors

    def no_fallback(*args):
        raise AssertionError("the stage 2 divisors did not decide: fell back to the table's divisors")

    monkeypatch.setattr(stage3, "_table_divisor_constant", no_fallback)
    K_stage2 = stage3.riemann_constant(sd, canon, dv)
    # the same candidate: the two differ only by the rounding of A(canonical divisor) / 2
    assert np.abs(K_stage2 - K_table).max() < 1e-13
