"""Rotation of a rigid body in a quadratic potential in Riemann theta functions (Section 4 II).

The method (derivation and checks in docs/theta_rotation.md)
------------------------------------------------------------
The Lax pair (4.11) ``L(E) = J^2 E^2 + M E + u``, ``A(E) = J E + omega``, ``Ldot = [L, A]``
is solved by the fundamental matrix ``Phi(E, t)`` of ``Phidot = -A(E, t) Phi``: then
``L(E, t) = Phi L(E, 0) Phi^{-1}`` and, at ``E = 0``, ``Phi(0, t) = Q(t)^T Q0``: the attitude
itself.  For a point ``P = (E, w)`` of the spectral curve (4.12) let ``psi(P)`` be the eigenvector
of ``L(E, 0)`` normalized by ``<alpha, psi> = 1``.  The vector Baker-Akhiezer function
``Psi(P, t) = Phi(E, t) psi(P)`` has the poles of ``psi`` (a divisor ``D0`` of degree g + 2),
the essential singularity ``exp(-J_j E t)`` at the place ``inf_j`` over ``E = infinity`` and
``Psi_k exp(J_j E t) -> delta_kj / alpha_j`` there.  Its components are theta quotients::

    Psi_k(P, t) = rho_k(P) exp(c_k(P) t) theta(A(P) + t V - e_k) theta(A(inf_k) - e_k)
                                        / theta(A(inf_k) + t V - e_k)
    e_k = A(D0) - sum_{j != k} A(inf_j) + K,     V = sum_j J_j omega(inf_j) / ds  (s = 1/E),

with ``rho_k = psi_k / theta(A(P) - e_k)`` and ``c_k`` fixed at t = 0.  For distinct J no Abel image
at infinity is used: ``e_k = A(Z_k) + K`` (Z_k the finite zeros of the k-th eigenvector component),
``A(inf_k) - e_k = sum_s A(P_s) - A(D0) - K`` (div E) and K from the divisor 2 sum_s P_s of
``E^2 dE / f_w`` (docs/theta_rotation.md: the places at infinity of a nearly symmetric body sit in a
cluster of branch points).  Evaluating at the three
places over ``E = 0`` gives ``Phi(0, t)``, hence ``Q(t)`` and ``omega = vee(-Phidot Phi^T)``;
``M = hat(I omega)`` and ``u = -Q^T a Q``.  Both constants are Cauchy means over a small circle
around the place, so they stay exact where a component of the initial eigenvector vanishes
(``rho_k`` then has a removable 0/0).  The exponents satisfy ``c_k(P_s) = F_s - G_k`` exactly
(``Omega(P_s) - Omega(inf_k)``); they are fitted in that form by weighted least squares, each entry
weighted by its conditioning, with auxiliary points near the branch points where eigenvectors mix,
and the fit only picks the integers of their exact values (:func:`_exact_exponents`: sigma makes
every exponent a half lattice rate ``pi n.U`` up to the third-kind rates of the nodes).  The periods
behind ``U`` are summed in double-double (:mod:`thetasol.curves.plane_curve`).

Everything is computed in a homology basis adapted to the real Liouville torus
(:mod:`thetasol.curves.adapted_basis`): there ``V`` is real and has only as many non-zero coordinates as
the torus has dimensions (3, the Prym variety; 2 for a rank-one potential), so theta along the
trajectory is a Fourier series in those phases (:mod:`thetasol.theta.flow`) and a far time costs
what t = 1 costs.

Degenerate data (only what the scene needs)
-------------------------------------------
* ``a`` with a repeated eigenvalue (the gravity gradient of Section 7): the curve has a node at
  ``E = 0`` and the same construction runs on its genus-3 normalization, the node's two branches
  taking the place of two of the points over ``E = 0``; there ``L(E) - w`` has two rows parallel to
  ``O(E)``, so eigenvalue and eigenvector come from a scaled eigenproblem (:func:`_node_branch`).
* ``a`` isotropic or zero, or a spherical body: no torque; :func:`thetasol.solve_rotation` uses the
  Euler top instead.
* a symmetric body (two equal ``J_i``): the spin about the symmetry axis is an integral and the
  curve has a node over ``E = infinity``.  In the frame turning at ``-spin`` about the axis
  (``Q~ = Q R(t)``, ``omega~ = R^T omega - spin e``) the Lax equation keeps its form and ``omega~``
  has no axial part, so the Baker-Akhiezer function has no third-kind singularity at the node's
  branches: the construction runs on the genus-3 normalization (genus 2 with a rank-one ``a``)
  with ``B`` the eigenvectors ``(e1 +- i e2) / sqrt 2`` of ``M`` at the node, and
  ``Q = Q~ R(t)^T``, ``omega = R omega~ + spin e``; the exponents' difference at the node (the
  rate of the turn about the axis) is exact, from the third-kind differential ``E^2 dE / f_w``
  (:func:`_node_exponent_gap`).  Without axial spin the branches touch
  (a tacnode; the axis moves as in Neumann's problem, :mod:`thetasol.solutions.neumann_rotation`).  A small spin puts two
  branch points near ``|E| ~ 1 / spin``; the expansions at the node's branches then grow like
  ``spin^-k``, so the quantities read there (``U``, the exponent gap) come in closed form (Euler-Jacobi,
  :func:`_velocity_at_infinity`) and the canonical divisor avoids them.  Measured to
  ``MIN_AXIAL_SPIN = 3e-4`` of ``|omega0| + sqrt|a|`` (docs/theta_rotation.md); below it, or with the
  farthest branch point beyond ``MAX_FAR_BRANCH`` (nearly spherical bodies), the data are refused at
  once (ClosedFormUnavailable).
"""
from __future__ import annotations

import warnings

from dataclasses import dataclass, field

import numpy as np
import sympy as sp

from thetasol.curves.adapted_basis import real_flow_basis
from thetasol.mechanics.lax import eigenvector_poles, lax_matrix, polish_eigenvector_poles, right_eigenvector
from thetasol.theta.flow import FlowTheta
from thetasol.core.so3 import hat, polar_orthonormalize, rotation_about, vee
from thetasol.mechanics.equations import inertia_from_moments, invariants as _invariants
from thetasol.solutions.base import ClosedFormUnavailable, RotationSolution
from thetasol.curves.spectral import spectral_curve
from thetasol.solutions._symmetry import SNAP_TOL, sorted_principal_frame as _principal_frame, symmetry_axis as _symmetry_axis
from thetasol.theta.riemann import RiemannTheta

__all__ = ["ThetaRotation"]

#: Nearly degenerate data refused at once (measured limits, docs/theta_rotation.md): a symmetric body's
#: axial spin relative to |omega0| + sqrt|a|, and the relative gap of two principal second moments.
MIN_AXIAL_SPIN = 3e-4
MIN_J_GAP = 1e-7
#: A symmetric body is also refused at once when its farthest branch point lies beyond this in units
#: of sqrt(max |eig a|) / max J (a small axial spin puts two of them near |E| ~ 1 / spin; nearly
#: spherical bodies have them farther still): the J gap 0.25 % body of the tests took 4.8 s CPU at 4.2e4
#: (relative spin 1e-3) and 114 s for the curve alone at 1.4e5 (3e-4).
MAX_FAR_BRANCH = 2e4
#: Points on the circles of the Cauchy means, and Gauss-Legendre nodes on their radii.
N_CIRCLE = 32
N_RAY = 16


def _choose_alpha(X: np.ndarray) -> np.ndarray:
    """A normalization vector far from orthogonal to the columns of X and to the axes."""
    best, score = None, -1.0
    rng = np.random.default_rng(20240601)
    cands = [np.array([1.0, 2 ** 0.5, 3 ** 0.5])] + [rng.normal(size=3) for _ in range(40)]
    Xn = X / np.linalg.norm(X, axis=0, keepdims=True)
    for c in cands:
        c = c / np.linalg.norm(c)
        sc = min(np.min(np.abs(c)), np.min(np.abs(c @ Xn)))
        if sc > score:
            best, score = c, sc
    return best


def _abel_friendly_divisor(Jp, M, u, alpha, bp, degree):
    """Pole divisor (E, w, alpha') of the eigenvector for the normalization vector alpha', among alpha
    and random ones, whose points are farthest from the branch points and all within 10 |bp|max of E = 0."""
    R = float(np.abs(bp).max())
    rng = np.random.default_rng(20240602)
    best, score = None, -np.inf
    for c in [alpha] + [rng.normal(size=3) for _ in range(24)]:
        E, w = eigenvector_poles(Jp, M, u, c)
        if len(E) != degree or not np.all(np.isfinite(w)):
            continue
        sc = np.min(np.abs(E[:, None] - bp[None, :])) / R if np.abs(E).max() <= 10.0 * R else -1.0
        if sc > score:
            best, score = (E, w, c), sc
    if best is None:
        raise RuntimeError("no normalization vector gives a finite eigenvector divisor")
    return best


def _lattice_coords(z: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Real coordinates (x1, x2) with z = x1 + tau x2 (z of shape (..., g))."""
    Y = tau.imag
    x2 = np.linalg.solve(Y, z.imag.T).T if z.ndim > 1 else np.linalg.solve(Y, z.imag)
    x1 = z.real - x2 @ tau.real.T
    return x1, x2


def _reduce(z: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """A representative of z modulo Z^g + tau Z^g with lattice coordinates in [-1/2, 1/2)."""
    x1, x2 = _lattice_coords(z, tau)
    return z - np.round(x1) - np.round(x2) @ tau.T


@dataclass(frozen=True, eq=False)
class ThetaRotation(RotationSolution):
    """Exact rotation in a quadratic potential in Riemann theta functions (Section 4 II).

    Built by :func:`thetasol.solve_rotation`; evaluates at any times in any order.  Besides the
    protocol of :class:`thetasol.RotationSolution` (``omega``, ``Q``, ``M``, ``u``, ``method``,
    ``invariants``) it exposes the spectral data of the initial state.

    Attributes
    ----------
    curve : thetasol.curves.spectral.SpectralCurve
        The spectral curve (4.12) of the initial data (principal frame, ascending ``J``).
    basis : ndarray of int, shape (2g, 2g)
        The symplectic homology basis used, adapted to the real Liouville torus: its columns are
        the new cycles ``[a' | b']`` in the coordinates of ``curve``'s own basis.
    riemann_matrix : ndarray, shape (g, g)
        ``tau`` of the curve's normalization in that basis (g = 4 generic, 3 for a rank-one
        potential).
    U : ndarray, shape (g,)
        Velocity of the linear flow on the Jacobian: the Abel image of the eigenvector divisor
        moves as ``A(D(t)) = A(D(0)) - t U``.  Real, zero outside the first
        ``invariants['torus_dimension']`` coordinates.
    abel_divisor : ndarray, shape (g,)
        Abel image ``A(D0)`` of the pole divisor of the initial eigenvector (normalized by
        ``<alpha, psi> = 1``), see :meth:`abel_map`.
    alpha : ndarray, shape (3,)
        The normalization vector (principal frame).
    """

    curve: object = field(default=None, repr=False)
    basis: np.ndarray = field(default=None, repr=False)
    riemann_matrix: np.ndarray = field(default=None, repr=False)
    U: np.ndarray = field(default=None, repr=False)
    abel_divisor: np.ndarray = field(default=None, repr=False)
    alpha: np.ndarray = field(default=None, repr=False)
    _c: dict = field(default=None, repr=False)

    # -- evaluation ---------------------------------------------------------------------------
    def _phi0(self, t: np.ndarray, derivative: bool):
        """Phi(0, t) (n, 3, 3) = Q'(t)^T Q'0 in the principal frame and, if asked, its derivative."""
        c = self._c
        _, v, dv = c["flow"](t, derivative)
        vb, vd = v[:, :9].reshape(-1, 3, 3), v[:, 9:]          # [n, s, k], [n, k]
        phase = np.exp(1j * np.multiply.outer(t, c["nu"]))      # [n, s, k]
        Psi = c["amp"][None] * phase * vb / vd[:, None, :]      # Psi_k(P_s, t)
        B = c["B"]                                              # components -> principal frame
        Phi = B @ np.einsum("nsk,si->nki", Psi, c["X0inv"])    # Phi X0 = B [Psi_c(P_s)]
        if not derivative:
            return Phi, None
        rate = 1j * c["nu"][None] + dv[:, :9].reshape(-1, 3, 3) / vb - (dv[:, 9:] / vd)[:, None, :]
        return Phi, B @ np.einsum("nsk,si->nki", Psi * rate, c["X0inv"])

    def _evaluate(self, t: np.ndarray):
        Phi, Phidot = self._phi0(t, derivative=True)
        Phi_r = Phi.real
        Qp = polar_orthonormalize(self._c["Q0p"] @ np.swapaxes(Phi_r, -1, -2))
        wp = vee(-Phidot.real @ np.swapaxes(Phi_r, -1, -2))
        if self._c["axis"] is not None:
            # back from the frame turning at -spin about the symmetry axis: Q = Q~ R^T, omega = R omega~ + spin e
            ax, spin = self._c["axis"], self._c["spin"]
            R = rotation_about(ax, -spin * t)                  # R(t) = exp(-spin t hat(e))
            Qp = Qp @ np.swapaxes(R, -1, -2)
            wp = np.einsum("nij,nj->ni", R, wp)
            wp[..., ax] += spin
        P = self._c["P"]
        return wp @ P.T, Qp @ P.T

    def abel_map(self, points) -> np.ndarray:
        """Abel map in the coordinates of :attr:`riemann_matrix` and :attr:`U`.

        ``points`` as for :meth:`thetasol.PlaneCurve.abel_map` (points (E, w) of the spectral curve
        in the principal frame, places, divisors); values modulo ``Z^g + tau Z^g``.
        """
        return self.curve.abel_map(points, normalized=False) @ self._c["Ainv"].T

    def imaginary_residual(self, t) -> np.ndarray:
        """max |Im Phi(0, t)|: the theta quotients are complex, their combination is real; the
        imaginary part left over measures the float64 error of the evaluation (shape ``t.shape``)."""
        tt, flat = self._times(t)
        Phi, _ = self._phi0(flat, derivative=False)
        return np.abs(Phi.imag).max(axis=(-1, -2)).reshape(tt.shape)


# -- set-up --------------------------------------------------------------------------------------

def _infinity_data(curve, J2, M):
    """The places over E = infinity with J_j (w / E^2 -> J_j^2) and the eigenvector b_j of L there.

    b_j spans the eigenspace of J^2 for J_j^2 when it is simple (a coordinate axis); for a symmetric
    body the node at infinity has two branches w = J_1^2 E^2 + mu E + ..., and b_j is the eigenvector
    of M compressed to that eigenspace with eigenvalue mu ((e1 +- i e2) / sqrt 2).  B = [b_1 b_2 b_3]
    is unitary and the components of the Baker-Akhiezer function are taken in it, so that at inf_j
    only the j-th component survives.
    """
    places = list(curve.places_at_infinity())
    if len(places) != 3:
        raise RuntimeError(f"expected three places over E = infinity, found {len(places)}")
    if not curve.symmetric_body:
        # ordered by j with w / E^2 -> J2[j] (J2 ascending): the coordinate axes, exactly
        return [curve.place_at_infinity(j) for j in range(3)], np.sqrt(J2), np.eye(3, dtype=complex)
    Js, bs = [], []
    for Pl in places:
        k, c = Pl.series(order=4)
        lam0 = complex(c[k == -2][0]) if np.any(k == -2) else 0.0
        lam1 = complex(c[k == -1][0]) if np.any(k == -1) else 0.0
        idx = np.flatnonzero(np.abs(J2 - lam0.real) <= 1e-8 * J2.max())
        if len(idx) == 1:
            b = np.eye(3)[idx[0]].astype(complex)
        elif len(idx) == 2:
            W = np.eye(3)[:, idx]
            mu, V = np.linalg.eig(W.T @ M @ W)
            b = W @ V[:, int(np.argmin(np.abs(mu - lam1)))]
            b = b / np.linalg.norm(b)
        else:
            raise RuntimeError(f"cannot label the place at infinity with w / E^2 -> {lam0}")
        Js.append(np.sqrt(lam0.real))
        bs.append(b)
    B = np.column_stack(bs)
    if np.abs(B.conj().T @ B - np.eye(3)).max() > 1e-8:
        raise RuntimeError("eigenvectors at infinity are not orthonormal")
    return places, np.array(Js), B


def _velocity_at_infinity(curve, nums) -> np.ndarray:
    """sum_j J_j omega_i / ds at the places over E = infinity (s = 1/E), omega_i = g_i dE / f_w.

    Distinct J_j: in closed form.  f = lc prod_l (w - w_l) with w_l = x_l E^2 + O(E), x_l = J_l^2, so
    omega_i / ds (inf_j) = -h_i(x_j) / (lc prod_{l != j} (x_j - x_l)), where only the weight-2 part
    h_i(x) = alpha_i + beta_i x of g_i (its E^2 and w coefficients) survives at s = 0.  The sum over j
    weighted by J_j = sqrt(x_j) is the second divided difference of sqrt(x) h_i(x):

        sum_j J_j omega_i / ds (inf_j) = -(beta_i e2 - alpha_i) / (lc (J1 + J2)(J1 + J3)(J2 + J3)),

    e2 = J1 J2 + J1 J3 + J2 J3.  The terms of the sum grow like 1 / (J_1 - J_2) for a nearly
    symmetric body and cancel; the divided difference does not (at J2/J1 = 1 + 1e-6 the sum lost
    six digits: U was 1e-10 off).

    Symmetric body (x_a = x_b = x_p at the node's two branches, x_s at the third place): the g_i
    have degree <= 1 in w, so by Euler-Jacobi sum_l g_i(E, w_l) / f_w(E, w_l) = 0 for every E and
    the t^0 coefficients at the three places add up to 0; the sum is (J_s - J_p) times the
    coefficient at inf_s, which has the closed form above:

        sum_j J_j omega_i / ds (inf_j) = -h_i(x_s) / (lc (J_s + J_p)(x_s - x_p)).

    The expansions at the node's branches are not used: their coefficients grow like spin^-k
    (branch points at |E| ~ 1 / spin, the axial spin) and the FFT lost 5e-12 of the t^0 sum at
    relative spin 4e-4 (measured against a 40-digit contour integral), a rate error of U.
    """
    E, w = curve.x, curve.y
    lc = float(sp.Poly(curve._poly.sympy_expr(), w).LC())
    x = np.asarray(curve.J2, float)                     # exact J_j^2 (snapped), not read off the places
    # the weight-2 part of each numerator: its E^2 and w coefficients (complex: on a symmetric body's
    # normalization the differentials come from the adjoint conditions)
    h = []
    for gnum in nums:
        pol = sp.Poly(sp.sympify(gnum), E, w)
        if pol.degree(w) > 1:
            raise RuntimeError(f"holomorphic differential {gnum} of degree > 1 in w (internal error)")
        cf = dict(pol.terms())
        h.append((complex(cf.get((2, 0), 0)), complex(cf.get((0, 1), 0))))
    if curve.symmetric_body:
        s_ = [i for i in range(3) if np.sum(x == x[i]) == 1]
        if len(s_) != 1:
            raise RuntimeError(f"symmetric body without a single distinct J^2 ({x}; internal error)")
        xs, xp = x[s_[0]], x[(s_[0] + 1) % 3]
        den = lc * (np.sqrt(xs) + np.sqrt(xp)) * (xs - xp)
        return np.array([-(alpha + beta * xs) / den for alpha, beta in h])
    J = np.sqrt(x)
    e2 = J[0] * J[1] + J[0] * J[2] + J[1] * J[2]
    den = lc * (J[0] + J[1]) * (J[0] + J[2]) * (J[1] + J[2])
    return np.array([-(beta.real * e2 - alpha.real) / den for alpha, beta in h])


def _zero_order(Pl, numerator) -> int:
    """Order of vanishing of numerator dE / f_w at the place (from its expansion).

    A coefficient is significant against the largest term c_k t0^k on the sampling circle |t| = |t0|,
    not against the largest c_k: near a tacnode (a symmetric body with little axial spin) two branch
    points sit at |E| ~ 1 / spin, the series in t = 1/E converges only for |t| < ~spin and c_k grows
    like spin^-k, so the unscaled test dropped the order-0 term at the node's branches (read 2 for 0
    from relative spin 1e-3: a canonical divisor of degree 8 on genus 3, and no Riemann constant).
    """
    k, c = Pl.expand(numerator, order=4)
    t0 = abs(Pl.curve._place_data(Pl, None, None)[1])
    F = np.abs(c) * t0 ** k.astype(float)
    sig = F > 1e-10 * F.max()
    return int(k[np.argmax(sig)])


def _node_branch(curve, slope, Es: np.ndarray):
    """(w, unit right eigenvector) on the node branch of slope ``slope`` at the small values Es.

    There L(E) - w = (u - lam) + E (M - (w - lam) / E) + E^2 J^2 has two rows parallel to O(E): its
    null vector and eigenvalue taken from L(E) in float64 carry ~eps |L| / (|mu_1 - mu_2| |E|) (1e-13
    on circles of radius 1e-2 around the node).  In the frame T = [k_1, k_2, n] of u (u - lam = lam_n n n^T)
    with v = T (y_1, y_2, E y_3) and w = lam + E x the rows divided by E are O(1):
    X(x) = [[M' + E J2' - x]_kk, E (M' + E J2')_kn; (M' + E J2')_nk, lam_n + E (M' - x + E J2')_nn],
    whose root x (Newton on det X from the float64 eigenvalue) and null vector y are accurate to eps.
    """
    lam, V = np.linalg.eigh(curve.u)
    lb = curve.node[1]
    order = np.argsort(np.abs(lam - lb))
    T = V[:, order]
    lam_n = lam[order[2]] - lb
    Mp = T.T @ curve.M @ T
    J2p = T.T @ np.diag(np.asarray(curve.J2, float)) @ T
    Ev = np.asarray(Es, complex)
    A = Mp + Ev[..., None, None] * J2p                                 # (..., 3, 3)
    X0 = A.copy()
    X0[..., :2, 2] *= Ev[..., None]
    X0[..., 2, 2] = lam_n + Ev * A[..., 2, 2]
    dX = -np.stack([np.ones_like(Ev), np.ones_like(Ev), Ev], -1)          # d X / dx, diagonal
    x = (_nearest_eigenvalue(curve, Ev, lb + slope * Ev) - lb) / Ev       # the branch, to ~eps / |E|
    for _ in range(8):
        X = X0 + dX[..., :, None] * np.eye(3) * x[..., None, None]
        minors = np.stack([X[..., 1, 1] * X[..., 2, 2] - X[..., 1, 2] * X[..., 2, 1],
                           X[..., 0, 0] * X[..., 2, 2] - X[..., 0, 2] * X[..., 2, 0],
                           X[..., 0, 0] * X[..., 1, 1] - X[..., 0, 1] * X[..., 1, 0]], -1)
        step = np.linalg.det(X) / (minors * dX).sum(-1)
        x = x - step
        if np.all(np.abs(step) <= 4 * np.finfo(float).eps * (1 + np.abs(x))):
            break
    X = X0 + dX[..., :, None] * np.eye(3) * x[..., None, None]
    y = right_eigenvector(X, np.zeros(x.shape))
    v = np.einsum("ij,...j->...i", T, y * np.stack([np.ones_like(Ev), np.ones_like(Ev), Ev], -1))
    return lb + Ev * x, v / np.linalg.norm(v, axis=-1, keepdims=True)


def _nearest_eigenvalue(curve, Es: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The eigenvalue of L(Es) nearest to ``target`` (float64; same shape as Es)."""
    W = np.linalg.eigvals(lax_matrix(np.sqrt(curve.J2), curve.M, curve.u, Es))
    idx = np.argmin(np.abs(W - target[..., None]), axis=-1)
    return np.take_along_axis(W, idx[..., None], axis=-1)[..., 0]


def _local_branch(curve, place, Es: np.ndarray) -> np.ndarray:
    """w on the branch of ``place`` (over E = 0) at the small values Es (same shape)."""
    if getattr(place, "_slope", None) is not None:
        return _node_branch(curve, place._slope, Es)[0]
    return _nearest_eigenvalue(curve, Es, np.full(np.shape(Es), complex(place.y)))


def _node_slopes(curve):
    """dw/dE on the node's two branches: the eigenvalues of M compressed to the 2D eigenspace of u."""
    lam, V = np.linalg.eigh(curve.u)
    lb = curve.node[1]
    idx = np.argsort(np.abs(lam - lb))[:2]
    W2 = V[:, idx]
    mu = np.linalg.eigvals(W2.T @ curve.M @ W2)
    return mu


def _circle_data(curve, place, radius, Jp, nums_arr):
    """Points on a circle |E| = radius around ``place`` (over E = 0), their w, and the local
    Abel integrals from the place along the radii (Gauss-Legendre)."""
    phis = 2 * np.pi * np.arange(N_CIRCLE) / N_CIRCLE
    Ec = radius * np.exp(1j * phis)
    xg, wg = np.polynomial.legendre.leggauss(N_RAY)
    sg = 0.5 * (xg + 1)
    Eq = Ec[:, None] * sg[None, :]                                   # (N, n) nodes on the radii
    wq = _local_branch(curve, place, Eq)
    num = np.zeros(nums_arr.shape[:1] + Eq.shape, complex)
    for i in range(nums_arr.shape[1]):
        for j in range(nums_arr.shape[2]):
            if np.any(nums_arr[:, i, j]):
                num += nums_arr[:, i, j][:, None, None] * (Eq ** i * wq ** j)[None]
    fy, _ = curve._poly.fy_fx(Eq.ravel(), wq.ravel()[:, None])
    fy = fy.reshape(Eq.shape)
    local = 0.5 * np.einsum("dnq,q->nd", num / fy[None] * Ec[None, :, None], wg)   # (N, g_raw)
    wc = _local_branch(curve, place, Ec)
    return Ec, wc, local


def _drop_node_point(Ez: np.ndarray, wz: np.ndarray):
    """The points of an eigenvector divisor on the normalization: the one at the node E = 0 removed."""
    k = int(np.argmin(np.abs(Ez)))
    if abs(Ez[k]) > 1e-8 * (1 + np.abs(Ez).max()):
        raise RuntimeError("expected the eigenvector divisor to pass through the node")
    return np.delete(Ez, k), np.delete(wz, k)


def _radius(curve, E_poles: np.ndarray, E_zeros: np.ndarray) -> float:
    """Radius of the Cauchy circles around E = 0.

    The poles of rho_k (the divisor D0) and the branch points must lie outside, with margin 3
    (trapezoidal error ~ 3^-N); the zeros of the eigenvector components, whose poles cancel only to
    rounding between the two terms of the mean, must not lie near the circle.  Among radii
    r_max 2^-j the one farthest (in log scale) from those zeros is taken.  (On a node's branches small
    circles once cost eps / r in the eigenvectors, 3.7e-9 at t = 4002 for a rank-one body at r_max / 128;
    since :func:`_node_branch` the error is the same at every radius, and the largest admissible one
    made a symmetric rank-one body's eigenvalue picking on the regular place's circle fail.)
    """
    bp = np.abs(np.asarray(curve.branch_points))
    far = np.concatenate([bp[bp > 0], np.abs(E_poles[np.abs(E_poles) > 0])])
    r_max = float(far.min()) / 3.0
    zeros = np.abs(E_zeros[np.isfinite(E_zeros)])
    zeros = zeros[zeros > 0]
    best, margin = r_max, -np.inf
    for j in range(8):
        r = r_max * 2.0 ** -j
        m = np.min(np.abs(np.log(zeros / r))) if zeros.size else np.inf
        if m > margin + 0.3:           # prefer larger radii unless clearly better placed
            best, margin = r, m
    return best


def _parities(curve, nums) -> np.ndarray:
    """Parity of each differential g dE / f_w under sigma: E^i w^j -> (-1)^(i+1)."""
    out = []
    for gn in nums:
        pol = sp.Poly(sp.sympify(gn), curve.x, curve.y)
        ps = {(-1) ** (i + 1) for (i, _), _c in pol.terms()}
        if len(ps) != 1:
            raise RuntimeError(f"differential numerator {gn} has no definite parity under E -> -E")
        out.append(ps.pop())
    return np.array(out, float)


def _fit_exponents(nu, nub, X0, nu_aux, h_aux, gap=None):
    """Weighted least-squares fit of nu_sk = F_s - G_k (imaginary parts).

    The error model of an entry grows like (|psi| / |psi_k|)^2: where a component is small the
    directly computed exponent depends on the Abel images through two nearly cancelling poles.
    ``gap = (k0, k1, value)`` imposes G_k0 - G_k1 = value (known exactly, see _node_exponent_gap).
    Returns (fitted nu (3, 3), max residual in units of the error model).
    """
    hs = np.abs(X0) / np.linalg.norm(X0, axis=0, keepdims=True)       # [k, s]
    err = np.abs(nu - nub) + 1e-15 * (1 + np.abs(nu)) / hs.T ** 2
    err_aux = 1e-15 * (1 + np.abs(nu_aux)) / h_aux ** 2
    rows = [(s_, k, nu[s_, k].imag, err[s_, k]) for s_ in range(3) for k in range(3)]
    rows += [(3 + i, k, nu_aux[i, k].imag, err_aux[i, k])
             for i in range(nu_aux.shape[0]) for k in range(3)]
    nF = 3 + nu_aux.shape[0]
    k0, k1, gval = gap if gap is not None else (0, -1, 0.0)
    # with the constraint, G_k1 = G_k0 - gap is eliminated: its rows become rows of G_k0 (its
    # column stays zero; lstsq's minimum-norm solution leaves it at 0)
    fit_rows = [(s_, k0, val - gval, er) if k == k1 else (s_, k, val, er) for s_, k, val, er in rows]
    A = np.zeros((len(rows) + 1, nF + 3))
    rhs = np.zeros(len(rows) + 1)
    for i, (s_, k, val, er) in enumerate(fit_rows):
        A[i, s_], A[i, nF + k], rhs[i] = 1.0 / er, -1.0 / er, val / er
    A[-1, nF] = 1.0 / min(r[3] for r in rows)                          # gauge G_0 = 0
    x, *_ = np.linalg.lstsq(A, rhs, rcond=None)
    if gap is not None:
        x[nF + k1] = x[nF + k0] - gval
    resid = max(abs(x[s_] - x[nF + k] - val) / er for s_, k, val, er in rows)
    return x[:3][:, None] - x[nF:][None, :], float(resid)


def _node_exponent_gap(curve, Pinf, Jinf, G, U, rdim, nu_fit):
    """G_k0 - G_k1 for the two branches inf_k0, inf_k1 of a symmetric body's node over E = infinity.

    The exponents' constants G_k = Omega(inf_k) (the regular part of the normalized abelian integral
    of the second kind with principal parts -J_j E at inf_j) are otherwise only fitted from theta
    derivatives, to ~1e-13: their difference at the node is the rate of the turn about the symmetry
    axis, and that error grew as 1.2e-13 t (4e-9 at t = 4000 for a fast spin, measured).  Exactly:
    the differential ``omega3 = E^2 dE / f_w`` is of the third kind on the normalization, with simple
    poles only at the node's branches (residues +-r); let Omega3 = omega3 / r minus its a-periods in
    the normalized holomorphic differentials.  Riemann's bilinear relation for the pair
    (Omega, Omega3), both with zero a-periods, leaves the sum of the residues of Omega Omega3 at
    infinity, so ``G_k0 - G_k1 = sum_j J_j c_j`` with c_j the t^0 coefficient of Omega3 / dt at
    inf_j (t = 1/E): the same pairing that gives U.  That value holds modulo 2 pi n.U (the path to
    infinity); n is the one the fitted exponents ``nu_fit`` point at.

    Returns ``(k0, k1, value in nu units)``, or None when the fit points at no single n (within 1e-8;
    the next candidate at least 1e-4 away): the fitted value is then kept (its rate error ~1e-13).
    """
    pair = [j for j in range(3) if np.sum(np.abs(Jinf - Jinf[j]) <= SNAP_TOL * Jinf.max()) == 2]
    if len(pair) != 2:
        raise RuntimeError(f"no node over E = infinity (J at infinity {Jinf}; internal error)")
    om = curve.x ** 2
    k0, k1 = pair
    r, pa = _third_kind_periods(curve, [Pinf[k0], Pinf[k1], Pinf[3 - k0 - k1]], om, G)
    # sum_j J_j c_j in closed form (Euler-Jacobi, see _velocity_at_infinity): the t^0 coefficients
    # at the node's branches grow like 1 / spin and the FFT loses them for a small axial spin
    Jc0 = _velocity_at_infinity(curve, [om])[0]
    value = float((Jc0 / r - pa @ U).imag)
    snapped = _snap_rate(float(nu_fit[0, k1] - nu_fit[0, k0]), value, U, rdim)
    return None if snapped is None else (k0, k1, snapped)


def _third_kind_periods(curve, places, numerator, G) -> tuple:
    """(r, p) of the third-kind differential numerator dE / f_w with residues +-r at places[0], places[1]
    (checked: zero at any further place given) and a-periods r p in the adapted basis G."""
    res = []
    for Pl in places:
        k, c = Pl.expand(numerator, order=3)
        res.append(complex(c[k == -1][0]) if np.any(k == -1) else 0.0)
    r = res[0]
    if abs(r) == 0 or abs(res[1] + r) > 1e-8 * abs(r) or any(abs(x) > 1e-8 * abs(r) for x in res[2:]):
        raise RuntimeError(f"{numerator} dE / f_w has residues {res}: not the node's third-kind differential "
                           "(internal error)")
    pa = (np.asarray(curve.period_matrix(differentials=[numerator])) @ G).ravel()[:curve.genus]
    return r, pa / r


def _snap_rate(fitted: float, value: float, U: np.ndarray, rdim: int):
    """The rate value + 2 pi n.U (n integer, |n_i| <= 3) the fitted one points at, or None when no single
    n is within 1e-8 (the next candidate at least 1e-4 away)."""
    n = np.array(np.meshgrid(*[np.arange(-3, 4)] * rdim, indexing="ij")).reshape(rdim, -1).T
    cand = value + 2 * np.pi * n @ U[:rdim]
    miss = np.abs(fitted - cand)
    order = np.argsort(miss)
    if miss[order[0]] > 1e-8 * (1 + abs(fitted)) or (len(miss) > 1 and miss[order[1]] <= 1e-4):
        return None
    return float(cand[order[0]])


def _exact_exponents(curve, P0, gap, G, U, rdim, nu_fit):
    """The exponents nu_sk = F_s - G_k (imaginary parts) from exact relations; the fit picks the integers.

    sigma: (E, w) -> (-E, w) maps the curve to itself (L(-E) = L(E)^T) and Omega to -Omega + const (its
    principal parts -J_j E change sign, the a-periods stay zero), so nu_{sigma s, sigma k} = -nu_sk
    modulo 2 pi n.U (the lattice shift of the theta quotients).  sigma fixes the regular places over
    E = 0 and the places over infinity with distinct J_j, and swaps the two branches of a node (P_a, P_b
    at E = 0 for a rank-one a; inf_k0, inf_k1 over infinity for a symmetric body).  A fixed pair gives
    2 (F_s - G_k) = 2 pi n.U: on a curve without nodes every exponent is a half lattice rate.  A node
    leaves one difference free, the rate of a third-kind integral: G_k0 - G_k1 (``gap``,
    :func:`_node_exponent_gap`) and F_a - F_b from dE / f_w, of the third kind with simple poles only at
    P_a, P_b (f_w ~ E on the node's branches; O(t^2) dt at infinity): by Riemann's bilinear relation as
    in _node_exponent_gap, F_a - F_b = -Im(p.U) with p its a-periods / residue at P_a.

    The fit alone was not enough: the circle means at a node's branches are biased by up to 6e-12
    (symmetric body, relative axial spin 2e-4; the same at two radii) and the fitted rates were off by
    up to 6e-13 (4.8e-13 for the fast-spin reference): the attitude drifted linearly.  Returns nu (3, 3),
    or None where a relation points at no single n or a node gap is unknown (the fit is then kept).
    """
    swap0 = [s_ for s_, Pl in enumerate(P0) if getattr(Pl, "_slope", None) is not None]
    if curve.symmetric_body and gap is None:
        return None
    f = nu_fit
    sig_s, dF = list(range(3)), np.zeros(3)          # sigma on the places over E = 0; F_s - F_sigma(s)
    sig_k, dG = list(range(3)), np.zeros(3)          # sigma on the places at infinity; G_k - G_sigma(k)
    if gap is not None:
        k0, k1, gval = gap
        sig_k[k0], sig_k[k1] = k1, k0
        dG[k0], dG[k1] = gval, -gval
    if swap0:
        sa, sb = swap0
        _, pa = _third_kind_periods(curve, [P0[sa], P0[sb]], sp.Integer(1), G)
        zgap = _snap_rate(float(f[sa, 0] - f[sb, 0]), float((-(pa @ U)).imag), U, rdim)
        if zgap is None:
            return None
        sig_s[sa], sig_s[sb] = sb, sa
        dF[sa], dF[sb] = zgap, -zgap
    # nu_sk + nu_{sigma s, sigma k} = 2 pi n.U and nu_sk - nu_{sigma s, sigma k} = dF_s - dG_k: each entry
    # from one snapped sum and the gaps (fewer roundings than a solve over all relations)
    nu = np.empty((3, 3))
    for s_ in range(3):
        for k in range(3):
            total = _snap_rate(float(f[s_, k] + f[sig_s[s_], sig_k[k]]), 0.0, U, rdim)
            if total is None:
                return None
            nu[s_, k] = 0.5 * (total + dF[s_] - dG[k])
    # the F_s - G_k form is implied: nu_sk - nu_s0 - nu_0k + nu_00 = 0
    form = nu - nu[:, :1] - nu[:1, :] + nu[0, 0]
    if np.abs(form).max() > 1e-12 * (1 + np.abs(nu).max()):
        raise RuntimeError("the exact exponents are not of the form F_s - G_k (internal error)")
    return nu


def _farthest_branch_point(Jp: np.ndarray, M: np.ndarray, u: np.ndarray) -> float:
    """max |E| over the finite branch points of (4.12) for a symmetric body, before the curve is built
    (which took minutes for the farthest ones): the roots of the curve engine's critical polynomial
    from the exact coefficients (a few ms)."""
    from thetasol.curves._poly import CurvePoly
    from thetasol.curves.spectral import _exact_coefficients

    Js = Jp.copy()
    i = int(np.argmin(np.diff(Js)))
    Js[i] = Js[i + 1] = 0.5 * (Js[i] + Js[i + 1])           # snapped as spectral_curve does
    C = _exact_coefficients(np.diag(Js), M, u)
    E, w = sp.symbols("E w")
    f = sp.Poly({(k, l): sp.Rational(c.numerator, c.denominator)
                 for k, row in enumerate(C) for l, c in enumerate(row) if c}, E, w)
    F = CurvePoly(f, E, w).critical_polynomial()[0]
    cf = np.array([complex(c) for c in F.all_coeffs()])
    return float(np.abs(np.roots(cf)).max()) if len(cf) > 1 else 0.0


def _setup(Jm: np.ndarray, a: np.ndarray, Q0: np.ndarray, omega0: np.ndarray):
    Jp, P = _principal_frame(Jm)
    Q0p = Q0 @ P
    w0p = P.T @ omega0
    Ip = inertia_from_moments(np.diag(Jp))
    spin, axis = 0.0, _symmetry_axis(Jp)
    if axis is not None:
        # Symmetric body: omega along the symmetry axis is an integral.  In the frame turning
        # about that axis at -spin relative to the body, omega has no axial part, so A(E) has no
        # E^0 term at the node over E = infinity and the Baker-Akhiezer function has no
        # third-kind singularity there (docs/theta_rotation.md).
        spin = float(w0p[axis])
        sqrt_a = np.sqrt(np.abs(np.linalg.eigvalsh(a)).max())
        scale = np.linalg.norm(w0p) + sqrt_a
        if abs(spin) < MIN_AXIAL_SPIN * scale:
            # Without spin the two places over E = infinity touch (a tacnode, genus 2: Neumann's
            # problem, dispatched before); for a small spin two branch points run off to |E| ~ 1 / spin.
            # Measured at 3e-4 on 23 random bodies (<= 3.9e-10 at t = 4002, before the exact exponents) and
            # on 16 rank-one ones down to 1e-4 (<= 7.2e-12, docs); full-rank bodies below 3e-4 were not
            # re-measured, and at 3e-5 the set-up failed or took minutes: refuse at once.
            raise ClosedFormUnavailable(
                f"symmetric body with little spin (or none) about its symmetry axis ({abs(spin) / scale:.1e} of "
                f"|omega0| + sqrt|a|, below {MIN_AXIAL_SPIN:g}): the spectral curve is at or near a tacnode "
                "over E = infinity (the axis moves as in Neumann's problem, genus 2), which is not "
                "implemented; use thetasol.integrate_rotation")
        far = _farthest_branch_point(Jp, hat(Ip @ w0p), -(Q0p.T @ a @ Q0p))
        far *= Jp[-1] / sqrt_a
        if far > MAX_FAR_BRANCH:
            raise ClosedFormUnavailable(
                f"symmetric body with branch points of its spectral curve at |E| ~ {far:.1e} sqrt|a| / J "
                f"(above {MAX_FAR_BRANCH:g}; axial spin {abs(spin) / scale:.1e} of |omega0| + sqrt|a|): near a "
                "tacnode over E = infinity, out of the curve engine's reach; use thetasol.integrate_rotation")
    else:
        gap = float(np.min(np.diff(Jp))) / Jp[-1]
        if gap < MIN_J_GAP:
            # branch points at |E| ~ 1 / gap: at 5e-9 the curve is numerically singular, below it the
            # construction took minutes; at 2e-8 .. 3e-8 2 of 16 random bodies stopped in the set-up, at
            # 5e-8 one took 1.55 s; from 7e-8 up 32 bodies were solved to <= 5.3e-12 within 0.77 s
            raise ClosedFormUnavailable(
                f"nearly symmetric body (two principal second moments {gap:.1e} apart relative, above the "
                f"snapping tolerance {SNAP_TOL:g} and below {MIN_J_GAP:g}): the spectral curve has branch "
                "points near |E| ~ 1 / gap, out of the curve engine's reach; use thetasol.integrate_rotation")
    curve = spectral_curve(np.diag(Jp), hat(Ip @ w0p), -(Q0p.T @ a @ Q0p), tol=SNAP_TOL)
    M, u = curve.M, curve.u
    W0 = hat(w0p - spin * np.eye(3)[axis]) if axis is not None else hat(w0p)
    g = curve.genus
    nums = curve.holomorphic_differentials()
    nums_arr = curve._numerators(nums)
    # homology basis adapted to the real torus: V real, non-zero in the first r coordinates only
    Pm = curve.period_matrix()
    G, rdim = real_flow_basis(Pm, _parities(curve, nums))
    Pn = Pm @ G
    Ainv = np.linalg.inv(Pn[:, :g])
    tau = Ainv @ Pn[:, g:]
    tau = 0.5 * (tau + tau.T)

    def abel(points):
        return curve.abel_map(points, normalized=False) @ Ainv.T

    Pinf, Jinf, B = _infinity_data(curve, curve.J2, M)
    Bc = B.conj()                                            # psi -> components: psi @ conj(B)
    U = Ainv @ _velocity_at_infinity(curve, nums)
    scaleU = np.abs(U).max()
    if np.abs(U.imag).max() > 1e-10 * scaleU or np.abs(U[rdim:]).max() > 1e-10 * scaleU:
        raise RuntimeError("the flow velocity is not real in the adapted basis: inaccurate periods")
    U = np.concatenate([U[:rdim].real, np.zeros(g - rdim)])
    th = RiemannTheta(tau)
    # places over E = 0 (for a node: its two branches on the normalization) and at infinity
    P0 = list(curve.places_over_zero())
    if len(P0) != 3:
        raise RuntimeError(f"expected three places over E = 0, found {len(P0)}")
    if curve.node is not None:
        # label the node's two branches among these very Place objects by their slopes
        lb = curve.node[1]
        branches = [Pl for Pl in P0 if abs(Pl.y - lb) <= 1e-6 * (1 + abs(lb))]
        if len(branches) != 2:
            raise RuntimeError(f"expected two branches over the node, found {len(branches)}")
        mu = _node_slopes(curve)
        for Pl, m in zip(_match_branches(curve, branches, mu), mu):
            Pl._slope = m
    P0_reg = [Pl for Pl in P0 if getattr(Pl, "_slope", None) is None]
    # Canonical divisor for K.  Abel images at infinity are avoided where possible (for a nearly
    # symmetric body inf_1, inf_2 sit in a cluster of branch points): with distinct J and no node,
    # E^2 dE / f_w is holomorphic and non-zero at infinity, so its divisor 2 (P_1 + P_2 + P_3) lies
    # over E = 0, at regular places far from the branch points.
    far = curve.node is None and not curve.symmetric_body
    if far:
        canon = {Pl: 2 for Pl in P0_reg}
    else:
        # E dE / f_w: simple zeros at the regular places over E = 0 (none at the node's branches)
        # and at the places at infinity (simple for distinct J; at a node read off the expansion)
        canon = {Pl: 1 for Pl in P0_reg}
        for Pl in Pinf:
            canon[Pl] = 1 if not curve.symmetric_body else _zero_order(Pl, curve.x)   # curve.x: E, not sympy's e
    if sum(canon.values()) != 2 * g - 2:
        raise RuntimeError(f"canonical divisor of E dE / f_w of degree {sum(canon.values())} on genus {g} "
                           "(orders read off the expansions at infinity; internal error)")
    # order 0 at the node's branches: no Abel image needed there (their series carry the noise of
    # E^2 - w / J_1^2 cancelling on w ~ J_1^2 E^2 for a small axial spin)
    canon = {Pl: m for Pl, m in canon.items() if m != 0}
    K = _riemann_constant(abel, th, canon, Jp, M, u, curve)
    Xtmp = np.column_stack([right_eigenvector(u, Pl.y) if getattr(Pl, "_slope", None) is None
                            else np.ones(3) for Pl in P0])
    alpha = _choose_alpha(Xtmp)
    Ed, wd = eigenvector_poles(Jp, M, u, alpha)
    if curve.node is not None:
        Ed, wd = _drop_node_point(Ed, wd)
    if len(Ed) != g + 2:
        raise RuntimeError(f"eigenvector divisor of degree {len(Ed)}, expected g + 2 = {g + 2}")
    if curve.node is None:
        # A(D0) does not depend on alpha (the pole divisors for two alphas differ by the divisor of
        # <alpha', v> / <alpha, v>): take it from an alpha whose divisor keeps away from the branch
        # points and from infinity, where Abel images lose accuracy.
        D_E, D_w, D_alpha = _abel_friendly_divisor(Jp, M, u, alpha, np.asarray(curve.branch_points), g + 2)
    else:
        D_E, D_w, D_alpha = Ed, wd, alpha
    # zeros of the eigenvector components v_k (alpha = e_k; for a symmetric body the components in
    # B, alpha = conj(b_k)): the places where psi_k vanishes
    comp_alpha = [Bc[:, k] if curve.symmetric_body else np.eye(3)[k] for k in range(3)]
    comp_zeros = [eigenvector_poles(Jp, M, u, al) for al in comp_alpha]
    r = _radius(curve, Ed, np.concatenate([Ez for Ez, _ in comp_zeros]))
    if curve.node is not None:
        # the node is a zero of every <alpha, v> (a base point, as for D0 above): on the normalization it
        # cancels in psi_k = v_k / <alpha, v>, and Z_k keeps g points
        comp_zeros = [_drop_node_point(Ez, wz) for Ez, wz in comp_zeros]
    R = float(np.abs(curve.branch_points).max())
    # A zero without a w (NaN) is where v_k vanishes on two sheets at once: the axis e_k is an
    # eigenvector of u, and the zeros sit at places over E = 0; those k take the other formula below.
    use_zeros = [len(Ez) == g and np.abs(Ez).max() <= 10.0 * R and np.all(np.isfinite(wz))
                 for Ez, wz in comp_zeros]
    # np.roots leaves the points a few ulps off: next to a tight pair of branch points (near a relative
    # equilibrium) that moved their Abel images by up to 6e-11
    D_E, D_w = polish_eigenvector_poles(Jp, M, u, D_alpha, D_E, D_w)
    for k in range(3):
        if use_zeros[k]:
            comp_zeros[k] = polish_eigenvector_poles(Jp, M, u, comp_alpha[k], *comp_zeros[k])
    # one Abel-map call for D0, the places over E = 0 and the zeros used (the paths are planned together)
    batch = [(complex(x), complex(y)) for x, y in zip(D_E, D_w)] + list(P0)
    for (Ez, wz), use in zip(comp_zeros, use_zeros):
        if use:
            batch += [(complex(x), complex(y)) for x, y in zip(Ez, wz)]
    A_all = abel(batch)
    nD = len(D_E)
    AD0 = A_all[:nD].sum(axis=0)
    AP0 = np.array([_reduce(v, tau) for v in A_all[nD:nD + 3]])
    AZ, pos = {}, nD + 3
    for k, use in enumerate(use_zeros):
        if use:
            AZ[k], pos = A_all[pos:pos + g].sum(axis=0), pos + g
    # psi_k vanishes at inf_j (j != k): div(psi_k) = Z_k + sum_{j != k} inf_j - D0 with Z_k the g
    # finite zeros of v_k, so e_k = A(Z_k) + K; and div(E) = sum P_s - sum inf_j turns
    # d_k = A(inf_k) - e_k into sum_s A(P_s) - A(D0) - K.  No Abel image at infinity is needed.
    # Where a zero of v_k runs off towards infinity (v_3 of a nearly symmetric body has one at
    # E ~ 1 / (J_2 - J_1)) use e_k = A(D0) - sum_s A(P_s) + A(inf_k) + K instead: inf_k is then
    # the place away from the cluster.  The same holds on the normalization of a symmetric
    # body's curve (its node over E = infinity; measured 1.5-2.5x closer to the references), and with
    # a node at E = 0 (rank-one a: for a symmetric body the node branches' Abel images at infinity lose
    # ~1 / spin^2; with distinct J both routes agree on the references since the exact exponents).
    e = np.empty((3, g), complex)
    for k in range(3):
        if use_zeros[k]:
            e[k] = _reduce(AZ[k] + K, tau)
        else:
            e[k] = _reduce(AD0 - AP0.sum(axis=0) + abel([Pinf[k]])[0] + K, tau)
    d = np.repeat(_reduce(AP0.sum(axis=0) - AD0 - K, tau)[None, :], 3, axis=0)
    ed_, vd_, gd_ = th.jet(d, order=1, separated=True)
    dlog_d = (gd_ @ U) / vd_

    def constants(radius):
        X0 = np.zeros((3, 3), complex)
        rho = np.zeros((3, 3), complex)                      # rho_k(P_s) theta(d_k), [s, k]
        cst = np.zeros((3, 3), complex)
        for s_, Pl in enumerate(P0):
            Ec, wc, local = _circle_data(curve, Pl, radius, Jp, nums_arr)
            A_loc = AP0[s_][None, :] + local @ Ainv.T         # (N, g)
            if getattr(Pl, "_slope", None) is not None:
                v = _node_branch(curve, Pl._slope, Ec)[1]
            else:
                v = right_eigenvector(lax_matrix(Jp, M, u, Ec), wc)
            psi = v / (v @ alpha)[:, None]
            dpsi = -np.einsum("nij,nj->ni", np.diag(Jp)[None] * Ec[:, None, None] + W0[None], psi) @ Bc
            psi = psi @ Bc
            X0[:, s_] = psi.mean(axis=0)
            eb, vb, gb = th.jet(A_loc[:, None, :] - e[None, :, :], order=1, separated=True)
            rho[s_] = (psi / vb * np.exp(ed_[None, :] - eb)).mean(axis=0) * vd_
            cst[s_] = (dpsi / psi - (gb @ U) / vb).mean(axis=0) + dlog_d
        return X0, rho, cst

    X0, rho, nu = constants(r)
    X0b, rhob, nub = constants(0.5 * r)
    nu_aux, h_aux = _auxiliary_rows(curve, abel, th, Jp, M, u, W0, alpha, e, U, dlog_d, Bc)
    nu_fit, resid = _fit_exponents(nu, nub, X0, nu_aux, h_aux)
    gap = _node_exponent_gap(curve, Pinf, Jinf, G, U, rdim, nu_fit) if curve.symmetric_body else None
    node_gap_change = None
    if gap is not None:
        k0, k1, val = gap
        node_gap_change = float(nu_fit[0, k1] - nu_fit[0, k0]) - val
        nu_fit, resid = _fit_exponents(nu, nub, X0, nu_aux, h_aux, gap)
    nu_exact_change = None
    nu_ex = _exact_exponents(curve, P0, gap, G, U, rdim, nu_fit)
    if nu_ex is not None:
        nu_exact_change = float(np.abs(nu_ex - nu_fit).max())
        nu_fit = nu_ex
    scale_nu = 1 + np.abs(nu).max()
    if np.abs(nu.real).max() > 1e-6 * scale_nu:
        raise RuntimeError(f"exponents are not imaginary (max |Re| {np.abs(nu.real).max():.2g}): "
                           "the spectral data are inconsistent")
    b = (AP0[:, None, :] - e[None, :, :]).reshape(9, g)
    # The shifts b_sk are known to ~1e-14 (sums of Abel images); where psi_k(P_s) is small or zero
    # that error shows directly in Psi.  Move each b_sk by the least amount that makes the theta
    # quotient reproduce psi_k(P_s) and its derivative -(omega0 x psi)_k at t = 0 exactly (two linear
    # conditions on the gradient and the Hessian): the shift lands on the theta divisor where the
    # component vanishes, and t = 0 returns the initial data.
    eb_, vb_, gb_, hb_ = th.jet(b, order=2, separated=True)
    scale_b = np.exp(eb_)
    rho_k = (rho / (np.exp(ed_) * vd_)[None, :]).ravel()               # rho_k(P_s), [s*3+k]
    h = X0.T.ravel()                                                     # psi_k(P_s)
    hdot = (-(B.conj().T @ W0 @ B @ X0)).T.ravel()                       # d/dt Psi_k(P_s) at t = 0
    dlogd = np.tile(dlog_d, 3)
    nu_rows = 1j * nu_fit.ravel()
    theta_b = scale_b * vb_
    val_target = h / rho_k
    der_target = hdot / rho_k - nu_rows * val_target + val_target * dlogd
    A = np.stack([scale_b[:, None] * gb_, scale_b[:, None] * (hb_ @ U)], axis=1)   # (9, 2, g)
    rhs = np.stack([val_target - theta_b, der_target - scale_b * (gb_ @ U)], axis=1)
    AAH = np.einsum("nig,njg->nij", A, A.conj())
    db = np.einsum("nig,ni->ng", A.conj(), np.linalg.solve(AAH, rhs[..., None])[..., 0])
    shift_correction = float(np.abs(db).max())
    if shift_correction > 1e-6:
        raise RuntimeError(f"theta quotients inconsistent with the initial eigenvectors (shift correction "
                           f"{shift_correction:.2g}): inaccurate Abel images")
    b = b + db
    flow = FlowTheta(tau, U[:rdim], np.concatenate([b, d]))
    eb = flow.e[:9].reshape(3, 3)
    amp = rho * np.exp(eb - flow.e[9:][None, :])             # rho theta(d) exp(e_b - e_d)
    consts = {"flow": flow, "nu": nu_fit, "amp": amp, "X0inv": np.linalg.inv(B @ X0), "Q0p": Q0p, "P": P, "B": B,
              "Ainv": Ainv, "G": G,
              "spin": spin, "axis": axis}
    diag = {
        "nu_real_part": float(np.abs(nu.real).max()),
        "nu_fit_residual": resid,
        "node_gap_change": node_gap_change,
        "nu_exact_change": nu_exact_change,
        "rho_two_radii": float(np.max(np.abs(rho - rhob) / np.maximum(np.abs(rho), 1e-300))),
        "X0_two_radii": float(np.max(np.abs(X0 - X0b))),
        "circle_radius": r,
        "shift_correction": shift_correction,
        "torus_dimension": rdim,
        "fourier_modes": int(flow.modes.shape[0]),
    }
    return curve, tau, U, AD0, alpha, consts, diag


def _auxiliary_rows(curve, abel, th, Jp, M, u, W0, alpha, e, U, dlog_d, Bc):
    """Exponent constants nu(P, k) at points P where eigenvectors mix (near branch points).

    Returns (nu (n, 3), relative component sizes |psi_k| / |psi| (n, 3)).
    """
    bp = np.asarray(curve.branch_points)
    scale = float(np.abs(bp).max())
    R = float(np.abs(bp)[np.abs(bp) > 1e-8 * scale].min())   # a branch point may sit at E = 0 (rank-one a)
    trial = [0.35 * R * np.exp(1j * ang) for ang in (0.3, 1.1, 1.9, 2.7)]
    # Far branch points (|E| ~ 1/(J_2 - J_1) for nearly symmetric bodies) are where L ~ J^2 E^2 and
    # eigenvectors lose accuracy: use the core of the set only.
    core = bp[np.abs(bp) <= 10.0 * np.median(np.abs(bp))]
    for b in core:
        sep = np.abs(bp - b)
        sep = min(sep[sep > 0].min(), abs(b))
        if sep <= 1e-8 * scale:
            continue                        # a branch point at E = 0 (rank-one a): a singular point
        trial += [b + 0.25 * sep * np.exp(1j * ang) for ang in (0.4, 2.5, 4.6)]
    cands = {}
    for E in trial:
        for w in np.linalg.eigvals(lax_matrix(Jp, M, u, E)):
            v = right_eigenvector(lax_matrix(Jp, M, u, E), w) @ Bc
            h = np.abs(v) / np.linalg.norm(v)
            order = np.argsort(h)
            pair = tuple(sorted(order[1:]))
            if h[order[1]] > cands.get(pair, (0.0,))[0]:
                cands[pair] = (h[order[1]], E, w)
    pts = sorted(cands.values(), key=lambda c: -c[0])
    E = np.array([c[1] for c in pts])
    w = np.array([c[2] for c in pts])
    A = abel([(complex(a_), complex(b_)) for a_, b_ in zip(E, w)])
    v = right_eigenvector(lax_matrix(Jp, M, u, E), w)
    psi = v / (v @ alpha)[:, None]
    dpsi = -np.einsum("nij,nj->ni", np.diag(Jp)[None] * E[:, None, None] + W0[None], psi) @ Bc
    psi = psi @ Bc
    _, vb, gb = th.jet(A[:, None, :] - e[None, :, :], order=1, separated=True)
    nu = dpsi / psi - (gb @ U) / vb + dlog_d[None, :]
    return nu, np.abs(psi) / np.linalg.norm(psi, axis=1, keepdims=True)


def _riemann_constant(abel, th, canon, Jp, M, u, curve) -> np.ndarray:
    """Vector of Riemann constants in the curve's normalized coordinates and base point.

    2K = -A(C) for the canonical divisor C of the holomorphic differential E dE / f_w (given as
    ``canon``, place -> order: the regular places over E = 0 and the places at infinity).  Of the 4^g candidates the one with
    theta(K + A(D')) = 0 for effective D' of degree g - 1 is taken (Riemann's vanishing theorem).
    Only regular places are involved, so clustered branch points do not matter.
    """
    g = th.g
    tau = th.tau
    places = list(canon)
    rng = np.random.default_rng(7)
    scale = float(np.abs(np.asarray(curve.branch_points)).max())
    pts = []
    for _ in range(3 * (g - 1)):                     # three random effective divisors of degree g - 1
        E = scale * (0.3 + 0.5 * rng.random()) * np.exp(2j * np.pi * rng.random())
        pts.append((E, rng.choice(np.linalg.eigvals(lax_matrix(Jp, M, u, E)))))
    A_all = abel(places + pts)                       # one call: the paths are planned together
    AC = np.array([canon[P] for P in places], float) @ A_all[:len(places)]
    bits = (np.arange(2 ** g)[:, None] >> np.arange(g)[None, :]) & 1
    a_, b_ = np.repeat(bits, 2 ** g, axis=0), np.tile(bits, (2 ** g, 1))
    cands = -0.5 * AC + 0.5 * a_ + 0.5 * (b_ @ tau.T)
    score = np.zeros(len(cands))
    for AD in A_all[len(places):].reshape(3, g - 1, g).sum(axis=1):
        _, v = th(cands + AD[None, :], separated=True)
        score = np.maximum(score, np.abs(v))
    order = np.argsort(score)
    # Near a pinched cycle two candidates differ only by exp(-pi Im tau_jj / 4) and give theta
    # functions equal to that size: the smallest is taken when both vanish to the accuracy of the
    # Abel images (1e-10..1e-9 on nearly degenerate curves).  A wrong choice would show in the
    # consistency checks of the set-up (imaginary exponents, size of the shift correction).
    best, nxt = score[order[0]], score[order[1]]
    if not (best < 1e-8 and (best < 0.1 * nxt or nxt < 1e-8)):
        raise RuntimeError(f"Riemann constant: no half-period candidate makes theta vanish "
                           f"(best {score[order[0]]:.2g}, next {score[order[1]]:.2g})")
    return cands[order[0]]


def _match_branches(curve, branches, mu):
    """Order the node's branches like the slopes ``mu`` (w = lambda + mu E + ...)."""
    lb = curve.node[1]
    out = []
    for m in mu:
        best = None
        for Pl in branches:
            if Pl in out:
                continue
            # a branch's y at the place is lambda; its first-order term distinguishes it
            ser = curve._place_data(Pl, None, None)
            k, t0, Fy, _ = ser
            c1 = Fy[k == 1][0] / t0 if np.any(k == 1) else 0.0
            dist = abs(c1 - m)
            if best is None or dist < best[0]:
                best = (dist, Pl)
        out.append(best[1])
    return out


def _solve_theta_rotation(J, a, Q0, omega0, dps=None) -> ThetaRotation:
    """Build the theta-function solution (called by :func:`thetasol.solve_rotation`)."""
    if dps is not None:
        raise ClosedFormUnavailable("dps= is not available for the theta-function solution")
    try:
        curve, tau, U, AD0, alpha, consts, diag = _setup(J, a, Q0, omega0)
    except ClosedFormUnavailable:
        raise
    except (ValueError, RuntimeError, np.linalg.LinAlgError) as exc:
        # the data were validated by solve_rotation: a failure here is the curve's, not the input's
        msg = f"theta-function solution unavailable for these data: {exc}"
        if _symmetry_axis(_principal_frame(J)[0]) is not None:
            msg += ("; a symmetric body with little spin about its symmetry axis has a spectral curve "
                    "near a tacnode over E = infinity (Neumann's problem), where the set-up fails")
        raise ClosedFormUnavailable(msg) from exc
    inv = _invariants(J, a, Q0, omega0)
    inv = {k: (float(v) if np.ndim(v) == 0 else v) for k, v in inv.items()}
    inv.update(diag)
    inv["genus"] = curve.genus
    kind = ("symmetric-" if consts["axis"] is not None else "") + ("nodal-" if curve.node is not None else "")
    method = f"theta/{kind}genus-{curve.genus}"
    sol = ThetaRotation(J=J, a=a, Q0=Q0, omega0=omega0, method=method, invariants=inv,
                        curve=curve, basis=consts["G"], riemann_matrix=tau, U=U, abel_divisor=AD0,
                        alpha=alpha, _c=consts)
    # Phi(0, t) is real: its imaginary part at a far time bounds what the set-up lost (it runs
    # 1e-13..1e-9 at t = 1000 on accurate solutions; it was 3e-7 where a nearly symmetric body's
    # spectral data came out 1e-7 off, before the engine's fix for clustered branch points).
    res = float(sol.imaginary_residual(np.array([1000.0]))[0])
    inv["imaginary_residual_t1000"] = res
    if res > 1e-8:
        warnings.warn(f"theta-function solution: |Im Phi(0, t)| = {res:.1g} at t = 1000; the set-up lost "
                      "accuracy (nearly degenerate spectral curve) and errors of that size are to be "
                      "expected; compare with thetasol.integrate_rotation", RuntimeWarning, stacklevel=3)
    return sol
