"""Compiled joint values, link frames and quaternions of many readings (private; ``/tf``).

:func:`quaternion_xyzw_into` is :func:`athenakin.ros._frames.quaternion_xyzw` element by
element: Shepperd's choice of the largest component (``argmax``, NaN first as numpy does),
the same expressions in the same order, the sign flip to ``w >= 0``; the results are bit
for bit the numpy function's (tested), in one pass without its temporaries.

:func:`joint_values_into` is :func:`athenakin.ros._frames.joint_values` reading by
reading: both evaluate :func:`athenakin._mechanism_formulas.tree_joint_formula` (compiled
here; libm's ``atan2`` where numpy may use its own SIMD one, so equal to the last bit or so,
tested). :func:`urdf_frames_into` is
:func:`athenakin.ros._frames.link_poses` followed by :func:`quaternion_xyzw` of the links
asked for, reading by reading (the URDF's forward kinematics, parent before child),
without the (N, 4, 4) temporaries of every link; it agrees with them to rounding (tested
to 1e-12).
"""

from __future__ import annotations

import math

import numpy as np

from .._backend import njit
from .._mechanism_formulas import FORMULA_JOINTS, tree_joint_formula

__all__ = ["quaternion_xyzw_into", "urdf_frames_into", "joint_values_into", "JOINT_CODES"]


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


@njit(error_model="numpy", cache=True, nogil=True, inline="always")
def _parent_times_origin(T, pa, origin, li):
    """The 12 entries (rows of ``[R | t]``) of ``T[pa] @ origin[li]``; the root: ``origin[li]``.

    ``T`` (L, 12): the poses of the links done so far (rows ``r00 r01 r02 t0 r10 ... t2``).
    """
    o00, o01, o02, o03 = origin[li, 0, 0], origin[li, 0, 1], origin[li, 0, 2], origin[li, 0, 3]
    o10, o11, o12, o13 = origin[li, 1, 0], origin[li, 1, 1], origin[li, 1, 2], origin[li, 1, 3]
    o20, o21, o22, o23 = origin[li, 2, 0], origin[li, 2, 1], origin[li, 2, 2], origin[li, 2, 3]
    if pa < 0:
        return o00, o01, o02, o03, o10, o11, o12, o13, o20, o21, o22, o23
    p00, p01, p02, p03 = T[pa, 0], T[pa, 1], T[pa, 2], T[pa, 3]
    p10, p11, p12, p13 = T[pa, 4], T[pa, 5], T[pa, 6], T[pa, 7]
    p20, p21, p22, p23 = T[pa, 8], T[pa, 9], T[pa, 10], T[pa, 11]
    return (p00 * o00 + p01 * o10 + p02 * o20,
            p00 * o01 + p01 * o11 + p02 * o21,
            p00 * o02 + p01 * o12 + p02 * o22,
            p00 * o03 + p01 * o13 + p02 * o23 + p03,
            p10 * o00 + p11 * o10 + p12 * o20,
            p10 * o01 + p11 * o11 + p12 * o21,
            p10 * o02 + p11 * o12 + p12 * o22,
            p10 * o03 + p11 * o13 + p12 * o23 + p13,
            p20 * o00 + p21 * o10 + p22 * o20,
            p20 * o01 + p21 * o11 + p22 * o21,
            p20 * o02 + p21 * o12 + p22 * o22,
            p20 * o03 + p21 * o13 + p22 * o23 + p23)


@njit(error_model="numpy", cache=True, nogil=True, inline="always")
def _rodrigues(x, y, z, v):
    """The 9 entries (row by row) of the rotation by ``v`` about the unit axis ``(x, y, z)``."""
    co, si = math.cos(v), math.sin(v)
    C = 1.0 - co
    return (co + x * x * C, x * y * C - z * si, x * z * C + y * si,
            y * x * C + z * si, co + y * y * C, y * z * C - x * si,
            z * x * C - y * si, z * y * C + x * si, co + z * z * C)


@njit(error_model="numpy", cache=True, nogil=True, boundscheck=False)
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
    T = np.empty((L, 12))           # rows of each link's pose: r00 r01 r02 t0 r10 ... t2
    for i in range(values.shape[0]):
        for li in range(L):
            (a00, a01, a02, a03, a10, a11, a12, a13,
             a20, a21, a22, a23) = _parent_times_origin(T, parent[li], origin, li)
            kd = kind[li]
            if kd == 1:                 # prismatic: translate by v * axis (joint frame)
                v = values[i, column[li]]
                x, y, z = v * axis[li, 0], v * axis[li, 1], v * axis[li, 2]
                a03 = a00 * x + a01 * y + a02 * z + a03
                a13 = a10 * x + a11 * y + a12 * z + a13
                a23 = a20 * x + a21 * y + a22 * z + a23
            elif kd == 2:               # hinge: rotate by v about axis (Rodrigues)
                v = values[i, column[li]]
                m00, m01, m02, m10, m11, m12, m20, m21, m22 = _rodrigues(
                    axis[li, 0], axis[li, 1], axis[li, 2], v)
                a00, a01, a02 = (a00 * m00 + a01 * m10 + a02 * m20,
                                 a00 * m01 + a01 * m11 + a02 * m21,
                                 a00 * m02 + a01 * m12 + a02 * m22)
                a10, a11, a12 = (a10 * m00 + a11 * m10 + a12 * m20,
                                 a10 * m01 + a11 * m11 + a12 * m21,
                                 a10 * m02 + a11 * m12 + a12 * m22)
                a20, a21, a22 = (a20 * m00 + a21 * m10 + a22 * m20,
                                 a20 * m01 + a21 * m11 + a22 * m21,
                                 a20 * m02 + a21 * m12 + a22 * m22)
            T[li, 0], T[li, 1], T[li, 2], T[li, 3] = a00, a01, a02, a03
            T[li, 4], T[li, 5], T[li, 6], T[li, 7] = a10, a11, a12, a13
            T[li, 8], T[li, 9], T[li, 10], T[li, 11] = a20, a21, a22, a23
        for k in range(wanted.shape[0]):
            w = wanted[k]
            out[i, k, 0] = T[w, 3]
            out[i, k, 1] = T[w, 7]
            out[i, k, 2] = T[w, 11]
            out[i, k, 3], out[i, k, 4], out[i, k, 5], out[i, k, 6] = _quat(
                T[w, 0], T[w, 1], T[w, 2], T[w, 4], T[w, 5], T[w, 6], T[w, 8], T[w, 9],
                T[w, 10])


#: What each joint of :data:`athenakin.sim.JOINTS` measures, as :func:`joint_values_into`'s
#: codes: its index in the result of
#: :func:`athenakin._mechanism_formulas.tree_joint_formula`.
JOINT_CODES = {name: k for k, name in enumerate(FORMULA_JOINTS)}

#: The one formula of the tree's joint values, compiled (numpy evaluates the same source).
_tree_joint_formula = njit(error_model="numpy", cache=True, nogil=True,
                           inline="always")(tree_joint_formula)


@njit(error_model="numpy", cache=True, nogil=True, boundscheck=False)
def joint_values_into(q, p, u, O_s, valid, lengths, zero, code, hinge, out):
    """:func:`athenakin.ros._frames.joint_values` of the valid readings, into ``out``.

    :func:`athenakin._mechanism_formulas.tree_joint_formula` compiled, element by element
    (the remainder of ``np.remainder``; libm's ``atan2`` and ``hypot``, which may differ from
    numpy's SIMD ones in the last bit: equal to 4e-15 rad, tested).

    Parameters
    ----------
    q : (n, 3); p : (n,); u : (n, 5); O_s : (n, 3)
    valid : (n,) bool
        Readings written (the others are left as they are).
    lengths : (7,) float64
        ``l1**2, l2, l3**2, l4, l5`` of the design, then 0, 0 (unused).
    zero : (J,) float64
        The URDF zero of each joint.
    code : (J,) int64
        What each joint measures (:data:`JOINT_CODES`).
    hinge : (J,) bool
        Hinges are wrapped to ``(-pi, pi]``.
    out : (n, J) float64
        May be a strided view.
    """
    l1sq, l2, l3sq, l4, l5 = lengths[0], lengths[1], lengths[2], lengths[3], lengths[4]
    two_pi = 2 * math.pi
    for i in range(q.shape[0]):
        if not valid[i]:
            continue
        a = _tree_joint_formula(q[i, 0], q[i, 1], q[i, 2], p[i], u[i, 0], u[i, 1], u[i, 2],
                                u[i, 3], u[i, 4], O_s[i, 1], O_s[i, 2], l1sq, l2, l3sq, l4, l5)
        for j in range(code.shape[0]):
            x = a[code[j]] - zero[j]
            if hinge[j]:
                x = -((-x + math.pi) % two_pi) + math.pi
            out[i, j] = x
