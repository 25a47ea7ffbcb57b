"""Messages <-> arrays: the conversions of the nodes' callbacks (private).

Every function here is a plain conversion: a message from numbers, or numbers from a
message with its fields checked (a named :class:`~athenakin.errors.InvalidInputError`
for a wrong length, a NaN, an unknown joint name or a frame the node does not serve).
The orientation of a pose is :func:`athenakin.ros._frames.quaternion_xyzw`, the one
rotation-to-quaternion of the ros package.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from .._typing import FloatArray
from ..errors import InvalidInputError
from ..ros._frames import quaternion_xyzw

__all__ = ["ACTUATORS", "joint_state", "pose_stamped", "twist_stamped", "actuator_command",
           "tip_command", "stamp_ns", "time_msg"]

#: Names of the three actuators in ``measured_js``, ``setpoint_js``, ``servo_jp``.
ACTUATORS = ("q1", "q2", "q3")
#: How far a command pose's quaternion norm may lie from 1 (tf2's test of a malformed one).
QUATERNION_NORM_TOL = 1e-3


def time_msg(ns: int) -> Any:
    """``builtin_interfaces/msg/Time`` of ``ns`` nanoseconds."""
    from builtin_interfaces.msg import Time

    return Time(sec=int(ns // 1_000_000_000), nanosec=int(ns % 1_000_000_000))


def stamp_ns(header: Any) -> int:
    """The stamp of a ``std_msgs/Header`` in nanoseconds (0: unstamped)."""
    return int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)


def joint_state(names: Sequence[str], position: Any, velocity: Any = (), effort: Any = (), *,
                stamp: Any = None, frame_id: str = "") -> Any:
    """``sensor_msgs/JointState`` of ``names`` (m or rad, m/s or rad/s, N or N m).

    Parameters
    ----------
    names : sequence of str
    position, velocity, effort : array-like, shape (len(names),) or empty
    stamp : builtin_interfaces/msg/Time, optional, keyword-only
    frame_id : str, keyword-only

    Returns
    -------
    sensor_msgs.msg.JointState
    """
    from sensor_msgs.msg import JointState

    msg = JointState()
    if stamp is not None:
        msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    msg.name = list(names)
    msg.position = [float(v) for v in position]
    msg.velocity = [float(v) for v in velocity]
    msg.effort = [float(v) for v in effort]
    return msg


def pose_stamped(T: FloatArray, frame_id: str, *, stamp: Any = None) -> Any:
    """``geometry_msgs/PoseStamped`` of a (4, 4) pose in ``frame_id`` (m; quaternion x, y, z, w)."""
    from geometry_msgs.msg import PoseStamped

    T = np.asarray(T, dtype=float)
    q = quaternion_xyzw(T[None, :3, :3])[0]
    msg = PoseStamped()
    if stamp is not None:
        msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    p = msg.pose.position
    p.x, p.y, p.z = (float(v) for v in T[:3, 3])
    o = msg.pose.orientation
    o.x, o.y, o.z, o.w = (float(v) for v in q)
    return msg


def twist_stamped(linear: FloatArray, angular: FloatArray, frame_id: str, *,
                  stamp: Any = None) -> Any:
    """``geometry_msgs/TwistStamped``: linear (m/s) and angular (rad/s) velocity in ``frame_id``."""
    from geometry_msgs.msg import TwistStamped

    msg = TwistStamped()
    if stamp is not None:
        msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    lin, ang = msg.twist.linear, msg.twist.angular
    lin.x, lin.y, lin.z = (float(v) for v in linear)
    ang.x, ang.y, ang.z = (float(v) for v in angular)
    return msg


def _finite(values: Sequence[float], name: str) -> FloatArray:
    x = np.array(values, dtype=float)
    if not np.all(np.isfinite(x)):
        raise InvalidInputError(f"{name}: expected finite numbers, got {x.tolist()}")
    return x


def actuator_command(msg: Any, names: Sequence[str] = ACTUATORS
                     ) -> tuple[FloatArray, FloatArray | None, FloatArray | None]:
    """The actuator positions, velocities and efforts of a ``sensor_msgs/JointState`` command.

    Parameters
    ----------
    msg : sensor_msgs.msg.JointState
        ``position`` of the three actuators (m); ``velocity`` (m/s) and ``effort`` (N)
        empty or of the same length. ``name`` empty (the order of ``names``) or a
        permutation of ``names``.
    names : sequence of str
        The actuators' names, in the order of the returned arrays.

    Returns
    -------
    position : ndarray, shape (3,)
    velocity, effort : ndarray, shape (3,), or None (empty in the message)

    Raises
    ------
    InvalidInputError
        A wrong length, a NaN or inf, a name not among ``names`` (each named).
    """
    n = len(names)
    got = list(msg.name)
    if got and sorted(got) != sorted(names):
        raise InvalidInputError(f"name: expected the joints {list(names)} (or none), got {got}")
    order = [got.index(k) for k in names] if got else list(range(n))
    out: list[FloatArray | None] = []
    for field in ("position", "velocity", "effort"):
        values = list(getattr(msg, field))
        if not values and field != "position":
            out.append(None)
            continue
        if len(values) != n:
            raise InvalidInputError(f"{field}: expected {n} values, got {len(values)}")
        out.append(_finite([values[i] for i in order], field))
    assert out[0] is not None
    return out[0], out[1], out[2]


def tip_command(msg: Any, frames: dict[str, str]) -> tuple[FloatArray, str]:
    """The tip position and its frame of a ``geometry_msgs/PoseStamped`` command.

    Parameters
    ----------
    msg : geometry_msgs.msg.PoseStamped
        The tip position in ``header.frame_id`` (m); the orientation is not used (the
        instrument's direction follows from the RCM) but must be a unit quaternion
        (to :data:`QUATERNION_NORM_TOL`): an all-zero pose is a message never filled in.
    frames : dict of str -> str
        Accepted ``frame_id`` -> the arm's frame name (``"base"`` or ``"rcm"``); the
        empty ``frame_id`` is the base frame.

    Returns
    -------
    tip : ndarray, shape (3,)
    frame : str

    Raises
    ------
    InvalidInputError
        An unknown ``frame_id``, a non-finite position, an orientation that is no unit
        quaternion.
    """
    fid = str(msg.header.frame_id)
    if fid not in frames:
        raise InvalidInputError(f"frame_id: expected one of {sorted(k for k in frames if k)} "
                                f"(or empty: the base frame), got {fid!r}")
    o = msg.pose.orientation
    xyzw = [o.x, o.y, o.z, o.w]
    norm = math.sqrt(math.fsum(v * v for v in xyzw))
    if not abs(norm - 1.0) <= QUATERNION_NORM_TOL:       # NaN fails too
        raise InvalidInputError(f"orientation: expected a unit quaternion (x, y, z, w), got "
                                f"{xyzw} (norm {norm:g}; identity: w = 1)")
    p = msg.pose.position
    return _finite([p.x, p.y, p.z], "position"), frames[fid]


def master_position(msg: Any) -> tuple[float, float, float]:
    """The handle position of a master ``PoseStamped`` (m), as it is (NaN included).

    The teleoperation core checks the sample itself (a non-finite one is flagged
    ``INVALID`` and ignored).
    """
    p = msg.pose.position
    return float(p.x), float(p.y), float(p.z)
