"""Truncated Taylor arithmetic (order 3) for exact path derivatives of the inverse kinematics.

A :class:`Jet` holds the Taylor coefficients ``c0..c3`` of a function of the path
parameter at a batch of points, ``f(lam0 + t) = c0 + c1 t + c2 t^2 + c3 t^3 + O(t^4)``
(arrays of the same shape). Propagating jets through the closed-form controller
inverse kinematics (:func:`q_jet`, the same formulas as
:func:`athenakin.q_from_tool_tip`) gives ``dq/dlam``, ``d2q/dlam2`` and ``d3q/dlam3``
to rounding error, also next to a singularity where finite differences fail.
"""

from __future__ import annotations

import numpy as np

from .._typing import FloatArray
from ..design import Design

__all__ = ["Jet", "jet_sqrt", "jet_sin_cos", "q_jet"]

Number = float | FloatArray


class Jet:
    """Taylor coefficients ``c[0..3]`` (``c[k]`` = k-th derivative / k!), each an array."""

    __slots__ = ("c",)

    def __init__(self, c: list[FloatArray]) -> None:
        self.c = c

    @staticmethod
    def const(x: Number, like: Jet | None = None) -> Jet:
        """A constant jet."""
        x = np.asarray(x, float)
        if like is not None:
            x = np.broadcast_to(x, np.shape(like.c[0]))
        z = np.zeros_like(x)
        return Jet([x, z, z, z])

    def derivatives(self) -> tuple[FloatArray, ...]:
        """``(f, f', f'', f''')``."""
        c = self.c
        return c[0], c[1], 2.0 * c[2], 6.0 * c[3]

    def _j(self, o: Jet | Number) -> Jet:
        return o if isinstance(o, Jet) else Jet.const(o)

    def __add__(self, o: Jet | Number) -> Jet:
        o = self._j(o)
        return Jet([a + b for a, b in zip(self.c, o.c, strict=True)])

    __radd__ = __add__

    def __neg__(self) -> Jet:
        return Jet([-a for a in self.c])

    def __sub__(self, o: Jet | Number) -> Jet:
        return self + (-self._j(o))

    def __rsub__(self, o: Number) -> Jet:
        return Jet.const(o) - self

    def __mul__(self, o: Jet | Number) -> Jet:
        if not isinstance(o, Jet):
            return Jet([a * o for a in self.c])
        a, b = self.c, o.c
        return Jet([a[0] * b[0], a[0] * b[1] + a[1] * b[0],
                    a[0] * b[2] + a[1] * b[1] + a[2] * b[0],
                    a[0] * b[3] + a[1] * b[2] + a[2] * b[1] + a[3] * b[0]])

    __rmul__ = __mul__

    def __truediv__(self, o: Jet | Number) -> Jet:
        if not isinstance(o, Jet):
            return Jet([a / o for a in self.c])
        a, b = self.c, o.c
        q0 = a[0] / b[0]
        q1 = (a[1] - b[1] * q0) / b[0]
        q2 = (a[2] - b[1] * q1 - b[2] * q0) / b[0]
        q3 = (a[3] - b[1] * q2 - b[2] * q1 - b[3] * q0) / b[0]
        return Jet([q0, q1, q2, q3])

    def __rtruediv__(self, o: Number) -> Jet:
        return Jet.const(o) / self


def jet_sqrt(a: Jet) -> Jet:
    """Square root of a jet (NaN where ``a.c[0] < 0``)."""
    c = a.c
    with np.errstate(invalid="ignore", divide="ignore"):
        s0 = np.sqrt(c[0])
        s1 = c[1] / (2 * s0)
        s2 = (c[2] - s1 * s1) / (2 * s0)
        s3 = (c[3] - 2 * s1 * s2) / (2 * s0)
    return Jet([s0, s1, s2, s3])


def jet_sin_cos(x0: FloatArray, w: float) -> tuple[Jet, Jet]:
    """Jets of ``sin(w (x0 + t))`` and ``cos(w (x0 + t))``."""
    s, c = np.sin(w * x0), np.cos(w * x0)
    return (Jet([s, w * c, -w * w * s / 2, -w ** 3 * c / 6]),
            Jet([c, -w * s, -w * w * c / 2, w ** 3 * s / 6]))


def q_jet(tip_e: list[Jet], T_b_e: FloatArray, design: Design) -> list[Jet]:
    """Jets of ``(q1, q2, q3)`` from jets of the tool tip in frame E (controller-form IK).

    The formulas of :func:`athenakin.q_from_tool_tip` and
    :func:`athenakin.parallel.parallel_ik_from_position`: ``O_s = c - (L - |tip|) d``,
    ``r1 = hypot(O_y, O_z) - l4``, ``h = ±sqrt(l1^2 - r1^2)``,
    ``q3 = |(y, z) - (m_y, l5)|`` with ``(y, z) = (O_y, O_z) r1 / rho``.

    Parameters
    ----------
    tip_e : list of 3 Jet
    T_b_e : ndarray, shape (4, 4)
    design : Design

    Returns
    -------
    list of 3 Jet
        NaN where the tip is outside the mechanism's workspace.
    """
    R, c = T_b_e[:3, :3], T_b_e[:3, 3]
    r = jet_sqrt(tip_e[0] * tip_e[0] + tip_e[1] * tip_e[1] + tip_e[2] * tip_e[2])
    k = design.tool_length / r - 1.0
    o_s = [c[i] - (R[i, 0] * tip_e[0] + R[i, 1] * tip_e[1] + R[i, 2] * tip_e[2]) * k
           for i in range(3)]
    rho = jet_sqrt(o_s[1] * o_s[1] + o_s[2] * o_s[2])
    r1 = rho - design.l4
    h = jet_sqrt(design.l1 ** 2 - r1 * r1) * design.h_sign
    f = r1 / rho
    y, z = o_s[1] * f, o_s[2] * f
    m_y = jet_sqrt(design.l3 ** 2 - h * h) + design.l2
    dy, dz = y - m_y, z - design.l5
    q3 = jet_sqrt(dy * dy + dz * dz)
    return [o_s[0] + h, o_s[0] - h, q3]
