"""Riemann theta functions with characteristics, derivatives and error control.

Definition (DLMF 21.2.5), for ``tau`` symmetric with ``Im tau`` positive definite::

    theta[alpha; beta](z | tau) = sum_{n in Z^g} exp(2 pi i (1/2 (n+alpha).tau.(n+alpha)
                                                     + (n+alpha).(z+beta)))

Method
------
* **Siegel reduction** (Frauendiener, Jaber, Klein 2019): LLL reduction of ``Im tau``,
  ``|Re tau_ij| <= 1/2`` and the quasi-inversion of ``tau_11`` while ``|tau_11| < 1``.  The
  composition of these elementary symplectic steps is kept exactly, so points map linearly,
  characteristics map through ``gamma^{-T}`` and the prefactor is an explicit
  ``exp(quadratic)`` without any eighth-root-of-unity ambiguity.  Ill-conditioned ``tau``
  (pinched cycles, ``Im tau`` eigenvalues from 0.05 to 50) thus cost no more than reduced ones.
* **Exponent separation**: ``theta = exp(e) v`` with ``e = pi y.(Im tau)^{-1}.y``, ``y = Im z``,
  and ``|v|`` bounded; ``v`` is what is summed, so nothing overflows (Deconinck, Heil, Bobenko,
  van Hoeij, Schmies, Math. Comp. 73 (2004), eqs. (4)-(6)).  ``z`` is first reduced modulo the
  period lattice of the *original* ``tau`` (exact quasi-periodicity), then mapped to the reduced
  frame, where each point is shifted again by Babai nearest-plane rounding of ``(Im tau)^{-1} Im z``.
* **Ellipsoid summation** over the union of the ellipsoids ``||T(m + f)|| < R`` for all Babai
  remainders ``f``, with ``R`` from the bound of Deconinck et al. (Thm 2), extended to the
  polynomial weights of derivatives.  One lattice set serves a whole batch of points, so the hot
  loop is a complex matrix product (see :mod:`thetasol.theta._core`).
* **All 2^(2g) half-integer characteristics** at once: the sums are grouped by ``alpha`` and the
  ``beta`` signs ``(-1)^{n.b}`` are columns of the same matrix product.
* **Precision where float64 fails**: the reduction steps are replayed in mpmath (the constants
  carry phases ~1e3), and the O(g^2)-per-point maps whose inputs are large but whose results
  are O(1) (``z - tau k``, ``pi k.X.k mod 2 pi``, ``e``, ``M z``, the Babai shift in the reduced
  frame) run in double-double (:mod:`thetasol.core.dd`).  The errors against FLINT on the test
  families are in docs/bench_theta.md, written by benchmarks/bench_theta.py.

Written by hand because no allowed dependency evaluates Riemann theta functions in float64
(python-flint's certified ``acb_theta`` is an optional test oracle, much slower per point,
docs/bench_theta.md).
An mpmath path (``dps=``) sums the defining series directly in the original frame.

Conventions
-----------
* ``z`` has shape ``(..., g)``; results have shape ``z.shape[:-1]`` (plus ``(2^(2g),)`` for
  ``char="all"``, plus ``(g,)``/``(g, g)`` for gradients/Hessians).
* ``char="all"`` orders characteristics as python-flint: index ``a * 2^g + b`` where
  ``a, b`` in ``{0,1}^g`` are read as binary numbers with the first coordinate most significant,
  ``alpha = a/2, beta = b/2``.
* ``tol`` bounds the truncation error of ``v`` (absolute, i.e. relative to ``exp(e)``); the
  k-th derivative's bound is ``tol * prod_i (1 + |v_i.(c - alpha)|)`` with ``c = (Im tau)^{-1} y``
  (the natural size of the derivative).  Float64 round-off adds ~1e-15 .. 1e-14.
"""
from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core.dd import DD, dd_matvec, dd_prod, dd_split_mp, dd_sum
from thetasol.theta._checks import (
    check_char as _check_char,
    check_dirs as _check_dirs,
    check_tau as _check_tau,
    check_tol as _check_tol,
    check_z as _check_z,
)
from thetasol.theta._core import TWO_PI_I, ReducedLattice, group_jets, jet_layout
from thetasol.theta.lattice import babai, siegel_reduction

__all__ = ["RiemannTheta", "riemann_theta", "riemann_theta_separated", "siegel_reduce"]

#: pi - float(pi)
_PI_LO = 1.2246467991473532e-16


# ----------------------------------------------------------------------------------------
# Public API
# ----------------------------------------------------------------------------------------
def siegel_reduce(tau: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Siegel reduction of a Riemann matrix (Frauendiener, Jaber, Klein 2019).

    Parameters
    ----------
    tau : array_like, shape (g, g)
        Complex symmetric matrix with positive definite imaginary part.

    Returns
    -------
    tau_red : ndarray, shape (g, g)
        ``(A tau + B)(C tau + D)^{-1}`` with ``Im tau_red`` LLL-reduced, ``|Re tau_red| <= 1/2``
        entrywise and ``|tau_red[0, 0]| >= 1``.
    gamma : ndarray of int64, shape (2g, 2g)
        ``[[A, B], [C, D]]`` in ``Sp(2g, Z)`` (``gamma^T J gamma = J``, ``J = [[0, 1], [-1, 0]]``,
        checked exactly; rounding ties such as ``Re tau_ij = +-1/2`` are resolved by exactly
        symplectic steps, see docs/theta.md).

    Notes
    -----
    Callers map points and characteristics with the theta transformation formula
    (Igusa; Mumford, Tata Lectures I, II.5): with ``z' = (C tau + D)^{-T} z`` and

        alpha' = D alpha - C beta + 1/2 diag(C D^T),
        beta'  = -B alpha + A beta + 1/2 diag(A B^T),

    one has ``theta[alpha'; beta'](z' | tau_red) = kappa * sqrt(det(C tau + D))
    * exp(pi i z.(C tau + D)^{-1} C z) * theta[alpha; beta](z | tau)`` with ``|kappa| = 1`` a
    constant depending on gamma and the characteristic (an eighth root of unity times
    ``exp(2 pi i phi(alpha, beta))``).  :class:`RiemannTheta` does not need kappa: it keeps the
    elementary steps and so knows every factor exactly.
    """
    t = _check_tau(tau)
    red = siegel_reduction(t)
    return red.tau.copy(), red.gamma.copy()


class RiemannTheta:
    """Reusable evaluator of ``theta[alpha; beta](z | tau)`` for one ``tau``.

    Validates and Siegel-reduces ``tau`` once, caches the Cholesky factor, the lattice point
    sets and the characteristic tables, and evaluates batches of points with matrix products.

    Parameters
    ----------
    tau : array_like, shape (g, g)
        Riemann matrix (symmetric to 1e-12 relative, ``Im tau`` positive definite).
    tol : float
        Absolute truncation error of the exponent-separated value ``v`` (see module notes).

    Examples
    --------
    >>> th = RiemannTheta([[1j, 0.5], [0.5, 2j]])
    >>> z0, V, c = np.zeros(2), np.array([0.3, 0.1]), np.array([[0.1, 0.2j], [0.5, -0.3j]])
    >>> t = np.linspace(0, 10, 1000)
    >>> z = (z0 + t[:, None] * V)[:, None, :] + c[None, :, :]   # (T, S, g)
    >>> th(z).shape, th.gradient(z).shape
    ((1000, 2), (1000, 2, 2))
    """

    def __init__(self, tau, tol: float = 1e-14):
        self.tau = _check_tau(tau)
        self.tol = _check_tol(tol)
        self.g = g = self.tau.shape[0]
        self._X0 = self.tau.real
        self._Y0 = self.tau.imag
        self._T0 = np.linalg.cholesky(self._Y0).T
        self._Y0inv = np.linalg.inv(self._Y0)
        self.reduction = siegel_reduction(self.tau)
        Mmp = self.reduction.mp["M"]
        self._M_dd = (*dd_split_mp([[x.real for x in row] for row in Mmp]),
                      *dd_split_mp([[x.imag for x in row] for row in Mmp]))
        ctx = self.reduction.mp["ctx"]
        self._Y0inv_dd = dd_split_mp(_mp_inverse_spd(ctx, self._Y0))
        Qmp = self.reduction.mp["Q"]
        self._Q_dd = (*dd_split_mp([[x.real for x in row] for row in Qmp]),
                      *dd_split_mp([[x.imag for x in row] for row in Qmp]))
        taur_mp = self.reduction.mp["tau"]
        self.lattice = ReducedLattice(self.reduction.tau, np.array(
            [[complex(taur_mp[i][j] - complex(self.reduction.tau[i, j])) for j in range(g)] for i in range(g)]))
        self._tables: dict = {}

    # -- characteristic tables ---------------------------------------------------------
    def _char_table(self, alpha: np.ndarray, beta: np.ndarray) -> dict:
        """Per characteristic: reduced characteristic and the constant K of the prefactor
        exp(K + pi i z.Q.z) (the transformation law has no linear term; checked on the first one)."""
        red, g = self.reduction, self.g
        mp = red.mp
        ctx = mp["ctx"]
        # (alpha', beta') = gamma^{-T} (alpha, beta) + (a_s, b_s), split into [0, 1) + integers: exact, in
        # integers for half characteristics, in mpmath for general ones
        Lam = red.lattice_map
        shift = np.concatenate([red.a_s, red.b_s])
        v2 = 2 * np.concatenate([alpha, beta], axis=1)
        if np.array_equal(v2, np.round(v2)):
            a1, b1, p, q, ar, br = _half_images(v2, Lam, shift, ctx)
        else:
            a1, b1, p, q, ar, br = _general_images(alpha, beta, Lam, shift, ctx)
        # K carries phases of size ~1e3 (large Q, c0 after inversions): sum it in mpmath, as the quadratic
        # form of (alpha, beta) assembled once (_char_form) and evaluated per characteristic
        tau0, Qm, lm, Mm = mp["tau0"], mp["Q"], mp["l"], mp["M"]
        # the zero characteristic (the theta-function rotation's only one) needs c alone: the
        # 2g x 2g form H costs many mpmath dot products
        zero = not (np.any(alpha) or np.any(beta))
        H, h, c = ([], [], _char_constant(mp, shift)) if zero else _char_form(mp, Lam, shift)
        n = alpha.shape[0]
        K = np.empty(n, dtype=complex)
        two_pi_i = 2j * ctx.pi
        rg, r2 = range(g), range(2 * g)
        for ci in range(n):
            v = [ctx.mpf(x) for x in np.concatenate([alpha[ci], beta[ci]])]
            nz = [i for i in r2 if v[i]]
            Kc = (c + ctx.fsum(v[i] * (h[i] + ctx.fsum(H[i][j] * v[j] for j in nz)) for i in nz)
                  + two_pi_i * ctx.fsum((a1[ci][i] - p[ci][i]) * q[ci][i] for i in rg))
            # Im K is a phase of size up to ~1e3: reduce it mod 2 pi before rounding to float64
            K[ci] = complex(float(Kc.real), float(ctx.fmod(Kc.imag, 2 * ctx.pi)))
            if ci == 0:  # linear coefficient of log(prefactor) in z: zero by the modular law
                al, be, a1c = v[:g], v[g:], list(a1[ci])
                d0 = [ctx.fdot(tau0[i], al) + be[i] for i in rg]
                L = [abs(al[j] + lm[j] + ctx.fdot(Qm[j], d0) - ctx.fdot(a1c, [Mm[i][j] for i in rg])) for j in rg]
                if max(L) > 1e-20:  # pragma: no cover - would mean a broken reduction
                    raise RuntimeError(f"internal error: theta transformation has a linear term {L}")
        return {"alpha": alpha, "beta": beta, "ar": ar, "br": br, "K": K}

    def _table_all(self) -> dict:
        if "all" not in self._tables:
            alpha, beta, _ = _check_char("all", self.g)
            tab = self._char_table(alpha, beta)
            ia = np.rint(2 * tab["ar"]).astype(np.int64)
            ib = np.rint(2 * tab["br"]).astype(np.int64)
            w = 1 << np.arange(self.g - 1, -1, -1)
            tab["red_index"] = (ia @ w) * (1 << self.g) + ib @ w
            self._tables["all"] = tab
        return self._tables["all"]

    # -- the evaluation pass -----------------------------------------------------------
    def _quad_phase(self, zr_re: DD, zr_im: DD) -> np.ndarray:
        """``Re(zr.Q.zr) / 2`` modulo 1, in double-double (Q from the mp replay); zr as (g, P)."""
        Qr_hi, Qr_lo, Qi_hi, Qi_lo = self._Q_dd
        g, P = zr_re.hi.shape
        xi = lambda d: DD(d.hi[:, None, :], d.lo[:, None, :])  # noqa: E731
        xj = lambda d: DD(d.hi[None, :, :], d.lo[None, :, :])  # noqa: E731
        rr = xi(zr_re).mul_dd(xj(zr_re)) - xi(zr_im).mul_dd(xj(zr_im))  # Re(z_i z_j)
        ii = xi(zr_re).mul_dd(xj(zr_im)) + xi(zr_im).mul_dd(xj(zr_re))  # Im(z_i z_j)
        h = lambda A: 0.5 * A[:, :, None]  # noqa: E731
        acc = rr.mul(h(Qr_hi)) + DD(rr.hi * h(Qr_lo)) - ii.mul(h(Qi_hi)) - DD(ii.hi * h(Qi_lo))
        return dd_sum(DD(acc.hi.reshape(g * g, P), acc.lo.reshape(g * g, P))).frac()

    def _reduce_points(self, z: np.ndarray):
        """``z = zr + tau k + j`` (k by Babai on (Im tau)^{-1} Im z); zr as DD (g, P), k, j as (P, g)."""
        k0 = babai(z.imag @ self._Y0inv, self._T0)
        kT = k0.T
        # X k and Y k in one call (the same operations per entry)
        XY = np.stack([self._X0.T, self._Y0.T], axis=1)[:, :, :, None]  # [j, re/im, i, 1]
        zk = DD(np.stack([z.real.T, z.imag.T])) - dd_sum(dd_prod(XY, kT[:, None, None, :]))  # (2, g, P)
        re, im = DD(zk.hi[0], zk.lo[0]), DD(zk.hi[1], zk.lo[1])
        j0 = np.rint(re.hi)
        return re - j0, im, k0, j0.T

    def _evaluate(self, z: np.ndarray, char, V: np.ndarray, order: int):
        """Exponent ``e`` (P,) and subset jets (P, nchar, jet.size) of ``exp(-e) D_S theta``."""
        g = self.g
        alpha, beta, is_all = _check_char(char, g)
        if is_all:
            tab = self._table_all()
        else:
            key = (alpha.tobytes(), beta.tobytes())
            tab = self._tables.get(key)
            if tab is None:
                if len(self._tables) > 256:  # bounded cache of general characteristics
                    self._tables = {k: v for k, v in self._tables.items() if k == "all"}
                tab = self._tables[key] = self._char_table(alpha, beta)
        jet = jet_layout(len(V), order)
        P = z.shape[0]
        # 1. reduce z modulo the period lattice of the original tau (double-double: k ~ |Im z|)
        red = self.reduction
        zr_re, zr_im, k0, j0 = self._reduce_points(z)
        zr = (zr_re.value() + 1j * zr_im.value()).T
        # e = pi y.Y^{-1}.y in double-double with Y^{-1} from mpmath: Y may have condition ~1e3
        # and y ~ 50, and e's error is a relative error of theta
        Yi_hi, Yi_lo = self._Y0inv_dd
        yT = z.imag.T
        yy = dd_prod(yT[:, None, :], yT[None, :, :]).mul_dd(DD(Yi_hi[:, :, None], Yi_lo[:, :, None]))
        acc = dd_sum(DD(yy.hi.reshape(g * g, P), yy.lo.reshape(g * g, P)))
        # pi * acc in dd; e is returned rounded and its rounding residual goes into v
        e_dd = acc.mul(math.pi) + DD(acc.hi * _PI_LO)
        e, e_res = e_dd.hi, e_dd.lo
        # quasi-periodicity phase / 2 pi = alpha.j - beta.k - k.X.k/2 - k.Re(zr)   (mod 1)
        aT, bT = tab["alpha"].T[:, :, None], tab["beta"].T[:, :, None]  # [i, c, 1]
        ph = dd_sum(dd_prod(aT, j0.T[:, None, :])) - dd_sum(dd_prod(bT, k0.T[:, None, :]))  # (nchar, P)
        kk = (k0.T[:, None, :] * k0.T[None, :, :]).reshape(g * g, P)
        own = dd_sum(zr_re.mul(k0.T)) + dd_sum(dd_prod(kk, 0.5 * self._X0.reshape(-1, 1)))
        ph = ph - DD(own.hi[None, :], own.lo[None, :])
        phi0 = 2 * math.pi * ph.frac().T  # (P, nchar)
        # 2. map into the reduced frame, u = M zr (double-double)
        Mr_hi, Mr_lo, Mi_hi, Mi_lo = self._M_dd
        # [Re M; Im M] times [Re zr | Im zr] in one call (the same operations per entry): blocks (2g, 2P)
        Mz = dd_matvec(np.concatenate([Mr_hi, Mi_hi]), np.concatenate([Mr_lo, Mi_lo]),
                       DD(np.concatenate([zr_re.hi, zr_im.hi], axis=1), np.concatenate([zr_re.lo, zr_im.lo], axis=1)))
        rows, cols = (slice(0, g), slice(g, 2 * g)), (slice(0, P), slice(P, 2 * P))
        blk = lambda a, b: DD(Mz.hi[rows[a], cols[b]], Mz.lo[rows[a], cols[b]])  # noqa: E731
        ur = blk(0, 0) - blk(1, 1)
        ui = blk(0, 1) + blk(1, 0)
        u = (ur.hi + 1j * ui.hi).T
        u_lo = (ur.lo + 1j * ui.lo).T
        # prefactor exp(K + pi i zr.Q.zr) (L = 0: the transformation law has no linear term);
        # |Q| reaches ~100 for pinched tau, so its phase pi Re(zr.Q.zr) is taken mod 2 pi in dd
        Qz = zr @ red.Q.T  # Q symmetric
        quad = self._quad_phase(zr_re, zr_im)  # Re(zr.Q.zr) / 2 mod 1
        K = tab["K"]
        logmag = K.real  # |prefactor| exp(e'(u) - e(zr)) is constant (modular invariance)
        phase = K.imag[None, :] + 2 * math.pi * quad[:, None] + phi0
        pref = np.exp(logmag[None, :] + e_res[:, None] + 1j * phase)
        # 3. reduced-frame jets
        Vr = V @ red.M.T
        tol_in = self.tol * math.exp(-max(float(np.max(logmag)), 0.0)) * 0.5
        a = 1.0
        if len(V):
            nv = np.linalg.norm(V, axis=1)
            nz = nv > 0  # a zero direction gives a zero derivative, whatever R
            a = float(np.max(np.linalg.norm(Vr[nz] @ self.lattice.Tinv, axis=1) / nv[nz], initial=1.0))
        R = self.lattice.radius(tol_in, order, a)
        lset = self.lattice.points(R)
        if is_all:
            bits = (np.arange(1 << g)[:, None] >> np.arange(g - 1, -1, -1)[None, :]) & 1
            Jr = np.concatenate([group_jets(self.lattice, lset, u, ab / 2.0, np.zeros(g), bits, jet, Vr,
                                            u_lo=u_lo) for ab in bits], axis=1)
            Jr = Jr[:, tab["red_index"], :]
        else:
            Jr = group_jets(self.lattice, lset, u, tab["ar"][0], tab["br"][0], np.zeros((1, g), np.int64),
                            jet, Vr, u_lo=u_lo)
        # 4. Leibniz with the prefactor exp(K + pi i z.Q.z - 2 pi i k0.z)
        if jet.size > 1:
            ell = (TWO_PI_I * (Qz - k0) @ V.T)[:, None, :]
            qd = TWO_PI_I * (V @ red.Q @ V.T)
            Jr = jet.leibniz(jet.factor(ell, qd), Jr)
        return e, Jr * pref[:, :, None], jet

    # -- public methods ----------------------------------------------------------------
    def _run(self, z, char, V, order):
        zz = _check_z(z, self.g)
        shape = zz.shape[:-1]
        flat = zz.reshape(-1, self.g)
        nchar = 4 ** self.g if isinstance(char, str) else 1
        # chunks of points keep the work arrays (~8 x P x nchar x jet size) near 100 MB
        step = max(64, (1 << 21) // (nchar * jet_layout(len(V), order).size))
        if len(flat) <= step:
            e, J, jet = self._evaluate(flat, char, V, order)
        else:
            parts = [self._evaluate(flat[s:s + step], char, V, order) for s in range(0, len(flat), step)]
            e = np.concatenate([p[0] for p in parts])
            J = np.concatenate([p[1] for p in parts])
            jet = parts[0][2]
        return shape, e, J, jet, isinstance(char, str)

    @staticmethod
    def _finish(shape, e, val, is_all, extra, separated):
        """Reshape (P, nchar, *extra) to shape (+ (nchar,)) + extra and apply exp(e) unless separated."""
        out = val if is_all else val[:, 0]
        out = out.reshape(shape + out.shape[1:])
        ee = e.reshape(shape)
        if separated:
            return (ee[()] if ee.ndim == 0 else ee), (out[()] if out.ndim == 0 else out)
        with np.errstate(over="ignore", invalid="ignore"):
            scale = np.exp(ee).reshape(shape + (1,) * (out.ndim - len(shape)))
            res = out * scale
        if not np.all(np.isfinite(res)):
            raise OverflowError(
                f"theta overflows float64 (exponent e up to {float(np.max(ee)):.4g}); "
                "use separated=True to get theta = exp(e) * v")
        return res[()] if res.ndim == 0 else res

    def __call__(self, z: ArrayLike, char: str | tuple[ArrayLike, ArrayLike] | None = None, derivs: Sequence = (),
                 separated: bool = False) -> np.ndarray | complex | tuple[np.ndarray, np.ndarray]:
        """``theta[alpha; beta](z | tau)`` or its directional derivative ``D_{v_1} .. D_{v_k} theta``.

        Parameters
        ----------
        z : array_like, shape (..., g)
        char : None, "all" or (alpha, beta)
        derivs : sequence of k direction vectors (length g, complex allowed)
        separated : bool
            Return ``(e, v)`` with ``result = exp(e) * v`` (never overflows).

        Returns
        -------
        complex ndarray of shape ``z.shape[:-1]`` (``+ (2^(2g),)`` for char="all"); a scalar
        for a single point.  With ``separated=True`` a pair ``(e, v)``.
        """
        V = _check_dirs(derivs, self.g)
        shape, e, J, jet, is_all = self._run(z, char, V, len(V))
        return self._finish(shape, e, J[:, :, -1] if len(V) else J[:, :, 0], is_all, (), separated)

    def separated(self, z: ArrayLike, char: str | tuple[ArrayLike, ArrayLike] | None = None,
                  derivs: Sequence = ()) -> tuple[np.ndarray, np.ndarray]:
        """Exponent-separated evaluation ``(e, v)``: ``theta = exp(e) v``, ``e = pi y.(Im tau)^{-1}.y``."""
        return self(z, char, derivs, separated=True)

    def jet(self, z: ArrayLike, char: str | tuple[ArrayLike, ArrayLike] | None = None, order: int = 1,
            separated: bool = False) -> tuple[np.ndarray, ...]:
        """Value, gradient (order >= 1) and Hessian (order 2) in one pass over the lattice.

        Returns a tuple ``(value, gradient[, hessian])`` with shapes ``s``, ``s + (g,)``,
        ``s + (g, g)`` where ``s = z.shape[:-1]`` (``+ (2^(2g),)`` for char="all"); with
        ``separated=True`` the tuple is ``(e, value, gradient[, hessian])`` in units of ``exp(e)``.
        """
        if order not in (0, 1, 2):
            raise ValueError(f"order must be 0, 1 or 2, got {order!r}")
        g = self.g
        # order 2 uses every unit direction twice, so that D_{e_i} D_{e_i} is a subset too
        V = np.eye(g, dtype=complex) if order < 2 else np.concatenate([np.eye(g), np.eye(g)]).astype(complex)
        shape, e, J, jet, is_all = self._run(z, char, V, order)
        parts = [J[..., 0]]
        if order >= 1:
            parts.append(J[..., [jet.index[1 << i] for i in range(g)]])
        if order >= 2:
            idx = [[jet.index[(1 << i) | (1 << (g + j))] for j in range(g)] for i in range(g)]
            parts.append(J[..., np.array(idx)])
        outs = [self._finish(shape, e, p, is_all, (), True)[1] for p in parts]
        if separated:
            ee = e.reshape(shape)
            return (ee[()] if ee.ndim == 0 else ee, *outs)
        return tuple(self._finish(shape, e, p, is_all, (), False) for p in parts)

    def gradient(self, z: ArrayLike, char: str | tuple[ArrayLike, ArrayLike] | None = None,
                 separated: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
        """Gradient ``d theta / d z_j``, shape ``z.shape[:-1] + (g,)`` (one pass over the lattice)."""
        res = self.jet(z, char, 1, separated)
        return (res[0], res[2]) if separated else res[1]

    def hessian(self, z: ArrayLike, char: str | tuple[ArrayLike, ArrayLike] | None = None,
                separated: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
        """Hessian ``d^2 theta / d z_i d z_j``, shape ``z.shape[:-1] + (g, g)``."""
        res = self.jet(z, char, 2, separated)
        return (res[0], res[3]) if separated else res[2]


def _mp_inverse_spd(ctx, Y: np.ndarray) -> list:
    """Inverse of a symmetric positive definite float matrix in mpmath at ``ctx``'s precision, by
    Gauss-Jordan elimination without pivoting (stable for positive definite matrices), as nested lists:
    cheaper than mpmath's matrix inverse."""
    g = len(Y)
    A = [[ctx.mpf(float(Y[i, j])) for j in range(g)] + [ctx.mpf(int(i == j)) for j in range(g)] for i in range(g)]
    for k in range(g):
        r = 1 / A[k][k]
        A[k] = [x * r for x in A[k]]
        for i in range(g):
            if i != k and A[i][k]:
                f = A[i][k]
                A[i] = [x - f * y for x, y in zip(A[i], A[k], strict=True)]
    return [row[g:] for row in A]


def _half_images(v2: np.ndarray, Lam: np.ndarray, shift: np.ndarray, ctx) -> tuple:
    """:func:`_general_images` for half-integer characteristics (``v2 = 2 (alpha, beta)`` integer), exactly
    in integers: the images are half-integers, ``a1 - p`` and ``b1 - q`` in ``{0, 1/2}``."""
    g = v2.shape[1] // 2
    img2 = np.rint(v2).astype(np.int64) @ Lam.astype(np.int64).T + np.rint(2 * shift).astype(np.int64)
    fl = img2 // 2
    half = lambda m: np.vectorize(lambda x: ctx.mpf(int(x)) / 2, otypes=[object])(m)  # noqa: E731
    whole = lambda m: np.vectorize(lambda x: ctx.mpf(int(x)), otypes=[object])(m)  # noqa: E731
    fr = (img2 - 2 * fl) / 2.0
    return half(img2[:, :g]), half(img2[:, g:]), whole(fl[:, :g]), whole(fl[:, g:]), fr[:, :g], fr[:, g:]


def _general_images(alpha: np.ndarray, beta: np.ndarray, Lam: np.ndarray, shift: np.ndarray, ctx) -> tuple:
    """``(a1, b1, p, q, ar, br)``: the images ``(a1, b1) = Lam (alpha, beta) + shift`` in mpmath, their floors
    ``p, q`` and the reduced characteristics ``a1 - p, b1 - q`` in float64."""
    g = alpha.shape[1]
    a1 = np.empty_like(alpha, dtype=object)
    b1 = np.empty_like(beta, dtype=object)
    for ci in range(alpha.shape[0]):
        ab = [ctx.mpf(float(x)) for x in np.concatenate([alpha[ci], beta[ci]])]
        img = [ctx.fsum(int(Lam[i, j]) * ab[j] for j in range(2 * g)) + ctx.mpf(shift[i]) for i in range(2 * g)]
        a1[ci], b1[ci] = img[:g], img[g:]
    # exact floor, no snapping: a characteristic 1e-13 off an integer is a different
    # characteristic (theta changes by ~2 pi |z| 1e-13), and the constant K uses the exact a1 - p
    p = np.vectorize(ctx.floor)(a1)
    q = np.vectorize(ctx.floor)(b1)
    return a1, b1, p, q, np.vectorize(float)(a1 - p).astype(float), np.vectorize(float)(b1 - q).astype(float)


def _char_form(mp: dict, Lam: np.ndarray, shift: np.ndarray) -> tuple[list, list, object]:
    """``(H, h, c)`` in mpmath with ``K(v) = c + v.H.v + h.v + 2 pi i (a1 - p).q`` for ``v = (alpha, beta)``:
    the sum of the prefactor's terms ``pi i al.tau0.al + 2 pi i al.be + c0 + 2 pi i l.d0 + pi i d0.Q.d0
    - pi i a1.taur.a1 - 2 pi i a1.b1`` with ``d0 = tau0 al + be`` and ``(a1, b1) = Lam v + shift``."""
    ctx = mp["ctx"]
    tau0, taur, Qm, lm = mp["tau0"], mp["tau"], mp["Q"], mp["l"]
    g = len(tau0)
    r2 = range(2 * g)
    pi_i = ctx.pi * 1j
    D = [[tau0[i][j] if j < g else ctx.mpf(int(i == j - g)) for j in r2] for i in range(g)]      # d0 = D v
    A = [[ctx.mpf(int(Lam[i, j])) for j in r2] for i in range(2 * g)]                             # a1, b1 = A v
    sa, sb = [ctx.mpf(x) for x in shift[:g]], [ctx.mpf(x) for x in shift[g:]]
    QD = [[ctx.fdot(Qm[i], [D[k][j] for k in range(g)]) for j in r2] for i in range(g)]
    TA = [[ctx.fdot(taur[i], [A[k][j] for k in range(g)]) for j in r2] for i in range(g)]
    H = [[pi_i * (ctx.fdot([D[k][i] for k in range(g)], [QD[k][j] for k in range(g)])
                  - ctx.fdot([A[k][i] for k in range(g)], [TA[k][j] for k in range(g)]))
          - 2 * pi_i * ctx.fdot([A[k][i] for k in range(g)], [A[g + k][j] for k in range(g)])
          for j in r2] for i in r2]
    for i in range(g):
        H[i][g + i] += 2 * pi_i
        for j in range(g):
            H[i][j] += pi_i * tau0[i][j]
    Ts = [ctx.fdot(taur[i], sa) for i in range(g)]
    h = [2 * pi_i * (ctx.fdot(lm, [D[k][j] for k in range(g)]) - ctx.fdot(Ts, [A[k][j] for k in range(g)])
                     - ctx.fdot(sa, [A[g + k][j] for k in range(g)]) - ctx.fdot(sb, [A[k][j] for k in range(g)]))
         for j in r2]
    return H, h, _char_constant(mp, shift)


def _char_constant(mp: dict, shift: np.ndarray):
    """The constant ``c = c0 - pi i sa.taur.sa - 2 pi i sa.sb`` of :func:`_char_form` (mpmath), with
    ``(sa, sb) = shift``: all of ``K`` at the zero characteristic."""
    ctx = mp["ctx"]
    taur = mp["tau"]
    g = len(taur)
    pi_i = ctx.pi * 1j
    sa, sb = [ctx.mpf(x) for x in shift[:g]], [ctx.mpf(x) for x in shift[g:]]
    Ts = [ctx.fdot(taur[i], sa) for i in range(g)]
    return mp["c0"] - pi_i * ctx.fdot(sa, Ts) - 2 * pi_i * ctx.fdot(sa, sb)


def riemann_theta(z: ArrayLike, tau: ArrayLike, char: str | tuple[ArrayLike, ArrayLike] | None = None,
                  derivs: Sequence = (), tol: float = 1e-14, dps: int | None = None) -> np.ndarray | complex:
    """Riemann theta function ``theta[alpha; beta](z | tau)`` (DLMF 21.2.5) or a derivative.

    Parameters
    ----------
    z : array_like, shape (..., g)
        Complex points.
    tau : array_like, shape (g, g)
        Riemann matrix: symmetric (to 1e-12 relative; symmetrized), ``Im tau`` positive definite.
    char : None, "all" or (alpha, beta)
        Characteristic (real vectors of length g); "all" gives the 2^(2g) half-integer ones
        (flint order, see module notes) along a new last axis.
    derivs : sequence of direction vectors
        ``(v_1, ..., v_k)``: returns ``D_{v_1} ... D_{v_k} theta`` (any order up to 8).
    tol : float
        Absolute error of ``theta * exp(-e)``, ``e = pi y.(Im tau)^{-1}.y`` (default 1e-14).
    dps : int, optional
        If given, evaluate with mpmath at ``dps`` decimal digits (object array of ``mpc``;
        tol is then ``10**-dps``).

    Returns
    -------
    ndarray of complex, shape ``z.shape[:-1]`` (a scalar for one point).

    Raises
    ------
    ValueError
        Bad input (non-symmetric tau, Im tau not positive definite, wrong shapes, NaN).
    OverflowError
        If ``|theta|`` overflows float64; use :func:`riemann_theta_separated`.
    """
    if dps is not None:
        from thetasol.theta._mp import theta_mp
        return theta_mp(z, tau, char, derivs, dps, separated=False)
    return RiemannTheta(tau, tol)(z, char, derivs)


def riemann_theta_separated(z: ArrayLike, tau: ArrayLike, char: str | tuple[ArrayLike, ArrayLike] | None = None,
                            derivs: Sequence = (), tol: float = 1e-14,
                            dps: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Exponent-separated theta: ``(e, v)`` with ``theta = exp(e) * v``.

    ``e = pi y.(Im tau)^{-1}.y`` (real, ``y = Im z``) and ``|v|`` is bounded by a constant
    depending on tau only (for derivatives, by that constant times the natural derivative
    size).  Same parameters as :func:`riemann_theta`; never overflows.
    """
    if dps is not None:
        from thetasol.theta._mp import theta_mp
        return theta_mp(z, tau, char, derivs, dps, separated=True)
    return RiemannTheta(tau, tol).separated(z, char, derivs)
