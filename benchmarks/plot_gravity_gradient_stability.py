"""The gravity-gradient stability diagram in the (k1, k3) plane, with example bodies marked.

    PYTHONPATH=. python benchmarks/plot_gravity_gradient_stability.py [out.png]

Drawn by thetasol.plot.stability_diagram: every grid point is classified by
thetasol.gravity_gradient_stability (not by re-coding the inequalities), so the picture shows what the
library computes.  Axes as in the library: 1 radial, 2 along-track, 3 orbit normal;
k1 = (I3 - I1)/I2, k3 = (I3 - I2)/I1.
"""
from __future__ import annotations

import sys

import matplotlib

matplotlib.use("Agg")

from thetasol.plot import stability_diagram  # noqa: E402

BODIES = {
    "example satellite I = (1200, 1500, 1800)": (1200.0, 1500.0, 1800.0),
    "DeBra-Delp example I = (0.7, 1, 0.65)": (0.7, 1.0, 0.65),
    "JEOD cylinder I = (500, 12250, 12250)": (500.0, 12250.0, 12250.0),
}


def main(out: str = "docs/img/gravity_gradient_stability.png") -> None:
    ax = stability_diagram(BODIES, n=401)
    ax.figure.set_dpi(110)
    ax.figure.tight_layout()
    ax.figure.savefig(out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(*sys.argv[1:])
