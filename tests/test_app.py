"""The app's pure layer (set-up, forward view, inverse step, playback, scene, read-outs) and
the viser binding in process (bad inputs keep it running). The browser: test_app_browser.py."""

import dataclasses
import importlib.util

import numpy as np
import pytest

import athenakin as ak
from athenakin.app import (
    WARN_DISTANCE_M,
    angles_from_tip,
    app_setup,
    forward_view,
    ghost_scene,
    inverse_step,
    load_playback,
    playback_q,
    readouts_html,
    robot_scene,
    slots_html,
    tip_from_angles,
)
from athenakin.errors import InvalidInputError, OutOfWorkspaceError, Reason
from athenakin.motion import PathFileError
from athenakin.plot import robot_geometry

D = ak.Design.default()
HAS_VISER = importlib.util.find_spec("viser") is not None


@pytest.fixture(scope="module")
def setup():
    return app_setup(D, backend="numpy")


def _random_q(rng, n, setup):
    return setup.q_lo + rng.random((n, 3)) * (setup.q_hi - setup.q_lo)


def test_setup_defaults_are_the_reference_setup(setup):
    np.testing.assert_array_equal(setup.q_home, ak.robot.REFERENCE_Q)
    np.testing.assert_allclose(setup.T_b_e, ak.default_rcm_frame(D), rtol=0, atol=1e-15)
    np.testing.assert_array_equal(setup.q_lo, D.stroke_min)
    np.testing.assert_array_equal(setup.q_hi, D.stroke_max)
    assert setup.backend == "numpy"


def test_setup_of_a_design_that_cannot_assemble_is_a_named_error():
    bad = dataclasses.replace(D, l5=5.0, name="broken")     # k2 never reaches k1
    with pytest.raises(OutOfWorkspaceError, match="broken: the parallel module assembles "
                                                  "nowhere"):
        app_setup(bad, backend="numpy")


def test_setup_starts_where_the_design_assembles():
    # the reference q is beyond these strokes: the start is the nearest assembled grid point
    d = dataclasses.replace(D, q_min=(-0.30, 0.15, 0.20), q_max=(-0.15, 0.30, 0.70))
    s = app_setup(d, backend="numpy")
    assert np.all((s.q_home >= s.q_lo) & (s.q_home <= s.q_hi))
    assert ak.parallel.parallel_forward_kinematics(s.q_home, d).valid[0]
    v = forward_view(s, s.q_home)
    assert v.geometry is not None


@pytest.mark.parametrize("T, match", [
    (np.diag([1.0, 2.0, 1.0, 1.0]), "rigid transform"),
    (np.eye(3), r"expected shape \(..., 4, 4\), got shape \(3, 3\)"),
])
def test_setup_rejects_a_non_rigid_rcm_frame(T, match):
    with pytest.raises(InvalidInputError, match=match):
        app_setup(D, T, backend="numpy")


def test_forward_view_reads_out_the_fk_values(setup):
    rng = np.random.default_rng(16)
    checked = 0
    for q in _random_q(rng, 12, setup):
        sol = ak.forward_kinematics(q, setup.T_b_e, D, errors="flag")
        for k in (0, 5, 11):
            v = forward_view(setup, q, slot=k)
            assert [s.valid for s in v.slots] == sol.valid.tolist()
            assert [s.reason for s in v.slots] == sol.reason.tolist()
            if not sol.valid.any():
                assert v.geometry is None and v.level == "error"
                assert Reason(int(sol.reason[0])).name in v.message
                continue
            g = v.geometry
            assert sol.valid[g.slot]
            if sol.valid[k]:
                assert g.slot == k
            else:
                assert f"slot {k} has no solution here" in v.message
            r = v.readouts
            np.testing.assert_allclose(r.q, q, rtol=0, atol=0)
            np.testing.assert_allclose(r.p, sol.p[g.slot], rtol=0, atol=1e-12)
            np.testing.assert_allclose(r.u, sol.u[g.slot], rtol=0, atol=1e-12)
            assert r.mode == sol.mode[g.slot]
            ref = robot_geometry(q, setup.T_b_e, D, slot=g.slot)
            np.testing.assert_allclose(r.tip_b, ref.points["tip"], rtol=0, atol=1e-12)
            T = setup.T_b_e
            np.testing.assert_allclose(T[:3, :3] @ r.tip_e + T[:3, 3], r.tip_b, atol=1e-12)
            checked += 1
    assert checked >= 15


def test_all_slots_ghosts_the_other_valid_ones(setup):
    v = forward_view(setup, setup.q_home, slot="all")
    valid = [s.slot for s in v.slots if s.valid]
    assert v.geometry.slot == valid[0]
    assert sorted(g.slot for g in v.ghosts) == valid[1:]
    ghosts = ghost_scene(v.ghosts)
    inst = next(ls for ls in ghosts.lines if ls.name == "ghost_instrument")
    assert inst.segments.shape == (len(valid) - 1, 2, 3)
    assert all(c > 150 for c in inst.color)           # paler than the solid red


def test_near_a_singular_set_warns(setup):
    q = np.array([0.0, 0.002, 0.45])                  # |h| = 1 mm: A and B almost meet
    v = forward_view(setup, q)
    assert "ab_coincide" in v.readouts.near and v.level == "warn"
    d = {x.name: x for x in v.readouts.distances}
    assert d["ab_coincide"].value == pytest.approx(0.001, abs=1e-15)
    assert d["ab_coincide"].warn_at == WARN_DISTANCE_M
    text = readouts_html(v.readouts)
    assert 'data-ro="d_ab_coincide" data-warn="1"' in text
    far = readouts_html(forward_view(setup, setup.q_home).readouts)
    assert 'data-ro="d_ab_coincide" data-warn' not in far
    assert 'data-ro="q1" style="text-align:right;">-100.00<' in far


@pytest.mark.parametrize("slot", [-1, 16, 2.0, "some", True])
def test_bad_slot_is_named(setup, slot):
    with pytest.raises(InvalidInputError, match="slot: expected an integer in 0..15 or 'all'"):
        forward_view(setup, setup.q_home, slot=slot)


def test_bad_q_is_named(setup):
    with pytest.raises(InvalidInputError, match="q"):
        forward_view(setup, [0.1, np.nan, 0.4])


def test_slots_html_greys_invalid_slots_with_their_reason(setup):
    q = np.array([-0.1, 0.1, 0.45])
    v = forward_view(setup, q)
    text = slots_html(v.slots, v.geometry.slot)
    for s in v.slots:
        assert f'data-slot="{s.slot}" data-valid="{int(s.valid)}"' in text
        if not s.valid:
            assert Reason(s.reason).name in text


def test_scene_draws_the_geometry_of_the_static_views(setup):
    g = robot_geometry(slot=3)
    sc = robot_scene(g)
    by = {ls.name: ls for ls in sc.lines}
    np.testing.assert_array_equal(by["instrument"].segments[0],
                                  np.stack(g.segments()["instrument"]))
    np.testing.assert_array_equal(by["actuator_q3"].segments[0],
                                  np.stack(g.segments()["actuator_q3"]))
    np.testing.assert_array_equal(by["circle_k1"].segments[:, 0], g.k1[:-1])
    assert len(by["frame_x"].segments) == 4                   # O_b, O_i, O_s, O_e
    labels = {lab.text: lab.position for lab in sc.labels}
    np.testing.assert_array_equal(labels["tip"], g.points["tip"])
    lo, hi = sc.bounds()
    assert np.all(lo <= g.points["RCM"]) and np.all(g.points["RCM"] <= hi)


def test_angles_round_trip():
    rng = np.random.default_rng(3)
    for az, pol, depth in zip(rng.uniform(-3, 3, 20), rng.uniform(0.1, 3.0, 20),
                              rng.uniform(0.01, 0.4, 20), strict=True):
        back = angles_from_tip(tip_from_angles(az, pol, depth))
        np.testing.assert_allclose(back, (az, pol, depth), rtol=0, atol=1e-12)


def test_inverse_step_reaches_a_target_and_fk_puts_the_tip_there(setup):
    v = forward_view(setup, setup.q_home)
    r = v.readouts
    rng = np.random.default_rng(7)
    for d in rng.normal(scale=0.01, size=(8, 3)):
        st = inverse_step(setup, r.tip_e, r.tip_e + d, r.q, r.mode)
        assert st.reached and st.reason == 0 and st.message == ""
        q_ref, _ = ak.q_from_tool_tip(setup.T_b_e, r.tip_e + d, D)
        np.testing.assert_allclose(st.q, q_ref, rtol=0, atol=1e-12)
        w = forward_view(setup, st.q, slot=0)
        np.testing.assert_allclose(w.readouts.tip_e, r.tip_e + d, rtol=0, atol=1e-9)


def test_inverse_step_stops_at_the_workspace_boundary(setup):
    r = forward_view(setup, setup.q_home).readouts
    target = r.tip_e + np.array([0.0, 0.5, 0.0])       # far out of the workspace
    st = inverse_step(setup, r.tip_e, target, r.q, r.mode, n=64)
    assert not st.reached and st.reason != 0
    assert "workspace boundary" in st.message
    _, ok = ak.q_from_tool_tip(setup.T_b_e, st.tip_e, D, errors="flag")
    assert ok.valid and ok.mode == r.mode                   # the robot stays where it is valid
    beyond = st.tip_e + (target - r.tip_e) / 64
    _, nxt = ak.q_from_tool_tip(setup.T_b_e, beyond, D, errors="flag")
    assert not nxt.valid                                    # ... and just before the boundary
    # no jump: each of the sampled steps moves q by little
    qs, _ = ak.q_from_tool_tip(setup.T_b_e, r.tip_e + np.linspace(0, 1, 65)[1:, None]
                               * (st.tip_e - r.tip_e), D, errors="flag")
    assert np.max(np.abs(np.diff(qs, axis=0))) < 0.01


def test_inverse_step_holds_q_when_even_the_first_step_fails(setup):
    r = forward_view(setup, setup.q_home).readouts
    st = inverse_step(setup, r.tip_e, -r.tip_e, r.q, r.mode, n=1)   # tip behind the RCM...
    st2 = inverse_step(setup, r.tip_e, r.tip_e * 2.0, r.q, r.mode, n=1)   # beyond L
    for s in (st, st2):
        assert not s.reached
        np.testing.assert_array_equal(s.q, r.q)
        assert "actuators held" in s.message
    assert st2.reason == Reason.INSERTION_RANGE


def _csv(tmp_path, text, name="traj.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_playback_reads_a_plan_csv_and_samples_it(tmp_path):
    p = _csv(tmp_path, "t_s,q1_m,q2_m,q3_m,tip_x_m\n0.0,-0.1,0.1,0.45,1\n0.5,-0.11,0.1,0.45,1\n"
                       "1.0,-0.12,0.1,,1\n")
    pb = load_playback(p)
    np.testing.assert_array_equal(pb.t, [0.0, 0.5, 1.0])
    np.testing.assert_array_equal(pb.q[2], pb.q[1])          # a missing reading holds
    assert pb.duration == 1.0
    for t, k in ((-1.0, 0), (0.0, 0), (0.49, 0), (0.5, 1), (0.9, 1), (7.0, 2)):
        q, i = playback_q(pb, t)
        assert i == k
        np.testing.assert_array_equal(q, pb.q[k])


@pytest.mark.parametrize("text, match", [
    ("t_s,q1_m,q2_m,q3_m\n0,-0.1,0.1,0.45\n1,-0.1,abc,0.45\n", "line 3.*q2_m"),
    ("t_s,q1_m,q3_m\n0,-0.1,0.45\n", "missing"),
    ("t_s,q1_m,q2_m,q3_m\n0,-0.1,0.1,0.45\n0,-0.1,0.1,0.45\n", "does not increase"),
    ("t_s,q1_m,q2_m,q3_m\n", "no readings"),
])
def test_playback_names_bad_rows(tmp_path, text, match):
    with pytest.raises(PathFileError, match=match):
        load_playback(_csv(tmp_path, text))


def test_playback_of_a_missing_file_is_a_path_error(tmp_path):
    with pytest.raises(PathFileError, match="cannot read"):
        load_playback(tmp_path / "nope.csv")


def test_cli_registers_app():
    from athenakin.cli import COMMANDS, build_parser

    assert "app" in COMMANDS
    args = build_parser().parse_args(["app", "--port", "0"])
    assert args.host == "127.0.0.1" and args.port == 0


@pytest.mark.skipif(not HAS_VISER, reason="needs the 'app' extra (viser)")
def test_app_keeps_running_on_bad_inputs(tmp_path):
    from athenakin.app import AthenaApp

    bad_design = _csv(tmp_path, "[design]\nl1 = 0.05\nl2 = 0.1\nl3 = 0.04\nl4 = 0.15\n"
                                "l5 = 5.0\n", "bad.toml")
    rcm = _csv(tmp_path, '{"T_b_e": [[1, 0, 0, 0], [0, 2, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}',
               "rcm.json")
    traj = _csv(tmp_path, "t_s,q1_m,q2_m,q3_m\n0,-0.1,0.1,0.45\n1,x,0.1,0.45\n")
    app = AthenaApp(bad_design, rcm, port=0, trajectory=traj, backend="numpy")
    try:
        text = " | ".join(app.errors)
        assert "bad.toml" in text or "design" in text
        assert "rigid transform" in text
        assert "line 3" in text and "q1_m" in text
        assert app.setup.design == D                    # fell back to the reference
        assert "Problems" in app._banner.content
        v = app.set_q([-0.12, 0.08, 0.47])              # ... and keeps answering
        assert v.geometry is not None and app.view is v
        np.testing.assert_allclose(v.readouts.q, [-0.12, 0.08, 0.47])
        bad = app.set_q([0.1, -0.1, 0.45])              # no solution: message, robot kept
        assert bad.geometry is None and app.view is v
        assert 'data-level="error"' in app._status.content
    finally:
        app.stop()
