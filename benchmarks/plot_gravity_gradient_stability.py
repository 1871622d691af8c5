"""The gravity-gradient stability diagram of the orbit-aligned attitude (docs/img/gravity_gradient_stability.png).

    PYTHONPATH=. python benchmarks/plot_gravity_gradient_stability.py [out.png]

Drawn by thetasol.plot.stability_diagram: every grid point is classified by
thetasol.gravity_gradient_stability (not by re-coding the inequalities), so the picture shows what the
library computes.  Axes as in the library: 1 radial, 2 along-track, 3 orbit normal;
k1 = (I3 - I1)/I2, k3 = (I3 - I2)/I1.  Marked: three example bodies, the effective bodies of
examples/orbiting_station.toml at their nearest orbit-aligned attitudes (a body at k1 = k3 = 1, a
near-rod, is drawn just inside the frame) and the gravity-gradient unstable target that
examples/station_lqr.py stabilizes.
"""
from __future__ import annotations

import sys

import matplotlib

matplotlib.use("Agg")

from thetasol.core.inertia import inertia  # noqa: E402
from thetasol.mechanics.gravity_gradient import gravity_gradient_stability  # noqa: E402
from thetasol.plot import stability_diagram  # noqa: E402
from thetasol.scenes.format import load_scene  # noqa: E402

STATION = "examples/orbiting_station.toml"
BODIES = {
    "example satellite I = (1200, 1500, 1800)": (1200.0, 1500.0, 1800.0),
    "DeBra-Delp example I = (0.7, 1, 0.65)": (0.7, 1.0, 0.65),
    "JEOD cylinder I = (500, 12250, 12250)": (500.0, 12250.0, 12250.0),
}


def station_points() -> dict:
    """(k1, k3) of the example station's effective bodies at their nearest orbit-aligned attitudes (the
    report's stability table), and the panel's target of examples/station_lqr.py (least inertia along-track)."""
    scene = load_scene(STATION)
    sol = scene.solution()
    pts = {f"station: {n} ({b.stability.region})": (b.stability.k1, b.stability.k3) for n, b in sol.stability.items()}
    Jp = scene.config.effective_body("panel").principal_moments           # ascending J = descending I
    st = gravity_gradient_stability(inertia(Jp[[1, 2, 0]]), 1.0)
    pts[f"station_lqr.py: panel target ({st.region}, LQR-stabilized)"] = (st.k1, st.k3)
    return pts


def main(out: str = "docs/img/gravity_gradient_stability.png") -> None:
    ax = stability_diagram(BODIES, n=401)
    for (label, (k1, k3)), mk in zip(station_points().items(), "DPXvp", strict=False):
        ax.plot(min(k1, 0.985), min(k3, 0.985), mk, color="C3", mec="k", ms=7,
                label=f"{label}: k1 = {k1:.3f}, k3 = {k3:.3f}")
    ax.legend(loc="upper left", fontsize=6)
    ax.figure.set_dpi(110)
    ax.figure.tight_layout()
    ax.figure.savefig(out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(*sys.argv[1:])
