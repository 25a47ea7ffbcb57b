"""Recorded masters and sessions outside the core loop: each test a regression of a finding.

``read_master`` and ``athenakin teleop --master`` blocked for ever on a FIFO; a pose
stamped days later made an endless grid; a wrong message type on the pose topic gave an
AttributeError (exit 70), on the clutch topic "never pressed"; a clutch change applied up
to one pose interval before its stamp; ``run_session`` raised on a numpy-array clutch;
the session MCAP started at 1970, wrote a constant NaN clearance, the feed-forward as
``measured_js.effort`` and identity orientations; the CLI checked no body clearance.
"""

import math
import os
import threading

import numpy as np
import pytest

import athenakin as ak
from athenakin.errors import InvalidInputError

pytest.importorskip("mcap_ros2")
pytest.importorskip("rosbags")

from athenakin.collision import Bodies  # noqa: E402
from athenakin.teleop import (  # noqa: E402
    CRTK_TOPICS,
    MAX_GAP_S,
    Teleop,
    TeleopOptions,
    read_master,
    run_session,
    write_session_mcap,
)

D = ak.Design.default()
T = ak.default_rcm_frame(D)
Q0 = np.array([-0.1, 0.1, 0.45])
T0_NS = 1_700_000_000 * 10**9
#: Deadline for a call that must not block, s (generous: two shared cores).
NO_BLOCK_S = 60.0


def _msgdef(name):
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_HUMBLE).generate_msgdef(name, ros_version=2)[0]


def _head(ns):
    return {"stamp": {"sec": ns // 10**9, "nanosec": ns % 10**9}, "frame_id": "master"}


def _pose(ns, x, y=0.0, z=0.0):
    return {"header": _head(ns), "pose": {"position": {"x": x, "y": y, "z": z},
                                          "orientation": {"x": 0.0, "y": 0.0, "z": 0.0,
                                                          "w": 1.0}}}


def _joy(ns, buttons):
    return {"header": _head(ns), "axes": [], "buttons": list(buttons)}


def _write(path, messages):
    """``messages``: (topic, type, log ns, message dict), written in that order."""
    from mcap_ros2.writer import Writer

    with open(path, "wb") as fh:
        w = Writer(fh)
        schemas = {}
        for topic, typ, ns, msg in messages:
            if typ not in schemas:
                schemas[typ] = w.register_msgdef(typ, _msgdef(typ))
            w.write_message(topic, schemas[typ], msg, log_time=ns, publish_time=ns)
        w.finish()
    return path


def _poses(n, *, rate_hz=100.0, t0=T0_NS, amp=0.02):
    """``n`` poses and a released clutch pedal at the start."""
    return [("/master/joy", "sensor_msgs/msg/Joy", t0, _joy(t0, [0]))] + [
            ("/master/pose", "geometry_msgs/msg/PoseStamped", t0 + int(k * 1e9 / rate_hz),
             _pose(t0 + int(k * 1e9 / rate_hz), amp * math.sin(2 * math.pi * k / rate_hz)))
            for k in range(n)]


def _no_block(fn):
    """Run ``fn`` in a thread; its exception, or a failure if it does not return in time."""
    box = {}

    def run():
        try:
            box["value"] = fn()
        except BaseException as exc:   # noqa: BLE001 - handed back to the test
            box["error"] = exc

    th = threading.Thread(target=run, daemon=True)
    th.start()
    th.join(NO_BLOCK_S)
    assert not th.is_alive(), "the call blocked"
    return box


# --- read_master --------------------------------------------------------------------------
@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_a_fifo_is_refused_without_blocking(tmp_path, capsys):
    from athenakin.cli import main

    fifo = tmp_path / "master.mcap"
    os.mkfifo(fifo)
    box = _no_block(lambda: read_master(fifo))
    assert isinstance(box.get("error"), InvalidInputError)
    assert "FIFO" in str(box["error"]) and "path" in str(box["error"])
    box = _no_block(lambda: main(["teleop", "--master", str(fifo), "--no-arm"]))
    assert box.get("value") == 1
    assert "FIFO" in capsys.readouterr().err


def test_a_gap_longer_than_max_gap_is_an_error(tmp_path):
    msgs = _poses(20)
    late = T0_NS + 3 * 86_400 * 10**9                  # a pose stamped three days later
    msgs.append(("/master/pose", "geometry_msgs/msg/PoseStamped", late, _pose(late, 0.0)))
    rec = _write(tmp_path / "gap.mcap", msgs)
    cycles = read_master(rec, clutch_topic=None)
    with pytest.raises(InvalidInputError, match="max_gap"):
        for _ in cycles:
            pass
    # a gap within the bound is on the grid: cycles without a sample
    msgs = _poses(20)
    t = T0_NS + int(2.0e9)
    msgs.append(("/master/pose", "geometry_msgs/msg/PoseStamped", t, _pose(t, 0.0)))
    rec = _write(tmp_path / "ok.mcap", msgs)
    samples = list(read_master(rec, clutch_topic=None, max_gap=5.0))
    assert len(samples) == 2001 and samples[-1][1] is not None
    assert sum(s[1] is None for s in samples[200:2000]) == 1800
    assert MAX_GAP_S == 10.0
    with pytest.raises(InvalidInputError, match="max_gap"):
        read_master(rec, clutch_topic=None, max_gap=0.0)


@pytest.mark.parametrize("topic, typ, words", [
    ("/master/pose", "geometry_msgs/msg/PointStamped", "pose topic"),
    ("/master/joy", "std_msgs/msg/String", "clutch topic"),
])
def test_both_topic_types_are_checked_by_name(tmp_path, capsys, topic, typ, words):
    from athenakin.cli import main

    msgs = [m for m in _poses(10) if m[0] != "/master/joy"]
    if typ == "geometry_msgs/msg/PointStamped":
        msgs = [("/master/joy", "sensor_msgs/msg/Joy", T0_NS, _joy(T0_NS, [0])),
                (topic, typ, T0_NS, {"header": _head(T0_NS),
                                     "point": {"x": 0.0, "y": 0.0, "z": 0.0}})]
    else:
        msgs.append((topic, typ, T0_NS, {"data": "pressed"}))
    rec = _write(tmp_path / "typed.mcap", msgs)
    with pytest.raises(InvalidInputError, match=words):
        read_master(rec)
    assert main(["teleop", "--master", str(rec), "--no-arm"]) == 1   # named, not exit 70
    err = capsys.readouterr().err
    assert typ in err and err.count("\n") == 1


def test_the_clutch_applies_from_its_own_stamp(tmp_path):
    msgs = _poses(100)                                   # every 10 ms
    press = T0_NS + 505_000_000                          # between the poses of 500 and 510 ms
    msgs.insert(52, ("/master/joy", "sensor_msgs/msg/Joy", press, _joy(press, [1])))
    release = T0_NS + 707_000_000
    msgs.insert(73, ("/master/joy", "sensor_msgs/msg/Joy", release, _joy(release, [0])))
    rec = _write(tmp_path / "clutch.mcap", msgs)
    samples = list(read_master(rec))
    follow = np.array([s[2] for s in samples])
    t = np.array([s[0] for s in samples])
    np.testing.assert_array_equal(follow, ~((t >= 0.505 - 1e-9) & (t < 0.707 - 1e-9)))


def test_a_clutch_button_the_recording_lacks_is_refused(tmp_path, capsys):
    from athenakin.cli import main

    msgs = [m for m in _poses(10) if m[0] != "/master/joy"]
    msgs.insert(3, ("/master/joy", "sensor_msgs/msg/Joy", T0_NS + 25_000_000,
                    _joy(T0_NS + 25_000_000, [0, 1])))
    rec = _write(tmp_path / "joy.mcap", msgs)
    with pytest.raises(InvalidInputError, match="no button 4"):
        list(read_master(rec, clutch_button=4))
    assert len(list(read_master(rec, clutch_button=1))) > 0
    assert main(["teleop", "--master", str(rec), "--clutch-button", "4", "--no-arm"]) == 1
    assert "no button 4" in capsys.readouterr().err


# --- run_session ---------------------------------------------------------------------------
def test_run_session_checks_the_bodies_by_default():
    items = [(k * 1e-3, (0.0, 0.0, 0.0), True) for k in range(3)]
    with pytest.raises(InvalidInputError, match="check_bodies=False"):
        run_session(Teleop(T, D, q0=Q0), None, items)
    log = run_session(Teleop(T, D, q0=Q0), None, items, check_bodies=False)
    assert np.isnan(log.clearance).all()
    log = run_session(Teleop(T, D, q0=Q0, bodies=Bodies.default(D)), None, items)
    assert np.all(np.isfinite(log.clearance)) and np.all(log.clearance > 0)
    with pytest.raises(TypeError, match="check_bodies"):
        run_session(Teleop(T, D, q0=Q0), None, items, check_bodies="no")


def test_run_session_refuses_an_arm_that_is_not_enabled():
    pytest.importorskip("mujoco")
    from athenakin.teleop import SimulatedArm

    arm = SimulatedArm(T, D, q0=Q0)
    with pytest.raises(InvalidInputError, match=r"enable\(\)"):
        run_session(Teleop(T, D, q0=Q0), arm, [], check_bodies=False)


def test_run_session_never_raises_where_step_does_not():
    pytest.importorskip("mujoco")
    from athenakin.teleop import SimulatedArm

    arm = SimulatedArm(T, D, q0=Q0)
    arm.enable()
    tele = Teleop(T, D, q0=Q0, options=TeleopOptions(feedforward=False))
    hostile = [(0.000, (0.0, 0.0, 0.0), True),
               (0.001, (0.001, 0.0, 0.0), np.array([True, False])),   # a numpy-array clutch
               (0.002, b"abc", True), (0.003, "123", True),
               (0.004, (math.nan, 0.0, 0.0), True), (0.005, (1e300, 0.0, 0.0), True),
               (0.006, [0.0, 0.0], True), (0.007, None, "yes"), (0.008, object(), 1),
               (0.009, (0.0, 0.0, 0.0), np.bool_(True))]
    log = run_session(tele, arm, hostile, check_bodies=False)
    assert len(log) == len(hostile)
    assert np.isnan(log.master[2:4]).all()                 # bytes and str are no positions
    assert np.isnan(log.master[6:9]).all()
    np.testing.assert_array_equal(log.clutch, [True, False, True, True, True, True, True,
                                               False, False, True])
    assert np.all(np.isfinite(log.q)) and arm.operating_state == "ENABLED"


# --- the session MCAP ----------------------------------------------------------------------
def _read_mcap(path):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    out = {}
    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        for _s, channel, message, msg in reader.iter_decoded_messages():
            out.setdefault(channel.topic, []).append((message.log_time, msg))
    return out


def test_the_session_mcap_of_the_cli(tmp_path, capsys):
    """The recording's time base, the checked clearance, the applied effort, orientations."""
    pytest.importorskip("mujoco")
    from athenakin.cli import main

    rec = _write(tmp_path / "rec.mcap", _poses(40))
    out = tmp_path / "session.mcap"
    assert main(["teleop", "--master", str(rec), "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "least clearance" in text
    topics = _read_mcap(out)
    status = topics[CRTK_TOPICS["status"]]
    assert status[0][0] == T0_NS                             # the first pose's stamp
    assert status[0][1].header.stamp.sec == T0_NS // 10**9
    cl = np.array([m.clearance_m for _, m in status])
    assert np.all(np.isfinite(cl)) and np.all(cl > 0)
    eff = np.array([m.effort for _, m in topics[CRTK_TOPICS["measured_js"]]])
    sp_eff = np.array([m.effort for _, m in topics[CRTK_TOPICS["setpoint_js"]]])
    np.testing.assert_array_equal(eff, sp_eff)               # CRTK: the applied effort
    for key in ("measured_cp", "servo_cp"):
        o = topics[CRTK_TOPICS[key]][-1][1].pose.orientation
        quat = np.array([o.x, o.y, o.z, o.w])
        assert abs(np.linalg.norm(quat) - 1.0) < 1e-12
        assert abs(o.w) < 1.0 - 1e-6                          # not the identity
    # the orientation is the FK tool-tip frame of the command
    sp = topics[CRTK_TOPICS["setpoint_js"]][-1][1]
    sol = ak.forward_kinematics(np.array(sp.position), T, D)
    o = topics[CRTK_TOPICS["servo_cp"]][-1][1].pose.orientation
    R = ak.study.rotation_from_quaternion([o.w, o.x, o.y, o.z])
    np.testing.assert_allclose(R, sol.T_b_tip[0][:3, :3], atol=1e-9)


def test_write_session_mcap_takes_the_logs_time_base(tmp_path):
    rec = _write(tmp_path / "rec.mcap", _poses(5))
    master = read_master(rec, clutch_topic=None)
    assert master.start_ns == T0_NS
    log = run_session(Teleop(T, D, q0=Q0), None, master, check_bodies=False)
    assert log.start_ns == T0_NS
    write_session_mcap(log, tmp_path / "s.mcap")
    first = _read_mcap(tmp_path / "s.mcap")[CRTK_TOPICS["status"]][0][0]
    assert first == T0_NS
    write_session_mcap(log, tmp_path / "z.mcap", start_ns=0)      # explicit: kept
    assert _read_mcap(tmp_path / "z.mcap")[CRTK_TOPICS["status"]][0][0] == 0


# --- the CLI's options ---------------------------------------------------------------------
def test_cli_bodies_environment_registration(tmp_path, capsys):
    from athenakin.cli import main

    rec = _write(tmp_path / "rec.mcap", _poses(30))
    assert main(["teleop", "--master", str(rec), "--no-arm", "--no-bodies"]) == 0
    assert "not checked" in capsys.readouterr().out
    env = tmp_path / "env.toml"
    ak.collision.Environment().sphere(T[:3, 3] + T[:3, :3] @ [0.3, 0.0, 0.1], 0.02,
                                      name="organ").write_toml(env)
    assert main(["teleop", "--master", str(rec), "--no-arm", "--environment", str(env)]) == 0
    assert "least clearance" in capsys.readouterr().out
    R = [0, -1, 0, 1, 0, 0, 0, 0, 1]
    assert main(["teleop", "--master", str(rec), "--no-arm", "--no-bodies",
                 "--registration", *map(str, R)]) == 0
    capsys.readouterr()
    assert main(["teleop", "--master", str(rec), "--no-arm", "--no-bodies",
                 "--registration", *map(str, [2, 0, 0, 0, 1, 0, 0, 0, 1])]) == 1
    assert "registration" in capsys.readouterr().err
    assert main(["teleop", "--master", str(rec), "--no-arm", "--no-bodies",
                 "--bodies", str(env)]) == 1
    assert "--no-bodies" in capsys.readouterr().err


def test_cli_hints_at_millimetres(tmp_path, capsys):
    from athenakin.cli import main

    msgs = _poses(30, amp=20.0)                          # a handle recorded in mm
    rec = _write(tmp_path / "mm.mcap", msgs)
    assert main(["teleop", "--master", str(rec), "--no-arm", "--no-bodies"]) == 0
    err = capsys.readouterr().err
    assert "millimetres" in err
