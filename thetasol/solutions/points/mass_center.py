"""The mass centre of a configuration in a quadratic potential, in closed form.

By Theorem 2 the system mass centre ``q(t)`` obeys the Lagrangian (3.2)
``L1 = 1/2 m |qdot|^2 - m phi(q)`` with ``phi(x) = 1/2 x^T a x + 1/2 b^T x`` (2.4), i.e.

    qddot = -(a q + b / 2).

Method.  With ``a = V diag(lam) V^T`` (``numpy.linalg.eigh``; every formula below is a
smooth function of ``a`` evaluated at its eigenvalues, so nearly equal eigenvalues and
their ill-conditioned eigenvectors cost no accuracy) each mode ``y = V^T q`` solves
``yddot = -lam y - beta`` with ``beta = V^T b / 2``:

    y(t)    = C y0 + t S v0 - t^2 P beta,
    ydot(t) = -lam t S y0 + C v0 - t S beta,

with the entire functions of ``z = lam t^2`` (Stumpff's ``c0, c1, c2``, :mod:`thetasol.special.stumpff`,
as in universal-variable Kepler solvers)

    C = cos(sqrt z),   S = sin(sqrt z) / sqrt z,   P = (1 - cos(sqrt z)) / z,

continued to ``cosh``/``sinh`` for ``z < 0``.  So one formula covers the trigonometric
(``lam > 0``), hyperbolic (``lam < 0``) and polynomial (``lam = 0``) modes and stays
accurate as an eigenvalue passes through 0 (a series near ``z = 0``, where ``1 - cos`` would cancel).
Why hand-written: ``scipy.linalg.expm`` of the 6x6 first-order system would do (it is the test reference)
but costs a dense exponential per time and cannot broadcast cheaply; here one ``eigh``
serves all times.

Conditioning.  A hyperbolic mode amplifies data errors by ``e^{sqrt(-lam) |t|}``; the
result keeps that (unavoidable) absolute error.  Overflow raises ``OverflowError``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import mpmath
import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.protocol import ROUNDOFF, Solution
from thetasol.special.stumpff import stumpff

__all__ = ["MassCenterMotion", "solve_mass_center"]


_KIND_ORDER = ("trigonometric", "hyperbolic", "polynomial")


def _symmetry_axes(lam: np.ndarray, Vec: np.ndarray, beta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Axes ``n`` about which ``phi`` is rotationally symmetric, and a centre ``c`` on each.

    ``phi`` is symmetric about the axis ``n = Vec[:, k]`` through ``c`` when the other two
    eigenvalues are equal (to the rounding of ``eigh``) and, for a zero pair, ``b`` has no
    component in their plane; then ``n . ((q - c) x v)`` is a first integral.  ``c`` is the
    equilibrium in that plane, ``-(beta_i e_i + beta_j e_j) / lam``.
    """
    scale = max(float(np.max(np.abs(lam))), np.finfo(float).tiny)
    tol = 32 * np.finfo(float).eps * scale
    btol = 16 * np.finfo(float).eps * float(np.linalg.norm(beta))
    axes, centers = [], []
    for k in range(3):
        i, j = (m for m in range(3) if m != k)
        if abs(lam[i] - lam[j]) > tol:
            continue
        mean = 0.5 * (lam[i] + lam[j])
        if abs(mean) > tol:
            c = -(beta[i] * Vec[:, i] + beta[j] * Vec[:, j]) / mean
        elif abs(beta[i]) <= btol and abs(beta[j]) <= btol:
            c = np.zeros(3)
        else:
            continue  # a constant force in the plane: no rotational symmetry
        axes.append(Vec[:, k])
        centers.append(c)
    return np.reshape(axes, (-1, 3)), np.reshape(centers, (-1, 3))


@dataclass(frozen=True, eq=False)
class MassCenterMotion(Solution):
    """Closed-form motion of the mass centre in ``phi(x) = 1/2 x^T a x + 1/2 b^T x`` (3.2).

    A :class:`~thetasol.protocol.Solution`: ``mc(t)`` returns ``(q, v)`` with shapes
    ``t.shape + (3,)``; ``mc(t, dps=n)`` evaluates the same formulas in mpmath at ``n`` digits.

    Parameters
    ----------
    a : array_like (3, 3)
        Symmetric potential matrix (any signs, singular allowed).
    b : array_like (3,)
        Linear coefficients of (2.4) (note the 1/2 in ``phi``).
    q0, v0 : array_like (3,)
        Position and velocity at ``t = 0``.
    dps : int, optional
        Decimal digits of the mpmath evaluation ``mc(t)`` uses when its call names none.

    Attributes
    ----------
    eigenvalues, axes : ndarray
        ``a = axes diag(eigenvalues) axes^T``.
    kinds : tuple of str
        ``"trigonometric"``, ``"hyperbolic"`` or ``"polynomial"`` per mode (``|lam|`` at the
        round-off level of ``eigh`` counts as zero; the formula is the same for all three).
    model, method : str
        ``"mass-center"`` and ``"elementary"``; ``case`` (``diagnostics["case"]``) joins the kinds present,
        e.g. ``"trigonometric+hyperbolic"``.
    invariants : dict
        First integrals per unit mass, at ``t = 0`` (:meth:`first_integrals`): ``energy``,
        ``mode_energies`` (3,) and ``angular_momentum`` (k,), the components of ``(q - c) x v``
        along the ``k`` axes about which ``phi`` is rotationally symmetric (``k = 0`` for
        distinct eigenvalues, 1 for a double one, 3 for ``a = c 1``).
    diagnostics : dict
        ``eigenvalues``, ``axes``, ``kinds``, and the symmetry axes and centres of the
        conserved angular momentum components (``angular_momentum_axes`` (k, 3),
        ``angular_momentum_centers`` (k, 3)), ``case`` and ``error_estimate`` (float64 rounding: the
        formula is exact).

    Examples
    --------
    >>> import numpy as np
    >>> mc = MassCenterMotion(np.diag([1.0, 0.0, -1.0]), [0, 0, 0], [1, 1, 1], [0, 0, 0])
    >>> q, v = mc(np.pi)
    >>> np.round(q, 6).tolist()
    [-1.0, 1.0, 11.591953]
    >>> mc.model, mc.method, mc.case
    ('mass-center', 'elementary', 'trigonometric+hyperbolic+polynomial')
    """

    model = "mass-center"

    a: np.ndarray
    b: np.ndarray
    q0: np.ndarray
    v0: np.ndarray
    dps: int | None = None
    eigenvalues: np.ndarray = field(init=False, repr=False)
    axes: np.ndarray = field(init=False, repr=False)
    kinds: tuple = field(init=False)
    method: str = field(init=False)
    invariants: dict = field(init=False, repr=False)
    diagnostics: dict = field(init=False, repr=False)

    def __post_init__(self) -> None:
        a = V.symmetric_matrix(self.a, "a")
        object.__setattr__(self, "a", a)
        object.__setattr__(self, "b", V.vector3(self.b, "b"))
        object.__setattr__(self, "q0", V.vector3(self.q0, "q0"))
        object.__setattr__(self, "v0", V.vector3(self.v0, "v0"))
        lam, Vec = np.linalg.eigh(a)
        object.__setattr__(self, "eigenvalues", lam)
        object.__setattr__(self, "axes", Vec)
        tiny = 16 * np.finfo(float).eps * max(np.max(np.abs(lam)), np.finfo(float).tiny)
        kinds = tuple("polynomial" if abs(x) <= tiny else "trigonometric" if x > 0 else "hyperbolic" for x in lam)
        object.__setattr__(self, "kinds", kinds)
        object.__setattr__(self, "method", "elementary")
        L_axes, L_centers = _symmetry_axes(lam, Vec, 0.5 * (Vec.T @ self.b))
        object.__setattr__(self, "diagnostics", {
            "eigenvalues": lam, "axes": Vec, "kinds": kinds,
            "angular_momentum_axes": L_axes, "angular_momentum_centers": L_centers,
            "case": "+".join(k for k in _KIND_ORDER if k in kinds), "error_estimate": ROUNDOFF})
        inv = self.first_integrals(self.q0, self.v0)
        object.__setattr__(self, "invariants", {**inv, "energy": float(inv["energy"])})

    def fastest_frequency(self) -> float:
        """The fastest mode's rate ``sqrt(max |eigenvalue|)`` (its growth rate for a hyperbolic one)."""
        return math.sqrt(float(np.abs(self.eigenvalues).max()))

    def __call__(self, t: ArrayLike, dps: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Position and velocity at times ``t``.

        Parameters
        ----------
        t : array_like
            Times, any shape.
        dps : int, optional
            Decimal digits for an mpmath evaluation (object arrays of ``mpmath.mpf``), by default
            the motion's own ``dps``; mpmath's global precision is not changed.

        Returns
        -------
        q, v : ndarray, shape ``t.shape + (3,)``
        """
        dps = self.dps if dps is None else dps
        if dps is not None:
            return self._mp(V.times(t, "t"), int(dps))
        return super().__call__(t)

    def evaluate(self, t: ArrayLike, dps: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Alias of ``mc(t, dps=dps)``."""
        return self(t, dps=dps)

    def _evaluate(self, tt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        lam, Vec = self.eigenvalues, self.axes
        y0, w0, beta = Vec.T @ self.q0, Vec.T @ self.v0, 0.5 * (Vec.T @ self.b)
        tc = tt[..., None]
        C, S, P, _ = stumpff(lam * (tc * tc))
        with np.errstate(over="ignore", invalid="ignore"):
            y = C * y0 + tc * S * w0 - tc * tc * P * beta
            yd = -lam * tc * S * y0 + C * w0 - tc * S * beta
            q = y @ Vec.T
            v = yd @ Vec.T
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
            raise OverflowError("the mass centre overflows float64 at the requested times "
                                f"(hyperbolic rate {np.sqrt(max(-lam.min(), 0)):.3g}, max |t| {np.max(np.abs(tt)):.3g}); "
                                "use dps= for an mpmath evaluation")
        return q, v

    def _mp(self, tt: np.ndarray, dps: int) -> tuple[np.ndarray, np.ndarray]:
        with mpmath.workdps(dps + 5):
            mp = mpmath.mp
            a = mp.matrix([[mp.mpf(float(x)) for x in row] for row in self.a])
            lam, E = mp.eigsy(a)
            Vec = [[E[i, j] for j in range(3)] for i in range(3)]
            q0 = [mp.mpf(float(x)) for x in self.q0]
            v0 = [mp.mpf(float(x)) for x in self.v0]
            b = [mp.mpf(float(x)) for x in self.b]
            y0 = [mp.fsum(Vec[i][k] * q0[i] for i in range(3)) for k in range(3)]
            w0 = [mp.fsum(Vec[i][k] * v0[i] for i in range(3)) for k in range(3)]
            beta = [mp.fsum(Vec[i][k] * b[i] for i in range(3)) / 2 for k in range(3)]
            qo = np.empty(tt.shape + (3,), dtype=object)
            vo = np.empty(tt.shape + (3,), dtype=object)
            for idx in np.ndindex(tt.shape):
                t = mp.mpf(float(tt[idx]))
                y, yd = [], []
                for k in range(3):
                    lk = lam[k]
                    x = mp.sqrt(abs(lk)) * abs(t)
                    cos, sin = (mp.cos, mp.sin) if lk >= 0 else (mp.cosh, mp.sinh)
                    C = cos(x)
                    # x = 0 (t = 0 or lam = 0) in both branches: sin x / x -> 1
                    S = sin(x) / x if x else mp.mpf(1)
                    S2 = sin(x / 2) / (x / 2) if x else mp.mpf(1)
                    P = S2 * S2 / 2
                    y.append(C * y0[k] + t * S * w0[k] - t * t * P * beta[k])
                    yd.append(-lk * t * S * y0[k] + C * w0[k] - t * S * beta[k])
                for i in range(3):
                    qo[idx + (i,)] = mp.fsum(Vec[i][k] * y[k] for k in range(3))
                    vo[idx + (i,)] = mp.fsum(Vec[i][k] * yd[k] for k in range(3))
        return qo, vo

    def potential(self, q: ArrayLike) -> np.ndarray:
        """``phi(q) = 1/2 q^T a q + 1/2 b^T q`` (2.4), shape ``q.shape[:-1]``."""
        q = np.asarray(q, dtype=float)
        return 0.5 * np.einsum("...i,ij,...j->...", q, self.a, q) + 0.5 * q @ self.b

    def energy(self, q: ArrayLike, v: ArrayLike) -> np.ndarray:
        """Energy per unit mass ``1/2 |v|^2 + phi(q)`` (constant along the motion)."""
        v = np.asarray(v, dtype=float)
        return 0.5 * np.sum(v * v, axis=-1) + self.potential(q)

    def first_integrals(self, q: ArrayLike, v: ArrayLike) -> dict[str, np.ndarray]:
        """The first integrals per unit mass at states ``(q, v)``, shapes ``q.shape[:-1]`` leading.

        ``energy`` ``1/2 |v|^2 + phi(q)``; ``mode_energies`` (..., 3) ``1/2 ydot_k^2 +
        1/2 lam_k y_k^2 + beta_k y_k`` with ``y = axes^T q`` (their sum is ``energy``);
        ``angular_momentum`` (..., k) ``n . ((q - c) x v)`` for each symmetry axis ``n`` and
        centre ``c`` of ``diagnostics``.
        """
        q = np.asarray(q, dtype=float)
        v = np.asarray(v, dtype=float)
        y, yd = q @ self.axes, v @ self.axes
        beta = 0.5 * (self.axes.T @ self.b)
        modes = 0.5 * yd * yd + 0.5 * self.eigenvalues * y * y + beta * y
        d = self.diagnostics
        r = q[..., None, :] - d["angular_momentum_centers"]
        L = np.einsum("kj,...kj->...k", d["angular_momentum_axes"], np.cross(r, v[..., None, :]))
        return {"energy": self.energy(q, v), "mode_energies": modes, "angular_momentum": L}

    def describe(self) -> list[str]:
        """One line per mode: eigenvalue, kind, frequency or rate, axis."""
        out = []
        for lam, kind, ax in zip(self.eigenvalues, self.kinds, self.axes.T, strict=True):
            if kind == "trigonometric":
                extra = f"frequency {np.sqrt(lam):.6g}"
            elif kind == "hyperbolic":
                extra = f"rate {np.sqrt(-lam):.6g}"
            else:
                extra = "uniform motion plus constant force"
            out.append(f"lambda = {lam:+.6g}: {kind} ({extra}), axis {np.round(ax, 6).tolist()}")
        return out


def solve_mass_center(a: ArrayLike, b: ArrayLike, q0: ArrayLike, v0: ArrayLike, *,
                      dps: int | None = None) -> MassCenterMotion:
    """Closed-form motion of the mass centre in ``phi(x) = 1/2 x^T a x + 1/2 b^T x`` (3.2).

    Parameters
    ----------
    a : array_like (3, 3)
        Symmetric; positive, negative and zero eigenvalues all allowed.
    b : array_like (3,)
        Linear part of (2.4).
    q0, v0 : array_like (3,)
        Initial position and velocity.
    dps : int, optional
        Decimal digits of an mpmath evaluation: ``mc(t)`` then returns object arrays.

    Returns
    -------
    MassCenterMotion
        ``mc(t) -> (q, v)`` with shapes ``t.shape + (3,)``, and the modes of the motion.
    """
    if dps is not None and (not isinstance(dps, (int, np.integer)) or dps < 15):
        raise ValueError(f"dps must be an integer >= 15, got {dps!r}")
    return MassCenterMotion(a, b, q0, v0, dps=dps)
