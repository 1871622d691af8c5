"""Rotors and configurations of coupled gyrostats (Section 8): CR^n- and CU^n-central trees.

A **gyrostat** is a carrier with rotors turning about axes fixed in it.  A :class:`Rotor` is a rigid
body given in its own frame, which is the carrier's frame at rotor angle ``phi = 0``: a rotor point
``r`` sits at ``P + R_l(phi) (r - P)`` in the carrier frame, ``P`` a point of the axis and ``R_l``
the rotation by ``phi`` about the unit axis ``l``.  So the rotor's attitude is
``Q_carrier R_l(phi)`` and its body angular velocity ``R_l(phi)^T omega_carrier + phidot l``.

A :class:`GyrostatConfiguration` is a tree of carriers (rigid :class:`~thetasol.mechanics.bodies.Body`
objects or a :class:`MasslessCarrier`, a frame without mass: the cross of a universal joint) with
their rotors, joined by ideal spherical :class:`~thetasol.mechanics.configuration.Joint` s.  A joint's
parent may be a carrier or a rotor (the paper's "rotors that play the role of carriers", Remark 6);
its ``parent_point`` is then in the rotor's frame.  Its child is a carrier.

The reduction of Theorem 5 (:meth:`GyrostatConfiguration.effective_gyrostats`, returned as
:class:`EffectiveGyrostat` records, children first as in the proof's induction):

* the **effective rotor** ``T_ka``: the rotor with the masses of the subtrees hanging from it put
  at their joint points (the paper's construction before Theorem 5).  Assumption (8.12): its mass
  centre lies on its axis and its second moments ``J~_ka`` are invariant under rotations about it,
  ``J~_ka = diag(B, B, C)`` in an axis frame.  A rotor that violates either is refused
  (``ValueError`` naming the rotor and the offending number), because the split does not hold for it;
* the **effective carrier** ``T_k0`` (8.17): the carrier with the masses of its child subtrees at
  their joint points and the effective rotors' masses at their mass centres; second moments ``J~_k``
  about the gyrostat's mass centre;
* ``J_k = J~_k + sum_a J_ka`` (8.23) (``J_ka`` the effective rotor's second moments about its own
  centre, in the carrier frame), the constants ``A_ka = -tr(J~_ka sigma^2)`` (the axial moment of
  inertia; (8.15) with ``J~``), ``B_ka = J~_ka[1, 1] = A_ka / 2`` (the coefficient of (8.15)),
  ``z_ka = -S_ka sigma S_ka^T = -hat(l_ka)`` (8.16), and, from an initial state, ``p_ka`` (8.25)
  ``= A_ka (omega_k . l_ka + phidot_ka)`` and ``N_k = -2 sum B/A p z = sum p_ka l_ka`` (8.33).

The carrier of the effective gyrostat then obeys (8.32) with the momentum ``m = I_gyro omega``,
``I_gyro = I(J_k) - sum_a A_ka l_ka l_ka^T`` (the paper's ``M_k`` of (8.33):
``2 B^2/A tr(z omega) z`` is ``-A (l . omega) hat(l)``), i.e. with the second moments
``J_gyro = J_k - sum_a (A_ka / 2)(1 - 2 l l^T)`` (rotor masses and transverse moments included,
axial moments not: what :func:`thetasol.solve_gyrostat` takes), and the potential acting on the full
``J_k``.  The rotor angles follow from (8.28) in its corrected form ``phidot = p / A - omega . l``.

A tree is **CR^n-central** when every joint sits, in the child, at the child's effective-gyrostat
mass centre (then the subtree's mass centre, whatever its joint and rotor angles);
:meth:`GyrostatConfiguration.check_central` refuses others.  CU^n: some carriers massless.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.inertia import inertia_from_moments, moments_from_inertia
from thetasol.core.so3 import complete_frame, hat
from thetasol.mechanics.bodies import Body
from thetasol.mechanics.configuration import CENTRAL_RTOL, Joint

__all__ = ["Rotor", "MasslessCarrier", "EffectiveRotor", "EffectiveGyrostat", "GyrostatConfiguration",
           "axis_rotation", "gyrostat_energy", "gyrostat_energy_from_moments", "ROTOR_RTOL"]

#: Relative tolerance of assumption (8.12): a rotor's mass centre off its axis by more than this times
#: its size, or its second moments asymmetric about the axis by more than this times their largest
#: value, is refused (a rotor composed in float64 is symmetric to a few ulps).
ROTOR_RTOL = 1e-12


def axis_rotation(axis: np.ndarray, phi: ArrayLike) -> np.ndarray:
    """Rotation by ``phi`` (any shape) about the unit ``axis``: ``phi.shape + (3, 3)``."""
    phi = np.asarray(phi, dtype=float)
    c, s = np.cos(phi)[..., None, None], np.sin(phi)[..., None, None]
    ll = np.outer(axis, axis)
    return c * np.eye(3) + s * hat(axis) + (1.0 - c) * ll


def _unit(v: ArrayLike, what: str) -> np.ndarray:
    v = V.vector3(v, what)
    n = float(np.linalg.norm(v))
    if not n > 0:
        raise ValueError(f"{what} must be a non-zero vector")
    return v / n


@dataclass(frozen=True, eq=False)
class Rotor:
    """A rotor on a carrier: a rigid body turning about an axis fixed in the carrier.

    Parameters
    ----------
    name : str
        Its name (distinct from every body and rotor of a configuration).
    carrier : str
        Name of the carrier.
    axis : array_like (3,)
        Direction of the axis in the carrier frame (normalized here).
    point : array_like (3,)
        A point of the axis, carrier frame.
    body : Body
        The rotor in its own frame, which is the carrier frame at ``phi = 0`` (mass, mass centre,
        second moments about it).  Its own mass centre may be off the axis only when the subtrees
        hanging from it bring the effective rotor's back (checked by the configuration).
    spin : float
        Initial relative rate ``phidot(0)`` (the angle starts at ``phi(0) = 0``).
    """

    name: str
    carrier: str
    axis: np.ndarray
    point: np.ndarray
    body: Body
    spin: float = 0.0

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise ValueError("a rotor needs a non-empty name")
        if not isinstance(self.body, Body):
            raise ValueError(f"rotor {self.name!r}: body must be a Body, got {type(self.body).__name__}")
        ax = _unit(self.axis, f"axis of rotor {self.name!r}")
        pt = V.vector3(self.point, f"point of rotor {self.name!r}").copy()
        ax.flags.writeable = False
        pt.flags.writeable = False
        spin = float(V.finite_array(self.spin, f"spin of rotor {self.name!r}", ()))
        object.__setattr__(self, "axis", ax)
        object.__setattr__(self, "point", pt)
        object.__setattr__(self, "spin", spin)

    @classmethod
    def symmetric(cls, name: str, carrier: str, axis: ArrayLike, point: ArrayLike, mass: float, A: float, B: float,
                  spin: float = 0.0) -> Rotor:
        """A rotor symmetric about its axis with its mass centre at ``point``: axial moment of inertia
        ``A``, transverse moment of inertia ``B`` about the mass centre (``A <= 2 B``, a physical body)."""
        ax = _unit(axis, f"axis of rotor {name!r}")
        A = float(V.finite_array(A, f"A of rotor {name!r}", ()))
        B = float(V.finite_array(B, f"B of rotor {name!r}", ()))
        if not (A > 0 and B > 0 and A <= 2 * B * (1 + 1e-15)):
            raise ValueError(f"rotor {name!r}: need 0 < A <= 2 B (a physical body), got A = {A}, B = {B}")
        ll = np.outer(ax, ax)
        J = 0.5 * A * (np.eye(3) - ll) + max(B - 0.5 * A, 0.0) * ll
        return cls(name, carrier, ax, point, Body(mass=mass, J=J, center=point, name=name), spin)

    def attitude(self, Q_carrier: np.ndarray, phi: ArrayLike) -> np.ndarray:
        """The rotor's attitude ``Q_carrier R_l(phi)`` (body to space)."""
        return np.asarray(Q_carrier) @ axis_rotation(self.axis, phi)

    def to_carrier(self, r: ArrayLike, phi: ArrayLike) -> np.ndarray:
        """A rotor-frame point in the carrier frame at angle ``phi``: ``P + R_l(phi)(r - P)``."""
        d = np.asarray(r, dtype=float) - self.point
        return self.point + np.einsum("...ij,j->...i", axis_rotation(self.axis, phi), d)


@dataclass(frozen=True)
class MasslessCarrier:
    """A carrier without mass (the cross of a universal joint, CU^n, Corollary 9): a frame only."""

    name: str

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise ValueError("a massless carrier needs a non-empty name")


@dataclass(frozen=True, eq=False)
class EffectiveRotor:
    """The effective rotor ``T_ka``: the rotor with the masses of its hanging subtrees, checked against (8.12).

    Attributes
    ----------
    name : str
    axis : ndarray (3,)
        ``l_ka``, carrier frame.
    mass : float
        ``m_ka``.
    center : ndarray (3,)
        Its mass centre ``P_ka`` (8.17), carrier frame (on the axis).
    J : ndarray (3, 3)
        ``J_ka = S J~_ka S^T``: second moments about ``center``, carrier frame (invariant under
        rotations about the axis).
    A : float
        ``A_ka = -tr(J~_ka sigma^2) = l . I(J_ka) l`` (8.15): the axial moment of inertia.
    B : float
        The paper's ``B_ka = A_ka / 2`` (8.15): the transverse SECOND moment ``J~_ka[1, 1]`` (not a
        moment of inertia).
    transverse_inertia : float
        Moment of inertia about a transverse axis through ``center``, ``B + C``.
    z : ndarray (3, 3)
        ``z_ka = -S sigma S^T = -hat(l)`` (8.16); ``tr(z hat(omega)) = 2 l . omega``.
    """

    name: str
    axis: np.ndarray
    mass: float
    center: np.ndarray
    J: np.ndarray
    A: float
    B: float
    transverse_inertia: float
    z: np.ndarray


@dataclass(frozen=True, eq=False)
class EffectiveGyrostat:
    """The effective gyrostat ``T_k`` of one carrier (Theorem 5), in the carrier's frame.

    Attributes
    ----------
    name : str
        The carrier.
    mass : float
        ``m_k``: carrier, rotors and every subtree below.
    center : ndarray (3,)
        Its mass centre, carrier frame (the subtree's mass centre when the tree is central).
    J_carrier : ndarray (3, 3)
        ``J~_k``: second moments of the effective carrier (8.17) about ``center`` (rotor masses at their
        centres, subtree masses at their joints).
    J : ndarray (3, 3)
        ``J_k = J~_k + sum_a J_ka`` (8.23): what the potential acts on ((8.22), (8.32)).
    J_gyro : ndarray (3, 3)
        ``J_k - sum_a (A_ka / 2)(1 - 2 l l^T)``: the second moments whose inertia ``I(J_gyro) =
        I(J_k) - sum A l l^T`` multiplies ``omega`` in the momentum ``M_k`` (8.33) (rotor axial
        moments excluded); :attr:`I_gyro` is the ``I`` of :func:`thetasol.solve_gyrostat`.
    rotors : tuple of EffectiveRotor
    """

    name: str
    mass: float
    center: np.ndarray
    J_carrier: np.ndarray
    J: np.ndarray
    J_gyro: np.ndarray
    rotors: tuple = ()

    @property
    def I_gyro(self) -> np.ndarray:
        """``I(J_gyro)``: the inertia in ``M_k = I_gyro omega`` (8.33), what :func:`thetasol.solve_gyrostat` takes."""
        return inertia_from_moments(self.J_gyro)

    def momenta(self, omega: ArrayLike, spins: ArrayLike) -> np.ndarray:
        """``p_ka = A_ka (omega . l_ka + phidot_ka)`` (8.25) for the carrier rate ``omega`` and rotor rates."""
        w = V.vector3(omega, "omega")
        s = V.finite_array(spins, "spins", (len(self.rotors),))
        return np.array([r.A * (w @ r.axis + s[i]) for i, r in enumerate(self.rotors)])

    def N(self, p: ArrayLike) -> np.ndarray:
        """``N_k = -2 sum_a (B_ka / A_ka) p_ka z_ka`` (8.33) as a vector: ``sum_a p_ka l_ka``."""
        p = V.finite_array(p, "p", (len(self.rotors),))
        Nm = sum((-2.0 * r.B / r.A * p[i] * r.z for i, r in enumerate(self.rotors)), np.zeros((3, 3)))
        return np.array([Nm[2, 1], Nm[0, 2], Nm[1, 0]])

    def rotor_specs(self, p: ArrayLike) -> list[dict]:
        """The ``rotors=`` argument of :func:`thetasol.solve_gyrostat` for the momenta ``p``."""
        return [{"axis": r.axis, "A": r.A, "B": r.transverse_inertia, "p": float(pk)}
                for r, pk in zip(self.rotors, p, strict=True)]


def _point_body(masses, points, base: Body | None):
    """Mass, centre and second moments about it of ``base`` plus point masses."""
    mk = np.asarray(masses, dtype=float).reshape(-1)
    pk = np.asarray(points, dtype=float).reshape(-1, 3)
    m0 = 0.0 if base is None else base.mass
    c0 = np.zeros(3) if base is None else base.center
    m = m0 + mk.sum()
    c = (m0 * c0 + mk @ pk) / m
    J = np.einsum("k,ki,kj->ij", mk, pk - c, pk - c)
    if base is not None:
        J = J + base.J + m0 * np.outer(c0 - c, c0 - c)
    return float(m), c, 0.5 * (J + J.T)


def _check_rotor(r: Rotor, m: float, c: np.ndarray, J: np.ndarray) -> EffectiveRotor:
    """The effective rotor, refused unless (8.12) holds: centre on the axis, J symmetric about it."""
    l = r.axis
    d = c - r.point
    off = d - (d @ l) * l
    size = max(np.sqrt(np.trace(J) / m), float(np.linalg.norm(d)), float(np.linalg.norm(r.point)))
    if np.linalg.norm(off) > ROTOR_RTOL * size:
        raise ValueError(f"rotor {r.name!r}: its (effective) mass centre {c.tolist()} is off its axis by "
                         f"{np.linalg.norm(off):.3g}; Theorem 5 assumes it on the axis (the paper's (8.12) setting): "
                         "the rotor would shift the gyrostat's mass centre as it turns")
    S = complete_frame(l)
    Js = S.T @ J @ S
    scale = max(float(np.max(np.abs(np.linalg.eigvalsh(J)))), np.finfo(float).tiny)
    asym = max(abs(Js[0, 2]), abs(Js[1, 2]), abs(Js[0, 1]), 0.5 * abs(Js[0, 0] - Js[1, 1]))
    if asym > ROTOR_RTOL * scale:
        raise ValueError(f"rotor {r.name!r}: its (effective) second moments are not symmetric about its axis "
                         f"(relative asymmetry {asym / scale:.3g}); (8.12) requires R J R^T = J for rotations R "
                         "about the axis, else the gyrostat's inertia would change as the rotor turns")
    B2 = 0.5 * (Js[0, 0] + Js[1, 1])
    Jsym = S @ np.diag([B2, B2, Js[2, 2]]) @ S.T
    return EffectiveRotor(name=r.name, axis=l, mass=m, center=c, J=0.5 * (Jsym + Jsym.T), A=2.0 * B2, B=B2,
                          transverse_inertia=B2 + float(Js[2, 2]), z=-hat(l))


class GyrostatConfiguration:
    """A tree of carriers with rotors on ideal spherical joints (CR^n; CU^n with massless carriers).

    Parameters
    ----------
    carriers : sequence of Body or MasslessCarrier
        Distinctly named carriers.
    rotors : sequence of Rotor
        Each on a carrier of the list.
    joints : sequence of Joint
        ``parent`` a carrier or a rotor (``parent_point`` in its frame), ``child`` a carrier.

    Raises
    ------
    ValueError
        Duplicate or unknown names, a rotor as a joint's child, a tree that is not one connected
        tree, a massless carrier with fewer than one rotor, or an effective rotor violating (8.12).
    """

    def __init__(self, carriers: Sequence[Body | MasslessCarrier], rotors: Sequence[Rotor] = (),
                 joints: Sequence[Joint] = ()):
        self.carriers: dict[str, Body | MasslessCarrier] = {}
        self.rotors: dict[str, Rotor] = {}
        for c in carriers:
            if not isinstance(c, (Body, MasslessCarrier)) or not c.name:
                raise ValueError("carriers must be named Body or MasslessCarrier objects")
            if c.name in self.carriers:
                raise ValueError(f"duplicate name {c.name!r}")
            self.carriers[c.name] = c
        if not self.carriers:
            raise ValueError("a configuration needs at least one carrier")
        for r in rotors:
            if not isinstance(r, Rotor):
                raise ValueError(f"rotors must be Rotor objects, got {type(r).__name__}")
            if r.name in self.carriers or r.name in self.rotors:
                raise ValueError(f"duplicate name {r.name!r}")
            if r.carrier not in self.carriers:
                raise ValueError(f"rotor {r.name!r}: unknown carrier {r.carrier!r}")
            self.rotors[r.name] = r
        self.rotors_of: dict[str, list[str]] = {n: [r.name for r in self.rotors.values() if r.carrier == n]
                                               for n in self.carriers}
        for n, c in self.carriers.items():
            if isinstance(c, MasslessCarrier) and not self.rotors_of[n]:
                raise ValueError(f"massless carrier {n!r} carries no rotor")
        self._tree(list(joints))
        self._effective = self._compute_effective()

    def _tree(self, joints: list[Joint]) -> None:
        self.joints: dict[str, Joint] = {}
        for j in joints:
            if not isinstance(j, Joint):
                raise ValueError(f"joints must be Joint objects, got {type(j).__name__}")
            if j.child not in self.carriers:
                raise ValueError(f"joint {j.parent!r} -> {j.child!r}: the child must be a carrier "
                                 "(a rotor is attached by its axis)")
            if j.parent not in self.carriers and j.parent not in self.rotors:
                raise ValueError(f"joint {j.parent!r} -> {j.child!r}: unknown parent {j.parent!r}")
            if j.child in self.joints:
                raise ValueError(f"carrier {j.child!r} has two parents")
            self.joints[j.child] = j
        self.children: dict[str, list[str]] = {n: [] for n in [*self.carriers, *self.rotors]}
        for j in joints:
            self.children[j.parent].append(j.child)
        roots = [n for n in self.carriers if n not in self.joints]
        if len(roots) != 1:
            raise ValueError(f"the carriers must form one tree, found roots {roots}")
        self.root = roots[0]
        order = [self.root]
        for n in order:
            kids = list(self.children[n])
            for r in self.rotors_of[n]:
                kids.extend(self.children[r])
            order.extend(kids)
        if len(order) != len(self.carriers):
            raise ValueError("the joints contain a cycle or leave carriers unconnected")
        self.order: list[str] = order

    def carrier_of(self, name: str) -> str:
        """The carrier a joint parent belongs to (itself for a carrier, the rotor's carrier for a rotor)."""
        return self.rotors[name].carrier if name in self.rotors else name

    def _compute_effective(self) -> dict[str, EffectiveGyrostat]:
        eff: dict[str, EffectiveGyrostat] = {}
        for n in reversed(self.order):
            rot = []
            for rn in self.rotors_of[n]:
                r = self.rotors[rn]
                kids = self.children[rn]
                m, c, J = _point_body([eff[k].mass for k in kids],
                                      [self.joints[k].parent_point for k in kids], r.body)
                # the hanging joint points are in the rotor frame = the carrier frame at phi = 0
                rot.append(_check_rotor(r, m, c, J))
            kids = self.children[n]
            masses = [eff[k].mass for k in kids] + [r.mass for r in rot]
            points = [self.joints[k].parent_point for k in kids] + [r.center for r in rot]
            c = self.carriers[n]
            base = c if isinstance(c, Body) else None
            m, centre, Jc = _point_body(masses, points, base)
            Jk = Jc + sum((r.J for r in rot), np.zeros((3, 3)))
            Jg = Jk - sum((0.5 * r.A * (np.eye(3) - 2 * np.outer(r.axis, r.axis)) for r in rot), np.zeros((3, 3)))
            eff[n] = EffectiveGyrostat(name=n, mass=m, center=centre, J_carrier=Jc, J=0.5 * (Jk + Jk.T),
                                       J_gyro=0.5 * (Jg + Jg.T), rotors=tuple(rot))
        return eff

    @property
    def body_names(self) -> list[str]:
        """The bodies with mass, root first: each carrier with mass, then its rotors (the order of the
        split's and the unsplit reference's trajectories)."""
        out = []
        for n in self.order:
            if isinstance(self.carriers[n], Body):
                out.append(n)
            out.extend(self.rotors_of[n])
        return out

    @property
    def mass(self) -> float:
        """Total mass."""
        return self._effective[self.root].mass

    def effective_gyrostats(self) -> dict[str, EffectiveGyrostat]:
        """The effective gyrostats (8.17), (8.23) of every carrier, root first."""
        return {n: self._effective[n] for n in self.order}

    def effective_gyrostat(self, name: str) -> EffectiveGyrostat:
        """The effective gyrostat of one carrier."""
        if name not in self._effective:
            raise ValueError(f"unknown carrier {name!r}")
        return self._effective[name]

    def violations(self) -> dict[str, float]:
        """Relative offset of every joint from its child's effective mass centre, keyed by child."""
        out = {}
        for n in self.order[1:]:
            e, j = self._effective[n], self.joints[n]
            d = float(np.linalg.norm(j.child_point - e.center))
            size = max(float(np.sqrt(np.trace(e.J) / e.mass)), float(np.linalg.norm(e.center)), 1e-300)
            out[n] = d / size
        return out

    def check_central(self, rtol: float = CENTRAL_RTOL) -> None:
        """Raise ValueError unless every joint is at its child's effective mass centre (CR^n-central)."""
        bad = {n: v for n, v in self.violations().items() if v > rtol}
        if bad:
            raise ValueError("the configuration is not CR^n-central: joints off the child's effective-gyrostat "
                             f"mass centre (relative offsets) {bad}")

    def initial_momenta(self, omega0: Mapping[str, ArrayLike]) -> dict[str, np.ndarray]:
        """``p_ka`` (8.25) of every carrier's rotors from the carriers' rates and the rotors' ``spin``."""
        out = {}
        for n in self.order:
            w = V.vector3(omega0.get(n, np.zeros(3)), f"omega0[{n!r}]")
            out[n] = self._effective[n].momenta(w, [self.rotors[r].spin for r in self.rotors_of[n]])
        return out

    def place(self, q: ArrayLike, qdot: ArrayLike, Q: Mapping[str, np.ndarray], omega: Mapping[str, np.ndarray],
              phi: Mapping[str, np.ndarray], phidot: Mapping[str, np.ndarray]) -> dict[str, dict[str, np.ndarray]]:
        """Every massive body (carriers and rotors) from the split variables (Theorem 5).

        ``q, qdot`` (shape ``T + (3,)``) the system mass centre; per carrier ``Q`` and ``omega``; per
        rotor ``phi`` and ``phidot`` (shape ``T``).  Returns name -> ``position`` (own mass centre),
        ``velocity``, ``attitude``, ``omega`` (body frame), for carriers with mass and all rotors.
        """
        X, Xd = {self.root: np.asarray(q, float)}, {self.root: np.asarray(qdot, float)}
        out = {}
        for n in self.order:
            e, Qn, Wn = self._effective[n], np.asarray(Q[n], float), np.asarray(omega[n], float)
            QW = Qn @ hat(Wn)

            def at(r_c, v_c=None, n=n, e=e, Qn=Qn, QW=QW):   # position, velocity of a carrier-frame point
                d = r_c - e.center
                x = X[n] + np.einsum("...ij,...j->...i", Qn, d)
                v = Xd[n] + np.einsum("...ij,...j->...i", QW, d)
                return x, v if v_c is None else v + np.einsum("...ij,...j->...i", Qn, v_c)

            c = self.carriers[n]
            if isinstance(c, Body):
                x, v = at(c.center)
                out[n] = {"position": x, "velocity": v, "attitude": Qn, "omega": Wn}
            for k in self.children[n]:
                X[k], Xd[k] = at(self.joints[k].parent_point)
            for rn in self.rotors_of[n]:
                self._place_rotor(self.rotors[rn], at, Qn, Wn, np.asarray(phi[rn], float),
                                  np.asarray(phidot[rn], float), X, Xd, out)
        return out

    def _place_rotor(self, r: Rotor, at, Qn, Wn, ph, phd, X, Xd, out) -> None:
        Rl = axis_rotation(r.axis, ph)

        def point(p):
            d = np.einsum("...ij,j->...i", Rl, p - r.point)
            return at(r.point + d, phd[..., None] * np.cross(r.axis, d))

        x, v = point(r.body.center)
        w = np.einsum("...ji,...j->...i", Rl, Wn) + phd[..., None] * r.axis
        out[r.name] = {"position": x, "velocity": v, "attitude": Qn @ Rl, "omega": w}
        for k in self.children[r.name]:
            X[k], Xd[k] = point(self.joints[k].parent_point)

    def __repr__(self) -> str:
        return (f"GyrostatConfiguration({len(self.carriers)} carriers, {len(self.rotors)} rotors, "
                f"root {self.root!r})")


def gyrostat_energy(I: ArrayLike, I_gyro: ArrayLike, a: np.ndarray, Q: np.ndarray,  # noqa: E741
                    omega: np.ndarray) -> np.ndarray:
    """The first integral (8.34) as a physical energy of a gyrostat, ``1/2 omega . I_gyro omega + V``.

    ``I`` is the inertia tensor of the whole body (carrier and rotors, the one the potential acts on) and
    ``I_gyro`` the gyrostat's inertia in ``M_k = I_gyro omega`` (8.33), :attr:`EffectiveGyrostat.I_gyro`, each three
    principal values or a symmetric 3x3 in the body frame.  Both are converted once to the paper's second
    moments (:func:`thetasol.second_moments`) for :func:`gyrostat_energy_from_moments`, where the
    potential ``V = 1/2 tr(Q^T a Q J)`` is written.
    """
    return gyrostat_energy_from_moments(moments_from_inertia(V.inertia(I, "I")),
                                        moments_from_inertia(V.principal_or_tensor(I_gyro, "I_gyro")), a, Q, omega)


def gyrostat_energy_from_moments(J: np.ndarray, J_gyro: np.ndarray, a: np.ndarray, Q: np.ndarray,
                                 omega: np.ndarray) -> np.ndarray:
    """The first integral (8.34) as a physical energy: ``1/2 omega . I(J_gyro) omega + 1/2 tr(Q^T a Q J)``.

    ``J`` and ``J_gyro`` are the paper's second moments (3x3) of the whole body and of the gyrostat.

    (8.34) ``H = 1/2 tr(M omega) + tr(u J)`` is ``-2`` times this with ``u = -Q^T a Q``
    (docs/conventions.md); independent of ``N`` and the ``p_ka``.  Broadcasts over leading axes.
    """
    Ig = inertia_from_moments(np.asarray(J_gyro, float))
    kin = 0.5 * np.einsum("...i,ij,...j->...", omega, Ig, omega)
    pot = 0.5 * np.einsum("...ji,jk,...kl,li->...", Q, a, Q, J)
    return kin + pot

