"""Simulation exports of ATHENA: MJCF (MuJoCo) with the loops closed, URDF of the tree.

The exports need only numpy; :func:`check_fk_with_mujoco` and :func:`load_model`
need the ``mujoco`` package (extra ``sim``).

* :func:`mjcf_from_design` / :func:`write_mjcf`: the whole closed-loop mechanism,
  prismatic actuators on ``q1, q2, q3``, passive joints, loop closures as
  equality constraints, keyframe ``home``.
* :func:`urdf_from_design` / :func:`write_urdf`: the spanning tree, couplings as
  ``<mimic>``, the other loop closures as documented pairs of frames; joint zero
  is the assembled reference configuration, with a ``tool_tip`` link.
* :func:`mechanism_joint_values`: every joint of the tree in one FK slot, in the
  model's convention and relative to the URDF's joint zero (docs/ros.md).
* :func:`actuator_drawn_lengths`: the housing and rod the exports draw for the q3
  actuator, telescoping without a gap over the stroke of q3.
* :func:`check_fk_with_mujoco`: drive MuJoCo to ``q``, let it close the loops,
  compare with :func:`athenakin.forward_kinematics`.
"""

from ._check import (
    PATH_MARGINS,
    RAMP_TIME,
    SETTLE_TIME,
    SPEED_TOL,
    MujocoCheck,
    check_fk_with_mujoco,
    load_model,
    sample_reachable_q,
    settle,
)
from ._layout import (
    ACTUATED,
    ACTUATOR_OVERLAP,
    ACTUATOR_ROD_FALLBACK,
    JOINTS,
    LOOP_CLOSURES,
    LoopClosure,
    MechanismJointValues,
    actuator_drawn_lengths,
    mechanism_joint_values,
    urdf_joint_zero,
)
from ._mjcf import mjcf_from_design, write_mjcf
from ._urdf import CLOSURE_PAIRS, MIMIC, urdf_from_design, write_urdf

__all__ = [
    "ACTUATED",
    "ACTUATOR_OVERLAP",
    "ACTUATOR_ROD_FALLBACK",
    "CLOSURE_PAIRS",
    "JOINTS",
    "LOOP_CLOSURES",
    "MIMIC",
    "PATH_MARGINS",
    "RAMP_TIME",
    "SETTLE_TIME",
    "SPEED_TOL",
    "LoopClosure",
    "MechanismJointValues",
    "MujocoCheck",
    "actuator_drawn_lengths",
    "check_fk_with_mujoco",
    "load_model",
    "mechanism_joint_values",
    "mjcf_from_design",
    "sample_reachable_q",
    "settle",
    "urdf_from_design",
    "urdf_joint_zero",
    "write_mjcf",
    "write_urdf",
]
