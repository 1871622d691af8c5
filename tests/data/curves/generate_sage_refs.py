"""Generate the reference period matrices in this directory with Sage (an oracle only).

Run with a Python that has Sage (passagemath) installed:  python generate_sage_refs.py [names...]
Each curve is written to <name>.json: the polynomial (exact rationals, variables x, y), the basis of
differential numerators g (omega = g dx / f_y) Sage used, and the period matrix at ``prec`` bits
as decimal strings.  thetasol's tests recompute the periods for the same numerators and compare the
two matrices as lattices (P_ours = P_ref T with T in Sp(2g, Z)).
"""
import json
import sys
import time
from fractions import Fraction

from sage.all__sagemath_schemes import QQ, PolynomialRing
from sage.schemes.riemann_surfaces.riemann_surface import RiemannSurface


def spectral_poly(J, M, u):
    """det(J^2 E^2 + M E + u - w) over QQ, in x = E, y = w."""
    from sage.all__sagemath_schemes import matrix
    R = PolynomialRing(QQ, "x,y")
    E, w = R.gens()
    J2 = matrix(QQ, J) ** 2
    L = J2 * E**2 + matrix(QQ, M) * E + matrix(QQ, u) - w * matrix.identity(3)
    return L.det()


def fr(s):
    return QQ(Fraction(s).numerator) / QQ(Fraction(s).denominator)


def curves():
    R = PolynomialRing(QQ, "x,y")
    x, y = R.gens()
    out = {
        "elliptic": y**2 - (x**3 + x + 1),
        "hyp_x5m1": y**2 - (x**5 - 1),
        "bolza": y**2 - (x**5 - x),
        "hyp_g2": y**2 - (x**6 + 2 * x**5 - 3 * x**3 + x + 5),
        "hyp_g3": y**2 - (x**7 - 2 * x**5 + x**4 + 3 * x - 1),
        "hyp_g4_even": y**2 - (x**10 - 3 * x**7 + x**6 + 2 * x**3 - x + QQ(7) / 3),
        "fermat4": x**4 + y**4 - 1,
        "klein": x**3 * y + y**3 + x,
        "quartic": x**4 + 2 * y**4 + x**3 * y - 3 * x * y**2 + 5 * x**2 - y + QQ(1) / 2,
        "trigonal": y**3 + x**4 + x + 1,
        "nodal_quartic": x**4 + y**4 - x**2 + 2 * y**2 + x * y**3,
        "cusp_quintic": y**4 - x**3 * (x - 1) * (x + 2) + x**2 * y**2,
        "singular_g3": (y**2 - x**3) ** 2 - x**7 + y**3,
        "quintic_in_y": y**5 - x**3 + 2 * x * y**2 - 1,
        "poles_of_y": x**2 * y**3 + y + x**3 - 2,
        "close_branch_points": y**2 - (x**2 - 1) * (x**2 - 1 - QQ(1) / 10**6) * (x - 3),
        "collinear_branch_points": y**2 - x * (x - 1) * (x - 2) * (x - 3) * (x - 4),
        "superelliptic": y**3 - (x**5 - x),
    }
    # spectral curves (4.12) with rational data; x = E, y = w
    J = [[1, 0, 0], [0, QQ(17) / 10, 0], [0, 0, QQ(29) / 10]]
    m = [QQ(3) / 10, QQ(-7) / 10, QQ(11) / 10]
    M = [[0, -m[2], m[1]], [m[2], 0, -m[0]], [-m[1], m[0], 0]]
    u = [[QQ(-12) / 10, QQ(3) / 10, QQ(1) / 10], [QQ(3) / 10, QQ(5) / 10, QQ(-4) / 10],
         [QQ(1) / 10, QQ(-4) / 10, QQ(9) / 10]]
    out["spectral_g4"] = spectral_poly(J, M, u)
    # rank-one a: u = lam 1 + alpha v v^T (v rational, so the node is exact)
    v = [QQ(2), QQ(-1), QQ(2)]
    alpha, lam = QQ(-1) / 3, QQ(1) / 5
    u1 = [[lam * (i == j) + alpha * v[i] * v[j] / 9 for j in range(3)] for i in range(3)]
    out["spectral_nodal_g3"] = spectral_poly(J, M, u1)
    # symmetric body J1 = J2
    Js = [[1, 0, 0], [0, 1, 0], [0, 0, QQ(29) / 10]]
    out["spectral_symmetric"] = spectral_poly(Js, M, u)
    return out


# Sage needs tens of minutes at 212 bits for this one; 128 bits (38 digits) is ample for the tests
PREC = {"close_branch_points": 120}


def main(names):
    allc = curves()
    if not names:
        names = list(allc)
    for name in names:
        f = allc[name]
        t0 = time.time()
        if name not in PREC:  # (the 53-bit run of close_branch_points does not finish)
            S53 = RiemannSurface(f, prec=53)
            S53.period_matrix()
        t53 = time.time() - t0 if name not in PREC else None
        prec = PREC.get(name, 212)
        t0 = time.time()
        S = RiemannSurface(f, prec=prec)
        P = S.period_matrix()
        t200 = time.time() - t0
        basis = [str(g) for g in S.cohomology_basis()]
        rec = {
            "name": name,
            "f": str(f),
            "variables": ["x", "y"],
            "genus": int(S.genus),
            "differentials": basis,
            "prec_bits": prec,
            "period_matrix_re": [[str(c.real()) for c in row] for row in P.rows()],
            "period_matrix_im": [[str(c.imag()) for c in row] for row in P.rows()],
            "sage_seconds_prec53": t53,
            "sage_seconds_high_prec": t200,
            "generator": "tests/data/curves/generate_sage_refs.py (Sage RiemannSurface, passagemath 10.8)",
        }
        with open(f"{name}.json", "w") as fh:
            json.dump(rec, fh, indent=1)
        print(name, "genus", S.genus, f"{t53}s / {t200:.2f}s", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
