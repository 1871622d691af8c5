"""Section 7: the orbiting station.

* :mod:`~thetasol.solutions.orbit.kepler`: the Kepler orbit of the system's mass centre (7.7);
* :mod:`~thetasol.solutions.orbit.orbiting_rotation`: the closed-form rotations of a body in the orbit's
  gravity gradient.
"""
