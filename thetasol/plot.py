"""Plots of solutions, scenes, reference scores, spectral curves and the gravity-gradient stability diagram.

Needs matplotlib (the ``plot`` extra: ``pip install "thetasol[plot]"``); ``import thetasol`` does not
load it, only ``import thetasol.plot`` does.  Every function draws with matplotlib's ``pyplot`` (so a
notebook shows the figure), takes an optional ``ax`` (one panel) or ``fig`` (several panels) to draw
into, and returns what it drew on: ``Axes`` or ``Figure``.

============================  =====================================================================
:func:`time_series`           the states of any :class:`~thetasol.Solution` against time
                              (``omega`` and the body axes' vertical components for a rotation)
:func:`on_sphere`             a path on the sphere (a point of Neumann's problem, a unit vector)
:func:`body_axes`             a body axis seen from space, ``Q(t) e_k``, traced on the unit sphere
:func:`trajectories`          a scene's :class:`~thetasol.Trajectories` (``python -m thetasol solve --plot``)
:func:`error_against_time`    a :class:`thetasol.reference.Report`: error and drift of the integrals
:func:`branch_points`         the branch points of a :class:`~thetasol.PlaneCurve` in the ``x``-plane
:func:`stability_diagram`     the gravity-gradient stability regions in the ``(k1, k3)`` plane
============================  =====================================================================
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence

try:
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch
except ImportError as exc:  # pragma: no cover - exercised in a subprocess without matplotlib
    raise ImportError(
        "thetasol.plot needs matplotlib, which is not installed: install the 'plot' extra, "
        "pip install \"thetasol[plot]\" (or pip install matplotlib)") from exc

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core.inertia import second_moments
from thetasol.mechanics.gravity_gradient import gravity_gradient_stability_from_moments
from thetasol.mechanics.trajectories import Trajectories
from thetasol.protocol import Solution, describe

__all__ = ["time_series", "on_sphere", "body_axes", "trajectories", "error_against_time", "branch_points",
           "stability_diagram", "stability_grid", "STABILITY_REGIONS"]

#: The regions of :func:`stability_diagram`, in the order of its colour map, with their colours.
STABILITY_REGIONS: dict[str, str] = {"unstable": "#f4cccc", "lagrange": "#b6d7a8", "debra-delp": "#a4c2f4",
                                     "marginal": "#666666", "non-physical": "#eeeeee"}

def _axes(ax, **kwargs):
    if ax is not None:
        return ax
    return plt.subplots(**kwargs)[1]


def _figure(fig, **kwargs):
    return fig if fig is not None else plt.figure(**kwargs)


# -- solutions ------------------------------------------------------------------------------------

def _default_labels(shapes: list[tuple]) -> list[str]:
    """Names for the state arrays of a solution, from their shapes."""
    if shapes == [(3,), (3, 3)]:
        return ["body angular velocity $\\omega$", "attitude $Q$"]
    if shapes == [(3,), (3,)]:
        return ["position", "velocity"]
    return [f"state {k + 1}" for k in range(len(shapes))]


def _draw_state(ax, t: np.ndarray, x: np.ndarray, label: str, vertical: np.ndarray) -> None:
    if x.shape[1:] == (3, 3):
        # an attitude: the vertical component of each body axis, cos of its angle to `vertical`
        up = np.einsum("i,nij->nj", vertical, x)
        for k in range(3):
            ax.plot(t, up[:, k], label=f"$e_{k + 1}$")
        ax.set_ylabel(f"{label}:\nvertical part of body axes", fontsize=9)
    else:
        flat = x.reshape(t.size, -1)
        sub = ("x", "y", "z") if flat.shape[1] == 3 else [str(k + 1) for k in range(flat.shape[1])]
        for k in range(flat.shape[1]):
            ax.plot(t, flat[:, k], label=sub[k])
        ax.set_ylabel(label, fontsize=9)
    ax.legend(loc="upper right", fontsize=8)


def time_series(sol, t: ArrayLike, *, labels: Sequence[str] | None = None, vertical: ArrayLike = (0.0, 0.0, 1.0),
                fig=None):
    """Every state array of a solution against time, one panel each.

    Parameters
    ----------
    sol : Solution
        Any closed form (``sol(t)`` returns a tuple of state arrays), e.g. from ``solve_rotation``,
        ``solve_heavy_top`` or ``solve_neumann``.
    t : array_like, shape (n,)
        Times.
    labels : sequence of str, optional
        Panel titles; default from the shapes: ``(omega, Q)`` for rotations, ``(position, velocity)``
        for a point.
    vertical : array_like, shape (3,)
        Space direction against which an attitude ``Q`` is shown: panel lines ``vertical . Q e_k``.
    fig : matplotlib.figure.Figure, optional
        Figure to draw into (new one by default).

    Returns
    -------
    matplotlib.figure.Figure
    """
    tt = np.asarray(t, dtype=float).ravel()
    states = sol(tt)
    shapes = [x.shape[1:] for x in states]
    labels = list(labels) if labels is not None else _default_labels(shapes)
    if len(labels) != len(states):
        raise ValueError(f"{len(labels)} labels for {len(states)} state arrays")
    up = np.asarray(vertical, dtype=float)
    up = up / np.linalg.norm(up)
    fig = _figure(fig, figsize=(8, 2.6 * len(states)))
    axs = fig.subplots(len(states), 1, sharex=True, squeeze=False)[:, 0]
    for ax, x, label in zip(axs, states, labels):
        _draw_state(ax, tt, np.asarray(x, dtype=float), label, up)
    axs[-1].set_xlabel("t")
    title = f"{sol.model}: {describe(sol)}" if isinstance(sol, Solution) else type(sol).__name__
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


def on_sphere(points: ArrayLike, *, t: ArrayLike | None = None, frame: ArrayLike | None = None, ax=None,
              title: str | None = None):
    """A path on the sphere (3-d axes, with a wire-frame unit sphere): unit vectors or a point on ``|q| = R``.

    Parameters
    ----------
    points : array_like, shape (n, 3)
        The path; scaled to the unit sphere by its first point's length.
    t : array_like, shape (n,), optional
        Times: colour the path by time (with a colour bar).
    frame : array_like, shape (3, 3), optional
        Rows are the space directions drawn as plot ``x, y, z`` (e.g. a frame whose third row is the
        angular momentum); default the space axes.
    ax : mpl_toolkits.mplot3d.Axes3D, optional
    title : str, optional

    Returns
    -------
    Axes3D
        The path is its first line (``t`` not given) or collection; the start is marked by a black dot.
    """
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"points must have shape (n, 3), got {p.shape}")
    F = np.eye(3) if frame is None else np.asarray(frame, dtype=float)
    xyz = p @ F.T / np.linalg.norm(p[0])
    if ax is None:
        ax = plt.figure(figsize=(5.5, 4.5)).add_subplot(projection="3d")
    if t is None:
        ax.plot(*xyz.T, lw=1)
    else:
        pts = ax.scatter(*xyz.T, c=np.asarray(t, dtype=float).ravel(), cmap="viridis", s=1)
        ax.figure.colorbar(pts, ax=ax, shrink=0.6, label="t")
    u, v = np.mgrid[0:2 * np.pi:40j, 0:np.pi:20j]
    ax.plot_wireframe(np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v), color="0.85", lw=0.5)
    ax.scatter(*xyz[0], color="k", s=15)
    ax.set_box_aspect((1, 1, 1), zoom=1.3)     # the unit sphere fills the panel
    ax.set_axis_off()
    if title:
        ax.set_title(title, fontsize=10)
    return ax


def body_axes(Q: ArrayLike, *, axis: int = 2, t: ArrayLike | None = None, frame: ArrayLike | None = None,
              ax=None):
    """The space image ``Q(t) e_axis`` of a body axis, traced on the unit sphere (:func:`on_sphere`).

    Parameters
    ----------
    Q : array_like, shape (n, 3, 3)
        Attitudes (body to space), e.g. ``sol.Q(t)``.
    axis : int
        Which body axis (0, 1, 2).
    t : array_like, shape (n,), optional
        Times: colour the trace by time (as in :func:`on_sphere`).
    frame : array_like, shape (3, 3), optional
        Rows are the space directions drawn as plot ``x, y, z`` (as in :func:`on_sphere`).
    ax : mpl_toolkits.mplot3d.Axes3D, optional

    Returns
    -------
    Axes3D
    """
    Qa = np.asarray(Q, dtype=float)
    if Qa.ndim != 3 or Qa.shape[1:] != (3, 3):
        raise ValueError(f"Q must have shape (n, 3, 3), got {Qa.shape}")
    if axis not in (0, 1, 2):
        raise ValueError(f"axis must be 0, 1 or 2, got {axis}")
    return on_sphere(Qa[:, :, axis], t=t, frame=frame, ax=ax,
                     title=f"body axis $Q(t)\\,e_{axis + 1}$ on the unit sphere")


# -- scenes -----------------------------------------------------------------------------------------

def _rotation_angle(Q: np.ndarray) -> np.ndarray:
    """Angle of ``Q(t) Q(0)^T`` (radians), robust near 0 and pi."""
    R = Q @ Q[0].T
    s = 0.5 * np.linalg.norm(np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0],
                                       R[:, 1, 0] - R[:, 0, 1]], axis=-1), axis=-1)
    c = 0.5 * (np.trace(R, axis1=1, axis2=2) - 1.0)
    return np.arctan2(s, c)


def trajectories(traj: Trajectories, *, fig=None):
    """A scene's trajectories: body centres in space, the system mass centre, ``|omega|`` and attitudes.

    Parameters
    ----------
    traj : Trajectories
        From :func:`thetasol.run`, a :class:`~thetasol.ConfigurationSolution` or
        :func:`thetasol.integrate_multibody`.
    fig : matplotlib.figure.Figure, optional

    Returns
    -------
    matplotlib.figure.Figure
        Four panels: the paths of the bodies' mass centres (3-d), the components of the system mass
        centre against time, each body's ``|omega|`` and its rotation angle from its initial attitude.
    """
    fig = _figure(fig, figsize=(11, 8))
    t = traj.t
    ax3 = fig.add_subplot(2, 2, 1, projection="3d")
    for i, name in enumerate(traj.names):
        ax3.plot(*traj.position[i].T, lw=1, label=name)
    ax3.plot(*traj.mass_center.T, "k--", lw=1, label="mass centre")
    ax3.set_title("mass centres of the bodies", fontsize=10)
    ax3.legend(fontsize=7, loc="upper left")
    ax = fig.add_subplot(2, 2, 2)
    for k, c in enumerate("xyz"):
        ax.plot(t, traj.mass_center[:, k], label=c)
    ax.set(xlabel="t", title="system mass centre q(t)")
    ax.legend(fontsize=8)
    ax_w = fig.add_subplot(2, 2, 3)
    ax_a = fig.add_subplot(2, 2, 4, sharex=ax_w)
    for i, name in enumerate(traj.names):
        ax_w.plot(t, np.linalg.norm(traj.omega[i], axis=-1), lw=1, label=name)
        ax_a.plot(t, np.degrees(_rotation_angle(traj.attitude[i])), lw=1, label=name)
    ax_w.set(xlabel="t", ylabel="|omega|", title="angular speed of each body")
    ax_a.set(xlabel="t", ylabel="degrees", title="rotation from the initial attitude")
    ax_w.legend(fontsize=7)
    fig.tight_layout()
    return fig


# -- reference cases --------------------------------------------------------------------------------

def _floor(x) -> np.ndarray:
    """Errors for a log axis: zeros drawn at 1e-17 (below double rounding)."""
    return np.maximum(np.asarray(x, dtype=float), 1e-17)


def error_against_time(report, *, fig=None):
    """Error against time and drift of the first integrals from :meth:`thetasol.reference.Case.report`.

    Parameters
    ----------
    report : thetasol.reference.Report or mapping of str to Report
        One report (one line per component group and per integral), or several labelled reports of
        the same case (e.g. one per integrator or tolerance: one line each, the worst group and the
        worst integral at each time).
    fig : matplotlib.figure.Figure, optional

    Returns
    -------
    matplotlib.figure.Figure
        Two log-scale panels: the error (relative as in :meth:`~thetasol.reference.Case.score`) and the
        drift of the first integrals.

    Examples
    --------
    >>> from scipy.integrate import solve_ivp
    >>> from thetasol import reference
    >>> import thetasol.plot
    >>> c = reference.case("free_top_long_axis")
    >>> r = solve_ivp(c.rhs, c.t_span, c.y0, method="RK45", rtol=1e-8, t_eval=c.times(201))
    >>> fig = thetasol.plot.error_against_time(c.report(r.t, r.y))
    """
    fig = _figure(fig, figsize=(9, 3.6))
    ax_e, ax_d = fig.subplots(1, 2, sharex=True)
    if isinstance(report, Mapping):
        for label, r in report.items():
            ax_e.semilogy(r.t, _floor(np.max(list(r.errors.values()), axis=0)), label=label)
            ax_d.semilogy(r.t, _floor(np.max(list(r.drift.values()), axis=0)), label=label)
        name = next(iter(report.values())).name if report else ""
    else:
        for g, e in report.errors.items():
            ax_e.semilogy(report.t, _floor(e), label=g)
        for k, d in report.drift.items():
            ax_d.semilogy(report.t, _floor(d), label=k)
        name = report.name
    ax_e.set(xlabel="t", ylabel="error against the exact solution", title=name)
    ax_d.set(xlabel="t", ylabel="drift of the first integrals", title=name)
    for ax in (ax_e, ax_d):
        ax.legend(fontsize=7)
        ax.grid(True, which="major", alpha=0.3)
    fig.tight_layout()
    return fig


# -- curves ---------------------------------------------------------------------------------------

def _trivial_monodromy(curve, pts: np.ndarray) -> np.ndarray:
    """True where going once around the critical value leaves every sheet in place."""
    perms = {complex(b): np.asarray(p) for b, p in curve.monodromy()[2] if np.isfinite(b)}
    out = np.zeros(pts.size, dtype=bool)
    for i, b in enumerate(pts):
        p = perms.get(complex(b))
        out[i] = p is not None and np.array_equal(p, np.arange(p.size))
    return out


def branch_points(curve, *, ax=None, monodromy: bool = True):
    """The finite branch points of a plane curve in the complex ``x``-plane (``E`` of (4.12)).

    Parameters
    ----------
    curve : PlaneCurve or array_like of complex
        A curve (e.g. ``sol.curve`` of a theta solution, or :func:`thetasol.spectral_curve`) or the points.
    monodromy : bool
        For a curve: draw critical values around which the sheets are not permuted (trivial monodromy:
        singular points, not branch points) hollow, and say so in the legend.
    ax : matplotlib.axes.Axes, optional

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax, figsize=(5.5, 4.5))
    if hasattr(curve, "branch_points"):
        pts = np.asarray(curve.branch_points, dtype=complex)
        trivial = _trivial_monodromy(curve, pts) if monodromy else np.zeros(pts.size, dtype=bool)
        title = f"branch points (genus {curve.genus})"
    else:
        pts, title = np.asarray(curve, dtype=complex).ravel(), "branch points"
        trivial = np.zeros(pts.size, dtype=bool)
    keep = np.isfinite(pts)
    pts, trivial = pts[keep], trivial[keep]
    ax.axhline(0, color="0.85", lw=0.8)
    ax.axvline(0, color="0.85", lw=0.8)
    ax.scatter(pts[~trivial].real, pts[~trivial].imag, color="C0", zorder=3, label=f"{np.sum(~trivial)} branch points")
    if np.any(trivial):
        ax.scatter(pts[trivial].real, pts[trivial].imag, facecolors="none", edgecolors="C3", zorder=3,
                   label=f"{np.sum(trivial)} with trivial monodromy")
    ax.set(xlabel="Re x", ylabel="Im x", title=title)
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(fontsize=8)
    return ax


# -- gravity gradient -------------------------------------------------------------------------------

def _region(k1: float, k3: float) -> str:
    """The library's classification of the body (I2 = 1) with these k1, k3; 'non-physical' if none exists."""
    if k3 == 1.0:
        return "non-physical"
    I1 = (1.0 - k1) / (1.0 - k3)
    I = np.array([I1, 1.0, I1 + k1])          # k1 = I3 - I1, k3 = (I3 - 1) / I1
    J = second_moments(I)                      # J >= 0: the triangle inequalities of the inertia
    if np.any(I <= 0) or np.any(J < 0):
        return "non-physical"
    return gravity_gradient_stability_from_moments(J, 1.0).region


def stability_grid(n: int = 201) -> tuple[np.ndarray, np.ndarray]:
    """``(k, regions)``: ``k`` the ``n`` values in ``[-1, 1]``, ``regions[i, j]`` the index in
    :data:`STABILITY_REGIONS` of the body with ``k1 = k[j]``, ``k3 = k[i]`` (classified by
    :func:`thetasol.gravity_gradient_stability`, one call a point)."""
    k = np.linspace(-1.0, 1.0, int(n))
    names = list(STABILITY_REGIONS)
    return k, np.array([[names.index(_region(k1, k3)) for k1 in k] for k3 in k])


def stability_diagram(bodies: Mapping[str, ArrayLike] | None = None, *, n: int = 201, ax=None):
    """The gravity-gradient stability regions of the orbit-aligned attitude in the ``(k1, k3)`` plane.

    Axes of the body along the orbit frame: 1 radial, 2 along-track, 3 orbit normal; ``k1 = (I3 - I1)/I2``,
    ``k3 = (I3 - I2)/I1``.  Every grid point is a body (``I2 = 1``) classified by
    :func:`thetasol.gravity_gradient_stability` (not by re-coding its inequalities), so the picture shows
    what the library computes.

    Parameters
    ----------
    bodies : mapping of str to array_like (3,), optional
        Bodies to mark, label -> principal inertia ``(I1, I2, I3)`` in the orbit axes.
    n : int
        Grid points per axis (``n^2`` classifications).
    ax : matplotlib.axes.Axes, optional

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax, figsize=(6.4, 6.0))
    k, grid = stability_grid(n)
    colors = list(STABILITY_REGIONS.values())
    ax.imshow(grid, origin="lower", extent=(k[0], k[-1], k[0], k[-1]), cmap=ListedColormap(colors),
              vmin=-0.5, vmax=len(colors) - 0.5, interpolation="nearest")
    markers = "os^vDP*X"
    for i, (label, inertia) in enumerate((bodies or {}).items()):
        I1, I2, I3 = (float(x) for x in np.asarray(inertia, dtype=float).reshape(3))
        k1, k3 = (I3 - I1) / I2, (I3 - I2) / I1
        ax.plot(k1, k3, markers[i % len(markers)], color="k", ms=8,
                label=f"{label}: $k_1$ = {k1:.3f}, $k_3$ = {k3:.3f}")
    patches = [Patch(color=c, label=r) for r, c in STABILITY_REGIONS.items()]
    ax.add_artist(ax.legend(handles=patches, loc="lower right", fontsize=8, title="region"))
    if bodies:
        ax.legend(loc="upper left", fontsize=7)
    ax.set_xlabel("$k_1 = (I_3 - I_1) / I_2$")
    ax.set_ylabel("$k_3 = (I_3 - I_2) / I_1$")
    ax.set_title("orbit-aligned attitude on a circular orbit\n(1 radial, 2 along-track, 3 orbit normal)",
                 fontsize=10)
    return ax
