"""Theorem 3 as a scene: the system mass centre of a C^2-central configuration on the sphere |q| = R.

The split (solve_configuration(..., constraint=Sphere(R)): Neumann's point for the mass centre by
solve_neumann, every rotation as without the constraint) against the unsplit multibody system
with the same constraint as one more KKT row (integrate_multibody(..., constraint=Sphere(R)):
maximal coordinates, the multiplier pushing every body in proportion to its mass, no effective
bodies, no Neumann formulas).  The unsplit side is checked on its own: energy summed body by body
conserved (the rod does no work), joints and sphere held, and its attitudes equal to those of the
same system without the rod (Theorem 3 seen without the split).
"""
import textwrap
from pathlib import Path

import numpy as np
import pytest

from thetasol.core.so3 import rodrigues
from thetasol.integrators.multibody import integrate_multibody
from thetasol.integrators.neumann import NumericalNeumann, integrate_neumann
from thetasol.mechanics.bodies import Body
from thetasol.mechanics.configuration import Configuration, Joint
from thetasol.mechanics.constraints import Sphere
from thetasol.protocol import ClosedFormUnavailable
from thetasol.scenes.format import load_scene
from thetasol.scenes.pipeline import solve_configuration
from thetasol.scenes.report import run
from thetasol.solutions.points.neumann import NeumannSolution, solve_neumann

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "neumann_station.toml"
EDGES = [("A", "B"), ("B", "C"), ("A", "D")]  # 4 bodies, C^2: a chain of length 2


def make_system(seed, R=1.5, eig=(2.0, 1.0, 0.4)):
    """A random C^2-central tree of point-mass bodies with its mass centre on |q| = R, b = 0."""
    rng = np.random.default_rng(seed)
    names = sorted({n for e in EDGES for n in e})
    bodies = [Body.from_point_masses(rng.uniform(0.5, 2, 5), rng.normal(size=(5, 3)), name=n) for n in names]
    cfg = Configuration(bodies, [Joint(p, c, rng.normal(size=3), np.zeros(3)) for p, c in EDGES]).make_central()
    Rot = rodrigues(rng.normal(size=3))
    a = Rot @ np.diag(eig) @ Rot.T
    u = rng.normal(size=3)
    u /= np.linalg.norm(u)
    v = rng.normal(size=3)
    v -= u * (u @ v)
    state = dict(q0=R * u, v0=v, Q0={n: rodrigues(rng.normal(size=3)) for n in names},
                 omega0={n: rng.normal(size=3) for n in names})
    return cfg, a, np.zeros(3), state


def energy(cfg, traj, a):
    """Total energy summed body by body in phi = 1/2 x^T a x (no split formula involved)."""
    E = 0.0
    for i, n in enumerate(traj.names):
        body = cfg.bodies[n]
        x, v, Q, w = traj.position[i], traj.velocity[i], traj.attitude[i], traj.omega[i]
        E = E + 0.5 * body.mass * np.sum(v * v, -1) + 0.5 * np.einsum("ti,ij,tj->t", w, body.I, w)
        E = E + body.mass * 0.5 * np.einsum("ti,ij,tj->t", x, a, x)
        E = E + 0.5 * np.trace(np.swapaxes(Q, 1, 2) @ a @ Q @ body.J, axis1=1, axis2=2)
    return E


def test_example_scene_split_against_unsplit():
    """examples/neumann_station.toml: closed-form rotations (theta, Neumann) and Neumann's mass centre
    against the constrained multibody system over t <= 60 (7 oscillations of the fastest coordinate
    of the mass centre, 4 of the slowest)."""
    sc = load_scene(EXAMPLE)
    assert sc.constraint == Sphere(2.0) and len(sc.config) == 4 and sc.config.depth == 2
    traj, report, checks = run(sc, check=False)  # the multibody check is repeated below, per quantity
    assert all(c.ok for c in checks), report
    assert "Neumann's problem on |q| = 2: closed form fourier/genus-2" in report
    assert all("closed form" in m for m in traj.info["models"]["rotations"].values())
    # the constraint along the split: measured 5.6e-16 relative
    assert np.max(np.abs(np.linalg.norm(traj.mass_center, axis=1) - 2.0)) < 4e-15
    mb = integrate_multibody(sc.config, sc.a, sc.b, sc.q0, sc.v0, sc.Q0, sc.omega0, sc.t, rtol=1e-12,
                             constraint=sc.constraint)
    dev = traj.deviation(mb)  # measured 1.2e-11, 6.3e-12, 1.2e-11, 4.2e-12, 6.6e-12
    assert dev["position"] < 1e-10 and dev["attitude"] < 1e-10
    assert dev["velocity"] < 1e-10 and dev["omega"] < 1e-10 and dev["mass_center"] < 1e-10
    assert mb.info["sphere_residual"] < 2e-12  # measured 1.6e-13
    assert mb.info["constraint_residual"] < 1e-11  # measured 6.7e-13


def test_split_matches_unsplit_random_tree_over_many_periods():
    """Point-mass bodies, eigenvalues (2, 1, 0.4) in a random frame, t <= 40, numerical rotations
    (DOP853 at rtol 1e-13) and Neumann's mass centre against the constrained multibody system."""
    cfg, a, b, s = make_system(3)
    t = np.linspace(0.0, 40.0, 161)
    sol = solve_configuration(cfg, a, b, rotation="numerical", rtol=1e-13, constraint=Sphere(1.5), **s)
    assert isinstance(sol.mass_center, NeumannSolution) and sol.diagnostics["parts"].startswith("neumann=")
    split = sol.trajectories(t)
    q = split.mass_center
    crossings = [int(np.sum(np.diff(np.sign(q[:, i])) != 0)) for i in range(3)]
    assert min(crossings) >= 10  # measured 18, 12, 12 sign changes of the coordinates
    assert np.max(np.abs(np.linalg.norm(q, axis=1) - 1.5)) < 4e-15 * 1.5  # measured 4.4e-16 relative
    mb = integrate_multibody(cfg, a, b, t=t, rtol=1e-12, constraint=Sphere(1.5), **s)
    dev = split.deviation(mb)
    assert dev["position"] < 1e-10 and dev["attitude"] < 1e-10  # measured 2.0e-11, 1.3e-11
    assert dev["velocity"] < 3e-10 and dev["omega"] < 1e-10  # measured 5.4e-11, 8.2e-12
    # the reference on its own: the rod does no work, joints and sphere hold
    E = energy(cfg, mb, a)
    assert np.max(np.abs(E - E[0])) < 2e-12 * abs(E[0])  # measured 3.9e-13
    assert np.max(np.abs(E - sol.invariants["energy"])) < 2e-12 * abs(E[0])  # measured 3.9e-13
    assert mb.info["sphere_residual"] < 1e-12 and mb.info["constraint_residual"] < 2e-11  # 8.6e-14, 1.9e-12


def test_rod_changes_the_mass_centre_not_the_rotations():
    """Theorem 3 on the unsplit system alone: with and without the rod the attitudes agree to the
    integrator's error while the mass centres part by O(1); the split without the constraint is
    far from the constrained system (the comparison above can fail)."""
    cfg, a, b, s = make_system(7)
    t = np.linspace(0.0, 20.0, 81)
    with_rod = integrate_multibody(cfg, a, b, t=t, rtol=1e-12, constraint=Sphere(1.5), **s)
    free = integrate_multibody(cfg, a, b, t=t, rtol=1e-12, **s)
    dev = with_rod.deviation(free)
    assert dev["attitude"] < 1e-11 and dev["omega"] < 1e-11  # measured 3.9e-13, 1.4e-12
    assert dev["mass_center"] > 0.1
    unconstrained_split = solve_configuration(cfg, a, b, rotation="numerical", rtol=1e-13, **s).trajectories(t)
    assert unconstrained_split.deviation(with_rod)["position"] > 0.1


# -- bad input -------------------------------------------------------------------------------------

@pytest.mark.parametrize("radius", [0.0, -1.0, float("nan"), float("inf"), "1", True])
def test_bad_radius(radius):
    with pytest.raises(ValueError, match="radius"):
        Sphere(radius)


@pytest.mark.parametrize("change, match", [
    (dict(b=[0.0, 0.0, 1e-3]), "b must be 0"),
    (dict(q0=[1.5 * (1 + 1e-10), 0.0, 0.0]), "q0 must be on the sphere"),
    (dict(q0=[0.0, 0.0, 0.0]), "q0 must be on the sphere"),
    (dict(v0=[1e-9, 1.0, 0.0]), "v0 must be tangent"),
])
@pytest.mark.parametrize("solver", ["split", "multibody"])
def test_bad_state_or_potential(change, match, solver):
    cfg, a, _, s = make_system(1)
    args = dict(b=np.zeros(3), q0=np.array([1.5, 0.0, 0.0]), v0=np.array([0.0, 0.3, -0.2]))
    args.update(change)
    s = {**s, "q0": args["q0"], "v0": args["v0"]}
    with pytest.raises(ValueError, match=match):
        if solver == "split":
            solve_configuration(cfg, a, args["b"], rotation="numerical", constraint=Sphere(1.5), **s)
        else:
            integrate_multibody(cfg, a, args["b"], t=[0.0, 1.0], constraint=Sphere(1.5), **s)


def test_tolerances_of_the_initial_state():
    """|q0| = R and q0.v0 = 0 are accepted within 1e-12 relative."""
    cfg, a, b, s = make_system(1)
    s = {**s, "q0": np.array([1.5 * (1 + 5e-13), 0.0, 0.0]), "v0": np.array([5e-13, 0.3, -0.4])}
    sol = solve_configuration(cfg, a, b, rotation="numerical", constraint=Sphere(1.5), **s)
    assert np.all(np.isfinite(sol.trajectories([0.0, 1.0]).position))


def test_constraint_must_be_a_sphere():
    cfg, a, b, s = make_system(1)
    with pytest.raises(ValueError, match="constraint must be a Sphere"):
        solve_configuration(cfg, a, b, rotation="numerical", constraint=1.5, **s)
    with pytest.raises(ValueError, match="constraint must be a Sphere"):
        integrate_multibody(cfg, a, b, t=[0.0, 1.0], constraint=1.5, **s)


SCENE = """
[constraint]
{constraint}
[potential]
a = [[1.0, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 0.2]]
{b}
[[bodies]]
name = "root"
mass = 4.0
I = [2.0, 2.5, 3.0]
[[bodies]]
name = "arm"
mass = 1.0
box = [1.0, 0.2, 0.2]
[[joints]]
parent = "root"
child = "arm"
parent_point = [1.0, 0.0, 0.0]
child_point = "central"
[initial]
q = {q}
v = {v}
[output]
t_end = 2.0
samples = 5
"""
GOOD = dict(constraint='type = "sphere"\nradius = 2.0', b="", q="[0.0, 1.2, 1.6]", v="[1.0, 0.4, -0.3]")


@pytest.mark.parametrize("change, match", [
    ({}, None),
    (dict(constraint='type = "cylinder"\nradius = 2.0'), 'constraint.type must be "sphere"'),
    (dict(constraint='radius = 2.0'), 'constraint.type must be "sphere"'),
    (dict(constraint='type = "sphere"'), "needs 'radius'"),
    (dict(constraint='type = "sphere"\nradius = -2.0'), "constraint.radius must be positive"),
    (dict(constraint='type = "sphere"\nradius = 2.0\ncentre = [0, 0, 0]'), r"\[constraint\]: unknown key"),
    (dict(b="b = [0.0, 0.1, 0.0]"), "potential.b must be 0"),
    (dict(q="[0.0, 1.2, 1.7]"), "initial.q must be on the sphere"),
    (dict(v="[1.0, 0.4, 0.3]"), "initial.v must be tangent"),
])
def test_scene_constraint_entry(tmp_path, change, match):
    p = tmp_path / "s.toml"
    p.write_text(textwrap.dedent(SCENE.format(**{**GOOD, **change})))
    if match is None:
        sc = load_scene(p)
        assert sc.constraint == Sphere(2.0)
        traj = sc.solve()
        assert np.allclose(np.linalg.norm(traj.mass_center, axis=1), 2.0, rtol=1e-14, atol=0)
        return
    with pytest.raises(ValueError, match=match) as err:
        load_scene(p)
    assert str(p) in str(err.value)


def test_constraint_table_must_be_a_table(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text(textwrap.dedent(SCENE.format(**GOOD)).replace("[constraint]\n", 'constraint = "sphere"\n', 1)
                 .replace('type = "sphere"\nradius = 2.0\n', "", 1))
    with pytest.raises(ValueError, match=r"\[constraint\] must be a table"):
        load_scene(p)


# -- the numerical fallback near a separatrix --------------------------------------------------------

def test_integrate_neumann_converges_to_the_closed_form():
    """integrate_neumann (Baumgarte-stabilized, both directions of time) against solve_neumann on the
    example's mass centre over t in [-60, 60]: the gap falls with rtol, so it is the integrator's."""
    sc = load_scene(EXAMPLE)
    t = np.linspace(-60.0, 60.0, 241)
    q, v = solve_neumann(sc.a, sc.q0, sc.v0)(t)
    gaps = []
    for rtol in (1e-10, 1e-13):
        qn, vn = integrate_neumann(sc.a, sc.q0, sc.v0, rtol=rtol)(t)
        gaps.append(max(np.max(np.abs(q - qn)), np.max(np.abs(v - vn))))
        assert np.max(np.abs(np.linalg.norm(qn, axis=1) - 2.0)) < 4e-15  # measured 4.4e-16 (projected)
    assert gaps[1] < 1e-11  # measured 1.7e-12
    assert gaps[0] / gaps[1] > 100  # measured 6.1e-9 / 1.7e-12
    sol = integrate_neumann(sc.a, sc.q0, sc.v0, rtol=1e-13)
    qs, vs = sol(t[1:].reshape(3, -1)[:, ::-1])  # any shape, any order
    assert qs.shape == (3, 80, 3) and np.allclose(qs, q[1:].reshape(3, -1, 3)[:, ::-1], atol=1e-11, rtol=0)


def test_fallback_matches_the_unsplit_system():
    """The mass centre started 1e-9 (relative) off the great circle of the two lower eigen-axes of a: the
    torus is 1e-18 thin, solve_neumann refuses the data, the split uses integrate_neumann and still
    agrees with the constrained multibody system."""
    cfg, a, b, s = make_system(7)
    axes = np.linalg.eigh(a)[1]
    q0 = 1.5 * (0.6 * axes[:, 0] + 0.8 * axes[:, 1] + 1e-9 * axes[:, 2])
    s = {**s, "q0": q0, "v0": 0.3 * (0.8 * axes[:, 0] - 0.6 * axes[:, 1])}
    with pytest.raises(ClosedFormUnavailable, match="great circle"):
        solve_neumann(a, s["q0"], s["v0"])
    sol = solve_configuration(cfg, a, b, rotation="numerical", rtol=1e-13, constraint=Sphere(1.5), **s)
    assert isinstance(sol.mass_center, NumericalNeumann)
    assert "numerical fallback" in sol.diagnostics["models"]["mass_center"]
    assert "great circle" in sol.diagnostics["mass_center_reason"]
    t = np.linspace(0.0, 20.0, 81)
    dev = sol.trajectories(t).deviation(integrate_multibody(cfg, a, b, t=t, rtol=1e-12, constraint=Sphere(1.5), **s))
    assert max(dev["position"], dev["attitude"]) < 1e-10  # measured 1.4e-12, 5.5e-13
