"""``athenakin track RECORDING -o OUT.mcap``, ``plan -o traj.mcap``, ``app --foxglove``."""

import re
import time
from types import SimpleNamespace

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap_ros2")

from _ros_recordings import positions, q_stream, stamps, write_mcap, write_rosbag2  # noqa: E402, I001

import athenakin as ak  # noqa: E402
from athenakin.cli import main  # noqa: E402

D = ak.Design.default()
T = ak.default_rcm_frame(D)
SQUARE = "x_m,y_m,z_m\n0.25,0,0\n0.26,-0.01,0\n0.25,0,0.01\n"


def _counts(path):
    from mcap.reader import make_reader

    with open(path, "rb") as fh:
        s = make_reader(fh).get_summary()
    return {s.channels[k].topic: v for k, v in s.statistics.channel_message_counts.items()}


def test_track_bag_to_mcap(tmp_path, capsys):
    bag = write_rosbag2(tmp_path / "bag", positions(q_stream(30)), stamps(30))
    out = tmp_path / "out.mcap"
    assert main(["track", str(bag), "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "tracked 30 samples from slot 0 (mode +1); 0 flagged" in text
    assert f"wrote {out}" in text
    assert _counts(out) == {"/robot_description": 1, "/tf_static": 1, "/athena/status": 30,
                            "/athena/tool_tip": 30, "/tf": 30, "/athena/joint_states": 30}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bag", "out.mcap"]


def test_track_mcap_with_names_scale_and_nan(tmp_path, capsys):
    q = q_stream(20)
    names = ("m3", "m1", "m2")
    pos = (q[:, [2, 0, 1]] * 1000.0)
    pos[7, 1] = np.nan
    src = write_mcap(tmp_path / "mm.mcap", pos, stamps(20), names=names)
    out = tmp_path / "o.mcap"
    assert main(["track", str(src), "-o", str(out), "--joints", "m1,m2,m3",
                 "--scale", "0.001"]) == 0
    text = capsys.readouterr().out
    assert "LOST: 1 samples" in text and f"sample 7 (stamp {stamps(20)[7]} ns" in text
    counts = _counts(out)
    assert counts["/athena/status"] == 20 and counts["/athena/tool_tip"] == 19


def test_track_recording_to_csv(tmp_path, capsys):
    bag = write_rosbag2(tmp_path / "bag", positions(q_stream(12)), stamps(12))
    out = tmp_path / "out.csv"
    assert main(["track", str(bag), "-o", str(out)]) == 0
    lines = out.read_text().splitlines()
    assert len(lines) == 13
    t1 = float(lines[2].split(",")[1])
    assert t1 == pytest.approx(1.000003e-3, abs=1e-12)          # seconds from the first stamp


def test_track_csv_to_mcap(tmp_path, capsys):
    q = q_stream(10)
    rows = "\n".join(f"{i * 0.002!r},{a!r},{b!r},{c!r}" for i, (a, b, c) in enumerate(q.tolist()))
    src = tmp_path / "s.csv"
    src.write_text("t_s,q1_m,q2_m,q3_m\n" + rows + "\n")
    out = tmp_path / "s.mcap"
    assert main(["track", str(src), "-o", str(out)]) == 0
    js = ak.ros.read_joint_states(out, topic="/athena/joint_states")
    np.testing.assert_array_equal(js.stamps_ns, np.arange(10) * 2_000_000)


@pytest.mark.parametrize("extra, match", [
    (["--topic", "/nope"], r"no topic '/nope'; topics present: /chatter"),
    (["--joints", "a,b,c"], r"no joint named 'a'; names present: \['roll'"),
    (["--joints", "a,b"], r"--joints: expected 3 comma-separated names"),
    (["--topic", "/chatter"], r"holds std_msgs/msg/String, expected sensor_msgs/msg/JointState"),
])
def test_track_bad_recording_input_writes_nothing(extra, match, tmp_path, capsys):
    bag = write_rosbag2(tmp_path / "bag", positions(q_stream(5)), stamps(5))
    out = tmp_path / "out.mcap"
    assert main(["track", str(bag), "-o", str(out), *extra]) == 1
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert re.search(match, err), err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bag"]


def test_track_truncated_recording_writes_nothing(tmp_path, capsys):
    src = write_mcap(tmp_path / "a.mcap", positions(q_stream(300)), stamps(300))
    data = src.read_bytes()
    src.write_bytes(data[:len(data) // 2])
    assert main(["track", str(src), "-o", str(tmp_path / "o.mcap")]) == 1
    assert "truncated or corrupt" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mcap"]


def test_plan_to_mcap(tmp_path, capsys):
    src = tmp_path / "path.csv"
    src.write_text(SQUARE)
    out = tmp_path / "traj.mcap"
    assert main(["plan", str(src), "-o", str(out), "--no-plots", "--rate", "100"]) == 0
    counts = _counts(out)
    assert counts["/athena/trajectory"] == 1
    assert counts["/athena/tool_tip"] == counts["/athena/status"] > 10


def test_app_foxglove_port_is_checked(capsys):
    pytest.importorskip("viser")
    assert main(["app", "--foxglove", "70000"]) == 1
    assert "--foxglove: expected a port 0..65535" in capsys.readouterr().err


def test_serve_app_follows_q_and_setup(monkeypatch):
    """serve_app publishes what an app shows (q, slot) and follows a change of set-up."""
    from athenakin.ros import _live

    published = []
    orig = _live.FoxgloveStream.publish

    def spy(self, q, **kw):
        published.append((np.array(q), kw.get("slot")))
        return orig(self, q, **kw)

    monkeypatch.setattr(_live.FoxgloveStream, "publish", spy)
    setup = SimpleNamespace(design=D, T_b_e=T)
    app = SimpleNamespace(q=np.array([-0.1, 0.1, 0.45]), slot=0, setup=setup)
    live = _live.serve_app(app, port=0, rate=100.0)
    try:
        deadline = time.monotonic() + 10.0
        while not published and time.monotonic() < deadline:
            time.sleep(0.02)
        app.q = np.array([-0.11, 0.09, 0.46])
        app.slot = "all"
        d2 = ak.Design.default()
        app.setup = SimpleNamespace(design=d2, T_b_e=T.copy())
        while time.monotonic() < deadline and not (
                published and np.allclose(published[-1][0], app.q)):
            time.sleep(0.02)
    finally:
        live.stop()
    assert published and np.allclose(published[-1][0], [-0.11, 0.09, 0.46], atol=0)
    assert published[-1][1] is None and published[0][1] == 0
    assert live.T_b_e is not T           # the new set-up was taken


def test_track_refuses_a_fifo_without_blocking(tmp_path, capsys):
    import os

    if not hasattr(os, "mkfifo"):
        pytest.skip("no FIFOs here")
    fifo = tmp_path / "rec.mcap"
    os.mkfifo(fifo)
    assert main(["track", str(fifo), "-o", str(tmp_path / "o.mcap")]) == 1
    assert "not a regular file" in capsys.readouterr().err


@pytest.mark.parametrize("tty, flags, shown", [
    (True, [], True), (True, ["--no-progress"], False), (False, [], False)])
def test_track_progress_is_a_tqdm_bar_on_a_terminal_only(tmp_path, capsys, monkeypatch,
                                                         tty, flags, shown):
    """A tqdm bar of the readings on stderr when it is a terminal, unless --no-progress;
    stdout (the summary) is the same either way."""
    import sys

    pytest.importorskip("tqdm")
    src = write_mcap(tmp_path / "a.mcap", positions(q_stream(40)), stamps(40))
    monkeypatch.setattr(sys.stderr, "isatty", lambda: tty)
    assert main(["track", str(src), "-o", str(tmp_path / "o.mcap"), *flags]) == 0
    cap = capsys.readouterr()
    assert "tracked 40 samples" in cap.out and "readings" not in cap.out
    assert bool(re.search(r"track: 40(\.0)? readings \[", cap.err)) == shown
    assert "\r  40 readings" not in cap.err          # the hand-written counter is gone
