"""The recorder against real nodes: rclpy and Fast DDS, the nodes each in its own process.

The arm node and the teleop node run through the CLI (``athenakin ros2 arm``, ``athenakin
ros2 teleop``) in subprocesses; :class:`athenakin.ros2.RecorderNode` runs in this process
(and ``athenakin ros2 record`` in one of its own). The test publishes with a plain rclpy
node of its own and reads every file back with the mcap library and rosbags, never with
athenakin's reader. Discovery stays on this machine: every process runs with
``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` and a ``ROS_DOMAIN_ID`` of this test run (from the
pid, 101 to 200: not test_ros2_nodes' domains). Waits follow readiness (a condition polled
with a generous deadline), never a fixed sleep.
"""

from __future__ import annotations

import os
import signal
import struct
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="the extra 'ros2' (the ROS 2 client wheels: ros-rclpy, "
                                    "ros-rmw-fastrtps-cpp) is not installed for this Python")
pytest.importorskip("mujoco", reason="the arm node serves the MuJoCo arm (extra 'sim')")
pytest.importorskip("rosbags", reason="the extra 'ros' (rosbags, mcap) reads the files back")
pytest.importorskip("mcap_ros2", reason="the extra 'ros' (mcap-ros2-support) reads them back")

from _ros2_graph import RELIABLE, Client, node_env, start, stop  # noqa: E402
from geometry_msgs.msg import PoseStamped  # noqa: E402
from mcap.reader import make_reader  # noqa: E402
from mcap_ros2.decoder import DecoderFactory  # noqa: E402
from sensor_msgs.msg import JointState, Joy  # noqa: E402

from athenakin.errors import InvalidInputError  # noqa: E402
from athenakin.ros2 import RecorderNode, RosContext, session_topics  # noqa: E402

DOMAIN = 101 + os.getpid() % 100
NS = "/rec"               # the nodes' namespace in these tests
POSE, CLUTCH = "/rec_master/pose", "/rec_master/joy"


def _start(args):
    return start(args, DOMAIN)


@pytest.fixture(scope="module")
def graph():
    """The arm node and the teleop node (in their own processes), and the test's client."""
    arm = _start(["arm", "--enable", "--namespace", NS, "--publish-rate", "100"])
    teleop = _start(["teleop", "--namespace", NS, "--pose-topic", POSE, "--clutch-topic",
                     CLUTCH, "--rate", "200", "--status-every", "1"])
    client = Client(DOMAIN, "test_record_client")
    try:
        yield arm, teleop, client
    finally:
        client.close()
        out = stop(arm) + stop(teleop)
        assert "Traceback" not in out, out


def _read_mcap(path):
    """``topic -> [(log_time, publish_time, decoded message)]``, by the mcap library."""
    out: dict[str, list] = {}
    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        for _, ch, m, msg in reader.iter_decoded_messages(log_time_order=True):
            out.setdefault(ch.topic, []).append((m.log_time, m.publish_time, msg))
    counts = {ch.topic: summary.statistics.channel_message_counts.get(cid, 0)
              for cid, ch in summary.channels.items()}
    return out, counts


def _ns(stamp):
    return stamp.sec * 10**9 + stamp.nanosec


def _pose(k):
    m = PoseStamped()
    m.header.stamp.sec, m.header.stamp.nanosec = 2000 + k // 1000, (k % 1000) * 10**6 + 7
    m.header.frame_id = "master"
    m.pose.position.x, m.pose.position.y = 1e-4 * k, -2e-4 * k
    m.pose.position.z = 0.001 * np.sin(0.1 * k)
    m.pose.orientation.z, m.pose.orientation.w = np.sin(0.01 * k), np.cos(0.01 * k)
    return m


def _joy(k, pressed):
    m = Joy(axes=[0.25 * k, -1.0], buttons=[int(pressed), 7])
    m.header.stamp.sec, m.header.stamp.nanosec = 2000 + k // 1000, (k % 1000) * 10**6 + 9
    m.header.frame_id = "joy"
    return m


# --------------------------------------------------------------------------- the recorder
@pytest.mark.slow
def test_every_message_sent_is_recorded_as_it_was_sent(graph, tmp_path):
    arm, teleop, c = graph
    procs = [arm, teleop]
    path = tmp_path / "session.mcap"
    ctx = RosContext(domain_id=DOMAIN)
    rec = RecorderNode(path, topics=session_topics(NS, pose_topic=POSE, clutch_topic=CLUTCH),
                       namespace=NS, context=ctx).start()
    try:
        c.listen("js", JointState, f"{NS}/measured_js")
        pose = c.node.create_publisher(PoseStamped, POSE, RELIABLE)
        joy = c.node.create_publisher(Joy, CLUTCH, RELIABLE)
        need = [f"{NS}/measured_js", f"{NS}/servo_jp", f"{NS}/teleop/status",
                f"{NS}/operating_state"]
        c.until(lambda: all(rec.counts[k] for k in need) and len(c.got["js"]) > 0
                and pose.get_subscription_count() >= 2 and joy.get_subscription_count() >= 2,
                "the nodes' topics in the recorder", procs=procs)
        # the recorder's readers have matched these writers once a probe arrives (DDS
        # matches each side on its own); the probes are stamped before every sample below
        probe = PoseStamped()
        probe.header.stamp.sec = 1
        c.until(lambda: pose.publish(probe) or rec.counts[POSE] > 0, "a recorded probe pose",
                procs=procs)
        c.until(lambda: joy.publish(Joy(buttons=[0])) or rec.counts[CLUTCH] > 0,
                "a recorded probe Joy", procs=procs)
        sent_pose = [_pose(k) for k in range(200)]
        sent_joy = [_joy(k, k % 2 == 0) for k in range(0, 200, 20)]
        for k, m in enumerate(sent_pose):           # one burst, within the QoS depths
            pose.publish(m)
            if k % 20 == 0:
                joy.publish(sent_joy[k // 20])
        # reliable QoS delivers one writer's messages in order: the last one ends the wait
        c.until(lambda: rec.last_log_times[POSE] == _ns(sent_pose[-1].header.stamp)
                and rec.last_log_times[CLUTCH] == _ns(sent_joy[-1].header.stamp),
                "every sample in the recorder", procs=procs)
        js_seen = len(c.got["js"])
        c.until(lambda: len(c.got["js"]) > js_seen + 20, "more measured_js", procs=procs)
    finally:
        assert rec.close() == path
        ctx.close()
    counts = rec.counts                            # final once closed
    msgs, file_counts = _read_mcap(path)
    assert file_counts == counts
    assert not [p for p in tmp_path.iterdir() if p.name != "session.mcap"]   # no temp file
    # the test's own samples: the same content, log time = header stamp, in order
    got = [m for _, _, m in msgs[POSE] if m.header.stamp.sec != 1]
    assert len(got) == len(sent_pose)
    for a, b in zip(got, sent_pose, strict=True):
        assert _ns(a.header.stamp) == _ns(b.header.stamp) and a.header.frame_id == "master"
        p, q = a.pose, b.pose
        assert (p.position.x, p.position.y, p.position.z) == \
            (q.position.x, q.position.y, q.position.z)          # the very bytes: exact
        assert (p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w) == \
            (q.orientation.x, q.orientation.y, q.orientation.z, q.orientation.w)
    assert all(t == _ns(m.header.stamp) for t, _, m in msgs[POSE])
    joys = [m for _, _, m in msgs[CLUTCH] if m.header.frame_id == "joy"]
    assert [(_ns(m.header.stamp), list(m.axes), list(m.buttons)) for m in joys] == \
        [(_ns(m.header.stamp), list(m.axes), list(m.buttons)) for m in sent_joy]
    # the nodes' messages: as this client received them, stamps in order
    recorded = {_ns(m.header.stamp): m for _, _, m in msgs[f"{NS}/measured_js"]}
    common = [m for m in c.got["js"] if _ns(m.header.stamp) in recorded]
    assert len(common) >= 20
    for m in common:
        r = recorded[_ns(m.header.stamp)]
        assert list(r.name) == list(m.name) and list(r.position) == list(m.position)
        assert list(r.velocity) == list(m.velocity) and list(r.effort) == list(m.effort)
    for topic in (f"{NS}/measured_js", f"{NS}/setpoint_js", f"{NS}/measured_cp",
                  f"{NS}/servo_jp", f"{NS}/teleop/status"):
        t = [lt for lt, _, _ in msgs[topic]]
        assert t == [_ns(m.header.stamp) for _, _, m in msgs[topic]], topic
        assert np.all(np.diff(t) > 0), topic
    # servo_jp and the teleop status of one cycle carry the same stamp (status every cycle)
    st = {_ns(m.header.stamp) for _, _, m in msgs[f"{NS}/teleop/status"]}
    servo = [_ns(m.header.stamp) for _, _, m in msgs[f"{NS}/servo_jp"]]
    assert len(st & set(servo)) >= 0.9 * len(servo)
    state = msgs[f"{NS}/operating_state"][0][2]            # latched: recorded on joining
    assert getattr(state, "state", getattr(state, "data", None)) == "ENABLED"


def _rosbags_counts(path):
    from rosbags.highlevel import AnyReader

    out: dict[str, int] = {}
    with AnyReader([Path(path)]) as r:
        for con, _, raw in r.messages():
            msg = r.deserialize(raw, con.msgtype)         # every message decodes
            assert msg is not None
            out[con.topic] = out.get(con.topic, 0) + 1
    return out


@pytest.mark.slow
def test_the_cli_records_until_ctrl_c_and_for_a_duration(graph, tmp_path):
    arm, teleop, c = graph
    args = ["record", "--namespace", NS, "--pose-topic", POSE, "--clutch-topic", CLUTCH]
    c.listen("cli_js", JointState, f"{NS}/measured_js")
    proc = _start([*args, "-o", str(tmp_path / "a.mcap")])
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.extend(iter(proc.stdout.readline, "")),
                              daemon=True)
    reader.start()
    # the recorder says when a topic's first message came; then a second more of the arm's
    c.until(lambda: f"ros2 record: recording {NS}/servo_jp\n" in lines
            and f"ros2 record: recording {NS}/measured_js\n" in lines,
            "the recorder's first messages", procs=[arm, teleop])
    assert lines[0].startswith("ros2 record: 10 topics -> ")
    n = len(c.got["cli_js"])
    c.until(lambda: len(c.got["cli_js"]) > n + 100, "a second of measured_js",
            procs=[arm, teleop, proc])
    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=60)
    reader.join(timeout=10)
    out = "".join(lines)
    assert proc.returncode == 0, out
    assert "Traceback" not in out and "wrote" in out, out
    _, counts = _read_mcap(tmp_path / "a.mcap")
    assert counts[f"{NS}/measured_js"] > 0 and counts[f"{NS}/servo_jp"] > 0, (counts, out)
    assert _rosbags_counts(tmp_path / "a.mcap") == {k: v for k, v in counts.items() if v}
    assert f"{NS}/measured_js: {counts[f'{NS}/measured_js']}" in out
    # --duration ends it alone; an existing file is refused without --force
    r = subprocess.run([sys.executable, "-m", "athenakin", "ros2", *args, "-o",
                        str(tmp_path / "b.mcap"), "--duration", "1.5", "--topic",
                        "measured_cv=geometry_msgs/msg/TwistStamped"], env=node_env(DOMAIN),
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    _, counts = _read_mcap(tmp_path / "b.mcap")
    assert f"{NS}/measured_cv" in counts and len(counts) == 11
    r = subprocess.run([sys.executable, "-m", "athenakin", "ros2", *args, "-o",
                        str(tmp_path / "b.mcap"), "--duration", "1"], env=node_env(DOMAIN),
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 1 and "exists" in r.stderr and "--force" in r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mcap", "b.mcap"]


# --------------------------------------------------------------------------- bad arguments
@pytest.mark.parametrize("kw, error, words", [
    ({"topics": {}}, InvalidInputError, "at least one topic"),
    ({"topics": ["/a"]}, TypeError, "mapping"),
    ({"topics": {"a b": "std_msgs/msg/String"}}, InvalidInputError, "topic name"),
    ({"topics": {"/a//b": "std_msgs/msg/String"}}, InvalidInputError, "repeated '/'"),
    ({"topics": {"~/status": "std_msgs/msg/String"}}, InvalidInputError, "recorder's own"),
    ({"namespace": "/1athena"}, InvalidInputError, "starts with a number"),
    ({"topics": {"/a": "std_msgs/String"}}, InvalidInputError, "pkg/msg/Type"),
    ({"topics": {"/a": "no_such_msgs/msg/X"}}, InvalidInputError, "not installed"),
    ({"topics": {"/a": int}}, TypeError, "message class"),
    ({"topics": {"/a": 3}}, TypeError, "message type"),
    ({"topics": {"x": "std_msgs/msg/String", "/athena/x": "std_msgs/msg/String"}},
     InvalidInputError, "second time"),
    ({"compression": "gzip"}, InvalidInputError, "compression"),
    ({"compression_level": 99}, InvalidInputError, "compression_level"),
    ({"depth": 0}, ValueError, "depth"),
    ({"namespace": "a b"}, ValueError, "namespace"),
])
def test_bad_arguments_are_named_errors_before_any_file(tmp_path, kw, error, words):
    with pytest.raises(error, match=words):
        RecorderNode(tmp_path / "x.mcap", **kw)
    assert list(tmp_path.iterdir()) == []


def test_a_folder_or_a_fifo_is_refused(tmp_path):
    with pytest.raises(InvalidInputError, match="folder"):
        RecorderNode(tmp_path)
    fifo = tmp_path / "f.mcap"
    os.mkfifo(fifo)
    with pytest.raises(InvalidInputError, match="FIFO"):
        RecorderNode(fifo)


@pytest.mark.parametrize("argv, words", [
    (["-o", "x.txt"], ".mcap"),
    (["-o", "x.mcap", "--duration", "-1"], "--duration"),
    (["-o", "x.mcap", "--topic", "measured_cv"], "NAME=pkg/msg/Type"),
    (["-o", "x.mcap", "--topic", "a=b/msg/C"], "not installed"),
])
def test_cli_bad_arguments(tmp_path, capsys, monkeypatch, argv, words):
    from athenakin.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["ros2", "record", *argv]) == 1
    assert words in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


# --------------------------------------------------------------------------- the pieces
def test_header_stamps_are_read_in_either_byte_order():
    from rclpy.serialization import serialize_message

    from athenakin.ros2._record import header_stamp_ns

    m = JointState(name=["q1"], position=[0.5])
    m.header.stamp.sec, m.header.stamp.nanosec = 1_700_000_000, 123_456_789
    raw = serialize_message(m)
    assert header_stamp_ns(raw, JointState) == 1_700_000_000_123_456_789
    big = b"\x00\x00\x00\x00" + struct.pack(">iI", 12, 34) + raw[12:]
    assert header_stamp_ns(big, JointState) == 12 * 10**9 + 34


def test_crtk_definitions_come_from_their_msg_files():
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    from athenakin.ros2._record import message_definition

    for name, field in (("crtk_msgs/msg/OperatingState", "string state"),
                        ("crtk_msgs/msg/StringStamped", "string string")):
        text = message_definition(name)
        assert field in text and "MSG: std_msgs/Header" in text
        store = get_typestore(Stores.ROS2_HUMBLE)       # the schema defines the type
        store.register(get_types_from_msg(text.split("=" * 80)[0], name))
        assert name in store.fielddefs
    with pytest.raises(InvalidInputError, match="no message definition"):
        message_definition("crtk_msgs/msg/NoSuchThing")


def test_a_chunk_of_messages_of_any_sizes_reads_back_in_log_time_order(tmp_path):
    from athenakin.ros._mcap import McapFile

    rng = np.random.default_rng(38)
    items = [(1 + k % 2, k, int(t), int(t) + 5, rng.bytes(int(rng.integers(4, 300))))
             for k, t in enumerate(rng.permutation(np.arange(50)) * 1000 + 10**9)]
    path = tmp_path / "m.mcap"
    with open(path, "wb") as fh:
        f = McapFile(fh, compression="zstd")
        s = f.schema("x/msg/Y", "ros2msg", b"uint8[] data")
        for topic in ("/a", "/b"):
            f.channel(topic, "cdr", s)
        f.messages(items[:30])
        f.messages(items[30:])
        f.close()
    with open(path, "rb") as fh:
        got = [(m.channel_id, m.sequence, m.log_time, m.publish_time, m.data)
               for _, _, m in make_reader(fh, validate_crcs=True).iter_messages()]
    assert got == sorted(items, key=lambda it: it[2])
