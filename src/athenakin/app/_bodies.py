"""The robot's bodies as solids in the live app, the closest pair coloured.

The pure part (numpy only, testable without a browser): :func:`bodies_view` turns
the drawn solution (:class:`~athenakin.plot.RobotGeometry`) into one triangle mesh
per capsule of :class:`athenakin.collision.Bodies` and the least clearance with its
pair and witness points; :func:`capsule_mesh` triangulates one capsule;
:func:`clearance_html` is the read-out. :class:`BodiesLayer` sends them to a viser
scene (a checkbox shows or hides the solids); the app calls
:meth:`BodiesLayer.update` after its page writer drew the sticks.
"""

from __future__ import annotations

import dataclasses
import html
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._typing import FloatArray
from ..plot._geometry import RobotGeometry
from ..plot._solids import BODY_COLORS, CLOSEST_COLOR, COLLIDING_COLOR, capsule_surface
from ._scene import Solid, rgb

__all__ = ["BodyMesh", "BodiesView", "bodies_view", "capsule_mesh", "clearance_html",
           "collision_note", "check_collision_models", "BodiesLayer", "BODY_OPACITY"]

#: Opacity of the solids in the app (the sticks stay visible through them).
BODY_OPACITY = 0.45
#: Points around each capsule and rings on each cap of the app's meshes.
N_AROUND = 12
N_CAP = 3


@dataclasses.dataclass(frozen=True)
class BodyMesh(Solid):
    """One body as a triangle mesh: a :class:`~athenakin.app.Solid` that knows its pair.

    Attributes
    ----------
    name, vertices, faces, color, opacity
        As for :class:`~athenakin.app.Solid`: the body's name
        (:data:`athenakin.collision.BODIES`), vertices (float32, base frame, m), faces
        (uint32, counter-clockwise seen from outside), RGB and :data:`BODY_OPACITY`.
    closest : bool
        One of the pair with the least clearance.
    """

    closest: bool = False


@dataclasses.dataclass(frozen=True)
class BodiesView:
    """The bodies of one drawn solution and their least clearance.

    Attributes
    ----------
    meshes : tuple of BodyMesh
        One per body of non-zero radius, in the order of the bodies.
    clearance : float
        Least signed distance between the bodies and to the obstacles, m (negative:
        penetration; ``inf`` when no pair is checked).
    pair : tuple of 2 str
        Its two names ("" when no pair is checked).
    witness : ndarray, shape (2, 3)
        The nearest points of the two solids, base frame, m (NaN when no pair).
    colliding : bool
        ``clearance < 0``.
    """

    meshes: tuple[BodyMesh, ...]
    clearance: float
    pair: tuple[str, str]
    witness: FloatArray
    colliding: bool


def _grid_faces(n_rows: int, n_cols: int) -> NDArray[np.uint32]:
    """Two triangles per cell of a (n_rows, n_cols) vertex grid, row-major."""
    i, j = np.meshgrid(np.arange(n_rows - 1), np.arange(n_cols - 1), indexing="ij")
    a = (i * n_cols + j).ravel()
    b, c, d = a + 1, a + n_cols, a + n_cols + 1
    return np.concatenate([np.stack([a, b, c], -1), np.stack([b, d, c], -1)]).astype(np.uint32)


def capsule_mesh(a: ArrayLike, b: ArrayLike, radius: float, *, n_around: int = N_AROUND,
                 n_cap: int = N_CAP) -> tuple[NDArray[np.float32], NDArray[np.uint32]]:
    """Triangle mesh of the capsule of segment ``a -> b`` and ``radius``.

    Returns
    -------
    vertices : ndarray of float32, shape ((2 n_cap + 2) (n_around + 1), 3)
        On the capsule's surface (:func:`athenakin.plot._solids.capsule_surface`).
    faces : ndarray of uint32, shape (2 (2 n_cap + 1) n_around, 3)
    """
    X, Y, Z = capsule_surface(a, b, radius, n_around=n_around, n_cap=n_cap)
    verts = np.stack([X, Y, Z], axis=-1).reshape(-1, 3).astype(np.float32)
    return verts, _grid_faces(*X.shape)


def bodies_view(g: RobotGeometry, *, bodies: Any = None, environment: Any = None,
                n_around: int = N_AROUND, n_cap: int = N_CAP,
                backend: str = "auto") -> BodiesView:
    """The bodies of the drawn solution ``g`` as meshes, and their least clearance.

    Parameters
    ----------
    g : RobotGeometry
        The solution drawn (its ``q``, ``T_b_e``, ``design`` and ``slot`` place the bodies).
    bodies : athenakin.collision.Bodies, optional, keyword-only
        Default :meth:`Bodies.default(g.design) <athenakin.collision.Bodies.default>`.
    environment : athenakin.collision.Environment, optional, keyword-only
        Obstacles in the clearance (not drawn).
    n_around, n_cap : int, keyword-only
        Mesh resolution (points around each capsule, rings on each cap).
    backend : {"auto", "numpy", "numba"}, keyword-only
        The backend of the placement and the clearance (:func:`athenakin.collision.clearance`).

    Returns
    -------
    BodiesView
    """
    from .._mechanism import body_segments, mechanism_points
    from ..collision import Bodies, clearance

    if not isinstance(g, RobotGeometry):
        raise TypeError(f"g: expected a RobotGeometry, got {type(g).__name__}")
    if bodies is None:
        bodies = Bodies.default(g.design)
    elif not isinstance(bodies, Bodies):
        raise TypeError(f"bodies: expected athenakin.collision.Bodies or None, got "
                        f"{type(bodies).__name__}")
    pts = mechanism_points(g.q, g.T_b_e, g.design, slot=g.slot, geometry=bodies.geometry,
                           backend=backend)  # type: ignore[arg-type]
    seg = body_segments(pts)
    c = clearance(g.q, g.T_b_e, g.design, slot=g.slot, bodies=bodies, environment=environment,
                  backend=backend)  # type: ignore[arg-type]
    pair, witness = _closest(c)
    colliding = bool(c.colliding)
    hot = rgb(COLLIDING_COLOR if colliding else CLOSEST_COLOR)
    meshes = []
    for i, name in enumerate(bodies.names):
        r = bodies.radius[name]
        if r <= 0 or not np.all(np.isfinite(seg[i])):
            continue
        v, f = capsule_mesh(seg[i, 0], seg[i, 1], r, n_around=n_around, n_cap=n_cap)
        close = name in pair
        color = hot if close else rgb(BODY_COLORS.get(name, "#808080"))
        meshes.append(BodyMesh(name, v, f, color, opacity=BODY_OPACITY, closest=close))
    return BodiesView(meshes=tuple(meshes), clearance=float(c.min_distance), pair=pair,
                      witness=witness, colliding=colliding)


def _closest(c: Any) -> tuple[tuple[str, str], FloatArray]:
    """The pair of a :class:`~athenakin.collision.Clearance` with the least clearance.

    Returns
    -------
    pair : tuple of 2 str
        The two names (``("", "")`` when no pair is checked).
    witness : ndarray, shape (2, 3)
        Their nearest points, base frame, m (NaN when no pair is checked).
    """
    k = int(c.closest_pair)
    if k < 0:
        return ("", ""), np.full((2, 3), np.nan)
    return (str(c.pairs[k][0]), str(c.pairs[k][1])), np.asarray(c.witness_points[k])


def clearance_html(bv: BodiesView) -> str:
    """The clearance read-out: value in mm and the pair, red when they overlap."""
    if not bv.pair[0]:
        return "<p>clearance: no pair checked</p>"
    color = COLLIDING_COLOR if bv.colliding else CLOSEST_COLOR
    word = "collision" if bv.colliding else "clearance"
    a, b = (html.escape(x) for x in bv.pair)
    return (f'<p data-clearance-m="{bv.clearance!r}" style="color:{color}">'
            f"<b>{word}</b> {bv.clearance * 1e3:.1f} mm: {a} &ndash; {b}</p>")


def collision_note(bv: BodiesView) -> str:
    """The app's status line for overlapping bodies (``""`` when they are clear)."""
    if not bv.colliding:
        return ""
    return (f"colliding: {bv.pair[0]} and {bv.pair[1]} overlap by "
            f"{-bv.clearance * 1e3:.1f} mm")


def check_collision_models(bodies: object, environment: object,
                           design: Any) -> tuple[Any, Any]:
    """The app's bodies and obstacles: given, read from TOML files, or None.

    Checked when the app starts, before its server does: a bad file is an error of the
    caller, not a message in the page (the design and the RCM frame fall back instead,
    since the page can change them; nothing in the page changes these).

    Parameters
    ----------
    bodies : athenakin.collision.Bodies, str, Path or None
        The capsules, or a TOML file with a ``[bodies]`` table
        (:meth:`Bodies.from_toml <athenakin.collision.Bodies.from_toml>`; a file without
        one gives the default capsules). None: the default capsules of the design drawn.
    environment : athenakin.collision.Environment, str, Path or None
        The obstacles, or a TOML file of ``[[environment.obstacle]]`` tables
        (:meth:`Environment.from_toml <athenakin.collision.Environment.from_toml>`).
    design : Design
        The design the app starts with (the default radii of a ``[bodies]`` table with
        ``scale_with_design = true`` follow it).

    Returns
    -------
    bodies : Bodies or None
    environment : Environment or None

    Raises
    ------
    OSError
        A file that cannot be read (the exception names it).
    InvalidInputError
        Not TOML, or a bad table; the message starts with the file name.
    TypeError
        Neither the model, a path nor None.
    """
    from ..collision import Bodies, Environment

    out = []
    for value, name, cls, read in (
            (bodies, "bodies", Bodies, lambda f: Bodies.from_toml(f, design=design)),
            (environment, "environment", Environment, Environment.from_toml)):
        if isinstance(value, (str, Path)):
            value = read(value)
        elif value is not None and not isinstance(value, cls):
            raise TypeError(f"{name}: expected {cls.__name__}, a TOML file or None, got "
                            f"{type(value).__name__}")
        out.append(value)
    return out[0], out[1]


class BodiesLayer:
    """The solids in a viser scene: one mesh node per body, the witness segment, a read-out.

    Parameters
    ----------
    server : viser.ViserServer
    bodies, environment : keyword-only, optional
        As in :func:`bodies_view`.
    visible : bool, keyword-only
        Initial state of the "solid bodies" checkbox.
    backend : {"auto", "numpy", "numba"}, keyword-only
        The backend of every clearance the layer computes.
    """

    def __init__(self, server: Any, *, bodies: Any = None, environment: Any = None,
                 visible: bool = True, backend: str = "auto") -> None:
        self.server = server
        self.backend = backend
        self.bodies = bodies
        self.environment = environment
        self.view: BodiesView | None = None
        self._meshes: dict[str, Any] = {}
        self._witness: Any = None
        self._geometry: RobotGeometry | None = None
        self.checkbox = server.gui.add_checkbox("solid bodies", initial_value=visible,
                                                hint="draw the bodies as capsules and the "
                                                     "least clearance")
        self.readout = server.gui.add_html("")
        self.checkbox.on_update(lambda _: self.update(self._geometry))

    def update(self, g: RobotGeometry | None) -> BodiesView | None:
        """Draw the bodies of ``g`` (None: nothing is drawn), or hide them if unchecked."""
        self._geometry = g
        scene = self.server.scene
        if g is None or not self.checkbox.value:
            for h in self._meshes.values():
                h.remove()
            self._meshes = {}
            if self._witness is not None:
                self._witness.remove()
                self._witness = None
            self.readout.content = ""
            self.view = None
            return None
        bv = bodies_view(g, bodies=self.bodies, environment=self.environment,
                         backend=self.backend)
        seen = set()
        for m in bv.meshes:
            h = self._meshes.get(m.name)
            if h is None:
                self._meshes[m.name] = scene.add_mesh_simple(
                    f"/bodies/{m.name}", m.vertices, m.faces, color=m.color,
                    opacity=m.opacity, cast_shadow=False, receive_shadow=False)
            else:
                h.vertices = m.vertices
                if tuple(h.color) != m.color:
                    h.color = m.color
            seen.add(m.name)
        for name in set(self._meshes) - seen:
            self._meshes.pop(name).remove()
        if self._witness is not None:
            self._witness.remove()
            self._witness = None
        if np.all(np.isfinite(bv.witness)):
            hot = rgb(COLLIDING_COLOR if bv.colliding else CLOSEST_COLOR)
            self._witness = scene.add_line_segments(
                "/bodies/closest", points=bv.witness[None].astype(np.float32),
                colors=np.array([[hot, hot]], dtype=np.uint8), thickness=3.0,
                thickness_units="screen")
        self.readout.content = clearance_html(bv)
        self.view = bv
        return bv

    def clearance_of(self, g: RobotGeometry) -> BodiesView:
        """The least clearance of ``g``, whether the solids are drawn or not.

        The view drawn last if it is ``g``'s; the app checks collisions with the solids
        hidden too.
        """
        if self.view is not None and self._geometry is g:
            return self.view
        from ..collision import Bodies, clearance

        bodies = self.bodies if self.bodies is not None else Bodies.default(g.design)
        c = clearance(g.q, g.T_b_e, g.design, slot=g.slot, bodies=bodies,
                      environment=self.environment)
        pair, witness = _closest(c)
        return BodiesView(meshes=(), clearance=float(c.min_distance), pair=pair,
                          witness=witness, colliding=bool(c.colliding))

    def clearance_along(self, T_b_e: FloatArray, design: Any,
                        slot: int) -> Callable[[FloatArray], FloatArray]:
        """``clearance(q)``: least clearance of configurations ``q`` (k, 3) in ``slot``.

        The least signed distance between the bodies and to the obstacles, m, shape (k,);
        :func:`athenakin.app.inverse_step` stops before a collision with it.
        """
        from ..collision import Bodies, clearance

        bodies = self.bodies if self.bodies is not None else Bodies.default(design)

        def along(q: FloatArray) -> FloatArray:
            c = clearance(q, T_b_e, design, slot=slot, bodies=bodies,
                          environment=self.environment,
                          backend=self.backend)  # type: ignore[arg-type]
            return np.asarray(c.min_distance, dtype=float)

        return along
