"""Compiled scan and fill of the records of MCAP chunks (private; the ROS reader and writer).

:func:`scan_records` walks the records of a chunk as :class:`athenakin.ros._mcap_stream._McapStream`
does record by record in Python, and returns where each one lies; the reader then reads
every message of a fixed CDR layout at once with numpy. Anything unusual (a record past
the end, a Message shorter than its header, a log time beyond ``2**63``) returns -1 and
the reader takes its record-by-record path, which raises its own error.

:func:`fill_records` is the writer's side: the Message records of a chunk of tracked
readings (fixed-size CDR messages: template bytes and numbers at fixed offsets) written
into one buffer in a single pass, the readings without a pose keeping only their status.
"""

from __future__ import annotations

import numpy as np

from .._backend import njit

__all__ = ["scan_records", "fill_records"]


@njit(cache=True, nogil=True)
def scan_records(raw, ops, starts, lengths, cids, times):
    """Records of ``raw`` (uint8) into the arrays: opcode, start and length of each body.

    For Messages also their channel and log time. Returns the number of records, or -1
    (see the module docstring).
    """
    o = 0
    end = raw.size
    n = 0
    while o < end:
        if end - o < 9:
            return -1
        length = 0
        for b in range(7):
            length |= int(raw[o + 1 + b]) << (8 * b)
        if raw[o + 8] != 0:                    # beyond 2**56 bytes: past any chunk
            return -1
        op = int(raw[o])
        o += 9
        if length > end - o:
            return -1
        ops[n] = op
        starts[n] = o
        lengths[n] = length
        if op == 5:
            if length < 22 or raw[o + 13] >= 128:
                return -1
            cids[n] = int(raw[o]) | (int(raw[o + 1]) << 8)
            t = 0
            for b in range(8):
                t |= int(raw[o + 6 + b]) << (8 * b)
            times[n] = t
        n += 1
        o += length
    return n


# Byte offsets are unsigned (uint64) below: an unsigned index needs no negative-index
# wraparound, so LLVM vectorises the template copy and merges the stores of a number's bytes
# (measured: about 15x faster than signed int64 offsets, within 2x of memcpy and one store).
_U8, _U16, _U24, _U32 = np.uint64(8), np.uint64(16), np.uint64(24), np.uint64(32)
_U40, _U48, _U56, _MASK = np.uint64(40), np.uint64(48), np.uint64(56), np.uint64(0xFF)


@njit(cache=True, nogil=True, inline="always")
def _copy_into(dst, at, src):
    """``dst[at:at + src.size] = src`` (uint8, ``at`` uint64); the caller sizes ``dst``."""
    n = np.uint64(src.size)
    k = np.uint64(0)
    while k < n:
        dst[at + k] = src[k]
        k += np.uint64(1)


@njit(cache=True, nogil=True, inline="always")
def _fill(out, o, words, i, off, size, col):
    """Field ``f``: the ``size[f]`` (1, 4, 8) low bytes of ``words[i, col[f]]`` at ``o + off[f]``.

    Little endian, unaligned; ``o`` uint64.
    """
    for f in range(off.size):
        w = words[i, col[f]]
        at = o + np.uint64(off[f])
        z = size[f]
        out[at] = np.uint8(w & _MASK)
        if z >= 4:
            out[at + np.uint64(1)] = np.uint8((w >> _U8) & _MASK)
            out[at + np.uint64(2)] = np.uint8((w >> _U16) & _MASK)
            out[at + np.uint64(3)] = np.uint8((w >> _U24) & _MASK)
            if z == 8:
                out[at + np.uint64(4)] = np.uint8((w >> _U32) & _MASK)
                out[at + np.uint64(5)] = np.uint8((w >> _U40) & _MASK)
                out[at + np.uint64(6)] = np.uint8((w >> _U48) & _MASK)
                out[at + np.uint64(7)] = np.uint8((w >> _U56) & _MASK)


@njit(cache=True, nogil=True, boundscheck=False)
def fill_records(out, status_tpl, pose_tpl, words, s_off, s_size, s_col, p_off, p_size, p_col,
                 valid, starts):
    """Message records of tracked readings, built in place (the MCAP writer's chunks).

    For each reading ``i``: the bytes of ``status_tpl`` then, where ``valid[i]``, those of
    ``pose_tpl``, one after the other in ``out``; then the numbers: field ``f`` of the
    status part gets the ``s_size[f]`` (1, 4 or 8) low bytes (little endian) of
    ``words[i, s_col[f]]`` at ``s_off[f]`` of its copy, and likewise the pose part.

    Parameters
    ----------
    out : (cap,) uint8
        At least ``n * len(status_tpl) + sum(valid) * len(pose_tpl)`` bytes (checked:
        -1 when too small).
    status_tpl, pose_tpl : uint8
    words : (n, C) uint64
        The numbers of each reading as 8-byte words (float64 bit patterns, two's
        complement integers).
    s_off, s_size, s_col, p_off, p_size, p_col : int64
        Offsets within the template (each field inside it), sizes, columns of ``words``.
    valid : (n,) bool
    starts : (n,) int64
        Filled: where the records of each reading start in ``out``.

    Returns
    -------
    int
        Bytes written, or -1 (nothing written) when ``out`` is too small or a field lies
        outside its template.
    """
    rs = status_tpl.size
    rp = pose_tpl.size
    need = 0
    for i in range(valid.size):
        need += rs + (rp if valid[i] else 0)
    if need > out.size:
        return -1
    for f in range(s_off.size):
        if s_off[f] < 0 or s_off[f] + s_size[f] > rs or s_col[f] >= words.shape[1]:
            return -1
    for f in range(p_off.size):
        if p_off[f] < 0 or p_off[f] + p_size[f] > rp or p_col[f] >= words.shape[1]:
            return -1
    o = np.uint64(0)
    us, up = np.uint64(rs), np.uint64(rp)
    for i in range(valid.size):
        starts[i] = o
        _copy_into(out, o, status_tpl)
        _fill(out, o, words, i, s_off, s_size, s_col)
        o += us
        if valid[i]:
            _copy_into(out, o, pose_tpl)
            _fill(out, o, words, i, p_off, p_size, p_col)
            o += up
    return np.int64(o)
