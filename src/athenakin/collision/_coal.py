"""coal for the shapes without a closed form here: boxes and meshes (private).

coal (the successor of hpp-fcl, Pinocchio's collision library) is imported on first use;
without it a named ImportError says which extra to install.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._typing import FloatArray
from ._mesh import winding_numbers
from ._obstacle import Obstacle

__all__ = ["import_coal", "coal_shape", "capsule_transform", "capsule_obstacle_distances"]


def import_coal() -> Any:
    """The coal module, or an ImportError naming the ``[collision]`` extra."""
    try:
        import coal
    except ImportError:
        raise ImportError("box and mesh obstacles need coal: pip install "
                          "'athenakin[collision]' (coal and trimesh)") from None
    return coal


def coal_shape(obstacle: Obstacle) -> Any:
    """The coal collision geometry of a box or mesh obstacle (in its own frame)."""
    coal = import_coal()
    if obstacle.kind == "box":
        return coal.Box(*(2.0 * np.asarray(obstacle.half_extents)))
    if obstacle.kind == "mesh":
        model = coal.BVHModelOBBRSS()
        model.beginModel(len(obstacle.faces), len(obstacle.vertices))
        model.addVertices(np.ascontiguousarray(obstacle.vertices, dtype=np.float64))
        model.addTriangles(np.ascontiguousarray(obstacle.faces, dtype=np.int64))
        model.endModel()
        if obstacle.convex:
            model.buildConvexHull(True, "Qt")
            return model.convex
        return model
    raise ValueError(f"coal_shape: no coal shape for a {obstacle.kind}")  # pragma: no cover


def _transform(R: FloatArray, t: FloatArray) -> Any:
    coal = import_coal()
    return coal.Transform3s(np.ascontiguousarray(R), np.ascontiguousarray(t))


def capsule_transform(a: FloatArray, b: FloatArray) -> tuple[float, Any]:
    """Length and pose of coal's capsule frame (axis ``z``, centred) for the segment a-b."""
    d = b - a
    L = float(np.linalg.norm(d))
    z = d / L if L > 0 else np.array([0.0, 0.0, 1.0])
    ax = np.eye(3)[int(np.argmin(np.abs(z)))]
    x = np.cross(ax, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return L, _transform(np.stack([x, y, z], axis=1), 0.5 * (a + b))


def _capsule_frames(seg: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """:func:`capsule_transform` of every segment at once: lengths, rotations, centres.

    Rows with a NaN give NaN (the caller skips them).
    """
    a, b = seg[:, 0], seg[:, 1]
    d = b - a
    L = np.linalg.norm(d, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        z = np.where((L > 0)[:, None], d / np.where(L > 0, L, 1.0)[:, None],
                     np.array([0.0, 0.0, 1.0]))
    ax = np.eye(3)[np.argmin(np.abs(np.nan_to_num(z, nan=0.0)), axis=-1)]
    x = np.cross(ax, z)
    x /= np.linalg.norm(x, axis=-1, keepdims=True)
    y = np.cross(z, x)
    R = np.ascontiguousarray(np.stack([x, y, z], axis=-1))
    return L, R, np.ascontiguousarray(0.5 * (a + b))


def capsule_obstacle_distances(seg: FloatArray, radius: float,
                               obstacle: Obstacle,
                               shape: Any | None = None) -> tuple[FloatArray,
                                                                  FloatArray]:
    """Signed distances of capsules to a box or mesh obstacle, one coal call each.

    Parameters
    ----------
    seg : ndarray, shape (n, 2, 3)
        Capsule segments (rows with a NaN give NaN).
    radius : float
        Capsule radius, m.
    obstacle : Obstacle
        A box or a mesh.
    shape : coal geometry, optional
        :func:`coal_shape` of ``obstacle``, built once by the caller.

    Returns
    -------
    distance : ndarray, shape (n,)
    witness : ndarray, shape (n, 2, 3)
        Nearest points on the capsule and on the obstacle.
    """
    coal = import_coal()
    shape = coal_shape(obstacle) if shape is None else shape
    T_o = _transform(obstacle.T_b_o[:3, :3], obstacle.T_b_o[:3, 3])
    n = seg.shape[0]
    dist = np.full(n, np.nan)
    wit = np.full((n, 2, 3), np.nan)
    req = coal.DistanceRequest()
    req.enable_signed_distance = True
    L, R, centre = _capsule_frames(seg)
    for i in np.flatnonzero(np.all(np.isfinite(seg), axis=(1, 2))):
        T_c = coal.Transform3s(R[i], centre[i])
        cap = coal.Capsule(radius, L[i]) if L[i] > 0 else coal.Sphere(radius)
        res = coal.DistanceResult()
        d = coal.distance(cap, T_c, shape, T_o, req, res)
        dist[i] = d
        wit[i, 0] = res.getNearestPoint1()
        wit[i, 1] = res.getNearestPoint2()
    if obstacle.kind == "mesh" and obstacle.closed and not obstacle.convex:
        _inside_closed_mesh(seg, radius, obstacle, dist, wit)
    return dist, wit


def _inside_closed_mesh(seg: FloatArray, radius: float, obstacle: Obstacle,
                        dist: FloatArray, wit: FloatArray) -> None:
    """Make the distance of capsules wholly inside a closed mesh negative, in place.

    A capsule clear of the triangles (``d > 0``) lies wholly on one side of them: its
    first end point tells which (winding number, :func:`winding_numbers`). Inside, the
    distance becomes minus the depth of the capsule's deepest point below the nearest
    point of the triangles, along the line of the two nearest points (``u``, into the
    solid): the end point ``e`` farthest along ``u`` plus ``r u``, a point of the
    capsule's surface, is its witness; ``-(d + 2 r)`` for a ball, more for a capsule
    along ``u``.
    """
    clear = np.flatnonzero(np.isfinite(dist) & (dist > 0))
    if clear.size == 0:
        return
    R, t = obstacle.T_b_o[:3, :3], obstacle.T_b_o[:3, 3]
    x = (seg[clear, 0] - t) @ R                  # R^T (x - t), the mesh frame
    inside = np.abs(winding_numbers(x, obstacle.vertices, obstacle.faces)) > 0.5
    rows = clear[inside]
    if rows.size == 0:
        return
    v = wit[rows, 0] - wit[rows, 1]             # from the triangles into the solid
    u = v / np.linalg.norm(v, axis=-1, keepdims=True)
    p, q = seg[rows, 0], seg[rows, 1]
    far_q = np.einsum("ni,ni->n", q - p, u) > 0
    deep = np.where(far_q[:, None], q, p) + radius * u
    wit[rows, 0] = deep
    dist[rows] = -np.einsum("ni,ni->n", deep - wit[rows, 1], u)
