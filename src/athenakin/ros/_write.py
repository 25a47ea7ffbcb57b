"""Write tracked poses and trajectories as MCAP files of ROS 2 messages (private).

One :class:`McapOutput` writes one file through a temporary file in the same
folder, renamed into place only when everything is written: a failure (or
Ctrl-C) leaves nothing, never a partial file. Messages are encoded by
:class:`~athenakin.ros._encoder.RosEncoder` through :mod:`._cdr` (vectorised
over readings; where numba runs, the records of a chunk are filled by
:func:`athenakin.ros._kernels.fill_records`, the same bytes) and written by
:mod:`._mcap`, chunked and compressed (zstd level -3 unless told); the schemas are
the ROS 2 message definitions (from rosbags' type store), so Foxglove, rosbags,
mcap-ros2-support and ``ros2 bag`` read the file as it is.

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
from .._typing import BoolArray, FloatArray, IntArray
from .._validation import check_argument_order, check_path
from ..design import Design
from ..robot._setup import resolve_rcm_frame
from ._encoder import RosEncoder, TrackedBatch, _trajectory_bytes, check_uint
from ._mcap import MESSAGE_HEADER, McapFile, check_compression, compressor_module
from ._messages import (
    STATUS_FLAG_FIELDS,
    STATUS_MSGDEF,
    STATUS_TYPE,
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
    backend : {"auto", "numpy", "numba"}, keyword-only
        The records, frames and quaternions filled by the compiled kernels or the numpy
        reference (:mod:`athenakin._backend`); the same bytes.

    Examples
    --------
    ::

        with McapOutput("run.mcap", T_b_e, design) as out:
            out.write_tracked(batch)
    """

    def __init__(self, path: str | Path, T_b_e: ArrayLike, design: Design, *,
                 compression: str = "zstd", compression_level: int | None = None,
                 target: str | Path | None = None, backend: str = "auto") -> None:
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
        self.encoder = RosEncoder(T_b_e, design, backend=backend)
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

        Parameters
        ----------
        stamp_ns : int
            Their stamp and log time, ns, 0 to 2**63 - 1 (later calls write nothing).

        Raises
        ------
        InvalidInputError
            ``stamp_ns`` out of range or not an integer.
        """
        check_uint(stamp_ns, "stamp_ns", 2**63)
        if self._static_done:
            return
        self._static_done = True
        self._add("robot_description", int(stamp_ns), self.encoder.robot_description())
        self._add("tf_static", int(stamp_ns), self.encoder.tf_static(int(stamp_ns)))

    def _compiled_records(self) -> bool:
        """Whether :meth:`write_tracked` fills its records with the compiled kernel."""
        return self.encoder.backend == "numba"

    def write_tracked(self, b: TrackedBatch) -> None:
        """Write a batch of tracked readings: status for each, poses for the valid ones.

        Each chunk of the file is one byte array of ``rows x (status, tool tip, tf,
        joint states)`` Message records built in place; the rows of readings without
        a pose keep only their status record.

        Parameters
        ----------
        b : TrackedBatch
            The readings (stamps ns, poses in m and rad in the base frame, flags), in order;
            the first batch also writes :meth:`write_static` at its first stamp.
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
        if self._compiled_records():
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
                     v: BoolArray, m: int) -> None:
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

    def _write_tracked_compiled(self, b: TrackedBatch, stamps: IntArray,
                                valid: BoolArray, keys: tuple[str, ...],
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

    def write_trajectory_message(self, stamp_ns: int, t_s: FloatArray,
                                 q: FloatArray, qd: FloatArray | None,
                                 qdd: FloatArray | None,
                                 joint_names: tuple[str, ...] = ("q1", "q2", "q3")) -> None:
        """One ``trajectory_msgs/msg/JointTrajectory`` with every sample as a point.

        Parameters
        ----------
        stamp_ns : int
            Stamp of the message, ns.
        t_s : ndarray, shape (N,)
            Time of each sample, s (``time_from_start`` is ``t_s - t_s[0]``).
        q : ndarray, shape (N, 3)
            Positions, m.
        qd, qdd : ndarray, shape (N, 3), or None
            Velocities (m/s) and accelerations (m/s^2); None leaves them empty.
        joint_names : tuple of str
            The joints of the points (default ``q1, q2, q3``).
        """
        self._add("trajectory", int(stamp_ns), _trajectory_bytes(stamp_ns, t_s, q, qd, qdd,
                                                                  joint_names))

    # ------------------------------------------------------------------ finish
    def close(self) -> Path:
        """Finish the file and move it into place; returns its path.

        Returns
        -------
        Path
            :attr:`path` (also when the file was closed already).

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
