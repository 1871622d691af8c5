"""thetasol.plot: what each helper draws is the data it was given (read back from the artists), the
stability diagram agrees with the published regions, and matplotlib stays optional."""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import thetasol  # noqa: E402
from thetasol import (
    plot,  # noqa: E402
)
from thetasol.mechanics.trajectories import Trajectories  # noqa: E402


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def test_import_thetasol_loads_no_matplotlib():
    code = ("import sys, thetasol; thetasol.solve_rotation; thetasol.reference; "
            "print('matplotlib' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_missing_matplotlib_names_the_extra():
    """With matplotlib unimportable, ``import thetasol.plot`` raises ImportError naming the extra."""
    code = ("import sys; sys.modules['matplotlib'] = None\n"
            "try:\n    import thetasol.plot\nexcept ImportError as e:\n    print(e)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "thetasol.plot needs matplotlib" in out.stdout and 'thetasol[plot]' in out.stdout


def _euler_top():
    I = np.array([2.0, 3.0, 4.0])
    return thetasol.solve_rotation(I, np.zeros((3, 3)), np.eye(3), [1e-3, 2.0, 1e-3])


def test_time_series_draws_the_solution():
    sol = _euler_top()
    t = np.linspace(0.0, 20.0, 201)
    omega, Q = sol(t)
    fig = plot.time_series(sol, t)
    ax_w, ax_Q = fig.axes
    for k in range(3):
        assert np.array_equal(ax_w.lines[k].get_ydata(), omega[:, k])
        assert np.array_equal(ax_Q.lines[k].get_ydata(), Q[:, 2, k])     # vertical part of body axis k
    assert fig.texts[0].get_text() == "rotation: elliptic"
    with pytest.raises(ValueError, match="1 labels for 2 state arrays"):
        plot.time_series(sol, t, labels=["omega"])


def test_time_series_of_a_point():
    sol = thetasol.solve_neumann(np.diag([0.0, 1.0, 2.5]), [0.6, 0.0, 0.8], [0.0, 0.7, 0.0])
    t = np.linspace(0.0, 5.0, 51)
    q, v = sol(t)
    fig = plot.time_series(sol, t)
    assert [ax.get_ylabel() for ax in fig.axes] == ["position", "velocity"]
    assert np.array_equal(fig.axes[1].lines[1].get_ydata(), v[:, 1])


def test_body_axes_on_the_unit_sphere():
    sol = _euler_top()
    t = np.linspace(0.0, 10.0, 301)
    Q = sol.Q(t)
    ax = plot.body_axes(Q, axis=1)
    x, y, z = ax.lines[0].get_data_3d()
    assert np.allclose(np.c_[x, y, z], Q[:, :, 1], atol=1e-15, rtol=0)    # divided by |Q(0) e2| = 1 to rounding
    assert np.max(np.abs(x * x + y * y + z * z - 1)) < 1e-14      # measured 4.4e-16
    with pytest.raises(ValueError, match=r"shape \(n, 3, 3\)"):
        plot.body_axes(Q[:, :2])
    with pytest.raises(ValueError, match="axis"):
        plot.body_axes(Q, axis=3)


def test_stability_grid_matches_published_regions():
    """Lagrange region k1 > k3 > 0; DeBra-Delp region k3 < k1 < 0 with 1 + 3 k1 + k1 k3 > 4 sqrt(k1 k3)
    (Hughes, Spacecraft Attitude Dynamics, ch. 9); inside the square every body exists.  Only points
    0.02 or more from every boundary are compared."""
    k, grid = plot.stability_grid(101)
    names = list(plot.STABILITY_REGIONS)
    K1, K3 = np.meshgrid(k, k)
    I1 = (1 - K1) / (1 - K3 + (K3 == 1))                  # I2 = 1, I3 = I1 + k1
    I = np.stack([I1, np.ones_like(I1), I1 + K1])
    physical = (K3 < 1) & np.all(I > 0, axis=0) & np.all(I.sum(axis=0) - 2 * I > 0.02, axis=0)
    # |k1|, |k3| <= 1 are the triangle inequalities: equalities (or I1 = 0) on the edges, rounding decides there
    edge = (np.abs(K1) > 0.95) | (np.abs(K3) > 0.95)
    assert np.all(grid[K3 == 1] == names.index("non-physical"))
    assert not np.any(grid[~edge] == names.index("non-physical"))
    lagrange = (K1 > K3 + 0.02) & (K3 > 0.02) & physical
    b, c = 1 + 3 * K1 + K1 * K3, K1 * K3
    debra = (K3 + 0.02 < K1) & (K1 < -0.02) & (b > 4 * np.sqrt(np.abs(c)) + 0.02) & physical
    assert lagrange.sum() > 500 and debra.sum() > 20
    assert np.all(grid[lagrange] == names.index("lagrange"))
    assert np.all(grid[debra] == names.index("debra-delp"))
    clearly_unstable = ((K3 > K1 + 0.02) | ((K1 > 0.02) & (K3 < -0.02))) & physical
    assert np.all(grid[clearly_unstable] == names.index("unstable"))


def test_stability_diagram_marks_bodies():
    ax = plot.stability_diagram({"satellite": (1200.0, 1500.0, 1800.0)}, n=21)
    (line,) = ax.lines
    assert line.get_xdata()[0] == pytest.approx(0.4) and line.get_ydata()[0] == pytest.approx(0.25)
    assert ax.images[0].get_array().shape == (21, 21)


def test_branch_points_and_trivial_monodromy():
    """y^2 = x^2 (x^2 - 1) (x - 2): critical values 0 (a node: the sheets do not swap), -1, 1, 2."""
    import sympy

    from thetasol.curves.plane_curve import PlaneCurve

    x, y = sympy.symbols("x y")
    curve = PlaneCurve(y**2 - x**2 * (x**2 - 1) * (x - 2), x, y)
    ax = plot.branch_points(curve)
    true, node = ax.collections
    assert np.allclose(np.sort(true.get_offsets()[:, 0]), [-1.0, 1.0, 2.0]) and np.allclose(node.get_offsets(), 0)
    ax = plot.branch_points([1 + 1j, -1 - 1j, np.inf])
    assert np.allclose(ax.collections[0].get_offsets(), [[1, 1], [-1, -1]])


def test_error_against_time_draws_the_report():
    from scipy.integrate import solve_ivp

    from thetasol import reference

    c = reference.case("free_top_long_axis")
    r = solve_ivp(c.rhs, c.t_span, c.y0, method="RK45", rtol=1e-6, t_eval=c.times(51))
    rep = c.report(r.t, r.y)
    fig = plot.error_against_time(rep)
    ax_e, ax_d = fig.axes
    assert [ln.get_label() for ln in ax_e.lines] == list(rep.errors)
    assert np.array_equal(ax_e.lines[1].get_ydata()[1:], rep.errors["Q"][1:])
    assert [ln.get_label() for ln in ax_d.lines] == list(rep.drift)
    fig = plot.error_against_time({"RK45": rep})
    worst = np.maximum(rep.errors["omega"], rep.errors["Q"])
    assert np.array_equal(fig.axes[0].lines[0].get_ydata()[1:], worst[1:])


def test_trajectories_panels():
    t = np.linspace(0.0, 1.0, 11)
    angle = 0.3 * t
    c, s = np.cos(angle), np.sin(angle)
    Q = np.zeros((11, 3, 3))
    Q[:, 0, 0], Q[:, 0, 1], Q[:, 1, 0], Q[:, 1, 1], Q[:, 2, 2] = c, -s, s, c, 1.0
    pos = np.stack([np.c_[t, 0 * t, 0 * t], np.c_[t, t, 0 * t]])
    traj = Trajectories(t=t, names=("a", "b"), position=pos, velocity=np.ones_like(pos),
                        attitude=np.stack([Q, Q]), omega=np.tile([0.0, 0.0, 0.3], (2, 11, 1)),
                        mass_center=pos.mean(axis=0), mass_center_velocity=np.ones((11, 3)))
    fig = plot.trajectories(traj)
    assert len(fig.axes) == 4
    angle_lines = fig.axes[3].lines
    assert np.allclose(angle_lines[0].get_ydata(), np.degrees(angle), rtol=0, atol=1e-13)
    assert np.allclose(fig.axes[2].lines[1].get_ydata(), 0.3)


def test_on_sphere_scales_a_point_of_neumann():
    """A point on |q| = 2 is drawn on the unit sphere; with times it is a scatter coloured by t."""
    sol = thetasol.solve_neumann(np.diag([0.0, 1.0, 2.5]), [1.2, 0.0, 1.6], [0.0, 0.7, 0.0])
    t = np.linspace(0.0, 5.0, 51)
    q, _ = sol(t)
    ax = plot.on_sphere(q)
    assert np.allclose(np.c_[ax.lines[0].get_data_3d()], q / 2, rtol=0, atol=1e-15)
    ax = plot.on_sphere(q, t=t)
    assert np.array_equal(ax.collections[0].get_array(), t)
    with pytest.raises(ValueError, match=r"shape \(n, 3\)"):
        plot.on_sphere(q[:, :2])
