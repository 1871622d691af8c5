"""The version, read by ``pyproject.toml`` (the single source)."""

__version__ = "0.1.0"
