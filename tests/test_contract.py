"""The result contract every solution follows (thetasol.protocol): its vocabulary, its error estimate and
check(), the refusal of text where numbers are expected, and the warning at far times."""
import numpy as np
import pytest

from thetasol import KeplerOrbit, solve_gyrostat, solve_heavy_top, solve_rotation
from thetasol.core import validate as V

W0 = [0.3, 1.2, -0.7]
J_TRI = [1.0, 2.0, 2.5]    # a body as inertia or as second moments alike (triangle inequalities hold)


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
    from thetasol import solve_gyrostat

    with pytest.raises(ValueError, match=r"rotors\[0\]\['A'\] must be numeric"):
        solve_gyrostat(J_TRI, None, np.eye(3), W0, rotors=[dict(axis=[0.0, 0.0, 1.0], A="0.1", B=0.0, p=0.5)])
    with pytest.raises(ValueError, match="tol must be numeric"):
        sol.check(tol="1e-10")


def test_numbers_of_every_numeric_type_still_pass():
    assert V.finite_array(np.float32(2), "x") == 2.0
    assert V.finite_array(True, "x") == 1.0
    assert np.array_equal(V.finite_array(np.array([1, 2], dtype=object), "x"), [1.0, 2.0])
    assert V.times(3, "t") == 3.0


# -- the vocabulary and the error estimate of every solution the library returns -----------------------
#
# Bodies are chosen valid whether the entry points read them as second moments or as inertia (both
# satisfy the triangle inequalities), so the checks hold under either reading.

def _rx(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _closed_forms():
    """(name, solution) for every closed form and every special case the dispatchers choose."""
    from thetasol import (
        reference,
        solve_gyrostat,
        solve_lagrange_gyrostat,
        solve_mass_center,
        solve_neumann,
        solve_orbiting_rotation,
    )

    Z, A = np.zeros((3, 3)), np.diag([1.0, 2.0, 3.0])
    out = [(c.name, c.solution) for c in reference.cases()]
    out += [("rest", solve_rotation(J_TRI, Z, np.eye(3), np.zeros(3))),
            ("steady", solve_rotation(J_TRI, Z, np.eye(3), [0.0, 0.0, 2.0])),
            ("symmetric", solve_rotation([1.0, 1.0, 1.5], Z, np.eye(3), W0)),
            ("dps", solve_rotation(J_TRI, Z, np.eye(3), W0, dps=20)),
            ("neumann-rotation", solve_rotation([1.0, 1.0, 1.5], A, np.eye(3), [0.1, 0.2, 0.0])),
            ("scaled", solve_rotation(np.array(J_TRI) * 1e6, A, np.eye(3), W0)),
            ("lagrange", solve_heavy_top([5.0, 5.0, 1.0], [0, 0, 1.0], np.eye(3), [0.3, 0, 5.0])),
            ("sleeping", solve_heavy_top([5.0, 5.0, 1.0], [0, 0, 1.0], np.eye(3), [0, 0, 5.0])),
            ("heavy-euler", solve_heavy_top([2.0, 3.0, 4.0], [0, 0, 0], np.eye(3), W0)),
            ("kovalevskaya", solve_heavy_top([2.0, 2.0, 1.0], [0.3, 0.4, 0], _rx(0.3), [1, 2, 3.0])),
            ("lagrange-gyrostat", solve_lagrange_gyrostat([5.0, 5.0, 1.0], [0, 0, 1.0], np.eye(3), [0.3, 0, 5.0],
                                                          N=[0, 0, 0.5])),
            ("gyrostat", solve_gyrostat(J_TRI, [0.1, 0.2, 0.3], np.eye(3), W0)),
            ("gyrostat-rest", solve_gyrostat(J_TRI, [0.1, 0.2, 0.3], np.eye(3), np.zeros(3))),
            ("gyrostat-sphere", solve_gyrostat([1.0, 1.0, 1.0], [0.1, 0.2, 0.3], np.eye(3), W0)),
            ("gyrostat-euler", solve_gyrostat(J_TRI, [0.0, 0.0, 0.0], np.eye(3), W0)),
            ("neumann-planar", solve_neumann(A, [1.0, 0.0, 0.0], [0.0, 0.5, 0.0])),
            ("mass-center", solve_mass_center(A, np.zeros(3), np.ones(3), np.zeros(3))),
            ("orbiting-sphere", solve_orbiting_rotation([1.0, 1.0, 1.0], KeplerOrbit(1.0, [1.0, 0, 0], [0, 1.0, 0]),
                                                        np.eye(3), W0))]
    return out


CLOSED = _closed_forms()


@pytest.mark.parametrize("name, sol", CLOSED, ids=[n for n, _ in CLOSED])
def test_every_closed_form_speaks_the_vocabulary(name, sol):
    from thetasol.protocol import METHODS, MODELS, NUMERICAL, vocabulary_problem

    assert vocabulary_problem(sol.model, sol.method) == ""
    assert sol.model in MODELS and sol.method in METHODS and not sol.method.startswith(NUMERICAL)
    est = sol.diagnostics["error_estimate"]
    assert isinstance(est, float) and 0.0 < est < 1e-8
    check = sol.check()
    assert check and check.ok and check.estimate == est and str(check).startswith("ok: ")
    assert sol.model in str(check) and sol.method in str(check)


def test_vocabulary_names_what_is_wrong():
    from thetasol.protocol import vocabulary_problem

    assert vocabulary_problem("rotation", "numerical/DOP853") == ""
    assert "model 'euler-top'" in vocabulary_problem("euler-top", "elliptic")
    assert "method 'euler-top/elliptic'" in vocabulary_problem("rotation", "euler-top/elliptic")
    assert "method 'numerical/'" in vocabulary_problem("rotation", "numerical/")


def test_scenes_are_configurations_whose_estimate_is_their_worst_part():
    from thetasol import load_scene
    from thetasol.protocol import worst_error

    for name in ("pivoted_top", "hooke"):
        sol = load_scene(_scene_path(name)).solution()
        assert (sol.model, sol.method) == ("configuration", "split")
        parts = list(sol.rotations.values()) if hasattr(sol, "rotations") else [p.sol for p in sol.parts.values()]
        assert sol.diagnostics["error_estimate"] == worst_error(parts + ([sol.mass_center]
                                                                         if name == "hooke" else []))
        assert "=" in sol.diagnostics["parts"]


def _scene_path(name):
    from pathlib import Path

    import thetasol.scenes

    return Path(thetasol.scenes.__file__).with_name("data") / f"{name}.toml"


def test_check_says_not_ok_and_why():
    sol = solve_rotation(J_TRI, np.zeros((3, 3)), np.eye(3), W0)
    strict = sol.check(tol=1e-18)
    assert not strict and "above the tolerance 1.0e-18" in str(strict) and str(strict).startswith("NOT ok: ")
    far = sol.check(t=[0.0, 1e12])
    assert not far and far.estimate > 1e-5 and "float64 times" in far.reason


def test_a_heavy_top_at_its_pivot_is_a_heavy_top():
    from thetasol import HeavyTopSolution

    I, W = [2.0, 3.0, 4.0], [0.3, 1.2, -0.7]
    sol = solve_heavy_top(I, [0.0, 0.0, 0.0], np.eye(3), W, mass=2.0)
    lagrange = solve_heavy_top([5.0, 5.0, 1.0], [0, 0, 1.0], np.eye(3), [0.3, 0, 5.0])
    assert isinstance(sol, HeavyTopSolution) and sol.model == lagrange.model == "heavy-top"
    assert np.array_equal(sol.I, np.diag(I)) and np.array_equal(sol.center, np.zeros(3)) and sol.mass == 2.0
    assert {"energy", "vertical_momentum", "axial_momentum"} <= set(sol.invariants)
    t = np.linspace(0.0, 3.0, 7).reshape(7, 1)
    w, Q = sol(t)
    assert w.shape == (7, 1, 3) and Q.shape == (7, 1, 3, 3)
    m = sol.m(t)
    assert np.allclose(np.linalg.norm(m, axis=-1), np.linalg.norm(np.diag(I) @ W), rtol=1e-13)
    # the same motion as the torque-free rotation, and as the heavy top without gravity
    assert np.array_equal(w, sol.rotation(t)[0])
    assert np.array_equal(w, solve_heavy_top(I, [0.0, 0.0, 0.3], np.eye(3), W, gravity=[0, 0, 0])(t)[0])


# -- far times ----------------------------------------------------------------------------------------

def test_far_times_warn_once_and_absurd_times_are_refused():
    import warnings

    sol = solve_rotation(J_TRI, np.zeros((3, 3)), np.eye(3), W0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sol(np.array([0.0, 1e3]))                     # well within float64's reach: silent
        assert caught == []
        sol(1e12)
        sol(np.array([1e12, 2e12]))
    assert len(caught) == 1 and caught[0].category is RuntimeWarning
    assert "relative error of about" in str(caught[0].message) and caught[0].filename == __file__
    expected = 1e12 * np.finfo(float).eps * sol.fastest_frequency()
    assert f"{expected:.1e}" in str(caught[0].message)
    for t in (1e300, -1e300, [0.0, 1e20]):
        with pytest.raises(ValueError, match="too far for float64"):
            sol(t)
    for t in (np.inf, np.nan, [0.0, -np.inf]):
        with pytest.raises(ValueError, match="NaN or inf"):
            sol(t)


@pytest.mark.parametrize("build", [
    lambda: solve_heavy_top([2.7, 2.3, 1.6], [0.0, 0.0, 0.0], np.eye(3), [0.1, 1.0, 0.2]),   # its free rotation
    lambda: solve_rotation([75.6, 97.5, 57.2], np.zeros((3, 3)), np.eye(3), [0.1, 1.0, 0.2]),  # rescaled
    lambda: solve_gyrostat([2.7, 2.3, 1.6], [0.0, 0.0, 1e-14], np.eye(3), [0.1, 1.0, 0.2]),  # the Euler top's
])
def test_a_composite_warns_once_in_its_own_name(build):
    """A solution evaluated through another (the heavy top with its centre at the pivot, a rescaled
    rotation, a gyrostat with a negligible rotor) warns about far times once, naming its own model."""
    import warnings

    sol = build()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sol(1e11)
        sol(np.array([1e11, 2e11]))
    assert len(caught) == 1 and str(caught[0].message).startswith(f"{sol.model}: at |t| = 1e+11")


def test_every_model_has_a_fastest_frequency():
    for name, sol in CLOSED:
        f = sol.fastest_frequency()
        # only a body at rest has no motion whose phase a time error could move
        assert np.isfinite(f) and (f > 0.0 or name.endswith("rest")), name
    assert solve_rotation(J_TRI, np.zeros((3, 3)), np.eye(3), [0.0, 0.0, 2.0]).fastest_frequency() == 2.0


def test_results_page_lists_the_vocabulary():
    """docs/results.md documents every model and method the protocol defines, in its tables."""
    from pathlib import Path

    from thetasol.protocol import METHODS, MODELS

    page = (Path(__file__).parents[1] / "docs" / "results.md").read_text()
    rows = {line.split("|")[1].strip().strip("`") for line in page.splitlines() if line.startswith("| `")}
    assert set(MODELS) <= rows and set(METHODS) <= rows
