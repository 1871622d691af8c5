"""The catalogue of reference cases: one builder per case, every model thetasol solves.

Each builder returns a :class:`~thetasol.reference.Case` whose ``rhs`` is the model's ODE
(:mod:`thetasol.reference._models`) and whose ``exact`` is the closed form of
:mod:`thetasol.solutions`, imported and built on first use so that listing the catalogue is cheap.
Data are dimensionless (time unit of order one period) except where a published case fixes them.
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from thetasol.core.inertia import inertia, second_moments
from thetasol.core.so3 import rodrigues
from thetasol.reference import _models as mdl
from thetasol.reference._case import Case, Group

__all__ = ["cases", "case", "names"]

_ROT_EQ = ("I omega' = (I omega) x omega + tau(Q),  Q' = Q hat(omega),  I = tr(J) 1 - J, "
           "tau = vee(J Q^T a Q - Q^T a Q J) (the torque of phi = 1/2 x^T a x, (4.8))")
_ROT_UNITS = "omega: rad per time unit (body frame); Q: body-to-space rotation matrix, row-major"
_VEC_UNITS = "length and length per time unit, space frame"

# A generic attitude and three potentials of the library's reference set (tests/data/rotation/refs.json)
_Q0 = [[0.7274479925655106, -0.3959219569441338, -0.560415222956993],
       [0.13276829459359238, 0.8825206864506512, -0.4511427910732705],
       [0.673195363964368, 0.2537775443103645, 0.6945537847716929]]
_A_GENERIC = [[0.0012301533574825742, -0.29592315062440216, -0.10699712638238955],
              [-0.29592315062440216, -0.45467078517172255, 0.17428434527903558],
              [-0.10699712638238955, 0.17428434527903558, -0.49220651855132963]]
_A_RANK_ONE = [[-0.2710571227788374, 0.45176187129806245, -0.7318542315028612],
               [0.45176187129806245, -0.7529364521634376, 1.2197570525047687],
               [-0.7318542315028612, 1.2197570525047687, -1.976006425057725]]


def _rotation_states(sol, extra=None):
    """flat t -> (n, 12 [+ extra]) from a RotationSolution ``(omega, Q)``."""
    def states(t):
        w, Q = sol(t)
        parts = [w, Q.reshape(t.size, 9)] + ([extra(t)] if extra is not None else [])
        return np.concatenate(parts, axis=1)
    return states


def _rotation_case(name, description, J, a, Q0, w0, t_span=(0.0, 20.0), model="body in a quadratic potential"):
    J, a, Q0, w0 = (np.asarray(x, dtype=float) for x in (J, a, Q0, w0))
    J = np.diag(J) if J.ndim == 1 else J
    rhs, integrals = mdl.rotation_system(J, a)
    if not np.any(a):
        integrals = mdl.free_top_integrals(J)

    def build():
        from thetasol.solutions.rotation.dispatch import solve_rotation
        sol = solve_rotation(inertia(J), a, Q0, w0)
        return sol, _rotation_states(sol)

    eq = _ROT_EQ if np.any(a) else "I omega' = (I omega) x omega,  Q' = Q hat(omega),  I = tr(J) 1 - J (Euler)"
    return Case(name=name, model=model, description=description, equations=eq, units=_ROT_UNITS,
                t_span=t_span, y0=np.concatenate([w0, Q0.ravel()]), columns=mdl.ROTATION_COLUMNS,
                groups=mdl.rotation_groups(), rhs=rhs, build=build, integrals=integrals)


# -- free rigid bodies (a = 0): the Euler top ------------------------------------------------------
# inertia I = (2, 3, 4): J = tr(I)/2 - I = (2.5, 1.5, 0.5); the separatrix is 2 w1^2 = 4 w3^2
_J_FREE = (2.5, 1.5, 0.5)


def _free_cases():
    z = np.zeros((3, 3))
    w_sep = np.array([0.5 * math.sqrt(2.0) * (1.0 + 1e-6), 0.7, 0.5])
    return [
        _rotation_case("free_top_long_axis", "free asymmetric top, I = (2, 3, 4), tumbling about the axis "
                       "of largest inertia (stable, m^2 < 2 E I_2)", _J_FREE, z, _Q0, [0.15, 0.25, 1.0],
                       model="free rigid body"),
        _rotation_case("free_top_short_axis", "free asymmetric top, I = (2, 3, 4), tumbling about the axis "
                       "of smallest inertia (stable, m^2 > 2 E I_2)", _J_FREE, z, _Q0, [1.0, 0.25, 0.15],
                       model="free rigid body"),
        _rotation_case("free_top_near_separatrix", "free asymmetric top, I = (2, 3, 4), 1e-6 (relative, in "
                       "omega_1) off the separatrix through the intermediate axis (Dzhanibekov flips)",
                       _J_FREE, z, _Q0, w_sep, model="free rigid body"),
        _rotation_case("free_top_symmetric", "free symmetric top, I = (2, 2, 3): regular precession",
                       (1.5, 1.5, 0.5), z, _Q0, [0.4, -0.3, 1.2], model="free rigid body"),
    ]


# -- bodies in quadratic potentials ----------------------------------------------------------------
def _potential_cases():
    a_pend = np.diag([0.4, -0.3, 1.1])
    return [
        _rotation_case("potential_generic", "asymmetric body I = (2.7, 2.3, 1.6) in a generic quadratic "
                       "potential: the genus-4 theta-function solution of Section 4 II",
                       (0.6, 1.0, 1.7), _A_GENERIC, _Q0, [0.5, -0.8, 0.6]),
        _rotation_case("potential_rank_one", "asymmetric body in a rank-one potential a = c g g^T "
                       "(gravity-gradient-like): nodal spectral curve, genus 3",
                       (0.6, 1.0, 1.7), _A_RANK_ONE, _Q0, [0.5, -0.8, 0.6]),
        _rotation_case("potential_symmetric_body", "symmetric body I = (2.7, 2.7, 2) with axial spin in a "
                       "generic potential: theta functions of the genus-3 curve",
                       (1.0, 1.0, 1.7), _A_GENERIC, _Q0, [0.5, -0.8, 0.6]),
        _rotation_case("potential_pendulum", "spin about a principal axis that is an eigenvector of "
                       "Q0^T a Q0: the body swings about that axis as a planar pendulum (elliptic functions)",
                       (0.6, 1.0, 1.7), a_pend, rodrigues(np.array([0.0, 0.0, 0.9])), [0.0, 0.0, 0.8]),
    ]


# -- gyrostats (Section 8) -------------------------------------------------------------------------
_GYRO_ROTORS = ({"axis": [0.0, 0.0, 1.0], "A": 0.1, "B": 0.02, "p": 0.5},
                {"axis": [0.6, 0.8, 0.0], "A": 0.05, "B": 0.01, "p": -0.3})


def _gyrostat_case(name, description, N, rotors=None):
    J = np.diag([2.5, 1.5, 0.5])
    Q0, w0 = np.asarray(_Q0), np.array([0.4, -0.6, 0.9])
    rot = [dict(r) for r in rotors] if rotors else None
    Nv = np.asarray(N, float) if N is not None else sum(r["p"] * np.asarray(r["axis"], float) for r in rot)
    rhs, integrals = mdl.gyrostat_system(J, Nv, rot)
    nr = len(rot or [])

    def build():
        from thetasol.solutions.gyrostat import solve_gyrostat
        sol = solve_gyrostat(inertia(J), Nv if rot is None else None, Q0, w0, rotors=rot)
        return sol, _rotation_states(sol, (lambda t: sol.rotor_angles(t).reshape(t.size, nr)) if nr else None)

    columns = mdl.ROTATION_COLUMNS + tuple(f"phi_{k + 1}" for k in range(nr))
    groups = mdl.rotation_groups() + ((Group("rotor_angles", 12, 12 + nr, 1.0),) if nr else ())
    eq = "I omega' = (I omega + N) x omega,  Q' = Q hat(omega)  (8.39)" + (
        ";  phi_k' = p_k / A_k - omega . l_k  (8.25), N = sum p_k l_k" if nr else ", N constant")
    return Case(name=name, model="free gyrostat", description=description, equations=eq,
                units=_ROT_UNITS + ("; phi_k: rotor angles relative to the carrier, rad" if nr else ""),
                t_span=(0.0, 20.0), y0=np.concatenate([w0, Q0.ravel(), np.zeros(nr)]), columns=columns,
                groups=groups, rhs=rhs, build=build, integrals=integrals)


def _gyrostat_cases():
    return [
        _gyrostat_case("gyrostat", "free gyrostat (Zhukovsky-Volterra), carrier I = (2, 3, 4) with a "
                       "constant rotor momentum N = (0.3, -0.2, 0.5)", [0.3, -0.2, 0.5]),
        _gyrostat_case("gyrostat_rotors", "free gyrostat with two rotors (axes e_3 and (0.6, 0.8, 0)): "
                       "carrier motion and the rotor angles", None, _GYRO_ROTORS),
    ]


# -- heavy tops (Section 5) ------------------------------------------------------------------------
def _heavy_top_case(name, description, I, center, Q0, w0, mass, gravity, t_span):
    I, c, Q0, w0, g = (np.asarray(x, dtype=float) for x in (I, center, Q0, w0, gravity))
    I = np.diag(I) if I.ndim == 1 else I
    rhs, integrals = mdl.heavy_top_system(I, c, mass, g)

    def build():
        from thetasol.solutions.tops.heavy_top import solve_heavy_top
        sol = solve_heavy_top(I, c, Q0, w0, mass=mass, gravity=g)
        return sol, _rotation_states(sol)

    return Case(name=name, model="heavy top", description=description,
                equations="I omega' = (I omega) x omega + c x (Q^T mass g),  Q' = Q hat(omega)  "
                          "(I about the fixed point, c the mass centre from it, body frame)",
                units=_ROT_UNITS, t_span=t_span, y0=np.concatenate([w0, Q0.ravel()]),
                columns=mdl.ROTATION_COLUMNS, groups=mdl.rotation_groups(), rhs=rhs, build=build,
                integrals=integrals)


def _heavy_top_cases():
    return [
        _heavy_top_case("lagrange_top", "Lagrange top I = (1.5, 1.5, 0.8), mass centre 0.4 up the axis, "
                        "g = 9.81, tilted 0.6 rad, spin 8: nutation between two latitudes",
                        [1.5, 1.5, 0.8], [0.0, 0.0, 0.4], rodrigues(np.array([0.6, 0.0, 0.0])),
                        [0.3, -0.2, 8.0], 1.0, [0.0, 0.0, -9.81], (0.0, 20.0)),
        _heavy_top_case("simo_wong_top", "the fast symmetric top of Simo & Wong (1991): I = diag(5, 5, 1) "
                        "about the pivot, M g l = 20, Lambda0 = exp(hat(0.05, 0, 0)), W0 = (0, 0, 50); "
                        "energy 1250 + 20 cos 0.05", [5.0, 5.0, 1.0], [0.0, 0.0, 1.0],
                        rodrigues(np.array([0.05, 0.0, 0.0])), [0.0, 0.0, 50.0], 20.0, [0.0, 0.0, -1.0],
                        (0.0, 10.0)),
    ]


# -- point models: Neumann, Kepler, the mass centre --------------------------------------------------
def _point_case(name, model, description, equations, y0, system, build_solution, t_span, scales=(None, None)):
    rhs, integrals = system

    def build():
        sol = build_solution()
        return sol, lambda t: np.concatenate(sol(t), axis=1)

    return Case(name=name, model=model, description=description, equations=equations, units=_VEC_UNITS,
                t_span=t_span, y0=y0, columns=("q_1", "q_2", "q_3", "v_1", "v_2", "v_3"),
                groups=(Group("q", 0, 3, scales[0]), Group("v", 3, 6, scales[1])), rhs=rhs, build=build,
                integrals=integrals)


def _point_cases():
    k = np.array([0.5, 1.3, 2.4])
    q0 = np.array([0.6, 0.48, 0.64])
    v0 = np.cross(q0, [0.3, -0.5, 0.4])
    a_mc, b_mc = np.array([[1.0, 0.2, 0.0], [0.2, -0.3, 0.1], [0.0, 0.1, 0.0]]), np.array([0.2, -0.4, 0.6])

    def neumann():
        from thetasol.solutions.points.neumann import solve_neumann
        return solve_neumann(np.diag(k), q0, v0)

    def kepler(r0, v):
        def make():
            from thetasol.solutions.orbit.kepler import solve_kepler
            return solve_kepler(1.0, r0, v)
        return make

    def mass_centre():
        from thetasol.solutions.points.mass_center import solve_mass_center
        return solve_mass_center(a_mc, b_mc, [0.3, -0.2, 0.5], [0.1, 0.4, -0.2])

    kep = "r' = v,  v' = -mu r / |r|^3  (7.7), mu = 1"
    return [
        _point_case("neumann", "Neumann problem", "point on the unit sphere in phi = 1/2 q^T diag(0.5, 1.3, "
                    "2.4) q: genus-2 (hyperelliptic) motion of Section 6",
                    "q'' = -a q + lambda q,  lambda = (q.aq - |q'|^2) / |q|^2  (6.1)-(6.2)",
                    np.concatenate([q0, v0]), mdl.neumann_system(k), neumann, (0.0, 20.0)),
        _point_case("kepler_ellipse", "Kepler orbit", "bound orbit, mu = 1, e = 0.44, inclined 0.3 rad",
                    kep, [1.0, 0.0, 0.0, 0.0, 1.2 * math.cos(0.3), 1.2 * math.sin(0.3)],
                    mdl.kepler_system(1.0), kepler([1.0, 0.0, 0.0], [0.0, 1.2 * math.cos(0.3), 1.2 * math.sin(0.3)]),
                    (0.0, 20.0)),
        _point_case("kepler_hyperbola", "Kepler orbit", "unbound orbit, mu = 1, e = 1.25 (|r| grows to ~15)",
                    kep, [1.0, 0.0, 0.0, 0.0, 1.5, 0.0], mdl.kepler_system(1.0),
                    kepler([1.0, 0.0, 0.0], [0.0, 1.5, 0.0]), (0.0, 20.0)),
        _point_case("mass_centre", "mass centre in a quadratic potential", "mass centre in phi = 1/2 x^T a x "
                    "+ 1/2 b.x with two oscillating modes (one slow: eigenvalue 0.027) and a hyperbolic one (3.2)",
                    "q'' = -(a q + b / 2)  (3.2)", [0.3, -0.2, 0.5, 0.1, 0.4, -0.2],
                    mdl.mass_center_system(a_mc, b_mc), mass_centre, (0.0, 10.0)),
    ]


# -- gravity-gradient pitch on a circular orbit (Section 7) ----------------------------------------
def _orbiting_case():
    Isat = np.array([1.2, 1.5, 1.8])
    J = np.diag(second_moments(Isat))
    r0, v0 = np.array([1.0, 0.0, 0.0]), np.array([0.0, math.cos(0.4), math.sin(0.4)])
    F0 = np.stack([r0, np.cross(np.cross(r0, v0), r0), np.cross(r0, v0)], axis=1)
    th0, thd = 0.5, 0.3                               # pitch angle from the radial and its rate (n = 1)
    Q0 = F0 @ rodrigues(np.array([0.0, 0.0, th0]))
    w0 = np.array([0.0, 0.0, 1.0 + thd])
    rhs, integrals = mdl.orbiting_system(J, 1.0)

    def build():
        from thetasol.solutions.orbit.kepler import solve_kepler
        from thetasol.solutions.orbit.orbiting_rotation import solve_orbiting_rotation
        orbit = solve_kepler(1.0, r0, v0)
        sol = solve_orbiting_rotation(Isat, orbit, Q0, w0)
        return sol, _rotation_states(sol, lambda t: np.concatenate(orbit(t), axis=1))

    cols = mdl.ROTATION_COLUMNS + ("r_1", "r_2", "r_3", "v_1", "v_2", "v_3")
    groups = mdl.rotation_groups() + (Group("r", 12, 15), Group("v", 15, 18))
    return Case(name="gravity_gradient_pitch", model="orbiting rigid body",
                description="body I = (1.2, 1.5, 1.8) on a circular orbit (mu = 1, r = 1, n = 1, inclined 0.4 "
                            "rad), largest axis along the orbit normal, pitching 0.5 rad from the radial at "
                            "rate 0.3 n: a pitch libration in elliptic functions (Section 7)",
                equations="I omega' = (I omega) x omega + 3 mu / |r|^5 (Q^T r) x I (Q^T r),  Q' = Q hat(omega), "
                          "r' = v,  v' = -mu r / |r|^3  (7.7), (7.16)",
                units=_ROT_UNITS + "; r, v: orbit position and velocity, space frame",
                t_span=(0.0, 4 * math.pi), y0=np.concatenate([w0, Q0.ravel(), r0, v0]), columns=cols,
                groups=groups, rhs=rhs, build=build, integrals=integrals)


@lru_cache(maxsize=1)
def _catalogue() -> tuple[Case, ...]:
    return tuple(_free_cases() + _potential_cases() + _gyrostat_cases() + _heavy_top_cases()
                 + _point_cases() + [_orbiting_case()])


def names() -> list[str]:
    """Names of all cases, in catalogue order."""
    return [c.name for c in _catalogue()]


def cases(names: list[str] | None = None, *, model: str | None = None) -> list[Case]:
    """The reference cases (shared instances: each builds its closed form once).

    Parameters
    ----------
    names : list of str, optional
        Only these cases, in this order (``KeyError`` naming an unknown one).
    model : str, optional
        Only the cases of this model (e.g. ``"heavy top"``).
    """
    allc = _catalogue()
    if names is not None:
        by = {c.name: c for c in allc}
        unknown = [n for n in names if n not in by]
        if unknown:
            raise KeyError(f"unknown reference case(s) {unknown}; known: {[c.name for c in allc]}")
        allc = tuple(by[n] for n in names)
    return [c for c in allc if model is None or c.model == model]


def case(name: str) -> Case:
    """The case called ``name``."""
    return cases([name])[0]
