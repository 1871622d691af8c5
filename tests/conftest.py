"""Shared test configuration.

Hypothesis runs derandomized by default, so that every run (and CI on a fresh clone) checks the
same examples and a failure is reproducible.  To search new examples locally:
``python -m pytest --hypothesis-profile=explore``.
"""
from hypothesis import settings

settings.register_profile("default", derandomize=True, print_blob=True)
settings.register_profile("explore", derandomize=False, print_blob=True)
settings.load_profile("default")


# -- helpers shared by the rigid-body tests (import them: ``from conftest import rand_Q``) -----

def rand_Q(rng):
    """A random rotation (QR of a Gaussian matrix, reflected into SO(3))."""
    import numpy as np

    Q = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    return Q * np.linalg.det(Q)


def inertia(J):
    """``I = tr(J) 1 - J`` from principal second moments (shape (3,)) or a tensor."""
    import numpy as np

    J = np.diag(J) if np.ndim(J) == 1 else np.asarray(J)
    return np.trace(J) * np.eye(3) - J


def label(sol):
    """``method`` and, when there is one, ``case``: ``"elliptic"``, ``"elliptic:separatrix"``."""
    return sol.method + (f":{sol.case}" if sol.case else "")
