"""athenakin.ros.FoxgloveStream: a real WebSocket client on the loopback decodes the live robot."""

import json
import struct
import time

import numpy as np
import pytest

pytest.importorskip("foxglove")
pytest.importorskip("rosbags")
ws_client = pytest.importorskip("websockets.sync.client")

import athenakin as ak  # noqa: E402
from athenakin.ros import FoxgloveStream  # noqa: E402

D = ak.Design.default()
T = ak.default_rcm_frame(D)
DEADLINE_S = 20.0
SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]
TOPICS = {"/athena/tool_tip": "geometry_msgs/msg/PoseStamped",
          "/tf": "tf2_msgs/msg/TFMessage",
          "/athena/joint_states": "sensor_msgs/msg/JointState",
          "/athena/status": "athenakin_msgs/msg/TrackStatus",
          "/robot_description": "std_msgs/msg/String"}


def _advertised(ws, deadline):
    chans = {}
    while time.monotonic() < deadline and not set(TOPICS) <= set(chans):
        msg = ws.recv(timeout=max(0.1, deadline - time.monotonic()))
        if isinstance(msg, str):
            obj = json.loads(msg)
            if obj.get("op") == "advertise":
                for c in obj["channels"]:
                    chans[c["topic"]] = c
    return chans


def test_live_stream_decodes_with_an_independent_client():
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    q = np.array([-0.11, 0.09, 0.47])
    stamp = 1_700_000_000_987_654_321
    with FoxgloveStream(T, D, port=0) as live:
        assert live.host == "127.0.0.1" and live.port > 0
        deadline = time.monotonic() + DEADLINE_S
        # foxglove-sdk 0.30 speaks the protocol under the name "foxglove.sdk.v1" (the
        # Foxglove WebSocket protocol v1, formerly "foxglove.websocket.v1"); offer both
        with ws_client.connect(live.url, subprotocols=SUBPROTOCOLS,
                               open_timeout=DEADLINE_S) as ws:
            assert ws.subprotocol in SUBPROTOCOLS
            chans = _advertised(ws, deadline)
            assert {t: c["schemaName"] for t, c in chans.items() if t in TOPICS} == TOPICS
            assert all(chans[t]["encoding"] == "cdr" and chans[t]["schemaEncoding"] ==
                       "ros2msg" for t in TOPICS)
            status_def = chans["/athena/status"]["schema"].split("=" * 80)[0]
            store.register(get_types_from_msg(status_def, "athenakin_msgs/msg/TrackStatus"))
            subs = {k + 1: t for k, t in enumerate(TOPICS)}
            ws.send(json.dumps({"op": "subscribe", "subscriptions": [
                {"id": sid, "channelId": chans[t]["id"]} for sid, t in subs.items()]}))
            got = {}
            while time.monotonic() < deadline and set(got) != set(TOPICS):
                live.publish(q, slot=0, stamp_ns=stamp)
                try:
                    msg = ws.recv(timeout=0.2)
                except TimeoutError:
                    continue
                while True:
                    if isinstance(msg, bytes) and msg[0] == 0x01:       # MessageData
                        sid, log_time = struct.unpack_from("<IQ", msg, 1)
                        topic = subs[sid]
                        got.setdefault(topic, (log_time, store.deserialize_cdr(
                            msg[13:], TOPICS[topic])))
                    try:
                        msg = ws.recv(timeout=0.05)
                    except TimeoutError:
                        break
    assert set(got) == set(TOPICS), f"received only {sorted(got)}"
    sol = ak.forward_kinematics(q, T, D)
    log_time, tip = got["/athena/tool_tip"]
    assert log_time == stamp
    assert tip.header.stamp.sec * 10**9 + tip.header.stamp.nanosec == stamp
    p = tip.pose.position
    np.testing.assert_allclose([p.x, p.y, p.z], sol.tip[0], rtol=0, atol=1e-12)
    tf = got["/tf"][1]
    assert {t.child_frame_id for t in tf.transforms} >= {"tool_tip", "rcm", "platform"}
    js = got["/athena/joint_states"][1]
    ref = ak.sim.mechanism_joint_values(q, T, D, slot=0).urdf
    np.testing.assert_allclose(js.position, [ref[n] for n in js.name], rtol=0, atol=1e-12)
    st = got["/athena/status"][1]
    assert st.valid and st.mode == 1 and st.slot == 0
    assert got["/robot_description"][1].data == ak.sim.urdf_from_design(D, T)


def test_subprotocol_names_the_server_accepts():
    """foxglove-sdk 0.30 accepts foxglove.sdk.v1 and refuses the old foxglove.websocket.v1.

    docs/ros.md says so: Foxglove Studio 1.x (it offers foxglove.websocket.v1 only; checked
    with Studio 1.48 in tools/foxglove-shot) cannot connect to FoxgloveStream.
    """
    from websockets.exceptions import InvalidStatus

    with FoxgloveStream(T, D, port=0) as live:
        with ws_client.connect(live.url, subprotocols=["foxglove.sdk.v1"],
                               open_timeout=DEADLINE_S) as ws:
            assert ws.subprotocol == "foxglove.sdk.v1"
            hello = json.loads(ws.recv(timeout=DEADLINE_S))
            assert hello["op"] == "serverInfo" and hello["name"] == "athenakin"
        with pytest.raises(InvalidStatus) as refused:
            ws_client.connect(live.url, subprotocols=["foxglove.websocket.v1"],
                              open_timeout=DEADLINE_S)
        assert refused.value.response.status_code == 400


def test_out_of_reach_publishes_an_invalid_status_only():
    with FoxgloveStream(T, D, port=0) as live:
        assert live.publish([0.3, -0.3, 0.45]) is False   # A/B order broken
        assert live.publish([-0.1, 0.1, 0.45]) is True


@pytest.mark.parametrize("kw, match", [({"port": 70000}, "port: expected"),
                                       ({"port": -1}, "port: expected")])
def test_bad_port(kw, match):
    with pytest.raises(ak.InvalidInputError, match=match):
        FoxgloveStream(T, D, **kw)


def test_follow_polls_a_state_and_stops():
    state = {"q": np.array([-0.1, 0.1, 0.45])}
    with FoxgloveStream(T, D, port=0) as live:
        live.follow(lambda: (state["q"], 0), rate=50.0)
        with pytest.raises(RuntimeError, match="already following"):
            live.follow(lambda: (state["q"], 0))
        time.sleep(0.1)
    assert live._thread is not None and not live._thread.is_alive()
