"""The Kepler orbit (7.7) by universal variables, against extended-precision references.

References nobody here wrote: heyoka's Taylor integrator of ``qddot = -mu q/|q|^3`` in 80-bit
(``np.longdouble``) and quadruple (``heyoka.real128``) precision, and the classical (not universal)
Kepler equation solved in 50-digit mpmath from the float64 data.  Errors are relative to the
orbit's size (apoapsis distance, or |r| for open orbits) and to the largest speed.
"""
import math

import mpmath
import numpy as np
import pytest

from thetasol.solutions.orbit.kepler import KeplerOrbit

MU_EARTH = 3.986004418e14


def _periapsis_start(e, mu=1.0, rp=1.0, incl=0.6):
    """r0 at periapsis on the x axis, v0 in the plane tilted by ``incl`` about x."""
    v = math.sqrt(mu * (1 + e) / rp)
    return np.array([rp, 0.0, 0.0]), np.array([0.0, v * math.cos(incl), v * math.sin(incl)])


def _state_from_elements(p, e, nu, incl=0.4, mu=1.0):
    """(r, v) at true anomaly nu of the conic (p, e), periapsis on x, plane tilted about x."""
    rn = p / (1 + e * math.cos(nu))
    c, s = math.cos(incl), math.sin(incl)
    rot = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    r = rn * np.array([math.cos(nu), math.sin(nu), 0.0])
    v = math.sqrt(mu / p) * np.array([-math.sin(nu), e + math.cos(nu), 0.0])
    return rot @ r, rot @ v


def _heyoka(mu, r0, v0, ts, fp="ldbl"):
    hy = pytest.importorskip("heyoka")
    ft, tol = (np.longdouble, np.longdouble(1e-19)) if fp == "ldbl" else (hy.real128, hy.real128("1e-32"))
    x = hy.make_vars("x", "y", "z", "vx", "vy", "vz")
    r3 = (x[0] ** 2 + x[1] ** 2 + x[2] ** 2) ** 1.5
    sys = [(x[i], x[3 + i]) for i in range(3)] + [(x[3 + i], -x[i] / r3 * float(mu)) for i in range(3)]
    ta = hy.taylor_adaptive(sys, np.array([ft(float(c)) for c in list(r0) + list(v0)]), fp_type=ft, tol=tol)
    res = ta.propagate_grid(np.array([ft(0.0)] + [ft(float(t)) for t in ts]))
    out = np.asarray(res[-1], dtype=float)[1:]
    return out[:, :3], out[:, 3:]


def _mp_kepler(mu, r0, v0, t, dps=50):
    """(r, v) at one float time from the elliptic or hyperbolic Kepler equation in mpmath."""
    with mpmath.workdps(dps):
        mpf = mpmath.mpf
        m = mpf(float(mu))
        R = mpmath.matrix([mpf(float(c)) for c in r0])
        Vv = mpmath.matrix([mpf(float(c)) for c in v0])
        r = mpmath.norm(R)
        alpha = 2 / r - (Vv.T * Vv)[0] / m
        s = (R.T * Vv)[0]
        t = mpf(float(t))
        if alpha > 0:
            a = 1 / alpha
            n = mpmath.sqrt(m / a ** 3)
            ec, es = 1 - r / a, s / mpmath.sqrt(m * a)          # e cos E0, e sin E0
            M = n * t
            M = M - 2 * mpmath.pi * mpmath.nint(M / (2 * mpmath.pi))
            dE = mpmath.findroot(lambda x: x - ec * mpmath.sin(x) + es * (1 - mpmath.cos(x)) - M, M)
            f = 1 - a / r * (1 - mpmath.cos(dE))
            g = (r * mpmath.sin(dE) + s * mpmath.sqrt(a / m) * (1 - mpmath.cos(dE))) * mpmath.sqrt(a / m)
            Rt = f * R + g * Vv
            rt = mpmath.norm(Rt)
            fd = -mpmath.sqrt(m * a) * mpmath.sin(dE) / (rt * r)
            gd = 1 - a / rt * (1 - mpmath.cos(dE))
        else:
            a = 1 / alpha                                       # negative
            n = mpmath.sqrt(m / (-a) ** 3)
            ec, es = 1 - r / a, s / mpmath.sqrt(-m * a)         # e cosh H0, e sinh H0
            dH = mpmath.findroot(lambda x: ec * mpmath.sinh(x) + es * (mpmath.cosh(x) - 1) - x - n * t,
                                 mpmath.asinh(n * t))
            f = 1 - a / r * (1 - mpmath.cosh(dH))
            g = (r * mpmath.sinh(dH) + s * mpmath.sqrt(-a / m) * (mpmath.cosh(dH) - 1)) * mpmath.sqrt(-a / m)
            Rt = f * R + g * Vv
            rt = mpmath.norm(Rt)
            fd = -mpmath.sqrt(-m * a) * mpmath.sinh(dH) / (rt * r)
            gd = 1 - a / rt * (1 - mpmath.cosh(dH))
        Vt = fd * R + gd * Vv
        return np.array([float(c) for c in Rt]), np.array([float(c) for c in Vt])


def _scales(orb):
    d = orb.diagnostics
    e, p = d["e"], d["p"]
    vmax = math.sqrt(orb.mu / p) * (1 + e)
    size = p / (1 - e) if d["kind"] == "elliptic" else None
    return size, vmax


# -- elliptic orbits: many revolutions ------------------------------------------------------

@pytest.mark.parametrize("e", [0.0, 0.3, 0.7, 0.9])
def test_elliptic_100_revolutions_against_heyoka_80bit(e):
    r0, v0 = _periapsis_start(e)
    orb = KeplerOrbit(1.0, r0, v0)
    assert orb.diagnostics["kind"] == "elliptic" and abs(orb.diagnostics["e"] - e) < 1e-15
    T = orb.period
    ts = np.linspace(0.0, 100 * T, 41)[1:] + 0.123 * T
    R, Vr = _heyoka(1.0, r0, v0, ts)
    r, v = orb(ts)
    size, vmax = _scales(orb)
    # measured 1.2e-15 / 1.2e-15 (e = 0) ... 2.0e-14 / 7.4e-15 (e = 0.9), the 80-bit reference's
    # own drift included (quad precision shows it: 6.4e-15 at e = 0.99 after 20 revolutions)
    assert np.abs(r - R).max() / size < 1e-13
    assert np.abs(v - Vr).max() / vmax < 5e-14


def test_e099_20_revolutions_against_heyoka_quad():
    r0, v0 = _periapsis_start(0.99)
    orb = KeplerOrbit(1.0, r0, v0)
    T = orb.period
    ts = np.array([0.37, 5.0, 19.5, 20.0]) * T      # 20 T is the periapsis passage
    R, Vr = _heyoka(1.0, r0, v0, ts, fp="quad")
    r, v = orb(ts)
    size, vmax = _scales(orb)
    # measured 1.8e-17 / 6.5e-17 (the 80-bit integration itself is 6.4e-15 off at 20 T)
    assert np.abs(r - R).max() / size < 1e-15
    assert np.abs(v - Vr).max() / vmax < 1e-15


@pytest.mark.slow
@pytest.mark.parametrize("e", [0.99, 0.999])
def test_high_e_100_revolutions_against_heyoka_quad(e):
    r0, v0 = _periapsis_start(e)
    orb = KeplerOrbit(1.0, r0, v0)
    T = orb.period
    ts = np.array([10.0, 100.0, 100.3]) * T
    R, Vr = _heyoka(1.0, r0, v0, ts, fp="quad")
    r, v = orb(ts)
    size, vmax = _scales(orb)
    er, ev = np.abs(r - R).max() / size, np.abs(v - Vr).max() / vmax
    # measured <= 1.1e-16 / 2.8e-17 (the 80-bit reference is 5e-13 / 7e-11 off here at e = 0.99 / 0.999)
    assert er < 1e-15 and ev < 1e-14


@pytest.mark.parametrize("e", [0.0, 0.5, 0.99, 0.999, 1 - 1e-9])
def test_far_times_against_mpmath_kepler_equation(e):
    """t up to 1e6 periods: the reduction modulo the period keeps the digits (and the cost)."""
    r0, v0 = _state_from_elements(1.0 - e * e, e, -2.0) if e < 0.9 else _periapsis_start(e, incl=0.3)
    orb = KeplerOrbit(1.0, r0, v0)
    T = orb.period
    ts = np.array([0.3, 1e2 + 0.41, 1e4 + 0.77, -1e6 - 0.2]) * T
    r, v = orb(ts)
    size, vmax = _scales(orb)
    for k, t in enumerate(ts):
        R, Vr = _mp_kepler(1.0, r0, v0, t)
        # measured <= 6.7e-16 / 5.6e-16
        assert np.abs(r[k] - R).max() / size < 4e-15
        assert np.abs(v[k] - Vr).max() / vmax < 4e-15


# -- open orbits ---------------------------------------------------------------------------------

@pytest.mark.parametrize("e", [1.0 + 1e-12, 1.0001, 1.5, 3.0, 30.0])
def test_hyperbolic_against_heyoka_80bit_and_mpmath(e):
    r0, v0 = _state_from_elements(2.0, e, 0.3)
    orb = KeplerOrbit(1.0, r0, v0)
    assert orb.period == np.inf and orb.diagnostics["kind"] == "hyperbolic"
    ts = np.array([0.3, 3.0, 30.0, 300.0, 3000.0])
    R, Vr = _heyoka(1.0, r0, v0, ts)
    r, v = orb(ts)
    er = np.abs(r - R).max(1) / np.linalg.norm(R, axis=1)
    ev = np.abs(v - Vr).max(1) / np.linalg.norm(Vr, axis=1)
    # measured <= 1.0e-15 / 2.1e-15, against mpmath <= 1.1e-15
    assert er.max() < 1e-14 and ev.max() < 1e-14
    for t in (-40.0, 7.0):
        Rm, Vm = _mp_kepler(1.0, r0, v0, t)
        rr, vv = orb(t)
        assert np.abs(rr - Rm).max() / np.linalg.norm(Rm) < 1e-14
        assert np.abs(vv - Vm).max() / np.linalg.norm(Vm) < 1e-14


def test_parabola_exact():
    """|v0|^2 = 2 mu/|r0| exactly in binary: alpha = 0, Barker's equation as the reference."""
    orb = KeplerOrbit(2.0, [1.0, 0.0, 0.0], [0.0, 2.0, 0.0])      # p = 2, periapsis q = 1 at r0
    d = orb.diagnostics
    assert d["kind"] == "parabolic" and d["e"] == 1.0 and d["a"] == np.inf
    # periapsis q = 1, p = 2: t = sqrt(p^3/mu)/2 (D + D^3/3), D = tan(nu/2); r = p / (1 + cos nu)
    for t in (0.1, 3.0, 1e4):
        with mpmath.workdps(40):
            p, mu = mpmath.mpf(2), mpmath.mpf(2)
            D = mpmath.findroot(lambda D, p=p, mu=mu, t=t: mpmath.sqrt(p ** 3 / mu) / 2 * (D + D ** 3 / 3) - t,
                                mpmath.cbrt(3 * t))
            nu = 2 * mpmath.atan(D)
            rr = p / (1 + mpmath.cos(nu))
            R = np.array([float(rr * mpmath.cos(nu)), float(rr * mpmath.sin(nu)), 0.0])
        r = orb.position(t)
        assert np.abs(r - R).max() / np.linalg.norm(R) < 4e-15


# -- invariants, units, shapes, elements ---------------------------------------------------------

def test_invariants_conserved():
    for r0, v0 in [_periapsis_start(0.8), (np.array([1.0, 0.3, -0.2]), np.array([0.1, 1.6, 0.4]))]:
        orb = KeplerOrbit(1.0, r0, v0)
        r, v = orb(np.linspace(-50, 50, 201))
        rn = np.linalg.norm(r, axis=1)
        h = np.cross(r, v)
        lrl = np.cross(v, h) - r / rn[:, None]
        energy = 0.5 * np.sum(v * v, axis=1) - 1.0 / rn
        inv = orb.invariants
        rv = rn * np.linalg.norm(v, axis=1)             # the rounding scale of r x v
        e_en = np.abs(energy - inv["energy"]).max() / abs(inv["energy"])
        e_h = (np.abs(h - inv["h"]).max(1) / rv).max()
        e_l = (np.abs(lrl - inv["lrl"]).max(1) / (rv * np.linalg.norm(v, axis=1) + 1.0)).max()
        # measured 1.8e-15, 1.2e-15, 6.5e-16 (relative to the rounding scales |r||v|, |r||v|^2 + mu)
        assert e_en < 1e-14 and e_h < 2e-14 and e_l < 2e-14


@pytest.mark.parametrize("alt, ecc", [(400e3, 0.0), (400e3, 0.01), (35786e3, 0.0), (500e3, 0.7)])
def test_si_units_leo_geo(alt, ecc):
    rp = 6378137.0 + alt
    r0, v0 = _periapsis_start(ecc, mu=MU_EARTH, rp=rp, incl=0.9)
    orb = KeplerOrbit(MU_EARTH, r0, v0)
    T = orb.period
    ts = np.array([0.25, 3.6, 20.0]) * T
    R, Vr = _heyoka(MU_EARTH, r0, v0, ts)
    r, v = orb(ts)
    size, vmax = _scales(orb)
    assert np.abs(r - R).max() / size < 1e-14 and np.abs(v - Vr).max() / vmax < 1e-13
    # the same orbit in normalized units (length rp, time sqrt(rp^3/mu)) is as accurate: no
    # tolerance depends on the units.  Measured <= 3.5e-16 / 1.5e-15 in both.
    L, tau = rp, math.sqrt(rp ** 3 / MU_EARTH)
    r0n, v0n, tn = r0 / L, v0 * tau / L, ts / tau
    orb1 = KeplerOrbit(1.0, r0n, v0n)
    R1, V1 = _heyoka(1.0, r0n, v0n, tn)
    r1, v1 = orb1(tn)
    assert np.abs(r1 - R1).max() / (size / L) < 1e-14 and np.abs(v1 - V1).max() / (vmax * tau / L) < 1e-13
    if ecc == 0.0 and alt > 1e7:
        assert abs(T - 86164.1) < 0.1 * 86164.1     # the geostationary radius gives a sidereal day


def test_shapes_and_scalar_path():
    orb = KeplerOrbit(1.0, [1.0, 0.1, 0.0], [0.0, 1.2, 0.3])
    r, v = orb(2.5)
    assert r.shape == (3,) and v.shape == (3,)
    t = np.linspace(-7, 7, 12).reshape(3, 4)
    r, v = orb(t)
    assert r.shape == (3, 4, 3) and orb.position(t).shape == (3, 4, 3) and orb.velocity(t).shape == (3, 4, 3)
    for tt, rr, vv in zip(t.ravel(), r.reshape(-1, 3), v.reshape(-1, 3), strict=True):
        rs, vs = orb.state_at(tt)
        assert np.abs(np.array(rs) - rr).max() < 4e-15 and np.abs(np.array(vs) - vv).max() < 4e-15
    r, v = orb(0.0)
    assert np.array_equal(r, orb.r0) and np.array_equal(v, orb.v0)


def test_elements_recovered():
    a, e, i, raan, argp, nu = 2.0, 0.3, 0.7, 1.1, 2.2, 0.5
    mu = 1.0
    p = a * (1 - e * e)
    rn = p / (1 + e * math.cos(nu))
    rpf = rn * np.array([math.cos(nu), math.sin(nu), 0.0])
    vpf = math.sqrt(mu / p) * np.array([-math.sin(nu), e + math.cos(nu), 0.0])
    def Rz(x):
        return np.array([[math.cos(x), -math.sin(x), 0], [math.sin(x), math.cos(x), 0], [0, 0, 1]])
    Rx = np.array([[1, 0, 0], [0, math.cos(i), -math.sin(i)], [0, math.sin(i), math.cos(i)]])
    Rm = Rz(raan) @ Rx @ Rz(argp)
    orb = KeplerOrbit(mu, Rm @ rpf, Rm @ vpf)
    el = orb.elements
    for k, want in zip(("a", "e", "i", "raan", "argp", "nu0"), (a, e, i, raan, argp, nu), strict=True):
        assert abs(el[k] - want) < 1e-13, k
    assert abs(orb.period - 2 * math.pi * math.sqrt(a ** 3 / mu)) < 1e-13
    assert orb.invariants["energy"] == pytest.approx(-mu / (2 * a), rel=1e-14)


@pytest.mark.parametrize("mu, r0, v0, what", [
    (1.0, [1.0, 0, 0], [2.0, 0, 0], "radial"),
    (1.0, [1.0, 0, 0], [0.0, 0, 0], "radial"),
    (0.0, [1.0, 0, 0], [0, 1.0, 0], "mu"),
    (-1.0, [1.0, 0, 0], [0, 1.0, 0], "mu"),
    (float("nan"), [1.0, 0, 0], [0, 1.0, 0], "mu"),
    (1.0, [np.nan, 0, 0], [0, 1.0, 0], "r0"),
    (1.0, [0.0, 0, 0], [0, 1.0, 0], "r0"),
    (1.0, [1.0, 0], [0, 1.0, 0], "r0"),
])
def test_bad_data_refused(mu, r0, v0, what):
    with pytest.raises(ValueError, match=what):
        KeplerOrbit(mu, r0, v0)
