"""Compiled per-sample reduction of a design's metrics over the task samples (numba).

The kernel of :func:`athenakin.synthesis._reduce.reduce_samples`: the same formulas as
its numpy reference :func:`~athenakin.synthesis._reduce.reduce_samples_numpy`, sample by
sample in one pass (to 1e-12, tested), with the same outputs in the same order
(:data:`~athenakin.synthesis._reduce.CONDITION_ORDER`).
"""

from __future__ import annotations

import math

import numpy as np

from .._backend import njit
from ._formulas import line_conditions_formula

#: The one formula of the line's conditions (numpy evaluates the same source).
_line_conditions = njit(cache=True, nogil=True, error_model="numpy",
                        inline="always")(line_conditions_formula)


@njit(cache=True, nogil=True, error_model="numpy")
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


@njit(cache=True, nogil=True, error_model="numpy")
def _kappa_f2(J):  # type: ignore[no-untyped-def]
    """Squared Frobenius condition number ``|J|_F^2 |adj J|_F^2 / det(J)^2`` of a 3 x 3 matrix.

    ``kappa_2 <= kappa_F <= 3 kappa_2`` (3 x 3), so the sample of the largest
    ``kappa_2`` is among those with ``kappa_F >= max(kappa_F) / 3``.
    """
    a, b, c = J[0, 0], J[0, 1], J[0, 2]
    d, e, f = J[1, 0], J[1, 1], J[1, 2]
    g, h, i = J[2, 0], J[2, 1], J[2, 2]
    m0 = e * i - f * h
    m1 = d * i - f * g
    m2 = d * h - e * g
    m3 = b * i - c * h
    m4 = a * i - c * g
    m5 = a * h - b * g
    m6 = b * f - c * e
    m7 = a * f - c * d
    m8 = a * e - b * d
    det = a * m0 - b * m1 + c * m2
    fro = a * a + b * b + c * c + d * d + e * e + f * f + g * g + h * h + i * i
    adj = (m0 * m0 + m1 * m1 + m2 * m2 + m3 * m3 + m4 * m4 + m5 * m5 + m6 * m6 + m7 * m7
           + m8 * m8)
    num = fro * adj
    if not math.isfinite(num):
        return math.inf
    if det == 0.0:
        return math.inf
    return num / (det * det)


@njit(cache=True, nogil=True, error_model="numpy")
def reduce_samples(idx, q, mode, R, rcm, d_e, depth, J_tip, J_par, lengths, L, lo,  # type: ignore[no-untyped-def]
                   hi, resolution):
    """Reduce one design's reachable samples ``idx`` (rows of ``J_tip``, ``J_par``).

    ``q``, ``mode`` are indexed like ``J_tip`` (reachable samples only); ``d_e``,
    ``depth`` like the task samples (``idx`` maps the first onto the second).
    Returns ``counts (3,)`` (reachable, mode +1, mode -1), ``margin (12,)`` and
    ``arg_margin (12,)`` (min of each condition and its row), ``cond (2,)`` and
    ``arg_cond (2,)`` (largest condition number of the tip and parallel Jacobians,
    closed-form eigenvalues, and its row), ``q_lo (3,)``, ``q_hi (3,)`` (actuator
    ranges), ``tip (2,)`` (max and sum of the worst-case tip error).
    """
    l1, l2, l3, l5 = lengths[0], lengths[1], lengths[2], lengths[4]
    n = idx.shape[0]
    counts = np.zeros(3, np.int64)
    margin = np.full(12, np.inf)
    arg_margin = np.full(12, -1, np.int64)
    cond = np.full(2, -np.inf)
    arg_cond = np.full(2, -1, np.int64)
    q_lo = np.full(3, np.inf)
    q_hi = np.full(3, -np.inf)
    tip = np.zeros(2)
    v = np.empty(12)
    kf = np.empty((2, n))
    kf_max = np.zeros(2)
    for j in range(n):
        k = idx[j]
        counts[0] += 1
        if mode[j] > 0:
            counts[1] += 1
        else:
            counts[2] += 1
        q1, q2, q3 = q[j, 0], q[j, 1], q[j, 2]
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
            st = min(st, q[j, i] - lo[i], hi[i] - q[j, i])
            q_lo[i] = min(q_lo[i], q[j, i])
            q_hi[i] = max(q_hi[i], q[j, i])
        v[5] = st
        p, sxy, v8, ds0, v10, v11 = _line_conditions(d_e[k, 0], d_e[k, 1], d_e[k, 2],
                                                     L - depth[k], R, rcm, L)
        v[6] = p
        v[7] = sxy
        v[8] = v8
        v[9] = abs(ds0) / sxy if sxy > 0.0 else 0.0
        v[10] = v10
        v[11] = v11
        for c in range(12):
            if v[c] < margin[c]:
                margin[c] = v[c]
                arg_margin[c] = j
        kt = _kappa_f2(J_tip[j])
        kp = _kappa_f2(J_par[j])
        kf[0, j] = kt
        kf[1, j] = kp
        kf_max[0] = max(kf_max[0], kt)
        kf_max[1] = max(kf_max[1], kp)
        # worst case |J dq| over the box |dq_i| <= resolution: a vertex (convexity)
        worst = 0.0
        for s1 in (1.0, -1.0):
            for s2 in (1.0, -1.0):
                e0 = J_tip[j, 0, 0] + s1 * J_tip[j, 0, 1] + s2 * J_tip[j, 0, 2]
                e1 = J_tip[j, 1, 0] + s1 * J_tip[j, 1, 1] + s2 * J_tip[j, 1, 2]
                e2 = J_tip[j, 2, 0] + s1 * J_tip[j, 2, 1] + s2 * J_tip[j, 2, 2]
                worst = max(worst, e0 * e0 + e1 * e1 + e2 * e2)
        err = resolution * math.sqrt(worst)
        tip[0] = max(tip[0], err)
        tip[1] += err
    # exact 2-norm condition numbers only where kappa_F^2 >= max(kappa_F^2) / 9
    for m in range(2):
        floor = kf_max[m] / 9.0
        for j in range(n):
            if kf[m, j] >= floor or not math.isfinite(kf[m, j]):
                c2 = _cond3(J_tip[j]) if m == 0 else _cond3(J_par[j])
                if c2 > cond[m]:
                    cond[m] = c2
                    arg_cond[m] = j
    return counts, margin, arg_margin, cond, arg_cond, q_lo, q_hi, tip
