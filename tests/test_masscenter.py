"""The closed-form mass centre against mpmath's matrix exponential of the first-order system.

Reference: d/dt (q, v, 1) = [[0, 1, 0], [-a, 0, -b/2], [0, 0, 0]] (q, v, 1), exponentiated by
mpmath.expm at 40 digits: no eigen-decomposition, no case split by eigenvalue sign.
"""
import dataclasses

import mpmath
import numpy as np
import pytest
from conftest import label
from hypothesis import given, settings, strategies as st

from thetasol.core.so3 import rodrigues
from thetasol.protocol import CHUNK, Solution
from thetasol.solutions.points.mass_center import MassCenterMotion, solve_mass_center


def expm_reference(a, b, q0, v0, t, dps=40):
    ctx = mpmath.MPContext()
    ctx.dps = dps
    A = ctx.zeros(7, 7)
    for i in range(3):
        A[i, 3 + i] = 1
        A[3 + i, 6] = -ctx.mpf(float(b[i])) / 2
        for j in range(3):
            A[3 + i, j] = -ctx.mpf(float(a[i, j]))
    y0 = ctx.matrix([float(x) for x in q0] + [float(x) for x in v0] + [1])
    out = []
    for tk in np.atleast_1d(t):
        y = ctx.expm(A * ctx.mpf(float(tk))) * y0
        out.append([y[i] for i in range(6)])
    return out


def to_float(rows):
    return np.array([[float(x) for x in r] for r in rows])


def matrix_with_eigenvalues(lam, rotvec):
    R = rodrigues(np.asarray(rotvec, dtype=float))
    return R @ np.diag(lam) @ R.T


@pytest.mark.parametrize("lam", [
    [1.0, 2.5, 0.3],          # trigonometric
    [-1.0, -0.4, -2.0],       # hyperbolic
    [0.0, 0.0, 0.0],          # polynomial
    [1.3, -0.7, 0.0],         # all three
    [1.0, 1.0 + 1e-13, 2.0],  # nearly degenerate eigenvalues
])
def test_against_matrix_exponential(lam):
    rng = np.random.default_rng(0)
    a = matrix_with_eigenvalues(lam, [0.4, -1.1, 0.7])
    b, q0, v0 = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
    t = np.array([0.0, 0.37, 1.0, -2.2, 5.0])
    q, v = solve_mass_center(a, b, q0, v0)(t)
    ref = to_float(expm_reference(a, b, q0, v0, t))
    scale = 1 + np.max(np.abs(ref), axis=1, keepdims=True)
    err = np.max(np.abs(np.concatenate([q, v], axis=1) - ref) / scale)
    assert err < 2e-15 * (1 + np.max(np.abs(t)) * np.sqrt(np.max(np.abs(lam))) * 4)


@settings(max_examples=60, deadline=None)
@given(eps=st.one_of(st.sampled_from([0.0, 5e-324, -5e-324, 1e-300, -1e-300, 1e-17, -1e-17]),
                     st.floats(-1e-3, 1e-3)),
       t=st.floats(-20, 20), seed=st.integers(0, 2**16))
def test_eigenvalue_through_zero(eps, t, seed):
    """Accurate on both sides of and at a zero eigenvalue, any b, including the secular t^2 term."""
    rng = np.random.default_rng(seed)
    a = matrix_with_eigenvalues([0.8, eps, -0.3], rng.normal(size=3))
    b, q0, v0 = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
    q, v = solve_mass_center(a, b, q0, v0)(t)
    ref = to_float(expm_reference(a, b, q0, v0, [t], dps=30))[0]
    scale = 1 + np.max(np.abs(ref))
    # error budget: eigh backward error (~1e-16 |a|) times the sensitivity t^2 |b|, plus round-off
    assert np.max(np.abs(np.concatenate([q, v]) - ref)) < 4e-15 * scale * (1 + abs(t)) ** 2


def test_continuous_in_the_eigenvalue():
    """q(t) is analytic in lam: the values at +-d straddle the value at 0 within O(d t^4)."""
    a0, q0, v0, b = np.zeros((3, 3)), np.array([1.0, 2, 3]), np.array([0.5, -1, 2]), np.array([1.0, 0, -1])
    t = 3.0
    q_zero, _ = solve_mass_center(a0, b, q0, v0)(t)
    # exact polynomial motion at lam = 0: q0 + v0 t - b t^2 / 4
    assert np.allclose(q_zero, q0 + v0 * t - b * t**2 / 4, rtol=0, atol=1e-14)
    for d in (1e-6, 1e-10, 1e-14):
        qp, _ = solve_mass_center(d * np.eye(3), b, q0, v0)(t)
        qm, _ = solve_mass_center(-d * np.eye(3), b, q0, v0)(t)
        assert np.all(np.abs(qp - q_zero) <= 2 * d * t**4 * 3 + 1e-14)
        # the odd part in lam cancels: what is left is O(d^2) or round-off
        assert np.all(np.abs(0.5 * (qp + qm) - q_zero) <= d**2 * t**8 + 1e-14)


def test_shapes_energy_and_modes():
    rng = np.random.default_rng(3)
    a = matrix_with_eigenvalues([1.0, -0.5, 0.0], rng.normal(size=3))
    mc = MassCenterMotion(a, rng.normal(size=3), rng.normal(size=3), rng.normal(size=3))
    assert mc.kinds == ("hyperbolic", "polynomial", "trigonometric")
    assert len(mc.describe()) == 3
    q, v = mc(1.5)
    assert q.shape == (3,) and v.shape == (3,)
    t = np.linspace(-3, 3, 12).reshape(3, 4)
    q, v = mc(t)
    assert q.shape == (3, 4, 3) and v.shape == (3, 4, 3)
    q1, _ = mc(t[1, 2])
    assert np.allclose(q1, q[1, 2], rtol=0, atol=1e-15)
    E = mc.energy(q, v)
    assert np.max(np.abs(E - E.flat[0])) < 1e-13 * (1 + np.max(np.abs(v)) ** 2)


def test_mpmath_path():
    rng = np.random.default_rng(5)
    a = matrix_with_eigenvalues([0.9, -0.2, 0.0], rng.normal(size=3))
    b, q0, v0 = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
    before = mpmath.mp.dps
    t = [0.0, 0.5, 4.0]  # t = 0 with a hyperbolic mode: sinh(x)/x at x = 0
    q, v = solve_mass_center(a, b, q0, v0, dps=35)(np.array(t))
    assert mpmath.mp.dps == before
    assert q.shape == (3, 3) and isinstance(q[0, 0], mpmath.mpf)
    ref = expm_reference(a, b, q0, v0, t, dps=45)
    for k in range(3):
        for i in range(3):
            assert abs(q[k, i] - ref[k][i]) < mpmath.mpf(10) ** -30
            assert abs(v[k, i] - ref[k][3 + i]) < mpmath.mpf(10) ** -30


def test_bad_input_and_overflow():
    good = dict(a=np.eye(3), b=np.zeros(3), q0=np.zeros(3), v0=np.zeros(3))
    with pytest.raises(ValueError, match="symmetric"):
        MassCenterMotion(**{**good, "a": [[1, 2, 0], [0, 1, 0], [0, 0, 1]]})
    with pytest.raises(ValueError, match="NaN"):
        MassCenterMotion(**{**good, "b": [0, np.nan, 0]})
    with pytest.raises(ValueError, match="shape"):
        MassCenterMotion(**{**good, "q0": [0, 0]})
    with pytest.raises(ValueError, match="NaN"):
        MassCenterMotion(**good)(np.array([1.0, np.inf]))
    mc = MassCenterMotion(**{**good, "a": -np.eye(3), "q0": [1, 0, 0]})
    with pytest.raises(OverflowError, match="dps"):
        mc(1000.0)
    q, _ = mc(1000.0, dps=20)  # the mpmath path has no overflow
    assert q[0] > mpmath.mpf(10) ** 400


def test_solution_protocol():
    rng = np.random.default_rng(7)
    a = matrix_with_eigenvalues([1.3, -0.7, 0.0], [0.2, 0.5, -0.9])
    mc = MassCenterMotion(a, rng.normal(size=3), rng.normal(size=3), rng.normal(size=3))
    assert isinstance(mc, Solution)
    assert label(mc) == "elementary:trigonometric+hyperbolic+polynomial"
    assert label(MassCenterMotion(np.eye(3), np.zeros(3), np.ones(3), np.zeros(3))) == "elementary:trigonometric"
    with pytest.raises(dataclasses.FrozenInstanceError):
        mc.a = np.eye(3)
    d = mc.diagnostics
    assert d["kinds"] == mc.kinds and np.array_equal(d["eigenvalues"], mc.eigenvalues)
    assert np.allclose(d["axes"] @ np.diag(d["eigenvalues"]) @ d["axes"].T, a, rtol=0, atol=1e-15)
    t = np.linspace(0, 4, 9).reshape(3, 3)
    q, v = mc.evaluate(t)
    assert q.shape == (3, 3, 3)
    qm, _ = mc.evaluate(t[0], dps=20)
    assert isinstance(qm[0, 0], mpmath.mpf)
    # long arrays are evaluated in chunks with the same values
    tl = np.linspace(-3, 3, 2 * CHUNK + 5)
    ql, _ = mc(tl)
    assert np.array_equal(ql[-5:], mc(tl[-5:])[0])


@pytest.mark.parametrize("lam, n_axes", [
    ([0.7, 0.7, -0.3], 1),    # axially symmetric: the component along the odd eigenvector
    ([0.5, 0.5, 0.5], 3),     # isotropic: all three components
    ([0.9, 0.4, -0.2], 0),    # distinct eigenvalues: none
])
def test_first_integrals_of_the_reference_motion(lam, n_axes):
    """The invariants are conserved along mpmath's matrix-exponential motion (40 digits)."""
    rng = np.random.default_rng(11)
    a = matrix_with_eigenvalues(lam, [0.4, -1.1, 0.7])
    b, q0, v0 = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
    mc = MassCenterMotion(a, b, q0, v0)
    t = [0.0, 0.37, 1.0, -2.2, 5.0]
    ref = to_float(expm_reference(a, b, q0, v0, t))
    fi = mc.first_integrals(ref[:, :3], ref[:, 3:])
    assert fi["angular_momentum"].shape == (5, n_axes) and fi["mode_energies"].shape == (5, 3)
    scale = 1 + np.max(np.abs(ref)) ** 2
    for k in ("energy", "mode_energies", "angular_momentum"):
        # measured <= 1.1e-16 (relative to 1 + max |state|^2)
        assert np.max(np.abs(fi[k] - mc.invariants[k]), initial=0.0) < 1e-15 * scale
    assert abs(np.sum(mc.invariants["mode_energies"]) - mc.invariants["energy"]) < 1e-15 * scale  # 7.6e-18
    if n_axes == 1:
        odd = matrix_with_eigenvalues([0, 0, 1], [0.4, -1.1, 0.7])  # projector on the odd eigenvector
        n = mc.diagnostics["angular_momentum_axes"][0]
        assert abs(n @ odd @ n - 1) < 1e-14
    # a component that is NOT conserved is not listed: along a distinct eigenvector L drifts
    if n_axes == 0:
        L = np.cross(ref[:, :3], ref[:, 3:]) @ mc.axes
        assert np.all(np.max(np.abs(L - L[0]), axis=0) > 1e-2)


def test_constant_force_in_a_zero_plane_breaks_the_symmetry():
    """a = diag(0, 0, 1) with b in the zero plane: uniform acceleration there, L_z not conserved."""
    a = np.diag([0.0, 0.0, 1.0])
    free = MassCenterMotion(a, [0, 0, 0.3], [1, 0, 0], [0, 1, 0])
    pushed = MassCenterMotion(a, [0.3, 0, 0], [1, 0, 0], [0, 1, 0])
    assert free.invariants["angular_momentum"].shape == (1,)
    assert pushed.invariants["angular_momentum"].shape == (0,)
    q, v = pushed(np.array([0.0, 2.0]))
    Lz = np.cross(q, v)[:, 2]
    assert abs(Lz[1] - Lz[0]) > 0.1
    q, v = free(np.linspace(0, 5, 11))
    assert np.allclose(free.first_integrals(q, v)["angular_momentum"], free.invariants["angular_momentum"],
                       rtol=0, atol=1e-14)
