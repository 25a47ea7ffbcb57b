"""The live app's Teleop tab, its pure logic (app/_teleop.py; issue 29, the virtual master).

The handle is the master in the scene's (base) frame; every cycle goes through the one core
object, ``teleop.Teleop.step``. Checked here without a browser: the tip follows the handle
scaled and in the same direction, a re-clutch and a scale change move no tip (1e-12 m), a
NaN or a 1 m jump of the handle holds the robot with a flag, a paused master trips the
watchdog within one cycle of 30 ms, the e-stop holds, the cycles follow the app's clock, and
the fixtures and flags are what is drawn and shown. The Chromium test is in
test_app_browser.py.
"""

import math

import numpy as np
import pytest

import athenakin as ak
from athenakin.app import app_setup
from athenakin.app._teleop import (
    MAX_CYCLES,
    SHOWN_FLAGS,
    TELEOP_RATE,
    Master,
    TeleopFrame,
    clutch_closed,
    fixture_solids,
    hold_clutch,
    start_teleop,
    teleop_cycles,
    teleop_frame,
    teleop_html,
    teleop_scene,
    teleop_state,
)
from athenakin.collision import Environment
from athenakin.teleop import TeleopOptions, TeleopStatus

#: Largest tip jump on a re-clutch or a scale change (the issue), m.
JUMP_TOL = 1e-12
DT = 1.0 / TELEOP_RATE
#: Cycles for the tip to settle on a still target (tremor filter, velocity limit), at 100 Hz.
SETTLE = 200


@pytest.fixture(scope="module")
def setup():
    return app_setup(None, None, backend="numpy")


def _start(setup, **kw):
    return start_teleop(setup, setup.q_home, **kw)


def _run(tele, master, t, n):
    """``n`` cycles from time ``t``: (last command, time of the last cycle)."""
    cmd = None
    for k in range(0, n, MAX_CYCLES):                 # a loop on time: no backlog dropped
        cmd, t = teleop_cycles(tele, master, t, t + min(MAX_CYCLES, n - k) * DT)
    return cmd, t


def _moved(master, d):
    return Master(tuple(np.add(master.handle_b, d)), master.clutched, master.held,
                  master.paused)


def test_the_handle_starts_at_the_tip_and_the_tip_follows_it_scaled_in_the_scene_frame(setup):
    tele, m = _start(setup)
    T = setup.T_b_e
    tip_b = T[:3, :3] @ np.asarray(tele.tip) + T[:3, 3]
    np.testing.assert_allclose(m.handle_b, tip_b, rtol=0, atol=1e-15)
    assert tele.scale == 0.2 and tele.rate == TELEOP_RATE
    cmd, t = _run(tele, m, 0.0, 5)
    assert cmd.status == TeleopStatus.NONE
    d = np.array([0.01, -0.005, 0.004])              # the handle moves 1 cm in x (base)
    cmd, t = _run(tele, _moved(m, d), t, SETTLE)
    f = teleop_frame(tele, _moved(m, d), cmd)
    np.testing.assert_allclose(f.tip_b - tip_b, 0.2 * d, rtol=0, atol=1e-9)
    assert f.following and f.flags == () and not f.watchdog and not f.estop
    sol = ak.forward_kinematics(f.q, T, setup.design)     # the robot drawn at cmd.q
    np.testing.assert_allclose(sol.tip[f.slot], f.tip_b, rtol=0, atol=1e-9)


def test_reclutch_moves_no_tip_and_the_clutch_lets_the_handle_move_freely(setup):
    tele, m = _start(setup)
    cmd, t = _run(tele, m, 0.0, 5)
    open_ = Master(m.handle_b, clutched=True)
    assert not clutch_closed(open_)
    cmd, t = _run(tele, open_, t, 5)
    tip0 = cmd.tip
    far = Master(tuple(np.add(m.handle_b, [0.05, 0.0, 0.0])), clutched=True)
    for _ in range(10):                               # the handle goes 5 cm away, clutched
        cmd, t = _run(tele, far, t, 1)
        assert cmd.status & TeleopStatus.CLUTCHED and cmd.tip == tip0
    closed = Master(far.handle_b, clutched=False)
    cmd, t = _run(tele, closed, t, 1)                 # re-engage: no jump
    assert np.max(np.abs(np.subtract(cmd.tip, tip0))) <= JUMP_TOL
    assert not cmd.status & TeleopStatus.CLUTCHED
    cmd, t = _run(tele, closed, t, SETTLE)
    np.testing.assert_allclose(cmd.tip, tip0, rtol=0, atol=JUMP_TOL)


def test_a_held_clutch_stays_open_until_its_release_however_late_the_cycles_run(setup):
    """Held from the first hold message to the release: no time-out re-engages it, even
    when the loop runs its cycles seconds after the last hold message (a loaded server)."""
    tele, m = _start(setup)
    held = hold_clutch(m)
    assert held.held and not held.clutched and not clutch_closed(held)
    cmd, t = teleop_cycles(tele, held, 1.0 - 5 * DT, 1.0)
    assert cmd.status & TeleopStatus.CLUTCHED
    tip0 = cmd.tip
    far = _moved(held, [0.03, 0.0, 0.0])              # the handle moves while held
    cmd, t = _run(tele, far, t, 500)                  # 5 s of cycles, no new hold message
    assert cmd.status & TeleopStatus.CLUTCHED and cmd.tip == tip0
    assert teleop_state(teleop_frame(tele, far, cmd))[0] == "clutched"
    released = hold_clutch(far, held=False)
    assert not released.held and clutch_closed(released)
    cmd, t = _run(tele, released, t, 1)               # re-engage: no jump
    assert not cmd.status & TeleopStatus.CLUTCHED
    assert np.max(np.abs(np.subtract(cmd.tip, tip0))) <= JUMP_TOL
    toggled = hold_clutch(Master(m.handle_b, clutched=True, held=True), held=False)
    assert toggled.clutched and not clutch_closed(toggled)   # the toggle is kept


def _frame_with(flags, *, following=True):
    st = TeleopStatus(0)
    for n in flags:
        st |= TeleopStatus[n]
    z = np.zeros(3)
    return TeleopFrame(t=0.0, q=z, slot=0, tip_b=z, target_b=z, handle_b=z, status=st,
                       flags=tuple(n for n in SHOWN_FLAGS if n in flags), scale=0.2,
                       following=following, watchdog="WATCHDOG" in flags,
                       estop="ESTOP" in flags)


@pytest.mark.parametrize(("flags", "following", "word"), [
    ((), True, "following"),
    (("VELOCITY",), True, "limited by VELOCITY"),
    (("CLEARANCE", "HOLD"), True, "held by CLEARANCE"),
    (("FIXTURE", "CLEARANCE", "HOLD"), True, "held by FIXTURE CLEARANCE"),
    (("HOLD",), True, "held"),
    (("CLUTCHED", "HOLD"), False, "clutched"),
    ((), False, "paused"),
    (("WATCHDOG", "HOLD"), False, "WATCHDOG"),
    (("ESTOP", "WATCHDOG", "HOLD"), False, "E-STOP"),
    (("FAULT", "HOLD"), True, "FAULT"),
])
def test_the_state_word_says_what_the_robot_does(flags, following, word):
    """A guard holding the robot never reads "following" (CLEARANCE and HOLD lit)."""
    f = _frame_with(flags, following=following)
    assert teleop_state(f)[0] == word
    assert 'data-ro="teleop_state"' in teleop_html(f) and f">{word}</span>" in teleop_html(f)
    if word != "following":
        assert teleop_state(f)[1] != teleop_state(_frame_with(()))[1]


def test_a_scale_change_while_following_or_clutched_moves_no_tip(setup):
    tele, m = _start(setup)
    cmd, t = _run(tele, _moved(m, [0.01, 0.0, 0.0]), 0.0, SETTLE)
    moved = _moved(m, [0.01, 0.0, 0.0])
    tip0 = cmd.tip
    tele.set_scale(0.8)                               # as the slider does
    cmd, t = _run(tele, moved, t, SETTLE)
    np.testing.assert_allclose(cmd.tip, tip0, rtol=0, atol=JUMP_TOL)
    assert teleop_frame(tele, moved, cmd).scale == 0.8
    cmd, t = _run(tele, Master(moved.handle_b, clutched=True), t, 3)
    tele.set_scale(0.05)
    cmd, t = _run(tele, moved, t, SETTLE)
    np.testing.assert_allclose(cmd.tip, tip0, rtol=0, atol=JUMP_TOL)
    # after the change the tip follows at the new scale
    cmd, t = _run(tele, _moved(moved, [0.015, 0.0, 0.0]), t, SETTLE)
    T = setup.T_b_e
    dx = T[:3, :3] @ np.subtract(cmd.tip, tip0)
    np.testing.assert_allclose(dx, [0.05 * 0.015, 0.0, 0.0], rtol=0, atol=1e-9)


@pytest.mark.parametrize("bad", [(math.nan, 0.0, 0.0), (math.inf, 0.0, 0.0), (1e9, 0.0, 0.0)])
def test_a_nan_or_absurd_handle_is_held_with_a_flag(setup, bad):
    tele, m = _start(setup)
    cmd, t = _run(tele, m, 0.0, 5)
    q0, tip0 = cmd.q, cmd.tip
    cmd, t = _run(tele, Master(bad), t, 1)
    assert cmd.status & TeleopStatus.INVALID and cmd.q == q0 and cmd.tip == tip0
    cmd, t = _run(tele, Master(bad), t, 5)           # silent for 30 ms: the watchdog
    f = teleop_frame(tele, Master(bad), cmd)
    assert f.watchdog and "WATCHDOG" in f.flags and cmd.q == q0
    assert all(np.isfinite(cmd.q)) and all(np.isfinite(cmd.tip))
    cmd, t = _run(tele, m, t, 1)                      # the handle back: no jump
    np.testing.assert_allclose(cmd.tip, tip0, rtol=0, atol=JUMP_TOL)


def test_a_one_metre_jump_of_the_handle_reengages_without_moving_the_tip(setup):
    tele, m = _start(setup)
    cmd, t = _run(tele, m, 0.0, 5)
    tip0 = cmd.tip
    jumped = _moved(m, [1.0, 0.0, 0.0])
    cmd, t = _run(tele, jumped, t, 1)
    assert cmd.status & TeleopStatus.JUMP
    assert np.max(np.abs(np.subtract(cmd.tip, tip0))) <= JUMP_TOL
    cmd, t = _run(tele, jumped, t, SETTLE)
    np.testing.assert_allclose(cmd.tip, tip0, rtol=0, atol=JUMP_TOL)


def test_a_paused_master_trips_the_watchdog_within_one_cycle_of_30_ms(setup):
    tele, m = _start(setup)
    cmd, t_sample = _run(tele, m, 0.0, 5)
    paused = Master(m.handle_b, paused=True)
    seen = None
    for k in range(1, 10):
        cmd, t = _run(tele, paused, t_sample + (k - 1) * DT, 1)
        if cmd.status & TeleopStatus.WATCHDOG:
            seen = t - t_sample
            break
    watchdog = TeleopOptions().watchdog
    assert seen is not None and watchdog <= seen + 1e-12 <= watchdog + DT + 1e-12
    f = teleop_frame(tele, paused, cmd)
    assert f.watchdog and not f.following
    assert 'data-ro="teleop_state"' in teleop_html(f) and ">WATCHDOG</span> &middot;" in \
        teleop_html(f)
    cmd, t = _run(tele, m, t, 1)                      # resumed: held, then follows again
    assert not cmd.status & TeleopStatus.WATCHDOG


def test_the_estop_holds_until_released(setup):
    tele, m = _start(setup)
    cmd, t = _run(tele, m, 0.0, 5)
    cmd, t = _run(tele, _moved(m, [0.005, 0.0, 0.0]), t, 5)      # moving
    tele.estop()
    moved = _moved(m, [0.02, 0.0, 0.0])
    cmd, t = _run(tele, moved, t, SETTLE)
    f = teleop_frame(tele, moved, cmd)
    assert f.estop and "ESTOP" in f.flags and not f.following
    assert cmd.qd == (0.0, 0.0, 0.0)                  # braked to rest, held
    q_held, tip_held = cmd.q, cmd.tip
    cmd, t = _run(tele, _moved(moved, [0.01, 0.0, 0.0]), t, 5)
    assert cmd.q == q_held
    tele.release()
    cmd, t = _run(tele, moved, t, 1)                  # re-engages at the tip held
    np.testing.assert_allclose(cmd.tip, tip_held, rtol=0, atol=JUMP_TOL)
    assert not cmd.status & TeleopStatus.ESTOP


def test_the_cycles_follow_the_apps_clock_and_a_late_loop_drops_its_backlog(setup):
    tele, m = _start(setup)
    cmd, t = teleop_cycles(tele, m, 0.0, 0.5 * DT)
    assert cmd is None and t == 0.0                   # none due yet
    cmd, t = teleop_cycles(tele, m, 0.0, 3.5 * DT)
    assert t == pytest.approx(3 * DT, abs=1e-15) and cmd.t == pytest.approx(3 * DT, abs=1e-15)
    cmd, t2 = teleop_cycles(tele, m, t, t + 1.0)      # a second late: MAX_CYCLES, up to now
    assert t2 == pytest.approx(t + 1.0, abs=1e-12)
    assert cmd.t == pytest.approx(t2, abs=1e-12)
    assert not cmd.status & TeleopStatus.WATCHDOG     # the handle was sampled every cycle
    cmd, t3 = teleop_cycles(tele, m, t2, t2 + (MAX_CYCLES + 0.5) * DT)
    assert t3 == pytest.approx(t2 + MAX_CYCLES * DT, abs=1e-12)


def test_fixtures_are_drawn_and_keep_the_tip_out(setup):
    tele0, m0 = _start(setup)
    tip_b = np.asarray(m0.handle_b)
    box = np.eye(4)
    box[:3, 3] = tip_b + [0.0, 0.1, 0.0]
    env = (Environment().sphere(tip_b + [0.012, 0.0, 0.0], 0.005, name="vessel")
           .halfspace(tip_b + [0.0, 0.0, -0.05], [0.0, 0.0, 1.0], name="floor")
           .capsule(tip_b + [0.0, -0.1, 0.0], tip_b + [0.0, -0.1, 0.05], 0.01, name="tube")
           .box(box, [0.01, 0.02, 0.03], name="block"))
    solids = fixture_solids(env)
    assert [s.name for s in solids] == ["fixture_vessel", "fixture_floor", "fixture_tube",
                                        "fixture_block"]
    sphere = solids[0].vertices
    np.testing.assert_allclose(np.linalg.norm(sphere - (tip_b + [0.012, 0, 0]), axis=-1), 0.005,
                               rtol=0, atol=1e-6)
    np.testing.assert_allclose(solids[1].vertices[:, 2], tip_b[2] - 0.05, rtol=0, atol=1e-12)
    blk = solids[3].vertices
    np.testing.assert_allclose(blk.max(0) - blk.min(0), [0.02, 0.04, 0.06], rtol=0, atol=1e-12)
    assert fixture_solids(None) == ()
    tele, m = _start(setup, environment=env, options=TeleopOptions(feedforward=False,
                                                                   filter="none",
                                                                   backend="numpy",
                                                                   check_clearance=False))
    cmd, t = _run(tele, m, 0.0, 3)
    flags = TeleopStatus.NONE
    for k in range(SETTLE):                           # 2 cm of tip motion: into the vessel
        into = _moved(m, [0.1 * min(k / 100, 1.0), 0.0, 0.0])
        cmd, t = _run(tele, into, t, 1)
        flags |= cmd.status
        d = np.linalg.norm(teleop_frame(tele, into, cmd).tip_b - (tip_b + [0.012, 0, 0]))
        assert d >= 0.005                             # never inside
    assert flags & TeleopStatus.FIXTURE


def test_scene_and_html_show_the_tips_the_flags_and_the_state(setup):
    tele, m = _start(setup)
    cmd, t = _run(tele, m, 0.0, 3)
    f = teleop_frame(tele, m, cmd)
    sc = teleop_scene(f)
    assert sc.lines == () and sc.points[0].points.shape == (2, 3)    # tip on its target
    text = teleop_html(f)
    assert all(f'data-flag="{n}" data-on="0"' in text for n in SHOWN_FLAGS)
    assert 'data-ro="teleop_state"' in text and ">following</span>" in text
    assert f'data-v="{float(f.tip_b[0])!r}"' in text
    clutched = Master(m.handle_b, clutched=True)
    cmd, t = _run(tele, _moved(clutched, [0.01, 0, 0]), t, 3)
    f = teleop_frame(tele, clutched, cmd)
    assert 'data-flag="CLUTCHED" data-on="1"' in teleop_html(f) and ">clutched</span>" in \
        teleop_html(f)
    assert ">off</span>" in teleop_html(None) and "why" in teleop_html(None, note="why")


def test_start_refuses_a_tip_inside_a_fixture_with_a_named_error(setup):
    _, m = _start(setup)
    env = Environment().sphere(m.handle_b, 0.01, name="blob")
    with pytest.raises(ak.errors.InvalidInputError, match="blob"):
        _start(setup, environment=env)
    with pytest.raises(TypeError, match="options"):
        _start(setup, options={"scale": 1})
    tele, m = _start(setup)
    with pytest.raises(TypeError, match="tele"):
        teleop_cycles(object(), m, 0.0, 1.0)
    with pytest.raises(TypeError, match="master"):
        teleop_cycles(tele, (0.0, 0.0, 0.0), 0.0, 1.0)
    with pytest.raises(ak.errors.InvalidInputError, match="t_now"):
        teleop_cycles(tele, m, 0.0, math.nan)


def test_the_tab_in_process_starts_at_the_tip_and_stops_without_a_page():
    """The viser layer without a browser: start puts the master at the tip and hides the IK
    handle; with no page connected the loop stops at once (no master: no teleoperation)
    and says so; a tip inside a fixture is refused with the reason in the read-out."""
    pytest.importorskip("viser")
    import socket
    import time

    from athenakin.app import AthenaApp

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    app = AthenaApp(port=port, backend="numpy")
    try:
        tab = app.teleop
        assert not tab.running and 'data-ro="teleop_state">off' in tab.readout.content
        tip = app.view.readouts.tip_b.copy()
        tab.start()
        t0 = time.monotonic()
        while "stopped" not in tab.readout.content and time.monotonic() - t0 < 60:
            time.sleep(0.05)                          # the note is the last thing stop sets
        assert not tab.running and "stopped: the page closed" in tab.readout.content
        assert app.tip_handle.visible and tab.master is None
        app.bodies.environment = Environment().sphere(tip, 0.01, name="blob")
        tab.start()
        assert not tab.running and "cannot start" in tab.readout.content
        assert "blob" in tab.readout.content
    finally:
        app.stop()


def test_an_app_started_with_environment_and_bodies_files_uses_them(tmp_path, monkeypatch):
    """``AthenaApp(environment=FILE, bodies=FILE)`` (``athenakin app --environment ...``):
    the file's obstacles are in the clearance read-out and are the Teleop tab's fixtures,
    the file's radii are the bodies checked; in-process, no browser."""
    pytest.importorskip("viser")
    from athenakin.app import AthenaApp
    from athenakin.collision import Bodies

    setup = app_setup(None, None, backend="numpy")
    tip = setup.T_b_e[:3, :3] @ start_teleop(setup, setup.q_home)[0].tip + setup.T_b_e[:3, 3]
    u = (tip - setup.T_b_e[:3, 3]) / np.linalg.norm(tip - setup.T_b_e[:3, 3])
    env = (Environment().sphere(tip + 0.011 * u, 0.002, name="vessel")   # 9 mm past the tip
           .halfspace(tip - [0.0, 0.0, 0.2], [0.0, 0.0, 1.0], name="floor"))
    env_file, bodies_file = tmp_path / "anatomy.toml", tmp_path / "bodies.toml"
    env_file.write_text(env.to_toml())
    bodies_file.write_text(Bodies.default().with_radius({"instrument": 0.003}).to_toml())
    app = AthenaApp(port=0, backend="numpy", environment=str(env_file), bodies=bodies_file)
    try:
        assert app.bodies.environment == Environment.from_toml(env_file)   # the one place
        assert app.bodies.bodies.radius["instrument"] == 0.003
        np.testing.assert_allclose(app.view.readouts.tip_b, tip, rtol=0, atol=1e-12)
        bv = app.bodies.view                  # sphere 11 mm out, radii 2 + 3 mm: 6 mm clear
        assert bv.pair == ("instrument", "vessel") and not bv.colliding
        assert bv.clearance == pytest.approx(0.006, abs=1e-9)
        assert "instrument &ndash; vessel" in app.bodies.readout.content
        tab = app.teleop
        monkeypatch.setattr(app.server, "get_clients", lambda: {0: object()})  # a page open
        tab.start()
        try:
            assert tab.running, tab.readout.content
            fixtures = {n: h for n, h in tab._nodes.items() if n.startswith("fixture_")}
            assert sorted(fixtures) == ["fixture_floor", "fixture_vessel"]
            r = np.linalg.norm(np.asarray(fixtures["fixture_vessel"].vertices)
                               - (tip + 0.011 * u), axis=-1)
            np.testing.assert_allclose(r, 0.002, rtol=0, atol=1e-6)     # float32 vertices
        finally:
            tab.stop()
        assert not any(n.startswith("fixture_") for n in tab._nodes)
    finally:
        app.stop()


def test_app_collision_models_are_checked_before_the_server_starts(tmp_path, capsys):
    pytest.importorskip("viser")
    from athenakin.app import AthenaApp, launch

    bad = tmp_path / "bad.toml"
    bad.write_text('[[environment.obstacle]]\nkind = "sphere"\nradius = -1\n')
    with pytest.raises(FileNotFoundError, match="nope.toml"):
        launch(port=0, backend="numpy", environment=tmp_path / "nope.toml")
    with pytest.raises(ak.errors.InvalidInputError, match="bad.toml"):
        launch(port=0, backend="numpy", environment=bad)
    assert "ATHENA at" not in capsys.readouterr().out         # never served
    with pytest.raises(TypeError, match="environment: expected Environment, a TOML file"):
        AthenaApp(port=0, backend="numpy", environment={"sphere": 1})
    with pytest.raises(TypeError, match="bodies: expected Bodies"):
        AthenaApp(port=0, backend="numpy", bodies=3)
