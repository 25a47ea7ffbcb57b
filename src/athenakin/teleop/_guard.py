"""The bodies' clearance for the teleoperation limiter (private).

One :class:`~athenakin.collision._workspace.ClearanceWorkspace` per pose kept (the
committed pose and the trial one, swapped on a commit: no copy), the body segments
placed from a tracked pose by the tracker's formula
(:meth:`athenakin.motion._clearance.PoseClearance.points`, pinned to
:func:`athenakin._mechanism.mechanism_points`), and the first-order change of every
pair's distance along a step from the witness points of the committed pose.

The gradient. For a pair of solids ``a, b`` at signed distance ``d`` with witness points
``w_a, w_b`` (``w_b - w_a = d n``, ``n`` the unit normal from ``a`` to ``b``, for either
sign of ``d``), a step that moves the material points under the witnesses by ``dw_a``,
``dw_b`` changes ``d`` by ``n . (dw_b - dw_a)`` to first order. A witness point's
displacement is interpolated along its body's segment from the two end points'
displacements (a rigid body's points move affinely along its axis to first order).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._backend import njit
from .._typing import FloatArray

__all__ = ["BodyGuard", "EXACT_BAND_M", "NORMAL_TOL_M"]

#: Band above the guard's floor within which every distance is exact (coal for boxes and
#: meshes), m; farther, a bounding-sphere lower bound may stand in.
EXACT_BAND_M = 0.02
#: Pairs closer than this to contact (|d|, m) have no reliable normal from their
#: witnesses: their step limit is the exact check alone.
NORMAL_TOL_M = 1e-9


@njit(error_model="numpy", cache=True, nogil=True)
def _fraction_kernel(seg0, seg1, dist, wit, body, floor, slack, tol):  # pragma: no cover
    """:meth:`BodyGuard.fraction` compiled: the same formula, pair by pair."""
    nb = seg0.shape[0]
    reach = 0.0
    for i in range(nb):
        for e in range(2):
            d2 = 0.0
            for j in range(3):
                v = seg1[i, e, j] - seg0[i, e, j]
                d2 += v * v
            reach = max(reach, d2)
    reach = 2.0 * math.sqrt(reach)
    lam = 1.0
    for k in range(dist.shape[0]):
        d = dist[k]
        if not d < floor + slack + reach:
            continue
        if not abs(d) > tol:
            continue
        rate = 0.0
        for side in range(2):
            i = body[k, side]
            if i < 0:
                continue
            L2 = 0.0
            t = 0.0
            for j in range(3):
                ab = seg0[i, 1, j] - seg0[i, 0, j]
                L2 += ab * ab
                t += (wit[k, side, j] - seg0[i, 0, j]) * ab
            t = min(1.0, max(0.0, t / L2)) if L2 > 0.0 else 0.0
            sign = 1.0 if side == 1 else -1.0
            for j in range(3):
                dw = ((seg1[i, 0, j] - seg0[i, 0, j]) * (1.0 - t)
                      + (seg1[i, 1, j] - seg0[i, 1, j]) * t)
                rate += sign * (wit[k, 1, j] - wit[k, 0, j]) / d * dw
        if rate < 0.0:
            room = d - floor - slack if d > floor else 0.0
            lam = min(lam, max(room, 0.0) / -rate)
        elif rate != rate:
            lam = 0.0
    return lam


@njit(error_model="numpy", cache=True, nogil=True)
def _place_kernel(q1, q2, p, u0, u1, u2, ox, oy, oz, d0, d1, d2, G, index, pts,
                  seg):  # pragma: no cover - numba
    """:meth:`athenakin.motion._clearance.PoseClearance.points` compiled, gathered to ``seg``.

    ``G``: ``l1, l2, l3, l4, l5, L, rail margin, half carriage, sphere radius, rail lo,
    rail hi, rcm (3), z_e (3)``; ``index`` (n_bodies, 2) the points of each body segment.
    """
    l1, l2, l3, l4, l5, L = G[0], G[1], G[2], G[3], G[4], G[5]
    rm, half, rs, lo, hi = G[6], G[7], G[8], G[9], G[10]
    rc0, rc1, rc2, ze0, ze1, ze2 = G[11], G[12], G[13], G[14], G[15], G[16]
    h = 0.5 * (q1 - q2)
    xm = 0.5 * (q1 + q2)
    yd = math.sqrt(l3 * l3 - h * h)
    r1 = math.sqrt(l1 * l1 - h * h)
    cy, cz = oy / (r1 + l4), oz / (r1 + l4)
    c1, s1, c2, s2 = math.cos(u0), math.sin(u0), math.cos(u1), math.sin(u1)
    c3, s3 = math.cos(u2), math.sin(u2)
    v0 = s3 * c1 * c2 - c3 * s1
    v1 = s3 * s1 * c2 + c3 * c1
    v2 = s3 * s2
    a40, a41, a42 = v0, cz * v1 + cy * v2, -cy * v1 + cz * v2
    side = -1.0 if p < 0 else 1.0
    t = p - side * rs
    if 0.0 <= t <= L:
        s30, s31, s32 = rc0 - side * rs * d0, rc1 - side * rs * d1, rc2 - side * rs * d2
    else:
        t = min(max(t, 0.0), L)
        s30, s31, s32 = ox + t * d0, oy + t * d1, oz + t * d2
    rows = (
        (q1, 0.0, 0.0), (q2, 0.0, 0.0), (xm, 0.0, 0.0), (xm, yd, 0.0),
        (xm, yd + l2, 0.0), (xm, yd + l2, l5), (ox, oy - l4 * cy, oz - l4 * cz),
        (ox, oy, oz), (rc0, rc1, rc2), (ox + L * d0, oy + L * d1, oz + L * d2),
        (min(min(q1, q2) - rm, lo), 0.0, 0.0), (max(max(q1, q2) + rm, hi), 0.0, 0.0),
        (q1 - half, 0.0, 0.0), (q1 + half, 0.0, 0.0),
        (q2 - half, 0.0, 0.0), (q2 + half, 0.0, 0.0),
        (s30, s31, s32),
        (rc0 + rs * a40, rc1 + rs * a41, rc2 + rs * a42),
        (rc0 + rs * ze0, rc1 + rs * ze1, rc2 + rs * ze2))
    for i in range(19):
        r = rows[i]
        pts[i, 0] = r[0]
        pts[i, 1] = r[1]
        pts[i, 2] = r[2]
    for b in range(index.shape[0]):
        for e in range(2):
            k = index[b, e]
            seg[b, e, 0] = pts[k, 0]
            seg[b, e, 1] = pts[k, 1]
            seg[b, e, 2] = pts[k, 2]


class BodyGuard:
    """Clearance of a tracked pose's bodies and the step fraction that keeps it.

    Parameters
    ----------
    design, T_b_e
        The robot.
    bodies : Bodies
    environment : Environment or None
    backend : {"auto", "numpy", "numba"}
        The capsule kernel's backend.
    floor : float
        Least clearance the guard keeps (m), the exact band's base.
    """

    def __init__(self, design: Any, T_b_e: FloatArray, bodies: Any, environment: Any, *,
                 backend: str, floor: float) -> None:
        from ..collision._workspace import ClearanceWorkspace
        from ..motion._clearance import PoseClearance

        self._pc = PoseClearance(design, T_b_e, bodies)
        below = floor + EXACT_BAND_M
        self._cur = ClearanceWorkspace(bodies, environment, backend=backend, exact_below=below)
        self._try = ClearanceWorkspace(bodies, environment, backend=backend, exact_below=below)
        self.pairs = self._cur.pairs
        self._body = self._cur.body
        self.evaluations = 0             # clearance evaluations of the current cycle
        self.clearance = math.nan        # the committed pose's least clearance, m
        self.closest = -1
        self._seg = np.empty_like(self._cur.segments)
        self._compiled = self._cur.compiled
        pc = self._pc
        self._G = np.array([pc.l1, pc.l2, pc.l3, pc.l4, pc.l5, pc.L, pc.rm, pc.half, pc.rs,
                            pc.lo, pc.hi, *pc.rcm, *pc.ze], dtype=np.float64)
        self._index = np.ascontiguousarray(pc.index, dtype=np.intp)
        self._pts = np.empty((19, 3))

    def segments(self, pose: Any) -> FloatArray:
        """The body segments of a tracked pose into the trial buffer, shape (n_bodies, 2, 3)."""
        seg = self._try.segments
        if self._compiled:
            q, u, o, d = pose.q, pose.u, pose.O_s, pose.direction_b
            _place_kernel(q[0], q[1], pose.p, u[0], u[1], u[2], o[0], o[1], o[2], d[0], d[1],
                          d[2], self._G, self._index, self._pts, seg)
            return seg
        pts = self._pc.points(pose.q, pose.p, pose.u, pose.O_s, pose.direction_b)
        np.take(pts, self._index, axis=0, out=seg)
        return seg

    def evaluate(self, pose: Any, *, placed: bool = False) -> float:
        """Least clearance of ``pose`` (m; the trial buffer), one evaluation counted.

        ``placed``: :meth:`fraction` has just placed this pose's segments.
        """
        if not placed:
            self.segments(pose)
        self.evaluations += 1
        d, k = self._try.evaluate()
        self._try_result = (d, k)
        return d

    def commit(self) -> None:
        """The last evaluated pose becomes the committed one (the buffers swap)."""
        self._cur, self._try = self._try, self._cur
        self.clearance, self.closest = self._try_result

    def start(self, pose: Any) -> float:
        """Evaluate and commit ``pose`` (the start or a reset); its least clearance, m."""
        self.evaluate(pose)
        self.commit()
        return self.clearance

    def trial_pair(self) -> tuple[str, str]:
        """The names of the last evaluated pose's closest pair (``("", "")`` with none)."""
        k = self._try_result[1]
        return self.pairs[k] if k >= 0 else ("", "")

    def closest_pair(self) -> tuple[str, str]:
        """The names of the committed pose's closest pair (``("", "")`` with none)."""
        return self.pairs[self.closest] if self.closest >= 0 else ("", "")

    def fraction(self, pose: Any, floor: float, slack: float) -> float:
        """The fraction of the step to ``pose`` that keeps every pair above ``floor`` (m).

        First order, from the committed pose's witness points and the segments of
        ``pose`` (placed here, not evaluated). A pair already below ``floor`` may not
        come closer; one above may come down to ``floor + slack``. Pairs that no step
        of this length can bring to ``floor`` (farther than twice the largest end-point
        displacement) are not looked at. Returns a fraction in [0, 1].
        """
        seg1 = self.segments(pose)
        cur = self._cur
        seg0 = cur.segments
        if self._compiled:
            return float(_fraction_kernel(seg0, seg1, cur.distances, cur.witness_points,
                                          self._body, floor, slack, NORMAL_TOL_M))
        disp = np.subtract(seg1, seg0, out=self._seg)
        reach = 2.0 * float(np.sqrt(np.einsum("ijk,ijk->ij", disp, disp).max()))
        d0 = cur.distances
        near = np.flatnonzero(d0 < floor + slack + reach)
        if not len(near):
            return 1.0
        k = near
        d = d0[k]
        w = cur.witness_points[k]
        body = self._body[k]
        wa, wb = w[:, 0], w[:, 1]
        dwa = _witness_motion(seg0, disp, body[:, 0], wa)
        dwb = _witness_motion(seg0, disp, np.maximum(body[:, 1], 0), wb)
        dwb[body[:, 1] < 0] = 0.0                   # an obstacle does not move
        ok = np.abs(d) > NORMAL_TOL_M
        with np.errstate(invalid="ignore", divide="ignore"):
            n = (wb - wa) / np.where(ok, d, 1.0)[:, None]
            rate = np.einsum("ij,ij->i", n, dwb - dwa)
            room = np.where(d > floor, d - floor - slack, 0.0)
            lam = np.where((rate < 0.0) & ok, np.maximum(room, 0.0) / -rate, 1.0)
        out = float(lam.min())
        return min(1.0, out) if out == out else 0.0


def _witness_motion(seg0: FloatArray, disp: FloatArray, i: Any, w: FloatArray) -> FloatArray:
    """Displacement of the material point under witness ``w`` of body ``i`` (rows), m."""
    a = seg0[i, 0]
    ab = seg0[i, 1] - a
    L2 = np.einsum("ij,ij->i", ab, ab)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(L2 > 0.0, np.einsum("ij,ij->i", w - a, ab) / np.where(L2 > 0, L2, 1.0), 0.0)
    t = np.clip(t, 0.0, 1.0)[:, None]
    return disp[i, 0] * (1.0 - t) + disp[i, 1] * t
