"""Compiled capsule-capsule distances (numba), the batch path of ``athenakin.collision``.

The same five candidates as the numpy reference
(:func:`athenakin.collision._distance.segment_segment`): the four end-point-to-segment
distances and the interior critical point where the segments are not parallel, in the
reference's two forms (Lumelsky's; cross products for nearly parallel segments, out of
line: 4.3 % of the default bodies' pairs take it); the smallest wins. Parallel,
degenerate (zero-length), touching and crossing segments are exact. Witness points and
the normal fallback (``d1 x d2``, a normal of ``d1``, ``+z``) follow the reference too
(one normal above ``WITNESS_DIRECT``, where the two forms agree to 1e-13 m). Candidates
are compared by squared distance and carry only their parameters ``(s, t)``; the
closest points are formed once, from the winner.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._backend import njit
from ._distance import NEARLY_PARALLEL, NOISE, WITNESS_DIRECT

__all__ = ["capsule_pairs", "capsule_pairs_into", "capsule_distances", "capsule_distances_into",
           "segment_distance", "workspace_into"]

#: ``contract``: fused multiply-adds (about 15 % faster, measured). No other fast-math flag:
#: NaN rows must stay NaN, and the results stay within 1e-13 m of the numpy reference
#: (tested); every candidate is still a true pair of points on the segments.
_OPTS: dict[str, Any] = dict(error_model="numpy", cache=True, nogil=True,
                             fastmath={"contract"})


@njit(inline="always", **_OPTS)
def _point_seg(x0, x1, x2, a0, a1, a2, d0, d1, d2, inv_dd):
    """Closest point a + t d of a segment to x: (squared distance, t).

    ``inv_dd`` is ``1 / (d . d)``, or 0 for a zero-length segment (then ``t = 0``).
    """
    t = ((x0 - a0) * d0 + (x1 - a1) * d1 + (x2 - a2) * d2) * inv_dd
    t = min(max(t, 0.0), 1.0)
    e0 = x0 - (a0 + t * d0)
    e1 = x1 - (a1 + t * d1)
    e2 = x2 - (a2 + t * d2)
    return e0 * e0 + e1 * e1 + e2 * e2, t


@njit(**_OPTS)
def segment_distance(S, out_c):
    """Distance of the segments ``S[0]-S[1]`` and ``S[2]-S[3]``; closest points into ``out_c``.

    Parameters
    ----------
    S : ndarray, shape (4, 3)
        ``p1, q1, p2, q2``.
    out_c : ndarray, shape (2, 3)
        Receives the closest points on the first and on the second segment.
    """
    d, x0, x1, x2, y0, y1, y2 = _seg_seg(S[0, 0], S[0, 1], S[0, 2], S[1, 0], S[1, 1], S[1, 2],
                                         S[2, 0], S[2, 1], S[2, 2], S[3, 0], S[3, 1], S[3, 2])
    out_c[0, 0] = x0
    out_c[0, 1] = x1
    out_c[0, 2] = x2
    out_c[1, 0] = y0
    out_c[1, 1] = y1
    out_c[1, 2] = y2
    return d


@njit(inline="always", **_OPTS)
def _along(a0, a1, a2, d0, d1, d2, t):
    """The point ``a + t d`` of a segment."""
    return a0 + t * d0, a1 + t * d1, a2 + t * d2


@njit(inline="always", **_OPTS)
def _nearer(w, dist, s, t, best, sb, tb):
    """``(dist, s, t)`` where ``w`` (the candidate is nearer), else ``(best, sb, tb)``.

    One conditional expression per value: compiled to selects, not to branches that the
    varying winner would mispredict.
    """
    return (dist if w else best), (s if w else sb), (t if w else tb)


@njit(**_OPTS)
def _interior_nearly_parallel(p10, p11, p12, d10, d11, d12, p20, p21, p22, d20, d21, d22,
                              inv_e):
    """Interior candidate of nearly parallel segments: (squared distance, s, t, ok).

    As the reference's: ``s`` from cross products, ``t`` of the point of segment 2
    nearest ``p1 + s d1``; ``ok`` is false for parallel segments. ``inv_e`` is
    ``1 / (d2 . d2)`` (0 for a zero-length segment 2). Not inlined: a rare branch.
    """
    n0 = d11 * d22 - d12 * d21
    n1 = d12 * d20 - d10 * d22
    n2 = d10 * d21 - d11 * d20
    nn = n0 * n0 + n1 * n1 + n2 * n2
    w0 = p20 - p10
    w1 = p21 - p11
    w2 = p22 - p12
    k0 = w1 * d22 - w2 * d21
    k1 = w2 * d20 - w0 * d22
    k2 = w0 * d21 - w1 * d20
    inv = 1.0 / nn if nn > 0.0 else 0.0
    s = min(max((k0 * n0 + k1 * n1 + k2 * n2) * inv, 0.0), 1.0)
    dist, t = _point_seg(p10 + s * d10, p11 + s * d11, p12 + s * d12, p20, p21, p22,
                         d20, d21, d22, inv_e)
    return dist, s, t, nn > 0.0


@njit(inline="always", **_OPTS)
def _seg_seg(p10, p11, p12, q10, q11, q12, p20, p21, p22, q20, q21, q22):
    """Segment-segment distance and closest points: (dist, x0, x1, x2, y0, y1, y2)."""
    d10 = q10 - p10
    d11 = q11 - p11
    d12 = q12 - p12
    d20 = q20 - p20
    d21 = q21 - p21
    d22 = q22 - p22
    a = d10 * d10 + d11 * d11 + d12 * d12
    e = d20 * d20 + d21 * d21 + d22 * d22
    inv_a = 1.0 / a if a > 0.0 else 0.0
    inv_e = 1.0 / e if e > 0.0 else 0.0
    # the candidates carry only their parameters (s on segment 1, t on segment 2)
    # candidate 1: p2 against segment 1
    best, sb = _point_seg(p20, p21, p22, p10, p11, p12, d10, d11, d12, inv_a)
    tb = 0.0
    # candidate 2: q2 against segment 1
    dist, u = _point_seg(q20, q21, q22, p10, p11, p12, d10, d11, d12, inv_a)
    best, sb, tb = _nearer(dist < best, dist, u, 1.0, best, sb, tb)
    # candidate 3: p1 against segment 2
    dist, u = _point_seg(p10, p11, p12, p20, p21, p22, d20, d21, d22, inv_e)
    best, sb, tb = _nearer(dist < best, dist, 0.0, u, best, sb, tb)
    # candidate 4: q1 against segment 2
    dist, u = _point_seg(q10, q11, q12, p20, p21, p22, d20, d21, d22, inv_e)
    best, sb, tb = _nearer(dist < best, dist, 1.0, u, best, sb, tb)
    # candidate 5: the interior critical point (not parallel: a e - b^2 > 0), Lumelsky's
    # form; nearly parallel segments take the reference's cross products instead
    r0 = p10 - p20
    r1 = p11 - p21
    r2 = p12 - p22
    b = d10 * d20 + d11 * d21 + d12 * d22
    c = d10 * r0 + d11 * r1 + d12 * r2
    f = d20 * r0 + d21 * r1 + d22 * r2
    denom = a * e - b * b
    inv = 1.0 / denom if denom > 0.0 else 0.0
    s = min(max((b * f - c * e) * inv, 0.0), 1.0)
    t = min(max((a * f - b * c) * inv, 0.0), 1.0)
    g0 = (p10 + s * d10) - (p20 + t * d20)
    g1 = (p11 + s * d11) - (p21 + t * d21)
    g2 = (p12 + s * d12) - (p22 + t * d22)
    dist = g0 * g0 + g1 * g1 + g2 * g2
    best4, sb4, tb4 = best, sb, tb
    best, sb, tb = _nearer((denom > 0.0) and (dist < best), dist, s, t, best, sb, tb)
    if denom <= NEARLY_PARALLEL * a * e:
        # a rare branch, its work an out-of-line call (4.3 % of the benchmark's pairs;
        # NaN rows, an invalid configuration's, stay on the straight path)
        dist, s, t, ok = _interior_nearly_parallel(p10, p11, p12, d10, d11, d12,
                                                   p20, p21, p22, d20, d21, d22, inv_e)
        best, sb, tb = _nearer(ok and (dist < best4), dist, s, t, best4, sb4, tb4)
    x0, x1, x2 = _along(p10, p11, p12, d10, d11, d12, sb)
    y0, y1, y2 = _along(p20, p21, p22, d20, d21, d22, tb)
    # candidates compared by squared distance (sqrt is monotonic): one sqrt, of the winner
    return math.sqrt(best), x0, x1, x2, y0, y1, y2


@njit(inline="always", **_OPTS)
def _normal(n, x0, x1, x2, y0, y1, y2, d10, d11, d12, d20, d21, d22):
    """Unit normal from x towards y (``n = |y - x|``), with the reference's fallbacks."""
    tiny = 1e-300
    v0 = y0 - x0
    v1 = y1 - x1
    v2 = y2 - x2
    # fast path: above WITNESS_DIRECT the direction is far above the rounding noise of
    # any coordinates within the 1e3 m that athenakin accepts
    if n > WITNESS_DIRECT:
        inv = 1.0 / n
        return v0 * inv, v1 * inv, v2 * inv
    noise = NOISE * (math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
                     + math.sqrt(d10 * d10 + d11 * d11 + d12 * d12)
                     + math.sqrt(d20 * d20 + d21 * d21 + d22 * d22)) + tiny
    if n > noise:
        return v0 / n, v1 / n, v2 / n
    x0 = d11 * d22 - d12 * d21
    x1 = d12 * d20 - d10 * d22
    x2 = d10 * d21 - d11 * d20
    nx = math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
    if nx > tiny and nx > NOISE * math.sqrt(d10 * d10 + d11 * d11 + d12 * d12) * math.sqrt(
            d20 * d20 + d21 * d21 + d22 * d22):
        return x0 / nx, x1 / nx, x2 / nx
    b0, b1, b2 = d10, d11, d12
    if not math.sqrt(d10 * d10 + d11 * d11 + d12 * d12) > 0.0:
        b0, b1, b2 = d20, d21, d22
    # cross with the axis of the smallest |component| (first on ties, as np.argmin)
    a0, a1, a2 = abs(b0), abs(b1), abs(b2)
    if a0 <= a1 and a0 <= a2:
        y0, y1, y2 = 0.0, b2, -b1            # b x e_x
    elif a1 <= a2:
        y0, y1, y2 = -b2, 0.0, b0            # b x e_y
    else:
        y0, y1, y2 = b1, -b0, 0.0            # b x e_z
    ny = math.sqrt(y0 * y0 + y1 * y1 + y2 * y2)
    if ny > tiny:
        return y0 / ny, y1 / ny, y2 / ny
    return 0.0, 0.0, 1.0


@njit(inline="always", **_OPTS)
def _across(n0, n1, n2, x0, x1, x2, d0, d1, d2):
    """``n`` without its component along ``d`` where ``x`` projects inside the segment.

    As :func:`athenakin.collision._distance._across` (``x`` relative to the start).
    """
    dd = d0 * d0 + d1 * d1 + d2 * d2
    xd = x0 * d0 + x1 * d1 + x2 * d2
    if dd > 0.0 and xd > 0.0 and xd < dd:
        c = (n0 * d0 + n1 * d1 + n2 * d2) / dd
        m0 = n0 - c * d0
        m1 = n1 - c * d1
        m2 = n2 - c * d2
        mm = math.sqrt(m0 * m0 + m1 * m1 + m2 * m2)
        if mm > 0.5:
            return m0 / mm, m1 / mm, m2 / mm
    return n0, n1, n2


@njit(inline="always", **_OPTS)
def _surface_point(out, row, c0, c1, c2, r, f0, f1, f2, t0, t1, t2, e0, e1, e2, a0, a1, a2,
                   d10, d11, d12, d20, d21, d22):
    """``c + r n`` into ``out[row]``: one witness point, on its capsule's surface.

    ``n`` is the unit normal from ``f`` towards ``t`` (:func:`_normal` of the axes ``d1``,
    ``d2``), made normal to the capsule's own axis ``a`` where ``e`` (relative to the
    axis' start) projects inside the segment (:func:`_across`).
    """
    g0 = t0 - f0
    g1 = t1 - f1
    g2 = t2 - f2
    n0, n1, n2 = _normal(math.sqrt(g0 * g0 + g1 * g1 + g2 * g2), f0, f1, f2, t0, t1, t2,
                         d10, d11, d12, d20, d21, d22)
    n0, n1, n2 = _across(n0, n1, n2, e0, e1, e2, a0, a1, a2)
    out[row, 0] = c0 + r * n0
    out[row, 1] = c1 + r * n1
    out[row, 2] = c2 + r * n2


@njit(inline="always", **_OPTS)
def _witnesses(out, p10, p11, p12, d10, d11, d12, r1, p20, p21, p22, d20, d21, d22, r2,
               x0, x1, x2, y0, y1, y2):
    """Witness points of two capsules into ``out`` (2, 3), as the reference.

    Each from the point of its own segment nearest the other closest point (``b1``
    nearest ``y``, ``b2`` nearest ``x``), along ``b1 -> y`` (``x -> b2``), normal to the
    axis inside the segment: on the surface (:func:`athenakin.collision.capsule_capsule`).
    """
    a = d10 * d10 + d11 * d11 + d12 * d12
    e = d20 * d20 + d21 * d21 + d22 * d22
    _, s = _point_seg(y0, y1, y2, p10, p11, p12, d10, d11, d12, 1.0 / a if a > 0.0 else 0.0)
    _, t = _point_seg(x0, x1, x2, p20, p21, p22, d20, d21, d22, 1.0 / e if e > 0.0 else 0.0)
    b10, b11, b12 = _along(p10, p11, p12, d10, d11, d12, s)
    b20, b21, b22 = _along(p20, p21, p22, d20, d21, d22, t)
    # b1 + r1 n along b1 -> y, and b2 - r2 n along x -> b2
    _surface_point(out, 0, b10, b11, b12, r1, b10, b11, b12, y0, y1, y2,
                   y0 - p10, y1 - p11, y2 - p12, d10, d11, d12, d10, d11, d12, d20, d21, d22)
    _surface_point(out, 1, b20, b21, b22, -r2, x0, x1, x2, b20, b21, b22,
                   x0 - p20, x1 - p21, x2 - p22, d20, d21, d22, d10, d11, d12, d20, d21, d22)


def capsule_pairs(solids, radii, ij):
    """Signed distances and witness points of capsule pairs over a batch.

    Parameters
    ----------
    solids : ndarray, shape (n, n_solids, 2, 3)
        Segment end points of every solid, per item (C-contiguous float64).
    radii : ndarray, shape (n_solids,)
    ij : ndarray of intp, shape (n_pairs, 2)
        The solids of each pair.

    Returns
    -------
    dist : ndarray, shape (n, n_pairs)
    witness : ndarray, shape (n, n_pairs, 2, 3)

    Notes
    -----
    The outputs are allocated here, by numpy, and filled by the compiled loop: numpy
    asks the kernel for huge pages on large arrays, numba's allocator does not, and
    first touching 4 KiB pages cost as much as the distances themselves (measured).
    """
    n, P = solids.shape[0], ij.shape[0]
    dist = np.empty((n, P))
    wit = np.empty((n, P, 2, 3))
    capsule_pairs_into(solids, radii, ij, dist, wit)
    return dist, wit


def capsule_distances(solids, radii, ij):
    """Signed distances only (no witness points) of capsule pairs over a batch.

    Same arguments and the same ``dist`` as :func:`capsule_pairs`, exactly; for callers
    that need no witness points (planners, design studies).
    """
    dist = np.empty((solids.shape[0], ij.shape[0]))
    capsule_distances_into(solids, radii, ij, dist)
    return dist


@njit(**_OPTS)
def capsule_pairs_into(solids, radii, ij, dist, wit):
    """Fill ``dist`` (n, P) and ``wit`` (n, P, 2, 3) (views allowed): see :func:`capsule_pairs`.

    Rows with NaN end points give NaN (no exception).
    """
    n = solids.shape[0]
    P = ij.shape[0]
    for m in range(n):
        for k in range(P):
            _capsule_pair(solids, radii, m, ij[k, 0], ij[k, 1], dist, wit, k)


@njit(inline="always", **_OPTS)
def _capsule_pair(solids, radii, m, i, j, dist, wit, k):
    """Solids ``i``, ``j`` of item ``m``: distance into ``dist[m, k]``, witnesses ``wit[m, k]``."""
    p10 = solids[m, i, 0, 0]
    p11 = solids[m, i, 0, 1]
    p12 = solids[m, i, 0, 2]
    q10 = solids[m, i, 1, 0]
    q11 = solids[m, i, 1, 1]
    q12 = solids[m, i, 1, 2]
    p20 = solids[m, j, 0, 0]
    p21 = solids[m, j, 0, 1]
    p22 = solids[m, j, 0, 2]
    q20 = solids[m, j, 1, 0]
    q21 = solids[m, j, 1, 1]
    q22 = solids[m, j, 1, 2]
    d, x0, x1, x2, y0, y1, y2 = _seg_seg(p10, p11, p12, q10, q11, q12,
                                         p20, p21, p22, q20, q21, q22)
    r1 = radii[i]
    r2 = radii[j]
    dist[m, k] = d - r1 - r2
    if not d <= WITNESS_DIRECT:        # NaN rows too: NaN witnesses, no detour
        # fast path, as _normal's: y - x is normal to both axes to rounding (the
        # closest points), far above the noise; the same points as _witnesses to
        # 1e-13 m
        inv = 1.0 / d
        n0 = (y0 - x0) * inv
        n1 = (y1 - x1) * inv
        n2 = (y2 - x2) * inv
        wit[m, k, 0, 0] = x0 + r1 * n0
        wit[m, k, 0, 1] = x1 + r1 * n1
        wit[m, k, 0, 2] = x2 + r1 * n2
        wit[m, k, 1, 0] = y0 - r2 * n0
        wit[m, k, 1, 1] = y1 - r2 * n1
        wit[m, k, 1, 2] = y2 - r2 * n2
    else:
        _witnesses(wit[m, k], p10, p11, p12, q10 - p10, q11 - p11, q12 - p12, r1,
                   p20, p21, p22, q20 - p20, q21 - p21, q22 - p22, r2,
                   x0, x1, x2, y0, y1, y2)


@njit(**_OPTS)
def capsule_distances_into(solids, radii, ij, dist):
    """Fill ``dist`` (n, P) (a view allowed): see :func:`capsule_distances`."""
    n = solids.shape[0]
    P = ij.shape[0]
    for m in range(n):
        for k in range(P):
            i = ij[k, 0]
            j = ij[k, 1]
            d = _seg_seg(solids[m, i, 0, 0], solids[m, i, 0, 1], solids[m, i, 0, 2],
                         solids[m, i, 1, 0], solids[m, i, 1, 1], solids[m, i, 1, 2],
                         solids[m, j, 0, 0], solids[m, j, 0, 1], solids[m, j, 0, 2],
                         solids[m, j, 1, 0], solids[m, j, 1, 1], solids[m, j, 1, 2])[0]
            dist[m, k] = d - radii[i] - radii[j]


# --- the per-pose workspace (athenakin.collision._workspace) ----------------------------
@njit(**_OPTS)
def workspace_into(solids, radii, ij, hb, hp, hn, proxy, below, dist, wit, exact, at,
                   since_at, since_dist, move, carry):  # pragma: no cover - numba
    """Every column of one item of :class:`athenakin.collision._workspace.ClearanceWorkspace`.

    The capsule pairs (:func:`_capsule_pair`), then the halfspaces (:func:`_halfspace_row`).
    With ``carry``, a column whose carried bound ``since_dist[c] - move[i] - move[j]`` is at
    least ``below`` keeps that bound (``exact[c]`` False, NaN witnesses) instead: ``move[i]``
    (written here) is the largest displacement of body ``i``'s end points from ``since_at``
    (the segments of the evaluation ``since_dist`` is of), 0 for a fixed obstacle. The body
    segments evaluated are copied to ``at``.

    Returns the column of the least distance (-1 with none; NaN distances are never
    least), whether a box or mesh column (``proxy``: their bounding spheres) evaluated
    here is below ``below`` (its exact distance is then wanted), and the least distance
    (``inf`` with none).
    """
    nb = at.shape[0]
    seg = solids[0]
    if carry:
        for i in range(nb):
            move[i] = _end_point_move(seg, since_at, i)
    d2 = dist.reshape(1, -1)
    w2 = wit.reshape(1, -1, 2, 3)
    nc = ij.shape[0]
    for c in range(nc):
        i = ij[c, 0]
        j = ij[c, 1]
        if carry:
            b = since_dist[c] - move[i] - (move[j] if j < nb else 0.0)
            if b >= below:                   # NaN never: evaluated
                _carried(dist, wit, exact, c, b)
                continue
        _capsule_pair(solids, radii, 0, i, j, d2, w2, c)
        exact[c] = True
    for k in range(hb.shape[0]):
        c = nc + k
        i = hb[k]
        if carry:
            b = since_dist[c] - move[i]
            if b >= below:
                _carried(dist, wit, exact, c, b)
                continue
        _halfspace_row(seg, radii, i, hp, hn, k, dist, wit, c)
        exact[c] = True
    k = -1
    best = math.inf
    for c in range(dist.shape[0]):
        if dist[c] < best:
            best = dist[c]
            k = c
    need = False
    for c in proxy:
        if exact[c]:                     # evaluated here: a bounding sphere's distance,
            exact[c] = False             # until coal's
            if dist[c] < below:
                need = True
    for i in range(nb):
        for e in range(2):
            for j in range(3):
                at[i, e, j] = seg[i, e, j]
    return k, need, best


@njit(inline="always", **_OPTS)
def _end_point_move(seg, since, i):
    """Largest displacement of body ``i``'s two end points from ``since`` (NaN stays NaN)."""
    m = 0.0
    for e in range(2):
        d2 = 0.0
        for j in range(3):
            v = seg[i, e, j] - since[i, e, j]
            d2 += v * v
        if not d2 <= m:                  # the larger, or NaN
            m = d2
            if d2 != d2:
                break
    return math.sqrt(m)


@njit(inline="always", **_OPTS)
def _carried(dist, wit, exact, c, b):
    """Column ``c`` keeps the lower bound ``b``: not exact, no witness points."""
    dist[c] = b
    exact[c] = False
    for s in range(2):
        for j in range(3):
            wit[c, s, j] = math.nan


@njit(inline="always", **_OPTS)
def _halfspace_row(seg, rad, i, point, normal, k, dist, wit, c):  # pragma: no cover - numba
    """Body ``i`` and halfspace ``k``: column ``c`` of ``dist`` / ``wit`` (the reference's)."""
    n0, n1, n2 = normal[k, 0], normal[k, 1], normal[k, 2]
    hp = ((seg[i, 0, 0] - point[k, 0]) * n0 + (seg[i, 0, 1] - point[k, 1]) * n1
          + (seg[i, 0, 2] - point[k, 2]) * n2)
    hq = ((seg[i, 1, 0] - point[k, 0]) * n0 + (seg[i, 1, 1] - point[k, 1]) * n1
          + (seg[i, 1, 2] - point[k, 2]) * n2)
    e = 1 if hq < hp else 0
    h = hq if hq < hp else hp
    r = rad[i]
    dist[c] = h - r
    for j in range(3):
        nj = normal[k, j]
        wit[c, 0, j] = seg[i, e, j] - r * nj
        wit[c, 1, j] = seg[i, e, j] - h * nj
