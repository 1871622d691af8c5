"""The vector of Riemann constants: the one rule that picks it among its 2^(2g) candidates.

``2K = -A(C)`` for a canonical divisor ``C`` fixes ``K`` up to a half period; the half period is the one
with ``theta(K + A(D)) = 0`` for every effective divisor ``D`` of degree ``g - 1`` (Riemann's vanishing
theorem; the algorithm of Deconinck and van Hoeij, Physica D 152-153 (2001) 28-46, as in abelfunctions'
``RiemannConstantVector``).  :func:`riemann_constant_vector` applies it for every curve of the library
(:class:`~thetasol.curves.plane_curve.PlaneCurve`, :class:`~thetasol.curves.hyperelliptic.HyperellipticCurve`
and the spectral curves of the theta-function rotation) with one acceptance rule, on test divisors built
from one fixed table of points (:data:`TEST_POINTS`, :func:`test_abscissae`): no random generator, so
the choice is the same in every run and on every machine.

The rule.  A candidate's score is the largest ``|theta(K + A(D))| exp(-pi y^T (Im tau)^-1 y)`` over the
test divisors (the exponent-separated size: lattice periodic and bounded).  The smallest score wins
when it is below :data:`VANISH` and the runner-up's is above both :data:`VANISH` and
:data:`SEPARATION` times it (the runner-up does not vanish by the test that makes the winner vanish).
When no set of test divisors decides, the smallest of the last set is taken if the runner-up vanishes
too: on a nearly pinched cycle two candidates differ by ``exp(-pi Im tau_jj / 4)`` and both vanish to
the accuracy of the Abel images.  Anything else is a ``RuntimeError`` (a nearly degenerate curve).
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from thetasol.theta.riemann import RiemannTheta, riemann_theta_separated

__all__ = ["FOLD_POINTS", "PRUNE", "SEPARATION", "TEST_POINTS", "VANISH", "half_period_candidates", "riemann_constant_vector",
           "test_abscissae", "theta_normalized_abs"]

#: theta at the right candidate vanishes to the accuracy of the Abel images: the rounding level, 1e-10..1e-9
#: on nearly degenerate curves; a score below this vanishes.
VANISH = 1e-8
#: A runner-up at least this many times the best score does not vanish by the same test.
SEPARATION = 10.0
#: Candidates scoring above this at the first test divisor can be neither chosen nor the runner-up that
#: decides (both need a score below VANISH or above SEPARATION x the best): the other divisors skip them.
PRUNE = 1e-7
#: Points (candidates x test divisors) up to which all are evaluated in one theta call: a call's fixed cost
#: exceeds that of these points, so one call beats the pruned two.
FOLD_POINTS = 64

#: The points of the test divisors, one per row, for up to three divisors of degree g - 1 <= 7:
#: ``(radius fraction, turn, sheet index)`` (uniform, uniform, one of three: pseudo-random draws kept as
#: data, so that the choice does not depend on numpy's generator streams).
TEST_POINTS = (
    (0.625095466604667, 0.8972138009695755, 1),
    (0.22520718999059186, 0.30016628491122543, 2),
    (0.8735534453962619, 0.005265304565574724, 1),
    (0.7970694287520462, 0.4679349528437208, 2),
    (0.3030324268193135, 0.2784256121007733, 2),
    (0.4450763058826466, 0.5045482589579533, 0),
    (0.5534973520744925, 0.9955002834343927, 2),
    (0.6221792294411627, 0.9889601476818849, 2),
    (0.21530869823559895, 0.16021203385784455, 2),
    (0.04394200796138337, 0.03568027877359614, 1),
    (0.5148888202713703, 0.4662060253252891, 2),
    (0.6292262544910104, 0.5141176465995139, 2),
    (0.49687343539350426, 0.24751492202733083, 2),
    (0.19240214398531064, 0.6920321208818392, 0),
    (0.2006067239869952, 0.3695363106022067, 1),
    (0.8300477298017456, 0.15446108106143985, 0),
    (0.26759930456378545, 0.8803321539808286, 0),
    (0.8471502463658693, 0.6397171669425262, 1),
    (0.7417709473618571, 0.09149560506304566, 0),
    (0.50777223630035, 0.8713393766928806, 1),
    (0.3612640590141576, 0.5981840672072131, 0),
)


def test_abscissae(center: complex, radius: float, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """The points of three test divisors of the given degree from :data:`TEST_POINTS`.

    Returns ``x`` (complex, shape (3, degree)) on the annulus ``0.3 <= |x - center| / radius <= 0.8`` and
    the sheet index of each point (shape (3, degree), 0..2; callers with ``n`` sheets take it modulo
    ``n``).  The caller lifts each ``x`` to the curve on that sheet.
    """
    if 3 * degree > len(TEST_POINTS):
        raise ValueError(f"the table of test points covers divisors of degree <= {len(TEST_POINTS) // 3}, "
                         f"got {degree}")
    rows = TEST_POINTS[:3 * degree]
    x = [center + radius * (0.3 + 0.5 * r) * np.exp(2j * np.pi * turn) for r, turn, _ in rows]
    return np.array(x, complex).reshape(3, degree), np.array([k for *_, k in rows], int).reshape(3, degree)


def theta_normalized_abs(z: ArrayLike, tau: np.ndarray, tol: float = 1e-14) -> np.ndarray:
    """|theta(z)| exp(-pi y^T Y^-1 y) for z of shape (N, g): lattice periodic, bounded; for zero tests."""
    tau = np.asarray(tau, dtype=complex)
    return np.abs(riemann_theta_separated(np.atleast_2d(np.asarray(z, dtype=complex)), 0.5 * (tau + tau.T),
                                          tol=tol)[1])


def half_period_candidates(canonical_image: ArrayLike, tau: np.ndarray) -> np.ndarray:
    """The 4^g half-period translates ``-A(C)/2 + (a + tau b)/2``, ``a, b`` in ``{0, 1}^g``, shape (4^g, g)."""
    AC = np.asarray(canonical_image, complex)
    g = len(AC)
    bits = (np.arange(2 ** g)[:, None] >> np.arange(g)[None, :]) & 1
    a_, b_ = np.repeat(bits, 2 ** g, axis=0), np.tile(bits, (2 ** g, 1))
    return -0.5 * AC + 0.5 * a_ + 0.5 * (b_ @ tau.T)


def _scores(theta: RiemannTheta, cands: np.ndarray, ADs: np.ndarray) -> np.ndarray:
    """max over the test divisors of the separated |theta(cand + A(D))|.

    Up to :data:`FOLD_POINTS` points (genus 2: 16 candidates at 4 divisors) every candidate at every
    divisor, in one call; above, every candidate at the first divisor and the candidates within
    :data:`PRUNE` at the others, in a second call.  The choice is the same: a pruned candidate's score
    is above PRUNE either way, so it is never the best and always a separated runner-up.
    """
    g = cands.shape[1]
    if len(cands) * len(ADs) <= FOLD_POINTS:
        z = (cands[None, :, :] + ADs[:, None, :]).reshape(-1, g)
        return np.abs(theta.separated(z)[1]).reshape(len(ADs), len(cands)).max(axis=0)
    score = np.abs(theta.separated(cands + ADs[0][None, :])[1])
    live = np.flatnonzero(score <= PRUNE)
    if len(ADs) > 1 and len(live):
        z = (cands[live][None, :, :] + ADs[1:, None, :]).reshape(-1, g)
        v = np.abs(theta.separated(z)[1]).reshape(len(ADs) - 1, len(live))
        score[live] = np.maximum(score[live], v.max(axis=0))
    return score


def riemann_constant_vector(tau: np.ndarray, canonical_image: ArrayLike, divisor_images: Sequence[ArrayLike] | np.ndarray,
                            *, theta: RiemannTheta | None = None, final: bool = True) -> np.ndarray | None:
    """The vector of Riemann constants by the rule of the module docstring.

    Parameters
    ----------
    tau : ndarray, shape (g, g)
        Riemann matrix.
    canonical_image : array_like, shape (g,)
        Abel image ``A(C)`` of a canonical divisor (normalized coordinates, the base of ``K``).
    divisor_images : array_like, shape (n, g)
        Abel images of ``n >= 1`` effective divisors of degree ``g - 1`` (same base; ``(g - 1)`` times
        the base point has image 0).
    theta : RiemannTheta, optional
        A theta of ``tau`` to reuse (its set-up is most of the cost).
    final : bool
        False: return None instead of accepting a near tie or raising, so that the caller can test
        other divisors.

    Returns
    -------
    ndarray, shape (g,), or None
        ``K`` in normalized coordinates.

    Raises
    ------
    RuntimeError
        (``final``) No candidate makes theta vanish unambiguously (a nearly degenerate curve).
    """
    tau = np.asarray(tau, complex)
    theta = RiemannTheta(tau) if theta is None else theta
    ADs = np.atleast_2d(np.asarray(divisor_images, complex))
    cands = half_period_candidates(canonical_image, tau)
    score = _scores(theta, cands, ADs)
    order = np.argsort(score)
    best, second = score[order[0]], score[order[1]]
    if best < VANISH and second > max(VANISH, SEPARATION * best):
        return cands[order[0]]
    if not final:
        return None
    if best < VANISH and second < VANISH:
        return cands[order[0]]
    raise RuntimeError(f"Riemann constant: no half-period candidate makes theta vanish unambiguously "
                       f"(best {best:.2g}, next {second:.2g}); nearly degenerate curve?")
