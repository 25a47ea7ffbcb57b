"""The ROS 2 messages the recorder writes: their definitions and their CDR templates."""

from __future__ import annotations

import functools
from typing import Any

from .._typing import FloatArray, IntArray
from ._cdr import CdrBuilder, Template, split_stamps
from ._errors import ros_extra_missing
from ._frames import (
    BASE_FRAME,
    quaternion_xyzw,
)

#: Type of ``/athena/status``.
STATUS_TYPE = "athenakin_msgs/msg/TrackStatus"


#: Its definition (ROS 2 .msg syntax).
STATUS_MSGDEF = """\
# The continuity tracker's verdict on one actuator reading (athenakin.motion.TrackFlag).
std_msgs/Header header
uint32 sample              # index of the reading in the stream
bool valid                 # false: no forward-kinematics solution (LOST); no pose published
int8 mode                  # assembly mode, +1 / -1 (0 when not valid)
uint8 slot                 # forward-kinematics slot 8 m + 4 r + 2 b + w
uint32 flags               # athenakin.motion.TrackFlag bits
bool lost
bool mode_switch
bool branch_switch
bool jump
bool ambiguous
bool out_of_stroke
bool near_singular         # any NEAR_* bit
float64 step               # distance to the previous pose, in units of the jump thresholds
float64 half_chord         # m: distance to the assembly-mode boundary
float64 sin_u2
float64 sin_u4
float64 clearance_m        # smallest distance between bodies, m; NaN: not computed
uint32 clearance_flags     # collision flags; 0: none or not computed
"""


#: Boolean fields of the status and the TrackFlag bits they report.
STATUS_FLAG_FIELDS = {"lost": 1, "mode_switch": 8, "branch_switch": 16, "jump": 4,
                      "ambiguous": 32, "out_of_stroke": 64}


_SEP = "=" * 80 + "\n"


@functools.lru_cache(maxsize=32)
def msgdef(typename: str) -> str:
    """The ROS 2 message definition of ``typename`` with its dependencies (MCAP ``ros2msg``)."""
    try:
        from rosbags.typesys import Stores, get_typestore
    except ModuleNotFoundError as exc:  # pragma: no cover
        raise ros_extra_missing(exc) from None
    store = get_typestore(Stores.ROS2_HUMBLE)
    if typename == STATUS_TYPE:
        head = store.generate_msgdef("std_msgs/msg/Header", ros_version=2)[0]
        return STATUS_MSGDEF + _SEP + "MSG: std_msgs/Header\n" + head
    return store.generate_msgdef(typename, ros_version=2)[0]


# ---------------------------------------------------------------------------- templates
def _pose_template() -> Template:
    b = CdrBuilder()
    b.header(BASE_FRAME)
    b.vec3("p")
    b.quat("o")
    return b.template()


def _tf_template(pairs: tuple[tuple[str, str], ...]) -> Template:
    b = CdrBuilder()
    b.num("u4", len(pairs))
    for k, (parent, child) in enumerate(pairs):
        b.header(parent, name=f"stamp{k}")
        b.string(child)
        b.vec3(f"t{k}")
        b.quat(f"r{k}")
    return b.template()


def _joint_state_template(names: tuple[str, ...]) -> Template:
    b = CdrBuilder()
    b.header("")
    b.strings(names)
    b.f8_seq("pos", len(names))
    b.num("u4", 0)      # velocity[]
    b.num("u4", 0)      # effort[]
    return b.template()


def _status_template() -> Template:
    b = CdrBuilder()
    b.header(BASE_FRAME)
    b.num("u4", 0, "sample")
    b.num("b1", False, "valid")
    b.num("i1", 0, "mode")
    b.num("u1", 0, "slot")
    b.num("u4", 0, "flags")
    for name in (*STATUS_FLAG_FIELDS, "near_singular"):
        b.num("b1", False, name)
    for name in ("step", "half_chord", "sin_u2", "sin_u4", "clearance_m"):
        b.num("f8", 0.0, name)
    b.num("u4", 0, "clearance_flags")
    return b.template()


def _string_message(text: str) -> bytes:
    b = CdrBuilder()
    b.string(text)
    return bytes(b.buf)


def _stamp_fields(values: dict[str, Any], stamps_ns: IntArray, names: list[str]
                  ) -> None:
    sec, nsec = split_stamps(stamps_ns)
    for n in names:
        values[f"{n}.sec"] = sec
        values[f"{n}.nanosec"] = nsec


def _put_frame(values: dict[str, Any], f: FloatArray, tname: str, rname: str
               ) -> None:
    """The numbers of a translation and a quaternion from ``f`` (N, 7) (:func:`link_frames`)."""
    for i, c in enumerate("xyz"):
        values[f"{tname}.{c}"] = f[:, i]
    for i, c in enumerate("xyzw"):
        values[f"{rname}.{c}"] = f[:, 3 + i]


def _put_pose(values: dict[str, Any], T: FloatArray, tname: str, rname: str, *,
              backend: str = "auto") -> None:
    for i, c in enumerate("xyz"):
        values[f"{tname}.{c}"] = T[:, i, 3]
    quat = quaternion_xyzw(T[:, :3, :3], backend=backend)
    for i, c in enumerate("xyzw"):
        values[f"{rname}.{c}"] = quat[:, i]
