"""Teleoperation of ATHENA: a master drives the tool tip through a safety layer.

* :class:`Teleop` (the core): master samples ``(t, position, clutch)`` -> actuator
  commands :class:`TeleopCommand` (``q, qd, qdd``, feed-forward forces, the commanded
  tip, :class:`TeleopStatus` flags), one cycle at a time; registration, motion scale,
  clutch, a tremor filter (:data:`TREMOR_FILTERS`), exact IK on the tracked branch,
  stroke / depth / singular-set / fixture / clearance / velocity / acceleration limits,
  watchdog and e-stop. Settings beyond the keywords: :class:`TeleopOptions`.
* :class:`SimulatedArm`: the robot in MuJoCo (the exported MJCF, loops closed by
  equality constraints, force motors) under a PD + feed-forward servo, with CRTK's
  command names; :class:`ArmBackend` is the two-method interface of a real driver.
* :func:`run_session`: any iterator of ``(t, position, clutch)`` through the core and
  the arm; :func:`read_master`: a recorded master (MCAP / rosbag2 ``PoseStamped`` and
  a ``Joy`` clutch button).

Frames and units: the master in its own frame (m), registered to the RCM frame E by a
rotation; tips in E (m) unless a name says ``_b`` (base frame); actuators in m, m/s,
m/s^2, N. docs/teleop.md has the measurements.
"""

from ._arm import OPERATING_STATES, JointState, SimulatedArm
from ._arm_backend import ArmBackend, MujocoBackend
from ._core import Teleop, TeleopCommand
from ._filter import (
    TREMOR_FILTERS,
    TREMOR_NOTCH,
    TREMOR_NOTCH_LOWPASS,
    TremorFilter,
    filter_response,
)
from ._master_recording import CLUTCH_TYPE, MAX_GAP_S, POSE_TYPE, MasterRecording, read_master
from ._options import TeleopOptions, TeleopStatus
from ._servo import ServoGains
from ._session import SessionLog, run_session
from ._session_mcap import CRTK_TOPICS, TELEOP_STATUS_MSGDEF, TELEOP_STATUS_TYPE, write_session_mcap

__all__ = [
    "CLUTCH_TYPE",
    "CRTK_TOPICS",
    "MAX_GAP_S",
    "POSE_TYPE",
    "MasterRecording",
    "TELEOP_STATUS_MSGDEF",
    "TELEOP_STATUS_TYPE",
    "SessionLog",
    "read_master",
    "run_session",
    "write_session_mcap",
    "OPERATING_STATES",
    "ArmBackend",
    "JointState",
    "MujocoBackend",
    "ServoGains",
    "SimulatedArm",
    "TREMOR_FILTERS",
    "TREMOR_NOTCH_LOWPASS",
    "TREMOR_NOTCH",
    "Teleop",
    "TeleopCommand",
    "TeleopOptions",
    "TeleopStatus",
    "TremorFilter",
    "filter_response",
]
