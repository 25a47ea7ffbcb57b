"""Benchmark cases of athenakin.ros: tracking a recording end to end, MCAP vs CSV.

Group ``ros-track`` (batch = readings; "poses/s" is readings per second):

* baseline: the CSV path of ``athenakin track STREAM.csv -o OUT.csv`` (read the CSV, track,
  write the tracked CSV);
* ``track_recording``: MCAP of ``sensor_msgs/JointState`` in, MCAP of the ROS 2 topics out
  (decode, track, encode every topic, write), the path of ``athenakin track REC -o OUT.mcap``
  (target of issue 22: >= 200k readings/s on one core);
* its parts: decoding alone (``read_joint_states``), tracking alone (``motion.track``, the
  compiled batched tracker; beside it ``Tracker.update`` called once per reading, the
  live API), encoding and writing alone (``write_track_log``).

Every note ends with the load average measured when the case last ran (a shared machine
slows everything; compare ratios within one run).
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

    def __str__(self) -> str:
        load = "n/a" if self.load is None else ", ".join(f"{x:.2f}" for x in self.load)
        return f"{self.text}; load {load}"


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

    def csv_path():
        qq, tt = read_q_stream_csv(csv)
        write_text_atomic(tmp / "out.csv", track_csv_text(track(qq, T, d), tt))

    notes = {k: _Note(v) for k, v in {
        "csv": "athenakin track STREAM.csv -o OUT.csv: read, track, write",
        "mcap": "decode + track + encode + write; target >= 200k readings/s",
        "decode": "read_joint_states of an MCAP file",
        "track": "motion.track alone (the compiled batched tracker)",
        "update": "Tracker.update once per reading (the live API, Python)",
        "encode": "write_track_log: every topic encoded and written",
        "zstd": "zstd level 1 of the output's bytes in 4 MB pieces, as the writer's chunks"
        }.items()}
    raw = _raw_output(tmp, stamps, log, T, d)
    return [
        {"name": "CSV in, track, CSV out", "group": "ros-track", "batch": n, "baseline": True,
         "call": _timed(notes["csv"], csv_path), "note": notes["csv"]},
        {"name": "MCAP in, track, MCAP out (track_recording)", "group": "ros-track",
         "batch": n, "note": notes["mcap"],
         "call": _timed(notes["mcap"], lambda: ak.ros.track_recording(rec, tmp / "o.mcap",
                                                                      T, d))},
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
             tmp / "o2.mcap", stamps, log, T, d))},
        {"name": "compress only (zstd level 1 of the output)", "group": "ros-track",
         "batch": n, "note": notes["zstd"], "call": _timed(notes["zstd"], lambda: _zstd(raw))},
    ]


def _raw_output(tmp: Path, stamps: np.ndarray, log, T: np.ndarray, d: ak.Design) -> list[bytes]:
    """The bytes of the MCAP output written without compression, in 4 MB pieces."""
    from athenakin.ros._track import _FIELDS, tracked_batch
    from athenakin.ros._write import McapOutput

    with McapOutput(tmp / "raw.mcap", d, T, compression="none") as w:
        w.write_tracked(tracked_batch(stamps, {f: getattr(log, f) for f in _FIELDS}))
    data = (tmp / "raw.mcap").read_bytes()
    return [data[k:k + 4 * 2**20] for k in range(0, len(data), 4 * 2**20)]


def _zstd(raw: list[bytes]) -> None:
    import zstandard

    c = zstandard.ZstdCompressor(level=1)
    for piece in raw:
        c.compress(piece)
