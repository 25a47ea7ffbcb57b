"""How the recorder lays out one batch's records: channels, sizes and offsets (_RecordPlan)."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._typing import FloatArray, IntArray
from ..sim import JOINTS
from ._cdr import Template
from ._frames import (
    MOVING_LINKS,
    RCM_FRAME,
    TOOL_TIP_FRAME,
)
from ._mcap import MESSAGE_HEADER, McapFile

#: Child frames of ``/tf`` (parent ``base``), in message order.
TF_FRAMES = (*MOVING_LINKS, TOOL_TIP_FRAME, RCM_FRAME)


@dataclasses.dataclass(frozen=True)
class _RecordPlan:
    """The Message records of one tracked reading as templates and numbers at offsets.

    ``status_tpl``: the status record (header and CDR message); ``pose_tpl``: the tool
    tip, ``/tf`` and joint-state records one after the other (``record_at[j]``: where
    record ``j`` of ``keys`` starts in it, ``record_at[0] = 0`` for the status). Field
    ``f`` of each part: ``size[f]`` bytes at ``off[f]`` holding column ``col[f]`` of the
    words of :meth:`words`, laid out as: the ``/tf`` frames (``K x 7`` float64, as
    :meth:`RosEncoder.frames`), the joint values (``JOINTS`` order), the status floats
    (``status_float``), then integers: stamp, status sequence, pose sequence, stamp
    seconds, stamp nanoseconds, the status integers (``status_int``).
    """

    status_tpl: NDArray[np.uint8]
    pose_tpl: NDArray[np.uint8]
    record_at: tuple[int, ...]
    s_off: IntArray
    s_size: IntArray
    s_col: IntArray
    p_off: IntArray
    p_size: IntArray
    p_col: IntArray
    status_float: tuple[str, ...]
    status_int: tuple[str, ...]
    n_frames: int

    @staticmethod
    def of(templates: dict[str, Template], keys: tuple[str, ...], cids: list[int]
           ) -> _RecordPlan:
        sizes = {"f8": 8, "i4": 4, "u4": 4, "u1": 1, "i1": 1, "b1": 1}
        nf = 7 * len(TF_FRAMES)
        tip = 7 * TF_FRAMES.index(TOOL_TIP_FRAME)
        status = templates["status"].fields
        s_float = tuple(nm for nm, _, kd in status if kd == "f8")
        s_int = tuple(nm for nm, _, kd in status if kd != "f8" and not nm.startswith("stamp"))
        base_int = nf + len(JOINTS) + len(s_float)
        special = {"@stamp": base_int, "@seq.status": base_int + 1, "@seq.pose": base_int + 2}
        comp = {c: i for i, c in enumerate("xyz")}

        def column(key: str, name: str) -> int:
            if name.endswith(".sec") and "stamp" in name:
                return base_int + 3
            if name.endswith(".nanosec") and "stamp" in name:
                return base_int + 4
            head, _, tail = name.partition(".")
            if key == "tool_tip":
                return tip + (comp[tail] if head == "p" else 3 + "xyzw".index(tail))
            if key == "tf":
                k = int(head[1:])
                return 7 * k + (comp[tail] if head[0] == "t" else 3 + "xyzw".index(tail))
            if key == "joint_states":
                return nf + int(tail)
            if name in s_float:
                return nf + len(JOINTS) + s_float.index(name)
            return base_int + 5 + s_int.index(name)

        parts: list[tuple[bytes, list[tuple[int, int, int]]]] = [(b"", []), (b"", [])]
        record_at = [0]
        for j, key in enumerate(keys):
            tpl = templates[key]
            head = np.zeros((1, MESSAGE_HEADER), dtype=np.uint8)
            McapFile.message_headers(head, cids[j], [0], [0], tpl.size)
            side = 0 if j == 0 else 1
            data, fields = parts[side]
            at = len(data)
            if j:
                record_at.append(at)
            seq = special["@seq.status" if j == 0 else "@seq.pose"]
            fields += [(at + 11, 4, seq), (at + 15, 8, special["@stamp"]),
                       (at + 23, 8, special["@stamp"])]
            fields += [(at + MESSAGE_HEADER + off, sizes[kind], column(key, name))
                       for name, off, kind in tpl.fields]
            parts[side] = (data + head.tobytes() + tpl.data, fields)
        (sd, sf), (pd, pf) = parts
        return _RecordPlan(
            status_tpl=np.frombuffer(sd, np.uint8), pose_tpl=np.frombuffer(pd, np.uint8),
            record_at=tuple(record_at),
            s_off=np.array([f[0] for f in sf], np.int64),
            s_size=np.array([f[1] for f in sf], np.int64),
            s_col=np.array([f[2] for f in sf], np.int64),
            p_off=np.array([f[0] for f in pf], np.int64),
            p_size=np.array([f[1] for f in pf], np.int64),
            p_col=np.array([f[2] for f in pf], np.int64),
            status_float=s_float, status_int=s_int, n_frames=len(TF_FRAMES))

    @property
    def n_words(self) -> int:
        """Columns of :meth:`words`."""
        return 7 * self.n_frames + len(JOINTS) + len(self.status_float) + 5 \
            + len(self.status_int)

    def words(self, buf: NDArray[np.uint64], stamps: IntArray,
              seq_status: IntArray, seq_pose: IntArray,
              status: dict[str, Any]) -> NDArray[np.uint64]:
        """The numbers of ``m`` readings as 8-byte words (m, C), in the plan's columns.

        Written into ``buf[:m]`` (at least ``m`` rows of :attr:`n_words`); the pose
        columns are left for :meth:`pose_columns` (unset where no reading has a pose:
        the pose records are then not written).
        """
        m = len(stamps)
        nf = 7 * self.n_frames
        nj = len(JOINTS)
        ns = len(self.status_float)
        base = nf + nj + ns
        words = buf[:m]
        as_float, as_int = words.view(np.float64), words.view(np.int64)
        for i, name in enumerate(self.status_float):
            as_float[:, nf + nj + i] = status[name]
        as_int[:, base] = stamps
        as_int[:, base + 1] = seq_status
        as_int[:, base + 2] = seq_pose
        as_int[:, base + 3] = status["stamp.sec"]
        as_int[:, base + 4] = status["stamp.nanosec"]
        for i, name in enumerate(self.status_int):
            as_int[:, base + 5 + i] = status[name]
        return words

    def pose_columns(self, words: NDArray[np.uint64]
                     ) -> tuple[FloatArray, FloatArray]:
        """Views of ``words`` as the ``/tf`` frames (m, K, 7) and the joints (m, J), float64."""
        m = words.shape[0]
        nf = 7 * self.n_frames
        as_float = words.view(np.float64)
        return (as_float[:, :nf].reshape(m, self.n_frames, 7),
                as_float[:, nf:nf + len(JOINTS)])
