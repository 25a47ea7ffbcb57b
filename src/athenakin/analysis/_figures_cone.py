"""Figures of the instrument cone and the tool-tip workspace (private).

:func:`plot_cone_chart`, :func:`wrapped_azimuth`, :func:`plot_instrument_cone` and
:func:`plot_tool_tip_slice`, the panels of
:func:`athenakin.analysis.figures.figure_instrument_cone` and
:func:`~athenakin.analysis.figures.figure_tool_tip`; all are importable from
:mod:`athenakin.analysis.figures`. matplotlib is imported inside each function.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._figstyle import tidy_3d_axes
from .._typing import BoolArray, FloatArray, IntArray
from ._cone import InstrumentCone
from ._figure_style import (
    COLLISION_COLOR,
    COLOR_MODE,
    MM,
    TWO_INTERVALS_COLOR,
    _ax,
    _collision_overlay,
    _slice_index,
)
from ._workspace import ToolTipWorkspace

__all__ = ["plot_cone_chart", "wrapped_azimuth", "plot_instrument_cone", "plot_tool_tip_slice"]


def plot_cone_chart(ic: InstrumentCone, *, quantity: str = "range", ax: Any = None) -> Any:
    """The instrument cone on the ``(azimuth, polar)`` chart of frame E.

    ``quantity="range"``: reachable insertion length ``p_max - p_min`` (mm);
    ``"p_min"`` / ``"p_max"``; ``"condition"``: ``log10`` of the best condition
    number of the tool-tip Jacobian along the direction; ``"clearance"`` (a cone
    computed with the collision check): the best clearance of the bodies over the
    reachable insertions along the direction (mm). Hatched and outlined (cyan):
    directions with two separate insertion intervals; (magenta, with the collision
    check): directions a collision blocks (:attr:`InstrumentCone.blocked`). The
    azimuth axis starts in the widest gap of unreachable azimuths
    (:func:`wrapped_azimuth`), so a region that crosses +-180 deg is drawn in one piece.
    """
    ax = _ax(ax)
    A, B = np.degrees(ic.azimuth), np.degrees(ic.polar)
    with np.errstate(invalid="ignore", divide="ignore"):
        if quantity == "range":
            v, label, cmap = (ic.p_max - ic.p_min) * MM, "insertion range p_max - p_min [mm]", \
                "magma"
        elif quantity in ("p_min", "p_max"):
            v, label, cmap = getattr(ic, quantity) * MM, f"{quantity} [mm]", "magma"
        elif quantity == "clearance":
            if ic.clearance is None:
                from ..errors import InvalidInputError

                raise InvalidInputError("quantity='clearance': the cone was computed without "
                                        "the collision check (bodies=, environment= or "
                                        "clearance_margin= of instrument_cone)")
            import warnings

            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                v = np.nanmax(ic.clearance, axis=-1) * MM
            label, cmap = "best clearance along the direction [mm]", "RdYlGn"
        else:
            import warnings

            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                v = np.clip(np.log10(np.nanmin(ic.condition, axis=-1)), 0, 4)
            label, cmap = "log10 min cond(d tip/dq) along the direction", "viridis_r"
    A, order = wrapped_azimuth(A, np.asarray(np.isfinite(v).any(axis=1)))
    kw = {"vmin": 0, "vmax": 4} if quantity == "condition" else {}
    im = ax.pcolormesh(A[order], B, v[order].T, shading="auto", cmap=cmap, rasterized=True, **kw)
    ax.figure.colorbar(im, ax=ax, shrink=0.85).set_label(label)
    two = (ic.n_intervals > 1)[order].T.astype(float)
    handles = []
    if np.any(two):
        import matplotlib as mpl
        from matplotlib.patches import Patch

        with mpl.rc_context({"hatch.linewidth": 1.6, "hatch.color": TWO_INTERVALS_COLOR}):
            ax.contourf(A[order], B, two, levels=[0.5, 1.5], colors="none", hatches=["xxx"])
        ax.contour(A[order], B, two, levels=[0.5], colors=TWO_INTERVALS_COLOR, linewidths=1.5)
        handles.append(Patch(facecolor="none", edgecolor=TWO_INTERVALS_COLOR, hatch="xxx",
                             lw=1.5, label="two insertion intervals"))
    if ic.blocked is not None:
        handles.append(_collision_overlay(ax, A[order], B, ic.blocked[order],
                                          "blocked by a collision"))
    if handles:
        ax.legend(handles=handles, loc="lower right", fontsize=7, framealpha=0.9)
    ax.set_xlabel("azimuth about z_e [deg]")
    ax.set_ylabel("polar angle from z_e [deg]")
    ax.set_xlim(A[order][0], A[order][-1])
    ax.set_ylim(180, 0)
    ax.set_title("Instrument cone: insertion range per direction" if quantity == "range"
                 else "Instrument cone about the RCM")
    return ax


def wrapped_azimuth(azimuth_deg: FloatArray, occupied: BoolArray
                    ) -> tuple[FloatArray, IntArray]:
    """Azimuths shifted by whole turns so that the occupied ones form one run.

    Parameters
    ----------
    azimuth_deg : ndarray, shape (n,)
        Azimuths, degrees, one turn.
    occupied : ndarray of bool, shape (n,)
        Azimuths with something to draw.

    Returns
    -------
    wrapped : ndarray, shape (n,)
        ``azimuth_deg`` plus 0 or 360, in one turn that starts in the middle of
        the widest circular gap of unoccupied azimuths (unchanged when there is
        none: every azimuth occupied, or none).
    order : ndarray of int, shape (n,)
        Indices that sort ``wrapped``.
    """
    a = np.asarray(azimuth_deg, dtype=float)
    occ = np.asarray(occupied, dtype=bool)
    order = np.argsort(a)
    if occ.all() or not occ.any():
        return a, order
    s_occ = occ[order]
    s_a = a[order]
    n = len(s_a)
    first = int(np.flatnonzero(s_occ)[0])
    best, best_len, run, start = 0, -1, 0, 0
    for step in range(1, n + 1):          # circular runs of unoccupied azimuths
        i = (first + step) % n
        if not s_occ[i]:
            if run == 0:
                start = i
            run += 1
            if run > best_len:
                best, best_len = start, run
        else:
            run = 0
    cut_index = (best + best_len // 2) % n
    cut = s_a[cut_index]
    wrapped = np.where(a < cut, a + 360.0, a)
    return wrapped, np.argsort(wrapped)


def plot_instrument_cone(ic: InstrumentCone, *, ax: Any = None, frame: str = "base",
                         radius: float | None = None, reference_q: Any = None) -> Any:
    """3-D view of the instrument cone about the RCM.

    The sphere patch of radius ``radius`` (default: the largest sampled ``p``)
    about the RCM marks every reachable instrument direction ``d`` on the
    patient side (``c + radius d``), coloured by the insertion range
    ``p_max - p_min`` along it; unreachable directions are left out. Black dot:
    the RCM; black line: the rail (``x_b`` axis, ``frame="base"`` only); blue
    line: the instrument at ``reference_q`` (optional), from ``O_s`` through the RCM.
    With the collision check, the directions a collision blocks are drawn in magenta.
    """
    import matplotlib as mpl

    from ..robot import direction_from_angles

    ax = _ax(ax, "3d")
    R = float(ic.p[-1]) if radius is None else float(radius)
    Rb, c = ic.T_b_e[:3, :3], ic.T_b_e[:3, 3]
    rot, origin = (Rb, c) if frame == "base" else (np.eye(3), np.zeros(3))
    az = np.append(ic.azimuth, ic.azimuth[0] + 2 * np.pi)  # close the seam
    A, B = np.meshgrid(az, ic.polar, indexing="ij")
    P = (origin + R * direction_from_angles(A, B) @ rot.T) * MM
    rng = np.concatenate([ic.p_max - ic.p_min, (ic.p_max - ic.p_min)[:1]], axis=0) * MM
    norm = mpl.colors.Normalize(vmin=0, vmax=max(float(np.nanmax(rng, initial=0)), 1e-9))
    cmap = mpl.colormaps["magma"]
    col = cmap(norm(np.nan_to_num(rng)))
    col[..., 3] = np.where(np.isfinite(rng), 0.6, 0.0)
    if ic.blocked is not None:
        blocked = np.concatenate([ic.blocked, ic.blocked[:1]], axis=0)
        col[blocked] = mpl.colors.to_rgba(COLLISION_COLOR, 0.8)
    ax.plot_surface(P[..., 0], P[..., 1], P[..., 2], facecolors=col, rstride=1, cstride=1,
                    linewidth=0, antialiased=False, shade=False)
    ax.scatter(*(origin * MM), color="k", s=30, depthshade=False)
    pts = [P[np.isfinite(rng)].reshape(-1, 3), origin[None] * MM]
    if frame == "base":
        lo, hi = min(P[..., 0].min(), -0.3 * MM), max(P[..., 0].max(), 0.3 * MM)
        ax.plot([lo, hi], [0, 0], [0, 0], color="k", lw=2.5)
        pts.append(np.array([[lo, 0, 0], [hi, 0, 0]]))
    if reference_q is not None:
        from ..robot._jacobians import parallel_state

        O_b = parallel_state(reference_q, None, 1)["O_s"]
        O_f = O_b if frame == "base" else (O_b - c) @ Rb
        ax.plot(*np.stack([O_f, 2 * origin - O_f]).T * MM, color=COLOR_MODE[1], lw=2)
        ax.scatter(*(O_f * MM), color=COLOR_MODE[1], s=20, depthshade=False)
        pts.append(np.stack([O_f, 2 * origin - O_f]) * MM)
    allp = np.vstack(pts)
    ctr = 0.5 * (allp.min(axis=0) + allp.max(axis=0))
    half = max(np.ptp(allp, axis=0).max() / 2, 1.0)
    ax.set_xlim(ctr[0] - half, ctr[0] + half)
    ax.set_ylim(ctr[1] - half, ctr[1] + half)
    ax.set_zlim(ctr[2] - half, ctr[2] + half)
    sm = mpl.cm.ScalarMappable(norm=norm, cmap=cmap)
    ax.figure.colorbar(sm, ax=ax, shrink=0.7, pad=0.1).set_label("insertion range [mm]")
    f = "e" if frame == "rcm" else "b"
    ax.set_xlabel(f"x_{f} [mm]")
    ax.set_ylabel(f"y_{f} [mm]")
    ax.zaxis.set_rotate_label(False)
    ax.set_zlabel(f"z_{f} [mm]", rotation=90)
    tidy_3d_axes(ax, nbins=3)
    ax.view_init(elev=20, azim=30)
    ax.set_box_aspect((1, 1, 1), zoom=0.8)     # room for the tick and axis labels
    ax.set_title("Instrument directions about the RCM")
    return ax


def plot_tool_tip_slice(tw: ToolTipWorkspace, *, axis: int = 2, value: float = 0.0,
                        quantity: str = "condition", ax: Any = None) -> Any:
    """A slice of the tool-tip workspace (frame E) coloured by ``log10 cond`` or mode.

    A map computed with the collision check (``tw.collision_free``) hatches, in
    magenta, the reachable tips where the bodies collide.
    """
    from matplotlib.colors import ListedColormap

    ax = _ax(ax)
    axes = [tw.x, tw.y, tw.z]
    i = _slice_index(axes[axis], value)
    idx: list[Any] = [slice(None)] * 3
    idx[axis] = i
    other = [k for k in range(3) if k != axis]
    U, V = axes[other[0]] * MM, axes[other[1]] * MM
    if quantity == "mode":
        m = tw.mode[tuple(idx)]
        code = np.where(m == 0, np.nan, np.where(m == 1, 0, 1))
        ax.pcolormesh(U, V, code.T, cmap=ListedColormap([COLOR_MODE[1], COLOR_MODE[-1]]),
                      vmin=-0.5, vmax=1.5, shading="auto", rasterized=True)
    else:
        with np.errstate(divide="ignore", invalid="ignore"):
            c = np.log10(tw.condition[tuple(idx)])
        im = ax.pcolormesh(U, V, np.clip(c, 0, 4).T, cmap="viridis_r", vmin=0, vmax=4,
                           shading="auto", rasterized=True)
        ax.figure.colorbar(im, ax=ax, shrink=0.85).set_label("log10 cond(d tip/dq)")
    if tw.collision_free is not None:
        ax.legend(handles=[_collision_overlay(
            ax, U, V, tw.reachable[tuple(idx)] & ~tw.collision_free[tuple(idx)],
            "bodies collide")], loc="lower right", fontsize=7, framealpha=0.9)
    ax.plot(0, 0, "k+", ms=10)
    names = "xyz"
    ax.set_xlabel(f"{names[other[0]]}_e [mm]")
    ax.set_ylabel(f"{names[other[1]]}_e [mm]")
    ax.set_aspect("equal")
    at = axes[axis][i] * MM
    ax.set_title(f"Tool-tip workspace, {names[axis]}_e = {0.0 if abs(at) < 0.5 else at:.0f} mm")
    return ax
