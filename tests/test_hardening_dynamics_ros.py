"""Regression rows of issue 23 for athenakin.dynamics and athenakin.ros.

Each row is a call that the adversarial audit (scripts/audit_api.py, ``--only
dynamics,ros``) once found raising a raw exception (a numpy / stdlib error, or a
``TypeError`` naming no argument) or returning NaN in an item flagged valid. Each now
raises a named error whose message starts with the argument's name (``match``).
"""

from __future__ import annotations

import numpy as np
import pytest

import athenakin as ak
import athenakin.dynamics as dyn
from athenakin import InvalidInputError

D = ak.Design.default()
T = ak.default_rcm_frame(D)
Q = np.array([-0.10, 0.10, 0.45])
FMAX = np.array([60.0, 60.0, 60.0])


def _cap(**kw):
    return dyn.force_capability(Q, T, D, **{"f_max": FMAX, **kw})


def _tip(**kw):
    return dyn.max_tip_force(Q, kw.pop("direction", [0.0, 0.0, -1.0]), T, D,
                             **{"f_max": FMAX, **kw})


def _metrics(**kw):
    return dyn.force_metrics(kw.pop("q", Q), T, kw.pop("design", D),
                             **{"slot": 0, **kw})


# (id, call, exception class, regex the message must match: it names the argument)
DYNAMICS = [
    ("segment_name_list", lambda: dyn.body_segment_in_frame([], D), TypeError, r"^name: "),
    ("segment_name_dict", lambda: dyn.body_segment_in_frame({"a": 1}, D), TypeError,
     r"^name: "),
    ("statics_rcm_load_none", lambda: dyn.statics(Q, T, D, rcm_load=None), TypeError,
     r"^rcm_load: "),
    ("statics_rcm_load_zero", lambda: dyn.statics(Q, T, D, rcm_load=0), TypeError,
     r"^rcm_load: "),
    ("cap_f_max_1e308", lambda: _cap(f_max=1e308), InvalidInputError, r"^f_max: .*1e\+09"),
    ("cap_f_max_elem_1e308", lambda: _cap(f_max=[1e308, 60.0, 60.0]), InvalidInputError,
     r"^f_max: "),
    ("cap_f_max_10e400", lambda: _cap(f_max=10**400), InvalidInputError, r"^f_max: "),
    ("cap_f_min_10e400", lambda: _cap(f_min=10**400), InvalidInputError, r"^f_min: "),
    ("cap_f_max_str", lambda: _cap(f_max="abc"), TypeError, r"^f_max: "),
    ("cap_f_max_ragged", lambda: _cap(f_max=[[1.0, 2.0, 3.0], [4.0]]), TypeError, r"^f_max: "),
    ("cap_f_min_object", lambda: _cap(f_min=object()), TypeError, r"^f_min: "),
    ("cap_f_max_complex", lambda: _cap(f_max=1 + 1j), TypeError, r"^f_max: "),
    ("cap_f_max_dict", lambda: _cap(f_max={"a": 1}), TypeError, r"^f_max: "),
    ("cap_f_max_batch", lambda: _cap(f_max=np.stack([FMAX, FMAX])), InvalidInputError,
     r"^f_max: .*shape \(3,\)"),
    ("cap_f_max_empty_batch", lambda: _cap(f_max=np.zeros((0, 3))), InvalidInputError,
     r"^f_max: "),
    ("tip_f_max_10e400", lambda: _tip(f_max=10**400), InvalidInputError, r"^f_max: "),
    ("tip_f_min_str", lambda: _tip(f_min="abc"), TypeError, r"^f_min: "),
    ("tip_direction_vs_q", lambda: dyn.max_tip_force(np.stack([Q, Q]), np.eye(3), T, D,
                                                     f_max=FMAX),
     InvalidInputError, r"direction \(3,\).*q \(2,\)"),
    ("metrics_q_batch_vs_slot", lambda: _metrics(q=np.stack([Q, Q]), slot=[0]),
     InvalidInputError, r"^slot: .*shape \(2,\)"),
    ("metrics_slot_none", lambda: _metrics(slot=None), TypeError, r"^slot: "),
    ("metrics_slot_nan", lambda: _metrics(slot=np.nan), TypeError, r"^slot: "),
    ("metrics_slot_big", lambda: _metrics(slot=10**400), TypeError, r"^slot: "),
    ("metrics_slot_str", lambda: _metrics(slot="abc"), TypeError, r"^slot: "),
    ("metrics_slot_out_of_range", lambda: _metrics(slot=16), InvalidInputError, r"^slot: "),
    ("metrics_design_none", lambda: _metrics(design=None), TypeError, r"^design: "),
    ("metrics_T_batch", lambda: dyn.force_metrics(Q, np.stack([T, T]), D, slot=0),
     InvalidInputError, r"^T_b_e: "),
    ("metrics_f_max_10e400", lambda: _metrics(f_max=10**400), InvalidInputError,
     r"^f_max: "),
    ("metrics_f_max_str", lambda: _metrics(f_max="abc"), TypeError, r"^f_max: "),
    ("metrics_masses_str", lambda: _metrics(masses="x"), TypeError, r"^masses: "),
    ("simulate_duration_1e308", lambda: dyn.simulate(Q, np.zeros(3), np.zeros(3), T, D,
                                                     duration=1e308),
     InvalidInputError, r"^duration / dt: "),
    ("simulate_dt_1e-308", lambda: dyn.simulate(Q, np.zeros(3), np.zeros(3), T, D,
                                                duration=1.0, dt=1e-308),
     InvalidInputError, r"^duration / dt: "),
    ("mass_from_mapping_none", lambda: dyn.MassModel.from_mapping(None), TypeError,
     r"^data: "),
    ("mass_from_mapping_list", lambda: dyn.MassModel.from_mapping([]), TypeError, r"^data: "),
]


@pytest.mark.parametrize("call, exc, match", [r[1:] for r in DYNAMICS],
                         ids=[r[0] for r in DYNAMICS])
def test_dynamics_bad_argument_is_named(call, exc, match):
    with pytest.raises(exc, match=match):
        call()


def test_force_limits_at_the_maximum_give_finite_vertices():
    cap = _cap(f_max=dyn._capability.MAX_FORCE_LIMIT)
    assert bool(cap.valid)
    assert np.all(np.isfinite(cap.vertices))


def test_rcm_load_false_still_documented_nan():
    st = dyn.statics(Q, T, D, rcm_load=False)
    assert np.all(np.isnan(st.rcm_force))
    assert np.all(np.isfinite(st.forces))


# ----------------------------------------------------------------------------------- ros
ros = pytest.importorskip("athenakin.ros")


def _bag(tmp_path):
    """A 3-reading rosbag2 (sqlite3) of /joint_states written with rosbags."""
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    Ty = store.types
    path = tmp_path / "bag"
    with Writer(path, version=9) as w:
        c = w.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=store)
        for i in range(3):
            st = 1_700_000_000_000_000_000 + i * 1_000_000
            m = Ty["sensor_msgs/msg/JointState"](
                header=Ty["std_msgs/msg/Header"](
                    stamp=Ty["builtin_interfaces/msg/Time"](sec=st // 10**9,
                                                             nanosec=st % 10**9),
                    frame_id=""),
                name=["q1", "q2", "q3"], position=Q + 1e-4 * i, velocity=np.zeros(0),
                effort=np.zeros(0))
            w.write(c, st, store.serialize_cdr(m, "sensor_msgs/msg/JointState"))
    return path


def _traj():
    tips = ak.forward_kinematics(Q, T, D).tip
    k = int(np.argmax(ak.forward_kinematics(Q, T, D).valid))
    tip_e = (np.linalg.inv(T) @ np.append(tips[k], 1.0))[:3]
    return ak.motion.plan(np.array([tip_e, tip_e + [0.004, 0, 0]]), T, D,
                          options=ak.motion.PlanOptions(rate=200.0))


STAMPS = np.array([0, 1_000_000, 2_000_000], dtype=np.int64)
QS = np.array([Q, Q + 1e-4, Q + 2e-4])

# (id, call(tmp_path), exception class, regex)
ROS = [
    ("read_scale_10e400", lambda t: ros.read_joint_states(_bag(t), scale=10**400),
     InvalidInputError, r"^scale: "),
    ("iter_scale_10e400", lambda t: ros.iter_joint_states(_bag(t), scale=10**400),
     InvalidInputError, r"^scale: "),
    ("iter_checks_at_the_call", lambda t: ros.iter_joint_states(t / "missing"),
     ros.RecordingError, r"missing"),
    ("format_path_none", lambda t: ros.recording_format(None), TypeError, r"^path: "),
    ("format_path_int", lambda t: ros.recording_format(0), TypeError, r"^path: "),
    ("mcap_design_list", lambda t: ros.McapOutput(t / "o.mcap", T, []), TypeError,
     r"^design: "),
    ("mcap_T_none", lambda t: ros.McapOutput(t / "o.mcap", None, D), TypeError, r"^T_b_e: "),
    ("mcap_T_3x3", lambda t: ros.McapOutput(t / "o.mcap", np.eye(3), D), InvalidInputError,
     r"^T_b_e"),
    ("mcap_T_10e400", lambda t: ros.McapOutput(t / "o.mcap", 10**400, D),
     (TypeError, InvalidInputError), r"^T_b_e"),
    ("mcap_target_nan", lambda t: ros.McapOutput(t / "o.mcap", T, D, target=np.nan),
     TypeError, r"^target: "),
    ("track_recording_none", lambda t: ros.track_recording(None, t / "o.mcap", T, D),
     TypeError, r"^recording: "),
    ("track_recording_out_int", lambda t: ros.track_recording(_bag(t), 0, T, D),
     TypeError, r"^out: "),
    ("track_recording_target", lambda t: ros.track_recording(_bag(t), t / "o.mcap", T, D,
                                                             target=1.5),
     TypeError, r"^target: "),
    ("track_recording_progress", lambda t: ros.track_recording(_bag(t), t / "o.mcap", T, D,
                                                               progress=5),
     TypeError, r"^progress: "),
    ("track_to_mcap_ragged", lambda t: ros.track_to_mcap([[1, 2], [3]], QS, t / "o.mcap", T,
                                                         D),
     TypeError, r"^stamps_ns: "),
    ("track_to_mcap_out_none", lambda t: ros.track_to_mcap(STAMPS, QS, None, T, D),
     TypeError, r"^out: "),
    ("track_to_mcap_target", lambda t: ros.track_to_mcap(STAMPS, QS, t / "o.mcap", T, D,
                                                         target={}),
     TypeError, r"^target: "),
    ("write_trajectory_target", lambda t: ros.write_trajectory(t / "o.mcap", _traj(),
                                                               target=[]),
     TypeError, r"^target: "),
    ("live_host_none", lambda t: ros.FoxgloveStream(T, D, host=None, port=0), TypeError,
     r"^host: "),
    ("live_host_unresolvable", lambda t: ros.FoxgloveStream(T, D, host="abc.invalid", port=0),
     InvalidInputError, r"^host: "),
    ("live_host_nul", lambda t: ros.FoxgloveStream(T, D, host="127.0.0.1\x00", port=0),
     InvalidInputError, r"^host: .*U\+0000"),
    ("live_name_int", lambda t: ros.FoxgloveStream(T, D, name=0, port=0), TypeError,
     r"^name: "),
    ("live_name_control", lambda t: ros.FoxgloveStream(T, D, name="a\x1bb", port=0),
     InvalidInputError, r"^name: "),
]


@pytest.mark.parametrize("call, exc, match", [r[1:] for r in ROS], ids=[r[0] for r in ROS])
def test_ros_bad_argument_is_named(call, exc, match, tmp_path):
    with pytest.raises(exc, match=match):
        call(tmp_path)
    assert not list(tmp_path.glob("o.mcap*")), "a refused call left a file"


@pytest.fixture(scope="module")
def live():
    s = ros.FoxgloveStream(T, D, port=0)
    yield s
    s.stop()


@pytest.mark.parametrize("kw, exc, match", [
    (dict(flags=None), TypeError, r"^flags: "),
    (dict(flags=np.nan), TypeError, r"^flags: "),
    (dict(flags=2**32), InvalidInputError, r"^flags: "),
    (dict(flags=-1), InvalidInputError, r"^flags: "),
    (dict(flags=np.zeros(2, int)), TypeError, r"^flags: "),
    (dict(stamp_ns=-1), InvalidInputError, r"^stamp_ns: "),
    (dict(stamp_ns="abc"), TypeError, r"^stamp_ns: "),
    (dict(stamp_ns=2**63), InvalidInputError, r"^stamp_ns: "),
], ids=["flags_none", "flags_nan", "flags_2_32", "flags_neg", "flags_array", "stamp_neg",
        "stamp_str", "stamp_2_63"])
def test_publish_bad_argument_is_named(live, kw, exc, match):
    with pytest.raises(exc, match=match):
        live.publish(Q, **kw)
    assert live.publish(Q, flags=2**32 - 1, stamp_ns=2**63 - 1)


def test_live_server_binds_loopback_port_zero():
    with ros.FoxgloveStream(T, D, port=0) as s:
        assert s.host == "127.0.0.1" and s.port > 0


def test_kernel_compiles_one_specialization_for_readonly_and_batched_inputs():
    # the audit's read-only / batched / float32 inputs once compiled a new kernel each
    # (about 2-13 s apiece on a cold cache)
    if not ak._backend.numba_available():
        pytest.skip("numba not available here (or ATHENAKIN_BACKEND=numpy)")
    from athenakin.dynamics._kernels import inverse_dynamics_kernel as kernel

    ro_q = Q.copy()
    ro_q.setflags(write=False)
    ro_T = T.copy()
    ro_T.setflags(write=False)
    z = np.zeros(3)
    dyn.inverse_dynamics(Q, z, z, T, D, backend="numba")
    n = len(kernel.signatures)
    for q, TT in ((ro_q, ro_T), (np.stack([Q, Q]), T), (Q.astype(np.float32), ro_T)):
        got = dyn.inverse_dynamics(q, z, z, TT, D, backend="numba")
        ref = dyn.inverse_dynamics(q, z, z, TT, D, backend="numpy")
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-9)
        assert got.shape == ref.shape
    dyn.simulate(Q, z, np.array([0.0, 0.0, 5.0]), T, D, duration=0.002)
    assert len(kernel.signatures) == n


@pytest.mark.parametrize("stamp, exc", [(None, TypeError), (np.nan, TypeError), ("1", TypeError),
                                        (-1, InvalidInputError), (2**63, InvalidInputError)],
                         ids=["none", "nan", "str", "negative", "2_63"])
def test_mcap_write_static_stamp_is_named(tmp_path, stamp, exc):
    out = ros.McapOutput(tmp_path / "s.mcap", T, D)
    try:
        with pytest.raises(exc, match=r"^stamp_ns: "):
            out.write_static(stamp)
    finally:
        out.discard()
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("kind", ["folder", "fifo"])
def test_mcap_output_onto_a_folder_or_fifo_is_named(tmp_path, kind):
    """An output path that is a folder or a FIFO: InvalidInputError naming the argument.

    (The split API audit of CI, --part 1/3, met ``track_to_mcap(out="abc")`` where an
    earlier call had made the folder ``abc``: a plain ValueError then.)
    """
    import os

    ros = pytest.importorskip("athenakin.ros")
    p = tmp_path / "abc"
    if kind == "folder":
        p.mkdir()
    else:
        if not hasattr(os, "mkfifo"):
            pytest.skip("no FIFOs here")
        os.mkfifo(p)
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    q = np.array([[-0.1, 0.1, 0.45]] * 2)
    what = "a folder" if kind == "folder" else "a FIFO"
    with pytest.raises(InvalidInputError, match=rf"^out: .*abc is {what}"):
        ros.track_to_mcap(np.arange(2), q, p, T, d)
    with pytest.raises(InvalidInputError, match=rf"^path: .*abc is {what}"):
        ros.McapOutput(p, T, d)
    assert sorted(x.name for x in tmp_path.iterdir()) == ["abc"]     # nothing left behind
