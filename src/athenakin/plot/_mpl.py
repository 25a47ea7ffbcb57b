"""Static 3-D views of the robot with matplotlib (PNG, SVG, PDF): one solution or all 16.

matplotlib is imported inside the functions, so that ``import athenakin.plot``
stays light.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from .._toml import TomlOptions
from .._typing import FloatArray
from .._validation import check_array
from ..design import Design, resolve_design
from ..errors import InvalidInputError, Reason
from ..robot import forward_kinematics
from ..robot._setup import resolve_rcm_frame
from ._geometry import (
    ARC_RADIUS,
    COLORS,
    FRAME_LENGTH,
    MM,
    VIEW,
    RobotGeometry,
    arc_points,
    cube_limits,
    robot_geometry,
    slot_label,
    union_bounds,
)
from ._labels import _renderer, place_labels

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.axes3d import Axes3D as Axes

__all__ = ["plot_robot", "PlotOptions", "plot_fk_solutions", "save_view", "place_labels",
           "legend_handles"]


def _point(ax: Axes, p: ArrayLike, **kw: Any) -> None:
    p = np.asarray(p, dtype=float)
    ax.scatter([p[0]], [p[1]], [p[2]], **kw)


def _points(ax: Axes, pts: FloatArray, **kw: Any) -> None:
    ax.scatter(pts[:, 0], pts[:, 1], pts[:, 2], **kw)


def _line(ax: Axes, a: ArrayLike, b: ArrayLike, **kw: Any) -> None:
    a, b = np.asarray(a), np.asarray(b)
    ax.plot([a[0], b[0]], [a[1], b[1]], [a[2], b[2]], **kw)


def _triad(ax: Axes, T: FloatArray, length: float) -> None:
    o = T[:3, 3]
    for i, c in enumerate("xyz"):
        _line(ax, o, o + length * T[:3, i], color=COLORS[c], lw=1.6, solid_capstyle="round")


def legend_handles(*, show_frames: bool = True, show_circles: bool = True,
                   show_other_mode: bool = True) -> list[Any]:
    """Proxy artists naming the colour of every part (for ``ax.legend(handles=...)``).

    ``show_other_mode`` (with ``show_circles``) adds the open circle that marks ``O_i`` of
    the other assembly mode (the second intersection of ``k1`` and ``k2``).
    """
    from matplotlib.lines import Line2D

    h = [Line2D([], [], color=COLORS["rail"], lw=4, marker="s", ms=6,
                label="rail, carriages A, B (q1, q2)"),
         Line2D([], [], color=COLORS["parallel"], lw=2.6, label="parallel module"),
         Line2D([], [], color=COLORS["actuator"], lw=3.4, label="actuator q3"),
         Line2D([], [], color="#333333", lw=2.5, marker="o", mfc=COLORS["joint"], mec="k",
                label="U-joint at O_s (fork: +u2)"),
         Line2D([], [], color=COLORS["serial"], lw=3.0, label="instrument"),
         Line2D([], [], color=COLORS["sphere"], lw=2.2, marker="*", ms=9,
                label="RCM, spherical joint u3-u5")]
    if show_circles:
        h.append(Line2D([], [], color=COLORS["circle_k1"], lw=0.9, ls="--",
                        label="circles k1 (blue), k2 (orange)"))
        if show_other_mode:
            h.append(Line2D([], [], ls="none", marker="o", ms=5.5, mfc="none",
                            mec=COLORS["joint"], label="O_i of the other assembly mode"))
    if show_frames:
        h += [Line2D([], [], color=COLORS[c], lw=1.6, label=f"frame axis {c}") for c in "xyz"]
    return h


def _labels(g: RobotGeometry, *, show_frames: bool) -> list[tuple[str, FloatArray, str]]:
    P = g.points
    dark = "#111111"
    items = [("RCM" if not show_frames else "$O_e$ (RCM)", P["RCM"], COLORS["sphere"]),
             ("$O_s$", P["O_s"], dark), ("$O_i$", P["O_i"], dark), ("tip", P["tip"],
                                                                   COLORS["serial"]),
             ("A", P["A"], dark), ("B", P["B"], dark), ("M", P["M"], dark),
             ("D", P["D"], dark), ("C", P["C"], dark)]
    if show_frames:
        items.append(("$O_b$", g.frames["b"][:3, 3], dark))
    return items


def _draw(ax: Axes, g: RobotGeometry, *, show_frames: bool, show_circles: bool,
          frame_length: float, joint_scale: float = 1.0) -> None:
    P = g.points
    seg = g.segments()
    _line(ax, g.rail[0], g.rail[1], color=COLORS["rail"], lw=4, alpha=0.8)
    if show_circles:
        ax.plot(*g.k1.T, color=COLORS["circle_k1"], lw=0.9, ls="--", alpha=0.7)
        ax.plot(*g.k2_arc.T, color=COLORS["circle_k2"], lw=0.9, ls="--", alpha=0.7)
        other = g.intersections[1 if g.mode > 0 else 0]
        if np.all(np.isfinite(other)):
            _point(ax, other, s=30, facecolors="none", edgecolors=COLORS["joint"],
                   depthshade=False)  # O_i of the other assembly mode
    for name in ("link_a1", "link_b1", "link_a3", "link_b3", "carrier_y", "carrier_z",
                 "offset_l4"):
        _line(ax, *seg[name], color=COLORS["parallel"], lw=2.6, solid_capstyle="round")
    _line(ax, *seg["actuator_q3"], color=COLORS["actuator"], lw=3.4, solid_capstyle="round")
    _line(ax, *seg["instrument"], color=COLORS["serial"], lw=3.0, solid_capstyle="round")
    rcm_on_shaft = 0.0 <= g.p <= g.design.tool_length
    if not rcm_on_shaft:
        _line(ax, P["O_s"], P["RCM"], color=COLORS["serial"], lw=1.0, ls=":")
    carriages = np.stack([P["A"], P["B"]])
    _points(ax, carriages, s=70, marker="s", color=COLORS["rail"], depthshade=False)
    joints = np.stack([P["D"], P["O_i"], P["C"]])
    _points(ax, joints, s=22, color=COLORS["joint"], depthshade=False)
    _point(ax, P["O_s"], s=55, marker="o", color=COLORS["joint"], edgecolor="k",
           depthshade=False)  # U-joint
    o, (a1, a2) = P["O_s"], g.ujoint_axes
    js = joint_scale
    _line(ax, o - 0.03 * js * a1, o + 0.03 * js * a1, color="#333333", lw=2.0)  # u1 axis
    _line(ax, o, o + 0.06 * js * a2, color="#333333", lw=3.0)                   # fork, +u2
    _point(ax, P["tip"], s=14, color=COLORS["serial"], depthshade=False)
    _point(ax, P["RCM"], s=90, marker="*", color=COLORS["sphere"], depthshade=False)
    # the spherical joint at the RCM: its three axes and the arcs between them
    c = P["RCM"]
    ax_ = g.wrist_axes
    r = ARC_RADIUS * js
    for k in range(3):
        _line(ax, c - 0.4 * r * ax_[k], c + 0.4 * r * ax_[k], color=COLORS["sphere"], lw=1.2)
    for k in range(2):
        ax.plot(*arc_points(c, ax_[k], ax_[k + 1], r).T, color=COLORS["sphere"], lw=2.2)
    if show_frames:
        for key in ("b", "i", "s", "e"):
            _triad(ax, g.frames[key], frame_length)


def _drawn_lines(g: RobotGeometry, *, show_frames: bool, show_circles: bool,
                 frame_length: float, joint_scale: float = 1.0) -> list[FloatArray]:
    """Every polyline the view draws (m), which labels keep clear of."""
    c, r = g.points["RCM"], ARC_RADIUS * joint_scale
    out = [np.stack(ab) for ab in g.segments().values()] + [g.rail]
    out += [arc_points(c, g.wrist_axes[k], g.wrist_axes[k + 1], r) for k in range(2)]
    out += [np.stack([c - 0.4 * r * a, c + 0.4 * r * a]) for a in g.wrist_axes]
    o = g.points["O_s"]
    out.append(np.stack([o, o + 0.06 * joint_scale * g.ujoint_axes[1]]))
    if show_circles:
        out += [g.k1, g.k2_arc]
    if show_frames:
        for key in ("b", "i", "s", "e"):
            T = g.frames[key]
            out += [np.stack([T[:3, 3], T[:3, 3] + frame_length * T[:3, i]]) for i in range(3)]
    return out


def _mm_axes(ax: Axes) -> None:
    """Tick labels in mm (data stay in m) and axis labels that say so."""
    from matplotlib.ticker import FuncFormatter, MaxNLocator

    fmt = FuncFormatter(lambda v, _pos: f"{v * MM:.0f}")
    for axis, name in ((ax.xaxis, "x"), (ax.yaxis, "y"), (ax.zaxis, "z")):
        axis.set_major_locator(MaxNLocator(5))
        axis.set_major_formatter(fmt)
        axis.set_label_text(f"{name}$_b$ [mm]", fontsize=8)


def _style(ax: Axes, lo: FloatArray, hi: FloatArray,
           view: tuple[float, float], zoom: float = 0.95, cube: bool = True) -> None:
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect((1, 1, 1) if cube else tuple(hi - lo), zoom=zoom)
    _mm_axes(ax)
    ax.tick_params(labelsize=7, pad=0)
    ax.view_init(elev=view[0], azim=view[1])


@dataclasses.dataclass(frozen=True)
class PlotOptions(TomlOptions):
    """How :func:`plot_robot` draws: what is shown, sizes, camera and axis box.

    Every field is checked at construction (a named error). A ``[plot]`` table of a
    TOML file holds them (:meth:`to_toml`, :meth:`from_toml`).

    Attributes
    ----------
    show_frames, show_labels, show_circles, show_legend : bool
        Frame triads (x red, y green, z blue), text labels, circles ``k1``/``k2``, the
        legend of the colours.
    frame_length : float
        Length of the drawn frame axes, m, in (0, 10].
    view : (float, float)
        Elevation and azimuth, degrees.
    limits : ((float, float, float), (float, float, float)) or None
        Axis box ``(lo, hi)``, m, ``lo < hi``; None: a cube around the robot.
    joint_scale : float
        Size factor of the U-joint fork and the spherical-joint arcs (the branch cues),
        in (0, 10].

    Examples
    --------
    >>> from athenakin.plot import PlotOptions
    >>> PlotOptions(show_labels=False, view=(30, 45)).view
    (30.0, 45.0)
    """

    TOML_TABLE: ClassVar[str] = "plot"

    show_frames: bool = True
    show_labels: bool = True
    show_circles: bool = True
    show_legend: bool = True
    frame_length: float = FRAME_LENGTH
    view: tuple[float, float] = VIEW
    limits: tuple[tuple[float, float, float], tuple[float, float, float]] | None = None
    joint_scale: float = 1.0

    def __post_init__(self) -> None:
        from ._geometry import check_length, check_view

        put = object.__setattr__
        for name in ("show_frames", "show_labels", "show_circles", "show_legend"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise TypeError(f"{name}: expected True or False, got "
                                f"{type(getattr(self, name)).__name__}")
            put(self, name, bool(getattr(self, name)))
        put(self, "frame_length", check_length(self.frame_length, "frame_length"))
        put(self, "joint_scale", check_length(self.joint_scale, "joint_scale"))
        put(self, "view", check_view(self.view))
        if self.limits is not None:
            lims = check_array(self.limits, "limits", (3,))  # type: ignore[arg-type]
            if lims.shape != (2, 3) or not np.all(lims[0] < lims[1]):
                raise InvalidInputError(f"limits: expected (lo, hi), two points (m) with lo < "
                                        f"hi, got {lims.tolist()}")
            put(self, "limits", (tuple(map(float, lims[0])), tuple(map(float, lims[1]))))


def plot_robot(q: ArrayLike | None = None, T_b_e: ArrayLike | None = None,
               design: Design | None = None, *, slot: int = 0,
               geometry: RobotGeometry | None = None, ax: Axes | None = None,
               bodies: Any = None, title: str | None = None,
               legend_extra: list[Any] | None = None,
               options: PlotOptions | None = None) -> Axes:
    """Draw the robot in one forward-kinematics solution on a 3-D matplotlib axes.

    Shows the base rail with carriages A and B, the bars of the parallel module
    (blue), the circles ``k1`` and ``k2`` (dashed), the ``q3`` actuator (orange),
    the intermediate and ``O_s`` frames, the U-joint at ``O_s``, the instrument
    (red) through the RCM, the spherical joint at the RCM (purple: its three axes
    and the arcs between them, the kinematic equivalent of the spherical five-bar)
    and the RCM frame E. Lengths are drawn in metres and labelled in millimetres
    on every axis; labels are placed so that none overlaps another
    (:func:`place_labels`).

    Parameters
    ----------
    q, T_b_e, design, slot
        As in :func:`~athenakin.plot.robot_geometry` (defaults: the reference ``q``, the
        default RCM frame and design, slot 0).
    geometry : RobotGeometry, keyword-only, optional
        Draw this instead of computing it from ``q``, ``T_b_e``, ``design``, ``slot``.
    ax : mpl_toolkits.mplot3d.Axes3D, keyword-only, optional
        Axes to draw on (a new figure otherwise).
    bodies : athenakin.collision.Bodies or True, keyword-only, optional
        Also draw the bodies as solids (shaded capsules), the pair with the least
        clearance coloured and the clearance written
        (:func:`~athenakin.plot.draw_bodies`); ``True``: the default bodies.
    title : str, keyword-only, optional
        Default: ``q`` and the slot's labels.
    legend_extra : list of matplotlib artists, keyword-only, optional
        More legend handles (e.g. what the caller drew before).
    options : PlotOptions, keyword-only, optional
        What is shown and how (every field: :class:`PlotOptions`); default
        ``PlotOptions()``.

    Returns
    -------
    Axes3D

    Raises
    ------
    KinematicsError
        The slot holds no solution.
    """
    import matplotlib.pyplot as plt

    opts = PlotOptions() if options is None else options
    _check_plot_robot(opts, geometry, ax, legend_extra)
    g = geometry if geometry is not None else robot_geometry(q, T_b_e, design, slot=slot)
    if ax is None:
        fig = plt.figure(figsize=(7.0, 6.6))
        ax = fig.add_subplot(projection="3d")
        fig.subplots_adjust(left=0.02, right=0.93, bottom=0.04, top=0.93)
    _draw(ax, g, show_frames=opts.show_frames, show_circles=opts.show_circles,
          frame_length=opts.frame_length, joint_scale=opts.joint_scale)
    if bodies is not None and bodies is not False:       # solids: plot/_solids.py
        from ._solids import draw_bodies

        draw_bodies(ax, g.q, g.T_b_e, g.design, slot=g.slot,
                    bodies=None if bodies is True else bodies)
    lo, hi = (cube_limits(*g.bounds()) if opts.limits is None else
              (np.asarray(opts.limits[0], float), np.asarray(opts.limits[1], float)))
    _style(ax, lo, hi, opts.view)
    if title is None:
        qmm = ", ".join(f"{MM * v:.0f}" for v in g.q)
        title = f"q = ({qmm}) mm\n{slot_label(g)}"
    ax.set_title(title, fontsize=9)
    boxes = [_legend_box(ax, g, opts, legend_extra)] if opts.show_legend else []
    if opts.show_labels:
        drawn = _drawn_lines(g, show_frames=opts.show_frames, show_circles=opts.show_circles,
                             frame_length=opts.frame_length, joint_scale=opts.joint_scale)
        place_labels(ax, _labels(g, show_frames=opts.show_frames), lines=drawn, boxes=boxes)
    return ax


def _check_plot_robot(opts: object, geometry: object, ax: object, legend_extra: object) -> None:
    """The arguments of :func:`plot_robot` that it does not pass on, else a named error."""
    from .._validation import check_axes, check_instance
    from ._geometry import RobotGeometry

    check_instance(opts, "options", PlotOptions)
    if geometry is not None:
        check_instance(geometry, "geometry", RobotGeometry)
    check_axes(ax, "ax")
    if legend_extra is not None and (not isinstance(legend_extra, (list, tuple)) or not all(
            callable(getattr(a, "get_label", None)) for a in legend_extra)):
        raise TypeError(f"legend_extra: expected a list of matplotlib artists or None, got "
                        f"{type(legend_extra).__name__}")


def _legend_box(ax: Axes, g: RobotGeometry, opts: PlotOptions,
                legend_extra: list[Any] | None) -> FloatArray:
    """Draw the legend of the colours (and ``legend_extra``); its display box (px)."""
    other = g.intersections[1 if g.mode > 0 else 0]
    leg = ax.legend(handles=legend_handles(show_frames=opts.show_frames,
                                           show_circles=opts.show_circles,
                                           show_other_mode=bool(np.all(np.isfinite(other))))
                    + list(legend_extra or []),
                    loc="upper left", fontsize=6.5, framealpha=0.9, borderaxespad=0.2)
    ax.apply_aspect()
    return np.asarray(leg.get_window_extent(_renderer(ax.figure)).extents)


def plot_fk_solutions(q: ArrayLike | None = None, T_b_e: ArrayLike | None = None,
                      design: Design | None = None, *, fig: Figure | None = None,
                      show_frames: bool = False, view: tuple[float, float] = VIEW,
                      title: str | None = None) -> Figure:
    """All 16 forward-kinematics solutions of one ``q`` side by side (4 x 4 grid).

    Row ``m * 2 + r`` (assembly mode, sign of ``p``), column ``2 b + w`` (U-joint and
    spherical-joint branches); that is, slot ``k`` is at row ``k // 4``, column
    ``k % 4``. Every panel uses the same axis box, fitted tightly around all the
    solutions, and a title naming its assembly mode and branch signs; the U-joint
    fork (along ``+u2``) and the spherical-joint arcs, which tell the branches of
    one row apart, are drawn twice their usual size. A slot without a solution
    shows its reason instead. One legend names the colours.

    Parameters
    ----------
    q : array-like, shape (3,), optional
    T_b_e : array-like, shape (4, 4), optional
    design : Design, optional
    fig : matplotlib.figure.Figure, keyword-only, optional
    show_frames : bool, keyword-only
        Frame triads in every panel (cluttered at this size; off by default).
    view : (float, float), keyword-only
    title : str, keyword-only, optional

    Returns
    -------
    Figure
    """
    import matplotlib.pyplot as plt

    from ..robot import REFERENCE_Q
    from ._geometry import check_view

    view = check_view(view)
    if fig is not None and not callable(getattr(fig, "add_subplot", None)):
        raise TypeError(f"fig: expected a matplotlib Figure or None, got {type(fig).__name__}")
    design = resolve_design(design)
    q = check_array(REFERENCE_Q if q is None else q, "q", (3,))
    T = resolve_rcm_frame(T_b_e, design)
    sol = forward_kinematics(q, T, design, errors="flag")
    geoms = {k: robot_geometry(q, T, design, slot=k) for k in map(int, np.flatnonzero(sol.valid))}
    lo, hi = _common_box(list(geoms.values()))
    panel = PlotOptions(show_frames=show_frames, show_labels=False, show_legend=False,
                        limits=(_xyz(lo), _xyz(hi)), view=view, frame_length=0.08, joint_scale=2.0)
    if fig is None:
        fig = plt.figure(figsize=(16, 17))
    for k in range(16):
        ax = fig.add_subplot(4, 4, k + 1, projection="3d")
        if k in geoms:
            _solution_panel(ax, geoms[k], panel)
        else:
            ax.set_axis_off()
            ax.text2D(0.5, 0.5, f"slot {k}\nno solution:\n{Reason(int(sol.reason[k])).name}",
                      ha="center", va="center", transform=ax.transAxes, fontsize=10)
    qmm = ", ".join(f"{MM * v:.0f}" for v in q)
    fig.suptitle(title or f"ATHENA: the {len(geoms)} forward-kinematics solutions of "
                 f"q = ({qmm}) mm", fontsize=18)
    fig.legend(handles=legend_handles(show_frames=show_frames), loc="lower center", ncol=4,
               fontsize=10, frameon=False, bbox_to_anchor=(0.5, 0.03))
    fig.text(0.5, 0.004, "rows: assembly mode and sign of p; columns: U-joint branch (U-joint "
             "+ / -: sign of sin u2, the fork at O_s points along +u2)\nand spherical-joint "
             "branch (wrist + / -: sign of sin u4, the purple arcs at the RCM); one scale in "
             f"every panel (orthographic view; bar: {SCALE_BAR * MM:.0f} mm)",
             ha="center", fontsize=11)
    fig.subplots_adjust(left=0.0, right=1.0, bottom=0.09, top=0.925, wspace=0.0, hspace=0.22)
    return fig


def _xyz(v: FloatArray) -> tuple[float, float, float]:
    """A point as the tuple of floats that :class:`PlotOptions` ``limits`` holds."""
    return float(v[0]), float(v[1]), float(v[2])


def _common_box(geoms: list[RobotGeometry], pad: float = 0.01
                ) -> tuple[FloatArray, FloatArray]:
    """Axis box ``(lo, hi)`` (m) tight around every geometry plus ``pad`` (none: a 2 m cube)."""
    if not geoms:
        return -np.ones(3), np.ones(3)
    lo, hi = union_bounds(geoms)
    return lo - pad, hi + pad


def _solution_panel(ax: Axes, g: RobotGeometry, panel: PlotOptions) -> None:
    """One panel of :func:`plot_fk_solutions`: orthographic, no panes, a scale bar, a title."""
    assert panel.limits is not None
    lo, hi = np.asarray(panel.limits[0], float), np.asarray(panel.limits[1], float)
    plot_robot(geometry=g, ax=ax, title="", options=panel)
    ax.set_proj_type("ortho")           # one scale everywhere: the scale bar holds
    ax.set_box_aspect(tuple(hi - lo), zoom=1.45)
    ax.set_axis_off()                   # no panes: the robot fills the panel
    _scale_bar(ax, lo, hi, panel.view, SCALE_BAR)
    # the title sits above the drawing, on a white band that lines may pass behind
    heading = ax.set_title(_panel_title(g), fontsize=GRID_TITLE_SIZE, y=1.02,
                           va="bottom", linespacing=1.15,
                           bbox={"facecolor": "white", "edgecolor": "none",
                                 "alpha": 0.92, "pad": 1.5})
    heading.set_zorder(1000)


#: Length of the scale bar of each panel of :func:`plot_fk_solutions`, m.
SCALE_BAR = 0.1
#: Font size of the panel titles of :func:`plot_fk_solutions`, pt.
GRID_TITLE_SIZE = 14.0


def _scale_bar(ax: Axes, lo: FloatArray, hi: FloatArray,
               view: tuple[float, float], length: float) -> None:
    """A bar of ``length`` m parallel to the screen, at the lower left of the axis box.

    With an orthographic projection and an equal-scale box a segment perpendicular to
    the line of sight shows at true scale, whatever the view.
    """
    elev, azim = np.radians(view[0]), np.radians(view[1])
    right = np.array([-np.sin(azim), np.cos(azim), 0.0])
    up = np.array([-np.sin(elev) * np.cos(azim), -np.sin(elev) * np.sin(azim), np.cos(elev)])
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                        for z in (lo[2], hi[2])])
    c = 0.5 * (lo + hi)
    r, u = (corners - c) @ right, (corners - c) @ up
    start = c + (r.min() + 0.04 * np.ptp(r)) * right + (u.min() + 0.04 * np.ptp(u)) * up
    end = start + length * right
    ax.plot(*np.stack([start, end]).T, color="k", lw=2.5, solid_capstyle="butt", clip_on=False)
    for p in (start, end):
        tick = np.stack([p - 0.008 * up, p + 0.008 * up])
        ax.plot(*tick.T, color="k", lw=1.2, clip_on=False)
    mid = 0.5 * (start + end) + 0.012 * up
    ax.text(*mid, f"{length * MM:.0f} mm", ha="center", va="bottom", fontsize=11)


def _panel_title(g: RobotGeometry) -> str:
    """Two lines: slot, assembly mode and sign of p; the two branch signs in words."""
    sgn = {1: "+", -1: "-"}
    return (f"slot {g.slot}: mode {g.mode:+d}, p {'>' if g.p_sign > 0 else '<'} 0\n"
            f"U-joint {sgn[g.ujoint]}, wrist {sgn[g.wrist]}")


#: Largest ``dpi`` of :func:`save_view` (a 6.4 x 4.8 in figure is then 7680 x 5760 px).
MAX_DPI = 1200


def save_view(path: str | Path, q: ArrayLike | None = None, T_b_e: ArrayLike | None = None,
              design: Design | None = None, *, slot: int = 0, all_solutions: bool = False,
              dpi: int = 120, **kwargs: Any) -> Path:
    """Write a view of the robot; the file suffix picks the format.

    ``.png``, ``.svg``, ``.pdf``: matplotlib (:func:`plot_robot`, or
    :func:`plot_fk_solutions` with ``all_solutions``); ``.html``: an interactive,
    self-contained page (:func:`~athenakin.plot.write_html`).

    Parameters
    ----------
    path : str or Path
    q, T_b_e, design, slot
        As in :func:`plot_robot`.
    all_solutions : bool, keyword-only
        The 16-solution grid (static) or, in HTML, every solution at once with one
        legend entry per slot (without it the page has a menu over the solutions).
    dpi : int, keyword-only
        Resolution of raster output, 1 to :data:`MAX_DPI`.
    **kwargs
        Passed to the drawing function (for :func:`plot_robot`: ``bodies``, ``title``,
        ``options``, a :class:`PlotOptions`).

    Returns
    -------
    Path
        ``path``, written as a PNG, SVG, PDF or HTML file.

    Raises
    ------
    ValueError
        A suffix other than ``.png``, ``.svg``, ``.pdf`` or ``.html``.
    """
    import matplotlib.pyplot as plt

    from .._output import check_output_path, naming_path
    from .._validation import check_count

    path = check_output_path(path)
    dpi = check_count(dpi, "dpi", minimum=1, maximum=MAX_DPI)
    suffix = path.suffix.lower()
    if suffix == ".html":
        from ._html import write_html

        return write_html(path, q, T_b_e, design, slot=slot, all_solutions=all_solutions,
                          **kwargs)
    if suffix not in (".png", ".svg", ".pdf"):
        raise ValueError(f"path: expected a .png, .svg, .pdf or .html file, got {path.name!r}")
    if all_solutions:
        fig = plot_fk_solutions(q, T_b_e, design, **kwargs)
    else:
        ax = plot_robot(q, T_b_e, design, slot=slot, **kwargs)
        fig = ax.figure
    try:
        with naming_path(path):
            fig.savefig(path, dpi=dpi)
    finally:
        plt.close(fig)
    return path
