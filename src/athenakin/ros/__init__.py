"""ATHENA's data in ROS 2: read recordings, write poses and frames, stream live to Foxglove.

Pure Python, no ROS installation: the extra ``ros`` (rosbags, mcap,
mcap-ros2-support, foxglove-sdk). Names, frames, units and topics: docs/ros.md.

* :func:`read_joint_states` / :func:`iter_joint_states`: actuator readings from a
  rosbag2 folder (sqlite3 or MCAP storage), an MCAP file or a ROS 1 bag of
  ``sensor_msgs/JointState``, header stamps to the nanosecond.
* :func:`track_recording` / :func:`track_to_mcap`: run the continuity tracker on a
  stream and write the tool tip, the frames (``/tf``), every joint of the URDF,
  the tracker's status and the URDF itself to an MCAP file that Foxglove opens
  (chunk size, events listed, compression: :class:`TrackOptions`).
* :func:`write_trajectory`: a planned trajectory as ``trajectory_msgs/JointTrajectory``
  plus the same visualisation topics.
* :class:`FoxgloveStream`: serve the live robot over the Foxglove WebSocket protocol.
"""

from ._errors import RecordingError, RecordingWarning, ServeError
from ._frames import BASE_FRAME, MOVING_LINKS, RCM_FRAME, TOOL_TIP_FRAME
from ._live import FoxgloveStream
from ._read import (
    CHUNK,
    JOINT_STATE_TYPES,
    MAX_READINGS,
    JointStates,
    iter_joint_states,
    read_joint_states,
    recording_format,
)
from ._track import (
    TrackingSummary,
    TrackOptions,
    track_recording,
    track_to_mcap,
    write_trajectory,
)
from ._write import STATUS_MSGDEF, STATUS_TYPE, TF_FRAMES, TOPICS, McapOutput, TrackedBatch

__all__ = [
    "BASE_FRAME",
    "CHUNK",
    "JOINT_STATE_TYPES",
    "MAX_READINGS",
    "MOVING_LINKS",
    "RCM_FRAME",
    "STATUS_MSGDEF",
    "STATUS_TYPE",
    "TF_FRAMES",
    "TOOL_TIP_FRAME",
    "TOPICS",
    "FoxgloveStream",
    "JointStates",
    "McapOutput",
    "RecordingError",
    "RecordingWarning",
    "ServeError",
    "TrackOptions",
    "TrackedBatch",
    "TrackingSummary",
    "iter_joint_states",
    "read_joint_states",
    "recording_format",
    "track_recording",
    "track_to_mcap",
    "write_trajectory",
]
