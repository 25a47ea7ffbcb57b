"""One obstacle around the robot and the checks of its fields (private).

An :class:`Obstacle` is a frozen description of one shape fixed in the base frame ``b``
(m): a halfspace, a sphere, a capsule, a box or a triangle mesh. It checks every field
as the :class:`~athenakin.collision.Environment` builders do, with the helpers here
that both use (points, lengths, unit vectors, poses, the bodies that may cross it).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from .._mechanism import BODIES
from .._typing import FloatArray, IntArray
from .._validation import check_array, check_scalar, check_transform
from ..errors import InvalidInputError
from ._mesh import _check_triangles, closed_surface

__all__ = ["Obstacle", "OBSTACLE_KINDS"]


#: Kinds of obstacle.
OBSTACLE_KINDS = ("halfspace", "sphere", "capsule", "box", "mesh")
_MAX_COORD = 1e3

ObstacleKind = Literal["halfspace", "sphere", "capsule", "box", "mesh"]


def _vec3(x: ArrayLike, name: str) -> tuple[float, float, float]:
    a = check_array(x, name, (3,))
    if a.shape != (3,):
        raise InvalidInputError(f"{name}: expected 3 numbers (m), got shape {a.shape}")
    if np.any(np.abs(a) > _MAX_COORD):
        raise InvalidInputError(f"{name}: expected coordinates within +/-{_MAX_COORD:g} m, got "
                                f"{a.tolist()}")
    return (float(a[0]), float(a[1]), float(a[2]))


def _length(x: object, name: str, *, positive: bool = False) -> float:
    v = check_scalar(x, name, nonnegative=not positive, positive=positive)
    if v > _MAX_COORD:
        raise InvalidInputError(f"{name}: expected a length within {_MAX_COORD:g} m, got {v:g}")
    return v


def _direction(x: ArrayLike, name: str) -> tuple[FloatArray, float]:
    """A non-zero finite vector of 3, shape (3,), and its norm."""
    n = np.array(check_array(x, name, (3,)), dtype=float).reshape(-1)
    if n.shape != (3,):
        raise InvalidInputError(f"{name}: expected 3 numbers, got shape {n.shape}")
    norm = float(np.linalg.norm(n))
    if not norm > 1e-12 or not math.isfinite(norm):
        raise InvalidInputError(f"{name}: expected a non-zero vector, got {n.tolist()}")
    return n, norm


def _unit(x: ArrayLike, name: str) -> tuple[float, float, float]:
    """A non-zero finite vector of 3 as a unit vector (kept as is when already unit)."""
    n, norm = _direction(x, name)
    if abs(norm - 1.0) > 1e-15:
        n = n / norm
    return (float(n[0]), float(n[1]), float(n[2]))


def _half_extents(x: ArrayLike) -> tuple[float, float, float]:
    """A box's half sizes along its axes: 3 positive lengths, m."""
    h = _vec3(x, "half_extents")
    if min(h) <= 0:
        raise InvalidInputError(f"half_extents: expected positive half sizes (m), got "
                                f"{list(h)}")
    return h


def _check_bool(x: object, name: str) -> bool:
    """``x`` if it is a bool, else a TypeError naming ``name``."""
    if not isinstance(x, bool):
        raise TypeError(f"{name}: expected a bool, got {type(x).__name__}")
    return x


def _allow(allow: object, name: str) -> tuple[str, ...]:
    if isinstance(allow, str):
        allow = (allow,)
    if isinstance(allow, bytes) or not isinstance(allow, Iterable):
        raise TypeError(f"{name}: expected a list of body names among {BODIES}, got "
                        f"{type(allow).__name__}")
    out = []
    for k, b in enumerate(allow):
        if not isinstance(b, str):
            raise TypeError(f"{name}[{k}]: expected a body name (str), got {type(b).__name__}")
        if b not in BODIES:
            raise InvalidInputError(f"{name}[{k}]: unknown body {b!r}; expected one of {BODIES}")
        if b not in out:
            out.append(b)
    return tuple(sorted(out, key=BODIES.index))


@dataclasses.dataclass(frozen=True, eq=False)
class Obstacle:
    """One obstacle of an :class:`Environment` (base frame, m).

    Attributes
    ----------
    kind : {"halfspace", "sphere", "capsule", "box", "mesh"}
    name : str
        Unique in its environment; the second name of its clearance pairs.
    allow : tuple of str
        Bodies that may cross it (never paired with it).
    point, normal : tuple of 3 floats
        ``halfspace``: a point of the boundary plane and the unit outward normal.
    center, radius : ``sphere``: centre and radius; ``capsule``: ``a``, ``b`` and radius.
    a, b : tuple of 3 floats
        ``capsule``: end points of its segment.
    T_b_o : ndarray, shape (4, 4)
        ``box`` / ``mesh``: pose of the shape's frame in the base frame.
    half_extents : tuple of 3 floats
        ``box``: half sizes along the box frame's axes.
    path : str
        ``mesh``: the file, as given.
    scale : float
        ``mesh``: factor from file units to metres (0.001 for a file in mm).
    convex : bool
        ``mesh``: use the convex hull (signed distance, penetration depth) instead of the
        triangles (a BVH; distance <= 0 once a body touches them; a body wholly inside a
        ``closed`` mesh is negative too).
    vertices, faces : ndarray
        ``mesh``: the loaded triangles (in the shape frame, m).
    closed : bool
        ``mesh``: the triangles close a solid (every edge between exactly two
        triangles, consistently oriented: :func:`closed_surface`). A body wholly
        inside a closed mesh is colliding (negative distance); set from ``faces``.
    """

    kind: ObstacleKind
    name: str
    allow: tuple[str, ...] = ()
    point: tuple[float, float, float] = (0.0, 0.0, 0.0)
    normal: tuple[float, float, float] = (0.0, 0.0, 1.0)
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    radius: float = 0.0
    a: tuple[float, float, float] = (0.0, 0.0, 0.0)
    b: tuple[float, float, float] = (0.0, 0.0, 0.0)
    T_b_o: FloatArray = dataclasses.field(default_factory=lambda: np.eye(4))
    half_extents: tuple[float, float, float] = (0.0, 0.0, 0.0)
    path: str = ""
    scale: float = 1.0
    convex: bool = False
    vertices: FloatArray = dataclasses.field(
        default_factory=lambda: np.zeros((0, 3)))
    faces: IntArray = dataclasses.field(
        default_factory=lambda: np.zeros((0, 3), dtype=np.int64))
    closed: bool = dataclasses.field(init=False, default=False, compare=False)

    def __post_init__(self) -> None:
        # the checks of the Environment builders, so that an Obstacle made directly is as
        # safe as one they make (a NaN or negative radius, a bad kind, an empty mesh)
        if not isinstance(self.kind, str) or self.kind not in OBSTACLE_KINDS:
            raise InvalidInputError(f"kind: expected one of {OBSTACLE_KINDS}, got "
                                    f"{self.kind!r:.80}")
        if not isinstance(self.name, str):
            raise TypeError(f"name: expected a str, got {type(self.name).__name__}")
        if not self.name.strip():
            raise InvalidInputError("name: expected a non-empty obstacle name")
        put = object.__setattr__
        put(self, "allow", _allow(self.allow, "allow"))
        for f in ("point", "center", "a", "b"):
            put(self, f, _vec3(getattr(self, f), f))
        put(self, "normal", _unit(self.normal, "normal"))
        put(self, "radius", _length(self.radius, "radius"))
        T = _pose(self.T_b_o, "T_b_o")
        put(self, "T_b_o", T)
        put(self, "half_extents", _half_extents(self.half_extents) if self.kind == "box"
            else _vec3(self.half_extents, "half_extents"))
        if not isinstance(self.path, str):
            raise TypeError(f"path: expected a str, got {type(self.path).__name__}")
        put(self, "scale", _length(self.scale, "scale", positive=True))
        _check_bool(self.convex, "convex")
        if self.kind == "mesh":
            V, F = _check_triangles(self.vertices, self.faces, f"mesh {self.name!r}")
            put(self, "vertices", V)
            put(self, "faces", F)
        put(self, "closed", self.kind == "mesh" and closed_surface(self.vertices, self.faces))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Obstacle):
            return NotImplemented
        for f in dataclasses.fields(self):
            x, y = getattr(self, f.name), getattr(other, f.name)
            if isinstance(x, np.ndarray):
                if x.shape != np.shape(y) or not np.array_equal(x, y):
                    return False
            elif x != y:
                return False
        return True

    def __hash__(self) -> int:
        # a subset of what __eq__ compares (the mesh arrays by shape): equal -> same hash
        return hash((self.kind, self.name, self.allow, self.point, self.normal, self.center,
                     self.radius, self.a, self.b, self.T_b_o.tobytes(), self.half_extents,
                     self.path, self.scale, self.convex, self.vertices.shape,
                     self.faces.shape))

    @property
    def is_primitive(self) -> bool:
        """Whether the exact closed forms handle it (halfspace, sphere, capsule)."""
        return self.kind in ("halfspace", "sphere", "capsule")

    def to_toml_table(self) -> dict[str, Any]:
        """The obstacle as a TOML table (``kind``, ``name``, shape keys, ``allow``).

        Returns
        -------
        dict of str -> TOML value
            Points in m in the base frame; a mesh's file path as given, with its pose and scale.
        """
        t: dict[str, Any] = {"kind": self.kind, "name": self.name}
        if self.kind == "halfspace":
            t.update(point=list(self.point), normal=list(self.normal))
        elif self.kind == "sphere":
            t.update(center=list(self.center), radius=self.radius)
        elif self.kind == "capsule":
            t.update(a=list(self.a), b=list(self.b), radius=self.radius)
        elif self.kind == "box":
            t.update(T_b_box=self.T_b_o.tolist(), half_extents=list(self.half_extents))
        else:
            t.update(path=self.path, T_b_mesh=self.T_b_o.tolist(), scale=self.scale,
                     convex=self.convex)
        if self.allow:
            t["allow"] = list(self.allow)
        return t


def _pose(T_or_center: ArrayLike, name: str) -> FloatArray:
    # check_array first: a ragged list, a str, an object is a named TypeError
    arr = check_array(T_or_center, name, (), allow_nonfinite=True)
    if arr.shape == (4, 4):
        T = check_transform(arr, name)
        if np.any(np.abs(T[:3, 3]) > _MAX_COORD):
            raise InvalidInputError(f"{name}: expected a position within +/-{_MAX_COORD:g} m")
        return np.array(T, dtype=np.float64)
    if arr.shape == (3,):
        T = np.eye(4)
        T[:3, 3] = _vec3(arr, name)
        return T
    raise InvalidInputError(f"{name}: expected a centre (3,) or a pose (4, 4), got shape "
                            f"{arr.shape}")
