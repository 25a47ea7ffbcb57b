"""Scene description of a robot view: coloured line sets, points and labels (numpy only).

The parts, colours and sizes are those of the static views (:mod:`athenakin.plot`):
the positions come from :class:`~athenakin.plot.RobotGeometry`, the colours from
:data:`athenakin.plot.COLORS`. A renderer draws each :class:`LineSet` as one node of
line segments, each :class:`PointSet` as one point cloud, each :class:`Label` as a text
label and each :class:`Solid` (a triangle mesh: link or collision bodies) as one shaded
mesh; ghosts (the other valid slots) are the same parts, paler. :func:`robot_scene`
draws no solids yet; a caller adds them with :func:`with_solids`.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import NDArray

from .._typing import FloatArray
from .._validation import check_instance
from ..plot._geometry import RobotGeometry, check_length
from ..plot._mpl import ARC_RADIUS, COLORS, FRAME_LENGTH, arc_points

__all__ = ["LineSet", "PointSet", "Label", "Solid", "Scene", "robot_scene", "with_solids", "rgb",
           "PART_STYLE"]

#: Colour (``"#rrggbb"``) and line width (pixels) of each drawn part (the static views').
PART_STYLE: dict[str, tuple[str, float]] = {
    "rail": (COLORS["rail"], 6.0), "parallel": (COLORS["parallel"], 5.0),
    "actuator_q3": (COLORS["actuator"], 6.0), "circle_k1": (COLORS["circle_k1"], 1.5),
    "circle_k2": (COLORS["circle_k2"], 1.5), "ujoint": ("#333333", 4.0),
    "instrument": (COLORS["serial"], 6.0), "instrument_axis": (COLORS["serial"], 1.0),
    "spherical_joint": (COLORS["sphere"], 3.0), "frame_x": (COLORS["x"], 3.0),
    "frame_y": (COLORS["y"], 3.0), "frame_z": (COLORS["z"], 3.0),
}
#: Half-length of the drawn ``u1`` axis and length of the ``u2`` fork at ``O_s``, m.
UJOINT_AXIS_HALF = 0.03
UJOINT_FORK = 0.045
#: Half-length of the drawn spherical-joint axes, in units of the arc radius.
WRIST_AXIS_HALF = 0.4


def rgb(color: str) -> tuple[int, int, int]:
    """``"#1f4fbf"`` -> ``(31, 79, 191)``."""
    h = color.lstrip("#")
    if len(h) != 6:
        raise ValueError(f"color: expected '#rrggbb', got {color!r}")
    return int(h[0:2], 16), int(h[2:4], 16), int(h[4:6], 16)


@dataclasses.dataclass(frozen=True)
class LineSet:
    """Straight segments of one part, drawn in one colour.

    Attributes
    ----------
    name : str
    segments : ndarray, shape (n, 2, 3)
        Start and end of each segment, base frame, m.
    color : tuple of 3 int
        RGB, 0..255.
    width : float
        Line width, pixels.
    """

    name: str
    segments: FloatArray
    color: tuple[int, int, int]
    width: float


@dataclasses.dataclass(frozen=True)
class PointSet:
    """Joints and points, one colour each.

    Attributes
    ----------
    name : str
    points : ndarray, shape (n, 3)
        Base frame, m.
    colors : ndarray of uint8, shape (n, 3)
    size : float
        Point size, m.
    """

    name: str
    points: FloatArray
    colors: NDArray[np.uint8]
    size: float


@dataclasses.dataclass(frozen=True)
class Label:
    """A text label at a point (base frame, m)."""

    text: str
    position: FloatArray


@dataclasses.dataclass(frozen=True)
class Solid:
    """A body drawn as a shaded triangle mesh (a link, a collision body).

    Attributes
    ----------
    name : str
        Unique within a scene (the renderer's node name).
    vertices : ndarray, shape (n, 3)
        Base frame, m.
    faces : ndarray of int, shape (m, 3)
        Vertex indices of each triangle, counter-clockwise seen from outside.
    color : tuple of 3 int
        RGB, 0..255.
    opacity : float
        1: opaque, 0: invisible.
    """

    name: str
    vertices: NDArray[np.floating]
    faces: NDArray[np.integer]
    color: tuple[int, int, int]
    opacity: float = 1.0


@dataclasses.dataclass(frozen=True)
class Scene:
    """Everything drawn for one view.

    Attributes
    ----------
    lines : tuple of LineSet
    points : tuple of PointSet
    labels : tuple of Label
    solids : tuple of Solid
        Shaded bodies (none by default).
    """

    lines: tuple[LineSet, ...]
    points: tuple[PointSet, ...]
    labels: tuple[Label, ...]
    solids: tuple[Solid, ...] = ()

    def bounds(self) -> tuple[FloatArray, FloatArray]:
        """Axis-aligned box ``(lo, hi)`` (each shape (3,)) around every line, point and solid.

        Returns
        -------
        lo, hi : ndarray, shape (3,)
            Least and greatest coordinates of the finite points, base frame, m.
        """
        pts: list[NDArray[np.floating]] = [ls.segments.reshape(-1, 3) for ls in self.lines]
        pts += [ps.points for ps in self.points]
        pts += [so.vertices for so in self.solids]
        allp = np.concatenate(pts).astype(np.float64, copy=False)
        allp = allp[np.all(np.isfinite(allp), axis=-1)]
        return allp.min(axis=0), allp.max(axis=0)


def _polyline_segments(pts: FloatArray) -> FloatArray:
    """A polyline (n, 3) as n - 1 segments (n - 1, 2, 3)."""
    return np.stack([pts[:-1], pts[1:]], axis=1)


def _seg(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.array([[a, b]])


#: Point names drawn as joints, their labels, colours and whether they are the big ones.
_POINTS = (("A", "A", "rail"), ("B", "B", "rail"), ("M", "M", "joint"), ("D", "D", "joint"),
           ("C", "C", "joint"), ("O_i", "O_i", "joint"), ("O_s", "O_s", "joint"),
           ("RCM", "RCM", "sphere"), ("tip", "tip", "serial"))


def robot_scene(g: RobotGeometry, *, frames: bool = True, labels: bool = True,
                frame_length: float = FRAME_LENGTH) -> Scene:
    """The parts of one solution as a scene (the static views' parts and colours).

    Parameters
    ----------
    g : RobotGeometry
    frames : bool, keyword-only
        Triads of ``O_b``, ``O_i``, ``O_s``, ``O_e`` (x red, y green, z blue).
    labels : bool, keyword-only
        Text labels of the points.
    frame_length : float, keyword-only
        Length of the drawn frame axes, m.

    Returns
    -------
    Scene
        Line sets ``rail``, ``parallel``, ``actuator_q3``, ``circle_k1``, ``circle_k2``,
        ``ujoint``, ``instrument``, ``instrument_axis`` (only when the RCM is off the
        shaft), ``spherical_joint`` and ``frame_x``/``_y``/``_z``; one point set
        ``joints``.
    """
    check_instance(g, "g", RobotGeometry)
    frame_length = check_length(frame_length, "frame_length")
    for name, flag in (("frames", frames), ("labels", labels)):
        if not isinstance(flag, (bool, np.bool_)):
            raise TypeError(f"{name}: expected a bool, got {type(flag).__name__}")
    P, seg = g.points, g.segments()
    c = {k: rgb(v) for k, v in COLORS.items()}

    def part(name: str, segments: FloatArray) -> LineSet:
        color, width = PART_STYLE[name]
        return LineSet(name, segments, rgb(color), width)

    O_s, uj = P["O_s"], g.ujoint_axes
    lines = [
        part("rail", _seg(*g.rail)),
        part("parallel", np.array([seg[k] for k in ("link_a1", "link_b1", "link_a3", "link_b3",
                                                    "carrier_y", "carrier_z", "offset_l4")])),
        part("actuator_q3", np.array([seg["actuator_q3"]])),
        part("circle_k1", _polyline_segments(g.k1)),
        part("circle_k2", _polyline_segments(g.k2_arc)),
        part("ujoint", np.concatenate([
            _seg(O_s - UJOINT_AXIS_HALF * uj[0], O_s + UJOINT_AXIS_HALF * uj[0]),
            _seg(O_s, O_s + UJOINT_FORK * uj[1])])),
        part("instrument", np.array([seg["instrument"]])),
    ]
    if not 0.0 <= g.p <= g.design.tool_length:
        lines.append(part("instrument_axis", _seg(P["O_s"], P["RCM"])))
    rc, ax = P["RCM"], g.wrist_axes
    h = WRIST_AXIS_HALF * ARC_RADIUS
    sph = [_seg(rc - h * a, rc + h * a) for a in ax]
    sph += [_polyline_segments(arc_points(rc, ax[k], ax[k + 1], ARC_RADIUS)) for k in range(2)]
    lines.append(part("spherical_joint", np.concatenate(sph)))
    if frames:
        triads = [(g.frames["b"], 1.5), (g.frames["i"], 1.0), (g.frames["s"], 1.0),
                  (g.frames["e"], 1.0)]
        for i, axis in enumerate("xyz"):
            lines.append(part(f"frame_{axis}", np.concatenate(
                [_seg(T[:3, 3], T[:3, 3] + s * frame_length * T[:3, i]) for T, s in triads])))
    pts = np.stack([P[k] for k, _, _ in _POINTS])
    cols = np.array([c[col] for _, _, col in _POINTS], dtype=np.uint8)
    points = [PointSet("joints", pts, cols, 0.012)]
    other = g.intersections[1 if g.mode > 0 else 0]
    if np.all(np.isfinite(other)):
        points.append(PointSet("other_mode_O_i", other[None], np.array([c["joint"]], np.uint8),
                               0.008))
    labs = tuple(Label(text, P[k].copy()) for k, text, _ in _POINTS) if labels else ()
    return Scene(lines=tuple(lines), points=tuple(points), labels=labs)


def with_solids(scene: Scene, solids: tuple[Solid, ...]) -> Scene:
    """``scene`` with ``solids`` added (names must stay unique).

    Parameters
    ----------
    scene : Scene
    solids : tuple of Solid
        Meshes in the base frame, m; names not in ``scene``.

    Returns
    -------
    Scene
        A new scene; ``scene`` is unchanged.

    Raises
    ------
    InvalidInputError
        Two solids share a name, or a solid's arrays have the wrong shape.
    """
    from ..errors import InvalidInputError

    check_instance(scene, "scene", Scene)
    if not isinstance(solids, (tuple, list)) or not all(isinstance(so, Solid) for so in solids):
        raise TypeError(f"solids: expected a tuple of Solid, got {type(solids).__name__}")
    solids = tuple(solids)
    for so in solids:
        if not isinstance(so.name, str):
            raise TypeError(f"solids: names must be str, got {type(so.name).__name__}")
        try:
            v = np.asarray(so.vertices, dtype=float)
            f = np.asarray(so.faces)
        except (TypeError, ValueError):
            raise InvalidInputError(f"solids[{so.name!r}]: vertices and faces must be numeric "
                                    f"arrays") from None
        if v.ndim != 2 or v.shape[1:] != (3,) or f.ndim != 2 or f.shape[1:] != (3,):
            raise InvalidInputError(f"solids[{so.name!r}]: expected vertices (n, 3) and faces "
                                    f"(m, 3), got {v.shape} and {f.shape}")
        if not np.isfinite(v).all():
            raise InvalidInputError(f"solids[{so.name!r}]: vertices must be finite")
        if f.size and (f.dtype.kind not in "iu" or f.min() < 0 or f.max() >= v.shape[0]):
            raise InvalidInputError(f"solids[{so.name!r}]: faces must be integer indices into "
                                    f"the {v.shape[0]} vertices")
    names = [so.name for so in (*scene.solids, *solids)]
    if len(set(names)) != len(names):
        raise InvalidInputError(f"solids: names must be unique, got {names}")
    for so in solids:
        v, f = np.asarray(so.vertices), np.asarray(so.faces)
        if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3:
            raise InvalidInputError(f"solids[{so.name!r}]: expected vertices (n, 3) and faces "
                                    f"(m, 3), got {v.shape} and {f.shape}")
    return dataclasses.replace(scene, solids=scene.solids + tuple(solids))
