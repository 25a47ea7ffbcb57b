"""The 3-DoF parallel module (paper Eq. 7-10): both assembly modes and its inverse kinematics."""

from ._module import (
    MODES,
    MODULE_POSE_TOL,
    TANGENT_TOL,
    ParallelIK,
    ParallelSolution,
    circle_geometry,
    parallel_forward_kinematics,
    parallel_ik_from_position,
    parallel_inverse_kinematics,
)

__all__ = [
    "MODES",
    "MODULE_POSE_TOL",
    "TANGENT_TOL",
    "ParallelIK",
    "ParallelSolution",
    "circle_geometry",
    "parallel_forward_kinematics",
    "parallel_ik_from_position",
    "parallel_inverse_kinematics",
]
