"""Compiled kernels of the teleoperation guard (numba; imported on the compiled branch only).

Their references: :meth:`athenakin.teleop._fixtures.TipFixtures.nearest` (a point's
signed distance to the tip fixtures, scalar Python),
:meth:`athenakin.teleop._guard.BodyGuard.fraction` (the first-order step limit from the
witness points) and :meth:`athenakin.motion._clearance.PoseClearance.points` (the body
points of a tracked pose: the same formula compiled, equal bit for bit), to 1e-12
(tests/test_teleop_loop.py).
"""

from __future__ import annotations

import math

from .._backend import njit
from .._mechanism_formulas import mechanism_points_formula

__all__ = ["place_segments", "step_fraction", "fixture_nearest"]


@njit(error_model="numpy", cache=True, nogil=True)
def step_fraction(seg0, seg1, dist, wit, exact, body, floor, slack, tol):  # pragma: no cover
    """:meth:`athenakin.teleop._guard.BodyGuard.fraction` compiled: the same formula."""
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
            if not exact[k]:                 # a carried bound: its largest closing
                rate -= _move(seg0, seg1, i)
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
def _move(seg0, seg1, i):  # pragma: no cover - numba
    """Largest displacement of body ``i``'s end points from ``seg0`` to ``seg1``, m."""
    m = 0.0
    for e in range(2):
        d2 = 0.0
        for j in range(3):
            v = seg1[i, e, j] - seg0[i, e, j]
            d2 += v * v
        m = max(m, d2)
    return math.sqrt(m)


_INLINE = dict(error_model="numpy", cache=True, nogil=True, inline="always")
#: The one formula of the mechanism's points, compiled (the tracker's clearance and numpy
#: evaluate the same source).
_points_formula = njit(**_INLINE)(mechanism_points_formula)


@njit(**_INLINE)
def _select(c, a, b):  # pragma: no cover - numba
    return a if c else b


@njit(**_INLINE)
def _min(a, b):  # pragma: no cover - numba
    return min(a, b)


@njit(**_INLINE)
def _max(a, b):  # pragma: no cover - numba
    return max(a, b)


@njit(**_INLINE)
def _sqrt(x):  # pragma: no cover - numba
    return math.sqrt(x)


@njit(error_model="numpy", cache=True, nogil=True)
def place_segments(q1, q2, p, u0, u1, u2, ox, oy, oz, G, index, pts,
                   seg):  # pragma: no cover - numba
    """:meth:`athenakin.motion._clearance.PoseClearance.points` compiled, gathered to ``seg``.

    ``G``: ``l1``, the formula's constants (:attr:`PoseClearance.G`), the RCM (3) and
    ``z_e`` (3); ``index`` (n_bodies, 2) the points of each body segment.
    """
    h = 0.5 * (q1 - q2)
    r1l4 = math.sqrt(G[0] * G[0] - h * h) + G[3]
    rows = _points_formula(q1, q2, p, math.cos(u0), math.sin(u0), math.cos(u1), math.sin(u1),
                           math.cos(u2), math.sin(u2), ox, oy, oz, oy / r1l4, oz / r1l4,
                           G[11], G[12], G[13], G[14], G[15], G[16], G[1:11], _sqrt, _min,
                           _max, _select)
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


@njit(error_model="numpy", cache=True, nogil=True)
def _radial(v0, v1, v2, r):  # pragma: no cover - numba
    n = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    if n > 0.0:
        return n - r, v0 / n, v1 / n, v2 / n
    return -r, 0.0, 0.0, 1.0


@njit(error_model="numpy", cache=True, nogil=True)
def fixture_nearest(x0, x1, x2, S):  # pragma: no cover - numba
    """Least signed distance of a point to the fixtures ``S`` (rows of ``_fixtures._table``).

    Returns ``(d, n0, n1, n2, index)``: the distance (m, negative inside), the outward unit
    normal and the row (``inf``, ``(0, 0, 1)``, -1 without rows).
    """
    best, b0, b1, b2, ib = math.inf, 0.0, 0.0, 1.0, -1
    for k in range(S.shape[0]):
        kind = S[k, 0]
        if kind == 0.0:                                 # halfspace: n . (x - p)
            n0, n1, n2 = S[k, 4], S[k, 5], S[k, 6]
            d = n0 * (x0 - S[k, 1]) + n1 * (x1 - S[k, 2]) + n2 * (x2 - S[k, 3])
        elif kind == 1.0:                               # sphere
            d, n0, n1, n2 = _radial(x0 - S[k, 1], x1 - S[k, 2], x2 - S[k, 3], S[k, 4])
        elif kind == 2.0:                               # capsule
            a0, a1, a2, e0, e1, e2 = S[k, 1], S[k, 2], S[k, 3], S[k, 4], S[k, 5], S[k, 6]
            abab = S[k, 7]
            t = 0.0
            if abab > 0.0:
                t = min(1.0, max(0.0, ((x0 - a0) * e0 + (x1 - a1) * e1 + (x2 - a2) * e2)
                                 / abab))
            d, n0, n1, n2 = _radial(x0 - (a0 + t * e0), x1 - (a1 + t * e1),
                                    x2 - (a2 + t * e2), S[k, 8])
        else:                                           # box: local p = R^T (x - c)
            v0, v1, v2 = x0 - S[k, 1], x1 - S[k, 2], x2 - S[k, 3]
            R00, R01, R02 = S[k, 4], S[k, 5], S[k, 6]
            R10, R11, R12 = S[k, 7], S[k, 8], S[k, 9]
            R20, R21, R22 = S[k, 10], S[k, 11], S[k, 12]
            p0 = R00 * v0 + R10 * v1 + R20 * v2
            p1 = R01 * v0 + R11 * v1 + R21 * v2
            p2 = R02 * v0 + R12 * v1 + R22 * v2
            q0, q1, q2 = abs(p0) - S[k, 13], abs(p1) - S[k, 14], abs(p2) - S[k, 15]
            if q0 > 0.0 or q1 > 0.0 or q2 > 0.0:
                e0 = math.copysign(q0, p0) if q0 > 0.0 else 0.0
                e1 = math.copysign(q1, p1) if q1 > 0.0 else 0.0
                e2 = math.copysign(q2, p2) if q2 > 0.0 else 0.0
                d = math.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
                l0, l1, l2 = e0 / d, e1 / d, e2 / d
            elif q0 >= q1 and q0 >= q2:
                d, l0, l1, l2 = q0, math.copysign(1.0, p0), 0.0, 0.0
            elif q1 >= q2:
                d, l0, l1, l2 = q1, 0.0, math.copysign(1.0, p1), 0.0
            else:
                d, l0, l1, l2 = q2, 0.0, 0.0, math.copysign(1.0, p2)
            n0 = R00 * l0 + R01 * l1 + R02 * l2
            n1 = R10 * l0 + R11 * l1 + R12 * l2
            n2 = R20 * l0 + R21 * l1 + R22 * l2
        if d < best:
            best, b0, b1, b2, ib = d, n0, n1, n2, k
    return best, b0, b1, b2, ib
