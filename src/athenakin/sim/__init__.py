"""Simulation exports of ATHENA: MJCF (MuJoCo) with the loops closed, URDF of the tree.

The exports need only numpy; :func:`check_fk_with_mujoco` and :func:`load_model`
need the ``mujoco`` package (extra ``sim``).

* :func:`mjcf_from_design` / :func:`write_mjcf`: the whole closed-loop mechanism,
  prismatic actuators on ``q1, q2, q3``, passive joints, loop closures as
  equality constraints, keyframe ``home``.
* :func:`urdf_from_design` / :func:`write_urdf`: the spanning tree, couplings as
  ``<mimic>``, the other loop closures as documented pairs of frames.
* :func:`mechanism_joint_values`: every joint of the tree in one FK slot.
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
from ._layout import ACTUATED, JOINTS, LOOP_CLOSURES, LoopClosure, mechanism_joint_values
from ._mjcf import mjcf_from_design, write_mjcf
from ._urdf import CLOSURE_PAIRS, MIMIC, urdf_from_design, write_urdf

__all__ = [
    "ACTUATED",
    "CLOSURE_PAIRS",
    "JOINTS",
    "LOOP_CLOSURES",
    "MIMIC",
    "PATH_MARGINS",
    "RAMP_TIME",
    "SETTLE_TIME",
    "SPEED_TOL",
    "LoopClosure",
    "MujocoCheck",
    "check_fk_with_mujoco",
    "load_model",
    "mechanism_joint_values",
    "mjcf_from_design",
    "sample_reachable_q",
    "settle",
    "urdf_from_design",
    "write_mjcf",
    "write_urdf",
]
