"""Trees, centrality, effective bodies and the split kinematics, by brute force over point masses.

Every body is a cloud of point masses; the references place every point in space by forward
kinematics from the root (joint by joint) and sum over points.  None of them uses the
effective bodies.
"""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from thetasol.core.so3 import rodrigues
from thetasol.mechanics.bodies import Body
from thetasol.mechanics.configuration import Configuration, Joint

TREE = [("A", "B"), ("B", "C"), ("A", "D"), ("D", "E"), ("A", "F")]  # depth 2, six bodies


def make_tree(seed, central=True, edges=TREE):
    rng = np.random.default_rng(seed)
    names = sorted({n for e in edges for n in e})
    clouds = {n: (rng.uniform(0.3, 2.0, 5), rng.normal(size=(5, 3)) + rng.normal(size=3)) for n in names}
    bodies = [Body.from_point_masses(*clouds[n], name=n) for n in names]
    joints = [Joint(p, c, rng.normal(size=3) * 2, rng.normal(size=3)) for p, c in edges]
    cfg = Configuration(bodies, joints)
    return (cfg.make_central() if central else cfg), clouds


def forward_states(cfg, clouds, origin, origin_dot, Q, W):
    """Point-mass positions and velocities by forward kinematics of the frame origins (joints hold)."""
    O, Od = {cfg.root: origin}, {cfg.root: origin_dot}
    x, v, m = [], [], []
    for n in cfg.order:
        if n != cfg.root:
            j = cfg.joints[n]
            p = j.parent
            O[n] = O[p] + Q[p] @ j.parent_point - Q[n] @ j.child_point
            Od[n] = Od[p] + Q[p] @ np.cross(W[p], j.parent_point) - Q[n] @ np.cross(W[n], j.child_point)
        r = clouds[n][1]
        x.append(O[n] + r @ Q[n].T)
        v.append(Od[n] + np.cross(W[n], r) @ Q[n].T)
        m.append(clouds[n][0])
    return np.concatenate(m), np.concatenate(x), np.concatenate(v)


def system_mass_centre(cfg, clouds, origin, Q):
    """The system mass centre summed over the point masses placed by forward kinematics."""
    m, x, _ = forward_states(cfg, clouds, origin, np.zeros(3), Q, {n: np.zeros(3) for n in cfg.order})
    return m @ x / m.sum()


def random_rotations(rng, names):
    return {n: rodrigues(rng.normal(size=3) * 2) for n in names}


# -- structure ------------------------------------------------------------------------------------

def body(name):
    return Body(mass=1.0, J=[1.0, 2.0, 2.5], name=name)


@pytest.mark.parametrize("edges, match", [
    ([("A", "B"), ("B", "Z")], "unknown child 'Z'"),
    ([("A", "B"), ("Z", "C")], "unknown parent 'Z'"),
    ([("A", "B"), ("B", "C"), ("C", "A")], "cycle"),
    ([("A", "B"), ("B", "C"), ("C", "B")], "two parents|cycle"),
    ([("A", "B"), ("C", "B")], "two parents"),
    ([("A", "B")], "not connected"),
])
def test_bad_trees(edges, match):
    bodies = [body(n) for n in "ABC"]
    joints = [Joint(p, c, [1, 0, 0], [0, 0, 0]) for p, c in edges]
    with pytest.raises(ValueError, match=match):
        Configuration(bodies, joints)


def test_cycle_away_from_root_is_found():
    bodies = [body(n) for n in "ABCD"]
    joints = [Joint("A", "B", [1, 0, 0], [0, 0, 0]), Joint("C", "D", [1, 0, 0], [0, 0, 0]),
              Joint("D", "C", [1, 0, 0], [0, 0, 0])]
    with pytest.raises(ValueError, match="cycle"):
        Configuration(bodies, joints)


def test_other_bad_input():
    with pytest.raises(ValueError, match="itself"):
        Joint("A", "A", [0, 0, 0], [0, 0, 0])
    with pytest.raises(ValueError, match="NaN"):
        Joint("A", "B", [0, np.nan, 0], [0, 0, 0])
    with pytest.raises(ValueError, match="duplicate"):
        Configuration([body("A"), body("A")])
    with pytest.raises(ValueError, match="name"):
        Configuration([Body(mass=1.0, J=[1, 1, 1])])
    with pytest.raises(ValueError, match="at least one"):
        Configuration([])


def test_order_depth_and_single_body():
    cfg, _ = make_tree(0)
    assert cfg.order[0] == "A" and len(cfg) == 6 and cfg.depth == 2
    for n in cfg.order[1:]:
        assert cfg.order.index(cfg.parent(n)) < cfg.order.index(n)
    one = Configuration([body("solo")])
    assert one.depth == 0 and one.is_central() and one.violations() == []
    e = one.effective_body("solo")
    assert np.allclose(e.J, np.diag([1.0, 2.0, 2.5]))


# -- effective bodies ---------------------------------------------------------------------------------

@pytest.mark.parametrize("seed", range(3))
def test_effective_bodies_against_point_masses(seed):
    """(2.15)/(3.7): the body's own points plus each child subtree's mass at its joint point."""
    cfg, clouds = make_tree(seed, central=False)
    subtree_mass = {}
    for n in reversed(cfg.order):
        subtree_mass[n] = clouds[n][0].sum() + sum(subtree_mass[k] for k in cfg.children[n])
    for n, e in cfg.effective_bodies().items():
        m = list(clouds[n][0]) + [subtree_mass[k] for k in cfg.children[n]]
        r = list(clouds[n][1]) + [cfg.joints[k].parent_point for k in cfg.children[n]]
        m, r = np.array(m), np.array(r)
        c = m @ r / m.sum()
        J = np.einsum("k,ki,kj->ij", m, r - c, r - c)
        assert e.mass == pytest.approx(m.sum(), rel=1e-14)
        assert np.allclose(e.center, c, atol=1e-13)
        assert np.allclose(e.J, J, atol=1e-12)
        assert np.allclose(e.I, np.trace(J) * np.eye(3) - J, atol=1e-12)
        assert np.allclose(e.axes @ np.diag(e.principal_moments) @ e.axes.T, J, atol=1e-12)
        assert np.allclose(e.principal_inertia, np.trace(J) - e.principal_moments)


# -- centrality -------------------------------------------------------------------------------------------

@pytest.mark.parametrize("seed", range(3))
def test_central_means_the_mass_centre_stays_put(seed):
    """The paper's mechanical definition: fix the root, rotate every other body about its joint,
    and the system mass centre does not move; it is the root's effective mass centre."""
    rng = np.random.default_rng(10 + seed)
    cfg, clouds = make_tree(seed)
    assert cfg.is_central()
    Qroot = rodrigues(rng.normal(size=3))
    origin = rng.normal(size=3)
    centres = []
    for _ in range(4):
        Q = random_rotations(rng, cfg.order)
        Q[cfg.root] = Qroot
        centres.append(system_mass_centre(cfg, clouds, origin, Q))
    expected = origin + Qroot @ cfg.effective_body(cfg.root).center
    assert np.allclose(centres, expected, atol=1e-12)


def test_non_central_tree_moves_and_is_reported():
    cfg, clouds = make_tree(0)
    shift = np.array([1e-3, -2e-3, 0.5e-3])
    joints = [Joint(j.parent, j.child, j.parent_point, j.child_point + (shift if j.child == "C" else 0))
              for j in (cfg.joints[n] for n in cfg.order[1:])]
    bad = Configuration([cfg.bodies[n] for n in cfg.order], joints)
    assert not bad.is_central()
    viol = {v.child: v for v in bad.violations()}
    assert viol["C"].distance == pytest.approx(np.linalg.norm(shift), rel=1e-9)
    assert np.allclose(viol["C"].offset, shift, atol=1e-14)
    assert all(v.distance < 1e-13 for k, v in viol.items() if k != "C")
    with pytest.raises(ValueError, match="'B' -> 'C'"):
        bad.check_central()
    # The mass centre now moves when C turns about its joint (by about m_C |shift|).
    Q = {n: np.eye(3) for n in bad.order}
    c0 = system_mass_centre(bad, clouds, np.zeros(3), Q)
    Q["C"] = rodrigues(np.array([0.0, 0.0, np.pi]))
    c1 = system_mass_centre(bad, clouds, np.zeros(3), Q)
    assert np.linalg.norm(c1 - c0) > 1e-4
    # make_central restores it and gives the opposite shift.
    fixed = bad.make_central()
    assert fixed.is_central()
    assert np.allclose(bad.central_shifts()["C"], -shift, atol=1e-14)
    for n in fixed.order[1:]:
        assert np.array_equal(fixed.joints[n].parent_point, bad.joints[n].parent_point)


# -- the split kinematics and Lagrangian (3.1) --------------------------------------------------------

@pytest.mark.parametrize("central", [True, False])
def test_lagrangian_splits_exactly_when_central(central):
    """Summed over point masses, T and V equal the split (3.1)-(3.3):
    1/2 M |qdot|^2 + M phi(q) + sum_alpha [1/2 w.I_eff w + 1/2 tr(Q^T a Q J_eff)], only if central."""
    rng = np.random.default_rng(7)
    cfg, clouds = make_tree(1, central=central)
    a = rng.normal(size=(3, 3))
    a = a + a.T
    bvec = rng.normal(size=3)
    Q = random_rotations(rng, cfg.order)
    W = {n: rng.normal(size=3) for n in cfg.order}
    m, x, v = forward_states(cfg, clouds, rng.normal(size=3), rng.normal(size=3), Q, W)
    q, qd = m @ x / m.sum(), m @ v / m.sum()
    T = 0.5 * np.sum(m * np.sum(v * v, axis=1))
    phi = lambda y: 0.5 * np.einsum("...i,ij,...j->...", y, a, y) + 0.5 * y @ bvec  # noqa: E731
    Vpot = np.sum(m * phi(x))
    M = cfg.mass
    eff = cfg.effective_bodies()
    T_split = 0.5 * M * qd @ qd + sum(0.5 * W[n] @ eff[n].I @ W[n] for n in cfg.order)
    V_split = M * phi(q) + sum(0.5 * np.trace(Q[n].T @ a @ Q[n] @ eff[n].J) for n in cfg.order)
    if central:
        assert T == pytest.approx(T_split, rel=1e-13)
        assert Vpot == pytest.approx(V_split, rel=1e-12)
        # and place() rebuilds the same bodies from (q, qdot, Q, omega)
        placed = cfg.place(q, qd, Q, W)
        k = 0
        for n in cfg.order:
            b, nk = cfg.bodies[n], clouds[n][0].size
            assert np.allclose(placed[n]["position"], clouds[n][0] @ x[k:k + nk] / b.mass, atol=1e-12)
            assert np.allclose(placed[n]["velocity"], clouds[n][0] @ v[k:k + nk] / b.mass, atol=1e-12)
            k += nk
    else:
        assert abs(T - T_split) > 1e-3 * T


def test_place_joints_coincide_and_velocities_are_derivatives():
    rng = np.random.default_rng(4)
    cfg, clouds = make_tree(2)
    q0, v = rng.normal(size=3), rng.normal(size=3)
    Q0 = random_rotations(rng, cfg.order)
    W = {n: rng.normal(size=3) for n in cfg.order}
    t = np.array([0.3 - 1e-5, 0.3, 0.3 + 1e-5])
    Qt = {n: Q0[n] @ rodrigues(t[:, None] * W[n]) for n in cfg.order}  # constant body rates
    Wt = {n: np.broadcast_to(W[n], (3, 3)) for n in cfg.order}
    placed = cfg.place(q0 + t[:, None] * v, np.broadcast_to(v, (3, 3)), Qt, Wt)
    for n in cfg.order:
        fd = (placed[n]["position"][2] - placed[n]["position"][0]) / 2e-5
        assert np.allclose(fd, placed[n]["velocity"][1], atol=1e-8)
        origin = placed[n]["origin"][1]
        assert np.allclose(origin + Qt[n][1] @ cfg.bodies[n].center, placed[n]["position"][1], atol=1e-13)
        if n != cfg.root:
            j = cfg.joints[n]
            P = placed[j.parent]["origin"][1] + Qt[j.parent][1] @ j.parent_point
            C = origin + Qt[n][1] @ j.child_point
            assert np.allclose(P, C, atol=1e-12)


def test_place_refuses_non_central():
    cfg, _ = make_tree(0, central=False)
    Q = {n: np.eye(3) for n in cfg.order}
    with pytest.raises(ValueError, match="not C\\^k-central"):
        cfg.place(np.zeros(3), np.zeros(3), Q)


@settings(max_examples=40, deadline=None)
@given(parents=st.lists(st.integers(0, 100), min_size=0, max_size=7), seed=st.integers(0, 2**16))
def test_random_trees(parents, seed):
    """Any tree shape: make_central() is central, the mass centre stays put, and T splits."""
    rng = np.random.default_rng(seed)
    names = [f"b{i}" for i in range(len(parents) + 1)]
    edges = [(names[p % (i + 1)], names[i + 1]) for i, p in enumerate(parents)]  # parent index < child
    clouds = {n: (rng.uniform(0.3, 2.0, 4), rng.normal(size=(4, 3))) for n in names}
    bodies = [Body.from_point_masses(*clouds[n], name=n) for n in names]
    cfg = Configuration(bodies, [Joint(p, c, rng.normal(size=3), rng.normal(size=3)) for p, c in edges])
    cfg = cfg.make_central()
    assert cfg.is_central() and cfg.root == "b0"
    Q = random_rotations(rng, cfg.order)
    W = {n: rng.normal(size=3) for n in cfg.order}
    m, x, v = forward_states(cfg, clouds, np.zeros(3), np.zeros(3), Q, W)
    assert np.allclose(m @ x / m.sum(), Q["b0"] @ cfg.effective_body("b0").center, atol=1e-12)
    qd = m @ v / m.sum()
    T = 0.5 * np.sum(m * np.sum(v * v, axis=1))
    eff = cfg.effective_bodies()
    T_split = 0.5 * cfg.mass * qd @ qd + sum(0.5 * W[n] @ eff[n].I @ W[n] for n in cfg.order)
    assert T == pytest.approx(T_split, rel=1e-12)
