"""Rotors in the model (Section 8): the data, assumption (8.12), and the reduction (8.15)-(8.33) checked
against bodies made of point masses.

The reduction is checked by brute force: carrier and rotors are clouds of point masses (a rotor of
masses with 4-fold symmetry about its axis has the symmetric second moments of (8.12)); the kinetic
energy of every point, moved by the carrier's rate and the rotor's relative spin, must equal
``1/2 omega . I_gyro omega + sum_a 1/2 A_a (omega . l_a + phidot_a)^2`` (the Lagrangian (8.22) with
``A``, ``B``, ``z`` of (8.15)-(8.16) and ``J_k`` (8.23)), and the potential energy
``sum m phi(x)`` must be that of the mass centre plus ``1/2 tr(Q J_k Q^T a)`` for every rotor angle.
"""
import numpy as np
import pytest
from conftest import rand_Q

from thetasol.core.inertia import inertia
from thetasol.core.so3 import complete_frame, hat
from thetasol.mechanics.bodies import Body
from thetasol.mechanics.configuration import Joint
from thetasol.mechanics.rotors import GyrostatConfiguration, MasslessCarrier, Rotor, axis_rotation, gyrostat_energy


def _frame(l):
    return tuple(complete_frame(l)[:, :2].T)


def _ring_rotor(name, carrier, axis, point, rng):
    """A rotor of point masses, 4-fold symmetric about its axis (so (8.12) holds exactly up to rounding)."""
    l = np.asarray(axis, float) / np.linalg.norm(axis)
    e1, e2 = _frame(l)
    pts, ms = [], []
    for h, r, m in ((0.05, 0.2, 0.3), (-0.05, 0.12, 0.2)):
        for c, s in ((1, 0), (0, 1), (-1, 0), (0, -1)):
            pts.append(point + h * l + r * (c * e1 + s * e2))
            ms.append(m)
    # two masses on the axis, placed so that the mass centre is at `point`
    ms += [0.25, 0.25]
    pts += [point + 0.3 * l, point - 0.3 * l]
    pts, ms = np.array(pts), np.array(ms)
    shift = ms @ (pts - point) / ms.sum()
    pts = pts - shift
    return Rotor(name, carrier, l, point, Body.from_point_masses(ms, pts, name=name), spin=rng.normal()), ms, pts


def _carrier_points(rng):
    pts = rng.normal(size=(7, 3))
    ms = rng.uniform(0.5, 2.0, size=7)
    return ms, pts


@pytest.mark.parametrize("seed", range(4))
def test_reduction_matches_point_masses(seed):
    rng = np.random.default_rng(seed)
    cm, cp = _carrier_points(rng)
    carrier = Body.from_point_masses(cm, cp, name="c")
    rotors, clouds = [], []
    for k in range(3):
        axis = rng.normal(size=3)
        r, m, p = _ring_rotor(f"r{k}", "c", axis, rng.normal(size=3), rng)
        rotors.append(r)
        clouds.append((m, p))
    gc = GyrostatConfiguration([carrier], rotors)
    e = gc.effective_gyrostat("c")
    w = rng.normal(size=3)
    phi = rng.uniform(-3, 3, size=3)
    phid = rng.normal(size=3)
    Q = rand_Q(rng)
    a = rng.normal(size=(3, 3))
    a = a + a.T
    # all points in the carrier frame relative to the gyrostat's mass centre, and their body velocities
    X, Vb, M = [cp - e.center], [np.cross(w, cp - e.center)], [cm]
    for r, (m, p), ph, phd in zip(rotors, clouds, phi, phid, strict=True):
        R = axis_rotation(r.axis, ph)
        d = (p - r.point) @ R.T
        x = r.point + d - e.center
        X.append(x)
        Vb.append(np.cross(w, x) + phd * np.cross(r.axis, d))
        M.append(m)
    X, Vb, M = np.concatenate(X), np.concatenate(Vb), np.concatenate(M)
    assert abs(M.sum() - e.mass) < 1e-13 * e.mass
    assert np.max(np.abs(M @ X)) < 1e-13 * e.mass * np.max(np.abs(X))   # the centre does not move with phi
    J_points = np.einsum("k,ki,kj->ij", M, X, X)
    assert np.max(np.abs(J_points - e.J)) < 1e-13 * np.max(np.abs(e.J))   # (8.23), any rotor angles
    T_points = 0.5 * np.sum(M * np.sum(Vb * Vb, axis=1))
    A = np.array([r.A for r in e.rotors])
    L = np.array([r.axis for r in e.rotors])
    T_reduced = 0.5 * w @ e.I_gyro @ w + 0.5 * np.sum(A * (L @ w + phid) ** 2)
    assert abs(T_points - T_reduced) < 1e-13 * T_points
    # the coupling of (8.15): B tr(z omega) = A (l . omega), i.e. B = A / 2 and z = -hat(l)
    for r in e.rotors:
        assert abs(2 * r.B - r.A) < 1e-15 * r.A
        assert abs(r.B * np.trace(r.z @ hat(w)) - r.A * (r.axis @ w)) < 1e-14 * r.A * np.linalg.norm(w)
    # (8.34)'s potential part: the points' 1/2 x.a x about the centre is 1/2 tr(Q J_k Q^T a)
    V_points = 0.5 * np.sum(M * np.einsum("ki,ij,kj->k", X @ Q.T, a, X @ Q.T))
    V_reduced = gyrostat_energy(inertia(e.J), np.zeros((3, 3)), a, Q, np.zeros(3))
    assert abs(V_points - V_reduced) < 1e-12 * np.max(np.abs(a)) * np.trace(e.J)
    # (8.25), (8.33): p = A (omega . l + phidot), N = sum p l
    p = e.momenta(w, phid)
    assert np.allclose(p, A * (L @ w + phid), rtol=1e-15, atol=0)
    assert np.allclose(e.N(p), p @ L, rtol=1e-14, atol=1e-15 * np.abs(p).sum())


def test_asymmetric_rotor_refused():
    c = Body.box(5.0, [1, 1, 1], name="c")
    bad = Rotor("wobbly", "c", [0, 0, 1], [0, 0, 0], Body(mass=1.0, J=[0.1, 0.2, 0.3]))
    with pytest.raises(ValueError, match=r"'wobbly'.*not symmetric about its axis.*\(8\.12\)"):
        GyrostatConfiguration([c], [bad])


def test_off_axis_rotor_refused():
    c = Body.box(5.0, [1, 1, 1], name="c")
    bad = Rotor("eccentric", "c", [0, 0, 1], [0, 0, 0], Body(mass=1.0, J=[0.1, 0.1, 0.3], center=[0.01, 0, 0]))
    with pytest.raises(ValueError, match=r"'eccentric'.*off its axis by 0\.01"):
        GyrostatConfiguration([c], [bad])


def test_off_axis_rotor_balanced_by_its_subtree_is_accepted():
    """A rotor whose own centre is off the axis, with a subtree that brings the effective rotor's back."""
    boom = Body.box(3.0, [2.0, 0.2, 0.2], name="boom")
    probe = Body.box(0.4, [0.3, 0.2, 0.25], name="probe")
    tt = Rotor("turntable", "boom", [1, 0, 0], [1, 0, 0],
               Body(mass=0.5, J=[0.01, 0.02, 0.065], center=[1.0, -0.2, 0.0], name="turntable"))
    gc = GyrostatConfiguration([boom, probe], [tt], [Joint("turntable", "probe", [1.0, 0.25, 0.0], [0, 0, 0])])
    er = gc.effective_gyrostat("boom").rotors[0]
    assert np.allclose(er.center, [1, 0, 0], atol=1e-15)
    assert er.A == pytest.approx(0.13, rel=1e-14) and er.mass == pytest.approx(0.9)
    gc.check_central()
    # without the probe the same rotor is refused
    with pytest.raises(ValueError, match="off its axis"):
        GyrostatConfiguration([boom], [tt])


def test_configuration_errors():
    c = Body.box(5.0, [1, 1, 1], name="c")
    r = Rotor.symmetric("w", "c", [1, 0, 0], [0, 0, 0], 1.0, 0.1, 0.08)
    with pytest.raises(ValueError, match="unknown carrier"):
        GyrostatConfiguration([c], [Rotor.symmetric("w", "x", [1, 0, 0], [0, 0, 0], 1.0, 0.1, 0.08)])
    with pytest.raises(ValueError, match="child must be a carrier"):
        GyrostatConfiguration([c], [r], [Joint("c", "w", [0, 0, 0], [0, 0, 0])])
    with pytest.raises(ValueError, match="carries no rotor"):
        GyrostatConfiguration([c, MasslessCarrier("x")], [r], [Joint("c", "x", [1, 0, 0], [0, 0, 0])])
    with pytest.raises(ValueError, match="A <= 2 B"):
        Rotor.symmetric("w", "c", [1, 0, 0], [0, 0, 0], 1.0, 0.3, 0.1)
    with pytest.raises(ValueError, match="duplicate"):
        GyrostatConfiguration([c], [r, r])
    off = GyrostatConfiguration([c, Body.box(1.0, [1, 1, 1], name="d")], [r],
                                [Joint("w", "d", [0, 0, 0], [0.1, 0, 0])])
    with pytest.raises(ValueError, match="not CR\\^n-central"):
        off.check_central()


def test_place_rotor_against_direct_transformation():
    """place(): a rotor's mass centre, attitude and body rate from the split variables, by hand."""
    rng = np.random.default_rng(5)
    c = Body.box(5.0, [1.2, 1, 0.8], name="c")
    gc = GyrostatConfiguration([c], [Rotor.symmetric("w", "c", [1, 0, 0], [0.2, 0.1, 0], 1.0, 0.1, 0.08)])
    assert gc.body_names == ["c", "w"]
    q, qd, Q, w = rng.normal(size=3), rng.normal(size=3), rand_Q(rng), rng.normal(size=3)
    e = gc.effective_gyrostat("c")
    out = gc.place(q, qd, {"c": Q}, {"c": w}, {"w": np.array(0.7)}, {"w": np.array(1.3)})
    R = axis_rotation(np.array([1.0, 0, 0]), 0.7)
    assert np.allclose(out["w"]["position"], q + Q @ (np.array([0.2, 0.1, 0]) - e.center), atol=1e-15)
    assert np.allclose(out["c"]["position"], q - Q @ e.center, atol=1e-15)
    assert np.allclose(out["w"]["attitude"], Q @ R, atol=1e-15)
    assert np.allclose(out["w"]["omega"], R.T @ w + [1.3, 0, 0], atol=1e-15)
    assert np.allclose(out["c"]["velocity"], qd + Q @ np.cross(w, -e.center), atol=1e-15)
