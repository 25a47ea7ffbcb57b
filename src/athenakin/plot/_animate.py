"""Animations of a motion (a sequence of ``q``, or an instrument path about the RCM) to GIF/MP4."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_array
from ..design import Design, resolve_design
from ..errors import KinematicsError
from ..robot import q_from_instrument
from ..robot._setup import resolve_rcm_frame
from ._geometry import VIEW, RobotGeometry, cube_limits, robot_geometry
from ._mpl import plot_robot

__all__ = ["instrument_cone_path", "render_frames", "animate", "ANIMATION_SIZE"]

#: Default frame size (width, height) in pixels; multiples of 16 suit video codecs.
ANIMATION_SIZE = (800, 640)


def instrument_cone_path(n: int = 48, T_b_e: ArrayLike | None = None,
                         design: Design | None = None, *, axis_e: ArrayLike = (1.0, 0.0, 0.0),
                         cone_angle: float = 0.1, p: ArrayLike | None = None,
                         turns: float = 1.0) -> NDArray[np.float64]:
    """Actuator values that sweep the instrument around a cone about the RCM.

    The instrument direction (frame E) turns ``turns`` times around ``axis_e`` at
    the half-angle ``cone_angle``; the insertion ``p`` (distance ``O_s`` -> RCM)
    is fixed or given per frame. Each direction is mapped to ``q`` by
    :func:`athenakin.q_from_instrument` (the controller-form IK).

    Parameters
    ----------
    n : int
        Number of samples (the last one is not the first again).
    T_b_e : array-like, shape (4, 4), optional
        RCM frame (default :func:`athenakin.default_rcm_frame`, whose reference
        instrument direction is ``x_e``).
    design : Design, optional
    axis_e : array-like, shape (3,), keyword-only
        Axis of the cone in frame E.
    cone_angle : float, keyword-only
        Half-angle of the cone, rad.
    p : array-like, shape () or (n,), keyword-only, optional
        Insertion, m (default :data:`athenakin.robot.REFERENCE_P`).
    turns : float, keyword-only

    Returns
    -------
    ndarray, shape (n, 3)
        ``q`` per sample, m.

    Raises
    ------
    KinematicsError
        A sample is out of the workspace (the message names the first).
    """
    from ..robot import REFERENCE_P

    design = resolve_design(design)
    T = resolve_rcm_frame(T_b_e, design)
    a = check_array(axis_e, "axis_e", (3,))
    a = a / np.linalg.norm(a)
    helper = np.array([0.0, 0.0, 1.0]) if abs(a[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(helper, a)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    t = 2 * np.pi * turns * np.arange(n) / n
    d = (np.cos(cone_angle) * a + np.sin(cone_angle) * (np.cos(t)[:, None] * e1
                                                         + np.sin(t)[:, None] * e2))
    pp = np.broadcast_to(np.asarray(REFERENCE_P if p is None else p, dtype=float), (n,))
    q, res = q_from_instrument(T, d, pp, design, errors="flag")
    if not np.all(res.valid):
        from ..errors import error_for_reason

        k = int(np.flatnonzero(~res.valid)[0])
        raise error_for_reason(int(res.reason[k]),
                               f"instrument path sample {k} (direction_e = "
                               f"{np.round(d[k], 4).tolist()}, p = {pp[k]} m)")
    return q


def _geometries(qs: NDArray[np.float64], T: NDArray[np.float64], design: Design,
                slot: int) -> list[RobotGeometry]:
    out = []
    for k, q in enumerate(qs):
        try:
            out.append(robot_geometry(q, T, design, slot=slot))
        except KinematicsError as exc:
            raise type(exc)(f"frame {k}: {exc}") from exc
    return out


def render_frames(q: ArrayLike, T_b_e: ArrayLike | None = None, design: Design | None = None,
                  *, slot: int = 0, size: tuple[int, int] = ANIMATION_SIZE, dpi: int = 100,
                  view: tuple[float, float] = VIEW, orbit: float = 0.0,
                  progress: bool = True, **kwargs: Any) -> list[NDArray[np.uint8]]:
    """Draw the robot at every ``q`` of a motion; one RGB image per sample.

    Parameters
    ----------
    q : array-like, shape (n, 3)
        The motion, m.
    T_b_e : array-like, shape (4, 4), optional
    design : Design, optional
    slot : int, keyword-only
        FK slot followed through the motion. The labels of a slot do not change
        along a continuous motion that avoids singularities.
    size : (int, int), keyword-only
        Width and height in pixels.
    dpi : int, keyword-only
    view : (float, float), keyword-only
        Elevation and azimuth of the first frame, degrees.
    orbit : float, keyword-only
        Degrees the camera turns about z over the motion.
    progress : bool, keyword-only
        tqdm progress bar.
    **kwargs
        Passed to :func:`~athenakin.plot.plot_robot`.

    Returns
    -------
    list of ndarray of uint8, each shape (height, width, 3)

    Raises
    ------
    KinematicsError
        A sample has no solution in ``slot`` (the message names the frame).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ..robot import REFERENCE_Q

    design = resolve_design(design)
    T = resolve_rcm_frame(T_b_e, design)
    qs = check_array(REFERENCE_Q if q is None else q, "q", (3,)).reshape(-1, 3)
    geoms = _geometries(qs, T, design, slot)
    los, his = zip(*(g.bounds() for g in geoms), strict=True)
    lo, hi = cube_limits(np.min(los, axis=0), np.max(his, axis=0))
    it: Any = range(len(geoms))
    if progress:
        from tqdm import tqdm

        it = tqdm(it, desc="rendering", unit="frame")
    frames: list[NDArray[np.uint8]] = []
    fig = Figure(figsize=(size[0] / dpi, size[1] / dpi), dpi=dpi)
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_subplot(projection="3d")
    fig.subplots_adjust(left=0, right=1, bottom=0, top=0.93)
    n = len(geoms)
    for k in it:
        ax.cla()
        frac = k / max(n - 1, 1)
        plot_robot(geometry=geoms[k], ax=ax, limits=(lo, hi),
                   view=(view[0], view[1] + orbit * frac), **kwargs)
        canvas.draw()
        rgba = np.asarray(canvas.buffer_rgba())
        frames.append(rgba[..., :3].copy())
    return frames


def animate(path: str | Path, q: ArrayLike, T_b_e: ArrayLike | None = None,
            design: Design | None = None, *, slot: int = 0, fps: float = 15.0,
            progress: bool = True, **kwargs: Any) -> Path:
    """Write an animation of a motion; the suffix picks the format (``.gif`` or ``.mp4``).

    Parameters
    ----------
    path : str or Path
        ``.gif`` (Pillow, loops forever) or ``.mp4`` (H.264 through imageio-ffmpeg).
    q : array-like, shape (n, 3)
        The motion, m (e.g. from :func:`instrument_cone_path` or a trajectory).
    T_b_e : array-like, shape (4, 4), optional
    design : Design, optional
    slot : int, keyword-only
    fps : float, keyword-only
        Frames per second.
    progress : bool, keyword-only
        tqdm progress bar while rendering.
    **kwargs
        Passed to :func:`render_frames`.

    Returns
    -------
    Path

    Raises
    ------
    ValueError
        Unknown suffix.
    KinematicsError
        A sample has no solution in ``slot``.
    """
    import imageio.v3 as iio

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".gif", ".mp4"):
        raise ValueError(f"path: expected a .gif or .mp4 file, got {path.name!r}")
    frames = render_frames(q, T_b_e, design, slot=slot, progress=progress, **kwargs)
    if suffix == ".gif":
        iio.imwrite(path, np.stack(frames), extension=".gif", duration=1000.0 / fps, loop=0)
    else:
        import imageio.v2 as iio2

        with iio2.get_writer(path, format="FFMPEG", mode="I", fps=fps, codec="libx264",
                             quality=7, pixelformat="yuv420p", macro_block_size=16) as w:
            for f in frames:
                w.append_data(f)  # type: ignore[attr-defined]
    return path
