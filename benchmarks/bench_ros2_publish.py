"""The arm node's ``publish_once`` per call: the state messages of one cycle, before and after.

Run from the repository root (the extras ``ros2`` and ``sim``; discovery stays on the
loopback)::

    python benchmarks/bench_ros2_publish.py [--calls 2000]

One :class:`athenakin.ros2.ArmNode` in this process (its threads not started) and a plain
rclpy subscriber of every state topic in its own process, so that each ``publish()``
delivers to a matched reader as on a graph. For each of ``--calls`` states of a moving
arm (one ``servo_jp`` and one ``step`` apart) it times, interleaved, the baseline (the
node's former ``publish_once``, kept here: the arm's ``measured_cp`` and ``setpoint_cp``,
a third forward kinematics, the tip Jacobian and the URDF joints through the validated
public functions, seven messages built anew) and the node's ``publish_once``, and
compares the two sets of messages of the same state (largest difference of each field,
relative to its scale). Wall time (``perf_counter``) and this thread's CPU time
(``thread_time``) per call; the machine's load beside every figure.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from _machine import load_text  # noqa: E402
from _ros2_procs import node_env  # noqa: E402

Q0 = (-0.1, 0.1, 0.45)
TOPICS = {"measured_js": "sensor_msgs/JointState", "joint_states": "sensor_msgs/JointState",
          "setpoint_js": "sensor_msgs/JointState", "measured_cp": "geometry_msgs/PoseStamped",
          "setpoint_cp": "geometry_msgs/PoseStamped",
          "measured_cv": "geometry_msgs/TwistStamped", "/joint_states": "sensor_msgs/JointState"}


def subscriber(domain: int) -> None:
    """A plain rclpy node that subscribes every state topic and spins until stdin closes."""
    import threading

    import rclpy
    from geometry_msgs.msg import PoseStamped, TwistStamped
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState

    types = {"sensor_msgs/JointState": JointState, "geometry_msgs/PoseStamped": PoseStamped,
             "geometry_msgs/TwistStamped": TwistStamped}
    ctx = Context()
    rclpy.init(context=ctx, domain_id=domain)
    node = rclpy.create_node("bench_publish_reader", context=ctx)
    qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
    for name, typ in TOPICS.items():
        topic = name if name.startswith("/") else f"/athena/{name}"
        node.create_subscription(types[typ], topic, lambda m: None, qos)
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(node)
    done = threading.Event()
    threading.Thread(target=lambda: (sys.stdin.read(), done.set()), daemon=True).start()
    while not done.is_set():
        ex.spin_once(timeout_sec=0.05)
    node.destroy_node()
    ctx.try_shutdown()


class Baseline:
    """The node's former ``publish_once``: three forward kinematics, messages built anew."""

    def __init__(self, node: object) -> None:
        self.node = node
        self.prev_R: np.ndarray | None = None

    def publish_once(self) -> dict[str, object]:
        """Publish one state as the node did; the messages, by topic key."""
        from athenakin import forward_kinematics
        from athenakin.analysis import tool_tip_jacobian
        from athenakin.ros._frames import BASE_FRAME, joint_values
        from athenakin.ros2._arm_state import rotation_rate
        from athenakin.ros2._convert import ACTUATORS, joint_state, pose_stamped, twist_stamped

        n = self.node
        arm = n.arm
        with n._lock:
            js, sp, cp, scp = (arm.measured_js(), arm.setpoint_js(), arm.measured_cp(),
                               arm.setpoint_cp())
        stamp = n._now()
        out = {"measured_js": joint_state(ACTUATORS, js.position, js.velocity, js.effort,
                                          stamp=stamp),
               "joint_states": joint_state(ACTUATORS, js.position, js.velocity, js.effort,
                                           stamp=stamp),
               "setpoint_js": joint_state(ACTUATORS, sp.position, sp.velocity, sp.effort,
                                          stamp=stamp),
               "measured_cp": pose_stamped(cp, BASE_FRAME, stamp=stamp),
               "setpoint_cp": pose_stamped(scp, BASE_FRAME, stamp=stamp)}
        q = np.asarray(js.position, dtype=float)
        sol = forward_kinematics(q, n.T_b_e, n.design, errors="flag")
        valid = np.flatnonzero(sol.valid)
        if valid.size and np.all(np.isfinite(cp)):
            err = np.linalg.norm(sol.T_b_tip[valid, :3, 3] - cp[:3, 3], axis=-1)
            k = int(valid[int(np.argmin(err))])
            J = tool_tip_jacobian(q, n.T_b_e, n.design, mode=int(sol.mode[k]))
            lin = J @ np.asarray(js.velocity, dtype=float)
            R = np.asarray(cp[:3, :3], dtype=float)
            ang = np.zeros(3) if self.prev_R is None else \
                rotation_rate(self.prev_R, R, 1.0 / n.publish_rate)
            self.prev_R = R
            out["measured_cv"] = twist_stamped(lin, ang, BASE_FRAME, stamp=stamp)
            jv = joint_values(n._urdf, q[None], sol.p[k][None], sol.u[k][None],
                              sol.T_b_s[k, :3, 3][None])
            out["/joint_states"] = joint_state(list(jv), [float(v[0]) for v in jv.values()],
                                               stamp=stamp)
        keys = {"/joint_states": "urdf_joint_states"}
        for key, msg in out.items():
            n._pubs[keys.get(key, key)].publish(msg)
        n._publish_state()
        return out


def _numbers(msg: object) -> np.ndarray:
    """Every number of a state message, in a fixed order."""
    if hasattr(msg, "position") and hasattr(msg, "effort"):          # JointState
        return np.concatenate([msg.position, msg.velocity, msg.effort])
    if hasattr(msg, "pose"):
        p, o = msg.pose.position, msg.pose.orientation
        return np.array([p.x, p.y, p.z, o.x, o.y, o.z, o.w])
    lin, ang = msg.twist.linear, msg.twist.angular
    return np.array([lin.x, lin.y, lin.z, ang.x, ang.y, ang.z])


def _new_messages(node: object) -> dict[str, object]:
    m = node._state
    return {"measured_js": m.measured_js, "joint_states": m.measured_js,
            "setpoint_js": m.setpoint_js, "measured_cp": m.measured_cp,
            "setpoint_cp": m.setpoint_cp, "measured_cv": m.measured_cv,
            "/joint_states": m.urdf_joint_states}


def _pct(x: np.ndarray) -> str:
    us = x * 1e6
    return f"p50 {np.percentile(us, 50):7.1f} us  p99 {np.percentile(us, 99):7.1f} us"


def measure(calls: int, domain: int) -> None:
    """Time and compare the two ``publish_once`` over ``calls`` states of a moving arm."""
    from athenakin.ros2 import ArmNode, RosContext

    reader = subprocess.Popen([sys.executable, __file__, "--subscribe", str(domain)],
                              env=node_env(domain), stdin=subprocess.PIPE)
    ctx = RosContext(domain_id=domain)
    node = ArmNode(q0=Q0, enable=True, publish_rate=1000.0, context=ctx)
    try:
        end = time.monotonic() + 120
        while min(p.get_subscription_count() for k, p in node._pubs.items()
                  if k in TOPICS or k == "urdf_joint_states") == 0:
            if time.monotonic() > end:
                raise SystemExit("bench: the subscriber process never matched the topics")
            time.sleep(0.05)
        base = Baseline(node)
        base.publish_once()                         # the first calls compile or load kernels
        node.publish_once()
        wall = np.empty((2, calls))
        cpu = np.empty((2, calls))
        worst: dict[str, float] = {}
        q = np.array(Q0)
        for k in range(calls):
            q[:] = Q0 + 0.004 * np.array([np.sin(k / 200), 1 - np.cos(k / 200), 0.0])
            node.arm.servo_jp(q)
            node.arm.step(1)
            for i, call in enumerate((base.publish_once, node.publish_once)):
                w, c = time.perf_counter(), time.thread_time()
                got = call()
                wall[i, k], cpu[i, k] = time.perf_counter() - w, time.thread_time() - c
                if i == 0:
                    old = got
            new = _new_messages(node)
            for key, msg in old.items():
                a, b = _numbers(msg), _numbers(new[key])
                scale = max(1.0, float(np.abs(a).max()))
                worst[key] = max(worst.get(key, 0.0), float(np.abs(a - b).max()) / scale)
    finally:
        node.close()
        ctx.close()
        reader.communicate(b"", timeout=30)
    load = load_text()
    for i, name in enumerate(("baseline (former)", "publish_once (now)")):
        print(f"{name:20s} wall {_pct(wall[i])}  CPU {_pct(cpu[i])}  ({load})")
    print(f"  now / former, p50 wall: {np.median(wall[1]) / np.median(wall[0]):.3f}  "
          f"({calls} states, 7 messages each, one matched reader in another process)")
    print("  largest difference of the same state's messages, relative to each field's "
          "scale: " + ", ".join(f"{k} {v:.1e}" for k, v in worst.items()))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--calls", type=int, default=2000, help="states to publish (2000)")
    ap.add_argument("--subscribe", type=int, metavar="DOMAIN", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.subscribe is not None:
        subscriber(args.subscribe)
        return
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    domain = int(os.environ.get("ROS_DOMAIN_ID") or 1 + os.getpid() % 100)
    measure(args.calls, domain)


if __name__ == "__main__":
    main()
