"""theta.grid.theta_grid (theta with half characteristics on a 2-D torus grid as matrix products) against
RiemannTheta.jet point by point, and the Kovalevskaya phase series built on it against the same series built
from KovalevskayaMotion.values_at point by point."""
from __future__ import annotations

import numpy as np
import pytest

from thetasol.theta.grid import theta_grid
from thetasol.theta.riemann import RiemannTheta


def _random_tau(rng, g, cond=1.0):
    Q, _ = np.linalg.qr(rng.normal(size=(g, g)))
    Y = Q @ np.diag(np.geomspace(1.0, cond, g) * rng.uniform(0.6, 1.4)) @ Q.T
    X = rng.uniform(-0.5, 0.5, (g, g))
    return 0.5 * (X + X.T) + 1j * Y


def _against_jet(tau, z0, k1, k2, a, b, V):
    """Max error of values and derivatives, relative to each point's largest value (derivative)."""
    g = len(tau)
    G = theta_grid(tau, z0, k1, k2, a, b, "all", V)
    x = a[:, None, None] * k1 + b[None, :, None] * k2 - G.shift
    e, v, gr = RiemannTheta(tau).jet(z0 + x[..., :g] + x[..., g:] @ tau.T, char="all", order=1, separated=True)
    ab = (np.arange(4 ** g)[:, None] >> np.arange(2 * g - 1, -1, -1)) & 1      # flint order: 2 alpha, 2 beta
    sign = 1 - 2 * np.mod(G.shift[..., :g] @ ab[:, :g].T + G.shift[..., g:] @ ab[:, g:].T, 2)
    f = np.exp(e - G.e)[..., None] * sign
    v, dv = v * f, (gr @ V) * f
    # the exponents (|e| up to ~600 here) are float64 numbers: exp(e) carries |e| eps, common to all
    # characteristics; that factor r is fitted per point and checked against the exponents' rounding
    r = np.sum(np.conj(v) * G.value, -1) / np.sum(np.abs(v) ** 2, -1)
    er = np.max(np.abs(r - 1) / (np.maximum(np.abs(e), np.abs(G.e)) + 1)) / np.finfo(float).eps
    v, dv = v * r[..., None], dv * r[..., None]
    ev = np.max(np.abs(G.value - v) / np.max(np.abs(v), -1, keepdims=True))
    ed = np.max(np.abs(G.derivative - dv) / np.max(np.abs(dv), -1, keepdims=True))
    return ev, ed, er


@pytest.mark.parametrize("seed, cond, bound", [(0, 1.0, 2e-14), (1, 1.0, 2e-14), (2, 30.0, 3e-14), (3, 300.0, 1.5e-13)])
def test_grid_genus2_against_jet(seed, cond, bound):
    # grids over several lattice cells (k1, k2 with entries up to 3).  Measured values / derivatives:
    # 3.2e-15 / 3.2e-15 and 2.8e-15 / 3.2e-15 (Im tau conditioned 1), 8.3e-15 / 1.3e-14 (30), 2.5e-14 / 4.6e-14
    # (300: the sum runs in the frame of tau, not Siegel-reduced, and its exponents lose ~cond(Im tau) eps);
    # the common factor within 21 |e| eps
    rng = np.random.default_rng(seed)
    tau = _random_tau(rng, 2, cond)
    k1, k2 = rng.integers(-3, 4, 4).astype(float), rng.integers(-3, 4, 4).astype(float)
    z0 = rng.uniform(-0.5, 0.5, 2) + 1j * (tau.imag @ rng.uniform(-0.5, 0.5, 2))
    V = rng.normal(size=2) + 1j * rng.normal(size=2)
    ev, ed, er = _against_jet(tau, z0, k1, k2, np.arange(48) / 48, (np.arange(40) + 0.5) / 40, V)
    assert ev < bound and ed < bound and er < 50


@pytest.mark.parametrize("g", [3, 4])
def test_grid_higher_genus_against_jet(g):
    # measured 2.7e-15 / 3.9e-15 (g = 3), 2.3e-15 / 2.6e-15 (g = 4), the common factor within 4 |e| eps
    rng = np.random.default_rng(10 + g)
    tau = _random_tau(rng, g, 5.0)
    k1, k2 = rng.integers(-2, 3, 2 * g).astype(float), rng.integers(-2, 3, 2 * g).astype(float)
    z0 = rng.uniform(-0.5, 0.5, g) + 1j * (tau.imag @ rng.uniform(-0.5, 0.5, g))
    V = rng.normal(size=g) + 1j * rng.normal(size=g)
    ev, ed, er = _against_jet(tau, z0, k1, k2, np.arange(12) / 12, np.arange(10) / 10, V)
    assert ev < 2e-14 and ed < 2e-14 and er < 16


def test_grid_selected_characteristics_and_order():
    # a selection of characteristics, in the caller's order, equals those columns of "all"
    rng = np.random.default_rng(5)
    tau = _random_tau(rng, 2)
    k1, k2, z0 = np.array([1.0, 0, 2, -1]), np.array([0.0, 1, -1, 1]), np.array([0.1 + 0.2j, -0.3 + 0.1j])
    a, b = np.arange(20) / 20, np.arange(16) / 16
    chars = [((0.5, 0.0), (0.5, 0.5)), None, ((0.0, 0.5), (0.0, 0.0))]
    G = theta_grid(tau, z0, k1, k2, a, b, chars, [1.0, 0.5j])
    H = theta_grid(tau, z0, k1, k2, a, b, "all", [1.0, 0.5j])
    f = np.exp(G.e - H.e)[..., None]
    idx = [2 * 4 + 3, 0, 1 * 4 + 0]
    assert np.max(np.abs(G.value * f - H.value[..., idx])) < 1e-14 * np.max(np.abs(H.value))
    assert np.max(np.abs(G.derivative * f - H.derivative[..., idx])) < 1e-14 * np.max(np.abs(H.derivative))
    with pytest.raises(ValueError, match="half-integer"):
        theta_grid(tau, z0, k1, k2, a, b, [((0.25, 0.0), (0.0, 0.0))])
    with pytest.raises(ValueError, match="empty"):
        theta_grid(tau, z0, k1, k2, a, [])
    with pytest.raises(ValueError, match="NaN"):
        theta_grid(tau, z0, k1, k2, np.array([0.1, np.nan]), b)
    with pytest.raises(ValueError, match="shape"):
        theta_grid(tau, z0, k1[:3], k2, a, b)


# -- the Kovalevskaya phase series: the grid against values_at point by point ------------------------------

def _pointwise(self, k1, k2, a, b, order=0):
    return self.values_at(np.asarray(a)[:, None, None] * k1 + np.asarray(b)[None, :, None] * k2, order)


@pytest.mark.parametrize("seed", [2, 4, 14, 17])
def test_kovalevskaya_phase_series_grid_against_pointwise(seed, monkeypatch):
    # measured: coefficients on the common modes <= 1.7e-15, mean rate <= 1.6e-15, phase tails <= 5.6e-16 apart,
    # Q(t) <= 4.6e-14 on [0, 30] (seed 4: its edge coefficient on axis 1 is at PHASE_TOL, so the two choose
    # 128 x 256 and 64 x 256 grids, and the mean rates differ by 1.6e-15); the other seeds pick the same grid
    from test_kovalevskaya_top import G, _top

    from thetasol.solutions.tops.kovalevskaya_attitude import build_kovalevskaya_top
    from thetasol.solutions.tops.kovalevskaya_top import KovalevskayaMotion

    I, c, Q0, w0 = _top(seed)
    att, diag = build_kovalevskaya_top(I, c, Q0, w0, **G)
    with monkeypatch.context() as mp:
        mp.setattr(KovalevskayaMotion, "values_on_grid", _pointwise)
        ref, rdiag = build_kovalevskaya_top(I, c, Q0, w0, **G)
    assert att.ref == ref.ref and (att.grid == ref.grid or seed == 4)
    (j1, k1), (j2, k2) = att.modes, ref.modes
    J, K = np.intersect1d(j1, j2), np.intersect1d(k1, k2)
    A = att.coef[np.ix_(np.isin(j1, J), np.isin(k1, K))]
    B = ref.coef[np.ix_(np.isin(j2, J), np.isin(k2, K))]
    assert np.max(np.abs(A - B)) < 5e-15
    assert abs(att.rate[0] - ref.rate[0]) < 5e-15 * max(1.0, abs(ref.rate[0]))
    assert abs(diag["phase_tail"] - rdiag["phase_tail"]) < 2e-15
    t = np.linspace(0.0, 30.0, 301)
    assert np.max(np.abs(att(t)[1] - ref(t)[1])) < 1.5e-13


def test_grid_genus1_unsorted_single_points():
    # genus 1; unsorted, unevenly spaced coordinates (sorted inside); a single point; a single column.  Measured
    # values / derivatives 1.5e-15 / 2.3e-15, 1.9e-15 / 2.3e-15, 5.4e-16 / 8.7e-16, 1.4e-15 / 1.4e-15
    rng = np.random.default_rng(0)
    cases = [(np.array([[0.3 + 1.2j]]), np.array([0.1 + 0.2j]), np.array([1.0, 2.0]), np.array([0.0, 1.0]),
              np.arange(10) / 10, np.arange(7) / 7, 1e-14)]
    tau = np.array([[1.1j, 0.3 + 0.2j], [0.3 + 0.2j, 0.9j - 0.4]])
    k1, k2, z0 = np.array([1.0, 0, 2, 1]), np.array([0.0, 1, -1, 2]), np.array([0.1, 0.2j])
    cases += [(tau, z0, k1, k2, rng.uniform(0, 1, 37), rng.uniform(-1, 2, 19), 1e-14),
              (tau, z0, k1, k2, np.array([0.3]), np.array([0.7]), 1e-14),
              (tau, z0, k1, k2, np.arange(33) / 33, np.array([0.7]), 1e-14)]
    for tau, z0, k1, k2, a, b, bound in cases:
        V = np.ones(len(tau)) + 0.5j
        ev, ed, er = _against_jet(tau, z0, k1, k2, a, b, V)
        assert ev < bound and ed < bound and er < 16
