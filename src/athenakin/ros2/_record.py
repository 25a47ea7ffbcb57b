"""Record a session from the graph: what the nodes published, into an MCAP file (private).

:class:`RecorderNode` subscribes to the topics of a session (:func:`session_topics`:
the arm node's state and commands, the teleop node's status, the master's pose and
clutch) with rclpy's raw subscriptions: each message arrives as the CDR bytes its
publisher sent and goes into the file as it is, decoded nowhere and encoded again by
no second serialiser. The file is written by the package's MCAP writer
(:class:`athenakin.ros._mcap.McapFile`: chunks of about :data:`CHUNK_BYTES`,
compressed, indexed), through a temporary file that :meth:`RecorderNode.close`
renames into place; the schemas are the ROS 2 message definitions
(:func:`athenakin.ros._messages.msgdef`; CRTK's from their ``.msg`` files), so
rosbags, the mcap library, Foxglove and ``ros2 bag`` read the file as it is.

Times of a message: its log time is its header stamp (the publishing node's clock
when it stamped the sample); where the type has no header, or the stamp is zero, the
DDS source timestamp (the publisher's system clock at ``publish()``). Its publish
time is always that source timestamp.
"""

from __future__ import annotations

import dataclasses
import functools
import importlib
import re
import struct
import threading
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .._output import AtomicFile, check_output_path, naming_path
from .._validation import check_count
from ..errors import InvalidInputError
from ..ros._mcap import MESSAGE_HEADER, McapFile, check_compression, compressor_module
from ..ros._write import _LATCHED_QOS
from ._arm_node import ARM_TOPICS, _create_node, _qos, check_namespace, resolve_topic
from ._runtime import RosContext, crtk_types, require_rclpy, run_until, spin_executor, stop_node
from ._teleop_node import TELEOP_TOPICS

__all__ = ["RecorderNode", "session_topics", "CHUNK_BYTES", "LATCHED_TOPICS"]

#: Uncompressed bytes of messages per MCAP chunk (about): a chunk is written when its
#: messages reach this size, and at :meth:`RecorderNode.close`.
CHUNK_BYTES = 2**20
#: Topics whose publishers latch their last message (transient local): recorded with
#: that durability, so that the last state before the recorder started is in the file.
LATCHED_TOPICS = (ARM_TOPICS["operating_state"], ARM_TOPICS["robot_description"])
#: ``pkg/msg/Type``: the name of a ROS 2 message type.
_TYPE_NAME = re.compile(r"([A-Za-z][A-Za-z0-9_]*)/msg/([A-Za-z][A-Za-z0-9_]*)")
_STAMP = {True: struct.Struct("<iI"), False: struct.Struct(">iI")}


def session_topics(namespace: str = "/athena", *, pose_topic: str = TELEOP_TOPICS["pose"],
                   clutch_topic: str | None = TELEOP_TOPICS["clutch"]) -> dict[str, str]:
    """The topics of a teleoperated session on the graph and their message types.

    The arm node's ``measured_js``, ``setpoint_js``, ``measured_cp``, ``setpoint_cp``,
    ``operating_state`` and ``status``, the command ``servo_jp``, the teleop node's
    ``teleop/status``, and the master's pose and clutch.

    Parameters
    ----------
    namespace : str
        The arm node's namespace (``/athena``).
    pose_topic : str, keyword-only
        The master's ``geometry_msgs/msg/PoseStamped`` (``/master/pose``).
    clutch_topic : str or None, keyword-only
        The master's ``sensor_msgs/msg/Joy`` clutch (``/master/joy``); None: none.

    Returns
    -------
    dict of str -> str
        Absolute topic name -> ``pkg/msg/Type``; ``operating_state`` and ``status``
        carry CRTK's types where ``crtk_msgs`` is built, else the ``std_msgs/msg/String``
        stand-ins (:func:`athenakin.ros2.crtk_types`), as the arm node does.

    Raises
    ------
    ValueError, TypeError
        A bad namespace or topic name.
    """
    ns = check_namespace(namespace)
    crtk = crtk_types()
    js, ps = "sensor_msgs/msg/JointState", "geometry_msgs/msg/PoseStamped"
    rel = {ARM_TOPICS["measured_js"]: js, ARM_TOPICS["setpoint_js"]: js,
           ARM_TOPICS["measured_cp"]: ps, ARM_TOPICS["setpoint_cp"]: ps,
           ARM_TOPICS["operating_state"]: _type_name(crtk.operating_state),
           ARM_TOPICS["status"]: _type_name(crtk.string_stamped),
           TELEOP_TOPICS["servo_jp"]: js,
           TELEOP_TOPICS["status"]: "diagnostic_msgs/msg/DiagnosticArray"}
    out = {_resolve(k, ns, "topics"): v for k, v in rel.items()}
    out[_resolve(pose_topic, ns, "pose_topic")] = ps
    if clutch_topic is not None:
        out[_resolve(clutch_topic, ns, "clutch_topic")] = "sensor_msgs/msg/Joy"
    return out


def _resolve(name: object, namespace: str, what: str) -> str:
    """The absolute name of a topic (a relative one under ``namespace``), rclpy's rules.

    A private name (``~``) or a substitution (``{node}``) would name the recorder's own
    topics, not the session's: refused.
    """
    if isinstance(name, str) and (name.startswith("~") or "{" in name):
        raise InvalidInputError(f"{what}: {name!r} would name the recorder's own topic; "
                                f"expected an absolute or relative name (e.g. "
                                f"/athena/measured_js or measured_js)")
    return resolve_topic(name, what, namespace=namespace)


def _type_name(cls: type) -> str:
    """``pkg/msg/Type`` of a generated ROS 2 message class."""
    return f"{cls.__module__.split('.')[0]}/msg/{cls.__name__}"


def _message_type(typ: object, topic: str) -> tuple[Any, str]:
    """The message class and its ``pkg/msg/Type`` name, from either.

    Raises
    ------
    TypeError
        Neither a str nor a generated message class.
    InvalidInputError
        A malformed name, or one whose interface package is not installed.
    """
    if isinstance(typ, type):
        if not hasattr(typ, "get_fields_and_field_types") or \
                not hasattr(type(typ), "__import_type_support__"):
            raise TypeError(f"topics[{topic!r}]: expected a ROS 2 message class (e.g. "
                            f"sensor_msgs.msg.JointState), got the class {typ.__name__}")
        return typ, _type_name(typ)
    if not isinstance(typ, str):
        raise TypeError(f"topics[{topic!r}]: expected a message type ('pkg/msg/Type' or its "
                        f"class), got {type(typ).__name__}")
    m = _TYPE_NAME.fullmatch(typ)
    if m is None:
        raise InvalidInputError(f"topics[{topic!r}]: expected a message type 'pkg/msg/Type' "
                                f"(e.g. sensor_msgs/msg/JointState), got {typ!r:.80}")
    try:
        cls = getattr(importlib.import_module(f"{m.group(1)}.msg"), m.group(2))
    except (ImportError, AttributeError):
        raise InvalidInputError(f"topics[{topic!r}]: no message type {typ!r} in this Python "
                                f"(its interface package is not installed)") from None
    return cls, typ


@functools.lru_cache(maxsize=64)
def message_definition(typename: str) -> str:
    """The ROS 2 definition of ``typename`` with its dependencies (an MCAP ``ros2msg`` schema).

    Types of ROS 2's own interface packages come from rosbags' type store
    (:func:`athenakin.ros._messages.msgdef`); another type is read from its ``.msg``
    file, installed by rosidl (``<prefix>/share/<pkg>/msg/``) or, for CRTK's, the one
    shipped in :data:`athenakin.ros2.CRTK_MSGS_DIR`.

    Parameters
    ----------
    typename : str
        ``pkg/msg/Type``.

    Returns
    -------
    str
        The definition, then each dependency's after a line of ``=`` and ``MSG: pkg/Type``.

    Raises
    ------
    InvalidInputError
        No definition of the type, or of one of its dependencies, is found.
    """
    import sys

    from ..ros._errors import ros_extra_missing
    from ..ros._messages import msgdef

    try:
        from rosbags.typesys import Stores, TypesysError, get_types_from_msg, get_typestore
    except ModuleNotFoundError as exc:
        raise ros_extra_missing(exc) from None
    from ._build import CRTK_MSGS_DIR

    try:
        return msgdef(typename)
    except TypesysError:
        pass
    pkg, _, name = typename.split("/")
    folders = [Path(sys.prefix) / "share" / pkg / "msg"]
    if pkg == "crtk_msgs":
        folders.append(CRTK_MSGS_DIR / "msg")
    for folder in folders:
        path = folder / f"{name}.msg"
        if path.is_file():
            store = get_typestore(Stores.ROS2_HUMBLE)
            try:
                store.register(get_types_from_msg(path.read_text(encoding="utf-8"), typename))
                return str(store.generate_msgdef(typename, ros_version=2)[0])
            except TypesysError as exc:
                raise InvalidInputError(f"{typename}: its definition {path} names a type "
                                        f"this recorder cannot define: {exc}") from None
    raise InvalidInputError(f"{typename}: no message definition found (rosbags' ROS 2 types, "
                            f"{Path(sys.prefix) / 'share' / pkg / 'msg'})")


def header_stamp_ns(raw: bytes, cls: type) -> int:
    """The header stamp (ns) of a serialised message whose first field is a ``std_msgs/Header``.

    Read in place from plain CDR (XCDR1 or XCDR2, either byte order: the stamp follows the
    4-byte encapsulation header); any other encapsulation is deserialised by rclpy.

    Parameters
    ----------
    raw : bytes
        The message as it travelled (encapsulation header first).
    cls : type
        Its message class.

    Returns
    -------
    int
        ``sec * 10**9 + nanosec`` (0 or less: unstamped).
    """
    if len(raw) >= 12 and raw[0] == 0 and raw[1] in (0, 1, 6, 7):
        sec, nsec = _STAMP[bool(raw[1] & 1)].unpack_from(raw, 4)
    else:
        from rclpy.serialization import deserialize_message

        header: Any = deserialize_message(raw, cls).header
        sec, nsec = header.stamp.sec, header.stamp.nanosec
    return int(sec) * 1_000_000_000 + int(nsec)


@dataclasses.dataclass(frozen=True)
class _Topic:
    name: str
    type_name: str
    cls: Any                  # the rclpy message class (generated: no static type)
    stamped: bool
    latched: bool


def _topic_table(topics: object, namespace: str) -> list[_Topic]:
    """The recorded topics, each name and type checked (named errors)."""
    if topics is None:
        topics = session_topics(namespace)
    if not isinstance(topics, Mapping):
        raise TypeError(f"topics: expected a mapping of topic name -> message type, got "
                        f"{type(topics).__name__}")
    if not topics:
        raise InvalidInputError("topics: expected at least one topic, got none")
    table: dict[str, _Topic] = {}
    for name, typ in topics.items():
        full = _resolve(name, namespace, "topics")
        if full in table:
            raise InvalidInputError(f"topics: {name!r} is {full!r} a second time")
        cls, tname = _message_type(typ, full)
        fields = list(cls.get_fields_and_field_types().items())
        stamped = bool(fields) and fields[0] == ("header", "std_msgs/Header")
        table[full] = _Topic(full, tname, cls, stamped, full in _latched(namespace))
    return list(table.values())


def _latched(namespace: str) -> set[str]:
    return {_resolve(t, namespace, "topics") for t in LATCHED_TOPICS}


class RecorderNode:
    """Record topics of a ROS 2 graph into an MCAP file, as their publishers sent them.

    Every message is written as the CDR bytes it travelled in, on a channel of its topic
    with the ROS 2 definition of its type as schema; its log time is its header stamp
    (the DDS source timestamp where the type has no header or the stamp is zero), its
    publish time the source timestamp. The subscriptions are reliable, ``depth`` deep,
    volatile (transient local for :data:`LATCHED_TOPICS`, whose last message before the
    start is then recorded too): a best-effort publisher is not recorded.

    Parameters
    ----------
    path : str or Path
        The MCAP file to write. It appears when :meth:`close` finishes it (a temporary
        file in the same folder until then); a Ctrl-C that ends the recording closes it
        complete, :meth:`discard` drops it.
    topics : mapping of str -> str or type, optional, keyword-only
        Topic name (absolute, or relative to ``namespace``) -> message type
        (``"sensor_msgs/msg/JointState"`` or the class); default
        :func:`session_topics` of ``namespace``.
    namespace : str, keyword-only
        The arm node's namespace (``/athena``).
    compression : {"zstd", "lz4", "none"}, keyword-only
    compression_level : int, optional, keyword-only
        As :class:`athenakin.ros.McapOutput`'s.
    depth : int, keyword-only
        History depth of each subscription (1000): messages the recorder may fall
        behind by before the oldest are lost.
    use_sim_time : bool, keyword-only
    target : str or Path, optional, keyword-only
        Write this file instead of a temporary one and do no rename (the caller renames
        it: the CLI's output manager).
    context : RosContext, optional, keyword-only
        The rclpy context to join (default: its own, closed with the node).
    node_name : str, keyword-only

    Attributes
    ----------
    path : Path
    topics : tuple of str
        The recorded topics (absolute names), in the file's channel order.
    error : str or None
        Why recording stopped early (the file could not be written), else None.

    Raises
    ------
    TypeError, ValueError
        A bad argument (:class:`~athenakin.errors.InvalidInputError`: a topic name, a
        message type not installed, a folder or FIFO as ``path``, a compression), named,
        before any file or ROS context is made.
    ModuleNotFoundError
        rclpy (the extra ``ros2``) or rosbags / zstandard (the extra ``ros``) missing.

    Examples
    --------
    ::

        with RecorderNode("session.mcap") as rec:     # /athena's session topics
            rec.spin(60.0)                            # 60 s, or until Ctrl-C
        print(rec.counts)
    """

    def __init__(self, path: str | Path, *, topics: Mapping[str, Any] | None = None,
                 namespace: str = "/athena", compression: str = "zstd",
                 compression_level: int | None = None, depth: int = 1000,
                 use_sim_time: bool = False, target: str | Path | None = None,
                 context: RosContext | None = None,
                 node_name: str = "athena_recorder") -> None:
        require_rclpy()
        compression, compression_level = check_compression(compression, compression_level)
        self.path = check_output_path(path)
        target = None if target is None else check_output_path(target, "target")
        self.namespace = check_namespace(namespace)
        depth = check_count(depth, "depth", minimum=1, maximum=1_000_000)
        table = _topic_table(topics, self.namespace)
        schemas = {t.type_name: message_definition(t.type_name) for t in table}
        compressor_module(compression)         # a missing extra: named, before any file
        self.topics = tuple(t.name for t in table)
        self.error: str | None = None
        self._table = table
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._buf: list[tuple[int, int, int, int, bytes]] = []
        self._size = 0
        self._counts = [0] * len(table)
        self._last: list[int | None] = [None] * len(table)
        self._finished = False
        self._threads: list[threading.Thread] = []
        self._atomic = AtomicFile(self.path, suffix=".mcap") if target is None else None
        with naming_path(self.path):
            if self._atomic is not None:
                self._fh = self._atomic.fh
            else:
                assert target is not None
                self._fh = open(target, "wb")  # noqa: SIM115
        self._own_context = context is None
        self.context: RosContext | None = None
        try:
            with naming_path(self.path):
                self._file = McapFile(self._fh, compression=compression,
                                      level=compression_level, library="athenakin.ros2")
                self._channels = self._define(schemas)
            self.context = RosContext() if context is None else context
            self._subscribe(node_name, use_sim_time, depth)
        except BaseException:
            self._drop()
            if self._own_context and self.context is not None:
                self.context.close()
            raise

    def _define(self, schemas: dict[str, str]) -> list[int]:
        """Write a schema per type and a channel per topic; the channel ids, in order."""
        sid = {name: self._file.schema(name, "ros2msg", text.encode())
               for name, text in schemas.items()}
        return [self._file.channel(t.name, "cdr", sid[t.type_name],
                                   {"offered_qos_profiles": _LATCHED_QOS} if t.latched else {})
                for t in self._table]

    def _subscribe(self, node_name: str, use_sim_time: bool, depth: int) -> None:
        from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.parameter import Parameter

        assert self.context is not None
        self.node = _create_node(node_name, self.namespace, self.context, use_sim_time,
                                 Parameter)
        group = MutuallyExclusiveCallbackGroup()
        self._subs = [self.node.create_subscription(
            t.cls, t.name, functools.partial(self._on_message, k), _qos(depth, latched=t.latched),
            callback_group=group, raw=True) for k, t in enumerate(self._table)]
        self._executor = SingleThreadedExecutor(context=self.context.context)
        self._executor.add_node(self.node)

    # --- messages -------------------------------------------------------------------
    def _on_message(self, k: int, raw: bytes, info: Any) -> None:
        """Keep one message (the executor's callback); write a chunk when enough are kept."""
        t = self._table[k]
        src = int(info["source_timestamp"]) or int(info["received_timestamp"]) \
            or time.time_ns()
        try:
            stamp = header_stamp_ns(raw, t.cls) if t.stamped else 0
        except Exception:        # bytes rclpy cannot read back: logged at their source time
            stamp = 0
        with self._lock:
            if self._finished or self.error is not None:
                return
            log = stamp if stamp > 0 else src
            self._buf.append((self._channels[k], self._counts[k], log, src, bytes(raw)))
            self._counts[k] += 1
            self._last[k] = log
            self._size += MESSAGE_HEADER + len(raw)
            if self._size >= CHUNK_BYTES:
                try:
                    self._flush()
                except OSError as exc:       # a full disk: stop recording, say why at close
                    self.error = f"{type(exc).__name__}: {exc}"
                    self._stop.set()

    def _flush(self) -> None:
        """Write the kept messages as one chunk (the caller holds the lock)."""
        items, self._buf, self._size = self._buf, [], 0
        with naming_path(self.path):
            self._file.messages(items)

    @property
    def counts(self) -> dict[str, int]:
        """Messages recorded so far, per topic (absolute name)."""
        with self._lock:
            return dict(zip(self.topics, self._counts, strict=True))

    @property
    def last_log_times(self) -> dict[str, int | None]:
        """Log time (ns) of the newest message recorded per topic (None: none yet).

        Messages of one publisher arrive in the order it sent them (reliable QoS): once
        its last message's stamp is here, everything it sent before is recorded too.
        """
        with self._lock:
            return dict(zip(self.topics, self._last, strict=True))

    @property
    def recording(self) -> bool:
        """Messages are being recorded: started, not stopped, no write error, context up."""
        return (bool(self._threads) and not self._stop.is_set() and not self._finished
                and self.context is not None and self.context.ok)

    # --- running --------------------------------------------------------------------
    def start(self) -> RecorderNode:
        """Start the executor's thread: messages are recorded from now (idempotent).

        Returns
        -------
        RecorderNode
            ``self``, started.
        """
        if not self._threads and not self._finished:
            assert self.context is not None
            self._threads = [threading.Thread(
                target=spin_executor, args=(self._stop, self._executor, self.context),
                name="athena-recorder", daemon=True)]
            self._threads[0].start()
        return self

    def spin(self, timeout: float | None = None) -> None:
        """Record until Ctrl-C, the context's shutdown, a write error, or ``timeout`` s.

        Parameters
        ----------
        timeout : float, optional
            Seconds to record at most (default: until shutdown).
        """
        self.start()
        assert self.context is not None
        run_until(self._stop, self.context, timeout)

    def _end(self) -> None:
        """Stop the subscriptions and the thread, destroy the node (idempotent)."""
        assert self.context is not None
        stop_node(self._stop, self._threads, self._executor, self.node,
                  self.context if self._own_context else None)
        self._threads = []

    def close(self) -> Path:
        """Stop recording, write the last chunk and the summary, move the file into place.

        Returns
        -------
        Path
            :attr:`path` (also when closed already).

        Raises
        ------
        OSError
            The file could not be written (now or while recording: :attr:`error`); the
            error names :attr:`path` and nothing is left behind.
        """
        self._end()
        with self._lock:
            if self._finished:
                return self.path
            self._finished = True
            try:
                if self.error is not None:
                    raise OSError(f"{self.path}: recording stopped: {self.error}")
                self._flush()
                with naming_path(self.path):
                    self._file.close()
                    if self._atomic is None:
                        self._fh.close()
            except BaseException:
                self._drop()
                raise
        if self._atomic is not None:
            self._atomic.commit()               # fsync, rename; names the path
        return self.path

    def _drop(self) -> None:
        """Remove the temporary file, or close the caller's ``target`` (idempotent)."""
        if self._atomic is not None:
            self._atomic.discard()
        elif not self._fh.closed:
            self._fh.close()

    def discard(self) -> None:
        """Stop recording and drop the file (nothing is written; idempotent)."""
        self._end()
        with self._lock:
            self._finished = True
        self._drop()

    def __enter__(self) -> RecorderNode:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()
