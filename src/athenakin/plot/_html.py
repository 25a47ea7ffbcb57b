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
from numpy.typing import ArrayLike, NDArray

from .._validation import check_array
from ..design import Design, resolve_design
from ..robot import forward_kinematics
from ..robot._setup import resolve_rcm_frame
from ._geometry import RobotGeometry, robot_geometry
from ._mpl import ARC_RADIUS, COLORS, FRAME_LENGTH, arc_points, slot_label

__all__ = ["robot_figure", "write_html", "HTML_DIV_ID"]

#: ``id`` of the plot's ``<div>`` in pages written by :func:`write_html`.
HTML_DIV_ID = "athenakin-robot"


def _polyline(segments: list[tuple[NDArray[np.float64], ...]]) -> tuple[list[Any], ...]:
    """x, y, z lists of several polylines separated by None (one plotly trace)."""
    xs: list[Any] = []
    ys: list[Any] = []
    zs: list[Any] = []
    for pts in segments:
        arr = np.asarray(pts)
        xs += arr[:, 0].tolist() + [None]
        ys += arr[:, 1].tolist() + [None]
        zs += arr[:, 2].tolist() + [None]
    return xs, ys, zs


def _traces(g: RobotGeometry, *, show_frames: bool, frame_length: float) -> list[dict[str, Any]]:
    """Scatter3d trace specs (plotly dicts) of one solution."""
    P = g.points
    seg = g.segments()

    def lines(name: str, segs: list[Any], color: str, width: float, dash: str = "solid"
              ) -> dict[str, Any]:
        x, y, z = _polyline(segs)
        return {"type": "scatter3d", "mode": "lines", "name": name, "x": x, "y": y, "z": z,
                "line": {"color": color, "width": width, "dash": dash}, "hoverinfo": "name"}

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
    names = ["A", "B", "M", "D", "C", "O_i", "O_s", "RCM", "tip"]
    labels = ["A", "B", "M", "D", "C", "O_i", "O_s (U-joint)", "RCM = O_e", "tool tip"]
    pts = np.stack([P[n] for n in names])
    other = g.intersections[1 if g.mode > 0 else 0]
    hover = [f"{lab}<br>({p[0]:.4f}, {p[1]:.4f}, {p[2]:.4f}) m"
             for lab, p in zip(labels, pts, strict=True)]
    colors = [COLORS["rail"], COLORS["rail"], COLORS["joint"], COLORS["joint"],
              COLORS["joint"], COLORS["joint"], COLORS["joint"], COLORS["sphere"],
              COLORS["serial"]]
    symbols = ["square", "square", "circle", "circle", "circle", "circle", "circle", "diamond",
               "circle"]
    out.append({"type": "scatter3d", "mode": "markers+text", "name": "points and joints",
                "x": pts[:, 0].tolist(), "y": pts[:, 1].tolist(), "z": pts[:, 2].tolist(),
                "text": labels, "textposition": "top center", "hovertext": hover,
                "hoverinfo": "text",
                "marker": {"size": [7, 7, 3, 4, 4, 5, 6, 7, 3], "color": colors,
                           "symbol": symbols}})
    if np.all(np.isfinite(other)):
        out.append({"type": "scatter3d", "mode": "markers", "name": "O_i of the other mode",
                    "x": [float(other[0])], "y": [float(other[1])], "z": [float(other[2])],
                    "marker": {"size": 5, "color": COLORS["joint"], "symbol": "circle-open"},
                    "hoverinfo": "name"})
    if show_frames:
        frames = [("O_b", g.frames["b"], 1.5), ("O_i", g.frames["i"], 1.0),
                  ("O_s", g.frames["s"], 1.0), ("O_e (RCM)", g.frames["e"], 1.0)]
        for i, axis in enumerate("xyz"):
            segs = [np.stack([T[:3, 3], T[:3, 3] + s * frame_length * T[:3, i]])
                    for _, T, s in frames]
            out.append(lines(f"frame axes {axis} (O_b, O_i, O_s, O_e)", segs, COLORS[axis], 5))
        out.append({"type": "scatter3d", "mode": "text", "name": "O_b", "x": [0.0],
                    "y": [0.0], "z": [-0.03], "text": ["O_b"], "hoverinfo": "skip"})
    return out


def robot_figure(q: ArrayLike | None = None, T_b_e: ArrayLike | None = None,
                 design: Design | None = None, *, slot: int = 0, all_slots: bool = True,
                 show_frames: bool = True, frame_length: float = FRAME_LENGTH,
                 title: str | None = None) -> Any:
    """Interactive plotly figure of the robot, with a menu over the FK solutions.

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
    show_frames : bool, keyword-only
        Triads of ``O_b``, ``O_i``, ``O_s``, ``O_e``.
    frame_length : float, keyword-only
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

    design = resolve_design(design)
    q = check_array(REFERENCE_Q if q is None else q, "q", (3,))
    T = resolve_rcm_frame(T_b_e, design)
    first = robot_geometry(q, T, design, slot=slot)
    if all_slots:
        sol = forward_kinematics(q, T, design, errors="flag")
        slots = [int(k) for k in np.flatnonzero(sol.valid)]
    else:
        slots = [first.slot]
    geoms = {k: (first if k == first.slot else robot_geometry(q, T, design, slot=k))
             for k in slots}
    fig = go.Figure()
    owner: list[int] = []
    for k in slots:
        for tr in _traces(geoms[k], show_frames=show_frames, frame_length=frame_length):
            tr["visible"] = k == first.slot
            tr["legendgroup"] = tr["name"]
            fig.add_trace(tr)
            owner.append(k)
    los, his = zip(*(g.bounds() for g in geoms.values()), strict=True)
    lo, hi = np.min(los, axis=0), np.max(his, axis=0)
    centre, half = 0.5 * (lo + hi), 0.5 * float(np.max(hi - lo)) + 0.05
    axis = {"showbackground": True, "backgroundcolor": "#f4f4f6", "gridcolor": "#cccccc"}
    qmm = ", ".join(f"{1000 * v:.0f}" for v in q)
    fig.update_layout(
        title={"text": title or f"ATHENA, q = ({qmm}) mm: {slot_label(first)}",
               "x": 0.02},
        scene={"xaxis": {**axis, "title": "x [m]",
                         "range": [centre[0] - half, centre[0] + half]},
               "yaxis": {**axis, "title": "y [m]",
                         "range": [centre[1] - half, centre[1] + half]},
               "zaxis": {**axis, "title": "z [m]",
                         "range": [centre[2] - half, centre[2] + half]},
               "aspectmode": "cube", "domain": {"x": [0.0, 0.74], "y": [0.0, 1.0]},
               "camera": {"eye": {"x": 1.4, "y": -1.5, "z": 0.8}}},
        legend={"x": 0.75, "y": 0.5, "yanchor": "middle", "font": {"size": 11}},
        margin={"l": 0, "r": 0, "t": 50, "b": 0}, paper_bgcolor="white")
    if len(slots) > 1:
        buttons = [{"label": slot_label(geoms[k]), "method": "update",
                    "args": [{"visible": [o == k for o in owner]},
                             {"title.text": f"ATHENA, q = ({qmm}) mm: {slot_label(geoms[k])}"}]}
                   for k in slots]
        fig.update_layout(updatemenus=[{
            "buttons": buttons, "direction": "down", "x": 0.99, "xanchor": "right", "y": 0.99,
            "yanchor": "top", "active": slots.index(first.slot), "showactive": True}])
    return fig


def write_html(path: str | Path, q: ArrayLike | None = None, T_b_e: ArrayLike | None = None,
               design: Design | None = None, *, slot: int = 0,
               include_plotlyjs: bool | str = True, **kwargs: Any) -> Path:
    """Write :func:`robot_figure` as an HTML page (self-contained by default).

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
    path = Path(path)
    fig = robot_figure(q, T_b_e, design, slot=slot, **kwargs)
    fig.write_html(path, include_plotlyjs=include_plotlyjs, full_html=True, div_id=HTML_DIV_ID,
                   config={"displaylogo": False, "responsive": True})
    return path
