"""``athenakin animate``: a GIF or MP4 of a motion (instrument cone, q segment, or a q file)."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from .._interrupt import remembered_interrupt
from ._common import add_robot_options, check_count, check_finite, load_robot
from ._output import add_force_option, outputs
from ._view import add_slot_option

#: Largest number of frames taken from a q file (evenly spaced), unless --frames says otherwise.
MAX_FILE_FRAMES = 120
#: Most frames rendered (about 0.1 s and 1 MB each).
MAX_FRAMES = 3000
#: Frames per second: default, bound, and the bound used to play a timed file in real time
#: (GIF frame delays are in hundredths of a second and viewers slow down faster ones).
DEFAULT_FPS = 15.0
MAX_FPS = 120.0
MAX_GIF_FPS = 50.0


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``animate`` subcommand."""
    p = sub.add_parser(
        "animate", help="animate a motion to GIF or MP4",
        description="Render a motion of the robot to .gif or .mp4 (by the suffix of -o), with "
                    "a progress bar. The motion is, by default, the instrument sweeping a cone "
                    "about the RCM (mapped to q by the inverse kinematics); or a straight "
                    "segment in q (--from, --to); or a file of q values (--q-file: CSV with "
                    "columns q1_m, q2_m, q3_m as written by 'athenakin plan', or three "
                    "numbers per line).")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="FILE",
                   help="output file: .gif or .mp4")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--cone", type=float, default=None, metavar="DEG",
                   help="half-angle of the instrument cone about the reference direction, "
                        "deg (default 5.7, i.e. 0.1 rad)")
    g.add_argument("--from", dest="q_from", nargs=3, type=float, metavar=("Q1", "Q2", "Q3"),
                   help="start of a straight segment in q, m (needs --to)")
    g.add_argument("--q-file", type=Path, metavar="FILE", help="file of q values, m")
    p.add_argument("--to", dest="q_to", nargs=3, type=float, metavar=("Q1", "Q2", "Q3"),
                   help="end of the segment in q, m")
    p.add_argument("--p", type=float, default=None,
                   help="insertion O_s -> RCM for the cone, m (default 0.20)")
    p.add_argument("--frames", type=int, default=None,
                   help="number of frames (default 36; a q file: all rows up to 120)")
    p.add_argument("--fps", type=float, default=None,
                   help="frames per second (default 15; a q file with t_s: the rate that "
                        "plays the motion in its own time, 1 to 50)")
    p.add_argument("--orbit", type=float, default=0.0, metavar="DEG",
                   help="turn the camera about z by this much over the motion, deg")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_force_option(p)
    add_slot_option(p)
    add_robot_options(p)
    p.set_defaults(func=run)


def read_q_file(path: Path) -> tuple[np.ndarray, np.ndarray | None]:
    """Actuator rows (the motion subpackage's q-stream reader).

    Returns ``(q, t)``: ``q`` of shape (n, 3), m; ``t`` of shape (n,), s, from an
    optional ``t_s`` column, else None.
    """
    from ..motion import read_q_stream_csv

    q, t = read_q_stream_csv(path)
    bad = np.flatnonzero(~np.all(np.isfinite(q), axis=1))
    if bad.size:
        raise ValueError(f"--q-file {path}: reading {int(bad[0])} is incomplete "
                         f"(an animation needs every q1, q2, q3)")
    if t is not None and (not np.all(np.isfinite(t)) or np.any(np.diff(t) < 0)):
        raise ValueError(f"--q-file {path}: t_s must be finite and non-decreasing")
    return q, t


def run(args: argparse.Namespace) -> int:
    """Execute ``animate``."""
    from ..plot import animate, instrument_cone_path

    out = Path(args.output)
    if out.suffix.lower() not in (".gif", ".mp4"):
        raise ValueError(f"-o: expected a .gif or .mp4 file, got {str(out)!r}")
    if args.frames is not None:
        check_count(args.frames, "--frames", 2, MAX_FRAMES)
    if args.fps is not None:
        check_finite(args.fps, "--fps", positive=True)
        if args.fps > MAX_FPS:
            raise ValueError(f"--fps: expected at most {MAX_FPS:g} frames per second, got "
                             f"{args.fps:g}")
    for opt, v in (("--cone", args.cone), ("--p", args.p), ("--orbit", args.orbit),
                   ("--from", args.q_from), ("--to", args.q_to)):
        if v is not None:
            check_finite(v, opt)
    if args.cone is not None and not 0 < args.cone <= 90:
        raise ValueError(f"--cone: expected a half-angle in (0, 90] deg, got {args.cone:g}")
    if (args.q_from is None) != (args.q_to is None):
        raise ValueError("--from and --to go together")
    with outputs(args) as outs:
        outs.add(out)
        design, T = load_robot(args)
        fps = DEFAULT_FPS if args.fps is None else float(args.fps)
        note = ""
        if args.q_file is not None:
            q, t = read_q_file(args.q_file)
            rows = len(q)
            n = min(rows, MAX_FILE_FRAMES) if args.frames is None else args.frames
            pick = np.unique(np.round(np.linspace(0, rows - 1, n)).astype(int))
            q = q[pick]
            what = (f"{len(q)} rows of {args.q_file}" if len(q) == rows else
                    f"{len(q)} of {rows} rows of {args.q_file} (evenly spaced; --frames "
                    f"sets how many)")
            if t is not None and t[-1] > t[0]:
                motion = float(t[-1] - t[0])
                if args.fps is None:  # play the motion in its own time
                    fps = min(MAX_GIF_FPS, max(1.0, (len(q) - 1) / motion))
                video = (len(q) - 1) / fps
                if abs(video - motion) > 0.05 * motion:
                    note = (f"; the video lasts {video:.2f} s ({len(q)} frames at {fps:g} fps) "
                            f"for a {motion:.2f} s motion"
                            + (" (--fps sets the speed)" if args.fps is not None else
                               f" ({MAX_GIF_FPS:g} fps at most; --frames fewer for real "
                               f"time)" if fps >= MAX_GIF_FPS else " (1 fps at least)"))
        elif args.q_from is not None:
            n = args.frames or 36
            tt = np.linspace(0.0, 1.0, n)[:, None]
            q = np.array(args.q_from) + tt * (np.array(args.q_to) - np.array(args.q_from))
            what = f"segment {args.q_from} -> {args.q_to} m"
        else:
            cone = np.radians(args.cone) if args.cone is not None else 0.1
            n = args.frames or 36
            q = instrument_cone_path(n, T, design, cone_angle=cone, p=args.p, lead=n // 6)
            what = (f"instrument cone of half-angle {np.degrees(cone):.1f} deg about the RCM"
                    + (", starting and ending on the cone axis x_e" if n // 6 else ""))
        # a Ctrl-C that matplotlib's callbacks swallow is raised again
        with remembered_interrupt():
            animate(outs.temp(out), q, T, design, slot=args.slot, fps=fps, orbit=args.orbit,
                    progress=not args.no_progress)
        outs.commit()
    print(f"wrote {out}: {len(q)} frames, {what}, solution {args.slot}{note}")
    return 0
