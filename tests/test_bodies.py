"""Rigid bodies (thetasol.mechanics.bodies) against brute-force sums over point masses."""
import numpy as np
import pytest

from thetasol.mechanics.bodies import Body, principal_axes


def random_points(rng, n=7):
    return rng.uniform(0.2, 3.0, n), rng.normal(size=(n, 3)) + rng.normal(size=3)


def test_point_masses_give_mass_centre_and_second_moments():
    rng = np.random.default_rng(0)
    m, r = random_points(rng)
    b = Body.from_point_masses(m, r, name="p")
    c = sum(mk * rk for mk, rk in zip(m, r)) / m.sum()
    # Inertia about the mass centre summed the textbook way, then J = tr(I)/2 - I (2.9).
    I = sum(mk * ((rk - c) @ (rk - c) * np.eye(3) - np.outer(rk - c, rk - c)) for mk, rk in zip(m, r))
    assert b.mass == pytest.approx(m.sum(), rel=1e-15)
    assert np.allclose(b.center, c, rtol=0, atol=1e-14)
    assert np.allclose(b.I, I, rtol=0, atol=1e-13)
    assert np.allclose(b.J, 0.5 * np.trace(I) * np.eye(3) - I, rtol=0, atol=1e-13)


def test_J_and_I_are_interchangeable():
    rng = np.random.default_rng(1)
    m, r = random_points(rng)
    b = Body.from_point_masses(m, r)
    b2 = Body(mass=b.mass, I=b.I, center=b.center)
    assert np.allclose(b2.J, b.J, atol=1e-13)
    b3 = Body(mass=2.0, I=[3.0, 4.0, 5.0])
    assert np.allclose(np.diag(b3.J), [3.0, 2.0, 1.0])  # J_i = (I_j + I_k - I_i) / 2


def test_box_matches_a_midpoint_grid():
    # Midpoint rule over n cells of x^2 on [-s/2, s/2] is exactly s^2/12 (1 - 1/n^2).
    n, size, mass = 6, np.array([1.0, 2.0, 0.5]), 3.0
    g = [(np.arange(n) + 0.5) / n * s - s / 2 for s in size]
    pts = np.stack(np.meshgrid(*g, indexing="ij"), -1).reshape(-1, 3) + [0.3, -0.2, 0.1]
    grid = Body.from_point_masses(np.full(n**3, mass / n**3), pts)
    box = Body.box(mass, size, center=[0.3, -0.2, 0.1])
    assert np.allclose(grid.J, box.J * (1 - 1 / n**2), atol=1e-14)
    assert np.allclose(grid.center, box.center, atol=1e-14)


def test_parallel_axes():
    rng = np.random.default_rng(2)
    m, r = random_points(rng)
    b = Body.from_point_masses(m, r)
    p = rng.normal(size=3)
    direct = sum(mk * np.outer(rk - p, rk - p) for mk, rk in zip(m, r))
    assert np.allclose(b.second_moments_about(p), direct, atol=1e-12)


@pytest.mark.parametrize("seed", range(5))
def test_principal_axes_right_handed_and_diagonalizing(seed):
    rng = np.random.default_rng(seed)
    m, r = random_points(rng)
    b = Body.from_point_masses(m, r)
    vals, A = b.principal()
    assert np.linalg.det(A) == pytest.approx(1.0, abs=1e-14)
    assert np.allclose(A @ np.diag(vals) @ A.T, b.J, atol=1e-13)
    assert np.all(np.diff(vals) >= 0)
    # Documented sign convention: the largest component of the first two axes is positive.
    for k in (0, 1):
        assert A[np.argmax(np.abs(A[:, k])), k] > 0
    vals2, A2 = principal_axes(-b.J)  # works on any symmetric tensor
    assert np.allclose(A2 @ np.diag(vals2) @ A2.T, -b.J, atol=1e-13)


def test_plate_allowed_and_arrays_read_only():
    b = Body.box(1.0, [1.0, 2.0, 0.0])
    assert np.isclose(b.J[2, 2], 0.0)
    with pytest.raises(ValueError):
        b.J[0, 0] = 3.0
    with pytest.raises(AttributeError):
        b.mass = 2.0


@pytest.mark.parametrize("kwargs, match", [
    (dict(mass=0.0, J=[1, 1, 1]), "mass"),
    (dict(mass=-1.0, J=[1, 1, 1]), "mass"),
    (dict(mass=float("nan"), J=[1, 1, 1]), "NaN"),
    (dict(mass=1.0, J=[1, float("inf"), 1]), "NaN or inf"),
    (dict(mass=1.0, J=[1, -0.1, 1]), "not physical"),
    (dict(mass=1.0, I=[1.0, 1.0, 3.0]), "not physical"),          # triangle inequality I3 > I1 + I2
    (dict(mass=1.0, I=[1.0, -1.0, 1.0]), "positive definite"),
    (dict(mass=1.0, J=[1.0, 0.0, 0.0]), "rod"),
    (dict(mass=1.0, J=[[1, 0.2, 0], [0, 1, 0], [0, 0, 1]]), "symmetric"),
    (dict(mass=1.0, J=[1, 2]), "shape"),
    (dict(mass=1.0), "exactly one"),
    (dict(mass=1.0, J=[1, 1, 1], I=[1, 1, 1]), "exactly one"),
    (dict(mass=1.0, J=[1, 1, 1], center=[0, 0]), "shape"),
    (dict(mass="heavy", J=[1, 1, 1]), "numeric"),
])
def test_bad_bodies(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Body(**kwargs)


def test_bad_point_masses():
    with pytest.raises(ValueError, match="rod"):
        Body.from_point_masses([1, 1, 1], [[0, 0, 0], [1, 1, 1], [2, 2, 2]])  # collinear
    with pytest.raises(ValueError, match="positive"):
        Body.from_point_masses([1, -1, 1], np.eye(3))
    with pytest.raises(ValueError, match="shape"):
        Body.from_point_masses([1, 1], np.eye(3))
