"""Shared pieces of the analysis figures (private): units, colours, axes, overlays.

Used by :mod:`athenakin.analysis.figures` and :mod:`athenakin.analysis._figures_cone`;
matplotlib is imported inside each function.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._typing import BoolArray, FloatArray

MM = 1e3
#: Colours of assembly mode +1, mode -1, and of positions outside the stroke limits.
COLOR_MODE = {1: "#1f77b4", -1: "#ff7f0e"}
COLOR_OUT = "#d9d9d9"
COLOR_LOCI = {"w0": "#d62728", "h0": "#2ca02c", "l3": "#9467bd", "stroke": "black"}
#: Hatching and outline of the directions with two insertion intervals.
TWO_INTERVALS_COLOR = "#00bcd4"
#: Hatching and outline of what a collision blocks (maps computed with the collision check).
COLLISION_COLOR = "#e7298a"


def _collision_overlay(ax: Any, U: FloatArray, V: FloatArray,
                       blocked: BoolArray, label: str) -> Any:
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


def _slice_index(axis: FloatArray, value: float) -> int:
    return int(np.argmin(np.abs(axis - value)))
