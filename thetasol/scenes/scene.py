"""The scene layer's public names in one place, for ``thetasol/__init__.py``.

The code lives in :mod:`thetasol.scenes.format` (scene files), :mod:`thetasol.scenes.pipeline`
(the split) and :mod:`thetasol.scenes.report` (the report); import from those.
"""
from thetasol.scenes.format import Scene, demo_scene_path, load_scene
from thetasol.scenes.pipeline import ConfigurationSolution, rotation_kind, solve_configuration
from thetasol.scenes.report import Check, run

__all__ = ["Scene", "load_scene", "demo_scene_path", "ConfigurationSolution", "solve_configuration",
           "rotation_kind", "Check", "run"]
