"""The gravity-gradient stability diagram in the (k1, k3) plane, with example bodies marked.

    PYTHONPATH=. python benchmarks/plot_gravity_gradient_stability.py [out.png]

Every grid point is classified by thetasol.mechanics.gravity_gradient.gravity_gradient_stability
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
    patches = [matplotlib.patches.Patch(color=c, label=name)
               for name, c in zip(REGIONS, colors, strict=True)]
    leg1 = ax.legend(handles=patches, loc="lower right", fontsize=8, title="region")
    ax.add_artist(leg1)
    ax.legend(loc="upper left", fontsize=7)
    ax.set_xlabel("k1 = (I3 - I1) / I2")
    ax.set_ylabel("k3 = (I3 - I2) / I1")
    ax.set_title("Orbit-aligned attitude on a circular orbit\n(1 radial, 2 along-track, 3 orbit normal)")
    fig.tight_layout()
    fig.savefig(out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(*sys.argv[1:])
