"""athenakin.ros.read_joint_states: every format, stamps to the ns, names, bad input."""

import os

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap_ros2")

from _ros_recordings import (  # noqa: E402
    NAMES,
    positions,
    q_stream,
    stamps,
    write_mcap,
    write_ros1,
    write_rosbag2,
)

import athenakin as ak  # noqa: E402
from athenakin.ros import RecordingError, iter_joint_states, read_joint_states  # noqa: E402

N = 40


def _write(kind, tmp_path, pos, st, vel=None, log_ns=None):
    if kind == "rosbag2/sqlite3":
        return write_rosbag2(tmp_path / "bag", pos, st, vel=vel, log_ns=log_ns)
    if kind == "rosbag2/mcap":
        return write_rosbag2(tmp_path / "bag", pos, st, storage="mcap", vel=vel, log_ns=log_ns)
    if kind == "rosbag1":
        return write_ros1(tmp_path / "run.bag", pos, st, vel=vel, log_ns=log_ns)
    return write_mcap(tmp_path / "run.mcap", pos, st, vel=vel, log_ns=log_ns)


KINDS = ["rosbag2/sqlite3", "rosbag2/mcap", "rosbag1", "mcap"]


@pytest.mark.parametrize("kind", KINDS)
def test_reads_every_format_by_name_to_the_ns(kind, tmp_path):
    q = q_stream(N)
    st = stamps(N)
    vel = positions(q) * 0.5
    path = _write(kind, tmp_path, positions(q), st, vel)
    js = read_joint_states(path)
    assert js.source == kind
    assert js.stamps_ns.dtype == np.int64
    np.testing.assert_array_equal(js.stamps_ns, st)          # header stamps, every ns
    np.testing.assert_array_equal(js.log_time_ns, st + 17)
    assert js.header_stamped.all()
    np.testing.assert_array_equal(js.q, q)                    # picked by name, exact
    np.testing.assert_allclose(js.qd, 0.5 * q, rtol=0, atol=0)
    assert js.joints == ("q1", "q2", "q3") and js.topic == "/joint_states"


@pytest.mark.parametrize("kind", ["rosbag2/sqlite3", "mcap"])
def test_zero_header_stamp_falls_back_to_log_time(kind, tmp_path):
    q = q_stream(5)
    log = stamps(5) + 1000
    hdr = stamps(5)
    hdr[2] = 0
    if kind == "mcap":
        path = write_mcap(tmp_path / "z.mcap", positions(q), hdr, log_ns=log)
    else:
        path = write_rosbag2(tmp_path / "bag", positions(q), hdr, log_ns=log)
    js = read_joint_states(path)
    np.testing.assert_array_equal(js.stamps_ns, [hdr[0], hdr[1], log[2], hdr[3], hdr[4]])
    assert js.header_stamped.tolist() == [True, True, False, True, True]


def test_scale_reads_mm_encoders(tmp_path):
    q = q_stream(6)
    path = write_mcap(tmp_path / "mm.mcap", positions(q, scale=1e-3), stamps(6))
    js = read_joint_states(path, scale=0.001)
    np.testing.assert_allclose(js.q, q, rtol=0, atol=1e-15)
    assert js.qd is None


def test_other_joint_names_and_topic(tmp_path):
    q = q_stream(5)
    names = ("m_left", "m_right", "m_k2", "extra")
    pos = np.column_stack([q, np.full(5, 3.0)])
    path = write_mcap(tmp_path / "x.mcap", pos, stamps(5), topic="/robot/joints", names=names)
    js = read_joint_states(path, topic="/robot/joints", joints=("m_left", "m_right", "m_k2"))
    np.testing.assert_array_equal(js.q, q)


def test_chunks_concatenate_to_the_whole(tmp_path):
    q = q_stream(N)
    path = write_rosbag2(tmp_path / "bag", positions(q), stamps(N))
    parts = list(iter_joint_states(path, chunk_size=7))
    assert [len(p) for p in parts] == [7] * 5 + [5]
    np.testing.assert_array_equal(np.concatenate([p.q for p in parts]), q)
    np.testing.assert_array_equal(np.concatenate([p.stamps_ns for p in parts]), stamps(N))


def test_nan_position_is_flagged_and_the_stream_goes_on(tmp_path):
    q = q_stream(10)
    pos = positions(q)
    pos[4, NAMES.index("q2")] = np.nan
    js = read_joint_states(write_mcap(tmp_path / "nan.mcap", pos, stamps(10)))
    assert js.finite.tolist() == [True] * 4 + [False] + [True] * 5
    d = ak.Design.default()
    log = ak.motion.track(js.q, ak.default_rcm_frame(d), d)
    assert not log.valid[4] and log.valid[5:].all()
    assert ak.motion.TrackFlag.LOST in ak.motion.TrackFlag(int(log.flags[4]))


# ---------------------------------------------------------------------------- bad input
def test_missing_topic_lists_the_topics(tmp_path):
    path = write_rosbag2(tmp_path / "bag", positions(q_stream(3)), stamps(3))
    with pytest.raises(RecordingError, match=r"no topic '/js'; topics present: /chatter "
                                             r"\(std_msgs/msg/String\), /joint_states"):
        read_joint_states(path, topic="/js")


def test_missing_topic_in_mcap_lists_the_topics(tmp_path):
    path = write_mcap(tmp_path / "a.mcap", positions(q_stream(3)), stamps(3))
    with pytest.raises(RecordingError, match=r"topics present: /joint_states"):
        read_joint_states(path, topic="/nope")


def test_absent_joint_names_list_the_names(tmp_path):
    path = write_mcap(tmp_path / "a.mcap", positions(q_stream(3)), stamps(3))
    with pytest.raises(RecordingError, match=r"no joint named 'm1'; names present: "
                                             r"\['roll', 'q3', 'gripper', 'q1', 'q2'\]"):
        read_joint_states(path, joints=("m1", "q2", "q3"))


def test_type_not_joint_state(tmp_path):
    path = write_rosbag2(tmp_path / "bag", positions(q_stream(3)), stamps(3))
    with pytest.raises(RecordingError, match=r"'/chatter' holds std_msgs/msg/String, expected "
                                             r"sensor_msgs/msg/JointState"):
        read_joint_states(path, topic="/chatter")


@pytest.mark.parametrize("kind", ["rosbag2/sqlite3", "rosbag1", "mcap"])
def test_stamps_going_backwards(kind, tmp_path):
    st = stamps(6)
    st[3] = st[1]             # header earlier than the one before; the log times increase
    path = _write(kind, tmp_path, positions(q_stream(6)), st, log_ns=stamps(6) + 17)
    with pytest.raises(RecordingError, match=r"stamps go backwards at message 3"):
        read_joint_states(path)


def test_truncated_mcap(tmp_path):
    path = write_mcap(tmp_path / "a.mcap", positions(q_stream(300)), stamps(300))
    data = path.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[:len(data) // 2])
    with pytest.raises(RecordingError, match=r"truncated or corrupt"):
        read_joint_states(cut)


def test_corrupt_rosbag1(tmp_path):
    path = write_ros1(tmp_path / "a.bag", positions(q_stream(50)), stamps(50))
    data = bytearray(path.read_bytes())
    data[len(data) // 2:] = b"\xff" * (len(data) - len(data) // 2)
    path.write_bytes(bytes(data))
    with pytest.raises(RecordingError, match=r"truncated or corrupt"):
        read_joint_states(path)


def test_not_a_recording(tmp_path):
    f = tmp_path / "x.mcap"
    f.write_bytes(b"hello, world\n")
    with pytest.raises(RecordingError, match=r"not a recording"):
        read_joint_states(f)
    with pytest.raises(RecordingError, match=r"without metadata.yaml"):
        read_joint_states(tmp_path)
    with pytest.raises(RecordingError, match=r"cannot open"):
        read_joint_states(tmp_path / "missing.bag")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_fifo_is_refused_without_blocking(tmp_path):
    fifo = tmp_path / "pipe.mcap"
    os.mkfifo(fifo)
    with pytest.raises(RecordingError, match=r"not a regular file"):
        read_joint_states(fifo)


@pytest.mark.parametrize("kw, match", [
    ({"joints": ("q1", "q2")}, "joints: expected 3 joint names"),
    ({"joints": ("q1", "q1", "q2")}, "joints: expected 3 different names"),
    ({"scale": 0.0}, "scale: expected a finite nonzero factor"),
    ({"scale": float("nan")}, "scale: expected a finite nonzero factor"),
    ({"topic": ""}, "topic: expected a topic name"),
    ({"max_readings": 0}, "max_readings: expected an integer"),
])
def test_bad_options(kw, match, tmp_path):
    path = write_mcap(tmp_path / "a.mcap", positions(q_stream(3)), stamps(3))
    with pytest.raises(ak.InvalidInputError, match=match):
        read_joint_states(path, **kw)


def test_max_readings(tmp_path):
    path = write_mcap(tmp_path / "a.mcap", positions(q_stream(30)), stamps(30))
    with pytest.raises(RecordingError, match=r"more than 10 readings"):
        read_joint_states(path, max_readings=10)


@pytest.mark.parametrize("compression, chunked", [("none", True), ("lz4", True),
                                                   ("zstd", True), ("none", False)])
def test_mcap_variants_of_the_mcap_library(compression, chunked, tmp_path):
    """Chunked (any compression) or not, as the mcap library writes them, with the
    definitions of another topic in between."""
    from mcap.writer import CompressionType, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    q = q_stream(30)
    pos = positions(q)
    st = stamps(30)
    path = tmp_path / "v.mcap"
    kind = {"none": CompressionType.NONE, "lz4": CompressionType.LZ4,
            "zstd": CompressionType.ZSTD}[compression]
    T_ = store.types
    with open(path, "wb") as fh:
        w = Writer(fh, compression=kind, use_chunking=chunked, chunk_size=512)
        w.start(profile="ros2")
        text = store.generate_msgdef("sensor_msgs/msg/JointState", ros_version=2)[0]
        sid = w.register_schema("sensor_msgs/msg/JointState", "ros2msg", text.encode())
        cid = w.register_channel("/joint_states", "cdr", sid)
        for i in range(30):
            if i == 12:
                s2 = w.register_schema("std_msgs/msg/String", "ros2msg", b"string data")
                c2 = w.register_channel("/chatter", "cdr", s2)
                w.add_message(c2, int(st[i]), bytes(store.serialize_cdr(
                    T_["std_msgs/msg/String"](data="x"), "std_msgs/msg/String")), int(st[i]))
            m = T_["sensor_msgs/msg/JointState"](
                header=T_["std_msgs/msg/Header"](stamp=T_["builtin_interfaces/msg/Time"](
                    sec=int(st[i] // 10**9), nanosec=int(st[i] % 10**9)), frame_id="f"),
                name=list(NAMES), position=pos[i], velocity=np.zeros(0), effort=np.zeros(0))
            w.add_message(cid, int(st[i]), bytes(store.serialize_cdr(
                m, "sensor_msgs/msg/JointState")), int(st[i]), i)
        w.finish()
    js = read_joint_states(path)
    np.testing.assert_array_equal(js.q, q)
    np.testing.assert_array_equal(js.stamps_ns, st)
    with pytest.raises(RecordingError, match="'/chatter' holds std_msgs/msg/String"):
        read_joint_states(path, topic="/chatter")


def test_corrupt_mcap_chunk(tmp_path):
    path = write_mcap(tmp_path / "a.mcap", positions(q_stream(300)), stamps(300))
    data = bytearray(path.read_bytes())
    i = data.index(b"zstd") + 40                 # inside the first chunk's compressed data
    data[i:i + 64] = b"\x00" * 64
    path.write_bytes(bytes(data))
    with pytest.raises(RecordingError, match="truncated or corrupt"):
        read_joint_states(path)


def test_joint_order_changing_mid_stream(tmp_path):
    """Messages whose names change order (or gain a joint) are each read by name."""
    from mcap_ros2.writer import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    text = store.generate_msgdef("sensor_msgs/msg/JointState", ros_version=2)[0]
    q = q_stream(9)
    st = stamps(9)
    orders = [("q1", "q2", "q3"), ("q3", "x", "q1", "q2"), ("q2", "q3", "q1")]
    path = tmp_path / "mixed.mcap"
    with open(path, "wb") as fh:
        w = Writer(fh)
        schema = w.register_msgdef("sensor_msgs/msg/JointState", text)
        for i in range(9):
            names = orders[i % 3]
            val = {"q1": q[i, 0], "q2": q[i, 1], "q3": q[i, 2], "x": 5.0}
            w.write_message("/joint_states", schema, {
                "header": {"stamp": {"sec": int(st[i] // 10**9), "nanosec": int(st[i] % 10**9)},
                           "frame_id": ""},
                "name": list(names), "position": [val[n] for n in names],
                "velocity": [2 * val[n] for n in names] if i % 2 else [], "effort": []},
                log_time=int(st[i]), publish_time=int(st[i]))
        w.finish()
    js = read_joint_states(path)
    np.testing.assert_array_equal(js.q, q)
    np.testing.assert_array_equal(js.qd[1::2], 2 * q[1::2])
    assert np.isnan(js.qd[0::2]).all()
