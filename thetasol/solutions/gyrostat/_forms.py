"""The gyrostat's trigonometric closed forms (steady rotation, spherical and axisymmetric
carriers) and the wrappers mapping an implementation to the body frame and the data's scale."""
from __future__ import annotations

import numpy as np

from thetasol.core.attitude import (
    angle_mod_2pi as _angle_mod_2pi,
    attitude_from_precession as _attitude,
    minimal_rotation as _minimal_rotation,
    norm3 as _norm,
    rotation_about_axis as _rot_about,
    uniform_rotation as _uniform_rotation,
    unit_rows as _unit,
)
from thetasol.protocol import quiet_far_times

__all__ = ["frame_with_e3", "Steady", "Sphere", "Axisymmetric", "Delegate", "Scaled", "BodyMap"]


def frame_with_e3(p):
    """A rotation P with P e_3 = p (columns: an orthonormal frame ending with p)."""
    p = p / np.linalg.norm(p)
    k = int(np.argmin(np.abs(p)))
    e = np.zeros(3)
    e[k] = 1.0
    x = np.cross(e, p)
    x /= np.linalg.norm(x)
    y = np.cross(p, x)
    return np.stack([x, y, p], axis=1)



class Steady:
    def __init__(self, Q0, w0):
        self.Q0, self.w0 = Q0, w0

    def evaluate(self, t):
        return _uniform_rotation(self.Q0, self.w0, t)

    def omega(self, t):
        return np.broadcast_to(self.w0, (t.size, 3)).copy()


class Sphere:
    """Spherical carrier: m rotates about N at rate |N|/I; Q = R(L, G t/I) Q0 R(N, -|N| t/I)."""

    def __init__(self, I, n, Q0, w0):
        self.I, self.n, self.Q0, self.w0 = I, n, Q0, w0
        m0 = I * w0
        h0 = m0 + n
        self.G = _norm(h0)
        self.L = Q0 @ h0 / self.G
        self.nn = _norm(n)
        self.nh = n / self.nn

    def evaluate(self, t):
        a1 = _angle_mod_2pi(self.nn / self.I, t, 0.0)
        E = _rot_about(self.nh, a1)
        w = np.einsum("nij,j->ni", E, self.w0)
        a2 = _angle_mod_2pi(self.G / self.I, t, 0.0)
        Q = _rot_about(self.L, a2) @ self.Q0 @ np.swapaxes(E, -1, -2)
        return w, Q

    def omega(self, t):
        return self.evaluate(t)[0]


class Axisymmetric:
    """Carrier symmetric about principal axis c with N along it (dual-spin): trigonometric.

    ``m_c`` is constant, ``(m_a, m_b)`` turn at ``Omega = (m_c + N_c)/I_1 - m_c/I_c``; with the
    pole on the symmetry axis ``psi' = (h.omega + G omega_c)/(G + h_c)`` is constant.
    """

    def __init__(self, Ip, n, m, c, Q0p, P):
        a_, b_ = [i for i in range(3) if i != c]
        self.c, self.ab = c, (a_, b_)
        self.Ip, self.n, self.m0, self.P = Ip, n, m, P
        h0 = m + n
        self.G = _norm(h0)
        s = 1.0 if h0[c] >= 0 else -1.0
        pole = np.zeros(3)
        pole[c] = s
        self.pole = pole
        self.Pw = frame_with_e3(pole)
        I1, Ic = Ip[a_], Ip[c]
        self.Om = (m[c] + n[c]) / I1 - m[c] / Ic
        w = m / Ip
        self.psidot = (h0 @ w + self.G * (w @ pole)) / (self.G + h0 @ pole)
        B0 = _minimal_rotation(_unit(self.Pw.T @ h0))
        self.S = Q0p @ self.Pw @ B0.T

    def _m(self, t):
        ang = _angle_mod_2pi(self.Om, t, 0.0)
        a_, b_ = self.ab
        # d/dt (m_a, m_b) = Omega (-m_b, m_a) when (a, b, c) is cyclic, the opposite otherwise
        sgn = 1.0 if (b_ - a_) % 3 == 1 else -1.0
        ca, sa = np.cos(ang), sgn * np.sin(ang)
        m = np.empty(t.shape + (3,))
        m[:, a_] = ca * self.m0[a_] - sa * self.m0[b_]
        m[:, b_] = sa * self.m0[a_] + ca * self.m0[b_]
        m[:, self.c] = self.m0[self.c]
        return m

    def evaluate(self, t):
        m = self._m(t)
        psi = _angle_mod_2pi(self.psidot, t, 0.0)
        Qp = _attitude(self.S, psi, (m + self.n) @ self.Pw, self.Pw)
        return (m / self.Ip) @ self.P.T, Qp @ self.P.T

    def omega(self, t):
        return (self._m(t) / self.Ip) @ self.P.T


class Delegate:
    """Another closed form's motion (the Euler top of a negligible rotor momentum), through its public
    calls: ``sol(t)`` and ``sol.omega(t)`` on the flat times (the gyrostat warns about far times for it)."""

    def __init__(self, sol):
        self.sol = quiet_far_times(sol)

    def evaluate(self, t):
        return self.sol(t)

    def omega(self, t):
        return self.sol.omega(t)



class Scaled:
    """The motion of the data scaled by 1/G, at time G t, with omega scaled back by G."""

    def __init__(self, impl, G):
        self.impl, self.G = impl, G

    def evaluate(self, t):
        w, Q = self.impl.evaluate(self.G * t)
        return self.G * w, Q

    def omega(self, t):
        return self.G * self.impl.omega(self.G * t)

    def separatrix_argument(self, t):
        """``tanh`` of the elliptic argument at the times ``t`` (on a separatrix)."""
        return self.impl.separatrix_argument(self.G * t)

    def omega_at_tanh(self, s):
        return self.G * self.impl.omega_at_tanh(s)

    @property
    def du_dt(self):
        """The rate of the elliptic argument in the data's time."""
        return self.impl.scale * self.G

    def __getattr__(self, name):  # expose the elliptic details (orbit, T, nu, ...) for inspection
        return getattr(self.impl, name)


class BodyMap:
    """Wraps a principal-frame implementation working with principal-frame Q0/omega."""

    def __init__(self, impl, R):
        self.impl, self.R = impl, R

    def evaluate(self, t):
        w, Q = self.impl.evaluate(t)
        return w @ self.R.T, Q @ self.R.T

    def omega(self, t):
        return self.impl.omega(t) @ self.R.T
