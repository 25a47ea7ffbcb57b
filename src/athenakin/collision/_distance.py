"""Exact closed-form distances between segments, points and planes: the numpy reference.

Capsules are segments swept by a ball, so the signed distance of two capsules is the
distance of their segments minus both radii (negative: the penetration depth, the
shortest translation that separates them; two crossing segments separate by an
arbitrarily small move, so they add nothing to it).

Segment to segment (:func:`segment_segment`): the minimum of a convex quadratic over
the unit square ``(s, t)`` lies either at its interior critical point or on an edge,
where it is the distance of an end point to the other segment. The reference takes
the smallest of these five candidates, each a true pair of points on the segments, so
it is exact for parallel (the interior candidate is dropped), degenerate (zero length:
the end-point candidates remain) and touching or crossing segments (distance 0).

The interior point takes one of two forms, by the angle ``theta`` between the segments:

- Lumelsky's ``s = (b f - c e) / (a e - b^2)``, ``t = (a f - b c) / (a e - b^2)``
  where ``sin^2 theta > NEARLY_PARALLEL`` (0.05): ``a e - b^2`` cancels to a relative
  error ``eps / sin^2``, at most ``20 eps`` there; the distance of two crossing
  segments (the worst case: there it is not stationary) is off by 2.1e-15 m at most
  over 160,000 crossing pairs at every angle, coordinates up to 1 m (tested to 5e-15 m);
- below (nearly parallel segments), ``s = ((p2 - p1) x d2) . n / |n|^2`` with
  ``n = d1 x d2`` (the same numerator and denominator in cross products, whose
  relative error is ``eps / sin``), paired with the point of the second segment nearest
  ``p1 + s d1``: a second, independently rounded ``t`` would add the difference of the
  two errors along the common axis to the distance (1e-6 m at 1e-7 rad; 2e-16 m this
  way). Taken for the rows that need it only (4.3 % of the pairs of the default
  bodies in the benchmark): the cross products cost 20 % of the compiled kernel's time
  when taken for every pair.

The compiled kernel (:mod:`athenakin.collision._kernels`) takes the same candidates
and forms, and the same witnesses, comparing squared distances, with fused
multiply-adds; it agrees with this reference to 1e-13 m (tested). Where the closest
points are not unique (overlapping parallel segments) the two may return different,
equally close, pairs of them.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._typing import BoolArray, FloatArray
from .._validation import check_array
from ..errors import InvalidInputError

__all__ = ["point_segment", "segment_segment", "capsule_capsule", "capsule_halfspace",
           "separation_normal"]


#: Largest coordinate or radius (m) the public distance functions accept: their squared
#: distances stay far from overflow. The clearance of the robot calls the unchecked
#: implementations (``_segment_segment`` ...) on points it made itself.
MAX_COORDINATE = 1e6

#: Relative size below which ``c2 - c1`` is rounding noise (:func:`separation_normal`).
NOISE = 1e-12

#: ``sin^2`` of the angle between two segments at or below which the interior candidate
#: is taken in cross products (nearly parallel segments; see the module docstring).
NEARLY_PARALLEL = 0.05

#: Distance of the segments (m) above which the witness points are ``c1 + r1 n`` and
#: ``c2 - r2 n`` with ``n`` along ``c2 - c1`` directly: there the direction is known to
#: 1e-13 rad, far above the rounding of any coordinates within :data:`MAX_COORDINATE`.
#: At or below, each witness is built from its own segment (:func:`_capsule_capsule`).
WITNESS_DIRECT = 1e-6


def _dot(x: FloatArray, y: FloatArray) -> FloatArray:
    return np.einsum("...i,...i->...", x, y)


def _point_segment(x: FloatArray, a: FloatArray, b: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Unchecked :func:`point_segment` (float arrays (..., 3), broadcast together)."""
    d = b - a
    dd = _dot(d, d)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(dd > 0, _dot(x - a, d) / np.where(dd > 0, dd, 1.0), 0.0)
    t = np.clip(t, 0.0, 1.0)
    c = a + t[..., None] * d
    return np.linalg.norm(x - c, axis=-1), c


def _interior_nearly_parallel(p1: FloatArray, q1: FloatArray, p2: FloatArray, q2: FloatArray
                              ) -> tuple[BoolArray, FloatArray, FloatArray, FloatArray]:
    """Interior candidate of nearly parallel segments, float arrays (k, 3).

    ``s`` from cross products, paired with the point of the second segment nearest
    ``p1 + s d1`` (module docstring). Returns ``(ok, dist, c1, c2)``; ``ok`` is false
    for parallel segments (no interior candidate).
    """
    d1 = q1 - p1
    d2 = q2 - p2
    nrm = np.cross(d1, d2)
    nn = _dot(nrm, nrm)
    ok = nn > 0
    with np.errstate(invalid="ignore", divide="ignore"):
        s = np.clip(_dot(np.cross(p2 - p1, d2), nrm) / np.where(ok, nn, 1.0), 0.0, 1.0)
    c1 = p1 + s[..., None] * d1
    dist, c2 = _point_segment(c1, p2, q2)
    return ok, dist, c1, c2


def _segment_segment(p1: FloatArray, q1: FloatArray, p2: FloatArray, q2: FloatArray
                     ) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Unchecked :func:`segment_segment` (float arrays (..., 3), broadcast together)."""
    p1, q1, p2, q2 = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64)
                                            for v in (p1, q1, p2, q2)))
    shape = p1.shape[:-1]
    p1, q1, p2, q2 = (v.reshape(-1, 3) for v in (p1, q1, p2, q2))
    d1 = q1 - p1
    d2 = q2 - p2
    # candidates 1-4: an end point against the other segment
    best, c1 = _point_segment(p2, p1, q1)
    c2 = p2.copy()
    for x, on_first, seg in ((q2, True, (p1, q1)), (p1, False, (p2, q2)),
                             (q1, False, (p2, q2))):
        dist, cc = _point_segment(x, *seg)
        better = dist < best
        best = np.where(better, dist, best)
        if on_first:
            c1 = np.where(better[..., None], cc, c1)
            c2 = np.where(better[..., None], x, c2)
        else:
            c1 = np.where(better[..., None], x, c1)
            c2 = np.where(better[..., None], cc, c2)
    # candidate 5: the interior critical point, where the segments are not parallel;
    # Lumelsky's form, and cross products where they are nearly parallel
    r = p1 - p2
    a = _dot(d1, d1)
    e = _dot(d2, d2)
    b = _dot(d1, d2)
    c = _dot(d1, r)
    f = _dot(d2, r)
    denom = a * e - b * b
    ok = denom > 0
    with np.errstate(invalid="ignore", divide="ignore"):
        safe = np.where(ok, denom, 1.0)
        s = np.clip((b * f - c * e) / safe, 0.0, 1.0)
        t = np.clip((a * f - b * c) / safe, 0.0, 1.0)
    i1 = p1 + s[..., None] * d1
    i2 = p2 + t[..., None] * d2
    di = np.linalg.norm(i1 - i2, axis=-1)
    near = denom <= NEARLY_PARALLEL * a * e           # NaN rows stay NaN without a detour
    if near.any():
        ok[near], di[near], i1[near], i2[near] = _interior_nearly_parallel(
            p1[near], q1[near], p2[near], q2[near])
    better = ok & (di < best)
    best = np.where(better, di, best)
    c1 = np.where(better[..., None], i1, c1)
    c2 = np.where(better[..., None], i2, c2)
    return best.reshape(shape), c1.reshape(shape + (3,)), c2.reshape(shape + (3,))


def separation_normal(c1: FloatArray, c2: FloatArray, d1: FloatArray, d2: FloatArray) -> FloatArray:
    """Unit vector from ``c1`` towards ``c2``; where they coincide, one normal to both segments.

    "Coincide" is ``|c2 - c1| <= NOISE (|c1| + |d1| + |d2|)``, the rounding noise of
    the closest points of touching or crossing segments.

    ``d1``, ``d2`` are the segment directions: the fallback is ``d1 x d2`` (crossing
    segments), else a vector normal to ``d1`` (or ``d2``; parallel or degenerate), else
    ``+z``.
    """
    v = c2 - c1
    n = np.linalg.norm(v, axis=-1)
    tiny = 1e-300
    # below rounding noise (relative 1e-12 of the coordinates), c2 - c1 has no direction
    noise = NOISE * (np.linalg.norm(c1, axis=-1) + np.linalg.norm(d1, axis=-1)
                     + np.linalg.norm(d2, axis=-1)) + tiny
    x = np.cross(d1, d2)
    nx = np.linalg.norm(x, axis=-1)
    # d1 x d2 of (nearly) parallel segments is rounding noise too: no direction
    nx = np.where(nx > NOISE * np.linalg.norm(d1, axis=-1) * np.linalg.norm(d2, axis=-1), nx, 0.0)
    base = np.where(np.linalg.norm(d1, axis=-1)[..., None] > 0, d1, d2)
    # a vector normal to base: cross with the axis of its smallest component
    ax = np.eye(3)[np.argmin(np.abs(base), axis=-1)]
    y = np.cross(base, ax)
    ny = np.linalg.norm(y, axis=-1)
    z = np.broadcast_to(np.array([0.0, 0.0, 1.0]), v.shape)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where((n > noise)[..., None], v / np.where(n > tiny, n, 1.0)[..., None],
                       np.where((nx > tiny)[..., None], x / np.where(nx > tiny, nx, 1.0)[..., None],
                                np.where((ny > tiny)[..., None],
                                         y / np.where(ny > tiny, ny, 1.0)[..., None], z)))
    return out  # type: ignore[no-any-return]


def _across(n: FloatArray, x: FloatArray, d: FloatArray) -> FloatArray:
    """``n`` without its component along ``d`` where ``x`` projects inside the segment.

    ``x`` is the point relative to the segment's start, ``d`` its direction. Inside
    (``0 < x . d < d . d``, the projection's parameter not clipped) the direction from
    the segment's nearest point is normal to ``d``; taking the rounding of a tiny
    ``c2 - b1`` out of it keeps the witness at the radius to rounding. The end caps and
    degenerate segments keep ``n``.
    """
    dd = _dot(d, d)
    xd = _dot(x, d)
    nd = _dot(n, d)
    with np.errstate(invalid="ignore", divide="ignore"):
        m = n - (nd / np.where(dd > 0, dd, 1.0))[..., None] * d
        mm = np.linalg.norm(m, axis=-1)
        inside = (xd > 0) & (xd < dd) & (mm > 0.5)
        out = np.where(inside[..., None], m / np.where(inside, mm, 1.0)[..., None], n)
    return out  # type: ignore[no-any-return]


def _witnesses_near(p1: FloatArray, q1: FloatArray, r1: FloatArray, p2: FloatArray,
                    q2: FloatArray, r2: FloatArray, c1: FloatArray, c2: FloatArray
                    ) -> FloatArray:
    """Witness points (k, 2, 3) of capsules whose segments are at most WITNESS_DIRECT apart.

    Each witness starts from the point of its own segment nearest the other closest
    point (``b1`` nearest ``c2``, ``b2`` nearest ``c1``) and goes along ``b1 -> c2``
    (``c1 -> b2``): every point of that ray has ``b1`` as its nearest point of segment 1,
    so the witness lies at exactly ``r1`` from segment 1, on the surface. Taking
    ``c1 + r1 n`` with ``n`` along ``c2 - c1`` instead puts it off the surface where
    ``c1`` and ``c2`` carry rounding along the axes that is not small against
    ``|c2 - c1|`` (segments crossing at 3.5e-12 m: 4.2e-5 m from the axis instead of
    ``r1 = 0.01`` m). Where ``b1`` and ``c2`` coincide (crossing, touching) the direction
    is :func:`separation_normal`'s fallback, ``d1 x d2``, the same for both witnesses.
    """
    d1 = q1 - p1
    d2 = q2 - p2
    _, b1 = _point_segment(c2, p1, q1)
    _, b2 = _point_segment(c1, p2, q2)
    n1 = _across(separation_normal(b1, c2, d1, d2), c2 - p1, d1)
    n2 = _across(separation_normal(c1, b2, d1, d2), c1 - p2, d2)
    return np.stack([b1 + r1[..., None] * n1, b2 - r2[..., None] * n2], axis=-2)


def _capsule_capsule(p1: FloatArray, q1: FloatArray, r1: FloatArray | float, p2: FloatArray,
                     q2: FloatArray, r2: FloatArray | float) -> tuple[FloatArray, FloatArray]:
    """Unchecked :func:`capsule_capsule` (what :func:`~athenakin.collision.clearance` calls)."""
    dist, c1, c2 = _segment_segment(p1, q1, p2, q2)
    shape = dist.shape
    r1a = np.broadcast_to(np.asarray(r1, dtype=np.float64), shape)
    r2a = np.broadcast_to(np.asarray(r2, dtype=np.float64), shape)
    # apart (above WITNESS_DIRECT): c1 + r1 n and c2 - r2 n with n along c2 - c1
    far = ~(dist <= WITNESS_DIRECT)                   # NaN rows: NaN witnesses, no detour
    with np.errstate(invalid="ignore", divide="ignore"):
        n = (c2 - c1) / np.where(far, dist, 1.0)[..., None]
    w = np.stack([c1 + r1a[..., None] * n, c2 - r2a[..., None] * n], axis=-2)
    near = ~far
    if near.any():
        p1n, q1n, p2n, q2n = (np.broadcast_to(np.asarray(v, dtype=np.float64), c1.shape)[near]
                              for v in (p1, q1, p2, q2))
        w[near] = _witnesses_near(p1n, q1n, r1a[near], p2n, q2n, r2a[near], c1[near],
                                  c2[near])
    return dist - r1a - r2a, w


def _capsule_halfspace(p: FloatArray, q: FloatArray, r: FloatArray | float, point: FloatArray,
                       normal: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Unchecked :func:`capsule_halfspace` with a unit ``normal``."""
    hp = _dot(p - point, normal)
    hq = _dot(q - point, normal)
    use_q = hq < hp
    h = np.where(use_q, hq, hp)
    e = np.where(use_q[..., None], q, p)
    ra = np.asarray(r, dtype=np.float64)
    w = np.stack(np.broadcast_arrays(e - ra[..., None] * normal, e - h[..., None] * normal),
                 axis=-2)
    return h - ra, w


# --------------------------------------------------------------------------------------
# public, checked entries (the clearance of the robot uses the private ones above)
def _points(**named: ArrayLike) -> list[FloatArray]:
    """Each argument as a finite float array of shape (..., 3), within MAX_COORDINATE."""
    out = []
    for name, v in named.items():
        a = check_array(v, name, (3,))
        if a.size and np.max(np.abs(a)) > MAX_COORDINATE:
            raise InvalidInputError(f"{name}: expected coordinates within +/-{MAX_COORDINATE:g} "
                                    f"m, got {np.max(np.abs(a)):g}")
        out.append(a)
    try:
        np.broadcast_shapes(*(a.shape for a in out))
    except ValueError:
        raise InvalidInputError(
            f"{', '.join(named)}: expected broadcastable batches, got shapes "
            f"{[a.shape for a in out]}") from None
    return out


def _radius(r: ArrayLike, name: str) -> FloatArray:
    a = check_array(r, name, ())
    if a.size and (np.min(a) < 0 or np.max(a) > MAX_COORDINATE):
        raise InvalidInputError(f"{name}: expected radii in [0, {MAX_COORDINATE:g}] m, got "
                                f"{a.min():g} .. {a.max():g}")
    return a


def _batch(points: list[FloatArray], radii: list[FloatArray], names: str
           ) -> tuple[list[FloatArray], list[FloatArray]]:
    """Points broadcast to (batch, 3) and radii to (batch), the batch of all of them."""
    try:
        batch = np.broadcast_shapes(*(p.shape[:-1] for p in points), *(r.shape for r in radii))
    except ValueError:
        raise InvalidInputError(f"{names}: expected broadcastable batches, got shapes "
                                f"{[p.shape for p in points] + [r.shape for r in radii]}"
                                ) from None
    return ([np.broadcast_to(p, batch + (3,)) for p in points],
            [np.broadcast_to(r, batch) for r in radii])


def point_segment(x: ArrayLike, a: ArrayLike, b: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Closest point of the segment ``a``-``b`` to ``x`` and its distance.

    Parameters
    ----------
    x, a, b : array-like, shape (..., 3)
        Broadcast together; ``a == b`` is a point. Finite, within
        :data:`MAX_COORDINATE` m.

    Returns
    -------
    dist : ndarray, shape (...)
    c : ndarray, shape (..., 3)
        Closest point on the segment.

    Raises
    ------
    TypeError, InvalidInputError
        A bad argument, named.
    """
    xx, aa, bb = _points(x=x, a=a, b=b)
    return _point_segment(xx, aa, bb)


def segment_segment(p1: ArrayLike, q1: ArrayLike, p2: ArrayLike, q2: ArrayLike
                    ) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Distance of the segments ``p1``-``q1`` and ``p2``-``q2``, and their closest points.

    Parameters
    ----------
    p1, q1, p2, q2 : array-like, shape (..., 3)
        End points, m; broadcast together. Zero-length segments are points. Finite,
        within :data:`MAX_COORDINATE` m.

    Returns
    -------
    dist : ndarray, shape (...)
        Euclidean distance (>= 0), m.
    c1, c2 : ndarray, shape (..., 3)
        Closest points on the first and on the second segment (``|c1 - c2| = dist``);
        where the closest pair is not unique (parallel overlapping segments), one of them.

    Raises
    ------
    TypeError, InvalidInputError
        A bad argument, named.
    """
    return _segment_segment(*_points(p1=p1, q1=q1, p2=p2, q2=q2))


def capsule_capsule(p1: ArrayLike, q1: ArrayLike, r1: ArrayLike, p2: ArrayLike, q2: ArrayLike,
                    r2: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Signed distance of two capsules and their witness points.

    Parameters
    ----------
    p1, q1, p2, q2 : array-like, shape (..., 3)
        Segment end points, m (finite, within :data:`MAX_COORDINATE`).
    r1, r2 : float or array-like, shape (...)
        Radii, m, in ``[0, MAX_COORDINATE]``.

    Returns
    -------
    distance : ndarray, shape (...)
        ``|c1 - c2| - r1 - r2``; negative is the penetration depth, m.
    witness : ndarray, shape (..., 2, 3)
        The point of each capsule's surface nearest the other (deepest point when they
        overlap), ``c1 + r1 n`` and ``c2 - r2 n`` with ``n`` from :func:`separation_normal`.

    Raises
    ------
    TypeError, InvalidInputError
        A bad argument, named.
    """
    pts = _points(p1=p1, q1=q1, p2=p2, q2=q2)
    ra, rb = _radius(r1, "r1"), _radius(r2, "r2")
    pts, (ra, rb) = _batch(pts, [ra, rb], "p1, q1, r1, p2, q2, r2")
    return _capsule_capsule(pts[0], pts[1], ra, pts[2], pts[3], rb)


def capsule_halfspace(p: ArrayLike, q: ArrayLike, r: ArrayLike, point: ArrayLike,
                      normal: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Signed distance of a capsule to the solid ``{x : normal . (x - point) <= 0}``.

    Parameters
    ----------
    p, q : array-like, shape (..., 3)
        The capsule's segment, m.
    r : float or array-like, shape (...)
        Its radius, m, in ``[0, MAX_COORDINATE]``.
    point, normal : array-like, shape (..., 3)
        A point of the plane and its normal (any non-zero length; pointing to the free
        side).

    Returns
    -------
    distance, witness
        As :func:`capsule_capsule`, the witness on the capsule first and on the plane
        second.

    Raises
    ------
    TypeError, InvalidInputError
        A bad argument, named (a zero normal among them).
    """
    pp, qq, pt, nn = _points(p=p, q=q, point=point, normal=normal)
    ra = _radius(r, "r")
    (pp, qq, pt, nn), (ra,) = _batch([pp, qq, pt, nn], [ra], "p, q, r, point, normal")
    norm = np.linalg.norm(nn, axis=-1, keepdims=True)
    if np.any(norm <= 1e-12):
        raise InvalidInputError("normal: expected a non-zero vector, got a zero normal")
    return _capsule_halfspace(pp, qq, ra, pt, nn / norm)
