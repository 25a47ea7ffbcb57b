"""Figures of a planned trajectory (matplotlib, imported lazily).

* :func:`plot_actuators`: ``q``, ``qd``, ``qdd`` (and ``qddd``) over time with the
  stroke, velocity, acceleration (and jerk) limits drawn;
* :func:`plot_tip_path`: the tool-tip path in 3-D about the RCM (frame E), with the
  instrument shaft drawn through the RCM at a few samples;
* :func:`plot_singularity_distance`: each singularity measure over its margin
  (1 = on the margin) over time.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np

from .._figstyle import tidy_3d_axes
from .._validation import check_axes, check_count, check_instance, check_path
from ._plan import Trajectory
from ._safety import MEASURE_NAMES

__all__ = ["plot_actuators", "plot_tip_path", "plot_singularity_distance", "render_plots",
           "plot_paths", "save_plots", "waypoint_labels"]

_COLORS = ("tab:blue", "tab:orange", "tab:green")
#: Waypoints closer than this (mm) share one label in :func:`plot_tip_path`.
WAYPOINT_TOL = 0.5
#: Millimetres per metre: figures show lengths in mm.
MM = 1e3

_MEASURE_LABELS = {
    "half_chord": "half-chord k1∩k2 (mode boundary)",
    "h": "|h| (h = 0)",
    "link": "min(l1, l3) - |h|",
    "sin_u2": "|sin u2| (U-joint)",
    "sin_u4": "|sin u4| (spherical joint)",
    "p": "p (O_s to RCM)",
    "depth": "tip depth beyond RCM",
    "cond": "cond margin / cond(d tip / d q)",
}


#: Largest ``dpi`` of the saved figures (three figures at 20000 dpi are gigabytes).
MAX_DPI = 1200


def plot_actuators(traj: Trajectory, *, axes: Any = None) -> Any:
    """Actuator position, velocity, acceleration (and jerk) over time, limits dashed.

    Lengths in mm (as in every figure of athenakin), time in s.

    Parameters
    ----------
    traj : Trajectory
    axes : sequence of matplotlib Axes, optional
        3 (or 4 with jerk) axes stacked vertically; created when omitted.

    Returns
    -------
    ndarray of Axes
    """
    check_instance(traj, "traj", Trajectory)
    if axes is not None:
        for a in np.atleast_1d(np.asarray(axes, dtype=object)).ravel():
            check_axes(a, "axes")
    import matplotlib.pyplot as plt

    limits = traj.limits
    rows = [("q", MM * traj.q, "position [mm]", None),
            ("qd", MM * traj.qd, "velocity [mm/s]", MM * np.asarray(limits.v_max)),
            ("qdd", MM * traj.qdd, "acceleration [mm/s²]", MM * np.asarray(limits.a_max))]
    if traj.qddd is not None:
        rows.append(("qddd", MM * traj.qddd, "jerk [mm/s³]", MM * np.asarray(limits.j_max)))
    if axes is None:
        _, axes = plt.subplots(len(rows), 1, sharex=True, figsize=(9, 2.3 * len(rows) + 0.8),
                               constrained_layout=True)
    axes = np.atleast_1d(axes)
    lo, hi = MM * traj.design.stroke_min, MM * traj.design.stroke_max
    for ax, (_, data, label, lim) in zip(axes, rows, strict=True):
        for i in range(3):
            ax.plot(traj.t, data[:, i], color=_COLORS[i], lw=1.2, label=f"q{i + 1}")
            if lim is None:
                for b in (lo[i], hi[i]):
                    if np.isfinite(b):
                        ax.axhline(b, color=_COLORS[i], ls="--", lw=0.8)
            elif i == 0 or not np.allclose(lim, lim[0]):
                for s in (-1, 1):
                    ax.axhline(s * lim[i], color="k" if np.allclose(lim, lim[0])
                               else _COLORS[i], ls="--", lw=0.8)
        for tw in traj.waypoint_times:
            ax.axvline(tw, color="0.8", lw=0.6, zorder=0)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper right", ncol=3, fontsize=8)
    axes[0].set_title("actuators (dashed: stroke limits, ±limits; grey: waypoints)")
    axes[-1].set_xlabel("time [s]")
    return axes


def plot_tip_path(traj: Trajectory, *, ax: Any = None, context: bool = True,
                  shafts: int = 8) -> Any:
    """The tool-tip path in 3-D in the RCM frame E (mm).

    Parameters
    ----------
    traj : Trajectory
    ax : matplotlib 3-D Axes, optional
    context : bool
        Also draw the RCM, the path of ``O_s`` and the instrument (from ``O_s``
        through the RCM to the tip) at ``shafts`` samples; without it the view is
        zoomed on the tip path and its waypoints (numbered).
    shafts : int
        Number of instrument positions drawn with ``context``.

    Returns
    -------
    Axes
    """
    check_instance(traj, "traj", Trajectory)
    check_axes(ax)
    shafts = check_count(shafts, "shafts", minimum=0, maximum=10_000)
    import matplotlib.pyplot as plt

    if ax is None:
        fig = plt.figure(figsize=(7, 6), constrained_layout=True)
        ax = fig.add_subplot(projection="3d")
    tip = traj.tip_e * 1e3
    ax.plot(tip[:, 0], tip[:, 1], tip[:, 2], color="tab:red", lw=1.8, label="tool-tip path")
    wp = traj.waypoints_e * 1e3
    ax.scatter(wp[:, 0], wp[:, 1], wp[:, 2], color="k", s=18, label="waypoints")
    pts = tip
    if context:
        L = traj.design.tool_length
        O_e = (traj.tip_e - L * traj.direction_e) * 1e3
        idx = np.unique(np.linspace(0, len(traj.t) - 1, max(shafts, 2)).astype(int))
        for j, i in enumerate(idx):
            ax.plot([O_e[i, 0], tip[i, 0]], [O_e[i, 1], tip[i, 1]], [O_e[i, 2], tip[i, 2]],
                    color="tab:gray", lw=0.8, alpha=0.7, label="instrument" if j == 0 else None)
        ax.plot(O_e[:, 0], O_e[:, 1], O_e[:, 2], color="tab:blue", lw=1.0, label="O_s")
        ax.scatter([0], [0], [0], color="tab:purple", s=60, marker="*", label="RCM")
        pts = np.concatenate([tip, O_e, np.zeros((1, 3))])
        # at this scale the tip path is a few pixels: ring it and give its size
        ext = np.ptp(tip, axis=0)
        ctr = 0.5 * (tip.max(axis=0) + tip.min(axis=0))
        ax.scatter(*ctr, s=700, facecolors="none", edgecolors="tab:red", lw=1.2,
                   depthshade=False)
        ax.text2D(0.98, 0.98, "red ring: the tool-tip path,\n" + " x ".join(
            f"{e:.0f}" for e in ext) + " mm (the tip-path view\nzooms on it)",
            transform=ax.transAxes, fontsize=8, color="tab:red", ha="right", va="top")
        ax.set_title("instrument about the RCM (frame E)")
    else:
        for text, w in waypoint_labels(wp):
            ax.text(w[0], w[1], w[2], f" {text}", fontsize=8)
        ax.set_title("tool-tip path (frame E; numbers: waypoints)")
    # a cube around what is drawn, with a margin that keeps the labels of the outermost
    # waypoints inside the box
    c, r = (pts.max(0) + pts.min(0)) / 2, max((pts.max(0) - pts.min(0)).max() / 2, 1e-3)
    r *= 1.12
    for setter, ci in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), c, strict=True):
        setter(ci - r, ci + r)
    ax.set_box_aspect((1, 1, 1))
    tidy_3d_axes(ax, nbins=5, labelsize=8)
    ax.set_xlabel("x_e [mm]")
    ax.set_ylabel("y_e [mm]")
    ax.set_zlabel("z_e [mm]")
    ax.legend(loc="upper left", fontsize=8)
    return ax


def waypoint_labels(waypoints: np.ndarray, *, tol: float = WAYPOINT_TOL
                    ) -> list[tuple[str, np.ndarray]]:
    """One label per distinct waypoint place: ``"0, 4"`` where waypoints 0 and 4 coincide.

    Parameters
    ----------
    waypoints : ndarray, shape (K, 3)
        Waypoints in drawing units (mm).
    tol : float
        Waypoints closer than this (same units) share a label.

    Returns
    -------
    list of (str, ndarray shape (3,))
        Text and position, in the order of each place's first waypoint.
    """
    places: list[tuple[list[int], np.ndarray]] = []
    for k, w in enumerate(np.asarray(waypoints, dtype=float)):
        for idx, p in places:
            if np.linalg.norm(w - p) <= tol:
                idx.append(k)
                break
        else:
            places.append(([k], w))
    return [(", ".join(map(str, idx)), p) for idx, p in places]


def plot_singularity_distance(traj: Trajectory, *, ax: Any = None) -> Any:
    """Each singularity measure divided by its margin over time (log scale; < 1 is unsafe).

    Parameters
    ----------
    traj : Trajectory
    ax : matplotlib Axes, optional

    Returns
    -------
    Axes
    """
    check_instance(traj, "traj", Trajectory)
    check_axes(ax)
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(9, 4), constrained_layout=True)
    ratios = traj.measures.ratio(traj.margins)
    for name in MEASURE_NAMES:
        if name in ratios:
            ax.plot(traj.t, ratios[name], lw=1.2, label=_MEASURE_LABELS[name])
    ax.axhline(1.0, color="k", ls="--", lw=1.0, label="margin")
    ax.set_yscale("log")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("measure / margin")
    ax.set_title("distance to each singularity (margin / cond for the condition number)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, ncol=2, loc="best")
    return ax


def render_plots(traj: Trajectory, *, dpi: int = 120) -> dict[str, bytes]:
    """The three figures as PNG bytes, keyed ``"actuators"``, ``"path3d"``, ``"singularity"``."""
    check_instance(traj, "traj", Trajectory)
    dpi = check_count(dpi, "dpi", minimum=1, maximum=MAX_DPI)
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    figs = {"actuators": plot_actuators(traj)[0].figure}
    fig = plt.figure(figsize=(13, 6), constrained_layout=True)
    plot_tip_path(traj, ax=fig.add_subplot(1, 2, 1, projection="3d"), context=True)
    plot_tip_path(traj, ax=fig.add_subplot(1, 2, 2, projection="3d"), context=False)
    figs["path3d"] = fig
    figs["singularity"] = plot_singularity_distance(traj).figure
    out = {}
    for name, f in figs.items():
        buf = io.BytesIO()
        f.savefig(buf, format="png", dpi=dpi)
        plt.close(f)
        out[name] = buf.getvalue()
    return out


def plot_paths(prefix: str | Path) -> dict[str, Path]:
    """File names ``<prefix>_actuators.png``, ``_path3d.png``, ``_singularity.png``."""
    prefix = check_path(prefix, "prefix")
    return {k: prefix.with_name(f"{prefix.name}_{k}.png")
            for k in ("actuators", "path3d", "singularity")}


def save_plots(traj: Trajectory, prefix: str | Path, *, dpi: int = 120) -> list[Path]:
    """Write the three figures as ``<prefix>_actuators.png``, ``_path3d.png``, ``_singularity.png``.

    Parameters
    ----------
    traj : Trajectory
        From :func:`plan`.
    prefix : str or Path
        Path prefix of the three files.
    dpi : int, keyword-only
        Resolution of the PNGs, 1 to 1200.

    Returns
    -------
    list of Path
        The files written.
    """
    from ._io import write_text_atomic

    pngs = render_plots(traj, dpi=dpi)
    paths = plot_paths(prefix)
    for k, data in pngs.items():
        write_text_atomic(paths[k], data)
    return list(paths.values())
