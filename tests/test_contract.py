"""The result contract every solution follows (thetasol.protocol): its vocabulary, its error estimate and
check(), the refusal of text where numbers are expected, and the warning at far times."""
import numpy as np
import pytest

from thetasol import KeplerOrbit, solve_heavy_top, solve_rotation
from thetasol.core import validate as V

W0 = [0.3, 1.2, -0.7]
J_TRI = [0.6, 1.0, 1.7]


@pytest.mark.parametrize("text", ["10", b"10", ["0", "1"], np.array(["1.5"]), [0.5, 0.0, "12"],
                                  np.array([1.0, "2"], dtype=object)])
def test_text_is_not_a_number(text):
    """numpy reads "10" as 10.0; the validators refuse it and name the argument."""
    with pytest.raises(ValueError, match="x must be numeric.*text"):
        V.finite_array(text, "x")


def test_text_refused_at_the_entry_points():
    sol = solve_rotation(J_TRI, np.zeros((3, 3)), np.eye(3), W0)
    with pytest.raises(ValueError, match="t must be numeric"):
        sol("10")
    with pytest.raises(ValueError, match="t must be numeric"):
        sol.omega(["1", "2"])
    with pytest.raises(ValueError, match="mass must be numeric"):
        solve_heavy_top([5.0, 5.0, 1.0], [0, 0, 1.0], np.eye(3), [0.3, 0, 5.0], mass="2")
    with pytest.raises(ValueError, match="center must be numeric"):
        solve_heavy_top([5.0, 5.0, 1.0], [0.5, 0.0, "12"], np.eye(3), [0.3, 0, 5.0])
    with pytest.raises(ValueError, match="mu must be numeric"):
        KeplerOrbit("1", [1.0, 0, 0], [0, 1.0, 0])


def test_numbers_of_every_numeric_type_still_pass():
    assert V.finite_array(np.float32(2), "x") == 2.0
    assert V.finite_array(True, "x") == 1.0
    assert np.array_equal(V.finite_array(np.array([1, 2], dtype=object), "x"), [1.0, 2.0])
    assert V.times(3, "t") == 3.0
