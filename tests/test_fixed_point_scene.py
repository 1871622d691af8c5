"""Section 5 as a scene: a C^k-central configuration turning about a point of its main body fixed in space.

The split (solve_fixed_point: the main effective body about the pivot by Corollaries 2-3 or numerically,
the other effective bodies as in Theorem 2, positions rebuilt down the tree) against the unsplit
multibody system with the pivot as a spherical joint to the ground (integrate_multibody(...,
constraint=Pivot(...)): maximal coordinates, three more KKT rows, no effective body, no pivot inertia).
"""
import textwrap
from pathlib import Path

import numpy as np
import pytest
from conftest import label

from thetasol.core.inertia import inertia
from thetasol.core.so3 import rodrigues
from thetasol.integrators.fixed_point import fixed_point_energy, integrate_fixed_point
from thetasol.integrators.heavy_top import integrate_heavy_top
from thetasol.integrators.multibody import integrate_multibody
from thetasol.mechanics.bodies import Body
from thetasol.mechanics.configuration import Configuration, Joint
from thetasol.mechanics.constraints import Pivot
from thetasol.scenes.fixed_point import pivoted_body, solve_fixed_point
from thetasol.scenes.format import load_scene
from thetasol.scenes.report import run

EXAMPLE = Path(__file__).resolve().parent.parent / "thetasol" / "scenes" / "data" / "pivoted_top.toml"
G = 9.81


def _random_body(rng, name):
    return Body.from_point_masses(rng.uniform(0.5, 2, 5), 0.4 * rng.normal(size=(5, 3)), name=name)


def _state(rng, names, spin=1.0):
    return ({n: rodrigues(rng.normal(size=3)) for n in names}, {n: spin * rng.normal(size=3) for n in names})


def symmetric_top(seed):
    """A C^2-central tree whose main effective body is a Lagrange top about the pivot: an axisymmetric
    root (box 0.4 x 0.4 x 1.2) with two random subtrees jointed on its axis, pivot on the axis."""
    rng = np.random.default_rng(seed)
    root = Body.box(3.0, [0.4, 0.4, 1.2], name="top")
    kids = [_random_body(rng, n) for n in ("cap", "arm", "hand")]
    joints = [Joint("top", "cap", [0, 0, 0.6], np.zeros(3)), Joint("top", "arm", [0, 0, 0.2], np.zeros(3)),
              Joint("arm", "hand", rng.normal(size=3), np.zeros(3))]
    cfg = Configuration([root] + kids, joints).make_central()
    Q0, w0 = _state(rng, cfg.order)
    w0["top"] = np.array([0.6, -0.3, 8.0])
    return cfg, Q0, w0, Pivot("top", [0.0, 0.0, -0.6], rng.normal(size=3))


def random_tree(seed):
    """A random C^2-central tree of point-mass bodies (4 bodies) and a random pivot in its root."""
    rng = np.random.default_rng(seed)
    names = ["A", "B", "C", "D"]
    cfg = Configuration([_random_body(rng, n) for n in names],
                        [Joint(p, c, rng.normal(size=3), np.zeros(3)) for p, c in (("A", "B"), ("B", "C"), ("A", "D"))]
                        ).make_central()
    Q0, w0 = _state(rng, names)
    return cfg, Q0, w0, Pivot("A", 0.5 * rng.normal(size=3), rng.normal(size=3)), rng


def split_vs_unsplit(cfg, a, b, pivot, Q0, w0, t, mb_rtol=1e-12, **kw):
    sol = solve_fixed_point(cfg, a, b, pivot, Q0, w0, **kw)
    mb = integrate_multibody(cfg, a, b, None, None, Q0, w0, t, rtol=mb_rtol, constraint=pivot)
    split = sol.trajectories(t)
    assert mb.info["pivot_residual"] < 1e-11 and mb.info["constraint_residual"] < 1e-11  # measured <= 1.9e-12
    return sol, split, split.deviation(mb)


def periods(x):
    """Oscillations of a sampled signal: half its sign changes about its mean."""
    return int(np.sum(np.diff(np.sign(x - x.mean())) != 0)) // 2


SLOW = pytest.mark.slow


# -- (a) a uniform field: Lagrange's top and Euler's top about the pivot ----------------------------

def test_effective_body_about_the_pivot_is_5_1_and_5_2():
    """R and J about the pivot summed over the root body and its subtrees' masses at their joints
    (the effective root body (3.7)), against pivoted_body."""
    cfg, Q0, w0, pivot = symmetric_top(0)
    root = cfg.bodies["top"]  # every subtree's mass sits at its joint (3.7)
    sub = {"cap": cfg.effective_body("cap").mass, "arm": cfg.effective_body("arm").mass}
    pts = [cfg.joints[k].parent_point for k in sub]
    m_tot = root.mass + sum(sub.values())
    R = root.mass * (root.center - pivot.point) + sum(m * (p - pivot.point) for m, p in zip(sub.values(), pts))
    J = root.J + root.mass * np.outer(root.center - pivot.point, root.center - pivot.point) + sum(
        m * np.outer(p - pivot.point, p - pivot.point) for m, p in zip(sub.values(), pts))
    pb = pivoted_body(cfg, pivot, np.zeros((3, 3)), [0, 0, 2 * G])
    assert pb.mass == pytest.approx(m_tot, rel=1e-15) and pb.mass == pytest.approx(cfg.mass, rel=1e-15)
    assert np.allclose(pb.R, R, rtol=0, atol=1e-14) and np.allclose(pb.J, J, rtol=0, atol=1e-14)
    assert pb.case == "a = 0" and np.all(pb.b == [0, 0, 2 * G])
    assert abs(pb.I[0, 0] - pb.I[1, 1]) < 1e-15 and abs(pb.R[0]) + abs(pb.R[1]) == 0  # Lagrange's top
    # the pivot's place enters through b + 2 a x_P only
    a = np.diag([1.0, 2.0, 3.0])
    assert pivoted_body(cfg, pivot, a, -2 * a @ pivot.position).case == "b = 0"
    assert pivoted_body(cfg, pivot, a, np.zeros(3)).case == "general"
    assert pivoted_body(cfg, pivot, 2 * np.eye(3), np.zeros(3)).case == "a isotropic"


@pytest.mark.parametrize("t_end, nutations, bound", [
    (5.0, 4, 2e-12),  # measured: positions 3.5e-13, attitudes 4.6e-13
    pytest.param(50.0, 40, 3e-10, marks=SLOW),  # measured: 4.5e-11, 5.7e-11 (velocities 2.4e-10)
])
def test_lagrange_top_about_the_pivot_matches_the_unsplit_system(t_end, nutations, bound):
    """Gravity along a random direction (a = 0, b = 2 g u), pivot at a random place: the main body is
    lagrange/elliptic, the three other effective bodies Euler tops (4.3 nutation periods per 5 s)."""
    cfg, Q0, w0, pivot = symmetric_top(1)
    u = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    t = np.linspace(0.0, t_end, int(40 * t_end) + 1)
    sol, split, dev = split_vs_unsplit(cfg, np.zeros((3, 3)), 2 * G * u, pivot, Q0, w0, t)
    assert label(sol.rotations["top"]) == "elliptic"
    assert all(type(sol.rotations[n]).__name__ == "EulerTopSolution" for n in ("cap", "arm", "hand"))
    assert t_end / sol.rotations["top"].diagnostics["period"] > nutations  # measured 4.27, 42.7
    assert dev["position"] < bound and dev["attitude"] < bound
    assert dev["velocity"] < 5 * bound and dev["omega"] < 5 * bound  # measured 1.3e-12, 1.4e-12 (t <= 5)
    # the pivot of the split stays at its place
    x = split.position[0] + np.einsum("tij,j->ti", split.attitude[0], pivot.point - cfg.bodies["top"].center)
    assert np.max(np.abs(x - pivot.position)) < 2e-15  # measured 3.3e-16


@pytest.mark.parametrize("t_end, mb_rtol, bound", [
    (10.0, 1e-12, 1e-10),  # measured: positions 1.2e-11, attitudes 1.6e-11 (3 periods)
    pytest.param(100.0, 1e-13, 1e-9, marks=SLOW),  # measured: 1.1e-10, 1.4e-10 (31 periods)
])
def test_euler_top_about_the_mass_centre_in_gravity(t_end, mb_rtol, bound):
    """The pivot at the system mass centre (R = 0, Corollary 2 case 1) in uniform gravity: the main body
    is an Euler top about the pivot.  The gap is the multibody integrator's: at t <= 100 it is 1.1e-8,
    1.1e-9, 1.1e-10 at rtol 1e-11, 1e-12, 1e-13."""
    cfg, Q0, w0, _, rng = random_tree(2)
    pivot = Pivot("A", cfg.effective_body("A").center, rng.normal(size=3))
    w0["A"] = 3 * w0["A"]
    t = np.linspace(0.0, t_end, int(2 * t_end) + 1)
    sol, split, dev = split_vs_unsplit(cfg, np.zeros((3, 3)), [0.0, 0.0, 2 * G], pivot, Q0, w0, t, mb_rtol=mb_rtol)
    assert sol.diagnostics["pivoted_body"].case == "R = 0"
    assert type(sol.rotations["A"]).__name__ == "EulerTopSolution"
    assert t_end / sol.rotations["A"].diagnostics["period"] > 0.3 * t_end  # period 3.16
    assert np.max(np.abs(split.mass_center - pivot.position)) < 1e-15  # measured 0 (R = 0)
    assert dev["position"] < bound and dev["attitude"] < bound


@SLOW
def test_kovalevskaya_top_about_the_pivot():
    """A main body whose inertia about the pivot is diag(2, 2, 1) with its mass centre on the body x axis,
    carrying a C^1 subtree jointed AT the pivot (which adds mass there and changes neither R nor J about
    the pivot): the main body is Kovalevskaya's top in genus-2 theta functions; t <= 20."""
    rng = np.random.default_rng(11)
    root = Body(mass=2.0, J=[0.5 - 2.0 * 0.3 ** 2, 0.5, 1.5], center=[0.3, 0.0, 0.0], name="K")
    kid, grand = _random_body(rng, "kid"), _random_body(rng, "grand")
    cfg = Configuration([root, kid, grand], [Joint("K", "kid", np.zeros(3), np.zeros(3)),
                                             Joint("kid", "grand", rng.normal(size=3), np.zeros(3))]).make_central()
    Q0, w0 = _state(rng, cfg.order)
    pivot = Pivot("K", np.zeros(3), rng.normal(size=3))
    t = np.linspace(0.0, 20.0, 201)
    sol, split, dev = split_vs_unsplit(cfg, np.zeros((3, 3)), [0.0, 0.0, 2 * G], pivot, Q0, w0, t)
    assert label(sol.rotations["K"]) == "theta/genus-2"
    assert min(periods(split.omega[0, :, i]) for i in range(3)) >= 3  # measured 4, 3, 6
    assert dev["position"] < 2e-10 and dev["attitude"] < 5e-10  # measured 2.0e-11, 6.6e-11


# -- (b) a purely quadratic potential about the pivot: Section 4 with J about the pivot ------------

@pytest.mark.parametrize("t_end, oscillations, bound", [
    (10.0, 1, 2e-12),  # measured: positions 1.9e-13, attitudes 3.6e-13
    pytest.param(60.0, 6, 5e-11, marks=SLOW),  # measured: 6.9e-12, 6.3e-12 (6, 9, 7 oscillations of omega)
])
def test_quadratic_potential_about_the_pivot_is_section_4(t_end, oscillations, bound):
    """b = -2 a x_P: the potential has no linear part about the pivot (Corollary 2 case 2) although b != 0;
    the main body is the theta-function closed form of Section 4 with J about the pivot."""
    cfg, Q0, w0, pivot, rng = random_tree(3)
    Rot = rodrigues(rng.normal(size=3))
    a = Rot @ np.diag([2.0, 1.0, 0.4]) @ Rot.T
    t = np.linspace(0.0, t_end, int(10 * t_end) + 1)
    sol, split, dev = split_vs_unsplit(cfg, a, -2 * a @ pivot.position, pivot, Q0, w0, t)
    assert sol.diagnostics["pivoted_body"].case == "b = 0"
    assert sol.rotations["A"].method.startswith("theta/")
    assert min(periods(split.omega[0, :, i]) for i in range(3)) >= oscillations
    assert dev["position"] < bound and dev["attitude"] < bound


# -- (c) no closed form: both terms act about the pivot ---------------------------------------------

def test_no_closed_form_is_numerical_and_says_so():
    """b = 0 with the pivot off the origin of a (b + 2 a x_P != 0) is NOT Corollary 2: the main body is
    integrated (integrate_fixed_point), the reason is given, the others are still closed forms.  The
    motion is chaotic: the gap grows from 3.1e-12 at t = 20 to 1.8e-8 at t = 50 (1.6e-9 with both
    sides at rtol 1e-13), so the check stops at t = 20 (4-5 oscillations of omega)."""
    cfg, Q0, w0, pivot, rng = random_tree(4)
    a = np.diag([1.5, 0.7, 0.2])
    t = np.linspace(0.0, 20.0, 81)
    sol, split, dev = split_vs_unsplit(cfg, a, np.zeros(3), pivot, Q0, w0, t, rtol=1e-13)
    r = sol.diagnostics["rotations"]["A"]
    assert sol.diagnostics["pivoted_body"].case == "general"
    assert not r["closed_form"] and "no closed form is known" in r["reason"]
    assert "numerical (integrate_fixed_point" in r["model"]
    assert all(sol.diagnostics["rotations"][n]["closed_form"] for n in "BCD")
    assert min(periods(split.omega[0, :, i]) for i in range(3)) >= 3
    assert dev["position"] < 2e-11 and dev["attitude"] < 2e-11  # measured 3.1e-12, 1.4e-12


def test_integrate_fixed_point_reduces_to_the_heavy_top_and_conserves_energy():
    rng = np.random.default_rng(5)
    A = rng.normal(size=(3, 3))
    J = A @ A.T + np.eye(3)
    Q0, w0 = rodrigues(rng.normal(size=3)), rng.normal(size=3)
    t = np.linspace(0.0, 10.0, 21)
    c, g = np.array([0.1, 0.2, 0.5]), np.array([0.3, -0.2, -G])
    w1, Q1 = integrate_fixed_point(inertia(J), 2 * c, np.zeros((3, 3)), -2 * g, Q0, w0, rtol=1e-13)(t)
    w2, Q2 = integrate_heavy_top(np.trace(J) * np.eye(3) - J, c, Q0, w0, mass=2.0, gravity=g, rtol=1e-13)(t)
    assert np.max(np.abs(Q1 - Q2)) < 1e-12 and np.max(np.abs(w1 - w2)) < 1e-12  # measured 0, 0
    a = np.diag([1.0, -0.5, 0.3])
    w, Q = integrate_fixed_point(inertia(J), 2 * c, a, -2 * g, Q0, w0, rtol=1e-13)(t)
    E = fixed_point_energy(inertia(J), 2 * c, a, -2 * g, Q, w)
    assert np.max(np.abs(E - E[0])) < 1e-12 * abs(E[0])  # measured 1.1e-13 relative


def test_multibody_pivot_alone_is_the_heavy_top():
    """One body on the pivot in maximal coordinates (KKT rows) against the Euler-Poisson equations; the gap
    is the multibody integrator's (attitudes 1.4e-10, 1.4e-11, 1.5e-12 at rtol 1e-11, 1e-12, 1e-13)."""
    rng = np.random.default_rng(6)
    body = _random_body(rng, "solo")
    pivot = Pivot("solo", body.center + rng.normal(size=3), rng.normal(size=3))
    Q0, w0 = rodrigues(rng.normal(size=3)), rng.normal(size=3)
    t = np.linspace(0.0, 10.0, 41)
    mb = integrate_multibody(Configuration([body]), np.zeros((3, 3)), [0, 0, 2 * G], None, None, {"solo": Q0},
                             {"solo": w0}, t, rtol=1e-12, constraint=pivot)
    d = body.center - pivot.point
    I = np.trace(body.J) * np.eye(3) - body.J + body.mass * (d @ d * np.eye(3) - np.outer(d, d))
    w, Q = integrate_heavy_top(I, d, Q0, w0, mass=body.mass, gravity=[0, 0, -G], rtol=1e-13)(t)
    assert np.max(np.abs(mb.attitude[0] - Q)) < 1e-10  # measured 1.4e-11
    assert np.max(np.abs(mb.omega[0] - w)) < 2e-10  # measured 3.0e-11
    assert mb.info["pivot_residual"] < 1e-11  # measured 2.3e-12


def test_multibody_pivot_initial_state_in_any_body():
    """The unsplit system takes a pivot in any body (not only the root): the pivot starts at its place at rest."""
    from thetasol.integrators.multibody import pivot_initial_state

    cfg, Q0, w0, _, rng = random_tree(7)
    pivot = Pivot("C", rng.normal(size=3), rng.normal(size=3))
    x, v, Q, w = pivot_initial_state(cfg, pivot, None, None, Q0, w0)
    i = cfg.order.index("C")
    rho = pivot.point - cfg.bodies["C"].center
    assert np.max(np.abs(x[i] + Q[i] @ rho - pivot.position)) < 1e-14
    assert np.max(np.abs(v[i] + Q[i] @ np.cross(w[i], rho))) < 1e-14
    with pytest.raises(ValueError, match="q0 = .* disagrees with the pivot"):
        pivot_initial_state(cfg, pivot, np.zeros(3), None, Q0, w0)
    with pytest.raises(ValueError, match="pivot body 'Z' is not in the configuration"):
        pivot_initial_state(cfg, Pivot("Z", np.zeros(3)), None, None, Q0, w0)


def test_pivot_outside_the_main_body_is_refused():
    cfg, Q0, w0, _, _ = random_tree(8)
    with pytest.raises(ValueError, match="the pivot must be in the main body"):
        solve_fixed_point(cfg, np.eye(3), np.zeros(3), Pivot("B", np.zeros(3)), Q0, w0)


# -- the scene entry ----------------------------------------------------------------------------------

SCENE = """
{extra}
[potential]
a = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
b = [0.0, 0.0, 19.62]
[[bodies]]
name = "top"
mass = 3.0
box = [0.4, 0.4, 1.2]
[[bodies]]
name = "cap"
mass = 0.5
box = [0.5, 0.2, 0.1]
[[joints]]
parent = "top"
child = "cap"
parent_point = [0.0, 0.0, 0.6]
child_point = "central"
[initial.omega]
top = [0.5, 0.0, 6.0]
{initial}
[output]
t_end = 2.0
samples = 5
"""
GOOD = dict(extra='[fixed_point]\nbody = "top"\npoint = [0.0, 0.0, -0.6]', initial="")


@pytest.mark.parametrize("change, match", [
    ({}, None),
    (dict(extra='[fixed_point]\nbody = "wheel"\npoint = [0.0, 0.0, -0.6]'), "fixed_point.body: unknown body 'wheel'"),
    (dict(extra='[fixed_point]\nbody = "cap"\npoint = [0.0, 0.0, 0.0]'), "fixed_point.body 'cap' is not the main body"),
    (dict(extra='[fixed_point]\nbody = "top"\npoint = [nan, 0.0, -0.6]'), "fixed_point.point contains NaN"),
    (dict(extra='[fixed_point]\nbody = "top"\npoint = [0.0, -0.6]'), "fixed_point.point must have shape"),
    (dict(extra='[fixed_point]\nbody = "top"\npoint = [0.0, 0.0, -0.6]\nposition = [0.0, inf, 0.0]'),
     "fixed_point.position contains NaN"),
    (dict(extra='[fixed_point]\nbody = "top"'), r"\[fixed_point\] needs 'point'"),
    (dict(extra='[fixed_point]\nbody = "top"\npoint = [0.0, 0.0, -0.6]\npivot = 1'), r"\[fixed_point\]: unknown key"),
    (dict(extra='[constraint]\ntype = "sphere"\nradius = 1.0\n[fixed_point]\nbody = "top"\npoint = [0.0, 0.0, -0.6]'),
     r"\[fixed_point\] and \[constraint\] together"),
    (dict(initial="[initial]\nq = [0.0, 0.0, 1.0]"), "initial.q: with \\[fixed_point\\] the system mass centre"),
    (dict(extra='fixed_point = "top"'), r"\[fixed_point\] must be a table"),
])
def test_scene_fixed_point_entry(tmp_path, change, match):
    p = tmp_path / "s.toml"
    p.write_text(textwrap.dedent(SCENE.format(**{**GOOD, **change})))
    if match is None:
        sc = load_scene(p)
        assert sc.fixed_point == Pivot("top", [0.0, 0.0, -0.6])
        traj = sc.solve()
        assert traj.info["parts"].startswith("about a fixed point: top=elliptic")
        tip = traj.position[0] + np.einsum("tij,j->ti", traj.attitude[0], [0.0, 0.0, -0.6])
        assert np.max(np.abs(tip)) < 1e-15  # measured 1.1e-16
        return
    with pytest.raises(ValueError, match=match) as err:
        load_scene(p)
    assert str(p) in str(err.value)


def test_bundled_example_report():
    """thetasol/scenes/data/pivoted_top.toml: every check of the report passes, the model lines name the
    corollaries, and the mass centre stays at |c - r_P| from the pivot."""
    sc = load_scene(EXAMPLE)
    traj, report, checks = run(sc, check=False)
    assert all(c.ok for c in checks), report
    assert "Corollary 3 (a = 0: a uniform field about the pivot): heavy top: closed form elliptic" in report
    assert "fixed point (Section 5)" in report and "energy (5.3)" in report
    d = np.linalg.norm(traj.mass_center - sc.fixed_point.position, axis=1)
    assert np.ptp(d) < 4e-15  # measured 7.8e-16 (|c - r_P| = 0.707)


@pytest.mark.slow
def test_bundled_example_against_the_unsplit_system():
    sc = load_scene(EXAMPLE)
    traj, report, checks = run(sc)
    assert all(c.ok for c in checks), report
    assert "split vs unsplit multibody" in report and "max pivot gap" in report
