"""thetasol: exact solutions of integrable rigid-body mechanics (Bogoyavlenskij, CMP 1992).

The public API, grouped by concept.  Names load on first use, so ``import thetasol`` is cheap;
the layers behind them are drawn in docs/architecture.md.  Conventions are fixed once, in
docs/conventions.md.
"""
from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from thetasol._version import __version__

#: public name -> module that defines it, grouped by concept
_API: dict[str, str] = {}


def _group(module: str, *names: str) -> None:
    for n in names:
        _API[n] = module


# the solution protocol and its exceptions
_group("thetasol.protocol", "Solution", "RotationSolution", "ClosedFormUnavailable")
# closed forms, one per physical model
_group("thetasol.solutions.rotation.dispatch", "solve_rotation")
_group("thetasol.solutions.gyrostat", "solve_gyrostat")
_group("thetasol.solutions.points.neumann", "solve_neumann", "NeumannSolution")
_group("thetasol.solutions.tops.heavy_top", "solve_heavy_top")
_group("thetasol.solutions.tops.heavy_top_base", "HeavyTopSolution")
_group("thetasol.solutions.orbit.kepler", "KeplerOrbit", "solve_kepler")
_group("thetasol.solutions.orbit.orbiting_rotation", "solve_orbiting_rotation", "OrbitingRotation")
_group("thetasol.solutions.points.mass_center", "MassCenterMotion", "solve_mass_center")
_group("thetasol.solutions.tops.lagrange_gyrostat", "solve_lagrange_gyrostat")
# mechanics: bodies, configurations, equations and first integrals
_group("thetasol.mechanics.bodies", "Body")
_group("thetasol.mechanics.configuration", "Configuration", "Joint")
_group("thetasol.mechanics.trajectories", "Trajectories")
_group("thetasol.mechanics.constraints", "Sphere", "Pivot")
_group("thetasol.mechanics.rotors", "Rotor", "MasslessCarrier", "GyrostatConfiguration", "EffectiveGyrostat",
       "EffectiveRotor", "gyrostat_energy")
_group("thetasol.core.inertia", "inertia", "second_moments")
_group("thetasol.mechanics.equations", "invariants", "spectral_coefficients", "torque")
_group("thetasol.mechanics.heavy_top", "heavy_top_invariants", "kovalevskaya_integral")
_group("thetasol.mechanics.gravity_gradient", "gravity_gradient_stability", "GravityGradientStability",
       "gravity_gradient_torque", "orbit_frame")
_group("thetasol.mechanics.attitude_control", "lqr_attitude_controller", "AttitudeLQR", "station_controller")
# numerical references
_group("thetasol.integrators.rotation", "integrate_rotation")
_group("thetasol.integrators.multibody", "integrate_multibody")
_group("thetasol.integrators.multibody_gravity", "integrate_multibody_gravity")
_group("thetasol.integrators.orbiting_rotation", "integrate_orbiting_rotation")
_group("thetasol.integrators.heavy_top", "integrate_heavy_top")
_group("thetasol.integrators.neumann", "integrate_neumann")
_group("thetasol.integrators.fixed_point", "integrate_fixed_point")
_group("thetasol.integrators.gyrostat", "integrate_gyrostat", "integrate_heavy_gyrostat")
_group("thetasol.integrators.multibody_rotors", "integrate_gyrostat_multibody")
# scenes: the split pipeline of a whole configuration
_group("thetasol.scenes.format", "Scene", "load_scene", "demo_scene_path")
_group("thetasol.scenes.pipeline", "solve_configuration", "ConfigurationSolution")
_group("thetasol.scenes.report", "run")
_group("thetasol.ensembles", "solve_many")
_group("thetasol.scenes.orbit", "solve_orbiting_configuration", "OrbitingConfigurationSolution")
_group("thetasol.scenes.fixed_point", "solve_fixed_point", "FixedPointSolution")
_group("thetasol.scenes.gyrostat_scene", "solve_gyrostat_configuration", "GyrostatSplit", "load_gyrostat_scene")
# the machinery: theta functions and curves
_group("thetasol.theta.riemann", "RiemannTheta", "riemann_theta", "riemann_theta_separated", "siegel_reduce")
_group("thetasol.theta.grid", "theta_grid", "ThetaGrid")
_group("thetasol.curves.plane_curve", "Numerator", "PlaneCurve", "Place")
_group("thetasol.curves.hyperelliptic", "HyperellipticCurve")
_group("thetasol.curves.protocol", "Curve")
_group("thetasol.curves.spectral", "SpectralCurve", "spectral_curve")

__all__ = sorted(_API) + ["reference", "__version__"]


def __getattr__(name: str):
    if name == "reference":  # the catalogue of exact cases is a subpackage
        return importlib.import_module("thetasol.reference")
    try:
        module = _API[name]
    except KeyError:
        raise AttributeError(f"module 'thetasol' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """The public API only (not the helpers this module imports to load it)."""
    return sorted(__all__)


if TYPE_CHECKING:
    from thetasol import reference
    from thetasol.core.inertia import inertia, second_moments
    from thetasol.curves.hyperelliptic import HyperellipticCurve
    from thetasol.curves.plane_curve import Numerator, Place, PlaneCurve
    from thetasol.curves.protocol import Curve
    from thetasol.curves.spectral import SpectralCurve, spectral_curve
    from thetasol.ensembles import solve_many
    from thetasol.integrators.fixed_point import integrate_fixed_point
    from thetasol.integrators.gyrostat import integrate_gyrostat, integrate_heavy_gyrostat
    from thetasol.integrators.heavy_top import integrate_heavy_top
    from thetasol.integrators.multibody import integrate_multibody
    from thetasol.integrators.multibody_gravity import integrate_multibody_gravity
    from thetasol.integrators.multibody_rotors import integrate_gyrostat_multibody
    from thetasol.integrators.neumann import integrate_neumann
    from thetasol.integrators.orbiting_rotation import integrate_orbiting_rotation
    from thetasol.integrators.rotation import integrate_rotation
    from thetasol.mechanics.attitude_control import AttitudeLQR, lqr_attitude_controller, station_controller
    from thetasol.mechanics.bodies import Body
    from thetasol.mechanics.configuration import Configuration, Joint
    from thetasol.mechanics.constraints import Pivot, Sphere
    from thetasol.mechanics.equations import invariants, spectral_coefficients, torque
    from thetasol.mechanics.gravity_gradient import (
        GravityGradientStability,
        gravity_gradient_stability,
        gravity_gradient_torque,
        orbit_frame,
    )
    from thetasol.mechanics.heavy_top import heavy_top_invariants, kovalevskaya_integral
    from thetasol.mechanics.rotors import (
        EffectiveGyrostat,
        EffectiveRotor,
        GyrostatConfiguration,
        MasslessCarrier,
        Rotor,
        gyrostat_energy,
    )
    from thetasol.mechanics.trajectories import Trajectories
    from thetasol.protocol import ClosedFormUnavailable, RotationSolution, Solution
    from thetasol.scenes.fixed_point import FixedPointSolution, solve_fixed_point
    from thetasol.scenes.format import Scene, demo_scene_path, load_scene
    from thetasol.scenes.gyrostat_scene import GyrostatSplit, load_gyrostat_scene, solve_gyrostat_configuration
    from thetasol.scenes.orbit import OrbitingConfigurationSolution, solve_orbiting_configuration
    from thetasol.scenes.pipeline import ConfigurationSolution, solve_configuration
    from thetasol.scenes.report import run
    from thetasol.solutions.gyrostat import solve_gyrostat
    from thetasol.solutions.orbit.kepler import KeplerOrbit, solve_kepler
    from thetasol.solutions.orbit.orbiting_rotation import OrbitingRotation, solve_orbiting_rotation
    from thetasol.solutions.points.mass_center import MassCenterMotion, solve_mass_center
    from thetasol.solutions.points.neumann import NeumannSolution, solve_neumann
    from thetasol.solutions.rotation.dispatch import solve_rotation
    from thetasol.solutions.tops.heavy_top import solve_heavy_top
    from thetasol.solutions.tops.heavy_top_base import HeavyTopSolution
    from thetasol.solutions.tops.lagrange_gyrostat import solve_lagrange_gyrostat
    from thetasol.theta.grid import ThetaGrid, theta_grid
    from thetasol.theta.riemann import RiemannTheta, riemann_theta, riemann_theta_separated, siegel_reduce
