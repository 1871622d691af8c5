"""Gyrostats in a potential, on an orbit and on a pivot (Section 8, (8.32)-(8.38)): the references
integrate_gyrostat / integrate_heavy_gyrostat against 80-bit heyoka, the closed free gyrostat, and their
first integrals; the Lagrange gyrostat in closed form against them.
"""
import math

import numpy as np
import pytest
from conftest import label, rand_Q

from thetasol import inertia
from thetasol.integrators.gyrostat import integrate_gyrostat, integrate_heavy_gyrostat
from thetasol.mechanics.rotors import gyrostat_energy
from thetasol.protocol import ClosedFormUnavailable
from thetasol.solutions.gyrostat import solve_gyrostat
from thetasol.solutions.orbit.kepler import KeplerOrbit
from thetasol.solutions.tops.lagrange_gyrostat import solve_lagrange_gyrostat

J0 = np.array([[1.2, 0.1, 0.05], [0.1, 0.7, 0.02], [0.05, 0.02, 0.4]])
ROTORS = [{"axis": [1.0, 0.0, 0.0], "A": 0.05, "B": 0.03, "p": 0.4},
          {"axis": [0.0, 0.6, 0.8], "A": 0.02, "B": 0.02, "p": -0.3}]
A_POT = np.array([[0.7, 0.1, 0.3], [0.1, 0.3, 0.2], [0.3, 0.2, 0.2]])


def _full(J, rotors):
    """The carrier's second moments with the rotors' axial moments restored (what the potential sees)."""
    return J + sum(0.5 * r["A"] * (np.eye(3) - 2 * np.outer(r["axis"], r["axis"])) for r in rotors)


def test_free_reference_matches_closed_form_with_rotor_angles():
    rng = np.random.default_rng(1)
    Q0, w0 = rand_Q(rng), np.array([0.3, -0.5, 0.9])
    t = np.linspace(-50.0, 100.0, 16).reshape(4, 4)   # both directions, any shape
    sol = solve_gyrostat(inertia(J0), None, Q0, w0, rotors=ROTORS)
    w, Q, ang = integrate_gyrostat(inertia(J0), None, Q0, w0, rotors=ROTORS, rtol=1e-13).evaluate_with_angles(t)
    # measured 8.7e-15, 7.4e-13, 2.3e-13
    assert np.max(np.abs(w - sol.omega(t))) < 1e-12
    assert np.max(np.abs(Q - sol.Q(t))) < 5e-12
    assert np.max(np.abs(ang - sol.rotor_angles(t))) < 2e-12


def test_potential_reference_against_80bit_heyoka_and_energy():
    pytest.importorskip("heyoka")
    rng = np.random.default_rng(2)
    Q0, w0 = rand_Q(rng), np.array([0.3, -0.5, 0.9])
    t = np.linspace(0.0, 100.0, 21)
    w, Q, ang = integrate_gyrostat(inertia(J0), None, Q0, w0, rotors=ROTORS, a=A_POT,
                                   rtol=1e-13).evaluate_with_angles(t)
    wh, Qh, angh = integrate_gyrostat(inertia(J0), None, Q0, w0, rotors=ROTORS, a=A_POT, rtol=1e-19, method="heyoka",
                                      fp_type=np.longdouble).evaluate_with_angles(t)
    # measured 4.1e-13, 1.3e-12, 5.2e-12 at rtol 1e-13
    assert np.max(np.abs(w - wh)) < 5e-12
    assert np.max(np.abs(Q - Qh)) < 1e-11
    assert np.max(np.abs(ang - angh)) < 5e-11
    E = gyrostat_energy(inertia(_full(J0, ROTORS)), inertia(J0), A_POT, Qh, wh)   # (8.34)
    assert np.max(np.abs(E - E[0])) < 5e-15 * abs(E[0])   # measured 5.4e-16 relative
    # the rotor momenta are data of the reduced system; its N is sum p l (8.33)
    with pytest.raises(ValueError, match="8.33"):
        integrate_gyrostat(inertia(J0), [1.0, 0, 0], Q0, w0, rotors=ROTORS, a=A_POT).evaluate_with_angles(t)


def test_axial_moments_act_in_the_potential():
    """The potential acts on the rotors' axial moments too: leaving them out is another motion."""
    rng = np.random.default_rng(3)
    Q0, w0 = rand_Q(rng), np.array([0.3, -0.5, 0.9])
    t = np.array([0.0, 20.0])
    N = sum(r["p"] * np.array(r["axis"]) for r in ROTORS)
    w1, _, _ = integrate_gyrostat(inertia(J0), None, Q0, w0, rotors=ROTORS, a=A_POT).evaluate_with_angles(t)
    w2, _, _ = integrate_gyrostat(inertia(J0), N, Q0, w0, a=A_POT).evaluate_with_angles(t)
    assert np.max(np.abs(w1 - w2)) > 1e-3


def test_circular_orbit_jacobi_integral_838():
    mu, r0 = 1.0, 4.0
    n = math.sqrt(mu / r0 ** 3)
    orbit = KeplerOrbit(mu, [r0, 0.0, 0.0], [0.0, math.sqrt(mu / r0), 0.0])
    rng = np.random.default_rng(4)
    Q0, w0 = rand_Q(rng), np.array([0.02, -0.05, 0.09])
    rot = [{"axis": [0.0, 0.0, 1.0], "A": 0.05, "p": 0.02}, {"axis": [1.0, 0.0, 0.0], "A": 0.02, "p": -0.01}]
    t = np.linspace(0.0, 2 * 2 * math.pi / n, 41)
    w, Q, _ = integrate_gyrostat(inertia(J0), None, Q0, w0, rotors=rot, orbit=orbit, rtol=1e-12).evaluate_with_angles(t)
    Jf = _full(J0, rot)
    If = np.trace(Jf) * np.eye(3) - Jf
    Ig = np.trace(J0) * np.eye(3) - J0
    N = sum(r["p"] * np.array(r["axis"]) for r in rot)
    r = np.array([orbit.state_at(x)[0] for x in t])
    gam = np.einsum("tji,tj->ti", Q, r / r0)
    nrm = np.einsum("tji,j->ti", Q, [0.0, 0.0, 1.0])
    m = w @ Ig
    H = 0.5 * np.sum(m * w, axis=1) + 1.5 * n ** 2 * np.einsum("ti,ij,tj->t", gam, If, gam) \
        - n * np.sum((m + N) * nrm, axis=1)
    # (8.38); measured 1.3e-12 relative over two orbits (DOP853 at rtol 1e-12)
    assert np.max(np.abs(H - H[0])) < 1e-11 * abs(H[0])
    # with the rotor momentum left out of the Jacobi integral it drifts
    H0 = H + n * (nrm @ N)
    assert np.ptp(H0) > 1e3 * np.ptp(H)


def _lagrange_case(k):
    rng = np.random.default_rng(10 + k)
    R = rand_Q(rng)
    A_, C_ = [(1.3, 0.6), (0.9, 1.4), (2.0, 0.5)][k]
    I = R @ np.diag([A_, A_, C_]) @ R.T
    c = R @ np.array([0.0, 0.0, 0.4])
    lam = [0.8, -2.5, 5.0][k]
    return I, c, lam * c / np.linalg.norm(c), rand_Q(rng), rng.normal(size=3) * [0.5, 0.5, 1.5]


@pytest.mark.parametrize("k", range(3))
def test_lagrange_gyrostat_against_80bit_heyoka(k):
    pytest.importorskip("heyoka")
    I, c, N, Q0, w0 = _lagrange_case(k)
    sol = solve_lagrange_gyrostat(I, c, Q0, w0, N=N, mass=2.0)
    assert label(sol) == "elliptic"
    t = np.linspace(0.0, 100.0, 201)
    w, Q = sol(t)
    wh, Qh = integrate_heavy_gyrostat(I, c, Q0, w0, N=N, mass=2.0, rtol=1e-19, method="heyoka",
                                      fp_type=np.longdouble)(t)
    # measured 1.9e-13 .. 3.3e-13 (omega), 3e-14 .. 1e-13 (Q)
    assert np.max(np.abs(w - wh)) < 2e-12 * max(1.0, np.max(np.abs(wh)))
    assert np.max(np.abs(Q - Qh)) < 1e-12
    wd, Qd = integrate_heavy_gyrostat(I, c, Q0, w0, N=N, mass=2.0, rtol=1e-13)(t[:21])
    assert np.max(np.abs(Qd - Qh[:21])) < 1e-11


@pytest.mark.parametrize("k", range(3))
def test_lagrange_gyrostat_invariants_far_away(k):
    I, c, N, Q0, w0 = _lagrange_case(k)
    sol = solve_lagrange_gyrostat(I, c, Q0, w0, N=N, mass=2.0)
    t = np.array([0.0, 1.0, 1e3, 1e6])
    w, Q = sol(t)
    g = np.array([0.0, 0.0, -9.81])
    m = w @ I.T + N
    E = 0.5 * np.sum((w @ I.T) * w, axis=1) - 2.0 * (Q @ c) @ g
    Lz = np.einsum("tij,tj->ti", Q, m)[:, 2]
    L3 = m @ (c / np.linalg.norm(c))
    inv = sol.invariants
    # measured <= 1.2e-15 relative up to t = 1e6
    for x, ref in ((E, inv["energy"]), (Lz, inv["vertical_momentum"]), (L3, inv["axial_momentum"])):
        assert np.max(np.abs(x - ref)) < 1e-14 * (abs(ref) + np.max(np.abs(E)))


def test_lagrange_gyrostat_refusals_and_limits():
    I, c, N, Q0, w0 = _lagrange_case(0)
    Ntilted = N + 0.1 * np.cross(c, [1.0, 0, 0])
    with pytest.raises(ClosedFormUnavailable, match="integrate_heavy_gyrostat"):
        solve_lagrange_gyrostat(I, c, Q0, w0, N=Ntilted)
    assert label(solve_lagrange_gyrostat(I, c, Q0, w0, N=np.zeros(3))) == "elliptic"
    free = solve_lagrange_gyrostat(I, c, Q0, w0, N=N, gravity=[0.0, 0.0, 0.0])
    # no torque: the free gyrostat of the same body, still a heavy-top result (its centre, mass, invariants)
    assert free.model == "heavy-top" and free.case.startswith("gyrostat") and np.array_equal(free.center, c)
    assert {"energy", "vertical_momentum", "axial_momentum"} <= set(free.invariants)
    t = np.linspace(0.0, 5.0, 11)
    gyro = solve_gyrostat(free.I, N, Q0, w0)   # the body as the heavy top validated it
    for sol in (free, solve_lagrange_gyrostat(I, np.zeros(3), Q0, w0, N=N)):
        assert sol.model == "heavy-top" and np.all(np.isfinite(list(sol.invariants.values())))
        (w, Q), (wg, Qg) = sol(t), gyro(t)
        assert np.array_equal(w, wg) and np.abs(Q - Qg).max() <= 4 * np.finfo(float).eps


def test_numerical_gyrostat_protocol():
    rng = np.random.default_rng(7)
    Q0, w0 = rand_Q(rng), np.array([0.3, -0.5, 0.9])
    sol = integrate_gyrostat(inertia(J0), None, Q0, w0, rotors=ROTORS, a=A_POT, rtol=1e-12)
    assert sol.model == "gyrostat" and sol.method == "numerical/DOP853" and sol.diagnostics["error_estimate"] == 1e-12
    t = np.array([[0.0, 3.0], [-2.0, 7.0]])
    w, Q = sol(t)
    assert w.shape == (2, 2, 3) and Q.shape == (2, 2, 3, 3) and sol.rotor_angles(t).shape == (2, 2, 2)
    w2, Q2, ang = sol.evaluate_with_angles(t)
    assert np.array_equal(w, w2) and np.array_equal(sol.rotor_angles(t), ang)
    E = gyrostat_energy(inertia(_full(J0, ROTORS)), inertia(J0), A_POT, Q, w)
    assert np.max(np.abs(E - sol.invariants["energy"])) < 1e-11 * abs(sol.invariants["energy"])
    assert np.allclose(sol.invariants["rotor_momenta"], [0.4, -0.3])
