"""Read actuator readings from recordings of ``sensor_msgs/JointState`` (private).

Formats, told apart by their content (not their name):

* a rosbag2 folder (``metadata.yaml`` and its storage files, sqlite3 or MCAP),
  checked with rosbags; MCAP storage files are then read as single MCAP files (the
  same fast path), sqlite3 storage message by message by rosbags;
* a single MCAP file (magic ``0x89 MCAP0``), read with the mcap library's record
  reader (chunk CRCs checked; a file cut short is read up to its last complete chunk,
  with a :class:`RecordingWarning` saying how much was lost), the Message records of
  each decompressed chunk decoded at once;
* a single rosbag2 sqlite3 file (``.db3``), read with rosbags;
* a ROS 1 bag (``#ROSBAG V2.0``), read with rosbags.

Messages are decoded in chunks (:func:`iter_joint_states`), so a recording of any
length is read with bounded memory. ROS 2 messages (CDR) go through a decoder of
this module that reuses the layout of the previous message (same frame and joint
names: the numbers sit at the same offsets), about ten times faster than a
generic decoder; ROS 1 messages through rosbags' deserializer.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
import stat
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._validation import check_path
from ..errors import InvalidInputError
from ._errors import RecordingError, RecordingWarning, ros_extra_missing
from ._mcap_stream import _Bulk, _CdrJointState, _McapStream, _same_layout

__all__ = ["JointStates", "read_joint_states", "iter_joint_states", "recording_format",
           "MAX_READINGS", "CHUNK", "JOINT_STATE_TYPES"]

#: Most readings :func:`read_joint_states` returns (use :func:`iter_joint_states` beyond).
MAX_READINGS = 50_000_000
#: Readings per chunk of :func:`iter_joint_states` (default).
CHUNK = 65_536
#: Largest accepted ``chunk_size``.
MAX_CHUNK = 10_000_000
#: Message type names of a joint state (ROS 2, ROS 1 spelling).
JOINT_STATE_TYPES = ("sensor_msgs/msg/JointState", "sensor_msgs/JointState")
#: Largest magnitude of ``scale``.
MAX_SCALE = 1e6

_MCAP_MAGIC = b"\x89MCAP0\r\n"
_ROS1_MAGIC = b"#ROSBAG V2.0\n"
_SQLITE_MAGIC = b"SQLite format 3\x00"


@dataclasses.dataclass(frozen=True)
class JointStates:
    """Actuator readings read from a recording.

    Attributes
    ----------
    stamps_ns : ndarray of int64, shape (N,)
        Time of each reading, ns since the epoch: the message's header stamp, or its
        log (record) time where the header stamp is zero. Never decreasing.
    q : ndarray, shape (N, 3)
        ``(q1, q2, q3)`` in m (the recorded positions times ``scale``). A reading whose
        message lacks a position for an actuator, or holds NaN, has NaN there (see
        :attr:`finite`).
    qd : ndarray, shape (N, 3) or None
        Velocities in m/s (times ``scale``) where the messages carry them (NaN in a
        message without), None when no message has velocities.
    log_time_ns : ndarray of int64, shape (N,)
        When the recorder logged each message, ns.
    header_stamped : ndarray of bool, shape (N,)
        False where the header stamp was zero and ``stamps_ns`` is the log time.
    topic : str
    joints : tuple of 3 str
        The names read as ``q1, q2, q3``.
    source : str
        The format: ``"rosbag2/sqlite3"``, ``"rosbag2/mcap"``, ``"mcap"`` or ``"rosbag1"``.
    """

    stamps_ns: NDArray[np.int64]
    q: NDArray[np.float64]
    qd: NDArray[np.float64] | None
    log_time_ns: NDArray[np.int64]
    header_stamped: NDArray[np.bool_]
    topic: str
    joints: tuple[str, str, str]
    source: str

    def __len__(self) -> int:
        return int(self.stamps_ns.shape[0])

    @property
    def finite(self) -> NDArray[np.bool_]:
        """True where all three positions are finite, shape (N,)."""
        return np.asarray(np.isfinite(self.q).all(axis=-1))


# ---------------------------------------------------------------------------- formats
def recording_format(path: str | Path) -> str:
    """The format of a recording: ``"rosbag2"``, ``"mcap"``, ``"db3"`` or ``"rosbag1"``.

    Parameters
    ----------
    path : str or Path
        A rosbag2 folder, an MCAP file, a ``.db3`` file or a ROS 1 bag.

    Returns
    -------
    str
        ``"rosbag2"`` (a folder), ``"mcap"``, ``"db3"`` or ``"rosbag1"``, told apart by
        the content, not the name.

    Raises
    ------
    RecordingError
        No such file, not a regular file or folder (a FIFO, a device), or none of
        these formats.
    """
    p = check_path(path)
    try:
        st = os.stat(p)
    except OSError as exc:
        raise RecordingError(f"{p}: cannot open the recording ({exc.strerror or exc})") \
            from None
    if stat.S_ISDIR(st.st_mode):
        if not (p / "metadata.yaml").is_file():
            raise RecordingError(f"{p}: a folder without metadata.yaml; expected a rosbag2 "
                                 f"folder, an MCAP file or a ROS 1 bag")
        return "rosbag2"
    if not stat.S_ISREG(st.st_mode):
        raise RecordingError(f"{p}: not a regular file (a FIFO, socket or device); expected "
                             f"a rosbag2 folder, an MCAP file or a ROS 1 bag")
    with open(p, "rb") as fh:
        head = fh.read(16)
    if head.startswith(_MCAP_MAGIC):
        return "mcap"
    if head.startswith(_ROS1_MAGIC):
        return "rosbag1"
    if head.startswith(_SQLITE_MAGIC):
        return "db3"
    raise RecordingError(f"{p}: not a recording (first bytes {head[:8]!r}); expected a "
                         f"rosbag2 folder, an MCAP file or a ROS 1 bag")


def _ros1_decoder() -> Callable[[bytes], tuple[int, int, tuple[str, ...], tuple[float, ...],
                                               tuple[float, ...]]]:
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    cache: dict[tuple[str, ...], tuple[str, ...]] = {}

    def decode(raw: bytes) -> tuple[int, int, tuple[str, ...], tuple[float, ...],
                                    tuple[float, ...]]:
        m: Any = store.deserialize_ros1(raw, "sensor_msgs/msg/JointState")
        names = tuple(m.name)
        names = cache.setdefault(names, names)
        return (m.header.stamp.sec, m.header.stamp.nanosec, names, tuple(m.position.tolist()),
                tuple(m.velocity.tolist()))

    return decode


# ---------------------------------------------------------------------------- sources
def _raw_messages(path: Path, kind: str, topic: str) -> Iterator[tuple[Any, Any, str]]:
    """``(log_time_ns, raw, encoding)`` of ``topic``, after checking topic and type."""
    if kind == "mcap":
        yield from _mcap_messages(path, topic)
        return
    try:
        from rosbags.rosbag1 import Reader as Reader1
        from rosbags.rosbag2 import Reader as Reader2
    except ModuleNotFoundError as exc:  # pragma: no cover - the extra is installed in CI
        raise ros_extra_missing(exc) from None
    if kind == "db3" and path.suffix != ".db3":
        raise RecordingError(f"{path}: a single rosbag2 sqlite3 file must be named *.db3 "
                             f"(or give its folder)")
    reader: Any = Reader1(path) if kind == "rosbag1" else Reader2(path)
    with reader:
        conns = [c for c in reader.connections if c.topic == topic]
        if not conns:
            _missing_topic(path, topic, {c.topic: c.msgtype for c in reader.connections})
        for c in conns:
            _check_type(path, topic, c.msgtype)
        files = _mcap_storage(path, reader) if kind == "rosbag2" else None
        if files is None:
            enc = "ros1" if kind == "rosbag1" else "cdr"
            for _conn, t, raw in reader.messages(connections=conns):
                yield int(t), raw, enc
            return
    for f in files:        # MCAP storage: each file through the MCAP fast path, in order
        yield from _mcap_messages(f, topic, in_bag=True)


def _mcap_storage(path: Path, reader: Any) -> list[Path] | None:
    """The MCAP storage files of a rosbag2 folder, in recording order, or None.

    None (rosbags reads it, message by message) for sqlite3 storage or compressed
    files or messages (``compression_mode`` set). The files are those of the folder
    named in its ``metadata.yaml``, ordered by their split index (``bag_0.mcap``,
    ``bag_1.mcap``, ..., ``bag_10.mcap``).
    """
    if getattr(reader, "compression_mode", None):
        return None
    try:
        listed = (path / "metadata.yaml").read_text(encoding="utf-8")
    except (OSError, UnicodeError):
        return None
    files = [f for f in path.iterdir() if f.suffix == ".mcap" and f.name in listed]
    if not files:
        return None
    for f in files:
        with open(f, "rb") as fh:
            if fh.read(8) != _MCAP_MAGIC:
                return None
    return sorted(files, key=lambda f: [int(t) if t.isdigit() else t
                                        for t in re.split(r"(\d+)", f.name)])


def _missing_topic(path: Path, topic: str, present: dict[str, str]) -> None:
    listed = ", ".join(f"{k} ({v})" for k, v in sorted(present.items())) or "none"
    raise RecordingError(f"{path}: no topic {topic!r}; topics present: {listed} (choose one "
                         f"with topic=... / --topic)")


def _check_type(path: Path, topic: str, msgtype: str) -> None:
    if msgtype not in JOINT_STATE_TYPES:
        raise RecordingError(f"{path}: topic {topic!r} holds {msgtype}, expected "
                             f"sensor_msgs/msg/JointState")


def _mcap_messages(path: Path, topic: str, *, in_bag: bool = False
                   ) -> Iterator[tuple[Any, Any, str]]:
    """Messages of ``topic`` in file order (the summary, when present, checks the topic).

    ``(log time, data, encoding)``, or for a run of messages read at once
    ``(log times, _Bulk, encoding)``. ``in_bag``: a storage file of a rosbag2 folder
    (the folder's metadata checked the topic; a file may hold none of its messages).
    """
    try:
        from mcap.reader import make_reader
    except ModuleNotFoundError as exc:  # pragma: no cover
        raise ros_extra_missing(exc) from None
    with open(path, "rb") as fh:
        try:
            summary = make_reader(fh).get_summary()
        except Exception:          # no footer (a truncated file): read it from the start
            summary = None
        if summary is not None and not in_bag:
            chans = {c.topic: summary.schemas.get(c.schema_id) for c in
                     summary.channels.values()}
            if topic not in chans:
                _missing_topic(path, topic, {k: (s.name if s else "?") for k, s in
                                             chans.items()})
        fh.seek(0)
        stream = _McapStream(fh, os.fstat(fh.fileno()).st_size, summary, topic)
        wanted: dict[int, str] = {}
        for cid, log_time, data in stream.messages():
            enc = wanted.get(cid)
            if enc is None:
                ch = stream.channels.get(cid)
                if ch is None or ch[0] != topic:
                    continue
                schema = stream.schemas.get(ch[1], "(no schema)")
                _check_type(path, topic, schema)
                if ch[2] not in ("cdr", "ros1"):
                    raise RecordingError(f"{path}: topic {topic!r} is encoded as {ch[2]!r}, "
                                         f"expected cdr or ros1")
                wanted[cid] = enc = ch[2]
            stream.read += len(log_time) if isinstance(data, _Bulk) else 1
            yield log_time, data, enc
        if stream.lost is not None:
            good, why = stream.lost
            if not stream.read:
                raise RecordingError(f"{path}: truncated or corrupt MCAP file: no complete "
                                     f"chunk of {topic!r} before byte {good} of "
                                     f"{stream.size} ({why})")
            warnings.warn(RecordingWarning(
                f"{path}: truncated MCAP file (a recorder stopped mid-run?): read "
                f"{stream.read} messages of {topic!r}, up to the last complete chunk "
                f"(byte {good} of {stream.size}); the rest, {stream.size - good} bytes "
                f"({100.0 * (stream.size - good) / max(stream.size, 1):.1f} % of the file), "
                f"could not be read ({why}); what the recorder never wrote is not known"),
                stacklevel=2)
        if not wanted and summary is None and not in_bag:
            present = {t: stream.schemas.get(sid, "?") for t, sid, _ in
                       stream.channels.values()}
            if topic not in present:
                _missing_topic(path, topic, present)


# ---------------------------------------------------------------------------- public
def _check_options(topic: object, joints: object, scale: object) -> tuple[str, tuple[str, ...],
                                                                          float]:
    if not isinstance(topic, str) or not topic:
        raise InvalidInputError(f"topic: expected a topic name such as '/joint_states', got "
                                f"{topic!r}")
    if isinstance(joints, str) or not isinstance(joints, (tuple, list)) or len(joints) != 3 \
            or not all(isinstance(j, str) and j for j in joints):
        raise InvalidInputError(f"joints: expected 3 joint names (q1, q2, q3), got {joints!r}")
    if len(set(joints)) != 3:
        raise InvalidInputError(f"joints: expected 3 different names, got {joints!r}")
    if isinstance(scale, bool) or not isinstance(scale, (int, float, np.integer, np.floating)):
        raise TypeError(f"scale: expected a number (0.001 for mm), got {type(scale).__name__}")
    try:
        s = float(scale)
    except OverflowError:
        s = math.inf
    if not (math.isfinite(s) and 0.0 < abs(s) <= MAX_SCALE):
        raise InvalidInputError(f"scale: expected a finite nonzero factor of magnitude at most "
                                f"{MAX_SCALE:g} (0.001 for mm), got {scale!r}")
    return topic, tuple(joints), s


def iter_joint_states(path: str | Path, *, topic: str = "/joint_states",
                      joints: tuple[str, str, str] | list[str] = ("q1", "q2", "q3"),
                      scale: float = 1.0, chunk_size: int = CHUNK) -> Iterator[JointStates]:
    """Read the actuator readings of a recording in chunks (bounded memory).

    Every chunk but the last holds ``chunk_size`` readings; an empty topic yields
    nothing. The arguments and the recording's format are checked when the function
    is called; the messages as the chunks are read: a chunk may come before the error
    of a later message.

    Parameters
    ----------
    path, topic, joints, scale : as in :func:`read_joint_states`
    chunk_size : int, keyword-only
        Readings per chunk, 1 to 10 000 000.

    Yields
    ------
    JointStates
    """
    topic, names, s = _check_options(topic, joints, scale)
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer)) \
            or not 1 <= chunk_size <= MAX_CHUNK:
        raise InvalidInputError(f"chunk_size: expected an integer from 1 to {MAX_CHUNK}, got "
                                f"{chunk_size!r}")
    p = check_path(path)
    kind = recording_format(p)
    # the arguments and the file's format are checked here, at the call; the messages as
    # the chunks are read
    return _iterate(p, kind, _source(p, kind), topic, names, s, int(chunk_size))


def _source(p: Path, kind: str) -> str:
    if kind == "rosbag2":
        return "rosbag2/mcap" if any(p.glob("*.mcap")) else "rosbag2/sqlite3"
    return {"db3": "rosbag2/sqlite3", "mcap": "mcap", "rosbag1": "rosbag1"}[kind]


class _Chunks:
    """The readings of one topic gathered into chunks of ``chunk`` readings (:func:`_iterate`).

    Holds the chunk being filled (stamps, log times, ``q``, ``qd``, header-stamped flags),
    the message count and the last stamp (stamps must never go backwards), and the
    decoders: the CDR decoder of ``sensor_msgs/JointState`` (whose layout the vectorised
    path reads) and the ROS 1 decoder, made on the first ROS 1 message.
    """

    def __init__(self, p: Path, source: str, topic: str, names: tuple[str, ...], s: float,
                 chunk: int) -> None:
        self.p, self.source, self.topic, self.names, self.s = p, source, topic, names, s
        self.chunk = chunk
        self.cdr = _CdrJointState()
        self.ros1: Callable[[bytes], tuple] | None = None  # type: ignore[type-arg]
        self.lookup: dict[int, tuple[tuple[str, ...], list[int]]] = {}
        self.stamps = np.empty(chunk, np.int64)
        self.logt = np.empty(chunk, np.int64)
        self.q = np.empty((chunk, 3))
        self.qd = np.empty((chunk, 3))
        self.stamped = np.zeros(chunk, bool)
        self.k = 0                  # readings in the chunk
        self.index = 0              # messages read
        self.last = -(2 ** 63)      # the last stamp, ns
        self.vel = False            # a message of the chunk has velocities

    def full(self) -> JointStates:
        """The readings of the chunk (a copy); the chunk starts again empty."""
        n = self.k
        out = JointStates(stamps_ns=self.stamps[:n].copy(), q=self.q[:n].copy(),
                          qd=self.qd[:n].copy() if self.vel else None,
                          log_time_ns=self.logt[:n].copy(),
                          header_stamped=self.stamped[:n].copy(), topic=self.topic,
                          joints=self.names, source=self.source)  # type: ignore[arg-type]
        self.k = 0
        self.vel = False
        return out

    def actuators(self, mnames: tuple[str, ...]) -> list[int]:
        """Indices of the three joints in a message's names (cached per names tuple)."""
        ent = self.lookup.get(id(mnames))
        if ent is None or ent[0] is not mnames:
            idx = []
            for j in self.names:
                if j not in mnames:
                    raise RecordingError(
                        f"{self.p}: topic {self.topic!r}, message {self.index}: no joint "
                        f"named {j!r}; names present: {list(mnames)} (choose with "
                        f"joints=... / --joints)")
                idx.append(mnames.index(j))
            self.lookup[id(mnames)] = ent = (mnames, idx)
        return ent[1]

    def backwards(self, t: int, last: int) -> RecordingError:
        return RecordingError(f"{self.p}: topic {self.topic!r}: stamps go backwards at message "
                              f"{self.index}: {t} ns after {last} ns")

    def one(self, t_log: int, raw: bytes, enc: str) -> bool:
        """Store one message; True when the chunk is full."""
        if enc == "cdr":
            sec, nsec, mnames, pos, vel = self.cdr.decode(raw)
        else:
            if self.ros1 is None:
                self.ros1 = _ros1_decoder()
            sec, nsec, mnames, pos, vel = self.ros1(raw)
        i0, i1, i2 = self.actuators(mnames)
        k, s = self.k, self.s
        t = sec * 1_000_000_000 + nsec
        self.stamped[k] = t != 0
        if t == 0:
            t = t_log
        if t < self.last:
            raise self.backwards(t, self.last)
        self.last = t
        self.stamps[k] = t
        self.logt[k] = t_log
        if len(pos) > max(i0, i1, i2):
            self.q[k] = (pos[i0] * s, pos[i1] * s, pos[i2] * s)
        else:
            self.q[k] = _NAN3
        if len(vel) == len(mnames):
            self.qd[k] = (vel[i0] * s, vel[i1] * s, vel[i2] * s)
            self.vel = True
        else:
            self.qd[k] = _NAN3
        self.k = k + 1
        self.index += 1
        return k + 1 == self.chunk

    def bulk(self, t_log: NDArray[np.int64], b: _Bulk, enc: str) -> Iterator[JointStates]:
        """Messages of one channel: those of the decoder's layout at once, others one by one."""
        j, m = 0, len(b)
        while j < m:
            e, rows = _same_layout(self.cdr, b, j) if enc == "cdr" else (j, None)
            if rows is None:
                if self.one(int(t_log[j]), b.message(j), enc):
                    yield self.full()
                j += 1
                continue
            yield from self.many(t_log[j:e], rows)
            j = e

    def many(self, t_log: NDArray[np.int64], rows: NDArray[np.uint8]) -> Iterator[JointStates]:
        """Messages of the layout of the decoder (rows of their bytes), vectorised."""
        t = (rows[:, 4:8].copy().view("<i4")[:, 0].astype(np.int64) * 1_000_000_000
             + rows[:, 8:12].copy().view("<u4")[:, 0])
        has = t != 0
        t = np.where(has, t, t_log)
        prev = np.concatenate([[self.last], t[:-1]])
        bad = np.flatnonzero(t < prev)
        n = int(bad[0]) if bad.size else len(t)
        qv, qdv, hv = self._values(rows)
        a = 0
        while a < n:
            k = self.k
            take = min(self.chunk - k, n - a)
            self.stamps[k:k + take] = t[a:a + take]
            self.logt[k:k + take] = t_log[a:a + take]
            self.stamped[k:k + take] = has[a:a + take]
            self.q[k:k + take] = qv[a:a + take]
            self.qd[k:k + take] = qdv[a:a + take]
            a += take
            self.k = k + take
            self.index += take
            self.last = int(t[a - 1])
            self.vel = self.vel or hv
            if self.k == self.chunk:
                yield self.full()
        if bad.size:
            raise self.backwards(int(t[n]), int(prev[n]))

    def _values(self, rows: NDArray[np.uint8]
                ) -> tuple[NDArray[np.float64], NDArray[np.float64], bool]:
        """``q``, ``qd`` (NaN where absent) of rows of the decoder's layout; True with ``qd``."""
        cdr, s = self.cdr, self.s
        i0, i1, i2 = self.actuators(cdr._names)
        npos, nvel = cdr._pos.size // 8, cdr._nvel  # type: ignore[union-attr]
        if npos > max(i0, i1, i2):
            o = cdr._off_pos
            pos = rows[:, o:o + 8 * npos].copy().view("<f8")
            qv = np.stack([pos[:, i0] * s, pos[:, i1] * s, pos[:, i2] * s], axis=-1)
        else:
            qv = np.full((len(rows), 3), math.nan)
        hv = nvel == len(cdr._names)
        if hv:
            o = cdr._off_vel
            vel = rows[:, o:o + 8 * nvel].copy().view("<f8")
            qdv = np.stack([vel[:, i0] * s, vel[:, i1] * s, vel[:, i2] * s], axis=-1)
        else:
            qdv = np.full((len(rows), 3), math.nan)
        return qv, qdv, hv


_NAN3 = (math.nan, math.nan, math.nan)


def _iterate(p: Path, kind: str, source: str, topic: str, names: tuple[str, ...], s: float,
             chunk: int) -> Iterator[JointStates]:
    """The chunks of the topic's readings; a damaged file is a :class:`RecordingError`."""
    c = _Chunks(p, source, topic, names, s, chunk)
    try:
        for t_log, raw, enc in _raw_messages(p, kind, topic):
            if isinstance(raw, _Bulk):
                yield from c.bulk(t_log, raw, enc)
            elif c.one(t_log, raw, enc):
                yield c.full()
        if c.k:
            yield c.full()
    except (RecordingError, ModuleNotFoundError, GeneratorExit):
        raise
    except Exception as exc:    # rosbags, mcap, struct, zstd, sqlite: a damaged file
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise RecordingError(f"{p}: truncated or corrupt recording at message {c.index} "
                             f"of {topic!r} ({type(exc).__name__}: {msg})") from None


def read_joint_states(path: str | Path, *, topic: str = "/joint_states",
                      joints: tuple[str, str, str] | list[str] = ("q1", "q2", "q3"),
                      scale: float = 1.0, max_readings: int = MAX_READINGS) -> JointStates:
    """Read the actuator readings of a ROS recording of ``sensor_msgs/JointState``.

    Parameters
    ----------
    path : str or Path
        A rosbag2 folder (sqlite3 or MCAP storage), a single MCAP file, a ``.db3``
        file or a ROS 1 bag (told apart by their content).
    topic : str, keyword-only
        The topic of the joint states (default ``/joint_states``).
    joints : 3 str, keyword-only
        Names of the joints read as ``q1, q2, q3``, among any others in the
        messages, in any order (default ``("q1", "q2", "q3")``, the names of the
        URDF export).
    scale : float, keyword-only
        Factor from the recorded unit to m (``0.001`` for encoders in mm).
    max_readings : int, keyword-only
        Refuse recordings of more readings (default :data:`MAX_READINGS`); read
        longer ones with :func:`iter_joint_states`.

    Returns
    -------
    JointStates
        ``stamps_ns`` (header stamps, or log times where the header is zero), ``q``
        in m, ``qd`` in m/s or None. An empty topic gives N = 0.

    Raises
    ------
    RecordingError
        Not a recording, truncated or corrupt; no such topic (the message lists the
        topics present); a message without one of ``joints`` (lists the names
        present); a message type other than JointState; stamps that go backwards;
        more than ``max_readings`` readings.
    InvalidInputError, TypeError
        Bad ``topic``, ``joints``, ``scale``.

    Examples
    --------
    ::

        js = ak.ros.read_joint_states("run_2026_11_25/", joints=("m1", "m2", "m3"),
                                      scale=0.001)
        log = ak.motion.track(js.q, T_b_e, design)
    """
    if isinstance(max_readings, bool) or not isinstance(max_readings, (int, np.integer)) \
            or not 1 <= max_readings <= MAX_READINGS:
        raise InvalidInputError(f"max_readings: expected an integer from 1 to {MAX_READINGS}, "
                                f"got {max_readings!r}")
    parts: list[JointStates] = []
    n = 0
    for part in iter_joint_states(path, topic=topic, joints=joints, scale=scale,
                                  chunk_size=min(CHUNK, int(max_readings) + 1)):
        n += len(part)
        if n > max_readings:
            raise RecordingError(f"{path}: more than {max_readings} readings on {topic!r} "
                                 f"(raise max_readings or read in chunks with "
                                 f"iter_joint_states)")
        parts.append(part)
    topic, names, _ = _check_options(topic, joints, scale)
    if not parts:
        return JointStates(np.zeros(0, np.int64), np.zeros((0, 3)), None,
                           np.zeros(0, np.int64), np.zeros(0, bool), topic,
                           names, _source(Path(path), recording_format(path)))  # type: ignore[arg-type]
    if len(parts) == 1:
        return parts[0]
    vel = any(x.qd is not None for x in parts)
    return JointStates(
        stamps_ns=np.concatenate([x.stamps_ns for x in parts]),
        q=np.concatenate([x.q for x in parts]),
        qd=np.concatenate([x.qd if x.qd is not None else np.full((len(x), 3), np.nan)
                           for x in parts]) if vel else None,
        log_time_ns=np.concatenate([x.log_time_ns for x in parts]),
        header_stamped=np.concatenate([x.header_stamped for x in parts]),
        topic=parts[0].topic, joints=parts[0].joints, source=parts[0].source)
