"""A planned set-up as an interactive page (plotly): the patient, the port and the robot.

:func:`setup_figure` draws, in the patient's frame ``p`` (mm): the patient's surfaces
(the skin semi-transparent, the forbidden structures, the table), the target coloured
face by face by coverage (each face's centroid checked with every test of
:func:`athenakin.synthesis.evaluate_setup`, every clearance included), the port and the
instrument's nominal axis, and the robot, as :func:`~athenakin.plot.robot_figure` draws
it, at a few covered targets, placed by ``T_p_b``, with a menu that switches between
them. :func:`write_setup_html` writes it as a self-contained page (as
:func:`~athenakin.plot.write_html` does).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._typing import BoolArray, FloatArray
from .._validation import check_count, check_instance
from ..design import Design, resolve_design
from ..errors import InvalidInputError
from ._geometry import MM, RobotGeometry, cube_limits, robot_geometry
from ._html import CAMERA_EYE, _hover, _place, _traces, write_figure_page

if TYPE_CHECKING:  # pragma: no cover
    from ..synthesis import Patient, PatientMesh, Setup, SetupOptions

__all__ = ["setup_figure", "write_setup_html", "SETUP_VIEW_COLORS", "SETUP_HTML_DIV_ID",
           "MAX_VIEW_TARGETS", "target_coverage"]

#: ``id`` of the plot's ``<div>`` in pages written by :func:`write_setup_html`.
SETUP_HTML_DIV_ID = "athenakin-setup"
#: Most robots drawn at covered targets (one menu entry each).
MAX_VIEW_TARGETS = 12
#: Colour and opacity of each part of the patient (the coverage map's colours are those
#: of ``docs/figures/setup_coverage.png``; ``target``: a target not coloured by coverage,
#: as the app draws it).
SETUP_VIEW_COLORS: dict[str, tuple[str, float]] = {
    "skin": ("#d9a383", 0.15), "covered": ("#2a9d8f", 0.95), "not covered": ("#c1121f", 0.95),
    "target": ("#e08a00", 0.9),
    "forbidden": ("#6a4c93", 0.8), "table": ("#7f8790", 0.3), "port": ("#111111", 1.0),
    "axis": ("#111111", 1.0), "second_port": ("#3a86ff", 0.9)}
#: Length of the nominal axis drawn outside the skin, beyond the port, m.
AXIS_OUTSIDE = 0.08


def target_coverage(patient: Patient, setup: Setup, design: Design | None = None, *,
                    options: SetupOptions | None = None
                    ) -> tuple[FloatArray, BoolArray, FloatArray, Any]:
    """The points of the coverage map and whether the set-up covers each.

    A closed target's points are its faces' centroids (points of its surface, one per
    triangle); a point-cloud target's, its points. Each is checked with every test of
    :func:`athenakin.synthesis.evaluate_setup`, every clearance included
    (:func:`athenakin.synthesis.covered_samples`).

    Parameters
    ----------
    patient : Patient
    setup : Setup
    design : Design, optional
    options : SetupOptions, optional, keyword-only

    Returns
    -------
    points : ndarray, shape (n, 3)
        Patient frame, m.
    covered : ndarray of bool, shape (n,)
    q : ndarray, shape (n, 3)
        Actuator values of the IK, m (NaN where not reached).
    mode : ndarray of int, shape (n,)
        Assembly mode (+1 / -1), 0 where not reached.
    """
    from ..synthesis import Patient, Setup, covered_samples

    check_instance(patient, "patient", Patient)
    check_instance(setup, "setup", Setup)
    if patient.target is not None:
        V, F = patient.target.vertices, patient.target.faces
        points = V[F].mean(axis=1)
    else:
        assert patient.target_points is not None
        points = np.array(patient.target_points)
    covered, q, mode = covered_samples(patient, setup, design, points=points, options=options)
    return points, covered, q, mode


def _spread(points: FloatArray, k: int) -> list[int]:
    """``k`` indices of ``points`` spread along their principal axis (both ends first)."""
    if points.shape[0] <= k:
        return list(range(points.shape[0]))
    c = points - points.mean(axis=0)
    axis = np.linalg.svd(c, full_matrices=False)[2][0]
    order = np.argsort(c @ axis, kind="stable")
    return [int(order[i]) for i in np.unique(np.linspace(0, order.size - 1, k).round()
                                                .astype(int))]


def _mesh_trace(name: str, V: FloatArray, F: Any, color: str, opacity: float) -> dict[str, Any]:
    """A plotly mesh3d trace (mm) of triangles ``F`` of vertices ``V`` (m, patient frame)."""
    P = np.asarray(V) * MM
    F = np.asarray(F)
    return {"type": "mesh3d", "name": name, "x": P[:, 0].tolist(), "y": P[:, 1].tolist(),
            "z": P[:, 2].tolist(), "i": F[:, 0].tolist(), "j": F[:, 1].tolist(),
            "k": F[:, 2].tolist(), "color": color, "opacity": opacity, "flatshading": True,
            "showlegend": True, "hovertemplate": _hover(name, "p")}


def _patient_traces(patient: Patient, covered: BoolArray, points: FloatArray
                    ) -> list[dict[str, Any]]:
    """The patient's surfaces, the target split into its covered and not-covered parts."""
    out = []
    for m in patient.meshes:
        if m.role == "target":
            continue
        name = m.name if m.role in ("skin", "table") else f"forbidden: {m.name}"
        out.append(_mesh_trace(name, m.vertices, m.faces, *SETUP_VIEW_COLORS[m.role]))
    tm: PatientMesh | None = patient.target
    for label, keep in (("covered", covered), ("not covered", ~covered)):
        name = f"target: {label} ({int(np.count_nonzero(keep))} of {covered.size})"
        color, opacity = SETUP_VIEW_COLORS[label]
        if tm is not None:
            out.append(_mesh_trace(name, tm.vertices, tm.faces[keep], color, opacity))
        else:
            P = points[keep] * MM
            out.append({"type": "scatter3d", "mode": "markers", "name": name,
                        "x": P[:, 0].tolist(), "y": P[:, 1].tolist(), "z": P[:, 2].tolist(),
                        "marker": {"size": 3, "color": color, "opacity": opacity},
                        "hovertemplate": _hover(name, "p")})
    return out


def _port_traces(patient: Patient, setup: Setup) -> list[dict[str, Any]]:
    """The port, the nominal axis to the target's centre, each second port's instrument.

    The port a marker, the axis a dashed line from outside the skin, each second port's
    instrument its shaft (a line).
    """
    c = patient.target_centroid
    ends = np.stack([setup.port - AXIS_OUTSIDE * setup.axis, c]) * MM
    port = setup.port * MM
    name_axis = "instrument's nominal axis"
    color, opacity = SETUP_VIEW_COLORS["second_port"]
    shafts = [
        {"type": "scatter3d", "mode": "lines", "name": f"second port: {sp.name}",
         "x": (sp.shaft[:, 0] * MM).tolist(), "y": (sp.shaft[:, 1] * MM).tolist(),
         "z": (sp.shaft[:, 2] * MM).tolist(), "opacity": opacity,
         "line": {"color": color, "width": 8}, "hovertemplate": _hover(f"second port: "
                                                                       f"{sp.name}", "p")}
        for sp in patient.second_ports]
    return shafts + [
        {"type": "scatter3d", "mode": "lines", "name": name_axis, "x": ends[:, 0].tolist(),
         "y": ends[:, 1].tolist(), "z": ends[:, 2].tolist(),
         "line": {"color": SETUP_VIEW_COLORS["axis"][0], "width": 3, "dash": "dash"},
         "hovertemplate": _hover(name_axis, "p")},
        {"type": "scatter3d", "mode": "markers", "name": "port (RCM)",
         "x": [port[0]], "y": [port[1]], "z": [port[2]],
         "marker": {"size": 6, "color": SETUP_VIEW_COLORS["port"][0], "symbol": "diamond"},
         "hovertemplate": _hover("port (RCM)", "p")}]


def _robots(setup: Setup, design: Design, points: FloatArray, covered: BoolArray, q: Any,
            mode: Any, targets: int) -> list[tuple[int, RobotGeometry]]:
    """The robot at up to ``targets`` covered points, spread over the covered target."""
    from ..robot import slot_index

    idx = np.flatnonzero(covered)
    picks = idx[_spread(points[idx], targets)] if idx.size else idx
    # the slot of the covered configuration: the IK's mode, p > 0 (the tool inserted),
    # the first branch of the U-joint and the wrist (those that evaluate_setup checks)
    return [(int(i), robot_geometry(q[i], setup.T_b_e, design,
                                    slot=slot_index(int(mode[i]), 1, 1, 1)))
            for i in picks]


def _box(patient: Patient, setup: Setup, geoms: list[RobotGeometry]
         ) -> tuple[FloatArray, FloatArray]:
    """A cube (patient frame, m) around the skin, the port and every robot drawn."""
    pts = [patient.skin.bounds, setup.port[None]]
    for g in geoms:
        lo, hi = g.bounds()
        corners = np.array([[a, b, c] for a in (lo[0], hi[0]) for b in (lo[1], hi[1])
                            for c in (lo[2], hi[2])])
        pts.append(_place(corners, setup.T_p_b))
    allp = np.concatenate(pts)
    return cube_limits(allp.min(axis=0), allp.max(axis=0), 0.03)


def setup_figure(patient: Patient, setup: Setup, design: Design | None = None, *,
                 targets: int = 3, options: SetupOptions | None = None,
                 show_frames: bool = False, title: str | None = None) -> Any:
    """Interactive plotly figure of a set-up: the patient, the coverage map, the port, the robot.

    Everything is drawn in the patient's frame (the frame of the mesh files), in mm. The
    traces, by name:

    - ``skin``, ``table``, ``forbidden: NAME`` (one per forbidden structure): the
      patient's surfaces (mesh3d; the skin semi-transparent);
    - ``target: covered (K of N)``, ``target: not covered (N - K of N)``: the target's
      faces (or points of a point-cloud target) by coverage, each face's centroid
      checked (:func:`target_coverage`);
    - ``instrument's nominal axis`` and ``port (RCM)``; ``second port: NAME``, the shaft
      of each second port's instrument;
    - the robot at each of up to ``targets`` covered points, spread along the covered
      target's principal axis: the traces of :func:`~athenakin.plot.robot_figure`
      (``instrument``, ``base rail (x_b)``, ...), placed by ``setup.T_p_b``, in legend
      group ``target K``. A menu shows one robot at a time (the first at the start).

    Parameters
    ----------
    patient : Patient
    setup : Setup
        The set-up drawn (``plan.chosen``, or :func:`~athenakin.synthesis.read_setup`'s).
    design : Design, optional
        The robot (default :meth:`Design.default`; a set-up file holds its own).
    targets : int, keyword-only
        Covered targets at which the robot is drawn, 1 to :data:`MAX_VIEW_TARGETS`
        (fewer when fewer are covered; none when none is).
    options : SetupOptions, optional, keyword-only
        The tests of coverage (default ``SetupOptions()``, the planner's).
    show_frames : bool, keyword-only
        The robot's frame triads.
    title : str, optional, keyword-only

    Returns
    -------
    plotly.graph_objects.Figure

    Raises
    ------
    TypeError
        ``patient`` is not a :class:`~athenakin.synthesis.Patient` or ``setup`` not a
        :class:`~athenakin.synthesis.Setup`.
    InvalidInputError
        ``targets`` out of range.
    """
    import plotly.graph_objects as go

    from ._geometry import FRAME_LENGTH

    targets = check_count(targets, "targets", minimum=1, maximum=MAX_VIEW_TARGETS)
    if not isinstance(show_frames, bool):
        raise TypeError(f"show_frames: expected a bool, got {type(show_frames).__name__}")
    design = resolve_design(design)
    points, covered, q, mode = target_coverage(patient, setup, design, options=options)
    robots = _robots(setup, design, points, covered, q, mode, targets)
    box = _box(patient, setup, [g for _, g in robots])
    fig = go.Figure()
    for tr in _patient_traces(patient, covered, points) + _port_traces(patient, setup):
        fig.add_trace(tr)
    fixed = len(fig.data)
    owner: list[int] = []
    labels = []
    for k, (i, g) in enumerate(robots):
        p = points[i] * MM
        labels.append(f"target {k + 1}: ({p[0]:.0f}, {p[1]:.0f}, {p[2]:.0f}) mm")
        for tr in _traces(g, show_frames=show_frames, frame_length=FRAME_LENGTH, box=box,
                          T_w_b=setup.T_p_b, frame="p"):
            tr["visible"] = k == 0
            tr["legendgroup"] = f"target {k + 1}"
            fig.add_trace(tr)
            owner.append(k)
    who = patient.name or "the patient"
    share = 100.0 * float(np.mean(covered)) if covered.size else 0.0
    what = "faces" if patient.target is not None else "points"
    head = (f"set-up for {who}: {share:.1f} % of the target's {covered.size} {what} "
            f"covered; the robot at {len(robots)} covered targets")
    axis = {"showbackground": True, "backgroundcolor": "#f4f4f6", "gridcolor": "#cccccc"}
    names = {"x": "x_p (cranial)", "y": "y_p (left)", "z": "z_p (anterior)"}
    scene = {**{f"{c}axis": {**axis, "title": f"{names[c]} [mm]",
                             "range": [MM * box[0][n], MM * box[1][n]]}
                for n, c in enumerate("xyz")},
             "aspectmode": "cube", "domain": {"x": [0.0, 0.74], "y": [0.0, 1.0]},
             "camera": {"eye": dict(CAMERA_EYE)}}
    fig.update_layout(title={"text": title or head, "x": 0.02}, scene=scene,
                      legend={"x": 0.75, "y": 0.5, "yanchor": "middle", "font": {"size": 11}},
                      margin={"l": 0, "r": 0, "t": 50, "b": 0}, paper_bgcolor="white",
                      hoverlabel={"align": "left"})
    if len(robots) > 1:
        buttons = [{"label": lab, "method": "update",
                    "args": [{"visible": [True] * fixed + [o == k for o in owner]}]}
                   for k, lab in enumerate(labels)]
        fig.update_layout(updatemenus=[{
            "buttons": buttons, "direction": "down", "x": 0.99, "xanchor": "right",
            "y": 0.99, "yanchor": "top", "active": 0, "showactive": True}])
    return fig


def write_setup_html(path: str | Path, patient: Patient, setup: Setup,
                     design: Design | None = None, *, include_plotlyjs: bool | str = True,
                     **kwargs: Any) -> Path:
    """Write :func:`setup_figure` as an HTML page (self-contained by default).

    Parameters
    ----------
    path : str or Path
        The page written (atomically).
    patient, setup, design
        As in :func:`setup_figure`.
    include_plotlyjs : bool or str, keyword-only
        ``True`` embeds plotly.js (offline, about 4.7 MB); ``"cdn"`` links it.
    **kwargs
        Passed to :func:`setup_figure` (``targets``, ``options``, ``show_frames``,
        ``title``).

    Returns
    -------
    Path

    Raises
    ------
    InvalidInputError
        ``path`` is a folder or a device; ``include_plotlyjs`` is neither a bool nor
        ``"cdn"``; as :func:`setup_figure`.
    """
    from .._output import check_output_path

    p = check_output_path(path)
    if not (isinstance(include_plotlyjs, bool) or include_plotlyjs == "cdn"):
        raise InvalidInputError(f"include_plotlyjs: expected True, False or 'cdn', got "
                                f"{include_plotlyjs!r}")
    fig = setup_figure(patient, setup, design, **kwargs)
    return write_figure_page(p, fig, include_plotlyjs=include_plotlyjs,
                             div_id=SETUP_HTML_DIV_ID)
