"""The gravity-gradient torque of Section 7 and the linear stability of the orbit-aligned attitude.

Torque.  The tidal potential of a body of second moments ``J`` at ``r`` from a point mass
(``mu = G m0``) is, to order ``|x|^2 / |r|^2`` (the corrected (7.3)-(7.8), docs/orbiting_station.md),
``V = -(mu / 2 |r|^3) tr((3 g g^T - 1) Q J Q^T)`` with ``g = r / |r|``: the quadratic potential
(2.4) with ``a = -3 mu g g^T / |r|^3`` (7.11) up to an isotropic part that exerts no torque.  Its
body-frame torque is the vector form of (7.16),

    tau = 3 mu / |r|^5  (Q^T r) x I (Q^T r),        I = tr(J) 1 - J.

(The matrix forms (7.15) with the paper's definitions give the opposite sign; the vector form is the
physical one, checked against point masses in tests/test_orbiting_rotation.py.)

Orbit frame.  Columns ``(e_r, e_t, e_n)``: radial ``r/|r|``, orbit normal ``r x v / |r x v|``,
along-track ``e_n x e_r`` (the velocity direction on a circular orbit).  On a circular orbit of
mean motion ``n`` it turns at ``n e_n``.

Linear stability (Hughes, *Spacecraft Attitude Dynamics*, ch. 9; DeBra & Delp 1961).  Principal
axes ``1, 2, 3`` along ``e_r, e_t, e_n`` (radial = yaw, along-track = roll, normal = pitch), the
body turning with the orbit frame.  Linearizing ``I wdot + w x I w = 3 n^2 g x I g`` in small
angles about the body axes gives, with ``k1 = (I3 - I1)/I2``, ``k3 = (I3 - I2)/I1`` (the standard
``k_1 = (I_pitch - I_yaw)/I_roll``, ``k_3 = (I_pitch - I_roll)/I_yaw``):

    pitch:      theta3'' + 3 n^2 (I2 - I1)/I3 theta3 = 0
    roll-yaw:   s^4 + n^2 (1 + 3 k1 + k1 k3) s^2 + 4 n^4 k1 k3 = 0

(derived in docs/orbiting_station.md; the middle coefficient is ``4 k1 + k3 + (1 - k1)(1 - k3)``).
The attitude is linearly stable iff ``I2 > I1`` (pitch), ``k1 k3 > 0``, ``1 + 3 k1 + k1 k3 > 0`` and
``(1 + 3 k1 + k1 k3)^2 > 16 k1 k3``; with ``I3 > I2 > I1`` (Lagrange region, the potential's minimum)
all hold; the rest of the stable set (``k1, k3 < 0``) is the DeBra-Delp region (gyroscopic
stability only).  The frequencies agree with the eigenvalues of the finite-difference Jacobian of
the full equations (central differences in 40-digit mpmath) to rounding, on bodies in the three
regions (tests/test_gravity_gradient.py).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.inertia import second_moments
from thetasol.core.so3 import cross

__all__ = ["gravity_gradient_torque", "orbit_frame", "GravityGradientStability", "gravity_gradient_stability",
           "gravity_gradient_stability_from_moments"]


def gravity_gradient_torque(I: ArrayLike, Q: np.ndarray, r: np.ndarray, mu: float) -> np.ndarray:  # noqa: E741
    """Body-frame torque ``3 mu / |r|^5 (Q^T r) x I (Q^T r)`` (7.16) on a body of inertia tensor ``I``.

    The vector form (7.16) is written in the inertia itself, so ``I`` is used as given (no conversion).

    Parameters
    ----------
    I : array_like, shape (3,) or (3, 3)
        Inertia tensor in the body frame: three principal values or a symmetric 3x3.
    Q : ndarray, shape (..., 3, 3)
        Attitude, body to space.
    r : ndarray, shape (..., 3)
        Position of the mass centre relative to the attracting centre (space frame).
    mu : float
        Gravitational parameter.

    Returns
    -------
    ndarray, shape ``broadcast(Q.shape[:-2], r.shape[:-1]) + (3,)``
    """
    I = np.asarray(I, dtype=float)  # noqa: E741
    if I.shape == (3,):
        I = np.diag(I)  # noqa: E741
    elif I.shape != (3, 3):
        raise ValueError(f"I must be 3 principal values or a 3x3 tensor, got shape {I.shape}")
    rb = np.einsum("...ji,...j->...i", Q, r)             # Q^T r
    rn2 = np.sum(r * r, axis=-1)[..., None]
    return 3.0 * mu / (rn2 * rn2 * np.sqrt(rn2)) * cross(rb, rb @ I.T)


def orbit_frame(r: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The orbit frame, columns ``(radial, along-track, normal)``; shape ``r.shape[:-1] + (3, 3)``."""
    r = np.asarray(r, dtype=float)
    h = cross(r, np.asarray(v, dtype=float))
    er = r / np.linalg.norm(r, axis=-1, keepdims=True)
    en = h / np.linalg.norm(h, axis=-1, keepdims=True)
    return np.stack([er, cross(en, er), en], axis=-1)


@dataclass(frozen=True)
class GravityGradientStability:
    """Linear stability of the orbit-aligned attitude on a circular orbit (module docstring).

    Attributes
    ----------
    stable : bool
        All six eigenvalues on the imaginary axis and distinct from 0 (strict inequalities).
    region : str
        ``"lagrange"`` (``I3 > I2 > I1``), ``"debra-delp"`` (stable with ``k1, k3 < 0``),
        ``"marginal"`` (on a boundary: an inequality holds with equality, e.g. a body symmetric
        about the radial axis, which has a zero frequency) or ``"unstable"``.
    pitch_frequency : float
        ``n sqrt(3 (I2 - I1)/I3)`` (``nan`` when the pitch motion is unstable).
    roll_yaw_frequencies : tuple of float
        The two roll-yaw frequencies, ascending (``nan`` where unstable).
    eigenvalues : ndarray, shape (6,)
        The eigenvalues of the linearized motion (complex), from the formulas.
    k1, k3 : float
        ``(I3 - I1)/I2`` and ``(I3 - I2)/I1``.
    inertia : ndarray, shape (3,)
        Principal moments ``I = tr(J) - J`` in the order radial, along-track, normal.
    mean_motion : float
    """

    stable: bool
    region: str
    pitch_frequency: float
    roll_yaw_frequencies: tuple
    eigenvalues: np.ndarray
    k1: float
    k3: float
    inertia: np.ndarray
    mean_motion: float

    @property
    def periods(self) -> dict:
        """``{"pitch": 2 pi / w_p, "roll_yaw": (2 pi / w_1, 2 pi / w_2)}`` (``inf`` for a zero frequency)."""
        def per(w):
            return 2 * math.pi / w if w > 0 else (math.inf if w == 0 else math.nan)
        return {"pitch": per(self.pitch_frequency), "roll_yaw": tuple(per(w) for w in self.roll_yaw_frequencies)}


def _roll_yaw_roots(b: float, c: float, n: float):
    """The two roots x = s^2 of x^2 + n^2 b x + 4 n^4 c (complex when the discriminant is negative)."""
    disc = b * b - 16.0 * c
    sq = complex(math.sqrt(disc)) if disc >= 0 else 1j * math.sqrt(-disc)
    # the larger root without cancellation, the other from the product 4 c n^4
    big = -0.5 * (b + (sq if b >= 0 else -sq))
    small = (4.0 * c / big) if big != 0 else 0.0
    return [n * n * big, n * n * small]


def gravity_gradient_stability(I: ArrayLike, mean_motion: float) -> GravityGradientStability:  # noqa: E741
    """Linear stability of a body on a circular orbit with its principal axes along the orbit frame.

    Parameters
    ----------
    I : array_like, shape (3,)
        Principal moments of inertia in the order axis 1 radial, axis 2 along-track, axis 3 orbit
        normal.  Converted once to the paper's second moments ``J = tr(I)/2 - I``
        (:func:`thetasol.second_moments`) for :func:`gravity_gradient_stability_from_moments`.
    mean_motion : float
        ``n = sqrt(mu / R^3)`` of the circular orbit (> 0), in the user's time unit.

    Returns
    -------
    GravityGradientStability

    Examples
    --------
    >>> s = gravity_gradient_stability([1.75, 0.75, 2.0], 1.0)   # I3 > I1 > I2
    >>> s.region, s.stable
    ('unstable', False)
    >>> s = gravity_gradient_stability([1.0, 1.5, 2.0], 1.0)
    >>> s.region, round(s.pitch_frequency, 6), [round(w, 6) for w in s.roll_yaw_frequencies]
    ('lagrange', 0.866025, [0.681774, 1.69367])
    """
    Iv = V.finite_array(I, "I", (3,))
    V.inertia(Iv, "I")                       # a physical inertia, or the message naming a J passed as I
    return gravity_gradient_stability_from_moments(second_moments(Iv), mean_motion)


def gravity_gradient_stability_from_moments(J: ArrayLike, mean_motion: float) -> GravityGradientStability:
    """:func:`gravity_gradient_stability` of a body given by its principal second moments ``J = sum m r r^T``.

    The paper's convention (``I = tr(J) - J``), for the callers inside thetasol that hold ``J``; same
    axes, result and checks.
    """
    Jv = V.finite_array(J, "J", (3,))
    if np.any(Jv < 0) or not np.sum(Jv) > 0:
        raise ValueError(f"J must be three principal second moments >= 0 with a positive sum, got {Jv}")
    n = float(V.finite_array(mean_motion, "mean_motion", ()))
    if not n > 0:
        raise ValueError(f"mean_motion must be positive, got {n}")
    I = np.sum(Jv) - Jv
    if np.any(I <= 0):
        raise ValueError(f"the inertia I = tr(J) - J = {I} has a zero moment (a rod or a point): "
                         "the stability is a limit, take the rod as J = (L^2, w, w) with small w")
    I1, I2, I3 = (float(x) for x in I)
    k1, k3 = (I3 - I1) / I2, (I3 - I2) / I1
    p2 = 3.0 * n * n * (I2 - I1) / I3
    b, c = 1.0 + 3.0 * k1 + k1 * k3, k1 * k3
    xs = _roll_yaw_roots(b, c, n)
    sp = complex(0.0, math.sqrt(p2)) if p2 >= 0 else complex(math.sqrt(-p2), 0.0)
    eig = [sp, -sp]
    for x in xs:
        s = complex(x) ** 0.5
        eig += [s, -s]
    eig = np.array(eig)
    pitch_ok, roll_yaw_ok = p2 > 0, (c > 0 and b > 0 and b * b > 16.0 * c)
    stable = bool(pitch_ok and roll_yaw_ok)
    boundary = p2 == 0 or c == 0 or b == 0 or b * b == 16.0 * c
    if stable:
        region = "lagrange" if k1 > 0 else "debra-delp"
    elif boundary and p2 >= 0 and b >= 0 and c >= 0 and b * b >= 16.0 * c:
        region = "marginal"
    else:
        region = "unstable"
    freq = [math.sqrt(-x.real) if (x.imag == 0 and x.real <= 0) else math.nan for x in map(complex, xs)]
    freq.sort(key=lambda w: (math.isnan(w), w))
    return GravityGradientStability(
        stable=stable, region=region, pitch_frequency=math.sqrt(p2) if p2 >= 0 else math.nan,
        roll_yaw_frequencies=tuple(freq), eigenvalues=eig, k1=k1, k3=k3, inertia=I, mean_motion=n)
