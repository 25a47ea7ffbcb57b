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
#: The Foxglove WebSocket protocol v1 under its new name (foxglove-sdk, Foxglove 2.x) and its
#: old one (Foxglove Studio 1.x, Lichtblick): a client offering either alone must connect.
OFFERS = {"sdk": ["foxglove.sdk.v1"], "legacy": ["foxglove.websocket.v1"]}
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


@pytest.mark.parametrize("offer", OFFERS.values(), ids=OFFERS.keys())
def test_live_stream_decodes_with_an_independent_client(offer):
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    q = np.array([-0.11, 0.09, 0.47])
    stamp = 1_700_000_000_987_654_321
    with FoxgloveStream(T, D, port=0) as live:
        assert live.host == "127.0.0.1" and live.port > 0
        deadline = time.monotonic() + DEADLINE_S
        with ws_client.connect(live.url, subprotocols=offer,
                               open_timeout=DEADLINE_S) as ws:
            assert ws.subprotocol == offer[0]
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
    assert got["/robot_description"][1].data == ak.sim.urdf_from_design(T, D)


@pytest.mark.parametrize("offer, answer", [
    (["foxglove.websocket.v1"], "foxglove.websocket.v1"),      # Foxglove Studio 1.x, Lichtblick
    (["foxglove.sdk.v1"], "foxglove.sdk.v1"),
    (["foxglove.sdk.v1.1"], "foxglove.sdk.v1.1"),
    (["foxglove.websocket.v1", "foxglove.sdk.v1"], "foxglove.sdk.v1"),   # the new name first
    (["chat", "foxglove.websocket.v1"], "foxglove.websocket.v1")])
def test_subprotocol_names_the_stream_accepts(offer, answer):
    """Old and new names of the protocol connect through the relay to the SDK server.

    foxglove-sdk 0.30 itself accepts only foxglove.sdk.v1(.1); the relay in front of it
    (athenakin.ros._relay) also accepts foxglove.websocket.v1, which Foxglove Studio 1.48
    offers alone (checked with tools/foxglove-shot --source live).
    """
    with FoxgloveStream(T, D, port=0) as live:
        with ws_client.connect(live.url, subprotocols=offer, open_timeout=DEADLINE_S) as ws:
            assert ws.subprotocol == answer
            hello = json.loads(ws.recv(timeout=DEADLINE_S))
            assert hello["op"] == "serverInfo" and hello["name"] == "athenakin"


@pytest.mark.parametrize("offer", [["foxglove.websocket.v2"], ["chat"], None],
                         ids=["unknown-version", "other", "none"])
def test_other_subprotocols_are_refused(offer):
    from websockets.exceptions import InvalidStatus

    with FoxgloveStream(T, D, port=0) as live:
        with pytest.raises(InvalidStatus) as refused:
            ws_client.connect(live.url, subprotocols=offer, open_timeout=DEADLINE_S)
        assert refused.value.response.status_code == 400
        assert b"foxglove.websocket.v1" in refused.value.response.body
        # the stream still serves after a refusal
        with ws_client.connect(live.url, subprotocols=OFFERS["legacy"],
                               open_timeout=DEADLINE_S) as ws:
            assert json.loads(ws.recv(timeout=DEADLINE_S))["op"] == "serverInfo"


def test_stop_closes_clients_and_leaves_no_thread():
    import threading

    from websockets.exceptions import ConnectionClosed

    before = set(threading.enumerate())
    live = FoxgloveStream(T, D, port=0)
    clients = [ws_client.connect(live.url, subprotocols=o, open_timeout=DEADLINE_S)
               for o in OFFERS.values()]
    for ws in clients:
        assert json.loads(ws.recv(timeout=DEADLINE_S))["op"] == "serverInfo"
    live.stop()
    live.stop()                                       # idempotent
    for ws in clients:
        with pytest.raises(ConnectionClosed) as closed:
            while True:                               # drain what was sent before the stop
                ws.recv(timeout=DEADLINE_S)
        assert closed.value.rcvd is not None and closed.value.rcvd.code == 1001
        ws.close()
    # every thread the stream or the clients started ends (the clients' keepalive threads
    # end a moment after close() returns: waited for, never a fixed sleep)
    deadline = time.monotonic() + DEADLINE_S
    while (extra := set(threading.enumerate()) - before) and time.monotonic() < deadline:
        next(iter(extra)).join(timeout=0.1)
    assert not extra
    with pytest.raises(OSError):                     # the public port is closed
        ws_client.connect(live.url, subprotocols=OFFERS["legacy"], open_timeout=2.0)


def test_relay_closes_a_client_when_the_sdk_server_is_gone():
    from websockets.exceptions import ConnectionClosed

    with FoxgloveStream(T, D, port=0) as live:
        live._server.stop()                           # the SDK server behind the relay
        with ws_client.connect(live.url, subprotocols=OFFERS["legacy"],
                               open_timeout=DEADLINE_S) as ws:
            with pytest.raises(ConnectionClosed) as closed:
                ws.recv(timeout=DEADLINE_S)
        assert closed.value.rcvd is not None and closed.value.rcvd.code == 1011


def test_port_in_use_raises_oserror_naming_the_address():
    with FoxgloveStream(T, D, port=0) as live:
        with pytest.raises(OSError, match=f"cannot serve Foxglove on 127.0.0.1:{live.port}"):
            FoxgloveStream(T, D, port=live.port)


def test_out_of_reach_publishes_an_invalid_status_only():
    with FoxgloveStream(T, D, port=0) as live:
        assert live.publish([0.3, -0.3, 0.45]) is False   # A/B order broken
        assert live.publish([-0.1, 0.1, 0.45]) is True


@pytest.mark.parametrize("kw, match", [({"port": 70000}, "port: expected"),
                                       ({"port": -1}, "port: expected"),
                                       ({"host": "no-such-host.invalid"}, "host: expected")])
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
