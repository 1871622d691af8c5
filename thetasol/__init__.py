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
from .theta import RiemannTheta, riemann_theta, riemann_theta_separated, siegel_reduce
from .rotation import ClosedFormUnavailable, RotationSolution, solve_rotation
from .gyrostat import solve_gyrostat

__all__ = ["integrate_rotation", "invariants", "spectral_coefficients", "torque",
           "RiemannTheta", "riemann_theta", "riemann_theta_separated", "siegel_reduce",
           "RotationSolution", "solve_rotation", "solve_gyrostat", "ClosedFormUnavailable"]
# mechanics of C^k-central configurations (issue 2)
from .bodies import Body  # noqa: E402
from .configuration import Configuration, Joint, Trajectories  # noqa: E402
from .masscenter import MassCenterMotion, mass_center  # noqa: E402
from .multibody import integrate_multibody  # noqa: E402
from .scene import Scene, load_scene, run, solve_configuration  # noqa: E402
__all__ += ["Body", "Configuration", "Joint", "Trajectories", "MassCenterMotion", "mass_center",
            "integrate_multibody", "Scene", "load_scene", "run", "solve_configuration"]
# algebraic curves: periods, Abel map, Riemann constant, spectral curve (4.12) (issue 4)
from .curves import Place, PlaneCurve  # noqa: E402
from .spectral import SpectralCurve, spectral_curve  # noqa: E402
__all__ += ["PlaneCurve", "Place", "SpectralCurve", "spectral_curve"]
__version__ = "0.1.0"
