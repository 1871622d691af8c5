"""Section 7 (the orbiting station): cost and error of the Kepler orbit, the numerical reference of the
rotation on an orbit and its closed forms.

    PYTHONPATH=. OPENBLAS_NUM_THREADS=1 python benchmarks/bench_orbiting_station.py [--station]

(``--station``: only the table of the example station's parts.)

Errors against heyoka in 80-bit (rotation) and quadruple (orbit) precision; times are CPU, best of 3.
"""
from __future__ import annotations

import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from _common import best_of, docs_page, docs_section, machine_info  # noqa: E402

from thetasol.core.inertia import inertia
from thetasol.core.so3 import rodrigues  # noqa: E402
from thetasol.integrators.multibody_gravity import integrate_multibody_gravity  # noqa: E402
from thetasol.integrators.orbiting_rotation import integrate_orbiting_rotation  # noqa: E402
from thetasol.mechanics.gravity_gradient import orbit_frame  # noqa: E402
from thetasol.scenes.format import load_scene  # noqa: E402
from thetasol.solutions.orbit.kepler import KeplerOrbit  # noqa: E402
from thetasol.solutions.orbit.orbiting_rotation import solve_orbiting_rotation  # noqa: E402

MU = 3.986004418e14
RP = 6378137.0 + 500e3
I_SAT = np.array([1200.0, 1500.0, 1800.0])
J_SAT = 0.5 * I_SAT.sum() - I_SAT
CPU = time.process_time


def orbit(e, mu=MU, rp=RP):
    v = math.sqrt(mu * (1 + e) / rp)
    return KeplerOrbit(mu, [rp, 0.0, 0.0], [0.0, v * math.cos(0.9), v * math.sin(0.9)])


def kepler_table():
    import heyoka as hy
    print("\n## Kepler orbit: 100 revolutions, 1e5 times (array) and one time (state_at)")
    print("| e | error vs quad heyoka (of size) | us per time (array) | us per state_at |")
    print("|---|---|---|---|")
    for e in (0.0, 0.7, 0.99):
        orb = orbit(e, mu=1.0, rp=1.0)
        T = orb.period
        ts = np.array([0.37, 50.0, 100.0]) * T
        x = hy.make_vars("x", "y", "z", "vx", "vy", "vz")
        r3 = (x[0] ** 2 + x[1] ** 2 + x[2] ** 2) ** 1.5
        sys_ = [(x[i], x[3 + i]) for i in range(3)] + [(x[3 + i], -x[i] / r3) for i in range(3)]
        q = hy.real128
        ta = hy.taylor_adaptive(sys_, np.array([q(float(c)) for c in list(orb.r0) + list(orb.v0)]), fp_type=q,
                                tol=q("1e-32"))
        R = np.asarray(ta.propagate_grid(np.array([q(0.0)] + [q(float(t)) for t in ts]))[-1], dtype=float)[1:, :3]
        err = np.abs(orb.position(ts) - R).max() / (orb.diagnostics["a"] * (1 + e))
        big = np.linspace(0, 100 * T, 100000)
        t_arr, _ = best_of(lambda b=big, o=orb: o(b), clock=CPU)
        t_one, _ = best_of(lambda o=orb: [o.state_at(0.123 * k) for k in range(1000)], clock=CPU)
        print(f"| {e} | {err:.1e} | {t_arr / big.size * 1e6:.2f} | {t_one / 1000 * 1e6:.1f} |")


def rotation_table():
    print("\n## Rotation on a LEO orbit, 20 orbits, SI units: DOP853 (rtol 1e-12) and closed forms vs 80-bit heyoka")
    print("| case | method | CPU s | error (|dQ|, |dw|/|w|max) |")
    print("|---|---|---|---|")
    for e, kind in ((0.0, "librating"), (0.0, "tumbling"), (0.05, "librating"), (0.3, "tumbling")):
        orb = orbit(e)
        n = orb.diagnostics["mean_motion"]
        F0 = orbit_frame(orb.r0, orb.v0)
        if kind == "librating":
            Q0 = F0 @ rodrigues([0.1, -0.05, 0.2])
            w0 = Q0.T @ F0[:, 2] * n * (1 + e) ** 2 / (1 - e * e) ** 1.5 + np.array([0.0, 0.0, 0.06 * n])
        else:
            Q0, w0 = F0 @ rodrigues([0.4, 1.1, -0.3]), np.array([3.0, -7.0, 5.0]) * n
        ts = np.linspace(0, 20 * orb.period, 6)[1:]
        args = (inertia(J_SAT), orb, Q0, w0)
        t_h, (wr, Qr) = best_of(lambda a=args: integrate_orbiting_rotation(*a, method="heyoka", fp_type=np.longdouble,
                                                                           rtol=1e-19)(ts), repeat=1, clock=CPU)
        t_d, (w, Q) = best_of(lambda a=args: integrate_orbiting_rotation(*a)(ts), repeat=1, clock=CPU)
        err = max(np.abs(Q - Qr).max(), np.abs(w - wr).max() / np.abs(wr).max())
        print(f"| e = {e}, {kind} | DOP853 | {t_d:.2f} | {err:.1e} |")
        print(f"| e = {e}, {kind} | heyoka 80-bit (reference) | {t_h:.2f} | - |")
    orb = orbit(0.0)
    n = orb.diagnostics["mean_motion"]
    F0 = orbit_frame(orb.r0, orb.v0)
    for th0, thd in ((0.3, 0.0), (0.0, 3.0)):
        Q0 = np.column_stack([math.cos(th0) * F0[:, 0] + math.sin(th0) * F0[:, 1],
                              -math.sin(th0) * F0[:, 0] + math.cos(th0) * F0[:, 1], F0[:, 2]])
        w0 = np.array([0.0, 0.0, n * (1 + thd)])
        sol = solve_orbiting_rotation(I_SAT, orb, Q0, w0)
        ts = np.linspace(0, 20 * orb.period, 6)[1:]
        wr, Qr = integrate_orbiting_rotation(inertia(J_SAT), orb, Q0, w0, method="heyoka", fp_type=np.longdouble,
                                             rtol=1e-19)(ts)
        w, Q = sol(ts)
        err = max(np.abs(Q - Qr).max(), np.abs(w - wr).max() / np.abs(wr).max())
        many = np.linspace(0, 1e6 * orb.period, 100000)
        t_set, _ = best_of(lambda a=(I_SAT, orb, Q0, w0): solve_orbiting_rotation(*a), clock=CPU)
        t_ev, _ = best_of(lambda s=sol, m=many: s(m), clock=CPU)
        print(f"| circular, {sol.method} | closed form: set-up {t_set * 1e3:.2f} ms, "
              f"{t_ev / many.size * 1e6:.1f} us per time (t up to 1e6 orbits) | - | {err:.1e} |")


def station_table(orbits: int = 2):
    """The cost of each part of the split of examples/orbiting_station.toml (Theorem 4) and of the unsplit check."""
    scene = load_scene(os.path.join(os.path.dirname(__file__), "..", "examples", "orbiting_station.toml"))
    print(f"\n## The example station (4 bodies, normalized units), {orbits} orbits, 201 output times")
    print("| part | model | CPU |")
    print("|---|---|---|")
    t = np.linspace(0.0, orbits * 2 * math.pi, 201)
    t_set, sol = best_of(lambda: scene.solution(), clock=CPU)
    print(f"| set-up of the split (orbit, 4 rotations, stability table) | - | {t_set * 1e3:.1f} ms |")
    t_orb, _ = best_of(lambda: sol.orbit(t), clock=CPU)
    print(f"| orbit | {sol.orbit.diagnostics['kind']} Kepler, closed form | {t_orb * 1e3:.2f} ms |")
    for n, rot in sol.rotations.items():
        t_rot, _ = best_of(lambda r=rot: r(t), clock=CPU)
        print(f"| rotation of {n} | {rot.method} | {t_rot * 1e3:.1f} ms |")
    t_all, _ = best_of(lambda: sol(t), clock=CPU)
    print(f"| the whole split, bodies placed | - | {t_all * 1e3:.1f} ms |")
    o = sol.orbit
    t_mb, mb = best_of(lambda: integrate_multibody_gravity(scene.config, o, scene.Q0, scene.omega0, t,
                                                           points=scene.orbit.points), repeat=1, clock=CPU)
    print(f"| unsplit station, exact 1/r field (rtol 1e-12) | maximal coordinates, {mb.info['nfev']} right-hand "
          f"sides | {t_mb:.2f} s |")


if __name__ == "__main__":
    page = docs_page("docs/orbiting_station.md")
    with docs_section(page, "benchmarks/bench_orbiting_station.py", section="station" * ("--station" in sys.argv)):
        print(machine_info("heyoka"))
        if "--station" not in sys.argv:
            kepler_table()
            rotation_table()
        station_table()
