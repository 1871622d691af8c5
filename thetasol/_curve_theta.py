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


def ellipsoid_points(Y, center, R2):
    """Integer points n with (n + center)^T Y (n + center) <= R2 (Fincke-Pohst, breadth first).

    Y symmetric positive definite (g x g); returns an int array (K, g).
    """
    g = Y.shape[0]
    L = np.linalg.cholesky(Y)  # Y = L L^T; use the upper factor U = L^T
    U = L.T
    c = np.asarray(center, dtype=float)
    # work from the last coordinate: q = sum_i (U_ii (n_i + c_i) + sum_{j>i} U_ij (n_j + c_j))^2
    pts = np.zeros((1, 0), dtype=np.int64)
    rem = np.array([R2])
    acc = np.zeros((1, g))  # partial sums sum_{j>i} U_ij (n_j + c_j) for each row i
    for i in range(g - 1, -1, -1):
        uii = U[i, i]
        shift = acc[:, i] / uii + c[i]  # (n_i + shift) * uii squared is the new term
        half = np.sqrt(np.maximum(rem, 0.0)) / uii
        lo = np.ceil(-half - shift).astype(np.int64)
        hi = np.floor(half - shift).astype(np.int64)
        cnt = np.maximum(hi - lo + 1, 0)
        if cnt.sum() == 0:
            return np.zeros((0, g), dtype=np.int64)
        rep = np.repeat(np.arange(len(cnt)), cnt)
        offs = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        ni = lo[rep] + offs
        term = (uii * (ni + shift[rep])) ** 2
        rem = rem[rep] - term
        acc = acc[rep] + np.outer(ni + c[i], U[:, i])
        pts = np.concatenate([ni[:, None], pts[rep]], axis=1)
    return pts


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
    R2 = np.log(1.0 / tol) + 2.0 + g
    cmax = 0.5 * np.sqrt(np.abs(Y).sum())  # max sqrt(c^T Y c) over the unit cube |c_i| <= 1/2
    pts = ellipsoid_points(Y, np.zeros(g), (np.sqrt(R2 / np.pi) + cmax) ** 2).astype(float)
    pY = pts @ Y
    quad = (pY * pts).sum(axis=1)  # (K,)
    Q = quad[None, :] + 2.0 * (cr @ pY.T) + ((cr @ Y) * cr).sum(axis=1)[:, None]
    expo = (1j * np.pi * ((pts @ X) * pts).sum(axis=1)[None, :]
            + 2j * np.pi * (xr @ pts.T)
            - np.pi * Q)
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


def half_period_scan(z0, tau, tol=1e-9):
    """|theta| exp(-pi y^T Y^-1 y) at all 4^g points z0 + (a + tau b)/2, a, b in {0, 1}^g.

    One lattice sum per b (grouped by n mod 2, then a sign transform over a) instead of 4^g sums.
    Returns (values (4^g,), a (4^g, g), b (4^g, g)) with a, b integer arrays.
    """
    z0 = np.asarray(z0, dtype=complex).ravel()
    tau = np.asarray(tau, dtype=complex)
    tau = 0.5 * (tau + tau.T)
    g = len(z0)
    U = lll_gram(tau.imag)
    Uinv = np.rint(np.linalg.inv(U)).astype(np.int64)
    taup = U.T @ tau @ U
    zp = U.T @ z0
    Y, X = taup.imag, taup.real
    Yinv = np.linalg.inv(Y)
    m = np.rint(Yinv @ zp.imag)
    zp = zp - taup @ m  # lattice shift: same candidate set modulo the lattice
    c = Yinv @ zp.imag
    x0 = zp.real
    R2 = np.log(1.0 / tol) + 2.0 + g
    bits = np.array([[(i >> k) & 1 for k in range(g)] for i in range(2 ** g)], dtype=np.int64)
    sign = 1 - 2 * (np.mod(bits @ bits.T, 2))  # (-1)^{class . a}, indexed [class, a]
    vals = np.zeros((2 ** g, 2 ** g))  # [b, a]
    for ib, b in enumerate(bits):
        n = ellipsoid_points(Y, 0.5 * b + c, R2 / np.pi)
        par = np.mod(n, 2) @ (1 << np.arange(g))  # class of n mod 2
        nf = n.astype(float)
        mm = nf + 0.5 * b  # m_n = n + b/2
        ww = mm + c
        qq = ((ww @ Y) * ww).sum(axis=1)
        phase = np.pi * ((mm @ X) * mm).sum(axis=1) + 2 * np.pi * (nf @ x0)
        T = np.exp(1j * phase - np.pi * qq)
        S = np.bincount(par, weights=T.real, minlength=2 ** g) + 1j * np.bincount(
            par, weights=T.imag, minlength=2 ** g)
        vals[ib] = np.abs(S @ sign)
    # back to the original (a, b): a = U^-T a' (mod 2), b = U b' (mod 2)
    A_out, B_out, V_out = [], [], []
    for ib, bp in enumerate(bits):
        for ia, ap in enumerate(bits):
            A_out.append(np.mod(Uinv.T @ ap, 2))
            B_out.append(np.mod(U @ bp, 2))
            V_out.append(vals[ib, ia])
    return np.array(V_out), np.array(A_out, dtype=np.int64), np.array(B_out, dtype=np.int64)
