"""Compiled forward kinematics of the whole robot (private): all 16 slots per pose.

The entry kernels: :func:`fk_full` (and its threaded twin) expands the per-mode scratch
that the stages of :mod:`._fk_stages` write for each chunk of poses (their arithmetic
and how it mirrors :func:`athenakin.forward_kinematics` are described there) into the
16 slots of :class:`~athenakin.FKSolution`'s arrays; :func:`fk_counts` reduces it to
histograms, :func:`fk_one` answers one pose in packed buffers. Every entry returns the
``FLAG_*`` bits of its input (non-finite ``q`` or ``T_b_e``, a ``T_b_e`` to re-check).
"""

# numba's cache does not follow the kernels this module calls from _fk_stages and
# _module_form: a change there must change this file too (revision 1).

from __future__ import annotations

import math

import numpy as np

from .._backend import njit, prange
from ._fk_stages import (
    _CY,
    _CZ,
    _NN,
    _OPTS,
    _PR,
    _PRES,
    _R,
    _RES,
    _TANGENT,
    _V1,
    _V2,
    _V3,
    _V4,
    _V5,
    _XM,
    _YS,
    _ZS,
    CHUNK,
    fk_chunk,
    gather,
    gather_items,
    scratch,
)
from ._scalar import finite_sum, nanmax2

__all__ = ["CHUNK", "scratch", "fk_chunk", "gather", "gather_items", "fk_full", "fk_full_parallel",
           "fk_counts", "item_reason", "rigid_flags", "FLAG_NONRIGID", "FLAG_Q_NONFINITE",
           "FLAG_T_NONFINITE", "FLAG_NO_SOLUTION"]


#: Bits of the flags the kernels return.
FLAG_NONRIGID = 1        # some T_b_e is not rigid within half the tolerance: re-check exactly
FLAG_Q_NONFINITE = 2     # some q holds NaN / inf
FLAG_T_NONFINITE = 4     # some T_b_e holds NaN / inf
#: Bit of the lean single calls' results (``fast._fk_sized.fk_one_lean``,
#: ``fast._ik_kernels.ik_paper_lean``): the item has no valid solution (reason != 0).
FLAG_NO_SOLUTION = 256


@njit(**_OPTS)
def _fin16(T, j):
    s = 0.0
    for r in range(4):
        for c in range(4):
            s += finite_sum(T[j, r, c])
    return s == 0.0


@njit(**_OPTS)
def _input_flags(q, T, rot_tol):
    """FLAG_* bits: non-finite q / T, and T not rigid within ``rot_tol / 2`` (re-check exactly)."""
    flags = 0
    for i in range(q.shape[0]):
        if not ((finite_sum(q[i, 0]) + finite_sum(q[i, 1]) + finite_sum(q[i, 2])) == 0.0):
            flags |= FLAG_Q_NONFINITE
    flags |= rigid_flags(T, rot_tol)
    return flags


@njit(**_OPTS)
def rigid_flags(T, rot_tol):
    """FLAG_T_NONFINITE / FLAG_NONRIGID over transforms ``T`` (n, 4, 4).

    ``FLAG_NONRIGID`` is conservative: it is set when ``|R^T R - I|``,
    ``|det R - 1|`` or the last row's deviation exceeds half the tolerance of
    :func:`athenakin._validation.check_transform`, which then decides exactly.
    """
    flags = 0
    lim = 0.5 * rot_tol
    for j in range(T.shape[0]):
        if not _fin16(T, j):
            flags |= FLAG_T_NONFINITE
            continue
        dev = 0.0
        for a in range(3):
            for b in range(3):
                g = T[j, 0, a] * T[j, 0, b] + T[j, 1, a] * T[j, 1, b] + T[j, 2, a] * T[j, 2, b]
                dev = max(dev, abs(g - (1.0 if a == b else 0.0)))
        det = (T[j, 0, 0] * (T[j, 1, 1] * T[j, 2, 2] - T[j, 1, 2] * T[j, 2, 1])
               - T[j, 0, 1] * (T[j, 1, 0] * T[j, 2, 2] - T[j, 1, 2] * T[j, 2, 0])
               + T[j, 0, 2] * (T[j, 1, 0] * T[j, 2, 1] - T[j, 1, 1] * T[j, 2, 0]))
        dev = max(dev, abs(det - 1.0))
        dev = max(dev, abs(T[j, 3, 0]), abs(T[j, 3, 1]), abs(T[j, 3, 2]), abs(T[j, 3, 3] - 1.0))
        if not dev <= lim:
            flags |= FLAG_NONRIGID
    return flags


@njit(**_OPTS, inline="always")
def _store_u_mode(Sm, ii, mask, u, i, k0):
    """``u`` of the 8 slots ``k0..k0+7`` of one assembly mode from its scratch column ``ii``.

    Slot ``k0 + j`` has root ``r = j >> 2``, U-joint branch ``b = (j >> 1) & 1`` and wrist
    branch ``w = j & 1`` (:data:`athenakin.robot.SLOT_MODE` and friends); ``mask`` is 0 or NaN.
    """
    v1 = (Sm[_V1 * CHUNK + ii] + mask, Sm[(_V1 + 1) * CHUNK + ii] + mask)
    v2 = (Sm[_V2 * CHUNK + ii] + mask, Sm[(_V2 + 1) * CHUNK + ii] + mask,
          Sm[(_V2 + 2) * CHUNK + ii] + mask, Sm[(_V2 + 3) * CHUNK + ii] + mask)
    v3 = (Sm[_V3 * CHUNK + ii] + mask, Sm[(_V3 + 1) * CHUNK + ii] + mask,
          Sm[(_V3 + 2) * CHUNK + ii] + mask, Sm[(_V3 + 3) * CHUNK + ii] + mask)
    v4 = (Sm[_V4 * CHUNK + ii] + mask, Sm[(_V4 + 1) * CHUNK + ii] + mask,
          Sm[(_V4 + 2) * CHUNK + ii] + mask, Sm[(_V4 + 3) * CHUNK + ii] + mask)
    v5 = (Sm[_V5 * CHUNK + ii] + mask, Sm[(_V5 + 1) * CHUNK + ii] + mask)
    for j in range(8):
        r = j >> 2
        b = (j >> 1) & 1
        w = j & 1
        k = k0 + j
        u[i, k, 0] = v1[b ^ r]
        u[i, k, 1] = v2[2 * b + r]
        u[i, k, 2] = v3[2 * (w ^ b) + r]
        u[i, k, 3] = v4[2 * w + r]
        u[i, k, 4] = v5[w ^ r]


@njit(**_OPTS, inline="always")
def _store_T_b_s_mode(Sm, ii, xm, pmask, Tbs, i, k):
    """``Tbs[i, k] = [[1, 0, 0, xm], [0, cz, cy, ys], [0, -cy, cz, zs], [0, 0, 0, 1]]``.

    The pose of ``O_s`` of one assembly mode (scratch column ``ii``); NaN where ``pmask``
    is (the mode does not assemble).
    """
    one, zero = 1.0 + pmask, pmask
    cy = Sm[_CY * CHUNK + ii] + pmask
    cz = Sm[_CZ * CHUNK + ii] + pmask
    Tbs[i, k, 0, 0] = one
    Tbs[i, k, 0, 1] = zero
    Tbs[i, k, 0, 2] = zero
    Tbs[i, k, 0, 3] = xm + pmask
    Tbs[i, k, 1, 0] = zero
    Tbs[i, k, 1, 1] = cz
    Tbs[i, k, 1, 2] = cy
    Tbs[i, k, 1, 3] = Sm[_YS * CHUNK + ii] + pmask
    Tbs[i, k, 2, 0] = zero
    Tbs[i, k, 2, 1] = -cy
    Tbs[i, k, 2, 2] = cz
    Tbs[i, k, 2, 3] = Sm[_ZS * CHUNK + ii] + pmask
    Tbs[i, k, 3, 0] = zero
    Tbs[i, k, 3, 1] = zero
    Tbs[i, k, 3, 2] = zero
    Tbs[i, k, 3, 3] = one


@njit(**_OPTS)
def _store_mode(Sm, ii, i, k0, xm, pres, reason, valid, p, u, Tbs, res):
    """Expand one assembly mode's scratch column into its 8 slots (branch-free)."""
    R = Sm[_R * CHUNK + ii]
    ok = R == 0.0
    mask = 0.0 if ok else math.nan
    pmask = 0.0 if Sm[_PR * CHUNK + ii] == 0.0 else math.nan
    nn = Sm[_NN * CHUNK + ii] + mask
    rv = nanmax2(Sm[_RES * CHUNK + ii], pres) + mask
    r8 = np.int8(R)
    for j in range(8):
        k = k0 + j
        reason[i, k] = r8
        valid[i, k] = ok
        res[i, k] = rv
        p[i, k] = nn if (j >> 2) == 0 else -nn
    _store_u_mode(Sm, ii, mask, u, i, k0)
    nk = 8 if Tbs.shape[1] == 16 else 1
    kb = k0 if Tbs.shape[1] == 16 else k0 // 8
    for j in range(nk):
        _store_T_b_s_mode(Sm, ii, xm, pmask, Tbs, i, kb + j)


@njit(**_OPTS)
def item_reason(R0, R1):
    """Per-item reason (robot._common.item_reason_from_slots) from the two modes' codes.

    0 if a mode has valid slots, else the first code in slot order that is not
    CIRCLES_TANGENT, else CIRCLES_TANGENT.
    """
    if (R0 == 0.0) | (R1 == 0.0):
        return 0.0
    if R0 != _TANGENT:
        return R0
    return R1


@njit(**_OPTS)
def _store_full(SH, S0, S1, n, c0, reason, valid, p, u, Tbs, res, item):
    """Expand scratch columns into the 16 slots of FKSolution's arrays (rows c0..c0+n-1)."""
    for ii in range(n):
        i = c0 + ii
        xm = SH[_XM * CHUNK + ii]
        pres = SH[_PRES * CHUNK + ii]
        item[i] = np.int8(item_reason(S0[_R * CHUNK + ii], S1[_R * CHUNK + ii]))
        _store_mode(S0, ii, i, 0, xm, pres, reason, valid, p, u, Tbs, res)
        _store_mode(S1, ii, i, 8, xm, pres, reason, valid, p, u, Tbs, res)


@njit(**_OPTS)
def _chunk_full(q, T, P, tol, G, SH, S0, S1, c0, n, reason, valid, p, u, Tbs, res, item):
    fk_chunk(q, T, P, tol, G, SH, S0, S1, c0, n)
    _store_full(SH, S0, S1, n, c0, reason, valid, p, u, Tbs, res, item)


@njit(**_OPTS)
def fk_full(q, T, P, tol, rot_tol, reason, valid, p, u, Tbs, res, item):
    """All 16 slots of ``N = max(len(q), len(T))`` poses into FKSolution-shaped arrays.

    Parameters
    ----------
    q : (Nq, 3) float64, Nq in (1, N); T : (NT, 4, 4) float64, NT in (1, N)
    P : (13,) design parameters (see ``_api.design_params``); tol : (4,) tolerances
        (tangent, degenerate, p_zero, closure); rot_tol : rigidity tolerance
    reason : (N, 16) int8; valid : (N, 16) bool; p, res : (N, 16); u : (N, 16, 5);
    Tbs : (N, 16, 4, 4) or (N, 2, 4, 4) (then one matrix per mode); item : (N,) int8

    Returns
    -------
    int
        FLAG_* bits about the input.
    """
    N = item.shape[0]
    G, SH, S0, S1 = scratch()
    for c0 in range(0, N, CHUNK):
        _chunk_full(q, T, P, tol, G, SH, S0, S1, c0, min(CHUNK, N - c0), reason, valid, p, u,
                    Tbs, res, item)
    return _input_flags(q, T, rot_tol)


@njit(parallel=True, **_OPTS)
def fk_full_parallel(q, T, P, tol, rot_tol, reason, valid, p, u, Tbs, res, item):
    """:func:`fk_full` with the chunks spread over numba's threads."""
    N = item.shape[0]
    nchunk = (N + CHUNK - 1) // CHUNK
    for ci in prange(nchunk):
        G, SH, S0, S1 = scratch()
        c0 = ci * CHUNK
        _chunk_full(q, T, P, tol, G, SH, S0, S1, c0, min(CHUNK, N - c0), reason, valid, p, u,
                    Tbs, res, item)
    return _input_flags(q, T, rot_tol)


@njit(**_OPTS)
def _count_chunk(S0, S1, n, counts, reasons, slots):
    for ii in range(n):
        R0 = S0[_R * CHUNK + ii]
        R1 = S1[_R * CHUNK + ii]
        ns = 8 * ((R0 == 0.0) + (R1 == 0.0))
        counts[ns] += 1
        reasons[int(item_reason(R0, R1))] += 1
        slots[0] += R0 == 0.0
        slots[1] += R1 == 0.0


@njit(**_OPTS)
def fk_counts(q, T, P, tol, counts, reasons, slots):
    """Reduce FK to histograms (no per-pose output): the kernel of a memory-free sweep.

    ``counts[k]`` += number of poses with ``k`` valid slots (k in 0..16),
    ``reasons[r]`` += number of poses whose ``item_reason`` is ``r``,
    ``slots[m]`` += number of poses whose assembly mode ``m`` has its 8 slots valid.
    """
    N = max(q.shape[0], T.shape[0])
    G, SH, S0, S1 = scratch()
    for c0 in range(0, N, CHUNK):
        n = min(CHUNK, N - c0)
        fk_chunk(q, T, P, tol, G, SH, S0, S1, c0, n)
        _count_chunk(S0, S1, n, counts, reasons, slots)


#: Layout of the packed single-pose buffers of :func:`fk_one`.
ONE_P, ONE_U, ONE_T, ONE_RES, ONE_F = 0, 16, 96, 352, 368
ONE_REASON, ONE_VALID, ONE_ITEM, ONE_I = 0, 16, 32, 33


@njit(**_OPTS)
def fk_one(q, T, P, tol, rot_tol, fbuf, ibuf):
    """One pose, q (3,) and T (4, 4), into packed buffers (low call overhead).

    ``fbuf`` (368,): p (16), u (16 x 5), T_b_s (16 x 4 x 4), residual (16);
    ``ibuf`` (33,) int8: reason (16), valid (16, 0/1), item_reason (1).
    Returns the FLAG_* bits.
    """
    q2 = q.reshape((1, 3))
    T2 = T.reshape((1, 4, 4))
    G, SH, S0, S1 = scratch()
    _chunk_full(q2, T2, P, tol, G, SH, S0, S1, 0, 1,
                ibuf[ONE_REASON:ONE_VALID].reshape((1, 16)),
                ibuf[ONE_VALID:ONE_ITEM].reshape((1, 16)),
                fbuf[ONE_P:ONE_U].reshape((1, 16)), fbuf[ONE_U:ONE_T].reshape((1, 16, 5)),
                fbuf[ONE_T:ONE_RES].reshape((1, 16, 4, 4)),
                fbuf[ONE_RES:ONE_F].reshape((1, 16)), ibuf[ONE_ITEM:ONE_I])
    return _input_flags(q2, T2, rot_tol)


@njit(parallel=True, **_OPTS)
def fk_counts_parallel(q, T, P, tol, counts, reasons, slots):
    """:func:`fk_counts` with the chunks spread over numba's threads."""
    N = max(q.shape[0], T.shape[0])
    nchunk = (N + CHUNK - 1) // CHUNK
    acc = np.zeros((nchunk, 17 + 16 + 2), np.int64)
    for ci in prange(nchunk):
        G, SH, S0, S1 = scratch()
        c0 = ci * CHUNK
        n = min(CHUNK, N - c0)
        fk_chunk(q, T, P, tol, G, SH, S0, S1, c0, n)
        _count_chunk(S0, S1, n, acc[ci, 0:17], acc[ci, 17:33], acc[ci, 33:35])
    for ci in range(nchunk):
        for k in range(17):
            counts[k] += acc[ci, k]
        for k in range(16):
            reasons[k] += acc[ci, 17 + k]
        for k in range(2):
            slots[k] += acc[ci, 33 + k]
