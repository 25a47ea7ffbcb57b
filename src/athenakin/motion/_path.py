"""Geometric paths of the tool tip about the RCM and their image in actuator space (private).

A path is a sequence of segments between waypoints, each parametrised by
``lam`` in [0, 1]:

* ``"line"``: the tip moves on the straight segment ``a + lam (b - a)`` (frame E);
* ``"arc"``: the instrument direction turns on the great circle from ``d0`` to
  ``d1`` (spherical linear interpolation) while the depth of the tip beyond the
  RCM changes linearly; this is the straight line of the (direction, insertion)
  coordinates.

Actuator values come from the exact inverse kinematics of each point
(:func:`athenakin.q_from_tool_tip`); their derivatives with respect to ``lam``
from Taylor arithmetic through the same closed form (:mod:`._jet`), exact to
rounding, also next to a singularity.

The timing works on a second parameter ``s`` in [0, 1], proportional to the arc
length of the segment's image in actuator space (:func:`reparametrised`):
``|dq/ds|`` is then the same all along the segment, so that limits of ``ds/dt``
derived from the worst point of the segment are nearly tight everywhere, even
where ``q(lam)`` speeds up next to a singularity. ``lam(s)`` is a quintic
interpolating spline of the tabulated inverse of ``s(lam)``; it only sets the
pace along the path: every sample still lies exactly on it.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .._typing import FloatArray, Int8Array, IntArray
from ..design import Design
from ..robot import q_from_tool_tip
from ._jet import Jet, jet_sin_cos, q_jet

__all__ = ["Segment", "line_segment", "arc_segment", "q_on_tips", "q_derivatives",
           "reparametrised", "tip_speed_factor", "REPARAM_GRID"]

#: Grid points of the arc-length table of :func:`reparametrised`.
REPARAM_GRID = 1001

@dataclasses.dataclass(frozen=True)
class Segment:
    """One segment of a tool-tip path in the RCM frame E.

    Attributes
    ----------
    kind : {"line", "arc"}
    start, end : ndarray, shape (3,)
        Tip at ``lam = 0`` and ``lam = 1``, frame E, m.
    scale : float
        An upper bound of ``|d tip / d lam|`` (m), 0 for a dwell (no motion).
    """

    kind: str
    start: FloatArray
    end: FloatArray
    scale: float
    lam_of_s: object | None = dataclasses.field(default=None, repr=False)

    def lam(self, s: FloatArray, nu: int = 0) -> FloatArray:
        """``lam(s)`` or its derivative of order ``nu`` (identity without reparametrisation)."""
        s = np.asarray(s, float)
        if self.lam_of_s is None:
            return s if nu == 0 else np.full(s.shape, 1.0 if nu == 1 else 0.0)
        return self.lam_of_s(s, nu)  # type: ignore[operator]

    def tips(self, s: FloatArray) -> FloatArray:
        """Tool tip (frame E, m) at path parameters ``s`` of shape (...) -> (..., 3)."""
        return self.tips_lam(self.lam(s))

    def tips_jet(self, lam: FloatArray) -> list[Jet]:
        """Jets (Taylor coefficients in ``lam``, order 3) of the tip coordinates at ``lam`` (n,)."""
        lam = np.asarray(lam, float)
        if self.kind == "line":
            dv = self.end - self.start
            z = np.zeros_like(lam)
            return [Jet([self.start[i] + lam * dv[i], z + dv[i], z, z]) for i in range(3)]
        r0, r1 = np.linalg.norm(self.start), np.linalg.norm(self.end)
        d0, d1 = self.start / r0, self.end / r1
        omega = float(np.arctan2(np.linalg.norm(np.cross(d0, d1)), np.dot(d0, d1)))
        rad = Jet([r0 + lam * (r1 - r0), np.full(lam.shape, r1 - r0), 0 * lam, 0 * lam])
        if omega == 0.0:
            return [rad * float(d0[i]) for i in range(3)]
        sa, _ = jet_sin_cos(lam - 1.0, -omega)   # sin((1 - lam) omega)
        sb, _ = jet_sin_cos(lam, omega)          # sin(lam omega)
        so = np.sin(omega)
        return [(sa * float(d0[i]) + sb * float(d1[i])) * rad / so for i in range(3)]

    def tips_lam(self, lam: FloatArray) -> FloatArray:
        """Tool tip (frame E, m) at geometric parameters ``lam`` of shape (...) -> (..., 3)."""
        lam = np.asarray(lam, float)[..., None]
        if self.kind == "line":
            return self.start + lam * (self.end - self.start)
        r0, r1 = np.linalg.norm(self.start), np.linalg.norm(self.end)
        d0, d1 = self.start / r0, self.end / r1
        omega = float(np.arctan2(np.linalg.norm(np.cross(d0, d1)), np.dot(d0, d1)))
        if omega == 0.0:
            d = np.broadcast_to(d0, lam.shape[:-1] + (3,))
        else:
            s = np.sin(omega)
            d = (np.sin((1 - lam) * omega) * d0 + np.sin(lam * omega) * d1) / s
        return d * (r0 + lam * (r1 - r0))


def line_segment(a: FloatArray, b: FloatArray) -> Segment:
    """Straight tip segment from ``a`` to ``b`` (frame E, m)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return Segment("line", a, b, float(np.linalg.norm(b - a)))


def arc_segment(a: FloatArray, b: FloatArray) -> Segment:
    """Great-circle direction + linear depth segment between tips ``a`` and ``b`` (frame E)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    r0, r1 = float(np.linalg.norm(a)), float(np.linalg.norm(b))
    omega = float(np.arctan2(np.linalg.norm(np.cross(a, b)), np.dot(a, b)))
    return Segment("arc", a, b, max(r0, r1) * omega + abs(r1 - r0))


def q_on_tips(tips_e: FloatArray, T_b_e: FloatArray, design: Design
              ) -> tuple[FloatArray, Int8Array, IntArray]:
    """Inverse kinematics of tool tips, stroke limits not applied.

    Returns
    -------
    q : ndarray, shape (..., 3)
        NaN where the tip is outside the mechanism's workspace.
    reason : ndarray of int8, shape (...)
        :class:`~athenakin.errors.Reason` (0 where ``q`` is defined).
    mode : ndarray of int, shape (...)
        Assembly mode (+1 / -1).
    """
    free = dataclasses.replace(design, q_min=None, q_max=None)
    q, res = q_from_tool_tip(T_b_e, tips_e, free, errors="flag")
    return q, res.reason, res.mode


def _q_lam_derivatives(seg: Segment, lam: FloatArray, T_b_e: FloatArray,
                       design: Design) -> tuple[FloatArray, ...]:
    """``q`` (exact IK) and its derivatives in ``lam`` (Taylor arithmetic), each (n, 3)."""
    q0, reason, _ = q_on_tips(seg.tips_lam(lam), T_b_e, design)
    if seg.scale == 0.0:
        z = np.zeros_like(q0)
        return q0, z, z, z
    free = dataclasses.replace(design, q_min=None, q_max=None)
    with np.errstate(invalid="ignore", divide="ignore"):
        jets = q_jet(seg.tips_jet(lam), T_b_e, free)
    bad = (reason != 0)[:, None]
    d = [np.where(bad, np.nan, np.stack([j.derivatives()[k] for j in jets], axis=-1))
         for k in (1, 2, 3)]
    return q0, d[0], d[1], d[2]


def q_derivatives(seg: Segment, s: FloatArray, T_b_e: FloatArray,
                  design: Design) -> tuple[FloatArray, ...]:
    """``q`` and its first three derivatives with respect to the path parameter ``s``.

    Parameters
    ----------
    seg : Segment
    s : ndarray, shape (n,)
    T_b_e : ndarray, shape (4, 4)
    design : Design

    Returns
    -------
    q, dq, ddq, dddq : ndarray, shape (n, 3)
        ``q(s)`` (exact IK) and ``d^k q / d s^k`` (m). NaN where a stencil point
        leaves the workspace.
    """
    s = np.asarray(s, float)
    lam = seg.lam(s)
    q0, d1, d2, d3 = _q_lam_derivatives(seg, lam, T_b_e, design)
    if seg.lam_of_s is None:
        return q0, d1, d2, d3
    l1, l2, l3 = (seg.lam(s, k)[:, None] for k in (1, 2, 3))
    return (q0, d1 * l1, d2 * l1 ** 2 + d1 * l2,
            d3 * l1 ** 3 + 3 * d2 * l1 * l2 + d1 * l3)


def reparametrised(seg: Segment, T_b_e: FloatArray, design: Design, *,
                   n: int = REPARAM_GRID) -> Segment:
    """The segment with ``s`` proportional to the arc length of ``q(lam)`` (module docstring).

    Returns the segment unchanged for a dwell, or where ``q(lam)`` is not defined
    on the whole segment (it then leaves the workspace; the safety check says where).
    """
    from scipy.integrate import cumulative_simpson
    from scipy.interpolate import make_interp_spline

    if seg.scale == 0.0:
        return seg
    lam = np.linspace(0.0, 1.0, n)
    _, d1, _, _ = _q_lam_derivatives(dataclasses.replace(seg, lam_of_s=None), lam, T_b_e,
                                     design)
    speed = np.linalg.norm(d1, axis=-1)
    if not np.all(np.isfinite(speed)) or np.any(speed <= 0):
        return seg
    cum = np.concatenate([[0.0], cumulative_simpson(speed, x=lam)])
    if not np.all(np.diff(cum) > 0):
        return seg
    spl = make_interp_spline(cum / cum[-1], lam, k=5)
    return dataclasses.replace(seg, lam_of_s=spl)


def tip_speed_factor(seg: Segment, lam: FloatArray) -> FloatArray:
    """``|d tip / d lam|`` (m) at ``lam``, shape (n,), from central differences."""
    if seg.scale == 0.0:
        return np.zeros(np.shape(lam))
    h = 1e-6
    lo, hi = np.clip(lam - h, 0, 1), np.clip(lam + h, 0, 1)
    return np.linalg.norm(seg.tips(hi) - seg.tips(lo), axis=-1) / (hi - lo)
