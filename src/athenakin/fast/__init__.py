"""Compiled (numba) fast paths of athenakin's kinematics, with the reference's results.

Drop-in replacements of the reference functions (same signatures, results,
reason codes, NaN policy and errors), compiled on first use and cached on disk
(``numba`` ``cache=True``):

- :func:`forward_kinematics` (all 16 slots), :func:`inverse_kinematics` (paper
  form), :func:`q_from_instrument`, :func:`q_from_tool_tip` (controller forms);
- :func:`parallel_forward_kinematics`, :func:`parallel_ik_from_position`,
  :func:`parallel_inverse_kinematics` (the parallel module);
- the analytic Jacobians of :mod:`athenakin.analysis`: :func:`parallel_jacobian`,
  :func:`parallel_inverse_jacobian`, :func:`parallel_twist_jacobian`,
  :func:`instrument_jacobian`, :func:`instrument_inverse_jacobian`,
  :func:`tool_tip_jacobian`, :func:`tool_tip_inverse_jacobian`.

The kinematics functions (not the Jacobians) take ``parallel=True`` to use numba's threads.
Concurrent ``parallel=True`` calls from several Python threads are serialised when numba
runs on its ``workqueue`` threading layer, which is not thread-safe (it would abort the
interpreter); on ``tbb`` and ``omp`` they run concurrently (:mod:`athenakin.fast._threads`).
For control loops, :class:`ControlLoop` holds a design and an RCM frame and
answers single poses in a microsecond or two; for sweeps over millions of
poses, :func:`sweep_fk` streams chunks in bounded memory. See
``docs/performance.md`` for the measurements and how they were taken.

Importing this subpackage imports numba (through :mod:`athenakin._backend`: an
:class:`ImportError` where numba is missing or ``ATHENAKIN_BACKEND=numpy``);
``import athenakin`` does not. Where kernels live: docs/architecture.md, "Compiled kernels".
"""

from ._api import (
    design_params,
    forward_kinematics,
    inverse_kinematics,
    q_from_instrument,
    q_from_tool_tip,
)
from ._control import ControlLoop
from ._jac_api import (
    instrument_inverse_jacobian,
    instrument_jacobian,
    parallel_inverse_jacobian,
    parallel_jacobian,
    parallel_twist_jacobian,
    tool_tip_inverse_jacobian,
    tool_tip_jacobian,
)
from ._parallel_api import (
    parallel_forward_kinematics,
    parallel_ik_from_position,
    parallel_inverse_kinematics,
)
from ._sweep import DEFAULT_CHUNK_SIZE, SweepSummary, sweep_fk

__all__ = [
    "ControlLoop",
    "DEFAULT_CHUNK_SIZE",
    "SweepSummary",
    "sweep_fk",
    "design_params",
    "forward_kinematics",
    "inverse_kinematics",
    "q_from_instrument",
    "q_from_tool_tip",
    "parallel_forward_kinematics",
    "parallel_ik_from_position",
    "parallel_inverse_kinematics",
    "parallel_jacobian",
    "parallel_inverse_jacobian",
    "parallel_twist_jacobian",
    "instrument_jacobian",
    "instrument_inverse_jacobian",
    "tool_tip_jacobian",
    "tool_tip_inverse_jacobian",
]
