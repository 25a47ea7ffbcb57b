"""Track a recorded stream and write the poses as ROS 2 topics; plans as trajectories (private)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._backend import BACKENDS
from .._output import check_output_path
from .._toml import TomlOptions
from .._typing import FloatArray, IntArray
from .._validation import check_array, check_choice, check_instance, check_path
from ..design import Design, resolve_design
from ..errors import InvalidInputError, KinematicsError
from ..motion import Tracker, TrackFlag, TrackLog, track
from ..motion._plan import Trajectory
from ..motion._stream import track_batch
from ..robot._setup import resolve_rcm_frame
from ._errors import RecordingError
from ._mcap import check_compression
from ._read import CHUNK, MAX_CHUNK, iter_joint_states
from ._write import McapOutput, TrackedBatch

__all__ = ["TrackOptions", "TrackingSummary", "track_recording", "track_to_mcap",
           "write_trajectory",
           "write_track_log", "tracked_batch", "first_tracker", "empty_topic_error"]

_LOST = int(TrackFlag.LOST)
#: Smallest ``chunk_size`` of :func:`track_recording`: each chunk costs a tracker call and
#: an MCAP chunk (about 0.2 ms), so 7 readings a chunk ran 200,000 readings in 44 s.
MIN_TRACK_CHUNK = 1024
_FIELDS = ("q", "valid", "slot", "mode", "p", "u", "O_s", "half_chord", "sin_u2", "sin_u4",
           "step", "flags")
#: Most flagged readings a summary lists (``max_events``).
MAX_EVENTS = 10**6


@dataclasses.dataclass(frozen=True)
class TrackOptions(TomlOptions):
    """How :func:`track_recording` and :func:`track_to_mcap` run and write.

    The recording, its topic and joints, the set-up and the tracker's keyword options
    (``slot``, ``jump_m``, ...) are arguments of the functions; these are the settings of
    the run and of its output. Every field is checked here, at construction (a named
    error); the defaults give the files the functions wrote before the options object
    existed. A ``[track]`` table of a TOML file holds them (:meth:`to_toml`,
    :meth:`from_toml`).

    Attributes
    ----------
    chunk_size : int
        Readings read, tracked and written at a time, :data:`MIN_TRACK_CHUNK` (1024) to
        10 000 000 (default :data:`~athenakin.ros.CHUNK`, 65 536): the memory bound.
    max_events : int
        Flagged readings listed in the summary, 0 to 1 000 000 (default 20).
    compression : {"zstd", "lz4", "none"}
        Chunk compression of the output (:class:`McapOutput`).
    compression_level : int or None
        Its level (zstd -7..22, lz4 0..16; None: zstd -3, lz4 0).
    backend : {"auto", "numpy", "numba"}
        The reading, tracking and writing on the compiled kernels or the numpy reference
        (:mod:`athenakin._backend`; default ``"auto"``); the same summary and file.

    Examples
    --------
    >>> from athenakin.ros import TrackOptions
    >>> o = TrackOptions(max_events=100, compression="lz4")
    >>> TrackOptions.from_mapping(o.to_mapping()) == o
    True
    """

    TOML_TABLE: ClassVar[str] = "track"

    chunk_size: int = CHUNK
    max_events: int = 20
    compression: str = "zstd"
    compression_level: int | None = None
    backend: str = "auto"

    def __post_init__(self) -> None:
        n = self.chunk_size
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) \
                or not MIN_TRACK_CHUNK <= n <= MAX_CHUNK:
            raise InvalidInputError(f"chunk_size: expected an integer from {MIN_TRACK_CHUNK} "
                                    f"to {MAX_CHUNK} (readings per chunk; default {CHUNK}), "
                                    f"got {n!r}")
        object.__setattr__(self, "chunk_size", int(n))
        object.__setattr__(self, "max_events", _check_events(self.max_events))
        check_compression(self.compression, self.compression_level)
        if self.compression_level is not None:
            object.__setattr__(self, "compression_level", int(self.compression_level))
        check_choice(self.backend, "backend", BACKENDS)


def _track_options(options: object) -> TrackOptions:
    """``options`` of :func:`track_recording` checked (None: the defaults)."""
    if options is None:
        return TrackOptions()
    check_instance(options, "options", TrackOptions)
    return options  # type: ignore[return-value]


@dataclasses.dataclass(frozen=True)
class TrackingSummary:
    """What tracking a stream into an MCAP file found.

    Attributes
    ----------
    n : int
        Readings tracked.
    n_valid : int
        Readings with a pose (the others are ``LOST``: no pose published).
    n_flagged : int
        Readings with at least one flag.
    counts : dict of str -> int
        Readings carrying each :class:`~athenakin.motion.TrackFlag` bit, by name.
    events : list of (int, int, tuple, int, int, int)
        The first flagged readings: ``(index, stamp_ns, q, flags, mode, slot)``.
    first_slot, first_mode : int
        Forward-kinematics slot and assembly mode of the first valid reading (-1, 0
        when none).
    last_tip_e : tuple of 3 float
        Tool tip of the last valid reading, RCM frame, m.
    last_p : float
    last_valid : bool
    messages : dict of str -> int
        Messages written per topic.
    path : Path or None
        The MCAP file (None when nothing was written).
    max_abs_q : float
        Largest finite magnitude of the readings, m (NaN: none finite): a stream with
        no pose and readings of hundreds of metres was recorded in mm.
    """

    n: int
    n_valid: int
    n_flagged: int
    counts: dict[str, int]
    events: list[tuple[int, int, tuple[float, ...], int, int, int]]
    first_slot: int
    first_mode: int
    last_tip_e: tuple[float, ...]
    last_p: float
    last_valid: bool
    messages: dict[str, int]
    path: Path | None
    max_abs_q: float = math.nan


def empty_topic_error(path: str | Path, topic: str) -> RecordingError:
    """The error of tracking a topic without messages (reading it gives 0 readings)."""
    return RecordingError(f"{path}: topic {topic!r} holds no message: nothing to track "
                          f"(choose the topic with topic=... / --topic)")


def tracked_batch(stamps_ns: IntArray, log: TrackLog | dict[str, Any]) -> TrackedBatch:
    """The fields the MCAP writer needs of a :class:`~athenakin.motion.TrackLog` (or a dict)."""
    g = (lambda k: log[k]) if isinstance(log, dict) else (lambda k: getattr(log, k))
    return TrackedBatch(stamps_ns=np.asarray(stamps_ns, np.int64), q=g("q"),
                        valid=np.asarray(g("valid"), bool), p=g("p"), u=g("u"), O_s=g("O_s"),
                        mode=g("mode"), slot=g("slot"), flags=g("flags"), step=g("step"),
                        half_chord=g("half_chord"), sin_u2=g("sin_u2"), sin_u4=g("sin_u4"),
                        **_clearance_fields(g))


def _clearance_fields(g: Callable[[str], Any]) -> dict[str, Any]:
    """``clearance_m`` and ``clearance_flags`` of the status topic, when the tracker checked."""
    from ..motion import TrackFlag

    try:
        clearance = np.asarray(g("clearance"), float)
    except (KeyError, AttributeError):
        return {}
    if not np.isfinite(clearance).any():
        return {}
    mask = int(TrackFlag.COLLISION | TrackFlag.NEAR_COLLISION)
    return {"clearance_m": clearance,
            "clearance_flags": np.asarray(g("flags"), np.int64) & mask}


class _Stream:
    """A :class:`~athenakin.motion.Tracker` over chunks.

    It starts at the first reading that assembles (readings before it are ``LOST``);
    each chunk is tracked at once by :func:`athenakin.motion._stream.track_batch`
    (compiled; bit for bit :meth:`~athenakin.motion.Tracker.update`), the tracker's
    state carried from chunk to chunk.
    """

    def __init__(self, T_b_e: FloatArray, design: Design,
                 options: dict[str, Any]) -> None:
        self.T, self.design, self.options = T_b_e, design, options
        self.tracker: Tracker | None = None
        self.first: tuple[int, int] = (-1, 0)
        self.seen = 0

    def run(self, q: FloatArray) -> dict[str, Any]:
        i = 0
        if self.tracker is None:
            i, self.tracker = first_tracker(q, self.T, self.design, self.options,
                                            first=self.seen)
            if self.tracker is None:
                self.seen += len(q)
                return _columns([None] * len(q), q)
            pose = self.tracker.pose
            self.first = (pose.slot, pose.mode)
            rows: list[Any] = [None] * i + [pose]
            i += 1
            self.seen += len(q)
            if i == len(q):
                return _columns(rows, q)
            rest = track_batch(self.tracker, q[i:])
            out = _columns(rows, q[:i])
            return {k: np.concatenate([v, rest[k]]) for k, v in out.items()}
        self.seen += len(q)
        return track_batch(self.tracker, q)


def first_tracker(q: FloatArray, T_b_e: FloatArray, design: Design,
                  options: dict[str, Any], *, first: int = 0) -> tuple[int, Tracker | None]:
    """The tracker started at the first reading of ``q`` that assembles.

    One rule for every entry point (:func:`track_recording`, ``athenakin track`` with any
    output): the stream starts at the first reading with a forward-kinematics solution;
    the readings before it are ``LOST``. A ``slot`` option that is not a solution there is
    an error naming that reading.

    Parameters
    ----------
    q : ndarray, shape (N, 3)
        Readings, m.
    T_b_e, design
    options : dict
        Keyword options of :class:`~athenakin.motion.Tracker`.
    first : int, keyword-only
        Index of ``q[0]`` in the whole stream (for messages).

    Returns
    -------
    (int, Tracker) or (-1, None)
        The reading's index in ``q`` and the tracker, or none assembles.

    Raises
    ------
    InvalidInputError
        ``slot`` is not a solution at the first reading that assembles, or a bad option.
    """
    from .._dispatch import forward_kinematics

    backend = options.get("backend", "auto")
    finite = np.flatnonzero(np.isfinite(q).all(axis=1))
    a, size = 0, 16          # the first reading usually assembles: a small batch first
    while a < len(finite):   # a batch FK (the backend's) skips the readings without a pose
        rows = finite[a:a + size]
        a, size = a + size, 4096
        with np.errstate(all="ignore"):
            ok = forward_kinematics(q[rows], T_b_e, design, errors="flag", fields=("valid",),
                                    backend=backend).valid.any(axis=1)
        for i in rows[ok].tolist():
            try:
                return i, Tracker(T_b_e, design, q0=q[i].tolist(), **options)
            except InvalidInputError as exc:   # a slot that is not valid there, a bad option
                raise InvalidInputError(str(exc).replace(
                    "q0 = ", f"reading {first + i} (the first with a pose), q = ")) from None
            except KinematicsError:
                continue                        # does not assemble after all: LOST
    return -1, None


def _columns(rows: list[Any], q: FloatArray) -> dict[str, Any]:
    n = len(rows)
    out: dict[str, Any] = {
        "q": q, "valid": np.zeros(n, bool), "slot": np.zeros(n, np.int64),
        "mode": np.zeros(n, np.int64), "p": np.full(n, np.nan), "u": np.full((n, 5), np.nan),
        "O_s": np.full((n, 3), np.nan), "half_chord": np.full(n, np.nan),
        "sin_u2": np.full(n, np.nan), "sin_u4": np.full(n, np.nan),
        "step": np.full(n, np.inf), "flags": np.full(n, _LOST, np.int64),
        "tip_e": np.full((n, 3), np.nan), "clearance": np.full(n, np.nan)}
    idx = [k for k, r in enumerate(rows) if r is not None]
    if idx:
        sub = [rows[k] for k in idx]
        cols = list(zip(*sub, strict=True))
        names = type(sub[0])._fields
        for name, col in zip(names, cols, strict=True):
            if name in out and name != "q":
                out[name][idx] = np.array(col, dtype=out[name].dtype)
    return out


def _stream(chunks: Iterable[tuple[IntArray, FloatArray]],
            out: McapOutput, T: FloatArray, design: Design,
            options: dict[str, Any], max_events: int,
            progress: Callable[[int], None] | None) -> TrackingSummary:
    st = _Stream(T, design, options)
    n = n_valid = n_flagged = 0
    counts: dict[str, int] = {}
    events: list[tuple[int, int, tuple[float, ...], int, int, int]] = []
    last: tuple[tuple[float, ...], float, bool] = ((math.nan,) * 3, math.nan, False)
    big = -math.inf
    for stamps, q in chunks:
        fin = np.abs(q[np.isfinite(q)])
        if fin.size:
            big = max(big, float(fin.max()))
        cols = st.run(q)
        out.write_tracked(tracked_batch(stamps, cols))
        flags = cols["flags"]
        n_flagged += int(np.count_nonzero(flags))
        for bit in TrackFlag:
            if bit:
                c = int(np.count_nonzero(flags & int(bit)))
                if c:
                    counts[str(bit.name)] = counts.get(str(bit.name), 0) + c
        if len(events) < max_events:
            for i in np.flatnonzero(flags)[:max_events - len(events)]:
                events.append((n + int(i), int(stamps[i]), tuple(q[i].tolist()),
                               int(flags[i]), int(cols["mode"][i]), int(cols["slot"][i])))
        ok = np.flatnonzero(cols["valid"])
        n_valid += ok.size
        if ok.size:
            j = ok[-1]
            last = (tuple(cols["tip_e"][j].tolist()), float(cols["p"][j]), bool(j == len(q) - 1))
        elif len(q):
            last = (last[0], last[1], False)
        n += len(q)
        if progress is not None:
            progress(n)
    return TrackingSummary(n=n, n_valid=n_valid, n_flagged=n_flagged, counts=counts, events=events,
                           first_slot=st.first[0], first_mode=st.first[1], last_tip_e=last[0],
                           last_p=last[1], last_valid=last[2], messages=dict(out.counts),
                           path=out.path, max_abs_q=big if big >= 0 else math.nan)


def _options(options: dict[str, Any]) -> dict[str, Any]:
    allowed = {"slot", "jump_m", "jump_rad", "margins", "bodies", "environment",
               "clearance_margin"}
    bad = set(options) - allowed
    if bad:
        raise TypeError(f"unexpected tracker option(s) {sorted(bad)}; expected some of "
                        f"{sorted(allowed)}")
    return options


def _stamps_array(stamps_ns: object) -> NDArray[Any]:
    """``stamps_ns`` as an array (its dtype and shape are checked by the caller)."""
    try:
        return np.asarray(stamps_ns)
    except (ValueError, TypeError, OverflowError) as exc:   # a ragged list and the like
        raise TypeError(f"stamps_ns: expected integers (ns), got an object numpy cannot "
                        f"convert ({exc})") from None


def _check_events(max_events: object) -> int:
    if isinstance(max_events, bool) or not isinstance(max_events, (int, np.integer)) \
            or not 0 <= max_events <= MAX_EVENTS:
        raise InvalidInputError(f"max_events: expected an integer from 0 to {MAX_EVENTS}, got "
                                f"{max_events!r}")
    return int(max_events)


def track_recording(recording: str | Path, out: str | Path, T_b_e: ArrayLike | None = None,
                    design: Design | None = None, *, topic: str = "/joint_states",
                    joints: tuple[str, str, str] | list[str] = ("q1", "q2", "q3"),
                    scale: float = 1.0, target: str | Path | None = None,
                    progress: Callable[[int], None] | None = None,
                    options: TrackOptions | None = None,
                    **tracker_options: Any) -> TrackingSummary:
    """Track the actuator readings of a recording and write the poses to an MCAP file.

    The recording is read, tracked and written in chunks of ``options.chunk_size``
    readings (bounded memory). The output (topics in docs/ros.md) appears only
    when everything succeeded.

    Parameters
    ----------
    recording : str or Path
        See :func:`read_joint_states`.
    out : str or Path
        The MCAP file to write.
    T_b_e : array-like, shape (4, 4), optional
        RCM frame (default :func:`athenakin.default_rcm_frame`).
    design : Design, optional
    topic, joints, scale : keyword-only
        The input (:func:`read_joint_states`).
    target : str or Path, keyword-only, optional
        Write there and do not rename (for a caller that renames, the CLI).
    progress : callable, keyword-only, optional
        Called with the number of readings done after each chunk.
    options : TrackOptions, keyword-only, optional
        Chunk size, events listed, the output's compression (default ``TrackOptions()``).
    **tracker_options
        ``slot``, ``jump_m``, ``jump_rad``, ``margins`` of
        :class:`~athenakin.motion.Tracker` (``slot`` is that of the first reading that
        assembles), and its collision check (``bodies``, ``environment``,
        ``clearance_margin``).

    Returns
    -------
    TrackingSummary

    Raises
    ------
    RecordingError
        See :func:`read_joint_states`, or the topic holds no message (reading it gives
        0 readings; tracking needs one); nothing is written.
    """
    check_path(recording, "recording")
    check_output_path(out, "out")
    if progress is not None and not callable(progress):
        raise TypeError(f"progress: expected a callable or None, got {type(progress).__name__}")
    design = resolve_design(design)
    T = resolve_rcm_frame(T_b_e, design)
    opts = _options(tracker_options)
    o = _track_options(options)
    opts["backend"] = o.backend
    chunks = ((js.stamps_ns, js.q) for js in
              iter_joint_states(recording, topic=topic, joints=joints, scale=scale,
                                chunk_size=o.chunk_size, backend=o.backend))
    with McapOutput(out, T, design, target=target, compression=o.compression,
                    compression_level=o.compression_level, backend=o.backend) as w:
        summary = _stream(chunks, w, T, design, opts, o.max_events, progress)
        if summary.n == 0:
            raise empty_topic_error(recording, topic)
        return summary


def track_to_mcap(stamps_ns: ArrayLike, q: ArrayLike, out: str | Path,
                  T_b_e: ArrayLike | None = None, design: Design | None = None, *,
                  target: str | Path | None = None, options: TrackOptions | None = None,
                  **tracker_options: Any) -> TrackingSummary:
    """Track readings given as arrays (e.g. a CSV stream) and write the poses to MCAP.

    Parameters
    ----------
    stamps_ns : array-like of int, shape (N,)
        Time of each reading, ns, never decreasing.
    q : array-like, shape (N, 3)
        Readings, m (NaN: a missing reading, flagged ``LOST``).
    out, T_b_e, design, target, options, **tracker_options
        As :func:`track_recording`.

    Returns
    -------
    TrackingSummary
    """
    check_output_path(out, "out")
    design = resolve_design(design)
    T = resolve_rcm_frame(T_b_e, design)
    qa = check_array(q, "q", (3,), allow_nonfinite=True)
    if qa.ndim != 2:
        raise InvalidInputError(f"q: expected shape (N, 3), got {qa.shape}")
    s = _stamps_array(stamps_ns)
    if s.shape != (len(qa),) or not np.issubdtype(s.dtype, np.integer):
        raise InvalidInputError(f"stamps_ns: expected {len(qa)} integers (ns), got "
                                f"{s.dtype} of shape {s.shape}")
    s = s.astype(np.int64)
    dec = np.flatnonzero(np.diff(s) < 0)
    if dec.size:
        raise InvalidInputError(f"stamps_ns: stamps go backwards at reading {dec[0] + 1}: "
                                f"{s[dec[0] + 1]} ns after {s[dec[0]]} ns")
    opts = _options(tracker_options)
    o = _track_options(options)
    opts["backend"] = o.backend
    size = o.chunk_size

    def chunks() -> Iterator[tuple[IntArray, FloatArray]]:
        for k in range(0, len(qa), size):
            yield s[k:k + size], qa[k:k + size]

    with McapOutput(out, T, design, target=target, compression=o.compression,
                    compression_level=o.compression_level, backend=o.backend) as w:
        return _stream(chunks(), w, T, design, opts, o.max_events, None)


def write_trajectory(path: str | Path, traj: Trajectory, *, start_ns: int = 0,
                     target: str | Path | None = None, compression: str = "zstd",
                     compression_level: int | None = None, backend: str = "auto") -> Path:
    """Write a planned trajectory as MCAP: the plan and what the robot will show.

    Topics: ``/athena/trajectory`` (one ``trajectory_msgs/msg/JointTrajectory``,
    joints ``q1, q2, q3``, one point per sample with positions m, velocities m/s,
    accelerations m/s^2 and ``time_from_start``) at ``start_ns``, and, for every
    sample, stamped ``start_ns + t``: ``/athena/tool_tip``, ``/tf``,
    ``/athena/joint_states``, ``/athena/status``, plus ``/robot_description`` and
    ``/tf_static`` once (docs/ros.md).

    Parameters
    ----------
    path : str or Path
        The ``.mcap`` file (written atomically).
    traj : Trajectory
        From :func:`athenakin.motion.plan`.
    start_ns : int, keyword-only
        Stamp of the first sample, ns since the epoch (default 0).
    target : str or Path, keyword-only, optional
        Write there and do not rename (for a caller that renames).
    compression, compression_level, backend : keyword-only
        As :class:`TrackOptions`.

    Returns
    -------
    Path
    """
    check_instance(traj, "traj", Trajectory)
    if isinstance(start_ns, bool) or not isinstance(start_ns, (int, np.integer)) \
            or not 0 <= start_ns < 2**62:
        raise InvalidInputError(f"start_ns: expected an integer from 0 to 2**62, got "
                                f"{start_ns!r}")
    t = np.asarray(traj.t, dtype=float)
    stamps = int(start_ns) + np.rint((t - t[0]) * 1e9).astype(np.int64)
    log = track(traj.q, traj.T_b_e, traj.design, backend=backend)
    with McapOutput(path, traj.T_b_e, traj.design, target=target, compression=compression,
                    compression_level=compression_level, backend=backend) as w:
        w.write_static(int(stamps[0]))
        w.write_trajectory_message(int(stamps[0]), t, traj.q, traj.qd, traj.qdd)
        for k in range(0, len(t), CHUNK):
            sl = slice(k, k + CHUNK)
            cols = {f: getattr(log, f)[sl] for f in _FIELDS}
            w.write_tracked(tracked_batch(stamps[sl], cols))
    return Path(path)


def write_track_log(path: str | Path, stamps_ns: ArrayLike, log: TrackLog,
                    T_b_e: ArrayLike | None = None, design: Design | None = None, *,
                    target: str | Path | None = None, compression: str = "zstd",
                    compression_level: int | None = None, backend: str = "auto") -> Path:
    """Write an already tracked stream (a :class:`~athenakin.motion.TrackLog`) as MCAP.

    Parameters
    ----------
    path : str or Path
        The ``.mcap`` file (written atomically); with ``target``, the file written
        directly (the caller renames it).
    stamps_ns : array-like of int, shape (N,)
        Stamp of each reading, ns.
    log : TrackLog
    T_b_e, design
        The set-up the log was tracked with.
    target : str or Path, keyword-only, optional
    compression, compression_level, backend : keyword-only
        As :class:`TrackOptions`.

    Returns
    -------
    Path
    """
    check_instance(log, "log", TrackLog)
    design = resolve_design(design)
    T = resolve_rcm_frame(T_b_e, design)
    s = _stamps_array(stamps_ns)
    if s.shape != (len(log.q),) or not np.issubdtype(s.dtype, np.integer):
        raise InvalidInputError(f"stamps_ns: expected {len(log.q)} integers (ns), got "
                                f"{s.dtype} of shape {s.shape}")
    with McapOutput(path, T, design, target=target, compression=compression,
                    compression_level=compression_level, backend=backend) as w:
        for k in range(0, len(s), CHUNK):
            sl = slice(k, k + CHUNK)
            cols = {f: getattr(log, f)[sl] for f in _FIELDS}
            w.write_tracked(tracked_batch(s[sl].astype(np.int64), cols))
    return Path(path)
