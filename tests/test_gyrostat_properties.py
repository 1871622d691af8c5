"""Property tests of the free gyrostat over random carriers, rotor momenta and initial
velocities: |h|, the energy and the space momentum Q h conserved within the solution's own
error estimate, Q orthogonal to 1e-14."""
import warnings

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from thetasol import solve_gyrostat

EPS = np.finfo(float).eps
vec = st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=3)


@st.composite
def gyrostats(draw):
    J = np.array(draw(st.lists(st.floats(0.05, 5.0), min_size=3, max_size=3)))
    if draw(st.booleans()):  # nearly or exactly axisymmetric carriers too
        J[1] = J[0] * (1 + draw(st.sampled_from([0.0, 1e-6, 1e-3, 0.1])))
    N = np.array(draw(vec)) * 10 ** draw(st.floats(-3, 1))
    if draw(st.booleans()):
        N[draw(st.integers(0, 2))] = 0.0
    w0 = np.array(draw(vec))
    return J, N, w0


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(gyrostats(), st.integers(0, 2 ** 32 - 1))
def test_conservation_and_orthogonality(data, seed):
    J, N, w0 = data
    rng = np.random.default_rng(seed)
    Q0 = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    Q0 *= np.linalg.det(Q0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        try:
            sol = solve_gyrostat(J, N, Q0, w0)
        except NotImplementedError:  # exactly on a separatrix of the gyrostat
            return
    I = J.sum() - J
    h0 = I * w0 + N
    G = np.linalg.norm(h0)
    scale_t = 1.0 / max(np.max(np.abs(w0)), np.max(np.abs(N / I)), 1e-12)
    t = scale_t * np.concatenate([rng.uniform(-30, 30, 12), [1e3]])
    w, Q = sol(t)
    assert np.max(np.abs(np.swapaxes(Q, -1, -2) @ Q - np.eye(3))) <= 1e-14
    if G == 0:
        return
    # the error estimate is per period; allow it to grow with the number of periods
    T = sol.invariants["period"]
    nper = 1.0 + (np.max(np.abs(t)) / T if T > 0 else 0.0)
    tol = 64 * EPS + sol.invariants["error_estimate"] * nper
    h = w * I + N
    assert np.max(np.abs(np.linalg.norm(h, axis=-1) / G - 1)) <= tol
    T0 = 0.5 * np.sum(I * w0 * w0)
    E = 0.5 * np.sum(I * w * w, axis=-1)
    assert np.max(np.abs(E - T0)) <= tol * (T0 + G * G / I.min())
    L = np.einsum("nij,nj->ni", Q, h)
    assert np.max(np.abs(L - Q0 @ h0)) <= 4 * tol * G
