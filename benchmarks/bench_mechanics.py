"""Speed against error for the mechanics: mass centre, split and unsplit (results in docs/bench_mechanics.md).

1. The mass centre (3.2) on 1000 times in [0, 100]: closed form (thetasol.solutions.points.mass_center) against
   scipy DOP853 at several tolerances and scipy.linalg.expm per time; errors against mpmath's
   matrix exponential at 40 digits.
2. The split against the unsplit multibody system (thetasol.integrators.multibody) for a 5-body
   C^2-central tree over t <= 60: multibody cost and gap at several tolerances, the split's
   cost with numerical rotations (DOP853 and heyoka if installed).
3. The CLI demo, wall time.

Run: python benchmarks/bench_mechanics.py   (best of `REPEAT` runs; the machine is shared)
"""
from __future__ import annotations

import subprocess
import sys

import mpmath
import numpy as np
from _common import best_of, docs_page, docs_section, machine_info
from scipy.integrate import solve_ivp
from scipy.linalg import expm

from thetasol.core.so3 import rodrigues
from thetasol.integrators.multibody import integrate_multibody
from thetasol.mechanics.bodies import Body
from thetasol.mechanics.configuration import Configuration, Joint
from thetasol.scenes.pipeline import solve_configuration
from thetasol.solutions.points.mass_center import solve_mass_center

REPEAT = 3


def mass_centre_table():
    print("## 1. mass centre on 1000 times in [0, 100]")
    cases = {"trigonometric": [1.0, 0.5, 0.2], "mixed (+, 0, -)": [1.0, 0.0, -0.05]}
    rng = np.random.default_rng(0)
    for label, lam in cases.items():
        R = rodrigues(np.array([0.3, -0.7, 0.4]))
        a = R @ np.diag(lam) @ R.T
        b, q0, v0 = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
        t = np.linspace(0, 100, 1000)
        A = np.zeros((7, 7))
        A[:3, 3:6] = np.eye(3)
        A[3:6, :3] = -a
        A[3:6, 6] = -b / 2
        y0 = np.r_[q0, v0, 1.0]
        with mpmath.workdps(40):
            Am = mpmath.matrix(A.tolist())
            tsub = t[::50]
            ref = np.array([[float(x) for x in (mpmath.expm(Am * mpmath.mpf(float(tk))) * mpmath.matrix(y0.tolist()))[:3]]
                            for tk in tsub])
        scale = np.max(np.abs(ref))
        rows = []
        sec, (q, _) = best_of(lambda: solve_mass_center(a, b, q0, v0)(t), REPEAT)
        rows.append(("closed form (thetasol)", sec, np.max(np.abs(q[::50] - ref)) / scale))
        for rtol in (1e-8, 1e-11, 1e-13):
            def run(rtol=rtol):
                return solve_ivp(lambda _t, y: np.r_[y[3:], -(a @ y[:3] + b / 2)], (0, 100), y0[:6],
                                 t_eval=t, method="DOP853", rtol=rtol, atol=rtol * 1e-3).y[:3].T
            sec, qd = best_of(run, REPEAT)
            rows.append((f"DOP853 rtol={rtol:g}", sec, np.max(np.abs(qd[::50] - ref)) / scale))
        sec, qe = best_of(lambda: np.array([(expm(A * tk) @ y0)[:3] for tk in t]), REPEAT)
        rows.append(("scipy.linalg.expm per time", sec, np.max(np.abs(qe[::50] - ref)) / scale))
        print(f"\n### {label}: eigenvalues {lam}\n")
        print(r"| method | time (ms) | max error / max \|q\| |")
        print("|---|---|---|")
        for name, sec, err in rows:
            print(f"| {name} | {sec * 1e3:.2f} | {err:.1e} |")


def make_system(seed=11):
    rng = np.random.default_rng(seed)
    names = "ABCDE"
    bodies = [Body.from_point_masses(rng.uniform(0.5, 2, 5), rng.normal(size=(5, 3)), name=n) for n in names]
    edges = [("A", "B"), ("B", "C"), ("A", "D"), ("D", "E")]
    cfg = Configuration(bodies, [Joint(p, c, rng.normal(size=3), np.zeros(3)) for p, c in edges]).make_central()
    R = rodrigues(rng.normal(size=3))
    a = R @ np.diag([2.0, 1.0, 0.4]) @ R.T
    b = rng.normal(size=3) * 0.2
    state = dict(q0=rng.normal(size=3), v0=rng.normal(size=3), Q0={n: rodrigues(rng.normal(size=3)) for n in names},
                 omega0={n: rng.normal(size=3) for n in names})
    return cfg, a, b, state


def split_table():
    print("\n## 2. split vs unsplit, 5-body C^2-central tree (tests/test_multibody.py data), t in [0, 60], 241 outputs\n")
    cfg, a, b, s = make_system()
    t = np.linspace(0, 60, 241)
    try:
        import heyoka  # noqa: F401
        ref = solve_configuration(cfg, a, b, rotation="numerical", method="heyoka", rtol=1e-16, **s).trajectories(t)
        ref_name = "split with heyoka rotations (tol 1e-16)"
    except ImportError:
        ref = solve_configuration(cfg, a, b, rotation="numerical", rtol=1e-14, **s).trajectories(t)
        ref_name = "split with DOP853 rotations (rtol 1e-14)"
    print(f"reference: {ref_name}\n")
    print("| solution | time (s) | RHS evals | max position / attitude deviation from the reference |")
    print("|---|---|---|---|")
    for rtol in (1e-10, 1e-12, 1e-13):
        sec, sp = best_of(lambda rtol=rtol: solve_configuration(cfg, a, b, rotation="numerical", rtol=rtol, **s).trajectories(t), 1)
        d = sp.deviation(ref)
        print(f"| split, DOP853 rotations rtol={rtol:g} | {sec:.2f} | - | {d['position']:.1e} / {d['attitude']:.1e} |")
    for rtol in (1e-10, 1e-11, 1e-12, 1e-13):
        sec, mb = best_of(lambda rtol=rtol: integrate_multibody(cfg, a, b, t=t, rtol=rtol, **s), 1)
        d = mb.deviation(ref)
        print(f"| unsplit multibody, DOP853 rtol={rtol:g} | {sec:.2f} | {mb.info['nfev']} | "
              f"{d['position']:.1e} / {d['attitude']:.1e} |")


def demo_table():
    print("\n## 3. `python -m thetasol demo` (6 bodies, t <= 30, 601 outputs, with the multibody check)\n")
    sec, _ = best_of(lambda: subprocess.run([sys.executable, "-m", "thetasol", "demo"], check=True,
                                            capture_output=True), 2)
    print(f"wall time {sec:.1f} s (best of 2)")


if __name__ == "__main__":
    with docs_section(docs_page("docs/bench_mechanics.md"), "benchmarks/bench_mechanics.py"):
        print(f"machine: {machine_info('mpmath')}\n")
        mass_centre_table()
        split_table()
        demo_table()
