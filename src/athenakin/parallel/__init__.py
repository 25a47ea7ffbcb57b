"""The 3-DoF parallel module (paper Eq. 7-10): both assembly modes and its inverse kinematics."""

from ._module import (
    IK_ROUNDING_ULPS,
    MODES,
    MODULE_POSE_TOL,
    TANGENT_TOL,
    ParallelIK,
    ParallelSolution,
    circle_geometry,
    parallel_forward_kinematics,
    parallel_ik_from_position,
    parallel_inverse_kinematics,
    position_ik_error,
)

__all__ = [
    "IK_ROUNDING_ULPS",
    "MODES",
    "MODULE_POSE_TOL",
    "TANGENT_TOL",
    "ParallelIK",
    "ParallelSolution",
    "circle_geometry",
    "parallel_forward_kinematics",
    "parallel_ik_from_position",
    "parallel_inverse_kinematics",
    "position_ik_error",
]
