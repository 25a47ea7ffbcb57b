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

__all__ = ["plot_pareto", "plot_parameter_coordinates", "plot_coverage_map", "label",
           "LABELS", "SENSE"]


def _ax(ax: Any) -> Any:
    try:
        import matplotlib.pyplot as plt
    except ModuleNotFoundError as exc:
        raise ModuleNotFoundError("athenakin.synthesis.figures needs matplotlib: "
                                  "pip install 'athenakin[plot]'", name="matplotlib") from exc
    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 4.8), layout="constrained")
    return ax


#: Axis names of the metric and parameter columns, with units (plot boundary).
LABELS: dict[str, str] = {
    "size": "size: total link length and actuator travel (m)",
    "coverage": "coverage (fraction of the task reached)",
    "coverage_mode": "single-mode coverage (fraction of the task)",
    "coverage_plus": "coverage in mode +1 (fraction)",
    "coverage_minus": "coverage in mode -1 (fraction)",
    "tip_error_max": "worst tip error from encoder resolution (µm)",
    "tip_error_mean": "mean tip error from encoder resolution (µm)",
    "margin_min": "smallest singularity margin",
    "cond_tip_max": "worst tool-tip conditioning",
    "cond_parallel_max": "worst parallel-module conditioning",
}
#: Whether a larger value of a metric is better (``max``) or worse (``min``).
SENSE: dict[str, str] = {"size": "min", "coverage": "max", "coverage_mode": "max",
                         "coverage_plus": "max", "coverage_minus": "max",
                         "tip_error_max": "min", "tip_error_mean": "min", "margin_min": "max",
                         "cond_tip_max": "min", "cond_parallel_max": "min"}


def label(column: str) -> str:
    """The axis name of a study column, with its unit (the column name if none is known)."""
    return LABELS.get(column, column)


def _um(column: str, values: Any) -> Any:
    return values * 1e6 if column.startswith("tip_error") else values


def plot_pareto(table: Any, *, front: Any = None, reference: Any = None, x: str = "size",
                y: str = "coverage_mode", color: str = "tip_error_max", ax: Any = None,
                **kwargs: Any) -> Any:
    """Designs of a study in the plane of two metrics, their front and the reference marked.

    The line joins the Pareto front of the two metrics drawn (the designs that no other
    drawn design beats in both, the better direction of each from :data:`SENSE`). The
    front of a search over more objectives (``front=``, e.g. ``SearchResult.front`` over
    size, single-mode coverage and tip error) holds designs that look dominated in any two
    of them; they get their own marker and a legend entry saying so. With a single valid
    design there is nothing to compare: no colour scale is drawn.

    Parameters
    ----------
    table : pandas.DataFrame
        Study table (:func:`~athenakin.synthesis.evaluate` or ``SearchResult.table``).
    front : pandas.DataFrame, optional
        Rows of the front of the search (all its objectives), marked with open circles.
    reference : pandas.Series, optional
        Row of the reference design (a star).
    x, y, color : str
        Metric columns for the axes and the colour (log scale for ``tip_error*``, in µm).
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib Axes
    """
    from ._search import pareto_mask

    ax = _ax(ax)
    ok = (table["valid"].to_numpy(bool) & np.isfinite(table[y].to_numpy(float))
          & np.isfinite(table[x].to_numpy(float)))
    X, Y = table[x].to_numpy(float)[ok], table[y].to_numpy(float)[ok]
    c = _um(color, table[color].to_numpy(float)[ok])
    if color.startswith("tip_error"):
        c = np.log10(c)
        clabel = f"log10 {label(color)}"
    else:
        clabel = label(color)
    finite = c[np.isfinite(c)]
    if len(X) > 1 and finite.size > 1 and finite.max() > finite.min():
        sc = ax.scatter(_um(x, X), _um(y, Y), c=c, s=14, cmap="viridis", zorder=2, **kwargs)
        ax.figure.colorbar(sc, ax=ax, label=clabel)
    else:
        ax.scatter(_um(x, X), _um(y, Y), s=14, color="tab:blue", label="design", zorder=2,
                   **kwargs)
    if len(X) > 1:
        sign = [1.0 if SENSE.get(k, "min") == "min" else -1.0 for k in (x, y)]
        on = pareto_mask(np.column_stack([sign[0] * X, sign[1] * Y]))
        order = np.argsort(X[on])
        ax.plot(_um(x, X[on][order]), _um(y, Y[on][order]), "-", color="crimson", lw=1.2,
                zorder=1, label=f"Pareto front of these two metrics ({int(on.sum())})")
    if front is not None and len(front):
        ax.plot(_um(x, front[x]), _um(y, front[y]), "o", mfc="none", mec="0.2", ms=8,
                label=f"front of the search over {_objectives(front)} ({len(front)})")
    if reference is not None:
        ax.plot([_um(x, reference[x])], [_um(y, reference[y])], "*", color="k", ms=16,
                label=str(reference.get("name", "reference")) or "reference")
    ax.set_xlabel(label(x))
    ax.set_ylabel(label(y))
    ax.legend(loc="best", fontsize=7)
    ax.set_title(f"{int(ok.sum())} design{'s' if ok.sum() != 1 else ''} against the task")
    return ax


def _objectives(front: Any) -> str:
    from ._search import DEFAULT_OBJECTIVES

    names = [k for k in DEFAULT_OBJECTIVES if k in getattr(front, "columns", ())]
    return f"{len(names)} objectives" if names else "its objectives"


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
    ax.figure.colorbar(mpl.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, label=label(color))
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
    ax.set_xlabel("θ cos φ (deg): angle from the cone axis")
    ax.set_ylabel("θ sin φ (deg)")
    ax.set_title(design.name or "design", fontsize=9)
    ax.legend(loc="upper right", fontsize=7, markerscale=4)
    return ax
