"""The MCAP reader's vectorised path (runs of one CDR layout) equals its message-by-message path."""

import numpy as np
import pytest
from _ros_recordings import NAMES, _js, _ros2_store, positions, q_stream, stamps

import athenakin as ak
from athenakin import _backend
from athenakin.ros import RecordingError

needs_numba = pytest.mark.skipif(not _backend.numba_available(),
                                 reason="numba not available here: the vectorised path needs it")

SEED = 2211


def write(path, msgs, chunk_size=6000):
    """MCAP of (topic, log_ns, cdr bytes) with the mcap library's writer (small chunks)."""
    from mcap.writer import Writer

    store = _ros2_store()
    text = store.generate_msgdef("sensor_msgs/msg/JointState", ros_version=2)[0]
    with open(path, "wb") as fh:
        w = Writer(fh, chunk_size=chunk_size)
        w.start(profile="ros2", library="test")
        sid = w.register_schema("sensor_msgs/msg/JointState", "ros2msg", text.encode())
        cids = {}
        for i, (topic, t, data) in enumerate(msgs):
            if topic not in cids:
                cids[topic] = w.register_channel(topic, "cdr", sid)
            w.add_message(cids[topic], t, data, t, i)
        w.finish()
    return path


def mixed(n, rng, *, backwards_at=None):
    """Readings whose layout changes: names reordered, velocities on and off, a longer
    frame id, zero header stamps, and a second topic interleaved."""
    store = _ros2_store()
    q = q_stream(n, SEED)
    pos = positions(q)
    st = stamps(n)
    if backwards_at is not None:
        st[backwards_at] = st[backwards_at - 1] - 5
    out = []
    order = np.array(NAMES)
    for i in range(n):
        names, p = NAMES, pos[i]
        if i >= n // 3:                                  # another order of the names
            perm = [2, 0, 4, 3, 1]
            names, p = tuple(order[perm]), pos[i][perm]
        vel = p * 0.5 if (i // 50) % 2 else None
        stamp = 0 if i % 97 == 5 else int(st[i])
        m = _js(store, stamp, p, vel, names=names)
        if i % 200 == 150:
            m.header.frame_id = "encoders"
        out.append(("/joint_states", int(st[i]) + 17, store.serialize_cdr(
            m, "sensor_msgs/msg/JointState")))
        if rng.random() < 0.05:
            out.append(("/other", int(st[i]) + 18, out[-1][2]))
    return out


def both(monkeypatch, fn):
    fast = fn()
    monkeypatch.setitem(_backend._STATE, "numba", False)
    try:
        slow = fn()
    finally:
        monkeypatch.setitem(_backend._STATE, "numba", True)
    return fast, slow


def assert_same(a, b):
    for f in ("stamps_ns", "q", "qd", "log_time_ns", "header_stamped"):
        x, y = getattr(a, f), getattr(b, f)
        if x is None or y is None:
            assert x is None and y is None, f
            continue
        assert x.dtype == y.dtype and np.array_equal(x, y, equal_nan=True), f


@needs_numba
@pytest.mark.parametrize("chunk", [37, 1000, 65536])
def test_vectorised_read_equals_message_by_message(tmp_path, monkeypatch, chunk):
    rng = np.random.default_rng(SEED)
    path = write(tmp_path / "mixed.mcap", mixed(1500, rng))
    fast, slow = both(monkeypatch, lambda: list(ak.ros.iter_joint_states(
        path, chunk_size=chunk, scale=0.001)))
    assert len(fast) == len(slow) and sum(len(c.q) for c in fast) == 1500
    for a, b in zip(fast, slow, strict=True):
        assert_same(a, b)
    assert any(c.qd is not None for c in fast) and not fast[0].header_stamped.all()


@needs_numba
@pytest.mark.parametrize("chunk", [64, 65536])
def test_vectorised_read_raises_where_the_stamps_go_back(tmp_path, monkeypatch, chunk):
    rng = np.random.default_rng(SEED + 1)
    path = write(tmp_path / "back.mcap", mixed(900, rng, backwards_at=700))

    def run():
        got = []
        with pytest.raises(RecordingError) as ei:
            for c in ak.ros.iter_joint_states(path, chunk_size=chunk):
                got.append(c)
        return got, str(ei.value)

    (fc, fm), (sc, sm) = both(monkeypatch, run)
    assert fm == sm and "backwards at message 700" in fm
    assert len(fc) == len(sc)
    for a, b in zip(fc, sc, strict=True):
        assert_same(a, b)


@needs_numba
def test_vectorised_read_missing_joint_named(tmp_path, monkeypatch):
    rng = np.random.default_rng(SEED + 2)
    path = write(tmp_path / "m.mcap", mixed(300, rng))

    def run():
        with pytest.raises(RecordingError) as ei:
            ak.ros.read_joint_states(path, joints=("q1", "q2", "wrist"))
        return str(ei.value)

    fast, slow = both(monkeypatch, run)
    assert fast == slow and "no joint named 'wrist'" in fast
