"""Arbitrary-precision Riemann theta (mpmath), the ``dps=`` path of :mod:`thetasol.theta.riemann`.

Sums the defining series directly in the original frame, over the lattice points of the union
ellipsoid around the Babai-rounded centre ``-(Im tau)^{-1} Im z - alpha`` with the radius of
the Deconinck et al. bound for ``10**-(dps + 3)``.  No Siegel reduction: this path is the
slow, transparent reference (terms for ill-conditioned tau are just more numerous).  The point
set is chosen in float64, which only decides which negligible terms are dropped; every term is
computed with mpmath at ``dps + 10`` digits inside ``mpmath.workdps`` (global precision untouched).
"""
from __future__ import annotations

import math

import mpmath
import numpy as np

from thetasol.theta._checks import (
    check_char as _check_char,
    check_dirs as _check_dirs,
    check_tau as _check_tau,
    check_z as _check_z,
)
from thetasol.theta.lattice import babai, radius_for, shortest_vector, union_set

#: Largest dps accepted (the float64 tail bound underflows beyond ~1e-300).
MAX_DPS = 250


def _to_mp_array(x, shape_check: np.ndarray) -> np.ndarray:
    """Object array of mpmath.mpc with the exact input values (floats or mpmath numbers)."""
    arr = np.asarray(x, dtype=object) if np.asarray(x).dtype == object else np.asarray(x, dtype=complex)
    out = np.empty(shape_check.shape, dtype=object)
    flat = arr.reshape(-1)
    of = out.reshape(-1)
    for i in range(flat.size):
        of[i] = mpmath.mpmathify(complex(flat[i]) if not isinstance(flat[i], (mpmath.mpf, mpmath.mpc))
                                 else flat[i])
    return out


def theta_mp(z, tau, char, derivs, dps: int, separated: bool):

    if not isinstance(dps, (int, np.integer)) or not 5 <= int(dps) <= MAX_DPS:
        raise ValueError(f"dps must be an integer in [5, {MAX_DPS}], got {dps!r}")
    dps = int(dps)
    tau_f = _check_tau(tau)
    g = tau_f.shape[0]
    z_f = _check_z(z, g)
    alpha, beta, is_all = _check_char(char, g)
    V_f = _check_dirs(derivs, g)
    shape = z_f.shape[:-1]
    Y = tau_f.imag
    T = np.linalg.cholesky(Y).T
    rho = shortest_vector(T)
    a = 1.0
    if len(V_f):
        nv = np.linalg.norm(V_f, axis=1)
        nz = nv > 0
        a = float(np.max(np.linalg.norm(V_f[nz] @ np.linalg.inv(T), axis=1) / nv[nz], initial=1.0))
    R = radius_for(10.0 ** -(dps + 3), rho, g, len(V_f), 2 * math.pi * max(a, 1.0) if len(V_f) else 1.0) + 0.05
    mset = union_set(T, R)
    # the alpha groups: "all" sums over alpha in {0,1/2}^g with the beta signs applied per term
    alphas = np.unique(alpha, axis=0) if is_all else alpha
    zf = z_f.reshape(-1, g)
    with mpmath.workdps(dps + 10):
        tau_in = np.asarray(tau)
        if tau_in.dtype == object:
            tm = _to_mp_array(tau_in, tau_in)
            tm = [[(tm[i, j] + tm[j, i]) / 2 for j in range(g)] for i in range(g)]
        else:
            tm = [[mpmath.mpc(complex(tau_f[i, j])) for j in range(g)] for i in range(g)]
        z_in = np.asarray(z)
        zm = (_to_mp_array(z_in, z_in) if z_in.dtype == object else _to_mp_array(z_f, z_f)).reshape(-1, g)
        Vm = [[mpmath.mpmathify(complex(x)) if not isinstance(x, (mpmath.mpf, mpmath.mpc)) else x for x in v]
              for v in (list(derivs) if len(V_f) else [])]
        upper = [(i, j) for i in range(g) for j in range(i, g)]
        tu = [tm[i][j] if i == j else 2 * tm[i][j] for i, j in upper]
        Ym = mpmath.matrix([[tm[i][j].imag for j in range(g)] for i in range(g)])
        Yinv = Ym ** -1
        pi, two_pi_i = mpmath.pi, 2j * mpmath.pi
        nchar = len(alpha)
        res = np.empty((len(zf), nchar), dtype=object)
        evals = np.empty(len(zf), dtype=object)
        for p in range(len(zf)):
            zp = zm[p]
            zl = [zp[i] for i in range(g)]
            y = [zp[i].imag for i in range(g)]
            e = pi * mpmath.fsum(y[i] * Yinv[i, j] * y[j] for i in range(g) for j in range(g))
            evals[p] = e
            c = np.array([float(mpmath.fsum(Yinv[i, j] * y[j] for j in range(g))) for i in range(g)])
            sums = [mpmath.mpc(0)] * nchar
            for al in alphas:
                k = babai((c + al)[None, :], T)[0]
                ns = mset - k.astype(np.int64)[None, :]
                mem = [ci for ci in range(nchar) if np.array_equal(alpha[ci], al)]
                alm = [mpmath.mpf(float(x)) for x in al]
                betas = [[mpmath.mpf(float(x)) for x in beta[ci]] for ci in mem]
                # exp(2 pi i (n+alpha).beta) = exp(2 pi i alpha.beta) (-1)^{n.2beta} for half-integer beta
                half = all(float(2 * x).is_integer() for ci in mem for x in beta[ci])
                const = [mpmath.expjpi(2 * mpmath.fsum(alm[i] * be[i] for i in range(g))) for be in betas]
                twob = np.rint(2 * beta[mem]).astype(np.int64)
                for n in ns:
                    na = [int(n[i]) + alm[i] for i in range(g)]
                    # (n+alpha).tau.(n+alpha) over the upper triangle (tau symmetric); the
                    # coefficients are exact products of the mpf entries
                    quad = mpmath.fdot([na[i] * na[j] for i, j in upper], tu)
                    term = mpmath.exp(1j * pi * quad + two_pi_i * mpmath.fdot(na, zl))
                    for v in Vm:
                        term *= two_pi_i * mpmath.fsum(v[i] * na[i] for i in range(g))
                    if half:
                        sg = (twob @ n) & 1
                        for idx, ci in enumerate(mem):
                            sums[ci] += -term * const[idx] if sg[idx] else term * const[idx]
                    else:
                        for ci, be in zip(mem, betas):
                            sums[ci] += term * mpmath.expjpi(2 * mpmath.fsum(na[i] * be[i] for i in range(g)))
            for ci in range(nchar):
                res[p, ci] = sums[ci] * mpmath.exp(-e) if separated else sums[ci]
    out = res if is_all else res[:, 0]
    out = out.reshape(shape + out.shape[1:])
    if separated:
        ev = evals.reshape(shape)
        return (ev[()] if ev.ndim == 0 else ev), (out[()] if out.ndim == 0 else out)
    return out[()] if out.ndim == 0 else out
