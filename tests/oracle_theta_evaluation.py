"""The numpy oracle of the compiled theta-rotation evaluation (thetasol.core.kernels, src/kernels.cpp).

The shipped library evaluates the theta-function rotation per time in C++ only; this module keeps the
same algorithm in numpy, written for reading rather than speed, so that the tests can run the kernel
against it (tests/test_core_kernels.py) and check the oracle's own steps against mpmath
(tests/test_theta_evaluation.py).  It computes from the frozen tables of
:class:`thetasol.theta.flow.FlowTheta` and :class:`thetasol.solutions.rotation.theta_rotation.evaluator.FlowEvaluator`,
with the operations in the kernel's order where that order is fixed (turns, powers, products over the
phases, the complex quotient); only the matrix products sum in BLAS's order.
"""
from __future__ import annotations

import math

import numpy as np

from thetasol.core.so3 import polar_near_orthogonal
from thetasol.core.turns import rate_turns

TWO_PI_I = 2j * math.pi


def flow_turns(flow, t: np.ndarray) -> np.ndarray:
    """``t u`` modulo 1 (n, r) in ``[-1/2, 1/2]``, from the exact pieces of the rates."""
    x = np.ascontiguousarray(rate_turns(np.asarray(t, float), *flow.u_pieces).T)
    x -= np.rint(x)
    return x


def table_columns(flow) -> tuple[np.ndarray, np.ndarray]:
    """``(i, k)`` of the columns of :func:`flow_tables`: column j holds ``exp(2 pi i k[j] phi_{i[j]})``."""
    owner = np.repeat(np.arange(len(flow.span)), flow.span)
    k = np.concatenate([np.arange(s) + lo for lo, s in zip(flow.lo, flow.span)]).astype(float)
    return owner, k


def flow_tables(flow, phi: np.ndarray) -> np.ndarray:
    """The tables ``exp(2 pi i k phi_i)`` side by side (n, sum span): powers of ``exp(2 pi i phi_i)``
    outwards from ``k = 0`` (``exp(-i x) = conj(exp(i x))``)."""
    n = phi.shape[0]
    base = np.exp(TWO_PI_I * phi)
    tab = np.empty((n, int(flow.span.sum())), complex)
    start = 0
    for i, (lo, span) in enumerate(zip(flow.lo, flow.span)):
        z, stop = start - lo, start + span
        tab[:, z] = 1.0
        for k in range(z + 1, stop):
            tab[:, k] = base[:, i] if k == z + 1 else tab[:, k - 1] * base[:, i]
        for k in range(z - 1, start - 1, -1):
            tab[:, k] = base[:, i].conj() if k == z - 1 else tab[:, k + 1] * base[:, i].conj()
        start = stop
    return tab


def flow_phases(flow, phi: np.ndarray) -> np.ndarray:
    """``exp(2 pi i p.phi)`` (n, P) of the modes up to sign: the products of their table entries, phase
    by phase from the first."""
    tab = flow_tables(flow, phi)
    starts = np.concatenate([[0], np.cumsum(flow.span)[:-1]])
    cols = flow.table_modes + starts[None, :]                         # (P, r)
    out = tab[:, cols[:, 0]]
    for i in range(1, cols.shape[1]):
        out = out * tab[:, cols[:, i]]
    return np.ascontiguousarray(out)


def flow_values(flow, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(v, dv)`` (n, S) each: theta along the flow and its t-derivative, scaled by ``exp(-e)``."""
    S = flow.D.shape[0]
    vd = (flow_phases(flow, flow_turns(flow, t)).view(float) @ flow.W).view(complex)
    return vd[:, :S], vd[:, S:]


def evaluate(ev, t: np.ndarray, values: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(omega (n, 3), Q (n, 3, 3))`` of a :class:`FlowEvaluator` at the flat times ``t``: ``Psi`` and
    ``Psidot`` through the folded linear map, the polar factor by one Newton-Schulz step, ``vee(F Fd^T)``,
    and the turning frame of a symmetric body.  ``values``: the flow's ``(v, dv)`` at ``t`` if given
    (the tests perturb them to measure the state's conditioning)."""
    t = np.asarray(t, float)
    v, dv = flow_values(ev.flow, t) if values is None else values
    n = t.shape[0]
    vb, vd = v[:, :9].reshape(n, 3, 3), v[:, 9:]
    ivd = 1.0 / vd
    q = np.exp(ev.turns.rows(t).T * TWO_PI_I).take(ev.turns.row_of, axis=1).reshape(n, 3, 3)
    q *= ev.amp
    q *= ivd[:, None, :]
    Z = np.empty((n, 2, 3, 3), complex)
    np.multiply(q, vb, out=Z[:, 0])
    rate = 1j * ev.nu - (dv[:, 9:] * ivd)[:, None, :]
    rate *= vb
    rate += dv[:, :9].reshape(n, 3, 3)
    np.multiply(q, rate, out=Z[:, 1])
    Y = ev.lin @ Z.reshape(n, 18).view(float).T
    Q = polar_near_orthogonal(Y[:9].reshape(3, 3, n))
    w = np.add.reduce((Y[27:36] * Y[9:18] - Y[36:45] * Y[18:27]).reshape(3, 3, n), axis=1)
    if ev.axis is not None:
        ax, spin, P = ev.axis, ev.spin, ev.P
        i, j = (ax + 1) % 3, (ax + 2) % 3
        c, s = np.cos(-spin * t), np.sin(-spin * t)
        Qr = np.empty_like(Q)
        Qr[:, ax] = Q[:, ax]
        Qr[:, i] = c * Q[:, i] - s * Q[:, j]
        Qr[:, j] = s * Q[:, i] + c * Q[:, j]
        wr = np.empty_like(w)
        wr[ax] = w[ax] + spin
        wr[i] = c * w[i] - s * w[j]
        wr[j] = s * w[i] + c * w[j]
        Q, w = np.matmul(P, Qr), P @ wr
    return np.ascontiguousarray(w.T), np.ascontiguousarray(Q.transpose(2, 0, 1))
