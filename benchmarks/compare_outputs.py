"""Record every numerical output of thetasol's public API on the test suite's reference data, and
compare a later run against the record (for layout changes that must not change any number).

    python benchmarks/compare_outputs.py --save baseline.npz      # record
    python benchmarks/compare_outputs.py --compare baseline.npz   # recompute, diff, exit 1 if flagged

Run with ``OPENBLAS_NUM_THREADS=1`` (BLAS reductions split over threads may change the last bit) and
``PYTHONPATH`` pointing at the checkout under test; the script prints ``thetasol.__file__``.

Only names exported by ``thetasol`` (``thetasol/__init__.py``) are used, so module moves do not touch
this script.  The inputs are read from ``tests/data`` under ``--root`` (default: the repository that
holds this script) or copied from the tests (the few numpy helpers the tests import from private
modules, ``rodrigues``/``hat``/``rand_Q``, are re-implemented here with the same operations).

Every output goes into one flat dict ``group/case/quantity -> array``: float, complex or integer
arrays, or text (method strings, warnings, and ``ExceptionClass: message`` of any call that raised,
so that a refusal that changes is caught too).  Text is stored as a bytes array (dtype ``S``).

``--compare`` prints, per key, the max absolute difference and the max difference relative to
max |reference| of that array, and flags: relative difference > 1e-15 (``--tol``), changed text,
changed shape/dtype kind/NaN pattern, missing or new keys.  Exit status 1 if anything is flagged.
"""
from __future__ import annotations

import os

# One BLAS thread unless the caller says otherwise (before numpy loads OpenBLAS): with 2 OpenBLAS threads
# a baseline moved by up to 2.6e-14 (Neumann near-unstable; an integer mode count changed) and
# 1e-15 .. 6e-15 on theta rotations and scenes, so baseline and comparison must use the same setting.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import glob
import io
import json
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

import thetasol
from thetasol import (
    ClosedFormUnavailable,  # noqa: F401  (public name; refusals are recorded by class name)
    PlaneCurve,
    RiemannTheta,
    integrate_rotation,
    invariants,
    load_scene,
    riemann_theta,
    riemann_theta_separated,
    run,
    second_moments,
    siegel_reduce,
    solve_configuration,
    solve_gyrostat,
    solve_mass_center,
    solve_rotation,
    spectral_coefficients,
    spectral_curve,
    torque,
)

TOL = 1e-15

# Times for the rotations: 44 equispaced in [0, 4002], the reference times of tests/data/rotation
# (0.7, 3.1, 17.3, 102, 997; 4002 is in the grid) and t = 1e6: 50 times.
T_ROT = np.concatenate([np.linspace(0.0, 4002.0, 44), [0.7, 3.1, 17.3, 102.0, 997.0], [1e6]])
# the closed forms of the other branches also run backwards
T_OTHER = np.concatenate([T_ROT, [-7.7, -123.4]])

# Period matrices of tests/data/curves too slow to record (PlaneCurve + period_matrix, one core) would be
# listed here and skipped (a fixed list, so that the key set does not depend on timing); none is.
SKIP_CURVES: dict[str, str] = {}


# -- helpers copied from the tests' private imports (inputs only, same floating-point operations) ------

def _hat(v):
    v = np.asarray(v)
    x, y, w = v[..., 0], v[..., 1], v[..., 2]
    S = np.zeros(v.shape[:-1] + (3, 3), dtype=v.dtype)
    S[..., 0, 1], S[..., 0, 2] = -w, y
    S[..., 1, 0], S[..., 1, 2] = w, -x
    S[..., 2, 0], S[..., 2, 1] = -y, x
    return S


def rodrigues(phi):
    """The rotation vector -> matrix map of thetasol.core.so3.rodrigues (same operations)."""
    phi = np.asarray(phi, dtype=float)
    th = np.linalg.norm(phi, axis=-1)[..., None, None]
    K = _hat(phi)
    small = th < 1e-4
    th2 = th * th
    with np.errstate(invalid="ignore", divide="ignore"):
        a = np.where(small, 1 - th2 / 6 * (1 - th2 / 20), np.sin(th) / np.where(small, 1, th))
        b = np.where(small, 0.5 * (1 - th2 / 12 * (1 - th2 / 30)),
                     (1 - np.cos(th)) / np.where(small, 1, th2))
    return np.eye(3) + a * K + b * (K @ K)


def rand_Q(rng):
    """tests/conftest.py rand_Q."""
    Q = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    return Q * np.linalg.det(Q)


def inertia(J):
    J = np.diag(J) if np.ndim(J) == 1 else np.asarray(J)
    return np.trace(J) * np.eye(3) - J


def _mpstr(arr, digits=25):
    """mpmath values (object arrays) as text with all their digits (str() would use mp.dps = 15)."""
    import mpmath

    return " ".join(mpmath.nstr(v, digits) for v in np.ravel(arr))


# -- the record ------------------------------------------------------------------------------------------

class Record:
    def __init__(self):
        self.data: dict[str, np.ndarray] = {}
        self.seconds: dict[str, float] = {}

    def num(self, key, value):
        a = np.asarray(value)
        if a.dtype == object or a.dtype.kind in "US":
            raise TypeError(f"{key}: not numeric ({a.dtype})")
        if key in self.data:
            raise KeyError(f"duplicate key {key}")
        self.data[key] = np.array(a, copy=True)

    def text(self, key, s):
        if key in self.data:
            raise KeyError(f"duplicate key {key}")
        self.data[key] = np.array(str(s).encode("utf-8"))

    def value(self, key, v):
        """Numbers and arrays as numbers, None/str/other as text."""
        if v is None or isinstance(v, str):
            self.text(key, repr(v) if v is None else v)
            return
        try:
            a = np.asarray(v)
        except Exception:  # pragma: no cover
            self.text(key, repr(v))
            return
        if a.dtype == object or a.dtype.kind in "US":
            self.text(key, repr(v))
        else:
            self.num(key, a)

    def guard(self, prefix, fn, *args, **kwargs):
        """Run fn, recording warnings under prefix/warnings and an exception under prefix/error."""
        start = time.perf_counter()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                out = fn(*args, **kwargs)
            except Exception as exc:  # noqa: BLE001 - any refusal is data
                self.text(f"{prefix}/error", f"{type(exc).__name__}: {exc}")
                out = None
        msgs = [f"{w.category.__name__}: {w.message}" for w in caught]
        if msgs:
            self.text(f"{prefix}/warnings", "\n".join(msgs))
        self.seconds[prefix] = time.perf_counter() - start
        return out


def record_solution(rec, prefix, make, t):
    """solve, then method, invariants, (omega, Q) = sol(t) and sol.omega(t)."""
    sol = rec.guard(prefix + "/solve", make)
    if sol is None:
        return None
    rec.text(prefix + "/method", sol.method)
    # first integrals and diagnostics under one name each, wherever the solution files them
    both = {**sol.invariants, **getattr(sol, "diagnostics", {})}
    for k in sorted(both):
        rec.value(f"{prefix}/inv/{k}", both[k])

    def evaluate():
        w, Q = sol(t)
        rec.num(prefix + "/omega", w)
        rec.num(prefix + "/Q", Q)
        rec.num(prefix + "/omega_only", sol.omega(t))

    rec.guard(prefix + "/eval", evaluate)
    return sol


# -- groups ----------------------------------------------------------------------------------------------

def group_rotation_refs(rec, root):
    """The 13 long-integration reference cases (tests/data/rotation/refs.json, test_theta_rotation.py)."""
    refs = json.loads((root / "tests" / "data" / "rotation" / "refs.json").read_text())
    for name, r in refs.items():
        J, a, Q0, w0 = np.diag(r["J"]), np.array(r["a"]), np.array(r["Q0"]), np.array(r["omega0"])
        sol = record_solution(rec, f"rotation/{name}", lambda: solve_rotation(inertia(J), a, Q0, w0), T_ROT)
        if sol is not None and name in ("generic", "symmetric_oblate", "rank_one"):
            # the public first integrals and spectral coefficients on the solution's own output
            def eq(sol=sol, name=name, J=J, a=a):
                w, Q = sol(T_ROT[:8])
                inv = invariants(inertia(J), a, Q, w)
                for k in sorted(inv):
                    rec.value(f"equations/{name}/invariants/{k}", inv[k])
                rec.num(f"equations/{name}/spectral_coefficients", spectral_coefficients(inertia(J), sol.M(T_ROT[:8]), sol.u(T_ROT[:8])))
                rec.num(f"equations/{name}/torque", torque(inertia(J), a, Q))
            rec.guard(f"equations/{name}", eq)
    return refs


def group_rotation_extra(rec, refs):
    """Refusals (ClosedFormUnavailable and friends), one numerical reference, the spectral curves."""
    A_DIAG = np.diag([0.5, 1.3, 2.0])
    OBLATE = np.array([0.8, 0.8, 1.5])
    R0 = rodrigues([0.3, 0.2, -0.1])
    rng = np.random.default_rng(3)
    a_ns = rng.normal(size=(3, 3))
    a_ns = 0.5 * (a_ns + a_ns.T)
    A_PLANE = np.diag([0.5, 2.0, 1.3])
    scale = np.linalg.norm([0.2, 0.5]) + np.sqrt(2.0)
    cases = {
        # test_theta_rotation / test_neumann refusals
        "tacnode_small_spin": ([0.5, 0.5, 1.2], np.diag([1.0, 2.0, 3.0]), np.eye(3), [0.1, 0.2, 1e-5], {}),
        "nearly_symmetric_1e-7": (np.array([0.8, 0.8 * (1 + 1e-7), 1.5]), a_ns, rodrigues(np.array([0.3, -0.5, 0.2])),
                                  np.array([0.4, -0.7, 0.5]), {}),
        "nearly_spherical_small_spin": ([1.0, 1.0025, 1.0], np.array([[0.84, 0.58, 1.74], [0.58, -1.57, 1.02],
                                                                      [1.74, 1.02, -2.47]]),
                                        np.eye(3), [-0.9, 0.003, -0.6], {}),
        "neumann_little_axial_spin": (OBLATE, A_DIAG, R0, np.array([0.2, 0.5, 1e-5 * scale]), {}),
        "neumann_dps": (OBLATE, A_DIAG, R0, [0.2, 0.5, 0.0], {"dps": 30}),
        "neumann_degenerate_torus": (OBLATE, A_PLANE, rodrigues([1e-6, 0.7, 0]) @ rodrigues([0, 0, 0.4]),
                                     rodrigues([0, 0, -0.4]) @ [1e-6, 0.1, 0], {}),
        "bad_dps": ([1.0, 2.0, 3.5], np.zeros((3, 3)), np.eye(3), [0.1, 1.0, 0.2], {"dps": 5}),
        "not_a_rotation": ([1.0, 2.0, 3.5], np.zeros((3, 3)), 2 * np.eye(3), [0.1, 1.0, 0.2], {}),
    }
    for name, (J, a, Q0, w0, kw) in cases.items():
        sol = rec.guard(f"refusals/{name}", solve_rotation, inertia(J), a, Q0, w0, **kw)
        if sol is not None:
            rec.text(f"refusals/{name}/method", sol.method)
            rec.guard(f"refusals/{name}/eval", lambda sol=sol, name=name: rec.num(f"refusals/{name}/Q", sol.Q(T_ROT[:6])))

    # Euler top through mpmath (dps): values as 25-digit strings (exact comparison)
    def mp_top():
        sol = solve_rotation(inertia([1.0, 1.7, 2.3]), np.zeros((3, 3)), rodrigues([0.1, 0.2, 0.3]), [0.05, 0.6, 0.4], dps=25)
        rec.text("dps/euler_top/method", sol.method)
        w, Q = sol(np.array([0.0, 3.1, 102.0]))
        rec.text("dps/euler_top/omega", _mpstr(w))
        rec.text("dps/euler_top/Q", _mpstr(Q))
    rec.guard("dps/euler_top", mp_top)

    # the numerical reference integrator (DOP853), deterministic
    r = refs["generic"]
    J, a, Q0, w0 = np.diag(r["J"]), np.array(r["a"]), np.array(r["Q0"]), np.array(r["omega0"])

    def integ():
        w, Q = integrate_rotation(thetasol.inertia(J), a, Q0, w0, rtol=1e-12)(np.array([0.0, 0.7, 3.1, 17.3]))
        rec.num("integrate_rotation/generic/omega", w)
        rec.num("integrate_rotation/generic/Q", Q)
    rec.guard("integrate_rotation/generic", integ)

    # spectral curves (4.12) of three reference cases at t = 0, from the data
    for name in ("generic", "symmetric_oblate", "rank_one"):
        r = refs[name]
        J, a, Q0, w0 = np.diag(r["J"]), np.array(r["a"]), np.array(r["Q0"]), np.array(r["omega0"])
        m = inertia(J) @ w0
        u = -(Q0.T @ a @ Q0)

        def sc(name=name, J=J, m=m, u=u):
            C = spectral_curve(J, m, u)
            p = f"spectral_curve/{name}"
            rec.num(p + "/genus", C.genus)
            rec.text(p + "/degeneracy", repr(C.degeneracy))
            rec.value(p + "/node", C.node)
            rec.num(p + "/branch_points", np.sort_complex(C.branch_points))
            rec.num(p + "/period_matrix", C.period_matrix())
            rec.num(p + "/riemann_matrix", C.riemann_matrix())
        rec.guard(f"spectral_curve/{name}", sc)


def group_neumann(rec):
    """A handful of test_neumann.CASES (symmetric body, no axial spin), one per method and potential type."""
    OBLATE = np.array([0.8, 0.8, 1.5])
    PROLATE = np.array([1.1, 1.1, 0.4])
    A_DIAG = np.diag([0.5, 1.3, 2.0])
    A_SADDLE = np.diag([-1.0, 0.5, 2.0])
    A_PLANE = np.diag([0.5, 2.0, 1.3])
    A_RANK1 = np.array([[9.0, 12.0, 0.0], [12.0, 16.0, 0.0], [0.0, 0.0, 0.0]]) / 8.0
    R0 = rodrigues([0.3, 0.2, -0.1])

    def near(idx, tilt, a):
        w, V = np.linalg.eigh(a)
        v = V[:, idx]
        e3 = np.array([0.0, 0.0, 1.0])
        ax = np.cross(e3, v)
        R = rodrigues(ax / np.linalg.norm(ax) * np.arccos(np.clip(e3 @ v, -1, 1))) if np.linalg.norm(ax) > 1e-12 \
            else np.eye(3)
        return rodrigues(tilt * np.array([0.6, -0.8, 0.0]) @ R.T) @ R

    cases = {
        "oblate-diag-identity": (OBLATE, A_DIAG, np.eye(3), [0.3, -0.4, 0.0]),
        "prolate-saddle": (PROLATE, A_SADDLE, R0, [0.2, 0.5, 0.0]),
        "oblate-fast": (OBLATE, A_DIAG, R0, [2.5, -1.5, 0.0]),
        "near-unstable": (OBLATE, A_DIAG, near(2, 0.1, A_DIAG), [0.1, 0.2, 0.0]),
        "oblate-rank1": (OBLATE, A_RANK1, R0, [0.2, 0.5, 0.0]),
        "prolate-rank1-rest": (PROLATE, A_RANK1, R0, [0.0, 0.0, 0.0]),
        "repeated-saddle": (PROLATE, np.diag([1.0, 1.0, -2.0]), R0, [0.2, 0.5, 0.0]),
        "planar-circulation": (OBLATE, A_PLANE, rodrigues([0, 0.7, 0]) @ rodrigues([0, 0, 0.4]),
                               rodrigues([0, 0, -0.4]) @ [0, 2.0, 0]),
    }
    for name, (J, a, Q0, w0) in cases.items():
        record_solution(rec, f"neumann/{name}", lambda: solve_rotation(inertia(J), a, Q0, w0), T_OTHER)


def group_pendulum(rec):
    """test_pendulum: the regimes, uniform rotation, the separatrix."""
    J = np.array([0.7, 1.1, 1.9])
    A = np.diag([1.0, 2.0, 3.0])
    cases = {
        "rest": (J, A, np.eye(3), np.zeros(3)),
        "libration": (J, A, rodrigues([0, 0, 0.4]), np.zeros(3)),
        "circulation-slow": (J, A, rodrigues([0, 0, 0.4]), [0, 0, 0.3]),
        "circulation-fast": (J, A, rodrigues([0, 0, 0.4]), [0, 0, 3.0]),
        "circulation-x": (J, A, rodrigues([0.7, 0, 0]), [-0.5, 0, 0]),
        "libration-y": (J, A, rodrigues([0, 1.2, 0]), [0, 0.2, 0]),
        "uniform": (np.array([0.8, 0.8, 1.5]), A, rodrigues([0, 0, 0.3]), [0, 0, 1.3]),
    }
    i, j, k = 2, 0, 1
    Jb = np.diag(second_moments(inertia(J)))   # the separatrix of the body solved: its second moments from I
    Ii = Jb.sum() - Jb[i]
    rho = 0.5 * abs(A[k, k] - A[j, j])
    nu = np.sqrt(2 * abs(Jb[k] - Jb[j]) * rho / Ii)
    cases["separatrix"] = (J, A, np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]), [0, 0, nu])
    for name, (Jc, a, Q0, w0) in cases.items():
        record_solution(rec, f"pendulum/{name}", lambda: solve_rotation(inertia(Jc), a, Q0, w0), T_OTHER)


def group_euler_top(rec):
    """test_euler_top.regimes(): all 13 (cheap), a = 0."""
    def omega_from_m(J, m):
        return np.linalg.solve(inertia(J), m)

    SEP_J = np.array([1.0, 2.0, 4.0])
    rng = np.random.default_rng(42)
    out = {
        "generic-max-axis": (rng.uniform(0.5, 2, 3), rand_Q(rng), np.array([0.2, 0.3, 1.1])),
        "generic-min-axis": (np.array([1.0, 1.7, 2.3]), rand_Q(rng), np.array([0.05, 0.6, 0.4])),
        "tensor": (None, rand_Q(rng), rng.normal(size=3)),
        "symmetric-oblate": (np.array([1.0, 1.0, 0.4]), rand_Q(rng), rng.normal(size=3)),
        "symmetric-prolate": (np.array([0.3, 1.0, 1.0]), rand_Q(rng), rng.normal(size=3)),
        "nearly-symmetric": (np.array([1.0, 1.0 + 1e-12, 0.4]), rand_Q(rng), rng.normal(size=3)),
        "near-steady": (np.array([1.0, 1.5, 2.5]), rand_Q(rng), np.array([1e-9, -2e-9, 0.7])),
        "sphere": (np.array([1.3, 1.3, 1.3]), rand_Q(rng), rng.normal(size=3)),
        "steady-mid-axis": (SEP_J, rand_Q(rng), np.array([0.0, 0.8, 0.0])),
        "rest": (SEP_J, rand_Q(rng), np.zeros(3)),
        "separatrix": (SEP_J, rand_Q(rng), omega_from_m(SEP_J, [2.0, 0.7, -1.0])),
        "near-separatrix-1e-10": (SEP_J, rand_Q(rng), omega_from_m(SEP_J, [2.0 * (1 + 1e-10), 0.7, 1.0])),
        "near-separatrix-other-side": (SEP_J, rand_Q(rng), omega_from_m(SEP_J, [2.0 * (1 - 1e-10), -0.7, 1.0])),
    }
    A = rng.normal(size=(3, 3))
    out["tensor"] = (A @ A.T + np.eye(3), out["tensor"][1], out["tensor"][2])
    Z = np.zeros((3, 3))
    for name, (J, Q0, w0) in out.items():
        record_solution(rec, f"euler_top/{name}", lambda: solve_rotation(inertia(J), Z, Q0, w0), T_OTHER)


def group_gyrostat(rec):
    """test_gyrostat: generic_cases()[0] and [3] (a tensor J), SPECIAL['dual-spin-z']."""
    rng = np.random.default_rng(0)
    gen = []
    for k in range(4):
        J = rng.uniform(0.3, 2.0, 3)
        if k % 4 == 3:
            A = rng.normal(size=(3, 3))
            J = A @ A.T + 0.3 * np.eye(3)
        N = rng.normal(size=3) * 10 ** rng.uniform(-2, 1)
        gen.append((J, N, rand_Q(rng), rng.normal(size=3)))
    cases = {
        "generic-0": gen[0],
        "generic-3-tensor": gen[3],
        "dual-spin-z": (np.array([1.0, 1.0, 0.5]), np.array([0.0, 0.0, 0.7]), rand_Q(np.random.default_rng(3)),
                        np.array([0.4, 0.3, -0.6])),
    }
    for name, (J, N, Q0, w0) in cases.items():
        sol = record_solution(rec, f"gyrostat/{name}", lambda: solve_gyrostat(inertia(J), N, Q0, w0), T_OTHER)
        if sol is not None:
            rec.guard(f"gyrostat/{name}/h", lambda sol=sol, name=name: rec.num(f"gyrostat/{name}/h", sol.h(T_OTHER)))


def group_curves(rec, root):
    """Every tests/data/curves/*.json: periods (stored and default differentials), Riemann matrix,
    intersection matrix, branch points, Riemann constant, Abel map of a few places."""
    import sympy as sp

    x, y = sp.symbols("x y")
    loc = {"x": x, "y": y}
    for path in sorted(glob.glob(str(root / "tests" / "data" / "curves" / "*.json"))):
        name = os.path.basename(path)[:-5]
        p = f"curves/{name}"
        if name in SKIP_CURVES:
            rec.text(p + "/skipped", SKIP_CURVES[name])
            continue
        d = json.loads(Path(path).read_text())
        f = sp.sympify(d["f"].replace("^", "**"), locals=loc)
        diffs = [sp.sympify(s.replace("^", "**"), locals=loc) for s in d["differentials"]]
        C = rec.guard(p + "/init", PlaneCurve, f, x, y)
        if C is None:
            continue

        def periods(C=C, p=p, diffs=diffs):
            rec.num(p + "/genus", C.genus)
            rec.num(p + "/period_matrix_ref_diffs", C.period_matrix(diffs))
            rec.num(p + "/period_matrix", C.period_matrix())
            rec.num(p + "/riemann_matrix", C.riemann_matrix())
            rec.num(p + "/intersection_matrix", C.intersection_matrix())
            rec.num(p + "/branch_points", C.branch_points)
            rec.text(p + "/holomorphic_differentials", repr([str(e) for e in C.holomorphic_differentials()]))
        rec.guard(p + "/periods", periods)

        def abel(C=C, p=p):
            rec.num(p + "/riemann_constant", C.riemann_constant())
            over = C.places_over(0.37 + 0.21j)
            rec.num(p + "/abel_map_over_c", C.abel_map(over))
            rec.num(p + "/abel_map_infinity", C.abel_map(C.places_at_infinity()))
            b = C.branch_points[0]
            rec.num(p + "/abel_map_over_branch_point", C.abel_map(C.places_over(b)))
            rec.num(p + "/abel_map_unnormalized_over_c", C.abel_map(over, normalized=False))
            D = {P: 1 for P in over}
            for P in C.places_at_infinity():
                D[P] = D.get(P, 0) - P.e
            rec.num(p + "/abel_map_divisor_x_minus_c", C.abel_map(D))
        rec.guard(p + "/abel", abel)


def group_theta(rec, root):
    """tests/data/theta (a tau with a tie of the Siegel reduction, z on its theta divisor) and a few
    random taus of genus 1-4 (test_theta.random_tau)."""
    tau = np.load(root / "tests" / "data" / "theta" / "theta_bug_tau.npy")
    z = np.load(root / "tests" / "data" / "theta" / "theta_bug_z.npy")
    Z = np.array([z, z + np.array([0.1, -0.2 + 0.3j, 0.05j]), 0.5 * z, z.conj(), np.zeros(3)])

    def tie():
        th = RiemannTheta(tau)
        p = "theta/bug"
        rec.num(p + "/value", th(Z))
        rec.num(p + "/gradient", th.gradient(Z))
        rec.num(p + "/hessian", th.hessian(Z))
        rec.num(p + "/all_chars", th(Z, char="all"))
        rec.num(p + "/all_chars_gradient", th.gradient(Z, char="all"))
        e, v = th.separated(Z)
        rec.num(p + "/separated_e", e)
        rec.num(p + "/separated_v", v)
        v0, G, H = th.jet(Z, order=2)
        rec.num(p + "/jet0", v0)
        rec.num(p + "/jet1", G)
        rec.num(p + "/jet2", H)
        w = np.array([0.3, -1.0 + 0.2j, 0.7])
        rec.num(p + "/directional_1", th(Z, derivs=[w]))
        rec.num(p + "/directional_3", th(Z, derivs=[w, w.conj(), np.eye(3)[1]]))
        rec.num(p + "/char_half", th(Z, char=(np.array([0, 0.5, 0]), np.array([0.5, 0.5, 0]))))
        rec.num(p + "/tau_perturbed", RiemannTheta(tau + 1e-15)(z))
        rec.num(p + "/riemann_theta", riemann_theta(Z, tau))
        v30 = riemann_theta(z, tau, dps=30)
        rec.num(p + "/riemann_theta_dps30", complex(v30))
        rec.text(p + "/riemann_theta_dps30_digits", _mpstr([v30], 30))
        d30 = riemann_theta(z, tau, derivs=[np.eye(3)[0]], dps=30)
        rec.num(p + "/riemann_theta_dps30_d0", complex(d30))
        rec.text(p + "/riemann_theta_dps30_d0_digits", _mpstr([d30], 30))
        tr, gam = siegel_reduce(tau)
        rec.num(p + "/siegel_tau", tr)
        rec.num(p + "/siegel_gamma", gam)
        rec.num(p + "/th_tau", th.tau)
    rec.guard("theta/bug", tie)

    def random_tau(g, rng, small=0.05, re=1.0):
        Qm, _ = np.linalg.qr(rng.normal(size=(g, g)))
        ev = np.concatenate([[small], rng.uniform(0.4, 2.0, g - 1)])
        Y = (Qm * ev) @ Qm.T
        X = rng.uniform(-re, re, (g, g))
        t = X + 1j * Y
        return 0.5 * (t + t.T)

    for g in (1, 2, 3, 4):
        def rnd(g=g):
            rng = np.random.default_rng(100 + g)
            t = random_tau(g, rng, small=0.08)
            zz = rng.normal(size=(6, g)) + 1j * rng.normal(size=(6, g))
            th = RiemannTheta(t)
            p = f"theta/random_g{g}"
            rec.num(p + "/tau", t)
            rec.num(p + "/value", th(zz))
            rec.num(p + "/gradient", th.gradient(zz))
            rec.num(p + "/all_chars", th(zz, char="all"))
            char = (rng.uniform(0, 1, g), rng.uniform(0, 1, g))
            rec.num(p + "/char_real", th(zz, char=char))
            e, v = riemann_theta_separated(zz, t)
            rec.num(p + "/separated_e", e)
            rec.num(p + "/separated_v", v)
        rec.guard(f"theta/random_g{g}", rnd)

    def overflow():
        t = np.array([[0.1 + 0.05j, 0.02], [0.02, 0.3 + 20j]])
        zz = np.array([0.3 + 0.3j, 0.1 + 200j])
        rec.guard("theta/overflow/direct", riemann_theta, zz, t)
        e, v = riemann_theta_separated(zz, t)
        rec.num("theta/overflow/separated_e", e)
        rec.num("theta/overflow/separated_v", v)
    rec.guard("theta/overflow", overflow)


def group_mass_center(rec):
    """test_masscenter.test_against_matrix_exponential data, plus one mpmath evaluation."""
    # |t| <= 30: at t = 1e3 the hyperbolic modes overflow float64 (refused, recorded once below)
    t = np.array([0.0, 0.37, 1.0, -2.2, 5.0, 17.0, -30.0])
    for lam in ([1.0, 2.5, 0.3], [-1.0, -0.4, -2.0], [0.0, 0.0, 0.0], [1.3, -0.7, 0.0], [1.0, 1.0 + 1e-13, 2.0]):
        rng = np.random.default_rng(0)
        R = rodrigues(np.array([0.4, -1.1, 0.7]))
        a = R @ np.diag(lam) @ R.T
        b, q0, v0 = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
        name = "lam_" + "_".join(f"{v:g}" for v in lam)

        def mc(a=a, b=b, q0=q0, v0=v0, name=name):
            q, v = solve_mass_center(a, b, q0, v0)(t)
            rec.num(f"mass_center/{name}/q", q)
            rec.num(f"mass_center/{name}/v", v)
        rec.guard(f"mass_center/{name}", mc)

        if lam == [1.3, -0.7, 0.0]:
            rec.guard("mass_center/overflow_refused",
                      lambda a=a, b=b, q0=q0, v0=v0: solve_mass_center(a, b, q0, v0)(np.array([0.0, 1e3])))

            def mp(a=a, b=b, q0=q0, v0=v0):
                q, v = solve_mass_center(a, b, q0, v0, dps=25)(t[:3])
                rec.text("mass_center/dps25/q", _mpstr(q))
                rec.text("mass_center/dps25/v", _mpstr(v))
            rec.guard("mass_center/dps25", mp)


SMALL_SCENE = """
name = "small"
[potential]
a = [[1.0, 0.2, 0.0], [0.2, 0.5, 0.0], [0.0, 0.0, -0.1]]
b = [0.1, 0.0, 0.0]
[[bodies]]
name = "root"
mass = 4.0
I = [2.0, 2.5, 3.0]
[[bodies]]
name = "arm"
mass = 1.0
box = [1.0, 0.2, 0.2]
[[bodies]]
name = "tip"
mass = 0.5
J = [0.02, 0.03, 0.04]
center = [0.0, 0.1, 0.0]
[[joints]]
parent = "root"
child = "arm"
parent_point = [1.0, 0.0, 0.0]
child_point = "central"
[[joints]]
parent = "arm"
child = "tip"
parent_point = [0.5, 0.0, 0.0]
child_point = [0.0, 0.1, 0.0]
[initial]
q = [0.1, 0.2, 0.0]
v = [0.0, 0.1, 0.0]
[initial.attitude]
arm = [0.0, 0.0, 0.4]
tip = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
[initial.omega]
root = [0.1, 0.2, 0.3]
tip = [1.0, 0.0, 0.5]
[output]
t_end = 4.0
samples = 41
"""


def _record_trajectories(rec, p, traj):
    rec.text(p + "/names", " ".join(traj.names))
    for k in ("t", "position", "velocity", "attitude", "omega", "mass_center", "mass_center_velocity"):
        rec.num(f"{p}/{k}", getattr(traj, k))
    models = traj.info.get("models")
    if models is not None:
        rec.text(p + "/models", json.dumps(models, sort_keys=True))


def group_scene(rec):
    """The bundled demo scene (run: split solution and its checks), test_scene's SMALL scene, and
    solve_configuration with numerical rotations on the demo's first 61 times."""
    pkg = Path(thetasol.__file__).resolve().parent
    demo = sorted(pkg.rglob("station.toml"))
    if len(demo) != 1:
        rec.text("scene/demo/error", f"demo scene not found uniquely under {pkg}: {demo}")
        return
    sc = rec.guard("scene/demo/load", load_scene, demo[0])
    if sc is None:
        return

    def demo_run():
        traj, report, checks = run(sc, out=io.StringIO())
        _record_trajectories(rec, "scene/demo/run", traj)
        rec.text("scene/demo/run/check_what", "\n".join(c.what for c in checks))
        rec.num("scene/demo/run/check_deviation", np.array([c.deviation for c in checks]))
        rec.num("scene/demo/run/check_tolerance", np.array([c.tolerance for c in checks]))
        rec.text("scene/demo/run/verdict", repr([c.ok for c in checks]))
    rec.guard("scene/demo/run", demo_run)

    def demo_numerical():
        try:  # a solution object: solve_configuration(...).trajectories(t)
            traj = solve_configuration(sc.config, sc.a, sc.b, sc.q0, sc.v0, sc.Q0, sc.omega0,
                                       rotation="numerical").trajectories(sc.t[:61])
        except TypeError:  # the older form that took the times
            traj = solve_configuration(sc.config, sc.a, sc.b, sc.q0, sc.v0, sc.Q0, sc.omega0, sc.t[:61],
                                       rotation="numerical")
        _record_trajectories(rec, "scene/demo/numerical", traj)
    rec.guard("scene/demo/numerical", demo_numerical)

    def small():
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "small.toml"
            path.write_text(SMALL_SCENE)
            s = load_scene(path)
        _record_trajectories(rec, "scene/small/solve", s.solve())
    rec.guard("scene/small", small)


def collect(root: Path) -> tuple[dict, dict]:
    rec = Record()
    timing = {}

    def timed(label, fn, *args):
        start = time.perf_counter()
        out = fn(*args)
        timing[label] = time.perf_counter() - start
        print(f"  {label:<28s} {timing[label]:7.2f} s", flush=True)
        return out

    refs = timed("rotation refs", group_rotation_refs, rec, root)
    timed("refusals/dps/spectral", group_rotation_extra, rec, refs)
    timed("neumann", group_neumann, rec)
    timed("pendulum", group_pendulum, rec)
    timed("euler_top", group_euler_top, rec)
    timed("gyrostat", group_gyrostat, rec)
    timed("curves", group_curves, rec, root)
    timed("theta", group_theta, rec, root)
    timed("mass_center", group_mass_center, rec)
    timed("scene", group_scene, rec)
    return rec.data, timing


# -- save / compare --------------------------------------------------------------------------------------

def _is_text(a):
    return a.dtype.kind == "S"


def compare(ref: dict, cur: dict, tol: float, verbose: bool = True) -> int:
    flagged = []
    stats: dict[str, list[int]] = {}   # group -> [keys, bit-identical, equal values, within tol, flagged]
    lines = []
    for key in sorted(set(ref) | set(cur)):
        if key.startswith("__"):
            continue
        group = key.split("/", 1)[0]
        st = stats.setdefault(group, [0, 0, 0, 0, 0])
        st[0] += 1
        if key not in cur:
            flagged.append((key, "MISSING in current run"))
            st[4] += 1
            continue
        if key not in ref:
            flagged.append((key, "NEW key (not in reference): " + (cur[key].tobytes().decode("utf-8", "replace")[:300]
                                                                  if _is_text(cur[key]) else f"shape {cur[key].shape}")))
            st[4] += 1
            continue
        a, b = ref[key], cur[key]
        if _is_text(a) or _is_text(b):
            if _is_text(a) and _is_text(b) and a.tobytes() == b.tobytes():
                st[1] += 1
                lines.append(f"  identical  {key}  (text)")
            else:
                sa = a.tobytes().decode("utf-8", "replace") if _is_text(a) else repr(a)
                sb = b.tobytes().decode("utf-8", "replace") if _is_text(b) else repr(b)
                flagged.append((key, f"TEXT changed:\n      was: {sa[:400]!r}\n      now: {sb[:400]!r}"))
                st[4] += 1
            continue
        if a.shape != b.shape:
            flagged.append((key, f"SHAPE changed {a.shape} -> {b.shape}"))
            st[4] += 1
            continue
        kind_note = ""
        if a.dtype != b.dtype:
            kind_note = f" dtype {a.dtype} -> {b.dtype}"
        if a.dtype == b.dtype and a.tobytes() == b.tobytes():
            st[1] += 1
            lines.append(f"  identical  {key}  shape {a.shape}  abs 0  rel 0")
            continue
        ac = np.atleast_1d(a.astype(complex))
        bc = np.atleast_1d(b.astype(complex))
        nan_a, nan_b = np.isnan(ac), np.isnan(bc)
        if np.any(nan_a != nan_b):
            flagged.append((key, f"NaN pattern changed ({nan_a.sum()} -> {nan_b.sum()} NaNs){kind_note}"))
            st[4] += 1
            continue
        ok = ~nan_a
        inf_a, inf_b = np.isinf(ac[ok]), np.isinf(bc[ok])
        if np.any(inf_a != inf_b) or np.any(ac[ok][inf_a] != bc[ok][inf_a]):
            flagged.append((key, f"inf pattern changed{kind_note}"))
            st[4] += 1
            continue
        fin = ok.copy()
        fin[ok] = ~inf_a
        diff = np.abs(ac[fin] - bc[fin])
        absd = float(diff.max()) if diff.size else 0.0
        scale = float(np.abs(ac[fin]).max()) if diff.size else 0.0
        rel = absd / scale if scale > 0 else (0.0 if absd == 0 else np.inf)
        status = "equal" if absd == 0 else ("within" if rel <= tol else "FLAG")
        if kind_note and a.dtype.kind != b.dtype.kind:
            status = "FLAG"
        msg = f"shape {a.shape}  abs {absd:.3g}  rel {rel:.3g}{kind_note}"
        if status == "FLAG":
            flagged.append((key, msg))
            st[4] += 1
        else:
            st[2 if status == "equal" else 3] += 1
            lines.append(f"  {status:<9s}  {key}  {msg}")
    print("\nper key (identical = same bits; equal = same values, e.g. -0.0 vs 0.0; within = rel <= tol):")
    print("\n".join(ln for ln in lines if verbose or not ln.startswith("  identical")))
    if flagged:
        print(f"\nFLAGGED ({len(flagged)}):")
        for key, why in flagged:
            print(f"  FLAG  {key}: {why}")
    print(f"\n{'group':<22s} {'keys':>6s} {'identical':>10s} {'equal':>6s} {'within':>7s} {'flagged':>8s}")
    for g, (n, i, e, w, f) in sorted(stats.items()):
        print(f"{g:<22s} {n:6d} {i:10d} {e:6d} {w:7d} {f:8d}")
    tot = np.sum(list(stats.values()), axis=0)
    print(f"{'total':<22s} {tot[0]:6d} {tot[1]:10d} {tot[2]:6d} {tot[3]:7d} {tot[4]:8d}")
    print(f"relative tolerance {tol:g}: " + ("NO DIFFERENCES FLAGGED" if not flagged else f"{len(flagged)} FLAGGED"))
    return 1 if flagged else 0


def main(argv=None):
    here = Path(__file__).resolve()
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    mode = ap.add_mutually_exclusive_group(required=True)
    mode.add_argument("--save", metavar="FILE.npz")
    mode.add_argument("--compare", metavar="FILE.npz")
    ap.add_argument("--root", default=str(here.parent.parent), help="repository root (tests/data); default %(default)s")
    ap.add_argument("--tol", type=float, default=TOL, help="relative tolerance (default %(default)g)")
    ap.add_argument("--quiet", action="store_true", help="compare: leave out the bit-identical keys")
    args = ap.parse_args(argv)
    start = time.perf_counter()
    root = Path(args.root).resolve()
    print(f"thetasol {getattr(thetasol, '__version__', '?')} from {thetasol.__file__}")
    print(f"data root {root}; numpy {np.__version__}; OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}")
    if os.environ.get("OPENBLAS_NUM_THREADS") != "1":
        print("warning: set OPENBLAS_NUM_THREADS=1 for reproducible BLAS reductions")
    print("collecting:")
    data, timing = collect(root)
    n_text = sum(1 for v in data.values() if _is_text(v))
    print(f"{len(data)} keys ({len(data) - n_text} numeric, {n_text} text)")
    rc = 0
    if args.save:
        meta = {"thetasol_file": thetasol.__file__, "numpy": np.__version__, "python": sys.version,
                "OPENBLAS_NUM_THREADS": os.environ.get("OPENBLAS_NUM_THREADS"),
                "timing": timing, "created": time.strftime("%Y-%m-%d %H:%M:%S")}
        out = dict(data)
        out["__meta__"] = np.array(json.dumps(meta).encode("utf-8"))
        np.savez_compressed(args.save, **out)
        print(f"saved {args.save}")
    else:
        with np.load(args.compare, allow_pickle=False) as z:
            ref = {k: z[k] for k in z.files}
        if "__meta__" in ref:
            meta = json.loads(ref["__meta__"].tobytes().decode())
            print(f"reference from {meta.get('thetasol_file')} ({meta.get('created')}), "
                  f"OPENBLAS_NUM_THREADS={meta.get('OPENBLAS_NUM_THREADS')}, numpy {meta.get('numpy')}")
            if meta.get("OPENBLAS_NUM_THREADS") != os.environ.get("OPENBLAS_NUM_THREADS") \
                    or meta.get("numpy") != np.__version__:
                print("warning: BLAS threads or numpy version differ from the reference's: last-bit differences "
                      "are expected from that alone")
        rc = compare(ref, data, args.tol, verbose=not args.quiet)
    print(f"total runtime {time.perf_counter() - start:.1f} s")
    return rc


if __name__ == "__main__":
    sys.exit(main())
