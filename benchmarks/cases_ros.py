"""Benchmark cases of athenakin.ros: tracking a recording end to end, MCAP vs CSV.

Group ``ros-track`` (batch = readings; "poses/s" is readings per second):

* baseline: the CSV path of ``athenakin track STREAM.csv -o OUT.csv`` (read the CSV, track,
  write the tracked CSV);
* ``track_recording``: MCAP of ``sensor_msgs/JointState`` in, MCAP of the ROS 2 topics out
  (decode, track, encode every topic, write), the path of ``athenakin track REC -o OUT.mcap``
  (target of issue 22: >= 200k readings/s on one core);
* the same with the other chunk compressions: zstd level 1 (the default before
  issue 22's speed work), lz4;
* its parts: decoding alone (``read_joint_states``), tracking alone (``motion.track``, the
  compiled batched tracker; beside it ``Tracker.update`` called once per reading, the
  live API), encoding and writing alone (``write_track_log``), compressing the output's
  bytes alone (zstd at the default level and at level 1).

Each call writes a new file (as ``athenakin track REC -o NEW.mcap`` does), up to 64 per
case: replacing an earlier call's output would add the file system's cost of freeing it
(about 15 ms for 13 MB here), which is not tracking. Every note ends with the load
average measured when the case last ran (a shared machine slows everything; compare ratios
within one run).
"""

import atexit
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np

import athenakin as ak
from athenakin.motion import track
from athenakin.motion._io import read_q_stream_csv, track_csv_text, write_text_atomic


class _Note:
    """A case note that ends with the load average of the case's last call."""

    def __init__(self, text: str) -> None:
        self.text = text
        self.load = None
        self.size = None        # bytes per reading of the file written, where one is

    def __str__(self) -> str:
        load = "n/a" if self.load is None else ", ".join(f"{x:.2f}" for x in self.load)
        size = "" if self.size is None else f"; {self.size:.0f} B per reading"
        return f"{self.text}{size}; load {load}"


def _timed(note: _Note, fn):
    def call():
        fn()
        note.load = os.getloadavg()
    return call


def _recording(path: Path, q: np.ndarray, stamps: np.ndarray) -> None:
    """A plain MCAP of JointState (names q1, q2, q3 among two others), mcap-ros2-support's
    writer would take minutes at this size: the messages are encoded with athenakin.ros'
    CDR templates and written with the mcap library."""
    from mcap.writer import Writer

    from athenakin.ros._cdr import CdrBuilder, split_stamps
    from athenakin.ros._write import msgdef

    b = CdrBuilder()
    b.header("")
    b.strings(("roll", "q3", "q1", "q2", "gripper"))
    b.f8_seq("pos", 5)
    b.num("u4", 0)
    b.num("u4", 0)
    sec, nsec = split_stamps(stamps)
    data = b.template().encode(len(q), {"stamp.sec": sec, "stamp.nanosec": nsec,
                                        "pos.0": 0.0, "pos.1": q[:, 2], "pos.2": q[:, 0],
                                        "pos.3": q[:, 1], "pos.4": 0.0})
    with open(path, "wb") as fh:
        w = Writer(fh)
        w.start(profile="ros2", library="benchmarks")
        sid = w.register_schema("sensor_msgs/msg/JointState", "ros2msg",
                                msgdef("sensor_msgs/msg/JointState").encode())
        cid = w.register_channel("/joint_states", "cdr", sid)
        for i in range(len(q)):
            w.add_message(cid, int(stamps[i]), data[i].tobytes(), int(stamps[i]), i)
        w.finish()


def _update_loop(q: np.ndarray, T: np.ndarray, d: ak.Design) -> None:
    tr = ak.motion.Tracker(T, d, q0=q[0])
    up = tr.update
    for row in q[1:].tolist():
        up(row)


class _Fresh:
    """A new output path for each call, in the run's temporary folder (at most ``keep``
    names, then reused)."""

    def __init__(self, folder: Path, stem: str, suffix: str, keep: int = 64) -> None:
        self.folder, self.stem, self.suffix, self.keep, self.k = folder, stem, suffix, keep, 0

    def __call__(self) -> Path:
        self.k += 1
        return self.folder / f"{self.stem}{self.k % self.keep}{self.suffix}"


def cases(quick: bool) -> list[dict]:
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    n = 1000 if quick else 20000
    t = np.arange(n) * 1e-3
    q = np.array([-0.10, 0.10, 0.45]) + 0.01 * np.column_stack(
        [np.sin(2 * t), np.cos(1.3 * t) - 1.0, np.sin(0.7 * t)])
    stamps = 1_700_000_000_000_000_000 + np.arange(n, dtype=np.int64) * 1_000_000
    tmp = Path(tempfile.mkdtemp(prefix="athenakin-bench-ros-"))
    atexit.register(shutil.rmtree, tmp, True)
    rec = tmp / "rec.mcap"
    _recording(rec, q, stamps)
    csv = tmp / "rec.csv"
    csv.write_text("t_s,q1_m,q2_m,q3_m\n" + "".join(
        f"{a!r},{b!r},{c!r},{e!r}\n" for a, (b, c, e) in zip(t.tolist(), q.tolist(),
                                                             strict=True)))
    log = track(q, T, d)

    out_csv = _Fresh(tmp, "out", ".csv")

    def csv_path():
        qq, tt = read_q_stream_csv(csv)
        write_text_atomic(out_csv(), track_csv_text(track(qq, T, d), tt))

    level = ak.ros._mcap.ZSTD_LEVEL
    notes = {k: _Note(v) for k, v in {
        "csv": "athenakin track STREAM.csv -o OUT.csv: read, track, write",
        "mcap": f"decode + track + encode + write, zstd level {level} (the default); target "
                f">= 200k readings/s",
        "mcap-zstd1": "the same, zstd level 1 (the default before the speed work)",
        "mcap-lz4": "the same, lz4 chunks",
        "decode": "read_joint_states of an MCAP file",
        "track": "motion.track alone (the compiled batched tracker)",
        "update": "Tracker.update once per reading (the live API, Python)",
        "encode": f"write_track_log: every topic encoded and written (zstd level {level})",
        "zstd": f"zstd level {level} of the output's bytes (not compressed) in 4 MB pieces, "
                f"as the writer's chunks",
        "zstd1": "zstd level 1 of the output's bytes (not compressed) in 4 MB pieces",
        "fsync": "write + fsync of a file of the tracked MCAP's size: the part of the end-to-end "
                 "time that durability costs (absent at 6c198b4)",
        }.items()}
    raw = _raw_output(tmp, stamps, log, T, d)
    notes["zstd"].size = notes["zstd1"].size = sum(len(x) for x in raw) / n

    def mcap(note: _Note, stem: str, **kw):
        out = _Fresh(tmp, stem, ".mcap")

        def call():
            path = out()
            ak.ros.track_recording(rec, path, T, d, options=ak.ros.TrackOptions(**kw))
            note.size = path.stat().st_size / n
        return call

    out_log = _Fresh(tmp, "log", ".mcap")
    out_sync = _Fresh(tmp, "sync", ".bin")

    return [
        {"name": "CSV in, track, CSV out", "group": "ros-track", "batch": n, "baseline": True,
         "call": _timed(notes["csv"], csv_path), "note": notes["csv"]},
        {"name": "MCAP in, track, MCAP out (track_recording)", "group": "ros-track",
         "batch": n, "note": notes["mcap"],
         "call": _timed(notes["mcap"], mcap(notes["mcap"], "zstd_default"))},
        {"name": "MCAP in, track, MCAP out, zstd level 1", "group": "ros-track",
         "batch": n, "note": notes["mcap-zstd1"],
         "call": _timed(notes["mcap-zstd1"], mcap(notes["mcap-zstd1"], "zstd1_",
                                                     compression_level=1))},
        {"name": "MCAP in, track, MCAP out, lz4", "group": "ros-track",
         "batch": n, "note": notes["mcap-lz4"],
         "call": _timed(notes["mcap-lz4"], mcap(notes["mcap-lz4"], "lz4_", compression="lz4"))},
        {"name": "decode only (read_joint_states)", "group": "ros-track", "batch": n,
         "note": notes["decode"],
         "call": _timed(notes["decode"], lambda: ak.ros.read_joint_states(rec))},
        {"name": "track only (motion.track)", "group": "ros-track", "batch": n,
         "note": notes["track"], "call": _timed(notes["track"], lambda: track(q, T, d))},
        {"name": "track only, Tracker.update per reading", "group": "ros-track", "batch": n,
         "note": notes["update"], "call": _timed(notes["update"], lambda: _update_loop(q, T, d))},
        {"name": "encode + write only (write_track_log)", "group": "ros-track", "batch": n,
         "note": notes["encode"],
         "call": _timed(notes["encode"], lambda: ak.ros._track.write_track_log(
             out_log(), stamps, log, T, d))},
        {"name": f"compress only (zstd level {level} of the output)", "group": "ros-track",
         "batch": n, "note": notes["zstd"],
         "call": _timed(notes["zstd"], lambda: _zstd(raw, level))},
        {"name": "compress only (zstd level 1 of the output)", "group": "ros-track",
         "batch": n, "note": notes["zstd1"],
         "call": _timed(notes["zstd1"], lambda: _zstd(raw, 1))},
        {"name": "fsync only (the output's size, as the atomic writer does)", "group": "ros-track",
         "batch": n, "note": notes["fsync"], "call": _timed(notes["fsync"], lambda: _fsync(
             out_sync(), notes["mcap"].size or 100.0, n))},
    ]


def _fsync(path: Path, bytes_per_reading: float, n: int) -> None:
    """Write and fsync a file of the tracked MCAP's size: the durability cost that
    ``athenakin._output.AtomicFile`` adds to every written file (issue 28, item 4)."""
    with open(path, "wb") as fh:
        fh.write(bytes(int(bytes_per_reading * n)))
        fh.flush()
        os.fsync(fh.fileno())


def _raw_output(tmp: Path, stamps: np.ndarray, log, T: np.ndarray, d: ak.Design) -> list[bytes]:
    """The bytes of the MCAP output written without compression, in 4 MB pieces."""
    from athenakin.ros._track import _FIELDS, tracked_batch
    from athenakin.ros._write import McapOutput

    with McapOutput(tmp / "raw.mcap", T, d, compression="none") as w:
        w.write_tracked(tracked_batch(stamps, {f: getattr(log, f) for f in _FIELDS}))
    data = (tmp / "raw.mcap").read_bytes()
    return [data[k:k + 4 * 2**20] for k in range(0, len(data), 4 * 2**20)]


def _zstd(raw: list[bytes], level: int) -> None:
    import zstandard

    c = zstandard.ZstdCompressor(level=level)
    for piece in raw:
        c.compress(piece)
