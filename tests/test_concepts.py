"""One implementation of each concept: the principal frame, the Stumpff functions, the potential
classifier and the Curve protocol, checked against independent definitions."""
from __future__ import annotations

import numpy as np
import pytest

from thetasol.core.attitude import principal_frame

# -- principal frame ---------------------------------------------------------------------------

@pytest.mark.parametrize("ascending", [False, True])
def test_principal_frame_diagonalizes_right_handed(ascending):
    rng = np.random.default_rng(3)
    A = rng.normal(size=(3, 3))
    J = A @ A.T + np.eye(3)
    Jp, R = principal_frame(J, ascending=ascending)
    assert np.allclose(R.T @ R, np.eye(3), atol=1e-14)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-14)
    assert np.allclose(R @ np.diag(Jp) @ R.T, J, atol=1e-13)
    assert np.all(np.diff(Jp) > 0)


def test_principal_frame_of_principal_data():
    J = np.diag([3.0, 1.0, 2.0])
    Jp, R = principal_frame(J)
    assert np.array_equal(Jp, [3.0, 1.0, 2.0]) and np.array_equal(R, np.eye(3))   # the body's own axes
    Jp, R = principal_frame(J, ascending=True)
    assert np.array_equal(Jp, [1.0, 2.0, 3.0])
    assert np.allclose(R @ np.diag(Jp) @ R.T, J, atol=1e-15) and np.linalg.det(R) == pytest.approx(1.0)
