"""Speed against accuracy of thetasol's curve engine, with Sage's RiemannSurface side by side.

Run:  python benchmarks/bench_curves.py [--quick] [--sage-python PATH]

For every curve: the time of thetasol (curve + period matrix; and the "full" pipeline: curve,
periods, tau, 12 Abel images, Riemann constant), its lattice distance to an independent 212-bit
reference (Sage at 212 bits, tests/data/curves, or thetasol's own 30-digit mpmath path where Sage has no
reference), the dps=30 path's time and accuracy, and Sage's RiemannSurface time and accuracy at 53
bits measured in the same run (a subprocess of a Python with Sage (passagemath) installed, given by
--sage-python PATH or the environment variable THETASOL_SAGE_PYTHON; without either the Sage columns
are skipped).  Times are the best of several runs (the machine is shared).
"""
from __future__ import annotations

import json
import os
import subprocess
import sys

import mpmath
import numpy as np
import sympy as sp

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, ROOT)

from _common import best_of, docs_page, docs_section, machine_info  # noqa: E402

from thetasol.core.so3 import hat  # noqa: E402
from thetasol.curves.plane_curve import PlaneCurve  # noqa: E402
from thetasol.curves.spectral import spectral_curve  # noqa: E402

DATA = os.path.join(ROOT, "tests", "data", "curves")
x, y = sp.symbols("x y")

SAGE_WORKER = r'''
import json, sys, time
from sage.all__sagemath_schemes import QQ, PolynomialRing
from sage.schemes.riemann_surfaces.riemann_surface import RiemannSurface
job = json.loads(sys.stdin.read())
R = PolynomialRing(QQ, "x,y")
out = []
for item in job:
    f = R(item["f"])
    best, P, basis = 1e99, None, None
    for _ in range(item["reps"]):
        t0 = time.time()
        try:
            S = RiemannSurface(f, prec=53)
            P = S.period_matrix()
            basis = [str(g) for g in S.cohomology_basis()]
        except Exception as exc:
            out.append({"error": str(exc)[:200]})
            break
        best = min(best, time.time() - t0)
    else:
        out.append({"time": best, "basis": basis,
                    "re": [[float(c.real()) for c in row] for row in P.rows()],
                    "im": [[float(c.imag()) for c in row] for row in P.rows()]})
print(json.dumps(out))
'''


def lattice_distance(P, Pref):
    """max |P - Pref T| / max |Pref| with T the nearest integer matrix (inf if T is not unimodular)."""
    def real(M):
        return np.vstack([M.real, M.imag])
    T = np.linalg.solve(real(Pref), real(P))
    Ti = np.rint(T)
    if abs(abs(np.linalg.det(Ti)) - 1) > 1e-6 or np.max(np.abs(T - Ti)) > 1e-3:
        return np.inf
    return float(np.max(np.abs(P - Pref @ Ti)) / np.max(np.abs(Pref)))


def float_spectral(seed=11):
    rng = np.random.default_rng(seed)
    J = np.sort(rng.uniform(0.5, 2.0, 3))
    m = rng.normal(size=3)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    a = rng.normal(size=(3, 3))
    return J, hat(m), -Q.T @ (a + a.T) @ Q


def near_rank_one(eps=1e-8, seed=3):
    rng = np.random.default_rng(seed)
    J = np.array([1.0, 1.7, 2.9])
    m = rng.normal(size=3)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    gam = np.array([0.3, -1.2, 0.8])
    a = 2.0 * np.outer(gam, gam) + eps * np.diag([1.0, 2.0, 3.0])
    return J, hat(m), -Q.T @ a @ Q


def load_ref(name):
    with open(os.path.join(DATA, name + ".json")) as fh:
        d = json.load(fh)
    loc = {"x": x, "y": y}
    f = sp.sympify(d["f"].replace("^", "**"), locals=loc)
    diffs = [sp.sympify(s.replace("^", "**"), locals=loc) for s in d["differentials"]]
    with mpmath.workdps(70):
        Pmp = mpmath.matrix([[mpmath.mpc(a, b) for a, b in zip(ra, ia)]
                             for ra, ia in zip(d["period_matrix_re"], d["period_matrix_im"])])
    P = np.array(Pmp.tolist(), dtype=complex)
    return f, diffs, P, Pmp


def lattice_distance_mp(Pm, Pref, Pref_mp):
    """lattice_distance computed in mpmath (for the dps path)."""
    Pf = np.array(Pm.tolist(), dtype=complex)
    def real(M):
        return np.vstack([M.real, M.imag])
    T = np.rint(np.linalg.solve(real(Pref), real(Pf))).astype(int)
    with mpmath.workdps(50):
        R = Pm - Pref_mp * mpmath.matrix(T.tolist())
        num = max(abs(R[i, j]) for i in range(R.rows) for j in range(R.cols))
        den = max(abs(Pref_mp[i, j]) for i in range(R.rows) for j in range(R.cols))
        return float(num / den)


def full_pipeline(C):
    C.riemann_matrix()
    rng = np.random.default_rng(0)
    pts = []
    for i in range(12):
        x0 = complex(rng.normal(), rng.normal())
        R, _ = C._poly.roots(np.array([x0]))
        pts.append((x0, R[0, i % C.n]))
    C.abel_map(pts)
    C.riemann_constant()


def main(quick=False, sage_python=None):
    reps = 2 if quick else 5
    cases = []
    for name, label in [("hyp_x5m1", "hyperelliptic g=2, y^2 = x^5 - 1"),
                        ("hyp_g3", "hyperelliptic g=3"),
                        ("hyp_g4_even", "hyperelliptic g=4 (degree 10)"),
                        ("fermat4", "Fermat quartic x^4 + y^4 = 1"),
                        ("klein", "Klein quartic"),
                        ("quartic", "generic smooth quartic"),
                        ("trigonal", "trigonal y^3 + x^4 + x + 1"),
                        ("spectral_g4", "spectral (4.12), rational data, g=4"),
                        ("spectral_nodal_g3", "spectral, rank-one a (nodal), g=3"),
                        ("spectral_symmetric", "spectral, symmetric body, g=3")]:
        f, diffs, Pref, Pref_mp = load_ref(name)
        cases.append(dict(label=label, make=lambda f=f: PlaneCurve(f, x, y), diffs=diffs, Pref=Pref,
                          Pref_mp=Pref_mp, sage_f=str(sp.expand(f)).replace("**", "^")))
    J, M, u = float_spectral()
    cases.append(dict(label="spectral (4.12), random float data, g=4",
                      make=lambda J=J, M=M, u=u: spectral_curve(J, M, u), diffs=None, Pref=None, sage_f=None))
    J, M, u = float_spectral(seed=12)
    cases.append(dict(label="spectral (4.12), random float data (2), g=4",
                      make=lambda J=J, M=M, u=u: spectral_curve(J, M, u), diffs=None, Pref=None, sage_f=None))
    J, M, u = float_spectral(seed=12)
    J = np.array([J[0], J[1], J[1] * 1.004])
    cases.append(dict(label="spectral, nearly symmetric body (J3/J2 = 1.004), g=4",
                      make=lambda J=J, M=M, u=u: spectral_curve(J, M, u), diffs=None, Pref=None, sage_f=None))
    J, M, u = near_rank_one()
    cases.append(dict(label="spectral, near rank-one a (eps 1e-8), g=4", make=lambda J=J, M=M, u=u: spectral_curve(J, M, u, tol=1e-12),
                      diffs=None, Pref=None, sage_f=None))
    # exact polynomials of the float-data curves, for Sage
    for c in cases:
        if c["sage_f"] is None:
            C = c["make"]()
            c["sage_f"] = str(sp.expand(C._poly.sympy_expr().subs({C.x: x, C.y: y}))).replace("**", "^")
            c["diffs"] = C.holomorphic_differentials()
            c["sage_names"] = {C.x: x, C.y: y}
    rows = []
    for c in cases:
        # thetasol
        t_pm, C = best_of(lambda: (lambda C: (C.period_matrix(c["diffs"]), C)[1])(c["make"]()), reps)
        P = C.period_matrix(c["diffs"])
        t_full, _ = best_of(lambda: full_pipeline(c["make"]()), max(2, reps // 2))
        C._cache.pop(("pm_mp", tuple(map(str, c["diffs"] or C.holomorphic_differentials())), 30), None)
        t_mp, Pm_mp = best_of(lambda: C.period_matrix(c["diffs"], dps=30), 1)
        Pm = np.array(Pm_mp.tolist(), dtype=complex)
        if c["Pref"] is None:
            ref, ref_name = Pm, "thetasol dps=30"
        else:
            ref, ref_name = c["Pref"], "Sage 212 bits"
        err = lattice_distance(P, ref)
        err_mp = lattice_distance_mp(Pm_mp, c["Pref"], c["Pref_mp"]) if c["Pref"] is not None else np.nan
        rows.append(dict(label=c["label"], g=C.genus, t_pm=t_pm, t_full=t_full, err=err, ref=ref_name,
                         t_mp=t_mp, err_mp=err_mp, ref_P=ref, sage_f=c["sage_f"],
                         diffs=[str(sp.sympify(g).subs(c.get("sage_names", {}))).replace("**", "^")
                                for g in (c["diffs"] or C.holomorphic_differentials())]))
        print(f"  done {c['label']}", file=sys.stderr, flush=True)
    # Sage, same run
    have_sage = sage_python is not None
    if have_sage:
        job = [{"f": r["sage_f"], "reps": 1 if quick else 2} for r in rows]
        try:
            res = subprocess.run([sage_python, "-c", SAGE_WORKER], input=json.dumps(job), capture_output=True,
                                 text=True, timeout=3600)
            sage = json.loads(res.stdout.strip().splitlines()[-1])
        except Exception as exc:  # pragma: no cover - environment dependent
            print(f"Sage run failed: {exc}", file=sys.stderr)
            have_sage = False
    print("# Curve benchmark\n")
    print(machine_info("sympy", "mpmath") + "\n")
    hdr = "| curve | g | thetasol periods [s] | full pipeline [s] | error (lattice) | reference | dps=30 [s] | dps=30 error |"
    if have_sage:
        hdr += " Sage 53 bits [s] | Sage error | Sage / thetasol |"
    print(hdr)
    print("|" + "---|" * (hdr.count("|") - 1))
    for i, r in enumerate(rows):
        line = (f"| {r['label']} | {r['g']} | {r['t_pm']:.3f} | {r['t_full']:.3f} | {r['err']:.1e} | {r['ref']} | "
                f"{r['t_mp']:.2f} | {r['err_mp']:.1e} |")
        if have_sage:
            s = sage[i]
            if "error" in s:
                line += f" fails: {s['error'][:60]} | - | - |"
            else:
                Ps = np.array(s["re"]) + 1j * np.array(s["im"])
                same_basis = s["basis"] == r["diffs"]
                es = lattice_distance(Ps, r["ref_P"]) if same_basis else np.nan
                line += f" {s['time']:.2f} | {es:.1e} | {s['time'] / r['t_pm']:.0f}x |"
        print(line)
    print("\nfull pipeline = curve + periods + tau + 12 Abel images + Riemann constant.")


def _sage_python(argv):
    """The Sage Python from --sage-python PATH or THETASOL_SAGE_PYTHON; None if neither is given."""
    path = os.environ.get("THETASOL_SAGE_PYTHON")
    if "--sage-python" in argv:
        i = argv.index("--sage-python")
        if i + 1 >= len(argv):
            sys.exit("--sage-python needs the path of a Python with Sage (passagemath) installed")
        path = argv[i + 1]
    if path is not None and not os.path.exists(path):
        sys.exit(f"no Sage Python at {path!r} (--sage-python / THETASOL_SAGE_PYTHON): give the path of a "
                 "Python with Sage (passagemath) installed, or neither to skip the Sage columns")
    return path


if __name__ == "__main__":
    with docs_section(docs_page("docs/bench_curves.md"), "benchmarks/bench_curves.py"):
        main(quick="--quick" in sys.argv, sage_python=_sage_python(sys.argv[1:]))
