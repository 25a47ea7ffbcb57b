"""``athenakin view``: a picture of the robot (PNG/SVG/PDF) or an interactive page (HTML)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..design import Design
from ._common import add_robot_options, check_dpi, load_robot
from ._output import add_force_option, outputs

if TYPE_CHECKING:  # pragma: no cover
    from ..design import Design

VIEW_SUFFIXES = (".png", ".svg", ".pdf", ".html")


def add_q_argument(p: argparse.ArgumentParser) -> None:
    """Optional positional ``Q1 Q2 Q3`` (m); none means the reference configuration."""
    p.add_argument("q", nargs="*", type=float, metavar="Q",
                   help="actuators q1 q2 q3, m (default: the reference configuration "
                        "-0.10 0.10 0.45)")


def q_from_args(args: argparse.Namespace) -> np.ndarray | None:
    """``args.q`` as an array of shape (3,), or None when not given."""
    if not args.q:
        return None
    if len(args.q) != 3:
        raise ValueError(f"q: expected 3 numbers (q1 q2 q3, m), got {len(args.q)}")
    q = np.array(args.q, dtype=float)
    if not np.all(np.isfinite(q)):
        raise ValueError(f"q: expected finite numbers (q1 q2 q3, m), got {args.q}")
    return q


def add_slot_option(p: argparse.ArgumentParser) -> None:
    """``--slot K``."""
    p.add_argument("--slot", type=int, default=0, metavar="K",
                   help="forward-kinematics solution 0..15 (0: mode +1, p > 0, sin u2 > 0, "
                        "sin u4 > 0; see 'athenakin fk')")


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``view`` subcommand."""
    p = sub.add_parser(
        "view", help="draw the robot: PNG/SVG/PDF picture or interactive HTML page",
        description="Draw the robot in one forward-kinematics solution (or all 16 with --all): "
                    "rail and carriages A, B, the parallel module, circles k1 and k2, frames "
                    "O_i, O_s and E, the U-joint, the instrument through the RCM and the "
                    "spherical joint. The suffix of -o picks the output: .png, .svg, .pdf "
                    "(matplotlib) or .html (self-contained interactive page with a menu of "
                    "the solutions).")
    add_q_argument(p)
    p.add_argument("-o", "--output", type=Path, required=True, metavar="FILE",
                   help="output file: .png, .svg, .pdf or .html")
    add_slot_option(p)
    p.add_argument("--all", action="store_true",
                   help="all 16 solutions: side by side (static formats) or all at once "
                        "with one legend entry per solution (HTML)")
    p.add_argument("--no-frames", action="store_true", help="hide the frame triads")
    p.add_argument("--no-labels", action="store_true", help="hide the text labels (static)")
    p.add_argument("--view", nargs=2, type=float, metavar=("ELEV", "AZIM"),
                   help="camera elevation and azimuth, deg (static formats)")
    p.add_argument("--dpi", type=int, default=120, help="resolution of PNG output (120)")
    p.add_argument("--bodies", nargs="?", const="default", default=None, metavar="FILE",
                   help="also draw the bodies as shaded capsules, the closest pair coloured "
                        "(one solution, static formats): the default capsules, or the "
                        "[bodies] table of FILE (the --design file's when it has one)")
    add_force_option(p)
    add_robot_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Execute ``view``."""
    out = Path(args.output)
    if out.suffix.lower() not in VIEW_SUFFIXES:
        raise ValueError(f"-o: expected a file ending in {', '.join(VIEW_SUFFIXES)}, "
                         f"got {str(out)!r}")
    check_dpi(args.dpi)
    if args.bodies is not None and (args.all or out.suffix.lower() == ".html"):
        raise ValueError("--bodies: draws one solution in a static format (.png, .svg, "
                         ".pdf), not with --all or .html")
    with outputs(args) as outs:
        outs.add(out)
        design, T = load_robot(args)
        q = q_from_args(args)
        _render(args, outs.temp(out), q, T, design)
        outs.commit()
    what = "all solutions" if args.all else f"solution {args.slot}"
    print(f"wrote {out} ({what})")
    return 0


def _render(args: argparse.Namespace, out: Path, q: np.ndarray | None, T: np.ndarray,
            design: Design) -> None:
    from ..plot import PlotOptions, save_view

    kw: dict = {"show_frames": not args.no_frames}  # type: ignore[type-arg]
    if out.suffix.lower() != ".html":
        if args.bodies is not None:       # the bodies as solids: plot/_solids.py
            from ..collision import Bodies

            src = args.bodies if args.bodies != "default" else getattr(args, "design", None)
            kw["bodies"] = (Bodies.from_toml(src, design=design) if src is not None
                            else Bodies.default(design))
        if args.view:
            kw["view"] = tuple(args.view)
        if not args.all:                  # plot_robot: the drawing options in one object
            kw["options"] = PlotOptions(show_frames=kw.pop("show_frames"),
                                        show_labels=not args.no_labels,
                                        **({"view": kw.pop("view")} if "view" in kw else {}))
        kw["dpi"] = args.dpi
    else:
        kw["all_slots"] = True
    save_view(out, q, T, design, slot=args.slot, all_solutions=args.all, **kw)
