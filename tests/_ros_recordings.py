"""Small ROS recordings of sensor_msgs/JointState, written by independent writers (test helper).

rosbags' writers for rosbag2 (sqlite3, MCAP storage) and ROS 1 bags, mcap-ros2-support's
writer for plain MCAP files. Nothing here uses athenakin.ros.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: A stamp with every nanosecond digit significant.
T0_NS = 1_700_000_000_123_456_789
#: Step between readings, ns (1 ms and 3 ns: not a round number).
DT_NS = 1_000_003
#: Joint names in the recording: the actuators among others, not in q order.
NAMES = ("roll", "q3", "gripper", "q1", "q2")
#: Where q1, q2, q3 sit in NAMES.
Q_INDEX = (3, 4, 1)


def q_stream(n: int, seed: int = 0) -> np.ndarray:
    """A smooth stream of n readings (m) about the reference configuration."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, n)
    w = rng.uniform(0.5, 2.0, 3)
    return np.array([-0.10, 0.10, 0.45]) + 0.01 * np.sin(np.outer(t, w))


def positions(q: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """Positions in the order of NAMES (the extra joints hold 7, 8, 9), divided by scale."""
    out = np.empty((len(q), len(NAMES)))
    out[:, 0], out[:, 2] = 7.0, 8.0
    for k, i in enumerate(Q_INDEX):
        out[:, i] = q[:, k] / scale
    return out


def stamps(n: int) -> np.ndarray:
    return T0_NS + DT_NS * np.arange(n, dtype=np.int64)


def _ros2_store():
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_HUMBLE)


def _js(store, stamp: int, pos: np.ndarray, vel: np.ndarray | None, names=NAMES):
    T = store.types
    return T["sensor_msgs/msg/JointState"](
        header=T["std_msgs/msg/Header"](
            stamp=T["builtin_interfaces/msg/Time"](sec=int(stamp // 10**9),
                                                    nanosec=int(stamp % 10**9)),
            frame_id=""),
        name=list(names), position=np.asarray(pos, float),
        velocity=np.zeros(0) if vel is None else np.asarray(vel, float),
        effort=np.zeros(0))


def write_rosbag2(path: Path, pos: np.ndarray, st: np.ndarray, *, storage: str = "sqlite3",
                  vel: np.ndarray | None = None, topic: str = "/joint_states",
                  log_ns: np.ndarray | None = None, extra_topic: bool = True) -> Path:
    """A rosbag2 folder with rosbags' writer; log time ``log_ns`` (default stamp + 17 ns)."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    store = _ros2_store()
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as w:
        c = w.add_connection(topic, "sensor_msgs/msg/JointState", typestore=store)
        if extra_topic:
            s = w.add_connection("/chatter", "std_msgs/msg/String", typestore=store)
            w.write(s, int(st[0]), store.serialize_cdr(store.types["std_msgs/msg/String"](
                data="hello"), "std_msgs/msg/String"))
        for i in range(len(pos)):
            m = _js(store, int(st[i]), pos[i], None if vel is None else vel[i])
            w.write(c, int(st[i]) + 17 if log_ns is None else int(log_ns[i]),
                    store.serialize_cdr(m, "sensor_msgs/msg/JointState"))
    return path


def write_ros1(path: Path, pos: np.ndarray, st: np.ndarray, *,
               vel: np.ndarray | None = None, log_ns: np.ndarray | None = None) -> Path:
    """A ROS 1 bag with rosbags' writer."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    T = store.types
    with Writer(path) as w:
        c = w.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=store)
        for i in range(len(pos)):
            m = T["sensor_msgs/msg/JointState"](
                header=T["std_msgs/msg/Header"](
                    seq=i, stamp=T["builtin_interfaces/msg/Time"](
                        sec=int(st[i] // 10**9), nanosec=int(st[i] % 10**9)), frame_id=""),
                name=list(NAMES), position=pos[i],
                velocity=np.zeros(0) if vel is None else vel[i], effort=np.zeros(0))
            t = int(st[i]) + 17 if log_ns is None else int(log_ns[i])
            w.write(c, t, store.serialize_ros1(m, "sensor_msgs/msg/JointState"))
    return path


def write_mcap(path: Path, pos: np.ndarray, st: np.ndarray, *, vel: np.ndarray | None = None,
               topic: str = "/joint_states", names=NAMES, log_ns: np.ndarray | None = None
               ) -> Path:
    """A plain MCAP file with mcap-ros2-support's writer (log time default stamp + 17 ns)."""
    from mcap_ros2.writer import Writer

    store = _ros2_store()
    text = store.generate_msgdef("sensor_msgs/msg/JointState", ros_version=2)[0]
    with open(path, "wb") as fh:
        w = Writer(fh)
        schema = w.register_msgdef("sensor_msgs/msg/JointState", text)
        for i in range(len(pos)):
            msg = {"header": {"stamp": {"sec": int(st[i] // 10**9),
                                        "nanosec": int(st[i] % 10**9)}, "frame_id": ""},
                   "name": list(names), "position": pos[i].tolist(),
                   "velocity": [] if vel is None else vel[i].tolist(), "effort": []}
            t = int(st[i]) + 17 if log_ns is None else int(log_ns[i])
            w.write_message(topic, schema, msg, log_time=t, publish_time=t, sequence=i)
        w.finish()
    return path
