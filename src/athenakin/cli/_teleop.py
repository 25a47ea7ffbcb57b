"""``athenakin teleop``: replay a recorded master through the teleoperation chain and the arm."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ..teleop._filter import TREMOR_FILTERS
from ._common import add_robot_options, check_finite, fmt, load_robot
from ._output import add_force_option, outputs


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
                    "Foxglove. Extras 'ros' and 'sim'. docs/teleop.md.")
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
    add_force_option(p)
    add_robot_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Execute ``teleop``."""
    from ..teleop import (
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
    if args.clutch_button < 0:
        raise ValueError(f"--clutch-button: expected a button index >= 0, got "
                         f"{args.clutch_button}")
    clutch_topic = None if args.clutch_topic.lower() == "none" else args.clutch_topic
    with outputs(args) as outs:
        if out is not None:
            outs.add(out)
        design, T = load_robot(args)
        q0 = np.array(args.q0, dtype=float)
        tele = Teleop(T, design, q0=q0, scale=args.scale, rate=args.rate,
                      options=TeleopOptions(filter=args.filter))
        arm = None if args.no_arm else SimulatedArm(T, design, q0=q0, rate=args.rate)
        master = read_master(args.path, rate=args.rate, pose_topic=args.pose_topic,
                             clutch_topic=clutch_topic, clutch_button=args.clutch_button)
        log = run_session(tele, arm, master)
        err = log.tip_error
        print(f"teleop: {len(log)} cycles at {fmt(args.rate)} Hz ({fmt(len(log) / args.rate)} s), "
              f"scale {fmt(args.scale)}, filter {args.filter}")
        for name, c in log.counts().items():
            print(f"  {name}: {c} cycles")
        if arm is not None:
            print(f"tip tracking error (MuJoCo - command): {fmt(np.sqrt(np.mean(err ** 2)) * 1e3)}"
                  f" mm RMS, {fmt(err.max() * 1e3)} mm max; loop closure "
                  f"{fmt(float(np.nanmax(log.closure_error)))} m max")
        if out is not None:
            counts = write_session_mcap(log, out, target=outs.temp(out))
            outs.commit()
            print(f"wrote {out} ({', '.join(f'{k}: {v}' for k, v in counts.items() if v)} "
                  f"messages)")
    return 0
