"""Compiled analytic Jacobians of the parallel module and the whole robot (private).

The arithmetic mirrors :mod:`athenakin.analysis._jacobians` operation by
operation (same formulas, same order of the floating-point operations,
including the multiplications by the zeros and ones of constant matrices, so
that inf and NaN propagate into the same entries), item by item instead of
array by array. Two differences change no result beyond rounding:

* the reference's 3 x 3 matrix products go through BLAS (possibly with FMA);
  here they are plain sums of products in index order;
* the direction angles of :func:`instrument_inverse_jacobian` come from the
  branch-free ``atan2`` / ``sincos`` of :mod:`._scalar` (within a few ulps of
  numpy's), not from the C library, so that the item loop has no library call.

The batch kernels take inputs with either ``N`` rows or a single row (which is
broadcast) and write ``out`` of shape ``(N, rows, 3)``; the item loop is
unswitched by hand (one loop per kind) so that LLVM sees straight-line code.
"""

from __future__ import annotations

import math

from numba import njit

from ._fk_kernels import FLAG_NONRIGID, FLAG_T_NONFINITE, rigid_flags
from ._scalar import atan2, hypot, sincos

__all__ = ["PAR_JAC", "PAR_INV", "PAR_TWIST", "INSTR_JAC", "INSTR_INV", "TIP_JAC", "TIP_INV",
           "parallel_kernel", "robot_kernel", "FLAG_NONRIGID", "FLAG_T_NONFINITE"]

#: Kinds of :func:`parallel_kernel`: ``d O_s / d q``, ``d q / d O_s``, the (6, 3) twist Jacobian.
PAR_JAC, PAR_INV, PAR_TWIST = 0, 1, 2
#: Kinds of :func:`robot_kernel`: instrument angles + insertion and tool tip, each and inverse.
INSTR_JAC, INSTR_INV, TIP_JAC, TIP_INV = 0, 1, 2, 3

_OPTS = dict(error_model="numpy", cache=True)


# --- the parallel module (parallel_state, _dphi_dq, _parallel_jacobian, _inverse) --------
@njit(**_OPTS)
def _module(q1, q2, q3, m, P, ttol):
    """``parallel_state`` of one item: ``h, x_M, r1, s3, m_y, y, z, ey, ez, D``."""
    l1, l2, l3, l5 = P[0], P[1], P[2], P[4]
    h = 0.5 * (q1 - q2)
    r1 = math.sqrt(l1 * l1 - h * h)
    r1 = r1 if r1 > 0 else math.nan
    s3 = math.sqrt(l3 * l3 - h * h)
    m_y = s3 + l2
    d2 = m_y * m_y + l5 * l5
    d = math.sqrt(d2)
    H = d2 + r1 * r1 - q3 * q3
    k = (r1 + q3 - d) * (r1 + q3 + d) * (d - r1 + q3) * (d + r1 - q3)
    a = math.sqrt(abs(k)) / (2 * d)
    a = a if k >= 0 else (0.0 if a <= ttol else math.nan)
    by, bz = H * m_y / (2 * d2), H * l5 / (2 * d2)
    y = by - m * a * l5 / d
    z = bz + m * a * m_y / d
    ey, ez = y / r1, z / r1
    return h, 0.5 * (q1 + q2), r1, s3, m_y, y, z, ey, ez, -m * a * d


@njit(**_OPTS)
def _dphi(h, r1, s3, m_y, q3, ey, ez, D, l5):
    """``d phi / d q`` (3 values; ``_dphi_dq``)."""
    dr1_dh = -h / r1
    dmy_dh = -h / s3
    e_dot_C = ey * m_y + ez * l5
    coef_h = (r1 - e_dot_C) * dr1_dh - (r1 * ey - m_y) * dmy_dh
    dphi_dh = coef_h / D
    return 0.5 * dphi_dh, -0.5 * dphi_dh, -q3 / D


@njit(**_OPTS)
def _pjac(q1, q2, q3, m, P, ttol):
    """``d O_s / d q`` (row-major 9-tuple) and ``d phi / d q`` of one item."""
    l4, l5 = P[3], P[4]
    h, _, r1, s3, m_y, _, _, ey, ez, D = _module(q1, q2, q3, m, P, ttol)
    f0, f1, f2 = _dphi(h, r1, s3, m_y, q3, ey, ez, D, l5)
    rho = r1 + l4
    g = -h / r1
    a0, a1, a2 = g * 0.5, g * -0.5, g * 0.0
    re, ry = rho * ez, rho * ey
    J = (0.5, 0.5, 0.0,
         a0 * ey - re * f0, a1 * ey - re * f1, a2 * ey - re * f2,
         a0 * ez + ry * f0, a1 * ez + ry * f1, a2 * ez + ry * f2)
    return J, (f0, f1, f2)


@njit(**_OPTS)
def _pinv(h, r1, s3, m_y, y, z, ey, ez, q3, l4, l5):
    """``d q / d O_s`` (row-major 9-tuple; ``_parallel_inverse_jacobian``)."""
    rho = r1 + l4
    p0, p1, p2 = 0.0 / rho, -ez / rho, ey / rho                 # dphi
    t = -r1 / h
    h0, h1, h2 = t * 0.0, t * ey, t * ez                        # dh
    v = r1 / s3
    m0, m1, m2 = v * 0.0, v * ey, v * ez                        # dmy
    rez, rey = r1 * ez, r1 * ey
    y0, y1, y2 = 0.0 * ey - rez * p0, ey * ey - rez * p1, ez * ey - rez * p2     # dOy
    z0, z1, z2 = 0.0 * ez + rey * p0, ey * ez + rey * p1, ez * ez + rey * p2     # dOz
    ym, zl = y - m_y, z - l5
    return (1.0 + h0, 0.0 + h1, 0.0 + h2,
            1.0 - h0, 0.0 - h1, 0.0 - h2,
            (ym * (y0 - m0) + zl * z0) / q3, (ym * (y1 - m1) + zl * z1) / q3,
            (ym * (y2 - m2) + zl * z2) / q3)


@njit(**_OPTS)
def _mm(A, B):
    """3 x 3 product of row-major 9-tuples, sums in index order."""
    return (A[0] * B[0] + A[1] * B[3] + A[2] * B[6], A[0] * B[1] + A[1] * B[4] + A[2] * B[7],
            A[0] * B[2] + A[1] * B[5] + A[2] * B[8],
            A[3] * B[0] + A[4] * B[3] + A[5] * B[6], A[3] * B[1] + A[4] * B[4] + A[5] * B[7],
            A[3] * B[2] + A[4] * B[5] + A[5] * B[8],
            A[6] * B[0] + A[7] * B[3] + A[8] * B[6], A[6] * B[1] + A[7] * B[4] + A[8] * B[7],
            A[6] * B[2] + A[7] * B[5] + A[8] * B[8])


@njit(**_OPTS)
def _tr(A):
    return (A[0], A[3], A[6], A[1], A[4], A[7], A[2], A[5], A[8])


@njit(**_OPTS)
def _store(out, i, J):
    out[i, 0, 0], out[i, 0, 1], out[i, 0, 2] = J[0], J[1], J[2]
    out[i, 1, 0], out[i, 1, 1], out[i, 1, 2] = J[3], J[4], J[5]
    out[i, 2, 0], out[i, 2, 1], out[i, 2, 2] = J[6], J[7], J[8]


@njit(**_OPTS)
def parallel_kernel(q, m, P, ttol, kind, out):
    """Jacobians of the parallel module for ``N = out.shape[0]`` items.

    Parameters
    ----------
    q : (N or 1, 3) float64
    m : (N or 1,) float64, +1 or -1
    P : (13,) float64, :func:`athenakin.fast.design_params`
    ttol : float, :data:`athenakin.parallel.TANGENT_TOL`
    kind : int, :data:`PAR_JAC`, :data:`PAR_INV` or :data:`PAR_TWIST`
    out : (N, 3, 3) or, for ``PAR_TWIST``, (N, 6, 3) float64
    """
    n = out.shape[0]
    bq, bm = q.shape[0] > 1, m.shape[0] > 1
    if kind == PAR_JAC:
        for i in range(n):
            iq, im = i if bq else 0, i if bm else 0
            J, _ = _pjac(q[iq, 0], q[iq, 1], q[iq, 2], m[im], P, ttol)
            _store(out, i, J)
    elif kind == PAR_INV:
        l4, l5 = P[3], P[4]
        for i in range(n):
            iq, im = i if bq else 0, i if bm else 0
            q3 = q[iq, 2]
            h, _, r1, s3, m_y, y, z, ey, ez, _ = _module(q[iq, 0], q[iq, 1], q3, m[im], P, ttol)
            _store(out, i, _pinv(h, r1, s3, m_y, y, z, ey, ez, q3, l4, l5))
    else:
        for i in range(n):
            iq, im = i if bq else 0, i if bm else 0
            J, f = _pjac(q[iq, 0], q[iq, 1], q[iq, 2], m[im], P, ttol)
            _store(out, i, J)
            out[i, 3, 0], out[i, 3, 1], out[i, 3, 2] = f[0], f[1], f[2]
            for r in range(4, 6):
                for c in range(3):
                    out[i, r, c] = 0.0


# --- whole robot in controller variables (_instrument, _tip_matrices and the four Jacobians) --
@njit(**_OPTS)
def _line(T, it, rcm, xm, r1, ey, ez, l4):
    """``_instrument``: unit direction ``d_b``, insertion ``p``, ``R_f`` (9-tuple), ``d_f``."""
    rho = r1 + l4
    r0, r1_, r2 = T[it, 0, 3] - xm, T[it, 1, 3] - rho * ey, T[it, 2, 3] - rho * ez
    p = math.sqrt(r0 * r0 + r1_ * r1_ + r2 * r2)
    d = (r0 / p, r1_ / p, r2 / p)
    if rcm:
        R = (T[it, 0, 0], T[it, 0, 1], T[it, 0, 2], T[it, 1, 0], T[it, 1, 1], T[it, 1, 2],
             T[it, 2, 0], T[it, 2, 1], T[it, 2, 2])
    else:
        R = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
    df = (R[0] * d[0] + R[3] * d[1] + R[6] * d[2], R[1] * d[0] + R[4] * d[1] + R[7] * d[2],
          R[2] * d[0] + R[5] * d[1] + R[8] * d[2])
    return d, p, R, df


@njit(**_OPTS)
def _instrument_jac(d, p, R, df, Jp):
    """``instrument_jacobian``: ``K @ J_par``."""
    dx, dy, dz = df
    rho2 = dx * dx + dy * dy
    rho = math.sqrt(rho2)
    az = (-dy / rho2, dx / rho2, 0.0 / rho2)
    po = (dx * dz / rho, dy * dz / rho, -rho2 / rho)
    K = (-(az[0] * R[0] + az[1] * R[1] + az[2] * R[2]) / p,
         -(az[0] * R[3] + az[1] * R[4] + az[2] * R[5]) / p,
         -(az[0] * R[6] + az[1] * R[7] + az[2] * R[8]) / p,
         -(po[0] * R[0] + po[1] * R[1] + po[2] * R[2]) / p,
         -(po[0] * R[3] + po[1] * R[4] + po[2] * R[5]) / p,
         -(po[0] * R[6] + po[1] * R[7] + po[2] * R[8]) / p,
         -d[0], -d[1], -d[2])
    return _mm(K, Jp)


@njit(**_OPTS)
def _instrument_inv(d, p, R, df, Pinv):
    """``instrument_inverse_jacobian``: ``J_par^-1 @ K``."""
    az = atan2(df[1], df[0])
    pol = atan2(hypot(df[0], df[1]), df[2])
    sa, ca = sincos(az)
    sp, cp = sincos(pol)
    a = (-sp * sa, sp * ca, 0.0)
    b = (cp * ca, cp * sa, -sp)
    K = (-(R[0] * a[0] + R[1] * a[1] + R[2] * a[2]) * p,
         -(R[0] * b[0] + R[1] * b[1] + R[2] * b[2]) * p, -d[0],
         -(R[3] * a[0] + R[4] * a[1] + R[5] * a[2]) * p,
         -(R[3] * b[0] + R[4] * b[1] + R[5] * b[2]) * p, -d[1],
         -(R[6] * a[0] + R[7] * a[1] + R[8] * a[2]) * p,
         -(R[6] * b[0] + R[7] * b[1] + R[8] * b[2]) * p, -d[2])
    return _mm(Pinv, K)


@njit(**_OPTS)
def _tip(d, p, L, inverse):
    """``_tip_matrices``: ``N`` or, with ``inverse``, ``N^-1`` (row-major 9-tuple)."""
    f = p / (p - L) if inverse else 1.0 - L / p
    o = (d[0] * d[0], d[0] * d[1], d[0] * d[2], d[1] * d[0], d[1] * d[1], d[1] * d[2],
         d[2] * d[0], d[2] * d[1], d[2] * d[2])
    return (o[0] + f * (1.0 - o[0]), o[1] + f * (0.0 - o[1]), o[2] + f * (0.0 - o[2]),
            o[3] + f * (0.0 - o[3]), o[4] + f * (1.0 - o[4]), o[5] + f * (0.0 - o[5]),
            o[6] + f * (0.0 - o[6]), o[7] + f * (0.0 - o[7]), o[8] + f * (1.0 - o[8]))


@njit(**_OPTS)
def _robot_item(q, m, T, P, ttol, kind, rcm, iq, im, it):
    q1, q2, q3, mm = q[iq, 0], q[iq, 1], q[iq, 2], m[im]
    l4, l5 = P[3], P[4]
    h, xm, r1, s3, m_y, y, z, ey, ez, _ = _module(q1, q2, q3, mm, P, ttol)
    if kind == INSTR_JAC or kind == TIP_JAC:
        Jp, _ = _pjac(q1, q2, q3, mm, P, ttol)
    else:
        Jp = _pinv(h, r1, s3, m_y, y, z, ey, ez, q3, l4, l5)
    if kind == INSTR_JAC or kind == INSTR_INV:
        d, p, R, df = _line(T, it, rcm, xm, r1, ey, ez, l4)
        if kind == INSTR_JAC:
            return _instrument_jac(d, p, R, df, Jp)
        return _instrument_inv(d, p, R, df, Jp)
    d, p, _, _ = _line(T, it, False, xm, r1, ey, ez, l4)
    if kind == TIP_JAC:
        J = _mm(_tip(d, p, P[12], False), Jp)
        return _mm(_tr(_rf(T, it)), J) if rcm else J
    J = _mm(Jp, _tip(d, p, P[12], True))
    return _mm(J, _rf(T, it)) if rcm else J


@njit(**_OPTS)
def _rf(T, it):
    return (T[it, 0, 0], T[it, 0, 1], T[it, 0, 2], T[it, 1, 0], T[it, 1, 1], T[it, 1, 2],
            T[it, 2, 0], T[it, 2, 1], T[it, 2, 2])


@njit(**_OPTS)
def robot_kernel(q, m, T, P, ttol, kind, rcm, check, rot_tol, out):
    """Jacobians of the whole robot in controller variables for ``N = out.shape[0]`` items.

    Parameters
    ----------
    q : (N or 1, 3) float64
    m : (N or 1,) float64, +1 or -1
    T : (N or 1, 4, 4) float64, the RCM frames
    P : (13,) float64, :func:`athenakin.fast.design_params`
    ttol : float, :data:`athenakin.parallel.TANGENT_TOL`
    kind : int, :data:`INSTR_JAC`, :data:`INSTR_INV`, :data:`TIP_JAC` or :data:`TIP_INV`
    rcm : bool, ``frame == "rcm"``
    check : bool, check ``T`` first (:func:`._fk_kernels.rigid_flags`)
    rot_tol : float, :data:`athenakin._validation.ROTATION_TOL`
    out : (N, 3, 3) float64

    Returns
    -------
    int
        0, or the flags of :func:`rigid_flags` (then nothing is computed: the
        caller hands the call to the reference, which raises or decides).
    """
    if check:
        flags = rigid_flags(T, rot_tol)
        if flags:
            return flags
    n = out.shape[0]
    bq, bm, bt = q.shape[0] > 1, m.shape[0] > 1, T.shape[0] > 1
    if kind == INSTR_JAC:
        for i in range(n):
            _store(out, i, _robot_item(q, m, T, P, ttol, INSTR_JAC, rcm, i if bq else 0,
                                       i if bm else 0, i if bt else 0))
    elif kind == INSTR_INV:
        for i in range(n):
            _store(out, i, _robot_item(q, m, T, P, ttol, INSTR_INV, rcm, i if bq else 0,
                                       i if bm else 0, i if bt else 0))
    elif kind == TIP_JAC:
        for i in range(n):
            _store(out, i, _robot_item(q, m, T, P, ttol, TIP_JAC, rcm, i if bq else 0,
                                       i if bm else 0, i if bt else 0))
    else:
        for i in range(n):
            _store(out, i, _robot_item(q, m, T, P, ttol, TIP_INV, rcm, i if bq else 0,
                                       i if bm else 0, i if bt else 0))
    return 0
