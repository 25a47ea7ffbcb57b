"""The ROS 2 nodes' message conversions and set-up, in one process (no graph needed)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="the extra 'ros2' (the ROS 2 client wheels) is not installed")

from geometry_msgs.msg import PoseStamped  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402

import athenakin as ak  # noqa: E402
from athenakin.errors import InvalidInputError  # noqa: E402
from athenakin.ros2 import crtk_types  # noqa: E402
from athenakin.ros2._arm_node import _rotation_rate, check_namespace  # noqa: E402
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
    np.testing.assert_allclose(_rotation_rate(np.eye(3), R1, dt), [0, 0, a / dt], rtol=1e-12,
                               atol=1e-9)
    np.testing.assert_array_equal(_rotation_rate(np.eye(3), np.eye(3), dt), [0, 0, 0])


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
