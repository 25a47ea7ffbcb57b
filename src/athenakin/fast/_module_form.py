"""The parallel module's closed form, written once for the compiled kernels (private module).

:func:`actuator_reason` is :func:`athenakin.parallel._module._actuator_checks` and
:func:`module_closed_form` the actuator checks, ``circle_geometry`` and the
circle intersection of :func:`athenakin.parallel.parallel_forward_kinematics`
for one actuator triple, in the reference's order of operations (the same
values bit for bit). The FK stage of the whole robot and the parallel-module FK
kernel call them; numba inlines them (``inline="always"``).
"""

from __future__ import annotations

import math

from .._backend import njit
from ..errors import Reason
from ._scalar import finite_sum

__all__ = ["actuator_reason", "module_closed_form"]

# Reason codes (athenakin.errors.Reason) as floats.
_NONFINITE, _STROKE, _AB_ORDER = (float(Reason.NONFINITE_INPUT), float(Reason.STROKE_LIMIT),
                                  float(Reason.AB_ORDER))
_LINK, _DISJOINT = float(Reason.LINK_TOO_SHORT), float(Reason.CIRCLES_DISJOINT)

_INLINE = dict(error_model="numpy", cache=True, nogil=True, inline="always")


@njit(**_INLINE)
def actuator_reason(q1, q2, q3, P):
    """Reason code (float) of the actuator checks: non-finite, stroke limit, A/B order, else 0."""
    lo0, lo1, lo2, hi0, hi1, hi2, hs = P[5], P[6], P[7], P[8], P[9], P[10], P[11]
    fin_q = (finite_sum(q1) + finite_sum(q2) + finite_sum(q3)) == 0.0
    stroke = (q1 < lo0) | (q1 > hi0) | (q2 < lo1) | (q2 > hi1) | (q3 < lo2) | (q3 > hi2)
    order = hs * (q1 - q2) < 0.0
    return _NONFINITE if not fin_q else _STROKE if stroke else _AB_ORDER if order else 0.0


@njit(**_INLINE)
def module_closed_form(q1, q2, q3, P, ttol):
    """The parallel module of one actuator triple, both assembly modes.

    Returns ``(reason, tangent, x_M, q3, r1, m_y, d, k, half, by, bz, ey, ez)``:
    the reason code (float, 0 valid; a non-finite ``q`` is computed as 0), the
    tangency flag, the slider midpoint, the (sanitised) ``q3``, the circle
    geometry and the intersection ``(y, z) = (by, bz) +- half * (ey, ez)``.
    """
    l1, l2, l3, l5 = P[0], P[1], P[2], P[4]
    pr = actuator_reason(q1, q2, q3, P)
    fin_q = pr != _NONFINITE
    q1 = q1 if fin_q else 0.0
    q2 = q2 if fin_q else 0.0
    q3 = q3 if fin_q else 0.0
    # parallel._module.circle_geometry
    h = 0.5 * (q1 - q2)
    r1 = math.sqrt(l1 * l1 - h * h)
    m_y = math.sqrt(l3 * l3 - h * h) + l2
    d2 = m_y * m_y + l5 * l5
    d = math.sqrt(d2)
    H = (d2 + r1 * r1) - q3 * q3
    k = (((r1 + q3) - d) * ((r1 + q3) + d)) * ((d - r1) + q3) * ((d + r1) - q3)
    half = math.sqrt(k if not (k < 0.0) else 0.0) / (2.0 * d)
    ah = abs(h)
    link = (ah >= l1) | (ah > l3)
    pr = _LINK if (pr == 0.0) & link else pr
    disjoint = (not link) & (k < 0.0) & (math.sqrt(abs(k)) / (2.0 * d) > ttol)
    pr = _DISJOINT if (pr == 0.0) & disjoint else pr
    tangent = (pr == 0.0) & (half <= ttol)
    dd = (2.0 * d) * d
    return (pr, tangent, 0.5 * (q1 + q2), q3, r1, m_y, d, k, half, (H * m_y) / dd,
            (H * l5) / dd, (-l5) / d, m_y / d)
