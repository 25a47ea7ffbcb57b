"""Compiled analytic Jacobians of the parallel module and the whole robot (private).

The arithmetic mirrors :mod:`athenakin.robot._jacobians` operation by
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
broadcast) and write ``out`` of shape ``(N, rows, 3)``. As in the FK kernels, the
items are walked in chunks of :data:`CHUNK`: a pass gathers the inputs into the
rows of a flat scratch, a straight-line pass per kind (helpers inlined in numba
IR, loops unswitched by hand, selects instead of branches) computes, and LLVM
vectorises it (AVX-512 divisions and square roots; an LLVM call left in the loop,
or an input indexed through a broadcast select, kept it scalar and 4-5 x
slower), a last pass scatters the results. The rigidity test of the frames runs
in the same chunks, vectorised too.
"""

# numba's cache does not follow the kernels this module inlines from _fk_kernels, _scalar
# and _mechanism_formulas: a change there must change this file too (revision 6).

from __future__ import annotations

import math

import numpy as np

from .._backend import njit
from .._mechanism_formulas import parallel_state_formula
from ._fk_kernels import FLAG_NONRIGID, FLAG_T_NONFINITE
from ._scalar import atan2, finite_sum, hypot, sincos

__all__ = ["PAR_JAC", "PAR_INV", "PAR_TWIST", "INSTR_JAC", "INSTR_INV", "TIP_JAC", "TIP_INV",
           "parallel_kernel", "robot_kernel", "tip_one", "frame_rows", "NG", "CHUNK",
           "FLAG_NONRIGID", "FLAG_T_NONFINITE"]

#: Kinds of :func:`parallel_kernel`: ``d O_s / d q``, ``d q / d O_s``, the (6, 3) twist Jacobian.
PAR_JAC, PAR_INV, PAR_TWIST = 0, 1, 2
#: Kinds of :func:`robot_kernel`: instrument angles + insertion and tool tip, each and inverse.
INSTR_JAC, INSTR_INV, TIP_JAC, TIP_INV = 0, 1, 2, 3

#: Items per chunk: a pass gathers the inputs into rows of a scratch, a straight-line pass
#: computes (LLVM vectorises it), a last pass scatters the results into ``out``.
CHUNK = 64
# Rows of the gathered input: q (3), mode (1), R of T_b_e row-major (9), its translation (3),
# its last row (4).
_GQ, _GM, _GR, _GT, _GL = 0, 3, 4, 13, 16
NG = 20
# Scratch arrays are flat, row-major (row * CHUNK + column), CHUNK a compile-time constant.

_OPTS = dict(error_model="numpy", cache=True, nogil=True)
# helpers are inlined in numba IR: an LLVM call left in the item loop stops vectorisation
_INLINE = dict(error_model="numpy", cache=True, nogil=True, inline="always")


# --- the parallel module (parallel_state, _dphi_dq, _parallel_jacobian, _inverse) --------
@njit(**_INLINE)
def _select(c, a, b):
    """``np.where`` of one item (numba's makes arrays of scalars)."""
    return a if c else b


#: The one formula of the module's state (numpy evaluates the same source).
_parallel_state = njit(**_INLINE)(parallel_state_formula)


@njit(**_INLINE)
def _module(q1, q2, q3, m, P, ttol):
    """``parallel_state`` of one item: ``h, x_M, r1, s3, m_y, y, z, ey, ez, D``."""
    h, r1, s3, m_y, d, a, y, z, ey, ez = _parallel_state(q1, q2, q3, m, P[0], P[1], P[2],
                                                          P[4], ttol, _select)
    return h, 0.5 * (q1 + q2), r1, s3, m_y, y, z, ey, ez, -m * a * d


@njit(**_INLINE)
def _dphi(h, r1, s3, m_y, q3, ey, ez, D, l5):
    """``d phi / d q`` (3 values; ``_dphi_dq``)."""
    dr1_dh = -h / r1
    dmy_dh = -h / s3
    e_dot_C = ey * m_y + ez * l5
    coef_h = (r1 - e_dot_C) * dr1_dh - (r1 * ey - m_y) * dmy_dh
    dphi_dh = coef_h / D
    return 0.5 * dphi_dh, -0.5 * dphi_dh, -q3 / D


@njit(**_INLINE)
def _pjac_of(h, r1, s3, m_y, ey, ez, D, q3, l4, l5):
    """``d O_s / d q`` (row-major 9-tuple) and ``d phi / d q`` from the module's state."""
    f0, f1, f2 = _dphi(h, r1, s3, m_y, q3, ey, ez, D, l5)
    rho = r1 + l4
    g = -h / r1
    a0, a1, a2 = g * 0.5, g * -0.5, g * 0.0
    re, ry = rho * ez, rho * ey
    J = (0.5, 0.5, 0.0,
         a0 * ey - re * f0, a1 * ey - re * f1, a2 * ey - re * f2,
         a0 * ez + ry * f0, a1 * ez + ry * f1, a2 * ez + ry * f2)
    return J, (f0, f1, f2)


@njit(**_INLINE)
def _pjac(q1, q2, q3, m, P, ttol):
    """``d O_s / d q`` (row-major 9-tuple) and ``d phi / d q`` of one item."""
    h, _, r1, s3, m_y, _, _, ey, ez, D = _module(q1, q2, q3, m, P, ttol)
    return _pjac_of(h, r1, s3, m_y, ey, ez, D, q3, P[3], P[4])


@njit(**_INLINE)
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


@njit(**_INLINE)
def _mm(A, B):
    """3 x 3 product of row-major 9-tuples, sums in index order."""
    return (A[0] * B[0] + A[1] * B[3] + A[2] * B[6], A[0] * B[1] + A[1] * B[4] + A[2] * B[7],
            A[0] * B[2] + A[1] * B[5] + A[2] * B[8],
            A[3] * B[0] + A[4] * B[3] + A[5] * B[6], A[3] * B[1] + A[4] * B[4] + A[5] * B[7],
            A[3] * B[2] + A[4] * B[5] + A[5] * B[8],
            A[6] * B[0] + A[7] * B[3] + A[8] * B[6], A[6] * B[1] + A[7] * B[4] + A[8] * B[7],
            A[6] * B[2] + A[7] * B[5] + A[8] * B[8])


@njit(**_INLINE)
def _tr(A):
    return (A[0], A[3], A[6], A[1], A[4], A[7], A[2], A[5], A[8])


# --- whole robot in controller variables (_instrument, _tip_matrices and the four Jacobians) --
_EYE = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)


@njit(**_INLINE)
def _line(R, c, xm, r1, ey, ez, l4):
    """``_instrument``: unit direction ``d_b``, insertion ``p`` and ``d_f = R_f^T d_b``."""
    rho = r1 + l4
    r0, r1_, r2 = c[0] - xm, c[1] - rho * ey, c[2] - rho * ez
    p = math.sqrt(r0 * r0 + r1_ * r1_ + r2 * r2)
    d = (r0 / p, r1_ / p, r2 / p)
    df = (R[0] * d[0] + R[3] * d[1] + R[6] * d[2], R[1] * d[0] + R[4] * d[1] + R[7] * d[2],
          R[2] * d[0] + R[5] * d[1] + R[8] * d[2])
    return d, p, df


@njit(**_INLINE)
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


@njit(**_INLINE)
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


@njit(**_INLINE)
def _tip(d, p, L, inverse):
    """``_tip_matrices``: ``N`` or, with ``inverse``, ``N^-1`` (row-major 9-tuple)."""
    f = p / (p - L) if inverse else 1.0 - L / p
    o = (d[0] * d[0], d[0] * d[1], d[0] * d[2], d[1] * d[0], d[1] * d[1], d[1] * d[2],
         d[2] * d[0], d[2] * d[1], d[2] * d[2])
    return (o[0] + f * (1.0 - o[0]), o[1] + f * (0.0 - o[1]), o[2] + f * (0.0 - o[2]),
            o[3] + f * (0.0 - o[3]), o[4] + f * (1.0 - o[4]), o[5] + f * (0.0 - o[5]),
            o[6] + f * (0.0 - o[6]), o[7] + f * (0.0 - o[7]), o[8] + f * (1.0 - o[8]))


# --- chunked loops: gather into rows, compute (vectorised), scatter ------------------------
@njit(**_INLINE)
def _gather(q, m, c0, nn, G):
    """Copy q and the mode of items c0..c0+nn-1 into rows of ``G`` (one row: broadcast)."""
    bq, bm = q.shape[0] > 1, m.shape[0] > 1
    for ii in range(nn):
        i = c0 + ii
        iq, im = i if bq else 0, i if bm else 0
        G[(_GQ) * CHUNK + ii] = q[iq, 0]
        G[(_GQ + 1) * CHUNK + ii] = q[iq, 1]
        G[(_GQ + 2) * CHUNK + ii] = q[iq, 2]
        G[(_GM) * CHUNK + ii] = m[im]


@njit(**_INLINE)
def _gather_T(T, c0, nn, G):
    """Copy the rotation and translation of the frames of items c0..c0+nn-1 into ``G``."""
    bt = T.shape[0] > 1
    for ii in range(nn):
        it = c0 + ii if bt else 0
        for r in range(3):
            for c in range(3):
                G[(_GR + 3 * r + c) * CHUNK + ii] = T[it, r, c]
            G[(_GT + r) * CHUNK + ii] = T[it, r, 3]
        for c in range(4):
            G[(_GL + c) * CHUNK + ii] = T[it, 3, c]


@njit(**_INLINE)
def _rigid_counts(G, nn, lim):
    """Numbers of gathered frames that are not finite, and that are not rigid within ``lim``.

    The test of :func:`._fk_kernels.rigid_flags` (``|R^T R - I|``, ``|det R - 1|`` and
    the last row's deviation), branch-free so that the loop vectorises.
    """
    n_nonfinite = 0
    n_nonrigid = 0
    for ii in range(nn):
        R0, R1, R2 = G[(_GR) * CHUNK + ii], G[(_GR + 1) * CHUNK + ii], G[(_GR + 2) * CHUNK + ii]
        R3, R4, R5 = G[(_GR + 3) * CHUNK + ii], G[(_GR + 4) * CHUNK + ii], G[(_GR + 5) * CHUNK + ii]
        R6, R7, R8 = G[(_GR + 6) * CHUNK + ii], G[(_GR + 7) * CHUNK + ii], G[(_GR + 8) * CHUNK + ii]
        L0, L1, L2, L3 = (G[(_GL) * CHUNK + ii], G[(_GL + 1) * CHUNK + ii],
                          G[(_GL + 2) * CHUNK + ii], G[(_GL + 3) * CHUNK + ii])
        t0, t1, t2 = G[(_GT) * CHUNK + ii], G[(_GT + 1) * CHUNK + ii], G[(_GT + 2) * CHUNK + ii]
        fin = (finite_sum(R0) + finite_sum(R1) + finite_sum(R2) + finite_sum(R3)
               + finite_sum(R4) + finite_sum(R5) + finite_sum(R6) + finite_sum(R7)
               + finite_sum(R8) + finite_sum(L0) + finite_sum(L1) + finite_sum(L2)
               + finite_sum(L3) + finite_sum(t0) + finite_sum(t1) + finite_sum(t2)) == 0.0
        e = (abs(R0 * R0 + R3 * R3 + R6 * R6 - 1.0), abs(R1 * R1 + R4 * R4 + R7 * R7 - 1.0),
             abs(R2 * R2 + R5 * R5 + R8 * R8 - 1.0), abs(R0 * R1 + R3 * R4 + R6 * R7),
             abs(R0 * R2 + R3 * R5 + R6 * R8), abs(R1 * R2 + R4 * R5 + R7 * R8),
             abs(R0 * (R4 * R8 - R5 * R7) - R1 * (R3 * R8 - R5 * R6)
                 + R2 * (R3 * R7 - R4 * R6) - 1.0),
             abs(L0), abs(L1), abs(L2), abs(L3 - 1.0))
        ok = ((e[0] <= lim) & (e[1] <= lim) & (e[2] <= lim) & (e[3] <= lim) & (e[4] <= lim)
              & (e[5] <= lim) & (e[6] <= lim) & (e[7] <= lim) & (e[8] <= lim) & (e[9] <= lim)
              & (e[10] <= lim))
        n_nonfinite += 0 if fin else 1
        n_nonrigid += 1 if fin and not ok else 0
    return n_nonfinite, n_nonrigid


@njit(**_INLINE)
def _put(S, ii, J):
    for k in range(len(J)):
        S[k * CHUNK + ii] = J[k]


@njit(**_INLINE)
def _scatter(S, c0, nn, rows, out):
    for ii in range(nn):
        for k in range(rows * 3):
            out[c0 + ii, k // 3, k % 3] = S[k * CHUNK + ii]


@njit(**_INLINE)
def _q(G, ii):
    return (G[(_GQ) * CHUNK + ii], G[(_GQ + 1) * CHUNK + ii], G[(_GQ + 2) * CHUNK + ii],
            G[(_GM) * CHUNK + ii])


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
    l4, l5 = P[3], P[4]
    G = np.empty(NG * CHUNK)
    S = np.empty(12 * CHUNK)
    for c0 in range(0, n, CHUNK):
        nn = min(CHUNK, n - c0)
        _gather(q, m, c0, nn, G)
        if kind == PAR_INV:
            for ii in range(nn):
                q1, q2, q3, mm = _q(G, ii)
                h, _, r1, s3, m_y, y, z, ey, ez, _ = _module(q1, q2, q3, mm, P, ttol)
                _put(S, ii, _pinv(h, r1, s3, m_y, y, z, ey, ez, q3, l4, l5))
            _scatter(S, c0, nn, 3, out)
            continue
        for ii in range(nn):
            q1, q2, q3, mm = _q(G, ii)
            J, f = _pjac(q1, q2, q3, mm, P, ttol)
            _put(S, ii, J)
            S[9 * CHUNK + ii], S[10 * CHUNK + ii], S[11 * CHUNK + ii] = f[0], f[1], f[2]
        if kind == PAR_JAC:
            _scatter(S, c0, nn, 3, out)
            continue
        _scatter(S, c0, nn, 4, out)
        for ii in range(nn):
            for k in range(6):
                out[c0 + ii, 4 + k // 3, k % 3] = 0.0


@njit(**_INLINE)
def _frame(G, ii):
    """The gathered RCM frame of an item: ``R`` (row-major 9-tuple) and its translation."""
    R = (G[(_GR) * CHUNK + ii], G[(_GR + 1) * CHUNK + ii], G[(_GR + 2) * CHUNK + ii],
         G[(_GR + 3) * CHUNK + ii], G[(_GR + 4) * CHUNK + ii], G[(_GR + 5) * CHUNK + ii],
         G[(_GR + 6) * CHUNK + ii], G[(_GR + 7) * CHUNK + ii], G[(_GR + 8) * CHUNK + ii])
    return R, (G[(_GT) * CHUNK + ii], G[(_GT + 1) * CHUNK + ii], G[(_GT + 2) * CHUNK + ii])


@njit(**_INLINE)
def _pick(a, b, first):
    """``a`` where ``first``, else ``b`` (9-tuples, entry by entry, no branch)."""
    return (a[0] if first else b[0], a[1] if first else b[1], a[2] if first else b[2],
            a[3] if first else b[3], a[4] if first else b[4], a[5] if first else b[5],
            a[6] if first else b[6], a[7] if first else b[7], a[8] if first else b[8])


@njit(**_INLINE)
def _item_line(G, ii, P, ttol, rotate):
    """An item's module state, RCM frame and instrument line: what the four kinds share.

    Returns ``q3``; the module's state (:func:`_module`: ``h, x_M, r1, s3, m_y, y, z, ey,
    ez, D``); the frame's rotation ``Rt`` (row-major 9-tuple); ``R``, which is ``Rt`` where
    ``rotate``, else the identity (multiplied as the reference does); and the line ``d, p,
    d_f`` of :func:`_line` in ``R``.
    """
    q1, q2, q3, m = _q(G, ii)
    st = _module(q1, q2, q3, m, P, ttol)
    Rt, c = _frame(G, ii)
    R = _pick(Rt, _EYE, rotate)
    d, p, df = _line(R, c, st[1], st[2], st[7], st[8], P[3])
    return q3, st, Rt, R, d, p, df


# One function per kind: each inlined copy in a kernel's item loop carries only its own
# kind's arithmetic (numba's inlining copies the callee's IR at every call site).
@njit(**_INLINE)
def _instrument_jac_item(G, ii, P, ttol, rcm):
    """``INSTR_JAC`` of one item (straight-line code)."""
    q3, st, _, R, d, p, df = _item_line(G, ii, P, ttol, rcm)
    h, _, r1, s3, m_y, _, _, ey, ez, D = st
    Jp, _ = _pjac_of(h, r1, s3, m_y, ey, ez, D, q3, P[3], P[4])
    return _instrument_jac(d, p, R, df, Jp)


@njit(**_INLINE)
def _instrument_inv_item(G, ii, P, ttol, rcm):
    """``INSTR_INV`` of one item (straight-line code)."""
    q3, st, _, R, d, p, df = _item_line(G, ii, P, ttol, rcm)
    h, _, r1, s3, m_y, y, z, ey, ez, _ = st
    return _instrument_inv(d, p, R, df, _pinv(h, r1, s3, m_y, y, z, ey, ez, q3, P[3], P[4]))


@njit(**_INLINE)
def _tip_jac_item(G, ii, P, ttol, rcm):
    """``TIP_JAC`` of one item (straight-line code): ``R^T N J_par`` or ``N J_par``."""
    q3, st, Rt, _, d, p, _ = _item_line(G, ii, P, ttol, False)
    h, _, r1, s3, m_y, _, _, ey, ez, D = st
    Jp, _ = _pjac_of(h, r1, s3, m_y, ey, ez, D, q3, P[3], P[4])
    J = _mm(_tip(d, p, P[12], False), Jp)
    return _pick(_mm(_tr(Rt), J), J, rcm)


@njit(**_INLINE)
def _tip_inv_item(G, ii, P, ttol, rcm):
    """``TIP_INV`` of one item (straight-line code): ``J_par^-1 N^-1 R`` or without ``R``."""
    q3, st, Rt, _, d, p, _ = _item_line(G, ii, P, ttol, False)
    h, _, r1, s3, m_y, y, z, ey, ez, _ = st
    J = _mm(_pinv(h, r1, s3, m_y, y, z, ey, ez, q3, P[3], P[4]), _tip(d, p, P[12], True))
    return _pick(_mm(J, Rt), J, rcm)


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
    check : bool, check that ``T`` holds finite rigid transforms (within half the tolerance)
    rot_tol : float, :data:`athenakin._validation.ROTATION_TOL`
    out : (N, 3, 3) float64

    Returns
    -------
    int
        0, or :data:`FLAG_T_NONFINITE` / :data:`FLAG_NONRIGID` (then ``out`` is
        incomplete: the caller hands the call to the reference, which raises or decides).
    """
    lim = 0.5 * rot_tol
    n = out.shape[0]
    G = np.empty(NG * CHUNK)
    S = np.empty(9 * CHUNK)
    for c0 in range(0, n, CHUNK):
        nn = min(CHUNK, n - c0)
        _gather(q, m, c0, nn, G)
        _gather_T(T, c0, nn, G)
        if check:
            n_nonfinite, n_nonrigid = _rigid_counts(G, nn, lim)
            if n_nonfinite or n_nonrigid:
                return (FLAG_T_NONFINITE if n_nonfinite else 0) | (
                    FLAG_NONRIGID if n_nonrigid else 0)
        if kind == INSTR_JAC:
            for ii in range(nn):
                _put(S, ii, _instrument_jac_item(G, ii, P, ttol, rcm))
        elif kind == INSTR_INV:
            for ii in range(nn):
                _put(S, ii, _instrument_inv_item(G, ii, P, ttol, rcm))
        elif kind == TIP_JAC:
            for ii in range(nn):
                _put(S, ii, _tip_jac_item(G, ii, P, ttol, rcm))
        else:
            for ii in range(nn):
                _put(S, ii, _tip_inv_item(G, ii, P, ttol, rcm))
        _scatter(S, c0, nn, 3, out)
    return 0


def frame_rows(T: np.ndarray) -> np.ndarray:
    """The scratch of :func:`tip_one` with the RCM frame ``T`` (4, 4) in its rows."""
    G = np.zeros(NG * CHUNK)
    for r in range(3):
        for c in range(3):
            G[(_GR + 3 * r + c) * CHUNK] = T[r, c]
        G[(_GT + r) * CHUNK] = T[r, 3]
    for c in range(4):
        G[(_GL + c) * CHUNK] = T[3, c]
    return G


@njit(**_OPTS)
def tip_one(q1, q2, q3, m, G, P, ttol, inverse, rcm, out):
    """One item of :func:`robot_kernel`'s ``TIP_JAC`` or (``inverse``) ``TIP_INV`` into ``out``.

    ``out`` is (3, 3); ``G`` is :func:`frame_rows` of the RCM frame (checked by the caller);
    no allocation. The tool-tip kinds alone: those of the control loop
    (:class:`athenakin.fast.ControlLoop`).
    """
    G[_GQ * CHUNK] = q1
    G[(_GQ + 1) * CHUNK] = q2
    G[(_GQ + 2) * CHUNK] = q3
    G[_GM * CHUNK] = m
    if inverse:
        J = _tip_inv_item(G, 0, P, ttol, rcm)
    else:
        J = _tip_jac_item(G, 0, P, ttol, rcm)
    for k in range(9):
        out[k // 3, k % 3] = J[k]
