"""Compiled inverse kinematics kernels of the whole robot (private).

Mirrors of :func:`athenakin.inverse_kinematics`, :func:`athenakin.q_from_instrument`,
:func:`athenakin.q_from_tool_tip` (same formulas,
same reason codes, same NaN policy). As in :mod:`._fk_stages` the pose loop
runs in chunks: a gather pass copies the inputs into a flat structure-of-arrays
scratch, a vectorised pass computes, a last pass writes the caller's arrays.

The controller forms are trig-free (two ``hypot``, two square roots per pose).
The paper form needs ``sin``/``cos`` of the given ``u3, u4, u5`` (the branch-free
Cephes :func:`._scalar.sincos`) and the angles ``u1, u2`` (branch-free ``atan``);
the orientation of the parallel module, ``Rx(theta)``, is formed from the
position of ``O_s`` without any angle (``cos theta = z / hypot(y, z)``).
"""

from __future__ import annotations

import math

import numpy as np

from .._backend import njit, prange
from ..chain._ups import P_ZERO_TOL
from ..errors import Reason
from ..robot._ik import IK_Q_ERROR_MAX
from ._fk_kernels import FLAG_T_NONFINITE, rigid_flags
from ._fk_stages import CHUNK, gather_items
from ._parallel_kernels import (
    _CT,
    _DO,
    _DX,
    _DY,
    _DZ,
    _MODE,
    _OX,
    _OY,
    _OZ,
    _P,
    _PRE,
    _Q1,
    _Q2,
    _Q3,
    _QE,
    _REASON,
    _RES,
    _ROUND,
    _ST,
    _U1,
    _U2,
    _U3,
    _U4,
    _U5,
    NK,
    _pik_stage,
)
from ._scalar import (
    atan2,
    finite_sum,
    hypot,
    nanmax2,
    sincos,
    wrap_mod,
)

__all__ = ["ik_paper", "ik_paper_parallel", "ik_line", "ik_line_parallel", "FLAG_SLOW",
           "FLAG_V_NONFINITE", "FLAG_P_NONFINITE", "FLAG_ZERO_DIRECTION", "WRAP_EXACT_MAX"]

# Reason codes (athenakin.errors.Reason) as floats.
_NONFINITE, _TANGENT = float(Reason.NONFINITE_INPUT), float(Reason.CIRCLES_TANGENT)
_CLOSURE = float(Reason.CLOSURE_FAILED)
_IK_SINGULAR, _INSERTION = float(Reason.IK_SINGULAR), float(Reason.INSERTION_RANGE)
_P_ZERO = float(Reason.SERIAL_P_ZERO)
#: athenakin.robot.IK_Q_ERROR_MAX (m).
_QE_MAX = IK_Q_ERROR_MAX
#: athenakin.chain.P_ZERO_TOL (m): |p| at or below which the instrument axis is undefined.
_P_ZERO_TOL = P_ZERO_TOL

#: Flags returned by the IK kernels (FLAG_NONRIGID = 1 and FLAG_T_NONFINITE = 4 as in FK).
FLAG_SLOW = 8              # some |u| > WRAP_EXACT_MAX: recompute those items in numpy
FLAG_V_NONFINITE = 16      # direction / tip / u345 holds NaN or inf
FLAG_P_NONFINITE = 32      # p holds NaN or inf
FLAG_ZERO_DIRECTION = 64   # a direction vector is zero
#: Largest ``|u|`` (rad) for which the kernels reproduce numpy's ``mod`` and ``sin``/``cos``
#: to 1e-12; items beyond are flagged (FLAG_SLOW) and recomputed by the caller.
WRAP_EXACT_MAX = 1.0e3

_OPTS = dict(error_model="numpy", cache=True, nogil=True)
_INLINE = dict(_OPTS, inline="always")

# --- controller forms (q_from_instrument, q_from_tool_tip) ------------------------------
@njit(**_OPTS)
def _line_gather(T, V, Pp, c0, n, kind, L, G):
    """Inputs of the controller forms into G: T (16), V (3), p (1)."""
    for ii in range(n):
        i = c0 + ii
        it = i if T.shape[0] > 1 else 0
        iv = i if V.shape[0] > 1 else 0
        ip = i if Pp.shape[0] > 1 else 0
        for r in range(3):
            for c in range(4):
                G[(4 * r + c) * CHUNK + ii] = T[it, r, c]
        for c in range(3):
            G[(12 + c) * CHUNK + ii] = V[iv, c]
        G[15 * CHUNK + ii] = Pp[ip] if kind == 0 else L


@njit(**_OPTS)
def _line_stage(G, K, kind, n):
    """O_s = RCM - p R d (d normalised; for kind 1, d and p from the tool tip)."""
    for ii in range(n):
        vx, vy, vz = G[12 * CHUNK + ii], G[13 * CHUNK + ii], G[14 * CHUNK + ii]
        # scale by the largest component first: no underflow / overflow of the norm
        m = max(abs(vx), max(abs(vy), abs(vz)))
        ms = m if m > 0.0 else 1.0
        sx, sy, sz = vx / ms, vy / ms, vz / ms
        sn = math.sqrt((sx * sx + sy * sy) + sz * sz)
        s = m * sn
        L = G[15 * CHUNK + ii]
        if kind == 1:
            pre = _IK_SINGULAR if m == 0.0 else _INSERTION if s >= L else 0.0
            dx = sx / sn if m > 0.0 else 0.0
            dy = sy / sn if m > 0.0 else 0.0
            dz = sz / sn if m > 0.0 else 1.0
            p = L - s
        else:
            p = L
            pre = _P_ZERO if abs(p) <= _P_ZERO_TOL else 0.0
            dx, dy, dz = sx / sn, sy / sn, sz / sn
        bx = (G[0 * CHUNK + ii] * dx + G[1 * CHUNK + ii] * dy) + G[2 * CHUNK + ii] * dz
        by = (G[4 * CHUNK + ii] * dx + G[5 * CHUNK + ii] * dy) + G[6 * CHUNK + ii] * dz
        bz = (G[8 * CHUNK + ii] * dx + G[9 * CHUNK + ii] * dy) + G[10 * CHUNK + ii] * dz
        K[_OX * CHUNK + ii] = G[3 * CHUNK + ii] - p * bx
        K[_OY * CHUNK + ii] = G[7 * CHUNK + ii] - p * by
        K[_OZ * CHUNK + ii] = G[11 * CHUNK + ii] - p * bz
        K[_PRE * CHUNK + ii] = pre
        K[_DO * CHUNK + ii] = 0.0
        K[_P * CHUNK + ii] = p
        K[_DX * CHUNK + ii] = bx
        K[_DY * CHUNK + ii] = by
        K[_DZ * CHUNK + ii] = bz


@njit(**_OPTS)
def _line_store(K, c0, n, q, p, d_b, O_s, mode, valid, reason, qe):
    for ii in range(n):
        i = c0 + ii
        r = K[_REASON * CHUNK + ii]
        mask = 0.0 if r == 0.0 else math.nan
        q[i, 0] = K[_Q1 * CHUNK + ii]
        q[i, 1] = K[_Q2 * CHUNK + ii]
        q[i, 2] = K[_Q3 * CHUNK + ii]
        p[i] = K[_P * CHUNK + ii] + mask
        d_b[i, 0] = K[_DX * CHUNK + ii] + mask
        d_b[i, 1] = K[_DY * CHUNK + ii] + mask
        d_b[i, 2] = K[_DZ * CHUNK + ii] + mask
        O_s[i, 0] = K[_OX * CHUNK + ii] + mask
        O_s[i, 1] = K[_OY * CHUNK + ii] + mask
        O_s[i, 2] = K[_OZ * CHUNK + ii] + mask
        qe[i] = K[_QE * CHUNK + ii] + mask
        mode[i] = np.int64(K[_MODE * CHUNK + ii]) if r == 0.0 else 0
        reason[i] = np.int8(r)
        valid[i] = r == 0.0


@njit(**_OPTS)
def _line_chunk(T, V, Pp, P, kind, G, K, c0, n, q, p, d_b, O_s, mode, valid, reason, qe):
    _line_gather(T, V, Pp, c0, n, kind, P[12], G)
    _line_stage(G, K, kind, n)
    _pik_stage(K, P, n)
    _line_store(K, c0, n, q, p, d_b, O_s, mode, valid, reason, qe)


@njit(**_OPTS)
def _line_flags(T, V, Pp, kind, rot_tol):
    flags = rigid_flags(T, rot_tol)
    for i in range(V.shape[0]):
        if not (finite_sum(V[i, 0]) + finite_sum(V[i, 1]) + finite_sum(V[i, 2])) == 0.0:
            flags |= FLAG_V_NONFINITE
        elif kind == 0 and V[i, 0] == 0.0 and V[i, 1] == 0.0 and V[i, 2] == 0.0:
            flags |= FLAG_ZERO_DIRECTION
    if kind == 0:
        for i in range(Pp.shape[0]):
            if not finite_sum(Pp[i]) == 0.0:
                flags |= FLAG_P_NONFINITE
    return flags


@njit(**_OPTS)
def ik_line(T, V, Pp, P, kind, rot_tol, q, p, d_b, O_s, mode, valid, reason, qe):
    """Controller-form IK: kind 0 = (direction V, insertion Pp), kind 1 = tool tip V.

    Parameters
    ----------
    T : (NT, 4, 4); V : (NV, 3); Pp : (NP,) -- each with 1 or N rows (broadcast)
    P : (13,) design parameters; kind : int; rot_tol : rigidity tolerance
    q, d_b, O_s : (N, 3); p, qe : (N,); mode : (N,) int64; valid : (N,) bool;
    reason : (N,) int8

    Returns
    -------
    int
        FLAG_* bits about the input (the caller raises the reference's errors).
    """
    flags = _line_flags(T, V, Pp, kind, rot_tol)
    if flags & (FLAG_T_NONFINITE | FLAG_V_NONFINITE | FLAG_P_NONFINITE | FLAG_ZERO_DIRECTION):
        return flags    # the caller raises the reference's error
    N = reason.shape[0]
    G = np.empty(16 * CHUNK)
    K = np.empty(NK * CHUNK)
    for c0 in range(0, N, CHUNK):
        _line_chunk(T, V, Pp, P, kind, G, K, c0, min(CHUNK, N - c0), q, p, d_b, O_s, mode,
                    valid, reason, qe)
    return flags


@njit(parallel=True, **_OPTS)
def ik_line_parallel(T, V, Pp, P, kind, rot_tol, q, p, d_b, O_s, mode, valid, reason, qe):
    """:func:`ik_line` with the chunks spread over numba's threads."""
    flags = _line_flags(T, V, Pp, kind, rot_tol)
    if flags & (FLAG_T_NONFINITE | FLAG_V_NONFINITE | FLAG_P_NONFINITE | FLAG_ZERO_DIRECTION):
        return flags    # the caller raises the reference's error
    N = reason.shape[0]
    nchunk = (N + CHUNK - 1) // CHUNK
    for ci in prange(nchunk):
        G = np.empty(16 * CHUNK)
        K = np.empty(NK * CHUNK)
        c0 = ci * CHUNK
        _line_chunk(T, V, Pp, P, kind, G, K, c0, min(CHUNK, N - c0), q, p, d_b, O_s, mode,
                    valid, reason, qe)
    return flags


# --- paper form (inverse_kinematics) -----------------------------------------------------
_NGP = 20   # gathered: T (16), u345 (3), finite (1)


@njit(**_OPTS)
def _paper_gather(T, U, c0, n, G):
    """T (rows 0-15), u345 (16-18) and their finiteness (19) of items c0..c0+n-1 into ``G``."""
    gather_items(T, U, c0, n, G, 0, 16, 19, True)


@njit(**_INLINE)
def _wrist(u3, u4, u5):
    """Rows of ``W = R(u3, u4) Rz(u5)``, the wrist's rotation."""
    s3, c3 = sincos(u3)
    s4, c4 = sincos(u4)
    s5, c5 = sincos(u5)
    return (c3 * c4 * c5 + s3 * s5, c3 * c4 * (-s5) + s3 * c5, c3 * s4,
            s3 * c4 * c5 + (-c3) * s5, s3 * c4 * (-s5) + (-c3) * c5, s3 * s4,
            s4 * c5, s4 * (-s5), -c4)


@njit(**_INLINE)
def _times_transpose(e00, e01, e02, e10, e11, e12, e20, e21, e22,
                     w00, w01, w02, w10, w11, w12, w20, w21, w22):
    """Rows of ``E W^T`` (``R_b_w = R_b_e W^T``)."""
    return ((e00 * w00 + e01 * w01) + e02 * w02, (e00 * w10 + e01 * w11) + e02 * w12,
            (e00 * w20 + e01 * w21) + e02 * w22, (e10 * w00 + e11 * w01) + e12 * w02,
            (e10 * w10 + e11 * w11) + e12 * w12, (e10 * w20 + e11 * w21) + e12 * w22,
            (e20 * w00 + e21 * w01) + e22 * w02, (e20 * w10 + e21 * w11) + e22 * w12,
            (e20 * w20 + e21 * w21) + e22 * w22)


@njit(**_OPTS)
def _paper_stage1(G, K, stol, n):
    """From T_b_e and u345 to O_s (rows _OX.._PRE), p, the wrapped u3..u5 and R_b_w."""
    for ii in range(n):
        fin = G[19 * CHUNK + ii] != 0.0
        e00 = G[0 * CHUNK + ii] if fin else 1.0
        e01 = G[1 * CHUNK + ii] if fin else 0.0
        e02 = G[2 * CHUNK + ii] if fin else 0.0
        e03 = G[3 * CHUNK + ii] if fin else 0.0
        e10 = G[4 * CHUNK + ii] if fin else 0.0
        e11 = G[5 * CHUNK + ii] if fin else 1.0
        e12 = G[6 * CHUNK + ii] if fin else 0.0
        e13 = G[7 * CHUNK + ii] if fin else 0.0
        e20 = G[8 * CHUNK + ii] if fin else 0.0
        e21 = G[9 * CHUNK + ii] if fin else 0.0
        e22 = G[10 * CHUNK + ii] if fin else 1.0
        e23 = G[11 * CHUNK + ii] if fin else 0.0
        u3 = G[16 * CHUNK + ii] if fin else 0.0
        u4 = G[17 * CHUNK + ii] if fin else 0.0
        u5 = G[18 * CHUNK + ii] if fin else 0.0
        w00, w01, w02, w10, w11, w12, w20, w21, w22 = _wrist(u3, u4, u5)
        b00, b01, b02, b10, b11, b12, b20, b21, b22 = _times_transpose(
            e00, e01, e02, e10, e11, e12, e20, e21, e22,
            w00, w01, w02, w10, w11, w12, w20, w21, w22)
        ny = hypot(b11, b21)
        nd = ny if ny > 0.0 else 1.0
        n0 = b11 / nd
        n1 = b21 / nd
        den = b12 * n0 + b22 * n1
        sing = (ny <= stol) | (abs(den) <= stol)
        pre = _NONFINITE if not fin else _IK_SINGULAR if sing else 0.0
        p = (e13 * n0 + e23 * n1) / (1.0 if sing else den)
        K[_DO * CHUNK + ii] = paper_o_error(e03, e13, e23, p, ny, den)
        K[_OX * CHUNK + ii] = e03 - p * b02
        K[_OY * CHUNK + ii] = e13 - p * b12
        K[_OZ * CHUNK + ii] = e23 - p * b22
        K[_PRE * CHUNK + ii] = pre
        K[_P * CHUNK + ii] = p
        K[_U3 * CHUNK + ii] = wrap_mod(u3)
        K[_U4 * CHUNK + ii] = wrap_mod(u4)
        K[_U5 * CHUNK + ii] = wrap_mod(u5)
        # keep R_b_w and W for stage 2 (in G, over T_b_e's rotation entries and spare rows)
        G[0 * CHUNK + ii] = b00
        G[1 * CHUNK + ii] = b01
        G[2 * CHUNK + ii] = b02
        G[4 * CHUNK + ii] = b10
        G[5 * CHUNK + ii] = b11
        G[6 * CHUNK + ii] = b12
        G[8 * CHUNK + ii] = b20
        G[9 * CHUNK + ii] = b21
        G[10 * CHUNK + ii] = b22
        G[12 * CHUNK + ii] = e00
        G[13 * CHUNK + ii] = e01
        G[14 * CHUNK + ii] = e02
        G[15 * CHUNK + ii] = e10
        G[16 * CHUNK + ii] = e11
        G[17 * CHUNK + ii] = e12
        G[18 * CHUNK + ii] = e20
        G[19 * CHUNK + ii] = e21
        G[20 * CHUNK + ii] = e22
        G[21 * CHUNK + ii] = e03
        G[22 * CHUNK + ii] = e13
        G[23 * CHUNK + ii] = e23
        G[24 * CHUNK + ii] = w00
        G[25 * CHUNK + ii] = w01
        G[26 * CHUNK + ii] = w02
        G[27 * CHUNK + ii] = w10
        G[28 * CHUNK + ii] = w11
        G[29 * CHUNK + ii] = w12
        G[30 * CHUNK + ii] = w20
        G[31 * CHUNK + ii] = w21
        G[32 * CHUNK + ii] = w22


_NGP2 = 33


@njit(**_OPTS)
def paper_o_error(cx, cy, cz, p, ny, den):
    """Bound (m) on the error of O_s = c - p z_w in the paper-form IK (robot._ik mirror).

    ``n = y_w / |y_w|`` carries a relative error ``eps / ny`` and ``p = (c . n) / den``
    divides it by ``den``: ``dp ~ eps (|c| + |p|) (1 + 1 / ny) / |den|``.
    """
    s = ((abs(cx) + abs(cy)) + abs(cz)) + abs(p)
    a = 1.0 + 1.0 / ny if ny > 0.0 else math.inf
    ad = abs(den)
    return _ROUND * s * (a / ad) if ad > 0.0 else math.inf


@njit(**_OPTS)
def _paper_stage2(G, K, ctol, n):
    """u1, u2 from R_b_s^T R_b_w, then the closure check of T_b_s T_s_e(p, u)."""
    for ii in range(n):
        ct, st = K[_CT * CHUNK + ii], K[_ST * CHUNK + ii]
        b01 = G[1 * CHUNK + ii]
        b10, b11, b12 = G[4 * CHUNK + ii], G[5 * CHUNK + ii], G[6 * CHUNK + ii]
        b20, b21, b22 = G[8 * CHUNK + ii], G[9 * CHUNK + ii], G[10 * CHUNK + ii]
        r01 = b01
        r11 = ct * b11 + st * b21
        r20 = -st * b10 + ct * b20
        r22 = -st * b12 + ct * b22
        K[_U1 * CHUNK + ii] = wrap_mod(atan2(r01, -r11))
        K[_U2 * CHUNK + ii] = wrap_mod(atan2(r20, -r22))
        h1 = hypot(r01, r11)
        h2 = hypot(r20, r22)
        c1, s1 = -r11 / h1, r01 / h1
        c2, s2 = -r22 / h2, r20 / h2
        # R_s_e = R(u1, u2) W, t_s_e = p z(u1, u2); then T_b_s @ T_s_e against T_b_e
        a00, a01, a02 = c1 * c2, s1, c1 * s2
        a10, a11, a12 = s1 * c2, -c1, s1 * s2
        a20, a22 = s2, -c2
        w00, w01, w02 = G[24 * CHUNK + ii], G[25 * CHUNK + ii], G[26 * CHUNK + ii]
        w10, w11, w12 = G[27 * CHUNK + ii], G[28 * CHUNK + ii], G[29 * CHUNK + ii]
        w20, w21, w22 = G[30 * CHUNK + ii], G[31 * CHUNK + ii], G[32 * CHUNK + ii]
        m00 = (a00 * w00 + a01 * w10) + a02 * w20
        m01 = (a00 * w01 + a01 * w11) + a02 * w21
        m02 = (a00 * w02 + a01 * w12) + a02 * w22
        m10 = (a10 * w00 + a11 * w10) + a12 * w20
        m11 = (a10 * w01 + a11 * w11) + a12 * w21
        m12 = (a10 * w02 + a11 * w12) + a12 * w22
        m20 = a20 * w00 + a22 * w20
        m21 = a20 * w01 + a22 * w21
        m22 = a20 * w02 + a22 * w22
        p = K[_P * CHUNK + ii]
        tx, ty, tz = p * a02, p * a12, p * a22
        # R_b_s = [[1, 0, 0], [0, ct, -st], [0, st, ct]]
        res = abs(m00 - G[12 * CHUNK + ii])
        res = nanmax2(res, abs(m01 - G[13 * CHUNK + ii]))
        res = nanmax2(res, abs(m02 - G[14 * CHUNK + ii]))
        res = nanmax2(res, abs((ct * m10 - st * m20) - G[15 * CHUNK + ii]))
        res = nanmax2(res, abs((ct * m11 - st * m21) - G[16 * CHUNK + ii]))
        res = nanmax2(res, abs((ct * m12 - st * m22) - G[17 * CHUNK + ii]))
        res = nanmax2(res, abs((st * m10 + ct * m20) - G[18 * CHUNK + ii]))
        res = nanmax2(res, abs((st * m11 + ct * m21) - G[19 * CHUNK + ii]))
        res = nanmax2(res, abs((st * m12 + ct * m22) - G[20 * CHUNK + ii]))
        res = nanmax2(res, abs((tx + K[_OX * CHUNK + ii]) - G[21 * CHUNK + ii]))
        res = nanmax2(res, abs(((ct * ty - st * tz) + K[_OY * CHUNK + ii]) - G[22 * CHUNK + ii]))
        res = nanmax2(res, abs(((st * ty + ct * tz) + K[_OZ * CHUNK + ii]) - G[23 * CHUNK + ii]))
        r = K[_REASON * CHUNK + ii]
        r = _IK_SINGULAR if (r == 0.0) & (not (K[_QE * CHUNK + ii] <= _QE_MAX)) else r
        r = _CLOSURE if (r == 0.0) & (not (res <= ctol)) else r
        K[_REASON * CHUNK + ii] = r
        K[_RES * CHUNK + ii] = res


@njit(**_OPTS, inline="always")
def _store_row(Tbs, i, r, a, b, c, d):
    """``Tbs[i, r] = (a, b, c, d)``."""
    Tbs[i, r, 0] = a
    Tbs[i, r, 1] = b
    Tbs[i, r, 2] = c
    Tbs[i, r, 3] = d


@njit(**_OPTS, inline="always")
def _store_T_b_s(K, ii, mask, Tbs, i):
    """Write the pose of ``O_s`` of chunk column ``ii`` into ``Tbs[i]`` (NaN when ``mask`` is).

    ``[[1, 0, 0, x], [0, ct, -st, y], [0, st, ct, z], [0, 0, 0, 1]]`` (Eq. 10).
    """
    ct = K[_CT * CHUNK + ii] + mask
    st = K[_ST * CHUNK + ii] + mask
    one, zero = 1.0 + mask, mask
    _store_row(Tbs, i, 0, one, zero, zero, K[_OX * CHUNK + ii] + mask)
    _store_row(Tbs, i, 1, zero, ct, -st, K[_OY * CHUNK + ii] + mask)
    _store_row(Tbs, i, 2, zero, st, ct, K[_OZ * CHUNK + ii] + mask)
    _store_row(Tbs, i, 3, zero, zero, zero, one)


@njit(**_OPTS, inline="always")
def _store_q(K, ii, q, i):
    """Write ``q`` of chunk column ``ii`` into ``q[i]`` (NaN where it has no solution).

    Returns the column's reason code and its NaN mask (0.0, or NaN where the reason is
    not 0), which the other fields of the column are stored with.
    """
    r = K[_REASON * CHUNK + ii]
    mask = 0.0 if r == 0.0 else math.nan
    q[i, 0] = K[_Q1 * CHUNK + ii] + mask
    q[i, 1] = K[_Q2 * CHUNK + ii] + mask
    q[i, 2] = K[_Q3 * CHUNK + ii] + mask
    return r, mask


@njit(**_OPTS)
def _paper_store(K, c0, n, q, p, u, mode, Tbs, res, valid, reason, qe):
    for ii in range(n):
        i = c0 + ii
        r, mask = _store_q(K, ii, q, i)
        p[i] = K[_P * CHUNK + ii] + mask
        for c in range(5):
            u[i, c] = K[(_U1 + c) * CHUNK + ii] + mask
        mode[i] = np.int64(K[_MODE * CHUNK + ii]) if r == 0.0 else 0
        _store_T_b_s(K, ii, mask, Tbs, i)
        res[i] = K[_RES * CHUNK + ii] + mask
        qe[i] = K[_QE * CHUNK + ii] + mask
        reason[i] = np.int8(r)
        valid[i] = r == 0.0


@njit(**_OPTS)
def _paper_chunk(T, U, P, stol, ctol, G, K, c0, n, q, p, u, mode, Tbs, res, valid, reason,
                 qe):
    _paper_gather(T, U, c0, n, G)
    _paper_stage1(G, K, stol, n)
    _pik_stage(K, P, n)
    _paper_stage2(G, K, ctol, n)
    _paper_store(K, c0, n, q, p, u, mode, Tbs, res, valid, reason, qe)


@njit(**_OPTS)
def _paper_flags(T, U, rot_tol):
    flags = rigid_flags(T, rot_tol)
    for i in range(U.shape[0]):
        s = 0.0
        big = False
        for c in range(3):
            s += finite_sum(U[i, c])
            big = big | (abs(U[i, c]) > WRAP_EXACT_MAX)
        if not s == 0.0:
            flags |= FLAG_V_NONFINITE
        elif big:
            flags |= FLAG_SLOW
    return flags


@njit(**_OPTS)
def ik_paper(T, U, P, stol, ctol, rot_tol, q, p, u, mode, Tbs, res, valid, reason, qe):
    """Paper-form IK (inverse_kinematics) of N = max(len(T), len(U)) items.

    Parameters
    ----------
    T : (NT, 4, 4); U : (NU, 3) -- 1 or N rows each
    P : (13,) design parameters; stol, ctol : singular and closure tolerances
    q : (N, 3); p, res, qe : (N,); u : (N, 5); mode : (N,) int64; Tbs : (N, 4, 4);
    valid : (N,) bool; reason : (N,) int8

    Returns
    -------
    int
        FLAG_* bits (FLAG_SLOW: some ``|u| > WRAP_EXACT_MAX``, recompute those items).
    """
    N = reason.shape[0]
    G = np.empty(_NGP2 * CHUNK)
    K = np.empty(NK * CHUNK)
    for c0 in range(0, N, CHUNK):
        _paper_chunk(T, U, P, stol, ctol, G, K, c0, min(CHUNK, N - c0), q, p, u, mode, Tbs,
                     res, valid, reason, qe)
    return _paper_flags(T, U, rot_tol)


@njit(parallel=True, **_OPTS)
def ik_paper_parallel(T, U, P, stol, ctol, rot_tol, q, p, u, mode, Tbs, res, valid, reason,
                      qe):
    """:func:`ik_paper` with the chunks spread over numba's threads."""
    N = reason.shape[0]
    nchunk = (N + CHUNK - 1) // CHUNK
    for ci in prange(nchunk):
        G = np.empty(_NGP2 * CHUNK)
        K = np.empty(NK * CHUNK)
        c0 = ci * CHUNK
        _paper_chunk(T, U, P, stol, ctol, G, K, c0, min(CHUNK, N - c0), q, p, u, mode, Tbs,
                     res, valid, reason, qe)
    return _paper_flags(T, U, rot_tol)
