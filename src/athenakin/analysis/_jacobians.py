"""Analytic Jacobians of the parallel module, the serial chain and the whole robot.

The public names resolve to the backend dispatch of :mod:`athenakin._dispatch`
(``backend="auto"``: the compiled kernels of :mod:`athenakin.fast` where numba
imports, the numpy reference otherwise). The numpy reference, with the
derivations, is :mod:`athenakin.robot._jacobians` (below the compiled layer,
so that the kernels can use it as their oracle without importing this layer).
"""

from __future__ import annotations

from .._dispatch import (
    instrument_inverse_jacobian,
    instrument_jacobian,
    parallel_inverse_jacobian,
    parallel_jacobian,
    parallel_twist_jacobian,
    tool_tip_inverse_jacobian,
    tool_tip_jacobian,
)
from ..robot._jacobians import (
    Frame,
    _parallel_inverse_jacobian,
    _parallel_jacobian,
    _rcm,
    _state,
    _tip_matrices,
    parallel_state,
    passive_jacobian,
    serial_jacobian,
)

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
    "_parallel_inverse_jacobian",
    "_parallel_jacobian",
    "_rcm",
    "_state",
    "_tip_matrices",
]
