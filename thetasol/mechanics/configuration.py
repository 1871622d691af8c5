"""Trees of rigid bodies on ideal spherical joints, C^k-centrality and effective bodies.

A :class:`Configuration` is a tree of :class:`~thetasol.mechanics.bodies.Body` objects joined by
:class:`Joint` s; every joint is given by its point in the parent's frame and in the
child's frame.  Definitions from Sections 2 and 3 of the paper:

* **effective rigid body** (2.15), (3.7) of a body B: B with the mass of each child subtree
  ``C_j`` put at the joint point ``p_j`` (B's frame).  Its mass is the subtree mass, its mass
  centre ``c = (m_B c_B + sum m(C_j) p_j) / m_eff`` and its second moments about ``c``
  ``J_eff = J_B + m_B (c_B - c)(c_B - c)^T + sum m(C_j) (p_j - c)(p_j - c)^T``;
* **C^k-central**: every subtree is attached at its own mass centre, i.e. the joint point
  of ``C_j`` in ``C_j``'s frame is the mass centre of ``C_j``'s effective body (which is
  the subtree's mass centre for any joint angles below ``C_j`` exactly when the
  subtree is itself central).  ``k`` is the depth of the tree.

Any tree becomes central by moving each joint point in the child to the child's effective
mass centre (:meth:`Configuration.make_central`); the effective centres do not depend on
those points, so one pass suffices.

For a central tree, Theorem 2 (3.1) splits the motion into the system mass centre ``q(t)``
in ``phi`` and independent rotations ``Q_B(t)`` of the effective bodies about their mass
centres; :meth:`Configuration.place` rebuilds every body's position and velocity from
``q``, ``qdot``, ``Q_B`` and ``omega_B`` down the tree.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from thetasol.core import validate as V
from thetasol.core.inertia import inertia, inertia_from_moments
from thetasol.core.so3 import hat
from thetasol.mechanics.bodies import Body, principal_axes

__all__ = ["CENTRAL_RTOL", "Joint", "EffectiveBody", "JointViolation", "Configuration", "initial_attitudes"]

#: Default relative tolerance of :meth:`Configuration.is_central` (joint offset / body size).
CENTRAL_RTOL = 1e-12


@dataclass(frozen=True, eq=False)
class Joint:
    """An ideal spherical joint: ``parent_point`` (parent's frame) coincides with ``child_point`` (child's frame)."""

    parent: str
    child: str
    parent_point: np.ndarray
    child_point: np.ndarray

    def __post_init__(self):
        label = f"joint {self.parent!r} -> {self.child!r}"
        for attr in ("parent_point", "child_point"):
            v = V.vector3(getattr(self, attr), f"{attr} of {label}").copy()
            v.flags.writeable = False
            object.__setattr__(self, attr, v)
        if self.parent == self.child:
            raise ValueError(f"{label} joins a body to itself")


@dataclass(frozen=True, eq=False)
class EffectiveBody:
    """Effective rigid body (2.15), (3.7) of one body of a configuration, in that body's frame.

    Attributes
    ----------
    name : str
        The physical body it belongs to.
    mass : float
        Mass of the body plus the masses of all its child subtrees.
    center : ndarray (3,)
        Its mass centre (the subtree's mass centre when the tree is central).
    J, I : ndarray (3, 3)
        Second moments and inertia about ``center``.
    principal_moments : ndarray (3,)
        Eigenvalues of ``J`` (ascending).
    axes : ndarray (3, 3)
        Right-handed principal axes (columns), ``J = axes diag(principal_moments) axes^T``.
    """

    name: str
    mass: float
    center: np.ndarray
    J: np.ndarray
    I: np.ndarray = field(init=False)
    principal_moments: np.ndarray = field(init=False)
    axes: np.ndarray = field(init=False)

    def __post_init__(self):
        object.__setattr__(self, "I", inertia_from_moments(self.J))
        vals, axes = principal_axes(self.J)
        object.__setattr__(self, "principal_moments", vals)
        object.__setattr__(self, "axes", axes)

    @property
    def principal_inertia(self) -> np.ndarray:
        """Principal moments of inertia ``I_i = tr(J) - J_i`` in the order of ``axes``."""
        return inertia(self.principal_moments)


@dataclass(frozen=True)
class JointViolation:
    """How far one joint is from central: ``offset = child_point - c_eff(child)`` (child's frame)."""

    parent: str
    child: str
    offset: np.ndarray
    distance: float
    relative: float  # distance / max(subtree radius sqrt(tr J_eff / m_eff), |c_eff|, |child_point|)


class Configuration:
    """A tree of rigid bodies on ideal spherical joints.

    Parameters
    ----------
    bodies : sequence of Body
        Distinctly named bodies.
    joints : sequence of Joint
        One joint per non-root body; ``parent`` and ``child`` are body names.

    Raises
    ------
    ValueError
        Duplicate or empty names, an unknown parent or child, a body with two parents, a
        cycle, a forest (several roots) or no bodies.

    Notes
    -----
    ``order`` lists the bodies root first, every parent before its children.
    """

    def __init__(self, bodies: Sequence[Body], joints: Sequence[Joint] = ()):
        bodies = list(bodies)
        joints = list(joints)
        if not bodies:
            raise ValueError("a configuration needs at least one body")
        self.bodies: dict[str, Body] = {}
        for b in bodies:
            if not isinstance(b, Body):
                raise ValueError(f"bodies must be Body objects, got {type(b).__name__}")
            if not b.name:
                raise ValueError("every body of a configuration needs a non-empty name")
            if b.name in self.bodies:
                raise ValueError(f"duplicate body name {b.name!r}")
            self.bodies[b.name] = b
        self.joints: dict[str, Joint] = {}  # keyed by child
        for j in joints:
            if not isinstance(j, Joint):
                raise ValueError(f"joints must be Joint objects, got {type(j).__name__}")
            for role in ("parent", "child"):
                if getattr(j, role) not in self.bodies:
                    raise ValueError(f"joint {j.parent!r} -> {j.child!r}: unknown {role} {getattr(j, role)!r}")
            if j.child in self.joints:
                raise ValueError(f"body {j.child!r} has two parents ({self.joints[j.child].parent!r} and "
                                 f"{j.parent!r}): joints must form a tree")
            self.joints[j.child] = j
        self.children: dict[str, list[str]] = {n: [] for n in self.bodies}
        for j in joints:
            self.children[j.parent].append(j.child)
        roots = [n for n in self.bodies if n not in self.joints]
        if not roots:
            raise ValueError(f"the joints contain a cycle ({_find_cycle(self.joints)}): no root body")
        if len(roots) > 1:
            cycle = _find_cycle(self.joints)
            if cycle:
                raise ValueError(f"the joints contain a cycle ({cycle})")
            raise ValueError(f"the bodies are not connected: several roots {roots}")
        self.root = roots[0]
        order = [self.root]
        for n in order:
            order.extend(self.children[n])
        if len(order) != len(self.bodies):
            raise ValueError(f"the joints contain a cycle ({_find_cycle(self.joints)})")
        self.order: list[str] = order
        self._effective = self._compute_effective()

    # -- structure -------------------------------------------------------------------------------

    def parent(self, name: str) -> str | None:
        """Name of the parent of ``name`` (None for the root)."""
        self._check_name(name)
        j = self.joints.get(name)
        return None if j is None else j.parent

    def _check_name(self, name):
        if name not in self.bodies:
            raise ValueError(f"unknown body {name!r}")

    @property
    def depth(self) -> int:
        """Length ``k`` of the longest chain below the root (the ``k`` of C^k; 0 for one body)."""
        depth = {self.root: 0}
        for n in self.order[1:]:
            depth[n] = depth[self.joints[n].parent] + 1
        return max(depth.values())

    @property
    def mass(self) -> float:
        """Total mass."""
        return sum(b.mass for b in self.bodies.values())

    def __len__(self) -> int:
        return len(self.bodies)

    def __repr__(self) -> str:
        return f"Configuration({len(self)} bodies, root {self.root!r}, depth {self.depth})"

    # -- effective bodies --------------------------------------------------------------------------

    def _compute_effective(self) -> dict[str, EffectiveBody]:
        eff: dict[str, EffectiveBody] = {}
        for n in reversed(self.order):  # children before parents
            b = self.bodies[n]
            kids = self.children[n]
            mk = np.array([eff[k].mass for k in kids])
            pk = np.array([self.joints[k].parent_point for k in kids]).reshape(-1, 3)
            m = b.mass + mk.sum()
            c = (b.mass * b.center + mk @ pk) / m
            d = b.center - c
            dk = pk - c
            J = b.J + b.mass * np.outer(d, d) + np.einsum("k,ki,kj->ij", mk, dk, dk)
            J = 0.5 * (J + J.T)
            eff[n] = EffectiveBody(name=n, mass=float(m), center=c, J=J)
        return eff

    def effective_bodies(self) -> dict[str, EffectiveBody]:
        """Effective rigid bodies (2.15), (3.7) of every body, keyed by name, root first."""
        return {n: self._effective[n] for n in self.order}

    def effective_body(self, name: str) -> EffectiveBody:
        """Effective rigid body of one body."""
        self._check_name(name)
        return self._effective[name]

    # -- centrality ----------------------------------------------------------------------------------

    def violations(self) -> list[JointViolation]:
        """Offset of every joint from its central position, in tree order (root's children first)."""
        out = []
        for n in self.order[1:]:
            j = self.joints[n]
            e = self._effective[n]
            off = j.child_point - e.center
            dist = float(np.linalg.norm(off))
            size = float(np.sqrt(np.trace(e.J) / e.mass))
            scale = max(size, float(np.linalg.norm(e.center)), float(np.linalg.norm(j.child_point)))
            out.append(JointViolation(j.parent, n, off, dist, dist / scale if scale > 0 else dist))
        return out

    def is_central(self, rtol: float = CENTRAL_RTOL) -> bool:
        """True when every joint is at its child's effective mass centre within ``rtol`` (relative to size)."""
        return all(v.relative <= rtol for v in self.violations())

    def check_central(self, rtol: float = CENTRAL_RTOL) -> None:
        """Raise ValueError listing the joints that are not central (relative offset above ``rtol``)."""
        bad = [v for v in self.violations() if v.relative > rtol]
        if bad:
            lines = "; ".join(
                f"{v.parent!r} -> {v.child!r}: child_point is {v.distance:.3g} (relative {v.relative:.2g}) "
                f"from the subtree mass centre {self._effective[v.child].center.tolist()}"
                for v in bad)
            raise ValueError(f"the configuration is not C^k-central: {lines}. "
                             "Configuration.make_central() gives the shifted joints.")

    def central_shifts(self) -> dict[str, np.ndarray]:
        """Shift of every child joint point (child's frame) that makes the tree central, keyed by child."""
        return {v.child: -v.offset for v in self.violations()}

    def make_central(self) -> Configuration:
        """The same bodies with every joint moved, in the child, to the child's effective mass centre.

        Parent points are kept; effective bodies do not depend on child points, so the result
        is central (the paper, Section 1: any tree becomes central after shifting joints).
        """
        joints = [Joint(j.parent, j.child, j.parent_point, self._effective[j.child].center)
                  for j in (self.joints[n] for n in self.order[1:])]
        return Configuration([self.bodies[n] for n in self.order], joints)

    # -- kinematics of the split -----------------------------------------------------------------

    def place(self, q: ArrayLike, qdot: ArrayLike, Q: Mapping[str, np.ndarray], omega: Mapping[str, np.ndarray] | None = None,
              check_central: bool = True) -> dict[str, dict[str, np.ndarray]]:
        """Positions and velocities of every body from the split variables (Theorem 2, (3.1)).

        Parameters
        ----------
        q, qdot : array_like, shape ``T + (3,)``
            System mass centre and its velocity (= mass centre of the root's effective body).
        Q : mapping name -> array ``T + (3, 3)``
            Attitude of every body (body to space).  The effective body shares the frame of
            its physical body.
        omega : mapping name -> array ``T + (3,)``, optional
            Body-frame angular velocities (needed for velocities).
        check_central : bool
            Refuse a non-central tree (the split does not hold there).  With False the same
            kinematics is evaluated anyway (used to show that a non-central tree does NOT split).

        Returns
        -------
        dict name -> {"position": T+(3,), "velocity": T+(3,), "origin": T+(3,), "effective_center": T+(3,)}
            ``position`` is the body's own mass centre, ``origin`` the origin of its frame.
        """
        if check_central:
            self.check_central()
        q = np.asarray(q, dtype=float)
        qdot = np.asarray(qdot, dtype=float)
        out: dict[str, dict[str, np.ndarray]] = {}
        X = {self.root: q}
        Xd = {self.root: qdot}
        for n in self.order:
            b, e, Qn = self.bodies[n], self._effective[n], np.asarray(Q[n], dtype=float)
            res = {"effective_center": X[n]}
            res["origin"] = X[n] - Qn @ e.center
            res["position"] = X[n] + Qn @ (b.center - e.center)
            if omega is not None:
                Wn = np.asarray(omega[n], dtype=float)
                QW = Qn @ hat(Wn)
                res["velocity"] = Xd[n] + QW @ (b.center - e.center)
            for k in self.children[n]:
                r = self.joints[k].parent_point - e.center
                X[k] = X[n] + Qn @ r
                if omega is not None:
                    Xd[k] = Xd[n] + QW @ r
            out[n] = res
        return out


def _find_cycle(parent_of: Mapping[str, Joint]) -> str:
    """A textual cycle 'a -> b -> ... -> a' among child->parent links, or '' if none."""
    for start in parent_of:
        seen = []
        n = start
        while n in parent_of and n not in seen:
            seen.append(n)
            n = parent_of[n].parent
        if n in seen:
            cyc = seen[seen.index(n):]
            return " -> ".join(reversed(cyc + [n]))
    return ""


def initial_attitudes(config: Configuration, Q0: Mapping[str, ArrayLike],
                      omega0: Mapping[str, ArrayLike]) -> tuple[np.ndarray, np.ndarray]:
    """Per-body initial attitudes and angular velocities in ``config.order`` (identity and zero
    where a body is missing), validated: arrays of shapes ``(N, 3, 3)`` and ``(N, 3)``."""
    names = config.order
    for d, what in ((Q0, "Q0"), (omega0, "omega0")):
        if not hasattr(d, "keys"):
            raise ValueError(f"{what} must map body names to values, got {type(d).__name__}")
        unknown = set(d) - set(names)
        if unknown:
            raise ValueError(f"{what} names unknown bodies {sorted(unknown)}")
    Q = np.array([V.rotation_matrix(Q0.get(n, np.eye(3)), f"Q0[{n!r}]") for n in names])
    w = np.array([V.vector3(omega0.get(n, np.zeros(3)), f"omega0[{n!r}]") for n in names])
    return Q, w
