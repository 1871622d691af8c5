"""Property tests of the exact free rigid body over random bodies and momenta in every regime:
first integrals conserved to round-off, Q orthogonal to 1e-14, the space angular momentum fixed."""
import math

import numpy as np
from conftest import label, rand_Q
from hypothesis import HealthCheck, given, settings, strategies as st

from thetasol import inertia, solve_rotation

Z = np.zeros((3, 3))
EPS = np.finfo(float).eps

moment = st.floats(0.05, 20.0)
closeness = st.sampled_from([0.0, 1e-15, 1e-12, 1e-8, 1e-4, 0.3])
# components 0 or of relative size >= 1e-100 (smaller ones are served by the slow mpmath
# fallback, tested separately in test_euler_top.py)
unit = st.floats(-1.0, 1.0).map(lambda x: 0.0 if abs(x) < 1e-100 else x)


@st.composite
def body_and_momentum(draw):
    """Principal second moments (nearly symmetric ones included) and a body angular momentum
    anywhere: generic, near or on the separatrix, near or on a principal axis."""
    j1 = draw(moment)
    j2 = j1 * (1 + draw(closeness)) if draw(st.booleans()) else draw(moment)
    j3 = draw(moment)
    J = np.array(draw(st.permutations([j1, j2, j3])))
    I = J.sum() - J
    kind = draw(st.sampled_from(["generic", "separatrix", "near-separatrix", "near-axis", "axis"]))
    m = np.array([draw(unit), draw(unit), draw(unit)])
    lo, mid, hi = np.argsort(I, kind="stable")
    if kind in ("separatrix", "near-separatrix") and I[mid] > I[lo] and I[hi] > I[mid]:
        # m_hi^2 (I_hi - I_mid)/I_hi = m_lo^2 (I_mid - I_lo)/I_lo on the separatrix
        rho = (I[mid] - I[lo]) * I[hi] / ((I[hi] - I[mid]) * I[lo])
        m[hi] = np.copysign(np.sqrt(rho) * abs(m[lo]), m[hi])
        if kind == "near-separatrix":
            m[hi] *= 1 + draw(st.sampled_from([-1e-10, 1e-10, -1e-6, 1e-13]))
    elif kind == "near-axis":
        ax = draw(st.integers(0, 2))
        m *= draw(st.sampled_from([1e-9, 1e-5]))
        m[ax] = 1.0
    elif kind == "axis":
        ax = draw(st.integers(0, 2))
        m = np.zeros(3)
        m[ax] = draw(unit) or 1.0
    scale = 10 ** draw(st.floats(-3, 3))
    return J, I, m * scale


@settings(max_examples=250, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(body_and_momentum(), st.integers(0, 2 ** 32 - 1))
def test_invariants_and_orthogonality(data, seed):
    J, I, m0 = data
    rng = np.random.default_rng(seed)
    Q0 = rand_Q(rng)
    w0 = m0 / I
    sol = solve_rotation(inertia(J), Z, Q0, w0)
    G0 = math.hypot(*m0)  # no underflow of tiny squares
    # times in units of the motion's own time scale, near and far
    Tscale = 1.0 / max(np.max(np.abs(w0)), 1e-300)
    t = Tscale * np.concatenate([rng.uniform(-50, 50, 20), [1e4, -3e5 + 0.7]])
    w, Q = sol(t)
    m = w * I / G0 if G0 > 0 else w * I  # relative to |m0| (no underflow of tiny squares)
    # Q in SO(3) to 1e-14
    assert np.max(np.abs(np.swapaxes(Q, -1, -2) @ Q - np.eye(3))) <= 1e-14
    assert np.max(np.abs(np.linalg.det(Q) - 1.0)) <= 1e-14
    if G0 == 0:
        return
    # |m|^2 and the energy to round-off
    m0u = m0 / G0
    assert np.max(np.abs(np.sum(m * m, -1) - 1)) <= 16 * EPS
    T0 = np.sum(m0u * m0u / I)
    assert np.max(np.abs(np.sum(m * m / I, -1) / T0 - 1)) <= 16 * EPS
    # the space angular momentum Q m is fixed
    L = np.einsum("nij,nj->ni", Q, m)
    assert np.max(np.abs(L - Q0 @ m0u)) <= 3e-14


@settings(max_examples=60, deadline=None)
@given(body_and_momentum())
def test_regime_labels_are_consistent(data):
    J, I, m0 = data
    sol = solve_rotation(inertia(J), Z, np.eye(3), m0 / I)
    G = math.hypot(*m0)
    # m x omega = 0 exactly: m_j m_k (I_j - I_k) = 0 for every pair, with I_j - I_k = J_k - J_j
    steady = all(m0[j] == 0 or m0[k] == 0 or J[k] == J[j] for j, k in ((1, 2), (2, 0), (0, 1)))
    if G == 0:
        assert label(sol) == "elementary:rest"
    elif steady:
        assert label(sol) == "elementary:steady"
    else:
        assert label(sol) in ("elliptic", "elliptic:separatrix", "elementary:symmetric")
        assert 0.0 <= sol.diagnostics["m"] <= 1.0
