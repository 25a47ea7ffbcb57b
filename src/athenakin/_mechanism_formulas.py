"""Closed forms of the mechanism that the numpy code and the compiled kernels share.

Each function here is the one source of its formula: :mod:`athenakin._mechanism`
evaluates it on numpy arrays and :mod:`athenakin.fast` compiles the same function with
numba. It imports nothing but numpy (so the kernels import it without pulling in the
layers above them) and uses only arithmetic and the ``np`` functions both support; where
a formula chooses between two values, it takes the select as an argument (``np.where``
on arrays, a compiled ``a if c else b`` in the kernels: numba's ``np.where`` makes arrays
of scalars).
"""

from __future__ import annotations

import numpy as np

__all__ = ["FORMULA_JOINTS", "tree_joint_formula", "parallel_state_formula"]

#: The joints :func:`tree_joint_formula` returns, in its order (that of
#: :data:`athenakin._mechanism.JOINTS`, checked there).
FORMULA_JOINTS = ("q1", "a_ujoint_x", "a_ujoint_y", "platform_y", "u1", "u2", "p", "u3", "u4",
                  "u5", "a_base_z", "carrier_z", "k2_x", "q3", "q2", "b_ujoint_x",
                  "b_ujoint_y", "b_base_z")


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
