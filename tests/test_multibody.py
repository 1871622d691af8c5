"""The split (Theorem 2, (3.1)) shown, not assumed: a whole C^2-central configuration integrated
as ONE constrained multibody system (thetasol.integrators.multibody: maximal coordinates, Newton-Euler per
body, joint forces from the KKT system, no effective bodies) against the split solution
(closed-form mass centre + integrate_rotation per effective body + the tree kinematics).

Accuracy statement behind the tolerances (measured, see docs/mechanics.md): over t <= 60 the
multibody DOP853 at rtol = 1e-12 stays within 6e-12 to 2e-11 of the split, depending on the
data (1.8e-12 at rtol = 1e-13, 2e-10 at 1e-11: the gap shrinks with the multibody tolerance,
so it IS that integrator's error); the split's rotations at rtol = 1e-13 are within ~1e-12
of heyoka at tol 1e-15.  Hence the tolerance 5e-11 (8x the measured gap for these data).
A non-central tree departs from the split by ~10x its joint offset.
"""
import numpy as np
import pytest

from thetasol.core.so3 import rodrigues
from thetasol.integrators.multibody import initial_state, integrate_multibody
from thetasol.mechanics.bodies import Body
from thetasol.mechanics.configuration import Configuration, Joint
from thetasol.scenes.pipeline import solve_configuration

EDGES = [("A", "B"), ("B", "C"), ("A", "D"), ("D", "E")]  # C^2: chains of length 2


def make_system(seed, eig=(2.0, 1.0, 0.4), edges=EDGES):
    rng = np.random.default_rng(seed)
    names = sorted({n for e in edges for n in e})
    bodies = [Body.from_point_masses(rng.uniform(0.5, 2, 5), rng.normal(size=(5, 3)), name=n) for n in names]
    cfg = Configuration(bodies, [Joint(p, c, rng.normal(size=3), np.zeros(3)) for p, c in edges]).make_central()
    R = rodrigues(rng.normal(size=3))
    a = R @ np.diag(eig) @ R.T
    b = rng.normal(size=3) * 0.2
    state = dict(q0=rng.normal(size=3), v0=rng.normal(size=3),
                 Q0={n: rodrigues(rng.normal(size=3)) for n in names},
                 omega0={n: rng.normal(size=3) for n in names})
    return cfg, a, b, state


def energy(cfg, traj, a, b):
    """Total energy summed body by body (no split formula involved)."""
    E = 0.0
    for i, n in enumerate(traj.names):
        body = cfg.bodies[n]
        x, v, Q, w = traj.position[i], traj.velocity[i], traj.attitude[i], traj.omega[i]
        E = E + 0.5 * body.mass * np.sum(v * v, -1) + 0.5 * np.einsum("ti,ij,tj->t", w, body.I, w)
        E = E + body.mass * (0.5 * np.einsum("ti,ij,tj->t", x, a, x) + 0.5 * x @ b)
        E = E + 0.5 * np.trace(np.swapaxes(Q, 1, 2) @ a @ Q @ body.J, axis1=1, axis2=2)
    return E


def test_split_matches_unsplit_over_many_periods():
    cfg, a, b, s = make_system(11)
    assert len(cfg) >= 4 and cfg.depth == 2 and cfg.is_central()
    t = np.linspace(0.0, 60.0, 241)  # mass-centre periods 4.4, 6.3, 9.9; rotation rates O(1)
    split = solve_configuration(cfg, a, b, rotation="numerical", rtol=1e-13, **s).trajectories(t)
    mb = integrate_multibody(cfg, a, b, t=t, rtol=1e-12, **s)
    dev = split.deviation(mb)  # measured 3e-12, 5e-12, 4e-12, 6e-12, 3e-14
    assert dev["position"] < 5e-11
    assert dev["attitude"] < 5e-11
    assert dev["velocity"] < 5e-11
    assert dev["omega"] < 5e-11
    assert dev["mass_center"] < 1e-12
    # The reference itself: joints held, Q orthogonal, energy conserved.
    assert mb.info["constraint_residual"] < 1e-10
    assert mb.info["orthogonality"] < 1e-10
    E = energy(cfg, mb, a, b)
    assert np.max(np.abs(E - E[0])) < 1e-12 * abs(E[0])  # measured 9e-14


def test_non_central_tree_does_not_split():
    """Move one joint by 1e-6 off the subtree mass centre: the same split formulas are now wrong
    by far more than the tolerance above, roughly in proportion to the offset."""
    cfg, a, b, s = make_system(11)
    t = np.linspace(0.0, 20.0, 81)
    devs = []
    for delta in (1e-6, 1e-5):
        joints = [Joint(j.parent, j.child, j.parent_point,
                        j.child_point + (delta * np.array([0.6, 0.0, 0.8]) if j.child == "C" else 0.0))
                  for j in (cfg.joints[n] for n in cfg.order[1:])]
        bad = Configuration([cfg.bodies[n] for n in cfg.order], joints)
        assert not bad.is_central()
        with pytest.raises(ValueError, match="not C\\^k-central"):
            solve_configuration(bad, a, b, **s)
        split = solve_configuration(bad, a, b, rotation="numerical", check_central=False, **s).trajectories(t)
        mb = integrate_multibody(bad, a, b, t=t, rtol=1e-11, **s)
        dev = split.deviation(mb)
        devs.append(max(dev["position"], dev["attitude"]))
        assert devs[-1] > 100 * 5e-11
        assert mb.info["constraint_residual"] < 1e-9  # the reference is fine; the split is not
    assert 5 < devs[1] / devs[0] < 20


def test_mixed_sign_potential_and_four_bodies():
    """Hyperbolic, polynomial and trigonometric mass-centre modes; a star of four bodies."""
    edges = [("A", "B"), ("A", "C"), ("C", "D")]
    cfg, a, b, s = make_system(3, eig=(1.5, 0.0, -0.3), edges=edges)
    t = np.linspace(0.0, 15.0, 61)
    split = solve_configuration(cfg, a, b, rotation="numerical", rtol=1e-13, **s).trajectories(t)
    mb = integrate_multibody(cfg, a, b, t=t, rtol=1e-12, **s)
    dev = split.deviation(mb)  # measured 1.5e-12 with positions up to 500 (hyperbolic mode)
    assert max(dev["position"], dev["attitude"], dev["velocity"], dev["omega"]) < 5e-11


def test_single_body_is_a_free_body_in_the_potential():
    rng = np.random.default_rng(2)
    body = Body.from_point_masses(rng.uniform(0.5, 2, 4), rng.normal(size=(4, 3)), name="solo")
    cfg = Configuration([body])
    a = np.diag([1.0, 0.3, -0.2])
    b = np.array([0.1, 0.0, -0.3])
    s = dict(q0=rng.normal(size=3), v0=rng.normal(size=3), Q0={"solo": rodrigues(rng.normal(size=3))},
             omega0={"solo": rng.normal(size=3)})
    t = np.linspace(0, 10, 21)
    dev = solve_configuration(cfg, a, b, rotation="numerical", rtol=1e-13, **s).trajectories(t).deviation(
        integrate_multibody(cfg, a, b, t=t, rtol=1e-12, **s))
    assert max(dev.values()) < 1e-10


def test_initial_state_holds_joints_and_mass_centre():
    cfg, a, b, s = make_system(5)
    x, v, Q, w = initial_state(cfg, **s)
    m = np.array([cfg.bodies[n].mass for n in cfg.order])
    assert np.allclose(m @ x / m.sum(), s["q0"], atol=1e-13)
    assert np.allclose(m @ v / m.sum(), s["v0"], atol=1e-13)
    idx = {n: i for i, n in enumerate(cfg.order)}
    for n in cfg.order[1:]:
        j = cfg.joints[n]
        p, c = idx[j.parent], idx[n]
        bp, bc = cfg.bodies[j.parent], cfg.bodies[n]
        gap = x[p] + Q[p] @ (j.parent_point - bp.center) - x[c] - Q[c] @ (j.child_point - bc.center)
        gdot = (v[p] + Q[p] @ np.cross(w[p], j.parent_point - bp.center)
                - v[c] - Q[c] @ np.cross(w[c], j.child_point - bc.center))
        assert np.allclose(gap, 0, atol=1e-13) and np.allclose(gdot, 0, atol=1e-13)


def test_output_shapes_and_t_zero():
    cfg, a, b, s = make_system(1)
    mb = integrate_multibody(cfg, a, b, t=[0.0, 0.5], **s)
    N = len(cfg)
    assert mb.position.shape == (N, 2, 3) and mb.attitude.shape == (N, 2, 3, 3) and mb.omega.shape == (N, 2, 3)
    assert mb.names == tuple(cfg.order)
    only0 = integrate_multibody(cfg, a, b, t=[0.0], **s)
    assert np.allclose(only0.mass_center[0], s["q0"], atol=1e-13)
    assert np.allclose(only0.body("B")["omega"][0], s["omega0"]["B"])


def test_bad_input():
    cfg, a, b, s = make_system(1)
    t = [0.0, 1.0]
    with pytest.raises(ValueError, match="Configuration"):
        integrate_multibody("tree", a, b, t=t, **s)
    with pytest.raises(ValueError, match="symmetric"):
        integrate_multibody(cfg, a + np.triu(np.ones((3, 3)), 1), b, t=t, **s)
    with pytest.raises(ValueError, match="increasing"):
        integrate_multibody(cfg, a, b, t=[1.0, 0.5], **s)
    with pytest.raises(ValueError, match="NaN"):
        integrate_multibody(cfg, a, [0, np.nan, 0], t=t, **s)
    bad = dict(s, Q0={**s["Q0"], "B": s["Q0"]["B"] * (1 + 1e-8)})
    with pytest.raises(ValueError, match="not orthogonal"):
        integrate_multibody(cfg, a, b, t=t, **bad)
    bad = dict(s, omega0={**s["omega0"], "Z": np.zeros(3)})
    with pytest.raises(ValueError, match="unknown bodies"):
        integrate_multibody(cfg, a, b, t=t, **bad)


@pytest.mark.slow
def test_gap_is_the_multibody_integration_error():
    """Over t <= 200 the split/unsplit gap falls with the multibody tolerance: model error would not."""
    cfg, a, b, s = make_system(11)
    t = np.linspace(0.0, 200.0, 401)
    split = solve_configuration(cfg, a, b, rotation="numerical", rtol=1e-13, **s).trajectories(t)
    gaps = []
    for rtol in (1e-10, 1e-12):
        dev = split.deviation(integrate_multibody(cfg, a, b, t=t, rtol=rtol, **s))
        gaps.append(max(dev["position"], dev["attitude"]))
    assert gaps[1] < 1e-9
    assert gaps[0] / gaps[1] > 20
