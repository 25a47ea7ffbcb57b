"""The parallel module's closed form, compiled once for the kernels (private module).

:func:`actuator_reason` and :func:`module_closed_form` are the one source's formulas
(:func:`athenakin._mechanism_formulas.actuator_reason_formula` and
:func:`~athenakin._mechanism_formulas.module_closed_form_formula`: the actuator checks,
``circle_geometry`` and the circle intersection of
:func:`athenakin.parallel.parallel_forward_kinematics` for one actuator triple, in the
reference's order of operations, the same values bit for bit) compiled. The FK stage of
the whole robot, the parallel-module FK kernel and the tracker's compiled stream
(:mod:`athenakin.motion._kernels`) call them; numba inlines them (``inline="always"``);
:class:`athenakin.motion.Tracker` evaluates the same source on Python floats.
"""

from __future__ import annotations

import math

from .._backend import njit
from .._mechanism_formulas import actuator_reason_formula, module_closed_form_formula

__all__ = ["actuator_reason", "module_closed_form"]

_INLINE = dict(error_model="numpy", cache=True, nogil=True, inline="always")

#: Reason code (float) of the actuator checks of ``(q1, q2, q3, P)``: non-finite, stroke
#: limit, A/B order, else 0.
actuator_reason = njit(**_INLINE)(actuator_reason_formula)
_closed_form = njit(**_INLINE)(module_closed_form_formula)


@njit(**_INLINE)
def _sqrt(x):
    return math.sqrt(x)            # NaN for x < 0 (error_model="numpy")


@njit(**_INLINE)
def module_closed_form(q1, q2, q3, P, ttol):
    """The parallel module of one actuator triple, both assembly modes.

    Returns ``(reason, tangent, x_M, h, q3, r1, m_y, d, k, half, by, bz, ey, ez)``:
    :func:`athenakin._mechanism_formulas.module_closed_form_formula` of the triple's
    :func:`actuator_reason`.
    """
    return _closed_form(q1, q2, q3, actuator_reason(q1, q2, q3, P), P, ttol, _sqrt)
