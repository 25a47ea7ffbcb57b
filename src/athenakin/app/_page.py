"""What the app's page shows (private): the scene nodes, the page script, the banner.

:class:`PageWriter` is a part that :class:`athenakin.app._server.AthenaApp` owns: it
holds the handles of the scene nodes it sent and sends the scene of an
:class:`~athenakin.app.AppView` (one line-segments node per line width, point clouds,
solids, labels), frames the camera and sends the page script. :func:`page_title`,
:func:`banner_html` and :func:`slot_options` are what the page's title, banner and slot
list say; :func:`write_value` shows a value in a GUI input without undoing newer input
from the browser. The app's state and what changes it (callbacks, the GUI inputs,
actions) are :mod:`athenakin.app._server`'s, and its tabs' (set-up, playback, teleop).
"""

from __future__ import annotations

import functools
import json
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._typing import FloatArray
from ._ghosts import ghost_scene
from ._model import AppSetup, AppView
from ._scene import Scene, Solid, robot_scene, with_solids
from ._script import run_page_script
from ._text import ERROR_COLOR

_ALL = "all valid slots (others ghosted)"
#: A label is sent again when its point moved by more than this, m.
LABEL_TOL_M = 1e-7
#: Style added to the page: the control panel's vertical scroll bar always visible.
_PANEL_CSS = (".mantine-ScrollArea-root:has([data-ro='banner']) > "
              ".mantine-ScrollArea-scrollbar[data-orientation='vertical']"
              "{display:flex !important;opacity:1 !important;width:10px !important}"
              ".mantine-ScrollArea-root:has([data-ro='banner']) .mantine-ScrollArea-thumb"
              "{background-color:rgba(0,0,0,0.35) !important}")
#: Keys of viser's camera (``event.code``): ignored while a control of the panel has focus.
CAMERA_KEYS = ("ArrowLeft", "ArrowRight", "ArrowUp", "ArrowDown", "KeyW", "KeyA", "KeyS",
               "KeyD", "KeyQ", "KeyE")
#: A node's colour layout: ``(colour, number of segments)`` of each part, in order.
_Layout = tuple[tuple[tuple[int, int, int], int], ...]
#: The GUI inputs an update read, with the values it read: ``((handle, value), ...)``.
_Read = tuple[tuple[Any, float], ...]


class PageWriter:
    """The scene nodes of the app's page: what it sent, and how to send a view's scene.

    Parameters
    ----------
    server : viser.ViserServer
        The server whose scene and page this part writes.
    solids_of : callable, optional
        ``solids_of(view) -> tuple[Solid, ...]``: solids added to the robot's scene.
    """

    def __init__(self, server: Any, *,
                 solids_of: Callable[[AppView], tuple[Solid, ...]] | None = None) -> None:
        self.server = server
        self._solids_of = solids_of
        self._solid_handles: dict[str, tuple[Any, tuple[int, ...]]] = {}
        self._line_handles: dict[str, Any] = {}
        self._point_handles: dict[str, Any] = {}
        self._label_handles: dict[str, Any] = {}
        self._line_layouts: dict[str, _Layout] = {}
        self._label_texts: tuple[str, ...] = ()
        self._label_pos: FloatArray = np.zeros((0, 3))

    def send_script(self, title: str) -> None:
        """Set the page title, keep camera keys off the controls, show the scroll bar.

        viser's camera moves on the arrow keys (and W A S D Q E) wherever the focus is,
        except in text fields: a focused slider would move and rotate the view at once.
        A listener on ``document.body`` (reached after the control's own handler, before
        viser's on ``document``) stops those keys when the focus is on an element other
        than the page or the 3-D canvas.

        Parameters
        ----------
        title : str
            The page's title (:func:`page_title`).
        """
        script = (
            f"document.title = {json.dumps(title)};"
            "if (!window.__athenakinKeys) { window.__athenakinKeys = true;"
            f" const keys = new Set({json.dumps(list(CAMERA_KEYS))});"
            " document.body.addEventListener('keydown', (e) => { const t = e.target;"
            " if (keys.has(e.code) && t instanceof Element && t !== document.body"
            " && t.tagName !== 'CANVAS') { e.stopPropagation(); } });"
            # the panel's scroll bar always shown: the read-outs continue below the window
            " const st = document.createElement('style');"
            f" st.textContent = {json.dumps(_PANEL_CSS)}; document.head.appendChild(st); }}")
        run_page_script(self.server, script)

    def draw(self, view: AppView) -> None:
        """Send the scene of ``view`` (inside the caller's atomic block).

        One line-segments node per line width (solid and ghosted apart), one point cloud
        per point set, the labels that moved.

        Parameters
        ----------
        view : AppView
            A view with its geometry (``view.geometry`` is not None).
        """
        assert view.geometry is not None
        solid = robot_scene(view.geometry)
        if self._solids_of is not None:
            solid = with_solids(solid, tuple(self._solids_of(view)))
        ghosts = (ghost_scene(view.ghosts, view.geometry) if view.ghosts is not None
                  else Scene((), (), ()))
        scene = self.server.scene
        handles = {}
        groups = {**_by_width(solid, "w"), **_by_width(ghosts, "ghost_w")}
        for name, (pts, layout, width) in groups.items():
            h = self._line_handles.pop(name, None)
            if h is None:
                h = scene.add_line_segments(f"/robot/{name}", points=pts,
                                            colors=_layout_colors(layout), thickness=width,
                                            thickness_units="screen")
            elif self._line_layouts.get(name) == layout:
                h.points = pts                          # the colours are those sent before
            else:
                h.points, h.colors = pts, _layout_colors(layout)
            self._line_layouts[name] = layout
            handles[name] = h
        for name, h in self._line_handles.items():      # parts not drawn any more
            h.remove()
            self._line_layouts.pop(name, None)
        self._line_handles = handles
        for ps in solid.points:
            pts = ps.points.astype(np.float32)
            h = self._point_handles.get(ps.name)
            if h is not None and len(h.points) == len(pts):
                h.points = pts
            else:
                if h is not None:
                    h.remove()
                self._point_handles[ps.name] = scene.add_point_cloud(
                    f"/robot/{ps.name}", points=pts, colors=ps.colors, point_size=ps.size,
                    point_shape="circle", precision="float32")
        for name in set(self._point_handles) - {ps.name for ps in solid.points}:
            self._point_handles.pop(name).remove()
        self._draw_solids(solid.solids + ghosts.solids)
        texts = tuple(lab.text for lab in solid.labels)
        pos = np.array([lab.position for lab in solid.labels]).reshape(-1, 3)
        if texts != self._label_texts or len(self._label_handles) != len(texts):
            moved = np.ones(len(texts), dtype=bool)
        else:                                           # one comparison for all labels
            moved = np.any(np.abs(pos - self._label_pos) > LABEL_TOL_M, axis=-1)
        for text, p, m in zip(texts, pos, moved.tolist(), strict=True):
            h = self._label_handles.get(text)
            if h is None:
                self._label_handles[text] = scene.add_label(f"/labels/{text}", text,
                                                            position=tuple(p.tolist()))
            elif m:
                h.position = p
        self._label_texts, self._label_pos = texts, pos

    def solid_handle(self, name: str) -> Any:
        """The mesh node of the solid ``name`` as last sent (``KeyError`` if none)."""
        return self._solid_handles[name][0]

    def _draw_solids(self, solids: tuple[Solid, ...]) -> None:
        """One mesh node per solid: new vertices where the mesh keeps its faces."""
        scene, handles = self.server.scene, {}
        for so in solids:
            verts = np.asarray(so.vertices, dtype=np.float32)
            faces = np.asarray(so.faces, dtype=np.uint32)
            key = (*faces.shape, hash(faces.tobytes()), *so.color, hash(so.opacity))
            old = self._solid_handles.pop(so.name, None)
            if old is not None and old[1] == key:
                old[0].vertices = verts
                handles[so.name] = old
                continue
            if old is not None:
                old[0].remove()
            h = scene.add_mesh_simple(f"/robot/solids/{so.name}", verts, faces,
                                      color=so.color, opacity=so.opacity,
                                      flat_shading=True)
            handles[so.name] = (h, key)
        for h, _ in self._solid_handles.values():      # bodies not drawn any more
            h.remove()
        self._solid_handles = handles

    def frame_camera(self, view: AppView | None) -> None:
        """Point the initial camera at the robot of ``view`` (nothing without geometry).

        Parameters
        ----------
        view : AppView or None
            The view whose geometry's bounds the camera frames.
        """
        if view is None or view.geometry is None:
            return
        lo, hi = view.geometry.bounds()
        centre = 0.5 * (lo + hi)
        span = float(np.max(hi - lo))
        cam = self.server.initial_camera
        cam.look_at = tuple(float(x) for x in centre)
        cam.position = tuple(float(x) for x in centre + span * np.array([0.8, -0.95, 0.55]))
        cam.up = (0.0, 0.0, 1.0)


def page_title(setup: AppSetup) -> str:
    """The page's title: the robot, the design and the app."""
    name = setup.design.name or "unnamed design"
    return f"ATHENA - {name} - athenakin"


def banner_html(setup: AppSetup, errors: list[str]) -> str:
    """The banner at the top of the panel: the design and backend, or the problems."""
    if not errors:
        d = setup.design
        return (f"<div data-ro='banner'><b>ATHENA</b> {d.name or ''} "
                f"(backend {setup.backend})</div>")
    items = "".join(f"<li>{_escape(e)}</li>" for e in errors)
    return (f"<div data-ro='banner' data-level='error' style='color:{ERROR_COLOR}'>"
            f"<b>Problems</b><ul style='margin:0;padding-left:1.2em'>{items}</ul></div>")


def slot_options(view: AppView | None) -> list[str]:
    """The FK slot dropdown's entries: all slots, then each slot (why it is invalid)."""
    if view is None:
        return [_ALL] + [f"slot {k}" for k in range(16)]
    return [_ALL] + [s.label if s.valid else f"{s.label} - invalid: "
                     f"{s.why.split(':')[0]}" for s in view.slots]


@functools.lru_cache(maxsize=64)
def _vertex_color(rgb: tuple[int, int, int]) -> NDArray[np.uint8]:
    """An sRGB colour (0..255) as a per-vertex colour that shows as given.

    three.js reads vertex colours as linear and converts them to sRGB on output.
    """
    c = np.asarray(rgb, dtype=float) / 255.0
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return np.round(255.0 * lin).astype(np.uint8)


def _by_width(scene: Scene, prefix: str) -> dict[str, tuple[NDArray[np.float32], _Layout, float]]:
    """The scene's line sets merged per line width: ``name -> (points, layout, width)``.

    One scene node per width instead of one per part: fewer messages per update. The
    colours follow from the layout (:func:`_layout_colors`), and only a changed layout
    needs them sent again.
    """
    groups: dict[float, list[Any]] = {}
    for ls in scene.lines:
        groups.setdefault(ls.width, []).append(ls)
    out = {}
    for w, sets in groups.items():
        pts = np.concatenate([ls.segments for ls in sets]).astype(np.float32)
        layout = tuple((ls.color, len(ls.segments)) for ls in sets)
        out[f"{prefix}{w:g}"] = (pts, layout, w)
    return out


def _layout_colors(layout: _Layout) -> NDArray[np.uint8]:
    """Per-vertex colours (n, 2, 3) of a node's layout."""
    return np.concatenate([np.broadcast_to(_vertex_color(c), (n, 2, 3)) for c, n in layout])


def write_value(handle: Any, value: float, read: _Read) -> None:
    """Show ``value`` in a GUI input, unless the browser moved it on since it was read.

    viser stores a value from the browser before the callback that reads it runs. If the
    input no longer holds what this update read, a newer value is waiting for its own
    callback: writing this update's value back would undo it (and the browser's slider
    would jump back, so that the next key press starts from the old value).
    """
    for h, v in read:
        if h is handle and handle.value != v:
            return
    if abs(handle.value - value) > 1e-9:
        handle.value = value


def _escape(text: str) -> str:
    import html

    return html.escape(text)
