"""Figures of the singularity loci, workspaces, conditioning and the instrument cone.

matplotlib is imported inside each function (``pip install athenakin[plot]``).
Single-panel functions take ``ax=None`` and return the Axes they drew on;
``figure_*`` functions build a whole figure and return it. Lengths are shown
in millimetres, angles in degrees (the plot boundary). The panels of the instrument
cone and the tool tip live in :mod:`athenakin.analysis._figures_cone`, the shared units,
colours and axes in :mod:`athenakin.analysis._figure_style`; all are importable from here.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._figstyle import tidy_3d_axes
from .._typing import FloatArray
from ..design import Design, resolve_design
from ._cone import InstrumentCone
from ._figure_style import COLLISION_COLOR as COLLISION_COLOR
from ._figure_style import (
    COLOR_LOCI,
    COLOR_MODE,
    COLOR_OUT,
    MM,
    _ax,
    _collision_overlay,
    _plt,
    _slice_index,
)
from ._figure_style import TWO_INTERVALS_COLOR as TWO_INTERVALS_COLOR
from ._figures_cone import (
    plot_cone_chart,
    plot_instrument_cone,
    plot_tool_tip_slice,
    wrapped_azimuth,
)
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


def _rect(hs: FloatArray, qs: FloatArray, ax: Any) -> Any:
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


def _box(ax: Any, lo: FloatArray, hi: FloatArray) -> None:
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
