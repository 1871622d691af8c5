"""Gyrostats with rotors (Section 8): solve_gyrostat(..., rotors=...) against the FULL
carrier-plus-rotors system integrated by heyoka in 80-bit precision.

The reference is built from the Lagrangian of the carrier and its rotors, term by term (nothing
of the reduced model (8.39) enters it):

    L = 1/2 omega . I_0 omega + sum_k [ 1/2 m_k |omega x r_k|^2 + 1/2 B_k (|omega|^2 - (omega . l_k)^2)
                                        + 1/2 A_k (omega . l_k + phidot_k)^2 ],

with the carrier's own inertia ``I_0``, rotor ``k`` of mass ``m_k`` centred at ``r_k`` on its axis
``l_k``, axial moment ``A_k`` and transverse moment ``B_k``.  The state is (omega, Q, phi_k, phidot_k);
the Euler-Poincare equation d/dt dL/domega = dL/domega x omega, the Lagrange equations
d/dt dL/dphidot_k = dL/dphi_k = 0 and Qdot = Q hat(omega), solved for (omegadot, phiddot) with the
mass matrix inverted in mpmath (40 digits).  The closed form gets what the paper's reduction says
it needs: ``J`` of the carrier with the rotors' masses and transverse moments (the second moments
of ``I_0 + sum_k [m_k (|r_k|^2 - r_k r_k^T) + B_k (1 - l_k l_k^T)]``), the axes, ``A_k``, ``B_k`` and
``p_k = A_k (omega0 . l_k + phidot_k(0))``.  The carrier's ``I_0`` is derived from that ``J`` in
mpmath, so both sides see the same body exactly.

Tolerance: ``max(1e-9, 100 x conditioning)``, the conditioning being the spread of the reference
itself when ``omega0`` moves by 1e-15 (relative): measured for each quantity (omega relative to
``max |omega|``, Q and the rotor angles absolute).
"""
import functools

import mpmath as mp
import numpy as np
import pytest
from conftest import label, rand_Q

from thetasol import ClosedFormUnavailable, inertia, solve_gyrostat, solve_many

_TAYLOR = {}


def _taylor(nrot):
    """heyoka integrator of the carrier-plus-rotors system with nrot rotors; runtime parameters:
    the momentum map K = Mtop (omega, phidot) (3 x (3 + nrot)) and the first three columns of the
    inverse mass matrix ((3 + nrot) x 3)."""
    hy = pytest.importorskip("heyoka")
    if nrot not in _TAYLOR:
        nv = 3 + nrot
        names = [f"w{i}" for i in range(3)] + [f"q{i}{j}" for i in range(3) for j in range(3)]
        names += [f"phi{k}" for k in range(nrot)] + [f"phid{k}" for k in range(nrot)]
        xs = hy.make_vars(*names)
        w = xs[:3]
        Q = [xs[3 + 3 * i: 6 + 3 * i] for i in range(3)]
        phid = xs[12 + nrot:]
        v = list(w) + list(phid)
        K = [sum(hy.par[nv * i + j] * v[j] for j in range(nv)) for i in range(3)]
        F = [K[1] * w[2] - K[2] * w[1], K[2] * w[0] - K[0] * w[2], K[0] * w[1] - K[1] * w[0]]
        off = 3 * nv
        acc = [sum(hy.par[off + 3 * r + c] * F[c] for c in range(3)) for r in range(nv)]
        W = [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]]
        Qd = [sum(Q[i][k] * W[k][j] for k in range(3)) for i in range(3) for j in range(3)]
        rhs = acc[:3] + Qd + list(phid) + acc[3:]
        fp = np.longdouble
        _TAYLOR[nrot] = hy.taylor_adaptive(list(zip(xs, rhs, strict=True)), np.zeros(len(xs), dtype=fp),
                                           tol=fp(1e-19), fp_type=fp, pars=np.zeros(off + 3 * nv, dtype=fp),
                                           compact_mode=True)
    return _TAYLOR[nrot]


def _ld(x):
    """An mpmath number as a long double (to its 64-bit mantissa)."""
    return np.longdouble(mp.nstr(x, 30, strip_zeros=False))


def _system(body):
    """Mpmath pieces of the full system: the carrier's own inertia I_0 (from J less the rotors'
    masses and transverse moments), the full mass matrix, and the initial rotor rates."""
    J, rot, w0 = body["J"], body["rotors"], body["omega0"]
    with mp.workdps(40):
        Jm = mp.matrix(np.diag(J).tolist() if np.ndim(J) == 1 else np.asarray(J).tolist())
        IJ = (Jm[0, 0] + Jm[1, 1] + Jm[2, 2]) * mp.eye(3) - Jm
        I0 = IJ.copy()
        for r in rot:
            l, c = mp.matrix(list(r["axis"])), mp.matrix(list(r["center"]))
            I0 -= r["mass"] * ((c.T * c)[0] * mp.eye(3) - c * c.T) + r["B"] * (mp.eye(3) - l * l.T)
        ev = mp.eigsy(I0)[0]
        assert min(ev) > 0 and 2 * max(ev) < sum(ev)  # a physical carrier
        n, nv = len(rot), 3 + len(rot)
        M = mp.zeros(nv, nv)
        Ifull = I0.copy()
        for k, r in enumerate(rot):
            l, c = mp.matrix(list(r["axis"])), mp.matrix(list(r["center"]))
            Ifull += r["mass"] * ((c.T * c)[0] * mp.eye(3) - c * c.T) + r["B"] * (mp.eye(3) - l * l.T)
            Ifull += r["A"] * l * l.T
            for i in range(3):
                M[i, 3 + k] = M[3 + k, i] = r["A"] * l[i]
            M[3 + k, 3 + k] = r["A"]
        for i in range(3):
            for j in range(3):
                M[i, j] = Ifull[i, j]
        Minv = M ** -1
        wm = mp.matrix(list(w0))
        phid0 = [r["p"] / r["A"] - (mp.matrix(list(r["axis"])).T * wm)[0] for r in rot]
        pars = [M[i, j] for i in range(3) for j in range(nv)] + [Minv[i, j] for i in range(nv) for j in range(3)]
        return [_ld(x) for x in pars], [_ld(x) for x in phid0], n


def full_reference(body, Q0, t, omega0=None):
    """(omega, Q, phi, p) of the carrier-plus-rotors system at the times t (either sign; 80-bit
    heyoka, forward and backward from 0)."""
    body = dict(body, omega0=body["omega0"] if omega0 is None else omega0)
    pars, phid0, n = _system(body)
    ta = _taylor(n)
    t = np.asarray(t, dtype=float)
    res = np.empty((t.size, 12 + 2 * n), dtype=np.longdouble)
    for sel in (t >= 0, t < 0):
        if not sel.any():
            continue
        idx = np.nonzero(sel)[0]
        order = idx[np.argsort(np.abs(t[idx]))]
        ta.pars[:] = np.array(pars, dtype=np.longdouble)
        st = [np.longdouble(float(x)) for x in body["omega0"]] + [np.longdouble(float(x)) for x in np.ravel(Q0)]
        ta.state[:] = np.array(st + [np.longdouble(0)] * n + phid0, dtype=np.longdouble)
        ta.time = np.longdouble(0)
        grid = [np.longdouble(float(x)) for x in t[order]]
        lead = [] if grid[0] == 0 else [np.longdouble(0)]
        res[order] = np.asarray(ta.propagate_grid(np.array(lead + grid))[-1])[len(lead):]
    pk = [body["rotors"][k]["A"] * (res[:, :3] @ np.array(body["rotors"][k]["axis"], dtype=np.longdouble)
                                    + res[:, 12 + n + k]) for k in range(n)]
    res = res.astype(float)
    return res[:, :3], res[:, 3:12].reshape(-1, 3, 3), res[:, 12:12 + n], np.array(pk, dtype=float).T


def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def make_body(seed, nrot):
    """A carrier with nrot rotors: random carrier inertia, rotor masses on random axes; ``J`` is
    the float64 second moments of the carrier with the rotors' masses and transverse moments."""
    rng = np.random.default_rng(seed)
    I0 = np.diag(rng.uniform(1.0, 2.0, 3))
    R = rand_Q(rng)
    I0 = R @ I0 @ R.T
    rotors, Itot = [], I0.copy()
    for _ in range(nrot):
        l = _unit(rng.normal(size=3))
        c = rng.uniform(-0.5, 0.5) * l  # the rotor's centre is on its axis
        mass, A, B = rng.uniform(0.1, 0.5), rng.uniform(0.05, 0.3), rng.uniform(0.03, 0.2)
        Itot = Itot + mass * (c @ c * np.eye(3) - np.outer(c, c)) + B * (np.eye(3) - np.outer(l, l))
        rotors.append({"axis": l, "A": A, "B": B, "p": rng.normal() * 2, "mass": mass, "center": c})
    J = 0.5 * np.trace(Itot) * np.eye(3) - Itot
    J = 0.5 * (J + J.T)
    return {"J": J, "rotors": rotors, "omega0": rng.normal(size=3)}


def solver_rotors(body):
    return [{k: r[k] for k in ("axis", "A", "B", "p")} for r in body["rotors"]]


def compare(body, Q0, t, slow_factor=1.0):
    """Closed form against the full reference: errors and bounds per quantity."""
    sol = solve_gyrostat(inertia(body["J"]), None, Q0, body["omega0"], rotors=solver_rotors(body))
    w, Q = sol(t)
    phi = sol.rotor_angles(t)
    wr, Qr, phir, pk = full_reference(body, Q0, t)
    rng = np.random.default_rng(99)
    w1 = body["omega0"] * (1 + 1e-15 * _unit(rng.normal(size=3)))
    wp, Qp, phip, _ = full_reference(body, Q0, t, omega0=w1)
    sw = np.max(np.abs(wr))
    err = {"omega": np.max(np.abs(w - wr)) / sw, "Q": np.max(np.abs(Q - Qr)), "phi": np.max(np.abs(phi - phir))}
    cond = {"omega": np.max(np.abs(wp - wr)) / sw, "Q": np.max(np.abs(Qp - Qr)), "phi": np.max(np.abs(phip - phir))}
    return sol, err, cond, pk


def _check(err, cond, floor=1e-9):
    """The acceptance bound max(1e-9, 100 x conditioning); ``floor`` tightens the 1e-9 where the
    measured errors are far below it."""
    for k in err:
        assert err[k] <= max(floor, 100 * cond[k]), (k, err[k], cond[k])


@pytest.mark.parametrize("seed, nrot", [(1, 1), (2, 2), (3, 3)])
def test_rotors_against_full_system(seed, nrot):
    """1-3 rotors, t in [-1000, 1000]: measured (seeds 1-3) omega 1.8e-13..5.3e-13 (relative), Q
    1.6e-13..6.6e-13, rotor angles 4.5e-13..3.6e-12 rad (|phi| up to 1e4 rad); the reference's own
    spread under a 1e-15 change of omega0 is of the same size.  Bound max(1e-11, 100 x conditioning), inside the
    acceptance bound max(1e-9, 100 x conditioning)."""
    body = make_body(seed, nrot)
    Q0 = rand_Q(np.random.default_rng(seed + 10))
    t = np.linspace(-1000.0, 1000.0, 101)
    sol, err, cond, pk = compare(body, Q0, t)
    assert label(sol) == "elliptic"
    _check(err, cond, floor=1e-11)
    # the reference conserves p_k (8.25), and the closed form's (8.28) rates give it back
    p = np.array([r["p"] for r in body["rotors"]])
    assert np.max(np.abs(pk - p)) <= 1e-15 * (1 + np.max(np.abs(p))) * 50
    L = np.array([r["axis"] for r in body["rotors"]])
    A = np.array([r["A"] for r in body["rotors"]])
    back = A * (sol.omega(t) @ L.T + sol.rotor_rates(t))
    assert np.max(np.abs(back - p)) <= 8e-16 * np.max(np.abs(p) + A * np.max(np.abs(sol.omega(t))))


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(100, 124))
def test_rotors_against_full_system_sweep(seed):
    """24 more bodies with 1-3 rotors, t in [-1000, 1000]: measured at most omega 1.6e-12, Q
    1.8e-12, angles 1.5e-11."""
    body = make_body(seed, 1 + seed % 3)
    Q0 = rand_Q(np.random.default_rng(seed + 10))
    t = np.linspace(-1000.0, 1000.0, 101)
    _, err, cond, _ = compare(body, Q0, t)
    _check(err, cond)


@pytest.mark.slow
def test_rotors_against_full_system_t1e4():
    """Farther: t up to 1e4.  (Beyond, the 80-bit reference of the full system drifts itself: at
    t = 3e4 its Q is 4.7e-13 off orthogonal and 1e-10 off the closed form about the momentum,
    while the reduced model's reference, 80-bit or quadruple, agrees with the closed form to
    3.5e-12.)"""
    body = make_body(7, 2)
    Q0 = rand_Q(np.random.default_rng(17))
    t = np.linspace(0.0, 1e4, 41)
    _, err, cond, _ = compare(body, Q0, t)
    _check(err, cond)


def separatrix_body(eps):
    """The gyrostat J = (0.75, 0.25, 1.25), N = (0, 0, 2), omega0 = (0, 2, 1) is on a separatrix
    (test_gyrostat.SEPARATRIX); here N comes from two tilted rotors and omega0_y is moved by eps."""
    s = np.sqrt(0.36)
    rotors = [{"axis": np.array([s, 0.0, 0.8]), "A": 0.2, "B": 0.05, "p": 1.25, "mass": 0.1,
               "center": np.array([0.3 * s, 0.0, 0.24])},
              {"axis": np.array([-s, 0.0, 0.8]), "A": 0.15, "B": 0.04, "p": 1.25, "mass": 0.2,
               "center": np.array([0.2 * s, 0.0, -0.16])}]
    return {"J": np.array([0.75, 0.25, 1.25]), "rotors": rotors, "omega0": np.array([0.0, 2.0 * (1 + eps), 1.0])}


@pytest.mark.parametrize("eps", [1e-4, 1e-8, 1e-12])
def test_rotors_next_to_the_separatrix(eps):
    """Near-separatrix motion (mc ~ eps), t in [-1000, 1000].  Measured: at eps = 1e-4 omega
    3.7e-11, Q 8.7e-11, angles 2.3e-10 (conditioning 2.7e-10, 6.4e-10, 1.7e-9); at 1e-8 9.3e-8, 1.7e-7,
    6.2e-7 (conditioning 6.9e-7, 1.3e-6, 4.6e-6); at 1e-12 the conditioning is 7e-3..5e-2 and
    the errors 0.14 of it: the closed form is as good as a 1.4e-16 change of the data."""
    body = separatrix_body(eps)
    Q0 = rand_Q(np.random.default_rng(21))
    t = np.linspace(-1000.0, 1000.0, 101)
    sol, err, cond, _ = compare(body, Q0, t)
    assert label(sol) == "elliptic"
    assert np.allclose(sol.N, [0.0, 0.0, 2.0], rtol=0, atol=1e-15)
    _check(err, cond)


SPECIAL = {
    # carrier symmetric about z, one rotor on the axis: the dual-spin (axisymmetric) closed form
    "axisymmetric": ({"J": np.array([0.6, 0.6, 0.4]), "rotors": [
        {"axis": np.array([0.0, 0.0, 1.0]), "A": 0.1, "B": 0.05, "p": 0.7, "mass": 0.2,
         "center": np.array([0.0, 0.0, 0.1])}], "omega0": np.array([0.3, -0.2, 1.1])}, "elementary:axisymmetric"),
    # spherical carrier: trigonometric
    "sphere": ({"J": np.array([0.5, 0.5, 0.5]), "rotors": [
        {"axis": np.array([0.6, 0.8, 0.0]), "A": 0.1, "B": 0.0, "p": 0.9, "mass": 0.0,
         "center": np.zeros(3)}], "omega0": np.array([0.3, -0.2, 1.1])}, "elementary:spherical"),
    # two opposite rotors of equal momentum: N = 0, the Euler top
    "euler-top": ({"J": np.array([0.7, 0.5, 0.3]), "rotors": [
        {"axis": np.array([0.0, 0.0, 1.0]), "A": 0.1, "B": 0.02, "p": 0.8, "mass": 0.1,
         "center": np.array([0.0, 0.0, 0.2])},
        {"axis": np.array([0.0, 0.0, -1.0]), "A": 0.2, "B": 0.02, "p": 0.8, "mass": 0.1,
         "center": np.array([0.0, 0.0, -0.2])}], "omega0": np.array([0.3, -0.9, 0.4])}, "elliptic"),
    # omega0 along a principal axis with N along it: steady rotation
    "steady": ({"J": np.array([0.7, 0.5, 0.3]), "rotors": [
        {"axis": np.array([0.0, 1.0, 0.0]), "A": 0.1, "B": 0.02, "p": 0.8, "mass": 0.1,
         "center": np.zeros(3)}], "omega0": np.array([0.0, 1.3, 0.0])}, "elementary:steady"),
}


@pytest.mark.parametrize("name", list(SPECIAL))
def test_rotors_in_the_special_closed_forms(name):
    """The trigonometric and limiting forms carry rotor angles too (t in [-1000, 1000]): measured
    omega <= 6.1e-14, Q <= 1.2e-13, angles <= 1.8e-12 (bound 1e-11)."""
    body, method = SPECIAL[name]
    Q0 = rand_Q(np.random.default_rng(31))
    t = np.linspace(-1000.0, 1000.0, 101)
    sol, err, cond, _ = compare(body, Q0, t)
    assert label(sol) == method
    _check(err, cond, floor=1e-11)


def test_invariants_and_rates():
    """(8.40) along the closed form, p_k among the invariants, and d phi_k/dt = rotor_rates
    (5-point differences, h = 1e-3: measured 9.5e-12 relative to max |phidot|, bound 1e-10;
    the invariants 1.9e-15, bound 1e-14)."""
    body = make_body(3, 3)
    sol = solve_gyrostat(inertia(body["J"]), None, np.eye(3), body["omega0"], rotors=solver_rotors(body))
    assert np.array_equal(sol.invariants["rotor_momenta"], [r["p"] for r in body["rotors"]])
    assert len(sol.rotors) == 3 and sol.rotors[1].A == body["rotors"][1]["A"]
    t = np.linspace(0.0, 50.0, 400)
    w, m, h = sol.omega(t), sol.m(t), sol.h(t)
    e = 0.5 * np.sum(m * w, -1)
    assert np.max(np.abs(e / sol.invariants["energy"] - 1)) < 1e-14
    assert np.max(np.abs(np.sum(h * h, -1) / sol.invariants["h2"] - 1)) < 1e-14
    hstep = 1e-3
    ph = [sol.rotor_angles(t + k * hstep) for k in (-2, -1, 1, 2)]
    d = (ph[0] - 8 * ph[1] + 8 * ph[2] - ph[3]) / (12 * hstep)
    r = sol.rotor_rates(t)
    assert np.max(np.abs(d - r)) < 1e-10 * np.max(np.abs(r))
    assert np.array_equal(sol.rotor_angles(0.0), np.zeros(3))


def test_far_times_and_wrapping():
    """phi_k at t = 1e6: the wrapped angles equal the unwrapped ones modulo 2 pi (to the unwrapped
    value's own rounding, |phi| eps), and the shapes follow t."""
    body = make_body(2, 2)
    sol = solve_gyrostat(inertia(body["J"]), None, np.eye(3), body["omega0"], rotors=solver_rotors(body))
    t = np.array([[1.0, 1e3], [1e5, 1e6]])
    phi, wr = sol.rotor_angles(t), sol.rotor_angles(t, wrap=True)
    assert phi.shape == (2, 2, 2) and wr.shape == (2, 2, 2)
    assert np.all(np.abs(wr) <= np.pi)
    diff = np.remainder(phi - wr + np.pi, 2 * np.pi) - np.pi
    assert np.all(np.abs(diff) <= 8 * np.finfo(float).eps * (np.abs(phi) + 1))
    assert sol.rotor_rates(t).shape == (2, 2, 2)


def test_without_rotors_there_are_no_angles():
    sol = solve_gyrostat(inertia([0.7, 0.5, 0.3]), [0.0, 0.1, 0.2], np.eye(3), [0.3, -0.9, 0.4])
    assert sol.rotors == ()
    with pytest.raises(ValueError, match="without rotors"):
        sol.rotor_angles(1.0)


def test_rotors_on_the_separatrix():
    """Exactly on the gyrostat's separatrix (Chebyshev series in tanh u), t in [0, 30] (the
    reference leaves the separatrix at its own rounding: its spread under a 1e-15 change of
    omega0 is 1.1e-10 in omega and Q, 5.0e-10 in the angles at t = 30): measured omega 1.7e-11,
    Q 1.7e-11, angles 7.5e-11 (bound max(1e-11, 100 x conditioning))."""
    body = separatrix_body(0.0)
    Q0 = rand_Q(np.random.default_rng(23))
    t = np.linspace(0.0, 30.0, 61)
    sol, err, cond, _ = compare(body, Q0, t)
    assert label(sol) == "elliptic:separatrix"
    _check(err, cond, floor=1e-11)
    # omega . l_k tends to the saddle's value: the rotor rates tend to p_k / A_k - omega_s . l_k
    ws = np.array([0.0, 0.0, 3.0])  # the saddle (test_gyrostat.test_separatrix_limits_are_the_saddle)
    late = sol.rotor_rates(np.array([60.0]))[0]
    assert np.allclose(late, [r["p"] / r["A"] - ws @ r["axis"] for r in body["rotors"]], rtol=0, atol=1e-8)


def test_euler_top_separatrix_refuses_rotor_angles():
    """Rotors whose momenta cancel on an Euler top's separatrix (I = (3, 4, 6), m = (6, 0, 6))."""
    r = [dict(axis=[0.0, 0.0, 1.0], A=0.1, B=0.0, p=0.5), dict(axis=[0.0, 0.0, -1.0], A=0.1, B=0.0, p=0.5)]
    with pytest.raises(ClosedFormUnavailable, match="Euler top"):
        solve_gyrostat(inertia([3.5, 2.5, 0.5]), None, np.eye(3), [2.0, 0.0, 1.0], rotors=r)


def test_refusals_are_returned_by_solve_many():
    """The refusal is a ClosedFormUnavailable, so solve_many(errors="return") returns it in place
    (a bare NotImplementedError was a fault raised in every mode)."""
    r = [dict(axis=[0.0, 0.0, 1.0], A=0.1, B=0.0, p=0.5), dict(axis=[0.0, 0.0, -1.0], A=0.1, B=0.0, p=0.5)]
    separatrix = (inertia([3.5, 2.5, 0.5]), None, np.eye(3), [2.0, 0.0, 1.0])
    out = solve_many([separatrix], solver=functools.partial(solve_gyrostat, rotors=r), workers=1, errors="return")
    assert isinstance(out[0], ClosedFormUnavailable) and "Euler top" in str(out[0])


_R = {"axis": [0.0, 0.0, 1.0], "A": 0.1, "B": 0.02, "p": 0.5}


@pytest.mark.parametrize("rotors, N, msg", [
    ([dict(_R, axis=[0.0, 0.0, 1.1])], None, "unit vector"),
    ([dict(_R, A=0.0)], None, "must be > 0"),
    ([dict(_R, B=-1.0)], None, "must be >= 0"),
    ([dict(_R, p=np.nan)], None, "finite"),
    ([{"axis": [0.0, 0.0, 1.0], "A": 0.1, "p": 0.5}], None, "keys"),
    ([dict(_R, C=1.0)], None, "unknown keys"),
    ([_R], [0.0, 0.0, 0.6], "does not match"),
    ([_R], [0.0, 1e-9, 0.5], "does not match"),
    (_R, None, "sequence"),
])
def test_bad_rotors(rotors, N, msg):
    with pytest.raises(ValueError, match=msg):
        solve_gyrostat(inertia([0.7, 0.5, 0.3]), N, np.eye(3), [0.3, -0.9, 0.4], rotors=rotors)


def test_rotor_data_are_normalized_and_checked():
    """An axis within 1e-12 of unit length is normalized; N within 1e-12 relative is accepted."""
    r = dict(_R, axis=[0.0, 0.0, 1.0 + 1e-13])
    sol = solve_gyrostat(inertia([0.7, 0.5, 0.3]), [0.0, 0.0, 0.5 * (1 + 1e-13)], np.eye(3), [0.3, -0.9, 0.4], rotors=[r])
    assert np.array_equal(sol.rotors[0].axis, [0.0, 0.0, 1.0])
