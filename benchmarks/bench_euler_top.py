"""Error against cost for the exact free rigid body (thetasol.solve_rotation, a = 0).

Run:  python benchmarks/bench_euler_top.py [--quick]

Prints, for one generic body and one body 1e-10 from the separatrix:

1. dense output over [0, 1000]: wall time and max error in omega and Q of the closed form,
   of scipy DOP853 at several tolerances, of integrate_rotation(method="splitting") at
   several steps and of heyoka (if installed), all measured in the same run;
2. single far-time queries t = 1, 1e3, 1e6: cost of one call and error;
3. random access: cost per time point in batches;
4. the problem's own conditioning: how far the exact trajectory moves when omega0 is
   perturbed by 1e-15 (relative).

The reference is the same closed form evaluated with mpmath at 40 digits (dps=40), which
the test-suite checks against heyoka's quadruple-precision Taylor integrator; with heyoka
installed the script re-checks it here.
"""
from __future__ import annotations

import argparse
import time

import numpy as np
from _common import best_of, docs_page, docs_section, machine_info

from thetasol import inertia, integrate_rotation, solve_rotation

Z = np.zeros((3, 3))


def err(a, b):
    (w, Q), (wr, Qr) = a, b
    return max(np.max(np.abs(w - wr)), np.max(np.abs(Q - Qr)))


def problems():
    rng = np.random.default_rng(2024)
    Q0 = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    Q0 *= np.linalg.det(Q0)
    J = np.array([0.9, 1.4, 2.3])
    generic = (J, Q0, np.array([0.4, -0.9, 0.7]))
    # I = [6, 5, 3] for J = [1, 2, 4]; separatrix m_0^2 = 4 m_2^2
    Js = np.array([1.0, 2.0, 4.0])
    m = np.array([2.0 * (1 + 1e-10), 0.7, 1.0])
    near_sep = (Js, Q0, m / np.array([6.0, 5.0, 3.0]))
    return {"generic": generic, "near-separatrix 1e-10": near_sep}


def reference(data, t, dps=40):
    J, Q0, w0 = data
    w, Q = solve_rotation(inertia(J), Z, Q0, w0, dps=dps)(t)
    return w.astype(float), Q.astype(float)


def dense(name, data, quick):
    J, Q0, w0 = data
    n = 501 if quick else 2001
    t = np.linspace(0.0, 1000.0, n)
    t0 = time.perf_counter()
    ref = reference(data, t)
    tref = time.perf_counter() - t0
    print(f"\n## {name}: dense output, {n} points on [0, 1000]  (reference: closed form, mpmath "
          f"40 digits, {tref:.1f} s)")
    rows = []
    cost, out = best_of(lambda: solve_rotation(inertia(J), Z, Q0, w0)(t), repeat=5)
    rows.append(("thetasol closed form (float64)", cost, err(out, ref)))
    for rtol in ([1e-6, 1e-9] if quick else [1e-6, 1e-9, 1e-12, 1e-13]):
        cost, out = best_of(lambda: integrate_rotation(inertia(J), Z, Q0, w0, rtol=rtol, atol=1e-3 * rtol)(t),
                            repeat=1)
        rows.append((f"DOP853 rtol={rtol:g}", cost, err(out, ref)))
    for rtol in ([1e-6] if quick else [1e-6, 1e-9, 1e-12]):
        cost, out = best_of(lambda: integrate_rotation(inertia(J), Z, Q0, w0, rtol=rtol, method="splitting")(t),
                            repeat=1)
        rows.append((f"splitting (order 6), rtol={rtol:g}", cost, err(out, ref)))
    try:
        import heyoka  # noqa: F401

        for label, fp, tol in (("dbl", float, 1e-16), ("ldbl", np.longdouble, 1e-19)):
            # the first call compiles; report the second
            integrate_rotation(inertia(J), Z, Q0, w0, rtol=tol, method="heyoka", fp_type=fp)(t[:3])
            cost, out = best_of(lambda: integrate_rotation(inertia(J), Z, Q0, w0, rtol=tol, method="heyoka",
                                                            # noqa: B023
                                                           fp_type=fp)(t), repeat=1)  # noqa: B023
            rows.append((f"heyoka {label} tol={tol:g} (2nd call, compiled code cached)", cost, err(out, ref)))
    except ImportError:
        rows.append(("heyoka", np.nan, np.nan))
    print("| method | wall time [s] | max error (omega, Q) |\n|---|---|---|")
    for r in rows:
        print(f"| {r[0]} | {r[1]:.3g} | {r[2]:.2e} |")


def far(name, data, quick):
    J, Q0, w0 = data
    print(f"\n## {name}: one far-time query")
    print("| t | thetasol cost per call [us] | thetasol error | DOP853 1e-13 [s] | DOP853 error | "
          "heyoka dbl [s] | heyoka error |\n|---|---|---|---|---|---|---|")
    sol = solve_rotation(inertia(J), Z, Q0, w0)
    has_hy = True
    try:
        import heyoka  # noqa: F401
    except ImportError:
        has_hy = False
    dop_1e3 = None   # DOP853's time to t = 1000: the far row extrapolates it (the cost is linear in t)
    for T in (1.0, 1e3, 1e6):
        tt = np.array([T])
        ref = reference(data, tt)
        cost, out = best_of(lambda: sol(tt), repeat=5, number=200)
        e = err(out, ref)
        if T <= 1e3 and not (quick and T > 1):
            cd, od = best_of(lambda: integrate_rotation(inertia(J), Z, Q0, w0, rtol=1e-13, atol=1e-16)(tt), repeat=1)
            dcol = f"{cd:.3g} | {err(od, ref):.1e}"
            dop_1e3 = cd if T == 1e3 else dop_1e3
        else:
            dcol = f"{dop_1e3 * T / 1e3:.3g} (est. from t = 1000) | -" if dop_1e3 else "- | -"
        if has_hy and not (quick and T > 1e3):
            integrate_rotation(inertia(J), Z, Q0, w0, rtol=1e-16, method="heyoka")(np.array([1e-3]))
            ch, oh = best_of(lambda: integrate_rotation(inertia(J), Z, Q0, w0, rtol=1e-16, method="heyoka")(tt),
                             repeat=1)
            hcol = f"{ch:.3g} | {err(oh, ref):.1e}"
        else:
            hcol = "- | -"
        print(f"| {T:g} | {cost * 1e6:.0f} | {e:.1e} | {dcol} | {hcol} |")
    # setup cost
    cs, _ = best_of(lambda: solve_rotation(inertia(J), Z, Q0, w0), repeat=5, number=20)
    print(f"\nsetup (solve_rotation, validation and invariants included): {cs * 1e6:.0f} us")


def batches(name, data):
    J, Q0, w0 = data
    sol = solve_rotation(inertia(J), Z, Q0, w0)
    rng = np.random.default_rng(0)
    print(f"\n## {name}: random access (times uniform in [0, 1e6])")
    print("| batch size | omega and Q [us/point] | omega only [us/point] |\n|---|---|---|")
    for n in (10, 1000, 100000):
        t = rng.uniform(0, 1e6, n)
        reps = max(3, 200000 // n)
        c1, _ = best_of(lambda: sol(t), repeat=5, number=max(1, reps // 5))
        c2, _ = best_of(lambda: sol.omega(t), repeat=5, number=max(1, reps // 5))
        print(f"| {n} | {c1 / n * 1e6:.2f} | {c2 / n * 1e6:.2f} |")


def conditioning(name, data, quick):
    """Spread of the exact trajectory under 1e-15 relative perturbations of omega0."""
    J, Q0, w0 = data
    t = np.concatenate([np.linspace(0.0, 100.0, 26), np.linspace(100.0, 1000.0, 46)[1:], [4000.0]])
    groups = {"t <= 100": t <= 100, "100 < t <= 1000": (t > 100) & (t <= 1000), "t = 4000": t == 4000}
    ref = reference(data, t)
    rng = np.random.default_rng(5)
    spread = {k: 0.0 for k in groups}
    for _ in range(2 if quick else 4):
        d = rng.normal(size=3)
        w1 = w0 * (1 + 1e-15 * d / np.linalg.norm(d))
        r1 = reference((J, Q0, w1), t)
        for k, g in groups.items():
            spread[k] = max(spread[k], err((r1[0][g], r1[1][g]), (ref[0][g], ref[1][g])))
    out = solve_rotation(inertia(J), Z, Q0, w0)(t)
    cells = []
    for k, g in groups.items():
        cells.append(f"{spread[k]:.1e} | {err((out[0][g], out[1][g]), (ref[0][g], ref[1][g])):.1e}")
    print(f"| {name} | " + " | ".join(cells) + " |")


def heyoka_check(data):
    try:
        import heyoka as hy
    except ImportError:
        return
    J, Q0, w0 = data
    t = np.array([10.0, 100.0])
    r = reference(data, t)
    h = integrate_rotation(inertia(J), Z, Q0, w0, rtol=1e-32, method="heyoka", fp_type=hy.real128)(t)
    print(f"\nreference check: mpmath closed form vs heyoka float128 (tol 1e-32) at t = 10, 100: "
          f"{err(r, h):.1e} (float64 rounding of both)")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="fewer points and tolerances")
    args = ap.parse_args()
    print("# bench_euler_top\n")
    print(machine_info("heyoka"))
    probs = problems()
    heyoka_check(probs["generic"])
    for name, data in probs.items():
        dense(name, data, args.quick)
    for name, data in probs.items():
        far(name, data, args.quick)
    batches("generic", probs["generic"])
    print("\n## conditioning: exact trajectories for omega0 perturbed by 1e-15 (relative), "
          "against the float64 closed form's error")
    print("| problem | spread t<=100 | thetasol error t<=100 | spread 100<t<=1000 | thetasol error "
          "100<t<=1000 | spread t=4000 | thetasol error t=4000 |\n|---|---|---|---|---|---|---|")
    for name, data in probs.items():
        conditioning(name, data, args.quick)


if __name__ == "__main__":
    with docs_section(docs_page("docs/bench_euler_top.md"), "benchmarks/bench_euler_top.py"):
        main()
