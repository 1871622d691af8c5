"""The spectral curve (4.12) of a rigid body in a quadratic potential, as a Riemann surface.

``det(J^2 E^2 + M E + u - w 1) = 0`` (library conventions, docs/conventions.md: ``M = hat(m)``,
``u = -Q^T a Q``), a 3-sheeted cover of the E-line, with the involution ``(E, w) -> (-E, w)``
(``L(-E)^T = L(E)``).  Generic genus 4: 12 branch points symmetric under ``E -> -E``, three
unramified places over ``E = infinity`` (``w / E^2 -> J_j^2``) and three over ``E = 0``
(``w`` = eigenvalues of ``u``).

Exactness.  The floats of J, M, u are taken as the exact binary rationals they represent and the
coefficients are expanded exactly (in float64 they lose the small terms, e.g. ``|M|^2`` near an
equilibrium); the odd powers of E, which vanish identically, are set to exact zeros.  Degenerate
data are detected with a relative tolerance and made exactly degenerate before the curve is built,
so that the curve's algebraic type is decided exactly, never by the size of rounding errors:

* a repeated eigenvalue ``lam`` of ``u`` (``a`` plus a multiple of 1 has rank one, e.g. the
  gravity-gradient potential of Section 7): ``u`` is replaced by ``lam 1 + rank one`` and the
  coefficients that must vanish at the node ``(E, w) = (0, lam)`` are set to exact zeros; the curve
  is nodal, geometric genus 3 (:attr:`SpectralCurve.genus`), arithmetic genus 4;
* two equal ``J_i`` (a symmetric body): made exactly equal; the places over ``E = infinity`` are then
  singular points of the plane model and the genus drops (to 3 generically); the normalization is
  still computed correctly, but the places at infinity cannot all be labelled by ``j``;
* a triple eigenvalue of ``u`` (``a`` isotropic or zero): the curve is reducible; a ValueError says so.

Every snap is reported in :attr:`SpectralCurve.degeneracy` with the size of the change.  Data that are
nearly but not within the tolerance of a degeneration give a genuinely smooth curve with close branch
points; the curve engine then either resolves them (raising precision where float64 cannot separate the
sheets) or raises a ValueError saying the curve is numerically singular.
"""
from __future__ import annotations

from fractions import Fraction
from math import comb

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core.validate import finite_array, second_moments
from thetasol.curves._poly import CurvePoly
from thetasol.curves._qpoly import discriminant_in_y
from thetasol.curves.plane_curve import Place, PlaneCurve

__all__ = ["spectral_curve", "SpectralCurve", "farthest_branch_point"]


def _skew(M, name="M"):
    M = finite_array(M, name)
    if M.shape == (3,):
        m = M
        return np.array([[0.0, -m[2], m[1]], [m[2], 0.0, -m[0]], [-m[1], m[0], 0.0]])
    if M.shape != (3, 3):
        raise ValueError(f"{name} must be a skew 3x3 matrix or a 3-vector, got shape {M.shape}")
    scale = max(np.max(np.abs(M)), np.finfo(float).tiny)
    asym = np.max(np.abs(M + M.T)) / scale
    if asym > 1e-12:
        raise ValueError(f"{name} must be skew-symmetric: max |{name} + {name}^T| / max|{name}| = {asym:.3g}")
    return 0.5 * (M - M.T)


def _sym(u, name="u"):
    u = finite_array(u, name, (3, 3))
    scale = max(np.max(np.abs(u)), np.finfo(float).tiny)
    asym = np.max(np.abs(u - u.T)) / scale
    if asym > 1e-12:
        raise ValueError(f"{name} must be symmetric: max |{name} - {name}^T| / max|{name}| = {asym:.3g}")
    return 0.5 * (u + u.T)


def _fr(v: float) -> Fraction:
    return Fraction(float(v))


def _exact_coefficients(J, M, u) -> list:
    """Coefficients ``C[k][l]`` of ``det(J^2 E^2 + M E + u - w 1) = sum C[k][l] E^k w^l`` (4.12), exact.

    The floats of J, M, u are taken as the binary rationals they are and the determinant is expanded in
    rational arithmetic.  In float64 the coefficients lose the small terms they carry: near an
    equilibrium ``|M|^2 ~ 1e-6`` enters the ``E^2 w`` coefficient beside O(1) terms, and a few ulps there
    move the flow velocity U enough to show in the attitude at far times.
    """
    Jf = [[_fr(v) for v in row] for row in np.asarray(J, float)]
    J2 = [[sum(Jf[i][k] * Jf[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    Mf = [[_fr(v) for v in row] for row in M]
    uf = [[_fr(v) for v in row] for row in u]
    # L as 3x3 polynomials in (E, w): dict {(k, l): Fraction}
    L = [[{} for _ in range(3)] for _ in range(3)]
    for i in range(3):
        for j in range(3):
            ent = {(0, 0): uf[i][j], (1, 0): Mf[i][j], (2, 0): J2[i][j]}
            if i == j:
                ent[(0, 1)] = Fraction(-1)
            L[i][j] = {kl: c for kl, c in ent.items() if c != 0}

    def mul(p, q):
        out = {}
        for (a, b), c in p.items():
            for (d, e), f in q.items():
                out[(a + d, b + e)] = out.get((a + d, b + e), Fraction(0)) + c * f
        return out

    det = {}
    for (i, j, k), sgn in (((0, 1, 2), 1), ((1, 2, 0), 1), ((2, 0, 1), 1),
                           ((0, 2, 1), -1), ((2, 1, 0), -1), ((1, 0, 2), -1)):
        for kl, c in mul(mul(L[0][i], L[1][j]), L[2][k]).items():
            det[kl] = det.get(kl, Fraction(0)) + sgn * c
    C = [[Fraction(0)] * 4 for _ in range(7)]
    for (k, l), c in det.items():
        C[k][l] = c
    return C


def farthest_branch_point(J: ArrayLike, M: ArrayLike, u: ArrayLike) -> float:
    """max ``|E|`` over the finite branch points of (4.12) for exactly these ``J, M, u``, without the curve.

    The roots of the discriminant in ``w`` of the cubic ``f = a w^3 + b w^2 + c w + d`` (``a = -1``, so
    the branch points are its roots), ``b^2 c^2 - 4 a c^3 - 4 b^3 d - 27 a^2 d^2 + 18 a b c d``
    (:func:`thetasol.curves._qpoly.discriminant_in_y`), formed from the exact rational coefficients
    (:func:`_exact_coefficients`) and rounded once: cheap, where
    building the Riemann surface of a curve with branch points far out (a nearly spherical symmetric
    body with a small axial spin) can take minutes.  A multiple root (a symmetric body's node)
    comes out of ``np.roots`` with ~sqrt(eps) relative error, a simple one with ~eps
    (tests/test_curve_public_helpers.py).  No snapping: pass the data as the curve is to be built
    (e.g. two ``J_i`` already made equal).

    Parameters
    ----------
    J : array_like, shape (3, 3)
        Second moments (diagonal in the principal frame).
    M : array_like, shape (3, 3)
        Skew angular momentum ``hat(m)``.
    u : array_like, shape (3, 3)
        Symmetric ``u = -Q^T a Q``.

    Returns
    -------
    float
        The largest modulus of the critical values (0.0 when there are none).
    """
    C = _exact_coefficients(J, M, u)
    disc = discriminant_in_y([[C[k][l] for k in range(len(C))] for l in range(4)])   # w^l's polynomial in E
    cf = np.array([float(x) for x in reversed(disc)])
    return float(np.abs(np.roots(cf)).max()) if len(cf) > 1 else 0.0


def spectral_curve(J: ArrayLike, M: ArrayLike, u: ArrayLike, *, tol: float = 1e-9) -> SpectralCurve:
    """The spectral curve (4.12) ``det(J^2 E^2 + M E + u - w 1) = 0`` as a :class:`SpectralCurve`.

    Parameters
    ----------
    J : array_like
        Second moments: 3 principal values or a symmetric 3x3 tensor (the paper's J, (2.9)).  Unlike
        the entry points, which take the inertia ``I``, this takes ``J``: the curve (4.12) is written in
        it; of a body given by its inertia pass ``thetasol.second_moments(I)``.
    M : array_like
        Angular momentum, skew 3x3 ``M = hat(m)`` or the 3-vector ``m``.
    u : array_like
        Symmetric 3x3 ``u = -Q^T a Q`` (docs/conventions.md).
    tol : float
        Relative tolerance under which two eigenvalues of ``u`` (relative to the spread of its
        eigenvalues and to ``|u|``) or two principal values of ``J^2`` count as equal; such data are
        made exactly degenerate (see the module docstring and :attr:`SpectralCurve.degeneracy`).

    Returns
    -------
    SpectralCurve
        A :class:`~thetasol.curves.plane_curve.PlaneCurve` in the coordinates ``x = E``, ``y = w``.
    """
    J = second_moments(J, "J")
    M = _skew(M)
    u = _sym(u)
    if not (tol >= 0 and np.isfinite(tol)):
        raise ValueError(f"tol must be a finite non-negative number, got {tol}")
    return SpectralCurve(J, M, u, tol)


def _check_reducible(J, M, u, Vu, tol):
    """Raise if J, u and M have a common invariant line (then a linear factor in w splits off)."""
    m = np.array([M[2, 1], M[0, 2], M[1, 0]])
    cands = [Vu[:, i] for i in range(3)] + [np.linalg.eigh(J)[1][:, i] for i in range(3)]
    if np.linalg.norm(m) > 0:
        cands.append(m / np.linalg.norm(m))
    sJ, su = np.abs(J).max(), max(np.abs(u).max(), np.finfo(float).tiny)
    # M v = 0 is judged against the size of the whole Lax matrix (M small against J^2 and u counts)
    sm = max(np.linalg.norm(m), sJ**2, su)
    for v in cands:
        rJ = np.linalg.norm(J @ v - (v @ J @ v) * v) / sJ
        ru = np.linalg.norm(u @ v - (v @ u @ v) * v) / su
        rm = np.linalg.norm(np.cross(m, v)) / sm
        if max(rJ, ru, rm) <= max(tol, 1e-13):
            raise ValueError(
                "the spectral curve is reducible: J, u and M have a common invariant line "
                f"(v = {np.array2string(v, precision=6)}, a principal axis of J and of u, with m along v "
                "or m = 0), so det(L - w) has a factor J_v^2 E^2 + u_v - w")


class SpectralCurve(PlaneCurve):
    """The spectral curve (4.12) with its involution and its special places.

    Attributes
    ----------
    J2 : (3,) principal values of ``J^2`` (after snapping);  M, u : the matrices used (after snapping)
    degeneracy : list of str, empty for generic data
    node : (0.0, lam) or None, the node at ``E = 0`` for a repeated eigenvalue ``lam`` of ``u``
    symmetric_body : bool
    """

    def __init__(self, J, M, u, tol):
        J = np.asarray(J, float)
        evJ, VJ = np.linalg.eigh(J)
        degeneracy = []
        scaleJ = max(abs(evJ).max(), np.finfo(float).tiny)
        # symmetric body: two equal principal values
        self.symmetric_body = False
        for i, j in ((0, 1), (1, 2), (0, 2)):
            if abs(evJ[i] - evJ[j]) <= tol * scaleJ:
                self.symmetric_body = True
        if self.symmetric_body:
            ev = evJ.copy()
            if abs(ev[0] - ev[1]) <= tol * scaleJ and abs(ev[1] - ev[2]) <= tol * scaleJ:
                ev[:] = ev.mean()
            elif abs(ev[0] - ev[1]) <= tol * scaleJ:
                ev[0] = ev[1] = 0.5 * (ev[0] + ev[1])
            else:
                ev[1] = ev[2] = 0.5 * (ev[1] + ev[2])
            change = float(np.max(np.abs(ev - evJ)))
            if np.all(ev == ev[0]):
                degeneracy.append(f"spherical body (all J_i equal, changed by {change:.3g})")
            else:
                degeneracy.append(f"symmetric body (two equal J_i, changed by {change:.3g}): the places "
                                  "over E = infinity are singular points of the plane model")
            evJ = ev
            J = (VJ * evJ) @ VJ.T if np.any(J - np.diag(np.diag(J))) else np.diag(evJ)
        lam, V = np.linalg.eigh(u)
        _check_reducible(J, M, u, V, tol)
        spread = lam[-1] - lam[0]
        scale_u = max(abs(lam).max(), np.finfo(float).tiny)
        if spread <= tol * scale_u:
            raise ValueError(
                "u has a triple eigenvalue (the potential a is isotropic or zero): the spectral curve is "
                "reducible (w - lam divides by E^3 after the shift); the rotation is the Euler top's")
        gaps = np.diff(lam)
        node = None
        shift = Fraction(0)
        k = int(np.argmin(gaps))
        if gaps[k] <= tol * max(spread, 0.0) or gaps[k] <= tol * scale_u:
            pair = (k, k + 1)
            other = 2 if k == 0 else 0
            lb = 0.5 * (lam[pair[0]] + lam[pair[1]])
            change = 0.5 * gaps[k]
            v = V[:, other]
            u_rank1 = (lam[other] - lb) * np.outer(v, v)
            node = (0.0, float(lb))
            shift = _fr(lb)
            degeneracy.append(f"rank-one a (u has a double eigenvalue {lb:.12g}, changed by {change:.3g}): "
                              f"node at (E, w) = (0, {lb:.12g}), geometric genus 3")
            Cx = _exact_coefficients(J, M, u_rank1)
            u = lb * np.eye(3) + u_rank1
        else:
            Cx = _exact_coefficients(J, M, u)
        odd = max(abs(float(c)) for kk in range(1, 7, 2) for c in Cx[kk])
        if odd > 1e-10 * max(abs(float(c)) for row in Cx for c in row):
            raise ValueError("odd powers of E do not cancel: M is not skew or J, u not symmetric")
        # odd powers vanish for exactly skew M and symmetric u; the floats given are so only to rounding
        for kk in range(1, 7, 2):
            Cx[kk] = [Fraction(0)] * 4
        if node is not None:
            # the node at (E, w') = (0, 0): R(0, 0) = d_w' R(0, 0) = 0 exactly (d_E R vanishes by parity)
            Cx[0][0] = Cx[0][1] = Fraction(0)
        C = np.array([[float(c) for c in row] for row in Cx])
        # exact rational coefficients of R(E, w) = sum C[k, l] E^k (w - shift)^l
        coef = {}
        for kk in range(C.shape[0]):
            for ll in range(C.shape[1]):
                cf = Cx[kk][ll]
                if cf == 0:
                    continue
                for m in range(ll + 1):
                    term = cf * comb(ll, m) * (-shift) ** (ll - m)
                    coef[(kk, m)] = coef.get((kk, m), Fraction(0)) + term
        self.J2 = evJ**2
        self.J = J
        self.M = M
        self.u = u
        self.tol = tol
        self.node = node
        self.degeneracy = degeneracy
        self.coefficients = C
        try:
            # coordinates named E, w: sympy Symbols of these names only when first asked for
            super().__init__(None, "E", "w", _poly=CurvePoly.from_exact(coef, "E", "w"))
        except ValueError as exc:
            if "reducible" in str(exc):
                raise ValueError(f"the spectral curve of these data is reducible ({exc}); for example "
                                 "u commutes with J and M = 0, or m is along a common eigenvector") from exc
            raise

    def _singular_sites(self):
        """The local data of the node over E = 0 (rank-one u) and, for a symmetric body, of the node
        over E = infinity, when these account for the whole drop of the genus (else None: all sites).
        The adjoint conditions then need the circles around them only (those around the other
        critical values are a large part of the set-up)."""
        sites = []
        if self.node is not None:
            k = self._site_index(0.0)
            if k < 0:
                return None
            sites.append(k)
        if self.symmetric_body:
            sites.append(-1)
        return sites if len(sites) == self.arithmetic_genus - self.genus else None

    # ------------------------------------------------------------------ involution
    def involution(self, p: Place | tuple[complex, complex]) -> tuple[complex, complex] | Place:
        """The involution sigma: (E, w) -> (-E, w), on points or places."""
        if isinstance(p, Place):
            return self._involution_place(p)
        E, w = p
        return (-complex(E), complex(w))

    def _involution_place(self, P):
        from thetasol.curves._places import series_eval
        if P.kind == "regular":
            return Place(self, "regular", -P.x, 1, y=P.y)
        cands = self.places_at_infinity() if P.kind == "infinity" else self.places_over(-P.x)
        if len(cands) == 1:
            return cands[0]
        k, t0, Fy, _ = self._place_data(P, None, None)
        # compare y along a small parameter value: s^e = -t^e (finite) or s^-e = -t^-e (infinity)
        tt = 0.3 * t0
        yP = series_eval(k, t0, Fy, tt)
        best = []
        for Q in cands:
            if Q.e != P.e:
                continue
            kq, s0, Fq, _ = self._place_data(Q, None, None)
            e = Q.e
            base = (-(tt**e)) ** (1.0 / e) if P.kind != "infinity" else (-(tt ** (-e))) ** (-1.0 / e)
            for j in range(e):
                s = base * np.exp(2j * np.pi * j / e)
                best.append((abs(series_eval(kq, s0, Fq, s) - yP), Q))
        best.sort(key=lambda r: r[0])
        return best[0][1]

    def prym_differentials(self) -> list:
        """The holomorphic differentials g dE / f_w that sigma maps to their negatives (g even in E).

        They span the differentials of the Prym variety, on which the flow of (4.8) is linear:
        {1, E^2, w} for generic data, {E^2, w - lam} for a rank-one potential (node at w = lam).
        """
        import sympy as sp
        out = []
        for g in self.holomorphic_differentials():
            if sp.expand(g.subs(self.x, -self.x) - g) == 0:
                out.append(g)
        return out

    # ------------------------------------------------------------------ special places
    def places_at_infinity(self) -> list:
        """The places over E = infinity, ordered by j with w / E^2 -> J2[j] (generic data).

        For a symmetric body fewer than three places may exist; they are ordered by their limit.
        """
        if "inf_sorted" not in self._cache:
            pl = super().places_at_infinity()
            lims = []
            for P in pl:
                k, t0, Fy, _ = self._place_data(P, None, None)
                # w / E^2 = w t^(2e) at t -> 0: the coefficient of t^(-2e) in the series of w
                c = Fy[k == -2 * P.e][0] / t0 ** (-2 * P.e) if np.any(k == -2 * P.e) else 0.0
                lims.append(complex(c))
            order = np.argsort(np.abs(lims), kind="stable")
            if not self.symmetric_body and len(pl) == 3:
                # assign j by the nearest J2
                order = sorted(order, key=lambda i: int(np.argmin(np.abs(self.J2 - lims[i]))))
            pl = [pl[i] for i in order]
            self._cache["inf_sorted"] = pl
        return list(self._cache["inf_sorted"])

    def place_at_infinity(self, j: int) -> Place:
        """The place over E = infinity with w / E^2 -> J2[j] (J2 sorted ascending)."""
        if self.symmetric_body:
            raise ValueError("symmetric body: the places over E = infinity cannot be labelled by j "
                             f"({self.degeneracy})")
        pl = self.places_at_infinity()
        return pl[j]

    def places_over_zero(self) -> list:
        """The places over E = 0: w -> eigenvalues of u (with the node's two branches if nodal)."""
        return self.places_over(0.0)

    def node_branches(self) -> list:
        """The two places over the node (E, w) = (0, lam) of a rank-one potential (swapped by sigma)."""
        if self.node is None:
            raise ValueError("the curve has no node (u has no repeated eigenvalue)")
        lb = self.node[1]
        out = [P for P in self.places_over(0.0) if abs(P.y - lb) <= 1e-6 * (1 + abs(lb))]
        if len(out) != 2:
            raise RuntimeError(f"expected two branches over the node, found {len(out)}")
        return out
