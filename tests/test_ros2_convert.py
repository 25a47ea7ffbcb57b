"""The ROS 2 nodes' message conversions and set-up, in one process (no graph needed)."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="the extra 'ros2' (the ROS 2 client wheels) is not installed")

from geometry_msgs.msg import PoseStamped  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402

import athenakin as ak  # noqa: E402
from athenakin.errors import InvalidInputError  # noqa: E402
from athenakin.ros2 import crtk_types  # noqa: E402
from athenakin.ros2._arm_node import check_namespace  # noqa: E402
from athenakin.ros2._arm_state import rotation_rate  # noqa: E402
from athenakin.ros2._convert import actuator_command, pose_stamped, tip_command  # noqa: E402


def test_actuator_command_by_name_and_order():
    q, v, e = actuator_command(JointState(name=["q3", "q1", "q2"], position=[3.0, 1.0, 2.0],
                                          velocity=[0.3, 0.1, 0.2]))
    np.testing.assert_array_equal(q, [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(v, [0.1, 0.2, 0.3])
    assert e is None
    q, v, e = actuator_command(JointState(position=[1.0, 2.0, 3.0]))
    assert v is None and e is None


@pytest.mark.parametrize("msg, word", [
    (JointState(position=[float("nan"), 0.0, 0.0]), "position"),
    (JointState(position=[0.0, 0.0]), "position"),
    (JointState(position=[0.0, 0.0, 0.0], effort=[1.0]), "effort"),
    (JointState(position=[0.0, 0.0, 0.0], velocity=[0.0, float("inf"), 0.0]), "velocity"),
    (JointState(name=["a", "b", "c"], position=[0.0, 0.0, 0.0]), "name"),
])
def test_actuator_command_refuses_by_name(msg, word):
    with pytest.raises(InvalidInputError, match=rf"\b{word}\b"):
        actuator_command(msg)


def test_tip_command_frames():
    m = PoseStamped()
    m.pose.position.x, m.pose.position.y, m.pose.position.z = 0.1, 0.2, 0.3
    frames = {"": "base", "base": "base", "rcm": "rcm"}
    for fid, want in (("", "base"), ("base", "base"), ("rcm", "rcm")):
        m.header.frame_id = fid
        tip, frame = tip_command(m, frames)
        assert frame == want and tip.tolist() == [0.1, 0.2, 0.3]
    m.header.frame_id = "world"
    with pytest.raises(InvalidInputError, match=r"\bframe_id\b"):
        tip_command(m, frames)
    m.header.frame_id = "base"
    m.pose.orientation.x, m.pose.orientation.w = 0.6, 0.8           # any unit quaternion
    assert tip_command(m, frames)[0].tolist() == [0.1, 0.2, 0.3]
    for xyzw in ((0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 2.0), (math.nan, 0.0, 0.0, 1.0)):
        o = m.pose.orientation
        o.x, o.y, o.z, o.w = xyzw                 # an unfilled, a scaled, a NaN orientation
        with pytest.raises(InvalidInputError, match=r"orientation: expected a unit quaternion"):
            tip_command(m, frames)


def test_pose_stamped_carries_the_rotation():
    d = ak.Design.default()
    sol = ak.forward_kinematics([-0.1, 0.1, 0.45], ak.default_rcm_frame(d), d)
    T = sol.T_b_tip[0]
    o = pose_stamped(T, "base").pose.orientation
    x, y, z, w = o.x, o.y, o.z, o.w
    R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    np.testing.assert_allclose(R, T[:3, :3], rtol=0, atol=1e-12)


def test_rotation_rate_of_a_known_turn():
    a, dt = 0.01, 0.002
    R1 = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    np.testing.assert_allclose(rotation_rate(np.eye(3), R1, dt), [0, 0, a / dt], rtol=1e-12,
                               atol=1e-9)
    np.testing.assert_array_equal(rotation_rate(np.eye(3), np.eye(3), dt), [0, 0, 0])


@pytest.mark.parametrize("ns, want", [("/athena", "/athena"), ("athena/", "/athena"),
                                      ("/PSM1", "/PSM1"), ("/a/b_2", "/a/b_2")])
def test_namespaces(ns, want):
    assert check_namespace(ns) == want


@pytest.mark.parametrize("ns", ["/1abc", "/a b", "/a//b", "/a-b"])
def test_bad_namespace_is_named(ns):
    with pytest.raises(ValueError, match=r"\bnamespace\b"):
        check_namespace(ns)


def test_crtk_types_carry_the_text_and_state():
    c = crtk_types()
    assert c.text(c.string("enable")) == "enable"
    msg = c.state("ENABLED", is_homed=True, is_busy=False)
    assert (msg.state if c.native else msg.data) == "ENABLED"
    stand_in = crtk_types(native=False)
    assert not stand_in.native and stand_in.text(stand_in.string("pause")) == "pause"


def test_use_sim_time_stamps_from_clock(monkeypatch):
    """With ``use_sim_time`` the arm node's stamps are ``/clock``'s (one process, loopback)."""
    import os
    import time

    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rosgraph_msgs.msg import Clock

    from athenakin.ros2 import ArmNode, RosContext

    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    domain = 1 + (os.getpid() + 50) % 100
    node = ArmNode(enable=True, use_sim_time=True,
                   context=RosContext(domain_id=domain), publish_rate=100.0)
    node.start()
    client_ctx = RosContext(domain_id=domain)
    try:
        c = rclpy.create_node("clock_source", context=client_ctx.context)
        ex = SingleThreadedExecutor(context=client_ctx.context)
        ex.add_node(c)
        got: list = []
        c.create_subscription(JointState, "/athena/measured_js", got.append, 10)
        clock = c.create_publisher(Clock, "/clock", 10)
        msg = Clock()
        msg.clock.sec = 4242
        end = time.monotonic() + 120
        while time.monotonic() < end and not any(m.header.stamp.sec == 4242 for m in got):
            clock.publish(msg)
            ex.spin_once(timeout_sec=0.02)
        assert any(m.header.stamp.sec == 4242 for m in got)
    finally:
        node.close()
        node.context.close()
        client_ctx.close()


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "numpy"])
def test_state_messages_carry_the_reference_kinematics(compiled):
    """The arm node's state messages, filled in place from one FK per state, hold the
    reference's numbers: the tip frames of the slot (position and orientation), the tip
    Jacobian times the measured velocity, the URDF joint values; nothing where the
    measured position does not assemble in the slot. Filled in two parts (the joint
    states, then the poses), the first touches no pose."""
    from athenakin._backend import numba_available

    if compiled and not numba_available():
        pytest.skip("the compiled kernels do not run here (numba missing or ATHENAKIN_BACKEND)")
    from builtin_interfaces.msg import Time

    from athenakin.analysis import tool_tip_jacobian
    from athenakin.ros._frames import joint_values, quaternion_xyzw, urdf_model
    from athenakin.ros2._arm_state import StateMessages
    from athenakin.teleop import JointState as ArmState
    from athenakin.testing import assert_allclose_scaled

    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    urdf = urdf_model(d, T)
    m = StateMessages(T, d, 0, urdf, dt=1e-3, compiled=compiled)
    rng = np.random.default_rng(38)
    q0 = np.array([-0.1, 0.1, 0.45])
    sq = q0.copy()
    for k in range(40):
        q = q0 + rng.normal(scale=0.01, size=3)
        if k % 10 == 9:
            q[2] = 2.0                     # beyond the stroke: does not assemble
        if k % 3:                          # else the setpoint stays (its pose is kept)
            sq = q0 + rng.normal(scale=0.01, size=3)
        qd, f = rng.normal(scale=0.05, size=3), rng.normal(size=3)
        js, sp, stamp = ArmState(0.0, q, qd, f), ArmState(0.0, sq, 0 * qd, f), Time(sec=7,
                                                                                  nanosec=k)
        if k % 2:
            ok = m.fill(js, sp, stamp)
        else:               # the joint states first (published before any kinematics) ...
            before = [_numbers(msg) for msg in (m.measured_cp, m.setpoint_cp, m.measured_cv,
                                                m.urdf_joint_states)]
            m.fill_joints(js, sp, stamp)
            np.testing.assert_array_equal(m.measured_js.position, q)
            for b, msg in zip(before, (m.measured_cp, m.setpoint_cp, m.measured_cv,
                                       m.urdf_joint_states), strict=True):
                np.testing.assert_array_equal(_numbers(msg), b)     # ... no pose touched
            ok = m.fill_poses(js, sp)
        assert m.measured_cp.header.stamp.nanosec == k == m.urdf_joint_states.header.stamp.nanosec
        np.testing.assert_array_equal(m.measured_js.position, q)
        np.testing.assert_array_equal(m.measured_js.velocity, qd)
        np.testing.assert_array_equal(m.setpoint_js.position, sq)
        for msg, x in ((m.measured_cp, q), (m.setpoint_cp, sq)):
            sol = ak.robot.forward_kinematics(x, T, d, errors="flag")
            ref = sol.T_b_tip[0]
            p, o = msg.pose.position, msg.pose.orientation
            got = np.array([p.x, p.y, p.z, o.x, o.y, o.z, o.w])
            want = np.concatenate([ref[:3, 3], quaternion_xyzw(ref[None, :3, :3],
                                                               backend="numpy")[0]])
            if not sol.valid[0]:
                assert np.isnan(got).all()
                continue
            assert_allclose_scaled(got[:3], want[:3], rtol=1e-14)
            assert_allclose_scaled(got[3:], want[3:], rtol=1e-14)
        sol = ak.robot.forward_kinematics(q, T, d, errors="flag")
        assert ok == bool(sol.valid[0])
        if not ok:
            continue
        lin = m.measured_cv.twist.linear
        J = tool_tip_jacobian(q, T, d, mode=1, backend="numpy")
        assert_allclose_scaled([lin.x, lin.y, lin.z], J @ qd, rtol=1e-12)
        jv = joint_values(urdf, q[None], sol.p[:1], sol.u[:1], sol.T_b_s[0, :3, 3][None])
        assert list(m.urdf_joint_states.name) == list(jv)
        assert_allclose_scaled(m.urdf_joint_states.position, [v[0] for v in jv.values()],
                               rtol=1e-13, scale=np.pi)


def test_a_motion_command_outside_enabled_is_the_arms_own_refusal(monkeypatch):
    """The node adds no state check of its own: outside ``ENABLED`` the arm holds a motion
    command and names why, the node answers that on ``status``, and nothing moves; once
    enabled (a ``state_command``) the same command is taken."""
    import os

    pytest.importorskip("mujoco", reason="the arm node serves the MuJoCo arm (extra 'sim')")
    from std_msgs.msg import String

    from athenakin.ros2 import ArmNode, RosContext

    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    node = ArmNode(context=RosContext(domain_id=1 + (os.getpid() + 30) % 100))
    try:
        before = node.arm.setpoint_js().position
        goal = [-0.1, 0.1, 0.451]
        node._on_servo_jp(JointState(position=goal))
        node._on_move_jp(JointState(position=goal))
        assert node.refusals == [("servo_jp", "held: servo_jp: the arm is DISABLED"),
                                 ("move_jp", "held: move_jp: the arm is DISABLED")]
        np.testing.assert_array_equal(node.arm.setpoint_js().position, before)
        state = node.crtk.string_stamped
        node._on_state_command(state(string="enable") if node.crtk.native
                               else String(data="enable"))
        node._on_servo_jp(JointState(position=goal))
        assert len(node.refusals) == 2 and node.arm.operating_state == "ENABLED"
        np.testing.assert_array_equal(node.arm.setpoint_js().position, goal)
    finally:
        node.close()
        node.context.close()


def _numbers(msg):
    """The float fields of a pose, twist or joint-state message (NaN kept), in one array."""
    if hasattr(msg, "pose"):
        p, o = msg.pose.position, msg.pose.orientation
        return np.array([p.x, p.y, p.z, o.x, o.y, o.z, o.w])
    if hasattr(msg, "twist"):
        a, b = msg.twist.linear, msg.twist.angular
        return np.array([a.x, a.y, a.z, b.x, b.y, b.z])
    return np.array(msg.position, dtype=float)


def test_a_state_topic_without_a_reader_is_neither_filled_nor_published(monkeypatch):
    """publish_once sends each state topic that has a subscription matched; with no reader
    of the poses (their twist, the URDF joints) it runs no kinematics, and the next twist
    after such cycles has no rotation before it (zero angular rate, as the first one)."""
    import os
    import time

    import rclpy
    from geometry_msgs.msg import TwistStamped

    pytest.importorskip("mujoco", reason="the arm node serves the MuJoCo arm (extra 'sim')")
    from athenakin.ros2 import ArmNode, RosContext

    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    domain = 1 + (os.getpid() + 70) % 100
    node = ArmNode(enable=True, context=RosContext(domain_id=domain))
    client_ctx = RosContext(domain_id=domain)
    calls = []
    fill_poses = node._state.fill_poses
    monkeypatch.setattr(node._state, "fill_poses",
                        lambda *a: calls.append(1) or fill_poses(*a))
    try:
        c = rclpy.create_node("reader", context=client_ctx.context)

        def matched(name):
            end = time.monotonic() + 120
            while node._pubs[name].get_subscription_count() == 0:
                assert time.monotonic() < end, f"no reader of {name} matched"
                time.sleep(0.01)

        c.create_subscription(JointState, "/athena/measured_js", lambda m: None, 10)
        matched("measured_js")
        node._state._prev_R = np.eye(3)              # as after a cycle with its kinematics
        node.publish_once()
        assert calls == [] and node._state._prev_R is None
        c.create_subscription(TwistStamped, "/athena/measured_cv", lambda m: None, 10)
        matched("measured_cv")
        node.publish_once()
        assert calls == [1]
        assert node._state.measured_cv.twist.angular.x == 0.0      # no rotation before it
        assert node._state._prev_R is not None
    finally:
        node.close()
        node.context.close()
        client_ctx.close()
