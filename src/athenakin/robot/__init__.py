"""The whole robot: forward kinematics (16 solutions), inverse kinematics, reference set-up."""

from ..design import Design
from ._fk import (
    FK_FIELDS,
    SLOT_MODE,
    SLOT_MODE_INDEX,
    SLOT_P_SIGN,
    SLOT_UJOINT,
    SLOT_WRIST,
    FKSolution,
    forward_kinematics,
    slot_index,
)
from ._ik import (
    IK_FIELDS,
    IK_Q_ERROR_MAX,
    IK_SINGULAR_TOL,
    InstrumentIK,
    PassiveJoints,
    angles_from_direction,
    direction_from_angles,
    inverse_kinematics,
    q_from_instrument,
    q_from_tool_tip,
)
from ._setup import REFERENCE_DIRECTION_B, REFERENCE_P, REFERENCE_Q, default_rcm_frame

__all__ = [
    "Design",
    "FK_FIELDS",
    "FKSolution",
    "IK_Q_ERROR_MAX",
    "IK_FIELDS",
    "IK_SINGULAR_TOL",
    "InstrumentIK",
    "PassiveJoints",
    "REFERENCE_DIRECTION_B",
    "REFERENCE_P",
    "REFERENCE_Q",
    "SLOT_MODE",
    "SLOT_MODE_INDEX",
    "SLOT_P_SIGN",
    "SLOT_UJOINT",
    "SLOT_WRIST",
    "angles_from_direction",
    "default_rcm_frame",
    "direction_from_angles",
    "forward_kinematics",
    "inverse_kinematics",
    "q_from_instrument",
    "q_from_tool_tip",
    "slot_index",
]
