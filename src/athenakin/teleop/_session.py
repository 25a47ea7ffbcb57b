"""Masters and sessions: any iterator of samples through the core and the arm (private).

* :func:`run_session`: ``(t, position, clutch)`` items (position None: no sample) ->
  :class:`Teleop` -> :class:`SimulatedArm` (``servo_jp`` with velocity and effort
  feed-forward), cycle by cycle; a :class:`SessionLog` of arrays.
* :func:`read_master`: a recorded master, an MCAP file or a rosbag2 folder of
  ``geometry_msgs/msg/PoseStamped`` (the handle) and ``sensor_msgs/msg/Joy`` (the
  clutch pedal: a button held = clutch pressed, dVRK's meaning: the master decoupled),
  resampled on the cycle grid (a cycle without a new pose gets None: the watchdog sees
  the recording's own gaps).
* :func:`write_session_mcap`: the session as CRTK topics (``measured_js``,
  ``setpoint_js``, ``measured_cp``, ``servo_cp``, ``status``) in an MCAP file that
  Foxglove opens, written through a temporary file renamed into place.
"""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import math
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._output import atomic_write
from .._typing import BoolArray, FloatArray, IntArray
from .._validation import check_count, check_path
from ..errors import InvalidInputError
from ._filter import check_rate
from ._options import TeleopStatus

__all__ = ["SessionLog", "run_session", "read_master", "write_session_mcap", "CRTK_TOPICS",
           "TELEOP_STATUS_TYPE", "TELEOP_STATUS_MSGDEF"]

#: Topics of :func:`write_session_mcap` (CRTK's command names under the arm's namespace).
CRTK_TOPICS = {
    "measured_js": "/athena/measured_js",
    "setpoint_js": "/athena/setpoint_js",
    "measured_cp": "/athena/measured_cp",
    "servo_cp": "/athena/servo_cp",
    "status": "/athena/teleop/status",
    "master": "/athena/teleop/master",
}
#: Type of the status topic.
TELEOP_STATUS_TYPE = "athenakin_msgs/msg/TeleopStatus"
#: Its definition (ROS 2 .msg syntax).
TELEOP_STATUS_MSGDEF = """\
# One cycle of athenakin.teleop.Teleop: the safety layer's flags (TeleopStatus bits).
std_msgs/Header header
uint32 flags               # athenakin.teleop.TeleopStatus bits
string names               # the set flags, e.g. "CLUTCHED|VELOCITY"; "" when none
bool clutched
bool limited               # STROKE, DEPTH, SINGULAR, FIXTURE, CLEARANCE, VELOCITY or ACCELERATION
bool hold                  # braking or held (watchdog, e-stop, no step possible)
bool watchdog
bool estop
float64 clearance_m        # least clearance of the bodies, m; NaN: not checked
float64 tip_error_m        # |measured tip - commanded tip|, m
"""
_LIMITED = int(TeleopStatus.STROKE | TeleopStatus.DEPTH | TeleopStatus.SINGULAR
               | TeleopStatus.FIXTURE | TeleopStatus.CLEARANCE | TeleopStatus.VELOCITY
               | TeleopStatus.ACCELERATION)


@dataclasses.dataclass(frozen=True)
class SessionLog:
    """Every cycle of a session, as arrays (N cycles).

    Attributes
    ----------
    t : ndarray, shape (N,)
        s.
    master : ndarray, shape (N, 3)
        The master's sample in its own frame, m (NaN: no sample that cycle).
    clutch : ndarray of bool, shape (N,)
    target, tip : ndarray, shape (N, 3)
        The master's target and the commanded tip, RCM frame E, m.
    tip_b : ndarray, shape (N, 3)
        The commanded tip, base frame, m.
    measured_tip_b : ndarray, shape (N, 3)
        The arm's tip after the cycle, base frame, m (MuJoCo's site ``tool_tip`` for
        the simulated arm, else the forward kinematics of its encoders).
    q, qd, qdd, forces : ndarray, shape (N, 3)
        The commands (m, m/s, m/s^2, N).
    measured_q, measured_qd : ndarray, shape (N, 3)
        The arm's encoders after the cycle.
    status : ndarray of int64, shape (N,)
        :class:`TeleopStatus` bits.
    closure_error : ndarray, shape (N,)
        Largest loop-closure error of the simulation, m (NaN for other backends).
    """

    t: FloatArray
    master: FloatArray
    clutch: BoolArray
    target: FloatArray
    tip: FloatArray
    tip_b: FloatArray
    measured_tip_b: FloatArray
    q: FloatArray
    qd: FloatArray
    qdd: FloatArray
    forces: FloatArray
    measured_q: FloatArray
    measured_qd: FloatArray
    status: IntArray
    closure_error: FloatArray

    def __len__(self) -> int:
        return int(self.t.shape[0])

    @property
    def tip_error(self) -> FloatArray:
        """``|measured_tip_b - tip_b|`` per cycle, m, shape (N,)."""
        return np.linalg.norm(self.measured_tip_b - self.tip_b, axis=-1)

    def counts(self) -> dict[str, int]:
        """Cycles that carry each :class:`TeleopStatus` flag."""
        return {f.name: int(np.count_nonzero(self.status & int(f)))  # type: ignore[misc]
                for f in TeleopStatus if f and np.any(self.status & int(f))}


def run_session(tele: Any, arm: Any, master: Iterable[tuple[float, Any, bool]], *,
                max_cycles: int | None = None) -> SessionLog:
    """Drive ``arm`` from ``master`` through ``tele``, one cycle per master item.

    Parameters
    ----------
    tele : Teleop
    arm : SimulatedArm, or None
        None: the commands only (``measured_*`` are the commands, ``closure_error`` NaN).
    master : iterable of (t, position, clutch)
        ``t`` in s; ``position`` (3,) in m in the master's frame, or None (no sample);
        ``clutch``: True while the tip follows the master.
    max_cycles : int, optional, keyword-only
        Stop after this many cycles (an endless master).

    Returns
    -------
    SessionLog
    """
    from ._arm import SimulatedArm
    from ._core import Teleop

    if not isinstance(tele, Teleop):
        raise TypeError(f"tele: expected an athenakin.teleop.Teleop, got {type(tele).__name__}")
    if arm is not None and not isinstance(arm, SimulatedArm):
        raise TypeError(f"arm: expected an athenakin.teleop.SimulatedArm or None, got "
                        f"{type(arm).__name__}")
    T = tele.T_b_e
    R, c = T[:3, :3], T[:3, 3]
    rows: list[tuple] = []
    sim = arm is not None and hasattr(arm.backend, "tip_b")
    if max_cycles is not None:
        max_cycles = check_count(max_cycles, "max_cycles", minimum=0)
    for t, pos, clutch in _master_items(master, max_cycles):
        cmd = tele.step(t, pos, clutch)
        if arm is not None:
            mq, mqd, mtip, ce = _servo(arm, cmd, sim)
        else:
            mq, mqd, ce = cmd.q, cmd.qd, math.nan
            mtip = R @ np.asarray(cmd.tip) + c
        rows.append((cmd.t, _master_row(pos), bool(clutch), cmd.target, cmd.tip, cmd.q, cmd.qd,
                     cmd.qdd, cmd.forces, tuple(mq), tuple(mqd), tuple(mtip), int(cmd.status),
                     ce))
    return _session_log(rows, R, c)


def _master_items(master: object, max_cycles: int | None
                  ) -> Iterator[tuple[float, Any, bool]]:
    """The ``(t, position, clutch)`` items of ``master`` (at most ``max_cycles``), checked."""
    try:
        items = iter(master)  # type: ignore[call-overload]
    except TypeError:
        raise TypeError(f"master: expected an iterable of (t, position, clutch), got "
                        f"{type(master).__name__}") from None
    return _unpacked(items if max_cycles is None else itertools.islice(items, max_cycles))


def _unpacked(items: Iterator[Any]) -> Iterator[tuple[float, Any, bool]]:
    for item in items:
        try:
            t, pos, clutch = item
        except (TypeError, ValueError):
            raise TypeError(f"master: expected items (t, position, clutch), got {item!r:.80}"
                            ) from None
        yield t, pos, clutch


def _servo(arm: Any, cmd: Any, sim: bool) -> tuple[Any, Any, Any, float]:
    """Send ``cmd`` to ``arm`` and step it one cycle.

    Returns the measured ``q``, ``qd``, tip (base frame) and closure error (NaN unless the
    MuJoCo backend reads it out).
    """
    effort = cmd.forces if all(math.isfinite(f) for f in cmd.forces) else None
    arm.servo_jp(cmd.q, velocity=cmd.qd, effort=effort)
    arm.step(1)
    js = arm.measured_js()
    if sim:     # the MuJoCo backend's own read-outs (not in the ArmBackend protocol)
        backend: Any = arm.backend
        return js.position, js.velocity, backend.tip_b(), backend.closure_error()
    return js.position, js.velocity, arm.measured_cp()[:3, 3], math.nan


def _master_row(pos: object) -> tuple[float, ...]:
    """The master's sample as logged: three floats, NaN where it was none or malformed."""
    if pos is None:
        return (math.nan,) * 3
    try:
        m = tuple(float(v) for v in pos)  # type: ignore[attr-defined]
        if len(m) != 3:
            m = (math.nan,) * 3
    except (TypeError, ValueError):
        m = (math.nan,) * 3
    return m


def _session_log(rows: list[tuple], R: FloatArray, c: FloatArray
                 ) -> SessionLog:
    """The rows of :func:`run_session` as arrays; ``R``, ``c``: the RCM frame in the base."""
    n = len(rows)

    def col(i: int, w: int | None = 3) -> NDArray[Any]:
        if w is None:
            return np.array([r[i] for r in rows])
        return np.array([r[i] for r in rows], dtype=float).reshape(n, w)

    tip = col(4)
    return SessionLog(t=col(0, None).astype(float).reshape(n), master=col(1),
                      clutch=np.array([r[2] for r in rows], dtype=bool), target=col(3),
                      tip=tip, tip_b=tip @ R.T + c, measured_tip_b=col(11), q=col(5),
                      qd=col(6), qdd=col(7), forces=col(8), measured_q=col(9),
                      measured_qd=col(10),
                      status=np.array([r[12] for r in rows], dtype=np.int64).reshape(n),
                      closure_error=np.array([r[13] for r in rows], dtype=float).reshape(n))


# ------------------------------------------------------------------ recorded masters
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
            _check_topics(path, topics, {c.topic for c in bag.connections})
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
            _check_topics(path, topics, {c.topic for c in summary.channels.values()})
        for _schema, channel, message, msg in reader.iter_decoded_messages(
                topics=list(topics), log_time_order=True):
            yield channel.topic, int(message.log_time), msg


def _check_topics(path: Path, wanted: tuple[str, ...], present: set[str]) -> None:
    """Each wanted topic is in the recording, else a named error listing what is there."""
    missing = [t for t in wanted if t not in present]
    if missing:
        raise InvalidInputError(f"{path}: no topic {missing[0]!r} in the recording (it has "
                                f"{sorted(present)}); name the pose and clutch topics with "
                                f"--pose-topic / --clutch-topic (clutch_topic=None: no clutch)")


def _stamp(msg: Any, fallback: int) -> int:
    try:
        st = msg.header.stamp
        ns = int(st.sec) * 1_000_000_000 + int(getattr(st, "nanosec", 0))
        return ns if ns > 0 else fallback
    except AttributeError:
        return fallback


def read_master(path: str | Path, *, rate: float = 1000.0, pose_topic: str = "/master/pose",
                clutch_topic: str | None = "/master/joy", clutch_button: int = 0
                ) -> Iterator[tuple[float, tuple[float, float, float] | None, bool]]:
    """A recorded master on the cycle grid: ``(t, position or None, clutch)`` per cycle.

    Parameters
    ----------
    path : str or Path
        An MCAP file or a rosbag2 folder (extra ``ros``).
    rate : float, keyword-only
        Cycles per second, Hz; ``t`` starts at 0 at the first pose.
    pose_topic : str, keyword-only
        ``geometry_msgs/msg/PoseStamped``: the handle's position (m, the master's frame).
    clutch_topic : str or None, keyword-only
        ``sensor_msgs/msg/Joy``; None: the clutch always follows.
    clutch_button : int, keyword-only
        The Joy button of the clutch pedal: held (1) = pressed = the master decoupled.

    Returns
    -------
    iterator of tuple
        ``(t s, (x, y, z) m or None, clutch)`` per cycle: the latest pose received in the
        cycle (None when none arrived), ``clutch`` True while the tip follows. The
        arguments, the file and its topics are checked when ``read_master`` is called.

    Raises
    ------
    InvalidInputError
        No such file, not an MCAP file or rosbag2 folder, a topic it lacks, a bad rate or
        button (a recording with no pose: when the iterator is consumed).
    """
    p = check_path(path, "path")
    if not p.exists():
        raise InvalidInputError(f"path: {path}: no such file or folder")
    rate = check_rate(rate)
    for name, topic in (("pose_topic", pose_topic), ("clutch_topic", clutch_topic)):
        if topic is not None and not (isinstance(topic, str) and topic):
            raise TypeError(f"{name}: expected a topic name (str), got {topic!r:.80}")
    if isinstance(clutch_button, bool) or not isinstance(clutch_button, (int, np.integer)) \
            or clutch_button < 0:
        raise InvalidInputError(f"clutch_button: expected a button index >= 0, got "
                                f"{clutch_button!r:.80}")
    topics = (pose_topic,) + ((clutch_topic,) if clutch_topic else ())
    messages = _messages(p, topics)
    first = next(messages, None)        # opens and checks the recording now, not on iteration
    return _master_cycles(p, first, messages, rate, pose_topic, clutch_topic,
                          int(clutch_button))


def _master_cycles(path: Path, first: tuple[str, int, Any] | None,
                   messages: Iterator[tuple[str, int, Any]], rate: float, pose_topic: str,
                   clutch_topic: str | None, clutch_button: int
                   ) -> Iterator[tuple[float, tuple[float, float, float] | None, bool]]:
    """The cycles of :func:`read_master` from its messages (``first`` already read)."""
    import itertools

    t0: int | None = None
    follow = True
    pending: tuple[float, float, float] | None = None
    k = 0
    seen_pose = False
    stream = itertools.chain([first], messages) if first is not None else iter(())
    for topic, log_ns, msg in stream:
        ns = _stamp(msg, log_ns)
        if topic == clutch_topic:
            b = list(getattr(msg, "buttons", []))
            follow = not (clutch_button < len(b) and int(b[clutch_button]) != 0)
            continue
        seen_pose = True
        pos = msg.pose.position
        if t0 is None:
            t0 = ns
        t = (ns - t0) * 1e-9
        cycle = int(math.floor(t * rate + 1e-9))
        while k < cycle:                       # cycles before this pose: the pending one
            yield k / rate, pending, follow
            pending = None
            k += 1
        pending = (float(pos.x), float(pos.y), float(pos.z))
    if not seen_pose:
        raise InvalidInputError(f"{path}: topic {pose_topic!r} holds no PoseStamped message")
    yield k / rate, pending, follow


# ------------------------------------------------------------------ CRTK topics out
def _msgdef(typename: str) -> str:
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    if typename == TELEOP_STATUS_TYPE:
        head = store.generate_msgdef("std_msgs/msg/Header", ros_version=2)[0]
        return TELEOP_STATUS_MSGDEF + "=" * 80 + "\nMSG: std_msgs/Header\n" + head
    return store.generate_msgdef(typename, ros_version=2)[0]


def _header(ns: int, frame: str) -> dict[str, Any]:
    return {"stamp": {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000},
            "frame_id": frame}


def _pose(ns: int, p: FloatArray) -> dict[str, Any]:
    return {"header": _header(ns, "base"),
            "pose": {"position": {"x": float(p[0]), "y": float(p[1]), "z": float(p[2])},
                     "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}}


def _js(ns: int, q: FloatArray, qd: FloatArray,
        f: FloatArray) -> dict[str, Any]:
    return {"header": _header(ns, ""), "name": ["q1", "q2", "q3"],
            "position": [float(v) for v in q], "velocity": [float(v) for v in qd],
            "effort": [0.0 if not math.isfinite(v) else float(v) for v in f]}


def write_session_mcap(log: SessionLog, path: str | Path, *, start_ns: int = 0,
                       target: str | Path | None = None) -> dict[str, int]:
    """Write a session's CRTK topics to an MCAP file (ROS 2 CDR; Foxglove opens it).

    Topics (:data:`CRTK_TOPICS`): ``measured_js`` / ``setpoint_js``
    (``sensor_msgs/msg/JointState``: q1..q3 in m, m/s, N), ``measured_cp`` / ``servo_cp``
    (``geometry_msgs/msg/PoseStamped``, frame ``base``: the measured and commanded tip,
    m; the orientation is left identity: the instrument's direction follows from the
    RCM), ``status`` (:data:`TELEOP_STATUS_TYPE`) and ``master``
    (``geometry_msgs/msg/PointStamped``, the master's sample, frame ``master``).

    Parameters
    ----------
    log : SessionLog
    path : str or Path
        The file to write; it appears only once complete (temporary file, then rename).
    start_ns : int, keyword-only
        Stamp of ``t = 0``, ns.
    target : str or Path, keyword-only, optional
        Write this file instead and do no rename (the CLI's output manager renames it).

    Returns
    -------
    dict
        Messages per topic.
    """
    if not isinstance(log, SessionLog):
        raise TypeError(f"log: expected a SessionLog, got {type(log).__name__}")
    path = check_path(path, "path")
    start_ns = check_count(start_ns, "start_ns", minimum=0, maximum=_MAX_START_NS)
    with contextlib.ExitStack() as stack:
        if target is None:      # the package's one atomic writer (fsync, rename)
            fh = stack.enter_context(atomic_write(path))
        else:                   # the caller stages the file itself (the CLI's outputs)
            fh = stack.enter_context(open(check_path(target, "target"), "wb"))
        return _write_session(fh, log, start_ns)


#: Latest ``start_ns`` of :func:`write_session_mcap`: a session of a day still stamps
#: within the signed 64-bit nanoseconds of an MCAP log time.
_MAX_START_NS = 2**63 - 1 - 86_400 * 10**9


def _write_session(fh: Any, log: SessionLog, start_ns: int) -> dict[str, int]:
    """The messages of :func:`write_session_mcap` into the open binary file ``fh``."""
    from mcap_ros2.writer import Writer

    counts = {v: 0 for v in CRTK_TOPICS.values()}
    w = Writer(fh)
    sch = {k: w.register_msgdef(k, _msgdef(k)) for k in (
        "sensor_msgs/msg/JointState", "geometry_msgs/msg/PoseStamped",
        "geometry_msgs/msg/PointStamped", TELEOP_STATUS_TYPE)}
    js, ps = sch["sensor_msgs/msg/JointState"], sch["geometry_msgs/msg/PoseStamped"]
    err = log.tip_error
    for i in range(len(log)):
        ns = int(start_ns + round(float(log.t[i]) * 1e9))
        st = int(log.status[i])
        msgs = [
            ("measured_js", js, _js(ns, log.measured_q[i], log.measured_qd[i],
                                    log.forces[i])),
            ("setpoint_js", js, _js(ns, log.q[i], log.qd[i], log.forces[i])),
            ("measured_cp", ps, _pose(ns, log.measured_tip_b[i])),
            ("servo_cp", ps, _pose(ns, log.tip_b[i])),
            ("status", sch[TELEOP_STATUS_TYPE], {
                "header": _header(ns, "base"), "flags": st,
                "names": TeleopStatus(st).name or "" if st else "",
                "clutched": bool(st & TeleopStatus.CLUTCHED),
                "limited": bool(st & _LIMITED), "hold": bool(st & TeleopStatus.HOLD),
                "watchdog": bool(st & TeleopStatus.WATCHDOG),
                "estop": bool(st & TeleopStatus.ESTOP),
                "clearance_m": math.nan, "tip_error_m": float(err[i])}),
        ]
        if np.all(np.isfinite(log.master[i])):
            m = log.master[i]
            msgs.append(("master", sch["geometry_msgs/msg/PointStamped"], {
                "header": _header(ns, "master"),
                "point": {"x": float(m[0]), "y": float(m[1]), "z": float(m[2])}}))
        for key, schema, msg in msgs:
            topic = CRTK_TOPICS[key]
            w.write_message(topic, schema, msg, log_time=ns, publish_time=ns,
                            sequence=counts[topic])
            counts[topic] += 1
    w.finish()
    return counts
