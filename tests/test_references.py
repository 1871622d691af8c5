"""The numerical references share one contract: the inertia I first, options checked, a Solution returned."""
from __future__ import annotations

import numpy as np
import pytest

from thetasol import (
    KeplerOrbit,
    Solution,
    integrate_fixed_point,
    integrate_gyrostat,
    integrate_heavy_gyrostat,
    integrate_heavy_top,
    integrate_neumann,
    integrate_orbiting_rotation,
    integrate_rotation,
)
from thetasol.core.so3 import rodrigues
from thetasol.protocol import vocabulary_problem

I3 = np.array([2.0, 3.0, 4.0])
A = np.diag([0.3, -0.2, 0.5])
Q0 = rodrigues(np.array([0.3, -0.2, 0.4]))
W0 = np.array([0.4, -0.3, 0.7])
ORBIT = KeplerOrbit(1.0, [1.0, 0.0, 0.0], [0.0, 1.05, 0.1])

REFERENCES = {
    "rotation": lambda **kw: integrate_rotation(I3, A, Q0, W0, **kw),
    "gyrostat": lambda **kw: integrate_gyrostat(I3, [0.1, 0.2, -0.3], Q0, W0, a=A, **kw),
    "heavy-top with rotors": lambda **kw: integrate_heavy_gyrostat(I3, [0.0, 0.1, 0.5], Q0, W0, N=[0.0, 0.0, 0.4],
                                                                   **kw),
    "heavy-top": lambda **kw: integrate_heavy_top(I3, [0.0, 0.1, 0.5], Q0, W0, mass=2.0, **kw),
    "orbiting-rotation": lambda **kw: integrate_orbiting_rotation(I3, ORBIT, Q0, W0, **kw),
    "neumann": lambda **kw: integrate_neumann(A, [0.6, 0.0, 0.8], [0.0, 0.5, 0.0], **kw),
    "fixed-point": lambda **kw: integrate_fixed_point(I3, [0.0, 0.2, 0.1], A, [0.0, 0.0, 0.3], Q0, W0, **kw),
}


@pytest.mark.parametrize("model", sorted(REFERENCES))
def test_every_reference_is_a_solution_of_its_model(model):
    sol = REFERENCES[model](rtol=1e-10)
    assert isinstance(sol, Solution)
    assert sol.model == model.split(" ")[0] and sol.method == "numerical/DOP853"
    assert sol.diagnostics["error_estimate"] == 1e-10 and sol.diagnostics["integrator"] == "DOP853"
    assert vocabulary_problem(sol.model, sol.method) == ""
    t = np.array([[0.0, 0.5], [-0.25, 1.0]])
    out = sol(t)
    assert all(x.shape[:2] == (2, 2) for x in out)
    first = sol(0.0)                                   # t = 0 is the initial state itself
    start = (Q0, W0) if model != "neumann" else (np.array([0.6, 0.0, 0.8]), np.array([0.0, 0.5, 0.0]))
    if model != "neumann":
        assert np.allclose(first[1], start[0], atol=1e-15) and np.allclose(first[0], start[1], atol=1e-15)
    else:
        assert np.allclose(first[0], start[0], atol=1e-15) and np.allclose(first[1], start[1], atol=1e-15)
    for k in range(2):                                 # one integration over all times, any order
        assert np.allclose(out[k][1, 1], sol(1.0)[k], rtol=0, atol=1e-9)


@pytest.mark.parametrize("model", sorted(REFERENCES))
def test_an_option_the_method_ignores_is_refused(model):
    make = REFERENCES[model]
    with pytest.raises(ValueError, match="method must be one of"):
        make(method="Euler")
    with pytest.raises(ValueError, match="rtol"):
        make(rtol=1.5)
    with pytest.raises(ValueError, match="rtol"):
        make(rtol="1e-10")
    with pytest.raises((ValueError, TypeError), match="step"):
        make(step=0.01)
    if model != "neumann":
        with pytest.raises((ValueError, TypeError), match="fp_type"):
            make(fp_type=np.longdouble)


def test_splitting_and_heyoka_refuse_what_they_ignore():
    with pytest.raises(ValueError, match="atol"):
        integrate_rotation(I3, A, Q0, W0, method="splitting", atol=1e-12)
    with pytest.raises(ValueError, match="step"):
        integrate_rotation(I3, A, Q0, W0, method="DOP853", step=0.01)
    with pytest.raises(ValueError, match="fp_type"):
        integrate_rotation(I3, A, Q0, W0, method="splitting", fp_type=np.longdouble)
    with pytest.raises(ValueError, match="atol"):
        integrate_heavy_top(I3, [0.0, 0.1, 0.5], Q0, W0, method="heyoka", atol=1e-12)
    with pytest.raises(ValueError, match="method"):
        integrate_heavy_top(I3, [0.0, 0.1, 0.5], Q0, W0, method="splitting")
    with pytest.raises(ValueError, match="heyoka"):
        integrate_gyrostat(I3, [0.1, 0.2, -0.3], Q0, W0, orbit=ORBIT, method="heyoka")
    sol = integrate_rotation(I3, A, Q0, W0, method="splitting", step=0.01)
    assert sol.diagnostics["step"] == 0.01 and sol.model == "rotation"


def test_second_moments_given_as_inertia_are_refused_when_unphysical():
    """I violating a triangle inequality (second moments J = [1, 1, 3] passed by mistake): refused with the
    message the closed forms give, naming the mix-up and its conversion."""
    for call in (lambda: integrate_rotation([1.0, 1.0, 3.0], A, Q0, W0),
                 lambda: integrate_heavy_top([1.0, 1.0, 3.0], [0.0, 0.0, 1.0], Q0, W0),
                 lambda: integrate_orbiting_rotation([1.0, 1.0, 3.0], ORBIT, Q0, W0)):
        with pytest.raises(ValueError, match=r"triangle.*look like second moments.*thetasol\.inertia\(J\)"):
            call()


class _Tabulated:
    """An orbit that is not a KeplerOrbit: the members of the Orbit protocol, delegated."""

    def __init__(self, orbit):
        self._o = orbit
        self.mu, self.r0, self.v0, self.diagnostics = orbit.mu, orbit.r0, orbit.v0, orbit.diagnostics

    def state_at(self, t):
        return self._o.state_at(t)

    def __call__(self, t):
        return self._o(t)


def test_the_orbit_is_any_object_with_the_members_the_references_use():
    t = np.array([0.5, 2.0])
    ref = integrate_orbiting_rotation(I3, ORBIT, Q0, W0, rtol=1e-10)(t)
    other = integrate_orbiting_rotation(I3, _Tabulated(ORBIT), Q0, W0, rtol=1e-10)(t)
    assert all(np.array_equal(x, y) for x, y in zip(ref, other, strict=True))
    g1 = integrate_gyrostat(I3, [0.1, 0.2, -0.3], Q0, W0, orbit=ORBIT, rtol=1e-10)(t)
    g2 = integrate_gyrostat(I3, [0.1, 0.2, -0.3], Q0, W0, orbit=_Tabulated(ORBIT), rtol=1e-10)(t)
    assert all(np.array_equal(x, y) for x, y in zip(g1, g2, strict=True))
    with pytest.raises(TypeError, match="state_at"):
        integrate_orbiting_rotation(I3, (ORBIT.r0, ORBIT.v0), Q0, W0)
