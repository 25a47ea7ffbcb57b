"""athenakin.ros' compiled paths equal their numpy references, and their files stay valid.

The writer fills the records of a chunk with a compiled kernel (``ros._kernels.
fill_records``) and computes the ``/tf`` frames compiled (``fast._frame_kernels.
urdf_frames_into``); the reader reads chunks that define channels in bulk and evenly
spaced messages as a strided view. Each against the path it replaces, byte for byte
where the numbers are the same, and the files against the mcap library's CRC-checking
readers and rosbags.
"""

import zlib
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from _ros_recordings import NAMES, _js, _ros2_store, positions, q_stream, stamps  # noqa: E402, I001

import athenakin as ak  # noqa: E402
from athenakin import _backend  # noqa: E402
from athenakin.errors import InvalidInputError  # noqa: E402
from athenakin.ros import _encoder, _mcap, _mcap_stream, _write  # noqa: E402
from athenakin.ros._frames import (  # noqa: E402
    MOVING_LINKS,
    TOOL_TIP_FRAME,
    joint_values,
    kernel_plan,
    link_frames,
    link_poses,
    urdf_model,
)

D = ak.Design.default()
T = ak.default_rcm_frame(D)
needs_numba = pytest.mark.skipif(not _backend.numba_available(),
                                 reason="numba not available here: the compiled paths need it")


def _stream(n, seed, lost=()):
    """Readings (stamps ns, q) with NaN readings at ``lost`` (LOST: status only)."""
    q = q_stream(n, seed)
    for i in lost:
        q[i] = np.nan
    return stamps(n), q


def _kernel_joint_values(model, q, p, u, O_s):
    """:func:`joint_values` through the compiled writer's kernel (as a dict)."""
    from athenakin.fast._frame_kernels import joint_values_into
    from athenakin.sim import JOINTS

    jv_args, _ = kernel_plan(model, (*MOVING_LINKS, TOOL_TIP_FRAME))
    out = np.full((len(q), len(JOINTS)), np.nan)
    joint_values_into(np.asarray(q, float), np.asarray(p, float), np.asarray(u, float),
                      np.asarray(O_s, float), np.ones(len(q), bool), *jv_args, out)
    return {name: out[:, i] for i, name in enumerate(JOINTS)}


def _numpy_writer(monkeypatch):
    """The numpy writer, given the compiled joint values (libm and numpy's SIMD atan2 may
    differ in the last bit): the encoders compared on the same numbers."""
    monkeypatch.setattr(_write.McapOutput, "_compiled_records", lambda self: False)
    monkeypatch.setattr(_encoder, "joint_values", _kernel_joint_values)


def _both_writers(tmp_path, monkeypatch, name, st, q, **kw):
    """The same stream written by the compiled writer and by the numpy writer."""
    fast = tmp_path / f"{name}_fast.mcap"
    slow = tmp_path / f"{name}_numpy.mcap"
    ak.ros.track_to_mcap(st, q, fast, T, D, **kw)
    _numpy_writer(monkeypatch)
    ak.ros.track_to_mcap(st, q, slow, T, D, **kw)
    monkeypatch.undo()
    return fast, slow


@needs_numba
@pytest.mark.parametrize("lost", [(), (0, 1, 2, 40, 41, 199), tuple(range(0, 300, 2))],
                         ids=["all-valid", "some-lost", "every-other-lost"])
def test_compiled_writer_writes_the_numpy_writers_bytes(tmp_path, monkeypatch, lost):
    st, q = _stream(300, 11, lost)
    fast, slow = _both_writers(tmp_path, monkeypatch, "w", st, q,
                               options=ak.ros.TrackOptions(compression="none"))
    assert fast.read_bytes() == slow.read_bytes()


@needs_numba
def test_compiled_writer_across_chunks_and_all_lost_chunk(tmp_path, monkeypatch):
    """More readings than one MCAP chunk holds (about 1600), one chunk entirely LOST."""
    st, q = _stream(4000, 12, lost=range(1700, 3400))
    fast, slow = _both_writers(tmp_path, monkeypatch, "c", st, q)
    assert fast.read_bytes() == slow.read_bytes()


@needs_numba
def test_compiled_writer_with_clearance_fields(tmp_path, monkeypatch):
    """The status' clearance columns when the tracker checked collisions."""
    from athenakin.ros._track import tracked_batch

    st, q = _stream(120, 13, lost=(5,))
    log = ak.motion.track(q, T, D)
    cols = {f: getattr(log, f) for f in ("q", "valid", "slot", "mode", "p", "u", "O_s",
                                         "half_chord", "sin_u2", "sin_u4", "step", "flags")}
    cols["clearance"] = np.linspace(0.001, 0.02, len(q))
    cols["flags"] = cols["flags"] | np.where(np.arange(len(q)) % 7 == 0,
                                             int(ak.motion.TrackFlag.NEAR_COLLISION), 0)
    out = {}
    for name in ("fast", "slow"):
        if name == "slow":
            _numpy_writer(monkeypatch)
        path = tmp_path / f"{name}.mcap"
        with _write.McapOutput(path, T, D, compression="none") as w:
            w.write_tracked(tracked_batch(st, cols))
        out[name] = path.read_bytes()
    assert out["fast"] == out["slow"]


def _validated_messages(path):
    """(topic, log time) of every message through both mcap readers, CRCs checked."""
    from mcap.reader import NonSeekingReader, SeekingReader

    got = []
    for cls in (SeekingReader, NonSeekingReader):
        with open(path, "rb") as fh:
            r = cls(fh, validate_crcs=True)
            got.append([(ch.topic, m.log_time) for _, ch, m in r.iter_messages()])
    assert got[0] and sorted(got[0]) == sorted(got[1])
    return got[0]


@pytest.mark.parametrize("compression, level", [("zstd", None), ("zstd", 1), ("lz4", None),
                                                ("lz4", 3), ("none", None)])
def test_files_pass_the_crc_checking_readers_and_rosbags(tmp_path, compression, level):
    from rosbags.highlevel import AnyReader

    n = 2500
    st, q = _stream(n, 14, lost=(3, 1999))
    path = tmp_path / "o.mcap"
    summary = ak.ros.track_to_mcap(st, q, path, T, D, options=ak.ros.TrackOptions(
        compression=compression, compression_level=level))
    msgs = _validated_messages(path)
    counts = {}
    for topic, _ in msgs:
        counts[topic] = counts.get(topic, 0) + 1
    assert counts == summary.messages and counts["/athena/status"] == n
    assert counts["/tf"] == n - 2
    logt = sorted(t for topic, t in msgs if topic == "/athena/status")
    np.testing.assert_array_equal(logt, st)                     # to the nanosecond
    with AnyReader([Path(path)]) as r:
        conn = [c for c in r.connections if c.topic == "/athena/tool_tip"]
        tips = [r.deserialize(raw, c.msgtype) for c, _, raw in r.messages(connections=conn)]
    assert len(tips) == n - 2
    ok = np.delete(np.arange(n), [3, 1999])
    stamp = [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for m in tips]
    np.testing.assert_array_equal(stamp, st[ok])


def test_compression_is_checked(tmp_path):
    st, q = _stream(5, 15)
    for kw, word in (({"compression": "gzip"}, "compression"),
                     ({"compression": "zstd", "compression_level": 23}, "compression_level"),
                     ({"compression": "zstd", "compression_level": 1.5}, "compression_level"),
                     ({"compression": "lz4", "compression_level": -1}, "compression_level"),
                     ({"compression": "none", "compression_level": 1}, "compression_level")):
        with pytest.raises(InvalidInputError, match=word):
            ak.ros.track_to_mcap(st, q, tmp_path / "x.mcap", T, D,
                                 options=ak.ros.TrackOptions(**kw))
    assert not (tmp_path / "x.mcap").exists()


def test_crc_functions_agree_and_either_writes_the_same_file(tmp_path, monkeypatch):
    rng = np.random.default_rng(16)
    data = rng.integers(0, 256, 100_003, dtype=np.uint8).tobytes()
    assert _mcap._crc32(data) == zlib.crc32(data)
    assert _mcap._crc32(memoryview(data)[7:], 12345) == zlib.crc32(data[7:], 12345)
    st, q = _stream(50, 16)
    ak.ros.track_to_mcap(st, q, tmp_path / "a.mcap", T, D)
    monkeypatch.setattr(_mcap, "_crc32", zlib.crc32)
    ak.ros.track_to_mcap(st, q, tmp_path / "b.mcap", T, D)
    assert (tmp_path / "a.mcap").read_bytes() == (tmp_path / "b.mcap").read_bytes()


@needs_numba
def test_fill_records_refuses_a_short_buffer_or_a_field_outside():
    from athenakin.ros._kernels import fill_records

    st_t, po_t = np.arange(10, dtype=np.uint8), np.arange(20, dtype=np.uint8)
    words = np.array([[0x0102030405060708, 7]] * 3, dtype=np.uint64)
    i8 = np.int64
    args = (np.array([2], i8), np.array([8], i8), np.array([0], i8),
            np.array([19], i8), np.array([1], i8), np.array([1], i8))
    valid = np.array([True, False, True])
    starts = np.empty(3, i8)
    out = np.zeros(3 * 10 + 2 * 20, np.uint8)
    assert fill_records(out[:-1], st_t, po_t, words, *args, valid, starts) == -1
    bad = (np.array([3], i8), *args[1:])                        # 3 + 8 > 10 bytes
    assert fill_records(out, st_t, po_t, words, *bad, valid, starts) == -1
    assert fill_records(out, st_t, po_t, words, *args, valid, starts) == len(out)
    np.testing.assert_array_equal(starts, [0, 30, 40])
    first = out[:30]
    np.testing.assert_array_equal(first[:2], [0, 1])
    np.testing.assert_array_equal(first[2:10], [8, 7, 6, 5, 4, 3, 2, 1])   # little endian
    assert first[10 + 19] == 7 and first[10] == 0                # pose part, 1 byte
    assert out[30 + 2] == 8 and out[40 + 10 + 19] == 7


@needs_numba
@pytest.mark.parametrize("seed", [20, 21])
def test_compiled_joint_values_equal_joint_values(seed):
    """Every joint in every FK slot (both modes, hinges wrapped near +-pi), to rounding."""
    rng = np.random.default_rng(seed)
    q = np.array(ak.robot.REFERENCE_Q) + rng.uniform(-0.04, 0.04, (60, 3))
    sol = ak.forward_kinematics(q, T, D)
    rows, slots = np.nonzero(sol.valid)
    assert len(set(slots.tolist())) > 4
    model = urdf_model(D, T)
    args = (q[rows], sol.p[rows, slots], sol.u[rows, slots], sol.T_b_s[rows, slots, :3, 3])
    want = joint_values(model, *args)
    got = _kernel_joint_values(model, *args)
    assert got.keys() == want.keys()
    for name in want:
        d = np.abs(np.angle(np.exp(1j * (got[name] - want[name]))))   # modulo 2 pi
        assert d.max() <= 4e-15, name
        assert (np.abs(got[name]) <= np.pi).all()
    # rows not valid are left as they are
    from athenakin.fast._frame_kernels import joint_values_into

    jv_args, _ = kernel_plan(model, (*MOVING_LINKS, TOOL_TIP_FRAME))
    out = np.full((len(rows), len(want)), -7.0)
    valid = np.arange(len(rows)) % 3 == 0
    joint_values_into(*(np.asarray(a, float) for a in args), valid, *jv_args, out)
    assert (out[~valid] == -7.0).all() and (out[valid] != -7.0).any()


@needs_numba
def test_compiled_link_frames_equal_link_poses(monkeypatch):
    rng = np.random.default_rng(17)
    q = np.array(ak.robot.REFERENCE_Q) + rng.uniform(-0.04, 0.04, (40, 3))
    sol = ak.forward_kinematics(q, T, D)
    rows, slots = np.nonzero(sol.valid)
    model = urdf_model(D, T)
    jv = joint_values(model, q[rows], sol.p[rows, slots], sol.u[rows, slots],
                      sol.T_b_s[rows, slots, :3, 3])
    links = (*MOVING_LINKS, TOOL_TIP_FRAME)
    out = np.full((len(rows), len(links) + 2, 9), np.nan)[:, 1:-1, 1:-1]   # a strided view
    got = link_frames(model, jv, links, out=out)
    assert got is out and np.isfinite(out).all()
    monkeypatch.setitem(_backend._STATE, "numba", False)
    ref = link_frames(model, jv, links)
    monkeypatch.undo()
    poses = link_poses(model, jv, links=links)
    for k, name in enumerate(links):
        np.testing.assert_allclose(got[:, k, :3], poses[name][:, :3, 3], rtol=0, atol=1e-12)
        np.testing.assert_allclose(got[:, k, :3], ref[:, k, :3], rtol=0, atol=1e-12)
        # quaternions: the same rotation (and w >= 0 on both sides)
        dot = np.abs(np.sum(got[:, k, 3:] * ref[:, k, 3:], axis=-1))
        np.testing.assert_allclose(dot, 1.0, rtol=0, atol=1e-12)
        assert (got[:, k, 6] >= 0).all()


def _mcap_with_late_channels(path, n):
    """An MCAP (mcap library's writer, large chunks) whose chunks define channels mid-way."""
    from mcap.writer import Writer

    store = _ros2_store()
    text = store.generate_msgdef("sensor_msgs/msg/JointState", ros_version=2)[0]
    pos = positions(q_stream(n, 18))
    st = stamps(n)
    with open(path, "wb") as fh:
        w = Writer(fh, chunk_size=1 << 20)
        w.start(profile="ros2", library="test")
        sid = w.register_schema("sensor_msgs/msg/JointState", "ros2msg", text.encode())
        cids = {"/joint_states": w.register_channel("/joint_states", "cdr", sid)}
        for i in range(n):
            data = store.serialize_cdr(_js(store, int(st[i]), pos[i], None, names=NAMES),
                                       "sensor_msgs/msg/JointState")
            w.add_message(cids["/joint_states"], int(st[i]), data, int(st[i]), i)
            if i == n // 2:
                cids["/late"] = w.register_channel("/late", "cdr", sid)
            if i > n // 2 and i % 10 == 0:
                w.add_message(cids["/late"], int(st[i]), data, int(st[i]), i)
        w.finish()
    return path


@needs_numba
def test_chunks_that_define_channels_are_read_in_bulk(tmp_path, monkeypatch):
    path = _mcap_with_late_channels(tmp_path / "late.mcap", 400)
    from mcap.reader import make_reader

    with open(path, "rb") as fh:
        n_messages = sum(1 for _ in make_reader(fh).iter_messages())
    calls = []
    real = _mcap_stream._scan

    def spy(data):
        calls.append(real(data))
        return calls[-1]

    monkeypatch.setattr(_mcap_stream, "_scan", spy)
    with open(path, "rb") as fh:
        stream = _mcap_stream._McapStream(fh, path.stat().st_size)
        items = list(stream.messages())
    assert calls and all(c is not None for c in calls)         # never record by record
    assert any(len(it) == 2 for c in calls for it in c)        # definitions in their place
    assert {ch[0] for ch in stream.channels.values()} == {"/joint_states", "/late"}
    assert all(isinstance(b, _mcap_stream._Bulk) for _, _, b in items)
    assert sum(len(t) for _, t, _ in items) == n_messages
    monkeypatch.undo()
    for topic in ("/joint_states", "/late"):
        fast = ak.ros.read_joint_states(path, topic=topic)
        monkeypatch.setitem(_backend._STATE, "numba", False)
        slow = ak.ros.read_joint_states(path, topic=topic)
        monkeypatch.undo()
        for f in ("stamps_ns", "q", "log_time_ns", "header_stamped"):
            np.testing.assert_array_equal(getattr(fast, f), getattr(slow, f))
        assert slow.qd is None and fast.qd is None


def test_rows_strided_view_equals_the_gather():
    rng = np.random.default_rng(19)
    data = rng.integers(0, 256, 1000, dtype=np.uint8)
    for offsets, even in ((np.arange(10, 900, 37), True), (np.array([5]), True),
                          (np.array([0, 37, 70, 111]), False),
                          (np.array([3, 50, 97, 144, 191]), True)):
        got = _mcap_stream._rows(data, offsets.astype(np.int64), 30)
        want = data[offsets[:, None] + np.arange(30)]
        np.testing.assert_array_equal(got, want)
        assert np.shares_memory(got, data) == even                # a view, or a gather
        assert got.flags.writeable != even                        # the view is read-only
    # past the end of the data: the gather raises as before, never a view past the end
    with pytest.raises(IndexError):
        _mcap_stream._rows(data, np.array([900, 950, 1000 - 20], np.int64), 30)
