"""Motion: instrument paths about the RCM to actuator trajectories, encoder streams to poses.

* :func:`plan`, :func:`plan_directions`: a tool-tip path (straight segments in the
  RCM frame) or a direction + insertion path -> a checked actuator trajectory
  sampled at a uniform rate (Ruckig time law; docs/motion.md); its settings (rate,
  limits, margins) in a :class:`PlanOptions`.
* :class:`Tracker`: actuator readings, one sample at a time -> the instrument pose
  of the forward-kinematics solution continuous with the previous one, with flags
  for mode / branch switches, jumps and the approach to singularities.
* :class:`Margins`, :func:`singularity_measures`: distances to the singularities.
* Files and figures: :func:`read_path_csv`, :func:`read_q_stream_csv`,
  :func:`save_trajectory`, :func:`save_plots` and the ``plot_*`` functions
  (matplotlib imported on first use).
* Errors: :class:`SafetyViolationError`, :class:`TimingInfeasibleError`,
  :class:`CollisionError`, :class:`PathFileError`, :class:`TrackingError` (all
  :class:`MotionError`, a :class:`~athenakin.errors.KinematicsError`).
* Collisions (:mod:`athenakin.collision`, imported only when asked): the tracker's
  ``COLLISION`` / ``NEAR_COLLISION`` flags and the planner's clearance check, both
  switched on by ``bodies=``, ``environment=`` or a clearance margin.

Needs the ``motion`` extra (``ruckig``) for planning; the tracker needs only numpy.
"""

from ._check import check_samples
from ._errors import (
    CollisionError,
    MotionError,
    PathFileError,
    SafetyViolationError,
    TimingInfeasibleError,
    TrackingError,
)
from ._io import PathSpec, read_path_csv, read_q_stream_csv, save_trajectory
from ._limits import Limits
from ._options import PlanOptions
from ._plan import Trajectory, plan, plan_directions
from ._plot import plot_actuators, plot_singularity_distance, plot_tip_path, save_plots
from ._safety import MEASURE_NAMES, Margins, SingularityMeasures, singularity_measures
from ._stream import track
from ._tracker import JUMP_M, JUMP_RAD, TrackedPose, Tracker, TrackFlag, TrackLog

__all__ = [
    "CollisionError",
    "JUMP_M",
    "JUMP_RAD",
    "TrackFlag",
    "TrackLog",
    "TrackedPose",
    "Tracker",
    "track",
    "Limits",
    "MEASURE_NAMES",
    "Margins",
    "MotionError",
    "PathFileError",
    "PathSpec",
    "PlanOptions",
    "SafetyViolationError",
    "SingularityMeasures",
    "TimingInfeasibleError",
    "TrackingError",
    "Trajectory",
    "check_samples",
    "plan",
    "plan_directions",
    "plot_actuators",
    "plot_singularity_distance",
    "plot_tip_path",
    "read_path_csv",
    "read_q_stream_csv",
    "save_plots",
    "save_trajectory",
    "singularity_measures",
]
