"""Symmetric body without axial spin in a quadratic potential (Neumann's problem), thetasol.neumann."""
import numpy as np
import pytest

from thetasol import ClosedFormUnavailable, integrate_rotation, invariants, solve_rotation
from thetasol._so3 import rodrigues

OBLATE = np.array([0.8, 0.8, 1.5])      # j3 > j
PROLATE = np.array([1.1, 1.1, 0.4])     # j3 < j
A_DIAG = np.diag([0.5, 1.3, 2.0])
A_SADDLE = np.diag([-1.0, 0.5, 2.0])
N_AXIS = np.array([0.3, -0.5, 0.81]) / np.linalg.norm([0.3, -0.5, 0.81])
A_RANK1 = 3.0 * np.outer(N_AXIS, N_AXIS)
R0 = rodrigues([0.3, 0.2, -0.1])
T_DOP = np.array([0.0, 0.7, 3.1, 17.3, 40.0])

CASES = [
    # (label, J, a, Q0, omega0, method)
    ("oblate-diag-identity", OBLATE, A_DIAG, np.eye(3), [0.3, -0.4, 0.0], "neumann/genus-2"),
    ("oblate-rest", OBLATE, A_DIAG, R0, [0.0, 0.0, 0.0], "neumann/genus-2"),
    ("prolate-rest", PROLATE, A_DIAG, R0, [0.0, 0.0, 0.0], "neumann/genus-2"),
    ("oblate-saddle", OBLATE, A_SADDLE, R0, [0.2, 0.5, 0.0], "neumann/genus-2"),
    ("prolate-saddle", PROLATE, A_SADDLE, R0, [0.2, 0.5, 0.0], "neumann/genus-2"),
    ("oblate-rank1", OBLATE, A_RANK1, R0, [0.2, 0.5, 0.0], "neumann/elliptic"),
    ("prolate-rank1", PROLATE, A_RANK1, R0, [0.2, 0.5, 0.0], "neumann/elliptic"),
    ("oblate-rank1-rest", OBLATE, A_RANK1, R0, [0.0, 0.0, 0.0], "neumann/planar-libration"),
    ("prolate-repeated-saddle", PROLATE, np.diag([1.0, 1.0, -2.0]), R0, [0.2, 0.5, 0.0], "neumann/elliptic"),
]


@pytest.mark.parametrize("label, J, a, Q0, w0, method", CASES, ids=[c[0] for c in CASES])
def test_against_dop853(label, J, a, Q0, w0, method):
    sol = solve_rotation(J, a, Q0, w0)
    assert sol.method == method
    w, Q = sol(T_DOP)
    wr, Qr = integrate_rotation(J, a, Q0, w0, T_DOP, rtol=1e-13)
    assert np.abs(w - wr).max() < 1e-11 and np.abs(Q - Qr).max() < 1e-11
    # t = 0 returns the data
    assert np.abs(w[0] - w0).max() < 1e-13 and np.abs(Q[0] - Q0).max() < 1e-13


def test_small_axial_spin_still_refused_by_the_theta_branch():
    w0 = np.array([0.2, 0.5, 1e-5 * 0.6])
    with pytest.raises(ClosedFormUnavailable, match="little spin"):
        solve_rotation(OBLATE, A_DIAG, R0, w0)
