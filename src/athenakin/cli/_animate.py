"""``athenakin animate``: a GIF or MP4 of a motion (instrument cone, q segment, or a q file)."""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np

from ._common import add_design_option, add_setup_options, load_design, load_rcm
from ._view import add_slot_option

#: Largest number of frames taken from a q file (evenly spaced), unless --frames says otherwise.
MAX_FILE_FRAMES = 120


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
    p.add_argument("--fps", type=float, default=15.0, help="frames per second (15)")
    p.add_argument("--orbit", type=float, default=0.0, metavar="DEG",
                   help="turn the camera about z by this much over the motion, deg")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_slot_option(p)
    add_design_option(p)
    add_setup_options(p)
    p.set_defaults(func=run)


def read_q_file(path: Path) -> np.ndarray:
    """Actuator rows from a CSV with columns q1_m, q2_m, q3_m, or 3 numbers per line."""
    text = Path(path).read_text()
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise ValueError(f"--q-file {path}: no data")
    head = [c.strip() for c in next(csv.reader([lines[0]]))]
    if {"q1_m", "q2_m", "q3_m"} <= set(head):
        idx = [head.index(c) for c in ("q1_m", "q2_m", "q3_m")]
        rows = [[r[i] for i in idx] for r in csv.reader(lines[1:])]
    else:
        rows = [ln.replace(",", " ").split() for ln in lines]
    try:
        q = np.array(rows, dtype=float)
    except ValueError as exc:
        raise ValueError(f"--q-file {path}: expected numbers, {exc}") from None
    if q.ndim != 2 or q.shape[1] != 3:
        raise ValueError(f"--q-file {path}: expected 3 values per row, got shape {q.shape}")
    return q


def run(args: argparse.Namespace) -> int:
    """Execute ``animate``."""
    from ..plot import animate, instrument_cone_path

    out = Path(args.output)
    if out.suffix.lower() not in (".gif", ".mp4"):
        raise ValueError(f"-o: expected a .gif or .mp4 file, got {str(out)!r}")
    if not out.parent.exists():
        raise ValueError(f"-o: folder {str(out.parent)!r} does not exist")
    if args.frames is not None and args.frames < 2:
        raise ValueError(f"--frames: expected at least 2, got {args.frames}")
    if (args.q_from is None) != (args.q_to is None):
        raise ValueError("--from and --to go together")
    design = load_design(args)
    T = load_rcm(args, design)
    if args.q_file is not None:
        q = read_q_file(args.q_file)
        n = min(len(q), MAX_FILE_FRAMES) if args.frames is None else args.frames
        q = q[np.unique(np.round(np.linspace(0, len(q) - 1, n)).astype(int))]
        what = f"{len(q)} rows of {args.q_file}"
    elif args.q_from is not None:
        n = args.frames or 36
        t = np.linspace(0.0, 1.0, n)[:, None]
        q = np.array(args.q_from) + t * (np.array(args.q_to) - np.array(args.q_from))
        what = f"segment {args.q_from} -> {args.q_to} m"
    else:
        cone = np.radians(args.cone) if args.cone is not None else 0.1
        n = args.frames or 36
        q = instrument_cone_path(n, T, design, cone_angle=cone, p=args.p, lead=n // 6)
        what = (f"instrument cone of half-angle {np.degrees(cone):.1f} deg about the RCM"
                + (", starting and ending on the cone axis x_e" if n // 6 else ""))
    animate(out, q, T, design, slot=args.slot, fps=args.fps, orbit=args.orbit,
            progress=not args.no_progress)
    print(f"wrote {out}: {len(q)} frames, {what}, solution {args.slot}")
    return 0
