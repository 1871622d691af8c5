"""A small Riemann theta sum, used to pick the Riemann constant among its 2^(2g) candidates.

Private and deliberately minimal (no derivatives, no error bounds beyond a fixed ellipsoid):
the library's theta module (issue 3) is the general tool.  Method: LLL-reduce Im(tau) by a
unimodular change of the summation lattice (which leaves theta unchanged), shift z by lattice
vectors so that c = Im(tau)^-1 Im(z) lies in the unit cube, and sum over the ellipsoid
pi (n + c)^T Y (n + c) <= R^2.  Values are returned in the e^u * v form: theta(z) = exp(u) v with
u = pi y^T Y^-1 y real for the reduced argument; |v| is a lattice-periodic, bounded measure of
theta that the zero tests use.
"""
from __future__ import annotations

import itertools

import numpy as np


def lll_gram(Y, delta=0.75):
    """Unimodular U with U^T Y U LLL-reduced (Y real symmetric positive definite)."""
    g = Y.shape[0]
    U = np.eye(g, dtype=np.int64)
    B = Y.astype(float).copy()

    def gso(B):
        mu = np.zeros((g, g))
        bstar = np.zeros(g)
        for i in range(g):
            for j in range(i):
                mu[i, j] = (B[i, j] - sum(mu[j, k] * mu[i, k] * bstar[k] for k in range(j))) / bstar[j]
            bstar[i] = B[i, i] - sum(mu[i, k] ** 2 * bstar[k] for k in range(i))
        return mu, bstar

    k = 1
    it = 0
    while k < g and it < 10000:
        it += 1
        mu, bstar = gso(B)
        for j in range(k - 1, -1, -1):
            q = int(np.rint(mu[k, j]))
            if q:
                T = np.eye(g, dtype=np.int64)
                T[j, k] = -q
                U = U @ T
                B = T.T @ B @ T
                mu, bstar = gso(B)
        if bstar[k] >= (delta - mu[k, k - 1] ** 2) * bstar[k - 1]:
            k += 1
        else:
            P = np.eye(g, dtype=np.int64)
            P[[k, k - 1]] = P[[k - 1, k]]
            U = U @ P
            B = P.T @ B @ P
            k = max(k - 1, 1)
    return U


def theta_uv(z, tau, tol=1e-14):
    """Riemann theta in the form theta(z) = exp(u) * v for z of shape (N, g).

    Returns (u, v): u real (N,), v complex (N,).
    """
    z = np.atleast_2d(np.asarray(z, dtype=complex))
    tau = np.asarray(tau, dtype=complex)
    tau = 0.5 * (tau + tau.T)
    g = tau.shape[0]
    Y = tau.imag
    U = lll_gram(Y)
    tau = U.T @ tau @ U
    z = z @ U  # z -> U^T z for each row
    Y = tau.imag
    X = tau.real
    Yinv = np.linalg.inv(Y)
    y = z.imag
    c = y @ Yinv  # (N, g)
    m = np.rint(c)
    # theta(z - tau m) = exp(-pi i m^T tau m + 2 pi i m^T z) theta(z)
    zr = z - m @ tau.T
    # zr = z - tau m; theta(z) = theta(zr + tau m) = exp(-pi i m^T tau m - 2 pi i m^T zr) theta(zr)
    log_fac = -1j * np.pi * np.einsum("ni,ij,nj->n", m, tau, m) - 2j * np.pi * np.einsum("ni,ni->n", m, zr)
    yr = zr.imag
    cr = yr @ Yinv
    xr = zr.real
    R2 = np.log(1.0 / tol) + 2.0 * np.log(10.0) + 2 * g
    Lc = np.linalg.cholesky(Y)  # Y = Lc Lc^T
    # bound |n_i + c_i| <= sqrt(R2 / pi * (Y^-1)_ii)
    rad = np.sqrt(R2 / np.pi * np.diag(Yinv)) + 0.5
    ranges = [np.arange(-int(np.ceil(r)), int(np.ceil(r)) + 1) for r in rad]
    pts = np.array(list(itertools.product(*ranges)), dtype=float)
    # keep points inside the union of ellipsoids centred at -c, |c_i| <= 1/2
    q = np.sqrt(np.einsum("ki,ij,kj->k", pts, Y, pts) * np.pi)
    cmax = 0.5 * np.sqrt(np.pi * np.abs(Y).sum())
    pts = pts[q <= np.sqrt(R2) + cmax]
    nc = pts[None, :, :] + cr[:, None, :]  # (N, K, g)
    expo = (1j * np.pi * np.einsum("ki,ij,kj->k", pts, X, pts)[None, :]
            + 2j * np.pi * np.einsum("ki,ni->nk", pts, xr)
            - np.pi * np.einsum("nki,ij,nkj->nk", nc, Y, nc))
    v = np.exp(expo).sum(axis=1)
    u = np.pi * np.einsum("ni,ij,nj->n", yr, Yinv, yr)
    # theta(z) = exp(log_fac) * exp(u) * v ; fold the phase of log_fac into v and its modulus into u
    u = u + log_fac.real
    v = v * np.exp(1j * log_fac.imag)
    return u, v


def theta_normalized_abs(z, tau, tol=1e-14):
    """|theta(z)| exp(-pi y^T Y^-1 y): lattice periodic, bounded; used for zero tests."""
    z = np.atleast_2d(np.asarray(z, dtype=complex))
    u, v = theta_uv(z, tau, tol)
    Y = np.asarray(tau).imag
    Y = 0.5 * (Y + Y.T)
    y = z.imag
    uu = np.pi * np.einsum("ni,ij,nj->n", y, np.linalg.inv(Y), y)
    return np.abs(v) * np.exp(u - uu)


def theta(z, tau, tol=1e-14):
    u, v = theta_uv(z, tau, tol)
    return np.exp(u) * v
