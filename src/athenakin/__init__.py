"""athenakin: kinematics of ATHENA, a hybrid parallel robot for pancreas surgery.

The conventions (frames, component orders, units) are those of
``docs/conventions.md``; equation numbers refer to the paper "Kinematics of
ATHENA, a Robot for Pancreas Surgery".

Subpackages: :mod:`athenakin.study` (Study parameters, dual quaternions),
:mod:`athenakin.parallel` (the parallel module), :mod:`athenakin.chain` (the
serial UPS chain), :mod:`athenakin.robot` (whole robot), :mod:`athenakin.testing`.
"""

from . import _interrupt, chain, parallel, robot, study  # noqa: F401 (_interrupt: CLI hook)
from ._dispatch import (
    forward_kinematics,
    inverse_kinematics,
    q_from_instrument,
    q_from_tool_tip,
)
from .design import Design
from .errors import (
    DegenerateChainError,
    InvalidInputError,
    KinematicsError,
    NotOnStudyQuadricError,
    OutOfWorkspaceError,
    Reason,
    SingularConfigurationError,
    StrokeLimitError,
)
from .robot import (
    FKSolution,
    InstrumentIK,
    PassiveJoints,
    angles_from_direction,
    default_rcm_frame,
    direction_from_angles,
)

__version__ = "0.1.0"

#: Subpackages imported on first attribute access (optional heavy dependencies).
_LAZY_SUBPACKAGES = ("analysis", "symbolic", "plot", "sim", "motion", "fast", "certified",
                     "calibration", "app", "collision", "ros", "dynamics", "synthesis",
                     "testing", "teleop")
#: Public functions of lazily imported subpackages, reachable as ``ak.<name>``.
_LAZY_FUNCTIONS = {"certified_forward_kinematics": "certified"}


def __getattr__(name: str) -> object:
    """Import optional subpackages lazily: ``ak.analysis`` works without an explicit import."""
    if name in _LAZY_SUBPACKAGES:
        import importlib

        return importlib.import_module(f"athenakin.{name}")
    if name in _LAZY_FUNCTIONS:
        import importlib

        return getattr(importlib.import_module(f"athenakin.{_LAZY_FUNCTIONS[name]}"), name)
    raise AttributeError(f"module 'athenakin' has no attribute {name!r}")

__all__ = [
    "__version__",
    "chain",
    "parallel",
    "robot",
    "study",
    "Design",
    "DegenerateChainError",
    "FKSolution",
    "InstrumentIK",
    "InvalidInputError",
    "KinematicsError",
    "NotOnStudyQuadricError",
    "OutOfWorkspaceError",
    "PassiveJoints",
    "Reason",
    "SingularConfigurationError",
    "StrokeLimitError",
    "angles_from_direction",
    "default_rcm_frame",
    "direction_from_angles",
    "forward_kinematics",
    "inverse_kinematics",
    "q_from_instrument",
    "q_from_tool_tip",
]
