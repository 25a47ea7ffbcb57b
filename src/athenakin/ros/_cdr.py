"""CDR encoding of the ROS 2 messages athenakin writes, vectorised over readings (private).

A ROS 2 message travels as CDR (OMG XCDR1, little endian): a 4-byte encapsulation
header ``00 01 00 00``, then the fields in order, each primitive aligned to its
size relative to the end of that header, strings as a ``uint32`` length (null
included) and the bytes, sequences as a ``uint32`` count and the elements.

Within one channel every message athenakin writes has the same strings and the
same sequence lengths (frame names, joint names): only numbers change from one
reading to the next. So the bytes of a message are a fixed *template* in which
numbers sit at fixed offsets. :class:`CdrBuilder` encodes one message and records
where each named number lies; :meth:`Template.encode` then writes the numbers of
``N`` readings at once with numpy (one structured array, no Python loop per
reading). The tests decode the result with two independent decoders (rosbags
and mcap-ros2-support).
"""

from __future__ import annotations

import dataclasses
import functools
import struct

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._typing import IntArray

__all__ = ["CdrBuilder", "Template", "ENCAPSULATION"]

#: CDR little-endian encapsulation header.
ENCAPSULATION = b"\x00\x01\x00\x00"

_FORMATS = {"f8": ("<d", 8), "i4": ("<i", 4), "u4": ("<I", 4), "u1": ("<B", 1),
            "i1": ("<b", 1), "b1": ("<?", 1)}


class CdrBuilder:
    """Encode one CDR message field by field, recording the offsets of named numbers.

    Offsets count from the start of the message (encapsulation header included).
    """

    def __init__(self) -> None:
        self.buf = bytearray(ENCAPSULATION)
        self.fields: list[tuple[str, int, str]] = []

    def align(self, n: int) -> None:
        """Pad with zeros to a multiple of ``n`` bytes after the encapsulation header."""
        pad = -(len(self.buf) - 4) % n
        self.buf += b"\x00" * pad

    def num(self, kind: str, value: float | int = 0, name: str | None = None) -> None:
        """A number of ``kind`` (``"f8"``, ``"i4"``, ``"u4"``, ``"u1"``, ``"i1"``, ``"b1"``)."""
        fmt, size = _FORMATS[kind]
        self.align(size)
        if name is not None:
            self.fields.append((name, len(self.buf), kind))
        self.buf += struct.pack(fmt, value)

    def string(self, s: str) -> None:
        """A string: ``uint32`` length with the null, the UTF-8 bytes, the null."""
        b = s.encode("utf-8")
        self.num("u4", len(b) + 1)
        self.buf += b + b"\x00"

    def strings(self, items: tuple[str, ...] | list[str]) -> None:
        """A ``string[]``."""
        self.num("u4", len(items))
        for s in items:
            self.string(s)

    def time(self, name: str) -> None:
        """A ``builtin_interfaces/Time`` (``int32 sec``, ``uint32 nanosec``) named ``name``."""
        self.num("i4", 0, f"{name}.sec")
        self.num("u4", 0, f"{name}.nanosec")

    def header(self, frame_id: str, name: str = "stamp") -> None:
        """A ``std_msgs/Header``."""
        self.time(name)
        self.string(frame_id)

    def f8_seq(self, name: str, n: int) -> None:
        """A ``float64[]`` of ``n`` numbers named ``name.0 .. name.{n-1}``."""
        self.num("u4", n)
        for i in range(n):
            self.num("f8", 0.0, f"{name}.{i}")

    def vec3(self, name: str) -> None:
        """Three ``float64`` named ``name.x``, ``.y``, ``.z``."""
        for c in "xyz":
            self.num("f8", 0.0, f"{name}.{c}")

    def quat(self, name: str) -> None:
        """A ``geometry_msgs/Quaternion``, ROS order ``x, y, z, w``."""
        for c in "xyzw":
            self.num("f8", 0.0, f"{name}.{c}")

    def template(self) -> Template:
        """The message as a :class:`Template`."""
        return Template(bytes(self.buf), tuple(self.fields))


@dataclasses.dataclass(frozen=True)
class Template:
    """The bytes of one message and the offsets of its numbers.

    Attributes
    ----------
    data : bytes
        The message with every named number zero.
    fields : tuple of (name, offset, kind)
    """

    data: bytes
    fields: tuple[tuple[str, int, str], ...]

    @property
    def size(self) -> int:
        """Bytes per message."""
        return len(self.data)

    def dtype(self) -> np.dtype:
        """A structured dtype over one message's bytes, one field per named number."""
        return np.dtype({"names": [f[0] for f in self.fields],
                         "formats": ["<" + f[2].replace("b1", "?") for f in self.fields],
                         "offsets": [f[1] for f in self.fields], "itemsize": self.size})

    def encode(self, n: int, values: dict[str, ArrayLike],
               out: NDArray[np.uint8] | None = None) -> NDArray[np.uint8]:
        """``n`` messages, shape (n, size) bytes, with the numbers of ``values``.

        Parameters
        ----------
        n : int
            Number of messages.
        values : dict of str -> array-like, shape (n,) or scalar
            Value of each named number (those not given keep the template's value).
        out : uint8 array, shape (n, size), optional
            Where to write (rows may be strided, each row contiguous): a slice of a
            larger buffer, to build records in place.
        """
        if out is None:
            out = np.empty((n, self.size), dtype=np.uint8)
        out[:] = np.frombuffer(self.data, dtype=np.uint8)
        names: list[str] = []
        formats: list[object] = []
        offsets: list[int] = []
        cols: list[ArrayLike] = []
        for run in _runs(self):
            if len(run) > 1 and all(f[0] in values for f in run):
                # numbers side by side (a translation, a quaternion, a float64[]): one
                # strided copy of an (n, m) block instead of m copies of a column
                block = np.empty((n, len(run)), dtype="<" + run[0][2])
                for j, f in enumerate(run):
                    block[:, j] = values[f[0]]
                names.append(run[0][0])
                formats.append(("<" + run[0][2], (len(run),)))
                offsets.append(run[0][1])
                cols.append(block)
                continue
            for f in run:
                if f[0] in values:
                    names.append(f[0])
                    formats.append("<" + f[2].replace("b1", "?"))
                    offsets.append(f[1])
                    cols.append(values[f[0]])
        rec = out.view(np.dtype({"names": names, "formats": formats, "offsets": offsets,
                                 "itemsize": self.size})).reshape(n)
        for k, v in zip(names, cols, strict=True):
            rec[k] = v
        return out


@functools.lru_cache(maxsize=64)
def _runs(t: Template) -> tuple[tuple[tuple[str, int, str], ...], ...]:
    """The named numbers of ``t`` in runs of one kind that follow each other in memory."""
    runs: list[list[tuple[str, int, str]]] = []
    size = {"f8": 8, "i4": 4, "u4": 4, "u1": 1, "i1": 1, "b1": 1}
    for f in t.fields:
        last = runs[-1][-1] if runs else None
        if (last is not None and f[2] == last[2] and f[2] == "f8"
                and f[1] == last[1] + size[last[2]]):
            runs[-1].append(f)
        else:
            runs.append([f])
    return tuple(tuple(r) for r in runs)


def split_stamps(stamps_ns: IntArray) -> tuple[IntArray, IntArray]:
    """``builtin_interfaces/Time`` fields ``(sec, nanosec)`` of stamps in ns (floor division)."""
    s = np.asarray(stamps_ns, dtype=np.int64)
    return s // 1_000_000_000, s % 1_000_000_000
