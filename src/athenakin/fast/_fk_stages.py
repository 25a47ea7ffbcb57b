"""The stages of the compiled forward kinematics (private): one chunk of poses, per mode.

The arithmetic mirrors :func:`athenakin.forward_kinematics` operation by
operation (same formulas, same order of the floating-point operations where
numpy's order is defined), with three differences that change no result
beyond rounding:

* the 8 serial slots of an assembly mode are sign flips of one another
  (``p -> -p`` negates rows 1, 2 of ``W = R(u1, u2)^T R_s_e``, the U-joint
  branch rows 0, 1; negation is exact in floating point), so ``W``, ``|sin u4|``
  and the closure residual are computed once per mode, and each angle once per
  distinct pair of signs;
* angles come from the branch-free ``atan`` of :mod:`._scalar` (no libm call),
  and the closure check rebuilds ``T_s_e`` from the cosines and sines directly
  (``cos(atan2(s, c)) = c / hypot(s, c)``) instead of calling ``cos``/``sin``
  (the reference's sequence is kept: ``u2`` from the projection on the plane ``u1``
  fixes, ``u4`` likewise, ``u5`` from what ``u3, u4`` leave of ``W``);
* the parallel module and the serial chain are evaluated for every pose
  without branches, and invalid results are masked afterwards.

Work per pose: 10 ``atan`` (5 per mode), 26 square roots, about 50 divisions
and 650 multiply-adds; no transcendental library call. The pose loop runs in
chunks of :data:`CHUNK`: this module's pass (:func:`fk_chunk`: gather, the parallel
module, the serial chain of each assembly mode) writes per-mode values into a
structure-of-arrays scratch; the entry kernels of :mod:`._fk_kernels` and
:mod:`._fk_sized` expand them into the 16 slots.
"""

from __future__ import annotations

import math
import sys

import numpy as np

from .._backend import njit
from ..chain._ups import CLOSURE_ULPS, DEGENERATE_ULPS
from ..errors import Reason
from ._module_form import module_closed_form
from ._scalar import atan2_from_q1, atan_q1, finite_sum, hypot, nanmax2, parallel_residual

__all__ = ["CHUNK", "MS", "NSH", "NG", "scratch", "gather", "gather_items", "fk_chunk",
           "mode_reason"]


#: Poses per chunk of the two-pass loop (the scratch holds 74 doubles per pose).
CHUNK = 64

# Reason codes (athenakin.errors.Reason), as floats in the scratch.
_NONFINITE, _TANGENT = float(Reason.NONFINITE_INPUT), float(Reason.CIRCLES_TANGENT)
_P_ZERO, _UJOINT = float(Reason.SERIAL_P_ZERO), float(Reason.UJOINT_SINGULAR)
_WRIST, _CLOSURE = float(Reason.WRIST_SINGULAR), float(Reason.CLOSURE_FAILED)
#: chain.DEGENERATE_ULPS times the machine epsilon.
_DEG_ROUND = DEGENERATE_ULPS * sys.float_info.epsilon
#: chain.CLOSURE_ULPS times the machine epsilon: the closure test's rounding allowance.
_CLOSE_ROUND = CLOSURE_ULPS * sys.float_info.epsilon

# Scratch rows per mode (offset MS * m) and shared rows.
_R, _PR, _NN, _RES = 0, 1, 2, 3
_V1 = 4      # 2 values, index f (f = 0: sig * rs = +1)
_V2 = 6      # 4 values, index 2 b + r
_V3 = 10     # 4 values, index 2 g + r (g = 0: tau * sig = +1)
_V4 = 14     # 4 values, index 2 w + r
_V5 = 18     # 2 values, index h (h = 0: tau * rs = +1)
_YS, _ZS, _CY, _CZ, _Y, _Z = 20, 21, 22, 23, 24, 25
MS = 26
# Rows of the shared scratch: x_M and r1 of the parallel module.
_XM, _R1, _PRES = 0, 1, 2      # _PRES: closure error of a merged (tangent) mode, m
NSH = 3
# Rows of the gathered input: q (3), T_b_e row-major (16), T finite (1).
_GQ, _GT, _GFIN = 0, 3, 19
NG = 20
# Scratch arrays are flat, row-major (row * CHUNK + column) with CHUNK a compile-time
# constant: LLVM then proves that rows do not overlap and vectorises the pose loops.

_OPTS = dict(error_model="numpy", cache=True, nogil=True)
#: The helpers of the stages, inlined into them (named steps, the same machine code).
_INLINE = dict(_OPTS, inline="always")


@njit(**_OPTS)
def scratch():
    """Fresh scratch arrays ``G, SH, S0, S1`` of one chunk (flat, row-major)."""
    buf = np.empty((NG + NSH + 2 * MS) * CHUNK)     # one allocation, four views
    a, b, c = NG * CHUNK, (NG + NSH) * CHUNK, (NG + NSH + MS) * CHUNK
    return buf[:a], buf[a:b], buf[b:c], buf[c:]


@njit(**_OPTS)
def _rot_pair(ca, sa, cb, sb):
    """Rows of ``R(a, b) = Rz(a) Rx(pi/2) Rz(b) Rx(pi/2)`` (chain._ups.rotation_u_pair)."""
    return (ca * cb, sa, ca * sb, sa * cb, -ca, sa * sb, sb, 0.0, -cb)


@njit(**_INLINE)
def gather_items(T, V, c0, n, G, row_T, row_V, row_fin, v_finite):
    """Copy items c0..c0+n-1 into ``G`` columns: a pose and a 3-vector per item.

    ``T[i]`` (4 x 4, row-major) goes to rows ``row_T .. row_T + 15``, ``V[i]`` to rows
    ``row_V .. row_V + 2`` (``T`` or ``V`` may have a single row: broadcast); row
    ``row_fin`` is 1.0 where ``T[i]`` (and ``V[i]`` when ``v_finite``) is finite, else 0.0.
    Inlined, so that the rows are constants of the caller (LLVM vectorises the loop).
    """
    for ii in range(n):
        i = c0 + ii
        it = i if T.shape[0] > 1 else 0
        iv = i if V.shape[0] > 1 else 0
        s = 0.0
        for r in range(4):
            for c in range(4):
                x = T[it, r, c]
                G[(row_T + 4 * r + c) * CHUNK + ii] = x
                s += finite_sum(x)
        for c in range(3):
            x = V[iv, c]
            G[(row_V + c) * CHUNK + ii] = x
            if v_finite:
                s += finite_sum(x)
        G[row_fin * CHUNK + ii] = 1.0 if s == 0.0 else 0.0


@njit(**_OPTS)
def gather(q, T, c0, n, G):
    """Copy poses c0..c0+n-1 (q or T may have a single row: broadcast) into ``G`` columns."""
    gather_items(T, q, c0, n, G, _GT, _GQ, _GFIN, False)    # q's finiteness: _fk_kernels


@njit(**_OPTS)
def _parallel_stage(G, P, tol, SH, S0, S1, n):
    """Parallel module, both assembly modes (parallel_forward_kinematics) for n columns."""
    l1, l4 = P[0], P[3]
    ttol = tol[0]
    for ii in range(n):
        q1, q2, q3 = G[(_GQ) * CHUNK + ii], G[(_GQ + 1) * CHUNK + ii], G[(_GQ + 2) * CHUNK + ii]
        pr, tangent, xm, _, q3, r1, _, d, k, half, by, bz, ey, ez = module_closed_form(
            q1, q2, q3, P, ttol)
        nan = 0.0 if pr == 0.0 else math.nan
        a = (0.0 if tangent else half) + nan
        SH[_XM * CHUNK + ii] = xm + nan
        SH[_R1 * CHUNK + ii] = r1 + nan
        # parallel._module.parallel_residual: the error of O_s from the rounding of k (a
        # merged mode: up to the half-chord off the true intersections)
        SH[_PRES * CHUNK + ii] = parallel_residual(r1, q3, d, k, l1, l4, tangent)
        S0[_PR * CHUNK + ii] = pr
        S1[_PR * CHUNK + ii] = _TANGENT if tangent else pr
        S0[_Y * CHUNK + ii] = by + a * ey
        S0[_Z * CHUNK + ii] = bz + a * ez
        S1[_Y * CHUNK + ii] = by + (-a) * ey
        S1[_Z * CHUNK + ii] = bz + (-a) * ez


@njit(**_INLINE)
def _s_e(G, ii, xm, cy, cz, ys, zs):
    """The upper 3 rows of T_s_e = T_b_s^-1 @ T_b_e of column ``ii`` (T_b_e gathered in ``G``).

    T_b_s = [[1, 0, 0, xm], [0, cz, cy, ys], [0, -cy, cz, zs]].
    """
    t00, t01 = G[_GT * CHUNK + ii], G[(_GT + 1) * CHUNK + ii]
    t02, t03 = G[(_GT + 2) * CHUNK + ii], G[(_GT + 3) * CHUNK + ii]
    t10, t11 = G[(_GT + 4) * CHUNK + ii], G[(_GT + 5) * CHUNK + ii]
    t12, t13 = G[(_GT + 6) * CHUNK + ii], G[(_GT + 7) * CHUNK + ii]
    t20, t21 = G[(_GT + 8) * CHUNK + ii], G[(_GT + 9) * CHUNK + ii]
    t22, t23 = G[(_GT + 10) * CHUNK + ii], G[(_GT + 11) * CHUNK + ii]
    t30, t31 = G[(_GT + 12) * CHUNK + ii], G[(_GT + 13) * CHUNK + ii]
    t32, t33 = G[(_GT + 14) * CHUNK + ii], G[(_GT + 15) * CHUNK + ii]
    ti0 = -xm
    ti1 = -(cz * ys - cy * zs)
    ti2 = -(cy * ys + cz * zs)
    e00 = t00 + ti0 * t30
    e01 = t01 + ti0 * t31
    e02 = t02 + ti0 * t32
    e03 = t03 + ti0 * t33
    e10 = (cz * t10 - cy * t20) + ti1 * t30
    e11 = (cz * t11 - cy * t21) + ti1 * t31
    e12 = (cz * t12 - cy * t22) + ti1 * t32
    e13 = (cz * t13 - cy * t23) + ti1 * t33
    e20 = (cy * t10 + cz * t20) + ti2 * t30
    e21 = (cy * t11 + cz * t21) + ti2 * t31
    e22 = (cy * t12 + cz * t22) + ti2 * t32
    e23 = (cy * t13 + cz * t23) + ti2 * t33
    return e00, e01, e02, e03, e10, e11, e12, e13, e20, e21, e22, e23


@njit(**_INLINE)
def _closure_residual(A1, B1, c2, s2, A3, B3, c4, s4, c5, s5, nn, e00, e01, e02, e03, e10,
                      e11, e12, e13, e20, e21, e22, e23):
    """Largest deviation of the chain of the angle pairs (scaled by ``nn``) from T_s_e."""
    a00, a01, a02, a10, a11, a12, a20, a21, a22 = _rot_pair(A1, B1, c2, s2)
    bx0, bx1, bx2 = A3 * c4, B3 * c4, s4
    by0, by1 = B3, -A3
    bz0, bz1, bz2 = A3 * s4, B3 * s4, -c4
    w00, w10, w20 = c5 * bx0 + s5 * by0, c5 * bx1 + s5 * by1, c5 * bx2
    w01, w11, w21 = c5 * by0 - s5 * bx0, c5 * by1 - s5 * bx1, -(s5 * bx2)
    res = abs(((a00 * w00 + a01 * w10) + a02 * w20) - e00)
    res = nanmax2(res, abs(((a00 * w01 + a01 * w11) + a02 * w21) - e01))
    res = nanmax2(res, abs(((a00 * bz0 + a01 * bz1) + a02 * bz2) - e02))
    res = nanmax2(res, abs(((a10 * w00 + a11 * w10) + a12 * w20) - e10))
    res = nanmax2(res, abs(((a10 * w01 + a11 * w11) + a12 * w21) - e11))
    res = nanmax2(res, abs(((a10 * bz0 + a11 * bz1) + a12 * bz2) - e12))
    res = nanmax2(res, abs(((a20 * w00 + a21 * w10) + a22 * w20) - e20))
    res = nanmax2(res, abs(((a20 * w01 + a21 * w11) + a22 * w21) - e21))
    res = nanmax2(res, abs(((a20 * bz0 + a21 * bz1) + a22 * bz2) - e22))
    res = nanmax2(res, abs(nn * a02 - e03))
    res = nanmax2(res, abs(nn * a12 - e13))
    res = nanmax2(res, abs(nn * a22 - e23))
    return res


@njit(**_INLINE)
def _store_second_angle(Sm, row, ii, rho_b, z):
    """``atan2(+-rho_b, -+z)``, the four sign patterns of a pair's second angle, into ``Sm``.

    Rows ``row .. row + 3``: ``(rho_b, -z), (rho_b, z), (-rho_b, -z), (-rho_b, z)``
    (index ``2 b + r`` of the branch label and the sign of ``p``).
    """
    a = atan_q1(abs(rho_b), abs(z))
    Sm[(row) * CHUNK + ii] = atan2_from_q1(a, rho_b, -z)
    Sm[(row + 1) * CHUNK + ii] = atan2_from_q1(a, rho_b, z)
    Sm[(row + 2) * CHUNK + ii] = atan2_from_q1(a, -rho_b, -z)
    Sm[(row + 3) * CHUNK + ii] = atan2_from_q1(a, -rho_b, z)


@njit(**_INLINE)
def _store_angles(Sm, ii, A1, B1, rho2, zz, A3, B3, rho4b, W22, y5, x5):
    """The 16 distinct angles of a mode (first-quadrant atan, then sign patterns) into ``Sm``."""
    a1 = atan_q1(abs(B1), abs(A1))
    Sm[(_V1) * CHUNK + ii] = atan2_from_q1(a1, B1, A1)
    Sm[(_V1 + 1) * CHUNK + ii] = atan2_from_q1(a1, -B1, -A1)
    _store_second_angle(Sm, _V2, ii, rho2, zz)          # u2
    a3 = atan_q1(abs(B3), abs(A3))
    Sm[(_V3) * CHUNK + ii] = atan2_from_q1(a3, B3, A3)
    Sm[(_V3 + 1) * CHUNK + ii] = atan2_from_q1(a3, -B3, A3)
    Sm[(_V3 + 2) * CHUNK + ii] = atan2_from_q1(a3, -B3, -A3)
    Sm[(_V3 + 3) * CHUNK + ii] = atan2_from_q1(a3, B3, -A3)
    _store_second_angle(Sm, _V4, ii, rho4b, W22)        # u4
    a5 = atan_q1(abs(y5), abs(x5))
    Sm[(_V5) * CHUNK + ii] = atan2_from_q1(a5, y5, x5)
    Sm[(_V5 + 1) * CHUNK + ii] = atan2_from_q1(a5, -y5, -x5)


@njit(**_INLINE)
def _angle_pair(x, y, z):
    """Cosines and sines of an angle pair of ``R(a, b)`` from the axis ``(x, y, z)``.

    As the reference, sequentially: ``a`` from the direction of ``(x, y)``, ``b`` from
    the projection on the plane ``a`` fixes; the cosine and sine of an angle are its
    normalised pair. Returns ``rho = |(x, y)|`` (the singularity measure), ``cos a``,
    ``sin a`` (``x``, ``y`` where ``rho = 0``), the projection ``rho_b``, ``cos b``,
    ``sin b``.
    """
    rho = hypot(x, y)
    r = rho if rho > 0.0 else 1.0
    ca = x / r
    sa = y / r
    rho_b = ca * x + sa * y
    n = hypot(rho_b, z)
    return rho, ca, sa, rho_b, -z / n, rho_b / n


@njit(**_OPTS)
def _serial_stage(G, P, tol, SH, Sm, n):
    """Serial chain (ups_solutions) of one assembly mode, scratch ``Sm``."""
    l4 = P[3]
    dtol, pztol, ctol = tol[1], tol[2], tol[3]
    for ii in range(n):
        xm, r1 = SH[_XM * CHUNK + ii], SH[_R1 * CHUNK + ii]
        y, z, pr = Sm[_Y * CHUNK + ii], Sm[_Z * CHUNK + ii], Sm[_PR * CHUNK + ii]
        cy = y / r1
        cz = z / r1
        ys = y + l4 * cy
        zs = z + l4 * cz
        e00, e01, e02, e03, e10, e11, e12, e13, e20, e21, e22, e23 = _s_e(
            G, ii, xm, cy, cz, ys, zs)
        fin = (finite_sum(e00) + finite_sum(e01) + finite_sum(e02) + finite_sum(e03)
               + finite_sum(e10) + finite_sum(e11) + finite_sum(e12) + finite_sum(e13)
               + finite_sum(e20) + finite_sum(e21) + finite_sum(e22) + finite_sum(e23)) == 0.0
        fin = fin & (G[(_GFIN) * CHUNK + ii] != 0.0)
        # chain._ups.ups_solutions, slot (p > 0, sin u2 > 0, sin u4 > 0)
        nrm = math.sqrt((e03 * e03 + e13 * e13) + e23 * e23)
        pz = nrm <= pztol
        nn = nrm if nrm > pztol else 1.0
        zx = e03 / nn
        zy = e13 / nn
        zz = e23 / nn
        rho, A1, B1, rho2, c2, s2 = _angle_pair(zx, zy, zz)      # u1, u2
        x0, x1, x2 = A1 * c2, B1 * c2, s2
        z0, z1, z2 = A1 * s2, B1 * s2, -c2
        # W = R1^T R_s_e (rows: the columns x, y, z of R1)
        W00 = (x0 * e00 + x1 * e10) + x2 * e20
        W02 = (x0 * e02 + x1 * e12) + x2 * e22
        W10 = B1 * e00 - A1 * e10
        W12 = B1 * e02 - A1 * e12
        W20 = (z0 * e00 + z1 * e10) + z2 * e20
        W22 = (z0 * e02 + z1 * e12) + z2 * e22
        rho4, A3, B3, rho4b, c4, s4 = _angle_pair(W02, W12, W22)  # u3, u4
        # u5 from what u3, u4 leave of W: closes the chain even where u3 is ill-conditioned
        y5 = B3 * W00 - A3 * W10
        x5 = (A3 * c4 * W00 + B3 * c4 * W10) + s4 * W20
        n5 = hypot(x5, y5)
        c5 = x5 / n5
        s5 = y5 / n5
        # closure residual (identical for the 8 slots: they are sign flips of each other)
        res = _closure_residual(A1, B1, c2, s2, A3, B3, c4, s4, c5, s5, nn, e00, e01, e02, e03,
                                e10, e11, e12, e13, e20, e21, e22, e23)
        # degeneracy relative to the direction's rounding, ~eps * (|t_b_e| + |O_s|) / p
        t03, t13, t23 = G[(_GT + 3) * CHUNK + ii], G[(_GT + 7) * CHUNK + ii], \
            G[(_GT + 11) * CHUNK + ii]
        sc = (max(abs(t03), max(abs(t13), abs(t23))) + max(abs(xm), max(abs(ys), abs(zs))))
        dt = max(dtol, _DEG_ROUND * sc / nn)
        ct = ctol + _CLOSE_ROUND * sc        # closure allows the rounding of a far pose
        # robot._fk._assemble: a slot whose O_s is not known within closure_tol is tangent
        ser = (_NONFINITE if not fin else _P_ZERO if pz else _UJOINT if rho <= dt
               else _WRIST if rho4 <= dt else _CLOSURE if not (res <= ct)
               else _TANGENT if SH[_PRES * CHUNK + ii] > ctol else 0.0)
        Sm[(_R) * CHUNK + ii] = pr if pr != 0.0 else ser
        Sm[(_NN) * CHUNK + ii] = nn
        Sm[(_RES) * CHUNK + ii] = res
        _store_angles(Sm, ii, A1, B1, rho2, zz, A3, B3, rho4b, W22, y5, x5)
        Sm[(_YS) * CHUNK + ii] = ys
        Sm[(_ZS) * CHUNK + ii] = zs
        Sm[(_CY) * CHUNK + ii] = cy
        Sm[(_CZ) * CHUNK + ii] = cz


@njit(**_OPTS)
def fk_chunk(q, T, P, tol, G, SH, S0, S1, c0, n):
    """Scratch for poses c0..c0+n-1: gather, parallel module, serial chain of each mode."""
    gather(q, T, c0, n, G)
    _parallel_stage(G, P, tol, SH, S0, S1, n)
    _serial_stage(G, P, tol, SH, S0, n)
    _serial_stage(G, P, tol, SH, S1, n)


@njit(**_OPTS)
def mode_reason(q, T, P, tol, G, SH, S0, S1, m):
    """The reason code (float; 0: valid) of one pose's 8 slots of assembly mode ``m``.

    :func:`fk_chunk` of one pose (``q`` (1, 3), ``T`` (1, 4, 4)) with the serial chain of
    mode ``m`` only (0: slots 0-7, 1: slots 8-15): the same stages on the same values, so
    the code is the ``reason`` that the entry kernels store in those slots.
    """
    gather(q, T, 0, 1, G)
    _parallel_stage(G, P, tol, SH, S0, S1, 1)
    Sm = S0 if m == 0 else S1
    _serial_stage(G, P, tol, SH, Sm, 1)
    return Sm[_R * CHUNK]
