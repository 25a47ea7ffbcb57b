"""Compiled parallel-module kernels (private): its FK and its IK from a position.

The IK stage (:func:`_pik_stage`) is shared with the whole-robot IK kernels of
:mod:`._ik_kernels`. Mirrors of :func:`athenakin.parallel.parallel_forward_kinematics` and
:func:`athenakin.parallel.parallel_ik_from_position` (same formulas, reason codes
and NaN policy); the closed form itself is :mod:`._module_form`'s.
"""

from __future__ import annotations

import math
import sys

import numpy as np

from .._backend import njit
from ..errors import Reason
from ..parallel._module import IK_ROUNDING_ULPS
from ._fk_kernels import CHUNK
from ._module_form import actuator_reason, module_closed_form
from ._scalar import atan2, finite_sum, hypot, parallel_residual, wrap_pi

__all__ = ["parallel_ik_position", "parallel_fk", "NK"]

_NONFINITE, _LINK = float(Reason.NONFINITE_INPUT), float(Reason.LINK_TOO_SHORT)
_TANGENT = float(Reason.CIRCLES_TANGENT)
_NOT_IMAGE = float(Reason.NOT_IN_MODULE_IMAGE)

_OPTS = dict(error_model="numpy", cache=True, nogil=True)

# --- parallel module IK (parallel_ik_from_position) --------------------------------------
# Rows of the IK scratch (flat, row * CHUNK + column).
_OX, _OY, _OZ, _PRE = 0, 1, 2, 3          # inputs of the parallel IK (O_s, earlier reason)
_Q1, _Q2, _Q3, _MODE, _REASON, _CT, _ST, _TH = 4, 5, 6, 7, 8, 9, 10, 11
_P, _U1, _U2, _U3, _U4, _U5, _RES = 12, 13, 14, 15, 16, 17, 18
_DX, _DY, _DZ = 19, 20, 21
_DO, _QE = 22, 23                        # error already in O_s (in); q_error (out)
NK = 24
#: parallel._module.IK_ROUNDING_ULPS times the machine epsilon.
_ROUND = IK_ROUNDING_ULPS * sys.float_info.epsilon


@njit(**_OPTS)
def _pik_stage(K, P, n):
    """parallel_ik_from_position for n columns (rows _OX.._PRE in, _Q1.._TH out)."""
    l1, l2, l3, l4, l5 = P[0], P[1], P[2], P[3], P[4]
    lo0, lo1, lo2, hi0, hi1, hi2, hs = P[5], P[6], P[7], P[8], P[9], P[10], P[11]
    for ii in range(n):
        pre = K[_PRE * CHUNK + ii]
        nanin = 0.0 if pre == 0.0 else math.nan
        ox = K[_OX * CHUNK + ii] + nanin
        oy = K[_OY * CHUNK + ii] + nanin
        oz = K[_OZ * CHUNK + ii] + nanin
        fin = (finite_sum(ox) + finite_sum(oy) + finite_sum(oz)) == 0.0
        px = ox if fin else 0.0
        py = oy if fin else 0.0
        pz = oz if fin else 0.0
        rho = hypot(py, pz)
        reason = _NONFINITE if not fin else _NOT_IMAGE if rho <= l4 else 0.0
        scale = max(abs(py), abs(pz))
        dr = _ROUND * ((scale + l1) + l4) + K[_DO * CHUNK + ii]
        r1 = rho - l4
        r1 = l1 if (r1 > l1) & (r1 - l1 <= dr) else r1
        h_abs = math.sqrt((l1 - r1) * (l1 + r1))
        # within rounding of |h| = l3: on it (parallel._module.position_ik)
        h_abs = l3 if (h_abs > l3) & (h_abs - l3 <= _h_error(r1, h_abs, dr)) else h_abs
        bad = (r1 > l1) | (h_abs > l3)
        reason = _LINK if (reason == 0.0) & bad else reason
        h_abs = 0.0 if h_abs * h_abs <= 2.0 * r1 * dr else h_abs
        ok = reason == 0.0
        mask = 0.0 if ok else math.nan
        h = hs * h_abs + mask
        xm = px + mask
        f = r1 / rho
        y = py * f + mask
        z = pz * f + mask
        m_y = math.sqrt(l3 * l3 - h * h) + l2
        q3 = hypot(y - m_y, z - l5)
        cross = m_y * z - l5 * y
        q1 = xm + h
        q2 = xm - h
        qe = _q_error(r1, h_abs, dr, l3) + _ROUND * abs(px)
        # within the error bound of a stroke limit: on it (parallel._module.position_ik)
        q1 = lo0 if (q1 < lo0) & (q1 >= lo0 - qe) else hi0 if (q1 > hi0) & (q1 <= hi0 + qe) else q1
        q2 = lo1 if (q2 < lo1) & (q2 >= lo1 - qe) else hi1 if (q2 > hi1) & (q2 <= hi1 + qe) else q2
        q3 = lo2 if (q3 < lo2) & (q3 >= lo2 - qe) else hi2 if (q3 > hi2) & (q3 <= hi2 + qe) else q3
        # parallel._module._actuator_checks on q (items that passed so far)
        act = actuator_reason(q1, q2, q3, P)
        reason = act if ok & (act != 0.0) else reason
        reason = pre if pre != 0.0 else reason
        vmask = 0.0 if reason == 0.0 else math.nan
        hh = hypot(y, z)
        K[_Q1 * CHUNK + ii] = q1 + vmask
        K[_Q2 * CHUNK + ii] = q2 + vmask
        K[_Q3 * CHUNK + ii] = q3 + vmask
        K[_MODE * CHUNK + ii] = 1.0 if cross >= 0.0 else -1.0
        K[_REASON * CHUNK + ii] = reason
        K[_CT * CHUNK + ii] = z / hh + vmask
        K[_ST * CHUNK + ii] = -y / hh + vmask
        K[_TH * CHUNK + ii] = atan2(-y, z) + vmask
        K[_QE * CHUNK + ii] = qe + vmask


@njit(**_OPTS)
def _q_error(r1, h_abs, dr, l3):
    """parallel._module._q_error: bound on the error of q for an error dr of r1."""
    dh = _h_error(r1, h_abs, dr)
    hd = h_abs + dh
    s3 = l3 * l3 - hd * hd
    s3 = math.sqrt(s3) if s3 > 0.0 else 0.0
    near = math.sqrt((2.0 * h_abs + dh) * dh)
    dmy = min(hd * dh / s3, near) if s3 > 0.0 else near
    return (2.0 * dr + dh) + dmy


@njit(**_OPTS)
def _h_error(r1, h_abs, dr):
    """parallel._module._h_error: bound on the error of |h| for an error dr of r1."""
    r1p = r1 if r1 > 0.0 else 0.0
    return 2.0 * r1p * dr / (math.sqrt(h_abs * h_abs + 2.0 * r1p * dr) + h_abs) + dr


@njit(**_OPTS)
def parallel_ik_position(Os, P, q, mode, theta, valid, reason, qe):
    """:func:`athenakin.parallel.parallel_ik_from_position` for O (N, 3)."""
    N = Os.shape[0]
    K = np.empty(NK * CHUNK)
    for c0 in range(0, N, CHUNK):
        n = min(CHUNK, N - c0)
        for ii in range(n):
            for c in range(3):
                K[(_OX + c) * CHUNK + ii] = Os[c0 + ii, c]
            K[_PRE * CHUNK + ii] = 0.0
            K[_DO * CHUNK + ii] = 0.0
        _pik_stage(K, P, n)
        for ii in range(n):
            i = c0 + ii
            for c in range(3):
                q[i, c] = K[(_Q1 + c) * CHUNK + ii]
            r = K[_REASON * CHUNK + ii]
            mode[i] = np.int64(K[_MODE * CHUNK + ii]) if r == 0.0 else 0
            theta[i] = K[_TH * CHUNK + ii]
            qe[i] = K[_QE * CHUNK + ii]
            reason[i] = np.int8(r)
            valid[i] = r == 0.0



# --- parallel module FK (parallel_forward_kinematics) ------------------------------------
@njit(**_OPTS)
def parallel_fk(q, P, ttol, valid, reason, T_b_i, T_b_s, theta, r1o, myo, wo, halfo, reso):
    """:func:`athenakin.parallel.parallel_forward_kinematics` for q (N, 3)."""
    l1, l4 = P[0], P[3]
    for i in range(q.shape[0]):
        pr, tangent, xm, _, q3, r1, m_y, d, k, half, by, bz, ey, ez = module_closed_form(
            q[i, 0], q[i, 1], q[i, 2], P, ttol)
        ok = pr == 0.0
        r1o[i] = r1
        myo[i] = m_y
        wo[i] = m_y * m_y * k
        halfo[i] = half
        nan = 0.0 if ok else math.nan
        a = (0.0 if tangent else half) + nan
        xm = xm + nan
        r1n = r1 + nan
        pres = parallel_residual(r1, q3, d, k, l1, l4, tangent) + nan
        for m in range(2):
            sr = pr if m == 0 else (_TANGENT if tangent else pr)
            reason[i, m] = np.int8(sr)
            valid[i, m] = sr == 0.0
            mask = 0.0 if sr == 0.0 else math.nan
            reso[i, m] = pres + mask
            sa = a if m == 0 else -a
            y = by + sa * ey
            z = bz + sa * ez
            cy = y / r1n
            cz = z / r1n
            theta[i, m] = wrap_pi(atan2(-cy, cz)) + mask
            for F, off in ((T_b_i, 0.0), (T_b_s, l4)):
                F[i, m, 0, 0] = 1.0 + mask
                F[i, m, 0, 1] = mask
                F[i, m, 0, 2] = mask
                F[i, m, 0, 3] = xm + mask
                F[i, m, 1, 0] = mask
                F[i, m, 1, 1] = cz + mask
                F[i, m, 1, 2] = cy + mask
                F[i, m, 1, 3] = (y + off * cy if off != 0.0 else y) + mask
                F[i, m, 2, 0] = mask
                F[i, m, 2, 1] = -cy + mask
                F[i, m, 2, 2] = cz + mask
                F[i, m, 2, 3] = (z + off * cz if off != 0.0 else z) + mask
                F[i, m, 3, 0] = mask
                F[i, m, 3, 1] = mask
                F[i, m, 3, 2] = mask
                F[i, m, 3, 3] = 1.0 + mask


