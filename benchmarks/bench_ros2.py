"""The arm node over a ROS 2 graph: ``servo_jp`` in -> ``measured_js`` out, beside one process.

Run from the repository root (the extra ``ros2``; discovery stays on the loopback)::

    python benchmarks/bench_ros2.py [--rate 1000] [--publish-rate RATE] [--seconds 5]
                                    [--sync clock|command|both] [--pin]

Starts ``athenakin ros2 arm`` in its own process, servoing at ``--rate`` with its state
published at ``--publish-rate`` (default: every servo cycle), and from this process sends
one ``servo_jp`` per published state (reliable QoS), each a distinct setpoint. The
latency of a command is the time from its ``publish()`` to the arrival of the first
``measured_js`` whose ``setpoint_js`` (same stamp) carries it: the command crossed the
graph, waited for the next servo cycle, was stepped and published, and crossed back.
It is split at the state's stamp (the arm node's ROS clock, the system clock here, as
this process's): send -> stamp holds the way in, the wait for the servo cycle (uniform
over one servo period for a command sent at any time) and the step; stamp -> arrival
the state's publishing and the way back.
Lost: commands the arm node never received (its own count at exit); replaced: received,
but a later one was the setpoint by the time a state message was published (two in one
publishing period: CRTK's servo keeps the latest). CPU: the arm process's user + system
time over the commands' window, as a share of one core and per servo cycle run in it
(the cycles counted from the state messages that arrived then), and so for the
2 s before the first command (the arm node alone: its states read, no command). Beside it, the same
loop in one process (``servo_jp``, ``step``, ``measured_js`` of
:class:`athenakin.teleop.SimulatedArm`, no graph), per cycle.
The machine's load is printed beside every figure.

``--sync`` is the arm node's (``clock``: cycles on its own grid; ``command``: a servo
command's arrival starts one); ``both`` (the default) runs one of each and prints the
ratios of their latencies. ``--pin`` runs the arm node on CPU 1 and this process on CPU 0.
This process's garbage collector is frozen (``gc.freeze``) while it times, so that a
collection of its own does not show as the graph's latency.

The commands start once the arm node publishes at its pace (a hundred states after its
first, not its first alone: a node still loading its kernels would take none of them),
in ``ROS_DOMAIN_ID`` where it is set (else one of this run's, from the pid). Where no
command shows on a ``setpoint_js`` the run says so by name, with what the arm node
answered (its counts, its first refusal on ``status``).
"""

from __future__ import annotations

import argparse
import gc
import os
import re
import sys
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from _machine import load_text  # noqa: E402
from _ros2_procs import start, stop  # noqa: E402

Q0 = (-0.1, 0.1, 0.45)
STEP = 1e-7          # m between two commands' q3 (the commands are told apart by it)
IDLE_S = 2.0         # s of the arm node alone (its states published, no command) first


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of process ``pid`` so far, s (``/proc/PID/stat``)."""
    fields = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def percentile_text(x: np.ndarray) -> str:
    """``x`` (latencies, s) as p50, p99 and max in us, or that there is no sample."""
    if not len(x):
        return "no latency sample"
    us = x * 1e6
    return (f"p50 {np.percentile(us, 50):8.1f} us  p99 {np.percentile(us, 99):8.1f} us  "
            f"max {us.max():9.1f} us")


def in_process(rate: float, cycles: int) -> np.ndarray:
    """Per-cycle time of servo_jp -> step -> measured_js in one process, s."""
    import athenakin as ak
    from athenakin.teleop import SimulatedArm

    d = ak.Design.default()
    arm = SimulatedArm(ak.default_rcm_frame(d), d, q0=Q0, rate=rate)
    arm.enable()
    q = np.array(Q0)
    dt = np.empty(cycles)
    for k in range(cycles):
        t0 = time.perf_counter()
        q[2] = Q0[2] + STEP * (k % 1000)
        arm.servo_jp(q)
        arm.step(1)
        arm.measured_js()
        dt[k] = time.perf_counter() - t0
    return dt


class GraphClient:
    """A benchmark's own rclpy node on the loopback, in ``domain``, reliable QoS of depth 1000.

    Its subscriptions and publishers are made on :attr:`node` with :attr:`qos`; then
    :meth:`spin` runs the events executor (as the nodes' own,
    ``ros2._runtime.control_executor``) in a thread until :meth:`close`.
    """

    def __init__(self, domain: int, name: str) -> None:
        import rclpy
        from rclpy.context import Context
        from rclpy.experimental import EventsExecutor
        from rclpy.qos import QoSProfile, ReliabilityPolicy

        os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain)
        self.node = rclpy.create_node(name, context=self.context)
        self._executor = EventsExecutor(context=self.context)
        self._executor.add_node(self.node)
        self.qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        self._done = threading.Event()
        self._spinner = threading.Thread(
            target=lambda: [self._executor.spin_once(timeout_sec=0.05)
                            for _ in iter(self._done.is_set, True)], daemon=True)

    def spin(self) -> None:
        """Start spinning the node in its thread."""
        self._spinner.start()

    def close(self) -> None:
        """Stop the spinning thread, destroy the node, shut its context down."""
        self._done.set()
        if self._spinner.is_alive():
            self._spinner.join(timeout=5)
        self.node.destroy_node()
        self.context.try_shutdown()


def over_graph(rate: float, publish_rate: float, seconds: float, domain: int, *,
               sync: str = "clock", pin: bool = False) -> dict[str, object]:
    """Run the arm node in its own process and time ``seconds`` of commands through it.

    ``sync``: the arm node's ``--sync``; ``pin``: the arm node on CPU 1, this process on
    CPU 0.
    """
    from sensor_msgs.msg import JointState

    try:                               # CRTK's own status type where crtk_msgs is built
        from crtk_msgs.msg import StringStamped as Status

        def text(m: object) -> str:
            return str(m.string)  # type: ignore[attr-defined]
    except ImportError:                # the node's std_msgs stand-in
        from std_msgs.msg import String as Status

        def text(m: object) -> str:
            return str(m.data)  # type: ignore[attr-defined]

    proc = start(["arm", "--enable", "--rate", str(rate), "--publish-rate", str(publish_rate),
                  "--sync", sync], domain, cpus={1} if pin else None)
    client = GraphClient(domain, "bench_client")
    node, qos = client.node, client.qos
    sent: dict[int, float] = {}
    seen: dict[tuple[int, int], float] = {}     # stamp of a measured_js -> arrival time, s
    sp_of: dict[tuple[int, int], int] = {}      # stamp of a setpoint_js -> the command index
    refusals: list[str] = []                    # the arm node's status texts
    lock = threading.Lock()

    def on_js(m: JointState) -> None:
        t = time.time()
        with lock:
            seen[(m.header.stamp.sec, m.header.stamp.nanosec)] = t

    def on_sp(m: JointState) -> None:
        k = round((m.position[2] - Q0[2]) / STEP)
        with lock:
            sp_of[(m.header.stamp.sec, m.header.stamp.nanosec)] = k

    node.create_subscription(JointState, "/athena/measured_js", on_js, qos)
    node.create_subscription(JointState, "/athena/setpoint_js", on_sp, qos)
    node.create_subscription(Status, "/athena/status", lambda m: refusals.append(text(m)), qos)
    pub = node.create_publisher(JointState, "/athena/servo_jp", qos)
    client.spin()
    end = time.monotonic() + 180
    # the arm node at its pace: a hundred states after its first (not the first alone)
    while (pub.get_subscription_count() == 0 or len(seen) < 100) and time.monotonic() < end:
        if proc.poll() is not None:
            break
        time.sleep(0.05)
    if len(seen) < 100:
        client.close()
        raise RuntimeError(f"the arm node did not publish at its pace within 180 s "
                           f"({len(seen)} measured_js): {stop(proc)}")
    # the arm node alone (no commands yet) for IDLE_S, while its reader matches this writer
    idle_cpu0, idle_w0 = cpu_seconds(proc.pid), time.time()
    time.sleep(IDLE_S)
    idle_cpu, idle_wall = cpu_seconds(proc.pid) - idle_cpu0, time.time() - idle_w0
    with lock:
        idle_states = sum(idle_w0 <= t for t in seen.values())
    gc.collect()              # this client's own garbage collections stay out of the timing
    gc.freeze()
    cpu0, w0, load = cpu_seconds(proc.pid), time.time(), load_text()
    n = int(seconds * publish_rate)
    period = 1.0 / publish_rate
    t_next = t_start = time.time()
    q = list(Q0)
    for k in range(1, n + 1):
        q[2] = Q0[2] + STEP * k
        msg = JointState(name=["q1", "q2", "q3"], position=[float(v) for v in q])
        sent[k] = time.time()
        pub.publish(msg)
        t_next += period
        wait = t_next - time.time()
        if wait > 0:
            time.sleep(wait)
    time.sleep(1.0)
    cpu, wall = cpu_seconds(proc.pid) - cpu0, time.time() - w0
    gc.unfreeze()
    with lock:
        states = sum(t >= t_start for t in seen.values())
        window = sum(t >= w0 for t in seen.values())       # states published in the window
    out = stop(proc, timeout=30.0)
    client.close()
    m = re.search(r"(\d+) cycles, (\d+) late, (\d+) on a command, (\d+) commands, "
                  r"(\d+) refused", out)
    cycles, late, synced, received, refused = ((int(g) for g in m.groups()) if m
                                               else (0, 0, 0, -1, -1))
    with lock:
        lat, back = _latencies(sent, seen, sp_of)
    return {"latency": lat, "in": lat - back, "back": back, "sent": n, "received": received,
            "reflected": len(lat),
            "refused": refused, "refusals": refusals[:1], "states": states,
            "cycles": cycles, "late": late, "synced": synced, "sync": sync, "cpu": cpu,
            "wall": wall,
            "window_cycles": window * round(rate / publish_rate), "load": load, "log": out,
            "idle": (idle_cpu, idle_wall, idle_states * round(rate / publish_rate))}


def _latencies(sent: dict[int, float], seen: dict[tuple[int, int], float],
               sp_of: dict[tuple[int, int], int]) -> tuple[np.ndarray, np.ndarray]:
    """Each shown command's latency and its stamp -> arrival part, s (commands in order).

    ``sent``: command -> send time; ``seen``: stamp of a ``measured_js`` -> its arrival;
    ``sp_of``: stamp of a ``setpoint_js`` -> the command it carries. A command's state is
    the first (earliest stamp) that carries it and arrived.
    """
    first: dict[int, tuple[int, int]] = {}
    for stamp, k in sp_of.items():
        if k in sent and stamp in seen and (k not in first or stamp < first[k]):
            first[k] = stamp
    order = sorted(first)
    arrival = np.array([seen[first[k]] for k in order])
    lat = arrival - np.array([sent[k] for k in order])
    back = arrival - np.array([first[k][0] + 1e-9 * first[k][1] for k in order])
    return lat, back


def _no_sample(r: dict[str, object]) -> str:
    """Why the run has no latency sample, by name: what the arm node received and answered."""
    first = r["refusals"][0] if r["refusals"] else "none"  # type: ignore[index]
    return (f"  no latency sample: none of the {r['sent']} servo_jp showed on a setpoint_js "
            f"(the arm node received {r['received']}, refused {r['refused']}, first status "
            f"{first!r}; {r['states']} measured_js arrived from the first command on; the end "
            f"of its log: {str(r['log']).strip()[-300:]!r})")


def report(r: dict[str, object], rate: float, publish: float, base: np.ndarray) -> None:
    """Print one run of :func:`over_graph`: latency, its split, losses, cycles, CPU."""
    lat = r["latency"]
    assert isinstance(lat, np.ndarray)
    lost = r["sent"] - r["received"] if r["received"] >= 0 else "unknown"
    print(f"over the graph, servo at {rate:g} Hz (--sync {r['sync']}), state and commands "
          f"at {publish:g} Hz, {r['sent']} servo_jp (reliable): {percentile_text(lat)} "
          f"({r['load']})")
    if not len(lat):
        print(_no_sample(r))
    else:
        wait = ("the wait for the next servo cycle" if r["sync"] == "clock" else
                "the cycle started on its arrival")
        print(f"  of which send -> stamp of that state (the graph in, {wait}, the step): "
              f"{percentile_text(r['in'])}")
        print(f"  and stamp -> arrival here (the state's publishing, the graph back): "
              f"{percentile_text(r['back'])}")
    replaced = r["received"] - max(0, r["refused"]) - r["reflected"]
    print(f"  lost {lost} of {r['sent']}; refused {r['refused']}; replaced before a state "
          f"message showed them {replaced}; arm cycles {r['cycles']}, late {r['late']}, "
          f"started on a command {r['synced']}")
    cpu, wall, run = r["idle"]  # type: ignore[misc]
    print(f"  arm node alone (its states read here, no command): {100 * cpu / wall:.0f} % of "
          f"one core over {wall:.1f} s ({1e6 * cpu / max(1, run):.0f} us per servo cycle run; "
          f"{run} cycles run of {round(wall * rate)} due)")
    run, due = r["window_cycles"], round(r["wall"] * rate)
    print(f"  arm node CPU {100 * r['cpu'] / r['wall']:.0f} % of one core over the "
          f"{r['wall']:.1f} s of commands ({1e6 * r['cpu'] / max(1, run):.0f} us per servo "
          f"cycle run; {run} cycles run of {due} due at {rate:g} Hz)")
    if len(lat):
        print(f"  p50 graph / p50 one process: "
              f"{np.percentile(lat, 50) / np.percentile(base, 50):.1f}x ({load_text()})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rate", type=float, default=1000.0, help="servo and command rate, Hz")
    ap.add_argument("--publish-rate", type=float, help="state and command rate, Hz (--rate)")
    ap.add_argument("--seconds", type=float, default=5.0, help="commands for this long, s")
    ap.add_argument("--sync", choices=("clock", "command", "both"), default="both",
                    help="the arm node's --sync (both: one run of each, compared)")
    ap.add_argument("--pin", action="store_true",
                    help="the arm node on CPU 1, this process on CPU 0")
    args = ap.parse_args()
    domain = int(os.environ.get("ROS_DOMAIN_ID") or 1 + os.getpid() % 100)
    if args.pin:
        if not {0, 1} <= os.sched_getaffinity(0):
            ap.error("--pin needs CPUs 0 and 1")
        os.sched_setaffinity(0, {0})
    where = "pinned: the arm node on CPU 1, this process on CPU 0" if args.pin else "not pinned"
    base = in_process(args.rate, int(args.seconds * args.rate))
    print(f"in one process, servo_jp -> step -> measured_js: {percentile_text(base)} "
          f"({load_text()}; {where})")
    publish = args.rate if args.publish_rate is None else args.publish_rate
    runs = {}
    for sync in (("clock", "command") if args.sync == "both" else (args.sync,)):
        r = runs[sync] = over_graph(args.rate, publish, args.seconds, domain, sync=sync,
                                    pin=args.pin)
        report(r, args.rate, publish, base)
    if len(runs) == 2 and all(len(r["latency"]) for r in runs.values()):  # type: ignore[arg-type]
        a, b = (runs[k]["latency"] for k in ("command", "clock"))
        print(f"--sync command / --sync clock: p50 "
              f"{np.percentile(a, 50) / np.percentile(b, 50):.2f}x, p99 "
              f"{np.percentile(a, 99) / np.percentile(b, 99):.2f}x ({load_text()}; {where})")


if __name__ == "__main__":
    main()
