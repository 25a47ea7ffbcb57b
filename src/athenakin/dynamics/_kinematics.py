"""Exact velocities and accelerations of every body, by second-order Taylor jets (private).

Every body's pose is a closed form of the actuators ``q`` and of the RCM frame
``T_b_e`` in one forward-kinematics slot (docs/conventions.md): the parallel module
(Eq. 7-10), then the instrument direction ``d = (RCM - O_s) / p``, the U-joint angles
``u1, u2`` from ``R_b_s^T d``, and the spherical joint ``u3, u4`` from
``R_3^T R_b_e``. Propagating truncated Taylor series ``x(t) = c0 + c1 t + c2 t^2``
through these formulas (no ``atan2``: sines and cosines come from the unit vectors)
gives the velocity ``c1`` and the acceleration ``2 c2`` of every point and rotation
matrix to rounding error.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .._typing import FloatArray
from ..design import Design

__all__ = ["J2", "BodyJets", "body_jets", "slot_signs"]


class J2:
    """A second-order jet: ``f(t) = c0 + c1 t + c2 t^2`` (coefficients are arrays)."""

    __slots__ = ("c0", "c1", "c2")

    def __init__(self, c0: FloatArray, c1: FloatArray, c2: FloatArray) -> None:
        self.c0, self.c1, self.c2 = c0, c1, c2

    def __add__(self, o: J2 | float) -> J2:
        if isinstance(o, J2):
            return J2(self.c0 + o.c0, self.c1 + o.c1, self.c2 + o.c2)
        return J2(self.c0 + o, self.c1, self.c2)

    __radd__ = __add__

    def __neg__(self) -> J2:
        return J2(-self.c0, -self.c1, -self.c2)

    def __sub__(self, o: J2 | float) -> J2:
        if isinstance(o, J2):
            return J2(self.c0 - o.c0, self.c1 - o.c1, self.c2 - o.c2)
        return J2(self.c0 - o, self.c1, self.c2)

    def __rsub__(self, o: float) -> J2:
        return J2(o - self.c0, -self.c1, -self.c2)

    def __mul__(self, o: J2 | float) -> J2:
        if isinstance(o, J2):
            return J2(self.c0 * o.c0, self.c0 * o.c1 + self.c1 * o.c0,
                      self.c0 * o.c2 + self.c1 * o.c1 + self.c2 * o.c0)
        return J2(self.c0 * o, self.c1 * o, self.c2 * o)

    __rmul__ = __mul__

    def __truediv__(self, o: J2 | float) -> J2:
        if not isinstance(o, J2):
            return J2(self.c0 / o, self.c1 / o, self.c2 / o)
        q0 = self.c0 / o.c0
        q1 = (self.c1 - o.c1 * q0) / o.c0
        q2 = (self.c2 - o.c1 * q1 - o.c2 * q0) / o.c0
        return J2(q0, q1, q2)

    def sq(self) -> J2:
        """``self * self``."""
        return J2(self.c0 * self.c0, 2 * self.c0 * self.c1,
                  2 * self.c0 * self.c2 + self.c1 * self.c1)

    def sqrt(self) -> J2:
        """Square root (NaN where ``c0 < 0``)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            s0 = np.sqrt(self.c0)
            s1 = self.c1 / (2 * s0)
            s2 = (self.c2 - s1 * s1) / (2 * s0)
        return J2(s0, s1, s2)


Entry = J2 | float
Vec = list[Entry]
Mat = list[list[Entry]]


def _mul(a: Entry, b: Entry) -> Entry:
    if isinstance(a, float) and a == 0.0 or isinstance(b, float) and b == 0.0:
        return 0.0
    if isinstance(a, float) and a == 1.0:
        return b
    if isinstance(b, float) and b == 1.0:
        return a
    return a * b  # type: ignore[operator]


def _sum(terms: list[Entry]) -> Entry:
    out: Entry = 0.0
    for t in terms:
        if isinstance(t, float) and t == 0.0:
            continue
        out = t if isinstance(out, float) and out == 0.0 else out + t  # type: ignore[operator]
    return out


def matmul(A: Mat, B: Mat) -> Mat:
    """Product of two 3x3 matrices of jets / constants."""
    return [[_sum([_mul(A[i][k], B[k][j]) for k in range(3)]) for j in range(3)]
            for i in range(3)]


def matvec(A: Mat, v: Vec) -> Vec:
    """``A v``."""
    return [_sum([_mul(A[i][k], v[k]) for k in range(3)]) for i in range(3)]


def rot_x(c: Entry, s: Entry) -> Mat:
    """``Rx`` from its cosine and sine."""
    return [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]  # type: ignore[list-item]


def rot_y(c: Entry, s: Entry) -> Mat:
    """``Ry`` from its cosine and sine."""
    return [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]  # type: ignore[list-item, operator]


def rot_z(c: Entry, s: Entry) -> Mat:
    """``Rz`` from its cosine and sine."""
    return [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]  # type: ignore[list-item, operator]


_RX90: Mat = [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]
_EYE: Mat = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]


def slot_signs(slot: int) -> tuple[float, float, float, float]:
    """``(mode, sign p, sign sin u2, sign sin u4)`` of a forward-kinematics slot."""
    return (1.0 - 2 * (slot // 8 % 2), 1.0 - 2 * (slot // 4 % 2),
            1.0 - 2 * (slot // 2 % 2), 1.0 - 2 * (slot % 2))


@dataclasses.dataclass(frozen=True)
class BodyJets:
    """Jets of every body frame (origin, rotation) and of the tool tip.

    Attributes
    ----------
    origin : dict of str -> list of 3 jets (or constants)
    rotation : dict of str -> 3x3 nested list of jets (or constants)
    tip : list of 3 jets
    hc : ndarray
        Half-chord of ``k1 ∩ k2`` (m), the distance to the assembly-mode singularity.
    sin_u2, sin_u4, p : ndarray
        The serial chain's distances to its degenerate sets.
    """

    origin: dict[str, Vec]
    rotation: dict[str, Mat]
    tip: Vec
    hc: FloatArray
    sin_u2: FloatArray
    sin_u4: FloatArray
    p: FloatArray


def body_jets(q: list[J2], rcm: list[J2], R_e: Mat, design: Design, slot: int) -> BodyJets:
    """Jets of every body frame of :data:`~athenakin.dynamics.MASS_BODIES`.

    Parameters
    ----------
    q : list of 3 J2
        Jets of ``q1, q2, q3`` (m).
    rcm : list of 3 J2
        Jets of the RCM position (translation of ``T_b_e``), m.
    R_e : 3x3 nested list of (J2 or float)
        Jets of the RCM frame's rotation.
    design : Design
    slot : int
        Forward-kinematics slot 0..15.

    Returns
    -------
    BodyJets
        Frames of the table of :mod:`athenakin.dynamics._model`; NaN where the slot holds
        no solution.
    """
    mode, ps, su2, su4 = slot_signs(slot)
    origin, rotation, cth, sth, hc = _module_jets(q, design, mode)
    O_s, R_i = origin["instrument"], rotation["platform"]
    # instrument: d = (RCM - O_s) / p, p = ps |RCM - O_s|
    cvj: list[J2] = [rcm[i] - O_s[i] for i in range(3)]  # type: ignore[operator, misc]
    p = (cvj[0].sq() + cvj[1].sq() + cvj[2].sq()).sqrt() * ps
    d = [v / p for v in cvj]
    # d in the platform frame: R_i^T d
    ds0: J2 = d[0]
    ds1: J2 = cth * d[1] + sth * d[2]
    ds2: J2 = cth * d[2] - sth * d[1]
    c2 = -ds2
    s2 = (ds0.sq() + ds1.sq()).sqrt() * su2
    c1, s1 = ds0 / s2, ds1 / s2
    # Rz(u1) Rx(pi/2) Rz(u2) Rx(pi/2)
    Q: Mat = [[c1 * c2, s1, c1 * s2], [s1 * c2, -c1, s1 * s2], [s2, 0.0, -c2]]
    R_3 = matmul(R_i, Q)
    # spherical joint: W = R_3^T R_e = Rz(u3) Rx(pi/2) Rz(u4) Rx(pi/2) Rz(u5)
    R_3T = [[R_3[j][i] for j in range(3)] for i in range(3)]
    W = matmul(R_3T, R_e)
    w02, w12, w22 = W[0][2], W[1][2], W[2][2]
    assert isinstance(w02, J2) and isinstance(w12, J2) and isinstance(w22, J2)
    c4 = -w22
    s4 = (w02.sq() + w12.sq()).sqrt() * su4
    c3, s3 = w02 / s4, w12 / s4
    R_s3 = matmul(R_3, rot_z(c3, s3))
    R_s4 = matmul(matmul(R_s3, _RX90), rot_z(c4, s4))
    tip: Vec = [O_s[i] + d[i] * design.tool_length for i in range(3)]
    origin.update({"guide": list[Entry](rcm), "sphere_link_2": list[Entry](rcm),
                   "sphere_link_1": list[Entry](rcm)})
    rotation.update({"instrument": R_3, "guide": R_3, "sphere_link_2": R_s3,
                     "sphere_link_1": R_s4})
    return BodyJets(origin=origin, rotation=rotation, tip=tip, hc=hc.c0, sin_u2=s2.c0,
                    sin_u4=s4.c0, p=p.c0)


def _module_jets(q: list[J2], design: Design, mode: float
                 ) -> tuple[dict[str, Vec], dict[str, Mat], J2, J2, J2]:
    """Frames of the parallel module's bodies (Eq. 7-10), in one assembly mode.

    Returns the origins (with ``"instrument"``: ``O_s``) and rotations (up to
    ``"platform"``: ``R_i = Rx(theta)``) by body name, ``cos theta``, ``sin theta`` and
    the half-chord of ``k1 ∩ k2``.
    """
    l1, l2, l3, l4, l5 = (float(x) for x in design.lengths)
    q1, q2, q3 = q
    h = (q1 - q2) * 0.5
    x_M = (q1 + q2) * 0.5
    h2 = h.sq()
    r1 = (l1 * l1 - h2).sqrt()
    y_D = (l3 * l3 - h2).sqrt()
    m_y = y_D + l2
    dd2 = m_y.sq() + l5 * l5
    dd = dd2.sqrt()
    a = (r1.sq() - q3.sq() + dd2) / (dd * 2.0)
    hc = (r1.sq() - a.sq()).sqrt()
    # O_i in the plane x = x_M, (y, z) from M: c2 direction (m_y, l5)/dd, normal (-l5, m_y)/dd
    o_y = (a * m_y - hc * (mode * l5)) / dd
    o_z = (a * l5 + hc * m_y * mode) / dd
    cth = o_z / r1            # z_i = (0, -sin theta, cos theta)
    sth = -(o_y / r1)
    zero = 0.0
    O_i: Vec = [x_M, o_y, o_z]
    O_s: Vec = [x_M, o_y + (-l4) * sth, o_z + l4 * cth]
    R_i = rot_x(cth, sth)
    A: Vec = [q1, zero, zero]
    B: Vec = [q2, zero, zero]
    D: Vec = [x_M, y_D, zero]
    C: Vec = [x_M, m_y, l5]
    # bars l1 (U-joints at A, B): Ry(phi), cos phi = r1 / l1, sin phi = -h / l1
    cph, sph = r1 / l1, h / (-l1)
    R_la = matmul(R_i, rot_y(cph, sph))
    R_lb = matmul(R_i, rot_y(cph, -sph))
    # bars l3 in the base plane
    R_lad = rot_z(h / (-l3), y_D / l3)
    R_lbd = rot_z(h / l3, y_D / l3)
    # q3 actuator: z from C to O_i = (0, -sin gamma, cos gamma)
    cga = (o_z - l5) / q3
    sga = -((o_y - m_y) / q3)
    R_act = rot_x(cga, sga)
    origin: dict[str, Vec] = {
        "carriage_a": A, "carriage_b": B, "link_a": A, "link_b": B, "link_ad": A,
        "link_bd": B, "carrier": D, "slider_d": D, "actuator": C, "actuator_rod": O_i,
        "platform": O_i, "instrument": O_s,
    }
    rotation: dict[str, Mat] = {
        "carriage_a": _EYE, "carriage_b": _EYE, "link_a": R_la, "link_b": R_lb,
        "link_ad": R_lad, "link_bd": R_lbd, "carrier": _EYE, "slider_d": _EYE,
        "actuator": R_act, "actuator_rod": R_act, "platform": R_i,
    }
    return origin, rotation, cth, sth, hc
