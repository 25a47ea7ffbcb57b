"""The teleoperation loop with every guard on: bounded work, a pure tracker step, strict edges.

The loop's guarantees checked on its commands (strokes, limits, clearance by an independent
evaluation: :func:`athenakin.collision.clearance` at the commanded ``q``), the work per cycle
(at most ``CLEARANCE_EVALUATIONS`` clearance evaluations), and one regression test per edge
the loop used to get wrong (a frozen clock, a lax reset, a tip stuck in a fixture, an
unbounded scale, malformed clutches and samples, the singular set, unflagged short steps,
the tremor filter below its band rate).
"""

import math

import numpy as np
import pytest

import athenakin as ak
from athenakin.collision import Bodies, Environment, clearance
from athenakin.collision._workspace import ClearanceWorkspace
from athenakin.errors import InvalidInputError
from athenakin.motion import Tracker
from athenakin.teleop import Teleop, TeleopOptions, TeleopStatus, TremorFilter, filter_response
from athenakin.teleop._core import MAX_SCALE
from athenakin.teleop._filter import BAND_DB, BAND_RATES
from athenakin.teleop._fixtures import TipFixtures
from athenakin.teleop._limiter import CLEARANCE_EVALUATIONS

D = ak.Design.default()
T = ak.default_rcm_frame(D)
Q0 = (-0.1, 0.1, 0.45)
RATE = 1000.0
NOFF = TeleopOptions(feedforward=False)
#: Relative slack on the limits in the checks (the limits hold on the IK's floats).
LIMIT_RTOL = 1e-9
#: Agreement of the workspace's distances with collision.clearance, m.
DIST_TOL = 1e-12
#: Agreement of the numpy and the compiled guard's commands over a guarded stream, m.
BACKEND_TOL = 1e-6
S = TeleopStatus
_LIMITS = (S.STROKE | S.DEPTH | S.SINGULAR | S.FIXTURE | S.CLEARANCE | S.VELOCITY
           | S.ACCELERATION | S.HOLD | S.CLUTCHED | S.WATCHDOG | S.ESTOP)


def _tip_b(tip_e):
    return T[:3, :3] @ np.asarray(tip_e) + T[:3, 3]


def _environment():
    """A halfspace, a sphere and a box around the tip's workspace (none touching q0)."""
    tb = _tip_b((0.25, 0.0, 0.0))
    box = np.eye(4)
    box[:3, 3] = tb + np.array([0.0, 0.06, 0.0])
    return (Environment().halfspace(tb + np.array([0.0, 0.0, -0.06]), [0.0, 0.0, 1.0],
                                    name="floor")
            .sphere(tb + np.array([0.0, -0.05, -0.02]), 0.012, name="vessel")
            .box(box, [0.015, 0.01, 0.015], name="retractor"))


def _moving(k):
    s = k / RATE
    return (0.06 * math.sin(2 * math.pi * 0.7 * s), 0.05 * math.sin(2 * math.pi * 0.45 * s),
            0.04 * math.sin(2 * math.pi * 0.3 * s))


def _check(tele, cmds):
    """Strokes, velocity and acceleration limits, no NaN, on every command."""
    q = np.array([c.q for c in cmds])
    qd = np.array([c.qd for c in cmds])
    qdd = np.array([c.qdd for c in cmds])
    assert np.all(np.isfinite(q)) and np.all(np.isfinite(qd)) and np.all(np.isfinite(qdd))
    assert np.all(q >= np.asarray(D.stroke_min)) and np.all(q <= np.asarray(D.stroke_max))
    assert np.all(np.abs(qd) <= np.asarray(tele.v_max) * (1 + LIMIT_RTOL))
    assert np.all(np.abs(qdd) <= np.asarray(tele.a_max) * (1 + LIMIT_RTOL))


# --- item 1: the guard's work and its result -------------------------------------------
def test_every_guard_on_keeps_clearance_with_bounded_evaluations():
    env = _environment()
    tele = Teleop(ak.Robot(T, D, bodies=Bodies.default(D), environment=env), q0=Q0,
                  options=NOFF, scale=0.5)
    rng = np.random.default_rng(37)
    cmds, evals = [], []
    m = np.zeros(3)
    for k in range(1500):
        m = m + rng.normal(scale=0.002, size=3) if k % 300 < 150 else m + [0.0, 0.0, -0.001]
        cmds.append(tele.step(k / RATE, m.copy()))
        evals.append(tele.clearance_evaluations)
    _check(tele, cmds)
    assert max(evals) <= CLEARANCE_EVALUATIONS
    assert any(c.status & S.CLEARANCE or c.status & S.FIXTURE for c in cmds)   # it bit
    margin = tele.options.clearance_margin
    idx = np.arange(0, len(cmds), 7)
    for i in idx:                                       # an independent evaluation
        c = cmds[i]
        ref = clearance(c.q, T, D, slot=c.slot, bodies=Bodies.default(D), environment=env)
        assert float(ref.min_distance) >= margin * (1 - 1e-9)
        if c.clearance < tele.options.clearance_margin + 0.02:
            assert abs(c.clearance - float(ref.min_distance)) <= DIST_TOL


def test_the_guard_inactive_leaves_the_commands_of_the_plain_chain():
    """Far bodies and no fixtures: the same commands as without the check, to rounding."""
    plain = Teleop(T, D, q0=Q0, options=NOFF)
    far = Environment().sphere(_tip_b((0.25, 0.0, 0.0)) + np.array([0.0, 0.0, -2.0]), 0.01,
                               name="far")
    fx = TipFixtures(far)
    assert fx.nearest(tuple(_tip_b((0.25, 0.0, 0.0))))[0] > 1.0
    guarded = Teleop(ak.Robot(T, D, bodies=Bodies.default(D).with_excluded("platform"),
                              environment=far), q0=Q0, options=NOFF)
    for k in range(800):
        a, b = plain.step(k / RATE, _moving(k)), guarded.step(k / RATE, _moving(k))
        if b.status & S.CLEARANCE:     # the robot's own bodies may bind: stop comparing
            break
        assert a.q == b.q and a.status == b.status
    assert k > 100


def test_robot_and_frame_forms_give_the_same_commands():
    a = Teleop(ak.Robot(T, D), q0=Q0, options=NOFF)
    b = Teleop(T, D, q0=Q0, options=NOFF)
    for k in range(200):
        assert a.step(k / RATE, _moving(k)) == b.step(k / RATE, _moving(k))
    with pytest.raises(TypeError, match="design"):
        Teleop(ak.Robot(T, D), D, q0=Q0)
    with pytest.raises(TypeError, match="bodies"):
        Teleop(ak.Robot(T, D, bodies=Bodies.default(D)), q0=Q0, bodies=Bodies.default(D))


def test_tracker_candidate_is_pure_and_commit_takes_it():
    tr, ref = Tracker(T, D, q0=Q0), Tracker(T, D, q0=Q0)
    q = np.array(Q0)
    for _ in range(50):
        q = q + np.array([1e-4, -5e-5, 2e-4])
        before = tr.pose
        c1 = tr.candidate(q + 1e-3)                # a try that is not taken
        c = tr.candidate(q)
        assert tr.pose is before                   # nothing changed
        assert tr.commit(c) == ref.update(q) == tr.pose
        with pytest.raises(InvalidInputError, match="candidate"):
            tr.commit(c1)                          # computed from the previous state
    with pytest.raises(TypeError, match="candidate"):
        tr.commit((0, 1))


def test_workspace_distances_equal_clearance():
    env = _environment().capsule([0.3, -0.1, 0.0], [0.3, 0.1, 0.0], 0.01, name="rod")
    B = Bodies.default(D)
    ws = ClearanceWorkspace(B, env, backend="auto")
    ws_lb = ClearanceWorkspace(B, env, backend="auto", exact_below=0.01)
    rng = np.random.default_rng(1)
    from athenakin._mechanism import body_segments, mechanism_points

    n = 0
    while n < 25:
        q = np.array(Q0) + rng.normal(scale=0.03, size=3)
        seg = body_segments(mechanism_points(q, T, D, geometry=B.geometry))
        if not np.all(np.isfinite(seg)):
            continue
        n += 1
        ref = clearance(q, T, D, bodies=B, environment=env)
        d, k = ws.evaluate(seg)
        d_lb, _ = ws_lb.evaluate(seg)
        assert abs(d - float(ref.min_distance)) <= DIST_TOL
        for j, (a, b) in enumerate(ws.pairs):
            r = float(ref.distance(a, b))
            assert abs(ws.distances[j] - r) <= DIST_TOL
            # the broad phase: exact below its threshold, a lower bound above it
            assert ws_lb.distances[j] <= r + DIST_TOL
            if ws_lb.distances[j] < 0.01:
                assert abs(ws_lb.distances[j] - r) <= DIST_TOL
        assert d_lb <= d + DIST_TOL


def test_bodies_pair_tables_are_computed_once():
    b = Bodies.default(D)
    assert b.pairs is b.pairs and b.excluded_pairs is b.excluded_pairs
    assert b.pair_index is b.pair_index and not b.pair_index.flags.writeable
    c = Bodies.default(D)
    assert c == b and c.pairs == b.pairs
    e = b.with_excluded(("rail", "carrier"))
    assert ("rail", "carrier") not in e.pairs and len(e.pairs) == len(b.pairs) - 1


def test_control_loop_inverse_jacobian_is_the_analysis_one():
    pytest.importorskip("numba")
    from athenakin.analysis import tool_tip_inverse_jacobian
    from athenakin.fast import ControlLoop

    ctl = ControlLoop(T, D)
    rng = np.random.default_rng(3)
    for _ in range(20):
        q = np.array(Q0) + rng.normal(scale=0.02, size=3)
        for mode in (1, -1):
            want = tool_tip_inverse_jacobian(q, T, D, mode=mode, frame="rcm")
            got = ctl.tool_tip_inverse_jacobian(q, mode)
            np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())


# --- item 3: the loop's edges ---------------------------------------------------------
@pytest.mark.parametrize("frozen", ["none", "same_stamp"])
def test_watchdog_counts_cycles_whatever_the_clock(frozen):
    tele = Teleop(T, D, q0=Q0, options=NOFF)
    for k in range(100):
        tele.step(k / RATE, _moving(k))
    t_last = 99 / RATE
    trips = []
    for _ in range(1000):
        # the caller's clock stands still: the last stamp again, with no sample or the
        # latched topic's last message
        c = tele.step(t_last, None if frozen == "none" else _moving(99))
        trips.append(bool(c.status & S.WATCHDOG))
    first = trips.index(True)
    assert first + 1 == tele.watchdog_cycles == 30
    assert all(trips[first:])


def test_reset_is_as_strict_as_the_constructor_and_keeps_the_estop():
    env = Environment().sphere(_tip_b((0.25, 0.0, 0.0)) + np.array([0.0, 0.0, -0.03]), 0.01,
                               name="vessel")
    tele = Teleop(T, D, q0=Q0, options=NOFF, environment=env)
    before = tele.q
    with pytest.raises(InvalidInputError, match="slot"):
        tele.reset(Q0, slot=4)                      # the instrument behind the RCM
    with pytest.raises(ak.errors.StrokeLimitError, match="stroke"):
        tele.reset((0.2, 0.1, 0.45))                # outside the stroke, as the constructor
    with pytest.raises(ak.errors.StrokeLimitError, match="stroke"):
        Teleop(T, D, q0=(0.2, 0.1, 0.45))
    inside = ak.q_from_tool_tip(T, (0.25, 0.0, -0.03), D)[0]        # a tip 3 cm away
    env_in = Environment().sphere(_tip_b((0.25, 0.0, -0.03)), 0.01, name="organ")
    tele_in = Teleop(T, D, q0=Q0, options=NOFF, environment=env_in)
    with pytest.raises(InvalidInputError, match="forbidden region"):
        tele_in.reset(inside)                       # the tip inside a fixture
    with pytest.raises(InvalidInputError, match="singular set"):
        tele.reset((-D.l3, D.l3, 0.45))
    assert tele.q == before
    tele.estop()
    tele.reset(Q0)
    assert tele.estopped
    assert tele.step(0.0, (0.0, 0.0, 0.0)).status & S.ESTOP
    tele.release()
    assert not tele.step(0.001, (0.0, 0.0, 0.0)).status & S.ESTOP


def test_a_tip_inside_a_fixture_moves_outward():
    tele = Teleop(T, D, q0=Q0, options=NOFF)
    tip_b = _tip_b(tele.tip)
    center = tip_b + np.array([0.0, 0.0, 0.004])             # the tip 4 mm inside
    env = Environment().sphere(center, 0.008, name="organ")
    tele._fixtures = TipFixtures(env)                      # a fixture that appeared
    tele._has_fixtures = True
    tele._tip_fix = tele._fixtures.nearest(tuple(tip_b))
    out = (tip_b - center) / np.linalg.norm(tip_b - center)
    out_e = T[:3, :3].T @ out
    d0 = tele._fixtures.nearest(tuple(tip_b))[0]
    assert d0 < 0
    cmds = [tele.step(k / RATE, tuple(0.0005 * k * out_e)) for k in range(400)]
    d = [tele._fixtures.nearest(tuple(_tip_b(c.tip)))[0] for c in cmds]
    assert d[-1] > 0.0 > d0                                # out of it
    assert all(b >= a - 1e-12 for a, b in zip(d, d[1:], strict=False))   # never deeper


def test_scale_is_bounded():
    with pytest.raises(InvalidInputError, match="scale"):
        Teleop(T, D, q0=Q0, scale=1e300)
    tele = Teleop(T, D, q0=Q0, options=NOFF, scale=MAX_SCALE)
    with pytest.raises(InvalidInputError, match="scale"):
        tele.set_scale(MAX_SCALE * 1.01)
    tele.set_scale(0.1)
    assert tele.scale == 0.1


class _Raising:
    def __len__(self):
        return 3

    def __getitem__(self, i):
        raise RuntimeError("a driver's broken sample")


@pytest.mark.parametrize("clutch", [np.array([1, 0]), "yes", None, 2, np.array([True])])
def test_a_malformed_clutch_is_invalid_not_fault(clutch):
    tele = Teleop(T, D, q0=Q0, options=NOFF)
    tele.step(0.0, (0.0, 0.0, 0.0))
    c = tele.step(0.001, (0.01, 0.0, 0.0), clutch)
    assert c.status & S.INVALID and c.status & S.CLUTCHED and not c.status & S.FAULT
    assert tele.fault is None and c.tip == tele.tip


@pytest.mark.parametrize("sample", [b"abc", "123", [True, False, True], _Raising(),
                                    np.array(["1", "2", "3"]), np.zeros((3, 1)), (1.0, 2.0)])
def test_strings_bytes_and_broken_samples_are_no_master_positions(sample):
    tele = Teleop(T, D, q0=Q0, options=NOFF)
    tele.step(0.0, (0.0, 0.0, 0.0))
    c = tele.step(0.001, sample)
    assert c.status & S.INVALID and not c.status & S.FAULT and tele.fault is None


def test_q0_on_the_singular_set_is_refused_by_name():
    with pytest.raises(InvalidInputError, match="singular set"):
        Teleop(T, D, q0=(-D.l3, D.l3, 0.45))
    Teleop(T, D, q0=(-D.l3 + 1e-3, D.l3 - 1e-3, 0.45), options=NOFF)   # near it: accepted


def test_every_shortened_step_is_flagged():
    tele = Teleop(T, D, q0=Q0, options=NOFF, scale=1.0)
    rng = np.random.default_rng(5)
    m = np.zeros(3)
    for k in range(3000):
        m = m + rng.normal(scale=0.003, size=3)     # fast: most steps are limited
        c = tele.step(k / RATE, m.copy())
        if not c.status & _LIMITS and not c.status & S.JUMP:
            # a step that no limit shortened reaches its target
            assert np.abs(np.subtract(c.tip, c.target)).max() <= 1e-12


@pytest.mark.parametrize("name", ["notch8-12", "notch8-12-lp15"])
def test_the_tremor_filter_is_refused_below_its_band_rate(name):
    least = BAND_RATES[name]
    f = np.linspace(8.0, 12.0, 401)
    att = -20 * np.log10(np.abs(filter_response(name, least, f)))
    assert att.min() >= BAND_DB                         # the band holds at its rate
    below = -20 * np.log10(np.abs(filter_response(name, 100.0, f)))
    assert below.min() < BAND_DB                        # and is lost below it
    with pytest.raises(InvalidInputError, match="rate"):
        TremorFilter(name, least * 0.99)
    with pytest.raises(InvalidInputError, match="rate"):
        Teleop(T, D, q0=Q0, rate=100.0, options=TeleopOptions(filter=name))
    TremorFilter(name, least)
    Teleop(T, D, q0=Q0, rate=100.0, options=TeleopOptions(filter="none", feedforward=False,
                                                          stroke_margin=0.005))


def test_the_numpy_guard_equals_its_kernels():
    """The guard's numpy paths (segments, workspace, first-order limit) and its kernels, on
    the poses of a guarded stream (the commands themselves diverge by rounding where the
    robot chatters between braking and a limited step: a discontinuous map)."""
    pytest.importorskip("numba")
    from athenakin.teleop._guard import BodyGuard

    env = _environment()
    B = Bodies.default(D)
    tele = Teleop(ak.Robot(T, D, bodies=B, environment=env), q0=Q0, scale=1.0, options=NOFF)
    floor = tele._clear_floor
    gn = BodyGuard(D, T, B, env, backend="numpy", floor=floor)
    gc = BodyGuard(D, T, B, env, backend="numba", floor=floor)
    down = T[:3, :3].T @ np.array([0.0, 0.0, -0.001])
    poses, seen = [tele._pose], S.NONE
    for k in range(700):
        c = tele.step(k / RATE, tuple(down * k))
        poses.append(tele._pose)
        seen |= c.status
    assert seen & S.CLEARANCE
    gn.start(poses[0])
    gc.start(poses[0])
    n_limited = 0
    for k, (prev, pose) in enumerate(zip(poses, poses[1:], strict=False)):
        if k % 10 == 0:            # a step 30 times as long from the committed pose
            far = Tracker(T, D, q0=prev.q, slot=prev.slot).candidate(
                np.add(prev.q, 30.0 * np.subtract(pose.q, prev.q)))
            if far.valid:
                fn, fc = gn.fraction(far, floor, 1e-6), gc.fraction(far, floor, 1e-6)
                assert abs(fn - fc) <= 1e-9
                n_limited += fc < 1.0
        np.testing.assert_allclose(gn.segments(pose), gc.segments(pose), rtol=0, atol=DIST_TOL)
        dn, dc = gn.evaluate(pose), gc.evaluate(pose)
        assert abs(dn - dc) <= DIST_TOL
        gn.commit()
        gc.commit()
    assert n_limited > 0


def test_tip_fixtures_are_pinned_to_collision_and_coal():
    """Each fixture shape's signed distance of a point: a zero-length capsule's, in collision."""
    from athenakin.collision import capsule_capsule, capsule_halfspace

    env = _environment().capsule([0.3, -0.1, 0.0], [0.3, 0.1, 0.05], 0.01, name="rod")
    fx = TipFixtures(env)
    rng = np.random.default_rng(11)
    tb = _tip_b((0.25, 0.0, 0.0))
    worst = 0.0
    for x in tb + rng.normal(scale=0.05, size=(200, 3)):
        for s, o in zip(fx.shapes, env.obstacles, strict=True):
            d, _ = fx._one(s, tuple(x))
            if o.kind == "halfspace":
                ref = float(capsule_halfspace(x, x, 0.0, o.point, o.normal)[0])
            elif o.kind == "sphere":
                ref = float(capsule_capsule(x, x, 0.0, o.center, o.center, o.radius)[0])
            elif o.kind == "capsule":
                ref = float(capsule_capsule(x, x, 0.0, o.a, o.b, o.radius)[0])
            else:
                pytest.importorskip("coal")
                from athenakin.collision._coal import capsule_obstacle_distances

                ref = float(capsule_obstacle_distances(np.array([[x, x]]), 0.0, o)[0][0])
            worst = max(worst, abs(d - ref))
    assert worst <= 1e-9


def test_the_fixture_kernel_is_the_scalar_reference():
    pytest.importorskip("numba")
    env = _environment().capsule([0.3, -0.1, 0.0], [0.3, 0.1, 0.05], 0.01, name="rod")
    ref, fast = TipFixtures(env), TipFixtures(env, compiled=True)
    rng = np.random.default_rng(12)
    for x in _tip_b((0.25, 0.0, 0.0)) + rng.normal(scale=0.05, size=(300, 3)):
        d0, n0, i0 = ref.nearest(tuple(x))
        d1, n1, i1 = fast.nearest(tuple(x))
        assert i0 == i1 and abs(d0 - d1) <= 1e-15 and np.allclose(n0, n1, rtol=0, atol=1e-15)
