"""Masters and sessions: any iterator of samples through the core and the arm (private).

* :func:`run_session`: ``(t, position, clutch)`` items (position None: no sample) ->
  :class:`Teleop` -> :class:`SimulatedArm` (``servo_jp`` with velocity and effort
  feed-forward), cycle by cycle; a :class:`SessionLog` of arrays. The robot's bodies are
  checked against each other by default: a ``Teleop`` that checks no clearance is
  refused unless ``check_bodies=False`` says so.
* :func:`read_master`: a recorded master, an MCAP file or a rosbag2 folder of
  ``geometry_msgs/msg/PoseStamped`` (the handle) and ``sensor_msgs/msg/Joy`` (the
  clutch pedal: a button held = clutch pressed, dVRK's meaning: the master decoupled),
  resampled on the cycle grid (a cycle without a new pose gets None: the watchdog sees
  the recording's own gaps, up to :data:`MAX_GAP_S`; a longer gap is an error). Each
  clutch change applies from the cycle of its own stamp. Only regular files and folders
  are read (a FIFO or a device is refused, nothing blocks).
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
from .._typing import BoolArray, FloatArray, Int8Array, IntArray
from .._validation import check_count, check_path, check_scalar
from ..errors import InvalidInputError
from ._filter import check_rate
from ._options import TeleopStatus

__all__ = ["SessionLog", "MasterRecording", "run_session", "read_master", "write_session_mcap",
           "CRTK_TOPICS", "TELEOP_STATUS_TYPE", "TELEOP_STATUS_MSGDEF", "MAX_GAP_S",
           "POSE_TYPE", "CLUTCH_TYPE"]

#: Longest gap between two poses of a recorded master that :func:`read_master` puts on
#: the cycle grid (the watchdog trips on it), s; a longer one is an error.
MAX_GAP_S = 10.0
#: Message type of the pose topic of a recorded master.
POSE_TYPE = "geometry_msgs/msg/PoseStamped"
#: Message type of its clutch topic.
CLUTCH_TYPE = "sensor_msgs/msg/Joy"

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
    clearance : ndarray, shape (N,)
        The core's least clearance of the bodies in the cycle, m (NaN: not checked).
    effort : ndarray, shape (N, 3)
        The force the arm applied in the cycle (PD + feed-forward, saturated), N; without
        an arm the feed-forward of the command.
    arm_state : ndarray of int8, shape (N,)
        Index in :data:`OPERATING_STATES` of the arm's state after the cycle (-1: no arm).
    slot : ndarray of int64, shape (N,)
        The commanded FK slot.
    tip_quat_b, measured_quat_b : ndarray, shape (N, 4)
        Orientation of the commanded and the measured tool-tip frame in the base frame
        (:attr:`athenakin.FKSolution.T_b_tip`), ``(x, y, z, w)`` (ROS order); NaN where the
        FK of ``q`` / ``measured_q`` does not assemble in the slot.
    start_ns : int or None
        Stamp of ``t = 0`` in ns since the epoch (a recording's first pose,
        :attr:`MasterRecording.start_ns`); None: ``t`` is taken as the stamp itself.
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
    clearance: FloatArray
    effort: FloatArray
    arm_state: Int8Array
    slot: IntArray
    tip_quat_b: FloatArray
    measured_quat_b: FloatArray
    start_ns: int | None = None

    def __len__(self) -> int:
        """The number of cycles."""
        return int(self.t.shape[0])

    @property
    def tip_error(self) -> FloatArray:
        """``|measured_tip_b - tip_b|`` per cycle, m, shape (N,)."""
        return np.linalg.norm(self.measured_tip_b - self.tip_b, axis=-1)

    def counts(self) -> dict[str, int]:
        """Cycles that carry each :class:`TeleopStatus` flag.

        Returns
        -------
        dict
            Flag name -> cycles, for the flags that occur.
        """
        return {f.name: int(np.count_nonzero(self.status & int(f)))  # type: ignore[misc]
                for f in TeleopStatus if f and np.any(self.status & int(f))}


def run_session(tele: Any, arm: Any, master: Iterable[tuple[float, Any, bool]], *,
                max_cycles: int | None = None, check_bodies: bool = True) -> SessionLog:
    """Drive ``arm`` from ``master`` through ``tele``, one cycle per master item.

    The loop raises nowhere :meth:`Teleop.step` does not: a malformed item's position or
    clutch is the core's ``INVALID`` (logged NaN / not engaged), the arm holds and flags
    what it refuses (:attr:`SimulatedArm.refusal`) and faults on what it cannot trust.

    Parameters
    ----------
    tele : Teleop
        Checking the bodies' clearance (``bodies=``, or an ``environment``) unless
        ``check_bodies=False``.
    arm : SimulatedArm, or None
        ``ENABLED`` (call :meth:`SimulatedArm.enable` first). None: the commands only
        (``measured_*`` are the commands, ``closure_error`` NaN).
    master : iterable of (t, position, clutch)
        ``t`` in s; ``position`` (3,) in m in the master's frame, or None (no sample);
        ``clutch``: True while the tip follows the master. A :class:`MasterRecording`
        also gives the session its time base (:attr:`SessionLog.start_ns`).
    max_cycles : int, optional, keyword-only
        Stop after this many cycles (an endless master).
    check_bodies : bool, keyword-only
        True (default): refuse a ``tele`` that checks no clearance of the robot's bodies
        against each other. False: run without, explicitly.

    Returns
    -------
    SessionLog

    Raises
    ------
    TypeError
        ``tele``, ``arm`` or ``master`` of the wrong kind; a master item that is not a
        ``(t, position, clutch)`` triple.
    InvalidInputError
        ``tele`` checks no body clearance and ``check_bodies`` is True; ``arm`` is not
        ``ENABLED``; a bad ``max_cycles``; a recorded master's named errors (a gap longer
        than :data:`MAX_GAP_S`, a clutch button its Joy lacks) when they are met.
    """
    from ._arm import OPERATING_STATES, SimulatedArm
    from ._core import Teleop

    if not isinstance(tele, Teleop):
        raise TypeError(f"tele: expected an athenakin.teleop.Teleop, got {type(tele).__name__}")
    if arm is not None and not isinstance(arm, SimulatedArm):
        raise TypeError(f"arm: expected an athenakin.teleop.SimulatedArm or None, got "
                        f"{type(arm).__name__}")
    if not isinstance(check_bodies, bool):
        raise TypeError(f"check_bodies: expected a bool, got {type(check_bodies).__name__}")
    if max_cycles is not None:
        max_cycles = check_count(max_cycles, "max_cycles", minimum=0)
    items = _master_items(master, max_cycles)
    if check_bodies and not tele.checks_clearance:
        raise InvalidInputError("tele: checks no clearance of the robot's bodies; build it "
                                "with bodies=athenakin.collision.Bodies.default(design) (or "
                                "an environment), or pass check_bodies=False to run without")
    if arm is not None and arm.operating_state != "ENABLED":
        raise InvalidInputError(f"arm: the arm is {arm.operating_state}; call arm.enable() "
                                f"before the session")
    T = tele.T_b_e
    R, c = T[:3, :3], T[:3, 3]
    rows: list[tuple] = []
    sim = arm is not None and hasattr(arm.backend, "tip_b")
    state_index = {s: i for i, s in enumerate(OPERATING_STATES)}
    for t, pos, clutch in items:
        cmd = tele.step(t, pos, clutch)
        if arm is not None:
            mq, mqd, mtip, ce, eff = _servo(arm, cmd, sim)
            st = state_index[arm.operating_state]
        else:
            mq, mqd, ce, eff, st = cmd.q, cmd.qd, math.nan, cmd.forces, -1
            mtip = R @ np.asarray(cmd.tip) + c
        rows.append((cmd.t, _master_row(pos), _clutch_row(clutch), cmd.target, cmd.tip, cmd.q,
                     cmd.qd, cmd.qdd, cmd.forces, tuple(mq), tuple(mqd), tuple(mtip),
                     int(cmd.status), ce, float(cmd.clearance), tuple(eff), st,
                     int(cmd.slot)))
    start = getattr(master, "start_ns", None)
    return _session_log(rows, tele, None if start is None else int(start))


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


def _servo(arm: Any, cmd: Any, sim: bool) -> tuple[Any, Any, Any, float, Any]:
    """Send ``cmd`` to ``arm`` and step it one cycle.

    Returns the measured ``q``, ``qd``, tip (base frame), closure error (NaN unless the
    MuJoCo backend reads it out) and the applied effort. The arm holds and flags what it
    refuses; nothing here raises for a command's values.
    """
    effort = cmd.forces if all(math.isfinite(f) for f in cmd.forces) else None
    arm.servo_jp(cmd.q, velocity=cmd.qd, effort=effort)
    arm.step(1)
    js = arm.measured_js()
    if sim:     # the MuJoCo backend's own read-outs (not in the ArmBackend protocol)
        backend: Any = arm.backend
        return js.position, js.velocity, backend.tip_b(), backend.closure_error(), js.effort
    return js.position, js.velocity, arm.measured_cp()[:3, 3], math.nan, js.effort


def _master_row(pos: object) -> tuple[float, ...]:
    """The master's sample as logged: three floats, NaN where it was none or malformed."""
    nan3 = (math.nan,) * 3
    if pos is None or isinstance(pos, (str, bytes, bytearray)):
        return nan3
    try:
        m = tuple(float(v) for v in pos)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        return nan3
    return m if len(m) == 3 else nan3


def _clutch_row(clutch: object) -> bool:
    """The clutch as logged: True only for a real boolean True (anything else: not engaged)."""
    return isinstance(clutch, (bool, np.bool_)) and bool(clutch)


def _session_log(rows: list[tuple], tele: Any, start_ns: int | None) -> SessionLog:
    """The rows of :func:`run_session` as arrays, with the orientations of their tips."""
    T = tele.T_b_e
    R, c = T[:3, :3], T[:3, 3]
    n = len(rows)

    def col(i: int, w: int | None = 3) -> NDArray[Any]:
        if w is None:
            return np.array([r[i] for r in rows])
        return np.array([r[i] for r in rows], dtype=float).reshape(n, w)

    tip = col(4)
    q, mq = col(5), col(9)
    slot = np.array([r[17] for r in rows], dtype=np.int64).reshape(n)
    return SessionLog(t=col(0, None).astype(float).reshape(n), master=col(1),
                      clutch=np.array([r[2] for r in rows], dtype=bool).reshape(n),
                      target=col(3), tip=tip, tip_b=tip @ R.T + c, measured_tip_b=col(11),
                      q=q, qd=col(6), qdd=col(7), forces=col(8), measured_q=mq,
                      measured_qd=col(10),
                      status=np.array([r[12] for r in rows], dtype=np.int64).reshape(n),
                      closure_error=np.array([r[13] for r in rows], dtype=float).reshape(n),
                      clearance=np.array([r[14] for r in rows], dtype=float).reshape(n),
                      effort=col(15),
                      arm_state=np.array([r[16] for r in rows], dtype=np.int8).reshape(n),
                      slot=slot, tip_quat_b=_tip_quaternions(q, slot, tele),
                      measured_quat_b=_tip_quaternions(mq, slot, tele), start_ns=start_ns)


def _tip_quaternions(q: FloatArray, slot: IntArray, tele: Any) -> FloatArray:
    """``(x, y, z, w)`` of the tool-tip frames of ``q`` (N, 3) in their slots; NaN if none."""
    from .._dispatch import forward_kinematics
    from ..study._study import _quaternion_from_rotation

    out = np.full((len(q), 4), np.nan)
    if not len(q):
        return out
    ok = np.all(np.isfinite(q), axis=-1)
    if not ok.any():
        return out
    sol = forward_kinematics(q[ok], tele.T_b_e, tele.design, errors="flag")
    Rt = np.asarray(sol.T_b_tip)[np.arange(int(ok.sum())), slot[ok], :3, :3]
    good = np.all(np.isfinite(Rt), axis=(-2, -1))
    x = np.full((len(Rt), 4), np.nan)
    if good.any():
        x0 = _quaternion_from_rotation(Rt[good])              # (x0, x1, x2, x3), x0 scalar
        x0 = np.where(x0[:, :1] < 0, -x0, x0)
        x[good] = x0[:, [1, 2, 3, 0]]
    out[ok] = x
    return out


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


def _pose(ns: int, p: FloatArray, quat: FloatArray) -> dict[str, Any]:
    x = quat if np.all(np.isfinite(quat)) else _NO_ORIENTATION
    return {"header": _header(ns, "base"),
            "pose": {"position": {"x": float(p[0]), "y": float(p[1]), "z": float(p[2])},
                     "orientation": {"x": float(x[0]), "y": float(x[1]), "z": float(x[2]),
                                     "w": float(x[3])}}}


#: The orientation written where a tip frame is not known (the FK did not assemble).
_NO_ORIENTATION = np.array([0.0, 0.0, 0.0, 1.0])


def _js(ns: int, q: FloatArray, qd: FloatArray,
        f: FloatArray) -> dict[str, Any]:
    return {"header": _header(ns, ""), "name": ["q1", "q2", "q3"],
            "position": [float(v) for v in q], "velocity": [float(v) for v in qd],
            "effort": [0.0 if not math.isfinite(v) else float(v) for v in f]}


def write_session_mcap(log: SessionLog, path: str | Path, *, start_ns: int | None = None,
                       target: str | Path | None = None) -> dict[str, int]:
    """Write a session's CRTK topics to an MCAP file (ROS 2 CDR; Foxglove opens it).

    Topics (:data:`CRTK_TOPICS`): ``measured_js`` (``sensor_msgs/msg/JointState``: q1..q3
    measured, m, m/s, and the applied effort, N), ``setpoint_js`` (the commands, m, m/s,
    and the applied effort, CRTK's meaning), ``measured_cp`` / ``servo_cp``
    (``geometry_msgs/msg/PoseStamped``, frame ``base``: the measured and commanded
    tool-tip frames, position m and the instrument's orientation), ``status``
    (:data:`TELEOP_STATUS_TYPE`, with the core's checked clearance) and ``master``
    (``geometry_msgs/msg/PointStamped``, the master's sample, frame ``master``).

    Parameters
    ----------
    log : SessionLog
    path : str or Path
        The file to write; it appears only once complete (temporary file, then rename).
    start_ns : int, keyword-only, optional
        Stamp of ``t = 0``, ns since the epoch; default the log's own time base
        (:attr:`SessionLog.start_ns`, a recording's first pose), else 0 (``t`` is then
        the stamp itself).
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
    if start_ns is None:
        start_ns = 0 if log.start_ns is None else log.start_ns
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
                                    log.effort[i])),
            ("setpoint_js", js, _js(ns, log.q[i], log.qd[i], log.effort[i])),
            ("measured_cp", ps, _pose(ns, log.measured_tip_b[i], log.measured_quat_b[i])),
            ("servo_cp", ps, _pose(ns, log.tip_b[i], log.tip_quat_b[i])),
            ("status", sch[TELEOP_STATUS_TYPE], {
                "header": _header(ns, "base"), "flags": st,
                "names": TeleopStatus(st).name or "" if st else "",
                "clutched": bool(st & TeleopStatus.CLUTCHED),
                "limited": bool(st & _LIMITED), "hold": bool(st & TeleopStatus.HOLD),
                "watchdog": bool(st & TeleopStatus.WATCHDOG),
                "estop": bool(st & TeleopStatus.ESTOP),
                "clearance_m": float(log.clearance[i]), "tip_error_m": float(err[i])}),
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
