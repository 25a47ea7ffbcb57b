"""``athenakin plan``: a tool-tip (or direction + insertion) path CSV -> checked trajectory."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ._collision import add_collision_options, collision_options
from ._common import add_robot_options, force_limits, load_robot
from ._output import add_force_option, outputs

if TYPE_CHECKING:
    from ..design import Design


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``plan`` subcommand."""
    p = sub.add_parser(
        "plan", help="plan a limit-respecting actuator trajectory from a tool-tip path CSV",
        description="Read waypoints about the RCM (columns x_m,y_m,z_m: tool tip in frame E; or "
                    "azimuth_deg,polar_deg,depth_m; optional t_s), plan a checked actuator "
                    "trajectory sampled at --rate, write it as CSV, JSON or MCAP (ROS 2 "
                    "topics for Foxglove, extra 'ros'; by the extension of -o) and, unless "
                    "--no-plots, three PNG figures next to it. Columns and units: "
                    "docs/motion.md; topics: docs/ros.md.")
    p.add_argument("path", type=Path, metavar="PATH.csv", help="waypoint file")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="OUT",
                   help="trajectory file, .csv, .json or .mcap (trajectory_msgs/JointTrajectory "
                        "and the robot's topics, docs/ros.md)")
    p.add_argument("--rate", type=float, default=None,
                   help="samples per second, at least 1 (1000, or that of --options)")
    p.add_argument("--v-max", type=float, default=None,
                   help="actuator speed limit, m/s (0.05, or that of --options)")
    p.add_argument("--a-max", type=float, default=None,
                   help="actuator acceleration limit, m/s^2 (0.5, or that of --options)")
    p.add_argument("--j-max", type=float, default=None,
                   help="actuator jerk limit, m/s^3 (default: none)")
    p.add_argument("--tip-speed", type=float, default=None, help="tool-tip speed limit, m/s")
    p.add_argument("--masses", type=Path, default=None, metavar="FILE",
                   help="TOML file with a [masses] table (e.g. the design file): the "
                        "trajectory carries the actuator forces (f1_N, f2_N, f3_N)")
    p.add_argument("--f-max", type=float, nargs="+", default=None, metavar="N",
                   help="actuator force limit(s), N (one, or one per actuator; needs "
                        "--masses): the motion is slowed down until the forces hold")
    p.add_argument("--max-duration", type=float, default=None, metavar="S",
                   help="refuse a trajectory longer than this, s (default: "
                        "athenakin.motion.MAX_DURATION, 3600)")
    p.add_argument("--max-samples", type=int, default=None, metavar="N",
                   help="refuse a trajectory of more samples than this (default: "
                        "athenakin.motion.MAX_SAMPLES, 2000000)")
    p.add_argument("--timing", choices=("stretch", "fixed"), default=None,
                   help="with t_s in the file: lengthen segments that break a limit (stretch, "
                        "default) or fail (fixed)")
    p.add_argument("--margin", action="append", default=[], metavar="NAME=VALUE",
                   help="singularity margin, e.g. --margin sin_u4=0.2 (names: half_chord, h, "
                        "link, p, depth in m; sin_u2, sin_u4; cond, an upper bound)")
    p.add_argument("--options", type=Path, default=None, metavar="FILE.toml",
                   help="planner settings: the [plan] table of a TOML file "
                        "(athenakin.motion.PlanOptions: rate, v_max, a_max, j_max, tip_speed, "
                        "timing, max_duration, max_samples, clearance_margin, f_max and a "
                        "[plan.margins] table); the options given here override it")
    add_collision_options(p, what="a trajectory with a sample closer than this is refused")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--plots", type=Path, metavar="PREFIX",
                   help="figure prefix (default: OUT without its extension)")
    g.add_argument("--no-plots", action="store_true", help="write no figures")
    add_force_option(p)
    add_robot_options(p)
    p.set_defaults(func=run)


def parse_margins(items: list[str], base: object = None) -> object:
    """``NAME=VALUE`` strings -> :class:`athenakin.motion.Margins` (those of ``base`` else)."""
    import dataclasses

    from ..motion import Margins

    kw = {}
    names = {f for f in Margins.__dataclass_fields__}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or name.strip() not in names:
            raise ValueError(f"--margin: expected NAME=VALUE with NAME in {sorted(names)}, "
                             f"got {item!r}")
        try:
            kw[name.strip()] = float(value)
        except ValueError:
            raise ValueError(f"--margin {name}: expected a number, got {value!r}") from None
    return Margins(**kw) if base is None else dataclasses.replace(base, **kw)  # type: ignore[type-var]


#: Plausible ranges of the actuator limits (beyond them the time law has no meaning).
LIMIT_RANGES = {"--v-max": (1e-6, 1e3), "--a-max": (1e-6, 1e4), "--j-max": (1e-6, 1e7),
                "--tip-speed": (1e-6, 1e3)}


def check_limits(args: argparse.Namespace) -> None:
    """Each actuator limit finite and within :data:`LIMIT_RANGES` (before any work)."""
    for opt, (lo, hi) in LIMIT_RANGES.items():
        v = getattr(args, opt[2:].replace("-", "_"))
        if v is not None and not lo <= v <= hi:
            raise ValueError(f"{opt}: expected a limit from {lo:g} to {hi:g} (SI units), "
                             f"got {v:g}")


def run(args: argparse.Namespace) -> int:
    """Execute ``plan``."""
    from ..motion import read_path_csv
    from ..motion._plan import MAX_WAYPOINTS

    check_limits(args)

    out = Path(args.output)
    if out.suffix.lower() not in (".csv", ".json", ".mcap"):
        raise ValueError(f"-o: expected a .csv or .json file name, or .mcap (ROS 2 topics), got "
                         f"{str(out)!r}")
    with outputs(args) as outs:
        # every output is checked before any work, written only when all is done
        outs.add(out)
        figures: dict[str, Path] = {}
        if not args.no_plots:
            from ..motion._plot import plot_paths

            prefix = args.plots if args.plots is not None else out.with_suffix("")
            figures = {k: outs.add(path, option="--plots")
                       for k, path in plot_paths(prefix).items()}
        design, T = load_robot(args)
        spec = read_path_csv(args.path)
        n = len(spec.tips_e if spec.tips_e is not None else spec.azimuth)  # type: ignore[arg-type]
        if n > MAX_WAYPOINTS:
            raise ValueError(f"{args.path}: {n} waypoints; expected at most {MAX_WAYPOINTS} "
                             f"(plan the path in parts)")
        traj = _plan(spec, T, design, args)
        from ..motion._io import trajectory_csv_text, trajectory_json_text

        if out.suffix.lower() == ".mcap":
            from ..ros import write_trajectory

            write_trajectory(out, traj, target=outs.temp(out))
        else:
            outs.write(out, trajectory_json_text(traj) if out.suffix.lower() == ".json"
                       else trajectory_csv_text(traj))
        if figures:
            from ..motion._plot import render_plots

            pngs = render_plots(traj)
            for k, path in figures.items():
                outs.write(path, pngs[k])
        written = outs.commit()
    _summary(traj, written)
    return 0


def _plan(spec: Any, T: np.ndarray, design: Design, args: argparse.Namespace) -> Any:
    """The trajectory of the path file ``spec`` with the options of the file and the flags."""
    from ..motion import plan, plan_directions

    models = collision_options(args, design)
    margin = models.pop("clearance_margin", None)
    masses, f_max = _force_options(args)
    opts = _plan_options(args, clearance_margin=margin, f_max=f_max)
    if opts.timing == "fixed" and spec.times is None:
        raise ValueError(f"--timing fixed: {args.path} has no t_s column")
    if spec.kind == "tip":
        return plan(spec.tips_e, T, design, times=spec.times, masses=masses, options=opts,
                    **models)
    return plan_directions(spec.azimuth, spec.polar, spec.depth, T, design, times=spec.times,
                           masses=masses, options=opts, **models)


def _plan_options(args: argparse.Namespace, **given: object) -> Any:
    """The :class:`~athenakin.motion.PlanOptions` of ``--options FILE``, the flags given on top."""
    import dataclasses

    from ..motion import PlanOptions

    base = PlanOptions() if args.options is None else PlanOptions.from_toml(args.options)
    flags = {"rate": args.rate, "v_max": args.v_max, "a_max": args.a_max, "j_max": args.j_max,
             "tip_speed": args.tip_speed, "timing": args.timing,
             "max_duration": args.max_duration, "max_samples": args.max_samples, **given}
    kw = {k: v for k, v in flags.items() if v is not None}
    if args.margin:
        kw["margins"] = parse_margins(args.margin, base.margins)
    return dataclasses.replace(base, **kw)


def _force_options(args: argparse.Namespace) -> tuple[object, object]:
    """``masses``, ``f_max`` from ``--masses FILE`` and ``--f-max``."""
    if args.masses is None:
        if args.f_max is not None:
            raise ValueError("--f-max: force limits need a mass model (--masses FILE)")
        return None, None
    from ..dynamics import MassModel

    f_max = force_limits(args)
    return MassModel.from_toml(args.masses), f_max


def _summary(traj: object, written: list[Path]) -> None:
    t = traj  # Trajectory
    lim = t.limits  # type: ignore[attr-defined]
    print(f"planned {len(t.t)} samples at {t.rate:g} Hz, duration {t.duration:.3f} s, "  # type: ignore[attr-defined]
          f"{len(t.waypoints_e)} waypoints")  # type: ignore[attr-defined]
    print("waypoint times [s]: " + ", ".join(f"{v:.3f}" for v in t.waypoint_times))  # type: ignore[attr-defined]
    if np.any(t.stretched):  # type: ignore[attr-defined]
        print(f"stretched segments (requested times too short for the limits): "
              f"{np.flatnonzero(t.stretched).tolist()}")  # type: ignore[attr-defined]
    rows = [("|qd| max [m/s]", np.abs(t.qd).max(0), lim.v_max),  # type: ignore[attr-defined]
            ("|qdd| max [m/s^2]", np.abs(t.qdd).max(0), lim.a_max)]  # type: ignore[attr-defined]
    if t.qddd is not None:  # type: ignore[attr-defined]
        rows.append(("|qddd| max [m/s^3]", np.abs(t.qddd).max(0), lim.j_max))  # type: ignore[attr-defined]
    for name, v, bound in rows:
        print(f"{name:>20}: " + "  ".join(f"q{i + 1} {v[i]:.4f}/{bound[i]:g}" for i in range(3)))
    forces = getattr(t, "forces", None)
    if forces is not None:
        print(f"{'|f| max [N]':>20}: " + "  ".join(
            f"q{i + 1} {np.abs(forces[:, i]).max():.3f}" for i in range(3)))
    ratios = t.measures.ratio(t.margins)  # type: ignore[attr-defined]
    worst = min(ratios, key=lambda k: float(np.min(ratios[k])))
    print(f"closest to a singularity: {worst} at {float(np.min(ratios[worst])):.2f} x its margin")
    if t.clearance is not None and np.any(np.isfinite(t.clearance)):  # type: ignore[attr-defined]
        i = int(np.nanargmin(t.clearance))  # type: ignore[attr-defined]
        a, b = t.closest_pair[i]  # type: ignore[attr-defined]
        print(f"least clearance: {float(t.clearance[i]):.6g} m between {a} and {b} at "  # type: ignore[attr-defined]
              f"t = {float(t.t[i]):.4f} s (margin {t.clearance_margin:g} m)")  # type: ignore[attr-defined]
    print("wrote " + ", ".join(str(w) for w in written))
