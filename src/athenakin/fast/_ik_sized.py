"""Compiled paper-form IK writing only the fields asked for (private).

The stages are those of :func:`._ik_kernels.ik_paper` (same values bit for bit);
only the store differs: ``want`` (a bit mask of ``WANT_*``) selects the arrays of
:class:`~athenakin.robot.PassiveJoints` to write, ``q`` is always written. A sweep
that needs ``q`` and ``valid`` writes 25 bytes per pose instead of 218.
"""

# numba's cache does not follow the kernels this module inlines from _fk_kernels, _ik_kernels and
# _scalar: a change there must change this file too (revision 3).

from __future__ import annotations

import numpy as np

from .._backend import njit
from ._fk_kernels import CHUNK
from ._ik_kernels import (
    _MODE,
    _NGP2,
    _P,
    _RES,
    _U1,
    NK,
    _paper_flags,
    _paper_gather,
    _paper_stage1,
    _paper_stage2,
    _pik_stage,
    _store_q,
    _store_T_b_s,
)

__all__ = ["WANT_P", "WANT_U", "WANT_MODE", "WANT_T", "WANT_RES", "WANT_VALID", "WANT_REASON",
           "WANT_ALL", "ik_paper_select"]

#: Bits of ``want`` in :func:`ik_paper_select`.
WANT_P, WANT_U, WANT_MODE, WANT_T, WANT_RES, WANT_VALID, WANT_REASON = 1, 2, 4, 8, 16, 32, 64
WANT_ALL = 127

_OPTS = dict(error_model="numpy", cache=True, nogil=True)


@njit(**_OPTS)
def _store_select(K, c0, n, want, q, p, u, mode, Tbs, res, valid, reason):
    """:func:`._ik_kernels._paper_store` writing only the fields in ``want``."""
    for ii in range(n):
        i = c0 + ii
        r, mask = _store_q(K, ii, q, i)
        if want & WANT_P:
            p[i] = K[_P * CHUNK + ii] + mask
        if want & WANT_U:
            for c in range(5):
                u[i, c] = K[(_U1 + c) * CHUNK + ii] + mask
        if want & WANT_MODE:
            mode[i] = np.int64(K[_MODE * CHUNK + ii]) if r == 0.0 else 0
        if want & WANT_T:
            _store_T_b_s(K, ii, mask, Tbs, i)
        if want & WANT_RES:
            res[i] = K[_RES * CHUNK + ii] + mask
        if want & WANT_REASON:
            reason[i] = np.int8(r)
        if want & WANT_VALID:
            valid[i] = r == 0.0


@njit(**_OPTS)
def ik_paper_select(T, U, P, stol, ctol, rot_tol, want, q, p, u, mode, Tbs, res, valid, reason):
    """:func:`._ik_kernels.ik_paper` writing ``q`` and the fields in ``want`` only.

    Arrays of fields not in ``want`` are not touched (they may have 0 rows); ``N``
    is ``len(q)``. Returns the FLAG_* bits of :func:`._ik_kernels.ik_paper`.
    """
    N = q.shape[0]
    G = np.empty(_NGP2 * CHUNK)
    K = np.empty(NK * CHUNK)
    for c0 in range(0, N, CHUNK):
        n = min(CHUNK, N - c0)
        _paper_gather(T, U, c0, n, G)
        _paper_stage1(G, K, stol, n)
        _pik_stage(K, P, n)
        _paper_stage2(G, K, ctol, n)
        _store_select(K, c0, n, want, q, p, u, mode, Tbs, res, valid, reason)
    return _paper_flags(T, U, rot_tol)
