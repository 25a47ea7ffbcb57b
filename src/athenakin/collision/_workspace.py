"""The clearance of one robot's bodies, pose after pose: tables and buffers built once (private).

:func:`athenakin.collision.clearance` is the batch function: it checks its arguments,
builds its pair tables and places the bodies from the forward kinematics on every call.
A control loop checks one pose per cycle, of one robot, against one environment: a
:class:`ClearanceWorkspace` holds what depends only on the bodies and the obstacles
(the pair tables, the index arrays, the radii, the capsule buffer with the fixed
obstacles already in it) and evaluates the body segments of a pose in one call of the
compiled capsule kernel (halfspaces in closed form, boxes and meshes through coal).

Boxes and meshes have a broad phase: each is first a sphere that contains it (centre and
radius from its corners or vertices), a lower bound of its distance to every body; only
the bodies whose bound is below ``exact_below`` meet the exact (coal) distance. Columns
of a box or mesh hold the exact distance below ``exact_below`` and a lower bound above
it (:attr:`ClearanceWorkspace.exact`), so that the least clearance is exact wherever it
is below ``exact_below``.

Carried bounds (``evaluate(since=...)``). From one cycle to the next most pairs stay far
apart, and their exact distance is not needed: below ``exact_below`` every distance must
be exact, above it a lower bound will do. A capsule's points are convex combinations of
its two end points, so where each end point of a body moves by at most ``m`` the whole
segment moves by at most ``m`` pointwise; the distance between two sets changes by at
most the sum of their largest displacements (it is 1-Lipschitz in each), and the radii
do not change. So ``d_now >= d_then - m_i - m_j`` for a body pair, ``d_then - m_i`` for a
body and a fixed obstacle, where ``d_then`` is the pair's exact distance at an earlier
evaluation or a lower bound of it, and ``m_i`` the displacement of body ``i``'s end points
from that evaluation's segments to the current ones (not summed over the cycles between:
the bound is the direct one). A column whose bound is at least ``exact_below`` keeps the
bound, with no witness points; every other column is evaluated exactly. Where a bound
is carried the true distance is above ``exact_below`` too, so the least clearance stays
exact wherever it is below ``exact_below``, and a lower bound above it. This is the
profile's saving: with ``Bodies.default`` and three obstacles (92 columns) the capsule
kernel over every column was 4-5 us of the teleoperation guard's 10 us a cycle
(:mod:`athenakin.teleop._guard`), and only the few pairs within the exact band of the
floor need it.
"""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._backend import resolve_backend
from .._mechanism import BODIES
from .._typing import FloatArray
from ..errors import InvalidInputError
from ._bodies import Bodies
from ._environment import Environment

__all__ = ["ClearanceWorkspace"]

def _halfspace_numpy(seg: FloatArray, rad: FloatArray, body: NDArray[np.intp],
                     point: FloatArray, normal: FloatArray, dist: FloatArray,
                     wit: FloatArray, c0: int, rows: NDArray[np.intp]) -> None:
    """Halfspace columns ``c0 + rows`` in numpy (``_distance._capsule_halfspace``).

    The kernel's reference; ``body``, ``point``, ``normal`` are those rows' entries.
    """
    from ._distance import _capsule_halfspace

    for k in range(len(body)):
        i = int(body[k])
        d, w = _capsule_halfspace(seg[i, 0], seg[i, 1], float(rad[i]), point[k], normal[k])
        dist[c0 + rows[k]] = d
        wit[c0 + rows[k]] = w


class ClearanceWorkspace:
    """The clearance of one pose's body segments, every table built once (owns its buffers).

    Parameters
    ----------
    bodies : Bodies
        The robot's capsules.
    environment : Environment, optional
        Obstacles (default none).
    backend : {"auto", "numpy", "numba"}, keyword-only
        The capsule pairs through the compiled kernel (``"auto"``: where numba imports)
        or the numpy reference.
    exact_below : float, keyword-only
        A box or mesh obstacle gets its exact (coal) distance to a body whose broad-phase
        bound is below this, m (default ``inf``: always exact).

    Attributes
    ----------
    pairs : tuple of (str, str)
        The name pair of every column: the body pairs of :attr:`Bodies.pairs`, then
        ``(body, obstacle)`` for the spheres and capsules, the halfspaces, the boxes and
        meshes (each obstacle's bodies in table order). Not the column order of
        :func:`~athenakin.collision.clearance`: look pairs up by name.
    body : ndarray of intp, shape (n_pairs, 2)
        Index into ``BODIES`` of each column's two solids (-1: an obstacle).
    distances : ndarray, shape (n_pairs,)
        The signed distances of the last :meth:`evaluate`, m (overwritten by the next).
    witness_points : ndarray, shape (n_pairs, 2, 3)
        Their witness points (first solid, second solid), base frame, m; NaN where a
        bound was carried.
    exact : ndarray of bool, shape (n_pairs,)
        False where the last :meth:`evaluate` left a lower bound (a box or mesh's
        bounding sphere, or a bound carried from ``since``).
    """

    def __init__(self, bodies: Bodies, environment: Environment | None = None, *,
                 backend: str = "auto", exact_below: float = math.inf) -> None:
        if not isinstance(bodies, Bodies):
            raise TypeError(f"bodies: expected athenakin.collision.Bodies, got "
                            f"{type(bodies).__name__}")
        env = Environment() if environment is None else environment
        if not isinstance(env, Environment):
            raise TypeError(f"environment: expected athenakin.collision.Environment or None, "
                            f"got {type(env).__name__}")
        self.bodies, self.environment = bodies, env
        self.compiled = resolve_backend(backend)
        self.exact_below = float(exact_below)
        nb = len(BODIES)
        rad = list(bodies.radii)
        fixed: list[tuple[Any, Any]] = []
        names = list(bodies.pairs)
        ij = [tuple(p) for p in bodies.pair_index.tolist()]
        body = [tuple(p) for p in bodies.pair_index.tolist()]
        half: list[tuple[int, Any, Any]] = []
        half_names: list[tuple[str, str]] = []
        coal_rows: list[tuple[int, Any, int]] = []     # (proxy column, obstacle, body)
        for o in env.obstacles:
            idx = [i for i, b in enumerate(BODIES) if b not in o.allow]
            if o.kind == "halfspace":
                for i in idx:
                    half.append((i, o.point, o.normal))
                    half_names.append((BODIES[i], o.name))
                continue
            if o.kind in ("sphere", "capsule"):
                a, b = (o.center, o.center) if o.kind == "sphere" else (o.a, o.b)
                r = o.radius
            else:                                 # box / mesh: a bounding sphere first
                a, r = _bounding_sphere(o)  # type: ignore[assignment]
                b = a
            s = nb + len(fixed)
            fixed.append((a, b))
            rad.append(float(r))
            for i in idx:
                if o.kind in ("box", "mesh"):
                    coal_rows.append((len(ij), o, i))
                ij.append((i, s))
                names.append((BODIES[i], o.name))
                body.append((i, -1))
        self._nc = len(ij)                         # capsule-kernel columns
        self._nh = len(half)
        names.extend(half_names)
        body.extend((h[0], -1) for h in half)
        self.pairs = tuple(names)
        self.body = np.array(body, dtype=np.intp).reshape(-1, 2)
        self.body.setflags(write=False)
        self._solids = np.zeros((1, nb + len(fixed), 2, 3))
        for k, (a, b) in enumerate(fixed):
            self._solids[0, nb + k, 0] = a
            self._solids[0, nb + k, 1] = b
        self._seg = self._solids[0, :nb]
        self._radii = np.array(rad, dtype=np.float64)
        self._ij = np.array(ij, dtype=np.intp).reshape(-1, 2)
        self._hb = np.array([h[0] for h in half], dtype=np.intp)
        self._hp = np.array([h[1] for h in half], dtype=np.float64).reshape(-1, 3)
        self._hn = np.array([h[2] for h in half], dtype=np.float64).reshape(-1, 3)
        self._coal = [(c, o, i) for c, o, i in coal_rows]
        self._coal_cols = np.array([c for c, _, _ in coal_rows], dtype=np.intp)
        self._shapes: dict[str, Any] = {}
        if coal_rows:
            from ._coal import coal_shape

            for _, o, _ in coal_rows:
                if o.name not in self._shapes:
                    self._shapes[o.name] = coal_shape(o)
        self._kernel: Any = None
        if self.compiled:
            from ._kernels import workspace_into

            self._kernel = workspace_into
        self._buffers()

    def _buffers(self) -> None:
        """Make the buffers of one workspace (its twins share the tables, not these)."""
        P, nb = len(self.pairs), len(BODIES)
        self.distances = np.empty(P)
        self.witness_points = np.empty((P, 2, 3))
        self.exact = np.ones(P, dtype=bool)
        self._at = np.full((nb, 2, 3), math.nan)   # the segments of the last evaluation
        self._move = np.zeros(nb)
        self._evaluated = False
        self._since: ClearanceWorkspace | None = None
        self._args = self._kernel_args(None)
        self._args_since = self._args

    def twin(self) -> ClearanceWorkspace:
        """A workspace of the same tables with its own buffers (a ``since`` for this one).

        Returns
        -------
        ClearanceWorkspace
            Not yet evaluated; its segment buffer holds this one's segments.
        """
        out = copy.copy(self)
        out._solids = self._solids.copy()
        out._seg = out._solids[0, :len(BODIES)]
        out._buffers()
        return out

    def __len__(self) -> int:
        return len(self.pairs)

    @property
    def segments(self) -> FloatArray:
        """The body-segment buffer, shape (n_bodies, 2, 3), m: write a pose's segments here."""
        return self._seg

    def evaluate(self, segments: FloatArray | None = None, *,
                 since: ClearanceWorkspace | None = None) -> tuple[float, int]:
        """Distances of every pair for body ``segments`` (default: :attr:`segments` as written).

        Parameters
        ----------
        segments : ndarray, shape (n_bodies, 2, 3), optional
            End points of every body of ``BODIES``, base frame, m; copied into the buffer.
        since : ClearanceWorkspace, optional, keyword-only
            A twin (:meth:`twin`) holding an earlier evaluation: a column whose bound
            carried from it (its distance there less the end-point displacements of the
            column's bodies since, the module docstring) is at least ``exact_below`` keeps
            that bound; the other columns are evaluated exactly. Default (or a twin not
            yet evaluated): every column evaluated.

        Returns
        -------
        min_distance : float
            The least signed distance, m (``inf`` with no pair; NaN with NaN segments);
            exact where below ``exact_below``, a lower bound above.
        column : int
            Its column in :attr:`pairs` (-1 with no pair).

        Raises
        ------
        InvalidInputError
            ``since`` is not a twin of this workspace, or is this workspace.
        """
        if segments is not None:
            self._seg[...] = segments
        if since is not None and since is not self._since:
            if since._ij is not self._ij or since is self:
                raise InvalidInputError("since: expected a twin of this workspace (Clearance"
                                        "Workspace.twin()) holding an earlier evaluation, got "
                                        "another workspace" if since is not self else
                                        "since: expected a twin of this workspace, got the "
                                        "workspace itself")
            self._since = since
            self._args_since = self._kernel_args(since)
        carry = since is not None and since._evaluated
        dist = self.distances
        if self._kernel is not None:
            # the kernel's arguments built once per ``since`` (each call checks them all)
            k, need, d = self._kernel(*(self._args_since if carry else self._args))
            if need:
                self._narrow_phase()
                k = _argmin(dist)
                d = float(dist[k]) if k >= 0 else d
        else:
            self._evaluate_numpy(since if carry else None)
            k = _argmin(dist)
            d = float(dist[k]) if k >= 0 else math.inf
        self._evaluated = True
        if k < 0:
            return (math.nan if len(dist) and np.isnan(dist).any() else math.inf), -1
        return d, k

    def _kernel_args(self, since: ClearanceWorkspace | None) -> tuple:
        """The compiled kernel's arguments: bounds carried from ``since``, or none."""
        ref = self if since is None else since
        return (self._solids, self._radii, self._ij, self._hb, self._hp, self._hn,
                self._coal_cols, self.exact_below, self.distances, self.witness_points,
                self.exact, self._at, ref._at, ref.distances, self._move, since is not None)

    def _evaluate_numpy(self, since: ClearanceWorkspace | None) -> None:
        """The numpy reference of the compiled :meth:`evaluate` (the same columns)."""
        from ._distance import _capsule_capsule

        dist, wit, nc, nb = self.distances, self.witness_points, self._nc, len(BODIES)
        todo = np.ones(len(dist), dtype=bool)
        if since is not None:
            d = self._seg - since._at
            move = np.append(np.sqrt(np.einsum("ijk,ijk->ij", d, d)).max(axis=1), 0.0)
            a, b = self.body[:, 0], np.where(self.body[:, 1] < 0, nb, self.body[:, 1])
            with np.errstate(invalid="ignore"):
                bound = since.distances - move[a] - move[b]
                todo = ~(bound >= self.exact_below)
            dist[~todo] = bound[~todo]
            wit[~todo] = math.nan
        self.exact[...] = todo
        cols = np.flatnonzero(todo[:nc])
        if len(cols):
            S, ij, r = self._solids[0], self._ij[cols], self._radii
            with np.errstate(invalid="ignore"):
                d, w = _capsule_capsule(S[ij[:, 0], 0], S[ij[:, 0], 1], r[ij[:, 0]],
                                       S[ij[:, 1], 0], S[ij[:, 1], 1], r[ij[:, 1]])
            dist[cols] = d
            wit[cols] = w
        rows = np.flatnonzero(todo[nc:])
        if len(rows):
            _halfspace_numpy(self._seg, self._radii, self._hb[rows], self._hp[rows],
                             self._hn[rows], dist, wit, nc, rows)
        if self._coal:
            fresh = self.exact[self._coal_cols]
            self.exact[self._coal_cols] = False    # the bounding spheres' distances
            if (dist[self._coal_cols[fresh]] < self.exact_below).any():
                self._narrow_phase()
        self._at[...] = self._seg

    def _narrow_phase(self) -> None:
        """Exact (coal) distances of the boxes and meshes whose bound is below ``exact_below``.

        Their columns hold the bounding spheres' distances (``exact`` False) or a carried
        bound (at least ``exact_below``).
        """
        from ._coal import capsule_obstacle_distances

        dist, wit, exact = self.distances, self.witness_points, self.exact
        for c, o, i in self._coal:
            if dist[c] < self.exact_below:         # a carried bound never is
                d, w = capsule_obstacle_distances(self._seg[i:i + 1], float(self._radii[i]), o,
                                                  self._shapes[o.name])
                dist[c] = d[0]
                wit[c] = w[0]
                exact[c] = True


def _argmin(dist: FloatArray) -> int:
    """Column of the least distance, NaN never least (-1: none)."""
    if not len(dist):
        return -1
    d = np.where(np.isnan(dist), np.inf, dist)
    k = int(np.argmin(d))
    return k if d[k] < math.inf else -1


def _bounding_sphere(o: Any) -> tuple[FloatArray, float]:
    """A sphere (centre in the base frame, radius, m) that contains a box or mesh obstacle."""
    T = np.asarray(o.T_b_o, dtype=float)
    if o.kind == "box":
        return T[:3, 3].copy(), float(np.linalg.norm(o.half_extents))
    v = np.asarray(o.vertices, dtype=float) @ T[:3, :3].T + T[:3, 3]
    c = 0.5 * (v.min(axis=0) + v.max(axis=0))
    return c, float(np.sqrt(((v - c) ** 2).sum(axis=1)).max())
