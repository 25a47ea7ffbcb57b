"""``athenakin track``: replay a recorded actuator stream through the continuity tracker."""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import stat
import sys
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ._collision import add_collision_options, collision_options
from ._common import add_robot_options, check_count, check_finite, fmt, load_robot, mm_hint
from ._output import Outputs, add_force_option, outputs

if TYPE_CHECKING:
    from ..design import Design
    from ..motion import TrackLog

#: Smallest jump threshold (mm or deg): below it, the threshold in SI units underflows.
JUMP_MIN = 1e-6
#: Flags that make ``--strict`` fail (``COLLISION`` only appears with the collision check).
STRICT_FLAGS = ("LOST", "JUMP", "MODE_SWITCH", "AMBIGUOUS", "COLLISION")


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``track`` subcommand."""
    p = sub.add_parser(
        "track", help="replay a recorded q stream (CSV, ROS bag, MCAP) through the pose tracker",
        description="Read actuator readings (a CSV with columns q1_m,q2_m,q3_m, optional t_s, "
                    "other columns ignored, so a trajectory from 'athenakin plan' replays as "
                    "is; or a ROS recording of sensor_msgs/JointState: a rosbag2 folder, an "
                    "MCAP file or a ROS 1 bag, extra 'ros'), follow the forward-kinematics "
                    "solution continuous with the first sample, and report every flagged "
                    "sample (mode or branch switch, jump, ambiguity, loss, approach to a "
                    "singularity). -o OUT.mcap writes the poses, frames and joints as ROS 2 "
                    "topics for Foxglove / RViz. Columns: docs/motion.md; topics: docs/ros.md.")
    p.add_argument("path", type=Path, metavar="RECORDING",
                   help="recorded readings: STREAM.csv, a rosbag2 folder, an MCAP file or a "
                        "ROS 1 bag")
    p.add_argument("-o", "--output", type=Path, metavar="OUT",
                   help="write the tracked poses (.csv, .json, or .mcap: ROS 2 topics)")
    p.add_argument("--topic", default="/joint_states",
                   help="JointState topic of a ROS recording (/joint_states)")
    p.add_argument("--joints", default="q1,q2,q3", metavar="J1,J2,J3",
                   help="names of the joints read as q1, q2, q3 in a ROS recording (q1,q2,q3)")
    p.add_argument("--scale", type=float, default=1.0,
                   help="factor from the recording's unit to m (0.001 for mm encoders; 1)")
    p.add_argument("--slot", type=int, default=None,
                   help="FK slot (0-15) of the first reading (default: mode +1, p > 0, "
                        "branches +1)")
    p.add_argument("--jump-mm", type=float, default=5.0,
                   help="jump threshold on O_s between samples, mm (5)")
    p.add_argument("--jump-deg", type=float, default=math.degrees(0.1),
                   help="jump threshold on the passive angles between samples, deg (5.73)")
    p.add_argument("--margin", action="append", default=[], metavar="NAME=VALUE",
                   help="singularity watch margin (half_chord, h, link, p in m; sin_u2, sin_u4)")
    p.add_argument("--strict", action="store_true",
                   help=f"exit with status 1 if any sample is flagged {', '.join(STRICT_FLAGS)}")
    p.add_argument("--max-events", type=int, default=20, help="events listed (20)")
    p.add_argument("--no-progress", action="store_true",
                   help="no progress bar (a ROS recording tracked into an MCAP file shows "
                        "one on a terminal)")
    add_collision_options(p, what="closer samples are flagged NEAR_COLLISION, overlapping "
                                   "ones COLLISION")
    add_force_option(p)
    add_robot_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Execute ``track``."""
    out = args.output
    for opt, v, hi in (("--jump-mm", args.jump_mm, 1e6), ("--jump-deg", args.jump_deg, 360.0)):
        if not JUMP_MIN <= v <= hi:
            raise ValueError(f"{opt}: expected a threshold from {JUMP_MIN:g} to {hi:g}, got {v:g}")
    check_count(args.max_events, "--max-events", 0, 10**9, "events")
    if out is not None and Path(out).suffix.lower() not in (".csv", ".json", ".mcap"):
        raise ValueError(f"-o: expected a .csv or .json file name, or .mcap (ROS 2 topics), got "
                         f"{str(out)!r}")
    joints = tuple(j.strip() for j in args.joints.split(","))
    if len(joints) != 3 or not all(joints):
        raise ValueError(f"--joints: expected 3 comma-separated names (J1,J2,J3), got "
                         f"{args.joints!r}")
    args.joint_names = joints
    check_finite(args.scale, "--scale", positive=True)
    if not args.topic.startswith("/") or any(c.isspace() or not c.isprintable()
                                             for c in args.topic):
        raise ValueError(f"--topic: expected an absolute ROS topic name such as "
                         f"/joint_states, got {args.topic!r}")
    csv = is_csv(args.path)
    if not csv or (out is not None and Path(out).suffix.lower() == ".mcap"):
        from ..ros._errors import READ_MODULES, WRITE_MODULES, require_ros

        require_ros(WRITE_MODULES if csv else READ_MODULES)   # a missing extra, up front
    with outputs(args) as outs:   # checked before any work: never over an input or, without
        if out is not None:       # --force, an existing file; written only at the end
            outs.add(out)
        if not csv:
            return _track_recording(args, outs)
        return _track(args, outs)


def is_csv(path: Path) -> bool:
    """True for a CSV stream (by its name, ``.csv``, or by not being a ROS recording).

    A folder is a rosbag2 recording, and so is a file named like a recording (``.mcap``,
    ``.bag``, ``.db3``) whatever it holds: the recording reader names what it is not
    (a ``.mcap`` file that is not MCAP is never read as a CSV). Any other file is a
    recording when it starts like one, else a CSV (the CSV reader reads a bounded
    amount: ``/dev/zero`` is "larger than" its limit).
    """
    if Path(path).suffix.lower() == ".csv":
        return True
    if Path(path).suffix.lower() in (".mcap", ".bag", ".db3"):
        return False
    try:
        mode = os.stat(path).st_mode
        if stat.S_ISDIR(mode):
            return False
        if not stat.S_ISREG(mode):
            return True
        with open(path, "rb") as fh:
            head = fh.read(16)
    except OSError:
        return True                  # the CSV reader names the problem
    return not head.startswith((b"\x89MCAP0", b"#ROSBAG V2.0", b"SQLite format 3"))


def _print_summary(n: int, first_slot: int, first_mode: int, counts: dict[str, int],
                   events: list, max_events: int, n_events: int, last: str) -> None:
    print(f"tracked {n} samples from slot {first_slot} (mode {first_mode:+d}); "
          f"{n_events} flagged")
    for name, c in sorted(counts.items()):
        print(f"  {name}: {c} samples")
    for line in events[:max_events]:
        print(line)
    if n_events > max_events:
        print(f"  ... {n_events - max_events} more (see -o)")
    print(last)


def _track_recording(args: argparse.Namespace, outs: Outputs) -> int:
    """A ROS recording: streamed into an MCAP file, or read whole for CSV / JSON / no output."""
    from .. import ros
    from ..motion import TrackFlag
    from ..ros._track import empty_topic_error
    out = args.output
    design, T = load_robot(args)
    opts = _tracker_options(args, design)
    if out is None or Path(out).suffix.lower() != ".mcap":
        with _recording_warnings(ros.RecordingWarning):
            js = ros.read_joint_states(args.path, topic=args.topic, joints=args.joint_names,
                                       scale=args.scale)
        if len(js) == 0:
            raise empty_topic_error(args.path, args.topic)
        t = (js.stamps_ns - js.stamps_ns[0]) * 1e-9
        return _track(args, outs, q=js.q, t=t)
    with _recording_warnings(ros.RecordingWarning), _progress_bar(args) as progress:
        s = ros.track_recording(args.path, out, T, design, topic=args.topic,
                                joints=args.joint_names, scale=args.scale,
                                target=outs.temp(out), progress=progress,
                                options=ros.TrackOptions(max_events=args.max_events), **opts)
    if s.n_valid == 0:
        raise ValueError(no_pose_message(args.path, s.n, s.max_abs_q, design, recording=True))
    lines = [f"  sample {i} (stamp {st} ns, q = {np.round(q, 6).tolist()} m): "
             f"{TrackFlag(f).name or f}, mode {m:+d}, slot {k}"
             for i, st, q, f, m, k in s.events]
    last = (f"last pose: tip_e = {np.round(s.last_tip_e, 6).tolist()} m, "
            f"p = {fmt(s.last_p)} m, valid = {s.last_valid}")
    _print_summary(s.n, s.first_slot, s.first_mode, s.counts, lines, args.max_events,
                   s.n_flagged, last)
    outs.commit()
    print(f"wrote {out} ({', '.join(f'{k}: {v}' for k, v in s.messages.items())} messages)")
    return _strict_status(args, s.counts)


def _tracker_options(args: argparse.Namespace, design: Design) -> dict[str, Any]:
    """The keyword options of :class:`~athenakin.motion.Tracker` given by the flags."""
    from ._plan import parse_margins

    return dict(slot=args.slot, jump_m=args.jump_mm * 1e-3, jump_rad=math.radians(args.jump_deg),
                margins=parse_margins(args.margin), **collision_options(args, design))


def _strict_status(args: argparse.Namespace, counts: dict[str, int]) -> int:
    """The exit status: 1 with ``--strict`` when a reading carries a flag of STRICT_FLAGS."""
    if args.strict and any(counts.get(n) for n in STRICT_FLAGS):
        bad = ", ".join(n for n in STRICT_FLAGS if counts.get(n))
        print(f"athenakin track: --strict: flagged {bad}")
        return 1
    return 0


def _max_abs(q: np.ndarray) -> float:
    a = np.abs(q[np.isfinite(q)])
    return float(a.max()) if a.size else math.nan


def no_pose_message(path: Path, n: int, max_abs_q: float, design: Design, *,
                    recording: bool) -> str:
    """The error of a stream in which no reading has a pose (every one ``LOST``)."""
    hint = mm_hint(max_abs_q, design, "max |q|") if math.isfinite(max_abs_q) else ""
    scale = (" (a recording in mm: --scale 0.001)" if recording else
             " (readings are in m: divide mm by 1000)")
    return (f"{path}: none of the {n} readings has a pose (all LOST: outside the strokes or "
            f"the workspace){hint}; check the units{scale}, --joints and --design")


def first_pose(q: np.ndarray, T: np.ndarray, design: Design, opts: dict  # type: ignore[type-arg]
               ) -> int:
    """Index of the first reading the tracker can start from (-1: none).

    The rule of the library's stream (:func:`athenakin.ros._track.first_tracker`, used
    by :func:`athenakin.ros.track_recording`): the first reading that assembles, the
    readings before it ``LOST``, whatever the output.
    """
    from ..ros._track import first_tracker

    tracker_opts = {k: v for k, v in opts.items()
                    if k in ("slot", "jump_m", "jump_rad", "margins")}
    return first_tracker(q, T, design, tracker_opts)[0]


def lost_before(log: TrackLog, q_head: np.ndarray) -> TrackLog:
    """``log`` with the readings ``q_head`` before it prepended as ``LOST`` rows.

    The rows of the stream's readings without a pose (:func:`first_pose`): the values
    of a ``LOST`` reading of the tracker (no pose: NaN, invalid, infinite step).
    """
    import dataclasses

    from ..motion import TrackFlag

    k = len(q_head)
    cols: dict[str, Any] = {}
    for f in dataclasses.fields(log):
        v = getattr(log, f.name)
        if v is None:
            cols[f.name] = None
            continue
        shape = (k, *v.shape[1:])
        if f.name == "q":
            head = q_head
        elif f.name == "flags":
            head = np.full(shape, int(TrackFlag.LOST), v.dtype)
        elif f.name == "step":
            head = np.full(shape, np.inf)
        elif v.dtype.kind == "f":
            head = np.full(shape, np.nan)
        elif v.dtype.kind in "US":
            head = np.full(shape, "", v.dtype)
        else:
            head = np.zeros(shape, v.dtype)
        cols[f.name] = np.concatenate([head, v])
    return dataclasses.replace(log, **cols)


@contextlib.contextmanager
def _recording_warnings(category: type[Warning]) -> Iterator[None]:
    """Print a warning of ``category`` (a truncated recording) as one line on stderr.

    Other warnings go on as they came.
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", category)
        try:
            yield
        finally:
            seen = list(caught)
    for w in seen:
        if issubclass(w.category, category):
            print(f"athenakin track: warning: {' '.join(str(w.message).split())}",
                  file=sys.stderr)
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)


@contextlib.contextmanager
def _progress_bar(args: argparse.Namespace) -> Iterator[Callable[[int], None] | None]:
    """A tqdm bar of the readings done, on stderr, or None.

    None (no bar) with ``--no-progress``, when stderr is no terminal (a pipe, a file, a
    test) or without tqdm (extra ``ros``). The callable takes the readings done so far.
    """
    if args.no_progress or not sys.stderr.isatty():
        yield None
        return
    try:
        from tqdm import tqdm
    except ImportError:              # pragma: no cover - tqdm is in the extra 'ros'
        yield None
        return
    bar = tqdm(desc="track", unit=" readings", unit_scale=True, file=sys.stderr)

    def show(n: int) -> None:
        bar.update(n - bar.n)

    try:
        yield show
    finally:
        bar.close()


def _track(args: argparse.Namespace, outs: Outputs, *, q: np.ndarray | None = None,
           t: np.ndarray | None = None) -> int:
    """A stream of readings (a CSV, or a recording read whole): tracked, reported, written."""
    from ..motion import track
    from ..motion._io import read_q_stream_csv

    design, T = load_robot(args)
    if q is None:
        q, t = read_q_stream_csv(args.path)
    if t is not None:
        t = _checked_times(args.path, t)
    opts = _tracker_options(args, design)
    first = first_pose(q, T, design, opts)
    if first < 0:
        raise ValueError(no_pose_message(args.path, len(q), _max_abs(q), design,
                                         recording=not is_csv(args.path)))
    log = track(q[first:], T, design, **opts)
    if first:
        log = lost_before(log, q[:first])
        print(f"readings 0 to {first - 1} have no pose (LOST): the tracker starts at reading "
              f"{first}, the first that assembles")
    counts = _report(log, q, t, args.max_events, checked="bodies" in opts)
    if args.output is not None:
        _write_log(Path(args.output), outs, log, t, T, design)
        outs.commit()
        print(f"wrote {args.output}")
    return _strict_status(args, counts)


def _checked_times(path: Path, t: np.ndarray) -> np.ndarray:
    """The stream's times ``t_s`` (NaN: missing): finite, never decreasing."""
    t = np.asarray(t, dtype=float)
    inf = np.flatnonzero(np.isinf(t))
    if inf.size:
        raise ValueError(f"{path}: t_s must be finite (or empty), got {t[inf[0]]} at "
                         f"sample {int(inf[0])}")
    seen = np.flatnonzero(np.isfinite(t))       # empty cells (NaN) are missing readings
    dec = np.flatnonzero(np.diff(t[seen]) < 0)
    if dec.size:
        i, j = int(seen[dec[0]]), int(seen[dec[0] + 1])
        raise ValueError(f"{path}: t_s must not decrease, got t_s = {t[j]:g} s at "
                         f"sample {j} after {t[i]:g} s at sample {i}")
    return t


def _report(log: TrackLog, q: np.ndarray, t: np.ndarray | None, max_events: int, *,
            checked: bool) -> dict[str, int]:
    """Print the summary of a tracked stream; the readings carrying each flag, by name."""
    from ..motion import TrackFlag

    events = log.events()
    counts: dict[str, int] = {}
    for _, f in events:
        for bit in TrackFlag:
            if bit and bit in f:
                counts[str(bit.name)] = counts.get(str(bit.name), 0) + 1
    lines = []
    for i, f in events[:max_events]:
        ts = "" if t is None else "t missing, " if np.isnan(t[i]) else f"t = {t[i]:.6g} s, "
        lines.append(f"  sample {i} ({ts}q = {np.round(q[i], 6).tolist()} m): "
                     f"{f.name or int(f)}, mode {int(log.mode[i]):+d}, slot {int(log.slot[i])}")
    tail = []
    if checked and log.clearance is not None and log.closest_pair is not None \
            and np.any(np.isfinite(log.clearance)):
        i = int(np.nanargmin(log.clearance))
        a, b = log.closest_pair[i]
        tail.append(f"least clearance: {fmt(float(log.clearance[i]))} m between {a} and {b} "
                    f"at sample {i}")
    last = len(q) - 1
    tail.append(f"last pose: tip_e = {np.round(log.tip_e[last], 6).tolist()} m, "
                f"p = {fmt(float(log.p[last]))} m, valid = {bool(log.valid[last])}")
    _print_summary(len(q), int(log.slot[0]), int(log.mode[0]), counts, lines, max_events,
                   len(events), "\n".join(tail))
    return counts


def _write_log(out: Path, outs: Outputs, log: TrackLog, t: np.ndarray | None,
               T: np.ndarray, design: Design) -> None:
    """Write the tracked stream to ``out``: MCAP (ROS 2 topics), JSON or CSV."""
    from .._serialize import json_text
    from ..motion import TrackFlag
    from ..motion._io import track_csv_text

    if out.suffix.lower() == ".mcap":
        from ..ros._track import write_track_log

        if t is None or not np.isfinite(t).all():
            stamps = np.arange(len(log.q), dtype=np.int64) * 1_000_000   # 1 kHz
        else:
            stamps = np.rint(np.asarray(t) * 1e9).astype(np.int64)
        write_track_log(outs.temp(out), stamps, log, T, design)
    elif out.suffix.lower() == ".json":
        import dataclasses

        obj = {k: getattr(log, k) for k in (f.name for f in dataclasses.fields(log))}
        obj["t_s"] = t
        obj["flag_bits"] = {b.name: int(b) for b in TrackFlag if b}
        outs.write(out, json_text(obj))
    else:
        outs.write(out, track_csv_text(log, t))
