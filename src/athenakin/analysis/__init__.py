"""Jacobians, the complete singularity set, workspace and assembly-mode maps of ATHENA.

* the analytic Jacobians: the parallel module ``d O_s / d q`` and its inverse, the serial
  UPS chain, the passive joints, and the whole robot in controller variables (instrument
  direction angles + insertion, tool-tip velocity). Those of the parallel module and the
  whole robot are the backend dispatch of :mod:`athenakin._dispatch` (``backend="auto"``:
  the compiled kernels of :mod:`athenakin.fast` where numba imports, the numpy reference
  otherwise); the numpy reference, with the derivations, is
  :mod:`athenakin.robot._jacobians` (below the compiled layer, so that the kernels can use
  it as their oracle).
* :mod:`._singularities` - every singularity condition with its closed-form test and
  distance measure (:func:`singularities`), the loci in actuator space.
* :mod:`._workspace` - grids: actuator plane, ``O_s`` workspace with assembly-mode
  regions, instrument cone about the RCM, tool-tip workspace; ``.npz`` storage.
* :mod:`.figures` - matplotlib figures (imported on demand: ``athenakin.analysis.figures``).

Derivations and the findings for the default design: ``docs/singularities.md``.
"""

from .._dispatch import (
    instrument_inverse_jacobian,
    instrument_jacobian,
    parallel_inverse_jacobian,
    parallel_jacobian,
    parallel_twist_jacobian,
    tool_tip_inverse_jacobian,
    tool_tip_jacobian,
)
from ..robot._jacobians import Frame, parallel_state, passive_jacobian, serial_jacobian
from ._cone import InstrumentCone, instrument_cone
from ._loci import (
    MEASURE_OF,
    near_singular_configurations,
    singular_sets_within_strokes,
    singularity_loci,
)
from ._singularities import (
    CONDITIONS,
    DEFAULT_TOL,
    Condition,
    SingularityReport,
    condition_number,
    sigma_min,
    singularities,
)
from ._workspace import (
    ActuatorMap,
    PointWorkspace,
    ToolTipWorkspace,
    actuator_map,
    load_npz,
    point_workspace,
    save_npz,
    tool_tip_workspace,
    workspace_summary,
)
from ._workspace_grid import CHUNK

__all__ = [
    "Frame",
    "parallel_jacobian",
    "parallel_inverse_jacobian",
    "parallel_twist_jacobian",
    "parallel_state",
    "serial_jacobian",
    "passive_jacobian",
    "instrument_jacobian",
    "instrument_inverse_jacobian",
    "tool_tip_jacobian",
    "tool_tip_inverse_jacobian",
    "CONDITIONS",
    "DEFAULT_TOL",
    "Condition",
    "SingularityReport",
    "singularities",
    "singularity_loci",
    "sigma_min",
    "condition_number",
    "singular_sets_within_strokes",
    "near_singular_configurations",
    "MEASURE_OF",
    "ActuatorMap",
    "PointWorkspace",
    "InstrumentCone",
    "ToolTipWorkspace",
    "actuator_map",
    "point_workspace",
    "instrument_cone",
    "tool_tip_workspace",
    "save_npz",
    "load_npz",
    "CHUNK",
    "workspace_summary",
]
