"""Obstacles around the robot: the patient, the table, the ports (private).

An :class:`Environment` is a frozen tuple of :class:`Obstacle`; every builder method
returns a new environment, so calls chain::

    env = (Environment()
           .halfspace((0, 0, -0.2), (0, 0, 1), name="table")
           .sphere((0, 0, 0.3), 0.1, name="abdomen", allow=("instrument",)))

Shapes, all fixed in the base frame ``b`` (m):

- ``halfspace``: every ``x`` with ``normal . (x - point) <= 0`` (the normal points out of
  the solid, towards the free side);
- ``sphere``, ``capsule``: exact closed forms like the bodies';
- ``box`` (pose + half extents) and ``mesh`` (STL / OBJ / PLY file through trimesh):
  distances by coal (extra ``[collision]``).

Each obstacle is an :class:`Obstacle` (``_obstacle.py``, which checks its fields as the
builders here do); the triangles of a mesh are read and checked in ``_mesh.py``.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._mechanism import BODIES
from .._output import naming_path
from .._toml import read_toml
from .._validation import check_keys, check_path
from ..errors import InvalidInputError
from ._mesh import MAX_MESH_FACES, _load_mesh, closed_surface, winding_numbers
from ._obstacle import (
    OBSTACLE_KINDS,
    Obstacle,
    _allow,
    _check_bool,
    _direction,
    _half_extents,
    _length,
    _pose,
    _unit,
    _vec3,
)

__all__ = ["Environment", "Obstacle", "OBSTACLE_KINDS", "MAX_OBSTACLES", "MAX_MESH_FACES",
           "OpenMeshWarning", "closed_surface", "winding_numbers"]

#: Most obstacles in one environment.
MAX_OBSTACLES = 1000


class OpenMeshWarning(UserWarning):
    """A mesh obstacle does not close a solid: only its surface is an obstacle."""


@dataclasses.dataclass(frozen=True)
class Environment:
    """The obstacles around the robot, built by chaining (each method returns a new one).

    Attributes
    ----------
    obstacles : tuple of Obstacle
        In the order they were added (the order of the obstacle pairs of a clearance).
    """

    obstacles: tuple[Obstacle, ...] = ()

    def __post_init__(self) -> None:
        if isinstance(self.obstacles, (str, bytes, Mapping)) or not isinstance(self.obstacles,
                                                                            Iterable):
            raise TypeError(f"obstacles: expected a tuple of Obstacle, got "
                            f"{type(self.obstacles).__name__}")
        try:
            obs = tuple(self.obstacles)
        except TypeError:
            raise TypeError(f"obstacles: expected a tuple of Obstacle, got "
                            f"{type(self.obstacles).__name__}") from None
        if len(obs) > MAX_OBSTACLES:
            raise InvalidInputError(f"environment: expected at most {MAX_OBSTACLES} obstacles, "
                                    f"got {len(obs)}")
        seen: set[str] = set()
        for o in obs:
            if not isinstance(o, Obstacle):
                raise TypeError(f"obstacles: expected Obstacle items, got {type(o).__name__}")
            if o.name in seen:
                raise InvalidInputError(f"name: obstacle name {o.name!r} used twice; names "
                                        f"must be unique")
            if o.name in BODIES:
                raise InvalidInputError(f"name: obstacle name {o.name!r} is a body name")
            seen.add(o.name)
        object.__setattr__(self, "obstacles", obs)

    def __len__(self) -> int:
        return len(self.obstacles)

    @property
    def names(self) -> tuple[str, ...]:
        """Obstacle names, in order."""
        return tuple(o.name for o in self.obstacles)

    def __getitem__(self, name: str) -> Obstacle:
        for o in self.obstacles:
            if o.name == name:
                return o
        raise InvalidInputError(f"name: no obstacle {name!r}; the environment has {self.names}")

    # --- builders -----------------------------------------------------------------------
    def _add(self, kind: str, name: object, allow: object, **kw: Any) -> Environment:
        if name is None:
            name = f"{kind}_{len(self.obstacles)}"
        if not isinstance(name, str):
            raise TypeError(f"name: expected a str, got {type(name).__name__}")
        if not name or not name.strip():
            raise InvalidInputError("name: expected a non-empty obstacle name")
        ob = Obstacle(kind=kind, name=name, allow=_allow(allow, "allow"),  # type: ignore[arg-type]
                      **kw)
        return Environment(self.obstacles + (ob,))

    def halfspace(self, point: ArrayLike, normal: ArrayLike, *, name: str | None = None,
                  allow: Iterable[str] = ()) -> Environment:
        """Add the solid ``{x : normal . (x - point) <= 0}`` (a floor, a table top, a wall).

        Parameters
        ----------
        point : array-like, shape (3,)
            A point of the boundary plane, m.
        normal : array-like, shape (3,)
            Outward normal (towards the free side); normalised here.
        name : str, keyword-only, optional
            Default ``"halfspace_<k>"``.
        allow : list of str, keyword-only
            Bodies that may cross it.

        Returns
        -------
        Environment
            A new environment with the obstacle last (this one is unchanged).

        Raises
        ------
        InvalidInputError
            A zero (or non-finite) normal, an unknown body in ``allow``, a name used twice.
        """
        p = _vec3(point, "point")
        n, norm = _direction(normal, "normal")
        return self._add("halfspace", name, allow, point=p, normal=_unit(n / norm, "normal"))

    def sphere(self, center: ArrayLike, radius: float, *, name: str | None = None,
               allow: Iterable[str] = ()) -> Environment:
        """Add a ball of ``radius`` (m, >= 0) about ``center`` (3,) (m).

        Parameters
        ----------
        center : array-like, shape (3,)
            Centre, base frame, m.
        radius : float
            m, >= 0.
        name : str, keyword-only, optional
            Default ``"sphere_<k>"``.
        allow : list of str, keyword-only
            Bodies that may cross it.

        Returns
        -------
        Environment
            A new environment with the obstacle last (this one is unchanged).

        Raises
        ------
        InvalidInputError
            A non-finite centre, a negative radius, an unknown body in ``allow``, a name used
            twice.
        """
        return self._add("sphere", name, allow, center=_vec3(center, "center"),
                         radius=_length(radius, "radius"))

    def capsule(self, a: ArrayLike, b: ArrayLike, radius: float, *, name: str | None = None,
                allow: Iterable[str] = ()) -> Environment:
        """Add every point within ``radius`` (m, >= 0) of the segment ``a``-``b`` (m).

        Parameters
        ----------
        a, b : array-like, shape (3,)
            Ends of the segment, base frame, m.
        radius : float
            m, >= 0.
        name : str, keyword-only, optional
            Default ``"capsule_<k>"``.
        allow : list of str, keyword-only
            Bodies that may cross it.

        Returns
        -------
        Environment
            A new environment with the obstacle last (this one is unchanged).

        Raises
        ------
        InvalidInputError
            A non-finite end, a negative radius, an unknown body in ``allow``, a name used twice.
        """
        return self._add("capsule", name, allow, a=_vec3(a, "a"), b=_vec3(b, "b"),
                         radius=_length(radius, "radius"))

    def box(self, T_b_box: ArrayLike, half_extents: ArrayLike, *, name: str | None = None,
            allow: Iterable[str] = ()) -> Environment:
        """Add a box (distances by coal).

        Parameters
        ----------
        T_b_box : array-like, shape (4, 4) or (3,)
            Pose of the box frame in the base frame, or only its centre (axes = base axes).
        half_extents : array-like, shape (3,)
            Half sizes along the box axes, m (> 0).
        name : str, keyword-only, optional
            Default ``"box_<k>"``.
        allow : list of str, keyword-only
            Bodies that may cross it.

        Returns
        -------
        Environment
            A new environment with the obstacle last (this one is unchanged).

        Raises
        ------
        InvalidInputError
            A bad pose, a half size that is not positive, an unknown body in ``allow``, a
            name used twice.
        """
        T = _pose(T_b_box, "T_b_box")
        return self._add("box", name, allow, T_b_o=T, half_extents=_half_extents(half_extents))

    def mesh(self, path: str | Path, *, T_b_mesh: ArrayLike | None = None, scale: float = 1.0,
             convex: bool = False, name: str | None = None,
             allow: Iterable[str] = ()) -> Environment:
        """Add a triangle mesh read from an STL, OBJ or PLY file (trimesh; distances by coal).

        Parameters
        ----------
        path : str or Path
            The file.
        T_b_mesh : array-like, shape (4, 4) or (3,), keyword-only, optional
            Pose (or offset) of the mesh frame in the base frame; default identity.
        scale : float, keyword-only
            File units to metres (0.001 for millimetres). Default 1.
        convex : bool, keyword-only
            Use the convex hull: signed distances with penetration depth. Default False:
            the triangles. A closed mesh (:attr:`Obstacle.closed`) is then a solid: a
            body that touches its triangles is at distance <= 0, a body wholly inside
            it at minus the depth of its deepest point below the nearest point of the
            triangles (at least ``d + 2 r``, ``d`` from its surface to the triangles,
            ``r`` its radius). An open mesh is a surface only, with an
            :class:`OpenMeshWarning`.
        name : str, keyword-only, optional
            Default the file's stem.
        allow : list of str, keyword-only
            Bodies that may cross it.

        Returns
        -------
        Environment
            A new environment with the obstacle last (this one is unchanged).

        Raises
        ------
        InvalidInputError
            The file does not exist, is not STL/OBJ/PLY, does not load or holds no
            triangles.
        """
        p = check_path(path, "path")
        s = _length(scale, "scale", positive=True)
        _check_bool(convex, "convex")
        T = np.eye(4) if T_b_mesh is None else _pose(T_b_mesh, "T_b_mesh")
        V, F = _load_mesh(p, s, "path")
        env = self._add("mesh", p.stem if name is None else name, allow, T_b_o=T,
                        path=str(path), scale=s, convex=convex, vertices=V, faces=F)
        ob = env.obstacles[-1]
        if not convex and not ob.closed:
            warnings.warn(f"mesh {ob.name!r} ({str(path)!r}) is open (not every edge joins "
                          f"two consistently oriented triangles): a body wholly inside it "
                          f"is not detected, only a body that touches its triangles; close "
                          f"it, or pass convex=True for its convex hull", OpenMeshWarning,
                          stacklevel=2)
        return env

    # --- TOML ---------------------------------------------------------------------------
    def to_toml_table(self) -> dict[str, Any]:
        """``{"obstacle": [table, ...]}``, the ``[[environment.obstacle]]`` array.

        Returns
        -------
        dict of str -> list of dict
            One table per obstacle, in order (:meth:`Obstacle.to_toml_table`).
        """
        return {"obstacle": [o.to_toml_table() for o in self.obstacles]}

    def to_toml(self) -> str:
        """TOML text with ``[[environment.obstacle]]`` tables that :meth:`from_toml` reads.

        Returns
        -------
        str
        """
        import tomli_w

        return tomli_w.dumps({"environment": self.to_toml_table()})

    def write_toml(self, path: str | Path, *, overwrite: bool = False) -> Path:
        """Write :meth:`to_toml` to ``path`` (refuses to replace a file unless ``overwrite``).

        Parameters
        ----------
        path : str or Path
            The file to write.
        overwrite : bool, keyword-only
            Replace an existing file (default False: refuse).

        Returns
        -------
        Path
            ``path``.

        Raises
        ------
        FileExistsError
            ``path`` exists and ``overwrite`` is False.
        OSError
            The file cannot be written (named).
        """
        p = check_path(path, "path")
        text = self.to_toml()
        with naming_path(p), open(p, "w" if overwrite else "x", encoding="utf-8") as fh:
            fh.write(text)                 # ENOSPC on write / close names the file
        return p

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], *,
                     base_dir: str | Path | None = None) -> Environment:
        """Read an ``environment`` table (``obstacle = [ {...}, ... ]``).

        Mesh paths that are relative are taken relative to ``base_dir`` (the TOML
        file's folder) when given.

        Parameters
        ----------
        data : mapping
            The table: ``obstacle``, a list of tables with ``kind`` (``halfspace``,
            ``sphere``, ``capsule``, ``box``, ``mesh``), ``name``, the shape's keys (m,
            base frame) and ``allow``.
        base_dir : str or Path, keyword-only, optional
            Folder of relative mesh paths.

        Returns
        -------
        Environment

        Raises
        ------
        TypeError
            ``data`` is not a table.
        InvalidInputError
            An unknown key or kind, or a bad obstacle (named by its position).
        """
        if not isinstance(data, Mapping):
            raise TypeError(f"data: expected the environment table, got {type(data).__name__}")
        check_keys(data, "environment", ("obstacle",))
        items = data.get("obstacle", [])
        if not isinstance(items, list):
            raise InvalidInputError(f"environment.obstacle: expected an array of tables, got "
                                    f"{type(items).__name__}")
        env = cls()
        keys = {"halfspace": ("point", "normal"), "sphere": ("center", "radius"),
                "capsule": ("a", "b", "radius"), "box": ("T_b_box", "half_extents"),
                "mesh": ("path", "T_b_mesh", "scale", "convex")}
        for k, t in enumerate(items):
            what = f"environment.obstacle[{k}]"
            if not isinstance(t, Mapping):
                raise InvalidInputError(f"{what}: expected a table, got {type(t).__name__}")
            kind = t.get("kind")
            if kind not in keys:
                raise InvalidInputError(f"{what}.kind: expected one of {OBSTACLE_KINDS}, got "
                                        f"{kind!r}")
            check_keys(t, f"{what} (a {kind})", sorted({"kind", "name", "allow", *keys[kind]}))
            need = [x for x in keys[kind] if x not in t and kind != "mesh"] + (
                ["path"] if kind == "mesh" and "path" not in t else [])
            if need:
                raise InvalidInputError(f"{what}: missing key(s) {need} of a {kind}")
            kw = {x: t[x] for x in keys[kind] if x in t}
            if kind == "mesh":
                mp = Path(kw.pop("path"))
                if base_dir is not None and not mp.is_absolute():
                    kw_path: str | Path = Path(base_dir) / mp
                else:
                    kw_path = mp
                try:
                    env = env.mesh(kw_path, name=t.get("name"), allow=t.get("allow", ()), **kw)
                except (InvalidInputError, TypeError) as exc:
                    raise InvalidInputError(f"{what}: {exc}") from None
                # keep the path as written in the file
                obs = env.obstacles[:-1] + (dataclasses.replace(env.obstacles[-1],
                                                                path=str(mp)),)
                env = Environment(obs)
                continue
            try:
                env = getattr(env, kind)(*kw.values(), name=t.get("name"),
                                         allow=t.get("allow", ()))
            except (InvalidInputError, TypeError) as exc:
                raise InvalidInputError(f"{what}: {exc}") from None
        return env

    @classmethod
    def from_toml(cls, path: str | Path) -> Environment:
        """Read the ``[[environment.obstacle]]`` tables of a TOML file (empty if none).

        Parameters
        ----------
        path : str or Path
            A TOML file; relative mesh paths are taken from its folder.

        Returns
        -------
        Environment

        Raises
        ------
        OSError
            The file cannot be read.
        InvalidInputError
            Not TOML, or a bad obstacle; the message starts with the file name.
        """
        p = check_path(path, "path")
        data = read_toml(p, what="environment file")
        try:
            return cls.from_mapping(data.get("environment", {}), base_dir=p.parent)
        except (InvalidInputError, TypeError) as exc:
            raise InvalidInputError(f"{path}: {exc}") from None
