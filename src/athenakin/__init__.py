"""athenakin: kinematics of ATHENA, a hybrid parallel robot for pancreas surgery.

The conventions (frames, component orders, units) are those of
``docs/conventions.md``; equation numbers refer to the paper "Kinematics of
ATHENA, a Robot for Pancreas Surgery".

Subpackages, by layer (bottom first; docs/architecture.md, enforced by tests/test_layers.py):

* maths core: :mod:`athenakin.study` (Study parameters, dual quaternions, Eq. 1-4),
  :mod:`athenakin.chain` (the serial UPS chain), :mod:`athenakin.parallel` (the parallel
  module), :mod:`athenakin.testing` (``assert_*`` helpers);
* numpy reference: :mod:`athenakin.robot` (whole-robot FK, IK, set-up),
  :mod:`athenakin.symbolic` (the paper's derivation in sympy, the algebraic FK);
* compiled kernels: :mod:`athenakin.fast` (numba kinematics kernels);
* mechanism: :mod:`athenakin._mechanism` (private: the one table of the bodies, points
  and links, and where they are for given actuator values);
* areas: :mod:`athenakin.analysis` (Jacobians, singularities, workspace),
  :mod:`athenakin.calibration`, :mod:`athenakin.certified` (certified FK),
  :mod:`athenakin.collision` (bodies, clearance), :mod:`athenakin.dynamics` (statics,
  dynamics), :mod:`athenakin.motion` (paths, trajectories, tracking),
  :mod:`athenakin.synthesis` (design studies), :mod:`athenakin.sim` (MuJoCo/URDF),
  :class:`athenakin.Robot` (the model);
* systems: :mod:`athenakin.teleop` (teleoperation),
  :mod:`athenakin.ros` (ROS 2 recordings, MCAP, Foxglove), :mod:`athenakin.ros2` (the CRTK
  arm node and the teleop node on a live ROS 2 graph);
* views: :mod:`athenakin.plot` (figures), :mod:`athenakin.app` (the live app);
* command line: :mod:`athenakin.cli`.

:class:`athenakin.Robot` bundles a design, its RCM frame, bodies and masses; its methods
are one-line calls of the functions above, and the tracker, the planner and the systems
take it as their model. Everything but the maths core and ``robot`` is
imported on first use (``ak.dynamics``, ``ak.Robot``).
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

# registers forward_kinematics(method="algebraic") with robot (which never imports symbolic)
from .symbolic import _solver as _algebraic_solver  # noqa: F401

__version__ = "0.1.0"

#: Subpackages imported on first attribute access (optional heavy dependencies).
_LAZY_SUBPACKAGES = ("analysis", "symbolic", "plot", "sim", "motion", "fast", "certified",
                     "calibration", "app", "collision", "ros", "dynamics", "synthesis",
                     "testing", "teleop", "ros2")
#: Public functions of lazily imported subpackages, reachable as ``ak.<name>``.
_LAZY_FUNCTIONS = {"certified_forward_kinematics": "certified", "Robot": "_robot_model"}


def __getattr__(name: str) -> object:
    """Import optional subpackages lazily: ``ak.analysis`` works without an explicit import."""
    if name in _LAZY_SUBPACKAGES:
        import importlib

        return importlib.import_module(f"athenakin.{name}")
    if name in _LAZY_FUNCTIONS:
        import importlib

        return getattr(importlib.import_module(f"athenakin.{_LAZY_FUNCTIONS[name]}"), name)
    raise AttributeError(f"module 'athenakin' has no attribute {name!r}")


def __dir__() -> list[str]:
    """List the eager names and the lazy ones, so that ``dir(ak)`` and completion show both."""
    return sorted({*globals(), *_LAZY_SUBPACKAGES, *_LAZY_FUNCTIONS})


__all__ = [
    "__version__",
    "chain",
    "parallel",
    "robot",
    "study",
    "Design",
    "Robot",
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
