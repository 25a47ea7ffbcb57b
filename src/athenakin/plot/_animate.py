"""Animations of a motion (a sequence of ``q``, or an instrument path about the RCM) to GIF/MP4."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._typing import FloatArray
from .._validation import check_array, check_scalar
from ..design import Design, resolve_design
from ..errors import KinematicsError
from ..robot import q_from_instrument
from ..robot._setup import resolve_rcm_frame
from ._geometry import VIEW, RobotGeometry, cube_around, robot_geometry
from ._mpl import PlotOptions, plot_robot

__all__ = ["instrument_cone_path", "render_frames", "animate", "draw_motion_frame",
           "ANIMATION_SIZE", "TRACE_COLOR", "MAX_PATH_SAMPLES", "MAX_TURNS"]

#: Default frame size (width, height) in pixels; multiples of 16 suit video codecs.
ANIMATION_SIZE = (800, 640)


#: Most samples of :func:`instrument_cone_path` (checked before anything is allocated).
MAX_PATH_SAMPLES = 100_000
#: Most turns of :func:`instrument_cone_path` about the cone axis.
MAX_TURNS = 1000.0


#: Largest width or height of a rendered frame, px (:func:`render_frames`).
MAX_FRAME_PIXELS = 8192


def instrument_cone_path(n: int = 48, T_b_e: ArrayLike | None = None,
                         design: Design | None = None, *, axis_e: ArrayLike = (1.0, 0.0, 0.0),
                         cone_angle: float = 0.1, p: ArrayLike | None = None,
                         turns: float = 1.0, lead: int = 0) -> FloatArray:
    """Actuator values that sweep the instrument around a cone about the RCM.

    The instrument direction (frame E) turns ``turns`` times around ``axis_e`` at
    the half-angle ``cone_angle``; the insertion ``p`` (distance ``O_s`` -> RCM)
    is fixed or given per frame. Each direction is mapped to ``q`` by
    :func:`athenakin.q_from_instrument` (the controller-form IK). With ``lead``,
    the motion starts on the axis (for the defaults: at
    :data:`athenakin.robot.REFERENCE_Q`), tilts out to the cone in ``lead``
    samples, sweeps it, and comes back to the axis in ``lead`` samples, so that
    an animation starts and ends at the reference and loops without a jump.

    Parameters
    ----------
    n : int
        Number of samples (the last one is not the first again), 2 to
        :data:`MAX_PATH_SAMPLES`.
    T_b_e : array-like, shape (4, 4), optional
        RCM frame (default :func:`athenakin.default_rcm_frame`, whose reference
        instrument direction is ``x_e``).
    design : Design, optional
    axis_e : array-like, shape (3,), keyword-only
        Axis of the cone in frame E.
    cone_angle : float, keyword-only
        Half-angle of the cone, rad, in ``[0, pi]``.
    p : array-like, shape () or (n,), keyword-only, optional
        Insertion, m (default :data:`athenakin.robot.REFERENCE_P`).
    turns : float, keyword-only
        Turns about the axis, in ``[-MAX_TURNS, MAX_TURNS]``.
    lead : int, keyword-only
        Samples (of the ``n``) that tilt out from the axis at the start, and as many
        that tilt back at the end; 0 (default): every sample is on the cone.

    Returns
    -------
    ndarray, shape (n, 3)
        ``q`` per sample, m.

    Raises
    ------
    InvalidInputError
        ``n - 2 lead`` is less than 2.
    KinematicsError
        A sample is out of the workspace (the message names the first).
    """
    from ..errors import InvalidInputError
    from ..robot import REFERENCE_P

    n, lead, cone_angle, turns = _check_cone(n, lead, cone_angle, turns)
    design = resolve_design(design)
    T = resolve_rcm_frame(T_b_e, design)
    d = _cone_directions(axis_e, n, lead, cone_angle, turns)
    pa = check_array(REFERENCE_P if p is None else p, "p", ())
    if pa.shape not in ((), (n,)):
        raise InvalidInputError(f"p: expected shape () or ({n},), got shape {pa.shape}")
    pp = np.broadcast_to(pa, (n,))
    q, res = q_from_instrument(T, d, pp, design, errors="flag")
    if not np.all(res.valid):
        from ..errors import error_for_reason

        k = int(np.flatnonzero(~res.valid)[0])
        raise error_for_reason(int(res.reason[k]),
                               f"instrument path sample {k} (direction_e = "
                               f"{np.round(d[k], 4).tolist()}, p = {pp[k]} m)")
    return q


def _check_cone(n: object, lead: object, cone_angle: object, turns: object
                ) -> tuple[int, int, float, float]:
    """``n``, ``lead``, ``cone_angle``, ``turns`` of :func:`instrument_cone_path`, checked."""
    from .._validation import check_count
    from ..errors import InvalidInputError

    n = check_count(n, "n", minimum=2, maximum=MAX_PATH_SAMPLES)
    if isinstance(lead, bool) or not isinstance(lead, (int, np.integer)) or lead < 0 \
            or n - 2 * lead < 2:
        raise InvalidInputError(f"lead: expected an integer in 0..{(n - 2) // 2} for n = {n} "
                                f"samples (2 lead + at least 2 on the cone), got {lead!r}")
    cone_angle = check_scalar(cone_angle, "cone_angle", nonnegative=True)
    if not cone_angle <= np.pi:
        raise InvalidInputError(f"cone_angle: expected a half-angle in [0, pi] rad, got "
                                f"{cone_angle}")
    turns = check_scalar(turns, "turns")
    if not abs(turns) <= MAX_TURNS:
        raise InvalidInputError(f"turns: expected a number in [-{MAX_TURNS}, {MAX_TURNS}], got "
                                f"{turns}")
    return n, int(lead), cone_angle, turns


def _cone_directions(axis_e: ArrayLike, n: int, lead: int, cone_angle: float,
                     turns: float) -> FloatArray:
    """Unit instrument directions (n, 3) in frame E of :func:`instrument_cone_path`.

    ``turns`` turns at the half-angle ``cone_angle`` about ``axis_e`` over ``n - 2 lead``
    samples, after ``lead`` samples that tilt out from the axis and before ``lead`` that
    tilt back.
    """
    from ..errors import InvalidInputError

    a = check_array(axis_e, "axis_e", (3,))
    if a.shape != (3,) or not np.any(a):
        raise InvalidInputError(f"axis_e: expected a non-zero direction of shape (3,), got "
                                f"{a.tolist()}")
    a = a / np.abs(a).max()
    a = a / np.linalg.norm(a)
    helper = np.array([0.0, 0.0, 1.0]) if abs(a[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(helper, a)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    m = n - 2 * lead
    t = 2 * np.pi * turns * np.arange(m) / m
    tilt = np.full(m, float(cone_angle))
    if lead:
        ramp = cone_angle * np.arange(lead) / lead             # 0 (on the axis) .. < cone
        t = np.concatenate([np.zeros(lead), t, np.full(lead, t[-1])])
        tilt = np.concatenate([ramp, tilt, cone_angle * np.arange(lead - 1, -1, -1) / lead])
    return (np.cos(tilt)[:, None] * a + np.sin(tilt)[:, None] * (np.cos(t)[:, None] * e1
                                                                  + np.sin(t)[:, None] * e2))


def _geometries(qs: FloatArray, T: FloatArray, design: Design,
                slot: int) -> list[RobotGeometry]:
    out = []
    for k, q in enumerate(qs):
        try:
            out.append(robot_geometry(q, T, design, slot=slot))
        except KinematicsError as exc:
            raise type(exc)(f"frame {k}: {exc}") from exc
    return out


#: Colour of the traced motion (the instrument's sweep and the tool-tip path).
TRACE_COLOR = "#e8743b"
#: Number of instrument lines drawn of the sweep.
TRACE_LINES = 24


def draw_motion_frame(ax: Any, geoms: list[RobotGeometry], k: int, *,
                      limits: tuple[FloatArray, FloatArray],
                      view: tuple[float, float] = VIEW, trace: bool = True,
                      **kwargs: Any) -> Any:
    """Draw frame ``k`` of a motion: the robot, and (``trace``) the whole motion faintly.

    The trace is the tool-tip path (dashed; solid up to frame ``k``) and
    :data:`TRACE_LINES` instrument lines spread over the motion, from ``O_s``
    through the RCM to the tip: the surface the instrument sweeps.

    Parameters
    ----------
    ax : Axes3D
    geoms : list of RobotGeometry
        Every frame of the motion.
    k : int
        The frame drawn.
    limits : (ndarray, ndarray), keyword-only
        Axis box (m), the same for every frame.
    view : (float, float), keyword-only
    trace : bool, keyword-only
    **kwargs
        Passed to :func:`~athenakin.plot.plot_robot`; the ``limits`` and ``view`` of
        its ``options`` (:class:`~athenakin.plot.PlotOptions`) are those given here.

    Returns
    -------
    Axes3D
    """
    if trace and len(geoms) > 1:
        from matplotlib.lines import Line2D

        kwargs.setdefault("legend_extra", [Line2D([], [], color=TRACE_COLOR, lw=1.5,
                                                  label="motion: instrument sweep, tip path")])
        tips = np.stack([g.points["tip"] for g in geoms])
        ax.plot(*tips.T, color=TRACE_COLOR, lw=1.2, ls="--", alpha=0.9)
        ax.plot(*tips[:k + 1].T, color=TRACE_COLOR, lw=2.4)
        for j in np.unique(np.linspace(0, len(geoms) - 1, TRACE_LINES).astype(int)):
            a, b = geoms[j].points["O_s"], geoms[j].points["tip"]
            ax.plot(*np.stack([a, b]).T, color=TRACE_COLOR, lw=0.9, alpha=0.45)
    base = kwargs.pop("options", None)
    opts = dataclasses.replace(PlotOptions() if base is None else base, limits=limits,
                               view=view)
    return plot_robot(geometry=geoms[k], ax=ax, options=opts, **kwargs)


def render_frames(q: ArrayLike, T_b_e: ArrayLike | None = None, design: Design | None = None,
                  *, slot: int = 0, size: tuple[int, int] = ANIMATION_SIZE, dpi: int = 100,
                  view: tuple[float, float] = VIEW, orbit: float = 0.0,
                  progress: bool = True, trace: bool = True,
                  **kwargs: Any) -> list[NDArray[np.uint8]]:
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
    trace : bool, keyword-only
        Draw the whole motion in every frame (:func:`draw_motion_frame`): the
        tool-tip path and the instrument lines it sweeps, which make a small
        cone about the RCM visible.
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

    from .._interrupt import check_interrupt
    from .._validation import check_count
    from ..robot import REFERENCE_Q
    from ._geometry import check_view

    size = _check_frame_size(size)
    dpi = check_count(dpi, "dpi", minimum=1, maximum=1200)
    view = check_view(view)
    orbit = check_scalar(orbit, "orbit")
    design = resolve_design(design)
    T = resolve_rcm_frame(T_b_e, design)
    qs = check_array(REFERENCE_Q if q is None else q, "q", (3,)).reshape(-1, 3)
    geoms = _geometries(qs, T, design, slot)
    lo, hi = cube_around(geoms)
    frames: list[NDArray[np.uint8]] = []
    fig = Figure(figsize=(size[0] / dpi, size[1] / dpi), dpi=dpi)
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_subplot(projection="3d")
    fig.subplots_adjust(left=0, right=1, bottom=0, top=0.93)
    n = len(geoms)
    for k in _progress(range(n), progress, desc="rendering", unit="frame"):
        check_interrupt()    # a Ctrl-C lost inside matplotlib's callbacks (_interrupt.py)
        ax.cla()
        # the box is fixed (limits): no autoscale after each of the frame's ~60 lines
        ax.set_autoscale_on(False)
        frac = k / max(n - 1, 1)
        draw_motion_frame(ax, geoms, k, limits=(lo, hi),
                          view=(view[0], view[1] + orbit * frac), trace=trace, **kwargs)
        canvas.draw()
        rgba = np.asarray(canvas.buffer_rgba())
        frames.append(rgba[..., :3].copy())
    return frames


def _check_frame_size(size: ArrayLike) -> tuple[int, int]:
    """``(width, height)`` of a frame, integers in 16..:data:`MAX_FRAME_PIXELS` px."""
    from ..errors import InvalidInputError

    sz = check_array(size, "size", (2,))
    if sz.shape != (2,) or not np.all((sz >= 16) & (sz <= MAX_FRAME_PIXELS)) \
            or not np.all(sz == np.round(sz)):
        raise InvalidInputError(f"size: expected (width, height), integers in 16.."
                                f"{MAX_FRAME_PIXELS} px, got {sz.tolist()}")
    return int(sz[0]), int(sz[1])


def _progress(it: Any, show: bool, **kwargs: Any) -> Any:
    """``it``, wrapped in a tqdm progress bar (on a terminal only) where ``show``."""
    if not show:
        return it
    from tqdm import tqdm

    return tqdm(it, disable=None, **kwargs)


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
        ``path``, written (a looping GIF or an H.264 MP4).

    Raises
    ------
    ValueError
        A suffix other than ``.gif`` or ``.mp4``, or ``fps`` above 120.
    KinematicsError
        A sample has no solution in ``slot``.
    """
    import imageio.v3 as iio

    from .._output import check_output_path

    path = check_output_path(path)
    fps = check_scalar(fps, "fps", positive=True)
    if not fps <= 120.0:
        raise ValueError(f"fps: expected frames per second in (0, 120], got {fps:g}")
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
