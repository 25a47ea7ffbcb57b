"""Placing point labels on a matplotlib view without overlaps (place_labels)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .._typing import FloatArray

if TYPE_CHECKING:  # pragma: no cover
    from mpl_toolkits.mplot3d.axes3d import Axes3D as Axes

#: Font size of the point labels, pt.
LABEL_SIZE = 8.5

#: Distances (pt) at which a label is tried around its point, nearest first.
LABEL_RADII = (5.0, 11.0, 18.0, 28.0, 40.0)

#: Half-size (px at 100 dpi) of the box kept free around each labelled point.
MARKER_HALF = 4.0

#: Share of a label's width (height) left of (below) its anchor, by alignment.
_SHIFT = {"left": 0.0, "bottom": 0.0, "center": 0.5, "right": 1.0, "top": 1.0}

#: Points that project closer than this (px at 100 dpi) share one label.
MERGE_PX = 6.0

#: Labels never merged with each other: the two carriages, labelled apart however close.
KEEP_APART = frozenset({"A", "B"})

#: Labels left out where they would share one with :data:`KEEP_APART` (M, the midpoint of
#: A and B, lies between them; give it after them).
LEFT_OUT_NEAR_APART = frozenset({"M"})


def _renderer(fig: Any) -> Any:
    get = getattr(fig.canvas, "get_renderer", None)
    if get is not None:
        return get()
    fig.draw_without_rendering()                      # pragma: no cover - non-Agg canvas
    return fig._get_renderer()                        # pragma: no cover


def _project(ax: Axes, pts: FloatArray) -> FloatArray:
    """Display coordinates (px) of 3-D points, shape (n, 2), with the axes' current view."""
    from mpl_toolkits.mplot3d import proj3d

    pts = np.atleast_2d(pts)
    x, y, _ = proj3d.proj_transform(pts[:, 0], pts[:, 1], pts[:, 2], ax.get_proj())
    return np.asarray(ax.transData.transform(np.column_stack([x, y])))


def _overlap(a: FloatArray, b: FloatArray) -> FloatArray:
    """Overlap areas of box ``a`` (x0, y0, x1, y1) with each of the boxes ``b``, shape (n,)."""
    b = np.asarray(b, dtype=float).reshape(-1, 4)
    w = np.minimum(a[2], b[:, 2]) - np.maximum(a[0], b[:, 0])
    h = np.minimum(a[3], b[:, 3]) - np.maximum(a[1], b[:, 1])
    return np.asarray(np.maximum(w, 0.0) * np.maximum(h, 0.0))


def _sample(poly: FloatArray, step: float) -> FloatArray:
    """Points along a polyline (n, 2) no farther apart than ``step``."""
    out = [poly[:1]]
    for a, b in zip(poly[:-1], poly[1:], strict=True):
        n = max(int(np.ceil(np.hypot(*(b - a)) / step)), 1)
        out.append(a + np.linspace(0.0, 1.0, n + 1)[1:, None] * (b - a))
    return np.concatenate(out)


def place_labels(ax: Axes, items: list[tuple[str, FloatArray, str]], *,
                 lines: list[FloatArray] | None = None,
                 boxes: list[FloatArray] | None = None,
                 fontsize: float = LABEL_SIZE) -> list[Any]:
    """Label 3-D points so that no two labels overlap and every label lies in the axes.

    Points that project to nearly the same pixel share one label (``"M, O_b"``), but for
    the carriages A and B (:data:`KEEP_APART`: two labels, placed apart) and M between
    them (:data:`LEFT_OUT_NEAR_APART`: left out when it would join A or B).
    Each label is tried at 8 directions around its point at growing distances
    (:data:`LABEL_RADII`) and goes to the place of least cost: overlap with labels
    placed before it and with ``boxes`` (weight 100), with the labelled points
    (weight 10) and with the drawn ``lines`` (weight 1); a place outside the
    axes is never taken while another is free. A label placed far from its point
    gets a thin leader line. The labels are 2-D annotations at the points'
    projections, so place them after the limits and view are final.

    Parameters
    ----------
    ax : Axes3D
    items : list of (str, ndarray shape (3,), str)
        Text, point (data units) and colour, most important first.
    lines : list of ndarray shape (n, 3), optional
        Drawn polylines (data units) that labels keep clear of where they can.
    boxes : list of ndarray shape (4,), optional
        Display boxes ``(x0, y0, x1, y1)`` (px) that labels avoid (e.g. a legend).
    fontsize : float

    Returns
    -------
    list of matplotlib.text.Annotation
    """
    fig = ax.figure
    ax.apply_aspect()
    renderer = _renderer(fig)
    scale = fig.dpi / 100.0
    anchors = _project(ax, np.stack([p for _, p, _ in items])) if items else np.zeros((0, 2))
    merged = _merge_labels(items, anchors, MERGE_PX * scale)
    half = MARKER_HALF * scale
    marks = np.array([[x - half, y - half, x + half, y + half] for _, _, (x, y), _ in merged])
    hard = [np.asarray(b, dtype=float).reshape(4) for b in boxes or []]
    soft = _line_boxes(ax, lines, scale)
    inv = ax.transData.inverted()
    out = []
    for text, _, xy, color in merged:
        x2, y2 = inv.transform(xy)
        ann = ax.annotate(text, xy=(x2, y2), xycoords="data", xytext=(0, 0),
                          textcoords="offset points", fontsize=fontsize, color=color,
                          ha="left", va="bottom", annotation_clip=False, zorder=20)
        ext = ann.get_window_extent(renderer)          # measured once; boxes follow
        off, ha, va, box = _best_place(ext, fig.dpi, ax.bbox.extents, hard, marks, soft)
        ann.set(ha=ha, va=va)
        ann.xyann = off
        if np.hypot(*off) > LABEL_RADII[1] + 1:         # far from its point: a leader line
            ann.remove()
            ann = ax.annotate(text, xy=(x2, y2), xycoords="data", xytext=off,
                              textcoords="offset points", fontsize=fontsize, color=color,
                              ha=ha, va=va, annotation_clip=False, zorder=20,
                              arrowprops={"arrowstyle": "-", "color": "0.5", "lw": 0.6,
                                          "shrinkA": 1.0, "shrinkB": 3.0})
        hard.append(box)
        out.append(ann)
    return out


def _merge_labels(items: list[tuple[str, FloatArray, str]],
                  anchors: FloatArray, merge_px: float
                  ) -> list[tuple[str, FloatArray, FloatArray, str]]:
    """``(text, point, pixel, colour)`` per label, where close points share one label.

    Points closer than ``merge_px`` on the screen share one label, but for
    :data:`KEEP_APART` and :data:`LEFT_OUT_NEAR_APART`.
    """
    merged: list[tuple[str, FloatArray, FloatArray, str]] = []
    for (text, p, color), xy in zip(items, anchors, strict=True):
        for k, (t0, p0, xy0, c0) in enumerate(merged):
            if np.hypot(*(xy - xy0)) >= merge_px:
                continue
            names = set(t0.split(", "))
            if text in LEFT_OUT_NEAR_APART and names & KEEP_APART:
                break                                    # M between close carriages
            if text in KEEP_APART and names & KEEP_APART:
                continue                                 # A and B: each its own label
            merged[k] = (f"{t0}, {text}", p0, xy0, c0)
            break
        else:
            merged.append((text, p, xy, color))
    return merged


def _line_boxes(ax: Axes, lines: list[FloatArray] | None,
                scale: float) -> FloatArray:
    """Small display boxes (n, 4) (px) along the drawn ``lines``: what labels should avoid."""
    if not lines:
        return np.zeros((0, 4))
    pts = np.concatenate([_sample(_project(ax, np.asarray(ln, dtype=float)), 3.0 * scale)
                          for ln in lines])
    lw = 1.5 * scale
    return np.column_stack([pts - lw, pts + lw])


#: The 8 directions (screen x, y) tried around a point, in order of preference.
_DIRECTIONS = ((1, 1), (1, -1), (-1, 1), (-1, -1), (1, 0), (-1, 0), (0, 1), (0, -1))


def _best_place(ext: Any, dpi: float, frame: FloatArray, hard: list[Any],
                marks: FloatArray, soft: FloatArray
                ) -> tuple[tuple[float, float], str, str, FloatArray]:
    """The least-cost place of a label whose box at offset 0 is ``ext`` (display px).

    Returns the offset (points), the horizontal and vertical alignment and the label's
    display box ``(x0, y0, x1, y1)``; costs as in :func:`place_labels`.
    """
    w, h = ext.width, ext.height
    x0, y0 = ext.x0, ext.y0                        # the box's corner at offset 0
    best: tuple[float, Any, str, str, FloatArray] | None = None
    for r in LABEL_RADII:
        for dx, dy in _DIRECTIONS:
            ha = "left" if dx > 0 else "right" if dx < 0 else "center"
            va = "bottom" if dy > 0 else "top" if dy < 0 else "center"
            off = (r * dx / np.hypot(dx, dy), r * dy / np.hypot(dx, dy))
            bx = x0 + off[0] * dpi / 72.0 - _SHIFT[ha] * w
            by = y0 + off[1] * dpi / 72.0 - _SHIFT[va] * h
            box = np.array([bx, by, bx + w, by + h])
            cost = (100.0 * float(sum(_overlap(box, b).sum() for b in hard))
                    + 10.0 * float(_overlap(box, marks).sum())
                    + float(_overlap(box, soft).sum()) + 0.5 * r)
            inside = (box[0] >= frame[0] and box[1] >= frame[1] and box[2] <= frame[2]
                      and box[3] <= frame[3])
            cost += 0.0 if inside else 1e12
            if best is None or cost < best[0]:
                best = (cost, off, ha, va, box)
    assert best is not None
    return best[1], best[2], best[3], best[4]
