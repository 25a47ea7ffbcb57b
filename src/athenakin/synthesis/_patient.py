"""The patient of a set-up plan: closed surfaces by role, read from the files of a segmentation.

A :class:`Patient` holds, in the patient's frame ``p`` (the frame of the mesh files, m):

- ``skin``: the abdominal wall, a closed surface around the abdomen (a solid);
- ``target``: the organ to reach, a closed surface (its volume is sampled) or a point cloud;
- ``forbidden``: structures the instrument must not cross (vessels, organs), closed surfaces;
- ``table``: the operating table, a closed surface (optional);
- ``second_ports``: other ports and their instruments (:class:`SecondPort`), capsules the
  robot keeps clear of (optional).

Every closed-surface role must close a solid (each edge between two consistently
oriented triangles, :func:`athenakin.collision._mesh.closed_surface`): inside / outside
is then exact (the winding number, an integer off the surface) and an open mesh is
refused (:class:`OpenSurfaceError`). :func:`~athenakin.synthesis.phantom` (:mod:`._phantom`)
builds a parametric abdomen in code.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._output import write_text_atomic
from .._toml import read_toml
from .._typing import BoolArray, FloatArray, IntArray
from .._validation import check_array, check_count, check_keys, check_path, check_rng, check_scalar
from ..collision._mesh import (
    _check_triangles,
    _load_mesh,
    closed_surface,
    load_geometry,
    winding_numbers,
)
from ..errors import InvalidInputError
from ._errors import SynthesisError
from ._second_port import SecondPort, SecondPortError, check_second_ports, second_ports_from_tables

__all__ = ["ROLES", "PatientMesh", "Patient", "PatientFileError", "OpenSurfaceError",
           "write_patient", "MAX_TARGET_SAMPLES"]

#: Roles of the surfaces of a patient file.
ROLES = ("skin", "target", "forbidden", "table")
#: Most target samples drawn at once.
MAX_TARGET_SAMPLES = 1_000_000
#: Candidate points drawn per rejection round of the target's volume sampling.
_REJECTION_BLOCK = 1 << 16


class PatientFileError(SynthesisError, InvalidInputError):
    """A patient file cannot be read: not TOML, a missing or unknown key, a missing mesh."""


class OpenSurfaceError(SynthesisError, InvalidInputError):
    """A closed-surface role (skin, target, forbidden, table) has a mesh that is not watertight."""


@dataclasses.dataclass(frozen=True, eq=False)
class PatientMesh:
    """One closed surface of a patient, in the patient's frame.

    Attributes
    ----------
    name : str
        Unique in its patient (the obstacle's name in the clearance pairs).
    role : {"skin", "target", "forbidden", "table"}
    vertices : ndarray, shape (n, 3)
        Patient frame, m.
    faces : ndarray of int, shape (m, 3)
        Triangles, counter-clockwise seen from outside (outward normals).
    path : str
        The file it was read from ("" when built in code).

    Raises
    ------
    OpenSurfaceError
        The triangles do not close a solid.
    InvalidInputError
        Bad arrays, an unknown role or an empty name.
    """

    name: str
    role: str
    vertices: FloatArray
    faces: IntArray
    path: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise InvalidInputError(f"name: expected a non-empty mesh name, got {self.name!r}")
        if self.role not in ROLES:
            raise InvalidInputError(f"role: expected one of {ROLES}, got {self.role!r}")
        V, F = _check_triangles(self.vertices, self.faces, f"mesh {self.name!r}")
        if not closed_surface(V, F):
            where = f" ({self.path})" if self.path else ""
            raise OpenSurfaceError(
                f"{self.role} {self.name!r}{where}: the mesh is not watertight (not every "
                f"edge joins two consistently oriented triangles); a {self.role} must close "
                f"a solid so that inside and outside are defined: close the surface (fill "
                f"its holes) in the segmentation tool and export it again")
        V.flags.writeable = False
        F.flags.writeable = False
        object.__setattr__(self, "vertices", V)
        object.__setattr__(self, "faces", F)
        if np.sum(_signed_volumes(V, F)) < 0:
            raise OpenSurfaceError(f"{self.role} {self.name!r}: the triangles face inwards "
                                   f"(negative volume); flip their orientation")

    @property
    def volume(self) -> float:
        """Volume of the solid, m^3."""
        return float(np.sum(_signed_volumes(self.vertices, self.faces)))

    @property
    def bounds(self) -> FloatArray:
        """Axis-aligned bounds ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]``, shape (2, 3), m."""
        return np.stack([self.vertices.min(axis=0), self.vertices.max(axis=0)])

    def inside(self, points: ArrayLike) -> BoolArray:
        """Whether points lie inside the solid (winding number, exact off the surface).

        Parameters
        ----------
        points : array-like, shape (..., 3)
            Patient frame, m.

        Returns
        -------
        ndarray of bool, shape (...)
        """
        P = check_array(points, "points", (3,))
        flat = P.reshape(-1, 3)
        lo, hi = self.bounds
        box = np.all((flat >= lo) & (flat <= hi), axis=1)
        out = np.zeros(flat.shape[0], dtype=bool)
        if np.any(box):
            w = winding_numbers(flat[box], self.vertices, self.faces)
            out[box] = np.abs(w) > 0.5
        return out.reshape(P.shape[:-1])


def _signed_volumes(V: FloatArray, F: IntArray) -> FloatArray:
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    return np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0  # type: ignore[no-any-return]


@dataclasses.dataclass(frozen=True, eq=False)
class Patient:
    """A patient for set-up planning: skin, target, forbidden structures and table.

    Attributes
    ----------
    skin : PatientMesh
        The abdominal wall as a closed surface around the abdomen.
    target : PatientMesh or None
        The target organ as a closed surface (its volume is sampled); None with
        ``target_points``.
    target_points : ndarray, shape (n, 3), or None
        The target as a point cloud (patient frame, m); None with ``target``.
    forbidden : tuple of PatientMesh
        Structures the instrument must not cross.
    table : PatientMesh or None
        The operating table.
    name : str
    second_ports : tuple of SecondPort
        Other ports and their instruments, which the robot's bodies keep clear of.
    inner_forbidden : tuple of str
        The forbidden structures wholly inside the skin (set from the meshes).

    Raises
    ------
    InvalidInputError
        Both or neither of ``target`` / ``target_points``, a mesh in the wrong role, a
        name used twice (meshes and second ports), target points outside the skin.
    PortOffSkinError
        A second port off the skin or with its tip outside it.
    """

    skin: PatientMesh
    target: PatientMesh | None = None
    target_points: FloatArray | None = None
    forbidden: tuple[PatientMesh, ...] = ()
    table: PatientMesh | None = None
    name: str = ""
    second_ports: tuple[SecondPort, ...] = ()
    inner_forbidden: tuple[str, ...] = dataclasses.field(init=False, default=())

    def __post_init__(self) -> None:
        for field, role in (("skin", "skin"), ("target", "target"), ("table", "table")):
            m = getattr(self, field)
            if m is None and field != "skin":
                continue
            if not isinstance(m, PatientMesh) or m.role != role:
                raise InvalidInputError(f"{field}: expected a PatientMesh of role {role!r}, "
                                        f"got {m!r:.80}")
        forb = tuple(self.forbidden)
        for k, m in enumerate(forb):
            if not isinstance(m, PatientMesh) or m.role != "forbidden":
                raise InvalidInputError(f"forbidden[{k}]: expected a PatientMesh of role "
                                        f"'forbidden', got {m!r:.80}")
        object.__setattr__(self, "forbidden", forb)
        if (self.target is None) == (self.target_points is None):
            raise InvalidInputError("target: expected exactly one of target (a closed surface) "
                                    "or target_points (a point cloud)")
        if self.target_points is not None:
            P = check_array(self.target_points, "target_points", (3,))
            if P.ndim != 2 or P.shape[0] == 0:
                raise InvalidInputError(f"target_points: expected shape (n, 3), n > 0, got "
                                        f"{P.shape}")
            if not np.all(self.skin.inside(P)):
                raise InvalidInputError("target_points: every target point must lie inside "
                                        "the skin")
            P = P.copy()
            P.flags.writeable = False
            object.__setattr__(self, "target_points", P)
        ports = check_second_ports(self.skin.vertices, self.skin.faces, self.second_ports)
        object.__setattr__(self, "second_ports", ports)
        names = [m.name for m in self.meshes] + [sp.name for sp in ports]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise InvalidInputError(f"name: mesh names used twice: {dup}")
        if not isinstance(self.name, str):
            raise TypeError(f"name: expected str, got {type(self.name).__name__}")
        object.__setattr__(self, "inner_forbidden", tuple(
            m.name for m in forb if np.all(self.skin.inside(m.vertices))))

    @property
    def meshes(self) -> tuple[PatientMesh, ...]:
        """Every closed surface: skin, target (if a surface), forbidden, table."""
        out = [self.skin]
        if self.target is not None:
            out.append(self.target)
        out.extend(self.forbidden)
        if self.table is not None:
            out.append(self.table)
        return tuple(out)

    def mesh(self, name: str) -> PatientMesh:
        """The surface called ``name``.

        Parameters
        ----------
        name : str
            A mesh's name (``patient.toml``'s ``name``, default the file's stem).

        Returns
        -------
        PatientMesh
            That surface, in the patient's frame, m.

        Raises
        ------
        InvalidInputError
            The patient has no mesh of that name (the message lists them).
        """
        for m in self.meshes:
            if m.name == name:
                return m
        raise InvalidInputError(f"name: no mesh {name!r}; the patient has "
                                f"{[m.name for m in self.meshes]}")

    @property
    def target_centroid(self) -> FloatArray:
        """Centre of the target, shape (3,), m: the solid's centroid or the points' mean."""
        if self.target_points is not None:
            return self.target_points.mean(axis=0)  # type: ignore[no-any-return]
        assert self.target is not None
        V, F = self.target.vertices, self.target.faces
        vol = _signed_volumes(V, F)
        cen = (V[F[:, 0]] + V[F[:, 1]] + V[F[:, 2]]) / 4.0
        return (vol[:, None] * cen).sum(axis=0) / vol.sum()  # type: ignore[no-any-return]

    def target_samples(self, n: int, *, seed: int | np.random.Generator = 0) -> FloatArray:
        """``n`` points of the target, uniform in its volume (or drawn from its point cloud).

        A closed target is sampled by rejection in its bounding box (the winding number
        decides inside); a point cloud gives all its points when ``n`` is at least their
        number, else ``n`` of them drawn without replacement.

        Parameters
        ----------
        n : int
            1 to :data:`MAX_TARGET_SAMPLES`.
        seed : int or numpy Generator, keyword-only

        Returns
        -------
        ndarray, shape (n, 3), or (n_points, 3) for a smaller point cloud
            Patient frame, m.
        """
        n = check_count(n, "n", minimum=1, maximum=MAX_TARGET_SAMPLES)
        rng = check_rng(seed, "seed")
        if self.target_points is not None:
            P = self.target_points
            if n >= P.shape[0]:
                return P.copy()
            return P[np.sort(rng.choice(P.shape[0], n, replace=False))]
        assert self.target is not None
        lo, hi = self.target.bounds
        # the expected acceptance is the solid's share of its box: draw about what is missing
        share = max(self.target.volume / float(np.prod(hi - lo)), 1e-3)
        out: list[FloatArray] = []
        got = 0
        while got < n:
            m = min(_REJECTION_BLOCK, int(1.2 * (n - got) / share) + 64)
            X = lo + (hi - lo) * rng.random((m, 3))
            X = X[self.target.inside(X)]
            out.append(X)
            got += X.shape[0]
        return np.concatenate(out)[:n]

    @classmethod
    def from_toml(cls, path: str | Path) -> Patient:
        """Read a patient file and the meshes it names.

        The file::

            [patient]
            name = "phantom"
            scale = 1.0                # file units to m (0.001 for files in mm)

            [[patient.mesh]]
            role = "skin"              # skin, target, forbidden, table
            name = "skin"              # default: the file's stem
            path = "skin.stl"          # STL, PLY or OBJ, relative to this file

            [[patient.mesh]]
            role = "target"
            path = "target.ply"
            points = true              # the target as a point cloud (the file's vertices)

            [[patient.second_port]]    # any number (SecondPort), in the file's units
            name = "assistant"
            port = [-0.06, -0.10, 0.22]   # a point of the skin
            tip = [0.0, -0.06, 0.16]      # the point its instrument reaches
            radius = 0.005                # the shaft's radius
            outside = 0.2                 # the shaft's length outside the skin

        Exactly one ``skin`` and one ``target``; any number of ``forbidden``; at most one
        ``table``.

        Parameters
        ----------
        path : str or Path
            The ``patient.toml``; mesh paths in it are relative to its folder.

        Returns
        -------
        Patient
            The patient, its meshes in m in the patient's frame.

        Raises
        ------
        PatientFileError
            Not TOML, a missing or unknown key, a role given twice, a missing or
            unreadable mesh file (the message names the file and the entry).
        OpenSurfaceError
            A closed-surface role whose mesh is not watertight.
        SecondPortError
            A bad second port (:class:`PortOffSkinError` for one off the skin).
        """
        p = check_path(path, "path")
        try:
            data = read_toml(p, error=PatientFileError, what="patient file")
        except OSError as exc:
            raise PatientFileError(f"{p}: cannot read the patient file ({exc.strerror})") \
                from None
        table: Any = data.get("patient", data)
        try:
            return _patient_from_mapping(table, p.parent)
        except (OpenSurfaceError, SecondPortError) as exc:
            raise type(exc)(f"{p}: {exc}") from None
        except (InvalidInputError, TypeError) as exc:
            raise PatientFileError(f"{p}: {exc}") from None


def _patient_from_mapping(data: Mapping[str, Any], base: Path) -> Patient:
    if not isinstance(data, Mapping):
        raise PatientFileError(f"patient: expected a table, got {type(data).__name__}")
    check_keys(data, "patient", ("name", "scale", "mesh", "second_port"),
               error=PatientFileError)
    scale = check_scalar(data.get("scale", 1.0), "patient.scale", positive=True)
    items = data.get("mesh", [])
    if not isinstance(items, list) or not items:
        raise PatientFileError("patient.mesh: expected an array of [[patient.mesh]] tables")
    kw: dict[str, Any] = {"forbidden": [], "second_ports": second_ports_from_tables(
        data.get("second_port", []), "patient.second_port", scale=scale)}
    for k, t in enumerate(items):
        what = f"patient.mesh[{k}]"
        if not isinstance(t, Mapping):
            raise PatientFileError(f"{what}: expected a table, got {type(t).__name__}")
        check_keys(t, what, ("role", "name", "path", "points"), error=PatientFileError)
        role = t.get("role")
        if role not in ROLES:
            raise PatientFileError(f"{what}.role: expected one of {ROLES}, got {role!r}")
        if "path" not in t or not isinstance(t["path"], str):
            raise PatientFileError(f"{what}.path: expected the mesh file (a string)")
        f = Path(t["path"])
        f = f if f.is_absolute() else base / f
        name = t.get("name", f.stem)
        points = t.get("points", False)
        if not isinstance(points, bool) or (points and role != "target"):
            raise PatientFileError(f"{what}.points: expected true or false, and true only "
                                   f"for the target")
        if points:
            value: Any = _load_points(f, scale, f"{what}.path")
            field = "target_points"
        else:
            V, F = _load_mesh(f, scale, f"{what}.path")
            value = PatientMesh(name=name, role=role, vertices=V, faces=F, path=t["path"])
            field = role
        if role == "forbidden":
            kw["forbidden"].append(value)
            continue
        if field in kw or (role == "target" and ("target" in kw or "target_points" in kw)):
            raise PatientFileError(f"{what}: a second {role}; a patient has one")
        kw[field] = value
    if "skin" not in kw or ("target" not in kw and "target_points" not in kw):
        raise PatientFileError("patient.mesh: expected one skin and one target")
    return Patient(name=str(data.get("name", "")), **kw)


def _load_points(path: Path, scale: float, name: str) -> FloatArray:
    """The vertices of a point-cloud (or mesh) file, m."""
    geom = load_geometry(path, name, force_mesh=False)
    V = np.asarray(getattr(geom, "vertices", np.zeros((0, 3))), dtype=float)
    if V.ndim != 2 or V.shape[1:] != (3,) or V.shape[0] == 0 or not np.all(np.isfinite(V)):
        raise InvalidInputError(f"{name}: {str(path)!r} holds no finite points")
    return V * scale


# --- writing --------------------------------------------------------------------------------
def write_patient(patient: Patient, folder: str | Path, *, overwrite: bool = False) -> Path:
    """Write a patient as STL files and ``patient.toml`` naming them with their roles.

    Parameters
    ----------
    patient : Patient
    folder : str or Path
        Created if missing.
    overwrite : bool, keyword-only
        Replace files that exist (default: refuse).

    Returns
    -------
    pathlib.Path
        ``folder / "patient.toml"``, which :meth:`Patient.from_toml` reads back.

    Raises
    ------
    FileExistsError
        A file exists and ``overwrite`` is False.
    """
    import tomli_w
    import trimesh

    if not isinstance(patient, Patient):
        raise TypeError(f"patient: expected Patient, got {type(patient).__name__}")
    out = check_path(folder, "folder")
    out.mkdir(parents=True, exist_ok=True)
    entries: list[dict[str, Any]] = []
    files: list[tuple[Path, bytes]] = []
    for m in patient.meshes:
        f = out / f"{m.name}.stl"
        data = trimesh.Trimesh(m.vertices, m.faces, process=False).export(file_type="stl")
        files.append((f, data if isinstance(data, bytes) else str(data).encode()))
        entries.append({"role": m.role, "name": m.name, "path": f.name})
    if patient.target_points is not None:
        f = out / "target_points.ply"
        data = trimesh.PointCloud(patient.target_points).export(file_type="ply")
        files.append((f, data if isinstance(data, bytes) else str(data).encode()))
        entries.append({"role": "target", "name": "target", "path": f.name, "points": True})
    toml = out / "patient.toml"
    table: dict[str, Any] = {"scale": 1.0, "mesh": entries}
    if patient.second_ports:
        table["second_port"] = [sp.to_table() for sp in patient.second_ports]
    if patient.name:
        table = {"name": patient.name, **table}
    text = ("# A patient for `athenakin setup plan`: closed surfaces in the patient's frame, m\n"
            + tomli_w.dumps({"patient": table}))
    if not overwrite:
        exist = [str(f) for f, _ in files if f.exists()] + ([str(toml)] if toml.exists() else [])
        if exist:
            raise FileExistsError(f"folder: {exist[0]} exists; pass overwrite=True "
                                  f"(--force) to replace it")
    for f, data in files:
        write_text_atomic(f, data)
    write_text_atomic(toml, text)
    return toml


def ray_down(mesh: PatientMesh, xy: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Where vertical lines first meet a surface from above: point and outward normal.

    Parameters
    ----------
    mesh : PatientMesh
    xy : array-like, shape (n, 2)
        Patient-frame ``(x, y)`` of the lines, m.

    Returns
    -------
    point : ndarray, shape (n, 3)
        The highest intersection (largest ``z``), NaN where the line misses the surface.
    normal : ndarray, shape (n, 3)
        The unit outward normal of the triangle met (NaN where missed).
    """
    P = check_array(xy, "xy", (2,)).reshape(-1, 2)
    V, F = mesh.vertices, mesh.faces
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    e1, e2 = b[:, :2] - a[:, :2], c[:, :2] - a[:, :2]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    nrm = np.cross(b - a, c - a)
    nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
    out = np.full((P.shape[0], 3), np.nan)
    nout = np.full((P.shape[0], 3), np.nan)
    ok = np.abs(det) > 0
    for i, p in enumerate(P):
        d = p - a[:, :2]
        with np.errstate(invalid="ignore", divide="ignore"):
            u = (d[:, 0] * e2[:, 1] - d[:, 1] * e2[:, 0]) / det
            v = (e1[:, 0] * d[:, 1] - e1[:, 1] * d[:, 0]) / det
            hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1)
        if not np.any(hit):
            continue
        z = a[hit, 2] + u[hit] * (b[hit, 2] - a[hit, 2]) + v[hit] * (c[hit, 2] - a[hit, 2])
        j = int(np.argmax(z))
        out[i] = (p[0], p[1], z[j])
        nout[i] = nrm[np.flatnonzero(hit)[j]]
    return out, nout


def segment_crossings(a: ArrayLike, b: ArrayLike, mesh: PatientMesh) -> IntArray:
    """How many triangles of a surface each segment ``a``-``b`` crosses (Moller-Trumbore).

    Parameters
    ----------
    a, b : array-like, shape (n, 3)
        End points, patient frame, m.
    mesh : PatientMesh

    Returns
    -------
    ndarray of int, shape (n,)
        Triangles whose interior or boundary the closed segment meets (a segment in a
        triangle's plane meets none).
    """
    A = check_array(a, "a", (3,)).reshape(-1, 3)
    Bp = check_array(b, "b", (3,)).reshape(-1, 3)
    V, F = mesh.vertices, mesh.faces
    t0 = V[F[:, 0]]
    e1, e2 = V[F[:, 1]] - t0, V[F[:, 2]] - t0
    out = np.zeros(A.shape[0], dtype=np.int64)
    step = max(1, _REJECTION_BLOCK * 4 // max(1, len(F)))
    for r0 in range(0, A.shape[0], step):
        o = A[r0:r0 + step, None, :]
        d = Bp[r0:r0 + step, None, :] - o
        pv = np.cross(d, e2[None])
        det = np.einsum("nfi,fi->nf", pv, e1)
        with np.errstate(invalid="ignore", divide="ignore"):
            inv = 1.0 / det
            tv = o - t0[None]
            u = np.einsum("nfi,nfi->nf", tv, pv) * inv
            qv = np.cross(tv, e1[None])
            v = np.einsum("nfi,nfi->nf", d, qv) * inv
            t = np.einsum("fi,nfi->nf", e2, qv) * inv
            hit = ((det != 0) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t >= 0) & (t <= 1))
        out[r0:r0 + step] = hit.sum(axis=1)
    return out

