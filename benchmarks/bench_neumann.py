"""Neumann's problem: the rotation branch of solve_rotation and the point model solve_neumann.

``rotation``: error against heyoka (80-bit, rtol 1e-19) at the rotation tests' times, set-up time and
evaluation cost per time (a batch of 1000 times spread over [0, 1e4]; best of 5, wall clock and process
CPU time, which is less disturbed by other jobs on a shared machine).

``point``: solve_neumann on tests/test_neumann_point.py's cases: set-up (best of 5, wall clock and process
CPU time), cost per time in
batches of 1000 times over [0, 1000] and of 1 time, the largest relative error (q / R, v / (|v0| +
R sqrt(a3 - a1))) at t in {0.7, 3.1, 17.3, 102, 1000} against heyoka 80-bit of the constrained
equations; next to it heyoka in double precision (tol 1e-16) and scipy's DOP853 (rtol 1e-13) producing
the same batch of 1000 times, with their errors at the same times.

``refusals``: the time solve_neumann takes to raise ClosedFormUnavailable on the data of
tests/test_neumann_point.py::test_refusals_name_the_reference (best of 5).

Run: OPENBLAS_NUM_THREADS=1 PYTHONPATH=. python benchmarks/bench_neumann.py [rotation|point|refusals]  (needs
heyoka for the error columns)."""
import os
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))
sys.path.insert(0, os.path.dirname(__file__))
from _common import best_of, docs_page, docs_section, machine_info  # noqa: E402
from test_neumann import CASES, T_FAR  # noqa: E402
from test_neumann_point import CASES as POINT_CASES, _data, _errors, _scales  # noqa: E402

from thetasol import inertia, integrate_rotation, solve_rotation  # noqa: E402
from thetasol.solutions.points.neumann import solve_neumann  # noqa: E402

T_POINT = np.array([0.7, 3.1, 17.3, 102.0, 1000.0])


def _have_heyoka():
    try:
        import heyoka  # noqa: F401
        return True
    except ImportError:
        return False


def rotation():
    have = _have_heyoka()
    tt = np.sort(np.random.default_rng(0).uniform(0.0, 1e4, 1000))
    print("| case | method | set-up (s) | us/time | us/time (CPU) | "
          + " | ".join(f"t={t:g}" for t in T_FAR) + " |")
    print("|---|---|---|---|---|" + "---|" * len(T_FAR))
    for label, J, a, Q0, w0, _ in CASES:
        setup, sol = best_of(lambda: solve_rotation(inertia(J), a, Q0, w0))
        ev = best_of(lambda: sol(tt), repeat=5)[0] / tt.size * 1e6
        cpu = best_of(lambda: sol(tt), repeat=5, clock=time.process_time)[0] / tt.size * 1e6
        errs = ["-"] * len(T_FAR)
        if have:
            w, Q = sol(T_FAR)
            wr, Qr = integrate_rotation(inertia(J), a, Q0, w0, method="heyoka", fp_type=np.longdouble,
                                        rtol=1e-19)(T_FAR)
            e = np.maximum(np.abs(w - wr).max(-1), np.abs(Q - Qr).max((-1, -2)))
            errs = [f"{x:.1e}" for x in e]
        print(f"| {label} | {sol.method} | {setup:.3f} | {ev:.1f} | {cpu:.1f} | " + " | ".join(errs) + " |")


def _rhs(a):
    def f(t, y):
        q, v = y[:3], y[3:]
        lam = (q @ a @ q - v @ v) / (q @ q)
        return np.r_[v, -a @ q + lam * q]
    return f


def _heyoka_point(a, q0, v0, t, dtype, tol):
    """(seconds to build the integrator, seconds to propagate over the sorted times t, states)."""
    import heyoka as hy
    t0 = time.perf_counter()
    q, v = hy.make_vars("q0", "q1", "q2"), hy.make_vars("v0", "v1", "v2")
    aq = [sum(float(a[i, j]) * q[j] for j in range(3)) for i in range(3)]
    lam = (sum(q[i] * aq[i] for i in range(3)) - sum(v[i] * v[i] for i in range(3))) \
        / sum(q[i] * q[i] for i in range(3))
    sys_ = [(q[i], v[i]) for i in range(3)] + [(v[i], -aq[i] + lam * q[i]) for i in range(3)]
    y0 = np.array([dtype(float(x)) for x in list(q0) + list(v0)])
    ta = hy.taylor_adaptive(sys_, y0, tol=dtype(tol), fp_type=dtype)
    t1 = time.perf_counter()
    res = ta.propagate_grid(np.array([dtype(float(x)) for x in t]))
    t2 = time.perf_counter()
    return t1 - t0, t2 - t1, np.asarray(res[-1], float)


def point():
    have = _have_heyoka()
    tt = np.sort(np.random.default_rng(0).uniform(0.0, 1e3, 1000))
    grid = np.unique(np.r_[0.0, T_POINT, tt])           # the integrators produce all of them in one run
    at = np.searchsorted(grid, T_POINT)
    print("| case | method | set-up (ms) | set-up (ms CPU) | us/time (batch) | us/time (CPU) | us (1 time) "
          "| max error t<=1000 | heyoka-dbl build (ms) / us/time / error | DOP853 us/time / error |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for label, a, q0, speed, _ in POINT_CASES:
        q0, v0 = _data(a, q0, speed, label)
        ts = 1e-3 if label == "units" else 1.0
        setup, sol = best_of(lambda: solve_neumann(a, q0, v0), repeat=5)
        setup_cpu = best_of(lambda: solve_neumann(a, q0, v0), repeat=5, clock=time.process_time)[0]
        ev = best_of(lambda: sol(ts * tt), repeat=5)[0] / tt.size * 1e6
        cpu = best_of(lambda: sol(ts * tt), repeat=5, clock=time.process_time)[0] / tt.size * 1e6
        one = best_of(lambda: sol(ts * 3.0), repeat=20)[0] * 1e6
        R, vs = _scales(a, q0, v0)
        err, hy_col, dop_col = "-", "-", "-"
        if have:
            _, _, ref = _heyoka_point(a, q0, v0, ts * np.r_[0.0, T_POINT], np.longdouble, 1e-19)
            q, v = sol(ts * T_POINT)
            err = f"{_errors(q, v, ref[1:, :3], ref[1:, 3:], R, vs).max():.1e}"
            build, run, st = _heyoka_point(a, q0, v0, ts * grid, float, 1e-16)
            e_hy = _errors(st[at, :3], st[at, 3:], ref[1:, :3], ref[1:, 3:], R, vs).max()
            hy_col = f"{build * 1e3:.0f} / {run / grid.size * 1e6:.1f} / {e_hy:.1e}"
            t0 = time.perf_counter()
            r = solve_ivp(_rhs(a), (0.0, ts * grid[-1]), np.r_[q0, v0], method="DOP853", t_eval=ts * grid,
                          rtol=1e-13, atol=1e-13 * max(R, vs))
            run = time.perf_counter() - t0
            st = r.y.T
            e_dop = _errors(st[at, :3], st[at, 3:], ref[1:, :3], ref[1:, 3:], R, vs).max()
            dop_col = f"{run / grid.size * 1e6:.0f} / {e_dop:.1e}"
        print(f"| {label} | {sol.method} | {setup * 1e3:.1f} | {setup_cpu * 1e3:.1f} | {ev:.1f} | {cpu:.1f} | {one:.0f} | {err} | "
              f"{hy_col} | {dop_col} |")


def refusals():
    from test_neumann_point import refused_cases

    from thetasol.protocol import ClosedFormUnavailable

    def attempt(a, q0, v0):
        try:
            solve_neumann(a, q0, v0)
        except ClosedFormUnavailable as err:
            return str(err)
        return "solved"

    print("| case | time to refuse (ms) | message |")
    print("|---|---|---|")
    for label, a, q0, v0, _ in refused_cases():
        dt, msg = best_of(lambda: attempt(a, q0, v0), repeat=5)
        print(f"| {label} | {dt * 1e3:.1f} | {msg[:90]}... |")


if __name__ == "__main__":
    with docs_section(docs_page("docs/neumann.md"), "benchmarks/bench_neumann.py", section=" ".join(sys.argv[1:])):
        which = sys.argv[1:] or ["rotation", "point", "refusals"]
        print("# " + machine_info("heyoka"))
        for name in which:
            print(f"\n## {name}\n")
            {"rotation": rotation, "point": point, "refusals": refusals}[name]()
