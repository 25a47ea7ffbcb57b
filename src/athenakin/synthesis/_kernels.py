"""Compiled per-sample reduction of a design's metrics over the task samples (numba).

One pass over the reachable samples: the closed-form singularity values of
``docs/singularities.md`` (the same expressions as
:func:`athenakin.analysis.singularities`), the condition numbers of the
Jacobians from the eigenvalues of ``J^T J`` (closed form for 3 x 3), the
worst-case tip error of an encoder box and the actuator ranges. The kernel only
*selects* the worst samples; :mod:`._metrics` re-evaluates the reported margins
and condition numbers there with :mod:`athenakin.analysis` (exact SVD).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: Singularity conditions in the order of the kernel's ``margin`` output.
CONDITION_ORDER = ("circles_tangent", "d_on_rail", "k1_degenerate", "ab_coincide",
                   "k2_degenerate", "stroke_limit", "p_zero", "ujoint", "wrist", "ik_cos_u1",
                   "ik_sin_u1_sin_u2", "tip_at_rcm")

_OPTS = {"cache": True, "nogil": True, "fastmath": False, "error_model": "numpy"}


@njit(**_OPTS)
def _cond3(J):  # type: ignore[no-untyped-def]
    """2-norm condition number of a 3 x 3 matrix from the eigenvalues of J^T J."""
    a11 = J[0, 0] * J[0, 0] + J[1, 0] * J[1, 0] + J[2, 0] * J[2, 0]
    a22 = J[0, 1] * J[0, 1] + J[1, 1] * J[1, 1] + J[2, 1] * J[2, 1]
    a33 = J[0, 2] * J[0, 2] + J[1, 2] * J[1, 2] + J[2, 2] * J[2, 2]
    a12 = J[0, 0] * J[0, 1] + J[1, 0] * J[1, 1] + J[2, 0] * J[2, 1]
    a13 = J[0, 0] * J[0, 2] + J[1, 0] * J[1, 2] + J[2, 0] * J[2, 2]
    a23 = J[0, 1] * J[0, 2] + J[1, 1] * J[1, 2] + J[2, 1] * J[2, 2]
    if not (math.isfinite(a11) and math.isfinite(a22) and math.isfinite(a33)
            and math.isfinite(a12) and math.isfinite(a13) and math.isfinite(a23)):
        return math.inf
    q = (a11 + a22 + a33) / 3.0
    p1 = a12 * a12 + a13 * a13 + a23 * a23
    b11 = a11 - q
    b22 = a22 - q
    b33 = a33 - q
    p2 = b11 * b11 + b22 * b22 + b33 * b33 + 2.0 * p1
    if p2 <= 0.0:
        return 1.0 if q > 0.0 else math.inf
    p = math.sqrt(p2 / 6.0)
    det_b = (b11 * (b22 * b33 - a23 * a23) - a12 * (a12 * b33 - a23 * a13)
             + a13 * (a12 * a23 - b22 * a13))
    r = det_b / (2.0 * p * p * p)
    r = min(1.0, max(-1.0, r))
    phi = math.acos(r) / 3.0
    e1 = q + 2.0 * p * math.cos(phi)
    e3 = q + 2.0 * p * math.cos(phi + 2.0 * math.pi / 3.0)
    if e3 <= 0.0:
        return math.inf
    return math.sqrt(e1 / e3)


@njit(**_OPTS)
def reduce_samples(q, mode, valid, O_s, rcm, d_e, J_tip, J_par, lengths, L, lo, hi,  # type: ignore[no-untyped-def]
                   resolution):
    """Reduce one design's samples.

    Returns ``counts (3,)`` (reachable, mode +1, mode -1), ``margin (12,)`` and
    ``arg_margin (12,)`` (min of each condition and its sample), ``cond (2,)`` and
    ``arg_cond (2,)`` (max estimated condition of the tip and parallel Jacobians),
    ``q_lo (3,)``, ``q_hi (3,)`` (actuator ranges), ``tip (2,)`` (max and sum of the
    worst-case tip error).
    """
    l1, l2, l3, l4, l5 = lengths[0], lengths[1], lengths[2], lengths[3], lengths[4]
    n = q.shape[0]
    counts = np.zeros(3, np.int64)
    margin = np.full(12, np.inf)
    arg_margin = np.full(12, -1, np.int64)
    cond = np.full(2, -np.inf)
    arg_cond = np.full(2, -1, np.int64)
    q_lo = np.full(3, np.inf)
    q_hi = np.full(3, -np.inf)
    tip = np.zeros(2)
    v = np.empty(12)
    for k in range(n):
        if not valid[k]:
            continue
        counts[0] += 1
        if mode[k] > 0:
            counts[1] += 1
        else:
            counts[2] += 1
        q1, q2, q3 = q[k, 0], q[k, 1], q[k, 2]
        h = 0.5 * (q1 - q2)
        ah = abs(h)
        r1 = math.sqrt(max(l1 * l1 - h * h, 0.0))
        s3 = math.sqrt(max(l3 * l3 - h * h, 0.0))
        dv = math.sqrt((s3 + l2) ** 2 + l5 * l5)
        v[0] = min(abs(q3 - abs(dv - r1)), abs(q3 - (dv + r1)))
        v[1] = l3 - ah
        v[2] = l1 - ah
        v[3] = ah
        v[4] = abs(q3)
        st = math.inf
        for i in range(3):
            st = min(st, q[k, i] - lo[i], hi[i] - q[k, i])
            q_lo[i] = min(q_lo[i], q[k, i])
            q_hi[i] = max(q_hi[i], q[k, i])
        v[5] = st
        # instrument line in the frame of O_s: R_b_s = Rx(theta), z_s radial from M
        oy, oz = O_s[k, 1], O_s[k, 2]
        rr = math.sqrt(oy * oy + oz * oz)
        ey, ez = oy / rr, oz / rr
        rbx, rby, rbz = rcm[0] - O_s[k, 0], rcm[1] - oy, rcm[2] - oz
        rs0, rs1, rs2 = rbx, ez * rby - ey * rbz, ey * rby + ez * rbz
        p = math.sqrt(rs0 * rs0 + rs1 * rs1 + rs2 * rs2)
        ds0, ds1 = rs0 / p, rs1 / p
        sxy = math.sqrt(ds0 * ds0 + ds1 * ds1)
        v[6] = p
        v[7] = sxy
        v[8] = math.sqrt(d_e[k, 0] * d_e[k, 0] + d_e[k, 1] * d_e[k, 1])
        v[9] = abs(ds0) / sxy if sxy > 0.0 else 0.0
        v[10] = abs(ds1)
        v[11] = abs(p - L)
        for c in range(12):
            if v[c] < margin[c]:
                margin[c] = v[c]
                arg_margin[c] = k
        ct = _cond3(J_tip[k])
        if ct > cond[0]:
            cond[0] = ct
            arg_cond[0] = k
        cp = _cond3(J_par[k])
        if cp > cond[1]:
            cond[1] = cp
            arg_cond[1] = k
        # worst case |J dq| over the box |dq_i| <= resolution: a vertex (convexity)
        worst = 0.0
        for s1 in (1.0, -1.0):
            for s2 in (1.0, -1.0):
                e0 = J_tip[k, 0, 0] + s1 * J_tip[k, 0, 1] + s2 * J_tip[k, 0, 2]
                e1 = J_tip[k, 1, 0] + s1 * J_tip[k, 1, 1] + s2 * J_tip[k, 1, 2]
                e2 = J_tip[k, 2, 0] + s1 * J_tip[k, 2, 1] + s2 * J_tip[k, 2, 2]
                worst = max(worst, e0 * e0 + e1 * e1 + e2 * e2)
        err = resolution * math.sqrt(worst)
        tip[0] = max(tip[0], err)
        tip[1] += err
    return counts, margin, arg_margin, cond, arg_cond, q_lo, q_hi, tip
