"""Static 3-D views of the robot with matplotlib (PNG, SVG, PDF): one solution or all 16.

matplotlib is imported inside the functions, so that ``import athenakin.plot``
stays light.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_array
from ..design import Design, resolve_design
from ..errors import Reason
from ..robot import forward_kinematics
from ..robot._setup import resolve_rcm_frame
from ._geometry import RobotGeometry, robot_geometry

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.axes3d import Axes3D as Axes

__all__ = ["plot_robot", "plot_fk_solutions", "save_view", "COLORS", "slot_label",
           "arc_points"]

#: Colours of the parts (paper Fig. 2: parallel module blue, serial part red).
COLORS = {
    "rail": "#555555", "parallel": "#1f4fbf", "actuator": "#f28e0f", "joint": "#7f7f7f",
    "serial": "#cc2222", "sphere": "#8e44ad", "circle_k1": "#1f4fbf", "circle_k2": "#f28e0f",
    "x": "#d62728", "y": "#2ca02c", "z": "#1f77b4",
}
#: Default length of drawn frame axes, m.
FRAME_LENGTH = 0.08
#: Radius of the drawn spherical-joint arcs about the RCM, m.
ARC_RADIUS = 0.07
#: Default view direction (elevation, azimuth), degrees.
VIEW = (20.0, -35.0)


def slot_label(g: RobotGeometry) -> str:
    """Short text of a slot: ``slot 3: mode +1, p>0, U-, S-``."""
    return (f"slot {g.slot}: mode {g.mode:+d}, p{'>' if g.p_sign > 0 else '<'}0, "
            f"U{'+' if g.ujoint > 0 else '-'}, S{'+' if g.wrist > 0 else '-'}")


def arc_points(centre: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64],
               radius: float, n: int = 16) -> NDArray[np.float64]:
    """Great-circle arc of ``radius`` about ``centre`` from direction a to direction b, (n, 3)."""
    a = a / np.linalg.norm(a)
    b = b / np.linalg.norm(b)
    ang = float(np.arccos(np.clip(a @ b, -1.0, 1.0)))
    perp = b - (a @ b) * a
    norm = np.linalg.norm(perp)
    if norm == 0:
        return np.repeat((centre + radius * a)[None], n, axis=0)
    t = np.linspace(0.0, ang, n)[:, None]
    return centre + radius * (np.cos(t) * a + np.sin(t) * perp / norm)


def _point(ax: Axes, p: ArrayLike, **kw: Any) -> None:
    p = np.asarray(p, dtype=float)
    ax.scatter([p[0]], [p[1]], [p[2]], **kw)


def _points(ax: Axes, pts: NDArray[np.float64], **kw: Any) -> None:
    ax.scatter(pts[:, 0], pts[:, 1], pts[:, 2], **kw)


def _line(ax: Axes, a: ArrayLike, b: ArrayLike, **kw: Any) -> None:
    a, b = np.asarray(a), np.asarray(b)
    ax.plot([a[0], b[0]], [a[1], b[1]], [a[2], b[2]], **kw)


def _triad(ax: Axes, T: NDArray[np.float64], length: float, name: str | None,
           labels: bool) -> None:
    o = T[:3, 3]
    for i, c in enumerate("xyz"):
        _line(ax, o, o + length * T[:3, i], color=COLORS[c], lw=1.6, solid_capstyle="round")
    if labels and name:
        e = o + 0.6 * length * (T[:3, 0] - T[:3, 2])
        ax.text(e[0], e[1], e[2], name, fontsize=8, color="#222222")


def _cube_limits(lo: NDArray[np.float64], hi: NDArray[np.float64], pad: float = 0.05
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    c = 0.5 * (lo + hi)
    half = 0.5 * float(np.max(hi - lo)) + pad
    return c - half, c + half


def _draw(ax: Axes, g: RobotGeometry, *, show_frames: bool, show_labels: bool,
          show_circles: bool, frame_length: float) -> None:
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
    _line(ax, o - 0.03 * a1, o + 0.03 * a1, color="#333333", lw=2.0)     # u1 axis
    _line(ax, o, o + 0.06 * a2, color="#333333", lw=3.0)                 # fork along +u2
    _point(ax, P["tip"], s=14, color=COLORS["serial"], depthshade=False)
    _point(ax, P["RCM"], s=90, marker="*", color=COLORS["sphere"], depthshade=False)
    # the spherical joint at the RCM: its three axes and the arcs between them
    c = P["RCM"]
    ax_ = g.wrist_axes
    for k in range(3):
        _line(ax, c - 0.4 * ARC_RADIUS * ax_[k], c + 0.4 * ARC_RADIUS * ax_[k],
              color=COLORS["sphere"], lw=1.2)
    for k in range(2):
        ax.plot(*arc_points(c, ax_[k], ax_[k + 1], ARC_RADIUS).T, color=COLORS["sphere"], lw=2.2)
    if show_frames:
        _triad(ax, g.frames["b"], frame_length, "$O_b$", show_labels)
        _triad(ax, g.frames["i"], frame_length, "$O_i$", show_labels)
        _triad(ax, g.frames["s"], frame_length, "$O_s$", show_labels)
        _triad(ax, g.frames["e"], frame_length, "$O_e$ (RCM)", show_labels)
    if show_labels:
        for name in ("A", "B", "D", "C", "M"):
            p = P[name]
            ax.text(p[0], p[1], p[2] - 0.035, name, fontsize=9, color="#111111")
        if not show_frames:
            for name, key in (("$O_i$", "O_i"), ("$O_s$", "O_s"), ("RCM", "RCM")):
                p = P[key]
                ax.text(p[0], p[1], p[2] + 0.02, name, fontsize=9, color="#111111")
        ax.text(P["tip"][0], P["tip"][1], P["tip"][2], " tip", fontsize=8,
                color=COLORS["serial"])


def _style(ax: Axes, lo: NDArray[np.float64], hi: NDArray[np.float64],
           view: tuple[float, float]) -> None:
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect((1, 1, 1), zoom=1.1)
    ax.set_xlabel("x [m]", fontsize=8)
    ax.set_ylabel("y [m]", fontsize=8)
    ax.set_zlabel("z [m]", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.view_init(elev=view[0], azim=view[1])


def plot_robot(q: ArrayLike | None = None, T_b_e: ArrayLike | None = None,
               design: Design | None = None, *, slot: int = 0,
               geometry: RobotGeometry | None = None, ax: Axes | None = None,
               show_frames: bool = True, show_labels: bool = True, show_circles: bool = True,
               frame_length: float = FRAME_LENGTH, view: tuple[float, float] = VIEW,
               limits: tuple[ArrayLike, ArrayLike] | None = None, title: str | None = None
               ) -> Axes:
    """Draw the robot in one forward-kinematics solution on a 3-D matplotlib axes.

    Shows the base rail with carriages A and B, the bars of the parallel module
    (blue), the circles ``k1`` and ``k2`` (dashed), the ``q3`` actuator (orange),
    the intermediate and ``O_s`` frames, the U-joint at ``O_s``, the instrument
    (red) through the RCM, the spherical joint at the RCM (purple: its three axes
    and the arcs between them, the kinematic equivalent of the spherical five-bar)
    and the RCM frame E.

    Parameters
    ----------
    q : array-like, shape (3,), optional
        Actuators, m (default :data:`athenakin.robot.REFERENCE_Q`).
    T_b_e : array-like, shape (4, 4), optional
        RCM frame (default :func:`athenakin.default_rcm_frame`).
    design : Design, optional
    slot : int, keyword-only
        FK slot 0..15.
    geometry : RobotGeometry, keyword-only, optional
        Draw this instead of computing it from ``q``, ``T_b_e``, ``design``, ``slot``.
    ax : mpl_toolkits.mplot3d.Axes3D, keyword-only, optional
        Axes to draw on (a new figure otherwise).
    show_frames, show_labels, show_circles : bool, keyword-only
        Frame triads (x red, y green, z blue), text labels, circles ``k1``/``k2``.
    frame_length : float, keyword-only
        Length of the drawn frame axes, m.
    view : (float, float), keyword-only
        Elevation and azimuth, degrees.
    limits : (array-like, array-like), keyword-only, optional
        Axis box ``(lo, hi)`` (each shape (3,)); default: a cube around the robot.
    title : str, keyword-only, optional
        Default: ``q`` and the slot's labels.

    Returns
    -------
    Axes3D

    Raises
    ------
    KinematicsError
        The slot holds no solution.
    """
    import matplotlib.pyplot as plt

    g = geometry if geometry is not None else robot_geometry(q, T_b_e, design, slot=slot)
    if ax is None:
        fig = plt.figure(figsize=(7.0, 6.6))
        ax = fig.add_subplot(projection="3d")
        fig.subplots_adjust(left=0.0, right=0.96, bottom=0.02, top=0.92)
    _draw(ax, g, show_frames=show_frames, show_labels=show_labels, show_circles=show_circles,
          frame_length=frame_length)
    lo, hi = (_cube_limits(*g.bounds()) if limits is None else
              (np.asarray(limits[0], float), np.asarray(limits[1], float)))
    _style(ax, lo, hi, view)
    if title is None:
        qmm = ", ".join(f"{1000 * v:.0f}" for v in g.q)
        title = f"q = ({qmm}) mm\n{slot_label(g)}"
    ax.set_title(title, fontsize=9)
    return ax


def plot_fk_solutions(q: ArrayLike | None = None, T_b_e: ArrayLike | None = None,
                      design: Design | None = None, *, fig: Figure | None = None,
                      show_frames: bool = False, view: tuple[float, float] = VIEW,
                      title: str | None = None) -> Figure:
    """All 16 forward-kinematics solutions of one ``q`` side by side (4 x 4 grid).

    Row ``m * 2 + r`` (assembly mode, sign of ``p``), column ``2 b + w`` (U-joint and
    spherical-joint branches); that is, slot ``k`` is at row ``k // 4``, column
    ``k % 4``. Every panel uses the same axis box. A slot without a solution shows
    its reason instead.

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

    design = resolve_design(design)
    q = check_array(REFERENCE_Q if q is None else q, "q", (3,))
    T = resolve_rcm_frame(T_b_e, design)
    sol = forward_kinematics(q, T, design, errors="flag")
    geoms: dict[int, RobotGeometry] = {}
    for k in map(int, np.flatnonzero(sol.valid)):
        geoms[k] = robot_geometry(q, T, design, slot=k)
    if geoms:
        los, his = zip(*(g.bounds() for g in geoms.values()), strict=True)
        lo, hi = _cube_limits(np.min(los, axis=0), np.max(his, axis=0))
    else:
        lo, hi = -np.ones(3), np.ones(3)
    if fig is None:
        fig = plt.figure(figsize=(16, 16))
    for k in range(16):
        ax = fig.add_subplot(4, 4, k + 1, projection="3d")
        if k in geoms:
            plot_robot(geometry=geoms[k], ax=ax, show_frames=show_frames, show_labels=False,
                       limits=(lo, hi), view=view, title=slot_label(geoms[k]),
                       frame_length=0.08)
            for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
                axis.set_ticklabels([])
                axis.label.set_visible(False)
            ax.title.set_fontsize(11)
        else:
            ax.set_axis_off()
            ax.text2D(0.5, 0.5, f"slot {k}\nno solution:\n{Reason(int(sol.reason[k])).name}",
                      ha="center", va="center", transform=ax.transAxes, fontsize=10)
    qmm = ", ".join(f"{1000 * v:.0f}" for v in q)
    fig.suptitle(title or f"ATHENA: the {len(geoms)} forward-kinematics solutions of "
                 f"q = ({qmm}) mm", fontsize=15)
    fig.text(0.5, 0.005, "rows: assembly mode and sign of p; columns: U-joint branch (fork at "
             "O_s) and spherical-joint branch (purple arcs at the RCM); same axis box in every "
             "panel", ha="center", fontsize=11)
    fig.subplots_adjust(left=0.0, right=1.0, bottom=0.02, top=0.95, wspace=0.0, hspace=0.05)
    return fig


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
        The 16-solution grid (static) or a page that switches between the solutions
        (HTML; it does so in any case).
    dpi : int, keyword-only
        Resolution of raster output.
    **kwargs
        Passed to the drawing function.

    Returns
    -------
    Path

    Raises
    ------
    ValueError
        Unknown suffix.
    """
    import matplotlib.pyplot as plt

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".html":
        from ._html import write_html

        return write_html(path, q, T_b_e, design, slot=slot, **kwargs)
    if suffix not in (".png", ".svg", ".pdf"):
        raise ValueError(f"path: expected a .png, .svg, .pdf or .html file, got {path.name!r}")
    if all_solutions:
        fig = plot_fk_solutions(q, T_b_e, design, **kwargs)
    else:
        ax = plot_robot(q, T_b_e, design, slot=slot, **kwargs)
        fig = ax.figure
    try:
        fig.savefig(path, dpi=dpi)
    finally:
        plt.close(fig)
    return path
