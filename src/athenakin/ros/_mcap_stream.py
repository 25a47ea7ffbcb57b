"""Reading MCAP files: the chunk stream, the CDR JointState layout, the bulk decode of a chunk."""

from __future__ import annotations

import io
import struct
from collections.abc import Iterator
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._typing import IntArray
from ._errors import RecordingError

#: Largest uncompressed MCAP chunk read, bytes.
MAX_CHUNK_BYTES = 1 << 30


_U32 = struct.Struct("<I")


_STAMP = struct.Struct("<iI")


# ---------------------------------------------------------------------------- CDR decoding
class _CdrJointState:
    """Decoder of ``sensor_msgs/msg/JointState`` in CDR, fast for repeated layouts.

    ``decode(raw)`` returns ``(sec, nanosec, names, positions, velocities)``;
    ``names`` is the previous message's tuple object when unchanged (so that the
    caller's lookup of the actuators is cached by identity).
    """

    def __init__(self) -> None:
        self._prefix = b""
        self._size = -1
        self._names: tuple[str, ...] = ()
        self._pos: struct.Struct | None = None
        self._off_pos = 0
        self._off_vcount = 0
        self._nvel = 0
        self._vel: struct.Struct | None = None
        self._off_vel = 0

    def decode(self, raw: bytes | memoryview) -> tuple[int, int, tuple[str, ...],
                                                      tuple[float, ...], tuple[float, ...]]:
        raw = bytes(raw)
        if (len(raw) == self._size and raw.startswith(self._prefix, 12)
                and _U32.unpack_from(raw, self._off_vcount)[0] == self._nvel):
            sec, nsec = _STAMP.unpack_from(raw, 4)
            pos = self._pos.unpack_from(raw, self._off_pos)  # type: ignore[union-attr]
            vel = self._vel.unpack_from(raw, self._off_vel) if self._vel else ()
            return sec, nsec, self._names, pos, vel
        return self._parse(raw)

    def _parse(self, raw: bytes) -> tuple[int, int, tuple[str, ...], tuple[float, ...],
                                          tuple[float, ...]]:
        if len(raw) < 4 or raw[1] != 1:
            raise ValueError(f"not little-endian CDR (encapsulation {raw[:4]!r})")
        o = 4

        def align(o: int, n: int) -> int:
            return o + (-(o - 4) % n)

        def u32(o: int) -> tuple[int, int]:
            o = align(o, 4)
            return _U32.unpack_from(raw, o)[0], o + 4

        def string(o: int) -> tuple[str, int]:
            n, o = u32(o)
            if n == 0 or o + n > len(raw):
                raise ValueError("bad string length")
            return raw[o:o + n - 1].decode("utf-8"), o + n

        def f8seq(o: int) -> tuple[int, int, int]:
            n, o = u32(o)
            o = align(o, 8) if n else o
            if o + 8 * n > len(raw):
                raise ValueError("sequence past the end of the message")
            return n, o, o + 8 * n

        sec, nsec = _STAMP.unpack_from(raw, o)
        o += 8
        _, o = string(o)
        nn, o = u32(o)
        if nn > len(raw):
            raise ValueError("bad name count")
        names = []
        for _ in range(nn):
            s, o = string(o)
            names.append(s)
        npos, off_pos, o = f8seq(o)
        off_vcount = align(o, 4)
        nvel, off_vel, o = f8seq(o)
        _ne, _, o = f8seq(o)
        tnames = tuple(names)
        if tnames != self._names:
            self._names = tnames
        self._prefix = raw[12:off_pos]
        self._size = len(raw)
        self._pos = struct.Struct(f"<{npos}d")
        self._off_pos = off_pos
        self._off_vcount = off_vcount
        self._nvel = nvel
        self._vel = struct.Struct(f"<{nvel}d") if nvel else None
        self._off_vel = off_vel
        return (sec, nsec, self._names, self._pos.unpack_from(raw, off_pos),
                self._vel.unpack_from(raw, off_vel) if self._vel else ())


class _McapStream:
    """The Message records of an MCAP file in file order, read with the mcap library.

    The mcap library reads the file's records (:class:`mcap.stream_reader.StreamReader`)
    and decompresses each chunk, checking its CRC (a mismatch raises
    :class:`~athenakin.ros.RecordingError`). With a summary, the chunks are read from
    its chunk indexes (the per-message index records, which the library parses one
    entry at a time in Python, are skipped); without one (a file cut short), the
    records are read from the start, the data section's CRC checked, and a file that
    ends mid-record stops at the last complete chunk (:attr:`lost`). Only the Message
    records of a decompressed chunk are decoded here, at once (:func:`_scan`): the
    library's reader costs about 20 us per message in Python (a record object each).
    """

    def __init__(self, fh: Any, size: int, summary: Any = None, topic: str | None = None,
                 *, backend: str = "auto") -> None:
        from .._backend import resolve_backend

        #: The chunks decoded at once by the compiled scan (the caller's backend).
        self.compiled = resolve_backend(backend)
        self.fh = fh
        self.size = size
        self.summary = summary
        self.topic = topic
        self.channels: dict[int, tuple[str, int, str]] = {}
        self.schemas: dict[int, str] = {}
        #: ``(byte, reason)``: where a truncated file stopped being readable, else None.
        self.lost: tuple[int, str] | None = None
        #: Messages of the topic handed out.
        self.read = 0
        if summary is not None:
            for sid, s in summary.schemas.items():
                self.schemas[sid] = s.name
            for cid, c in summary.channels.items():
                self.channels[cid] = (c.topic, c.schema_id, c.message_encoding)

    def _keep(self, cid: int) -> bool:
        ch = self.channels.get(cid)
        return self.topic is None or ch is None or ch[0] == self.topic

    def _definition(self, rec: Any) -> None:
        from mcap.records import Channel, Schema

        if isinstance(rec, Schema):
            self.schemas[rec.id] = rec.name
        elif isinstance(rec, Channel):
            self.channels[rec.id] = (rec.topic, rec.schema_id, rec.message_encoding)

    def messages(self) -> Iterator[tuple[int, Any, Any]]:
        """``(channel id, log time, data)`` of the Message records, in file order.

        Runs of Messages of the topic's channel in a chunk come as one item (channel
        id, log times, :class:`_Bulk`) where :func:`_scan` can read the chunk at once.
        """
        from mcap.exceptions import McapError
        from mcap.records import Chunk, Footer, Message
        from mcap.stream_reader import StreamReader

        if self.summary is not None and self.summary.chunk_indexes:
            for ci in sorted(self.summary.chunk_indexes, key=lambda c: c.chunk_start_offset):
                self.fh.seek(ci.chunk_start_offset)
                rec = next(iter(StreamReader(self.fh, skip_magic=True, emit_chunks=True,
                                             record_size_limit=MAX_CHUNK_BYTES).records))
                if not isinstance(rec, Chunk):
                    raise ValueError(f"no chunk at byte {ci.chunk_start_offset} where the "
                                     f"summary's index puts one")
                yield from self._chunk(rec, ci.chunk_start_offset)
            return
        reader = StreamReader(self.fh, emit_chunks=True, validate_crcs=True,
                              record_size_limit=MAX_CHUNK_BYTES)
        records = iter(reader.records)
        good = 8
        while True:
            try:
                rec = next(records)
            except StopIteration:
                return
            except (McapError, struct.error, EOFError, UnicodeDecodeError) as exc:
                self.lost = (good, _why(exc))   # the file ends inside a record
                return
            if isinstance(rec, Chunk):
                yield from self._chunk(rec, good)
            elif isinstance(rec, Message):
                if self._keep(rec.channel_id):
                    yield rec.channel_id, rec.log_time, rec.data
            elif isinstance(rec, Footer):
                return
            else:
                self._definition(rec)
            good = self.fh.tell()

    def _chunk(self, chunk: Any, at: int) -> Iterator[tuple[int, Any, Any]]:
        """The Messages of one chunk (decompressed and CRC-checked by the mcap library)."""
        from mcap.stream_reader import get_chunk_data_stream

        from ._mcap import crc32

        if chunk.uncompressed_size > MAX_CHUNK_BYTES:
            raise ValueError(f"chunk of {chunk.uncompressed_size} bytes uncompressed (at most "
                             f"{MAX_CHUNK_BYTES})")
        if chunk.compression not in ("", "zstd", "lz4"):
            raise ValueError(f"unknown chunk compression {chunk.compression!r}")
        data, n = get_chunk_data_stream(chunk)          # decompressed by the library
        raw = data.read(n) if n else b""
        if len(raw) != chunk.uncompressed_size:
            raise ValueError("chunk does not decompress to its stated size")
        if chunk.uncompressed_crc != 0:   # the check of the library's validate_crc=True,
            crc = crc32(raw)              # with ISA-L's CRC-32 where installed (5x zlib's)
            if crc != chunk.uncompressed_crc:
                raise RecordingError(
                    f"{self.fh.name}: corrupt MCAP file: the chunk at byte {at} fails its "
                    f"CRC check (stored {chunk.uncompressed_crc:#010x}, computed "
                    f"{crc:#010x})")
        bulk = _scan(raw) if self.compiled else None
        if bulk is not None:
            for item in bulk:
                if len(item) == 2:                 # (-opcode, body): a definition
                    self._raw_definition(-item[0], item[1])
                    continue
                yield from self._runs(*item)
            return
        head, msg = _HEAD, _MSG
        o, end = 0, len(raw)
        while o < end:
            op, length = head.unpack_from(raw, o)
            o += 9
            if length > end - o:
                raise ValueError("record past the end of its chunk")
            if op == 0x05:
                cid, _, log_time, _ = msg.unpack_from(raw, o)
                if self._keep(cid):
                    yield cid, log_time, raw[o + 22:o + length]
            elif op in (0x03, 0x04):
                self._raw_definition(op, raw[o:o + length])
            o += length

    def _runs(self, cid: IntArray, t: IntArray, data: NDArray[np.uint8],
              off: IntArray, size: IntArray
              ) -> Iterator[tuple[int, Any, Any]]:
        """The messages of the topic among those of a chunk, as runs of one channel.

        The other channels' messages are dropped at once: a tracked file interleaves
        four topics reading by reading, and the topic's messages of a chunk then make
        one run (a strided view of the chunk, :func:`_rows`), not one run each.
        """
        if not len(cid):
            return
        c0 = int(cid[0])
        ids = [c0] if (cid == c0).all() else np.unique(cid).tolist()
        keep = [c for c in ids if self._keep(c)]
        if len(keep) < len(ids):
            sel = np.isin(cid, keep)
            cid, t, off, size = cid[sel], t[sel], off[sel], size[sel]
        cut = [0, *(np.flatnonzero(np.diff(cid)) + 1).tolist(), len(cid)]
        for i, j in zip(cut[:-1], cut[1:], strict=True):
            if j > i:
                yield int(cid[i]), t[i:j], _Bulk(data, off[i:j], size[i:j])

    def _raw_definition(self, op: int, body: bytes) -> None:
        """A Schema or Channel record of a chunk, from its bytes (spec: mcap.dev/spec)."""
        from mcap.data_stream import ReadDataStream
        from mcap.records import Channel, Schema

        stream = ReadDataStream(io.BytesIO(body))
        self._definition(Schema.read(stream) if op == 0x03 else Channel.read(stream))


def _why(exc: BaseException) -> str:
    """Why the records stopped: a cut record, or what the mcap library says."""
    from mcap.exceptions import EndOfFile

    if isinstance(exc, (EndOfFile, EOFError, struct.error)):
        return "the file ends inside a record"
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


_HEAD = struct.Struct("<BQ")


_MSG = struct.Struct("<HIQQ")


class _Bulk:
    """Messages of one channel in a chunk, message ``i`` at ``data[offsets[i]:][:sizes[i]]``."""

    def __init__(self, data: NDArray[np.uint8], offsets: IntArray,
                 sizes: IntArray) -> None:
        self.data, self.offsets, self.sizes = data, offsets, sizes

    def __len__(self) -> int:
        return len(self.offsets)

    def message(self, i: int) -> bytes:
        o = int(self.offsets[i])
        return self.data[o:o + int(self.sizes[i])].tobytes()


def _scan(raw: bytes) -> list[Any] | None:
    """The Messages of a decompressed chunk, between its definitions, or None.

    Items in record order: ``(channel ids, log times, data, offsets, sizes)`` of the
    Messages between two definitions, ``(-opcode, body)`` for a Schema or Channel
    record. None (the record-by-record path) when
    :func:`athenakin.ros._kernels.scan_records` finds anything unusual. The compiled
    scan: the caller has resolved its backend to numba (:class:`_McapStream`).
    """
    if not raw:
        return None
    from ._kernels import scan_records

    data = np.frombuffer(raw, dtype=np.uint8)
    cap = len(raw) // 9 + 1
    ops, starts, lengths, cids, times = (np.empty(cap, np.int64) for _ in range(5))
    n = scan_records(data, ops, starts, lengths, cids, times)
    if n < 0:
        return None
    ops = ops[:n]
    items: list[Any] = []
    # Schema and Channel records (rosbag2 writes them in the first chunk) cut the chunk:
    # each is handed over in its place, before the messages that follow it
    defs = np.flatnonzero((ops == 0x03) | (ops == 0x04)).tolist()
    for a, b in zip([0, *(d + 1 for d in defs)], [*defs, n], strict=True):
        msg = a + np.flatnonzero(ops[a:b] == 0x05)
        if msg.size:
            items.append((cids[msg], times[msg], data, starts[msg] + 22, lengths[msg] - 22))
        if b < n:
            o = int(starts[b])
            items.append((-int(ops[b]), raw[o:o + int(lengths[b])]))
    return items


def _same_layout(cdr: _CdrJointState, b: _Bulk, j: int
                 ) -> tuple[int, NDArray[np.uint8] | None]:
    """The run of messages from ``j`` with the decoder's last layout, and their bytes.

    ``(e, rows)``: messages ``j .. e-1`` have the size, the bytes between the stamp and
    the positions (frame, names, counts) and the velocity count of the decoder's last
    message, ``rows`` (e - j, size) their bytes; ``(j, None)`` when message ``j`` does not
    (or no layout is known yet): it is decoded alone.
    """
    size = cdr._size
    if size < 0:
        return j, None
    ok = b.sizes[j:] == size
    e = j + (int(np.argmin(ok)) if not ok.all() else len(ok))
    if e == j:
        return j, None
    rows = _rows(b.data, b.offsets[j:e], size)
    prefix = np.frombuffer(cdr._prefix, dtype=np.uint8)
    o = cdr._off_vcount
    good = ((rows[:, 12:12 + len(prefix)] == prefix).all(axis=1)
            & (rows[:, o:o + 4].copy().view("<u4")[:, 0] == cdr._nvel))
    if not good.all():
        e = j + int(np.argmin(good))
        rows = rows[:e - j]
    return (e, rows) if e > j else (j, None)


def _rows(data: NDArray[np.uint8], offsets: IntArray, size: int) -> NDArray[np.uint8]:
    """``data[offsets[i]:offsets[i] + size]`` as rows (n, size).

    Records of one size one after the other (a single topic) are evenly spaced: a
    read-only strided view of ``data``, no copy; otherwise a gather (a copy).
    """
    n = len(offsets)
    step = int(offsets[1] - offsets[0]) if n > 1 else size
    if n and step > 0 and (n == 1 or (np.diff(offsets) == step).all()) \
            and int(offsets[0]) + (n - 1) * step + size <= len(data):
        view = np.lib.stride_tricks.as_strided(data[int(offsets[0]):], shape=(n, size),
                                               strides=(step, 1), writeable=False)
        return view
    return data[offsets[:, None] + np.arange(size)]
