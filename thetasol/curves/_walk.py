"""The fast walk of the tracker's matching pass (:meth:`thetasol.curves._quad.Tracker._match_pass`).

The matching tests of every step are computed beforehand for every root a track may hold at the
previous node; where every step then passes them (the usual case) the walk along the tracks only
picks entries, two numpy calls per step, and the tests are checked for all steps at once.
"""
from __future__ import annotations

import numpy as np


def walk_safe(choice, I, SAFE, pos, nact, tt, kk, tq, n) -> bool:
    """The walk of :meth:`Tracker._match_pass` when every step is safe (the usual case), in two numpy
    calls per step instead of ten: fills ``choice`` and returns True if then every step passed both
    tests (safe, and no two tracks of a piece on one root), else False (``choice`` to be redone)."""
    for k in range(1, choice.shape[1]):
        na = int(nact[k])
        if na == 0:
            break
        choice[:na, k] = I[choice[:na, k - 1], pos[:na, k]]
    c, i = choice[tt, kk], choice[tt, kk + 1]
    if not SAFE[c, np.arange(len(tt))].all():
        return False
    key = (kk * (int(tq.max(initial=0)) + 1) + tq[tt]) * (n + 1) + i
    return bool((np.bincount(key)[key] == 1).all())
