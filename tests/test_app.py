"""The app's pure layer (set-up, forward view, inverse step, playback, scene, read-outs) and
the viser binding in process (bad inputs keep it running). The browser: test_app_browser.py."""

import asyncio
import dataclasses
import importlib.util
import os
from pathlib import Path
from types import SimpleNamespace

import _budget
import numpy as np
import pytest

import athenakin as ak
from athenakin._transforms import rot_x, transform_from_rotation_translation
from athenakin.app import (
    GHOST_BLEND,
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
    slot_ghosts,
    slots_html,
    tip_from_angles,
)
from athenakin.app._ghosts import arcs_points
from athenakin.errors import InvalidInputError, OutOfWorkspaceError, Reason
from athenakin.motion import PathFileError
from athenakin.plot import robot_geometry
from athenakin.plot._mpl import arc_points
from athenakin.robot import SLOT_MODE

D = ak.Design.default()
HAS_VISER = importlib.util.find_spec("viser") is not None


@pytest.fixture(scope="module")
def setup():
    return app_setup(design=D, backend="numpy")


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
        app_setup(design=bad, backend="numpy")


def test_setup_starts_where_the_design_assembles():
    # the reference q is beyond these strokes: the start is the nearest assembled grid point
    d = dataclasses.replace(D, q_min=(-0.30, 0.15, 0.20), q_max=(-0.15, 0.30, 0.70))
    s = app_setup(design=d, backend="numpy")
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
        app_setup(T, D, backend="numpy")


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
    assert v.ghosts.slot.tolist() == valid[1:] and len(v.ghosts) == len(valid) - 1
    ghosts = ghost_scene(v.ghosts, v.geometry)
    by = {ls.name: ls for ls in ghosts.lines}
    inst = by["ghost_instrument"]
    assert inst.segments.shape == (len(valid) - 1, 2, 3)
    assert all(c > 150 for c in inst.color)           # paler than the solid red
    assert "ghost_circle_k1" not in by and "ghost_rail" not in by    # drawn by the solid slot
    other = next(int(k) for k in v.ghosts.slot if SLOT_MODE[k] != v.geometry.mode)
    np.testing.assert_allclose(by["ghost_parallel"].segments,        # the other mode, once
                               robot_scene(robot_geometry(setup.q_home, slot=other)).lines[1]
                               .segments, rtol=0, atol=1e-12)
    assert forward_view(setup, setup.q_home, slot=3).ghosts is None


def _ghost_scene_loop(geoms, solid):
    """Reference: the ghosts drawn one slot at a time from each slot's RobotGeometry and
    robot_scene (the app's first implementation)."""
    parts, style, modes_done = {}, {}, {solid.mode}
    for g in geoms:
        new_mode = g.mode not in modes_done
        for ls in robot_scene(g, frames=False, labels=False).lines:
            if ls.name in ("circle_k1", "circle_k2", "rail") or (
                    ls.name in ("parallel", "actuator_q3") and not new_mode):
                continue
            parts.setdefault(ls.name, []).append(ls.segments)
            color = tuple(round(c + GHOST_BLEND * (255 - c)) for c in ls.color)
            style[ls.name] = (color, max(1.0, 0.6 * ls.width))
        modes_done.add(g.mode)
    return {f"ghost_{k}": (np.concatenate(v), *style[k]) for k, v in parts.items()}


@pytest.mark.parametrize("design", ["default", "other"])
def test_batched_ghosts_draw_what_one_slot_at_a_time_draws(design):
    rng = np.random.default_rng(16)
    if design == "default":
        d, T = D, None
    else:
        d = dataclasses.replace(D, l4=D.l4 * 1.3, tool_length=D.tool_length * 0.8)
        T = ak.default_rcm_frame(d) @ transform_from_rotation_translation(
            rot_x(np.asarray(0.2)), np.array([0.01, -0.02, 0.03]))
    s = app_setup(T, d, backend="numpy")
    checked = 0
    for q in _random_q(rng, 12, s):
        sol = ak.forward_kinematics(q, s.T_b_e, d, errors="flag")
        valid = np.flatnonzero(sol.valid)
        if len(valid) < 2:
            continue
        solid = robot_geometry(q, s.T_b_e, d, slot=int(valid[0]), fk=sol)
        order = rng.permutation(valid[1:])                  # any subset, any order
        ghosts = slot_ghosts(sol, q, s.T_b_e, d, order)
        ref = _ghost_scene_loop([robot_geometry(q, s.T_b_e, d, slot=int(k), fk=sol)
                                 for k in order], solid)
        got = {ls.name: ls for ls in ghost_scene(ghosts, solid).lines}
        assert set(got) == set(ref)
        for name, (segments, color, width) in ref.items():
            np.testing.assert_allclose(got[name].segments, segments, rtol=0, atol=1e-12,
                                       err_msg=name)
            assert got[name].color == color and got[name].width == width
        for i, k in enumerate(order):                      # the geometry itself
            g = robot_geometry(q, s.T_b_e, d, slot=int(k), fk=sol)
            np.testing.assert_allclose(ghosts.tip[i], g.points["tip"], rtol=0, atol=1e-12)
            np.testing.assert_allclose(ghosts.wrist_axes[i], g.wrist_axes, rtol=0, atol=1e-12)
            np.testing.assert_allclose(ghosts.ujoint_axes[i], g.ujoint_axes, rtol=0,
                                       atol=1e-12)
            np.testing.assert_allclose(ghosts.O_i_mode[(1 - g.mode) // 2], g.points["O_i"],
                                       rtol=0, atol=1e-12)
        checked += 1
    assert checked >= 5


def test_batched_arcs_match_the_static_views_including_parallel_axes():
    rng = np.random.default_rng(7)
    a = rng.normal(size=(5, 3))
    b = rng.normal(size=(5, 3))
    b[0] = 2.5 * a[0]                                     # parallel: a point repeated
    b[1] = -a[1]                                          # antiparallel: no plane, repeated too
    c = np.array([0.1, -0.2, 0.3])
    got = arcs_points(c, a, b, 0.07)
    for i in range(5):
        np.testing.assert_allclose(got[i], arc_points(c, a[i], b[i], 0.07), rtol=0, atol=1e-14)


def test_slot_ghosts_rejects_an_invalid_slot(setup):
    sol = ak.forward_kinematics(setup.q_home, setup.T_b_e, D, errors="flag")
    bad = int(np.flatnonzero(~sol.valid)[0]) if not sol.valid.all() else 16
    with pytest.raises(InvalidInputError, match="slots: expected valid slots"):
        slot_ghosts(sol, setup.q_home, setup.T_b_e, D, [bad])
    with pytest.raises(InvalidInputError, match="fk: expected the FKSolution"):
        slot_ghosts(sol.valid, setup.q_home, setup.T_b_e, D, [0])
    with pytest.raises(InvalidInputError, match="ghosts, solid: expected"):
        ghost_scene([robot_geometry(setup.q_home, slot=1)], robot_geometry(setup.q_home))


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
    assert 'data-ro="q1" data-v="-0.1" style="text-align:right;">-100.00<' in far


def test_singular_rows_have_plain_names_units_and_a_legend(setup):
    from athenakin.analysis import CONDITIONS
    from athenakin.app import SINGULAR_NAMES

    assert set(SINGULAR_NAMES) == set(CONDITIONS)                 # every set has a plain name
    q = np.array([0.0, 0.002, 0.45])
    r = forward_view(setup, q).readouts
    text = readouts_html(r)
    assert 'data-ro="legend"' in text and "within 5 mm or 5 deg" in text
    for d in r.distances:
        name, shown = SINGULAR_NAMES[d.name]
        assert f"<td>{name}</td>" in text and "_" not in name.replace("O_s", "").replace(
            "z_e", "").replace("z_s", "")
        cell = text.split(f'data-ro="d_{d.name}"')[1].split(">", 1)[1].split("<", 1)[0]
        if np.isnan(d.value):
            continue
        if shown == "deg":                                       # a sine shown as its angle
            assert cell == f"{np.degrees(np.arcsin(min(abs(d.value), 1.0))):.1f} deg"
        else:
            assert cell.endswith(" mm")
            assert float(cell[:-3]) == pytest.approx(d.value * 1e3, abs=0.005 + 1e-9)
    wrist = text.split('data-ro="d_wrist"')[0].rsplit("<tr", 1)[1]
    assert "title=" in wrist and "instrument along z_e" in wrist   # hover: the meaning


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


def test_inverse_step_names_the_stroke_limit_it_stops_at(setup):
    r = forward_view(setup, setup.q_home).readouts
    st = inverse_step(setup, r.tip_e, r.tip_e + np.array([0.0, 0.0, -0.2]), r.q, r.mode)
    assert not st.reached and st.reason == Reason.STROKE_LIMIT
    assert "STROKE_LIMIT" in st.message
    assert np.all(st.q >= D.stroke_min) and np.all(st.q <= D.stroke_max)
    assert np.min(np.minimum(st.q - D.stroke_min, D.stroke_max - st.q)) < 0.01   # at the limit


def test_inverse_step_holds_q_when_even_the_first_step_fails(setup):
    r = forward_view(setup, setup.q_home).readouts
    st = inverse_step(setup, r.tip_e, -r.tip_e, r.q, r.mode, n=1)   # tip behind the RCM...
    st2 = inverse_step(setup, r.tip_e, r.tip_e * 2.0, r.q, r.mode, n=1)   # beyond L
    for s in (st, st2):
        assert not s.reached
        np.testing.assert_array_equal(s.q, r.q)
        assert "actuators held" in s.message
    assert st2.reason == Reason.INSERTION_RANGE


@pytest.mark.parametrize("slot", [12, 15, 8, 11])                # p < 0 and p > L, mode -1
def test_inverse_step_stays_on_the_slots_branch_of_p(setup, slot):
    v = forward_view(setup, setup.q_home, slot=slot)
    r = v.readouts
    assert r.slot == slot and r.mode == -1 and not 0 < r.p < D.tool_length
    rng = np.random.default_rng(slot)
    for d in rng.normal(scale=0.005, size=(4, 3)):
        st = inverse_step(setup, r.tip_e, r.tip_e + d, r.q, r.mode, p_from=r.p)
        assert st.reached and st.message == "", st.message
        w = forward_view(setup, st.q, slot=slot)                  # the same slot, moved
        assert w.readouts.slot == slot
        np.testing.assert_allclose(w.readouts.tip_e, r.tip_e + d, rtol=0, atol=1e-9)
        assert (w.readouts.p < 0) == (r.p < 0)
    # across the branch's end (p = 0, or the tip at the RCM): held, and says why
    end = r.tip_e * (0.9 * D.tool_length / np.linalg.norm(r.tip_e) if r.p < 0 else 0.0)
    st = inverse_step(setup, r.tip_e, end, r.q, r.mode, p_from=r.p, n=1)
    assert not st.reached and "actuators held" in st.message
    assert ("branch p < 0 ends" if r.p < 0 else "branch p > L") in st.message
    np.testing.assert_array_equal(st.q, r.q)


def test_inverse_step_rejects_a_bad_p_from(setup):
    r = forward_view(setup, setup.q_home).readouts
    with pytest.raises(InvalidInputError, match="p_from"):
        inverse_step(setup, r.tip_e, r.tip_e, r.q, r.mode, p_from=np.nan)


def test_solids_join_a_scene_with_unique_names():
    from athenakin.app import Solid, with_solids

    g = robot_geometry(ak.robot.REFERENCE_Q, slot=0)
    sc = robot_scene(g)
    assert sc.solids == ()
    box = Solid("box", np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]),
                np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]), (10, 20, 30))
    sc2 = with_solids(sc, (box,))
    assert sc2.solids == (box,) and sc2.lines == sc.lines
    np.testing.assert_array_equal(sc2.bounds()[1], np.maximum(sc.bounds()[1], 1.0))
    with pytest.raises(InvalidInputError, match="unique"):
        with_solids(sc2, (box,))
    with pytest.raises(InvalidInputError, match="box2"):
        with_solids(sc, (Solid("box2", np.zeros((3, 2)), np.zeros((1, 3), int), (0, 0, 0)),))


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
    assert args.environment is None and args.bodies is None
    args = build_parser().parse_args(["app", "--environment", "a.toml", "--bodies", "b.toml"])
    assert args.environment == Path("a.toml") and args.bodies == Path("b.toml")


@pytest.mark.skipif(not HAS_VISER, reason="needs the 'app' extra (viser)")
def test_app_keeps_running_on_bad_inputs(tmp_path):
    from athenakin.app import AthenaApp

    bad_design = _csv(tmp_path, "[design]\nl1 = 0.05\nl2 = 0.1\nl3 = 0.04\nl4 = 0.15\n"
                                "l5 = 5.0\n", "bad.toml")
    rcm = _csv(tmp_path, '{"T_b_e": [[1, 0, 0, 0], [0, 2, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}',
               "rcm.json")
    traj = _csv(tmp_path, "t_s,q1_m,q2_m,q3_m\n0,-0.1,0.1,0.45\n1,x,0.1,0.45\n")
    app = AthenaApp(rcm, bad_design, port=0, trajectory=traj, backend="numpy")
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


def test_cli_without_viser_names_the_extra(monkeypatch, capsys):
    import sys

    from athenakin.cli import main

    monkeypatch.setitem(sys.modules, "viser", None)          # import viser fails
    assert main(["app", "--port", "0"]) == 1
    assert "pip install 'athenakin[app]'" in capsys.readouterr().err


@pytest.mark.skipif(not HAS_VISER, reason="needs the 'app' extra (viser)")
@pytest.mark.parametrize("option,name,content,want", [
    ("--environment", "nope.toml", None, "FileNotFoundError: [Errno 2] No such file"),
    ("--bodies", "nope.toml", None, "FileNotFoundError: [Errno 2] No such file"),
    ("--environment", "bin.toml", bytes(range(256)), "environment file is not UTF-8 text"),
    ("--environment", "bad.toml", b'[[environment.obstacle]]\nkind = "cone"\n',
     "environment.obstacle[0].kind: expected one of"),
    ("--bodies", "bad.toml", b"[bodies]\nradius = {link1 = 0.01}\n", "unknown body 'link1'"),
])
def test_cli_refuses_a_bad_bodies_or_environment_file_in_one_line(tmp_path, capsys, option,
                                                                   name, content, want):
    """A bad collision file stops the start (the design, RCM frame and trajectory fall back
    with a warning instead): one line naming the file, exit 1, nothing served."""
    from athenakin.cli import main

    if content is not None:
        (tmp_path / name).write_bytes(content)
    code = main(["app", "--port", "0", "--backend", "numpy", option, str(tmp_path / name)])
    out, err = capsys.readouterr()
    assert code == 1 and "serving" not in out, out
    assert err.count("\n") == 1 and err.startswith("athenakin app: error: "), err
    assert name in err and want in err, err


@pytest.mark.skipif(not HAS_VISER, reason="needs the 'app' extra (viser)")
def test_app_tip_handle_and_slot_menu_in_process():
    from athenakin.app import AthenaApp

    app = AthenaApp(port=0, backend="numpy")
    try:
        r = app.view.readouts
        T = app.setup.T_b_e
        target_e = r.tip_e + np.array([0.0, 0.01, 0.01])
        app._handle.position = tuple(T[:3, :3] @ target_e + T[:3, 3])   # a drag ...
        _handle_event(app, "update")
        _handle_event(app, "end")                      # ... and release
        q_ref, _ = ak.q_from_tool_tip(T, target_e, D)
        np.testing.assert_allclose(app.q, q_ref, rtol=0, atol=1e-12)
        np.testing.assert_allclose(app._handle.position, app.view.readouts.tip_b, atol=1e-6)
        assert [sl.value for sl in app._q_sliders] == pytest.approx(q_ref * 1e3, abs=1e-3)
        far = T[:3, :3] @ (r.tip_e * 5.0) + T[:3, 3]                    # beyond the tool
        app._handle.position = tuple(far)
        _handle_event(app, "end")
        # the straight path out crosses an overlap of the bodies before the workspace
        # boundary (issue 30): it stops there (pure: the inverse_step tests)
        assert "stopped before a collision" in app._status.content
        assert app.view.geometry is not None and not app.bodies.view.colliding  # held, drawn
        _, ok = ak.q_from_tool_tip(T, app.view.readouts.tip_e, D, errors="flag")
        assert ok.valid
        # the slot menu: invalid slots are marked with their reason
        v = app.set_q([-0.1, 0.1, 0.26])                # near the tangency: some invalid
        opts = app._slot_dd.options
        assert len(opts) == 17 and opts[0].startswith("all valid")
        for s in v.slots:
            assert opts[1 + s.slot].startswith(s.label)
            assert ("invalid" in opts[1 + s.slot]) == (not s.valid)
    finally:
        app.stop()


@pytest.mark.skipif(not HAS_VISER, reason="needs the 'app' extra (viser)")
def test_tip_handle_snaps_back_when_a_drag_ends_before_its_last_update():
    """A synchronous callback runs on viser's thread pool, where a drag's end could be
    handled before its start or its last update (a drag left on for ever, a doubled
    travel): the drags' callbacks are coroutines, which viser awaits on its event loop in
    the page's order. Should an update still come after the end, the handle snaps to the
    tip reached and follows the sliders afterwards."""
    import inspect

    from athenakin.app import AthenaApp

    app = AthenaApp(port=0, backend="numpy")
    try:
        for callback in (app._on_handle, app._on_grip, app.forces._on_handle):
            assert inspect.iscoroutinefunction(callback)
        T, r = app.setup.T_b_e, app.view.readouts
        _handle_event(app, "start")
        app.tip_handle.position = tuple(T[:3, :3] @ (r.tip_e * 5.0) + T[:3, 3])  # too far
        _handle_event(app, "end")            # the end first ...
        _handle_event(app, "update")         # ... then the last update
        tip = app.view.readouts.tip_b
        assert np.linalg.norm(tip - r.tip_b) > 1e-3             # it moved, to the boundary
        np.testing.assert_allclose(app.tip_handle.position, tip, rtol=0, atol=1e-6)
        app.set_q(app.setup.q_home)
        np.testing.assert_allclose(app.tip_handle.position, r.tip_b, rtol=0, atol=1e-6)
    finally:
        app.stop()


@pytest.mark.skipif(not HAS_VISER, reason="needs the 'app' extra (viser)")
def test_launch_playback_and_setup_tab_in_process(tmp_path, capsys):
    import time

    from athenakin.app import launch

    traj = _csv(tmp_path, "t_s,q1_m,q2_m,q3_m\n0,-0.1,0.1,0.45\n0.1,-0.11,0.09,0.46\n"
                          "0.2,-0.12,0.08,0.47\n")
    app = launch(port=0, trajectory=traj, backend="numpy")
    try:
        assert f"ATHENA at {app.url}" in capsys.readouterr().out
        assert app.url.startswith("http://127.0.0.1:")
        np.testing.assert_allclose(app.q, [-0.1, 0.1, 0.45])
        app.playback_tab.play()                                 # the play button
        t0 = time.monotonic()
        while time.monotonic() - t0 < 10 and not np.allclose(app.q, [-0.12, 0.08, 0.47]):
            time.sleep(0.05)
        np.testing.assert_allclose(app.q, [-0.12, 0.08, 0.47])
        # the set-up tab: another design is applied, a bad one refused
        other = dataclasses.replace(D, q_min=(-0.25, -0.05, 0.25), name="narrow")
        (tmp_path / "narrow.toml").write_text(other.to_toml())
        app.setup_tab.design_path.value = str(tmp_path / "narrow.toml")
        app.setup_tab.apply()
        assert app.setup.design == other
        assert [sl.min for sl in app._q_sliders] == pytest.approx([-250.0, -50.0, 250.0])
        app.setup_tab.design_path.value = str(tmp_path / "missing.toml")
        app.setup_tab.apply()
        assert app.setup.design == other
        assert "set-up not changed" in app._status.content
    finally:
        app.stop()


@pytest.mark.skipif(not HAS_VISER, reason="needs the 'app' extra (viser)")
def test_cli_reports_bad_inputs_at_startup_and_serves(tmp_path):
    import signal
    import subprocess
    import sys

    from athenakin.collision import Bodies, Environment

    bad = _csv(tmp_path, "[design]\nl1 = 0.3\nl2 = 0.1\nl3 = 0.25\nl4 = 0.15\nl5 = 5.0\n",
               "far.toml")
    env = _csv(tmp_path, Environment().halfspace([0, 0, -1.0], [0, 0, 1.0]).to_toml(), "e.toml")
    bodies = _csv(tmp_path, Bodies.default().with_radius({"instrument": 0.003}).to_toml(),
                  "b.toml")
    proc = subprocess.Popen(             # good collision files: served with the fallbacks
        [sys.executable, "-m", "athenakin.cli", "app", "--port", "0", "--backend", "numpy",
         "--design", str(bad), "--trajectory", str(tmp_path / "none.csv"),
         "--environment", str(env), "--bodies", str(bodies)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        env={**os.environ, **_budget.FAULTHANDLER_ENV})
    try:
        lines = []
        for line in proc.stdout:
            lines.append(line)
            if "serving ATHENA at" in line:
                break
        text = "".join(lines)
        assert "warning: design: OutOfWorkspaceError" in text and "assembles nowhere" in text
        assert "warning: trajectory: PathFileError" in text and "none.csv" in text
        assert "serving ATHENA at http://127.0.0.1:" in text
        assert _budget.wait_after_signal(proc, signal.SIGINT, 10.0) == 0
        assert "athenakin app: stopped" in proc.stdout.read()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        proc.stdout.close()


@pytest.mark.skipif(not HAS_VISER, reason="needs the 'app' extra (viser)")
def test_a_p_below_zero_slot_keeps_its_branch_across_tabs_in_process():
    """The issue's state bug: pick slot 15 (mode -1, p < 0) in the Forward tab, then step
    the azimuth in the Inverse tab: the sliders agree with the read-outs, and the IK stays
    on slot 15; the title names the design; solids are drawn and updated."""

    from athenakin.app import AthenaApp, Solid

    def solids(view):
        tip = view.readouts.tip_b
        return (Solid("tip_box", tip + np.array([[0, 0, 0], [0.01, 0, 0], [0, 0.01, 0],
                                                 [0, 0, 0.01]]),
                      np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]), (200, 0, 0)),)

    app = AthenaApp(port=0, backend="numpy", solids=solids)
    try:
        assert app.title == "ATHENA - athenakin reference design - athenakin"
        mesh = app.page.solid_handle("tip_box")
        np.testing.assert_allclose(mesh.vertices[0], app.view.readouts.tip_b, atol=1e-6)
        app._slot_dd.value = app._slot_dd.options[1 + 15]
        app._on_slot(None)
        r = app.view.readouts
        assert r.slot == 15 and r.p < 0
        az, pol, depth = angles_from_tip(r.tip_e)
        assert app._depth.value == pytest.approx(depth * 1e3, abs=0.01)   # 1151.6, not 449
        assert app._depth.min <= app._depth.value <= app._depth.max
        assert app._az.value == pytest.approx(np.degrees(az), abs=0.01)
        app._az.value = app._az.value + 0.1                         # one azimuth step
        app._on_angles(None)
        r2 = app.view.readouts
        assert r2.slot == 15 and app._status.content.count("held") == 0
        assert np.max(np.abs(r2.q - r.q)) > 1e-5                     # it moved ...
        sol = ak.forward_kinematics(r2.q, app.setup.T_b_e, D, errors="flag")
        np.testing.assert_allclose(r2.tip_b, sol.tip[15], rtol=0, atol=1e-9)
        np.testing.assert_allclose(r2.u, sol.u[15], rtol=0, atol=1e-9)   # ... on slot 15
        a2, p2, d2 = angles_from_tip(r2.tip_e)
        assert np.degrees(a2) == pytest.approx(app._az.value, abs=1e-6)
        assert d2 * 1e3 == pytest.approx(app._depth.value, abs=1e-6)
        mesh = app.page.solid_handle("tip_box")                      # the solid followed
        np.testing.assert_allclose(mesh.vertices[0], r2.tip_b, atol=1e-6)
        # the tip grip: a drag in the view plane moves the tip by the pointer's motion
        tip0 = r2.tip_b.copy()
        _drag_grip(app, tip0, [tip0, tip0 + [0.0, 0.0, 0.004], tip0 + [0.0, 0.0, 0.004]])
        np.testing.assert_allclose(app.view.readouts.tip_b, tip0 + [0, 0, 0.004], atol=1e-9)
        assert app.view.readouts.slot == 15
        np.testing.assert_allclose(app._grip.position, app.view.readouts.tip_b, atol=1e-6)
    finally:
        app.stop()


def _handle_event(app, phase):
    """One event of a tip-handle drag as viser delivers it (on an event loop), its move done."""
    asyncio.run(app._on_handle(SimpleNamespace(phase=phase)))
    app._moves.drain()


def _drag_grip(app, grab, pointer):
    """One drag of the tip grip as viser delivers it: ``start`` at ``pointer[0]``, the
    updates, ``end`` at ``pointer[-1]``, in order on one event loop and without waiting
    for the moves; returns once the grip's worker has applied them."""
    phases = ["start"] + ["update"] * (len(pointer) - 2) + ["end"]

    async def send():
        for phase, p in zip(phases, pointer, strict=True):
            await app._on_grip(SimpleNamespace(phase=phase, start_position=tuple(grab),
                                               end_position=tuple(p)))

    asyncio.run(send())
    app._moves.drain()                                   # one worker: the moves are done


@pytest.mark.skipif(not HAS_VISER, reason="needs the 'app' extra (viser)")
def test_a_burst_of_grip_events_moves_the_tip_by_the_pointer_once():
    """A drag whose events reach the server faster than the IK runs (a loaded machine):
    the tip ends at the grab's tip plus the pointer's travel, not twice it (a late update
    handled after the end started a second grab from the moved tip), and the grip is
    placed on the tip."""
    from athenakin.app import AthenaApp

    app = AthenaApp(port=0, backend="numpy")
    try:
        tip0 = app.view.readouts.tip_b.copy()
        travel = np.array([0.0, 0.006, -0.004])
        pointer = [tip0 + s * travel for s in np.linspace(0.0, 1.0, 25)]
        _drag_grip(app, tip0, pointer)
        np.testing.assert_allclose(app.view.readouts.tip_b, tip0 + travel, rtol=0,
                                   atol=1e-9)
        np.testing.assert_allclose(app._grip.position, tip0 + travel, rtol=0, atol=1e-6)
        assert not app._dragging and app._grab is None
        _drag_grip(app, tip0 + travel, [tip0 + travel, tip0])       # and back: a new grab
        np.testing.assert_allclose(app.view.readouts.tip_b, tip0, rtol=0, atol=1e-9)
    finally:
        app.stop()


def _clearance_fn(setup, slot=0):
    from athenakin.collision import clearance

    return lambda q: clearance(q, setup.T_b_e, setup.design, slot=slot).min_distance


def test_inverse_step_stops_before_a_collision(setup):
    """Issue 30: an IK move drove the carriages 50 mm into each other. With ``clearance``
    the motion stops before the bodies overlap; out of an overlap it goes on."""
    clear = _clearance_fn(setup)
    r = forward_view(setup, setup.q_home, slot=0).readouts
    target = tip_from_angles(np.radians(-180.0), np.radians(5.0), 0.25)
    blind = inverse_step(setup, r.tip_e, target, r.q, r.mode, p_from=r.p)
    assert clear(blind.q[None])[0] < -0.04                     # the bug, without the check
    step = inverse_step(setup, r.tip_e, target, r.q, r.mode, p_from=r.p, clearance=clear)
    assert step.collision and not step.reached and step.reason == 0
    assert "collision" in step.message
    assert 0 <= clear(step.q[None])[0] < 0.02                  # stopped close, not inside
    np.testing.assert_allclose(forward_view(setup, step.q, slot=0).readouts.tip_e,
                               step.tip_e, rtol=0, atol=1e-9)
    # from an overlap (placed by the q sliders) a motion that separates the bodies goes on
    v = forward_view(setup, np.array([-0.03, 0.03, 0.45]), slot=0).readouts
    assert clear(v.q[None])[0] < 0
    out = inverse_step(setup, v.tip_e, r.tip_e, v.q, v.mode, p_from=v.p, clearance=clear)
    assert out.reached and not out.collision
    assert inverse_step(setup, r.tip_e, r.tip_e + 0.001, r.q, r.mode, p_from=r.p,
                        clearance=clear).reached                # clear motions: unchanged


def test_inverse_step_rejects_a_bad_clearance(setup):
    r = forward_view(setup, setup.q_home, slot=0).readouts
    with pytest.raises(InvalidInputError, match="clearance: expected a function"):
        inverse_step(setup, r.tip_e, r.tip_e, r.q, clearance=0.01)
    with pytest.raises(InvalidInputError, match=r"clearance: expected shape \(49,\)"):
        inverse_step(setup, r.tip_e, r.tip_e, r.q, clearance=lambda q: np.zeros(3))


@pytest.mark.skipif(not HAS_VISER, reason="needs the 'app' extra (viser)")
def test_app_stops_an_ik_move_before_a_collision_and_says_colliding_at_the_top():
    from athenakin.app import AthenaApp

    app = AthenaApp(port=0, backend="numpy")
    clear = _clearance_fn(app.setup)
    try:
        with app._echo():                    # the browser's values, then their callback
            app._az.value, app._pol.value = -180.0, 5.0
        app._on_angles(None)
        assert clear(app.q[None])[0] >= 0 and not app.bodies.view.colliding
        assert 'data-level="warn"' in app._status.content
        assert "stopped before a collision" in app._status.content
        app.set_q([-0.03, 0.03, 0.45])       # the q sliders may place an overlap: said so
        assert 'data-level="error"' in app._status.content
        assert "colliding: carriage_a and carriage_b overlap by 50.0 mm" in app._status.content
        app.bodies.checkbox.value = False    # solids hidden: still checked and said
        app.set_q([-0.03, 0.032, 0.45])
        assert "colliding: carriage_a and carriage_b overlap by 48.0 mm" in app._status.content
        app.set_q(app.setup.q_home)
        assert 'data-level="ok"' in app._status.content
    finally:
        app.stop()


@pytest.mark.skipif(not HAS_VISER, reason="needs the 'app' extra (viser)")
def test_a_key_press_that_arrives_during_an_update_is_not_undone(monkeypatch):
    """Issue 30's lost key press. viser stores the browser's value, then runs its callback
    on a thread pool. An update that wrote its own (older) value back to the slider undid
    a key press that arrived meanwhile, and the next callback read the old value."""
    from athenakin.app import AthenaApp, _server

    app = AthenaApp(port=0, backend="numpy")
    sl = app._q_sliders[0]
    real = _server.forward_view

    def next_key_arrives(*args, **kwargs):
        monkeypatch.setattr(_server, "forward_view", real)
        with app._echo():
            sl.value = -99.0                 # the next key press, during this update
        return real(*args, **kwargs)

    try:
        with app._echo():
            sl.value = -99.5                 # a key press ...
        monkeypatch.setattr(_server, "forward_view", next_key_arrives)
        app._on_q(None)                      # ... and its callback
        assert sl.value == -99.0             # the newer value is kept
        app._on_q(None)                      # the next key press's callback
        assert app.q[0] == pytest.approx(-0.099, abs=1e-12)
    finally:
        app.stop()


@pytest.mark.skipif(not HAS_VISER, reason="needs the 'app' extra (viser)")
def test_a_browser_update_is_not_dropped_while_another_thread_writes_the_gui(monkeypatch):
    """The other half of the lost key press: the flag that ignores the app's own writes was
    shared by every thread, so a callback of the browser on another thread saw it and
    returned. The flag is per thread, and the callback waits for the update in progress."""
    import threading
    import time

    from athenakin.app import AthenaApp
    from athenakin.app._sync import Echo

    echo, seen = Echo(), []
    with echo():
        t = threading.Thread(target=lambda: seen.append(bool(echo)))
        t.start()
        t.join()
        assert echo
    assert seen == [False] and not echo
    app = AthenaApp(port=0, backend="numpy")
    sl, threads = app._q_sliders[0], []
    place = app._place_handle

    def meanwhile():                          # inside the first update's GUI writes
        if not threads:
            with app._echo():
                sl.value = -99.0              # the browser's next value; its callback runs
            threads.append(threading.Thread(target=app._on_q, args=(None,)))
            threads[0].start()
            time.sleep(0.2)                   # (it must wait, whenever it gets here)
        place()

    try:
        monkeypatch.setattr(app, "_place_handle", meanwhile)
        with app._echo():
            sl.value = -99.5
        app._on_q(None)
        threads[0].join()
        assert app.q[0] == pytest.approx(-0.099, abs=1e-12) and sl.value == -99.0
    finally:
        app.stop()


def test_page_scripts_need_viser_s_script_channel_and_say_so():
    """The one private viser channel (``app._script``): a server without it is a named
    ImportError naming viser, not an AttributeError from inside the app."""
    from types import SimpleNamespace

    from athenakin.app._script import run_page_script

    sent = []
    ok = SimpleNamespace(gui=SimpleNamespace(_websock_interface=SimpleNamespace(
        queue_message=sent.append)))
    if importlib.util.find_spec("viser") is None:
        pytest.skip("viser not installed")
    run_page_script(ok, "document.title = 'x';")
    assert [m.source for m in sent] == ["document.title = 'x';"]
    with pytest.raises(ImportError, match=r"RunJavascriptMessage channel") as info:
        run_page_script(SimpleNamespace(gui=SimpleNamespace()), "1;")
    assert info.value.name == "viser"


@pytest.mark.skipif(not HAS_VISER, reason="needs the 'app' extra (viser)")
def test_a_grip_event_after_stop_is_ignored():
    """A drag event that reaches a stopped app moves nothing and raises nothing."""
    from athenakin.app import AthenaApp

    app = AthenaApp(port=0, backend="numpy")
    tip0 = app.view.readouts.tip_b.copy()
    app.stop()
    asyncio.run(app._on_grip(SimpleNamespace(phase="start", start_position=tuple(tip0),
                                             end_position=tuple(tip0 + 0.01))))
    np.testing.assert_array_equal(app.view.readouts.tip_b, tip0)


@pytest.mark.skipif(not HAS_VISER, reason="needs the 'app' extra (viser)")
def test_a_handle_drag_ends_where_its_end_put_the_handle():
    """The end of a drag reaches the event loop while an update's move still runs: the tip
    ends where the end put the handle (a move that read the handle's live position took the
    position that the update's move had just placed the handle at)."""
    from athenakin.app import AthenaApp

    app = AthenaApp(port=0, backend="numpy")
    try:
        T, r = app.setup.T_b_e, app.view.readouts
        at = [r.tip_e + [0.0, 0.002, 0.002], r.tip_e + [0.0, 0.004, 0.004]]   # update, end
        move_tip, calls = app._move_tip, []

        def slow_move(tip_e, **kw):
            calls.append(tip_e)
            if len(calls) == 2:              # the update's move: the end arrives meanwhile
                app._handle.position = tuple(T[:3, :3] @ at[1] + T[:3, 3])
                asyncio.run(app._on_handle(SimpleNamespace(phase="end")))
            move_tip(tip_e, **kw)

        app._move_tip = slow_move
        _handle_event(app, "start")
        app._handle.position = tuple(T[:3, :3] @ at[0] + T[:3, 3])
        _handle_event(app, "update")
        app._moves.drain()                   # the end's move, submitted during the update's
        np.testing.assert_allclose(app.view.readouts.tip_e, at[1], rtol=0, atol=1e-9)
        np.testing.assert_allclose(app._handle.position, app.view.readouts.tip_b, atol=1e-9)
        assert not app._dragging and len(calls) == 3
    finally:
        app.stop()
