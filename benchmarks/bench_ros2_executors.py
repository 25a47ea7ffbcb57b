"""rclpy's executors on one subscriber: CPU per message, events beside single-threaded.

Run from the repository root (the extra ``ros2``; discovery stays on the loopback)::

    python benchmarks/bench_ros2_executors.py [--rate 1000] [--seconds 5]

A publisher in its own process sends ``sensor_msgs/JointState`` (three joints, reliable,
depth 1000) at ``--rate``; this process subscribes with a plain callback (a counter) on
rclpy's ``SingleThreadedExecutor`` (the baseline), then on ``rclpy.experimental.EventsExecutor``
(what the arm and teleop nodes spin: ``athenakin.ros2._runtime.control_executor``), each in
an executor thread spinning ``spin_once``, as the nodes do. For each: the messages taken in
``--seconds``, this process's CPU time (user + system, every thread: the executor's Python
and the middleware's) per message and as a share of one core, and the ratio to the
baseline. The machine's load is printed beside every figure. ``ROS_DOMAIN_ID`` where set,
else one of this run's (from the pid).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import threading
import time

from _machine import load_text

WARM_UP = 100        # messages taken before the window opens (the reader matched, caches warm)


def _context(domain: int):  # type: ignore[no-untyped-def]
    import rclpy
    from rclpy.context import Context

    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    ctx = Context()
    rclpy.init(context=ctx, domain_id=domain)
    return rclpy.create_node(f"bench_executors_{os.getpid()}", context=ctx), ctx


def _qos():  # type: ignore[no-untyped-def]
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    return QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)


def publish(domain: int, rate: float, seconds: float) -> None:
    """The publisher process: JointState at ``rate`` for ``seconds`` once a reader matched."""
    from sensor_msgs.msg import JointState

    node, ctx = _context(domain)
    pub = node.create_publisher(JointState, "/bench_executors", _qos())
    end = time.monotonic() + 120.0
    while pub.get_subscription_count() == 0 and time.monotonic() < end:
        time.sleep(0.01)
    period, t_next = 1.0 / rate, time.perf_counter()
    for k in range(int(seconds * rate)):
        pub.publish(JointState(name=["q1", "q2", "q3"], position=[0.1, 0.2, float(k)]))
        t_next += period
        wait = t_next - time.perf_counter()
        if wait > 0:
            time.sleep(wait)
    node.destroy_node()
    ctx.try_shutdown()


def subscribe(domain: int, kind: str, rate: float, seconds: float) -> tuple[int, float, float]:
    """Messages taken, CPU s and wall s over the window, with executor ``kind``."""
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.experimental import EventsExecutor
    from sensor_msgs.msg import JointState

    node, ctx = _context(domain)
    count = [0]

    def on_msg(_: JointState) -> None:
        count[0] += 1

    node.create_subscription(JointState, "/bench_executors", on_msg, _qos())
    ex = (SingleThreadedExecutor if kind == "single" else EventsExecutor)(context=ctx)
    ex.add_node(node)
    stop = threading.Event()

    def spin() -> None:
        while not stop.is_set():
            ex.spin_once(timeout_sec=0.05)

    pub = subprocess.Popen([sys.executable, __file__, "--publisher", "--domain", str(domain),
                            "--rate", str(rate), "--seconds", str(seconds + 2.0)])
    th = threading.Thread(target=spin, daemon=True)
    th.start()
    end = time.monotonic() + 120.0
    while count[0] < WARM_UP and time.monotonic() < end and pub.poll() is None:
        time.sleep(0.01)
    if count[0] < WARM_UP:
        stop.set()
        pub.kill()
        raise RuntimeError(f"{kind}: {count[0]} messages within 120 s (no publisher matched)")
    n0, c0, w0 = count[0], time.process_time(), time.perf_counter()
    time.sleep(seconds)
    n, cpu, wall = count[0] - n0, time.process_time() - c0, time.perf_counter() - w0
    stop.set()
    th.join(timeout=5.0)
    pub.wait(timeout=60.0)
    ex.shutdown()
    node.destroy_node()
    ctx.try_shutdown()
    return n, cpu, wall


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rate", type=float, default=1000.0, help="messages per second")
    ap.add_argument("--seconds", type=float, default=5.0, help="the window of each, s")
    ap.add_argument("--publisher", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--domain", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args()
    domain = args.domain or int(os.environ.get("ROS_DOMAIN_ID") or 1 + os.getpid() % 100)
    if args.publisher:
        publish(domain, args.rate, args.seconds)
        return
    print(f"one subscriber, JointState at {args.rate:g} Hz from another process, "
          f"{args.seconds:g} s each ({load_text()})")
    base = None
    for kind, name in (("single", "SingleThreadedExecutor (baseline)"),
                       ("events", "EventsExecutor (the nodes')")):
        n, cpu, wall = subscribe(domain, kind, args.rate, args.seconds)
        per = cpu / max(1, n)
        base = per if base is None else base
        print(f"  {name:36s} {n:6d} messages  {1e6 * per:7.1f} us CPU per message  "
              f"{100 * cpu / wall:5.1f} % of one core  x base {per / base:.2f}  ({load_text()})")


if __name__ == "__main__":
    main()
