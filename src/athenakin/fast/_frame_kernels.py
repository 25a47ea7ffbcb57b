"""Compiled link frames and unit quaternions of many readings (private; the MCAP writer's ``/tf``).

:func:`quaternion_xyzw_into` is :func:`athenakin.ros._frames.quaternion_xyzw` element by
element: Shepperd's choice of the largest component (``argmax``, NaN first as numpy does),
the same expressions in the same order, the sign flip to ``w >= 0``; the results are bit
for bit the numpy function's (tested), in one pass without its temporaries.

:func:`urdf_frames_into` is :func:`athenakin.ros._frames.link_poses` followed by
:func:`quaternion_xyzw` of the links asked for, reading by reading (the URDF's forward
kinematics, parent before child), without the (N, 4, 4) temporaries of every link; it
agrees with them to rounding (tested to 1e-12).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["quaternion_xyzw_into", "urdf_frames_into"]


@njit(error_model="numpy", cache=True, nogil=True, inline="always")
def _quat(m00, m01, m02, m10, m11, m12, m20, m21, m22):
    """``(x, y, z, w)`` of one rotation matrix (the body of :func:`quaternion_xyzw_into`)."""
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
    a = (m21 - m12) * f
    b = (m02 - m20) * f
    c = (m10 - m01) * f
    d = (m01 + m10) * f
    e = (m02 + m20) * f
    g = (m12 + m21) * f
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
    return x * sign, y * sign, z * sign, w * sign


@njit(error_model="numpy", cache=True, nogil=True)
def quaternion_xyzw_into(R, out):
    """Quaternions ``(x, y, z, w)`` of rotations ``R`` (n, 3, 3) into ``out`` (n, 4)."""
    for i in range(R.shape[0]):
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = _quat(
            R[i, 0, 0], R[i, 0, 1], R[i, 0, 2], R[i, 1, 0], R[i, 1, 1], R[i, 1, 2],
            R[i, 2, 0], R[i, 2, 1], R[i, 2, 2])


@njit(error_model="numpy", cache=True, nogil=True)
def urdf_frames_into(values, parent, origin, kind, axis, column, wanted, out):
    """Translation and quaternion of links of a URDF tree for each reading.

    Parameters
    ----------
    values : (n, J) float64
        Joint values (m for prismatic joints, rad for hinges).
    parent : (L,) int64
        Index of each link's parent link, -1 for the root (links parent first).
    origin : (L, 4, 4) float64
        Origin of the joint into each link, in its parent's frame.
    kind : (L,) int64
        0 fixed, 1 prismatic, 2 hinge.
    axis : (L, 3) float64
        Joint axis (unit), in the joint frame.
    column : (L,) int64
        Column of ``values`` of each link's joint (ignored for fixed joints).
    wanted : (K,) int64
        Links written.
    out : (n, K, 7) float64
        ``tx, ty, tz, qx, qy, qz, qw`` of each wanted link in the root frame (m).
    """
    L = parent.shape[0]
    T = np.empty((L, 3, 4))
    A = np.empty((3, 4))
    M = np.empty((3, 4))
    for i in range(values.shape[0]):
        for li in range(L):
            pa = parent[li]
            Og = origin[li]
            # A = T[parent] @ origin (rows of a rigid transform; the root is the identity)
            if pa < 0:
                for r in range(3):
                    for c in range(4):
                        A[r, c] = Og[r, c]
            else:
                P = T[pa]
                for r in range(3):
                    for c in range(4):
                        acc = P[r, 0] * Og[0, c] + P[r, 1] * Og[1, c] + P[r, 2] * Og[2, c]
                        if c == 3:
                            acc += P[r, 3]
                        A[r, c] = acc
            kd = kind[li]
            if kd == 0:
                for r in range(3):
                    for c in range(4):
                        T[li, r, c] = A[r, c]
                continue
            v = values[i, column[li]]
            x, y, z = axis[li, 0], axis[li, 1], axis[li, 2]
            if kd == 1:
                for r in range(3):
                    for c in range(3):
                        T[li, r, c] = A[r, c]
                    T[li, r, 3] = A[r, 0] * (v * x) + A[r, 1] * (v * y) + A[r, 2] * (v * z) \
                        + A[r, 3]
                continue
            co, si = math.cos(v), math.sin(v)
            C = 1.0 - co
            M[0, 0] = co + x * x * C
            M[0, 1] = x * y * C - z * si
            M[0, 2] = x * z * C + y * si
            M[1, 0] = y * x * C + z * si
            M[1, 1] = co + y * y * C
            M[1, 2] = y * z * C - x * si
            M[2, 0] = z * x * C - y * si
            M[2, 1] = z * y * C + x * si
            M[2, 2] = co + z * z * C
            for r in range(3):
                for c in range(3):
                    T[li, r, c] = A[r, 0] * M[0, c] + A[r, 1] * M[1, c] + A[r, 2] * M[2, c]
                T[li, r, 3] = A[r, 3]
        for k in range(wanted.shape[0]):
            W = T[wanted[k]]
            out[i, k, 0] = W[0, 3]
            out[i, k, 1] = W[1, 3]
            out[i, k, 2] = W[2, 3]
            out[i, k, 3], out[i, k, 4], out[i, k, 5], out[i, k, 6] = _quat(
                W[0, 0], W[0, 1], W[0, 2], W[1, 0], W[1, 1], W[1, 2], W[2, 0], W[2, 1],
                W[2, 2])
