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

Telling the formats apart and reading the raw messages of a topic from each:
:mod:`athenakin.ros._sources`; this module decodes them into chunks of readings.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._typing import BoolArray, FloatArray, IntArray
from .._validation import check_path
from ..errors import InvalidInputError
from ._errors import RecordingError
from ._mcap_stream import _Bulk, _CdrJointState, _same_layout
from ._sources import JOINT_STATE_TYPES, _raw_messages, _source, recording_format

__all__ = ["JointStates", "read_joint_states", "iter_joint_states", "recording_format",
           "MAX_READINGS", "CHUNK", "JOINT_STATE_TYPES"]

#: Most readings :func:`read_joint_states` returns (use :func:`iter_joint_states` beyond).
MAX_READINGS = 50_000_000
#: Readings per chunk of :func:`iter_joint_states` (default).
CHUNK = 65_536
#: Largest accepted ``chunk_size``.
MAX_CHUNK = 10_000_000
#: Largest magnitude of ``scale``.
MAX_SCALE = 1e6


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

    stamps_ns: IntArray
    q: FloatArray
    qd: FloatArray | None
    log_time_ns: IntArray
    header_stamped: BoolArray
    topic: str
    joints: tuple[str, str, str]
    source: str

    def __len__(self) -> int:
        return int(self.stamps_ns.shape[0])

    @property
    def finite(self) -> BoolArray:
        """True where all three positions are finite, shape (N,)."""
        return np.asarray(np.isfinite(self.q).all(axis=-1))


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
                      scale: float = 1.0, chunk_size: int = CHUNK,
                      backend: str = "auto") -> Iterator[JointStates]:
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
    backend : {"auto", "numpy", "numba"}, keyword-only
        MCAP chunks decoded by the compiled scan or record by record (the same readings).

    Yields
    ------
    JointStates
    """
    topic, names, s = _check_options(topic, joints, scale)
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer)) \
            or not 1 <= chunk_size <= MAX_CHUNK:
        raise InvalidInputError(f"chunk_size: expected an integer from 1 to {MAX_CHUNK}, got "
                                f"{chunk_size!r}")
    from .._backend import resolve_backend

    chosen = "numba" if resolve_backend(backend) else "numpy"
    p = check_path(path)
    kind = recording_format(p)
    # the arguments and the file's format are checked here, at the call; the messages as
    # the chunks are read
    return _iterate(p, kind, _source(p, kind), topic, names, s, int(chunk_size), chosen)


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

    def bulk(self, t_log: IntArray, b: _Bulk, enc: str) -> Iterator[JointStates]:
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

    def many(self, t_log: IntArray, rows: NDArray[np.uint8]) -> Iterator[JointStates]:
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
                ) -> tuple[FloatArray, FloatArray, bool]:
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
             chunk: int, backend: str) -> Iterator[JointStates]:
    """The chunks of the topic's readings; a damaged file is a :class:`RecordingError`."""
    c = _Chunks(p, source, topic, names, s, chunk)
    try:
        for t_log, raw, enc in _raw_messages(p, kind, topic, backend=backend):
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
                      scale: float = 1.0, max_readings: int = MAX_READINGS,
                      backend: str = "auto") -> JointStates:
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
    backend : {"auto", "numpy", "numba"}, keyword-only
        MCAP chunks decoded by the compiled scan or record by record (the same readings).

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
                                  chunk_size=min(CHUNK, int(max_readings) + 1),
                                  backend=backend):
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
