"""Interactive 3-D view in a self-contained HTML page (plotly).

Why plotly: it is a pure-Python dependency of the ``plot`` extra whose
``write_html`` embeds plotly.js in one file that opens offline in any browser,
with rotation, zoom, hover read-outs, a legend that hides parts, and menus
(here: a switch between the 16 FK solutions) without a server or a notebook.
matplotlib's HTML back ends and bokeh have no 3-D; k3d and pythreejs need a
Jupyter kernel; three.js would mean maintaining a JavaScript app. The costs:
the page is about 4.7 MB (plotly.js inline; ``include_plotlyjs="cdn"`` gives a
small page that needs the network) and the browser needs WebGL (software
rendering is enough).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from .._validation import check_array
from ..design import Design, resolve_design
from ..robot import forward_kinematics
from ..robot._setup import resolve_rcm_frame
from ._geometry import (
    ARC_RADIUS,
    COLORS,
    FRAME_LENGTH,
    MM,
    RobotGeometry,
    arc_points,
    cube_around,
    robot_geometry,
    slot_label,
)

__all__ = ["robot_figure", "write_html", "HTML_DIV_ID", "screen_points", "label_boxes",
           "text_positions"]

#: ``id`` of the plot's ``<div>`` in pages written by :func:`write_html`.
HTML_DIV_ID = "athenakin-robot"


#: Default camera of the scene (plotly's eye, in units of the half box); far enough that
#: the whole axis box stays inside the page.
CAMERA_EYE = {"x": 1.55, "y": -1.65, "z": 0.8}
#: plotly text positions tried for a point label, each with its direction on the screen.
_TEXT_POSITIONS = {"top right": (1, 1), "top left": (-1, 1), "bottom right": (1, -1),
                   "bottom left": (-1, -1), "middle right": (1, 0), "middle left": (-1, 0),
                   "top center": (0, 1), "bottom center": (0, -1)}
#: Estimated size of a label character and line on the page (px, 12 px font).
_CHAR_PX, _LINE_PX = 7.0, 14.0


def _place(pts: ArrayLike, T_w_b: FloatArray | None) -> FloatArray:
    """Points (..., 3) of the base frame in the frame ``w`` of ``T_w_b`` (None: unchanged), m."""
    P = np.asarray(pts, dtype=float)
    return P if T_w_b is None else P @ T_w_b[:3, :3].T + T_w_b[:3, 3]


def _polyline(segments: list[FloatArray], T_w_b: FloatArray | None = None
              ) -> tuple[list[Any], ...]:
    """x, y, z lists (mm) of several polylines (m) separated by None (one plotly trace).

    ``T_w_b`` (optional) places the base-frame points in another frame first.
    """
    xs: list[Any] = []
    ys: list[Any] = []
    zs: list[Any] = []
    for pts in segments:
        arr = _place(pts, T_w_b) * MM
        xs += arr[:, 0].tolist() + [None]
        ys += arr[:, 1].tolist() + [None]
        zs += arr[:, 2].tolist() + [None]
    return xs, ys, zs


def screen_points(pts: FloatArray, lo: FloatArray, hi: FloatArray,
                  *, eye: dict[str, float] = CAMERA_EYE, size: float = 600.0
                  ) -> FloatArray:
    """Approximate page position (px, y up) of points in a cubic scene seen from ``eye``.

    An orthographic view along ``eye`` of the scene box ``lo``..``hi`` (m) scaled to
    ``size`` px; plotly's perspective differs by a few per cent, enough to decide
    on which side of its point each label goes.
    """
    e = np.array([eye["x"], eye["y"], eye["z"]])
    e /= np.linalg.norm(e)
    right = np.cross([0.0, 0.0, 1.0], e)
    right /= np.linalg.norm(right)
    up = np.cross(e, right)
    u = (np.atleast_2d(pts) - 0.5 * (lo + hi)) / float(np.max(hi - lo))
    return size * np.column_stack([u @ right, u @ up])


def label_boxes(xy: FloatArray, texts: list[str], positions: list[str],
                marker_px: float = 6.0) -> FloatArray:
    """Estimated page boxes ``(x0, y0, x1, y1)`` (px) of labels at plotly text positions."""
    out = []
    for (x, y), t, pos in zip(xy, texts, positions, strict=True):
        dx, dy = _TEXT_POSITIONS[pos]
        w, h = _CHAR_PX * len(t), _LINE_PX
        cx = x + dx * (marker_px + w / 2)
        cy = y + dy * (marker_px + h / 2)
        out.append([cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2])
    return np.array(out).reshape(-1, 4)


def _overlap(a: FloatArray, b: FloatArray) -> float:
    w = min(a[2], b[2]) - max(a[0], b[0])
    h = min(a[3], b[3]) - max(a[1], b[1])
    return max(w, 0.0) * max(h, 0.0)


def text_positions(xy: FloatArray, texts: list[str]) -> list[str]:
    """A plotly text position per label such that the estimated labels do not overlap.

    Greedy, in order: each label takes the first of the 8 positions whose box
    overlaps no label placed before it and no other point (or, failing that, the
    position with the least overlap).
    """
    half = 5.0
    points = [np.r_[p - half, p + half] for p in xy]
    placed: list[FloatArray] = []
    out = []
    for i, (p, t) in enumerate(zip(xy, texts, strict=True)):
        best: tuple[float, str, FloatArray] | None = None
        for pos in _TEXT_POSITIONS:
            box = label_boxes(p[None], [t], [pos])[0]
            cost = (sum(_overlap(box, b) for b in placed)
                    + sum(_overlap(box, b) for j, b in enumerate(points) if j != i))
            if best is None or cost < best[0]:
                best = (cost, pos, box)
            if cost == 0.0:
                break
        assert best is not None
        out.append(best[1])
        placed.append(best[2])
    return out


def _hover(name: str, frame: str = "b") -> str:
    """Hover template of a trace: its name and the point's coordinates in ``frame``, mm."""
    f = frame
    return (f"<b>{name}</b><br>x<sub>{f}</sub> = %{{x:.1f}} mm<br>y<sub>{f}</sub> = "
            f"%{{y:.1f}} mm<br>z<sub>{f}</sub> = %{{z:.1f}} mm<extra></extra>")


#: Labelled points of the view: key in :attr:`RobotGeometry.points`, text, name in the hover.
POINT_LABELS = (("A", "A", "carriage A (q1)"), ("B", "B", "carriage B (q2)"),
                ("M", "M", "M, midpoint of A and B"), ("D", "D", "D"), ("C", "C", "C"),
                ("O_i", "O_i", "O_i"), ("O_s", "O_s", "O_s, U-joint"),
                ("RCM", "RCM", "RCM = O_e"), ("tip", "tip", "tool tip"))


def _traces(g: RobotGeometry, *, show_frames: bool, frame_length: float,
            box: tuple[FloatArray, FloatArray] | None = None,
            T_w_b: FloatArray | None = None, frame: str = "b") -> list[dict[str, Any]]:
    """Scatter3d trace specs (plotly dicts, coordinates in mm) of one solution.

    ``T_w_b`` (shape (4, 4), optional) draws the robot in the frame ``w`` in which its
    base frame has that pose (``box`` is then in ``w``); ``frame`` names it in the hovers.
    """
    P = g.points
    seg = g.segments()

    def lines(name: str, segs: list[Any], color: str, width: float, dash: str = "solid"
              ) -> dict[str, Any]:
        x, y, z = _polyline(segs, T_w_b)
        return {"type": "scatter3d", "mode": "lines", "name": name, "x": x, "y": y, "z": z,
                "line": {"color": color, "width": width, "dash": dash},
                "hovertemplate": _hover(name, frame)}

    out = [
        lines("base rail (x_b)", [g.rail], COLORS["rail"], 9),
        lines("parallel module (l1, l3, carrier, l4)",
              [np.stack(seg[k]) for k in ("link_a1", "link_b1", "link_a3", "link_b3",
                                          "offset_l4")]
              + [np.stack([P["D"], P["C_foot"], P["C"]])], COLORS["parallel"], 7),
        lines("actuator q3 (radius of k2)", [np.stack(seg["actuator_q3"])],
              COLORS["actuator"], 9),
        lines("circle k1", [g.k1], COLORS["circle_k1"], 2, "dash"),
        lines("circle k2 (arc through both intersections)", [g.k2_arc], COLORS["circle_k2"], 2,
              "dash"),
        lines("U-joint at O_s (u1 axis, fork along +u2)",
              [np.stack([P["O_s"] - 0.03 * g.ujoint_axes[0], P["O_s"] + 0.03 * g.ujoint_axes[0]]),
               np.stack([P["O_s"], P["O_s"] + 0.045 * g.ujoint_axes[1]])], "#333333", 6),
        lines("instrument", [np.stack(seg["instrument"])], COLORS["serial"], 8),
    ]
    if not 0.0 <= g.p <= g.design.tool_length:
        out.append(lines("instrument axis to the RCM", [np.stack([P["O_s"], P["RCM"]])],
                         COLORS["serial"], 2, "dot"))
    c, ax_ = P["RCM"], g.wrist_axes
    sph = [np.stack([c - 0.4 * ARC_RADIUS * a, c + 0.4 * ARC_RADIUS * a]) for a in ax_]
    sph += [arc_points(c, ax_[k], ax_[k + 1], ARC_RADIUS) for k in range(2)]
    out.append(lines("spherical joint at the RCM (u3, u4, u5)", sph, COLORS["sphere"], 5))
    out.append(_point_trace(g, show_frames=show_frames, box=box, T_w_b=T_w_b, frame=frame))
    other = g.intersections[1 if g.mode > 0 else 0]
    if np.all(np.isfinite(other)):
        x, y, z = (_place(other, T_w_b) * MM).tolist()
        out.append({"type": "scatter3d", "mode": "markers",
                    "name": "O_i of the other assembly mode", "x": [x], "y": [y], "z": [z],
                    "marker": {"size": 5, "color": COLORS["joint"], "symbol": "circle-open"},
                    "hovertemplate": _hover("O_i of the other assembly mode", frame)})
    if show_frames:
        frames = [("O_b", g.frames["b"], 1.5), ("O_i", g.frames["i"], 1.0),
                  ("O_s", g.frames["s"], 1.0), ("O_e (RCM)", g.frames["e"], 1.0)]
        for i, axis in enumerate("xyz"):
            segs = [np.stack([T[:3, 3], T[:3, 3] + s * frame_length * T[:3, i]])
                    for _, T, s in frames]
            out.append(lines(f"frame axes {axis} (O_b, O_i, O_s, O_e)", segs, COLORS[axis], 5))
    return out


def _point_trace(g: RobotGeometry, *, show_frames: bool,
                 box: tuple[FloatArray, FloatArray] | None,
                 T_w_b: FloatArray | None = None, frame: str = "b") -> dict[str, Any]:
    """The labelled points of one solution (one label where points coincide on screen).

    ``T_w_b``, ``frame``: as in :func:`_traces` (pass ``box``, in the frame drawn, with
    ``T_w_b``: the labels' sides are chosen on the screen of that box).
    """
    P = g.points
    keys, labels, names = (list(t) for t in zip(*POINT_LABELS, strict=True))
    pts = np.stack([P[k] for k in keys])
    if show_frames:                         # the base frame's origin, labelled with M
        keys.append("O_b")
        labels.append("O_b")
        names.append("O_b, origin of the base frame")
        pts = np.vstack([pts, np.zeros(3)])
    pts = _place(pts, T_w_b)
    lo, hi = box if box is not None else g.bounds()
    xy = screen_points(pts, lo, hi)
    # points drawn at one place share one label (M and O_b in the reference configuration)
    text = list(labels)
    for i in range(len(text)):
        for j in range(i):
            if text[j] and np.hypot(*(xy[i] - xy[j])) < 4.0:
                text[j] = f"{text[j]}, {text[i]}"
                text[i] = ""
                break
    shown = [i for i, t in enumerate(text) if t]
    positions = ["top center"] * len(text)
    for i, pos in zip(shown, text_positions(xy[shown], [text[i] for i in shown]), strict=True):
        positions[i] = pos
    f = frame
    hover = [f"<b>{n}</b><br>x<sub>{f}</sub> = {p[0] * MM:.1f} mm<br>y<sub>{f}</sub> = "
             f"{p[1] * MM:.1f} mm<br>z<sub>{f}</sub> = {p[2] * MM:.1f} mm"
             for n, p in zip(names, pts, strict=True)]
    palette = {"A": COLORS["rail"], "B": COLORS["rail"], "RCM": COLORS["sphere"],
               "tip": COLORS["serial"], "O_b": "#222222"}
    symbols = {"A": "square", "B": "square", "RCM": "diamond"}
    sizes = {"A": 7, "B": 7, "M": 3, "O_i": 5, "O_s": 6, "RCM": 7, "tip": 3, "O_b": 3}
    return {"type": "scatter3d", "mode": "markers+text", "name": "points (hover: mm)",
            "x": (pts[:, 0] * MM).tolist(), "y": (pts[:, 1] * MM).tolist(),
            "z": (pts[:, 2] * MM).tolist(), "text": text, "textposition": positions,
            "hovertext": hover, "hoverinfo": "text",
            "marker": {"size": [sizes.get(k, 4) for k in keys],
                       "color": [palette.get(k, COLORS["joint"]) for k in keys],
                       "symbol": [symbols.get(k, "circle") for k in keys]}}


def robot_figure(q: ArrayLike | None = None, T_b_e: ArrayLike | None = None,
                 design: Design | None = None, *, slot: int = 0, all_slots: bool = True,
                 all_solutions: bool = False, show_frames: bool = True,
                 frame_length: float = FRAME_LENGTH, title: str | None = None) -> Any:
    """Interactive plotly figure of the robot, with a menu over the FK solutions.

    Coordinates are in millimetres (base frame); hovering over any point of a
    part shows its name and coordinates.

    Parameters
    ----------
    q : array-like, shape (3,), optional
        Actuators, m (default :data:`athenakin.robot.REFERENCE_Q`).
    T_b_e : array-like, shape (4, 4), optional
    design : Design, optional
    slot : int, keyword-only
        Solution shown first.
    all_slots : bool, keyword-only
        Include every valid solution, selectable in a drop-down menu; otherwise
        only ``slot``.
    all_solutions : bool, keyword-only
        Show every valid solution at once, one legend entry per slot (a click on it
        hides or shows that solution, a double click shows it alone); the menu
        then offers "all solutions" and each slot. Only the first solution's points
        carry text labels (the others are named on hover).
    show_frames : bool, keyword-only
        Triads of ``O_b``, ``O_i``, ``O_s``, ``O_e``.
    frame_length : float, keyword-only
        m.
    title : str, keyword-only, optional

    Returns
    -------
    plotly.graph_objects.Figure

    Raises
    ------
    KinematicsError
        ``slot`` holds no solution.
    """
    import plotly.graph_objects as go

    from ..robot import REFERENCE_Q
    from ._geometry import check_length

    frame_length = check_length(frame_length, "frame_length")
    design = resolve_design(design)
    q = check_array(REFERENCE_Q if q is None else q, "q", (3,))
    T = resolve_rcm_frame(T_b_e, design)
    first = robot_geometry(q, T, design, slot=slot)
    geoms = _solution_geometries(q, T, design, first, every=all_slots or all_solutions)
    slots = list(geoms)
    box = cube_around(geoms.values())
    fig = go.Figure()
    owner = _add_solution_traces(fig, geoms, first.slot, all_solutions=all_solutions,
                                 show_frames=show_frames, frame_length=frame_length, box=box)
    qmm = ", ".join(f"{MM * v:.0f}" for v in q)
    head = (f"ATHENA, q = ({qmm}) mm: all {len(slots)} solutions" if all_solutions
            else f"ATHENA, q = ({qmm}) mm: {slot_label(first)}")
    fig.update_layout(title={"text": title or head, "x": 0.02}, scene=_scene(*box),
                      legend={"x": 0.75, "y": 0.5, "yanchor": "middle", "font": {"size": 11}},
                      margin={"l": 0, "r": 0, "t": 50, "b": 0}, paper_bgcolor="white",
                      hoverlabel={"align": "left"})
    if len(slots) > 1:
        buttons = _solution_buttons(geoms, owner, qmm, head if all_solutions else None)
        active = 0 if all_solutions else slots.index(first.slot)
        fig.update_layout(updatemenus=[{
            "buttons": buttons, "direction": "down", "x": 0.99, "xanchor": "right", "y": 0.99,
            "yanchor": "top", "active": active, "showactive": True}])
    return fig


def _solution_geometries(q: FloatArray, T: FloatArray, design: Design,
                         first: RobotGeometry, *, every: bool) -> dict[int, RobotGeometry]:
    """Geometry of each solution shown, by slot: every valid one (``every``) or ``first``."""
    if not every:
        return {first.slot: first}
    sol = forward_kinematics(q, T, design, errors="flag")
    return {k: (first if k == first.slot else robot_geometry(q, T, design, slot=k))
            for k in (int(k) for k in np.flatnonzero(sol.valid))}


def _add_solution_traces(fig: Any, geoms: dict[int, RobotGeometry], shown: int, *,
                         all_solutions: bool, show_frames: bool, frame_length: float,
                         box: tuple[FloatArray, FloatArray]) -> list[int]:
    """Add the traces of every solution to ``fig``; returns the slot of each trace.

    ``all_solutions``: all visible, one legend group (and entry) per slot, text labels on
    the first slot only; otherwise only slot ``shown`` is visible.
    """
    slots = list(geoms)
    owner: list[int] = []
    for k in slots:
        for tr in _traces(geoms[k], show_frames=show_frames, frame_length=frame_length,
                          box=box):
            if all_solutions:
                tr["visible"] = True
                tr["legendgroup"] = f"slot {k}"
                tr["showlegend"] = tr["name"] == "instrument"     # one entry, in red
                if tr["showlegend"]:
                    tr["name"] = slot_label(geoms[k])
                if tr["mode"] == "markers+text" and k != slots[0]:
                    tr["mode"] = "markers"      # one set of labels; hover names the rest
            else:
                tr["visible"] = k == shown
                tr["legendgroup"] = tr["name"]
            fig.add_trace(tr)
            owner.append(k)
    return owner


def _scene(lo: FloatArray, hi: FloatArray) -> dict[str, Any]:
    """The plotly scene: the axis box ``(lo, hi)`` (m, a cube), axes in mm."""
    axis = {"showbackground": True, "backgroundcolor": "#f4f4f6", "gridcolor": "#cccccc"}
    return {**{f"{c}axis": {**axis, "title": f"{c}_b [mm]", "range": [MM * lo[i], MM * hi[i]]}
               for i, c in enumerate("xyz")},
            "aspectmode": "cube", "domain": {"x": [0.0, 0.74], "y": [0.0, 1.0]},
            "camera": {"eye": dict(CAMERA_EYE), "center": {"x": 0.0, "y": 0.0, "z": -0.15}}}


def _solution_buttons(geoms: dict[int, RobotGeometry], owner: list[int], qmm: str,
                      all_head: str | None) -> list[dict[str, Any]]:
    """Menu entries: "all solutions" (where ``all_head`` is the title), then each slot."""
    buttons = []
    if all_head is not None:
        buttons.append({"label": f"all {len(geoms)} solutions", "method": "update",
                        "args": [{"visible": [True] * len(owner)}, {"title.text": all_head}]})
    buttons += [{"label": slot_label(g), "method": "update",
                 "args": [{"visible": [o == k for o in owner]},
                          {"title.text": f"ATHENA, q = ({qmm}) mm: {slot_label(g)}"}]}
                for k, g in geoms.items()]
    return buttons


def write_html(path: str | Path, q: ArrayLike | None = None, T_b_e: ArrayLike | None = None,
               design: Design | None = None, *, slot: int = 0,
               include_plotlyjs: bool | str = True, **kwargs: Any) -> Path:
    """Write :func:`robot_figure` as an HTML page (self-contained by default).

    The page's ``<title>`` is the figure's title (``q`` and the solution shown).

    Parameters
    ----------
    path : str or Path
    q, T_b_e, design, slot
        As in :func:`robot_figure`.
    include_plotlyjs : bool or str, keyword-only
        ``True`` embeds plotly.js (offline, about 4.7 MB); ``"cdn"`` links it.
    **kwargs
        Passed to :func:`robot_figure`.

    Returns
    -------
    Path
    """
    from .._output import check_output_path

    path = check_output_path(path)
    fig = robot_figure(q, T_b_e, design, slot=slot, **kwargs)
    return write_figure_page(path, fig, include_plotlyjs=include_plotlyjs)


def write_figure_page(path: Path, fig: Any, *, include_plotlyjs: bool | str = True,
                      div_id: str = HTML_DIV_ID) -> Path:
    """Write a plotly figure as an HTML page, atomically; its ``<title>`` the figure's.

    Parameters
    ----------
    path : Path
        A checked output path (:func:`athenakin._output.check_output_path`).
    fig : plotly.graph_objects.Figure
    include_plotlyjs : bool or str, keyword-only
        ``True`` embeds plotly.js (offline); ``"cdn"`` links it.
    div_id : str, keyword-only
        ``id`` of the plot's ``<div>``.

    Returns
    -------
    Path
        ``path``.
    """
    import html

    from .._output import write_text_atomic

    text = fig.to_html(include_plotlyjs=include_plotlyjs, full_html=True, div_id=div_id,
                       config={"displaylogo": False, "responsive": True})
    page_title = html.escape(fig.layout.title.text or "ATHENA")
    text = text.replace("<head>", f"<head>\n<title>{page_title}</title>", 1)
    write_text_atomic(path, text)
    return path
