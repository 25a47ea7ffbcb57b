"""athenakin.teleop: the master mapping, the tremor filter and the safety layer (issue 29).

Each property is checked on the commands themselves: every cycle's ``q`` within the
stroke, ``|qd| <= v_max``, ``|qdd| <= a_max`` (to a relative 1e-9: the limits are
enforced on the IK's floats), the tip outside every forbidden region, the clearance
above its margin, nothing NaN. The 10^6-cycle version of the hostile streams is
``benchmarks/bench_teleop.py --hostile``.
"""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import athenakin as ak
from athenakin.collision import Bodies, Environment
from athenakin.teleop import (
    TREMOR_FILTERS,
    Teleop,
    TeleopOptions,
    TeleopStatus,
    filter_response,
)
from athenakin.teleop._fixtures import TipFixtures

D = ak.Design.default()
T = ak.default_rcm_frame(D)
Q0 = (-0.1, 0.1, 0.45)
TIP0 = np.array([0.25, 0.0, 0.0])
RATE = 1000.0
NOFF = TeleopOptions(feedforward=False)
#: Relative slack on the velocity and acceleration limits in the checks.
LIMIT_RTOL = 1e-9
#: Largest tip jump on a re-clutch or a scale change (the issue), m.
JUMP_TOL = 1e-12


def _tip_b(tip_e):
    return T[:3, :3] @ np.asarray(tip_e) + T[:3, 3]


def _env():
    """A vessel (sphere) 3 cm under the tip and a floor 6 cm under it (base frame)."""
    tb = _tip_b(TIP0)
    return (Environment().sphere(tb + np.array([0.0, 0.0, -0.03]), 0.01, name="vessel")
            .halfspace(tb + np.array([0.0, 0.0, -0.06]), [0.0, 0.0, 1.0], name="floor"))


def _run(tele, samples):
    return [tele.step(t, m, clutch=c) for t, m, c in samples]


def _check_commands(tele, cmds, *, fixtures=None):
    """Every command within the stroke, the limits, outside the fixtures; nothing NaN."""
    q = np.array([c.q for c in cmds])
    qd = np.array([c.qd for c in cmds])
    qdd = np.array([c.qdd for c in cmds])
    tip = np.array([c.tip for c in cmds])
    assert np.all(np.isfinite(q)) and np.all(np.isfinite(qd)) and np.all(np.isfinite(qdd))
    assert np.all(np.isfinite(tip))
    assert np.all(q >= np.asarray(D.stroke_min)) and np.all(q <= np.asarray(D.stroke_max))
    assert np.all(np.abs(qd) <= np.asarray(tele.v_max) * (1 + LIMIT_RTOL))
    assert np.all(np.abs(qdd) <= np.asarray(tele.a_max) * (1 + LIMIT_RTOL))
    assert not any(c.status & TeleopStatus.FAULT for c in cmds), tele.fault
    # q and qd are consistent: q_k = q_{k-1} + qd_k / rate
    np.testing.assert_allclose(np.diff(q, axis=0), qd[1:] / tele.rate, rtol=0, atol=1e-15)
    # the commanded tip is the forward kinematics of q on the tracked slot
    sol = ak.forward_kinematics(q, T, D)
    slot = np.array([c.slot for c in cmds])
    assert np.all(slot == slot[0])
    tb = sol.tip[np.arange(len(q)), slot]
    np.testing.assert_allclose(tb, (T[:3, :3] @ tip.T).T + T[:3, 3], rtol=0, atol=1e-9)
    if fixtures is not None:
        d = [fixtures.nearest(tuple(x))[0] for x in (T[:3, :3] @ tip.T).T + T[:3, 3]]
        assert min(d) >= 0.0
    return q, qd, qdd, tip


# --- the tremor filter ----------------------------------------------------------------
def test_tremor_filter_frequency_response():
    f_band = np.linspace(8.0, 12.0, 401)
    h = filter_response("notch8-12", RATE, f_band)
    assert -20 * np.log10(np.abs(h).max()) >= 20.0          # >= 20 dB over 8-12 Hz
    for f in (0.02, 0.1, 0.5, 1.0):                         # <= 10 ms below 1 Hz
        hf = filter_response("notch8-12", RATE, f)
        delay = -np.angle(hf) / (2 * np.pi * f)
        assert 0.0 <= delay <= 0.010, (f, delay)
        assert abs(abs(hf) - 1.0) <= 0.03
    f_all = np.logspace(-2, np.log10(RATE / 2 * 0.99), 3000)
    assert 20 * np.log10(np.abs(filter_response("notch8-12", RATE, f_all)).max()) < 1.5
    assert np.all(filter_response("none", RATE, f_all) == 1.0)
    assert set(TREMOR_FILTERS) == {"notch8-12", "notch8-12-lp15", "none"}


#: Frequency step of the central difference for the group delay, Hz.
GROUP_DF = 1e-4


def _delays(name, f):
    """Phase delay and group delay (s) of filter ``name`` at ``f`` Hz (central difference)."""
    h = filter_response(name, RATE, f)
    hm, hp = filter_response(name, RATE, f - GROUP_DF), filter_response(name, RATE, f + GROUP_DF)
    return -np.angle(h) / (2 * np.pi * f), -np.angle(hp / hm) / (2 * np.pi * 2 * GROUP_DF)


@settings(max_examples=200, deadline=None)
@given(st.floats(15.0, RATE / 2 * 0.999), st.floats(0.01, 1.0), st.floats(8.0, 12.0))
def test_lowpass_filter_rolls_off_above_the_band_without_delaying_slow_motion(f_hi, f_lo, f_band):
    """``notch8-12-lp15``: >= 20 dB over 8-12 Hz, >= 12 dB from 15 Hz and >= 20 dB from
    30 Hz up, and below 1 Hz a phase and a group delay in [0, 10 ms], gain within 3 %."""
    name = "notch8-12-lp15"
    att = -20 * np.log10(np.abs(filter_response(name, RATE, [f_band, f_hi])))
    assert att[0] >= 20.0
    assert att[1] >= (20.0 if f_hi >= 30.0 else 12.0), (f_hi, att[1])
    phase, group = _delays(name, f_lo)
    assert 0.0 <= phase <= 0.010 and -1e-4 <= group <= 0.010, (f_lo, phase, group)
    assert abs(abs(filter_response(name, RATE, f_lo)) - 1.0) <= 0.03


def test_lowpass_filter_frequency_response_on_a_grid():
    """The same bounds on dense grids (the property test draws points; this sweeps), and
    the notch's high band for contrast: it passes what lies above 15 Hz."""
    name = "notch8-12-lp15"
    f_hi = np.geomspace(15.0, RATE / 2 * 0.999, 2000)
    gain_db = 20 * np.log10(np.abs(filter_response(name, RATE, f_hi)))
    assert gain_db.max() <= -12.0 and gain_db[f_hi >= 30.0].max() <= -20.0
    assert 20 * np.log10(np.abs(filter_response("notch8-12", RATE, f_hi)).max()) > 0.0
    f_lo = np.geomspace(0.01, 1.0, 200)
    phase, group = _delays(name, f_lo)
    assert phase.max() <= 0.0085 and group.max() <= 0.0085 and group.min() >= -1e-4
    f_all = np.geomspace(0.01, RATE / 2 * 0.999, 3000)
    assert 20 * np.log10(np.abs(filter_response(name, RATE, f_all)).max()) < 3.0


def _fit(x, t, f):
    """Amplitude and phase of the component of ``x`` at ``f`` Hz (least squares)."""
    A = np.column_stack([np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t), np.ones_like(t)])
    c, *_ = np.linalg.lstsq(A, x, rcond=None)
    return math.hypot(c[0], c[1]), math.atan2(c[1], c[0])


@pytest.mark.parametrize("filt", ["notch8-12", "notch8-12-lp15"])
def test_tremor_is_attenuated_at_the_tip_command_and_slow_motion_is_not_delayed(filt):
    """10 Hz, 0.5 mm tremor on a 0.5 Hz motion of the master, through the whole chain."""
    tele = Teleop(T, D, q0=Q0, options=TeleopOptions(filter=filt, feedforward=False))
    n = 6000
    t = np.arange(n) / RATE
    motion = 0.02 * np.sin(2 * np.pi * 0.5 * t)
    tremor = 0.0005 * np.sin(2 * np.pi * 10.0 * t)
    cmds = _run(tele, [(t[k], (0.0, motion[k] + tremor[k], 0.0), True) for k in range(n)])
    _check_commands(tele, cmds)
    y = np.array([c.tip[1] for c in cmds])
    keep = t >= 2.0
    a_in, _ = _fit(tele.scale * tremor[keep], t[keep], 10.0)
    a_out, _ = _fit(y[keep], t[keep], 10.0)
    assert 20 * np.log10(a_in / a_out) >= 20.0
    m_in, ph_in = _fit(tele.scale * motion[keep], t[keep], 0.5)
    m_out, ph_out = _fit(y[keep], t[keep], 0.5)
    delay = (ph_in - ph_out) / (2 * np.pi * 0.5)
    assert 0.0 <= delay <= 0.010
    assert abs(m_out / m_in - 1.0) < 0.02
    assert not any(c.status for c in cmds[200:])      # the start-up transient only


# --- mapping: registration, clutch, scale -------------------------------------------------
def test_registration_rotates_the_master_into_the_rcm_frame():
    R = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])   # Rz(90 deg)
    tele = Teleop(T, D, q0=Q0, options=TeleopOptions(registration=R, filter="none",
                                                     feedforward=False))
    tele.step(0.0, (0.0, 0.0, 0.0))
    for k in range(1, 400):
        cmd = tele.step(k / RATE, (0.01 * min(k, 100) / 100, 0.0, 0.0))
    np.testing.assert_allclose(np.subtract(cmd.tip, TIP0), [0.0, 0.002, 0.0], atol=1e-12)
    assert cmd.status == TeleopStatus.NONE


def _moving(k):
    s = k / RATE
    return (0.02 * math.sin(2 * math.pi * 0.4 * s), 0.015 * math.sin(2 * math.pi * 0.3 * s),
            0.01 * math.sin(2 * math.pi * 0.2 * s))


def test_reclutch_does_not_move_the_tip():
    tele = Teleop(T, D, q0=Q0, options=NOFF)
    cmds = []
    k = 0
    for _ in range(500):
        cmds.append(tele.step(k / RATE, _moving(k)))
        k += 1
    for _ in range(300):                                       # clutch open: master roams
        cmds.append(tele.step(k / RATE, np.add(_moving(k), 0.05), clutch=False))
        k += 1
    assert cmds[-1].status & TeleopStatus.CLUTCHED
    before = cmds[-1].tip
    cmd = tele.step(k / RATE, np.add(_moving(k), 0.05), clutch=True)     # re-engage
    assert np.abs(np.subtract(cmd.target, before)).max() <= JUMP_TOL
    assert np.abs(np.subtract(cmd.tip, before)).max() <= JUMP_TOL
    cmds.append(cmd)
    for j in range(1, 300):                                   # and it follows again
        cmds.append(tele.step((k + j) / RATE, np.add(_moving(k + j), 0.05)))
    assert cmds[-1].status == TeleopStatus.NONE
    assert np.abs(np.subtract(cmds[-1].tip, cmds[-1].target)).max() < 1e-4
    _check_commands(tele, cmds)


@pytest.mark.parametrize("filt", ["none", "notch8-12", "notch8-12-lp15"])
def test_scale_change_does_not_move_the_target(filt):
    """The target after a scale change: the old target plus the new scale times the
    filtered master's advance (with the filter off and a master at rest: unchanged)."""
    tele = Teleop(T, D, q0=Q0, options=TeleopOptions(filter=filt, feedforward=False))
    cmds = []
    k = 0
    for new_scale in (0.5, 0.1, 0.3):
        for _ in range(300):
            cmds.append(tele.step(k / RATE, _moving(k)))
            k += 1
        m = _moving(k - 1)
        y_prev = tele._y                                       # the filtered master
        prev = cmds[-1]
        tele.set_scale(new_scale)
        again = tele.step(k / RATE, m)                         # the same sample again
        k += 1
        expect = np.add(prev.target, new_scale * np.subtract(tele._y, y_prev))
        assert np.abs(np.subtract(again.target, expect)).max() <= JUMP_TOL
        if filt == "none":
            assert np.abs(np.subtract(again.target, prev.target)).max() <= JUMP_TOL
        cmds.append(again)
    tele.step(k / RATE, (0.0, 0.0, 0.0), clutch=False)        # and while clutched
    tele.set_scale(0.7)
    cmd0 = tele.step((k + 1) / RATE, (0.0, 0.0, 0.0), clutch=False)
    cmd1 = tele.step((k + 2) / RATE, (0.0, 0.0, 0.0), clutch=True)
    assert np.abs(np.subtract(cmd1.target, cmd0.tip)).max() <= JUMP_TOL
    assert tele.scale == 0.7
    _check_commands(tele, cmds)


def test_watchdog_holds_within_one_cycle_of_30_ms_of_silence():
    tele = Teleop(T, D, q0=Q0, options=NOFF)
    k = 0
    for _ in range(300):
        tele.step(k / RATE, _moving(k))
        k += 1
    t_last = (k - 1) / RATE
    cmds = []
    while k / RATE < t_last + 0.2:
        cmds.append(tele.step(k / RATE, None))
        k += 1
    times = np.array([c.t for c in cmds])
    wd = np.array([bool(c.status & TeleopStatus.WATCHDOG) for c in cmds])
    first = int(np.argmax(wd))
    assert np.all(wd[first:]) and not np.any(wd[:first])
    assert times[first] - t_last >= 0.03 - 1e-12
    assert times[first] - t_last < 0.03 + 1.0 / RATE + 1e-12       # within one cycle
    held = [c for c in cmds[first:] if c.qd == (0.0, 0.0, 0.0)]
    assert held and held[-1].q == cmds[-1].q                          # at rest, held
    # the master returns elsewhere: it re-engages without a jump
    back = tele.step(k / RATE, (0.3, -0.2, 0.1))
    assert not back.status & TeleopStatus.WATCHDOG
    assert np.abs(np.subtract(back.target, cmds[-1].tip)).max() <= JUMP_TOL
    _check_commands(tele, cmds + [back])


def test_estop_brakes_and_holds_until_released():
    tele = Teleop(T, D, q0=Q0, options=NOFF)
    cmds = []
    for k in range(300):
        if k == 150:
            tele.estop()
        cmds.append(tele.step(k / RATE, _moving(k)))
    assert all(c.status & TeleopStatus.ESTOP for c in cmds[150:])
    assert cmds[-1].qd == (0.0, 0.0, 0.0) and cmds[-1].q == cmds[-2].q
    tele.release()
    nxt = tele.step(300 / RATE, _moving(300))
    assert not nxt.status & TeleopStatus.ESTOP
    assert np.abs(np.subtract(nxt.target, cmds[-1].tip)).max() <= JUMP_TOL
    _check_commands(tele, cmds + [nxt])


# --- hostile streams ----------------------------------------------------------------------
def test_garbage_never_raises_and_never_gives_nan():
    tele = Teleop(T, D, q0=Q0, options=NOFF)
    junk = [None, "abc", [1.0, 2.0], object(), (math.nan, 0.0, 0.0), (math.inf, 0, 0),
            (1e308, 1e308, 1e308), np.array([1.0, 2.0, 3.0, 4.0]), (1.0, 1.0, 1.0),
            {"x": 1}, (10**400, 0, 0), (0.0, 0.0, 0.0)]
    cmds = []
    for k in range(400):
        t = k / RATE if k % 37 else math.nan
        cmds.append(tele.step(t, junk[k % len(junk)], clutch=bool(k % 3)))
    flags = TeleopStatus(0)
    for c in cmds:
        flags |= c.status
    assert flags & TeleopStatus.INVALID and flags & TeleopStatus.JUMP
    _check_commands(tele, cmds)


def _hostile(seed, n):
    """Random walk with jumps, NaN, dropouts, far-away targets, clutch chatter."""
    rng = np.random.default_rng(seed)
    m = np.zeros(3)
    out = []
    for k in range(n):
        r = rng.random()
        if r < 0.02:
            m = m + rng.normal(scale=1.0, size=3)            # a metre-scale jump
        elif r < 0.03:
            out.append((k / RATE, (math.nan, 0.0, 0.0), True))
            continue
        elif r < 0.05:
            out.append((k / RATE, None, True))
            continue
        else:
            m = m + rng.normal(scale=0.003, size=3)           # fast wandering (3 m/s)
        out.append((k / RATE, m.copy(), bool(rng.random() > 0.05)))
    return out


@pytest.mark.parametrize("seed", [1, 2])
def test_hostile_streams_with_fixtures_and_clearance(seed):
    env = _env()
    tele = Teleop(T, D, q0=Q0, environment=env, bodies=Bodies.default(D), options=NOFF)
    cmds = _run(tele, _hostile(seed, 600))
    _check_commands(tele, cmds, fixtures=TipFixtures(env))
    assert min(c.clearance for c in cmds) >= tele.options.clearance_margin


def test_a_target_into_a_fixture_slides_on_it_and_never_enters():
    env = Environment().sphere(_tip_b(TIP0) + np.array([0.0, 0.0, -0.03]), 0.01, name="vessel")
    fx = TipFixtures(env)
    tele = Teleop(T, D, q0=Q0, environment=env,
                  options=TeleopOptions(feedforward=False, check_clearance=False))
    # the master pushes the tip straight down (base -z) through the vessel to a target 2 cm
    # beyond it: the tip meets the vessel and slides around it, never into it
    down_e = T[:3, :3].T @ np.array([0.0, 0.0, -1.0])
    side_e = T[:3, :3].T @ np.array([1.0, 0.0, 0.0])
    cmds = [tele.step(k / RATE, 0.4 * down_e * min(k, 800) / 800, True) for k in range(1200)]
    d = [fx.nearest(tuple(_tip_b(c.tip)))[0] for c in cmds]
    assert 0.0 <= min(d) <= tele.options.fixture_margin + 1e-3        # in contact, outside
    assert any(c.status & TeleopStatus.FIXTURE for c in cmds)
    # then sideways: the tip follows, never into the vessel
    rest = cmds[-1].tip
    for k in range(1200, 2400):
        m = 0.4 * down_e + 0.15 * side_e * min(k - 1200, 800) / 800
        cmds.append(tele.step(k / RATE, m, True))
    assert np.linalg.norm(np.subtract(cmds[-1].tip, rest)) > 0.005
    _check_commands(tele, cmds, fixtures=fx)


def test_targets_across_the_singular_set_and_out_of_the_workspace_are_limited():
    """Sweep the tip target far in every direction: the slot never changes, nothing NaN."""
    tele = Teleop(T, D, q0=Q0, options=TeleopOptions(feedforward=False, filter="none"))
    cmds = []
    k = 0
    for direction in ([0, 0, 1], [1, 0, 0], [0, -1, 0], [-1, 1, -1]):
        d = np.asarray(direction, float)
        for j in range(1000):
            cmds.append(tele.step(k / RATE, 2.0 * d * min(j, 700) / 700))
            k += 1
        cmds.append(tele.step(k / RATE, None, clutch=False))      # re-centre the master
        k += 1
    _check_commands(tele, cmds)
    flags = TeleopStatus(0)
    for c in cmds:
        flags |= c.status
    assert flags & (TeleopStatus.SINGULAR | TeleopStatus.STROKE)
    assert flags & TeleopStatus.DEPTH


_sample = st.one_of(
    st.none(),
    st.tuples(*[st.floats(-0.3, 0.3, allow_nan=False)] * 3),
    st.tuples(*[st.floats(allow_nan=True, allow_infinity=True)] * 3),
)


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(_sample, st.booleans(), st.integers(1, 30)), min_size=1, max_size=8))
def test_hypothesis_streams_never_violate(events):
    """Piecewise-constant hostile master streams (a value held for 1-30 cycles), fixtures on."""
    env = _env()
    tele = Teleop(T, D, q0=Q0, environment=env,
                  options=TeleopOptions(feedforward=False, check_clearance=False))
    cmds = []
    k = 0
    for m, clutch, n in events:
        for _ in range(n):
            cmds.append(tele.step(k / RATE, m, clutch))
            k += 1
    _check_commands(tele, cmds, fixtures=TipFixtures(env))


# --- construction -------------------------------------------------------------------------
def test_bad_construction_is_named():
    with pytest.raises(ak.InvalidInputError, match="registration"):
        TeleopOptions(registration=np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(ValueError, match="filter"):
        TeleopOptions(filter="butter")
    with pytest.raises(ak.InvalidInputError, match="stroke_margin"):
        Teleop(T, D, q0=Q0, a_max=0.1, options=NOFF)
    with pytest.raises(ak.InvalidInputError, match="forbidden"):
        env = Environment().sphere(_tip_b(TIP0), 0.01, name="blob")
        Teleop(T, D, q0=Q0, environment=env, options=NOFF)
    with pytest.raises(ak.InvalidInputError, match="scale"):
        Teleop(T, D, q0=Q0, scale=-1.0, options=NOFF)
    with pytest.raises(TypeError, match="options"):
        Teleop(T, D, q0=Q0, options={"filter": "none"})


def test_feedforward_forces_are_the_inverse_dynamics():
    from athenakin.dynamics import inverse_dynamics

    tele = Teleop(T, D, q0=Q0)
    cmds = [tele.step(k / RATE, _moving(k)) for k in range(60)]
    cmds += [tele.step((60 + k) / RATE, None if k > 40 else _moving(60), clutch=False)
             for k in range(200)]                       # brake, then held at rest (cached)
    assert cmds[-1].qd == (0.0, 0.0, 0.0) and cmds[-2].qd == (0.0, 0.0, 0.0)
    for c in cmds[::20] + cmds[-3:]:
        ref = inverse_dynamics(c.q, c.qd, c.qdd, T, D, slot=c.slot)
        np.testing.assert_allclose(c.forces, ref, rtol=0, atol=1e-9)


def test_docstring_examples():
    import doctest
    import importlib

    mod = importlib.import_module("athenakin.teleop._core")
    assert doctest.testmod(mod, optionflags=doctest.ELLIPSIS).failed == 0


def _run_sampled(master_hz):
    tele = Teleop(T, D, q0=Q0, options=TeleopOptions(feedforward=False))
    every = int(RATE / master_hz)
    limited, tips = 0, []
    for k in range(3000):
        t = k / RATE
        m = (0.03 * math.sin(2 * math.pi * 0.5 * t), 0.0, 0.0) if k % every == 0 else None
        cmd = tele.step(t, m)
        assert not cmd.status & TeleopStatus.WATCHDOG
        limited += bool(cmd.status & (TeleopStatus.ACCELERATION | TeleopStatus.HOLD))
        tips.append(cmd.tip)
    return limited, np.array(tips)


@pytest.mark.parametrize("master_hz", [100.0, 250.0])
def test_a_master_slower_than_the_loop_moves_the_tip_smoothly(master_hz):
    """A 100 Hz master on the 1 kHz loop: the filter takes the master interpolated between
    its samples (one master interval late), so the tip moves as with a 1 kHz master instead
    of the limit-and-hold stutter of a staircase (the first version flagged ACCELERATION or
    HOLD in 80 % of the cycles of a 100 Hz recording)."""
    limited_fast, tips_fast = _run_sampled(RATE)
    limited, tips = _run_sampled(master_hz)
    assert limited <= limited_fast + 5
    step = np.linalg.norm(np.diff(tips, axis=0), axis=1)
    v_tip = 0.2 * 0.03 * 2 * math.pi * 0.5 / RATE      # the scaled master's peak step, m
    assert step.max() < 1.5 * v_tip
    lag = 1.0 / master_hz                              # the interpolation's delay
    shift = int(round(lag * RATE))
    np.testing.assert_allclose(tips[1000 + shift:2500 + shift], tips_fast[1000:2500],
                               rtol=0, atol=2e-5)
