"""The ROS 2 nodes against real nodes: rclpy and Fast DDS, each node in its own process.

The arm node and the teleop node are started through the CLI (``athenakin ros2 arm``,
``athenakin ros2 teleop``) in subprocesses; the test talks to them with a plain rclpy
node of its own that shares no code with ``athenakin.ros2`` (its own QoS, its own
message handling). Discovery stays on this machine: every process runs with
``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` and a ``ROS_DOMAIN_ID`` of this test run
(from the pid, 1 to 100). Waits follow readiness (a condition polled while spinning,
with a generous deadline), never a fixed sleep.
"""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="the extra 'ros2' (the ROS 2 client wheels: ros-rclpy, "
                                    "ros-rmw-fastrtps-cpp) is not installed for this Python")
pytest.importorskip("mujoco", reason="the arm node serves the MuJoCo arm (extra 'sim')")

from _ros2_graph import DEADLINE, RELIABLE, Client, start, stop  # noqa: E402
from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
from geometry_msgs.msg import PoseStamped  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402
from sensor_msgs.msg import JointState, Joy  # noqa: E402
from std_msgs.msg import Bool, String  # noqa: E402

import athenakin as ak  # noqa: E402
from athenakin.sim import urdf_from_design  # noqa: E402

try:                                   # CRTK's own types where crtk_msgs is built
    from crtk_msgs.msg import OperatingState, StringStamped  # noqa: E402

    def _text(msg):
        return msg.string

    def _state(msg):
        return msg.state

    def _command(text):
        return StringStamped(string=text)
except ImportError:                     # the nodes' std_msgs stand-ins
    OperatingState = StringStamped = String

    def _text(msg):
        return msg.data

    def _state(msg):
        return msg.data

    def _command(text):
        return String(data=text)

Q0 = (-0.1, 0.1, 0.45)
RATE = 200.0              # the teleop node's rate in these tests, Hz
WATCHDOG = 0.03           # TeleopOptions' default, s
A_MAX = 2.0               # TeleopOptions' default a_max, m/s^2
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)


DOMAIN = 1 + os.getpid() % 100


def _start(args):
    return start(args, DOMAIN)


@pytest.fixture(scope="module")
def nodes():
    """The arm node and the teleop node (in their own processes), and the test's client."""
    arm = _start(["arm", "--enable", "--publish-rate", "100"])
    teleop = _start(["teleop", "--namespace", "/tele", "--q0", *map(str, Q0),
                     "--rate", str(RATE), "--status-every", "1", "--filter", "none"])
    e2e = _start(["teleop", "--with-arm", "--namespace", "/e2e", "--pose-topic",
                  "/e2e_master/pose", "--clutch-topic", "none", "--rate", "500"])
    replay = _start(["teleop", "--clock", "master", "--namespace", "/replay", "--pose-topic",
                     "/replay_master/pose", "--clutch-topic", "none", "--q0", *map(str, Q0),
                     "--rate", "1000"])
    client = Client(DOMAIN)
    try:
        yield arm, teleop, client, e2e, replay
    finally:
        client.close()
        out = stop(arm) + stop(teleop) + stop(e2e) + stop(replay)
        assert "Traceback" not in out, out


def _servo_at(msgs, stamp):
    """The servo_jp message of ``msgs`` stamped ``stamp`` (None: not received yet)."""
    return next((m for m in reversed(msgs) if m.header.stamp.sec == stamp.sec
                 and m.header.stamp.nanosec == stamp.nanosec), None)


def _ns(stamp):
    """A header stamp in nanoseconds."""
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def _tip(msg):
    p = msg.pose.position
    return np.array([p.x, p.y, p.z])


# --------------------------------------------------------------------------- the arm node
def test_servo_a_trajectory_and_read_it_back(nodes):
    arm, _, c, _, _ = nodes
    c.listen("js", JointState, "/athena/measured_js")
    c.listen("cp", PoseStamped, "/athena/measured_cp")
    c.listen("state", OperatingState, "/athena/operating_state", LATCHED)
    servo = c.node.create_publisher(JointState, "/athena/servo_jp", RELIABLE)
    c.until(lambda: c.got["js"] and c.got["state"] and servo.get_subscription_count() > 0,
            "measured_js, operating_state and a servo_jp subscriber", procs=[arm])
    assert _state(c.got["state"][-1]) == "ENABLED"
    T, d = ak.default_rcm_frame(ak.Design.default()), ak.Design.default()
    q0 = np.array(Q0)
    path = [q0 + 0.004 * np.array([math.sin(s), 1 - math.cos(s), 0.5 * math.sin(2 * s)])
            for s in np.linspace(0.0, math.pi, 40)]
    for q in path:                      # 40 setpoints, each after the arm's next state
        n = len(c.got["js"])
        servo.publish(JointState(name=["q1", "q2", "q3"], position=[float(v) for v in q]))
        c.until(lambda n=n: len(c.got["js"]) > n, "the next measured_js", procs=[arm])
    goal = path[-1]
    c.until(lambda: np.abs(np.array(c.got["js"][-1].position) - goal).max() < 2e-5,
            "the arm at the trajectory's end", procs=[arm])
    # every measured_cp is the reference FK of the measured_js of the same stamp
    by_stamp = {(m.header.stamp.sec, m.header.stamp.nanosec): m for m in c.got["js"]}
    pairs = [(by_stamp[k], cp) for cp in c.got["cp"]
             if (k := (cp.header.stamp.sec, cp.header.stamp.nanosec)) in by_stamp]
    assert len(pairs) >= 40
    for js, cp in pairs:
        assert cp.header.frame_id == "base"
        sol = ak.forward_kinematics(np.array(js.position), T, d)
        ref = sol.T_b_tip[0, :3, 3]          # the arm's slot: q0's FK slot 0
        scale = max(1.0, float(np.linalg.norm(ref)))
        np.testing.assert_allclose(_tip(cp), ref, rtol=0, atol=1e-9 * scale)


def test_a_refused_command_is_answered_and_not_executed(nodes):
    arm, _, c, _, _ = nodes
    status = c.listen("status", StringStamped, "/athena/status")
    c.listen("sp", JointState, "/athena/setpoint_js")
    servo = c.node.create_publisher(JointState, "/athena/servo_jp", RELIABLE)
    move = c.node.create_publisher(JointState, "/athena/move_jp", RELIABLE)
    cp = c.node.create_publisher(PoseStamped, "/athena/servo_cp", RELIABLE)
    c.until(lambda: c.got["sp"] and servo.get_subscription_count() > 0
            and move.get_subscription_count() > 0 and cp.get_subscription_count() > 0
            and status.get_publisher_count() > 0,
            "setpoint_js and the command subscribers", procs=[arm])
    before = np.array(c.got["sp"][-1].position)
    servo.publish(JointState(position=[float("nan"), 0.1, 0.45]))
    move.publish(JointState(position=[-0.1, 0.1, 5.0]))             # far beyond the stroke
    wrong = PoseStamped()
    wrong.header.frame_id = "world"
    cp.publish(wrong)
    # finite commands the arm holds and flags (its refusal), answered as refusals too
    servo.publish(JointState(position=[-0.1, 0.1, 0.9]))           # q3 past its stroke
    servo.publish(JointState(position=list(before), effort=[1e6, 0.0, 0.0]))   # 1 MN
    c.until(lambda: len(c.got["status"]) >= 5, "five refusals on status", procs=[arm])
    texts = [_text(m) for m in c.got["status"]]
    assert any(t.startswith("refused servo_jp: held:") and "stroke" in t for t in texts), texts
    assert any(t.startswith("refused servo_jp: held:") and "max_force" in t
               for t in texts), texts
    assert any(t.startswith("refused servo_jp:") and "position" in t for t in texts), texts
    assert any(t.startswith("refused move_jp:") and "stroke" in t for t in texts), texts
    assert any(t.startswith("refused servo_cp:") and "frame_id" in t for t in texts), texts
    n = len(c.got["sp"])
    c.until(lambda: len(c.got["sp"]) > n + 5, "more setpoint_js", procs=[arm])
    np.testing.assert_allclose(np.array(c.got["sp"][-1].position), before, rtol=0, atol=1e-12)
    assert arm.poll() is None


def _same_xml(a, b, path="robot"):
    assert a.tag == b.tag, path
    assert set(a.attrib) == set(b.attrib), path
    for k, va in a.attrib.items():
        vb = b.attrib[k]
        try:
            fa, fb = np.array(va.split(), float), np.array(vb.split(), float)
        except ValueError:
            assert va == vb, (path, k)
        else:
            np.testing.assert_allclose(fa, fb, rtol=1e-12, atol=1e-12, err_msg=f"{path}@{k}")
    assert len(a) == len(b), path
    for ca, cb in zip(a, b, strict=True):
        _same_xml(ca, cb, f"{path}/{ca.tag}[{ca.get('name', '')}]")


def test_robot_description_and_every_urdf_joint(nodes):
    arm, _, c, _, _ = nodes
    c.listen("urdf", String, "/robot_description", LATCHED)
    c.listen("joints", JointState, "/joint_states")
    c.until(lambda: c.got["urdf"] and c.got["joints"], "/robot_description and /joint_states",
            procs=[arm])
    d = ak.Design.default()
    ref = ET.fromstring(urdf_from_design(ak.default_rcm_frame(d), d))
    got = ET.fromstring(c.got["urdf"][0].data)
    _same_xml(got, ref)
    moving = {j.get("name"): j for j in ref.iter("joint") if j.get("type") != "fixed"}
    msg = c.got["joints"][-1]
    assert set(msg.name) == set(moving) and len(msg.position) == len(msg.name)
    value = dict(zip(msg.name, msg.position, strict=True))
    assert all(math.isfinite(v) for v in value.values())
    for name, j in moving.items():        # the <mimic> joints agree with their masters
        m = j.find("mimic")
        if m is not None:
            want = float(m.get("multiplier", "1")) * value[m.get("joint")] + \
                float(m.get("offset", "0"))
            assert abs(value[name] - want) <= 1e-12 * max(1.0, abs(want)), name


def test_the_arm_node_stamps_from_clock_with_use_sim_time(nodes):
    """``--use-sim-time``: the state's stamps follow ``/clock`` (the events executor takes it)."""
    from builtin_interfaces.msg import Time
    from rosgraph_msgs.msg import Clock

    _, _, c, _, _ = nodes
    sim = _start(["arm", "--use-sim-time", "--namespace", "/simtime", "--publish-rate", "100"])
    try:
        clock = c.node.create_publisher(Clock, "/clock", RELIABLE)
        c.listen("simtime", JointState, "/simtime/measured_js")
        for sec in (1000, 2000):           # a simulator's clock, far from the system's
            def stamped(sec=sec):
                clock.publish(Clock(clock=Time(sec=sec, nanosec=250_000_000)))
                got = c.got["simtime"]
                return bool(got) and got[-1].header.stamp.sec == sec
            c.until(stamped, f"a measured_js stamped {sec} s from /clock", procs=[sim])
            last = c.got["simtime"][-1].header.stamp
            assert (last.sec, last.nanosec) == (sec, 250_000_000)
        assert all(m.header.stamp.sec in (0, 1000, 2000) for m in c.got["simtime"])
    finally:
        out = stop(sim)
    assert "Traceback" not in out, out


def test_the_arm_node_steps_on_each_servo_command_with_sync_command(nodes):
    """``--sync command``: each servo_jp starts a servo cycle, and the state shows it."""
    import re

    _, _, c, _, _ = nodes
    sync = _start(["arm", "--enable", "--sync", "command", "--namespace", "/sync",
                   "--publish-rate", "1000"])
    n = 30
    try:
        c.listen("sync_sp", JointState, "/sync/setpoint_js")
        servo = c.node.create_publisher(JointState, "/sync/servo_jp", RELIABLE)
        c.until(lambda: c.got["sync_sp"] and servo.get_subscription_count() > 0,
                "the /sync arm's setpoint_js and its servo_jp subscriber", procs=[sync])
        for k in range(1, n + 1):          # each after the previous one showed
            q = [Q0[0], Q0[1], Q0[2] + 1e-5 * k]
            servo.publish(JointState(name=["q1", "q2", "q3"], position=q))
            c.until(lambda q=q: np.allclose(c.got["sync_sp"][-1].position, q, rtol=0,
                                            atol=1e-12),
                    f"servo_jp {k} on /sync/setpoint_js", procs=[sync])
    finally:
        out = stop(sync)
    assert "Traceback" not in out, out
    m = re.search(r"(\d+) cycles, (\d+) late, (\d+) on a command, (\d+) commands, "
                  r"(\d+) refused", out)
    assert m, out
    cycles, _, synced, commands, refused = map(int, m.groups())
    assert (commands, refused) == (n, 0)
    # one cycle per command (two that came within one cycle's window would share one)
    assert n // 2 <= synced <= n <= cycles


# ------------------------------------------------------------------------ the teleop node
def _values(arr):
    return {kv.key: kv.value for kv in arr.status[0].values}


def test_teleop_follows_the_master_and_the_watchdog_holds(nodes):
    _, teleop, c, _, _ = nodes
    c.listen("servo", JointState, "/tele/servo_jp")
    c.listen("tstatus", DiagnosticArray, "/tele/teleop/status")
    pose = c.node.create_publisher(PoseStamped, "/master/pose", RELIABLE)
    joy = c.node.create_publisher(Joy, "/master/joy", RELIABLE)
    estop = c.node.create_publisher(Bool, "/tele/teleop/estop", RELIABLE)
    c.until(lambda: c.got["servo"] and pose.get_subscription_count() > 0
            and joy.get_subscription_count() > 0 and estop.get_subscription_count() > 0,
            "servo_jp from the teleop node and its master subscribers", procs=[teleop])
    joy.publish(Joy(buttons=[0]))                  # clutch closed: the tip follows
    for k in range(60):                            # the master moves 6 mm, one sample a cycle
        m = PoseStamped()
        m.pose.position.x = 1e-4 * k
        pose.publish(m)
        n = len(c.got["tstatus"])
        c.until(lambda n=n: len(c.got["tstatus"]) > n, "the next teleop status",
                procs=[teleop])
    c.until(lambda: _values(c.got["tstatus"][-1])["watchdog"] == "True", "the watchdog",
            procs=[teleop])
    st = [_values(a) for a in c.got["tstatus"]]
    cycles = [int(v["cycle"]) for v in st]
    first = next(i for i, v in enumerate(st) if v["watchdog"] == "True"
                 and i > 0 and st[i - 1]["watchdog"] == "False")
    # the watchdog trips in consecutive cycles of the loop, after the master stopped, and
    # no cycle whose sample is older than the watchdog's time goes unheld (it counts
    # cycles without a new sample: a loop catching up trips it early, never late)
    assert cycles[first - 1] == cycles[first] - 1
    assert all(v["watchdog"] == "True" for v in st[first:]
               if float(v["sample_age_s"]) > WATCHDOG)
    assert "HOLD" in st[first]["names"]
    # the bodies are checked by default: every cycle reports their least clearance
    clear = [float(v["clearance_m"]) for v in st]
    assert all(math.isfinite(x) and x > 0 for x in clear), clear[:5]
    # while the master ran, the tip followed it (no watchdog, moving commands)
    following = [v for v in st[:first] if v["watchdog"] == "False"]
    assert following and all(v["estop"] == "False" for v in following)
    servo = c.got["servo"]
    assert all(len(m.position) == 3 and len(m.velocity) == 3 and len(m.effort) == 3
               for m in servo)
    moved = np.ptp(np.array([m.position for m in servo]), axis=0).max()
    assert moved > 1e-5
    # held, then the master back 4 cm away: it re-engages without a jump of the commanded
    # tip. The check needs the statuses of the last held cycle and the re-engaging one; on a
    # loaded machine the node's status queue (keep last 100) can drop cycles while a reader
    # lags, so the hold and the return are repeated until both arrive (at most 5 times)
    for attempt in range(5):
        c.until(lambda: _values(c.got["tstatus"][-1])["watchdog"] == "True"
                and np.abs(np.array(c.got["servo"][-1].velocity)).max() == 0.0,
                "the held command at rest", procs=[teleop])
        held = len(c.got["tstatus"])
        x = 0.05 if attempt % 2 == 0 else 0.01

        def back(x=x, held=held):
            m = PoseStamped()
            m.pose.position.x = x
            pose.publish(m)
            return any(_values(a)["watchdog"] == "False" for a in c.got["tstatus"][held:])

        c.until(back, "the master's return", procs=[teleop])
        arrays = list(c.got["tstatus"])
        st = [_values(a) for a in arrays]
        i = next(k for k in range(held, len(st)) if st[k]["watchdog"] == "False")
        if (st[i - 1]["watchdog"] == "True"
                and int(st[i]["cycle"]) == int(st[i - 1]["cycle"]) + 1):
            break
    else:
        pytest.fail("5 returns of the master, each with the statuses around the "
                    "re-engagement dropped")
    before, after = (np.array(st[k]["tip_b"].split(), float) for k in (i - 1, i))
    # the servo_jp of the last held cycle (the same stamp as its status; or the last one
    # before it, where the stream dropped it likewise)
    stamp = arrays[i - 1].header.stamp
    c.until(lambda: any(_ns(m.header.stamp) >= _ns(stamp) for m in c.got["servo"]),
            "the servo_jp stream past the last held cycle", procs=[teleop])
    held_cmd = [m for m in c.got["servo"] if _ns(m.header.stamp) <= _ns(stamp)][-1]
    if not np.any(np.array(held_cmd.velocity)):
        # from rest: the commanded tip does not move in the re-engaging cycle
        np.testing.assert_allclose(after, before, rtol=0,
                                   atol=1e-12 * max(1.0, np.abs(before).max()))
    else:
        # a master sample delayed past the watchdog (a loaded machine) re-engaged while the
        # robot still braked: the command goes on from its velocity, within one cycle's
        # acceleration limit (no jump), never toward the master's new position at once
        engaged = _servo_at(c.got["servo"], arrays[i].header.stamp)
        assert engaged is not None
        dq = np.abs(np.array(engaged.position) - np.array(held_cmd.position))
        dt = 1.0 / RATE
        assert np.all(dq <= np.abs(np.array(held_cmd.velocity)) * dt + A_MAX * dt * dt + 1e-12)
    # a NaN master sample is INVALID, a Joy without the clutch button is refused by name
    seen = len(c.got["tstatus"])
    m = PoseStamped()
    m.pose.position.y = float("nan")
    pose.publish(m)
    joy.publish(Joy(buttons=[]))
    c.until(lambda: any("INVALID" in _values(a)["names"] for a in c.got["tstatus"][seen:])
            and any("button 0" in _values(a)["refused"] for a in c.got["tstatus"][seen:]),
            "INVALID and the refused clutch", procs=[teleop])
    assert teleop.poll() is None
    # an e-stop latches ESTOP, also when the master comes back
    estop.publish(Bool(data=True))
    c.until(lambda: _values(c.got["tstatus"][-1])["estop"] == "True", "ESTOP", procs=[teleop])
    m = PoseStamped()
    pose.publish(m)
    n = len(c.got["tstatus"])
    c.until(lambda: len(c.got["tstatus"]) > n + 5, "more teleop status", procs=[teleop])
    assert _values(c.got["tstatus"][-1])["estop"] == "True"


def test_the_arm_node_survives_a_hostile_burst(nodes):
    arm, _, c, _, _ = nodes
    status = c.listen("fuzz_status", StringStamped, "/athena/status")
    c.listen("fuzz_js", JointState, "/athena/measured_js")
    servo = c.node.create_publisher(JointState, "/athena/servo_jp", RELIABLE)
    state = c.node.create_publisher(StringStamped, "/athena/state_command", RELIABLE)
    c.until(lambda: c.got["fuzz_js"] and servo.get_subscription_count() > 0
            and state.get_subscription_count() > 0 and status.get_publisher_count() > 0,
            "measured_js, the subscribers and the status publisher", procs=[arm])
    # the arm's reader has matched this writer once a probe is answered (DDS matches each
    # side on its own: a writer that sees the reader may still be unseen by it)
    probe = JointState(position=[float("nan")] * 3)
    c.until(lambda: servo.publish(probe) or c.got["fuzz_status"], "the probe's refusal",
            procs=[arm])
    del c.got["fuzz_status"][:]
    q = np.array(c.got["fuzz_js"][-1].position)
    rng = np.random.default_rng(38)
    bad = 0
    for k in range(60):        # one burst, no wait between the messages (within QoS depths)
        m = JointState(position=[float(v) for v in q + rng.uniform(-1e-4, 1e-4, 3)])
        kind = k % 6
        if kind == 1:
            m.position = [float("nan"), 0.0, float("inf")]
        elif kind == 2:
            m.position = m.position[:2]
        elif kind == 3:
            m.name = ["q1", "q2", "elbow"]
        elif kind == 4:                    # a stamp before the previous command's
            m.header.stamp.sec = 1
        elif kind == 5:
            m.velocity = [0.0]
        m.header.stamp.sec = m.header.stamp.sec or 10 + k
        bad += kind != 0
        servo.publish(m)
    state.publish(_command("fly"))

    def answered():
        return [t for m in c.got["fuzz_status"] if "[nan, nan, nan]" not in (t := _text(m))]

    c.until(lambda: sum(t.startswith("refused servo_jp:") for t in answered()) >= bad
            and any(t.startswith("refused state_command:") for t in answered()),
            "every refusal of the burst", procs=[arm])
    texts = answered()
    assert texts and all(t.startswith("refused ") for t in texts), texts[:5]
    fields = ("position", "name", "stamp", "velocity", "state_command")
    assert all(any(f in t for f in fields) for t in texts), texts[:5]
    assert sum(t.startswith("refused servo_jp:") for t in texts) == bad, texts
    n = len(c.got["fuzz_js"])
    c.until(lambda: len(c.got["fuzz_js"]) > n + 5, "measured_js after the burst", procs=[arm])
    assert all(math.isfinite(v) for v in c.got["fuzz_js"][-1].position)
    assert np.abs(np.array(c.got["fuzz_js"][-1].position) - q).max() < 1e-3


def test_the_teleop_node_drives_the_arm_node_over_the_graph(nodes):
    _, _, c, e2e, _ = nodes
    c.listen("e2e_js", JointState, "/e2e/measured_js")
    c.listen("e2e_servo", JointState, "/e2e/servo_jp")
    pose = c.node.create_publisher(PoseStamped, "/e2e_master/pose", RELIABLE)
    c.until(lambda: c.got["e2e_js"] and c.got["e2e_servo"] and pose.get_subscription_count() > 0,
            "the arm's measured_js and the teleop's servo_jp", procs=[e2e])
    start = np.array(c.got["e2e_js"][-1].position)
    for k in range(120):          # the master 12 mm along x, then still (samples go on)
        m = PoseStamped()
        m.pose.position.x = 1e-4 * min(k, 100)
        pose.publish(m)
        n = len(c.got["e2e_servo"])
        c.until(lambda n=n: len(c.got["e2e_servo"]) > n, "the next servo_jp", procs=[e2e])

    def settled():
        m = PoseStamped()
        m.pose.position.x = 1e-2
        pose.publish(m)             # the master held still: no watchdog
        cmd = np.array(c.got["e2e_servo"][-1].position)
        return np.abs(np.array(c.got["e2e_js"][-1].position) - cmd).max() < 1e-4

    c.until(settled, "the arm at the teleop's command", procs=[e2e])
    moved = np.abs(np.array(c.got["e2e_js"][-1].position) - start).max()
    assert moved > 5e-4             # 12 mm of master at scale 0.2: a few mm of actuator travel


def test_a_replayed_master_gives_the_commands_of_run_session(nodes):
    from athenakin.collision import Bodies
    from athenakin.teleop import Teleop, run_session

    _, _, c, _, replay = nodes
    c.listen("replay", JointState, "/replay/servo_jp")
    pose = c.node.create_publisher(PoseStamped, "/replay_master/pose", RELIABLE)
    c.until(lambda: pose.get_subscription_count() > 0, "the replay node's master subscriber",
            procs=[replay])
    ns = [1000 * 10**9 + k * 10**6 for k in range(300)]         # 1 kHz stamps, ns
    pts = [(0.02 * math.sin(math.pi * k / 1000), 0.01 * math.sin(0.6 * math.pi * k / 1000),
            0.005 * (1 - math.cos(0.4 * math.pi * k / 1000))) for k in range(300)]
    d = ak.Design.default()
    # the teleop node checks the default bodies, as the session here does
    log = run_session(Teleop(ak.default_rcm_frame(d), d, q0=Q0, rate=1000.0,
                             bodies=Bodies.default(d)), None,
                      [(t * 1e-9, p, True) for t, p in zip(ns, pts, strict=True)])

    def send(k):
        m = PoseStamped()
        m.header.stamp.sec, m.header.stamp.nanosec = divmod(ns[k], 10**9)
        m.pose.position.x, m.pose.position.y, m.pose.position.z = pts[k]
        pose.publish(m)

    # the node's reader has matched this writer once the first sample is answered (the
    # node runs no cycle on a repeated stamp)
    c.until(lambda: send(0) or c.got["replay"], "the answer to the first sample",
            procs=[replay])
    c.got["replay"][:] = c.got["replay"][:1]
    for k in range(1, 300):
        send(k)
        c.until(lambda k=k: any(m.header.stamp.nanosec == ns[k] % 10**9 and
                                m.header.stamp.sec == ns[k] // 10**9
                                for m in c.got["replay"][-3:]), "the sample's command",
                procs=[replay])
    got = {(m.header.stamp.sec, m.header.stamp.nanosec): np.array(m.position)
           for m in c.got["replay"]}
    q = np.array([got[divmod(t, 10**9)] for t in ns])
    np.testing.assert_allclose(q, log.q, rtol=0, atol=1e-12)
    assert np.ptp(log.q, axis=0).max() > 1e-4          # the commands moved


def test_the_teleop_node_survives_a_hostile_master(nodes):
    """Bursts of wrong frame ids, repeated and older stamps, NaN and inf samples and a Joy
    without the clutch button: each refused by name or flagged INVALID, a cycle for every
    accepted sample and none for a refused one, every command finite, no crash."""
    c = nodes[2]
    fuzz = _start(["teleop", "--clock", "master", "--namespace", "/fuzz", "--pose-topic",
                   "/fuzz_master/pose", "--clutch-topic", "/fuzz_master/joy",
                   "--master-frame", "master", "--q0", *map(str, Q0), "--status-every", "1",
                   "--filter", "none"])
    try:
        c.listen("fuzz_servo", JointState, "/fuzz/servo_jp")
        c.listen("fuzz_tstatus", DiagnosticArray, "/fuzz/teleop/status")
        pose = c.node.create_publisher(PoseStamped, "/fuzz_master/pose", RELIABLE)
        joy = c.node.create_publisher(Joy, "/fuzz_master/joy", RELIABLE)
        def stamp(j):                                    # (sec, nanosec) of sample j, 1 ms apart
            return divmod(2000 * 10**9 + j * 10**6, 10**9)

        def stamp_of(m):
            return (m.header.stamp.sec, m.header.stamp.nanosec)

        def msg(j, *, frame="master", xyz=(0.0, 0.0, 0.0)):
            m = PoseStamped()
            m.header.frame_id = frame
            m.header.stamp.sec, m.header.stamp.nanosec = stamp(j)
            m.pose.position.x, m.pose.position.y, m.pose.position.z = xyz
            return m

        def commanded(j):
            return any(stamp_of(m) == stamp(j) for m in c.got["fuzz_servo"])

        # the readers on both sides have matched once a sample's command and status came
        # back (a fresh stamp each try: the node runs no cycle on a repeated one)
        probes: list[int] = []

        def probe():
            probes.append(len(probes))
            pose.publish(msg(probes[-1]))

        c.until(lambda: (pose.get_subscription_count() > 0 and joy.get_subscription_count() > 0
                         and c.got["fuzz_servo"] and c.got["fuzz_tstatus"]) or probe(),
                "the command and the status of a first sample", procs=[fuzz])
        j = first = len(probes) + 10
        accepted = set()
        for r in range(3):                    # three bursts of ten, no wait inside a burst
            burst = [msg(j + 1, frame="world"),                     # refused: frame_id
                     msg(j + 1, xyz=(1e-4 * r, 0.0, 0.0)),
                     msg(j + 1),                                    # refused: repeated
                     msg(j + 2),
                     msg(j - 3),                                    # refused: older
                     msg(j + 3),
                     msg(j + 4, xyz=(float("nan"), 0.0, 0.0)),      # INVALID
                     msg(j + 5, xyz=(0.0, 0.0, float("inf"))),      # INVALID
                     msg(j + 6)]
            joy.publish(Joy(buttons=[]))                            # refused: no button 0
            for m in burst:
                pose.publish(m)
            accepted |= {j + 1, j + 2, j + 3, j + 4, j + 5, j + 6}
            j += 6
            c.until(lambda j=j: commanded(j), "the burst's last command", procs=[fuzz])
        # nine refusals before one cycle (within the reader's depth of 10): the status
        # carries the first eight and counts the ninth
        for _ in range(9):
            pose.publish(msg(j + 1, frame="world"))
        pose.publish(msg(j + 1))
        accepted.add(j + 1)
        j += 1
        end = stamp(j)
        c.until(lambda: any(stamp_of(a) == end for a in c.got["fuzz_tstatus"]),
                "the last sample's status", procs=[fuzz])
        assert fuzz.poll() is None
        start = stamp(first)
        stamps = {stamp_of(m) for m in c.got["fuzz_servo"] if stamp_of(m) > start}
        assert stamps == {stamp(k) for k in accepted}
        assert all(len(m.position) == 3 and all(math.isfinite(v) for v in m.position)
                   for m in c.got["fuzz_servo"])
        st = [_values(a) for a in c.got["fuzz_tstatus"] if stamp_of(a) > start]
        refused = " ".join(v["refused"] for v in st)
        assert "frame_id 'world'" in refused and "expected 'master'" in refused, refused
        assert "is not after the previous" in refused, refused
        assert "button 0" in refused, refused
        assert sum("INVALID" in v["names"] for v in st) == 6, [v["names"] for v in st]
        many = next(a for a in c.got["fuzz_tstatus"] if stamp_of(a) == end)
        texts = _values(many)["refused"].split("; ")
        assert texts[-1] == "and 1 more" and len(texts) == 9, texts
        assert all("frame_id 'world'" in t for t in texts[:8]), texts
    finally:
        out = stop(fuzz)
    assert "Traceback" not in out, out


def test_the_teleop_node_refuses_to_run_without_the_bodies_unless_told(capsys):
    """Safe by default: the node's core checks the bodies; turning that off takes the
    explicit opt-out, and contradictory options are refused by name before any node."""
    from athenakin.cli import main
    from athenakin.errors import InvalidInputError
    from athenakin.ros2 import TeleopNode
    from athenakin.teleop import TeleopOptions

    with pytest.raises(InvalidInputError, match="check_bodies=False"):
        TeleopNode(q0=Q0, options=TeleopOptions(check_clearance=False))
    with pytest.raises(TypeError, match="check_bodies"):
        TeleopNode(q0=Q0, check_bodies=1)
    env = Path(__file__).parent / "data" / "no_such_bodies.toml"
    assert main(["ros2", "teleop", "--q0", *map(str, Q0), "--no-bodies", "--bodies",
                 str(env), "--duration", "0.1"]) == 1
    assert "--no-bodies" in capsys.readouterr().err


@pytest.mark.parametrize("option, topic", [("--pose-topic", "bad topic"),
                                           ("--clutch-topic", "/bad topic"),
                                           ("--pose-topic", ""),
                                           ("--pose-topic", "/master//pose"),
                                           ("--clutch-topic", "master/joy/")])
def test_a_topic_name_ros_refuses_is_a_named_error(capsys, option, topic):
    """A topic name with a space (or empty) is the user's error, exit 1 with the option and
    rclpy's reason, not "a bug" (exit 70), and no node is started."""
    from athenakin.cli import main
    from athenakin.ros2 import TeleopNode

    what = option.removeprefix("--").replace("-", "_")
    with pytest.raises(ValueError, match=rf"{what}: expected a ROS topic name"):
        TeleopNode(q0=Q0, **{what: topic})
    assert main(["ros2", "teleop", "--q0", *map(str, Q0), option, topic,
                 "--duration", "0.1"]) == 1
    err = capsys.readouterr().err
    assert f"{what}: expected a ROS topic name" in err and "a bug" not in err


def test_the_teleop_node_waits_for_the_arm_no_longer_than_its_duration():
    """Without --q0 the node waits for the arm's first measured_js: at most --wait-for-arm
    s and never past --duration; with no arm on the graph it ends with the named wait, exit 1."""
    proc = _start(["teleop", "--namespace", "/nobody_here", "--duration", "0.5"])
    try:
        rc = proc.wait(timeout=DEADLINE)
    finally:
        out = stop(proc)
    assert rc == 1, out
    assert "no /nobody_here/measured_js within 0.5 s" in out and "Traceback" not in out, out
