"""The numerical references of Section 8: a gyrostat's carrier in a potential, on an orbit, on a pivot.

The carrier of an effective gyrostat (Theorem 5) with the constant rotor momentum ``N = sum p_k l_k``
(8.33) obeys, in the conventions of :func:`thetasol.integrators.rotation.integrate_rotation`
(``m = I omega`` with ``I`` the inertia WITHOUT the rotors' axial moments, ``J = tr(I)/2 1 - I`` its
second moments),

    mdot = (m + N) x omega + tau,     Qdot = Q hat(omega),     Phidot = omega,

the vector form of (8.32) (``tau = vee([J_full, Q^T a Q])`` in the quadratic potential ``1/2 x^T a x``),
of (8.37) (``tau = 3 mu / |r|^5 (Q^T r) x I_full (Q^T r)`` on a Kepler orbit ``r(t)``), or of the heavy
top (``tau = c x Q^T (mass g)`` about a fixed point).  ``J_full = J + sum_k (A_k/2)(1 - 2 l_k l_k^T)``
restores the rotors' axial moments: the potential acts on the whole mass distribution.  ``Phi`` is
``int_0^t omega``, so the rotor angles of (8.28) (corrected: ``phidot_k = p_k / A_k - omega . l_k``)
are ``phi_k = (p_k / A_k) t - l_k . Phi`` with no further quadrature.

Methods as for :func:`integrate_rotation`: ``"DOP853"`` (any explicit ``solve_ivp`` method) and
``"heyoka"`` (``fp_type=numpy.longdouble`` or ``heyoka.real128`` for extended precision; potential and
pivot only).
First integrals (tests/test_gyrostat_potential.py): (8.34) ``1/2 omega . I omega + 1/2 tr(Q^T a Q J_full)``,
on a circular orbit (8.38) ``1/2 m . omega + (a0/2) gamma . I_full gamma - Omega (m + N) . n``, on a
pivot the energy, the vertical momentum ``(m + N) . gamma`` and, for a Lagrange gyrostat, ``(m + N) . e3``.
"""
from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import solve_ivp

from thetasol.core import validate as V
from thetasol.core.inertia import inertia_from_moments, second_moments
from thetasol.core.so3 import cross, hat, polar_orthonormalize, vee
from thetasol.integrators._common import Settings, body_inertia, extended_inertia, heyoka_and_type, heyoka_tol, settings
from thetasol.mechanics.heavy_top import heavy_top_data, heavy_top_invariants
from thetasol.mechanics.orbit import Orbit, check_orbit
from thetasol.protocol import RotationSolution

__all__ = ["integrate_gyrostat", "integrate_heavy_gyrostat", "gyrostat_rotor_data", "NumericalGyrostat",
           "NumericalHeavyGyrostat"]


def gyrostat_rotor_data(rotors: Sequence[Mapping] | None, N: ArrayLike | None
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(axes (n, 3), A (n,), p (n,), N)`` from ``rotors`` (mappings with ``axis``, ``A``, ``p`` and
    optionally ``B``, as for :func:`thetasol.solve_gyrostat`) and ``N`` (checked to be ``sum p l``,
    relative 1e-12, or taken from it when None)."""
    if rotors is None:
        if N is None:
            raise ValueError("N is required without rotors")
        return np.zeros((0, 3)), np.zeros(0), np.zeros(0), V.vector3(N, "N")
    ax, A, p = [], [], []
    for k, r in enumerate(rotors):
        if not isinstance(r, Mapping) or not {"axis", "A", "p"} <= set(r) or set(r) - {"axis", "A", "B", "p"}:
            raise ValueError(f"rotors[{k}] must be a mapping with keys 'axis', 'A', 'p' (and optionally 'B')")
        l = V.vector3(r["axis"], f"rotors[{k}]['axis']")
        if abs(np.linalg.norm(l) - 1.0) > 1e-12:
            raise ValueError(f"rotors[{k}]['axis'] must be a unit vector (norm {np.linalg.norm(l)!r})")
        Ak = float(V.finite_array(r["A"], f"rotors[{k}]['A']", ()))
        if not Ak > 0:
            raise ValueError(f"rotors[{k}]['A'] must be > 0, got {Ak}")
        ax.append(l / np.linalg.norm(l))
        A.append(Ak)
        p.append(float(V.finite_array(r["p"], f"rotors[{k}]['p']", ())))
    axes, A, p = np.array(ax).reshape(-1, 3), np.array(A), np.array(p)
    total = p @ axes
    if N is None:
        return axes, A, p, total
    n = V.vector3(N, "N")
    if np.linalg.norm(n - total) > 1e-12 * (np.linalg.norm(n) + np.sum(np.abs(p))):
        raise ValueError(f"N = {n.tolist()} is not sum p_k l_k = {total.tolist()} (8.33)")
    return axes, A, p, n


def _grid(t: np.ndarray, run: Callable[[np.ndarray], np.ndarray], y0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """States at the distinct times (forward for t > 0, backward for t < 0) and the inverse index."""
    ts, inv = np.unique(t.ravel(), return_inverse=True)
    Y = np.tile(y0, (ts.size, 1))
    for sel in (ts > 0, ts < 0):
        idx = np.flatnonzero(sel)
        if idx.size:
            idx = idx[::-1] if ts[idx[0]] < 0 else idx
            Y[idx] = run(ts[idx])
    return Y, inv


def _finish(Y, inv, tt, Im, axes, A, p):
    Q = polar_orthonormalize(Y[:, 3:12].reshape(-1, 3, 3))
    omega = np.linalg.solve(Im, Y[:, :3, None])[..., 0]
    ts = np.unique(tt.ravel())
    ang = ts[:, None] * (p / A)[None, :] - Y[:, 12:15] @ axes.T
    return (omega[inv].reshape(tt.shape + (3,)), Q[inv].reshape(tt.shape + (3, 3)),
            ang[inv].reshape(tt.shape + (len(A),)))


def _rhs_factory(Im: np.ndarray, N: np.ndarray, torque: Callable) -> Callable:
    I_inv = np.linalg.inv(Im)

    def rhs(time, y):
        m, Q = y[:3], y[3:12].reshape(3, 3)
        w = I_inv @ m
        mdot = cross(m + N, w) + torque(time, Q)
        return np.concatenate([mdot, (Q @ hat(w)).ravel(), w])

    return rhs


def _scipy_run(rhs, y0, rtol, atol, method):
    def run(grid):
        sol = solve_ivp(rhs, (0.0, float(grid[-1])), y0, method=method, t_eval=grid, rtol=rtol, atol=atol)
        if not sol.success:
            raise RuntimeError(f"integration failed: {sol.message}")
        return sol.y.T
    return run


def integrate_gyrostat(I: ArrayLike, N: ArrayLike | None, Q0: ArrayLike, omega0: ArrayLike, *,  # noqa: E741
                       rotors: Sequence[Mapping] | None = None, a: ArrayLike | None = None, orbit: Orbit | None = None,
                       method: str = "DOP853", rtol: float = 1e-12, atol: float | None = None,
                       fp_type: Any = float) -> NumericalGyrostat:
    """A gyrostat's carrier in ``1/2 x^T a x`` (8.32) or on an orbit (8.35)-(8.37), integrated numerically.

    Parameters
    ----------
    I : array_like, shape (3,) or (3, 3)
        Inertia of the carrier with the rotors' masses and transverse moments, WITHOUT their axial
        moments (as :func:`thetasol.solve_gyrostat` takes it): ``m = I omega``.
    N : array_like (3,) or None
        Constant rotor momentum ``sum p_k l_k`` (8.33), body frame (None: from ``rotors``).
    Q0, omega0 : array_like
        Initial attitude (body to space) and body angular velocity of the carrier.
    rotors : sequence of mappings, optional
        ``axis``, ``A``, ``p`` (and ``B``, ignored) per rotor, as for :func:`thetasol.solve_gyrostat`;
        their axial moments join the body in the potential, and their angles are returned.
    a : array_like (3, 3), optional
        Symmetric potential matrix (default 0: the free gyrostat (8.39)).
    orbit : Orbit, optional
        Instead of ``a``: the gravity-gradient torque of (8.37) along this orbit of the mass centre
        (:class:`thetasol.KeplerOrbit` or any :class:`thetasol.mechanics.orbit.Orbit`; ``a`` must be None).
    method, rtol, atol, fp_type
        As for :func:`thetasol.integrate_rotation` (``"DOP853"``, any solve_ivp method, or ``"heyoka"``,
        which is not offered with ``orbit``; ``atol`` defaults to ``1e-3 rtol (|m0| + |N|)``).

    Returns
    -------
    NumericalGyrostat
        ``sol(t) -> (omega, Q)``, ``sol.rotor_angles(t)`` and ``sol.evaluate_with_angles(t)`` for any
        shape of ``t``, one integration from ``t = 0`` per call; rotor angles
        ``phi_k(t) = (p_k / A_k) t - l_k . int_0^t omega`` ((8.28) corrected), ``phi_k(0) = 0``.
        ``model`` is ``"gyrostat"``, ``method`` ``"numerical/<method>"``; ``invariants`` the
        ``rotor_momenta`` (the ``p_k``) and, in a potential, the ``energy`` ((8.34) as a physical energy,
        with the rotors' axial moments in the potential); ``diagnostics`` the integrator settings and
        ``error_estimate`` (its ``rtol``).
    """
    Im, Jm = body_inertia(I)
    axes, A, p, Nv = gyrostat_rotor_data(rotors, N)
    Q0m = V.rotation_matrix(Q0, "Q0")
    w0 = V.vector3(omega0, "omega0")
    opts = settings(method, rtol, atol, fp_type)
    if orbit is not None and a is not None:
        raise ValueError("give the potential a or the orbit, not both")
    if orbit is not None and opts.method == "heyoka":
        raise ValueError("method='heyoka' is not offered with an orbit; use DOP853")
    inv = {"rotor_momenta": p.copy()}
    if orbit is None:
        am = np.zeros((3, 3)) if a is None else V.symmetric_matrix(a, "a")
        Jfull = _with_rotors(Jm, axes, A)
        inv["energy"] = float(0.5 * w0 @ Im @ w0 + 0.5 * np.trace(Q0m.T @ am @ Q0m @ Jfull))
    else:
        orbit = check_orbit(orbit)
        r = np.asarray(orbit.r0, dtype=float)
        rn = float(np.linalg.norm(r))
        am = -3.0 * orbit.mu / rn ** 3 * np.outer(r, r) / rn ** 2     # the tidal matrix (7.11) at t = 0
    return NumericalGyrostat(J=Jm, a=am, Q0=Q0m, omega0=w0, method=f"numerical/{opts.method}", invariants=inv,
                             diagnostics=opts.diagnostics(), I_given=Im, N=Nv, axes=axes, A=A, p=p, orbit=orbit,
                             settings=opts)


def _with_rotors(Jm: np.ndarray, axes: np.ndarray, A: np.ndarray) -> np.ndarray:
    """``J_full = J + sum_k (A_k/2)(1 - 2 l_k l_k^T)``: the second moments with the rotors' axial moments."""
    return Jm + sum((0.5 * Ak * (np.eye(3) - 2 * np.outer(l, l)) for l, Ak in zip(axes, A, strict=True)),
                    np.zeros((3, 3)))


@dataclass(frozen=True, eq=False)
class NumericalGyrostat(RotationSolution):
    """The gyrostat of :func:`integrate_gyrostat` behind the RotationSolution protocol.

    ``sol(t)`` integrates on demand from ``t = 0`` (one integration per call, any shape and order of
    ``t``); :meth:`rotor_angles` and :meth:`evaluate_with_angles` give the rotor angles of (8.28).
    ``I`` is the carrier's inertia without the rotors' axial moments, ``J`` its second moments;
    ``axes``, ``A``, ``p`` the rotors' unit axes, axial moments and momenta; with ``orbit`` set the
    torque is the gravity gradient along it and ``a`` its tidal matrix at ``t = 0``.
    """

    N: np.ndarray = None
    axes: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    A: np.ndarray = field(default_factory=lambda: np.zeros(0))
    p: np.ndarray = field(default_factory=lambda: np.zeros(0))
    orbit: Orbit | None = field(default=None, repr=False)
    settings: Settings = Settings()

    model: ClassVar[str] = "gyrostat"
    _AT_ONCE = True  # one integration over all requested times

    def evaluate_with_angles(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(omega, Q, rotor angles)`` at times ``t`` of any shape, one integration."""
        tt, flat = self._times(t)
        out = self._run(self._evaluate_all, flat)
        return tuple(x.reshape(tt.shape + x.shape[1:]) for x in out)

    def _evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self._evaluate_all(t)[:2]

    def rotor_angles(self, t: ArrayLike) -> np.ndarray:
        """Rotor angles ``phi_k(t)``, ``phi_k(0) = 0``, shape ``t.shape + (n_rotors,)``."""
        return self.evaluate_with_angles(t)[2]

    def _evaluate_all(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        s, Im, Nv, Q0m, w0, orbit = self.settings, self.I, self.N, self.Q0, self.omega0, self.orbit
        Jfull = _with_rotors(self.J, self.axes, self.A)
        m0 = Im @ w0
        scale = max(np.linalg.norm(m0) + np.linalg.norm(Nv), np.finfo(float).tiny)
        atol = 1e-3 * s.rtol * scale if s.atol is None else s.atol
        y0 = np.concatenate([m0, Q0m.ravel(), np.zeros(3)])
        if orbit is not None:
            torque = _orbit_torque(orbit, inertia_from_moments(Jfull))
        else:
            am = self.a

            def torque(_time, Q):
                ap = Q.T @ am @ Q
                return vee(Jfull @ ap - ap @ Jfull)
        if s.method == "heyoka":
            run = _heyoka_run(Im, w0, Nv, Q0m, s.rtol, s.fp_type, ("quadratic", Jfull, self.a))
        else:
            run = _scipy_run(_rhs_factory(Im, Nv, torque), y0, s.rtol, atol, s.method)
        Y, inv = _grid(t, run, y0)
        return _finish(Y, inv, t, Im, self.axes, self.A, self.p)


def _orbit_torque(orbit: Orbit, If: np.ndarray) -> Callable:
    """The gravity-gradient torque (8.37) on a body of inertia ``If`` along ``orbit``, as ``torque(t, Q)``."""
    mu3 = 3.0 * float(orbit.mu)

    def torque(time, Q):
        r = np.array(orbit.state_at(time)[0])
        g = Q.T @ r
        return mu3 / (r @ r) ** 2.5 * cross(g, If @ g)

    return torque


def integrate_heavy_gyrostat(I: ArrayLike, center: ArrayLike, Q0: ArrayLike, omega0: ArrayLike, *,  # noqa: E741
                             N: ArrayLike, mass: float = 1.0, gravity: ArrayLike = (0.0, 0.0, -9.81),
                             method: str = "DOP853", rtol: float = 1e-12, atol: float | None = None,
                             fp_type: Any = float) -> NumericalHeavyGyrostat:
    """A heavy gyrostat about a fixed point, ``mdot = (m + N) x omega + c x Q^T (mass g)``, integrated numerically.

    ``I`` is the inertia about the fixed point without the rotors' axial moments, ``center`` the mass
    centre seen from it, ``N`` the constant rotor momentum (body frame); the rest as for
    :func:`thetasol.integrate_heavy_top`.  Returns a :class:`NumericalHeavyGyrostat`: ``sol(t) -> (omega, Q)``
    for any shape of ``t``; ``model`` ``"heavy-top"`` (as the closed form's), ``method`` ``"numerical/<method>"``,
    ``invariants`` the ``energy`` and the ``vertical_momentum`` ``Q (m + N) . up`` at ``t = 0``.
    """
    Im, c, Q0m, w0, mass, g = heavy_top_data(I, center, Q0, omega0, mass, gravity)
    Nv = V.vector3(N, "N")
    opts = settings(method, rtol, atol, fp_type)
    first = heavy_top_invariants(Im, c, mass, g, w0, Q0m)
    gn = np.linalg.norm(g)
    up = -g / gn if gn > 0 else np.array([0.0, 0.0, 1.0])
    inv = {"energy": float(first["energy"]), "vertical_momentum": float(Q0m @ (Im @ w0 + Nv) @ up)}
    return NumericalHeavyGyrostat(J=second_moments(Im), a=np.zeros((3, 3)), Q0=Q0m, omega0=w0,
                                  method=f"numerical/{opts.method}", invariants=inv, diagnostics=opts.diagnostics(),
                                  I_given=Im, center=c, mass=mass, gravity=g, N=Nv, settings=opts)


@dataclass(frozen=True, eq=False)
class NumericalHeavyGyrostat(RotationSolution):
    """The heavy gyrostat of :func:`integrate_heavy_gyrostat` behind the RotationSolution protocol:
    ``sol(t)`` integrates on demand, once per call, from ``t = 0`` (``a`` is zero, the field the uniform
    ``gravity``; ``I`` the inertia about the fixed point without the rotors' axial moments)."""

    center: np.ndarray = None
    mass: float = 1.0
    gravity: np.ndarray = None
    N: np.ndarray = None
    settings: Settings = Settings()

    model: ClassVar[str] = "heavy-top"    # as the Lagrange gyrostat's closed form: a top carrying rotors
    _AT_ONCE = True  # one integration over all requested times

    def _evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        s, Im, c, Nv, Q0m, w0 = self.settings, self.I, self.center, self.N, self.Q0, self.omega0
        F = self.mass * self.gravity
        atol = 1e-3 * s.rtol if s.atol is None else s.atol
        y0 = np.concatenate([Im @ w0, Q0m.ravel(), np.zeros(3)])
        if s.method == "heyoka":
            run = _heyoka_run(Im, w0, Nv, Q0m, s.rtol, s.fp_type, ("pivot", c, F))
        else:
            run = _scipy_run(_rhs_factory(Im, Nv, lambda _time, Q: cross(c, Q.T @ F)), y0, s.rtol, atol, s.method)
        Y, inv = _grid(t, run, y0)
        omega, Q, _ = _finish(Y, inv, t, Im, np.zeros((0, 3)), np.zeros(0), np.zeros(0))
        return omega, Q


def _heyoka_run(Im, w0, Nv, Q0, rtol, fp_type, torque_spec):
    """heyoka's Taylor integrator of the same equations (state m, Q, Phi), in ``fp_type`` arithmetic."""
    hy, ft = heyoka_and_type(fp_type)
    xs = hy.make_vars(*[f"m{i}" for i in range(3)], *[f"q{i}{j}" for i in range(3) for j in range(3)],
                      *[f"f{i}" for i in range(3)])
    m, Q = xs[:3], [xs[3 + 3 * i: 6 + 3 * i] for i in range(3)]
    Iw, m0w = extended_inertia(Im, w0, ft)
    w = [sum(Iw[i][k] * m[k] for k in range(3)) for i in range(3)]
    tau = _heyoka_torque(Q, torque_spec)
    h = [m[i] + float(Nv[i]) for i in range(3)]
    mdot = [h[1] * w[2] - h[2] * w[1] + tau[0], h[2] * w[0] - h[0] * w[2] + tau[1], h[0] * w[1] - h[1] * w[0] + tau[2]]
    W = [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]]
    Qdot = [sum(Q[i][k] * W[k][j] for k in range(3)) for i in range(3) for j in range(3)]
    y0 = np.array(m0w + [ft(float(v)) for v in Q0.ravel()] + [ft(0.0)] * 3)
    tol = heyoka_tol(hy, ft, rtol)
    ta = hy.taylor_adaptive(list(zip(xs, mdot + Qdot + w, strict=True)), y0, tol=tol, fp_type=ft)

    def run(grid):
        ta.time = ft(0.0)
        ta.state[:] = y0
        res = ta.propagate_grid(np.array([ft(float(v)) for v in np.concatenate([[0.0], grid])]))
        return np.asarray(res[-1], dtype=float)[1:]

    return run


def _heyoka_torque(Q, spec):
    if spec[0] == "pivot":
        c, F = [float(x) for x in spec[1]], [float(x) for x in spec[2]]
        Fb = [sum(Q[k][i] * F[k] for k in range(3)) for i in range(3)]
        return [c[1] * Fb[2] - c[2] * Fb[1], c[2] * Fb[0] - c[0] * Fb[2], c[0] * Fb[1] - c[1] * Fb[0]]
    Jf, am = spec[1], spec[2]
    aQ = [[sum(float(am[i, k]) * Q[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    ap = [[sum(Q[k][i] * aQ[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    JA = [[sum(float(Jf[i, k]) * ap[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    return [JA[2][1] - JA[1][2], JA[0][2] - JA[2][0], JA[1][0] - JA[0][1]]
