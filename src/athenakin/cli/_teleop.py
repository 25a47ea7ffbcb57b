"""``athenakin teleop``: replay a recorded master through the teleoperation chain and the arm."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from ..teleop._filter import TREMOR_FILTERS
from ._collision import add_session_collision_options, session_collision
from ._common import add_robot_options, check_finite, fmt, load_robot
from ._output import add_force_option, outputs

#: Largest master coordinate (m) before the command hints at millimetres: a handle's
#: workspace is well under a metre.
MM_HINT_M = 2.0


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``teleop`` subcommand."""
    p = sub.add_parser(
        "teleop", help="replay a recorded master (MCAP / rosbag2) through teleop and the "
                       "simulated arm",
        description="Read a recorded master handle (geometry_msgs/PoseStamped, m, and a "
                    "sensor_msgs/Joy clutch pedal: a held button decouples the master), run "
                    "it at the cycle rate through athenakin.teleop.Teleop (scale, tremor "
                    "filter, exact IK, safety layer, feed-forward) and the MuJoCo arm under "
                    "its PD + feed-forward servo, print the safety layer's flags and the "
                    "tracking error, and with -o write the CRTK topics (measured_js, "
                    "setpoint_js, measured_cp, servo_cp, status) to an MCAP file for "
                    "Foxglove, stamped on the recording's time base. The robot's bodies "
                    "are kept apart by default (--no-bodies turns that off); "
                    "--environment adds obstacles (virtual fixtures for the tip). "
                    "Extras 'ros' and 'sim'. docs/teleop.md.")
    p.add_argument("--master", dest="path", type=Path, required=True, metavar="REC",
                   help="recorded master: an MCAP file or a rosbag2 folder")
    p.add_argument("-o", "--output", type=Path, metavar="OUT.mcap",
                   help="write the session's CRTK topics (.mcap)")
    p.add_argument("--pose-topic", default="/master/pose",
                   help="PoseStamped topic of the handle (/master/pose)")
    p.add_argument("--clutch-topic", default="/master/joy",
                   help="Joy topic of the clutch pedal (/master/joy); 'none': always engaged")
    p.add_argument("--clutch-button", type=int, default=0, help="Joy button of the clutch (0)")
    p.add_argument("--scale", type=float, default=0.2, help="motion scale (0.2)")
    p.add_argument("--rate", type=float, default=1000.0, help="cycle rate, Hz (1000)")
    p.add_argument("--filter", default="notch8-12", choices=tuple(TREMOR_FILTERS),
                   help="tremor filter (default notch8-12; notch8-12-lp15 adds a roll-off "
                        "above 15 Hz; none)")
    p.add_argument("--q0", nargs=3, type=float, metavar=("Q1", "Q2", "Q3"),
                   default=[-0.1, 0.1, 0.45], help="where the robot stands, m (-0.1 0.1 0.45)")
    p.add_argument("--no-arm", action="store_true",
                   help="commands only, no MuJoCo arm (the measured topics echo the commands)")
    p.add_argument("--registration", nargs=9, type=float, metavar="R",
                   help="rotation R_e_m from the master's frame to the RCM frame E, nine "
                        "numbers row by row (default identity)")
    p.add_argument("--max-gap", type=float, default=None, metavar="S",
                   help="longest gap between two poses of the recording, s (default 10); a "
                        "longer one is an error")
    add_session_collision_options(p)
    add_force_option(p)
    add_robot_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Execute ``teleop``."""
    from ..teleop import (
        MAX_GAP_S,
        SimulatedArm,
        Teleop,
        TeleopOptions,
        read_master,
        run_session,
        write_session_mcap,
    )

    out = args.output
    if out is not None and Path(out).suffix.lower() != ".mcap":
        raise ValueError(f"-o: expected an .mcap file name, got {str(out)!r}")
    check_finite(args.scale, "--scale", positive=True)
    check_finite(args.rate, "--rate", positive=True)
    check_finite(args.q0, "--q0")
    if args.registration is not None:
        check_finite(args.registration, "--registration")
    max_gap = MAX_GAP_S if args.max_gap is None else args.max_gap
    check_finite(max_gap, "--max-gap", positive=True)
    if args.clutch_button < 0:
        raise ValueError(f"--clutch-button: expected a button index >= 0, got "
                         f"{args.clutch_button}")
    clutch_topic = None if args.clutch_topic.lower() == "none" else args.clutch_topic
    with outputs(args) as outs:
        if out is not None:
            outs.add(out)
        design, T = load_robot(args)
        col = session_collision(args, design)
        opts: dict = {"filter": args.filter, **col["options"]}
        if args.registration is not None:
            opts["registration"] = np.array(args.registration, dtype=float).reshape(3, 3)
        q0 = np.array(args.q0, dtype=float)
        tele = Teleop(T, design, q0=q0, scale=args.scale, rate=args.rate, bodies=col["bodies"],
                      environment=col["environment"], options=TeleopOptions(**opts))
        arm = None if args.no_arm else SimulatedArm(T, design, q0=q0, rate=args.rate)
        if arm is not None:
            arm.enable()
        master = read_master(args.path, rate=args.rate, pose_topic=args.pose_topic,
                             clutch_topic=clutch_topic, clutch_button=args.clutch_button,
                             max_gap=max_gap)
        log = run_session(tele, arm, master, check_bodies=not args.no_bodies)
        err = log.tip_error
        print(f"teleop: {len(log)} cycles at {fmt(args.rate)} Hz ({fmt(len(log) / args.rate)} s), "
              f"scale {fmt(args.scale)}, filter {args.filter}")
        for name, c in log.counts().items():
            print(f"  {name}: {c} cycles")
        cl = log.clearance[np.isfinite(log.clearance)]
        print(f"bodies: least clearance {fmt(float(cl.min()) * 1e3)} mm" if cl.size else
              "bodies: not checked (--no-bodies)")
        if arm is not None:
            print(f"tip tracking error (MuJoCo - command): {fmt(np.sqrt(np.mean(err ** 2)) * 1e3)}"
                  f" mm RMS, {fmt(err.max() * 1e3)} mm max; loop closure "
                  f"{fmt(float(np.nanmax(log.closure_error)))} m max; arm "
                  f"{arm.operating_state}" + (f" ({arm.fault})" if arm.fault else ""))
        hint = _mm_hint(log.master)
        if hint:
            print(hint, file=sys.stderr)
        if out is not None:
            counts = write_session_mcap(log, out, target=outs.temp(out))
            outs.commit()
            print(f"wrote {out} ({', '.join(f'{k}: {v}' for k, v in counts.items() if v)} "
                  f"messages)")
    return 0


def _mm_hint(master: np.ndarray) -> str:
    """A hint on stderr when the master's positions look like millimetres, else ""."""
    a = np.abs(master[np.isfinite(master)])
    if a.size and float(a.max()) > MM_HINT_M:
        return (f"hint: the master's positions reach {float(a.max()):.6g} m, beyond a "
                f"handle's reach: positions are in metres (a recording in millimetres?)")
    return ""
