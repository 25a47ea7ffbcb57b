"""Compiled scan of the records of a decompressed MCAP chunk (private; the ROS reader).

:func:`scan_records` walks the records of a chunk as :class:`athenakin.ros._read._McapStream`
does record by record in Python, and returns where each one lies; the reader then reads
every message of a fixed CDR layout at once with numpy. Anything unusual (a record past
the end, a Message shorter than its header, a log time beyond ``2**63``) returns -1 and
the reader takes its record-by-record path, which raises its own error.
"""

from __future__ import annotations

from numba import njit

__all__ = ["scan_records"]


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
