"""The CDR messages of ATHENA's topics, encoded without a file (private).

:class:`RosEncoder` turns poses and tracker states of one design and set-up into the
ROS 2 messages of docs/ros.md (``/athena/tool_tip``, ``/tf``, ``/tf_static``,
``/athena/joint_states``, ``/athena/status``, ``/robot_description``), vectorised
over readings; :class:`TrackedBatch` is what it and the MCAP writer
(:class:`athenakin.ros._write.McapOutput`) take of a batch of tracked readings;
:func:`_trajectory_bytes` encodes a ``trajectory_msgs/msg/JointTrajectory``. The live
stream (:mod:`._live`) sends the same messages.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._typing import BoolArray, FloatArray, IntArray
from ..design import Design
from ..errors import InvalidInputError
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
from ._messages import (
    STATUS_FLAG_FIELDS,
    _joint_state_template,
    _pose_template,
    _put_frame,
    _put_pose,
    _stamp_fields,
    _status_template,
    _string_message,
    _tf_template,
)
from ._record_plan import TF_FRAMES

__all__ = ["RosEncoder", "TrackedBatch", "check_uint"]

_NEAR_BITS = 128 | 256 | 512 | 1024 | 2048 | 4096


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

    stamps_ns: IntArray
    q: FloatArray
    valid: BoolArray
    p: FloatArray
    u: FloatArray
    O_s: FloatArray
    mode: IntArray
    slot: IntArray
    flags: IntArray
    step: FloatArray
    half_chord: FloatArray
    sin_u2: FloatArray
    sin_u4: FloatArray
    clearance_m: FloatArray | None = None
    clearance_flags: IntArray | None = None


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
    backend : {"auto", "numpy", "numba"}, keyword-only
        The frames and quaternions on the compiled kernels or the numpy reference.
    """

    def __init__(self, T_b_e: ArrayLike, design: Design, *, backend: str = "auto") -> None:
        from .._backend import resolve_backend

        #: ``"numba"`` or ``"numpy"``: the caller's backend, resolved once.
        self.backend = "numba" if resolve_backend(backend) else "numpy"
        self.model: UrdfModel = urdf_model(design, np.asarray(T_b_e, dtype=float))
        self.tf_pairs = tuple((BASE_FRAME, c) for c in TF_FRAMES)
        self.templates = {"tool_tip": _pose_template(), "tf": _tf_template(self.tf_pairs),
                          "joint_states": _joint_state_template(tuple(JOINTS)),
                          "status": _status_template()}
        rcm = self.model.T_b_e[None]
        #: ``/tf``'s ``rcm`` frame: translation and quaternion of ``T_b_e`` (fixed).
        self.rcm_frame = np.concatenate([rcm[0, :3, 3], quaternion_xyzw(rcm[:, :3, :3],
                                                                          backend=self.backend)[0]])
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
            _put_pose(vals, j.origin[None], f"t{k}", f"r{k}", backend=self.backend)
        return _tf_template(pairs).encode(1, vals).tobytes()

    def pose_values(self, stamps_ns: IntArray, q: FloatArray,
                    p: FloatArray, u: FloatArray, O_s: FloatArray
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

    def frames(self, jv: dict[str, FloatArray], *,
               out: FloatArray | None = None) -> FloatArray:
        """Translation and quaternion of every ``/tf`` child (:data:`TF_FRAMES`), (N, K, 7).

        ``out``: where to write (a view, e.g. columns of the writer's words).
        """
        if out is None:
            out = np.empty((len(next(iter(jv.values()))), len(TF_FRAMES), 7))
        link_frames(self.model, jv, TF_FRAMES[:-1], out=out[:, :-1], backend=self.backend)
        out[:, -1] = self.rcm_frame
        return out

    def poses(self, stamps_ns: IntArray, q: FloatArray,
              p: FloatArray, u: FloatArray, O_s: FloatArray
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



def _trajectory_bytes(stamp_ns: int, t_s: FloatArray, q: FloatArray,
                      qd: FloatArray | None, qdd: FloatArray | None,
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
