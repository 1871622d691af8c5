"""thetasol: exact solutions of integrable rigid-body mechanics (Bogoyavlenskij, CMP 1992).

The pipeline, one module per concept:

mechanics (:mod:`thetasol.bodies`, :mod:`thetasol.configuration`)
  -> equations and invariants (:mod:`thetasol.equations`)
  -> numerical reference (:mod:`thetasol.integrate`)
  -> curves, theta and elliptic functions
  -> closed-form solutions, one per physical model.

Conventions are fixed once, in docs/conventions.md.
"""
from .equations import invariants, spectral_coefficients, torque
from .integrate import integrate_rotation
from .rotation import RotationSolution, solve_rotation

__all__ = ["integrate_rotation", "invariants", "spectral_coefficients", "torque",
           "RotationSolution", "solve_rotation"]
__version__ = "0.1.0"
