"""Property tests of the free gyrostat over random carriers, rotor momenta and initial
velocities: |h|, the energy and the space momentum Q h conserved within the solution's own
error estimate, Q orthogonal to 1e-14.  A second family is concentrated on the singular level
sets (separatrices through saddles, and regular orbits on level sets with a relative
equilibrium elsewhere), exactly on them (to the rounding of the data) and at 1e-15 to 1e-4 from
them: there the solution is checked against the flow itself (DOP853 over a short step from
the closed-form state, anywhere on the orbit) and against heyoka in quadruple precision, and
its error estimate must bound the error."""
import importlib.util
import warnings

import numpy as np
import pytest
from conftest import rand_Q
from hypothesis import HealthCheck, assume, example, given, settings, strategies as st
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from thetasol import ClosedFormUnavailable, inertia, solve_gyrostat
from thetasol.core.so3 import hat

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


# found by the explore profile: W&W's inversion based at a general point has common zeros of
# numerator and denominator on this orbit (evaluated as written, the energy is 6.9e-11 of its scale
# off); with these seeds the random times fall next to them (5e-13 and 4e-12 off as written).
# Measured: energy 1.5 and 0.5 eps, |h| 3 and 1 eps
_FAILURE = (np.array([4.5, 2.0, 3.5]), np.array([0.0, -1.75, 1.421875]), np.array([0.0, 3.0, 0.0]))


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(gyrostats(), st.integers(0, 2 ** 32 - 1))
@example(_FAILURE, 0)
@example(_FAILURE, 26)
def test_conservation_and_orthogonality(data, seed):
    J, N, w0 = data
    rng = np.random.default_rng(seed)
    Q0 = rand_Q(rng)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        try:
            sol = solve_gyrostat(inertia(J), N, Q0, w0)
        except ClosedFormUnavailable:  # exactly on a separatrix of the gyrostat
            return
    I = J.sum() - J
    scale_t = 1.0 / max(np.max(np.abs(w0)), np.max(np.abs(N / I)), 1e-12)
    _check_invariants(sol, J, N, Q0, w0, scale_t * np.concatenate([rng.uniform(-30, 30, 12), [1e3]]))


def _check_invariants(sol, J, N, Q0, w0, t):
    """Q orthogonal to 1e-14; |h|, the energy and the space momentum Q h conserved at the times
    ``t`` within 64 eps plus the error estimate (per period: it grows with the periods)."""
    I = J.sum() - J
    h0 = I * w0 + N
    G = np.linalg.norm(h0)
    w, Q = sol(t)
    assert np.max(np.abs(np.swapaxes(Q, -1, -2) @ Q - np.eye(3))) <= 1e-14
    if G == 0:
        return
    T = sol.diagnostics["period"]  # (inf on a separatrix)
    nper = 1.0 + (np.max(np.abs(t)) / T if T > 0 else 0.0)
    tol = 64 * EPS + sol.diagnostics["error_estimate"] * nper
    h = w * I + N
    assert np.max(np.abs(np.linalg.norm(h, axis=-1) / G - 1)) <= tol
    T0 = 0.5 * np.sum(I * w0 * w0)
    E = 0.5 * np.sum(I * w * w, axis=-1)
    assert np.max(np.abs(E - T0)) <= tol * (T0 + G * G / I.min())
    L = np.einsum("nij,nj->ni", Q, h)
    assert np.max(np.abs(L - Q0 @ h0)) <= 4 * tol * G


# -- next to separatrices -------------------------------------------------------------------------

def _on_singular_level_set(J, N, lam, ang, beta, side):
    """Data on the level set of |h| and the energy through the relative equilibrium
    h_s = A N / (A - mu) (A = I^-1, mu = A_min + lam (A_max - A_min)): a point where a great
    circle of the momentum sphere through h_s crosses that level set again.  At a saddle the
    circle leaves h_s at the angle beta from an asymptotic direction of the level set (small beta:
    a point close to the saddle), at a centre at the angle ang.  None if the circle does not
    cross (or the data are out of range)."""
    I = J.sum() - J
    A = 1.0 / I
    mu = A.min() + lam * (A.max() - A.min())
    if np.any(np.abs(A - mu) < 1e-3 * A):
        return None
    hs = A * N / (A - mu)
    Gs = np.linalg.norm(hs)
    if not 1e-6 < Gs < 1e6:
        return None
    u = hs / Gs
    t1 = np.cross(u, np.eye(3)[np.argmin(np.abs(u))])
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(u, t1)
    Hm = np.diag(A - mu)
    H = np.array([[t1 @ Hm @ t1, t1 @ Hm @ t2], [t2 @ Hm @ t1, t2 @ Hm @ t2]])
    ev, V = np.linalg.eigh(H)
    if ev[0] * ev[1] < 0:  # a saddle
        a = np.arctan(np.sqrt(-ev[0] / ev[1]))
        v = V @ np.array([np.cos(a), side * np.sin(a)])
        ang = np.arctan2(v[1], v[0]) + beta
    d = np.cos(ang) * t1 + np.sin(ang) * t2
    Es = 0.5 * np.sum(A * (hs - N) ** 2)

    def f(al):
        h = Gs * (np.cos(al)[..., None] * u + np.sin(al)[..., None] * d)
        return 0.5 * np.sum(A * (h - N) ** 2, -1) - Es

    al = np.linspace(1e-4, 2 * np.pi - 1e-4, 4001)
    fv = f(al)
    idx = np.nonzero(np.sign(fv[:-1]) * np.sign(fv[1:]) < 0)[0]
    if len(idx) == 0:
        return None
    a0 = brentq(lambda x: float(f(np.array(x))), al[idx[0]], al[idx[0] + 1], xtol=1e-300, rtol=8.9e-16)
    h0 = Gs * (np.cos(a0) * u + np.sin(a0) * d)
    return A * (h0 - N)


@st.composite
def near_separatrix(draw):
    J = np.array(draw(st.lists(st.floats(0.1, 4.0), min_size=3, max_size=3)))
    N = np.array(draw(vec)) * 10 ** draw(st.floats(-1, 1))
    lam = draw(st.floats(-0.2, 1.2))
    beta = draw(st.sampled_from([0.0, 1e-6, 1e-3, 0.05, 0.3])) * draw(st.sampled_from([-1, 1]))
    w0 = _on_singular_level_set(J, N, lam, draw(st.floats(0, 2 * np.pi)), beta,
                                draw(st.sampled_from([-1.0, 1.0])))
    assume(w0 is not None)
    dist = draw(st.sampled_from([0.0, 1e-15, 1e-12, 1e-8, 1e-4]))
    w0 = w0 * (1 + dist * np.array(draw(st.lists(st.floats(-1, 1), min_size=3, max_size=3))))
    return J, N, w0


def _solve(J, N, Q0, w0):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        try:
            return solve_gyrostat(inertia(J), N, Q0, w0)
        except ClosedFormUnavailable:  # within 1e-307 of a separatrix
            return None


# the first two were found on singular level sets: a data point next to the saddle (the tangent
# line of the pencil's anchor passes close to it: 2.4e-11 with the anchor there), a turning point
# of the pencil next to the saddle (a residual coefficient cancels there: 1e-12)
_HARD = [
    (np.array([1.5422519500024736, 1.737423829414948, 1.0215431193207938]),
     np.array([-5.829591040703852, -3.4742576190041543, -4.5236231145773225]),
     np.array([52.78821807222933, -40.973780990940874, 7.149238634824681])),
    (np.array([0.8802899850162753, 2.693647151186379, 0.41676817476893424]),
     np.array([-0.8480358053942576, 0.6699161416834842, -1.363954913923379]),
     np.array([-0.18837914651566254, -2.0416296115943746, -0.08081750545349492])),
    (np.array([0.75, 0.25, 1.25]), np.array([0.0, 0.0, 2.0]), np.array([0.0, 2.0, 1.0])),  # on it
    # mc = 5e-17: the mpmath algebra needs digits growing like log(1/mc) (at a fixed 34 digits the
    # re-anchored curve's mc is off by 3e-12 and the phase by 1e-13 after 0.08 periods)
    (np.array([3.30182274, 1.9, 1.80965273]), np.array([0.0, 1e-05, 0.0]),
     np.array([9.18896998e-10, -1.01638667e-05, 4.84024988e-10])),
]


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(near_separatrix(), st.integers(0, 2 ** 32 - 1))
@example(_HARD[0], 1)
@example(_HARD[1], 2)
@example(_HARD[2], 3)
def test_near_separatrix_invariants_and_flow(data, seed):
    """Invariants to round-off (within the estimate) at random and far times, Q orthogonal, and the
    closed form a solution of the equations of motion anywhere on the orbit: DOP853 from the
    closed-form state at t1 over a short step lands on the closed form at t1 + dt."""
    J, N, w0 = data
    rng = np.random.default_rng(seed)
    Q0 = rand_Q(rng)
    sol = _solve(J, N, Q0, w0)
    if sol is None:
        return
    I = J.sum() - J
    G = np.linalg.norm(I * w0 + N)
    assert G > 0
    T = sol.diagnostics["period"]
    tc = 1.0 / max(np.max(np.abs(w0)), np.max(np.abs(N / I)))
    tspan = min(T, 1e3 * tc) if np.isfinite(T) and T > 0 else 30 * tc
    t = np.concatenate([rng.uniform(-3, 3, 10) * tspan, [1e4 * tspan, -1e6 * tc]])
    _check_invariants(sol, J, N, Q0, w0, t)
    # the flow: one step of ~1/|omega| from a random point of the orbit (a saddle passage
    # included when the point is next to one)
    t1 = rng.uniform(-2, 2) * tspan
    dt = 2 * tc
    w1, Q1 = sol(np.array([t1, t1 + dt]))

    def rhs(_t, y):
        w_ = y[:3] / I
        return np.concatenate([np.cross(y[:3] + N, w_), (y[3:].reshape(3, 3) @ hat(w_)).ravel()])

    y = solve_ivp(rhs, (0, dt), np.concatenate([I * w1[0], Q1[0].ravel()]), rtol=1e-13,
                  atol=1e-16 * G, method="DOP853").y[:, -1]
    assert np.max(np.abs(y[:3] - I * w1[1])) <= 1e-12 * G
    assert np.max(np.abs(y[3:].reshape(3, 3) - Q1[1])) <= 1e-12


@pytest.mark.skipif(importlib.util.find_spec("heyoka") is None, reason="heyoka not installed")
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(near_separatrix(), st.integers(0, 2 ** 32 - 1))
@example(_HARD[0], 4)
@example(_HARD[1], 5)
@example(_HARD[2], 6)
@example(_HARD[3], 0)
def test_near_separatrix_error_estimate_bounds_the_error(data, seed):
    """Against heyoka in quadruple precision (tol 1e-32, the same exact data): over the first
    stretch of the orbit (a saddle passage when the data are next to one) the error in m,
    relative to max |m|, is within the solution's error estimate (per period) and within
    1e-12, and so is the attitude's."""
    from test_gyrostat import heyoka_ref

    J, N, w0 = data
    rng = np.random.default_rng(seed)
    Q0 = rand_Q(rng)
    sol = _solve(J, N, Q0, w0)
    if sol is None or sol.method != "elliptic":
        return
    I = J.sum() - J
    T = sol.diagnostics["period"]
    tc = 1.0 / max(np.max(np.abs(w0)), np.max(np.abs(N / I)))
    tspan = min(T, 40 * tc) if np.isfinite(T) else 40 * tc
    t = np.sort(rng.uniform(-1, 1, 12)) * tspan
    w, Q = sol(t)
    wr, Qr = heyoka_ref(inertia(J), N, Q0, w0, t, quad=True)
    m, mr = w * I, wr * I
    err = np.max(np.abs(m - mr)) / np.max(np.abs(mr))
    nper = 1.0 + (tspan / T if np.isfinite(T) else 0.0)
    assert err <= 2 * sol.diagnostics["error_estimate"] * nper + 16 * EPS
    assert err <= 1e-12
    assert np.max(np.abs(Q - Qr)) <= 1e-12
