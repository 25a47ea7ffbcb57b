"""Per-sample reduction of a design's metrics over the task samples: the numpy reference.

One pass over the reachable samples: the closed-form singularity values of
``docs/singularities.md`` (the same expressions as
:func:`athenakin.analysis.singularities`), the condition numbers of the Jacobians from
the eigenvalues of ``J^T J`` (closed form for 3 x 3), the worst-case tip error of an
encoder box and the actuator ranges. The reduction only *selects* the worst samples;
:mod:`._metrics` re-evaluates the reported margins and condition numbers there with
:mod:`athenakin.analysis` (exact SVD).

:func:`reduce_samples` runs the compiled kernel of :mod:`._kernels` (the same formulas,
sample by sample) where :mod:`athenakin._backend` says so, else :func:`reduce_samples_numpy`;
both agree to 1e-12 (tested).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._backend import resolve_backend
from .._typing import FloatArray, IntArray
from ._formulas import line_conditions_formula

__all__ = ["CONDITION_ORDER", "reduce_samples", "reduce_samples_numpy"]


#: Singularity conditions in the order of the reduction's ``margin`` output.
CONDITION_ORDER = ("circles_tangent", "d_on_rail", "k1_degenerate", "ab_coincide",
                   "k2_degenerate", "stroke_limit", "p_zero", "ujoint", "wrist", "ik_cos_u1",
                   "ik_sin_u1_sin_u2", "tip_at_rcm")


def _cond3(J: FloatArray) -> FloatArray:
    """2-norm condition numbers of 3 x 3 matrices (..., 3, 3) from the eigenvalues of J^T J."""
    A = np.einsum("...ki,...kj->...ij", J, J)
    a11, a22, a33 = A[..., 0, 0], A[..., 1, 1], A[..., 2, 2]
    a12, a13, a23 = A[..., 0, 1], A[..., 0, 2], A[..., 1, 2]
    finite = np.all(np.isfinite(A), axis=(-2, -1))
    q = (a11 + a22 + a33) / 3.0
    p1 = a12 * a12 + a13 * a13 + a23 * a23
    b11, b22, b33 = a11 - q, a22 - q, a33 - q
    p2 = b11 * b11 + b22 * b22 + b33 * b33 + 2.0 * p1
    with np.errstate(invalid="ignore", divide="ignore"):
        p = np.sqrt(p2 / 6.0)
        det_b = (b11 * (b22 * b33 - a23 * a23) - a12 * (a12 * b33 - a23 * a13)
                 + a13 * (a12 * a23 - b22 * a13))
        r = np.clip(det_b / (2.0 * p * p * p), -1.0, 1.0)
        phi = np.arccos(r) / 3.0
        e1 = q + 2.0 * p * np.cos(phi)
        e3 = q + 2.0 * p * np.cos(phi + 2.0 * np.pi / 3.0)
        out = np.where(e3 <= 0.0, np.inf, np.sqrt(e1 / e3))
    out = np.where(p2 <= 0.0, np.where(q > 0.0, 1.0, np.inf), out)
    return np.where(finite, out, np.inf)  # type: ignore[no-any-return]


def _kappa_f2(J: FloatArray) -> FloatArray:
    """Squared Frobenius condition numbers ``|J|_F^2 |adj J|_F^2 / det(J)^2``, (..., 3, 3).

    ``kappa_2 <= kappa_F <= 3 kappa_2`` (3 x 3), so the sample of the largest ``kappa_2``
    is among those with ``kappa_F >= max(kappa_F) / 3``.
    """
    a, b, c = J[..., 0, 0], J[..., 0, 1], J[..., 0, 2]
    d, e, f = J[..., 1, 0], J[..., 1, 1], J[..., 1, 2]
    g, h, i = J[..., 2, 0], J[..., 2, 1], J[..., 2, 2]
    m = [e * i - f * h, d * i - f * g, d * h - e * g, b * i - c * h, a * i - c * g,
         a * h - b * g, b * f - c * e, a * f - c * d, a * e - b * d]
    det = a * m[0] - b * m[1] + c * m[2]
    fro = a * a + b * b + c * c + d * d + e * e + f * f + g * g + h * h + i * i
    adj = m[0] * m[0]
    for x in m[1:]:
        adj = adj + x * x
    num = fro * adj
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        out = num / (det * det)
    return np.where(np.isfinite(num) & (det != 0.0), out, np.inf)  # type: ignore[no-any-return]


def _first_min(v: FloatArray) -> tuple[float, int]:
    """The least value below ``inf`` of ``v`` and its first index, else ``(inf, -1)``."""
    w = np.where(np.isnan(v), np.inf, v)
    if not w.size:
        return np.inf, -1
    k = int(np.argmin(w))
    return (float(w[k]), k) if w[k] < np.inf else (np.inf, -1)


def _condition_values(idx: IntArray, q: FloatArray, R: FloatArray, rcm: FloatArray,
                      d_e: FloatArray, depth: FloatArray, lengths: FloatArray, L: float,
                      lo: FloatArray, hi: FloatArray) -> FloatArray:
    """The value of each condition of :data:`CONDITION_ORDER` per reached sample, (12, n)."""
    l1, l2, l3, l5 = lengths[0], lengths[1], lengths[2], lengths[4]
    q1, q2, q3 = q[:, 0], q[:, 1], q[:, 2]
    h = 0.5 * (q1 - q2)
    ah = np.abs(h)
    r1 = np.sqrt(np.maximum(l1 * l1 - h * h, 0.0))
    s3 = np.sqrt(np.maximum(l3 * l3 - h * h, 0.0))
    dv = np.sqrt((s3 + l2) ** 2 + l5 * l5)
    v = np.empty((12, q.shape[0]))
    v[0] = np.minimum(np.abs(q3 - np.abs(dv - r1)), np.abs(q3 - (dv + r1)))
    v[1] = l3 - ah
    v[2] = l1 - ah
    v[3] = ah
    v[4] = np.abs(q3)
    v[5] = np.min(np.minimum(q - lo, hi - q), axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        v[6], v[7], v[8], ds0, v[10], v[11] = line_conditions_formula(
            d_e[idx, 0], d_e[idx, 1], d_e[idx, 2], L - depth[idx], R, rcm, L)
        sxy = v[7]
        v[9] = np.where(sxy > 0.0, np.abs(ds0) / np.where(sxy > 0.0, sxy, 1.0), 0.0)
    return v


def _largest_conditions(J_tip: FloatArray, J_par: FloatArray) -> tuple[FloatArray, IntArray]:
    """Largest 2-norm condition number of each Jacobian stack (tip, parallel) and its row."""
    cond = np.full(2, -np.inf)
    arg_cond = np.full(2, -1, np.int64)
    # exact 2-norm condition numbers only where kappa_F^2 >= max(kappa_F^2) / 9
    for m, J in enumerate((J_tip, J_par)):
        kf = _kappa_f2(J)
        floor = max(0.0, float(np.max(kf))) / 9.0
        pick = np.flatnonzero((kf >= floor) | ~np.isfinite(kf))
        if pick.size:
            c2 = _cond3(J[pick])
            c2 = np.where(np.isnan(c2), -np.inf, c2)
            k = int(np.argmax(c2))
            if c2[k] > -np.inf:
                cond[m], arg_cond[m] = c2[k], pick[k]
    return cond, arg_cond


def _tip_errors(J_tip: FloatArray, resolution: float) -> FloatArray:
    """Max and sum over the samples of the worst-case tip error of an encoder box, m."""
    # worst case |J dq| over the box |dq_i| <= resolution: a vertex (convexity)
    worst = np.zeros(J_tip.shape[0])
    for s1 in (1.0, -1.0):
        for s2 in (1.0, -1.0):
            e = J_tip[:, :, 0] + s1 * J_tip[:, :, 1] + s2 * J_tip[:, :, 2]
            worst = np.maximum(worst, e[:, 0] * e[:, 0] + e[:, 1] * e[:, 1] + e[:, 2] * e[:, 2])
    err = resolution * np.sqrt(worst)
    tip = np.array([max(0.0, float(np.max(err))), float(np.sum(err))])
    return tip


def reduce_samples_numpy(idx: IntArray, q: FloatArray, mode: IntArray, R: FloatArray,
                         rcm: FloatArray, d_e: FloatArray, depth: FloatArray, J_tip: FloatArray,
                         J_par: FloatArray, lengths: FloatArray, L: float, lo: FloatArray,
                         hi: FloatArray, resolution: float) -> tuple[Any, ...]:
    """Reduce one design's reachable samples ``idx`` (rows of ``J_tip``, ``J_par``), numpy.

    Parameters
    ----------
    idx : ndarray of int, shape (n,)
        The task samples reached (indices into ``d_e``, ``depth``).
    q : ndarray, shape (n, 3)
        Their actuator values, m.
    mode : ndarray of int, shape (n,)
        Their assembly modes (+1 / -1).
    R, rcm : ndarray, shapes (3, 3) and (3,)
        Rotation and origin of the RCM frame in the base frame.
    d_e, depth : ndarray, shapes (N, 3) and (N,)
        Instrument directions (frame E) and depths (m) of every task sample.
    J_tip, J_par : ndarray, shape (n, 3, 3)
        Tool-tip and parallel Jacobians of the reached samples.
    lengths : ndarray, shape (5,)
        ``l1..l5`` of the design, m.
    L : float
        Tool length, m.
    lo, hi : ndarray, shape (3,)
        Stroke limits, m.
    resolution : float
        Encoder resolution, m.

    Returns
    -------
    counts : ndarray of int, shape (3,)
        Reached, mode +1, mode -1.
    margin, arg_margin : ndarray, shape (12,)
        Least value of each condition of :data:`CONDITION_ORDER` and its row (-1: none).
    cond, arg_cond : ndarray, shape (2,)
        Largest condition number of the tip and parallel Jacobians (closed-form
        eigenvalues) and its row.
    q_lo, q_hi : ndarray, shape (3,)
        Actuator ranges, m.
    tip : ndarray, shape (2,)
        Max and sum of the worst-case tip error, m.
    """
    n = idx.shape[0]
    counts = np.array([n, np.count_nonzero(mode > 0), np.count_nonzero(mode <= 0)], np.int64)
    margin = np.full(12, np.inf)
    arg_margin = np.full(12, -1, np.int64)
    if n == 0:
        return (counts, margin, arg_margin, np.full(2, -np.inf), np.full(2, -1, np.int64),
                np.full(3, np.inf), np.full(3, -np.inf), np.zeros(2))
    v = _condition_values(idx, q, R, rcm, d_e, depth, lengths, L, lo, hi)
    for c in range(12):
        margin[c], arg_margin[c] = _first_min(v[c])
    cond, arg_cond = _largest_conditions(J_tip, J_par)
    tip = _tip_errors(J_tip, resolution)
    return counts, margin, arg_margin, cond, arg_cond, q.min(axis=0), q.max(axis=0), tip


def reduce_samples(idx: IntArray, q: FloatArray, mode: IntArray, R: FloatArray, rcm: FloatArray,
                   d_e: FloatArray, depth: FloatArray, J_tip: FloatArray, J_par: FloatArray,
                   lengths: FloatArray, L: float,
                   lo: FloatArray, hi: FloatArray, resolution: float, *,
                   backend: str = "auto") -> tuple[Any, ...]:
    """:func:`reduce_samples_numpy`, compiled where ``backend`` resolves to numba.

    Parameters and Returns as :func:`reduce_samples_numpy`; ``backend``
    (``"auto" | "numpy" | "numba"``, keyword-only) as :func:`athenakin._backend.resolve_backend`.
    """
    if resolve_backend(backend):
        from ._kernels import reduce_samples as kernel

        return kernel(idx, q, mode, R, rcm, d_e, depth, J_tip, J_par,  # type: ignore[no-any-return]
                      lengths, L, lo, hi, resolution)
    return reduce_samples_numpy(idx, q, mode, R, rcm, d_e, depth, J_tip, J_par, lengths, L,
                                lo, hi, resolution)
