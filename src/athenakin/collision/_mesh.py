"""Triangle meshes of obstacles: loading, checking, closedness and winding numbers."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .._typing import FloatArray, IntArray
from ..errors import InvalidInputError

#: Most triangles of one mesh obstacle (checked after loading, before building the BVH).
MAX_MESH_FACES = 2_000_000


def load_geometry(path: Path, name: str, *, force_mesh: bool = True) -> Any:
    """A mesh (or point-cloud) file loaded by trimesh, unprocessed: the one file reader.

    Parameters
    ----------
    path : Path
        An STL, OBJ or PLY file.
    name : str
        The parameter or entry that named the file, first in every message.
    force_mesh : bool, keyword-only
        Load a triangle mesh (trimesh's ``force="mesh"``); False: whatever the file holds
        (a PLY of vertices only is a point cloud).

    Returns
    -------
    trimesh.Trimesh or trimesh.PointCloud

    Raises
    ------
    InvalidInputError
        Another suffix, a missing file, a file trimesh cannot load (named).
    ImportError
        trimesh is missing (the message names the extra).
    """
    try:
        import trimesh
    except ImportError:  # pragma: no cover - the extra is installed in CI
        raise ImportError("reading mesh files needs trimesh: pip install "
                          "'athenakin[collision]'") from None
    if path.suffix.lower() not in (".stl", ".obj", ".ply"):
        raise InvalidInputError(f"{name}: expected an STL, OBJ or PLY file, got "
                                f"{path.suffix or 'no extension'} ({str(path)!r})")
    if not path.is_file():
        raise InvalidInputError(f"{name}: mesh file {str(path)!r} does not exist")
    try:
        if force_mesh:
            return trimesh.load(str(path), process=False, force="mesh")
        return trimesh.load(str(path), process=False)
    except Exception as exc:  # trimesh raises many kinds on a bad file
        raise InvalidInputError(f"{name}: mesh file {str(path)!r} does not load "
                                f"({type(exc).__name__}: {exc})") from None


def _load_mesh(path: Path, scale: float, name: str) -> tuple[FloatArray,
                                                             IntArray]:
    """Vertices (n, 3) scaled to m and faces (m, 3) of a mesh file, checked."""
    mesh = load_geometry(path, name)
    V, F = _check_triangles(getattr(mesh, "vertices", np.zeros((0, 3))),
                            getattr(mesh, "faces", np.zeros((0, 3))),
                            f"mesh file {str(path)!r}", name=name)
    return V * scale, F


def _check_triangles(vertices: object, faces: object, what: str, *, name: str | None = None
                     ) -> tuple[FloatArray, IntArray]:
    """Vertices (n, 3), finite, and faces (m, 3), 0 < m <= MAX_MESH_FACES, indexing them.

    ``name`` (the parameter) starts the messages when given, else ``vertices`` /
    ``faces``; ``what`` says which mesh.
    """
    vn, fn = (name, name) if name else ("vertices", "faces")
    try:
        V = np.asarray(vertices, dtype=np.float64)
        F = np.asarray(faces)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{vn}: {what}: expected numeric arrays of vertices (n, 3) and "
                                f"faces (m, 3)") from None
    if F.dtype.kind not in "iu" and F.size:
        if F.dtype.kind != "f" or not np.all(np.isfinite(F)) or np.any(F != np.round(F)):
            raise InvalidInputError(f"{fn}: {what}: expected integer vertex indices")
    if V.ndim != 2 or V.shape[1:] != (3,) or F.ndim != 2 or F.shape[1:] != (3,) or len(F) == 0:
        raise InvalidInputError(f"{fn}: {what} holds no triangles (expected vertices of shape "
                                f"(n, 3) and faces of shape (m, 3), m > 0; got {V.shape} and "
                                f"{F.shape})")
    if len(F) > MAX_MESH_FACES:
        raise InvalidInputError(f"{fn}: {what} has {len(F)} triangles; expected at most "
                                f"{MAX_MESH_FACES}")
    if not np.all(np.isfinite(V)):
        raise InvalidInputError(f"{vn}: {what} has non-finite vertices")
    F = F.astype(np.int64)
    if F.min() < 0 or F.max() >= len(V):
        raise InvalidInputError(f"{fn}: {what} has faces that index missing vertices")
    return V, F


def closed_surface(vertices: FloatArray, faces: IntArray) -> bool:
    """Whether triangles close a solid: each directed edge once, its reverse once.

    That is a watertight, consistently oriented surface (trimesh's ``is_watertight``
    and ``is_winding_consistent`` together), the condition for an inside: the winding
    number (:func:`winding_numbers`) is then an integer off the surface. Vertices at
    the same coordinates are one vertex (an STL file repeats them per triangle).
    """
    F = np.asarray(faces, dtype=np.int64)
    if F.ndim != 2 or F.shape[1:] != (3,) or len(F) == 0:
        return False
    _, merged = np.unique(np.asarray(vertices, dtype=np.float64), axis=0,
                          return_inverse=True)
    F = merged.reshape(-1)[F]
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    if np.any(e[:, 0] == e[:, 1]):
        return False                       # a degenerate triangle
    n = int(max(F.max(), 0)) + 1
    key = e[:, 0] * n + e[:, 1]
    rev = e[:, 1] * n + e[:, 0]
    ks = np.sort(key)
    if np.any(ks[1:] == ks[:-1]):
        return False                       # a directed edge twice: inconsistent / non-manifold
    return bool(np.array_equal(ks, np.sort(rev)))


#: Triangle-point pairs evaluated together by :func:`winding_numbers` (memory bound).
_WINDING_BLOCK = 1 << 18


def winding_numbers(points: FloatArray, vertices: FloatArray,
                    faces: IntArray) -> FloatArray:
    """Generalized winding numbers of points about a triangle surface.

    ``w(x) = sum Omega_f(x) / (4 pi)`` over the triangles, ``Omega_f`` the signed solid
    angle of triangle ``f`` seen from ``x`` (Van Oosterom and Strackee's formula,
    ``tan(Omega / 2) = a . (b x c) / (|a||b||c| + (a.b)|c| + (b.c)|a| + (c.a)|b|)`` with
    ``a, b, c`` the corners relative to ``x``). For a closed surface it is +-1 inside
    (the sign of the orientation) and 0 outside, to rounding, off the surface.

    Parameters
    ----------
    points : ndarray, shape (n, 3)
        In the mesh frame, m.
    vertices : ndarray, shape (m, 3)
    faces : ndarray of int, shape (k, 3)

    Returns
    -------
    ndarray, shape (n,)

    Notes
    -----
    ``O(n k)`` work, in blocks of about ``2**18`` point-triangle pairs (bounded memory).
    """
    P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    tri = np.asarray(vertices, dtype=np.float64)[np.asarray(faces, dtype=np.int64)]
    out = np.zeros(P.shape[0])
    fstep = max(1, min(len(tri), _WINDING_BLOCK))
    pstep = max(1, _WINDING_BLOCK // fstep)
    for f0 in range(0, len(tri), fstep):
        T3 = tri[f0:f0 + fstep]
        for p0 in range(0, P.shape[0], pstep):
            x = P[p0:p0 + pstep, None, None, :]
            a, b, c = (T3[None, :, k] - x[:, :, 0] for k in range(3))
            la, lb, lc = (np.linalg.norm(v, axis=-1) for v in (a, b, c))
            num = np.einsum("pfi,pfi->pf", a, np.cross(b, c))
            den = (la * lb * lc + np.einsum("pfi,pfi->pf", a, b) * lc
                   + np.einsum("pfi,pfi->pf", b, c) * la + np.einsum("pfi,pfi->pf", c, a) * lb)
            out[p0:p0 + pstep] += np.arctan2(num, den).sum(axis=-1)
    return out / (2.0 * np.pi)
