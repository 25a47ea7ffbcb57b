"""Compiled unit quaternions of many rotations (private; the MCAP writer's ``/tf``).

:func:`quaternion_xyzw_into` is :func:`athenakin.ros._frames.quaternion_xyzw` element by
element: Shepperd's choice of the largest component (``argmax``, NaN first as numpy does),
the same expressions in the same order, the sign flip to ``w >= 0``; the results are bit
for bit the numpy function's (tested), in one pass without its temporaries.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = ["quaternion_xyzw_into"]


@njit(error_model="numpy", cache=True, nogil=True)
def quaternion_xyzw_into(R, out):
    """Quaternions ``(x, y, z, w)`` of rotations ``R`` (n, 3, 3) into ``out`` (n, 4)."""
    for i in range(R.shape[0]):
        m00 = R[i, 0, 0]
        m11 = R[i, 1, 1]
        m22 = R[i, 2, 2]
        tr = m00 + m11 + m22
        k = 0
        best = tr
        if not math.isnan(tr):
            for j in range(1, 4):
                v = m00 if j == 1 else (m11 if j == 2 else m22)
                if math.isnan(v):
                    k = j
                    best = v
                    break
                if v > best:
                    k = j
                    best = v
        r = 1.0 + 2.0 * best - tr
        s = math.sqrt(r if r >= 0.0 or math.isnan(r) else 0.0)   # np.maximum(r, 0.0)
        f = 0.5 / s
        a = (R[i, 2, 1] - R[i, 1, 2]) * f
        b = (R[i, 0, 2] - R[i, 2, 0]) * f
        c = (R[i, 1, 0] - R[i, 0, 1]) * f
        d = (R[i, 0, 1] + R[i, 1, 0]) * f
        e = (R[i, 0, 2] + R[i, 2, 0]) * f
        g = (R[i, 1, 2] + R[i, 2, 1]) * f
        h = 0.5 * s
        if k == 0:
            w, x, y, z = h, a, b, c
        elif k == 1:
            w, x, y, z = a, h, d, e
        elif k == 2:
            w, x, y, z = b, d, h, g
        else:
            w, x, y, z = c, e, g, h
        sign = -1.0 if w < 0.0 else 1.0
        out[i, 0] = x * sign
        out[i, 1] = y * sign
        out[i, 2] = z * sign
        out[i, 3] = w * sign
