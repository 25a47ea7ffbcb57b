"""Compiled FK sized to the information (private): ``T_b_s`` once per mode, chosen fields only.

The arithmetic is that of :mod:`._fk_stages` (the same scratch stages, hence the
same values bit for bit); only the stores differ:

* ``T_b_s`` is written once per assembly mode, ``(N, 2, 4, 4)`` instead of
  ``(N, 16, 4, 4)`` (the 8 slots of a mode share it): 256 instead of 2048 bytes
  per pose;
* :func:`fk_select` writes only the fields asked for (``want``, a bit mask of
  ``WANT_*``): a sweep that needs ``p``, ``u`` and ``valid`` writes 784 bytes per
  pose instead of 1185. The arrays of the fields not asked for may have 0 rows.
"""

# numba's cache does not follow the kernels this module inlines from _fk_stages,
# _fk_kernels and _scalar: a change there must change this file too (revision 4).

from __future__ import annotations

import math

import numpy as np

from .._backend import njit
from ._fk_kernels import (
    FLAG_NO_SOLUTION,
    _chunk_full,
    _input_flags,
    _store_T_b_s_mode,
    _store_u_mode,
    item_reason,
)
from ._fk_stages import _NN, _PR, _PRES, _R, _RES, _XM, CHUNK, fk_chunk, scratch
from ._scalar import nanmax2

__all__ = ["WANT_VALID", "WANT_REASON", "WANT_P", "WANT_U", "WANT_T", "WANT_RES", "WANT_ALL",
           "fk_select", "fk_one_arrays", "fk_one_lean", "FLAG_NO_SOLUTION"]


#: Bits of ``want`` in :func:`fk_select`.
WANT_VALID, WANT_REASON, WANT_P, WANT_U, WANT_T, WANT_RES = 1, 2, 4, 8, 16, 32
WANT_ALL = 63

_OPTS = dict(error_model="numpy", cache=True, nogil=True)

@njit(**_OPTS)
def _store_mode_select(Sm, ii, i, k0, m, xm, pres, want, reason, valid, p, u, Tbs, res):
    """:func:`._fk_kernels._store_mode` writing only the fields in ``want``."""
    R = Sm[_R * CHUNK + ii]
    ok = R == 0.0
    mask = 0.0 if ok else math.nan
    if want & (WANT_VALID | WANT_REASON | WANT_RES):
        r8 = np.int8(R)
        rv = nanmax2(Sm[_RES * CHUNK + ii], pres) + mask   # merged modes (_fk_kernels)
        for j in range(8):
            if want & WANT_REASON:
                reason[i, k0 + j] = r8
            if want & WANT_VALID:
                valid[i, k0 + j] = ok
            if want & WANT_RES:
                res[i, k0 + j] = rv
    if want & WANT_P:
        nn = Sm[_NN * CHUNK + ii] + mask
        for j in range(8):
            p[i, k0 + j] = nn if (j >> 2) == 0 else -nn
    if want & WANT_U:
        _store_u_mode(Sm, ii, mask, u, i, k0)
    if want & WANT_T:
        pmask = 0.0 if Sm[_PR * CHUNK + ii] == 0.0 else math.nan
        _store_T_b_s_mode(Sm, ii, xm, pmask, Tbs, i, m)


@njit(**_OPTS)
def fk_select(q, T, P, tol, rot_tol, want, reason, valid, p, u, Tbs, res, item):
    """The fields ``want`` of ``N = len(item)`` poses (``T_b_s`` per mode: (N, 2, 4, 4)).

    Parameters and the returned FLAG_* bits as :func:`._fk_kernels.fk_full`; arrays of
    fields not in ``want`` are not touched (they may have 0 rows). ``item`` is always
    written.
    """
    N = item.shape[0]
    G, SH, S0, S1 = scratch()
    for c0 in range(0, N, CHUNK):
        n = min(CHUNK, N - c0)
        fk_chunk(q, T, P, tol, G, SH, S0, S1, c0, n)
        for ii in range(n):
            i = c0 + ii
            xm = SH[_XM * CHUNK + ii]
            pres = SH[_PRES * CHUNK + ii]
            item[i] = np.int8(item_reason(S0[_R * CHUNK + ii], S1[_R * CHUNK + ii]))
            _store_mode_select(S0, ii, i, 0, 0, xm, pres, want, reason, valid, p, u, Tbs, res)
            _store_mode_select(S1, ii, i, 8, 1, xm, pres, want, reason, valid, p, u, Tbs, res)
    return _input_flags(q, T, rot_tol)


@njit(**_OPTS)
def fk_one_arrays(q, T, P, tol, rot_tol, reason, valid, p, u, Tbs, res, item):
    """One pose into the result's own arrays (shapes (16,), (16, 5), (2, 4, 4), (1,)).

    The 1-pose form of :func:`._fk_kernels.fk_full`: the reshapes happen here, in
    compiled code, instead of as numpy views in Python. Returns the FLAG_* bits.
    """
    q2 = q.reshape((1, 3))
    T2 = T.reshape((1, 4, 4))
    G, SH, S0, S1 = scratch()
    _chunk_full(q2, T2, P, tol, G, SH, S0, S1, 0, 1, reason.reshape((1, 16)),
                valid.reshape((1, 16)), p.reshape((1, 16)), u.reshape((1, 16, 5)),
                Tbs.reshape((1, 2, 4, 4)), res.reshape((1, 16)), item)
    return _input_flags(q2, T2, rot_tol)


@njit(**_OPTS)
def fk_one_lean(q, T, PT, reason, valid, p, u, Tbs, res):
    """:func:`fk_one_arrays` for the lean single call: options packed, no ``item`` array.

    ``PT`` (18,): the design's parameter vector (13), the four tolerances of
    :func:`._fk_kernels.fk_full`'s ``tol`` and ``rot_tol``, as one array (each
    argument costs the dispatch about 50 ns). Returns the FLAG_* bits, plus
    :data:`FLAG_NO_SOLUTION` when the pose has no valid slot: 0 means a result to
    return as it is (``item_reason`` 0), anything else sends the caller down the
    general path.
    """
    item = np.empty(1, np.int8)
    flags = fk_one_arrays(q, T, PT[:13], PT[13:17], PT[17], reason, valid, p, u, Tbs, res,
                          item)
    return flags | (FLAG_NO_SOLUTION if item[0] != 0 else 0)
