"""The gravity-gradient stability diagram in the (k1, k3) plane, with example bodies marked.

    PYTHONPATH=. python benchmarks/plot_gravity_gradient_stability.py [out.png]

Marked: three example bodies, the effective bodies of examples/orbiting_station.toml at their nearest
orbit-aligned attitudes (a body at k1 = k3 = 1, a near-rod, is drawn just inside the frame) and the
gravity-gradient unstable target that examples/station_lqr.py stabilizes.  Every grid point is classified by thetasol.mechanics.gravity_gradient.gravity_gradient_stability
(not by re-coding the inequalities), so the picture shows what the library computes.  Axes as in
the library: 1 radial, 2 along-track, 3 orbit normal; k1 = (I3 - I1)/I2, k3 = (I3 - I2)/I1.
"""
from __future__ import annotations

import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from thetasol.mechanics.gravity_gradient import gravity_gradient_stability  # noqa: E402
from thetasol.scenes.format import load_scene  # noqa: E402

STATION = "examples/orbiting_station.toml"

REGIONS = {"unstable": 0, "lagrange": 1, "debra-delp": 2, "marginal": 3, "non-physical": 4}


def inertia_from_k(k1: float, k3: float):
    """Principal inertia (I1, I2 = 1, I3) with the given k1, k3 (None where k3 = 1)."""
    if k3 == 1.0:
        return None
    I1 = (1.0 - k1) / (1.0 - k3)
    return np.array([I1, 1.0, I1 + k1])


def classify(k1: float, k3: float) -> int:
    I = inertia_from_k(k1, k3)
    if I is None or np.any(I <= 0):
        return REGIONS["non-physical"]
    J = 0.5 * I.sum() - I
    if np.any(J < 0):                         # a triangle inequality fails
        return REGIONS["non-physical"]
    return REGIONS[gravity_gradient_stability(J, 1.0).region]


def station_points() -> dict:
    """(k1, k3) of the example station's effective bodies at their nearest orbit-aligned attitudes (the
    report's stability table), and the panel's target of examples/station_lqr.py (least inertia along-track)."""
    scene = load_scene(STATION)
    sol = scene.solution()
    pts = {f"station: {n} ({b.stability.region})": (b.stability.k1, b.stability.k3) for n, b in sol.stability.items()}
    Jp = scene.config.effective_body("panel").principal_moments           # ascending J = descending I
    st = gravity_gradient_stability(Jp[[1, 2, 0]], 1.0)
    pts[f"station_lqr.py: panel target ({st.region}, LQR-stabilized)"] = (st.k1, st.k3)
    return pts


def main(out: str = "docs/img/gravity_gradient_stability.png") -> None:
    k = np.linspace(-1, 1, 401)
    grid = np.array([[classify(a, b) for a in k] for b in k])
    colors = ["#f4cccc", "#b6d7a8", "#a4c2f4", "#999999", "#eeeeee"]
    cmap = matplotlib.colors.ListedColormap(colors)
    fig, ax = plt.subplots(figsize=(6.4, 6.0), dpi=110)
    ax.imshow(grid, origin="lower", extent=(-1, 1, -1, 1), cmap=cmap, vmin=-0.5, vmax=4.5,
              interpolation="nearest")
    bodies = {
        "example satellite I = (1200, 1500, 1800)": (1200.0, 1500.0, 1800.0),
        "DeBra-Delp example I = (0.7, 1, 0.65)": (0.7, 1.0, 0.65),
        "JEOD cylinder I = (500, 12250, 12250)": (500.0, 12250.0, 12250.0),
    }
    for (label, I), mk in zip(bodies.items(), ("o", "s", "^"), strict=True):
        I1, I2, I3 = I
        k1, k3 = (I3 - I1) / I2, (I3 - I2) / I1
        ax.plot(k1, k3, mk, color="k", ms=8, label=f"{label}: k1 = {k1:.3f}, k3 = {k3:.3f}")
    station = station_points()
    for (label, (k1, k3)), mk in zip(station.items(), "DPXvp", strict=False):
        ax.plot(min(k1, 0.985), min(k3, 0.985), mk, color="C3", mec="k", ms=7, label=f"{label}: k1 = {k1:.3f}, k3 = {k3:.3f}")
    # the plate-like and rod-like bodies crowd the corner k1 = k3 = 1: zoom on it
    kz = np.linspace(0.96, 1.0, 161)
    zoom = ax.inset_axes([0.05, 0.05, 0.32, 0.32])
    zoom.imshow(np.array([[classify(a, b) for a in kz] for b in kz]), origin="lower", extent=(0.96, 1, 0.96, 1),
                cmap=cmap, vmin=-0.5, vmax=4.5, interpolation="nearest")
    for (k1, k3), mk in zip(station.values(), "DPXvp", strict=False):
        zoom.plot(min(k1, 0.999), min(k3, 0.999), mk, color="C3", mec="k", ms=6)
    zoom.set_xlim(0.96, 1.0)
    zoom.set_ylim(0.96, 1.0)
    zoom.tick_params(labelsize=6)
    zoom.yaxis.tick_right()
    zoom.set_title("k1, k3 in [0.96, 1]", fontsize=7)
    patches = [matplotlib.patches.Patch(color=c, label=name)
               for name, c in zip(REGIONS, colors, strict=True)]
    leg1 = ax.legend(handles=patches, loc="lower right", fontsize=8, title="region")
    ax.add_artist(leg1)
    ax.legend(loc="upper left", fontsize=6)
    ax.set_xlabel("k1 = (I3 - I1) / I2")
    ax.set_ylabel("k3 = (I3 - I2) / I1")
    ax.set_title("Orbit-aligned attitude on a circular orbit\n(1 radial, 2 along-track, 3 orbit normal)")
    fig.tight_layout()
    fig.savefig(out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(*sys.argv[1:])
