"""The per-time evaluation of the theta-function rotation: the real form of the Fourier flow, the
folded linear map after it and the Newton-Schulz polar factor, each against the direct formula
(the complex series over all modes, ``Phi(0, t)`` with its 3x3 products, the SVD)."""
import json
import pathlib

import numpy as np
import oracle_theta_evaluation as oracle
import pytest

from thetasol import inertia, solve_rotation
from thetasol.core.so3 import polar_near_orthogonal, polar_orthonormalize, rodrigues, rotation_about, vee

REFS = json.loads((pathlib.Path(__file__).parent / "data" / "rotation" / "refs.json").read_text())
TIMES = np.array([0.0, 0.37, 2.9, 41.3, 997.0, 1e6, 3.3e7])


def _solve(name):
    r = REFS[name]
    return solve_rotation(inertia(np.diag(r["J"])), np.array(r["a"]), np.array(r["Q0"]), np.array(r["omega0"]))


@pytest.fixture(scope="module", params=["generic", "near_unstable_equilibrium", "symmetric_oblate"])
def sol(request):
    return _solve(request.param)


@pytest.mark.parametrize("many", [False, True])
def test_real_form_of_the_flow_against_the_complex_series(sol, many):
    """FlowTheta (its compiled kernel) sums cos/sin of the modes up to sign; the complex series over every
    mode m with the coefficients D(m), D(m) 2 pi i m.u gives the same values (to rounding of the sum of
    |D|), for a few times and for 300."""
    flow = sol.evaluator.flow
    t = np.concatenate([TIMES, np.linspace(-7.0, 3e3, 300)]) if many else TIMES
    _, v, dv = flow(t)
    X = np.exp(2j * np.pi * oracle.flow_turns(flow, t) @ flow.modes.T)
    scale = np.abs(flow.D).sum(axis=1).max()
    assert np.abs(v - X @ flow.D.T).max() <= 1e-14 * scale
    Dd = flow.D * (2j * np.pi * (flow.modes @ flow.u))[None, :]
    assert np.abs(dv - X @ Dd.T).max() <= 1e-14 * np.abs(Dd).sum(axis=1).max()


def test_flow_turns_against_mpmath(sol):
    """The turns of the flow (the oracle's, which the kernel repeats operation for operation): ``t u`` modulo 1 against mpmath at 40 digits, for one time and in a batch, up to
    |t| = 2e9, and one time beyond 2^31 (the plain product there).  Measured on the 13 reference bodies:
    <= 6.3e-17 max(1, |u|) off for |t| < 2^31 (the rounded product ``t u``: 1.4e-7); bound 4 eps max(1, |u|)."""
    import mpmath

    flow = sol.evaluator.flow
    times = np.array([0.7, -4002.0, 1e6 + 0.3, 1e9 + 0.5, -2e9 + 0.25])
    with mpmath.workdps(40):
        ref = np.array([[float(mpmath.frac(mpmath.mpf(t) * mpmath.mpf(float(u)) + mpmath.mpf(0.5)) - 0.5)
                         for u in flow.u] for t in times])
    bound = 4 * np.finfo(float).eps * max(1.0, float(np.abs(flow.u).max()))
    batch = oracle.flow_turns(flow, times)
    np.testing.assert_array_equal(batch, np.concatenate([oracle.flow_turns(flow, times[i:i + 1])
                                                         for i in range(len(times))]))
    d = batch - ref
    assert np.abs(d - np.rint(d)).max() <= bound
    far = np.array([3e9 + 0.5])
    plain = np.multiply.outer(far, flow.u)
    np.testing.assert_array_equal(oracle.flow_turns(flow, far), plain - np.rint(plain))


def test_folded_evaluation_against_phi0(sol):
    """evaluate() (one real product to Q0 Phi^T P^T, P Phi, P Phidot, Newton-Schulz) against the
    definition from Phi(0, t): Q = polar(Q0p Phi^T) R^T P^T, omega = P (R vee(-Phidot Phi^T) + spin e)
    (measured <= 6e-15 on generic, symmetric_oblate, 2e-13 near the unstable equilibrium, whose Phi is
    that sensitive to rounding: its error against the 80-bit reference is 3e-12)."""
    ev = sol.evaluator
    w, Q = ev.evaluate(TIMES)
    Phi, Phidot = ev.phi0(TIMES, derivative=True)
    Phi_r = Phi.real
    Qp = polar_orthonormalize(ev.Q0p @ np.swapaxes(Phi_r, -1, -2))
    wp = vee(-Phidot.real @ np.swapaxes(Phi_r, -1, -2))
    if ev.axis is not None:
        R = rotation_about(ev.axis, -ev.spin * TIMES)
        Qp = Qp @ np.swapaxes(R, -1, -2)
        wp = np.einsum("nij,nj->ni", R, wp)
        wp[:, ev.axis] += ev.spin
    bound = 1e-12 if sol.diagnostics["fourier_modes"] > 2000 else 2e-14
    assert np.abs(Q - Qp @ ev.P.T).max() <= bound
    assert np.abs(w - wp @ ev.P.T).max() <= bound * np.abs(w).max()


def test_a_time_gives_the_same_state_alone_and_in_any_batch(sol):
    """The evaluation works per time (blocks of the flow, chunks of Solution.__call__): a time alone,
    in a short batch and in a long one agree to rounding (the BLAS may pick another kernel for one
    row: measured <= 4.6e-15 relative (near the unstable equilibrium, 1.6e-15 on the generic body),
    bound 1.5e-14)."""
    t = np.concatenate([TIMES, np.linspace(0.0, 50.0, 5001)])
    w, Q = sol(t)
    for idx in ([5], [0, 1, 2], list(range(3, 40)), [6]):
        ws, Qs = sol(t[idx])
        assert np.abs(ws - w[idx]).max() <= 1.5e-14 * np.abs(w).max()
        assert np.abs(Qs - Q[idx]).max() <= 1.5e-14


def test_polar_near_orthogonal_against_long_double():
    """One Newton-Schulz step on component rows against the polar factor in long double (three
    Newton-Schulz steps in 80-bit): nearly orthogonal matrices (|X^T X - 1| ~ 1e-14 .. 1e-9, measured
    <= 4.8e-16; the float64 SVD's polar factor is off by 4.3e-15 .. 5.3e-15 there), and far ones
    take the SVD (identical to polar_orthonormalize)."""
    rng = np.random.default_rng(3)
    R = rodrigues(rng.normal(size=(200, 3)))
    S = rng.normal(size=(200, 3, 3))
    S = S + np.swapaxes(S, -1, -2)
    for size in (1e-14, 1e-10, 1e-9):
        X = R @ (np.eye(3) + size * S)
        ref = X.astype(np.longdouble)
        for _ in range(3):
            XtX = np.einsum("nri,nrj->nij", ref, ref)
            ref = np.einsum("nri,nij->nrj", ref, 1.5 * np.eye(3, dtype=np.longdouble) - 0.5 * XtX)
        got = polar_near_orthogonal(X.transpose(1, 2, 0)).transpose(2, 0, 1)
        assert float(np.abs(got - ref).max()) <= 1e-15
    X = R @ (np.eye(3) + 1e-3 * S)
    got = polar_near_orthogonal(X.transpose(1, 2, 0)).transpose(2, 0, 1)
    assert np.array_equal(got, polar_orthonormalize(X))


def test_flow_tables_against_mpmath(sol):
    """The flow's tables (the oracle's, which the kernel repeats operation for operation): exp(2 pi i k phi)
    as powers of exp(2 pi i phi) against mpmath at 160 far times.
    The error grows with |k| either way (the rounded argument 2 pi phi, times k); measured max
    |error| / max(1, |k|): 3.4e-16 (generic, |k| <= 6), 4.0e-16 (near_unstable_equilibrium, |k| <= 12,
    and symmetric_oblate), and max |error| 0.64-0.84 x that of the direct exp(2 pi i fl(k phi)); bounds
    1.75x and 1x."""
    import math

    import mpmath

    flow = sol.evaluator.flow
    phi = oracle.flow_turns(flow, np.linspace(1e6, 1e6 + 50.0, 160))
    owner, k = oracle.table_columns(flow)
    with mpmath.workdps(30):
        ref = np.array([[complex(mpmath.expjpi(2 * mpmath.mpf(row[owner[j]]) * int(k[j]))) for j in range(k.size)]
                        for row in phi])
    direct = np.abs(np.exp(2j * math.pi * (phi.take(owner, axis=1) * k)) - ref)
    err = np.abs(oracle.flow_tables(flow, phi) - ref)
    assert (err / np.maximum(1.0, np.abs(k))).max() <= 7e-16
    assert err.max() <= direct.max()
