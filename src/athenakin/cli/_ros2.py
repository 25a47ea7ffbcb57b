"""``athenakin ros2``: the arm node, the teleop node, the recorder, the CRTK messages' build."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from typing import Any

from ..teleop._filter import TREMOR_FILTERS
from ._collision import add_session_collision_options, session_collision
from ._common import add_robot_options, check_finite, load_robot
from ._output import add_force_option, outputs


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``ros2`` and its own subcommands ``arm``, ``teleop``, ``record``, ``build-msgs``."""
    p = sub.add_parser(
        "ros2", help="ATHENA live on a ROS 2 graph: the CRTK arm node, the teleop node",
        description="Run ATHENA's nodes on a ROS 2 graph with the real rclpy and Fast DDS "
                    "(extra 'ros2', no ROS installation). Keep discovery on this machine with "
                    "ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST. docs/ros2.md.")
    own = p.add_subparsers(dest="ros2_command", metavar="NODE")
    own.required = True
    a = _node_parser(own, "arm", help="serve the simulated arm under CRTK names",
                     description="The MuJoCo arm under CRTK's topics in a namespace: "
                                 "measured_js, setpoint_js, measured_cp, setpoint_cp, "
                                 "measured_cv, operating_state, status; commands servo_jp, "
                                 "servo_cp, move_jp, move_cp, state_command, hold; "
                                 "/joint_states and /robot_description.",
                     namespace_help="CRTK namespace (/athena)",
                     rate_help="servo rate, Hz (1000)")
    a.add_argument("--publish-rate", type=float, default=100.0,
                   help="state messages per second, Hz (100)")
    a.add_argument("--q0", nargs=3, type=float, metavar=("Q1", "Q2", "Q3"),
                   default=[-0.1, 0.1, 0.45], help="where the robot stands, m (-0.1 0.1 0.45)")
    a.add_argument("--sync", choices=("clock", "command"), default="clock",
                   help="start a servo cycle on the node's clock (default), or also on each "
                        "servo command's arrival: no wait for the next cycle")
    a.add_argument("--enable", action="store_true", help="enable the arm at start")
    _add_run_options(a, run_arm)
    t = _node_parser(own, "teleop", help="drive the arm node from a master's topics",
                     description="A master's geometry_msgs/PoseStamped (m) and "
                                 "sensor_msgs/Joy clutch (a held button decouples) through "
                                 "athenakin.teleop.Teleop to the arm node's servo_jp, with "
                                 "the status on <namespace>/teleop/status and an e-stop "
                                 "on <namespace>/teleop/estop.",
                     namespace_help="the arm node's namespace (/athena)",
                     rate_help="teleop rate, Hz (1000)")
    t.add_argument("--preset", choices=("default", "dvrk-mtmr"), default="default",
                   help="master topics: default /master/pose + /master/joy; dvrk-mtmr "
                        "/MTMR/measured_cp + /footpedals/clutch")
    t.add_argument("--pose-topic", help="the master's PoseStamped topic (overrides --preset)")
    t.add_argument("--clutch-topic",
                   help="the clutch's Joy topic (overrides --preset); 'none': always engaged")
    t.add_argument("--clutch-button", type=int, default=0, help="Joy button of the clutch (0)")
    t.add_argument("--master-frame", help="frame_id the master's poses must carry")
    t.add_argument("--scale", type=float, default=0.2, help="motion scale (0.2)")
    t.add_argument("--watchdog", type=float, help="watchdog, s (TeleopOptions' 0.03)")
    t.add_argument("--status-every", type=int, default=10,
                   help="publish the status every N cycles and on every change (10)")
    t.add_argument("--q0", nargs=3, type=float, metavar=("Q1", "Q2", "Q3"),
                   help="where the robot stands, m (default: the arm's first measured_js)")
    t.add_argument("--filter", default="notch8-12", choices=tuple(TREMOR_FILTERS),
                   help="tremor filter (notch8-12)")
    t.add_argument("--clock", choices=("ros", "master"), default="ros",
                   help="ros: cycles at --rate on the ROS clock (the watchdog counts silent "
                        "cycles); master: one cycle per master message at its stamp (replays)")
    t.add_argument("--wait-for-arm", type=float, default=30.0,
                   help="without --q0: wait this long for the arm's first measured_js, s "
                        "(30; never longer than --duration)")
    t.add_argument("--with-arm", action="store_true",
                   help="run an arm node (enabled) in this process too")
    add_session_collision_options(t)
    _add_run_options(t, run_teleop)
    _record_parser(own)
    b = own.add_parser("build-msgs", help="build CRTK's crtk_msgs with the rosidl wheels",
                       description="Build and install crtk_msgs (OperatingState, "
                                   "StringStamped) into this Python's prefix: needs the extra "
                                   "'ros2-msgs', CMake and a C compiler (about 30 s). "
                                   "Nothing to do where the installed one was built from "
                                   "the same sources and generators (--force rebuilds).")
    b.add_argument("--prefix", help="install prefix (default: this Python's)")
    b.add_argument("--force", action="store_true",
                   help="build even where the installed crtk_msgs is up to date")
    b.add_argument("--verbose", action="store_true", help="show CMake's output")
    b.set_defaults(func=run_build)


def _record_parser(own: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """``ros2 record``: the session's topics from the graph into an MCAP file."""
    r = own.add_parser("record", help="record a session's topics from the graph into an MCAP",
                       description="Record what the nodes publish (the arm's measured_js, "
                                   "setpoint_js, measured_cp, setpoint_cp, operating_state, "
                                   "status; servo_jp; the teleop status; the master's pose "
                                   "and clutch) as it travelled into an MCAP file that "
                                   "rosbags, the mcap library and Foxglove read; log times "
                                   "are the header stamps. Stops at --duration or Ctrl-C, "
                                   "and the file is complete either way.")
    r.add_argument("-o", "--output", required=True, metavar="OUT.mcap",
                   help="the MCAP file to write")
    r.add_argument("--namespace", default="/athena", help="the arm node's namespace (/athena)")
    r.add_argument("--preset", choices=("default", "dvrk-mtmr"), default="default",
                   help="master topics, as ros2 teleop's (default /master/pose + /master/joy)")
    r.add_argument("--pose-topic", help="the master's PoseStamped topic (overrides --preset)")
    r.add_argument("--clutch-topic",
                   help="the clutch's Joy topic (overrides --preset); 'none': not recorded")
    r.add_argument("--topic", action="append", default=[], metavar="NAME=TYPE",
                   help="record this topic too, e.g. measured_cv=geometry_msgs/msg/TwistStamped "
                        "(repeatable; a relative name is under --namespace)")
    r.add_argument("--compression", choices=("zstd", "lz4", "none"), default="zstd",
                   help="chunk compression (zstd)")
    r.add_argument("--use-sim-time", action="store_true", help="the node's clock from /clock")
    r.add_argument("--duration", type=float, help="stop after this many seconds")
    add_force_option(r)
    r.set_defaults(func=run_record)


def _node_parser(own: argparse._SubParsersAction, name: str, *, help: str,  # type: ignore[type-arg]
                 description: str, namespace_help: str,
                 rate_help: str) -> argparse.ArgumentParser:
    """A node's subcommand with the options every node takes first: --namespace, --rate."""
    p = own.add_parser(name, help=help, description=description)
    p.add_argument("--namespace", default="/athena", help=namespace_help)
    p.add_argument("--rate", type=float, default=1000.0, help=rate_help)
    return p


def _add_run_options(p: argparse.ArgumentParser, run: Callable[[argparse.Namespace], int]
                     ) -> None:
    """The options every node takes last (--use-sim-time, --duration, the robot's), its run."""
    p.add_argument("--use-sim-time", action="store_true", help="stamp from /clock")
    p.add_argument("--duration", type=float, help="stop after this many seconds")
    add_robot_options(p)
    p.set_defaults(func=run)


def _spin_and_close(node: Any, duration: float | None, summary: Callable[[], str]) -> None:
    """Spin ``node`` for ``duration`` s (None: until Ctrl-C), close it, print ``summary()``."""
    try:
        node.spin(duration)
    except KeyboardInterrupt:     # Ctrl-C: the node's normal end
        pass
    finally:
        node.close()
        print(summary(), flush=True)


def _duration(args: argparse.Namespace) -> float | None:
    if args.duration is not None:
        check_finite(args.duration, "--duration", positive=True)
    return args.duration


def run_arm(args: argparse.Namespace) -> int:
    """Execute ``ros2 arm``."""
    from ..ros2 import ArmNode

    check_finite(args.q0, "--q0")
    duration = _duration(args)
    design, T = load_robot(args)
    node = ArmNode(T_b_e=T, design=design, q0=args.q0, rate=args.rate,
                   namespace=args.namespace, publish_rate=args.publish_rate,
                   sync=args.sync, enable=args.enable, use_sim_time=args.use_sim_time)
    kind = "crtk_msgs" if node.crtk.native else "std_msgs stand-ins"
    print(f"ros2 arm: {node.namespace} at {args.rate:g} Hz (--sync {node.sync}), state at "
          f"{node.publish_rate:g} Hz, {node.arm.operating_state}, CRTK types: {kind}",
          flush=True)
    _spin_and_close(node, duration, lambda: f"ros2 arm: {node.cycles} cycles, "
                    f"{node.late_cycles} late, {node.synced_cycles} on a command, {node.commands} "
                    f"commands, {node.refused} refused")
    return 0


def run_teleop(args: argparse.Namespace) -> int:
    """Execute ``ros2 teleop``."""
    from ..ros2 import MASTER_PRESETS, TeleopNode
    from ..teleop import TeleopOptions

    duration = _duration(args)
    preset = MASTER_PRESETS[args.preset]
    pose = preset["pose"] if args.pose_topic is None else args.pose_topic
    clutch = preset["clutch"] if args.clutch_topic is None else args.clutch_topic
    if args.q0 is not None:
        check_finite(args.q0, "--q0")
    check_finite(args.wait_for_arm, "--wait-for-arm", positive=True)
    wait = args.wait_for_arm if duration is None else min(args.wait_for_arm, duration)
    design, T = load_robot(args)
    col = session_collision(args, design)
    options = TeleopOptions(filter=args.filter, **col["options"],
                            **({} if args.watchdog is None else {"watchdog": args.watchdog}))
    context = arm = None
    if args.with_arm:
        from ..ros2 import ArmNode, RosContext

        context = RosContext()
        arm = ArmNode(T_b_e=T, design=design, q0=args.q0, namespace=args.namespace,
                      enable=True, use_sim_time=args.use_sim_time, context=context).start()
    try:
        node = TeleopNode(T, design, q0=args.q0, rate=args.rate, scale=args.scale,
                          options=options, bodies=col["bodies"],
                          environment=col["environment"], check_bodies=not args.no_bodies,
                          arm_namespace=args.namespace, pose_topic=pose,
                          clutch_topic=None if clutch.lower() == "none" else clutch,
                          clutch_button=args.clutch_button, master_frame=args.master_frame,
                          status_every=args.status_every, use_sim_time=args.use_sim_time,
                          clock=args.clock, wait_for_arm=wait, context=context)
        print(f"ros2 teleop: {pose} + {clutch} -> {node.namespace}/servo_jp at "
              f"{args.rate:g} Hz, bodies "
              + ("checked" if node.teleop.checks_clearance else "not checked (--no-bodies)")
              + (" (arm node in this process)" if arm else ""), flush=True)
        _spin_and_close(node, duration, lambda: f"ros2 teleop: {node.cycles} cycles, "
                        f"{node.late_cycles} late")
    finally:
        if arm is not None:
            arm.close()
        if context is not None:
            context.close()
    return 0


def _record_topics(args: argparse.Namespace) -> dict[str, str]:
    """The topics of ``ros2 record``: the session's, the master's, and each ``--topic``."""
    from ..ros2 import MASTER_PRESETS, session_topics

    preset = MASTER_PRESETS[args.preset]
    clutch = preset["clutch"] if args.clutch_topic is None else args.clutch_topic
    topics = session_topics(args.namespace,
                            pose_topic=preset["pose"] if args.pose_topic is None
                            else args.pose_topic,
                            clutch_topic=None if clutch.lower() == "none" else clutch)
    for item in args.topic:
        name, sep, typ = item.partition("=")
        if not sep or not name or not typ:
            raise ValueError(f"--topic: expected NAME=pkg/msg/Type (e.g. "
                             f"measured_cv=geometry_msgs/msg/TwistStamped), got {item!r}")
        topics[name] = typ
    return topics


def _record_until(node: Any, duration: float | None) -> None:
    """Record for ``duration`` s (None: until Ctrl-C); say when each topic's first message came."""
    import time

    end = None if duration is None else time.monotonic() + duration
    node.start()
    seen: set[str] = set()
    while node.recording:
        left = None if end is None else end - time.monotonic()
        if left is not None and left <= 0:
            return
        node.spin(0.25 if left is None else min(0.25, left))
        for topic, n in node.counts.items():
            if n and topic not in seen:
                seen.add(topic)
                print(f"ros2 record: recording {topic}", flush=True)


def run_record(args: argparse.Namespace) -> int:
    """Execute ``ros2 record``."""
    from pathlib import Path

    from ..ros2 import RecorderNode

    out = Path(args.output)
    if out.suffix.lower() != ".mcap":
        raise ValueError(f"-o: expected an .mcap file name, got {str(out)!r}")
    duration = _duration(args)
    topics = _record_topics(args)
    with outputs(args) as outs:
        outs.add(out)
        node = RecorderNode(out, topics=topics, namespace=args.namespace,
                            compression=args.compression, use_sim_time=args.use_sim_time,
                            target=outs.temp(out))
        print(f"ros2 record: {len(node.topics)} topics -> {out}"
              + ("" if duration else " (Ctrl-C to stop)"), flush=True)
        try:
            _record_until(node, duration)
        except KeyboardInterrupt:     # Ctrl-C: the recording's normal end, the file complete
            pass
        except BaseException:
            node.discard()
            raise
        node.close()
        outs.commit()
    counts = node.counts
    print(f"ros2 record: wrote {out}: {sum(counts.values())} messages ("
          + ", ".join(f"{k}: {v}" for k, v in counts.items()) + ")", flush=True)
    return 0


def run_build(args: argparse.Namespace) -> int:
    """Execute ``ros2 build-msgs``."""
    from ..ros2 import build_crtk_msgs, crtk_msgs_current

    if not args.force and crtk_msgs_current(args.prefix):
        print("ros2 build-msgs: the installed crtk_msgs is up to date (built from these "
              "sources and generators; --force rebuilds)")
        return 0
    try:
        path = build_crtk_msgs(prefix=args.prefix, verbose=args.verbose)
    except RuntimeError as exc:     # CMake or the compiler failed: the build's, not a bug
        print(f"athenakin ros2 build-msgs: error: {exc}", file=sys.stderr)
        return 1
    print(f"ros2 build-msgs: installed crtk_msgs in {path}")
    return 0
