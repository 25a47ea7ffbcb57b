"""Where the messages of a recording come from (private): formats and raw sources.

:func:`recording_format` tells the formats apart by their content;
:func:`_raw_messages` yields the raw messages of one topic, after checking the topic
and its type: a single MCAP file or the MCAP storage files of a rosbag2 folder through
the MCAP record reader (:class:`~athenakin.ros._mcap_stream._McapStream`), sqlite3
storage and ROS 1 bags through rosbags. Decoding the messages into readings is
:mod:`athenakin.ros._read`'s.
"""

from __future__ import annotations

import os
import re
import stat
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from .._validation import check_path
from ._errors import RecordingError, RecordingWarning, ros_extra_missing
from ._mcap_stream import _Bulk, _McapStream

__all__ = ["recording_format", "JOINT_STATE_TYPES"]

#: Message type names of a joint state (ROS 2, ROS 1 spelling).
JOINT_STATE_TYPES = ("sensor_msgs/msg/JointState", "sensor_msgs/JointState")

_MCAP_MAGIC = b"\x89MCAP0\r\n"
_ROS1_MAGIC = b"#ROSBAG V2.0\n"
_SQLITE_MAGIC = b"SQLite format 3\x00"


# ---------------------------------------------------------------------------- formats
def recording_format(path: str | Path) -> str:
    """The format of a recording: ``"rosbag2"``, ``"mcap"``, ``"db3"`` or ``"rosbag1"``.

    Parameters
    ----------
    path : str or Path
        A rosbag2 folder, an MCAP file, a ``.db3`` file or a ROS 1 bag.

    Returns
    -------
    str
        ``"rosbag2"`` (a folder), ``"mcap"``, ``"db3"`` or ``"rosbag1"``, told apart by
        the content, not the name.

    Raises
    ------
    RecordingError
        No such file, not a regular file or folder (a FIFO, a device), or none of
        these formats.
    """
    p = check_path(path)
    try:
        st = os.stat(p)
    except OSError as exc:
        raise RecordingError(f"{p}: cannot open the recording ({exc.strerror or exc})") \
            from None
    if stat.S_ISDIR(st.st_mode):
        if not (p / "metadata.yaml").is_file():
            raise RecordingError(f"{p}: a folder without metadata.yaml; expected a rosbag2 "
                                 f"folder, an MCAP file or a ROS 1 bag")
        return "rosbag2"
    if not stat.S_ISREG(st.st_mode):
        raise RecordingError(f"{p}: not a regular file (a FIFO, socket or device); expected "
                             f"a rosbag2 folder, an MCAP file or a ROS 1 bag")
    with open(p, "rb") as fh:
        head = fh.read(16)
    if head.startswith(_MCAP_MAGIC):
        return "mcap"
    if head.startswith(_ROS1_MAGIC):
        return "rosbag1"
    if head.startswith(_SQLITE_MAGIC):
        return "db3"
    raise RecordingError(f"{p}: not a recording (first bytes {head[:8]!r}); expected a "
                         f"rosbag2 folder, an MCAP file or a ROS 1 bag")


def _source(p: Path, kind: str) -> str:
    if kind == "rosbag2":
        return "rosbag2/mcap" if any(p.glob("*.mcap")) else "rosbag2/sqlite3"
    return {"db3": "rosbag2/sqlite3", "mcap": "mcap", "rosbag1": "rosbag1"}[kind]


# ---------------------------------------------------------------------------- sources
def _raw_messages(path: Path, kind: str, topic: str, *,
                  backend: str = "auto") -> Iterator[tuple[Any, Any, str]]:
    """``(log_time_ns, raw, encoding)`` of ``topic``, after checking topic and type."""
    if kind == "mcap":
        yield from _mcap_messages(path, topic, backend=backend)
        return
    try:
        from rosbags.rosbag1 import Reader as Reader1
        from rosbags.rosbag2 import Reader as Reader2
    except ModuleNotFoundError as exc:  # pragma: no cover - the extra is installed in CI
        raise ros_extra_missing(exc) from None
    if kind == "db3" and path.suffix != ".db3":
        raise RecordingError(f"{path}: a single rosbag2 sqlite3 file must be named *.db3 "
                             f"(or give its folder)")
    reader: Any = Reader1(path) if kind == "rosbag1" else Reader2(path)
    with reader:
        conns = [c for c in reader.connections if c.topic == topic]
        if not conns:
            _missing_topic(path, topic, {c.topic: c.msgtype for c in reader.connections})
        for c in conns:
            _check_type(path, topic, c.msgtype)
        files = _mcap_storage(path, reader) if kind == "rosbag2" else None
        if files is None:
            enc = "ros1" if kind == "rosbag1" else "cdr"
            for _conn, t, raw in reader.messages(connections=conns):
                yield int(t), raw, enc
            return
    for f in files:        # MCAP storage: each file through the MCAP fast path, in order
        yield from _mcap_messages(f, topic, in_bag=True, backend=backend)


def _mcap_storage(path: Path, reader: Any) -> list[Path] | None:
    """The MCAP storage files of a rosbag2 folder, in recording order, or None.

    None (rosbags reads it, message by message) for sqlite3 storage or compressed
    files or messages (``compression_mode`` set). The files are those of the folder
    named in its ``metadata.yaml``, ordered by their split index (``bag_0.mcap``,
    ``bag_1.mcap``, ..., ``bag_10.mcap``).
    """
    if getattr(reader, "compression_mode", None):
        return None
    try:
        listed = (path / "metadata.yaml").read_text(encoding="utf-8")
    except (OSError, UnicodeError):
        return None
    files = [f for f in path.iterdir() if f.suffix == ".mcap" and f.name in listed]
    if not files:
        return None
    for f in files:
        with open(f, "rb") as fh:
            if fh.read(8) != _MCAP_MAGIC:
                return None
    return sorted(files, key=lambda f: [int(t) if t.isdigit() else t
                                        for t in re.split(r"(\d+)", f.name)])


def _missing_topic(path: Path, topic: str, present: dict[str, str]) -> None:
    listed = ", ".join(f"{k} ({v})" for k, v in sorted(present.items())) or "none"
    raise RecordingError(f"{path}: no topic {topic!r}; topics present: {listed} (choose one "
                         f"with topic=... / --topic)")


def _check_type(path: Path, topic: str, msgtype: str) -> None:
    if msgtype not in JOINT_STATE_TYPES:
        raise RecordingError(f"{path}: topic {topic!r} holds {msgtype}, expected "
                             f"sensor_msgs/msg/JointState")


def _mcap_messages(path: Path, topic: str, *, in_bag: bool = False,
                   backend: str = "auto") -> Iterator[tuple[Any, Any, str]]:
    """Messages of ``topic`` in file order (the summary, when present, checks the topic).

    ``(log time, data, encoding)``, or for a run of messages read at once
    ``(log times, _Bulk, encoding)``. ``in_bag``: a storage file of a rosbag2 folder
    (the folder's metadata checked the topic; a file may hold none of its messages).
    ``backend``: the chunks decoded by the compiled scan or record by record.
    """
    try:
        from mcap.reader import make_reader
    except ModuleNotFoundError as exc:  # pragma: no cover
        raise ros_extra_missing(exc) from None
    with open(path, "rb") as fh:
        try:
            summary = make_reader(fh).get_summary()
        except Exception:          # no footer (a truncated file): read it from the start
            summary = None
        if summary is not None and not in_bag:
            chans = {c.topic: summary.schemas.get(c.schema_id) for c in
                     summary.channels.values()}
            if topic not in chans:
                _missing_topic(path, topic, {k: (s.name if s else "?") for k, s in
                                             chans.items()})
        fh.seek(0)
        stream = _McapStream(fh, os.fstat(fh.fileno()).st_size, summary, topic,
                             backend=backend)
        wanted: dict[int, str] = {}
        for cid, log_time, data in stream.messages():
            enc = wanted.get(cid)
            if enc is None:
                ch = stream.channels.get(cid)
                if ch is None or ch[0] != topic:
                    continue
                schema = stream.schemas.get(ch[1], "(no schema)")
                _check_type(path, topic, schema)
                if ch[2] not in ("cdr", "ros1"):
                    raise RecordingError(f"{path}: topic {topic!r} is encoded as {ch[2]!r}, "
                                         f"expected cdr or ros1")
                wanted[cid] = enc = ch[2]
            stream.read += len(log_time) if isinstance(data, _Bulk) else 1
            yield log_time, data, enc
        if stream.lost is not None:
            good, why = stream.lost
            if not stream.read:
                raise RecordingError(f"{path}: truncated or corrupt MCAP file: no complete "
                                     f"chunk of {topic!r} before byte {good} of "
                                     f"{stream.size} ({why})")
            warnings.warn(RecordingWarning(
                f"{path}: truncated MCAP file (a recorder stopped mid-run?): read "
                f"{stream.read} messages of {topic!r}, up to the last complete chunk "
                f"(byte {good} of {stream.size}); the rest, {stream.size - good} bytes "
                f"({100.0 * (stream.size - good) / max(stream.size, 1):.1f} % of the file), "
                f"could not be read ({why}); what the recorder never wrote is not known"),
                stacklevel=2)
        if not wanted and summary is None and not in_bag:
            present = {t: stream.schemas.get(sid, "?") for t, sid, _ in
                       stream.channels.values()}
            if topic not in present:
                _missing_topic(path, topic, present)
