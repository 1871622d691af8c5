"""Roots in y at the tracker's nodes (thetasol.curves._poly.CurvePoly.roots_from_coeffs, ``any_order``):
Cardano's closed form for cubics, with a fallback to companion eigenvalues.

Reference: mpmath.polyroots at 40 digits on the same float64 coefficients.
"""
import mpmath
import numpy as np
import pytest
import sympy as sp

from thetasol.curves._poly import CurvePoly

_X, _Y = sp.symbols("x y")
_CUBIC = CurvePoly(_Y**3 - _X, _X, _Y)   # any curve with three sheets: roots_from_coeffs uses only A


def _reference(A):
    with mpmath.workdps(40):
        return np.array([[complex(z) for z in mpmath.polyroots([mpmath.mpc(complex(v)) for v in row[::-1]],
                                                                maxsteps=400, extraprec=200)] for row in A])


def _errors(Y, ref):
    """Largest distance of a reference root to the nearest computed one, relative to the largest root."""
    d = np.abs(Y[:, :, None] - ref[:, None, :]).min(axis=1)
    return (d.max(axis=1) / np.abs(ref).max(axis=1)).max()


def _cubics(kind, scale, k=40, seed=3):
    rng = np.random.default_rng(seed)
    z = lambda *s: rng.standard_normal(s) + 1j * rng.standard_normal(s)  # noqa: E731
    if kind == "random":
        r = z(k, 3)
    elif kind == "real":
        r = rng.standard_normal((k, 3)) + 0j
    elif kind == "close pair":
        c = z(k)
        r = np.stack([c, c + 1e-6 * z(k), z(k)], axis=1)
    else:   # a pair 6 apart at 1e8 and a root near 1 (the far branch points of a symmetric body)
        r = np.stack([np.full(k, 1e8), 1e8 + 6 * rng.uniform(0.5, 2, k), 1 + rng.standard_normal(k)], axis=1) + 0j
    return np.array([np.poly(row * scale)[::-1] for row in r])    # a_0 .. a_3 (a_3 = 1)


# Errors of the closed form against the eigenvalues' on the same cubics (40 each), measured: before
# the Newton steps 0.2-1.1 times theirs (random 3-7e-15, real 2-7e-13, close pair 2-4e-9, far pair 1-3e-8);
# after them (both limited by the conditioning) 0.1-2.5 times theirs.
@pytest.mark.parametrize("kind", ["random", "real", "close pair", "far pair"])
@pytest.mark.parametrize("scale", [1e-8, 1.0, 1e8])
def test_closed_form_roots_against_mpmath(kind, scale):
    A = _cubics(kind, scale).astype(complex)
    ref = _reference(A)
    seeds = [_CUBIC.roots_from_coeffs(A, polish=0, any_order=o) for o in (True, False)]
    assert _errors(seeds[0], ref) <= 1.5 * _errors(seeds[1], ref)
    roots = [_CUBIC.roots_from_coeffs(A, any_order=o) for o in (True, False)]
    assert _errors(roots[0], ref) <= 4 * _errors(roots[1], ref) + 1e-15
    assert _errors(roots[0], ref) <= {"random": 1e-14, "real": 1e-12, "close pair": 1e-8, "far pair": 1e-6}[kind]


def test_rows_beyond_the_closed_form_fall_back_to_eigenvalues():
    """Roots ~1e80: p^3 overflows in Cardano's formula; those rows come from the eigenvalues.
    (Reference: the roots the coefficients were made from; mpmath.polyroots does not converge here.)"""
    r = np.array([1.0, 2.0 + 1j, -3.0])
    A = np.array([np.poly(r * s)[::-1] for s in (1e80, 1.0)], complex)
    fast = _CUBIC.roots_from_coeffs(A, any_order=True)
    assert _errors(fast, np.array([r * 1e80, r])) <= 1e-14      # measured 1.1e-17
