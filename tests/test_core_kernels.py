"""The compiled per-time evaluation of the theta-function rotation (thetasol.core.kernels) against its
numpy oracle (tests/oracle_theta_evaluation.py) on the 13 reference bodies of
tests/data/rotation/refs.json.

The kernel repeats the oracle's operations in the same order except in the two real matrix products
(the Fourier flow's ``(cos, sin) @ W`` and the folded linear map), whose summation order BLAS chooses.
Their rounding is at most ``terms x eps`` of the sum of the absolute terms; the bounds below are a few
eps of that sum (stated per test), and the state's bound follows from them through the quotient by
theta(d), the 45x36 product and the 3x3 algebra.
"""
import json
import pathlib

import numpy as np
import oracle_theta_evaluation as oracle
import pytest

from thetasol import inertia, solve_rotation

REFS = json.loads((pathlib.Path(__file__).parent / "data" / "rotation" / "refs.json").read_text())
TIMES = np.concatenate([[0.0, 0.37, 2.9, 41.3, 997.0, 1e6, 3.3e7, -12.5, 2.0 ** 31 + 0.25],
                        np.linspace(-3.0, 1000.0, 77)])
EPS = np.finfo(float).eps


@pytest.fixture(scope="module", params=sorted(REFS))
def sol(request):
    r = REFS[request.param]
    return solve_rotation(inertia(np.diag(r["J"])), np.array(r["a"]), np.array(r["Q0"]), np.array(r["omega0"]))


def test_flow_values_against_the_oracle(sol):
    """[v | dv] of the compiled flow against the oracle's, both against the long-double product of the
    oracle's phases with W.  The phases have modulus 1, so a sum in any order is within (terms) eps of
    ``sum |W|`` over the column; the kernel's blocked sums stay within 4 eps of it, and the two within
    16 eps of each other (the oracle's BLAS product may sum in any order, so it gets the looser bound)."""
    flow = sol.evaluator.flow
    _, v, dv = flow(TIMES)
    ov, odv = oracle.flow_values(flow, TIMES)
    scale = EPS * np.abs(flow.W).sum(axis=0).reshape(-1, 2).max(axis=1)           # per complex column
    S = v.shape[1]
    assert np.all(np.abs(v - ov) <= 16 * scale[None, :S])
    assert np.all(np.abs(dv - odv) <= 16 * scale[None, S:])
    phases = oracle.flow_phases(flow, oracle.flow_turns(flow, TIMES)).view(float)
    exact = (phases.astype(np.longdouble) @ flow.W.astype(np.longdouble)).view(np.clongdouble)
    assert np.all(np.abs(np.hstack([v, dv]) - exact) <= 4 * scale[None, :])


def test_state_against_the_oracle(sol):
    """omega and Q of the compiled evaluation against the oracle's, to rounding.  The flow's values differ
    by up to 16 eps of their column sums (test above), and the state amplifies that by its conditioning
    (large next to the unstable equilibrium, where theta(d) is small against its terms): the oracle run on
    values moved by that amount, with random signs, measures the amplification, and the kernel must lie
    within twice that spread (plus 2 eps for the last roundings after the quotient)."""
    ev = sol.evaluator
    w, Q = ev.evaluate(TIMES)
    ow, oQ = oracle.evaluate(ev, TIMES)
    assert w.shape == (len(TIMES), 3) and Q.shape == (len(TIMES), 3, 3)
    v, dv = oracle.flow_values(ev.flow, TIMES)
    scale = 16 * EPS * np.abs(ev.flow.W).sum(axis=0).reshape(-1, 2).max(axis=1)
    rng = np.random.default_rng(1)
    spread_w, spread_Q = np.zeros(len(TIMES)), np.zeros(len(TIMES))
    for _ in range(8):
        kick = scale * np.exp(2j * np.pi * rng.random((len(TIMES), scale.size)))
        pw, pQ = oracle.evaluate(ev, TIMES, (v + kick[:, :10], dv + kick[:, 10:]))
        spread_w = np.maximum(spread_w, np.abs(pw - ow).max(axis=1))
        spread_Q = np.maximum(spread_Q, np.abs(pQ - oQ).max(axis=(1, 2)))
    assert np.abs(Q - oQ).max() <= 2 * spread_Q.max() + 2 * EPS
    assert np.abs(w - ow).max() <= 2 * spread_w.max() + 2 * EPS * np.abs(ow).max()


def test_one_time_is_a_batch_of_one(sol):
    """Each time alone gives the bits of the batch: the kernel runs the same operations per time."""
    w, Q = sol.evaluator.evaluate(TIMES)
    for i in (0, 5, 6, 8, 20):
        w1, Q1 = sol.evaluator.evaluate(TIMES[i:i + 1])
        assert np.array_equal(w1[0], w[i]) and np.array_equal(Q1[0], Q[i])


def test_empty_times(sol):
    w, Q = sol.evaluator.evaluate(np.zeros(0))
    assert w.shape == (0, 3) and Q.shape == (0, 3, 3)
