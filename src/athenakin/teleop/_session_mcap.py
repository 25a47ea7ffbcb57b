"""A session as CRTK topics: the MCAP file of :func:`write_session_mcap` (private).

The cycles of a :class:`~athenakin.teleop.SessionLog` as ``measured_js``,
``setpoint_js``, ``measured_cp``, ``servo_cp``, ``status`` and ``master`` messages (ROS 2
CDR, :data:`CRTK_TOPICS`) in an MCAP file that Foxglove opens, written through a
temporary file renamed into place.

Units: m, m/s, N; stamps in ns since the epoch.
"""

from __future__ import annotations

import contextlib
import math
from pathlib import Path
from typing import Any

import numpy as np

from .._output import atomic_write
from .._typing import FloatArray
from .._validation import check_count, check_path
from ._options import TeleopStatus
from ._session import SessionLog

__all__ = ["write_session_mcap", "CRTK_TOPICS", "TELEOP_STATUS_TYPE", "TELEOP_STATUS_MSGDEF"]

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
