"""docs/figures/ros2_session.png: a teleoperated session recorded from a live ROS 2 graph.

Run from the repository root (the extras ``ros2``, ``ros``, ``sim``, ``plot``)::

    python scripts/ros2_session_figure.py [--out docs/figures/ros2_session.png]
                                          [--mcap session.mcap] [--rate 200]

1. starts ``athenakin ros2 arm --enable`` and ``athenakin ros2 teleop`` in their own
   processes (discovery on the loopback: ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``, a
   ``ROS_DOMAIN_ID`` of this run), and :class:`athenakin.ros2.RecorderNode` in this one;
2. (first, in this process: a short session of the core, so that numba's kernels are
   compiled or loaded from its cache before the nodes need them)
   once the recorder has the nodes' topics and the teleop node follows the master, a
   scripted master (its own plain rclpy node: ``PoseStamped`` at 100 Hz, ``Joy`` at
   10 Hz) plays 12 s: still, a few centimetres of motion, the clutch held 1.5 s while
   the hand moves on, motion again, 0.6 s of silence (the watchdog trips and the arm
   holds), the master back elsewhere (it re-engages without a jump), still again;
3. closes the recording and draws the figure from the MCAP alone, read with the mcap
   library: the master, the commanded (``servo_jp``) and measured (``measured_js``)
   actuators, the commanded (the teleop status's ``tip_b``) and measured
   (``measured_cp``) tip, and the teleop flags and the master's clutch over time;
4. prints the numbers docs/ros2.md quotes (messages per topic, the watchdog's trip after
   the silence, the commanded tip's step at re-engagement, the machine's load).

Every wait follows readiness (a condition polled with a generous deadline); only the
master's own timeline is paced by the clock.
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))      # the node processes' helpers, as golden.py does
from _ros2_procs import start, stop  # noqa: E402

DEADLINE = 180.0         # s: the longest wait for a node (numba's first compile, a loaded machine)
MASTER_RATE = 100.0      # master poses per second, Hz
JOY_EVERY = 10           # a Joy every this many poses (10 Hz)
WATCHDOG = 0.1           # s: the teleop node's watchdog (scheduling jitter of a loaded machine
#                          stays below it; the scripted silence is six times longer)
#: Shortest drawn span of a status flag, s (a flag of one cycle stays visible).
MIN_SPAN = 0.04
#: The master's timeline, s: (start, end, phase).
TIMELINE = ((0.0, 1.0, "still"), (1.0, 5.0, "move"), (5.0, 6.5, "clutch"), (6.5, 8.0, "move"),
            (8.0, 8.6, "silent"), (8.6, 11.0, "return"), (11.0, 12.0, "still"))


def _load() -> str:
    a, b, c = os.getloadavg()
    return f"load {a:.1f} / {b:.1f} / {c:.1f} on {os.cpu_count()} cores"


def master_at(s: float) -> tuple[tuple[float, float, float] | None, bool]:
    """The master's handle (m, its frame) at ``s`` s of the timeline, and the clutch held.

    None during the silence. The hand moves on while the clutch is held, and comes back
    after the silence 2 cm away from where it stopped.
    """
    phase = next((p for a, b, p in TIMELINE if a <= s < b), "still")
    if phase == "silent":
        return None, False
    u = min(max(s - 1.0, 0.0), 10.0)            # motion time, s
    if phase == "return" or (phase == "still" and s >= 11.0):
        u = min(s, 11.0) - 1.6                  # on along the path, 0.6 s later
    elif phase == "still":
        u = 0.0
    w = 2 * math.pi * 0.35
    x = 0.03 * math.sin(w * u)
    y = 0.02 * (1 - math.cos(w * u))
    z = 0.01 * math.sin(0.5 * w * u)
    if s >= 8.6:
        z += 0.02                              # back elsewhere: 2 cm above
    return (x, y, z), phase == "clutch"


class Master:
    """The scripted master: a plain rclpy node of this script (PoseStamped + Joy)."""

    def __init__(self, domain: int) -> None:
        import rclpy
        from diagnostic_msgs.msg import DiagnosticArray
        from geometry_msgs.msg import PoseStamped
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import Joy

        self.PoseStamped, self.Joy = PoseStamped, Joy
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain)
        self.node = rclpy.create_node("scripted_master", context=self.context)
        qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
        self.pose = self.node.create_publisher(PoseStamped, "/master/pose", qos)
        self.joy = self.node.create_publisher(Joy, "/master/joy", qos)
        self.status: list = []
        self.node.create_subscription(DiagnosticArray, "/athena/teleop/status",
                                      self.status.append, qos)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def send(self, p: tuple[float, float, float] | None, held: bool, k: int) -> None:
        """Publish the pose ``p`` (none when None) and, every :data:`JOY_EVERY`, the clutch."""
        stamp = self.node.get_clock().now().to_msg()
        if p is not None:
            m = self.PoseStamped()
            m.header.stamp, m.header.frame_id = stamp, "master"
            m.pose.position.x, m.pose.position.y, m.pose.position.z = p
            m.pose.orientation.w = 1.0
            self.pose.publish(m)
            if k % JOY_EVERY == 0:
                j = self.Joy(buttons=[int(held)], axes=[])
                j.header.stamp = stamp
                self.joy.publish(j)

    def following(self) -> bool:
        """The teleop node's latest status says it follows (no watchdog)."""
        self.executor.spin_once(timeout_sec=0.01)
        if not self.status:
            return False
        values = {kv.key: kv.value for kv in self.status[-1].status[0].values}
        return values["watchdog"] == "False"

    def close(self) -> None:
        """Destroy the node, shut its context down."""
        self.node.destroy_node()
        self.context.try_shutdown()


def _until(cond, what: str, procs: list[subprocess.Popen], timeout: float = DEADLINE) -> None:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cond():
            return
        for p in procs:
            if p.poll() is not None:
                raise SystemExit(f"a node exited ({p.returncode}) while waiting for {what}:\n"
                                 + (p.stdout.read() if p.stdout else ""))
        time.sleep(0.05)
    raise SystemExit(f"no {what} within {timeout:g} s")


def warm_up(rate: float) -> None:
    """Compile the kernels the nodes run (or load them from numba's cache) before they start.

    On a fresh checkout the first teleop cycles that move would otherwise wait seconds
    for numba in the middle of the session; the nodes load what this writes to the cache.
    """
    import athenakin as ak
    from athenakin._dispatch import warmup
    from athenakin.collision import Bodies
    from athenakin.teleop import SimulatedArm, Teleop, TeleopOptions, run_session

    warmup()
    d = ak.Design.default()
    T, q0 = ak.default_rcm_frame(d), (-0.1, 0.1, 0.45)
    tele = Teleop(T, d, q0=q0, rate=rate, bodies=Bodies.default(d),
                  options=TeleopOptions(watchdog=WATCHDOG))
    arm = SimulatedArm(T, d, q0=q0, rate=rate)
    arm.enable()
    run_session(tele, arm, ((k / rate, master_at(1.0 + k / rate)[0], True) for k in range(200)))


def record(mcap: Path, rate: float) -> dict[str, int]:
    """Run the nodes, the recorder and the scripted master; the messages per topic."""
    from athenakin.ros2 import RecorderNode, RosContext

    domain = 1 + os.getpid() % 100
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    procs = [start(["arm", "--enable", "--publish-rate", "100"], domain),
             start(["teleop", "--rate", str(rate), "--status-every", "1",
                     "--watchdog", str(WATCHDOG)], domain)]
    ctx = RosContext(domain_id=domain)
    master = rec = None
    try:
        rec = RecorderNode(mcap, context=ctx).start()
        master = Master(domain)
        need = ("/athena/measured_js", "/athena/servo_jp", "/athena/teleop/status",
                "/athena/operating_state")
        _until(lambda: all(rec.counts[k] for k in need) and
               master.pose.get_subscription_count() >= 2 and
               master.joy.get_subscription_count() >= 2,
               "the nodes' topics in the recorder and the master's subscribers", procs)
        home, _ = master_at(0.0)
        end = time.monotonic() + DEADLINE
        k = 0
        while not (master.following() and rec.counts["/master/pose"] > 0):
            master.send(home, False, k)            # held still at the master's rate
            k += 1
            time.sleep(1.0 / MASTER_RATE)
            if time.monotonic() > end or any(p.poll() is not None for p in procs):
                raise SystemExit("the teleop node did not follow the master: "
                                 + "".join(stop(p, timeout=30.0) for p in procs))
        t0 = time.perf_counter()
        n = round(TIMELINE[-1][1] * MASTER_RATE)
        for k in range(n):                        # the master's own clock paces this loop
            p, held = master_at(k / MASTER_RATE)
            master.send(p, held, k)
            wait = t0 + (k + 1) / MASTER_RATE - time.perf_counter()
            if wait > 0:
                time.sleep(wait)
        # silent again: once the teleop node holds, and the arm published a while after, stop
        seen = rec.counts["/athena/measured_js"]
        _until(lambda: not master.following() and
               rec.counts["/athena/measured_js"] > seen + 50, "the session's end", procs)
    finally:
        if master is not None:
            master.close()
        if rec is not None:
            rec.close()
        ctx.close()
        out = "".join(stop(p, timeout=30.0) for p in procs)
    print(out.strip())
    return rec.counts


# ---------------------------------------------------------------------------- the figure
def read_session(mcap: Path) -> dict[str, list[tuple[float, object]]]:
    """``topic -> [(log time in ns, decoded message)]`` of the MCAP, by the mcap library."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    out: dict[str, list] = {}
    with open(mcap, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        for _, channel, message, msg in reader.iter_decoded_messages(log_time_order=True):
            out.setdefault(channel.topic, []).append((message.log_time, msg))
    return out


def _values(arr) -> dict[str, str]:
    return {kv.key: kv.value for kv in arr.status[0].values}


def session_arrays(s: dict) -> dict[str, np.ndarray]:
    """The figure's series (s from the first master pose; m; TeleopStatus bits)."""
    t0 = s["/master/pose"][0][0]

    def t(topic):
        return (np.array([ns for ns, _ in s[topic]], dtype=np.int64) - t0) * 1e-9

    pos = lambda m: [m.pose.position.x, m.pose.position.y, m.pose.position.z]  # noqa: E731
    st = [_values(m) for _, m in s["/athena/teleop/status"]]
    return {
        "t_master": t("/master/pose"), "master": np.array([pos(m) for _, m in s["/master/pose"]]),
        "t_joy": t("/master/joy"),
        "joy": np.array([bool(m.buttons[0]) for _, m in s["/master/joy"]]),
        "t_cmd": t("/athena/servo_jp"),
        "cmd": np.array([m.position for _, m in s["/athena/servo_jp"]]),
        "t_js": t("/athena/measured_js"),
        "js": np.array([m.position for _, m in s["/athena/measured_js"]]),
        "t_cp": t("/athena/measured_cp"),
        "cp": np.array([pos(m) for _, m in s["/athena/measured_cp"]]),
        "t_st": t("/athena/teleop/status"),
        "tip_cmd": np.array([[float(v) for v in x["tip_b"].split()] for x in st]),
        "flags": np.array([int(x["flags"]) for x in st], dtype=np.int64),
    }


def silence(a: dict[str, np.ndarray]) -> tuple[float, float]:
    """The master's longest silence in the recording: (last pose before, first after), s."""
    gap = np.diff(a["t_master"])
    i = int(np.argmax(gap))
    return float(a["t_master"][i]), float(a["t_master"][i + 1])


def numbers(a: dict[str, np.ndarray]) -> dict[str, float]:
    """The watchdog's trip after the silence, the commanded tip's step on re-engaging."""
    from athenakin.teleop import TeleopStatus

    wd = (a["flags"] & int(TeleopStatus.WATCHDOG)) != 0
    last, back = silence(a)
    i_on = int(np.flatnonzero(wd & (a["t_st"] > last))[0])
    i_back = int(np.flatnonzero(~wd & (a["t_st"] > a["t_st"][i_on]))[0])
    step = float(np.linalg.norm(a["tip_cmd"][i_back] - a["tip_cmd"][i_back - 1]))
    return {"silence_s": back - last, "watchdog_after_last_sample_s": float(a["t_st"][i_on] - last),
            "reengaged_after_return_s": float(a["t_st"][i_back] - back),
            "reengage_tip_step_m": step}


def _gaps(t: np.ndarray, x: np.ndarray, longest: float) -> tuple[np.ndarray, np.ndarray]:
    """``t``, ``x`` with a NaN row wherever two samples lie more than ``longest`` s apart."""
    cut = np.flatnonzero(np.diff(t) > longest) + 1
    return (np.insert(t, cut, np.nan), np.insert(x.astype(float), cut, np.nan, axis=0))


def draw(a: dict[str, np.ndarray], path: Path) -> None:
    """The four panels, written atomically to ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from athenakin._output import atomic_path
    from athenakin.teleop import TeleopStatus

    fig, ax = plt.subplots(4, 1, figsize=(10.5, 10.5), sharex=True,
                           gridspec_kw={"height_ratios": [2, 2, 2, 1.4]})
    beside = {"loc": "upper left", "bbox_to_anchor": (1.01, 1.0), "fontsize": 8,
              "frameon": False}
    colors = ("C0", "C1", "C2")
    tm, xm = _gaps(a["t_master"], a["master"], 5.0 / MASTER_RATE)
    for i, c in enumerate("xyz"):
        ax[0].plot(tm, xm[:, i] * 1e3, lw=1.2, color=colors[i], label=f"master {c}")
    tj, held = a["t_joy"], a["joy"]
    for k in np.flatnonzero(held):               # held from this Joy to the next one
        ax[0].axvspan(tj[k], tj[k + 1] if k + 1 < len(tj) else tj[k] + JOY_EVERY / MASTER_RATE,
                      color="0.85", lw=0, zorder=0)
    ax[0].plot([], [], "s", color="0.85", label="clutch held (Joy)")
    ax[0].set_ylabel("/master/pose [mm]\n(master frame)")
    ax[0].legend(**beside)
    q0 = a["js"][0]
    for i in range(3):
        ax[1].plot(a["t_cmd"], (a["cmd"][:, i] - q0[i]) * 1e3, lw=1.2, color=colors[i],
                   label=f"servo_jp q{i + 1}")
        ax[1].plot(a["t_js"], (a["js"][:, i] - q0[i]) * 1e3, "k:", lw=0.9)
    ax[1].plot([], [], "k:", label="measured_js")
    ax[1].set_ylabel("actuator - start [mm]")
    ax[1].legend(**beside)
    p0 = a["cp"][0]
    for i, c in enumerate("xyz"):
        ax[2].plot(a["t_st"], (a["tip_cmd"][:, i] - p0[i]) * 1e3, lw=1.2, color=colors[i],
                   label=f"commanded tip {c}")
        ax[2].plot(a["t_cp"], (a["cp"][:, i] - p0[i]) * 1e3, "k:", lw=0.9)
    ax[2].plot([], [], "k:", label="measured_cp")
    ax[2].set_ylabel("tip - start [mm]\n(base frame)")
    ax[2].legend(**beside)
    names = [f for f in TeleopStatus if f and np.any(a["flags"] & int(f))]
    for j, f in enumerate(names):
        on = np.concatenate([[0], ((a["flags"] & int(f)) != 0).astype(np.int8), [0]])
        starts, ends = np.flatnonzero(np.diff(on) == 1), np.flatnonzero(np.diff(on) == -1)
        t_end = np.append(a["t_st"][1:], a["t_st"][-1])     # a status holds until the next
        spans = [(a["t_st"][i], max(t_end[e - 1] - a["t_st"][i], MIN_SPAN))
                 for i, e in zip(starts, ends, strict=True)]
        ax[3].broken_barh(spans, (j - 0.4, 0.8), color=f"C{j}", lw=0)
    ax[3].set_yticks(range(len(names)), [f.name for f in names], fontsize=8)
    ax[3].set_ylim(-0.6, len(names) - 0.4)
    ax[3].set_xlabel("t [s] (header stamps, from the first master pose)")
    ax[3].set_title("/athena/teleop/status flags", fontsize=9)
    ax[3].set_xlim(min(a["t_st"][0], 0.0) - 0.2, a["t_st"][-1] + 0.2)
    last, back = silence(a)
    for a_ in ax:
        a_.axvspan(last, back, color="C3", alpha=0.12, lw=0, zorder=0)
    ax[0].text(0.5 * (last + back), ax[0].get_ylim()[1], "master silent", ha="center",
               va="bottom", fontsize=8, color="C3")
    fig.suptitle("athenakin.ros2: a session recorded from the graph (RecorderNode, MCAP)")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)


def main() -> None:
    """Record the session, print its numbers, draw the figure."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--out", type=Path, default=ROOT / "docs" / "figures" / "ros2_session.png")
    p.add_argument("--mcap", type=Path, help="keep the recording here (default: a temp file)")
    p.add_argument("--rate", type=float, default=200.0, help="teleop rate, Hz (200)")
    args = p.parse_args()
    print(_load())
    with tempfile.TemporaryDirectory() as tmp:
        mcap = args.mcap or Path(tmp) / "session.mcap"
        t = time.perf_counter()
        warm_up(args.rate)
        print(f"warmed up in {time.perf_counter() - t:.1f} s")
        t = time.perf_counter()
        counts = record(mcap, args.rate)
        print(f"recorded {mcap} in {time.perf_counter() - t:.1f} s ({_load()}):")
        for k, v in counts.items():
            print(f"  {k}: {v}")
        a = session_arrays(read_session(mcap))
        for k, v in numbers(a).items():
            print(f"{k}: {v:.6g}")
        draw(a, args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
