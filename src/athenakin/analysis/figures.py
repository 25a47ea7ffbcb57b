"""Figures of the singularity loci, workspaces, conditioning and the instrument cone.

matplotlib is imported inside each function (``pip install athenakin[plot]``).
Single-panel functions take ``ax=None`` and return the Axes they drew on;
``figure_*`` functions build a whole figure and return it. Lengths are shown
in millimetres, angles in degrees (the plot boundary).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._figstyle import tidy_3d_axes
from ..design import Design, resolve_design
from ._cone import InstrumentCone
from ._loci import singularity_loci
from ._workspace import ActuatorMap, PointWorkspace, ToolTipWorkspace

__all__ = [
    "plot_singularity_loci",
    "plot_actuator_space_3d",
    "plot_actuator_conditioning",
    "plot_workspace_slice",
    "plot_workspace_3d",
    "plot_instrument_cone",
    "plot_cone_chart",
    "wrapped_azimuth",
    "plot_tool_tip_slice",
    "figure_singularities",
    "figure_workspace",
    "figure_conditioning",
    "figure_instrument_cone",
    "figure_tool_tip",
    "figure_measure_scaling",
]

MM = 1e3
#: Colours of assembly mode +1, mode -1, and of positions outside the stroke limits.
COLOR_MODE = {1: "#1f77b4", -1: "#ff7f0e"}
COLOR_OUT = "#d9d9d9"
COLOR_LOCI = {"w0": "#d62728", "h0": "#2ca02c", "l3": "#9467bd", "stroke": "black"}
#: Hatching and outline of the directions with two insertion intervals.
TWO_INTERVALS_COLOR = "#00bcd4"
#: Hatching and outline of what a collision blocks (maps computed with the collision check).
COLLISION_COLOR = "#e7298a"


def _collision_overlay(ax: Any, U: NDArray[np.float64], V: NDArray[np.float64],
                       blocked: NDArray[np.bool_], label: str) -> Any:
    """Hatch and outline ``blocked`` (shape (len(U), len(V))); returns the legend patch."""
    import matplotlib as mpl
    from matplotlib.patches import Patch

    b = np.asarray(blocked, dtype=float).T
    if np.any(b):
        with mpl.rc_context({"hatch.linewidth": 1.2, "hatch.color": COLLISION_COLOR}):
            ax.contourf(U, V, b, levels=[0.5, 1.5], colors="none", hatches=["////"])
        ax.contour(U, V, b, levels=[0.5], colors=COLLISION_COLOR, linewidths=1.2)
    return Patch(facecolor="none", edgecolor=COLLISION_COLOR, hatch="////", lw=1.2, label=label)


def _plt() -> Any:
    import matplotlib

    if matplotlib.get_backend().lower() not in ("agg", "module://matplotlib_inline.backend_inline"):
        try:
            import matplotlib.pyplot as plt  # noqa: F401
        except Exception:  # pragma: no cover - headless without a GUI backend
            matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _ax(ax: Any, projection: str | None = None) -> Any:
    if ax is not None:
        return ax
    plt = _plt()
    fig = plt.figure()
    return fig.add_subplot(projection=projection)


# --------------------------------------------------------------------------------------
# actuator space
# --------------------------------------------------------------------------------------
def plot_singularity_loci(design: Design | None = None, *, am: ActuatorMap | None = None,
                          mode: int = 1, ax: Any = None) -> Any:
    """Singularity loci of the parallel module in the actuator plane ``(h, q3)``.

    Background: ``log10`` of the condition number of ``d O_s / d q`` in ``mode``
    (white where the circles do not intersect). Lines: ``w = 0`` (the assembly
    modes meet; outer/inner tangency), ``h = 0`` (inverse singularity),
    ``|h| = l3`` (D on the rail); dashed rectangle: the stroke limits.
    """
    design = resolve_design(design)
    ax = _ax(ax)
    loci = singularity_loci(design)
    if am is not None:
        k = 0 if mode == 1 else 1
        with np.errstate(divide="ignore", invalid="ignore"):
            c = np.log10(am.condition[..., k]).T
        im = ax.pcolormesh(am.h * MM, am.q3 * MM, np.clip(c, 0, 4), cmap="viridis_r",
                           shading="auto", vmin=0, vmax=4, rasterized=True)
        cb = ax.figure.colorbar(im, ax=ax, shrink=0.85)
        cb.set_label(f"log10 cond(dO_s/dq), mode {mode:+d}")
    h = loci["h"] * MM
    ax.plot(h, loci["q3_external"] * MM, color=COLOR_LOCI["w0"], lw=2,
            label="w = 0 (modes meet)")
    ax.plot(h, loci["q3_internal"] * MM, color=COLOR_LOCI["w0"], lw=2, ls="-.")
    ax.axvline(0, color=COLOR_LOCI["h0"], lw=2, label="h = 0 (A, B meet: inverse)")
    for s in (-1, 1):
        ax.axvline(s * design.l3 * MM, color=COLOR_LOCI["l3"], lw=2,
                   label="|h| = l3 (D on the rail)" if s == 1 else None)
    hs, qs = loci["h_stroke"] * MM, loci["q3_stroke"] * MM
    if np.all(np.isfinite(hs)) and np.all(np.isfinite(qs)):
        ax.add_patch(_rect(hs, qs, ax))
    top = max(loci["q3_external"].max() * MM * 1.15, qs[1] * 1.05 if np.isfinite(qs[1]) else 0)
    lim = max(abs(h[0]), abs(h[-1]), *(abs(hs[np.isfinite(hs)]))) * 1.08
    forbidden = (0, lim) if design.h_sign < 0 else (-lim, 0)
    ax.axvspan(*forbidden, facecolor="none", edgecolor="0.6", hatch="//", lw=0,
               label=f"excluded by the A/B order ({design.ab_order})")
    ax.set_xlabel("h = (q1 - q2)/2 [mm]")
    ax.set_ylabel("q3 [mm]")
    ax.set_xlim(-lim, lim)
    ax.set_ylim(0, top)
    ax.legend(loc="upper left", fontsize=7, framealpha=0.9)
    ax.set_title(f"Parallel singularities in (h, q3), mode {mode:+d}")
    return ax


def _rect(hs: NDArray[np.float64], qs: NDArray[np.float64], ax: Any) -> Any:
    from matplotlib.patches import Rectangle

    return Rectangle((hs[0], qs[0]), hs[1] - hs[0], qs[1] - qs[0], fill=False, ls="--",
                     lw=1.5, ec=COLOR_LOCI["stroke"], label="stroke limits")


def plot_actuator_space_3d(design: Design | None = None, *, n: int = 41, ax: Any = None) -> Any:
    """The singular surfaces inside the stroke box ``(q1, q2, q3)`` (3-D view).

    ``w = 0`` surfaces (red), the plane ``q1 = q2`` (``h = 0``, green) and the
    planes ``|q1 - q2| = 2 l3`` (purple), clipped to the stroke box (edges black).
    """
    design = resolve_design(design)
    ax = _ax(ax, "3d")
    lo, hi = design.stroke_min.copy(), design.stroke_max.copy()
    lo = np.where(np.isfinite(lo), lo, [-0.5, -0.5, 0.0])
    hi = np.where(np.isfinite(hi), hi, [0.5, 0.5, 1.0])
    q1, q2 = np.meshgrid(np.linspace(lo[0], hi[0], n), np.linspace(lo[1], hi[1], n),
                         indexing="ij")
    h = 0.5 * (q1 - q2)
    with np.errstate(invalid="ignore"):
        r1 = np.sqrt(design.l1 ** 2 - h * h)
        d = np.hypot(np.sqrt(design.l3 ** 2 - h * h) + design.l2, design.l5)
    order = design.h_sign * h >= 0
    for q3s, ls in ((d + r1, 1.0), (np.abs(d - r1), 0.7)):
        Z = np.where(order & (q3s >= lo[2]) & (q3s <= hi[2]), q3s, np.nan)
        ax.plot_surface(q1 * MM, q2 * MM, Z * MM, color=COLOR_LOCI["w0"], alpha=0.55 * ls,
                        linewidth=0, shade=True)
    # h = 0 plane and |h| = l3 planes: vertical planes q2 = q1 + c
    t = np.linspace(0, 1, 2)
    for c, col in ((0.0, COLOR_LOCI["h0"]), (-2 * design.h_sign * design.l3, COLOR_LOCI["l3"])):
        a = np.linspace(max(lo[0], lo[1] - c), min(hi[0], hi[1] - c), 2)
        if a[0] >= a[1]:
            continue
        A, T3 = np.meshgrid(a, lo[2] + t * (hi[2] - lo[2]))
        ax.plot_surface(A * MM, (A + c) * MM, T3 * MM, color=col, alpha=0.35, linewidth=0)
    _box(ax, lo * MM, hi * MM)
    ax.set_xlabel("q1 [mm]")
    ax.set_ylabel("q2 [mm]")
    ax.set_zlabel("q3 [mm]")
    tidy_3d_axes(ax)
    ax.set_title("Singular surfaces in the stroke box")
    from matplotlib.patches import Patch

    ax.legend(handles=[Patch(color=COLOR_LOCI["w0"], label="w = 0 (modes meet)"),
                       Patch(color=COLOR_LOCI["h0"], label="q1 = q2 (h = 0)"),
                       Patch(color=COLOR_LOCI["l3"], label="|q1 - q2| = 2 l3")],
              loc="upper left", fontsize=7)
    return ax


def _box(ax: Any, lo: NDArray[np.float64], hi: NDArray[np.float64]) -> None:
    import itertools

    for a, b in itertools.combinations(itertools.product(*zip(lo, hi, strict=True)), 2):
        if sum(x != y for x, y in zip(a, b, strict=True)) == 1:
            ax.plot(*zip(a, b, strict=True), color="k", lw=0.8)


def plot_actuator_conditioning(am: ActuatorMap, *, mode: int = 1, quantity: str = "condition",
                               ax: Any = None, norm: Any = None, colorbar: bool = True) -> Any:
    """Colour map over ``(h, q3)`` of ``log10 cond``, ``sigma_min`` or ``inverse_sigma_min``.

    ``log10 cond`` is drawn on the fixed range 0..4 (as every conditioning map
    here), so maps of both assembly modes compare; pass ``norm``
    (a :class:`matplotlib.colors.Normalize`) to share any other range, and
    ``colorbar=False`` to draw one colour bar for several panels.
    """
    ax = _ax(ax)
    k = 0 if mode == 1 else 1
    v = getattr(am, quantity)[..., k].T
    with np.errstate(divide="ignore", invalid="ignore"):
        data, label, cmap = ((np.clip(np.log10(v), 0, 4), "log10 cond(dO_s/dq)", "viridis_r")
                             if quantity == "condition" else (v, quantity, "viridis"))
    if norm is None and quantity == "condition":
        from matplotlib.colors import Normalize

        norm = Normalize(vmin=0.0, vmax=4.0)
    im = ax.pcolormesh(am.h * MM, am.q3 * MM, data, shading="auto", cmap=cmap, norm=norm,
                       rasterized=True)
    if colorbar:
        ax.figure.colorbar(im, ax=ax, shrink=0.85).set_label(label)
    ax.add_patch(_rect(am.h_stroke * MM, am.q3_stroke * MM, ax))
    ax.set_xlabel("h [mm]")
    ax.set_ylabel("q3 [mm]")
    ax.set_title(f"dO_s/dq, mode {mode:+d}")
    return ax


# --------------------------------------------------------------------------------------
# O_s workspace
# --------------------------------------------------------------------------------------
def _slice_index(axis: NDArray[np.float64], value: float) -> int:
    return int(np.argmin(np.abs(axis - value)))


def plot_workspace_slice(pw: PointWorkspace, *, x: float | None = None, quantity: str = "mode",
                         ax: Any = None, legend: bool = True) -> Any:
    """A slice ``x = const`` of the ``O_s`` workspace in the base ``(y, z)`` plane.

    ``quantity="mode"``: reachable voxels coloured by assembly mode (blue +1,
    orange -1), grey where the module gets there only beyond the stroke
    limits; the red line is the surface where the modes meet
    (``mode_margin = 0``). ``quantity="condition"``: ``log10`` of the
    condition number of ``d O_s / d q`` over the reachable voxels. A map computed
    with the collision check (``pw.collision_free``) hatches, in magenta, the
    reachable voxels where the bodies collide.
    """
    from matplotlib.colors import ListedColormap

    ax = _ax(ax)
    i = _slice_index(pw.x, 0.5 * (pw.x[0] + pw.x[-1]) if x is None else x)
    Y, Z = pw.y * MM, pw.z * MM
    if quantity == "mode":
        code = np.where(pw.mode[i] == 0, np.nan,
                        np.where(~pw.reachable[i], 0, np.where(pw.mode[i] == 1, 1, 2)))
        cmap = ListedColormap([COLOR_OUT, COLOR_MODE[1], COLOR_MODE[-1]])
        ax.pcolormesh(Y, Z, code.T, cmap=cmap, vmin=-0.5, vmax=2.5, shading="auto",
                      rasterized=True)
        mm = pw.mode_margin[i]
        if np.any(np.isfinite(mm)):
            ax.contour(Y, Z, mm.T, levels=[0.0],
                       colors=COLOR_LOCI["w0"], linewidths=1.5)
        from matplotlib.patches import Patch

        handles = [Patch(color=COLOR_MODE[1], label="mode +1"),
                   Patch(color=COLOR_MODE[-1], label="mode -1"),
                   Patch(color=COLOR_OUT, label="beyond strokes"),
                   Patch(color=COLOR_LOCI["w0"], label="modes meet (w = 0)")]
        if pw.collision_free is not None:
            handles.append(_collision_overlay(ax, Y, Z, pw.reachable[i] & ~pw.collision_free[i],
                                              "bodies collide"))
        if legend:
            ax.legend(handles=handles, loc="center", fontsize=7)
    else:
        with np.errstate(divide="ignore", invalid="ignore"):
            c = np.where(pw.reachable[i], np.log10(pw.condition[i]), np.nan)
        im = ax.pcolormesh(Y, Z, np.clip(c, 0, 4).T, cmap="viridis_r", vmin=0, vmax=4,
                           shading="auto", rasterized=True)
        ax.figure.colorbar(im, ax=ax, shrink=0.85).set_label("log10 cond(dO_s/dq)")
    ax.plot(0, 0, "k+", ms=8)
    ax.set_aspect("equal")
    ax.set_xlabel("y_b [mm]")
    ax.set_ylabel("z_b [mm]")
    at = pw.x[i] * MM
    ax.set_title(f"O_s workspace, x_b = {0.0 if abs(at) < 0.5 else at:.0f} mm")
    return ax


def plot_workspace_3d(pw: PointWorkspace, *, ax: Any = None, max_points: int = 6000) -> Any:
    """3-D view of the reachable ``O_s`` set: its boundary voxels coloured by mode."""
    ax = _ax(ax, "3d")
    r = pw.reachable
    inner = r.copy()
    for axis in range(3):
        for s in (1, -1):
            inner &= np.roll(r, s, axis=axis)
    for axis in range(3):
        idx = [slice(None)] * 3
        for j in (0, -1):
            idx[axis] = j  # type: ignore[call-overload]
            inner[tuple(idx)] = False
    boundary = r & ~inner
    X, Y, Z = np.meshgrid(pw.x, pw.y, pw.z, indexing="ij")
    rng = np.random.default_rng(0)
    for m in (1, -1):
        sel = np.flatnonzero(boundary & (pw.mode == m))
        if sel.size > max_points:
            sel = rng.choice(sel, max_points, replace=False)
        ax.scatter(X.ravel()[sel] * MM, Y.ravel()[sel] * MM, Z.ravel()[sel] * MM, s=2,
                   color=COLOR_MODE[m], alpha=0.5, label=f"mode {m:+d}", depthshade=True)
    ax.scatter([0], [0], [0], color="k", marker="o", s=10)
    xr = pw.x[[0, -1]] * MM
    ax.plot(xr, [0, 0], [0, 0], "k-", lw=2, label="rail (x_b axis)")
    ax.set_xlabel("x_b [mm]")
    ax.set_ylabel("y_b [mm]")
    ax.set_zlabel("z_b [mm]")
    tidy_3d_axes(ax, nbins=3)
    ax.legend(loc="upper left", fontsize=7, markerscale=4)
    ax.set_title("Reachable O_s (boundary voxels)")
    try:
        ax.set_box_aspect((np.ptp(pw.x), np.ptp(pw.y), np.ptp(pw.z)))
    except Exception:  # pragma: no cover - old matplotlib
        pass
    return ax


# --------------------------------------------------------------------------------------
# instrument cone and tool tip
# --------------------------------------------------------------------------------------
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


def wrapped_azimuth(azimuth_deg: NDArray[np.float64], occupied: NDArray[np.bool_]
                    ) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
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


# --------------------------------------------------------------------------------------
# composite figures (used by the CLI and the docs)
# --------------------------------------------------------------------------------------
def figure_singularities(design: Design | None = None, *, am: ActuatorMap | None = None) -> Any:
    """Singularity loci: the ``(h, q3)`` plane (both modes) and the 3-D stroke box."""
    plt = _plt()
    design = resolve_design(design)
    fig = plt.figure(figsize=(15, 4.8))
    plot_singularity_loci(design, am=am, mode=1, ax=fig.add_subplot(1, 3, 1))
    plot_singularity_loci(design, am=am, mode=-1, ax=fig.add_subplot(1, 3, 2))
    plot_actuator_space_3d(design, ax=fig.add_subplot(1, 3, 3, projection="3d"))
    fig.tight_layout()
    return fig


def figure_workspace(pw: PointWorkspace, *, x_values: tuple[float, ...] | None = None) -> Any:
    """``O_s`` workspace: slices by mode at three ``x`` and a 3-D view."""
    plt = _plt()
    xs = x_values or tuple(np.quantile(pw.x, [0.15, 0.5, 0.85]))
    fig = plt.figure(figsize=(16, 4.6))
    for k, x in enumerate(xs):
        plot_workspace_slice(pw, x=x, ax=fig.add_subplot(1, len(xs) + 1, k + 1),
                             legend=k == 0)
    plot_workspace_3d(pw, ax=fig.add_subplot(1, len(xs) + 1, len(xs) + 1, projection="3d"))
    fig.tight_layout()
    return fig


def figure_conditioning(am: ActuatorMap, pw: PointWorkspace, tw: ToolTipWorkspace | None = None
                        ) -> Any:
    """Conditioning maps: actuator plane, an ``O_s`` slice and a tool-tip slice."""
    from matplotlib.colors import Normalize

    plt = _plt()
    n = 3 if tw is None else 4
    fig = plt.figure(figsize=(5 * n, 4.4), layout="constrained")
    fig.get_layout_engine().set(w_pad=0.08, wspace=0.04)
    norm = Normalize(vmin=0.0, vmax=4.0)            # one colour range for both modes
    pair = [fig.add_subplot(1, n, k + 1) for k in range(2)]
    for ax, mode in zip(pair, (1, -1), strict=True):
        plot_actuator_conditioning(am, mode=mode, ax=ax, norm=norm, colorbar=False)
    cb = fig.colorbar(pair[0].collections[0], ax=pair, shrink=0.85)
    cb.set_label("log10 cond(dO_s/dq), modes +1 and -1")
    plot_workspace_slice(pw, quantity="condition", ax=fig.add_subplot(1, n, 3))
    if tw is not None:
        plot_tool_tip_slice(tw, axis=2, value=0.0, ax=fig.add_subplot(1, n, 4))
    return fig


def figure_instrument_cone(ic: InstrumentCone, *, reference_q: Any = None) -> Any:
    """Instrument cone: 3-D view (frame E) and the chart of insertion ranges and conditioning.

    With the collision check the third panel shows the best clearance per direction
    instead of the conditioning.
    """
    plt = _plt()
    fig = plt.figure(figsize=(16, 4.8))
    plot_instrument_cone(ic, ax=fig.add_subplot(1, 3, 1, projection="3d"),
                         reference_q=reference_q)
    plot_cone_chart(ic, quantity="range", ax=fig.add_subplot(1, 3, 2))
    if ic.clearance is not None:
        ax = plot_cone_chart(ic, quantity="clearance", ax=fig.add_subplot(1, 3, 3))
        ax.set_title("Best clearance of the bodies along each direction")
    else:
        ax = plot_cone_chart(ic, quantity="condition", ax=fig.add_subplot(1, 3, 3))
        ax.set_title("Best tool-tip conditioning along each direction")
    fig.tight_layout()
    return fig


def figure_tool_tip(tw: ToolTipWorkspace) -> Any:
    """Tool-tip workspace: three orthogonal slices through the RCM (frame E)."""
    plt = _plt()
    fig = plt.figure(figsize=(15, 4.6))
    for k in range(3):
        plot_tool_tip_slice(tw, axis=k, value=0.0, ax=fig.add_subplot(1, 3, k + 1))
    fig.tight_layout()
    return fig


def figure_measure_scaling(design: Design | None = None, *, n: int = 45) -> Any:
    """Jacobian distance measures against the closed-form distance to each singular set.

    Each condition is approached with :func:`~athenakin.analysis.near_singular_configurations`
    from 1e-13 to 1e-1; straight lines of slope 1 (``h = 0``, serial, IK, tool tip) and
    1/2 (the forward singularities ``w = 0`` and ``|h| = l3``) confirm the power law
    each measure follows down to rounding.
    """
    from ._loci import MEASURE_OF, near_singular_configurations
    from ._singularities import singularities

    plt = _plt()
    design = resolve_design(design)
    dist = np.logspace(-13, -1, n)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), sharey=True)
    groups = (("parallel module", ("ab_coincide", "circles_tangent", "d_on_rail")),
              ("serial chain, paper-form IK, tool tip",
               ("ujoint", "wrist", "p_zero", "ik_cos_u1", "ik_sin_u1_sin_u2", "tip_at_rcm")))
    for ax, (title, names) in zip(axes, groups, strict=True):
        for name in names:
            measure, power = MEASURE_OF[name]
            q, T = near_singular_configurations(name, dist, design)
            rep = singularities(q, T, design)
            v = rep.conditions[name].value
            ax.loglog(v, np.abs(rep.measures[measure]), lw=2,
                      label=f"{name}: {measure} (slope {power:g})")
        for power, ls in ((1.0, ":"), (0.5, "--")):
            ax.loglog(dist, dist ** power, color="0.5", ls=ls, lw=1,
                      label=f"reference slope {power:g}")
        ax.set_xlabel("closed-form distance to the singular set (m or sine)")
        ax.set_title(title)
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=7, loc="lower right")
    axes[0].set_ylabel("Jacobian measure (smallest singular value)")
    fig.tight_layout()
    return fig
