"""Statics, force capability and dynamics of ATHENA's closed chain.

* :mod:`._model` - :class:`MassModel`: mass, centre of mass and inertia of every body
  (the names of :data:`athenakin._mechanism.BODIES` plus ``slider_d``,
  ``actuator_rod``, ``guide``), from slender rods, solid capsules or a ``[masses]``
  TOML table.
* :mod:`._api` - :func:`actuator_forces` / :func:`statics` (gravity and a tip force,
  the load on the RCM mount), :func:`inverse_dynamics`, :func:`mass_matrix`,
  :func:`forward_dynamics`, :func:`mechanical_energy`: exact to rounding by virtual
  power on the closed chain with second-order Taylor jets of the closed-form kinematics.
* :mod:`._capability` - :func:`force_capability` (the polytope of tip forces resisted
  within actuator force limits, its weakest direction), :func:`max_tip_force`.
* :mod:`._simulate` - :func:`simulate` (fixed-step RK4; stops with
  :class:`SimulationStoppedError` at a stroke limit or next to a singular set).

Conventions: docs/conventions.md ("Forces"); findings: docs/dynamics.md.
"""

from ._api import (
    CHUNK,
    MAX_BATCH,
    STANDARD_GRAVITY,
    MechanicalEnergy,
    Statics,
    actuator_forces,
    forward_dynamics,
    inverse_dynamics,
    mass_matrix,
    mechanical_energy,
    statics,
)
from ._capability import (
    COND_MARGIN,
    ForceCapability,
    force_capability,
    max_tip_force,
    tip_condition_number,
)
from ._loop import InverseDynamicsLoop
from ._metrics import (
    STUDY_F_MAX,
    STUDY_TIP_ACCELERATION,
    STUDY_TIP_SPEED,
    ForceMetrics,
    force_metrics,
)
from ._model import (
    INERTIA_TOL,
    MASS_BODIES,
    MAX_MASS,
    MOVING_BODIES,
    REFERENCE_MASSES,
    MassModel,
    actuator_part_length,
    body_segment_in_frame,
)
from ._simulate import SINGULARITY_MARGINS, Simulation, SimulationStoppedError, simulate

__all__ = [
    "InverseDynamicsLoop",
    "MassModel", "MASS_BODIES", "MOVING_BODIES", "REFERENCE_MASSES", "INERTIA_TOL",
    "MAX_MASS", "actuator_part_length", "body_segment_in_frame",
    "Statics", "statics", "actuator_forces", "inverse_dynamics", "mass_matrix",
    "forward_dynamics", "mechanical_energy", "MechanicalEnergy", "STANDARD_GRAVITY",
    "MAX_BATCH", "CHUNK",
    "ForceCapability", "force_capability", "max_tip_force", "tip_condition_number",
    "COND_MARGIN",
    "ForceMetrics", "force_metrics", "STUDY_TIP_SPEED", "STUDY_TIP_ACCELERATION", "STUDY_F_MAX",
    "Simulation", "simulate", "SimulationStoppedError", "SINGULARITY_MARGINS",
]
