"""Clearance: the signed distance of every checked pair of bodies and obstacles (private)."""

from __future__ import annotations

import dataclasses
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._backend import Backend, resolve_backend
from .._mechanism import BODIES, body_segments, mechanism_points
from .._typing import BoolArray, FloatArray, Int8Array
from .._validation import check_scalar
from ..design import Design, resolve_design
from ..errors import InvalidInputError
from ._bodies import Bodies, resolve_bodies
from ._distance import _capsule_capsule, _capsule_halfspace
from ._environment import Environment
from ._obstacle import Obstacle

__all__ = ["Clearance", "clearance", "segment_clearance", "capsule_distances", "MAX_MARGIN"]

#: Largest ``margin`` accepted, m.
MAX_MARGIN = 10.0
#: Capsule pairs evaluated together by the numpy path (bounded memory: about 0.3 KiB of
#: temporaries each, so about 80 MiB).
_NUMPY_PAIRS_PER_CHUNK = 1 << 18


@dataclasses.dataclass(frozen=True, eq=False)
class Clearance:
    """Signed distances of the checked pairs, for a batch of configurations.

    Attributes
    ----------
    pairs : tuple of (str, str)
        The checked pairs: first the body-body pairs of :attr:`Bodies.pairs`, then
        ``(body, obstacle)`` for every obstacle in order and every body it does not allow.
    distances : ndarray, shape (..., n_pairs)
        Signed minimum distance of each pair, m; negative is the penetration depth.
        NaN exactly where ``valid`` is False.
    witness_points : ndarray, shape (..., n_pairs, 2, 3)
        The nearest (deepest, when they overlap) point of each of the two solids, base frame,
        m. With ``clearance(..., witness=False)`` a read-only all-NaN view that holds no
        memory (``np.broadcast_to``).
    valid : ndarray of bool, shape (...)
        Whether the FK slot exists (the bodies are placed).
    reason : ndarray of int8, shape (...)
        :class:`~athenakin.errors.Reason` of an invalid slot, 0 where valid.
    min_distance : ndarray, shape (...)
        Smallest entry of ``distances`` (``+inf`` with no pair; NaN where invalid), m.
    closest_pair : ndarray of int, shape (...)
        Index into :attr:`pairs` of the smallest distance (-1 with no pair or where invalid).
    colliding : ndarray of bool, shape (...)
        ``min_distance < 0`` (False where invalid).
    near : ndarray of bool, shape (...)
        ``min_distance < margin`` (False where invalid): closer than the margin.
    margin : float
        The margin asked for, m.
    """

    pairs: tuple[tuple[str, str], ...]
    distances: FloatArray
    witness_points: FloatArray
    valid: BoolArray
    reason: Int8Array
    min_distance: FloatArray
    closest_pair: NDArray[np.intp]
    colliding: BoolArray
    near: BoolArray
    margin: float = 0.0

    def pair_index(self, a: str, b: str) -> int:
        """Index of the pair ``(a, b)`` (either order) in :attr:`pairs`.

        Parameters
        ----------
        a, b : str
            Names of two bodies, or of a body and an obstacle (:data:`athenakin.collision.BODIES`,
            :attr:`Obstacle.name`).

        Returns
        -------
        int
            Column of the pair in :attr:`distances` and :attr:`witness_points`.

        Raises
        ------
        InvalidInputError
            ``(a, b)`` is not a checked pair (the message lists those that are).
        """
        for k, p in enumerate(self.pairs):
            if p == (a, b) or p == (b, a):
                return k
        raise InvalidInputError(f"pair: ({a!r}, {b!r}) is not a checked pair; checked are "
                                f"{self.pairs}")

    def distance(self, a: str, b: str) -> FloatArray:
        """The distances of one pair, shape (...), m.

        Parameters
        ----------
        a, b : str
            As :meth:`pair_index`.

        Returns
        -------
        ndarray, shape (...)
            Signed distance, m (negative: penetration depth); NaN where the slot is invalid.

        Raises
        ------
        InvalidInputError
            ``(a, b)`` is not a checked pair.
        """
        return self.distances[..., self.pair_index(a, b)]

    def closest_names(self) -> NDArray[np.object_]:
        """``pairs[closest_pair]`` as an object array of (str, str) (None where -1), shape (...).

        Returns
        -------
        ndarray of object, shape (...)
            The ``(name, name)`` of the least distance of each item, None where no pair is
            checked or the slot is invalid.
        """
        out = np.empty(self.closest_pair.shape, dtype=object)
        for idx in np.ndindex(out.shape):
            k = int(self.closest_pair[idx])
            out[idx] = self.pairs[k] if k >= 0 else None
        return out


def _check_environment(environment: object) -> Environment:
    if environment is None:
        return Environment()
    if not isinstance(environment, Environment):
        raise TypeError(f"environment: expected athenakin.collision.Environment or None, got "
                        f"{type(environment).__name__}")
    return environment


def _check_margin(margin: object) -> float:
    m = check_scalar(margin, "margin", nonnegative=True)
    if m > MAX_MARGIN:
        raise InvalidInputError(f"margin: expected a distance in [0, {MAX_MARGIN:g}] m, got {m:g}")
    return m


def _pair_tables(bodies: Bodies, environment: Environment) -> tuple[
        tuple[tuple[str, str], ...], NDArray[np.intp],
        list[tuple[Obstacle, NDArray[np.intp]]]]:
    """Pair names, body-body index pairs, and per obstacle the indices of its bodies."""
    names = list(bodies.pairs)
    obs = []
    for o in environment.obstacles:
        idx = np.array([i for i, b in enumerate(BODIES) if b not in o.allow], dtype=np.intp)
        names.extend((BODIES[i], o.name) for i in idx)
        obs.append((o, idx))
    return tuple(names), bodies.pair_index, obs


def capsule_distances(solids: FloatArray, radii: FloatArray,
                      ij: NDArray[np.intp], *, backend: Backend = "auto") -> FloatArray:
    """Signed distances of capsule pairs over a batch (the kernel where ``backend`` says so).

    Parameters
    ----------
    solids : ndarray, shape (n, n_solids, 2, 3)
        Segment end points of every capsule, per item, m.
    radii : ndarray, shape (n_solids,)
        Radii, m.
    ij : ndarray of intp, shape (n_pairs, 2)
        The capsules of each pair.
    backend : {"auto", "numpy", "numba"}, keyword-only
        The numba kernel or the numpy reference (:func:`athenakin._backend.resolve_backend`).

    Returns
    -------
    ndarray, shape (n, n_pairs)
        Signed distances, m (negative: penetration depth); NaN rows stay NaN. The kernel
        :func:`athenakin.collision._kernels.capsule_distances` and the numpy reference
        :func:`athenakin.collision._distance._capsule_capsule` agree to 1e-13 m (tested).
    """
    if resolve_backend(backend):
        from ._kernels import capsule_distances as kernel

        return kernel(np.ascontiguousarray(solids, dtype=np.float64),  # type: ignore[no-any-return]
                      np.asarray(radii, dtype=np.float64), np.asarray(ij, dtype=np.intp))
    A = solids[:, ij[:, 0]]
    B = solids[:, ij[:, 1]]
    with np.errstate(invalid="ignore"):
        d, _ = _capsule_capsule(A[..., 0, :], A[..., 1, :], radii[ij[:, 0]],
                               B[..., 0, :], B[..., 1, :], radii[ij[:, 1]])
    return np.asarray(d, dtype=np.float64)


@dataclasses.dataclass(frozen=True)
class _Columns:
    """Which engine computes each column of the distance table (private).

    Capsule-like solids are the bodies, then the sphere and capsule obstacles (``fixed``
    segments and ``radii``); ``capsules`` pairs them (indices over bodies + obstacles) for
    the columns ``capsule_cols``; ``halfspace`` lists ``(column, body, obstacle)``;
    ``coal`` lists ``(first column, obstacle, its bodies)`` of the meshes and boxes.
    """

    fixed: list[tuple[tuple[float, float, float], tuple[float, float, float]]]
    radii: list[float]
    capsules: list[tuple[int, int]]
    capsule_cols: list[int]
    halfspace: list[tuple[int, int, Obstacle]]
    coal: list[tuple[int, Obstacle, NDArray[np.intp]]]


def _columns(bb: NDArray[np.intp], obs: list[tuple[Obstacle, NDArray[np.intp]]]) -> _Columns:
    """The columns of the body-body pairs ``bb``, then of every obstacle's bodies in order."""
    prim_seg = []
    prim_rad = []
    for o, _ in obs:
        if o.kind == "sphere":
            prim_seg.append((o.center, o.center))
            prim_rad.append(o.radius)
        elif o.kind == "capsule":
            prim_seg.append((o.a, o.b))
            prim_rad.append(o.radius)
    nb = len(BODIES)
    # capsule pairs: (index of first solid, index of second solid) over bodies + primitives
    cap_pairs: list[tuple[int, int]] = [tuple(p) for p in bb.tolist()]  # type: ignore[misc]
    cap_cols = list(range(len(cap_pairs)))
    half_rows: list[tuple[int, int, Obstacle]] = []   # (column, body, obstacle)
    coal_rows: list[tuple[int, Obstacle, NDArray[np.intp]]] = []
    col = len(cap_pairs)
    k_prim = 0
    for o, idx in obs:
        if o.kind in ("sphere", "capsule"):
            for i in idx:
                cap_pairs.append((int(i), nb + k_prim))
                cap_cols.append(col)
                col += 1
            k_prim += 1
        elif o.kind == "halfspace":
            for i in idx:
                half_rows.append((col, int(i), o))
                col += 1
        else:
            coal_rows.append((col, o, idx))
            col += len(idx)
    return _Columns(prim_seg, prim_rad, cap_pairs, cap_cols, half_rows, coal_rows)


def segment_clearance(segments: FloatArray, valid: BoolArray,
                      bodies: Bodies, environment: Environment, *, compiled: bool,
                      witness: bool = True) -> tuple[tuple[tuple[str, str], ...],
                                                     FloatArray,
                                                     FloatArray | None]:
    """Distances and witness points from body segments (the core of :func:`clearance`).

    Parameters
    ----------
    segments : ndarray, shape (n, n_bodies, 2, 3)
        Flat batch of body segments (``body_segments``), m.
    valid : ndarray of bool, shape (n,)
    bodies, environment
    compiled : bool
        Use the numba kernel for the capsule pairs (else the numpy reference).
    witness : bool
        Also compute the witness points (else None is returned for them).

    Returns
    -------
    pairs, distances (n, n_pairs), witness_points (n, n_pairs, 2, 3) or None
    """
    names, bb, obs = _pair_tables(bodies, environment)
    n = segments.shape[0]
    P = len(names)
    # every row is computed (invalid rows hold NaN segments and give NaN), then invalid
    # rows are set to NaN: no gather / scatter copies of the large witness array
    dist = np.empty((n, P))
    wit = np.empty((n, P, 2, 3)) if witness else None
    rad = bodies.radius_array
    seg = segments
    cols = _columns(bb, obs)
    if cols.capsules:
        if cols.fixed:
            fixed = np.broadcast_to(np.array(cols.fixed, dtype=np.float64),
                                    (n, len(cols.fixed), 2, 3))
            solids = np.concatenate([seg, fixed], axis=1)
        else:
            solids = seg
        radii = np.concatenate([rad, np.array(cols.radii, dtype=np.float64)])
        ij = np.array(cols.capsules, dtype=np.intp).reshape(-1, 2)
        _capsule_columns(solids, radii, ij, cols.capsule_cols, dist, wit, compiled)
    for c, i, o in cols.halfspace:
        d, w = _capsule_halfspace(seg[:, i, 0], seg[:, i, 1], rad[i], np.array(o.point),
                                 np.array(o.normal))
        dist[:, c] = d
        if wit is not None:
            wit[:, c] = w
    if cols.coal:
        _coal_columns(seg, rad, valid, cols.coal, dist, wit)
    if not np.all(valid):
        dist[~valid] = np.nan
        if wit is not None:
            wit[~valid] = np.nan
    return names, dist, wit


def _capsule_columns(solids: FloatArray, radii: FloatArray,
                     ij: NDArray[np.intp], cap_cols: list[int], dist: FloatArray,
                     wit: FloatArray | None, compiled: bool) -> None:
    """Fill the capsule-capsule columns ``cap_cols`` of ``dist`` (and ``wit``) in place."""
    n = solids.shape[0]
    c0, c1 = cap_cols[0], cap_cols[-1] + 1
    contiguous = cap_cols == list(range(c0, c1))
    if compiled:
        from ._kernels import capsule_distances_into, capsule_pairs_into
        solids = np.ascontiguousarray(solids)
        if wit is None:
            if contiguous:
                capsule_distances_into(solids, radii, ij, dist[:, c0:c1])
            else:
                d = np.empty((n, len(ij)))
                capsule_distances_into(solids, radii, ij, d)
                dist[:, cap_cols] = d
        elif contiguous:
            capsule_pairs_into(solids, radii, ij, dist[:, c0:c1], wit[:, c0:c1])
        else:
            d = np.empty((n, len(ij)))
            w = np.empty((n, len(ij), 2, 3))
            capsule_pairs_into(solids, radii, ij, d, w)
            dist[:, cap_cols] = d
            wit[:, cap_cols] = w
        return
    # the numpy reference in chunks of rows: its temporaries (about 0.3 KiB a
    # pair) stay those of one chunk, whatever the batch
    step = max(1, _NUMPY_PAIRS_PER_CHUNK // len(ij))
    for r0 in range(0, n, step):
        rows = slice(r0, min(r0 + step, n))
        A = solids[rows][:, ij[:, 0]]
        B = solids[rows][:, ij[:, 1]]
        with np.errstate(invalid="ignore"):
            d, w = _capsule_capsule(A[..., 0, :], A[..., 1, :], radii[ij[:, 0]],
                                   B[..., 0, :], B[..., 1, :], radii[ij[:, 1]])
        dist[rows, cap_cols] = d
        if wit is not None:
            wit[rows, cap_cols] = w


def _coal_columns(seg: FloatArray, rad: FloatArray, valid: BoolArray,
                  coal_rows: list[tuple[int, Obstacle, NDArray[np.intp]]],
                  dist: FloatArray, wit: FloatArray | None) -> None:
    """Fill the columns of the coal obstacles (boxes, meshes) in place, valid rows only."""
    from ._coal import capsule_obstacle_distances, coal_shape
    iv = np.flatnonzero(valid)
    for c, o, idx in coal_rows:
        shape = coal_shape(o)
        for j, i in enumerate(idx):
            d, w = capsule_obstacle_distances(seg[iv, i], float(rad[i]), o, shape)
            dist[:, c + j] = np.nan
            dist[iv, c + j] = d
            if wit is not None:
                wit[:, c + j] = np.nan
                wit[iv, c + j] = w


def clearance(q: ArrayLike, T_b_e: ArrayLike, design: Design | None = None, *,
              slot: int | Literal["all"] = 0, bodies: Bodies | None = None,
              environment: Environment | None = None, margin: float = 0.0,
              witness: bool = True,
              backend: Literal["auto", "numpy", "numba"] = "auto") -> Clearance:
    """Signed distances between the robot's bodies, and to the obstacles, for a batch of poses.

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Actuators ``(q1, q2, q3)``, m.
    T_b_e : array-like, shape (..., 4, 4)
        RCM frame (set-up), broadcast with ``q``.
    design : Design, optional
        Default :meth:`Design.default`.
    slot : int or "all", keyword-only
        Forward-kinematics slot 0..15 (docs/conventions.md) that places the bodies, or
        ``"all"`` for a trailing batch axis of the 16 slots. Default 0.
    bodies : Bodies, keyword-only, optional
        Default :meth:`Bodies.default` of ``design``.
    environment : Environment, keyword-only, optional
        Obstacles; default none.
    margin : float, keyword-only
        Distance below which :attr:`Clearance.near` is set, m (default 0).
    witness : bool, keyword-only
        Compute the witness points (default). False makes
        :attr:`Clearance.witness_points` an all-NaN view, saves its memory (48 bytes per pair and
        item: 16 slots x 53 pairs x 100,000 configurations are 4 GB) and about a third
        of the time: for planners and design studies that need only the distances.
    backend : {"auto", "numpy", "numba"}, keyword-only
        The forward kinematics that places the bodies and the capsule pairs through the
        compiled kernels (``"auto"`` where numba imports) or the numpy reference; the
        same values to 1e-12 m.

    Returns
    -------
    Clearance
        Batch shape ``...`` (``(..., 16)`` with ``slot="all"``); an invalid FK slot is
        flagged (``valid`` False, distances NaN), never raised.

    Raises
    ------
    InvalidInputError
        A bad ``q``, ``T_b_e``, ``slot`` or ``margin``.
    TypeError
        ``bodies`` / ``environment`` of the wrong type.

    Examples
    --------
    >>> import numpy as np, athenakin as ak
    >>> from athenakin.collision import clearance
    >>> c = clearance([-0.1, 0.1, 0.4], ak.robot.default_rcm_frame(), slot=0)
    >>> c.distances.shape == (len(c.pairs),)
    True
    """
    design = resolve_design(design)
    bodies = resolve_bodies(bodies, design)
    environment = _check_environment(environment)
    m = _check_margin(margin)
    if not isinstance(witness, bool):
        raise TypeError(f"witness: expected a bool, got {type(witness).__name__}")
    compiled = resolve_backend(backend)
    pts = mechanism_points(q, T_b_e, design, slot=slot, geometry=bodies.geometry,
                           backend=backend)
    segs = body_segments(pts)
    batch = pts.valid.shape
    flat = segs.reshape((-1,) + segs.shape[-3:])
    valid = pts.valid.reshape(-1)
    names, dist, wit = segment_clearance(flat, valid, bodies, environment, compiled=compiled,
                                         witness=witness)
    shape = batch + (len(names), 2, 3)
    return _result(names, dist.reshape(batch + dist.shape[1:]),
                   np.broadcast_to(np.nan, shape) if wit is None else wit.reshape(shape),
                   pts.valid, pts.reason, m)


def _result(names: tuple[tuple[str, str], ...], dist: FloatArray,
            wit: FloatArray, valid: BoolArray,
            reason: Int8Array,
            margin: float) -> Clearance:
    batch = valid.shape
    if len(names):
        k = np.argmin(np.where(valid[..., None], dist, np.inf), axis=-1)
        dmin = np.take_along_axis(dist, k[..., None], axis=-1)[..., 0]
    else:
        k = np.zeros(batch, dtype=np.intp)
        dmin = np.full(batch, np.inf)
    dmin = np.where(valid, dmin, np.nan)
    closest = np.where(valid & (len(names) > 0), k, -1).astype(np.intp)
    with np.errstate(invalid="ignore"):
        colliding = valid & (dmin < 0)
        near = valid & (dmin < margin)
    return Clearance(pairs=names, distances=dist, witness_points=wit, valid=np.asarray(valid),
                     reason=np.asarray(reason), min_distance=dmin, closest_pair=closest,
                     colliding=colliding, near=near, margin=margin)
