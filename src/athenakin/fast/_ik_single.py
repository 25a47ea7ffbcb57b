"""Compiled single-item IK kernels (private): the packed buffers of a single call.

:func:`ik_paper_one` / :func:`ik_paper_lean` (paper form) and :func:`ik_line_one` /
:func:`ik_line_one_packed` (controller forms) run the chunk kernels of
:mod:`._ik_kernels` on one item and pack the results into one float and one int
buffer (layouts ``ONE_*``, ``LINE_*``), for the lean calls and :class:`ControlLoop`.
"""

from __future__ import annotations

import numpy as np

from .._backend import njit
from ._fk_kernels import CHUNK, FLAG_NO_SOLUTION, FLAG_T_NONFINITE
from ._ik_kernels import (
    _NGP2,
    FLAG_P_NONFINITE,
    FLAG_V_NONFINITE,
    FLAG_ZERO_DIRECTION,
    _line_chunk,
    _line_flags,
    _line_stage,
    _paper_chunk,
    _paper_flags,
)
from ._parallel_kernels import _Q1, _REASON, NK, _pik_stage

__all__ = ["ik_paper_one", "ik_paper_lean", "ik_line_one", "ik_line_one_packed"]

_OPTS = dict(error_model="numpy", cache=True, nogil=True)
_INLINE = dict(_OPTS, inline="always")


#: Layout of the packed single-item buffer of :func:`ik_paper_one`:
#: q (3), p (1), u (5), T_b_s (16), residual (1), q_error (1); ints: mode, valid, reason.
ONE_Q, ONE_P, ONE_U, ONE_T, ONE_RES, ONE_QE, ONE_F = 0, 3, 4, 9, 25, 26, 27


@njit(**_INLINE)
def _paper_item(T2, U2, P, stol, ctol, fbuf, mode, Tbs):
    """One paper-form item through the chunk kernel: ``(valid, reason)``.

    ``fbuf`` (27,) receives q, p, u, residual and q_error (layout ``ONE_*``); ``mode``
    (1,) and ``Tbs`` (1, 4, 4) the mode and ``T_b_s`` (views of the caller's arrays).
    """
    G = np.empty(_NGP2 * CHUNK)
    K = np.empty(NK * CHUNK)
    valid = np.empty(1, np.bool_)
    reason = np.empty(1, np.int8)
    _paper_chunk(T2, U2, P, stol, ctol, G, K, 0, 1, fbuf[ONE_Q:ONE_P].reshape((1, 3)),
                 fbuf[ONE_P:ONE_U], fbuf[ONE_U:ONE_T].reshape((1, 5)), mode, Tbs,
                 fbuf[ONE_RES:ONE_QE], valid, reason, fbuf[ONE_QE:ONE_F])
    return valid[0], reason[0]


@njit(**_OPTS)
def ik_paper_one(T, U, P, stol, ctol, rot_tol, fbuf, ibuf):
    """Paper-form IK of one item, T (4, 4) and U (3,), into packed buffers.

    ``fbuf`` (27,): q, p, u, T_b_s, residual, q_error; ``ibuf`` (3,) int64: mode, valid,
    reason.
    Returns the FLAG_* bits.
    """
    T2 = T.reshape((1, 4, 4))
    U2 = U.reshape((1, 3))
    ibuf[1], ibuf[2] = _paper_item(T2, U2, P, stol, ctol, fbuf, ibuf[0:1],
                                   fbuf[ONE_T:ONE_RES].reshape((1, 4, 4)))
    return _paper_flags(T2, U2, rot_tol)


@njit(**_OPTS)
def ik_paper_lean(T, U, PT, fbuf, Tbs, mode):
    """:func:`ik_paper_one` for the lean single call, into the result's own arrays.

    ``PT`` (16,): the design's parameter vector (13), ``singular_tol``, ``closure_tol``
    and the rigidity tolerance, as one array (each argument costs the dispatch about
    50 ns, as :func:`._fk_sized.fk_one_lean`'s).
    ``fbuf`` (27,) as :func:`ik_paper_one`'s (its ``T_b_s`` part unused here),
    ``Tbs`` (4, 4) and ``mode`` (0-d int64) receive ``T_b_s`` and the mode (no
    views to make in Python); the same stages as :func:`ik_paper_one`. Returns the
    FLAG_* bits, plus :data:`FLAG_NO_SOLUTION` when the item has no solution: 0 means
    a valid result (``valid`` True, ``reason`` 0); anything else sends the caller down
    the general path.
    """
    T2 = T.reshape((1, 4, 4))
    U2 = U.reshape((1, 3))
    reason = _paper_item(T2, U2, PT[:13], PT[13], PT[14], fbuf, mode.reshape((1,)),
                         Tbs.reshape((1, 4, 4)))[1]
    return _paper_flags(T2, U2, PT[15]) | (FLAG_NO_SOLUTION if reason != 0 else 0)


@njit(**_OPTS)
def ik_line_one(T, V, pv, P, kind, q):
    """Controller-form IK of one item (no input checks): writes q (3,), returns the reason.

    ``kind`` 0: V is the direction in E and ``pv`` the insertion; 1: V is the tool tip.
    """
    G = np.empty(16 * CHUNK)
    K = np.empty(NK * CHUNK)
    for r in range(3):
        for c in range(4):
            G[(4 * r + c) * CHUNK] = T[r, c]
    for c in range(3):
        G[(12 + c) * CHUNK] = V[c]
    G[15 * CHUNK] = pv if kind == 0 else P[12]
    _line_stage(G, K, kind, 1)
    _pik_stage(K, P, 1)
    for c in range(3):
        q[c] = K[(_Q1 + c) * CHUNK]
    return int(K[_REASON * CHUNK])


#: Packed single-item output of :func:`ik_line_one_packed`: q (3), p, d_b (3), O_s (3),
#: q_error.
LINE_Q, LINE_P, LINE_D, LINE_O, LINE_QE, LINE_F = 0, 3, 4, 7, 10, 11


@njit(**_OPTS)
def ik_line_one_packed(T, V, pv, P, kind, rot_tol, fbuf, ibuf):
    """Controller-form IK of one item with input flags: fbuf (11,), ibuf (3,) int64.

    ``ibuf`` receives mode, valid, reason. Returns the FLAG_* bits (nothing computed
    when an input is non-finite or a direction is zero: the caller raises).
    """
    T2 = T.reshape((1, 4, 4))
    V2 = V.reshape((1, 3))
    Pp = np.empty(1)
    Pp[0] = pv
    flags = _line_flags(T2, V2, Pp, kind, rot_tol)
    if flags & (FLAG_T_NONFINITE | FLAG_V_NONFINITE | FLAG_P_NONFINITE | FLAG_ZERO_DIRECTION):
        return flags
    G = np.empty(16 * CHUNK)
    K = np.empty(NK * CHUNK)
    valid = np.empty(1, np.bool_)
    reason = np.empty(1, np.int8)
    _line_chunk(T2, V2, Pp, P, kind, G, K, 0, 1, fbuf[LINE_Q:LINE_P].reshape((1, 3)),
                fbuf[LINE_P:LINE_D], fbuf[LINE_D:LINE_O].reshape((1, 3)),
                fbuf[LINE_O:LINE_QE].reshape((1, 3)), ibuf[0:1], valid, reason,
                fbuf[LINE_QE:LINE_F])
    ibuf[1] = valid[0]
    ibuf[2] = reason[0]
    return flags
