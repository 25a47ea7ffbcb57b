"""Figures of a design study (matplotlib, imported on demand).

Each function takes ``(..., *, ax=None, **kwargs)`` and returns the Axes;
angles are shown in degrees (plot boundary).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..design import Design
from ._metrics import reachability
from ._task import Task

__all__ = ["plot_pareto", "plot_parameter_coordinates", "plot_coverage_map"]


def _ax(ax: Any) -> Any:
    try:
        import matplotlib.pyplot as plt
    except ModuleNotFoundError as exc:
        raise ModuleNotFoundError("athenakin.synthesis.figures needs matplotlib: "
                                  "pip install 'athenakin[plot]'", name="matplotlib") from exc
    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 4.8), layout="constrained")
    return ax


def plot_pareto(table: Any, *, front: Any = None, reference: Any = None, x: str = "size",
                y: str = "coverage_mode", color: str = "tip_error_max", ax: Any = None,
                **kwargs: Any) -> Any:
    """Designs of a study in the plane of two metrics, the front and the reference marked.

    Parameters
    ----------
    table : pandas.DataFrame
        Study table (:func:`~athenakin.synthesis.evaluate` or ``SearchResult.table``).
    front : pandas.DataFrame, optional
        Rows to draw as the Pareto front (joined in order of ``x``).
    reference : pandas.Series, optional
        Row of the reference design (a star).
    x, y, color : str
        Metric columns for the axes and the colour (log scale for ``tip_error*``).
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib Axes
    """
    ax = _ax(ax)
    ok = table["valid"].to_numpy(bool) & np.isfinite(table[y].to_numpy(float))
    c = table[color].to_numpy(float)[ok]
    if color.startswith("tip_error"):
        c = np.log10(c * 1e6)
        label = f"log10 {color} (um)"
    else:
        label = color
    sc = ax.scatter(table[x][ok], table[y][ok], c=c, s=14, cmap="viridis", **kwargs)
    ax.figure.colorbar(sc, ax=ax, label=label)
    if front is not None and len(front):
        f = front.sort_values(x)
        ax.plot(f[x], f[y], "o", mfc="none", mec="crimson", ms=8, label="Pareto front")
    if reference is not None:
        ax.plot([reference[x]], [reference[y]], "*", color="k", ms=16,
                label=str(reference.get("name", "reference")) or "reference")
    ax.set_xlabel(f"{x} (m)" if x in ("size",) or x.startswith("tip") else x)
    ax.set_ylabel(y)
    ax.legend(loc="lower right", fontsize=8)
    ax.set_title("designs against the task")
    return ax


def plot_parameter_coordinates(table: Any, *, columns: Sequence[str] | None = None,
                               color: str = "coverage_mode", highlight: Any = None,
                               ax: Any = None, **kwargs: Any) -> Any:
    """Parallel coordinates of the design parameters (and metrics), each axis scaled to [0, 1].

    Parameters
    ----------
    table : pandas.DataFrame
    columns : sequence of str, optional
        Default: ``l1..l5``, the strokes, then ``coverage_mode`` and ``size``.
    color : str
        Metric that colours each line.
    highlight : pandas.DataFrame, optional
        Rows drawn on top in black (e.g. the Pareto front).
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib Axes
    """
    from ._search import SEARCH_VARIABLES

    ax = _ax(ax)
    cols = list(columns or (*SEARCH_VARIABLES, "coverage_mode", "size"))
    ok = table["valid"].to_numpy(bool)
    V = table.loc[ok, cols].to_numpy(float)
    lo, hi = np.nanmin(V, axis=0), np.nanmax(V, axis=0)
    span = np.where(hi > lo, hi - lo, 1.0)
    import matplotlib as mpl

    cvals = table.loc[ok, color].to_numpy(float)
    norm = mpl.colors.Normalize(np.nanmin(cvals), np.nanmax(cvals))
    cmap = mpl.colormaps["viridis"]
    xs = np.arange(len(cols))
    for row, cv in zip((V - lo) / span, cvals, strict=True):
        ax.plot(xs, row, color=cmap(norm(cv)) if math.isfinite(cv) else "0.8", lw=0.6,
                alpha=0.6, **kwargs)
    if highlight is not None and len(highlight):
        for row in (highlight[cols].to_numpy(float) - lo) / span:
            ax.plot(xs, row, color="k", lw=1.2)
    ax.figure.colorbar(mpl.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, label=color)
    ax.set_xticks(xs, cols, rotation=45, ha="right")
    ax.set_ylabel("scaled to [min, max] of the valid designs")
    ax.set_title("design parameters")
    return ax


def plot_coverage_map(design: Design, task: Task, *, samples: int = 20_000, seed: int = 0,
                      ax: Any = None, **kwargs: Any) -> Any:
    """Which task samples a design reaches, over the cone of directions.

    Each sample is a dot at ``theta (cos phi, sin phi)`` (deg; ``theta`` from the cone
    axis, ``phi`` about it from ``y_e``): blue mode +1, orange mode -1, grey unreachable.

    Parameters
    ----------
    design : Design
    task : Task
    samples, seed : int, keyword-only
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib Axes
    """
    ax = _ax(ax)
    s, _, mode, _ = reachability(design, task, samples=samples, seed=seed)
    r = np.degrees(s.theta)
    x, y = r * np.cos(s.phi), r * np.sin(s.phi)
    for m, col, lab in ((0, "0.75", "unreachable"), (1, "tab:blue", "mode +1"),
                        (-1, "tab:orange", "mode -1")):
        k = mode == m
        if np.any(k):
            ax.scatter(x[k], y[k], s=2, color=col, label=f"{lab} ({k.mean():.0%})",
                       rasterized=True, **kwargs)
    a = math.degrees(task.half_angle)
    t = np.linspace(0, 2 * math.pi, 200)
    ax.plot(a * np.cos(t), a * np.sin(t), "k-", lw=0.8)
    ax.set_aspect("equal")
    ax.set_xlabel("theta cos(phi) (deg)")
    ax.set_ylabel("theta sin(phi) (deg)")
    ax.set_title(design.name or "design", fontsize=9)
    ax.legend(loc="upper right", fontsize=7, markerscale=4)
    return ax
