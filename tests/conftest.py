"""Shared test configuration.

Hypothesis runs derandomized by default, so that every run (and CI on a fresh clone) checks the
same examples and a failure is reproducible.  To search new examples locally:
``python -m pytest --hypothesis-profile=explore``.
"""
from hypothesis import settings

settings.register_profile("default", derandomize=True, print_blob=True)
settings.register_profile("explore", derandomize=False, print_blob=True)
settings.load_profile("default")
