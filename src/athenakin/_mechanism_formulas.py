"""Closed forms of the mechanism that the numpy code and the compiled kernels share.

Each function here is the one source of its formula: :mod:`athenakin._mechanism`
evaluates it on numpy arrays and :mod:`athenakin.fast` compiles the same function with
numba. It imports nothing but numpy and the reason codes of :mod:`athenakin.errors` (so
the kernels import it without pulling in the layers above them) and uses only arithmetic
and the ``np`` functions both support; where a formula chooses between two values, it
takes the select as an argument (``np.where`` on arrays, a compiled ``a if c else b`` in
the kernels: numba's ``np.where`` makes arrays of scalars), and where it takes a square
root that may be of a negative number, the square root (NaN there: numba's ``math.sqrt``
under ``error_model="numpy"``; ``math.sqrt`` itself raises).

The parallel module's closed form of one actuator triple (:func:`actuator_reason_formula`,
:func:`module_closed_form_formula`, over the parameter vector of :func:`module_params`)
is compiled by :mod:`athenakin.fast._module_form` for the FK kernels and the tracker's
compiled stream, and evaluated on Python floats by :class:`athenakin.motion.Tracker`.
"""

from __future__ import annotations

import numpy as np

from .errors import Reason

__all__ = ["FORMULA_JOINTS", "FORMULA_POINTS", "tree_joint_formula", "parallel_state_formula",
           "module_params", "actuator_reason_formula", "module_closed_form_formula",
           "mechanism_points_formula"]

# Reason codes (athenakin.errors.Reason) as floats.
_NONFINITE, _STROKE, _AB_ORDER = (float(Reason.NONFINITE_INPUT), float(Reason.STROKE_LIMIT),
                                  float(Reason.AB_ORDER))
_LINK, _DISJOINT = float(Reason.LINK_TOO_SHORT), float(Reason.CIRCLES_DISJOINT)

#: The joints :func:`tree_joint_formula` returns, in its order (that of
#: :data:`athenakin._mechanism.JOINTS`, checked there).
FORMULA_JOINTS = ("q1", "a_ujoint_x", "a_ujoint_y", "platform_y", "u1", "u2", "p", "u3", "u4",
                  "u5", "a_base_z", "carrier_z", "k2_x", "q3", "q2", "b_ujoint_x",
                  "b_ujoint_y", "b_base_z")

#: The points :func:`mechanism_points_formula` returns, in its order (that of
#: :data:`athenakin._mechanism.POINT_NAMES`, checked there).
FORMULA_POINTS = ("A", "B", "M", "D", "C_foot", "C", "O_i", "O_s", "RCM", "tip", "rail_lo",
                  "rail_hi", "A_lo", "A_hi", "B_lo", "B_hi", "S_3", "S_4", "S_5")


def tree_joint_formula(q1, q2, q3, p, u1, u2, u3, u4, u5, oy, oz,  # type: ignore[no-untyped-def]
                       l1sq, l2, l3sq, l4, l5):
    """Every joint of the exports' tree (model convention) from the forward kinematics.

    The one formula of the tree's joint values (:data:`athenakin._mechanism.TREE`): numpy
    evaluates it on arrays (:func:`athenakin._mechanism.mechanism_state`,
    :func:`athenakin.ros._frames.joint_values`) and numba compiles it for the ``/tf``
    writer (:mod:`athenakin.fast._frame_kernels`).

    Parameters
    ----------
    q1, q2, q3, p, u1, u2, u3, u4, u5 : float or ndarray
        Actuators (m), ``p`` (m) and ``u1..u5`` (rad) of the configuration.
    oy, oz : float or ndarray
        ``y`` and ``z`` of ``O_s`` in the base frame, m.
    l1sq, l2, l3sq, l4, l5 : float
        ``l1**2``, ``l2``, ``l3**2``, ``l4``, ``l5`` of the design.

    Returns
    -------
    tuple of 18
        The values in the order of :data:`FORMULA_JOINTS` (m for slides, rad for hinges):
        ``R_b_i = Rx(theta)`` with ``z_i`` from M to ``O_i`` (``theta`` from ``O_s``),
        the bars ``l1`` tilted by ``phi = atan2(-h, r1)``, the bars ``l3`` at
        ``atan2(sqrt(l3^2 - h^2), -+h)``, the q3 actuator at ``gamma`` about ``x_b``.
    """
    h = 0.5 * (q1 - q2)
    r1 = np.sqrt(l1sq - h * h)
    s3 = np.sqrt(l3sq - h * h)
    theta = np.arctan2(-oy, oz)
    rad = np.hypot(oy, oz)
    oi_y = oy - l4 * oy / rad
    oi_z = oz - l4 * oz / rad
    gamma = np.arctan2(-(oi_y - (s3 + l2)), oi_z - l5)
    phi_a = np.arctan2(-h, r1)
    ang_a3 = np.arctan2(s3, -h)
    return (q1, theta, phi_a, -phi_a, u1, u2, p, u3, u4, u5, ang_a3, -ang_a3, gamma, q3, q2,
            theta, -phi_a, np.arctan2(s3, h))


def parallel_state_formula(q1, q2, q3, mode, l1, l2, l3, l5,  # type: ignore[no-untyped-def]
                           tangent_tol, where):
    """The parallel module's geometry for its Jacobians (paper Eq. 7-8), without checks.

    The one formula of :func:`athenakin.robot._jacobians.parallel_state` (numpy arrays,
    ``where=np.where``) and of the compiled Jacobians (:mod:`athenakin.fast._jac_kernels`,
    one item at a time, ``where`` a compiled select). Stroke limits and the A/B order are
    not applied: the Jacobian is local geometry.

    Parameters
    ----------
    q1, q2, q3 : float or ndarray
        Actuators, m.
    mode : float or ndarray
        Assembly mode, +1 or -1.
    l1, l2, l3, l5 : float
        Lengths of the design, m.
    tangent_tol : float
        Half-chord (m) within which circles that rounding set apart still touch.
    where : callable ``where(condition, a, b)``
        The select: ``np.where`` for arrays.

    Returns
    -------
    tuple of 10
        ``h, r1, s3, m_y, d, a, y, z, ey, ez``: ``h = (q1 - q2) / 2``, ``r1``, ``s3 =
        sqrt(l3^2 - h^2)``, ``m_y``, ``d = |C - M|``, the half-chord ``a`` (NaN where the
        circles are apart by more than ``tangent_tol``, 0 within it), ``O_i - M = (y, z)``
        and ``z_i = (ey, ez)``; NaN where the module cannot be assembled.
    """
    h = 0.5 * (q1 - q2)
    r1 = np.sqrt(l1 * l1 - h * h)
    r1 = where(r1 > 0, r1, np.nan)
    s3 = np.sqrt(l3 * l3 - h * h)
    m_y = s3 + l2
    d2 = m_y * m_y + l5 * l5
    d = np.sqrt(d2)
    H = d2 + r1 * r1 - q3 * q3
    k = (r1 + q3 - d) * (r1 + q3 + d) * (d - r1 + q3) * (d + r1 - q3)
    a = np.sqrt(np.abs(k)) / (2 * d)
    # rounding makes k slightly negative at tangency: within tangent_tol it is tangent
    a = where(k >= 0, a, where(a <= tangent_tol, 0.0, np.nan))
    by, bz = H * m_y / (2 * d2), H * l5 / (2 * d2)
    y = by - mode * a * l5 / d
    z = bz + mode * a * m_y / d
    return h, r1, s3, m_y, d, a, y, z, y / r1, z / r1


def module_params(design, stroke_min=None, stroke_max=None):  # type: ignore[no-untyped-def]
    """The parameter vector ``P`` (13 floats) of the module's closed form and the FK kernels.

    ``(l1, l2, l3, l4, l5, stroke_min (3), stroke_max (3), h_sign, tool_length)`` of a
    :class:`athenakin.Design`, its strokes replaced by ``stroke_min`` / ``stroke_max``
    (m, 3 each) where given.

    Returns
    -------
    tuple of 13 float
    """
    lo = design.stroke_min if stroke_min is None else stroke_min
    hi = design.stroke_max if stroke_max is None else stroke_max
    return (float(design.l1), float(design.l2), float(design.l3), float(design.l4),
            float(design.l5), float(lo[0]), float(lo[1]), float(lo[2]), float(hi[0]),
            float(hi[1]), float(hi[2]), float(design.h_sign), float(design.tool_length))


def actuator_reason_formula(q1, q2, q3, P):  # type: ignore[no-untyped-def]
    """Reason code (float) of the actuator checks: non-finite, stroke limit, A/B order, else 0.

    :func:`athenakin.parallel._module._actuator_checks` for one triple (m), over the
    parameter vector ``P`` of :func:`module_params`.
    """
    lo0, lo1, lo2, hi0, hi1, hi2, hs = P[5], P[6], P[7], P[8], P[9], P[10], P[11]
    fin_q = ((q1 - q1) + (q2 - q2) + (q3 - q3)) == 0.0     # x - x: 0 finite, NaN else
    stroke = (q1 < lo0) | (q1 > hi0) | (q2 < lo1) | (q2 > hi1) | (q3 < lo2) | (q3 > hi2)
    order = hs * (q1 - q2) < 0.0
    return _NONFINITE if not fin_q else _STROKE if stroke else _AB_ORDER if order else 0.0


def module_closed_form_formula(q1, q2, q3, pr, P, ttol, sqrt):  # type: ignore[no-untyped-def]
    """The parallel module of one actuator triple, both assembly modes (paper Eq. 7-8).

    The actuator checks' code ``pr`` (:func:`actuator_reason_formula`), ``circle_geometry``
    and the circle intersection of :func:`athenakin.parallel.parallel_forward_kinematics`,
    in the reference's order of operations (the same values bit for bit).

    Parameters
    ----------
    q1, q2, q3 : float
        Actuators, m.
    pr : float
        :func:`actuator_reason_formula` of ``q1, q2, q3``.
    P : sequence of 13 float
        :func:`module_params`.
    ttol : float
        Half-chord (m) within which circles that rounding set apart still touch.
    sqrt : callable
        The square root, NaN for a negative number.

    Returns
    -------
    tuple
        ``(reason, tangent, x_M, h, q3, r1, m_y, d, k, half, by, bz, ey, ez)``: the reason
        code (float, 0 valid; a non-finite ``q`` is computed as 0), the tangency flag, the
        slider midpoint, ``h = (q1 - q2) / 2``, the (sanitised) ``q3``, the circle geometry
        and the intersection ``O_i - M = (y, z) = (by, bz) +- a (ey, ez)`` with the
        half-chord ``a = half`` (``a = 0`` where ``tangent``: the two modes merged).
    """
    l1, l2, l3, l5 = P[0], P[1], P[2], P[4]
    fin_q = pr != _NONFINITE
    q1 = q1 if fin_q else 0.0
    q2 = q2 if fin_q else 0.0
    q3 = q3 if fin_q else 0.0
    # parallel._module.circle_geometry
    h = 0.5 * (q1 - q2)
    r1 = sqrt(l1 * l1 - h * h)
    m_y = sqrt(l3 * l3 - h * h) + l2
    d2 = m_y * m_y + l5 * l5
    d = sqrt(d2)
    H = (d2 + r1 * r1) - q3 * q3
    k = (((r1 + q3) - d) * ((r1 + q3) + d)) * ((d - r1) + q3) * ((d + r1) - q3)
    half = sqrt(k if not (k < 0.0) else 0.0) / (2.0 * d)
    ah = abs(h)
    link = (ah >= l1) | (ah > l3)
    pr = _LINK if (pr == 0.0) & link else pr
    disjoint = (not link) & (k < 0.0) & (sqrt(abs(k)) / (2.0 * d) > ttol)
    pr = _DISJOINT if (pr == 0.0) & disjoint else pr
    tangent = (pr == 0.0) & (half <= ttol)
    dd = (2.0 * d) * d
    return (pr, tangent, 0.5 * (q1 + q2), h, q3, r1, m_y, d, k, half, (H * m_y) / dd,
            (H * l5) / dd, (-l5) / d, m_y / d)


def mechanism_points_formula(q1, q2, p, ca, sa, cb, sb, c3, s3,  # type: ignore[no-untyped-def]
                             ox, oy, oz, cy, cz, rc0, rc1, rc2, ze0, ze1, ze2, G, sqrt,
                             minimum, maximum, where):
    """Every named point of the mechanism (base frame, m) from one FK slot's configuration.

    The one formula of the points (:data:`athenakin._mechanism.POINT_NAMES`): numpy
    evaluates it on arrays (:func:`athenakin._mechanism.mechanism_points`), the tracker's
    clearance on Python floats (:class:`athenakin.motion._clearance.PoseClearance`) and
    the teleoperation guard compiled (:mod:`athenakin.teleop._kernels`).

    Parameters
    ----------
    q1, q2, p : float or ndarray
        The carriages (m) and the insertion ``p`` (m) of the slot.
    ca, sa, cb, sb, c3, s3 : float or ndarray
        Cosines and sines of ``u1, u2, u3``.
    ox, oy, oz, cy, cz : float or ndarray
        ``O_s`` (m) and ``R_b_s = [[1, 0, 0], [0, cz, cy], [0, -cy, cz]]`` (the FK's
        ``T_b_s``).
    rc0, rc1, rc2, ze0, ze1, ze2 : float or ndarray
        The RCM and the z axis of the RCM frame E (base frame).
    G : sequence of 10 float
        ``l2, l3, l4, l5, tool length, rail margin, half the carriage length, sphere
        radius, rail's low end, rail's high end`` (m).
    sqrt, minimum, maximum, where : callable
        The square root, the element-wise min and max of two, the select.

    Returns
    -------
    tuple of 19 (x, y, z)
        In the order of :data:`FORMULA_POINTS` (components may be plain numbers).
    """
    l2, l3, l4, l5, L, rm, half, rs, lo, hi = (G[0], G[1], G[2], G[3], G[4], G[5], G[6],
                                               G[7], G[8], G[9])
    h = 0.5 * (q1 - q2)
    x_M = 0.5 * (q1 + q2)
    y_D = sqrt(l3 * l3 - h * h)
    # R_3 = R_b_s R(u1, u2) (chain._ups.rotation_u_pair): its third column is the instrument
    # axis d (O_s -> RCM if p > 0), R_3 (sin u3, -cos u3, 0) the axis a4 of u4
    x, y, z = ca * sb, sa * sb, -cb
    d0, d1, d2 = x, cz * y + cy * z, cz * z - cy * y
    x, y, z = ca * cb * s3 - sa * c3, sa * cb * s3 + ca * c3, sb * s3
    a0, a1, a2 = x, cz * y + cy * z, cz * z - cy * y
    # S_3: the instrument guide, rs from the RCM towards O_s (O_s + t d, t = p -+ rs); where
    # that is off the instrument (|p| < rs), the guide holds it at its nearest point
    side = where(p < 0.0, -1.0, 1.0)                    # O_s is on the side -p d of the RCM
    t = p - side * rs
    on = (t >= 0.0) & (t <= L)
    tc = minimum(maximum(t, 0.0), L)
    ms = -side
    s_3 = (where(on, rc0 + rs * (ms * d0), ox + tc * d0),
           where(on, rc1 + rs * (ms * d1), oy + tc * d1),
           where(on, rc2 + rs * (ms * d2), oz + tc * d2))
    # S_4 on the u4 axis as the chain orients it, S_5 on +z_e: u4 is perpendicular to the
    # instrument, and at the home pose so is u5, so a side of O_s would flip them with the
    # rounding of a zero dot product
    return ((q1, 0.0, 0.0), (q2, 0.0, 0.0), (x_M, 0.0, 0.0), (x_M, y_D, 0.0),
            (x_M, y_D + l2, 0.0), (x_M, y_D + l2, l5), (ox, oy - l4 * cy, oz - l4 * cz),
            (ox, oy, oz), (rc0, rc1, rc2), (ox + L * d0, oy + L * d1, oz + L * d2),
            (minimum(minimum(q1, q2) - rm, lo), 0.0, 0.0),
            (maximum(maximum(q1, q2) + rm, hi), 0.0, 0.0), (q1 - half, 0.0, 0.0),
            (q1 + half, 0.0, 0.0), (q2 - half, 0.0, 0.0), (q2 + half, 0.0, 0.0), s_3,
            (rc0 + rs * a0, rc1 + rs * a1, rc2 + rs * a2),
            (rc0 + rs * ze0, rc1 + rs * ze1, rc2 + rs * ze2))
