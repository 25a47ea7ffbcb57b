"""A minimal MCAP writer whose chunks are built with numpy, many messages at once (private).

The mcap library's writer costs tens of microseconds per message in Python; a
tracked reading makes four messages. Here a chunk of thousands of readings is
laid out as one byte array (the Message records of fixed-size CDR messages sit at
computable offsets), compressed once, and followed by its MessageIndex records;
the summary (schemas, channels, statistics, chunk indexes, summary offsets) and
the CRCs follow the MCAP specification (https://mcap.dev/spec). The tests read
every file back with the mcap library, rosbags and mcap-ros2-support.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Callable
from typing import IO, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._typing import IntArray
from ._errors import ros_extra_missing

__all__ = ["McapFile", "MESSAGE_HEADER", "COMPRESSIONS", "ZSTD_LEVEL", "check_compression",
           "compressor_module"]


MAGIC = b"\x89MCAP0\r\n"
#: Bytes of a Message record before its data: opcode, length, channel, sequence, two times.
MESSAGE_HEADER = 1 + 8 + 2 + 4 + 8 + 8
#: Chunk compressions.
COMPRESSIONS = ("zstd", "lz4", "none")
_OP = {"header": 0x01, "footer": 0x02, "schema": 0x03, "channel": 0x04, "message": 0x05,
       "chunk": 0x06, "message_index": 0x07, "chunk_index": 0x08, "statistics": 0x0B,
       "summary_offset": 0x0E, "data_end": 0x0F}
_MSG_DTYPE = np.dtype({"names": ["op", "length", "channel", "sequence", "log_time",
                                 "publish_time"],
                       "formats": ["u1", "<u8", "<u2", "<u4", "<u8", "<u8"],
                       "offsets": [0, 1, 9, 11, 15, 23], "itemsize": MESSAGE_HEADER})
_INDEX_DTYPE = np.dtype([("log_time", "<u8"), ("offset", "<u8")])


def _crc32_function() -> Callable[..., int]:
    """CRC-32 (the zlib polynomial MCAP uses): ISA-L's where installed, else zlib's.

    The same numbers; ISA-L's is several times faster (a tracked reading makes about
    2.5 kB of records, each checked once uncompressed in its chunk).
    """
    try:
        from isal.isal_zlib import crc32
    except ImportError:
        return zlib.crc32
    return crc32  # type: ignore[no-any-return]


_crc32 = _crc32_function()
#: CRC-32 of MCAP (public within the package: the reader checks chunks with it).
crc32 = _crc32


def _s(text: str) -> bytes:
    b = text.encode("utf-8")
    return struct.pack("<I", len(b)) + b


def _record(op: str, body: bytes) -> bytes:
    return struct.pack("<BQ", _OP[op], len(body)) + body


def _map_str(d: dict[str, str]) -> bytes:
    body = b"".join(_s(k) + _s(v) for k, v in d.items())
    return struct.pack("<I", len(body)) + body


#: zstd level of the chunks unless told (see :func:`check_compression`).
ZSTD_LEVEL = -3
#: Accepted levels: zstd's fast (negative) levels and its usual 1..22; lz4 frame 0..16.
_LEVELS = {"zstd": (-7, 22), "lz4": (0, 16)}


def check_compression(compression: object, level: object) -> tuple[str, int | None]:
    """``(compression, level)`` checked; ``level`` None -> the default of the compression.

    Raises
    ------
    InvalidInputError
        ``compression`` not one of :data:`COMPRESSIONS`; ``level`` not an integer in the
        range of the compression (zstd -7..22, lz4 0..16), or given with ``"none"``.
    """
    from ..errors import InvalidInputError

    if not isinstance(compression, str) or compression not in COMPRESSIONS:
        raise InvalidInputError(f"compression: expected one of {COMPRESSIONS}, got "
                                f"{compression!r}")
    if level is None:
        return compression, (ZSTD_LEVEL if compression == "zstd" else
                             0 if compression == "lz4" else None)
    if compression == "none":
        raise InvalidInputError(f"compression_level: expected None with compression='none', "
                                f"got {level!r}")
    lo, hi = _LEVELS[compression]
    if isinstance(level, bool) or not isinstance(level, (int, np.integer)) \
            or not lo <= int(level) <= hi:
        raise InvalidInputError(f"compression_level: expected an integer from {lo} to {hi} "
                                f"for {compression}, got {level!r}")
    return compression, int(level)


def compressor_module(compression: str) -> Any:
    """The module of a chunk compression: ``zstandard``, ``lz4.frame``, or None for "none".

    Raises
    ------
    ModuleNotFoundError
        The package is not installed (the ``ros`` extra); ``name`` is the package's,
        the message says which extra installs it.
    """
    try:
        if compression == "zstd":
            import zstandard

            return zstandard
        if compression == "lz4":
            import lz4.frame

            return lz4.frame
    except ModuleNotFoundError as exc:
        raise ros_extra_missing(exc) from None
    return None


class McapFile:
    """Write an MCAP file: schemas, channels, then chunks of messages, then the summary.

    Parameters
    ----------
    fh : binary file
        Opened for writing, positioned at 0.
    compression : {"zstd", "lz4", "none"}
    level : int, optional
        Compression level (:func:`check_compression`; default :data:`ZSTD_LEVEL` for
        zstd, 0 for lz4).
    profile, library : str
        The Header record's fields.
    """

    def __init__(self, fh: IO[bytes], *, compression: str = "zstd", level: int | None = None,
                 profile: str = "ros2", library: str = "athenakin.ros") -> None:
        compression, level = check_compression(compression, level)
        self._fh = fh
        self._compression = compression
        if compression == "zstd":
            self._compress = compressor_module("zstd").ZstdCompressor(
                level=ZSTD_LEVEL if level is None else level).compress
        elif compression == "lz4":
            import functools

            self._compress = functools.partial(compressor_module("lz4").compress,
                                               compression_level=level)
        self._pos = 0
        self._crc = 0
        self._schemas: list[bytes] = []
        self._channels: list[bytes] = []
        self._chunk_indexes: list[bytes] = []
        self._counts: dict[int, int] = {}
        self._start: int | None = None
        self._end: int | None = None
        self._n_chunks = 0
        self._write(MAGIC)
        self._write(_record("header", _s(profile) + _s(library)))

    def _write(self, data: bytes | memoryview) -> None:
        self._fh.write(data)
        self._crc = _crc32(data, self._crc)
        self._pos += len(data)

    # ------------------------------------------------------------------ definitions
    def schema(self, name: str, encoding: str, data: bytes) -> int:
        """Write a Schema record; returns its id (1, 2, ...)."""
        sid = len(self._schemas) + 1
        rec = _record("schema", struct.pack("<H", sid) + _s(name) + _s(encoding)
                      + struct.pack("<I", len(data)) + data)
        self._schemas.append(rec)
        self._write(rec)
        return sid

    def channel(self, topic: str, message_encoding: str, schema_id: int,
                metadata: dict[str, str] | None = None) -> int:
        """Write a Channel record; returns its id (1, 2, ...)."""
        cid = len(self._channels) + 1
        rec = _record("channel", struct.pack("<HH", cid, schema_id) + _s(topic)
                      + _s(message_encoding) + _map_str(metadata or {}))
        self._channels.append(rec)
        self._counts[cid] = 0
        self._write(rec)
        return cid

    # ------------------------------------------------------------------ messages
    @staticmethod
    def message_headers(out: NDArray[np.uint8], channel: int, sequence: ArrayLike,
                        log_time: ArrayLike, size: int) -> None:
        """Write the headers of ``n`` Message records of ``size`` data bytes into ``out``.

        ``out`` has shape (n, MESSAGE_HEADER), each row contiguous (a column slice of a
        larger buffer); the data follows each header in the caller's buffer.
        """
        n = out.shape[0]
        head = out.view(_MSG_DTYPE).reshape(n)
        head["op"] = _OP["message"]
        head["length"] = MESSAGE_HEADER - 9 + size
        head["channel"] = channel
        head["sequence"] = np.asarray(sequence) & 0xFFFFFFFF
        head["log_time"] = log_time
        head["publish_time"] = log_time

    @staticmethod
    def message_records(channel: int, sequence: ArrayLike, log_time: ArrayLike,
                        data: NDArray[np.uint8]) -> NDArray[np.uint8]:
        """Message records of ``n`` messages of one size: shape (n, MESSAGE_HEADER + size)."""
        n, size = data.shape
        out = np.empty((n, MESSAGE_HEADER + size), dtype=np.uint8)
        McapFile.message_headers(out[:, :MESSAGE_HEADER], channel, sequence, log_time, size)
        out[:, MESSAGE_HEADER:] = data
        return out

    def chunk(self, records: bytes | NDArray[np.uint8],
              index: dict[int, tuple[IntArray, IntArray]]) -> None:
        """Write one chunk of Message records and its MessageIndex records.

        Parameters
        ----------
        records : bytes or uint8 array
            The chunk's records, one after the other, in log-time order.
        index : dict of channel id -> (log times, offsets of the records in ``records``)
        """
        # a contiguous array is read in place (buffer protocol): no copy of the chunk
        raw: bytes | memoryview = (memoryview(np.ascontiguousarray(records)).cast("B")  # type: ignore[arg-type]
                                   if isinstance(records, np.ndarray) else bytes(records))
        if not len(raw):
            return
        start = min(int(t.min()) for t, _ in index.values() if len(t))
        end = max(int(t.max()) for t, _ in index.values() if len(t))
        crc = _crc32(raw)
        packed = raw if self._compression == "none" else self._compress(raw)
        comp = "" if self._compression == "none" else self._compression
        body = (struct.pack("<QQQI", start, end, len(raw), crc) + _s(comp)
                + struct.pack("<Q", len(packed)))
        chunk_start = self._pos
        self._write(struct.pack("<BQ", _OP["chunk"], len(body) + len(packed)) + body)
        self._write(packed)
        chunk_length = self._pos - chunk_start
        offsets = {}
        index_start = self._pos
        for cid in sorted(index):
            t, off = index[cid]
            if not len(t):
                continue
            entries = np.empty(len(t), _INDEX_DTYPE)
            entries["log_time"] = t
            entries["offset"] = off
            eb = entries.tobytes()
            offsets[cid] = self._pos
            self._write(_record("message_index", struct.pack("<HI", cid, len(eb)) + eb))
            self._counts[cid] += len(t)
        idx_map = b"".join(struct.pack("<HQ", c, o) for c, o in offsets.items())
        self._chunk_indexes.append(_record("chunk_index", struct.pack(
            "<QQQQ", start, end, chunk_start, chunk_length)
            + struct.pack("<I", len(idx_map)) + idx_map
            + struct.pack("<Q", self._pos - index_start) + _s(comp)
            + struct.pack("<QQ", len(packed), len(raw))))
        self._start = start if self._start is None else min(self._start, start)
        self._end = end if self._end is None else max(self._end, end)
        self._n_chunks += 1

    def messages(self, items: list[tuple[int, int, int, int, bytes]]) -> None:
        """Write one chunk of messages of any sizes, in log-time order.

        Parameters
        ----------
        items : list of (channel, sequence, log_time, publish_time, data)
            Channel ids, sequence numbers, times (ns) and the messages' bytes; sorted
            here by log time (stably) before they are laid out.
        """
        if not items:
            return
        items = sorted(items, key=lambda it: it[2])
        head = struct.Struct("<BQHIQQ")
        buf = bytearray()
        index: dict[int, tuple[list[int], list[int]]] = {}
        for channel, sequence, log_time, publish_time, data in items:
            times, offsets = index.setdefault(channel, ([], []))
            times.append(log_time)
            offsets.append(len(buf))
            buf += head.pack(_OP["message"], MESSAGE_HEADER - 9 + len(data), channel,
                             sequence & 0xFFFFFFFF, log_time, publish_time)
            buf += data
        self.chunk(bytes(buf), {c: (np.array(t, dtype=np.uint64), np.array(o, dtype=np.uint64))
                                for c, (t, o) in index.items()})

    def single(self, channel: int, sequence: int, log_time: int, data: bytes) -> None:
        """One message in a chunk of its own."""
        rec = self.message_records(channel, np.array([sequence]), np.array([log_time]),
                                   np.frombuffer(data, dtype=np.uint8)[None, :])
        self.chunk(rec, {channel: (np.array([log_time]), np.array([0]))})

    # ------------------------------------------------------------------ finish
    def close(self) -> None:
        """Write DataEnd, the summary section and the footer (the file is then complete)."""
        self._write(_record("data_end", struct.pack("<I", self._crc)))
        summary_start = self._pos
        self._crc = 0
        groups = []
        counts = {c: n for c, n in self._counts.items()}
        stats = (struct.pack("<QHIIII", sum(counts.values()), len(self._schemas),
                             len(self._channels), 0, 0, self._n_chunks)
                 + struct.pack("<QQ", self._start or 0, self._end or 0))
        cmap = b"".join(struct.pack("<HQ", c, n) for c, n in counts.items())
        stats += struct.pack("<I", len(cmap)) + cmap
        for op, recs in (("schema", self._schemas), ("channel", self._channels),
                         ("statistics", [_record("statistics", stats)]),
                         ("chunk_index", self._chunk_indexes)):
            if not recs:
                continue
            g0 = self._pos
            for r in recs:
                self._write(r)
            groups.append((op, g0, self._pos - g0))
        summary_offset_start = self._pos
        for op, g0, glen in groups:
            self._write(_record("summary_offset", struct.pack("<BQQ", _OP[op], g0, glen)))
        head = struct.pack("<BQQQ", _OP["footer"], 8 + 8 + 4, summary_start,
                           summary_offset_start)
        crc = _crc32(head, self._crc)
        self._fh.write(head + struct.pack("<I", crc) + MAGIC)
