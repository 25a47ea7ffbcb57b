"""Recorded masters: an MCAP file or a rosbag2 folder on the cycle grid (private).

:func:`read_master` reads ``geometry_msgs/msg/PoseStamped`` (the handle) and
``sensor_msgs/msg/Joy`` (the clutch pedal: a button held = clutch pressed, dVRK's
meaning: the master decoupled), resampled on the cycle grid: a cycle without a new pose
gets None, so the watchdog sees the recording's own gaps, up to :data:`MAX_GAP_S`; a
longer gap is an error. Each clutch change applies from the cycle of its own stamp. Only
regular files and folders are read (a FIFO or a device is refused, nothing blocks). The
:class:`MasterRecording` it returns is an iterator of ``(t, position, clutch)`` for
:func:`~athenakin.teleop.run_session`, with the recording's time base.

Units: s, m; stamps in ns since the epoch.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from .._validation import check_path, check_scalar
from ..errors import InvalidInputError
from ._filter import check_rate

__all__ = ["MasterRecording", "read_master", "MAX_GAP_S", "POSE_TYPE", "CLUTCH_TYPE"]

#: Longest gap between two poses of a recorded master that :func:`read_master` puts on
#: the cycle grid (the watchdog trips on it), s; a longer one is an error.
MAX_GAP_S = 10.0
#: Message type of the pose topic of a recorded master.
POSE_TYPE = "geometry_msgs/msg/PoseStamped"
#: Message type of its clutch topic.
CLUTCH_TYPE = "sensor_msgs/msg/Joy"


def _messages(path: Path, topics: tuple[str, ...]) -> Iterator[tuple[str, int, Any]]:
    """``(topic, stamp ns, message)`` of an MCAP file or a rosbag2 folder, in time order.

    A file or folder the readers cannot parse raises :class:`InvalidInputError` naming it.
    """
    try:
        yield from _raw_messages(path, topics)
    except (InvalidInputError, MemoryError):
        raise
    except Exception as exc:             # mcap's, rosbags' and the OS's errors: one named error
        raise InvalidInputError(f"{path}: expected an MCAP file or a rosbag2 folder of "
                                f"PoseStamped / Joy messages, could not read it "
                                f"({type(exc).__name__}: {exc})") from exc


def _raw_messages(path: Path, topics: tuple[str, ...]) -> Iterator[tuple[str, int, Any]]:
    if path.is_dir():
        from rosbags.highlevel import AnyReader

        with AnyReader([path]) as bag:
            _check_topics(path, topics, {c.topic: c.msgtype for c in bag.connections})
            conns = [c for c in bag.connections if c.topic in topics]
            for conn, stamp, raw in bag.messages(connections=conns):
                yield conn.topic, int(stamp), bag.deserialize(raw, conn.msgtype)
        return
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        if summary is not None:
            _check_topics(path, topics, {
                c.topic: (summary.schemas[c.schema_id].name
                          if c.schema_id in summary.schemas else "")
                for c in summary.channels.values()})
        for schema, channel, message, msg in reader.iter_decoded_messages(
                topics=list(topics), log_time_order=True):
            _check_type(path, channel.topic, schema.name if schema is not None else "",
                        topics)
            yield channel.topic, int(message.log_time), msg


def _check_topics(path: Path, wanted: tuple[str, ...], present: dict[str, str]) -> None:
    """Each wanted topic is in the recording with its type, else a named error."""
    missing = [t for t in wanted if t not in present]
    if missing:
        raise InvalidInputError(f"{path}: no topic {missing[0]!r} in the recording (it has "
                                f"{sorted(present)}); name the pose and clutch topics with "
                                f"--pose-topic / --clutch-topic (clutch_topic=None: no clutch)")
    for topic in wanted:
        _check_type(path, topic, present[topic], wanted)


def _check_type(path: Path, topic: str, msgtype: str, wanted: tuple[str, ...]) -> None:
    """The pose topic holds PoseStamped, the clutch topic Joy (``wanted``: pose first)."""
    expected = POSE_TYPE if topic == wanted[0] else CLUTCH_TYPE
    if _normal_type(msgtype) != expected:
        what = "pose" if topic == wanted[0] else "clutch"
        raise InvalidInputError(f"{path}: the {what} topic {topic!r} holds {msgtype!r} "
                                f"messages, expected {expected!r}")


def _normal_type(name: str) -> str:
    """``pkg/msg/Type`` for ``pkg/Type`` (ROS 1 style) and ``pkg/msg/Type``."""
    parts = str(name).split("/")
    return f"{parts[0]}/msg/{parts[1]}" if len(parts) == 2 else str(name)


def _stamp(msg: Any, fallback: int) -> int:
    try:
        st = msg.header.stamp
        ns = int(st.sec) * 1_000_000_000 + int(getattr(st, "nanosec", 0))
        return ns if ns > 0 else fallback
    except AttributeError:
        return fallback


class MasterRecording:
    """The cycles of a recorded master: an iterator of ``(t, position or None, clutch)``.

    Returned by :func:`read_master`; iterate it once.

    Attributes
    ----------
    start_ns : int
        Stamp of ``t = 0`` (the first pose), ns since the epoch: the session's time base
        (:func:`run_session` keeps it in :attr:`SessionLog.start_ns`).
    path : Path
        The recording.
    rate : float
        The cycle rate, Hz.
    """

    def __init__(self, path: Path, start_ns: int, cycles: Iterator[tuple[float, Any, bool]],
                 rate: float) -> None:
        self.path, self.start_ns, self.rate = path, start_ns, rate
        self._cycles = cycles

    def __iter__(self) -> MasterRecording:
        """The recording itself (an iterator)."""
        return self

    def __next__(self) -> tuple[float, tuple[float, float, float] | None, bool]:
        """The next cycle: ``(t s, (x, y, z) m or None, clutch)``."""
        return next(self._cycles)


def read_master(path: str | Path, *, rate: float = 1000.0, pose_topic: str = "/master/pose",
                clutch_topic: str | None = "/master/joy", clutch_button: int = 0,
                max_gap: float = MAX_GAP_S) -> MasterRecording:
    """A recorded master on the cycle grid: ``(t, position or None, clutch)`` per cycle.

    Parameters
    ----------
    path : str or Path
        An MCAP file or a rosbag2 folder (extra ``ros``); a FIFO, a socket or a device is
        refused (nothing blocks).
    rate : float, keyword-only
        Cycles per second, Hz; ``t`` starts at 0 at the first pose.
    pose_topic : str, keyword-only
        :data:`POSE_TYPE` messages: the handle's position (m, the master's frame).
    clutch_topic : str or None, keyword-only
        :data:`CLUTCH_TYPE` messages; None: the clutch always follows.
    clutch_button : int, keyword-only
        The Joy button of the clutch pedal: held (1) = pressed = the master decoupled.
    max_gap : float, keyword-only
        Longest gap between two poses put on the grid, s (:data:`MAX_GAP_S`): the cycles
        of a gap carry no sample and the core's watchdog holds the robot; a longer gap
        is an error (a recording spliced from two sessions, a stamp days off).

    Returns
    -------
    MasterRecording
        An iterator of ``(t s, (x, y, z) m or None, clutch)`` per cycle: the latest pose
        received in the cycle (None when none arrived), ``clutch`` True while the tip
        follows; a clutch change applies from the cycle of its own stamp. The
        arguments, the file and its topics (names and types) are checked when
        ``read_master`` is called.

    Raises
    ------
    InvalidInputError
        No such file, not a regular file or folder, not an MCAP file or rosbag2 folder,
        a topic it lacks or of another type, a bad rate, button or ``max_gap``; when the
        iterator is consumed: a recording with no pose, a gap longer than ``max_gap``, a
        Joy message without ``clutch_button``.
    """
    p = check_path(path, "path")
    if not p.exists():
        raise InvalidInputError(f"path: {path}: no such file or folder")
    if not (p.is_file() or p.is_dir()):
        raise InvalidInputError(f"path: {path}: expected a regular file or a rosbag2 folder, "
                                f"got a FIFO, socket or device (it would block)")
    rate = check_rate(rate)
    gap = check_scalar(max_gap, "max_gap", positive=True)
    for name, topic in (("pose_topic", pose_topic), ("clutch_topic", clutch_topic)):
        if topic is not None and not (isinstance(topic, str) and topic):
            raise TypeError(f"{name}: expected a topic name (str), got {topic!r:.80}")
    if isinstance(clutch_button, bool) or not isinstance(clutch_button, (int, np.integer)) \
            or clutch_button < 0:
        raise InvalidInputError(f"clutch_button: expected a button index >= 0, got "
                                f"{clutch_button!r:.80}")
    if clutch_topic is not None and clutch_topic == pose_topic:
        raise InvalidInputError(f"clutch_topic: {clutch_topic!r} is the pose topic too")
    topics = (pose_topic,) + ((clutch_topic,) if clutch_topic else ())
    messages = _messages(p, topics)
    head: list[tuple[str, int, Any]] = []
    for item in messages:               # up to the first pose: opens and checks it now
        head.append(item)
        if item[0] == pose_topic:
            break
    if not head or head[-1][0] != pose_topic:
        raise InvalidInputError(f"{p}: topic {pose_topic!r} holds no PoseStamped message")
    t0 = _stamp(head[-1][2], head[-1][1])
    cycles = _master_cycles(p, itertools.chain(head, messages), t0, rate, gap, pose_topic,
                            clutch_topic, int(clutch_button))
    return MasterRecording(p, t0, cycles, rate)


def _check_gap(path: Path, t: float, last: float, max_gap: float) -> None:
    """A message at ``t`` within ``max_gap`` of the last pose (at ``last``), else an error."""
    if t - last > max_gap:
        raise InvalidInputError(f"{path}: a gap of {t - last:.6g} s after the pose at t = "
                                f"{last:.6g} s, longer than max_gap = {max_gap:g} s (a "
                                f"recording spliced from two sessions, or a stamp far off?)")


def _master_cycles(path: Path, stream: Iterator[tuple[str, int, Any]], t0: int, rate: float,
                   max_gap: float, pose_topic: str, clutch_topic: str | None,
                   clutch_button: int
                   ) -> Iterator[tuple[float, tuple[float, float, float] | None, bool]]:
    """The cycles of :func:`read_master` from its messages (``t0``: the first pose, ns)."""
    follow = True
    pending: tuple[float, float, float] | None = None
    k = 0                      # the next cycle to yield
    last_pose_t = 0.0
    for topic, log_ns, msg in stream:
        t = (_stamp(msg, log_ns) - t0) * 1e-9
        cycle = max(int(math.floor(t * rate + 1e-9)), 0)
        if topic == clutch_topic:
            b = list(getattr(msg, "buttons", []))
            if clutch_button >= len(b):
                raise InvalidInputError(f"{path}: the clutch topic {clutch_topic!r} has "
                                        f"{len(b)} button(s), no button {clutch_button} "
                                        f"(--clutch-button)")
            pressed = int(b[clutch_button]) != 0
            if pressed == (not follow):
                continue
            _check_gap(path, t, last_pose_t, max_gap)
            while k < cycle:                   # cycles before the change: the old state
                yield k / rate, pending, follow
                pending = None
                k += 1
            follow = not pressed
            continue
        _check_gap(path, t, last_pose_t, max_gap)
        last_pose_t = max(last_pose_t, t)
        pos = msg.pose.position
        while k < cycle:                       # cycles before this pose: the pending one
            yield k / rate, pending, follow
            pending = None
            k += 1
        pending = (float(pos.x), float(pos.y), float(pos.z))
    yield k / rate, pending, follow

