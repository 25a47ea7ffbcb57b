"""Shared touches of athenakin's matplotlib figures: 3-D tick labels that do not collide, units.

Imported by the figure modules (``analysis.figures``, ``calibration._report``,
``motion._plot``, ``synthesis.figures``, ``plot._mpl``) inside their functions, after
matplotlib; it imports nothing of athenakin, so every layer may use it.
"""

from __future__ import annotations

from typing import Any

__all__ = ["MICRO_M", "tidy_3d_axes"]

#: The micrometre, as figures write it.
MICRO_M = "µm"


def tidy_3d_axes(ax: Any, *, nbins: int = 4, labelsize: float = 7.0,
                 labelpad: float = 1.0) -> Any:
    """Few tick labels per 3-D axis, none at either end, so that no two labels touch.

    Matplotlib puts the last tick label of one 3-D axis and the first of the next one
    at the same corner of the box ("250500"). At most ``nbins`` intervals per axis,
    the outermost ticks dropped (``MaxNLocator(prune="both")``), small labels close to
    the axis and the axis names a little further out.

    Parameters
    ----------
    ax : mpl_toolkits.mplot3d.axes3d.Axes3D
    nbins : int, keyword-only
        Most tick intervals per axis before the ends are pruned.
    labelsize : float, keyword-only
        Font size of the tick labels, pt.
    labelpad : float, keyword-only
        Distance of the axis names from the tick labels, pt.

    Returns
    -------
    Axes3D
        ``ax``.
    """
    from matplotlib.ticker import MaxNLocator

    for name in ("x", "y", "z"):
        axis = getattr(ax, f"{name}axis")
        axis.set_major_locator(MaxNLocator(nbins=nbins, prune="both"))
        axis.labelpad = labelpad
        ax.tick_params(axis=name, labelsize=labelsize, pad=0)
    return ax
