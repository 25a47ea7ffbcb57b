"""ROS and MCAP I/O, round 5 (issues 28 item 4 and 30 sections 1.7, 1.8, 2.1, 2.4, 2.5, 3.1,
3.4, 3.5): one atomic writer, the mcap library's reader with CRCs, truncated and empty
recordings, the fast path of rosbag2 folders and tracked files, a core-only install, named
errors and the millimetre hint.
"""

from __future__ import annotations

import errno
import os
import re
import socket
import stat
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import athenakin as ak
from athenakin import _output
from athenakin._compat import tomllib
from athenakin.cli import COMMANDS, EXTRAS, extra_of, main

pytest.importorskip("mcap")
pytest.importorskip("rosbags")

from _ros_recordings import (  # noqa: E402
    NAMES,
    positions,
    q_stream,
    stamps,
    write_mcap,
    write_rosbag2,
)

from athenakin.ros import (  # noqa: E402
    RecordingError,
    RecordingWarning,
    ServeError,
    _mcap_stream,
    _sources,
    read_joint_states,
    track_recording,
)

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
D = ak.Design.default()
T = ak.default_rcm_frame(D)


def _mcap_chunked(path: Path, pos: np.ndarray, st: np.ndarray, *, chunk_size: int = 4096,
                  topic: str = "/joint_states") -> Path:
    """A plain MCAP file of many small chunks (mcap-ros2-support's writer)."""
    from mcap_ros2.writer import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    text = store.generate_msgdef("sensor_msgs/msg/JointState", ros_version=2)[0]
    with open(path, "wb") as fh:
        w = Writer(fh, chunk_size=chunk_size)
        schema = w.register_msgdef("sensor_msgs/msg/JointState", text)
        for i in range(len(pos)):
            msg = {"header": {"stamp": {"sec": int(st[i] // 10**9),
                                        "nanosec": int(st[i] % 10**9)}, "frame_id": ""},
                   "name": list(NAMES), "position": pos[i].tolist(), "velocity": [],
                   "effort": []}
            w.write_message(topic, schema, msg, log_time=int(st[i]), publish_time=int(st[i]),
                            sequence=i)
        w.finish()
    return path


def _cli(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


# ---------------------------------------------------------------- one atomic writer
def test_no_umask_toggling_and_one_rename_in_src():
    """The writers share _output.AtomicFile: no os.umask anywhere, one os.replace."""
    hits = {"umask": [], "replace": []}
    for f in SRC.rglob("*.py"):
        text = f.read_text(encoding="utf-8")
        if "os.umask(" in text:
            hits["umask"].append(f.name)
        if "os.replace(" in text or "os.rename(" in text:
            hits["replace"].append(str(f.relative_to(SRC)))
    assert hits["umask"] == []
    assert hits["replace"] == ["athenakin/_output.py"]


def test_atomic_file_syncs_keeps_modes_and_never_reads_the_umask(tmp_path, monkeypatch):
    synced = []
    real_fsync = os.fsync
    monkeypatch.setattr(os, "fsync", lambda fd: (synced.append(fd), real_fsync(fd)))
    monkeypatch.setattr(os, "umask", lambda *a: pytest.fail("umask toggled"))
    new = tmp_path / "new.txt"
    _output.write_text_atomic(new, "a")
    assert new.read_text() == "a" and synced            # the file (and the folder) synced
    old = tmp_path / "old.txt"
    old.write_text("x")
    os.chmod(old, 0o640)
    with _output.atomic_write(old) as fh:
        fh.write(b"y")
    assert old.read_bytes() == b"y" and stat.S_IMODE(old.stat().st_mode) == 0o640
    with pytest.raises(RuntimeError), _output.atomic_path(tmp_path / "p.bin") as tmp:
        tmp.write_bytes(b"half")
        raise RuntimeError("boom")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["new.txt", "old.txt"]


def test_atomic_file_new_mode_follows_the_umask(tmp_path):
    old = os.umask(0o027)
    try:
        _output.write_text_atomic(tmp_path / "f.txt", "a")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "f.txt").stat().st_mode) == 0o640


def test_mcap_writer_names_the_path_on_a_full_disk(tmp_path, monkeypatch):
    from athenakin.ros import _mcap

    def full(self, *a, **k):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(_mcap.McapFile, "chunk", full)
    out = tmp_path / "o.mcap"
    with pytest.raises(OSError) as info:
        ak.ros.track_to_mcap(stamps(5), q_stream(5), out, T, D)
    assert info.value.errno == errno.ENOSPC and info.value.filename == str(out)
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------- missing extras
_BLOCK = ["sympy", "matplotlib", "plotly", "imageio", "imageio_ffmpeg", "tqdm", "scipy",
          "mujoco", "yourdfpy", "ruckig", "dask", "distributed", "pandas", "pyarrow", "pymoo",
          "pinocchio", "flint", "viser", "coal", "trimesh", "rosbags", "mcap", "mcap_ros2",
          "foxglove", "isal", "websockets", "zstandard", "lz4", "pytest_benchmark"]


def _core_only(argv: list[str], cwd: Path, block: list[str] = _BLOCK
               ) -> subprocess.CompletedProcess[str]:
    """The CLI in a fresh interpreter where every optional module fails to import."""
    code = ("import sys\n"
            f"for m in {block!r}: sys.modules[m] = None\n"
            "from athenakin.cli import main\n"
            f"sys.exit(main({[str(a) for a in argv]!r}))\n")
    env = {**os.environ, "PYTHONPATH": str(SRC), "ATHENAKIN_BACKEND": "numpy"}
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, env=env, text=True,
                          capture_output=True, timeout=600)


def test_mcap_output_without_zstandard_is_the_extra_message(tmp_path):
    """Issue 30 3.1: was AttributeError '_closed', exit 70."""
    (tmp_path / "t.csv").write_text("t_s,q1_m,q2_m,q3_m\n0,-0.1,0.1,0.45\n0.01,-0.1,0.1,0.451\n")
    r = _core_only(["track", "t.csv", "-o", "y.mcap"], tmp_path, ["zstandard"])
    assert r.returncode == 1, r.stderr
    assert "needs the optional package 'zstandard': pip install 'athenakin[ros]'" in r.stderr
    assert "tracked" not in r.stdout                 # said before any work
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.csv"]


def _command_lines(tmp: Path) -> list[list[str]]:
    (tmp / "t.csv").write_text("t_s,q1_m,q2_m,q3_m\n0,-0.1,0.1,0.45\n0.01,-0.1,0.1,0.451\n")
    (tmp / "wp.csv").write_text("x_m,y_m,z_m\n0.25,0,0\n0.25,0.01,0\n")
    (tmp / "bag").mkdir()
    (tmp / "bag" / "metadata.yaml").write_text("rosbag2_bagfile_information: {}\n")
    (tmp / "r.mcap").write_bytes(b"\x89MCAP0\r\n" + bytes(64))
    return [["fk", "-0.1", "0.1", "0.45"], ["ik", "--tip", "0.25", "0", "0"], ["demo"],
            ["plan", "wp.csv", "-o", "p.csv"], ["track", "t.csv"],
            ["track", "t.csv", "-o", "y.mcap"], ["track", "r.mcap"], ["track", "bag"],
            ["workspace", "--resolution", "5", "--out", "ws"],
            ["singularities", "--resolution", "5"], ["view", "-o", "v.png"],
            ["animate", "-o", "a.gif"], ["export", "-o", "m.xml"], ["derive"], ["design"],
            ["calibrate", "--plan", "3", "-o", "c.toml"],
            ["synthesize", "--designs", "2", "-o", "syn"], ["app"], ["warmup"],
            ["ros2", "arm", "--duration", "1"], ["setup", "phantom", "--write", "ph"]]


def test_core_only_install_runs_every_command_to_a_named_message(tmp_path):
    """Issue 30 3.1 / 3.4: no command of a core-only install ends in an internal error."""
    lines = _command_lines(tmp_path)
    assert {a[0] for a in lines} >= set(COMMANDS) - {"teleop"}
    wanted = {"plan": "motion", "synthesize": "synthesis", "track": "ros", "view": "plot",
              "derive": "symbolic", "app": "app", "ros2": "ros2", "setup": "collision"}
    for argv in lines:
        r = _core_only(argv, tmp_path)
        assert r.returncode in (0, 1), (argv, r.returncode, r.stderr[-2000:])
        assert "Traceback" not in r.stderr and "internal error" not in r.stderr, argv
        if r.returncode == 1:
            last = r.stderr.strip().splitlines()[-1]
            assert last.startswith(f"athenakin {argv[0]}: error: "), (argv, last)
            assert "None" not in last, (argv, last)
            if "optional package" in last and argv[0] in wanted:
                assert f"athenakin[{wanted[argv[0]]}]" in last, (argv, last)


def test_extras_table_matches_pyproject():
    aliases = {"pin": "pinocchio", "python-flint": "flint", "mcap-ros2-support": "mcap_ros2",
               "foxglove-sdk": "foxglove", "imageio-ffmpeg": "imageio_ffmpeg",
               "pytest-benchmark": "pytest_benchmark", "catkin-pkg": "catkin_pkg"}
    aliases.update({n: n[4:].replace("-", "_") for r in (ROOT / "pyproject.toml").read_text()
                    .split('"') if (n := r.split(">")[0]).startswith("ros-")})
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"]
    def modules(name):
        mods = set()
        for r in extras[name]:
            ref = re.fullmatch(r"athenakin\[([a-z,]+)\]", r)
            if ref:                       # an extra that references others
                mods |= set().union(*(modules(e) for e in ref.group(1).split(",")))
            else:
                n = re.split(r"[<>=!~;\[ ]", r, maxsplit=1)[0]
                mods.add(aliases.get(n, n).replace("-", "_"))
        return mods

    for name in extras:
        if name != "all":
            assert set(EXTRAS[name]) == modules(name), name
    assert set(EXTRAS) == set(extras) - {"all"}
    assert extra_of("scipy", "plan") == "motion" and extra_of("pandas", "synthesize") == \
        "synthesis" and extra_of("zstandard") == "ros"


def test_debug_is_accepted_after_the_subcommand(tmp_path, capsys):
    with pytest.raises(OSError):        # --debug: the error propagates (no exit code)
        main(["track", str(tmp_path / "missing.csv"), "--debug"])
    code, _, err = _cli(["track", str(tmp_path / "missing.csv")], capsys)
    assert code == 1 and "--debug" not in err


def test_ros_extra_missing_names_the_package():
    from athenakin.ros._errors import ros_extra_missing

    exc = ros_extra_missing(ModuleNotFoundError("No module named 'lz4.frame'", name="lz4.frame"))
    assert exc.name == "lz4" and "'lz4'" in str(exc)


# ---------------------------------------------------------------- the MCAP reader
def test_bad_chunk_crc_is_a_named_error(tmp_path):
    src = _mcap_chunked(tmp_path / "a.mcap", positions(q_stream(600)), stamps(600))
    data = bytearray(src.read_bytes())
    at = data.find(b"\x06", 8 + 9 + 4)                  # the first Chunk record
    crc_at = at + 9 + 8 + 8 + 8                          # op, length, start, end, size
    data[crc_at] ^= 0xFF
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    with pytest.raises(RecordingError, match="fails its CRC check"):
        read_joint_states(bad)


def test_truncated_mcap_is_read_to_its_last_complete_chunk(tmp_path):
    n = 3000
    pos, st = positions(q_stream(n)), stamps(n)
    src = _mcap_chunked(tmp_path / "a.mcap", pos, st)
    full = read_joint_states(src)
    data = src.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[:len(data) * 2 // 3])
    with pytest.warns(RecordingWarning, match=r"truncated MCAP file.*could not be read"):
        part = read_joint_states(cut)
    assert 0.5 * n < len(part) < 0.8 * n        # the summary at the end is lost too
    np.testing.assert_array_equal(part.q, full.q[:len(part)])
    np.testing.assert_array_equal(part.stamps_ns, full.stamps_ns[:len(part)])



def test_truncated_mcap_in_the_cli_is_one_warning_line(tmp_path, capsys):
    src = _mcap_chunked(tmp_path / "a.mcap", positions(q_stream(3000)), stamps(3000))
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(src.read_bytes()[:src.stat().st_size // 2])
    for extra in ([], ["-o", tmp_path / "o.mcap"]):
        code, out, err = _cli(["track", cut, *extra], capsys)
        assert code == 0 and "tracked" in out
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("athenakin track: warning: ")
        assert "truncated MCAP file" in lines[0] and "% of the file" in lines[0]


def test_truncated_before_any_chunk_is_refused(tmp_path):
    src = write_mcap(tmp_path / "a.mcap", positions(q_stream(400)), stamps(400))
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(src.read_bytes()[:int(src.stat().st_size * 0.6)])
    with pytest.raises(RecordingError, match="no complete chunk"):
        read_joint_states(cut)


def test_rosbag2_mcap_folder_takes_the_fast_path(tmp_path, monkeypatch):
    n = 500
    pos, st = positions(q_stream(n)), stamps(n)
    bag = write_rosbag2(tmp_path / "bag", pos, st, storage="mcap")
    calls = []
    real = _sources._mcap_messages
    monkeypatch.setattr(_sources, "_mcap_messages",
                        lambda *a, **k: (calls.append(a[0]), real(*a, **k))[1])
    from rosbags.rosbag2 import Reader

    monkeypatch.setattr(Reader, "messages", lambda *a, **k: pytest.fail("message by message"))
    js = read_joint_states(bag)
    assert calls and js.source == "rosbag2/mcap" and len(js) == n
    monkeypatch.undo()
    ref = read_joint_states(write_mcap(tmp_path / "ref.mcap", pos, st))
    np.testing.assert_array_equal(js.q, ref.q)
    np.testing.assert_array_equal(js.stamps_ns, ref.stamps_ns)


def test_tracked_mcap_joint_states_read_back_in_runs(tmp_path, monkeypatch):
    """A tracked file interleaves four topics: the joint states of a chunk make one run."""
    n = 5000
    q = q_stream(n)
    out = tmp_path / "t.mcap"
    ak.ros.track_to_mcap(stamps(n), q, out, T, D)
    runs = []
    real = _mcap_stream._McapStream._runs

    def spy(self, *a):
        items = list(real(self, *a))
        runs.extend(len(t) for _, t, _ in items)
        yield from items

    monkeypatch.setattr(_mcap_stream._McapStream, "_runs", spy)
    joints = tuple(list(ak.sim.JOINTS)[:3])
    js = read_joint_states(out, topic="/athena/joint_states", joints=joints)
    assert len(js) == n
    if ak._dispatch.numba_available():
        assert runs and max(runs) > 1000
    monkeypatch.undo()
    monkeypatch.setitem(ak._dispatch._STATE, "numba", False)      # message by message
    ref = read_joint_states(out, topic="/athena/joint_states", joints=joints)
    np.testing.assert_array_equal(js.q, ref.q)
    np.testing.assert_array_equal(js.stamps_ns, ref.stamps_ns)


# ---------------------------------------------------------------- empty topics
def test_empty_topic_reads_zero_and_tracking_it_is_an_error(tmp_path, capsys):
    src = write_rosbag2(tmp_path / "bag", positions(q_stream(0)), stamps(1), storage="mcap")
    assert len(read_joint_states(src)) == 0
    with pytest.raises(RecordingError, match="holds no message"):
        track_recording(src, tmp_path / "o.mcap", T, D)
    assert not (tmp_path / "o.mcap").exists()
    for extra in ([], ["-o", tmp_path / "o.mcap"]):
        code, _, err = _cli(["track", src, *extra], capsys)
        assert code == 1 and "holds no message" in err


# ---------------------------------------------------------------- the track command
def test_first_reading_lost_exits_the_same_with_and_without_output(tmp_path, capsys):
    q = q_stream(200)
    q[0] = [-5.0, 5.0, 5.0]                                # out of stroke
    src = write_mcap(tmp_path / "a.mcap", positions(q), stamps(200))
    codes = []
    for extra in ([], ["-o", tmp_path / "o.mcap"], ["-o", tmp_path / "o.csv"]):
        code, out, err = _cli(["track", src, *extra], capsys)
        codes.append(code)
        assert "q0" not in out + err
    assert codes == [0, 0, 0]
    csv = tmp_path / "s.csv"
    csv.write_text("q1_m,q2_m,q3_m\n-5,5,5\n" + "".join(f"{a},{b},{c}\n" for a, b, c in q[1:]))
    code, out, err = _cli(["track", csv], capsys)
    assert code == 0 and "starts at reading 1" in out and "q0" not in out + err


def test_mcap_named_file_that_is_not_mcap_is_not_read_as_csv(tmp_path, capsys):
    f = tmp_path / "x.mcap"
    f.write_text("q1_m,q2_m,q3_m\n-0.1,0.1,0.45\n")
    code, _, err = _cli(["track", f], capsys)
    assert code == 1 and "RecordingError" in err and "not a recording" in err


def test_nul_bytes_are_not_echoed(tmp_path, capsys):
    f = tmp_path / "zeros"
    f.write_bytes(bytes(4096))
    code, _, err = _cli(["track", f], capsys)
    assert code == 1 and "\x00" not in err and len(err) < 300 and "NUL" in err


def test_track_recording_chunk_size_has_a_lower_bound():
    with pytest.raises(ak.errors.InvalidInputError, match="chunk_size: expected an integer "
                                                          "from 1024"):
        ak.ros.TrackOptions(chunk_size=7)


# ---------------------------------------------------------------- millimetres typed
def test_millimetres_typed_get_the_hint(tmp_path, capsys):
    hint = "millimetres typed?"
    code, _, err = _cli(["fk", "-100", "100", "450"], capsys)
    assert code == 1 and hint in err
    code, _, err = _cli(["ik", "--tip", "250", "0", "0"], capsys)
    assert code == 1 and hint in err
    q_mm = q_stream(50) * 1000
    csv = tmp_path / "mm.csv"
    csv.write_text("q1_m,q2_m,q3_m\n" + "".join(f"{a},{b},{c}\n" for a, b, c in q_mm))
    code, _, err = _cli(["track", csv], capsys)
    assert code == 1 and hint in err and "none of the 50 readings has a pose" in err
    rec = write_mcap(tmp_path / "mm.mcap", positions(q_stream(50), 0.001), stamps(50))
    for extra in ([], ["-o", tmp_path / "o.mcap"]):
        code, _, err = _cli(["track", rec, *extra], capsys)
        assert code == 1 and hint in err and "--scale 0.001" in err
    assert not (tmp_path / "o.mcap").exists()


# ---------------------------------------------------------------- the live stream
def test_foxglove_on_a_port_in_use_is_a_named_error():
    pytest.importorskip("foxglove")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        with pytest.raises(ServeError, match=f"127.0.0.1:{port}: the port is in use") as info:
            ak.ros.FoxgloveStream(port=port)
    assert isinstance(info.value, OSError) and info.value.errno == errno.EADDRINUSE


def test_no_warning_on_a_complete_file(tmp_path):
    src = _mcap_chunked(tmp_path / "a.mcap", positions(q_stream(300)), stamps(300))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(read_joint_states(src)) == 300
