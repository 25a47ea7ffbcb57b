"""Closed forms of the design-study reduction that numpy and the compiled kernel share.

Each function here is the one source of its formula: :func:`._reduce.reduce_samples_numpy`
evaluates it on numpy arrays (all reachable samples at once) and :mod:`._kernels` compiles
the same function with numba (one sample at a time), as :mod:`athenakin._mechanism_formulas`
does for the mechanism. It imports nothing but numpy and uses only arithmetic and the ``np``
functions both support; a choice between two values (``np.where`` on arrays, a branch on
one sample) is left to the caller.
"""

from __future__ import annotations

import numpy as np

__all__ = ["line_conditions_formula"]


def line_conditions_formula(de0, de1, de2, pp, R, rcm, L):  # type: ignore[no-untyped-def]
    """Conditions 6-8, 10 and 11 of :data:`._reduce.CONDITION_ORDER` from the instrument line.

    ``O_s = rcm - (L - depth) d_b``; the line is taken in the frame of ``O_s``,
    ``R_b_s = Rx(theta)`` with ``z_s`` radial from ``M`` (``docs/singularities.md``).

    Parameters
    ----------
    de0, de1, de2 : float or ndarray
        Instrument direction ``d_e`` of the samples, RCM frame.
    pp : float or ndarray
        ``L - depth``: distance from ``O_s`` to the RCM along the line, m.
    R : ndarray, shape (3, 3)
        Rotation of the RCM frame (base frame).
    rcm : ndarray, shape (3,)
        Origin of the RCM frame, base frame, m.
    L : float
        Tool length, m.

    Returns
    -------
    tuple of 6
        ``p_zero`` (m), ``ujoint``, ``wrist``, the line's x component ``ds0`` in the
        frame of ``O_s`` (condition 9, ``ik_cos_u1``, is ``|ds0| / ujoint``, 0 where
        ``ujoint`` is 0: the caller's select), ``ik_sin_u1_sin_u2``, ``tip_at_rcm`` (m);
        each a float or an array like ``de0``.
    """
    rbx = pp * (R[0, 0] * de0 + R[0, 1] * de1 + R[0, 2] * de2)
    rby = pp * (R[1, 0] * de0 + R[1, 1] * de1 + R[1, 2] * de2)
    rbz = pp * (R[2, 0] * de0 + R[2, 1] * de1 + R[2, 2] * de2)
    oy, oz = rcm[1] - rby, rcm[2] - rbz
    rr = np.sqrt(oy * oy + oz * oz)
    ey, ez = oy / rr, oz / rr
    rs0, rs1, rs2 = rbx, ez * rby - ey * rbz, ey * rby + ez * rbz
    p = np.sqrt(rs0 * rs0 + rs1 * rs1 + rs2 * rs2)
    ds0, ds1 = rs0 / p, rs1 / p
    sxy = np.sqrt(ds0 * ds0 + ds1 * ds1)
    return p, sxy, np.sqrt(de0 * de0 + de1 * de1), ds0, np.abs(ds1), np.abs(p - L)
