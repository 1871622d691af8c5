"""One call on a few times (a far time): the theta-function rotation's evaluation of few times against
the same times in a batch, and its phases far out.

One implementation serves every number of times: the compiled kernel (thetasol.core.kernels) runs the
same operations per time whatever the batch, so one time and the same time in a batch agree (the bounds
below are those of the former numpy path, whose matrix products summed in another order for one row).
"""
import json
import pathlib

import numpy as np
import pytest

from thetasol import inertia, invariants, solve_rotation
from thetasol.core import validate as V
from thetasol.solutions.rotation.theta_rotation.solution import ThetaRotation, solve_theta_rotation

REFS = json.loads((pathlib.Path(__file__).parent / "data" / "rotation" / "refs.json").read_text())
TIMES = np.array([0.0, 0.7, 3.1, 17.3, 102.0, 997.0, 4002.0, 1e6])


@pytest.fixture(scope="module", params=["generic", "near_unstable_equilibrium", "symmetric_oblate",
                                        "symmetric_rank_one"])
def sol(request):
    r = REFS[request.param]
    return solve_rotation(inertia(np.diag(r["J"])), np.array(r["a"]), np.array(r["Q0"]), np.array(r["omega0"]))


def test_one_call_against_the_batch(sol):
    """sol(one time) and sol(16 times) against the same times inside a batch of 4008: the flow's matrix
    product with one row sums in another order than with many.  Measured, omega relative to its
    largest component and Q absolute: one time <= 3.9e-15 (6.2e-14 near the unstable equilibrium, whose
    state is that sensitive), 16 times <= 3.7e-15; bounds 4x."""
    big = np.concatenate([TIMES, np.linspace(0.0, 50.0, 4000)])
    wb, Qb = sol(big)
    bound = 2.5e-13 if sol.diagnostics["fourier_modes"] > 2000 else 1.6e-14
    for i, t in enumerate(TIMES):
        w, Q = sol(np.array([t]))
        assert np.abs(w[0] - wb[i]).max() <= bound * np.abs(wb[i]).max()
        assert np.abs(Q[0] - Qb[i]).max() <= bound
    w, Q = sol(big[:16])
    assert np.abs(w - wb[:16]).max() <= 1.5e-14 * np.abs(wb[:16]).max()
    assert np.abs(Q - Qb[:16]).max() <= 1.5e-14


def test_scalar_and_shaped_times(sol):
    """A scalar time and a (2, 1) array give the shapes of the protocol and the values of flat times
    (the same calls, so the same bits)."""
    w, Q = sol(1e6)
    assert w.shape == (3,) and Q.shape == (3, 3)
    w1, Q1 = sol(np.array([1e6]))
    assert np.array_equal(w, w1[0]) and np.array_equal(Q, Q1[0])
    w2, Q2 = sol(np.array([[0.7], [1e6]]))
    w3, Q3 = sol(np.array([0.7, 1e6]))
    assert w2.shape == (2, 1, 3) and Q2.shape == (2, 1, 3, 3)
    assert np.array_equal(w2[:, 0], w3) and np.array_equal(Q2[:, 0], Q3)


def test_times_checks():
    """A float64 array of times passes as it is, a Python float as a 0-d array; NaN and inf still raise, in
    any input form."""
    t = np.array([0.0, 1e6])
    assert V.times(t) is t
    assert V.times([1, 2]).dtype == np.float64
    one = V.times(1e6)
    assert type(one) is np.ndarray and one.shape == () and one.dtype == np.float64 and one == 1e6
    for bad in (np.array([1.0, np.nan]), np.array([[np.inf]]), [0.0, float("-inf")], np.float64(np.nan),
                float("nan"), float("inf")):
        with pytest.raises(ValueError, match="NaN or inf"):
            V.times(bad)


def _drift(J, a, Q0, w0, w, Q) -> float:
    """Max drift of the energy and of I2 (4.13) over (w, Q), relative to the sum of the magnitudes of
    their terms at t = 0 (as benchmarks/bench_theta_rotation.py)."""
    I = np.trace(J) * np.eye(3) - J
    m0 = I @ w0
    u0 = -(Q0.T @ a @ Q0)
    scale_E = abs(0.5 * w0 @ m0) + abs(0.5 * np.trace(u0 @ J))
    scale_I2 = 2 * float(m0 @ m0) + abs(2 * np.trace(J @ J @ u0))
    i0, it = invariants(inertia(J), a, Q0, w0), invariants(inertia(J), a, Q, w)
    return float(max(np.abs(it["energy"] - i0["energy"]).max() / scale_E,
                     np.abs(it["I2"] - i0["I2"]).max() / scale_I2))


@pytest.mark.parametrize("name", ["rank_one", "symmetric_oblate", "symmetric_prolate_saddle", "symmetric_rank_one",
                                  "symmetric_fast_spin", "fast_spin"])
def test_far_times_keep_the_first_integrals(name):
    """The phases ``nu_sk t`` are integer combinations of the rates' turns reduced modulo 1 exactly
    (:class:`thetasol.solutions.rotation.theta_rotation.exponents.PhaseRates`), and so are the theta flow's
    phases ``t u`` (:class:`thetasol.theta.flow.FlowTheta`): the nine exponents keep their exact
    relations far out (the form ``F_s - G_k``, the lattice rate U), still combine into an orthogonal
    Phi(0, t), and energy and I2 do not drift on [T, T + 100] at T = 0, 1e6, 1e9; with the rounded floats
    nu_sk, the rounded products nu t or the rounded flow phases ``t u`` instead, the drift grows with T
    by orders of magnitude past the bound.  The recorded body (its second moments J, which no float64
    inertia reproduces exactly) is solved by the theta-function stage itself, the branch
    solve_rotation takes for it: the test is about the evaluation, not the conversion of the data."""
    r = REFS[name]
    J, a, Q0, w0 = np.diag(r["J"]), np.array(r["a"]), np.array(r["Q0"]), np.array(r["omega0"])
    assert type(solve_rotation(inertia(J), a, Q0, w0)) is ThetaRotation   # the branch the public call takes
    sol = solve_theta_rotation(J, a, Q0, w0)
    grid = np.linspace(0.0, 100.0, 2001)
    near = _drift(J, a, Q0, w0, *sol(grid))
    assert near <= 5e-14
    assert _drift(J, a, Q0, w0, *sol(grid + 1e6)) <= 5e-14
    assert _drift(J, a, Q0, w0, *sol(grid + 1e9)) <= 5e-14


def test_turns_against_mpmath(sol):
    """The turns ``nu_sk t / 2 pi`` modulo 1 against mpmath at 40 digits from the exact exponents
    ``pi n_sk.U + e_sk.gaps`` (PhaseRates), for one time and in a batch, up to t = 2e9; and the float
    exponents ``nu`` within 3 ulps (of the largest) of those.  Measured on the 13 reference bodies:
    turns <= 1.1e-16 off, nu <= 0.66 ulps; bound 5e-16 turns."""
    import mpmath

    ev = sol.evaluator
    ph = ev.phase
    times = [0.7, 4002.0, 1e6 + 0.3, 1e9 + 0.5, 2e9 - 0.25]
    with mpmath.workdps(40):
        nu = [mpmath.pi * sum(int(n) * mpmath.mpf(float(u)) for n, u in zip(ph.n[m], ph.lattice, strict=True))
              + sum(int(e) * mpmath.mpf(float(g)) for e, g in zip(ph.e[m], ph.gaps, strict=True)) for m in range(9)]
        scale = np.spacing(np.abs(ev.nu).max())
        assert max(abs(mpmath.mpf(float(ev.nu.ravel()[m])) - nu[m]) for m in range(9)) <= 3 * scale
        ref = np.array([[float(mpmath.frac(nu[m] * mpmath.mpf(t) / (2 * mpmath.pi) + mpmath.mpf(0.5)) - 0.5)
                         for m in range(9)] for t in times])
    batch = ev.turns(np.array(times)).reshape(-1, 9)
    one = np.concatenate([ev.turns(np.array([t])).reshape(-1, 9) for t in times])
    for x in (batch, one):
        d = x - ref
        assert np.abs(d - np.rint(d)).max() <= 5e-16
    assert np.array_equal(batch, one)


def test_fitted_exponents_keep_their_own_rates(sol):
    """Where the exact relations point at no integers the fitted exponents are kept, each a rate of its
    own (PhaseRates.of_fit): the turns are then ``nu t / 2 pi`` of the floats nu (mpmath, 40 digits),
    and the state agrees with the exact combinations' up to the exponents' last bits times t.  Measured
    on the 13 reference bodies: turns <= 1.1e-16 off, states at t <= 4002 <= 1.9e-13 apart; bounds
    5e-16 and 1e-12."""
    import mpmath

    from thetasol.solutions.rotation.theta_rotation.evaluator import build_evaluator
    from thetasol.solutions.rotation.theta_rotation.exponents import PhaseRates

    ev = sol.evaluator
    fit = build_evaluator(ev.flow, ev.nu, PhaseRates.of_fit(ev.nu), ev.amp, ev.X0inv, ev.B, ev.Q0p, ev.P, ev.spin,
                          ev.axis)
    assert fit.phase.lattice.size == 0 and np.array_equal(fit.phase.e, np.eye(9))
    times = [0.7, 4002.0, 1e6 + 0.3, 1e9 + 0.5]
    with mpmath.workdps(40):
        ref = np.array([[float(mpmath.frac(mpmath.mpf(float(x)) * mpmath.mpf(t) / (2 * mpmath.pi) + mpmath.mpf(0.5))
                               - 0.5) for x in ev.nu.ravel()] for t in times])
    for x in (fit.turns(np.array(times)).reshape(-1, 9),
              np.concatenate([fit.turns(np.array([t])).reshape(-1, 9) for t in times])):
        d = x - ref
        assert np.abs(d - np.rint(d)).max() <= 5e-16
    t = TIMES[TIMES <= 4002.0]
    (w1, Q1), (w2, Q2) = fit.evaluate(t), ev.evaluate(t)
    assert np.abs(w1 - w2).max() <= 1e-12 * np.abs(w2).max() and np.abs(Q1 - Q2).max() <= 1e-12




def test_split_rate_exact_is_split_rate_on_floats():
    """core.turns: the splitting of a rate known beyond float64 (the exponents' gaps / 2 pi) is the float
    splitting on float rates, piece for piece, and its pieces sum to the mpmath rate to the rounding of
    c3, ~2^-97 relative (measured 1.3e-31 on 1.3 / 2 pi; bound 1e-30)."""
    import mpmath

    from thetasol.core.turns import split_rate, split_rate_exact

    rng = np.random.default_rng(8)
    u = rng.normal(size=50) * 10.0 ** rng.uniform(-6, 3, 50)
    want = np.array(split_rate(u)).T
    got = np.array([split_rate_exact(float(x)) for x in u])
    assert np.array_equal(got, want)
    with mpmath.workdps(50):
        x = mpmath.mpf(1.3) / (2 * mpmath.pi)
        c1, c2, c3 = split_rate_exact(x)
        assert abs((mpmath.mpf(c1) + c2 + c3) - x) <= mpmath.mpf(10) ** -30 * abs(x)
