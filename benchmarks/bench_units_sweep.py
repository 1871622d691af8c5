"""solve_rotation on random bodies of every regime in random units, against heyoka in 80 bits.

    python benchmarks/bench_units_sweep.py [N_PER_REGIME] [SEED]

Each body is drawn in units where max J and max(|omega0|, sqrt|a - c 1|) are of order one, then put in
random units: J x 10^U(-8, 8), time x 10^U(-6, 6) (omega0 / s, a / s^2) and, for half of the bodies,
an isotropic part c 1 with |c| up to 1e6 |a - c 1|.  The reference is heyoka's Taylor integrator in
80-bit precision (tolerance 1e-19) run in decimal units formed in 80 bits, at the natural times
0.7, 17.3, 102, 997, 4002 (in units of 1 / max(|omega0|, sqrt|a|)).  A solution counts as correct
when its largest error (|omega - omega_ref| / max|omega_ref| and |Q - Q_ref|) is at most
max(1e-9, 100 x the data's conditioning), the conditioning being the reference's own spread under a
change of a and omega0 of the rounding size eps (3 + |c| / |a - c 1|).

Outcomes per regime: correct (no warning), warned (a RuntimeWarning, right or wrong), refused
(ClosedFormUnavailable), silent-wrong (above the bound without a warning), crash (any other error);
the largest refusal time, the median set-up time and the cost per evaluated time (1000 times).
Output: a markdown table (docs/units.md has the recorded one).
"""
from __future__ import annotations

import os
import sys
import time
import warnings

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from _common import docs_page, docs_section, machine_info  # noqa: E402

from thetasol import ClosedFormUnavailable, inertia, solve_rotation  # noqa: E402
from thetasol.core.so3 import rodrigues  # noqa: E402
from thetasol.integrators.rotation import rotation_expressions  # noqa: E402

LD = np.longdouble
EPS = np.finfo(float).eps
T_NAT = np.array([0.7, 17.3, 102.0, 997.0, 4002.0])
_TA = {}


# -- the reference (the equations of tests/test_units.py, through integrators.rotation.rotation_expressions) -

def _integrator():
    import heyoka as hy

    if "ta" not in _TA:
        xs = hy.make_vars(*[f"m{i}" for i in range(3)], *[f"q{i}{j}" for i in range(3) for j in range(3)])
        m, Q = xs[:3], [xs[3 + 3 * i: 6 + 3 * i] for i in range(3)]
        p = [hy.par[k] for k in range(27)]
        Iinv, J, A = ([p[o + 3 * i: o + 3 * i + 3] for i in range(3)] for o in (0, 9, 18))
        odes = list(zip(xs, rotation_expressions(m, Q, Iinv, J, A), strict=True))
        _TA["ta"] = hy.taylor_adaptive(odes, np.zeros(12, dtype=LD), tol=LD(1e-19), fp_type=LD,
                                       pars=np.zeros(27, dtype=LD))
    return _TA["ta"]


def _inv3(M):
    C = np.empty((3, 3), dtype=LD)
    for i in range(3):
        for j in range(3):
            r, c = [k for k in range(3) if k != i], [k for k in range(3) if k != j]
            C[j, i] = (-1) ** (i + j) * (M[r[0], c[0]] * M[r[1], c[1]] - M[r[0], c[1]] * M[r[1], c[0]])
    return C / (M[0] @ C[:, 0])


def heyoka_rotation(J, a, Q0, omega0, t):
    ta = _integrator()
    J, a = np.asarray(J, float), np.asarray(a, float)
    adev = a.astype(LD) - LD(a[0, 0]) * np.eye(3, dtype=LD)
    ev = np.linalg.eigvalsh(a - a[0, 0] * np.eye(3))
    wl = np.asarray(omega0, float).astype(LD)
    r = max(np.sqrt(np.sum(wl * wl)), np.sqrt(LD(np.abs(ev - ev.mean()).max())))
    r = LD(1) if r == 0 else r
    Jn = J.astype(LD) / LD(np.abs(J).max())
    In = (Jn[0, 0] + Jn[1, 1] + Jn[2, 2]) * np.eye(3, dtype=LD) - Jn
    Iinv = _inv3(In)
    ta.pars[:] = np.concatenate([Iinv.ravel(), Jn.ravel(), (adev / (r * r)).ravel()])
    ta.time = LD(0)
    ta.state[:] = np.concatenate([In @ (wl / r), np.asarray(Q0, float).astype(LD).ravel()])
    st = ta.propagate_grid(np.concatenate([[LD(0)], np.asarray(t, float).astype(LD) * r]))[-1][1:]
    w = np.einsum("ij,nj->ni", Iinv, st[:, :3]) * r
    return w.astype(float), st[:, 3:].reshape(-1, 3, 3).astype(float)


# -- bodies of every regime, in units of order one --------------------------------------------------

def _sym(rng):
    S = rng.normal(size=(3, 3))
    return 0.5 * (S + S.T)


def _unit(v):
    return v / np.linalg.norm(v)


def _body(regime, rng):
    """(J diagonal 3x3, a, Q0, omega0) of the regime, of order one."""
    J = np.sort(rng.uniform(0.3, 1.0, 3)) * [1.0, 1.3, 1.6]
    Q0, w0, a = rodrigues(rng.normal(size=3)), rng.normal(size=3), _sym(rng)
    if regime == "nearly symmetric":
        J[1] = J[0] * (1 + 10 ** rng.uniform(-6, -2))
    elif regime == "symmetric":
        J = np.array([0.7, 0.7, 1.3])[rng.permutation(3)]
        w0[np.argmax(J)] += 0.5
    elif regime == "rank-one":
        a = -rng.uniform(0.5, 2.0) * np.outer(*(2 * [_unit(rng.normal(size=3))]))
    elif regime == "rank-two":
        lam, V = np.linalg.eigh(a)
        a = V @ np.diag([lam[0], lam[1], 0.0]) @ V.T
    elif regime == "nearly isotropic":
        a = np.eye(3) + 10 ** rng.uniform(-10, -4) * a
    elif regime == "tiny a":
        a *= 10 ** rng.uniform(-16, -9)
    elif regime == "huge a":
        a *= 10 ** rng.uniform(3, 8)
    elif regime == "fast spin":
        w0 = 10 ** rng.uniform(2, 4) * _unit(w0)
    elif regime == "zero spin":
        w0 = np.zeros(3)
    elif regime == "near relative equilibrium":
        lam, V = np.linalg.eigh(a)
        V = V[:, rng.permutation(3)]
        Q0 = (V * np.linalg.det(V)) @ rodrigues(10 ** rng.uniform(-4, -2) * rng.normal(size=3))
        w0 = 10 ** rng.uniform(-4, -2) * rng.normal(size=3)
    return np.diag(J), a, Q0, w0


REGIMES = ["generic", "nearly symmetric", "symmetric", "rank-one", "rank-two", "nearly isotropic", "tiny a",
           "huge a", "fast spin", "zero spin", "near relative equilibrium"]


def _random_units(J, a, w0, rng, with_c):
    sJ, s = 10 ** rng.uniform(-8, 8), 10 ** rng.uniform(-6, 6)
    dev = np.abs(np.linalg.eigvalsh(a - np.trace(a) / 3 * np.eye(3))).max()
    c = rng.choice([-1, 1]) * 10 ** rng.uniform(-3, 6) * dev if with_c else 0.0
    return J * sJ, (a + c * np.eye(3)) / s**2, w0 / s, s, c * 1.0


def _error(w, Q, wr, Qr):
    return max(np.abs(w - wr).max() / max(np.abs(wr).max(), 1e-300), np.abs(Q - Qr).max())


def run_case(regime, rng):
    J, a, Q0, w0 = _body(regime, rng)
    Ju, au, wu, s, c = _random_units(J, a, w0, rng, with_c=rng.random() < 0.5)
    dev = np.linalg.eigvalsh(au - np.trace(au) / 3 * np.eye(3))
    rate = max(np.linalg.norm(wu), np.sqrt(np.abs(dev).max()))
    t = T_NAT / (rate if rate > 0 else 1.0)
    rec = {"regime": regime}
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            sol = solve_rotation(inertia(Ju), au, Q0, wu)
        except ClosedFormUnavailable:
            rec.update(outcome="refused", setup=time.perf_counter() - t0)
            return rec
        except Exception as exc:  # noqa: BLE001 - a crash is an outcome to count
            rec.update(outcome="crash", setup=time.perf_counter() - t0, error=repr(exc)[:200])
            return rec
        rec["setup"] = time.perf_counter() - t0
        w, Q = sol(t)
        tt = np.linspace(0.0, t[-1], 1000)
        t1 = time.perf_counter()
        sol(tt)
        rec["per_point"] = (time.perf_counter() - t1) / tt.size
    warned = any(issubclass(x.category, RuntimeWarning) for x in caught)
    wr, Qr = heyoka_rotation(Ju, au, Q0, wu, t)
    delta = EPS * (3 + abs(c) / max(np.abs(dev).max(), 1e-300))
    S = _sym(rng)
    ap = au + delta * np.abs(dev).max() * S / np.abs(S).max()
    wp, Qp = heyoka_rotation(Ju, ap, Q0, wu * (1 + delta * rng.choice([-1, 1], 3)), t)
    cond = _error(wp, Qp, wr, Qr)
    err = _error(w, Q, wr, Qr)
    ok = err <= max(1e-9, 100 * cond)
    rec.update(err=err, cond=cond, method=sol.method,
               outcome="warned" if warned else ("correct" if ok else "silent-wrong"))
    if not ok and not warned:
        rec["data"] = (Ju.tolist(), au.tolist(), Q0.tolist(), wu.tolist())
    return rec


def main(n: int = 16, seed: int = 0):
    import heyoka

    rng = np.random.default_rng(seed)
    print(machine_info("heyoka"))
    print(f"thetasol from {sys.modules['thetasol'].__file__}", file=sys.stderr)
    print(f"\n{n} bodies per regime, seed {seed}")
    rows = []
    t_start = time.perf_counter()
    for regime in REGIMES:
        recs = []
        for _ in range(n):
            r = run_case(regime, rng)
            recs.append(r)
            if r["outcome"] in ("silent-wrong", "crash"):
                print("  ", r, flush=True)
        rows.append(_row(regime, recs))
        print(f"  {regime}: done at {time.perf_counter() - t_start:.0f} s", file=sys.stderr, flush=True)
    print(f"\nheyoka {heyoka.__version__}; total {time.perf_counter() - t_start:.0f} s\n")
    print("| regime | n | correct | warned | refused | silent-wrong | crash | max error (solved) | "
          "max error / bound | max refusal time | median set-up | cost per point |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for row in rows:
        print(row)


def _row(regime, recs):
    count = {k: sum(r["outcome"] == k for r in recs) for k in
             ("correct", "warned", "refused", "silent-wrong", "crash")}
    solved = [r for r in recs if "err" in r]
    errs = [r["err"] for r in solved]
    ratio = [r["err"] / max(1e-9, 100 * r["cond"]) for r in solved]
    refused = [r["setup"] for r in recs if r["outcome"] == "refused"]
    setups = [r["setup"] for r in solved]
    cost = [r["per_point"] for r in solved]

    def fmt(xs, f):
        return f(xs) if xs else "-"

    return (f"| {regime} | {len(recs)} | {count['correct']} | {count['warned']} | {count['refused']} | "
            f"{count['silent-wrong']} | {count['crash']} | {fmt(errs, lambda x: f'{max(x):.1e}')} | "
            f"{fmt(ratio, lambda x: f'{max(x):.2g}')} | {fmt(refused, lambda x: f'{max(x):.2f} s')} | "
            f"{fmt(setups, lambda x: f'{np.median(x):.2f} s')} | {fmt(cost, lambda x: f'{np.median(x) * 1e6:.0f} us')} |")


if __name__ == "__main__":
    page = docs_page("docs/units.md")
    seed = sys.argv[2] if len(sys.argv) > 2 else "0"
    with docs_section(page, "benchmarks/bench_units_sweep.py", section=f"seed {seed}"):
        main(*(int(x) for x in sys.argv[1:3]))
