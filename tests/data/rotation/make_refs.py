"""Regenerate the long high-accuracy reference trajectories used by the rotation tests.

Each case is integrated with heyoka's Taylor method in quadruple precision (fp_type=heyoka.real128,
tolerance 1e-25) at the sample times TIMES of tests/test_theta_rotation.py, the inverse inertia and
m0 = I omega0 formed in that precision from the float64 data (integrate_rotation).  The extended-precision run (80-bit,
tolerance 1e-19) is the cross-check: its largest distance from the stored values over all six
times is ``ref_error`` (4e-11 near the unstable relative equilibrium, 5e-10 at worst on 801 times
in [0, 4002] there; 1.3e-12 for fast spin; f128 at tolerance 1e-28 moved the dense values by 7e-16).
Run:  python tests/data/rotation/make_refs.py [NAME ...]   (needs thetasol[bench]; about 8 minutes
for all cases; with names only those are regenerated).
"""
import json
import pathlib

import numpy as np

from thetasol import integrate_rotation
from thetasol.core.inertia import inertia
from thetasol.core.so3 import rodrigues

TIMES = [0.7, 3.1, 17.3, 102.0, 997.0, 4002.0]


def _frame(seed):
    rng = np.random.default_rng(seed)
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    return R * np.linalg.det(R)


def cases():
    J = [0.6, 1.0, 1.7]
    rng = np.random.default_rng(7)
    a_gen = rng.normal(size=(3, 3))
    a_gen = 0.5 * (a_gen + a_gen.T)
    R = _frame(3)
    Q0 = rodrigues(np.array([0.4, -0.7, 0.3]))
    w0 = np.array([0.5, -0.8, 0.6])
    gamma = np.array([0.3, -0.5, 0.81])
    gamma /= np.linalg.norm(gamma)
    out = {
        "generic": (J, a_gen, Q0, w0),
        "saddle": (J, R @ np.diag([-1.0, 0.4, 1.5]) @ R.T, Q0, w0),
        "fast_spin": (J, a_gen, Q0, 12.0 * w0 / np.linalg.norm(w0)),
        "slow_spin": (J, a_gen, Q0, 0.02 * w0 / np.linalg.norm(w0)),
        "nearly_symmetric": ([1.0, 1.0 + 1e-6, 1.7], a_gen, Q0, w0),
        "rank_one": (J, -3.0 * np.outer(gamma, gamma), Q0, w0),
        "rank_one_plus_isotropic": (J, 0.7 * np.eye(3) - 3.0 * np.outer(gamma, gamma), Q0, w0),
    }
    # Relative equilibria: principal axes along eigenvectors of a.  V = 1/2 sum J_i e_i^T Q^T a Q e_i
    # is least when the largest J_i meets the smallest eigenvalue of a (stable), largest when it
    # meets the largest eigenvalue (unstable for the rotation about a fixed point).
    lam, U = np.linalg.eigh(R @ np.diag([-1.0, 0.4, 1.5]) @ R.T)
    a_eq = U @ np.diag(lam) @ U.T
    Q_stable = U[:, ::-1] * np.linalg.det(U[:, ::-1])    # body axis 3 (largest J) -> smallest lambda
    Q_unstable = U * np.linalg.det(U)                     # body axis 3 -> largest lambda
    kick = rodrigues(np.array([1e-3, -2e-3, 1.5e-3]))
    out["near_stable_equilibrium"] = (J, a_eq, Q_stable @ kick, np.array([1e-3, 2e-3, -1e-3]))
    out["near_unstable_equilibrium"] = (J, a_eq, Q_unstable @ kick, np.array([1e-3, 2e-3, -1e-3]))
    # Symmetric bodies (two equal J_i; the axial spin is an integral): oblate and prolate, a saddle
    # potential, fast spin, and a rank-one potential (two nodes: genus 2).
    out["symmetric_oblate"] = ([1.0, 1.0, 1.7], a_gen, Q0, w0)
    out["symmetric_prolate_saddle"] = ([0.6, 1.7, 1.7], R @ np.diag([-1.0, 0.4, 1.5]) @ R.T, Q0, w0)
    out["symmetric_fast_spin"] = ([1.0, 1.0, 1.7], a_gen, Q0, 12.0 * w0 / np.linalg.norm(w0))
    out["symmetric_rank_one"] = ([1.0, 1.0, 1.7], -3.0 * np.outer(gamma, gamma), Q0, w0)
    return out


def main(only=None):
    """Regenerate all cases, or only the named ones (the others are kept as stored)."""
    path = pathlib.Path(__file__).with_name("refs.json")
    data = json.loads(path.read_text()) if only else {}
    import heyoka as hy

    t = np.array(TIMES)
    for name, (J, a, Q0, w0) in cases().items():
        if only and name not in only:
            continue
        w, Q = integrate_rotation(inertia(J), a, Q0, w0, method="heyoka", fp_type=hy.real128, rtol=1e-25)(t)
        wl, Ql = integrate_rotation(inertia(J), a, Q0, w0, method="heyoka", fp_type=np.longdouble, rtol=1e-19)(t)
        err = max(np.abs(Ql - Q).max(), np.abs(wl - w).max())
        data[name] = {"J": list(map(float, J)), "a": np.asarray(a).tolist(), "Q0": np.asarray(Q0).tolist(),
                      "omega0": np.asarray(w0).tolist(), "t": TIMES, "omega": w.tolist(), "Q": Q.tolist(),
                      "ref_error": float(err)}
        print(f"{name:28s} ldbl vs f128 (t <= 4002): {err:.2e}", flush=True)
    path.write_text(json.dumps(data, indent=1))


if __name__ == "__main__":
    import sys

    main(sys.argv[1:] or None)
