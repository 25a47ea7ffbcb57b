"""Write tracked poses and trajectories as MCAP files of ROS 2 messages (private).

One :class:`McapOutput` writes one file through a temporary file in the same
folder, renamed into place only when everything is written: a failure (or
Ctrl-C) leaves nothing, never a partial file. Messages are encoded by
:mod:`._cdr` (vectorised over readings; where numba runs, the records of a chunk
are filled by :func:`athenakin.ros._kernels.fill_records`, the same bytes)
and written by :mod:`._mcap`, chunked and compressed (zstd level -3 unless told);
the schemas are the ROS 2 message definitions
(from rosbags' type store), so Foxglove, rosbags, mcap-ros2-support and
``ros2 bag`` read the file as it is.

Topics (docs/ros.md):

``/athena/tool_tip``     geometry_msgs/msg/PoseStamped, frame ``base``
``/tf``                  tf2_msgs/msg/TFMessage: base -> moving links, tool_tip, rcm
``/tf_static``           tf2_msgs/msg/TFMessage: the URDF's fixed frames (once)
``/athena/joint_states`` sensor_msgs/msg/JointState: every joint of the URDF
``/athena/status``       athenakin_msgs/msg/TrackStatus: the tracker's flags
``/robot_description``   std_msgs/msg/String: the URDF (once, transient local)
``/athena/trajectory``   trajectory_msgs/msg/JointTrajectory (plans only)
"""

from __future__ import annotations

import contextlib
import dataclasses
from pathlib import Path
from types import TracebackType
from typing import IO, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._output import AtomicFile, check_output_path, naming_path
from .._validation import check_argument_order, check_path
from ..design import Design
from ..errors import InvalidInputError
from ..robot._setup import resolve_rcm_frame
from ..sim import JOINTS
from ._cdr import CdrBuilder, Template, split_stamps
from ._frames import (
    BASE_FRAME,
    TOOL_TIP_FRAME,
    UrdfModel,
    joint_values,
    kernel_plan,
    link_frames,
    quaternion_xyzw,
    urdf_model,
)
from ._mcap import MESSAGE_HEADER, McapFile, check_compression, compressor_module
from ._messages import (
    STATUS_FLAG_FIELDS,
    STATUS_MSGDEF,
    STATUS_TYPE,
    _joint_state_template,
    _pose_template,
    _put_frame,
    _put_pose,
    _stamp_fields,
    _status_template,
    _string_message,
    _tf_template,
    msgdef,
)
from ._record_plan import TF_FRAMES, _RecordPlan

__all__ = ["McapOutput", "RosEncoder", "TrackedBatch", "TOPICS", "STATUS_TYPE",
           "STATUS_MSGDEF", "TF_FRAMES", "STATUS_FLAG_FIELDS"]

#: Topic of each output stream.
TOPICS = {
    "tool_tip": "/athena/tool_tip",
    "tf": "/tf",
    "tf_static": "/tf_static",
    "joint_states": "/athena/joint_states",
    "status": "/athena/status",
    "robot_description": "/robot_description",
    "trajectory": "/athena/trajectory",
}
_NEAR_BITS = 128 | 256 | 512 | 1024 | 2048 | 4096
_MSG_TYPES = {"tool_tip": "geometry_msgs/msg/PoseStamped", "tf": "tf2_msgs/msg/TFMessage",
              "tf_static": "tf2_msgs/msg/TFMessage",
              "joint_states": "sensor_msgs/msg/JointState", "status": STATUS_TYPE,
              "robot_description": "std_msgs/msg/String",
              "trajectory": "trajectory_msgs/msg/JointTrajectory"}
#: Uncompressed bytes per MCAP chunk (about).
_CHUNK_BYTES = 4 * 2**20
#: QoS of a latched topic as rosbag2 records it (durability 1: transient local).
_LATCHED_QOS = ("- history: 3\n  depth: 0\n  reliability: 1\n  durability: 1\n"
                "  deadline:\n    sec: 2147483647\n    nsec: 4294967295\n"
                "  lifespan:\n    sec: 2147483647\n    nsec: 4294967295\n"
                "  liveliness: 1\n  liveliness_lease_duration:\n    sec: 2147483647\n"
                "    nsec: 4294967295\n  avoid_ros_namespace_conventions: false\n")


# ---------------------------------------------------------------------------- the file
@dataclasses.dataclass(frozen=True)
class TrackedBatch:
    """What :meth:`McapOutput.write_tracked` needs of a batch of tracked readings.

    Attributes
    ----------
    stamps_ns : ndarray of int64, shape (N,)
    q : ndarray, shape (N, 3)
    valid : ndarray of bool, shape (N,)
    p : ndarray, shape (N,)
    u : ndarray, shape (N, 5)
    O_s : ndarray, shape (N, 3)
    mode, slot, flags : ndarray of int, shape (N,)
    step, half_chord, sin_u2, sin_u4 : ndarray, shape (N,)
    clearance_m : ndarray, shape (N,) or None
        Smallest distance between bodies (athenakin.collision), m; None: not computed.
    clearance_flags : ndarray of int, shape (N,) or None
    """

    stamps_ns: NDArray[np.int64]
    q: NDArray[np.float64]
    valid: NDArray[np.bool_]
    p: NDArray[np.float64]
    u: NDArray[np.float64]
    O_s: NDArray[np.float64]
    mode: NDArray[np.int64]
    slot: NDArray[np.int64]
    flags: NDArray[np.int64]
    step: NDArray[np.float64]
    half_chord: NDArray[np.float64]
    sin_u2: NDArray[np.float64]
    sin_u4: NDArray[np.float64]
    clearance_m: NDArray[np.float64] | None = None
    clearance_flags: NDArray[np.int64] | None = None


def check_uint(x: object, name: str, bound: int) -> int:
    """An integer in ``[0, bound)`` (a uint32 field, a stamp in ns)."""
    if isinstance(x, bool) or not isinstance(x, (int, np.integer)):
        raise TypeError(f"{name}: expected an integer, got {type(x).__name__}")
    if not 0 <= int(x) < bound:
        raise InvalidInputError(f"{name}: expected an integer from 0 to {bound - 1}, got {x!r:.40}")
    return int(x)


class RosEncoder:
    """The CDR messages of ATHENA's topics for one design and set-up (no file).

    Parameters
    ----------
    T_b_e : ndarray, shape (4, 4)
        The RCM frame in the base frame (m).
    design : Design
    """

    def __init__(self, T_b_e: ArrayLike, design: Design) -> None:
        self.model: UrdfModel = urdf_model(design, np.asarray(T_b_e, dtype=float))
        self.tf_pairs = tuple((BASE_FRAME, c) for c in TF_FRAMES)
        self.templates = {"tool_tip": _pose_template(), "tf": _tf_template(self.tf_pairs),
                          "joint_states": _joint_state_template(tuple(JOINTS)),
                          "status": _status_template()}
        rcm = self.model.T_b_e[None]
        #: ``/tf``'s ``rcm`` frame: translation and quaternion of ``T_b_e`` (fixed).
        self.rcm_frame = np.concatenate([rcm[0, :3, 3], quaternion_xyzw(rcm[:, :3, :3])[0]])
        self._kernel_plan: tuple[Any, ...] | None = None

    @property
    def kernel_plan(self) -> tuple[Any, ...]:
        """The compiled joint values' and ``/tf`` frames' arguments (:func:`kernel_plan`)."""
        if self._kernel_plan is None:
            self._kernel_plan = kernel_plan(self.model, TF_FRAMES[:-1])
        return self._kernel_plan

    def robot_description(self) -> bytes:
        """``std_msgs/msg/String`` holding the URDF."""
        return _string_message(self.model.text)

    def tf_static(self, stamp_ns: int) -> bytes:
        """``tf2_msgs/msg/TFMessage`` of the URDF's fixed frames (but ``tool_tip``)."""
        fixed = [j for j in self.model.joints if j.kind == "fixed"
                 and j.child != TOOL_TIP_FRAME]
        pairs = tuple((j.parent, j.child) for j in fixed)
        vals: dict[str, Any] = {}
        _stamp_fields(vals, np.array([int(stamp_ns)]), [f"stamp{k}" for k in range(len(pairs))])
        for k, j in enumerate(fixed):
            _put_pose(vals, j.origin[None], f"t{k}", f"r{k}")
        return _tf_template(pairs).encode(1, vals).tobytes()

    def pose_values(self, stamps_ns: NDArray[np.int64], q: NDArray[np.float64],
                    p: NDArray[np.float64], u: NDArray[np.float64], O_s: NDArray[np.float64]
                    ) -> dict[str, dict[str, Any]]:
        """The numbers of the ``tool_tip``, ``tf`` and ``joint_states`` messages of N poses."""
        jv = joint_values(self.model, q, p, u, O_s)
        frames = self.frames(jv)
        sec, nsec = split_stamps(stamps_ns)
        tip: dict[str, Any] = {"stamp.sec": sec, "stamp.nanosec": nsec}
        _put_frame(tip, frames[:, TF_FRAMES.index(TOOL_TIP_FRAME)], "p", "o")
        tf: dict[str, Any] = {}
        for k in range(len(self.tf_pairs)):
            tf[f"stamp{k}.sec"], tf[f"stamp{k}.nanosec"] = sec, nsec
            _put_frame(tf, frames[:, k], f"t{k}", f"r{k}")
        js: dict[str, Any] = {f"pos.{i}": jv[name] for i, name in enumerate(JOINTS)}
        js["stamp.sec"], js["stamp.nanosec"] = sec, nsec
        return {"tool_tip": tip, "tf": tf, "joint_states": js}

    def frames(self, jv: dict[str, NDArray[np.float64]], *,
               out: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
        """Translation and quaternion of every ``/tf`` child (:data:`TF_FRAMES`), (N, K, 7).

        ``out``: where to write (a view, e.g. columns of the writer's words).
        """
        if out is None:
            out = np.empty((len(next(iter(jv.values()))), len(TF_FRAMES), 7))
        link_frames(self.model, jv, TF_FRAMES[:-1], out=out[:, :-1])
        out[:, -1] = self.rcm_frame
        return out

    def poses(self, stamps_ns: NDArray[np.int64], q: NDArray[np.float64],
              p: NDArray[np.float64], u: NDArray[np.float64], O_s: NDArray[np.float64]
              ) -> dict[str, NDArray[np.uint8]]:
        """Messages ``tool_tip``, ``tf``, ``joint_states`` of N poses, each (N, size) bytes."""
        vals = self.pose_values(stamps_ns, q, p, u, O_s)
        return {k: self.templates[k].encode(len(stamps_ns), v) for k, v in vals.items()}

    def status_values(self, b: TrackedBatch, first_sample: int = 0) -> dict[str, Any]:
        """The numbers of the ``/athena/status`` messages of a batch."""
        n = len(b.stamps_ns)
        flags = np.asarray(b.flags, dtype=np.int64)
        valid = np.asarray(b.valid, bool)
        vals: dict[str, Any] = {"sample": np.arange(n) + first_sample,
                                "valid": valid, "mode": np.where(valid, b.mode, 0),
                                "slot": np.where(valid, b.slot, 0), "flags": flags,
                                "near_singular": (flags & _NEAR_BITS) != 0,
                                "step": b.step, "half_chord": b.half_chord,
                                "sin_u2": b.sin_u2, "sin_u4": b.sin_u4,
                                "clearance_m": np.nan if b.clearance_m is None
                                else b.clearance_m,
                                "clearance_flags": 0 if b.clearance_flags is None
                                else b.clearance_flags}
        for name, bit in STATUS_FLAG_FIELDS.items():
            vals[name] = (flags & bit) != 0
        vals["stamp.sec"], vals["stamp.nanosec"] = split_stamps(b.stamps_ns)
        return vals

    def status(self, b: TrackedBatch, first_sample: int = 0) -> NDArray[np.uint8]:
        """``/athena/status`` messages of a batch, (N, size) bytes."""
        return self.templates["status"].encode(len(b.stamps_ns),
                                               self.status_values(b, first_sample))


def _compiled() -> bool:
    """Whether :meth:`McapOutput.write_tracked` fills its records with the compiled kernel."""
    from .._backend import numba_available

    return numba_available()


class McapOutput:
    """An MCAP file of ATHENA's ROS 2 topics, written atomically.

    Parameters
    ----------
    path : str or Path
        The file to write (``.mcap``). It appears only when :meth:`close` succeeds;
        the context manager closes it on success and discards it on an exception.
    T_b_e : ndarray, shape (4, 4)
        The RCM frame in the base frame (m).
    design : Design
    compression : {"zstd", "lz4", "none"}, keyword-only
        Chunk compression (default zstd; all three are MCAP's and Foxglove reads them).
    compression_level : int, keyword-only, optional
        zstd -7..22 (default -3: a fast level, about 10% larger files than level 1 and
        a quarter less time; docs/ros.md), lz4 0..16 (default 0).
    target : str or Path, keyword-only, optional
        Write this file instead of a temporary one and do no rename (the caller
        renames it: the CLI's own output manager).

    Examples
    --------
    ::

        with McapOutput("run.mcap", T_b_e, design) as out:
            out.write_tracked(batch)
    """

    def __init__(self, path: str | Path, T_b_e: ArrayLike, design: Design, *,
                 compression: str = "zstd", compression_level: int | None = None,
                 target: str | Path | None = None) -> None:
        compression, compression_level = check_compression(compression, compression_level)
        self._closed = True                    # nothing to close until the file is open
        self.path = check_output_path(path)    # a folder, FIFO or device: named error
        check_argument_order(T_b_e, "T_b_e", given_for="frame")
        check_argument_order(design, "design", given_for="design")
        if not isinstance(design, Design):
            raise TypeError(f"design: expected a Design, got {type(design).__name__}")
        if T_b_e is None:
            raise TypeError("T_b_e: expected the RCM frame, a rigid transform of shape (4, 4), "
                            "got None")
        T_b_e = resolve_rcm_frame(T_b_e, design)
        if target is not None:
            target = check_path(target, "target")
        compressor_module(compression)         # a missing extra: named, before any file
        msgdef(_MSG_TYPES["tool_tip"])         # rosbags (the schemas): likewise
        self.encoder = RosEncoder(T_b_e, design)
        self.model = self.encoder.model
        self._atomic: AtomicFile | None = None
        if target is None:
            self._atomic = AtomicFile(self.path, suffix=".mcap")
            self._tmp = self._atomic.temp
            self._fh: IO[bytes] = self._atomic.fh
        else:
            self._tmp = Path(target)
            with naming_path(self.path):
                self._fh = open(self._tmp, "wb")   # noqa: SIM115 - closed in close/discard
        self._closed = False
        try:
            with naming_path(self.path):
                self._file = McapFile(self._fh, compression=compression,
                                      level=compression_level)
        except BaseException:
            self.discard()
            raise
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, int] = {}
        self._seq: dict[str, int] = {}
        self._static_done = False
        self._closed = False
        self._plan: _RecordPlan | None = None
        self._buf: NDArray[np.uint8] | None = None
        self._words: NDArray[np.uint64] | None = None
        self.counts: dict[str, int] = {}

    # ------------------------------------------------------------------ channels
    def _channel(self, key: str) -> int:
        cid = self._channels.get(key)
        if cid is None:
            typ = _MSG_TYPES[key]
            sid = self._schemas.get(typ)
            if sid is None:
                sid = self._file.schema(typ, "ros2msg", msgdef(typ).encode())
                self._schemas[typ] = sid
            meta = {"offered_qos_profiles": _LATCHED_QOS} \
                if key in ("robot_description", "tf_static") else {}
            cid = self._file.channel(TOPICS[key], "cdr", sid, meta)
            self._channels[key] = cid
            self._seq[key] = 0
            self.counts[TOPICS[key]] = 0
        return cid

    def _add(self, key: str, stamp: int, data: bytes) -> None:
        cid = self._channel(key)
        with naming_path(self.path):          # a full disk, an I/O error: name the file
            self._file.single(cid, self._seq[key], stamp, data)
        self._seq[key] += 1
        self.counts[TOPICS[key]] += 1

    def write_static(self, stamp_ns: int) -> None:
        """``/robot_description`` (the URDF) and ``/tf_static`` (fixed frames), once.

        ``stamp_ns``: int, ns, 0 to 2**63 - 1.
        """
        check_uint(stamp_ns, "stamp_ns", 2**63)
        if self._static_done:
            return
        self._static_done = True
        self._add("robot_description", int(stamp_ns), self.encoder.robot_description())
        self._add("tf_static", int(stamp_ns), self.encoder.tf_static(int(stamp_ns)))

    def write_tracked(self, b: TrackedBatch) -> None:
        """Write a batch of tracked readings: status for each, poses for the valid ones.

        Each chunk of the file is one byte array of ``rows x (status, tool tip, tf,
        joint states)`` Message records built in place; the rows of readings without
        a pose keep only their status record.
        """
        n = len(b.stamps_ns)
        if n == 0:
            return
        stamps = np.asarray(b.stamps_ns, dtype=np.int64)
        self.write_static(int(stamps[0]))
        keys = ("status", "tool_tip", "tf", "joint_states")
        cids = [self._channel(k) for k in keys]
        sizes = [self.encoder.templates[k].size for k in keys]
        cols = np.cumsum([0] + [MESSAGE_HEADER + z for z in sizes])
        row = int(cols[-1])
        rs = int(cols[1])
        per = max(1, _CHUNK_BYTES // row)
        valid = np.asarray(b.valid, bool)
        if _compiled():
            self._write_tracked_compiled(b, stamps, valid, keys, cids, per)
            return
        for a in range(0, n, per):
            e = min(n, a + per)
            m = e - a
            v = valid[a:e]
            st = stamps[a:e]
            buf = np.empty((m, row), dtype=np.uint8)
            part: dict[str, Any] = {f.name: (None if getattr(b, f.name) is None
                                             else getattr(b, f.name)[a:e])
                                    for f in dataclasses.fields(TrackedBatch)}
            sub = TrackedBatch(**part)
            vals = {"status": self.encoder.status_values(sub, self._seq["status"])}
            if v.any():
                with np.errstate(invalid="ignore", divide="ignore"):
                    vals.update(self.encoder.pose_values(st, sub.q, sub.p, sub.u, sub.O_s))
            seq_pose = np.cumsum(v) - 1
            for j, k in enumerate(keys):
                if k not in vals:
                    continue
                c0 = int(cols[j])
                seq = self._seq[k] + (np.arange(m) if k == "status" else seq_pose)
                McapFile.message_headers(buf[:, c0:c0 + MESSAGE_HEADER], cids[j], seq, st,
                                         sizes[j])
                self.encoder.templates[k].encode(m, vals[k],
                                                 out=buf[:, c0 + MESSAGE_HEADER:int(cols[j + 1])])
            if v.all():
                rec = buf.reshape(-1)
                row_off = np.arange(m, dtype=np.int64) * row
            elif not v.any():
                rec = np.ascontiguousarray(buf[:, :rs]).reshape(-1)
                row_off = np.arange(m, dtype=np.int64) * rs
            else:
                keep = np.ones((m, row), bool)
                keep[~v, rs:] = False
                rec = buf[keep]
                row_off = np.concatenate([[0], np.cumsum(np.where(v, row, rs))[:-1]])
            index = {cids[0]: (st, row_off)}
            if v.any():
                for j in range(1, 4):
                    index[cids[j]] = (st[v], row_off[v] + int(cols[j]))
            self._write_chunk(rec, index, keys, v, m)

    def _write_chunk(self, data: Any, index: dict[int, Any], keys: tuple[str, ...],
                     v: NDArray[np.bool_], m: int) -> None:
        """Write one chunk of ``m`` readings (``v``: the valid ones) and count its messages.

        ``/athena/status`` has a message for every reading, the other topics of ``keys``
        one for every valid reading.
        """
        with naming_path(self.path):          # a full disk, an I/O error: name the file
            self._file.chunk(data, index)
        nv = int(v.sum())
        self._seq["status"] += m
        self.counts[TOPICS["status"]] += m
        for k in keys[1:]:
            self._seq[k] += nv
            self.counts[TOPICS[k]] += nv

    def _record_plan(self, keys: tuple[str, ...], cids: list[int]) -> _RecordPlan:
        """Templates and field tables of a reading's records (:func:`fill_records`)."""
        if self._plan is None:
            self._plan = _RecordPlan.of(self.encoder.templates, keys, cids)
        return self._plan

    def _write_tracked_compiled(self, b: TrackedBatch, stamps: NDArray[np.int64],
                                valid: NDArray[np.bool_], keys: tuple[str, ...],
                                cids: list[int], per: int) -> None:
        """:meth:`write_tracked` with the records of each chunk filled by a compiled kernel.

        The same bytes as the numpy path (tested): the template of each record, the
        numbers of :meth:`RosEncoder.status_values` and :meth:`RosEncoder.pose_values`
        written at their offsets, the readings without a pose keeping only their status.
        """
        from ..fast._frame_kernels import joint_values_into, urdf_frames_into
        from ._kernels import fill_records

        plan = self._record_plan(keys, cids)
        (lengths, zero, code, hinge), (parent, origin, kind, axis, column, wanted) = \
            self.encoder.kernel_plan
        n = len(stamps)
        rs, rp = len(plan.status_tpl), len(plan.pose_tpl)
        cap = min(n, per) * (rs + rp)
        if self._buf is None or len(self._buf) < cap:
            self._buf = np.empty(cap, dtype=np.uint8)
        if self._words is None or len(self._words) < min(n, per):
            self._words = np.empty((min(n, per), plan.n_words), dtype=np.uint64)
        for a in range(0, n, per):
            e = min(n, a + per)
            m = e - a
            v = valid[a:e]
            st = stamps[a:e]
            part: dict[str, Any] = {f.name: (None if getattr(b, f.name) is None
                                             else getattr(b, f.name)[a:e])
                                    for f in dataclasses.fields(TrackedBatch)}
            sub = TrackedBatch(**part)
            status = self.encoder.status_values(sub, self._seq["status"])
            words = plan.words(self._words, st, self._seq["status"] + np.arange(m),
                               self._seq["tool_tip"] + np.cumsum(v) - 1, status)
            if v.any():
                # joint values (JOINTS order) then the /tf frames, compiled, straight into
                # the words (the rows without a pose are skipped or never written)
                frames, joints = plan.pose_columns(words)
                joint_values_into(np.asarray(sub.q, float), np.asarray(sub.p, float),
                                  np.asarray(sub.u, float), np.asarray(sub.O_s, float), v,
                                  lengths, zero, code, hinge, joints)
                urdf_frames_into(joints, parent, origin, kind, axis, column, wanted,
                                 frames[:, :-1])
                frames[:, -1] = self.encoder.rcm_frame
            starts = np.empty(m, dtype=np.int64)
            size = fill_records(self._buf, plan.status_tpl, plan.pose_tpl, words,
                                plan.s_off, plan.s_size, plan.s_col, plan.p_off,
                                plan.p_size, plan.p_col, v, starts)
            if size < 0:   # pragma: no cover - the plan is built to fit
                raise RuntimeError("internal error: the records do not fit their buffer")
            index = {cids[0]: (st, starts)}
            if v.any():
                for j in range(1, len(keys)):
                    index[cids[j]] = (st[v], starts[v] + rs + plan.record_at[j])
            self._write_chunk(self._buf[:size], index, keys, v, m)

    def write_trajectory_message(self, stamp_ns: int, t_s: NDArray[np.float64],
                                 q: NDArray[np.float64], qd: NDArray[np.float64] | None,
                                 qdd: NDArray[np.float64] | None,
                                 joint_names: tuple[str, ...] = ("q1", "q2", "q3")) -> None:
        """One ``trajectory_msgs/msg/JointTrajectory`` with every sample as a point."""
        self._add("trajectory", int(stamp_ns), _trajectory_bytes(stamp_ns, t_s, q, qd, qdd,
                                                                  joint_names))

    # ------------------------------------------------------------------ finish
    def close(self) -> Path:
        """Finish the file and move it into place; returns its path.

        Raises
        ------
        OSError
            The file cannot be written (a full disk, an I/O error): the error names
            :attr:`path`; nothing is left behind.
        """
        if self._closed:
            return self.path
        try:
            with naming_path(self.path):
                self._file.close()
                if self._atomic is None:
                    self._fh.close()
        except BaseException:
            self.discard()
            raise
        self._closed = True
        if self._atomic is not None:
            self._atomic.commit()               # fsync, rename; names the path
        return self.path

    def discard(self) -> None:
        """Drop the file (nothing is written)."""
        if not self._closed:
            self._closed = True
            if self._atomic is None:
                with contextlib.suppress(OSError):
                    self._fh.close()
        if self._atomic is not None:
            self._atomic.discard()

    def __enter__(self) -> McapOutput:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        if exc_type is None:
            self.close()
        else:
            self.discard()


def _trajectory_bytes(stamp_ns: int, t_s: NDArray[np.float64], q: NDArray[np.float64],
                      qd: NDArray[np.float64] | None, qdd: NDArray[np.float64] | None,
                      joint_names: tuple[str, ...]) -> bytes:
    """CDR of a JointTrajectory: header, joint names, then one point per sample."""
    n = len(t_s)
    b = CdrBuilder()
    b.header(BASE_FRAME)
    b.strings(joint_names)
    b.num("u4", n)
    head = bytearray(b.buf)
    sec, nsec = split_stamps(np.array([int(stamp_ns)]))
    head[4:12] = np.array([sec[0]], "<i4").tobytes() + np.array([nsec[0]], "<u4").tobytes()
    dt = np.rint((np.asarray(t_s, float) - float(t_s[0])) * 1e9).astype(np.int64)
    dsec, dnsec = split_stamps(dt)
    parts = [bytes(head)]
    start = len(head)
    k = 0
    cols = [q, qd, qdd]
    while k < n:
        # the layout of a point depends on its start offset modulo 8; from the second
        # point on it repeats when the point's size is a multiple of 8
        pb = CdrBuilder()
        pb.buf = bytearray(b"\x00" * start)   # offsets relative to the message start
        for name, arr in zip(("pos", "vel", "acc"), cols, strict=True):
            pb.f8_seq(name, 0 if arr is None else arr.shape[1])
        pb.num("u4", 0)                       # effort[]
        pb.num("i4", 0, "dsec")
        pb.num("u4", 0, "dnsec")
        size = len(pb.buf) - start
        tpl = Template(bytes(pb.buf[start:]),
                       tuple((nm, off - start, kd) for nm, off, kd in pb.fields))
        m = n - k if size % 8 == 0 else 1
        vals: dict[str, Any] = {"dsec": dsec[k:k + m], "dnsec": dnsec[k:k + m]}
        for name, arr in zip(("pos", "vel", "acc"), cols, strict=True):
            if arr is not None:
                for i in range(arr.shape[1]):
                    vals[f"{name}.{i}"] = arr[k:k + m, i]
        parts.append(tpl.encode(m, vals).tobytes())
        start += size * m
        k += m
    return b"".join(parts)
