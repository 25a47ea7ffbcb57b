"""athenakin.ros writers: MCAP of ROS 2 topics read back by rosbags and mcap-ros2-support."""

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap_ros2")

from _ros_recordings import NAMES, positions, q_stream, stamps, write_mcap, write_rosbag2  # noqa: E402, I001

import athenakin as ak  # noqa: E402
from athenakin.ros import (  # noqa: E402
    RecordingError,
    TF_FRAMES,
    TOPICS,
    TrackOptions,
    track_recording,
    track_to_mcap,
    write_trajectory,
)
from athenakin.sim import JOINTS, mechanism_joint_values, urdf_from_design  # noqa: E402

D = ak.Design.default()
T = ak.default_rcm_frame(D)
N = 60


def _rosbags_read(path):
    """{topic: [(log_time, msg)]} through rosbags' AnyReader (its own CDR decoder)."""
    from rosbags.highlevel import AnyReader

    out = {}
    with AnyReader([Path(path)]) as r:
        types = {c.topic: c.msgtype for c in r.connections}
        for conn, t, raw in r.messages():
            out.setdefault(conn.topic, []).append((t, r.deserialize(raw, conn.msgtype)))
    return out, types


def _mcap_ros2_read(path, topics=None):
    """{topic: [(log_time, msg)]} through mcap-ros2-support's decoder."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    out = {}
    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        for _, ch, m, msg in reader.iter_decoded_messages(topics=topics):
            out.setdefault(ch.topic, []).append((m.log_time, msg))
    return out


def _ns(stamp):
    return stamp.sec * 10**9 + stamp.nanosec


def _R_from_xyzw(x, y, z, w):
    return ak.study.rotation_from_quaternion([w, x, y, z])


@pytest.fixture(scope="module")
def tracked(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("ros")
    q = q_stream(N, seed=3)
    pos = positions(q)
    pos[10, NAMES.index("q1")] = np.nan                      # one bad reading
    bag = write_rosbag2(tmp / "bag", pos, stamps(N), storage="mcap")
    out = tmp / "out.mcap"
    summary = track_recording(bag, out, T, D)
    return q, out, summary


def test_tracking_rosbags_reads_counts_and_stamps(tracked):
    q, out, summary = tracked
    msgs, types = _rosbags_read(out)
    assert types == {TOPICS["robot_description"]: "std_msgs/msg/String",
                     TOPICS["tf_static"]: "tf2_msgs/msg/TFMessage",
                     TOPICS["status"]: "athenakin_msgs/msg/TrackStatus",
                     TOPICS["tool_tip"]: "geometry_msgs/msg/PoseStamped",
                     TOPICS["tf"]: "tf2_msgs/msg/TFMessage",
                     TOPICS["joint_states"]: "sensor_msgs/msg/JointState"}
    counts = {k: len(v) for k, v in msgs.items()}
    assert counts == {"/robot_description": 1, "/tf_static": 1, "/athena/status": N,
                      "/athena/tool_tip": N - 1, "/tf": N - 1, "/athena/joint_states": N - 1}
    assert summary.messages == counts and summary.n == N and summary.n_valid == N - 1
    ok = np.delete(np.arange(N), 10)
    for topic in ("/athena/tool_tip", "/tf", "/athena/joint_states"):
        logt = np.array([t for t, _ in msgs[topic]])
        np.testing.assert_array_equal(logt, stamps(N)[ok])            # to the ns
    hdr = [_ns(m.header.stamp) for _, m in msgs["/athena/tool_tip"]]
    np.testing.assert_array_equal(hdr, stamps(N)[ok])
    tf_hdr = [_ns(m.transforms[0].header.stamp) for _, m in msgs["/tf"]]
    np.testing.assert_array_equal(tf_hdr, stamps(N)[ok])
    status = [m for _, m in msgs["/athena/status"]]
    assert [s.valid for s in status] == [i != 10 for i in range(N)]
    assert status[10].lost and status[10].flags & int(ak.motion.TrackFlag.LOST)
    assert status[11].flags & int(ak.motion.TrackFlag.REACQUIRED)
    assert np.isnan(status[0].clearance_m) and status[0].clearance_flags == 0
    assert [s.sample for s in status] == list(range(N))


def test_tool_tips_match_forward_kinematics(tracked):
    q, out, _ = tracked
    msgs, _ = _rosbags_read(out)
    ok = np.delete(np.arange(N), 10)
    sol = ak.forward_kinematics(q[ok], T, D)
    T_tip = sol.T_b_tip[:, 0]                                # the stream stays in slot 0
    for k, (_, m) in enumerate(msgs["/athena/tool_tip"]):
        assert m.header.frame_id == "base"
        p, o = m.pose.position, m.pose.orientation
        np.testing.assert_allclose([p.x, p.y, p.z], T_tip[k, :3, 3], rtol=0, atol=1e-12)
        np.testing.assert_allclose(_R_from_xyzw(o.x, o.y, o.z, o.w), T_tip[k, :3, :3],
                                   rtol=0, atol=1e-12)


def test_tf_frames_and_joint_states_match_the_urdf(tracked):
    q, out, _ = tracked
    msgs = _mcap_ros2_read(out)                              # the other decoder
    assert msgs["/robot_description"][0][1].data == urdf_from_design(T, D)
    static = msgs["/tf_static"][0][1]
    assert {t.child_frame_id for t in static.transforms} >= {"rcm_setup", "platform_oi"}
    ok = np.delete(np.arange(N), 10)
    sol = ak.forward_kinematics(q[ok], T, D)
    for k in (0, 17, len(ok) - 1):
        tf = msgs["/tf"][k][1]
        frames = [t.child_frame_id for t in tf.transforms]
        assert tuple(frames) == TF_FRAMES
        assert all(t.header.frame_id == "base" for t in tf.transforms)
        by = {t.child_frame_id: t.transform for t in tf.transforms}
        tip = by["tool_tip"].translation
        np.testing.assert_allclose([tip.x, tip.y, tip.z], sol.tip[k, 0], rtol=0, atol=1e-12)
        rcm = by["rcm"]
        np.testing.assert_allclose([rcm.translation.x, rcm.translation.y, rcm.translation.z],
                                   T[:3, 3], rtol=0, atol=1e-15)
        r = rcm.rotation
        np.testing.assert_allclose(_R_from_xyzw(r.x, r.y, r.z, r.w), T[:3, :3], rtol=0,
                                   atol=1e-12)
        Os = by["ujoint_cross"].translation                  # the U-joint at O_s
        np.testing.assert_allclose([Os.x, Os.y, Os.z], sol.T_b_s[k, 0, :3, 3], rtol=0,
                                   atol=1e-12)
        js = msgs["/athena/joint_states"][k][1]
        assert list(js.name) == list(JOINTS)
        ref = mechanism_joint_values(q[ok][k], T, D, slot=0).urdf
        np.testing.assert_allclose(js.position, [ref[n] for n in JOINTS], rtol=0, atol=1e-12)


def test_cdr_bytes_equal_rosbags_serializer(tracked):
    """The vectorised encoder writes the bytes rosbags' serializer writes, bit for bit."""
    from mcap.reader import make_reader
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    _, out, _ = tracked
    with open(out, "rb") as fh:
        for _, ch, m in make_reader(fh).iter_messages(topics=["/athena/tool_tip", "/tf",
                                                              "/athena/joint_states"]):
            typ = {"/athena/tool_tip": "geometry_msgs/msg/PoseStamped",
                   "/tf": "tf2_msgs/msg/TFMessage",
                   "/athena/joint_states": "sensor_msgs/msg/JointState"}[ch.topic]
            msg = store.deserialize_cdr(m.data, typ)
            assert bytes(store.serialize_cdr(msg, typ)) == m.data


def test_csv_stream_to_mcap_and_back(tmp_path):
    q = q_stream(25, seed=5)
    st = stamps(25)
    s = track_to_mcap(st, q, tmp_path / "a.mcap", T, D)
    assert s.n == 25 and s.n_valid == 25 and s.first_slot == 0
    msgs, _ = _rosbags_read(tmp_path / "a.mcap")
    np.testing.assert_array_equal([_ns(m.header.stamp) for _, m in msgs["/athena/status"]], st)


def test_tracking_output_is_readable_by_the_reader_itself(tmp_path):
    """The joint states written are a JointState recording that read_joint_states reads."""
    q = q_stream(12, seed=2)
    track_to_mcap(stamps(12), q, tmp_path / "a.mcap", T, D)
    js = ak.ros.read_joint_states(tmp_path / "a.mcap", topic="/athena/joint_states")
    np.testing.assert_allclose(js.q, q - np.array(ak.robot.REFERENCE_Q), rtol=0, atol=1e-15)
    np.testing.assert_array_equal(js.stamps_ns, stamps(12))


def test_no_partial_output_on_a_corrupt_recording(tmp_path):
    src = write_mcap(tmp_path / "a.mcap", positions(q_stream(400)), stamps(400))
    data = src.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[:int(len(data) * 0.6)])
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    with pytest.raises(RecordingError):
        track_recording(cut, out_dir / "o.mcap", T, D, options=TrackOptions(chunk_size=1024))
    assert list(out_dir.iterdir()) == []


def test_no_partial_output_when_stamps_go_backwards(tmp_path):
    st = stamps(3000)
    st[2500] = st[10]
    src = write_mcap(tmp_path / "a.mcap", positions(q_stream(3000)), st,
                     log_ns=stamps(3000) + 17)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    with pytest.raises(RecordingError, match="backwards at message 2500"):
        track_recording(src, out_dir / "o.mcap", T, D, options=TrackOptions(chunk_size=1024))
    assert list(out_dir.iterdir()) == []


def test_write_trajectory_round_trip(tmp_path):
    from athenakin.motion import PlanOptions, plan

    tips = np.array([[0.25, 0.0, 0.0], [0.26, -0.01, 0.005], [0.25, 0.0, 0.01]])
    traj = plan(tips, T, D, options=PlanOptions(rate=200.0))
    start = 1_700_000_000_000_000_001
    path = write_trajectory(tmp_path / "traj.mcap", traj, start_ns=start)
    msgs, types = _rosbags_read(path)
    assert types["/athena/trajectory"] == "trajectory_msgs/msg/JointTrajectory"
    (t0, jt), = msgs["/athena/trajectory"]
    assert t0 == start and _ns(jt.header.stamp) == start
    assert list(jt.joint_names) == ["q1", "q2", "q3"]
    assert len(jt.points) == len(traj.t)
    np.testing.assert_array_equal(np.array([p.positions for p in jt.points]), traj.q)
    np.testing.assert_array_equal(np.array([p.velocities for p in jt.points]), traj.qd)
    np.testing.assert_array_equal(np.array([p.accelerations for p in jt.points]), traj.qdd)
    dt = np.array([_ns(p.time_from_start) for p in jt.points])
    np.testing.assert_array_equal(dt, np.rint((traj.t - traj.t[0]) * 1e9).astype(np.int64))
    assert len(msgs["/athena/tool_tip"]) == len(traj.t)
    tip = np.array([[m.pose.position.x, m.pose.position.y, m.pose.position.z]
                    for _, m in msgs["/athena/tool_tip"]])
    tip_e = (tip - T[:3, 3]) @ T[:3, :3]
    np.testing.assert_allclose(tip_e, traj.tip_e, rtol=0, atol=1e-9)
    other = _mcap_ros2_read(path, topics=["/athena/trajectory"])
    assert len(other["/athena/trajectory"][0][1].points) == len(traj.t)


@pytest.mark.parametrize("bad, match", [
    ({"stamps_ns": np.array([3, 2, 5])}, "stamps go backwards at reading 1"),
    ({"stamps_ns": np.array([1.0, 2.0, 3.0])}, "stamps_ns: expected 3 integers"),
])
def test_track_to_mcap_bad_stamps(bad, match, tmp_path):
    with pytest.raises(ak.InvalidInputError, match=match):
        track_to_mcap(bad["stamps_ns"], q_stream(3), tmp_path / "a.mcap", T, D)
    assert not (tmp_path / "a.mcap").exists()


def test_mcap_structure_crcs_and_index(tracked):
    """The file's CRCs check, its chunk indexes find every message, and a streaming reader
    that ignores the summary sees the same messages in log-time order."""
    from mcap.reader import NonSeekingReader, SeekingReader

    _, out, summary = tracked
    with open(out, "rb") as fh:
        seeking = [(c.topic, m.log_time, m.sequence)
                   for _, c, m in SeekingReader(fh, validate_crcs=True).iter_messages()]
    with open(out, "rb") as fh:
        streamed = [(c.topic, m.log_time, m.sequence)
                    for _, c, m in NonSeekingReader(fh, validate_crcs=True).iter_messages()]
    assert sorted(seeking) == sorted(streamed)
    assert [t for _, t, _ in streamed] == sorted(t for _, t, _ in streamed)
    assert len(streamed) == sum(summary.messages.values())
    for topic in ("/athena/status", "/tf"):
        seqs = [s for tp, _, s in streamed if tp == topic]
        assert seqs == list(range(len(seqs)))


def test_foxglove_layout_names_written_topics_and_fields():
    """docs/foxglove_layout.json refers only to topics and fields the files hold."""
    import json
    import re

    from athenakin.ros import STATUS_MSGDEF

    layout = json.loads((Path(__file__).resolve().parents[1] / "docs" /
                         "foxglove_layout.json").read_text())
    text = json.dumps(layout)
    paths = set(re.findall(r'"(/[a-z_/]+)(?:\.([a-z_.]+))?"', text))
    assert paths
    status_fields = set(re.findall(r"^\w+(?:/\w+)*\s+(\w+)", STATUS_MSGDEF, flags=re.M))
    for topic, field in paths:
        assert topic in TOPICS.values(), topic
        if topic == "/athena/status" and field:
            assert field in status_fields, field
        if topic == "/athena/tool_tip" and field:
            assert field.startswith("pose.position.") or field.startswith("pose.orientation.")


def test_foxglove_layout_is_what_foxglove_1_48_reads():
    """The layout's panels and values are ones Foxglove Studio 1.48 accepts and draws sanely.

    Found by opening the file in Foxglove (tools/foxglove-shot/shot.py): every panel of the
    tree has its config; the 3D panel reads a pose's ``axisScale`` as the axis length in m
    (0.5 hid the robot, whose links are ~0.2-0.5 m); a plot legend is one of Foxglove's three
    placements.
    """
    import json

    layout = json.loads((Path(__file__).resolve().parents[1] / "docs" /
                         "foxglove_layout.json").read_text())

    def leaves(node):
        if isinstance(node, str):
            return [node]
        assert set(node) >= {"first", "second", "direction"}, node
        assert node["direction"] in ("row", "column")
        return leaves(node["first"]) + leaves(node["second"])

    panel_ids = leaves(layout["layout"])
    assert sorted(panel_ids) == sorted(layout["configById"])
    assert {i.split("!")[0] for i in panel_ids} == {"3D", "Plot", "RawMessages"}
    for panel_id, config in layout["configById"].items():
        kind = panel_id.split("!")[0]
        if kind == "Plot":
            assert config["legendDisplay"] in ("floating", "top", "left"), panel_id
            assert config["xAxisVal"] == "timestamp"
        if kind == "3D":
            assert config["followTf"] == "base"
            for topic, settings in config["topics"].items():
                if settings.get("type") == "axis":
                    assert 0.0 < settings["axisScale"] <= 0.1, topic


def test_stream_starting_with_unusable_readings(tmp_path):
    """Readings before the first that assembles are LOST; tracking starts there."""
    from rosbags.highlevel import AnyReader  # noqa: F401  (the extra is present)

    q = q_stream(8, seed=4)
    q[0] = np.nan
    q[1] = [0.3, -0.3, 0.45]                               # A/B order broken: no pose
    s = track_to_mcap(stamps(8), q, tmp_path / "a.mcap", T, D)
    assert s.n == 8 and s.n_valid == 6 and s.first_slot == 0
    assert s.counts["LOST"] == 2 and [e[0] for e in s.events[:2]] == [0, 1]
    msgs, _ = _rosbags_read(tmp_path / "a.mcap")
    assert [m.valid for _, m in msgs["/athena/status"]] == [False, False] + [True] * 6
    assert len(msgs["/athena/tool_tip"]) == 6


def test_ctrl_c_leaves_nothing(tmp_path):
    """A KeyboardInterrupt half way (here from the progress callback) leaves no file."""
    src = write_mcap(tmp_path / "a.mcap", positions(q_stream(3000)), stamps(3000))
    out_dir = tmp_path / "out"
    out_dir.mkdir()

    def interrupt(n):
        if n >= 2048:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        track_recording(src, out_dir / "o.mcap", T, D, progress=interrupt,
                        options=TrackOptions(chunk_size=1024))
    assert list(out_dir.iterdir()) == []
