"""The teleop node over a ROS 2 graph: a master's pose in -> ``servo_jp`` out, beside one process.

Run from the repository root (the extra ``ros2``; discovery stays on the loopback)::

    python benchmarks/bench_ros2_teleop.py [--rate 1000] [--seconds 10] [--jump-every 0.05]
                                           [--arm-sync clock|command] [--arm-publish-rate 100]

Starts ``athenakin ros2 arm --enable`` and ``athenakin ros2 teleop`` (every guard on: the
default bodies checked, the watchdog, the limits; the tremor filter off, so that a
master's step shows in the very next command) in their own processes, the teleop node
driving the arm node over the graph. This process is the master: it publishes a
``PoseStamped`` at ``--rate`` (reliable QoS) with its clutch engaged, still but for a
step of the master's x by ``JUMP`` m (there and back) every ``--jump-every`` s. The
latency of a step is the time from the ``publish()`` of its first sample to the arrival
here of the first ``servo_jp`` that moved (its positions more than 1e-9 m from the
last command stamped before the step): the sample crossed the graph, waited for the
next teleop cycle, was stepped through :meth:`athenakin.teleop.Teleop.step` and
published, and the command crossed back. It is split at the command's stamp (the teleop
node's ROS clock, the system clock here, as this process's): send -> stamp holds the way
in, the wait for the cycle (uniform over one teleop period) and the step; stamp ->
arrival the publishing and the way back.
Also: the teleop node's CPU (user + system, share of one core and per cycle run over the
window), its cycles run of those due and late (its own count at exit), the ``servo_jp``
that arrived of the cycles run, the watchdog trips in the window (the master never
paused: 0 expected), and the arm node's CPU beside it. Beside the graph, the same
master stream through :class:`athenakin.teleop.Teleop` in one process with the same
bodies (per cycle). The machine's load is printed beside every figure. This process's
garbage collector is frozen while it times (as in ``bench_ros2.py``).

And on to the arm: each step from the same ``publish()`` to the arrival of the first
``setpoint_js`` of the arm node that carries the moved command (the teleop node's
command crossed the graph again and the arm took it), with the arm node's ``--sync``
(``--arm-sync``) and its state published at ``--arm-publish-rate`` (100 Hz by default, as
``athenakin ros2 arm``'s; at 1000 Hz the state shows every servo cycle).
"""

from __future__ import annotations

import argparse
import gc
import os
import re
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from _machine import load_text  # noqa: E402
from _ros2_procs import start, stop  # noqa: E402
from bench_ros2 import GraphClient, cpu_seconds, percentile_text  # noqa: E402

Q0 = (-0.1, 0.1, 0.45)
JUMP = 5e-4          # m of the master's x per step (0.1 mm of the tip at the scale 0.2)
MOVED = 1e-9         # m: a command this far from the one before the step moved


def master_x(k: int, rate: float, jump_every: float) -> float:
    """The master's x at sample ``k``: 0, then ``JUMP`` from the first step on, and back."""
    return JUMP * (int(k / (rate * jump_every)) % 2)


def in_process(rate: float, cycles: int, jump_every: float) -> tuple[np.ndarray, np.ndarray]:
    """Per-cycle time of :meth:`Teleop.step` on the same master stream, one process, s.

    Returns every cycle's time and those of the cycles that took a step's first sample.
    A first core runs 2000 cycles (kernels compiled or loaded, caches warm); a second
    one is timed.
    """
    import athenakin as ak
    from athenakin.collision import Bodies
    from athenakin.teleop import Teleop, TeleopOptions

    d = ak.Design.default()
    robot = ak.Robot(ak.default_rcm_frame(d), d, bodies=Bodies.default(d))
    opts = TeleopOptions(filter="none")
    warm = Teleop(robot, q0=Q0, rate=rate, options=opts)
    for k in range(2000):
        warm.step(k / rate, (master_x(k, rate, jump_every), 0.0, 0.0))
    tele = Teleop(robot, q0=Q0, rate=rate, options=opts)
    dt = np.empty(cycles)
    x = [master_x(k, rate, jump_every) for k in range(cycles)]
    for k in range(cycles):
        sample = (x[k], 0.0, 0.0)
        t0 = time.perf_counter()
        tele.step(k / rate, sample)
        dt[k] = time.perf_counter() - t0
    first = np.flatnonzero(np.diff(x) != 0.0) + 1
    return dt, dt[first]


def over_graph(rate: float, seconds: float, jump_every: float, domain: int, *,
               arm_sync: str = "clock", arm_publish_rate: float = 100.0) -> dict[str, object]:
    """Run the arm and teleop nodes in their own processes; master them for ``seconds``.

    ``arm_sync`` and ``arm_publish_rate``: the arm node's ``--sync`` and ``--publish-rate``.
    """
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import PoseStamped
    from sensor_msgs.msg import JointState, Joy

    arm = start(["arm", "--enable", "--sync", arm_sync, "--publish-rate",
                 str(arm_publish_rate)], domain)
    tele = start(["teleop", "--rate", str(rate), "--filter", "none"], domain)
    client = GraphClient(domain, "bench_master")
    node, qos = client.node, client.qos
    cmds: list[tuple[float, float, tuple[float, ...]]] = []   # (stamp, arrival, q), s, m
    sps: list[tuple[float, float, tuple[float, ...]]] = []    # the arm's setpoint_js, alike
    status: list[tuple[float, dict[str, str]]] = []           # (arrival, values)
    lock = threading.Lock()

    def keep(into: list[tuple[float, float, tuple[float, ...]]]) -> Callable[[JointState], None]:
        """A callback keeping each JointState's (stamp, arrival, positions) in ``into``."""
        def on_js(m: JointState) -> None:
            t = time.time()
            with lock:
                into.append((m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec, t,
                             tuple(m.position)))
        return on_js

    def on_status(m: DiagnosticArray) -> None:
        t = time.time()
        with lock:
            status.append((t, {kv.key: kv.value for kv in m.status[0].values}))

    node.create_subscription(JointState, "/athena/servo_jp", keep(cmds), qos)
    node.create_subscription(DiagnosticArray, "/athena/teleop/status", on_status, qos)
    node.create_subscription(JointState, "/athena/setpoint_js", keep(sps), qos)
    pose = node.create_publisher(PoseStamped, "/master/pose", qos)
    joy = node.create_publisher(Joy, "/master/joy", qos)
    client.spin()

    def close() -> str:
        out = stop(tele, timeout=30.0) + stop(arm, timeout=30.0)
        client.close()
        return out

    # the teleop node at its pace (a thousand commands after its first) and both master
    # topics matched; the master's first samples (still) and the clutch engaged
    end = time.monotonic() + 180
    while time.monotonic() < end and arm.poll() is None and tele.poll() is None:
        with lock:
            n = len(cmds)
        if n >= 1000 and pose.get_subscription_count() and joy.get_subscription_count():
            break
        time.sleep(0.05)
    else:
        out = close()
        raise RuntimeError(f"the teleop node did not command at its pace within 180 s "
                           f"({len(cmds)} servo_jp): {out.strip()[-600:]}")
    joy.publish(Joy(buttons=[0]))                  # the clutch engaged: the tip follows
    period = 1.0 / rate
    msg = PoseStamped()
    for _ in range(int(0.5 * rate)):               # half a second still, engaged
        pose.publish(msg)
        time.sleep(period)
    gc.collect()              # this master's own garbage collections stay out of the timing
    gc.freeze()
    cpu0 = {p.pid: cpu_seconds(p.pid) for p in (arm, tele)}
    w0, load = time.time(), load_text()
    n = int(seconds * rate)
    steps: list[float] = []                        # send time of each step's first sample
    t_next = time.time()
    x_prev = 0.0
    for k in range(n):
        x = master_x(k, rate, jump_every)
        msg.pose.position.x = x
        t = time.time()
        pose.publish(msg)
        if x != x_prev:
            steps.append(t)
        x_prev = x
        t_next += period
        wait = t_next - time.time()
        if wait > 0:
            time.sleep(wait)
    w1 = time.time()
    cpu = {pid: cpu_seconds(pid) - c for pid, c in cpu0.items()}
    time.sleep(0.5)
    gc.unfreeze()
    with lock:
        cmd, st, sp = list(cmds), list(status), list(sps)
    out = close()
    m = re.search(r"ros2 teleop: (\d+) cycles, (\d+) late", out)
    window = [v for t, v in st if w0 <= t <= w1]
    cycles_run = (int(window[-1]["cycle"]) - int(window[0]["cycle"])) if len(window) > 1 else 0
    span = (float(window[-1]["t"]) - float(window[0]["t"])) if len(window) > 1 else 0.0
    lat, back = _step_latencies(steps, cmd)
    return {"latency": lat, "in": lat - back, "back": back, "steps": len(steps),
            "to_arm": _step_latencies(steps, sp)[0],
            "sent": n, "wall": w1 - w0, "load": load,
            "cpu_teleop": cpu[tele.pid], "cpu_arm": cpu[arm.pid],
            "cycles_run": cycles_run, "cycles_due": round(span * rate),
            "servo_in_window": sum(w0 <= a <= w1 for _, a, _ in cmd),
            "watchdog": sum(v["watchdog"] == "True" for v in window),
            "late": int(m.group(2)) if m else -1, "cycles": int(m.group(1)) if m else -1,
            "log": out}


def _step_latencies(steps: list[float], cmds: list[tuple[float, float, tuple[float, ...]]]
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Each step's latency and its stamp -> arrival part, s (steps whose command showed).

    ``steps``: send time of each step's first sample; ``cmds``: (stamp, arrival, q) of
    every ``servo_jp``, in arrival order. A step's command is the first one stamped at or
    after its send time whose q moved more than :data:`MOVED` from the last one stamped
    before it.
    """
    cmds = sorted(cmds)
    stamps = np.array([c[0] for c in cmds])
    q = np.array([c[2] for c in cmds])
    lat, back = [], []
    for t in steps:
        i = int(np.searchsorted(stamps, t))
        if i == 0 or i >= len(cmds):
            continue
        moved = np.flatnonzero(np.abs(q[i:] - q[i - 1]).max(axis=1) > MOVED)
        if len(moved):
            stamp, arrival, _ = cmds[i + moved[0]]
            lat.append(arrival - t)
            back.append(arrival - stamp)
    return np.array(lat), np.array(back)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rate", type=float, default=1000.0, help="teleop and master rate, Hz")
    ap.add_argument("--seconds", type=float, default=10.0, help="master samples for this long")
    ap.add_argument("--jump-every", type=float, default=0.05, help="s between master steps")
    ap.add_argument("--arm-sync", choices=("clock", "command"), default="clock",
                    help="the arm node's --sync")
    ap.add_argument("--arm-publish-rate", type=float, default=100.0,
                    help="the arm node's --publish-rate, Hz (its setpoint_js shows the step)")
    args = ap.parse_args()
    domain = int(os.environ.get("ROS_DOMAIN_ID") or 1 + os.getpid() % 100)
    base, base_steps = in_process(args.rate, int(args.seconds * args.rate), args.jump_every)
    print(f"in one process, Teleop.step with the default bodies, every cycle: "
          f"{percentile_text(base)} ({load_text()})")
    print(f"  the cycles that took a step's first sample: {percentile_text(base_steps)}")
    # a loop of this rate in one process: a sample waits for the next cycle (uniform over
    # one period, half of it at p50), then the step
    floor = 0.5 / args.rate + np.percentile(base_steps, 50)
    r = over_graph(args.rate, args.seconds, args.jump_every, domain, arm_sync=args.arm_sync,
                   arm_publish_rate=args.arm_publish_rate)
    lat = r["latency"]
    assert isinstance(lat, np.ndarray)
    print(f"over the graph, teleop at {args.rate:g} Hz, master at {args.rate:g} Hz (reliable), "
          f"{len(lat)} of {r['steps']} master steps shown on servo_jp: {percentile_text(lat)} "
          f"({r['load']})")
    if not len(lat):
        print(f"  no latency sample; the end of the nodes' logs: {str(r['log']).strip()[-600:]!r}")
        return
    print(f"  of which send -> stamp of that command (the graph in, the wait for the next "
          f"teleop cycle, the step): {percentile_text(r['in'])}")
    print(f"  and stamp -> arrival here (the command's publishing, the graph back): "
          f"{percentile_text(r['back'])}")
    wall, run = r["wall"], r["cycles_run"]
    print(f"  teleop node CPU {100 * r['cpu_teleop'] / wall:.0f} % of one core over the "
          f"{wall:.1f} s of master samples ({1e6 * r['cpu_teleop'] / max(1, run):.0f} us per "
          f"cycle run; {run} cycles run of {r['cycles_due']} due; {r['servo_in_window']} "
          f"servo_jp arrived; watchdog in {r['watchdog']} status messages; "
          f"{r['late']} late of {r['cycles']} cycles in the whole run)")
    print(f"  arm node CPU beside it {100 * r['cpu_arm'] / wall:.0f} % of one core")
    to_arm = r["to_arm"]
    assert isinstance(to_arm, np.ndarray)
    print(f"  and on to the arm (--sync {args.arm_sync}, state at {args.arm_publish_rate:g} "
          f"Hz): {len(to_arm)} of {r['steps']} master steps shown on its setpoint_js, from the "
          f"master's publish() to the arrival here: {percentile_text(to_arm)}")
    print(f"  p50 graph / p50 of the same loop in one process (half a period's wait, the "
          f"step: {1e6 * floor:.0f} us): {np.percentile(lat, 50) / floor:.1f}x ({load_text()})")


if __name__ == "__main__":
    main()
