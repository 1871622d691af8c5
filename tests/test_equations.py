"""First integrals (4.7), (4.9), (4.13) and the spectral curve (4.12) along integrate_rotation
trajectories; integrate_rotation's shapes and bad input.

The curve coefficients are checked against sympy's determinant (independent of the
polynomial arithmetic in thetasol.mechanics.equations) and the Lax pair (4.11) against finite
differences along a trajectory.
"""
import numpy as np
import pytest
import sympy as sp

from thetasol import inertia, integrate_rotation, invariants, spectral_coefficients
from thetasol.core.so3 import rodrigues
from thetasol.mechanics.equations import paper_variables


def random_case(seed, a_kind="generic"):
    rng = np.random.default_rng(seed)
    R = rodrigues(rng.normal(size=3))
    J = R @ np.diag(rng.uniform(0.3, 2.0, 3)) @ R.T  # a general (non-principal) tensor
    if a_kind == "generic":
        a = rng.normal(size=(3, 3))
        a = a + a.T
    elif a_kind == "zero":
        a = np.zeros((3, 3))
    elif a_kind == "isotropic":
        a = 0.7 * np.eye(3)
    elif a_kind == "rank-one":
        g = rng.normal(size=3)
        a = 1.3 * np.outer(g, g) / (g @ g)
    Q0 = rodrigues(rng.normal(size=3))
    w0 = rng.normal(size=3)
    return J, a, Q0, w0


def rel_drift(x):
    x = np.asarray(x)
    return np.max(np.abs(x - x[0])) / max(np.max(np.abs(x[0])), 1e-300)


# -- the curve coefficients themselves -----------------------------------------------------------

def test_spectral_coefficients_match_sympy_determinant():
    J, a, Q0, w0 = random_case(0)
    M, u, _ = paper_variables(J, a, Q0, w0)
    C = spectral_coefficients(inertia(J), M, u)
    E, w = sp.symbols("E w")
    L = sp.Matrix(J @ J) * E**2 + sp.Matrix(M) * E + sp.Matrix(u) - w * sp.eye(3)
    poly = sp.Poly(sp.expand(L.det()), E, w)
    ref = np.zeros((7, 4))
    for (k, l), c in poly.terms():
        ref[k, l] = float(c)
    assert np.allclose(C, ref, rtol=0, atol=1e-12 * np.max(np.abs(ref)))
    # the involution E -> -E: only even powers of E (4.12)
    assert np.max(np.abs(ref[1::2])) < 1e-12 * np.max(np.abs(ref))
    assert np.max(np.abs(C[1::2])) < 1e-12 * np.max(np.abs(ref))


def test_lax_pair_holds_along_a_trajectory():
    """(4.11): dL/dt = [L, A] with L = J^2 E^2 + M E + u, A = J E + omega, for several E."""
    J, a, Q0, w0 = random_case(1)
    h = 1e-4
    w, Q = integrate_rotation(inertia(J), a, Q0, w0, rtol=1e-13)(np.array([0.7 - h, 0.7, 0.7 + h]))
    M, u, W = paper_variables(J, a, Q, w)
    for E in (0.0, 0.5, -1.3, 2.0):
        L = J @ J * E**2 + M * E + u
        A = J * E + W[1]
        Ldot = (L[2] - L[0]) / (2 * h)
        assert np.allclose(Ldot, L[1] @ A - A @ L[1], atol=2e-7 * (1 + E**2))


# -- conservation along numerical trajectories -------------------------------------------------------

@pytest.mark.parametrize("a_kind", ["generic", "rank-one", "isotropic", "zero"])
@pytest.mark.parametrize("method", ["DOP853", "splitting"])
def test_first_integrals_constant(a_kind, method):
    J, a, Q0, w0 = random_case(2, a_kind)
    # measured max drifts: DOP853 3.5e-12 over t <= 40; splitting (symplectic) 2.3e-13 over t <= 20
    rtol, t_end, tol = (1e-12, 40.0, 2e-11) if method == "DOP853" else (1e-10, 20.0, 2e-12)
    t = np.linspace(0.0, t_end, 41)
    w, Q = integrate_rotation(inertia(J), a, Q0, w0, rtol=rtol, method=method)(t)
    inv = invariants(inertia(J), a, Q, w)
    for key in ("energy", "H", "I2", "I3"):  # (4.9), (4.13)
        assert rel_drift(inv[key]) < tol, key
    C = inv["curve"]  # every coefficient of (4.12), relative to the largest
    assert np.max(np.abs(C - C[0])) < tol * np.max(np.abs(C[0]))
    assert np.allclose(inv["H"], -2 * inv["energy"], rtol=1e-12)  # documented sign
    M, u, W = paper_variables(J, a, Q, w)
    I1 = 0.5 * np.trace(M @ M, axis1=-2, axis2=-1)
    assert np.allclose(I1, -inv["m2"], rtol=1e-13)  # (4.7): 1/2 tr(M^2) = -|m|^2
    if a_kind in ("zero", "isotropic"):
        # (4.7): both 1/2 tr(M^2) and 1/2 tr(M omega) are integrals of the free rotation
        assert rel_drift(I1) < tol
        assert rel_drift(0.5 * np.trace(M @ W, axis1=-2, axis2=-1)) < tol
    else:
        # ...and not in a torque-producing potential: the check can fail
        assert rel_drift(I1) > 1e-3


def test_invariants_broadcast_and_values():
    J, a, Q0, w0 = random_case(3)
    inv = invariants(inertia(J), a, Q0, w0)
    Iner = np.trace(J) * np.eye(3) - J
    assert inv["energy"] == pytest.approx(0.5 * w0 @ Iner @ w0 + 0.5 * np.trace(Q0.T @ a @ Q0 @ J), rel=1e-14)
    assert inv["m2"] == pytest.approx(np.sum((Iner @ w0) ** 2), rel=1e-14)
    Qs = np.broadcast_to(Q0, (2, 5, 3, 3))
    ws = np.broadcast_to(w0, (2, 5, 3))
    inv2 = invariants(inertia(J), a, Qs, ws)
    assert inv2["H"].shape == (2, 5) and inv2["curve"].shape == (2, 5, 7, 4)
    assert np.allclose(inv2["curve"][1, 3], inv["curve"])


def test_heyoka_float64_reference_conserves_to_round_off():
    pytest.importorskip("heyoka")
    J, a, Q0, w0 = random_case(4)
    t = np.linspace(0.0, 100.0, 11)
    w, Q = integrate_rotation(inertia(J), a, Q0, w0, rtol=1e-15, method="heyoka")(t)
    inv = invariants(inertia(J), a, Q, w)
    for key in ("H", "I2", "I3"):
        assert rel_drift(inv[key]) < 1e-13, key
    wd, Qd = integrate_rotation(inertia(J), a, Q0, w0, rtol=1e-12)(t)
    assert np.max(np.abs(Qd - Q)) < 1e-9 and np.max(np.abs(wd - w)) < 1e-9  # the acceptance bound for t <= 100


@pytest.mark.parametrize("dtype", ["ldbl", "f128"])
def test_extended_precision_references_integrate_the_body_of_the_data(dtype):
    """I^-1 and m0 = I omega0 of the extended-precision paths are those of the float64 inertia I and omega0,
    rounded once in the working precision (mpmath at 60 digits as the reference): the float64 inverse is
    another body, one ulp away, and near an unstable relative equilibrium that ulp moves the reference far
    more than the data's conditioning."""
    hy = pytest.importorskip("heyoka")
    import mpmath

    from thetasol.integrators._common import extended_inertia

    fp, ulp = {"ldbl": (np.longdouble, 2.0 ** -63), "f128": (hy.real128, 2.0 ** -112)}[dtype]
    J, _, _, w0 = random_case(6)
    Iv = inertia(J)
    Iinv, m0 = extended_inertia(Iv, w0, fp)
    with mpmath.workdps(60):
        I = mpmath.matrix(Iv.tolist())
        Iinv_ref, m0_ref = I ** -1, I * mpmath.matrix(w0.tolist())
        err_inv = max(abs(mpmath.mpf(str(Iinv[i][k])) - Iinv_ref[i, k]) / abs(Iinv_ref[i, k])
                      for i in range(3) for k in range(3))
        err_m = max(abs(mpmath.mpf(str(m0[i])) - m0_ref[i]) / abs(m0_ref[i]) for i in range(3))
        err_f64 = max(abs(mpmath.mpf(float(x)) - Iinv_ref[i, k]) / abs(Iinv_ref[i, k])
                      for (i, k), x in np.ndenumerate(np.linalg.inv(Iv)))
    assert err_inv <= ulp and err_m <= ulp, (err_inv, err_m)
    assert err_f64 > 100 * ulp    # the float64 inverse is not the body's (the test can fail)


@pytest.mark.parametrize("dtype, rtol, bound", [("ldbl", 1e-19, 2e-9),
                                                 pytest.param("f128", 1e-25, 1e-10, marks=pytest.mark.slow)])
def test_extended_precision_reference_next_to_an_unstable_equilibrium_matches_the_closed_form(dtype, rtol, bound):
    """The near-unstable-equilibrium case of tests/data/rotation/refs.json at its worst time on a dense grid
    (t = 3726.8625): heyoka in extended precision against the theta-function solution, which is exact for the
    body I = tr(J) 1 - J of the float64 data.  Measured: 80-bit 5.1e-10 (5.8e-9 with the float64 I^-1, so
    this default check sees the wiring of extended_inertia); quadruple 2.7e-11 (5.5e-9 while the
    reference rounded I^-1 to float64)."""
    hy = pytest.importorskip("heyoka")
    import json
    import pathlib

    from thetasol import solve_rotation

    r = json.loads((pathlib.Path(__file__).parent / "data" / "rotation" / "refs.json").read_text())[
        "near_unstable_equilibrium"]
    J, a, Q0, w0 = np.diag(r["J"]), np.array(r["a"]), np.array(r["Q0"]), np.array(r["omega0"])
    t = np.array([3726.8625])
    fp = {"ldbl": np.longdouble, "f128": hy.real128}[dtype]
    wq, Qq = integrate_rotation(inertia(J), a, Q0, w0, method="heyoka", fp_type=fp, rtol=rtol)(t)
    ws, Qs = solve_rotation(inertia(J), a, Q0, w0)(t)
    assert max(np.abs(ws - wq).max(), np.abs(Qs - Qq).max()) <= bound


# -- integrate_rotation: shapes and input ------------------------------------------------------------------

def test_shapes_order_and_time_zero():
    J, a, Q0, w0 = random_case(5)
    w, Q = integrate_rotation(inertia(J), a, Q0, w0)(1.5)
    assert w.shape == (3,) and Q.shape == (3, 3)
    t = np.array([[2.0, -1.0, 0.0], [0.5, 2.0, -0.25]])
    w2, Q2 = integrate_rotation(inertia(J), a, Q0, w0)(t)
    assert w2.shape == (2, 3, 3) and Q2.shape == (2, 3, 3, 3)
    assert np.allclose(Q2[0, 2], Q0, atol=1e-15) and np.allclose(w2[0, 2], w0, atol=1e-15)
    assert np.array_equal(Q2[0, 0], Q2[1, 1])  # duplicate times, one integration
    for (i, j), tk in np.ndenumerate(t):  # unordered and negative times match single calls
        wk, Qk = integrate_rotation(inertia(J), a, Q0, w0)(tk)
        assert np.allclose(Qk, Q2[i, j], atol=1e-10) and np.allclose(wk, w2[i, j], atol=1e-10)
    assert np.allclose(np.swapaxes(Q2, -1, -2) @ Q2, np.eye(3), atol=1e-14)
    we, Qe = integrate_rotation(inertia(J), a, Q0, w0)(np.zeros((0,)))
    assert we.shape == (0, 3) and Qe.shape == (0, 3, 3)


def test_principal_values_equal_diagonal_tensor():
    _, a, Q0, w0 = random_case(6)
    t = np.array([0.3, 1.0])
    w1, Q1 = integrate_rotation(inertia([0.5, 1.0, 1.4]), a, Q0, w0)(t)
    w2, Q2 = integrate_rotation(inertia(np.diag([0.5, 1.0, 1.4])), a, Q0, w0)(t)
    assert np.allclose(Q1, Q2, atol=1e-14) and np.allclose(w1, w2, atol=1e-14)


def test_reversibility():
    """Integrate to t, flip omega, integrate t again: back to the start (time reversal)."""
    J, a, Q0, w0 = random_case(7)
    w, Q = integrate_rotation(inertia(J), a, Q0, w0, rtol=1e-13)(3.0)
    wb, Qb = integrate_rotation(inertia(J), a, Q, -w, rtol=1e-13)(3.0)
    assert np.allclose(Qb, Q0, atol=1e-10) and np.allclose(-wb, w0, atol=1e-10)


GOOD = dict(J=[0.5, 1.0, 1.4], a=np.diag([1.0, 2.0, 3.0]), Q0=np.eye(3), omega0=[0.1, 0.2, 0.3], t=[1.0])


@pytest.mark.parametrize("change, match", [
    (dict(I=[1.0, 1.0, 2.5]), "triangle"),
    (dict(I=[0.0, 1.0, 1.0]), "positive definite"),
    (dict(I=[0.5, np.nan, 1.4]), "NaN"),
    (dict(I=[[1, 0.1, 0], [0, 1, 0], [0, 0, 1]]), "symmetric"),
    (dict(I=[1.0, 2.0]), "shape"),
    (dict(a=[[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]), "symmetric"),
    (dict(a=np.diag([1.0, np.inf, 1.0])), "NaN or inf"),
    (dict(a=np.eye(2)), "shape"),
    (dict(Q0=np.eye(3) * (1 + 1e-9)), "not orthogonal"),
    (dict(Q0=np.diag([1.0, 1.0, -1.0])), "reflection"),
    (dict(Q0=np.eye(2)), "shape"),
    (dict(omega0=[0.1, 0.2]), "shape"),
    (dict(omega0=[0.1, 0.2, np.nan]), "NaN"),
    (dict(t=[1.0, np.nan]), "NaN"),
    (dict(t="soon"), "numeric"),
])
def test_bad_input(change, match):
    kw = {**GOOD, **change}
    with pytest.raises(ValueError, match=match):
        integrate_rotation(kw.get("I", inertia(kw["J"])), kw["a"], kw["Q0"], kw["omega0"])(kw["t"])


def test_bad_options_and_tolerated_round_off():
    g = GOOD
    for rtol in (0.0, 1.0, -1e-3):
        with pytest.raises(ValueError, match="rtol"):
            integrate_rotation(inertia(g["J"]), g["a"], g["Q0"], g["omega0"], rtol=rtol)(g["t"])
    with pytest.raises(ValueError, match="method"):
        integrate_rotation(inertia(g["J"]), g["a"], g["Q0"], g["omega0"], method="Euler")(g["t"])
    # round-off in Q0 (below 1e-10) and in the symmetry of a is accepted and cleaned
    Q0 = rodrigues(np.array([0.3, 0.2, 0.1])) + 1e-12
    a = g["a"] + np.triu(np.full((3, 3), 1e-15), 1)
    w, Q = integrate_rotation(inertia(g["J"]), a, Q0, g["omega0"])([0.0])
    assert np.allclose(Q[0].T @ Q[0], np.eye(3), atol=1e-15)


@pytest.mark.slow
def test_first_integrals_long_run():
    J, a, Q0, w0 = random_case(8)
    t = np.linspace(0.0, 1000.0, 201)
    w, Q = integrate_rotation(inertia(J), a, Q0, w0, rtol=1e-13)(t)
    inv = invariants(inertia(J), a, Q, w)
    for key in ("H", "I2", "I3"):
        assert rel_drift(inv[key]) < 1e-10, key
    C = inv["curve"]
    assert np.max(np.abs(C - C[0])) < 1e-10 * np.max(np.abs(C[0]))


def test_invariants_take_I_as_solve_rotation_does():
    """I as a list, a 1-D array of principal values or a 3x3 tensor: the same integrals; other shapes name I."""
    a = np.array([[0.3, -0.2, 0.1], [-0.2, -0.4, 0.25], [0.1, 0.25, 0.6]])
    Q, w = np.eye(3), np.array([0.3, -0.6, 0.45])
    ref = invariants(np.diag([2.7, 2.3, 1.6]), a, Q, w)
    for I in ([2.7, 2.3, 1.6], np.array([2.7, 2.3, 1.6])):  # noqa: E741 - the inertia tensor's usual name
        got = invariants(I, a, Q, w)
        assert all(np.array_equal(got[k], ref[k]) for k in ref)
    with pytest.raises(ValueError, match="I must be 3 principal values"):
        invariants([2.7, 2.3], a, Q, w)
