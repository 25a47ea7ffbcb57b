"""ATHENA live on a ROS 2 graph: a CRTK arm node and a teleop node on the real rclpy.

The extra ``ros2`` installs the ROS 2 client and Fast DDS as wheels (no ROS
installation). Topics, QoS, the executor design and the watchdog: docs/ros2.md.

* :class:`ArmNode` (``athenakin ros2 arm``): an :class:`athenakin.teleop.SimulatedArm`
  under CRTK's names in a namespace (``/athena``): ``measured_js``, ``setpoint_js``,
  ``measured_cp``, ``setpoint_cp``, ``measured_cv``, ``operating_state``; commands
  ``servo_jp``, ``servo_cp``, ``move_jp``, ``move_cp``, ``state_command``, ``hold``,
  each refused command answered on ``status``; ``/joint_states`` of every URDF joint
  and ``/robot_description`` for ``robot_state_publisher``; the ``joint_states`` /
  ``joint_commands`` pair of topic_based_ros2_control.
* :class:`TeleopNode` (``athenakin ros2 teleop``): a master's ``PoseStamped`` and
  ``Joy`` clutch through :class:`athenakin.teleop.Teleop` to the arm's ``servo_jp``,
  with its status, watchdog and e-stop.
* :class:`RecorderNode` (``athenakin ros2 record``): what the nodes publish
  (:func:`session_topics`), as it travelled, into an MCAP file that rosbags, the mcap
  library and Foxglove read.
* :func:`build_crtk_msgs`: CRTK's ``crtk_msgs`` built with the rosidl generator wheels
  (``athenakin ros2 build-msgs``); without it the nodes use ``std_msgs`` stand-ins.
  :func:`crtk_msgs_current` tells whether the installed one is up to date.
"""

from ._arm_node import ARM_TOPICS, STATE_COMMANDS, ArmNode
from ._build import CRTK_MSGS_DIR, build_crtk_msgs, crtk_msgs_current
from ._record import CHUNK_BYTES, LATCHED_TOPICS, RecorderNode, session_topics
from ._runtime import CrtkTypes, RosContext, crtk_types
from ._teleop_node import DVRK_PRESET, MASTER_PRESETS, TELEOP_TOPICS, TeleopNode

__all__ = [
    "ARM_TOPICS",
    "CHUNK_BYTES",
    "CRTK_MSGS_DIR",
    "DVRK_PRESET",
    "LATCHED_TOPICS",
    "MASTER_PRESETS",
    "STATE_COMMANDS",
    "TELEOP_TOPICS",
    "ArmNode",
    "CrtkTypes",
    "RecorderNode",
    "RosContext",
    "TeleopNode",
    "build_crtk_msgs",
    "crtk_msgs_current",
    "crtk_types",
    "session_topics",
]
