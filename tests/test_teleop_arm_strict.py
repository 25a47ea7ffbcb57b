"""SimulatedArm refuses what the core refuses: servo checks, force bound, faults, CRTK states.

Each test is a regression of a finding: a servo setpoint beyond the strokes or with the
carriages reversed reached the backend, 1 MN of effort was applied, fixed gains went
unstable with other mass models and rates while the arm stayed ENABLED, a driver's bad
reading crashed ``step``, ``DISABLED`` kept writing forces, the arm started ENABLED.
"""

import math

import numpy as np
import pytest

import athenakin as ak
from athenakin.errors import InvalidInputError, KinematicsError

pytest.importorskip("mujoco")

from athenakin.dynamics import MassModel  # noqa: E402
from athenakin.dynamics._model import MASS_BODIES  # noqa: E402
from athenakin.teleop import ServoGains, SimulatedArm  # noqa: E402
from athenakin.teleop._arm import MAX_STEPS  # noqa: E402
from athenakin.teleop._arm_backend import CLOSURE_TOL  # noqa: E402
from athenakin.teleop._arm_checks import READING_MARGIN  # noqa: E402
from athenakin.teleop._servo import MAX_FORCE  # noqa: E402

D = ak.Design.default()
T = ak.default_rcm_frame(D)
Q0 = np.array([-0.1, 0.1, 0.45])
GOAL = Q0 + np.array([0.01, -0.01, 0.02])
#: A goal one cycle of the ideal driver reaches at a plausible speed (1-2 m/s).
NEAR = Q0 + np.array([0.001, -0.001, 0.002])


class _Driver:
    """A lab's driver: an ideal position actuator that records every write."""

    def __init__(self, q, *, reading=None):
        self.q, self.qd = np.array(q, float), np.zeros(3)
        self.forces, self.positions = [], []
        self.reading = reading

    def read_encoders(self):
        if self.reading is not None:
            return self.reading
        return self.q.copy(), self.qd.copy()

    def write(self, forces, positions):
        self.forces.append(np.array(forces, float))
        self.positions.append(np.array(positions, float))
        if np.all(np.isfinite(positions)):
            self.qd = (positions - self.q) * 1000.0
            self.q = np.array(positions, float)
        else:
            self.qd = np.zeros(3)


class _HomingDriver(_Driver):
    def __init__(self, q):
        super().__init__(q)
        self.homed = 0

    def home(self):
        self.homed += 1


def _enabled(**kw):
    arm = SimulatedArm(T, D, q0=Q0, **kw)
    arm.enable()
    return arm


# --- servo_jp / servo_cp: hold and flag ---------------------------------------------------
@pytest.mark.parametrize("q, velocity, effort, words", [
    ([-0.1, 0.1, 0.9], None, None, "stroke"),                  # q3 11 cm past its stroke
    ([0.1, -0.1, 0.45], None, None, "wrong order"),            # the carriages reversed
    ([np.nan, 0.1, 0.45], None, None, "finite"),
    (Q0, [np.inf, 0.0, 0.0], None, "velocity"),
    (Q0, [5.0, 0.0, 0.0], None, "v_max 0.1 m/s"),              # 50x the arm's v_max
    (Q0, [0.0, -1e308, 0.0], None, "v_max 0.1 m/s"),           # not "does not assemble"
    (Q0, None, [1e6, 0.0, 0.0], "max_force"),                  # 1 MN
    (Q0, None, [np.nan, 0.0, 0.0], "max_force"),
])
def test_servo_jp_holds_and_flags_what_the_core_refuses(q, velocity, effort, words):
    drv = _Driver(Q0)
    arm = SimulatedArm(T, D, q0=Q0, backend=drv)
    arm.enable()
    arm.servo_jp(NEAR, velocity=[0.01, 0.0, 0.0])
    arm.step(1)
    arm.servo_jp(q, velocity=velocity, effort=effort)
    assert arm.refusal is not None and words in arm.refusal
    sp = arm.setpoint_js()
    np.testing.assert_array_equal(sp.position, NEAR)            # held where it was, at rest
    np.testing.assert_array_equal(sp.velocity, 0.0)
    arm.step(3)
    assert np.all(np.abs(np.array(drv.forces)) <= MAX_FORCE)
    assert np.all(np.isfinite(drv.positions[-1]))
    for p in drv.positions:
        assert np.all(p >= D.stroke_min) and np.all(p <= D.stroke_max)
    arm.servo_jp(Q0)
    assert arm.refusal is None                                  # an accepted command clears it


def test_position_refusal_agrees_with_the_modules_actuator_checks():
    """The servo's check of one triple gives the reason the module's numpy checks give."""
    from athenakin.parallel._module import _actuator_checks
    from athenakin.teleop._arm_checks import position_refusal

    rng = np.random.default_rng(37)
    span = D.stroke_max - D.stroke_min
    q = D.stroke_min - 0.1 * span + 1.2 * span * rng.random((400, 3))
    edges = np.array([D.stroke_min, D.stroke_max, [np.nan, 0.1, 0.45], [-0.1, np.inf, 0.45],
                      [-0.1, 0.1, -np.inf], [0.1, 0.1, 0.45], [0.1, -0.1, 0.45],
                      [np.nan, np.nan, 9.0]])
    words = {0: None, 1: "finite", 2: "stroke", 3: "wrong order"}
    for x in np.concatenate([q, edges]):
        code = int(_actuator_checks(x, D))
        reason = position_refusal(x, D, "q")
        if words.get(code) is None:
            assert reason is None, (x, code, reason)
        else:
            assert reason is not None and words[code] in reason, (x, code, reason)


def test_servo_jp_refuses_a_setpoint_that_does_not_assemble():
    arm = _enabled(backend=_Driver(Q0))
    far = np.array([-0.29338895, 0.2253081, 0.65637779])   # within the strokes, off slot 0
    assert np.isnan(ak.dynamics.inverse_dynamics(far, np.zeros(3), np.zeros(3), T, D,
                                                 errors="flag")).all()
    arm.servo_jp(far)
    assert "does not assemble" in arm.refusal


def test_servo_cp_flags_a_tip_out_of_reach_and_raises_for_a_bad_shape():
    arm = _enabled(backend=_Driver(Q0))
    arm.servo_cp([5.0, 0.0, 0.0], frame="rcm")
    assert "out of reach" in arm.refusal
    with pytest.raises(InvalidInputError, match=r"\btip\b"):
        arm.servo_cp([0.1, 0.2])
    with pytest.raises(InvalidInputError, match=r"\bq\b"):
        arm.servo_jp([0.1, 0.2])


def test_the_servo_force_saturates_at_max_force():
    arm = _enabled(max_force=20.0)
    arm.servo_jp(Q0 + np.array([0.05, 0.0, 0.0]))       # 5 cm step: Kp e ~ 1.7 kN unbounded
    arm.step(1)
    assert arm.saturated
    js, sp = arm.measured_js(), arm.setpoint_js()
    assert np.abs(js.effort).max() == pytest.approx(20.0, rel=1e-12)
    np.testing.assert_array_equal(sp.effort, js.effort)          # the applied effort, CRTK
    arm.step(2000)
    assert arm.operating_state == "ENABLED" and not arm.saturated
    np.testing.assert_allclose(arm.measured_js().position, Q0 + [0.05, 0, 0], atol=1e-5)


@pytest.mark.parametrize("jump", [[0.0, 0.0, 0.12], [-0.12, 0.0, 0.0], [0.03, -0.05, 0.1]])
def test_a_far_servo_setpoint_is_approached_at_v_max_not_faster(jump):
    """A servo jump of 12 cm: the plain PD law drove the carriages at 3.5 m/s (35 v_max)
    and the loop closure opened past CLOSURE_TOL (FAULT); the velocity-bounded law
    approaches at v_max, the loop stays closed to a tenth of CLOSURE_TOL, the arm arrives."""
    arm = _enabled()
    goal = Q0 + np.array(jump)
    arm.servo_jp(goal)
    assert arm.refusal is None
    v_max = arm.limits[0]
    n = int(1.5 * np.abs(jump).max() / v_max * arm.rate) + 500
    peak = closure = 0.0
    for _ in range(n):
        arm.step(1)
        peak = max(peak, float(np.abs(arm.measured_js().velocity).max()))
        closure = max(closure, arm.backend.closure_error())
        assert arm.operating_state == "ENABLED", arm.fault
    assert 0.9 * v_max < peak <= 1.05 * v_max         # at v_max; the overshoot of the lag
    assert closure < 0.1 * CLOSURE_TOL
    np.testing.assert_allclose(arm.measured_js().position, goal, atol=1e-5)


@pytest.mark.parametrize("axis, end, sign", [(2, "stroke_max", 1.0), (0, "stroke_min", -1.0)])
def test_the_full_force_into_a_stroke_end_stays_within_the_reading_margin(axis, end, sign):
    """MuJoCo's default (soft) joint limit let max_force push a carriage 5 mm past its
    stroke end: FAULT, and no enable() could clear it (the brakes held it there). The
    backend's stroke ends are as stiff as its loop closures: under max_force for 3 s the
    carriage stays within a tenth of READING_MARGIN, the arm ENABLED."""
    arm = _enabled()
    q = Q0.copy()
    q[axis] = getattr(D, end)[axis]
    effort = np.zeros(3)
    effort[axis] = sign * arm.max_force
    arm.servo_jp(q, effort=effort)
    assert arm.refusal is None
    past = 0.0
    for _ in range(3000):
        arm.step(1)
        assert arm.operating_state == "ENABLED", arm.fault
        past = max(past, sign * (arm.measured_js().position[axis] - q[axis]))
    assert past < 0.1 * READING_MARGIN


#: A setpoint near the internal tangency of the module (w = 0, q3 in [0.2315, 0.2546] m),
#: beside one of a seeded random stream: its inverse dynamics at rest is 132 N on q3 (the
#: mass matrix grows without bound towards the tangency; 0.1 mm lower it does not assemble).
NEAR_TANGENCY = [-0.27836, 0.04771, 0.2421]


def test_a_setpoint_the_actuators_cannot_follow_is_held_and_flagged():
    """Accepted before: a setpoint of the seeded stream there had a feed-forward of -730 N,
    clipped to max_force, that threw the carriages at 2.4 m/s into the tangency. The arm
    refuses a setpoint whose inverse dynamics exceeds max_force, and a velocity jumped to in
    one cycle (an acceleration beyond the actuators); it takes the same velocity reached
    over 0.2 s."""
    arm = _enabled()
    arm.servo_jp(NEAR_TANGENCY)
    assert arm.refusal is not None and "beyond max_force" in arm.refusal
    np.testing.assert_array_equal(arm.setpoint_js().position, Q0)
    arm.servo_jp(NEAR, velocity=[0.08, 0.0, 0.0])          # from rest within one cycle
    assert arm.refusal is not None and "beyond max_force" in arm.refusal
    arm.step(200)
    arm.servo_jp(NEAR, velocity=[0.08, 0.0, 0.0])
    assert arm.refusal is None
    arm.step(400)
    assert arm.operating_state == "ENABLED"


def test_a_move_into_what_the_actuators_cannot_follow_stops_and_holds():
    """A planned move towards the tangency stops where its profile's inverse dynamics
    passes max_force, held and flagged, the arm ENABLED."""
    arm = _enabled()
    arm.move_jp(NEAR_TANGENCY)
    for _ in range(5000):
        arm.step(1)
        assert arm.operating_state == "ENABLED", arm.fault
        if not arm.is_busy:
            break
    assert arm.refusal is not None and "cannot be followed" in arm.refusal
    assert "beyond max_force" in arm.refusal
    np.testing.assert_array_equal(arm.setpoint_js().velocity, np.zeros(3))


def test_a_servo_commands_acceleration_lasts_the_span_it_was_differenced_over():
    """A client slower than the servo: the acceleration is the velocity's change over the
    time since the setpoint was set, applied for as long; before, it was differenced over
    one cycle and held until the next command (10x too large at 100 Hz, and for ever)."""
    from athenakin.dynamics import InverseDynamicsLoop

    arm = _enabled(backend=_Driver(Q0))
    loop = InverseDynamicsLoop(T, D, masses=arm.masses)
    arm.step(10)
    v = np.array([0.02, -0.01, 0.03])
    arm.servo_jp(NEAR, velocity=v)
    with_acc = loop(NEAR, v, v / (10 * arm.dt)).copy()
    without = loop(NEAR, v, np.zeros(3)).copy()
    for k in range(15):
        np.testing.assert_allclose(arm.feedforward_effort, with_acc if k < 10 else without,
                                   rtol=1e-12, atol=1e-12 * np.abs(with_acc).max())
        arm.step(1)
    arm.servo_jp(NEAR, velocity=v)                          # no change of velocity: qdd 0
    np.testing.assert_allclose(arm.feedforward_effort, without, rtol=1e-12, atol=1e-12)


def test_random_far_servo_commands_never_fault_the_arm():
    """A seeded stream of setpoints anywhere in the strokes, some with a velocity, each held
    50-400 cycles: before, the arm faulted at the first (a loop-closure error), then threw
    the carriages into the tangency at 2-4 m/s; now every accepted one keeps it ENABLED with
    the loop closed to a tenth of CLOSURE_TOL."""
    rng = np.random.default_rng(3)
    lo, hi = np.asarray(D.stroke_min), np.asarray(D.stroke_max)
    arm = _enabled()
    accepted = closure = 0.0
    for _ in range(60):
        q = lo + (hi - lo) * rng.random(3)
        v = rng.uniform(-0.1, 0.1, 3) * (rng.random() < 0.5)
        arm.servo_jp(q, velocity=v)
        if arm.refusal is not None:
            continue
        accepted += 1
        for _ in range(int(rng.integers(50, 400))):
            arm.step(1)
            assert arm.operating_state == "ENABLED", arm.fault
            closure = max(closure, arm.backend.closure_error())
    assert accepted >= 30 and closure < 0.1 * CLOSURE_TOL


def test_a_saturated_servo_force_keeps_the_pd_direction():
    """Clipping each component of a coupled PD force alone turns it (the acceleration
    M^-1 f can point away from the setpoint); the saturated force is ff + s pd, s in [0, 1],
    its largest component at max_force."""
    from athenakin.teleop._servo import approach_gain, pd_force

    rng = np.random.default_rng(11)
    arm = _enabled(backend=_Driver(Q0))
    L = approach_gain(arm.kp, arm.kd)
    for _ in range(50):
        ff = rng.uniform(-20, 20, 3)
        q_sp, q = Q0 + 0.05 * rng.normal(size=3), Q0 + 0.05 * rng.normal(size=3)
        qd = rng.normal(size=3)
        plain, _ = pd_force(ff, arm.kp, arm.kd, q_sp, np.zeros(3), q, qd, math.inf,
                            L=L, v_max=0.1)
        f, saturated = pd_force(ff, arm.kp, arm.kd, q_sp, np.zeros(3), q, qd, 50.0,
                                L=L, v_max=0.1)
        assert np.abs(f).max() <= 50.0
        if saturated:
            pd, part = plain - ff, f - ff
            s = np.dot(part, pd) / np.dot(pd, pd)
            assert 0.0 <= s <= 1.0
            np.testing.assert_allclose(part, s * pd, atol=1e-9 * np.abs(pd).max())
            assert np.abs(f).max() == pytest.approx(50.0, rel=1e-12)


def test_the_velocity_bound_leaves_a_near_setpoint_to_the_plain_pd_law():
    """Below v_max the bounded law is the PD law bit for bit; above it the approach
    velocity (on top of the setpoint's own) is scaled to v_max with its direction kept."""
    from athenakin.teleop._servo import approach_gain, pd_force

    rng = np.random.default_rng(7)
    arm = _enabled()
    L = approach_gain(arm.kp, arm.kd)
    assert L is not None
    np.testing.assert_allclose(arm.kd @ L, arm.kp, rtol=1e-12, atol=1e-9 * np.abs(arm.kp).max())
    for _ in range(50):
        ff, q, qd = rng.normal(size=3), Q0 + 1e-4 * rng.normal(size=3), 0.01 * rng.normal(size=3)
        sp, spd = Q0 + 1e-4 * rng.normal(size=3), 0.01 * rng.normal(size=3)
        plain = pd_force(ff, arm.kp, arm.kd, sp, spd, q, qd, math.inf)
        bounded = pd_force(ff, arm.kp, arm.kd, sp, spd, q, qd, math.inf, L=L, v_max=0.1)
        np.testing.assert_array_equal(bounded[0], plain[0])
        far = Q0 + 0.1 * rng.normal(size=3)
        f, _ = pd_force(ff, arm.kp, arm.kd, far, spd, q, qd, math.inf, L=L, v_max=0.1)
        v_cmd = np.linalg.solve(arm.kd, f - ff) + qd - spd   # the approach it servoes to
        v_corr = L @ (far - q)
        np.testing.assert_allclose(np.abs(v_cmd).max(), 0.1, rtol=1e-9)
        np.testing.assert_allclose(v_cmd / np.linalg.norm(v_cmd),
                                   v_corr / np.linalg.norm(v_corr), atol=1e-9)
    assert approach_gain(arm.kp, np.zeros((3, 3))) is None    # kd = 0: no approach velocity


# --- stability for every mass model and rate the constructor accepts ---------------------
_RODS = {b: 0.1 for b in MASS_BODIES if b != "rail"}


@pytest.mark.parametrize("masses, rate", [
    (None, 1000.0), (None, 250.0), (None, 100.0), (None, 4000.0),
    ("rods", 1000.0), ("rods", 250.0),
])
def test_the_servo_is_stable_for_accepted_masses_and_rates(masses, rate):
    mm = MassModel.slender_rods(_RODS, D) if masses == "rods" else None
    arm = _enabled(masses=mm, rate=rate)
    arm.servo_jp(GOAL)
    closure = 0.0
    for _ in range(int(rate)):                          # one second
        arm.step(1)
        closure = max(closure, arm.backend.closure_error())
        assert arm.operating_state == "ENABLED", arm.fault
    assert closure <= CLOSURE_TOL / 10                  # the backend's stated accuracy
    np.testing.assert_allclose(arm.measured_js().position, GOAL, atol=1e-5)


@pytest.mark.parametrize("kw, words", [
    ({"masses": MassModel.zeros()}, "mass matrix"),
    ({"masses": MassModel.slender_rods({"carriage_a": 0.3, "carriage_b": 0.3,
                                        "actuator": 0.2, "platform": 0.05}, D)}, "'q3'"),
    ({"rate": 250.0, "gains": ServoGains(kp=4e4, kd=800.0)}, "unstable"),
    ({"rate": 5.0}, "10 Hz"),
    ({"q0": [-0.1, 0.1, 0.9]}, "stroke"),
    ({"q0": [0.1, -0.1, 0.45]}, "order"),
])
def test_what_cannot_be_servoed_stably_is_refused_by_name(kw, words):
    with pytest.raises(InvalidInputError, match=words):
        SimulatedArm(T, D, **{"q0": Q0, **kw})


# --- faults within one cycle, never a silent reset ---------------------------------------
def test_a_mujoco_instability_faults_the_arm_in_that_cycle():
    arm = _enabled()
    arm.step(5)
    arm.backend.data.qvel[:] = 1e30                     # MuJoCo warns and resets its state
    arm.step(1)
    assert arm.operating_state == "FAULT"
    assert "unstable" in arm.fault
    arm.step(3)                                         # FAULT writes no force
    np.testing.assert_array_equal(arm.measured_js().effort, 0.0)
    np.testing.assert_array_equal(arm.backend.data.ctrl, 0.0)


def test_a_loop_closure_error_faults_the_arm_in_that_cycle():
    import mujoco

    arm = _enabled()
    arm.step(5)
    d, m = arm.backend.data, arm.backend.model
    j = m.joint("k2_x").id                               # a passive hinge: opens a loop
    d.qpos[m.jnt_qposadr[j]] += 0.05
    arm.step(1)
    assert arm.operating_state == "FAULT" and "loop-closure" in arm.fault
    mujoco.mj_resetDataKeyframe(m, d, 0)                 # a sound state again: enable clears
    mujoco.mj_forward(m, d)
    arm.enable()
    assert arm.operating_state == "ENABLED" and arm.fault is None


@pytest.mark.parametrize("reading, words", [
    ((np.zeros(2), np.zeros(3)), "shape"),
    ((np.zeros((3, 1)), np.zeros(3)), "shape"),
    ((np.array([np.nan, 0.1, 0.45]), np.zeros(3)), "non-finite"),
    ((Q0 + [0, 0, 0.5], np.zeros(3)), "beyond the strokes"),
    ((Q0, np.array([0.0, 0.0, 50.0])), "speed"),
    ((Q0,), "unreadable"),
    (None, "unreadable"),
])
def test_a_drivers_bad_reading_faults_with_a_named_reason(reading, words):
    drv = _Driver(Q0)
    arm = SimulatedArm(T, D, q0=Q0, backend=drv)
    arm.enable()
    arm.step(2)
    drv.reading = reading if reading is not None else 42
    arm.step(1)                                           # never raises
    assert arm.operating_state == "FAULT" and words in arm.fault, arm.fault
    np.testing.assert_array_equal(arm.measured_js().position, Q0)   # the last sound reading
    arm.step(1)
    np.testing.assert_array_equal(drv.forces[-1], 0.0)
    assert np.isnan(drv.positions[-1]).all()
    arm.enable()                                          # still bad: stays in FAULT
    assert arm.operating_state == "FAULT"
    drv.reading = None
    arm.enable()
    assert arm.operating_state == "ENABLED"


def test_a_bad_reading_at_start_is_a_named_error():
    with pytest.raises(InvalidInputError, match="backend: encoders"):
        SimulatedArm(T, D, q0=Q0, backend=_Driver(Q0, reading=(np.zeros(4), np.zeros(3))))


def test_reading_margin_is_the_stated_tolerance():
    drv = _Driver(Q0)
    arm = SimulatedArm(T, D, q0=Q0, backend=drv)
    arm.enable()
    hi = np.asarray(D.stroke_max)
    drv.reading = (np.array([Q0[0], Q0[1], hi[2] + 0.5 * READING_MARGIN]), np.zeros(3))
    arm.step(1)
    assert arm.operating_state == "ENABLED"
    drv.reading = (np.array([Q0[0], Q0[1], hi[2] + 2 * READING_MARGIN]), np.zeros(3))
    arm.step(1)
    assert arm.operating_state == "FAULT"


# --- CRTK operating states ---------------------------------------------------------------
def test_crtk_operating_states():
    drv = _Driver(Q0)
    arm = SimulatedArm(T, D, q0=Q0, backend=drv)
    assert arm.operating_state == "DISABLED"
    arm.step(3)                                           # DISABLED writes no force
    assert all(np.all(f == 0) for f in drv.forces)
    assert all(np.isnan(p).all() for p in drv.positions)
    arm.servo_jp(NEAR)
    assert "DISABLED" in arm.refusal
    arm.enable()
    assert arm.operating_state == "ENABLED"
    arm.pause()
    assert arm.operating_state == "PAUSED"
    arm.enable()                                          # CRTK: resume leaves PAUSED
    assert arm.operating_state == "PAUSED"
    arm.servo_jp(NEAR)
    assert "PAUSED" in arm.refusal
    arm.resume()
    assert arm.operating_state == "ENABLED"
    arm.servo_jp(NEAR)
    assert arm.refusal is None
    arm.disable()
    assert arm.operating_state == "DISABLED"
    n = len(drv.forces)
    arm.step(2)
    assert all(np.all(f == 0) for f in drv.forces[n:])


def test_homing_state():
    assert SimulatedArm(T, D, q0=Q0).is_homed             # MuJoCo: absolute encoders
    drv = _HomingDriver(Q0)
    arm = SimulatedArm(T, D, q0=Q0, backend=drv)
    assert not arm.is_homed
    arm.home()
    assert "DISABLED" in arm.refusal and drv.homed == 0
    arm.enable()
    arm.servo_jp(NEAR)
    assert "not homed" in arm.refusal
    arm.home()
    assert arm.is_homed and drv.homed == 1
    arm.servo_jp(NEAR)
    assert arm.refusal is None
    arm.unhome()
    arm.servo_jp(Q0)
    assert "not homed" in arm.refusal


# --- queries, bounds, errors named -------------------------------------------------------
def test_measured_cp_has_no_side_effect():
    arm = _enabled()
    arm.servo_jp(GOAL)
    arm.step(50)
    before = {k: (v.copy() if isinstance(v, np.ndarray) else v)
              for k, v in vars(arm).items() if not k.startswith("backend")}
    a, b = arm.measured_cp(), arm.measured_cp()
    np.testing.assert_array_equal(a, b)
    after = vars(arm)
    for k, v in before.items():
        if isinstance(v, np.ndarray):
            np.testing.assert_array_equal(after[k], v)
    sol = ak.forward_kinematics(arm.measured_js().position, T, D)
    np.testing.assert_allclose(a, sol.T_b_tip[arm.slot], rtol=0, atol=1e-12)
    np.testing.assert_allclose(a[:3, 3], arm.backend.tip_b(), atol=1e-6)


@pytest.mark.parametrize("n", [MAX_STEPS + 1, -1, 1.5, True, "3"])
def test_step_is_bounded(n):
    arm = SimulatedArm(T, D, q0=Q0, backend=_Driver(Q0))
    with pytest.raises((InvalidInputError, TypeError), match=r"\bn\b"):
        arm.step(n)


def test_ruckig_errors_are_named(monkeypatch):
    import ruckig

    arm = _enabled(backend=_Driver(Q0))

    class _Broken:
        def __init__(self, *a):
            pass

        def calculate(self, *a):
            raise RuntimeError("pybind11: bad input")

    monkeypatch.setattr(ruckig, "Ruckig", _Broken)
    with pytest.raises(KinematicsError, match="move_jp: Ruckig failed"):
        arm.move_jp(GOAL)
    monkeypatch.undo()
    with pytest.raises(InvalidInputError, match="stroke"):
        arm.move_jp([-0.1, 0.1, 0.9])
    with pytest.raises(InvalidInputError, match="goal_velocity"):
        arm.move_jp(GOAL, goal_velocity=[math.nan, 0, 0])
    with pytest.raises(InvalidInputError, match="goal_velocity.*v_max"):
        arm.move_jp(GOAL, goal_velocity=[0.2, 0, 0])


def test_a_servo_velocity_at_v_max_is_taken_and_beyond_it_refused():
    """The arm's ``v_max`` bounds a servo command's velocity feed-forward (a limiter's
    velocity of exactly ``v_max`` passes to its rounding); a teleop session at the
    default limits is never refused for it."""
    from athenakin.teleop._arm_checks import VELOCITY_SLACK

    arm = _enabled(backend=_Driver(Q0))
    arm.step(200)               # held 0.2 s: v_max from rest is 0.5 m/s^2, not 100 in a cycle
    v_max = arm.limits[0]
    arm.servo_jp(Q0, velocity=[v_max * (1 + 0.5 * VELOCITY_SLACK), -v_max, 0.0])
    assert arm.refusal is None
    arm.servo_jp(Q0, velocity=[v_max * (1 + 2 * VELOCITY_SLACK), 0.0, 0.0])
    assert arm.refusal is not None and "exceeds the arm's v_max" in arm.refusal
    arm2 = _enabled(backend=_Driver(Q0), v_max=0.5)
    arm2.step(200)
    arm2.servo_jp(Q0, velocity=[0.4, 0.0, 0.0])
    assert arm2.refusal is None
    # a master far ahead: the core limits every |qd_i| to its v_max (0.1 m/s, the arm's)
    from athenakin.teleop import Teleop

    tele = Teleop(T, D, q0=Q0, rate=arm.rate)
    arm3 = _enabled(backend=_Driver(Q0))
    fastest = 0.0
    for k in range(200):
        cmd = tele.step(k * arm.dt, [0.05 * math.sin(0.05 * k), 0.03, 0.0])
        arm3.servo_jp(cmd.q, velocity=cmd.qd)
        assert arm3.refusal is None, arm3.refusal
        fastest = max(fastest, float(np.max(np.abs(cmd.qd))))
    assert fastest == pytest.approx(v_max, rel=1e-4)          # the limit was reached


def test_the_model_form():
    robot = ak.Robot.default(masses=MassModel.reference(D))
    arm = SimulatedArm(robot, q0=Q0, backend=_Driver(Q0))
    assert arm.masses is robot.masses and arm.design is robot.design
    with pytest.raises(TypeError, match="design"):
        SimulatedArm(robot, D, q0=Q0)


def test_masses_beside_a_robot_follow_resolve_robot():
    """One policy with Teleop, Tracker and plan: masses beside a Robot fill a gap only."""
    own = ak.Robot.default(masses=MassModel.reference(D))
    other = MassModel.slender_rods(_RODS, D)
    with pytest.raises(TypeError, match="^masses: the Robot has its own masses"):
        SimulatedArm(own, masses=other, q0=Q0, backend=_Driver(Q0))
    arm = SimulatedArm(ak.Robot.default(), masses=other, q0=Q0, backend=_Driver(Q0))
    assert arm.masses is other
    assert SimulatedArm(ak.Robot.default(), q0=Q0, backend=_Driver(Q0)).masses == \
        MassModel.reference(D)


def test_one_feed_forward_path():
    """The setpoint's feed-forward is the dynamics loop's, equal to inverse_dynamics."""
    arm = _enabled(backend=_Driver(Q0))
    arm.servo_jp(GOAL, velocity=[0.01, -0.02, 0.0])
    want = ak.dynamics.inverse_dynamics(GOAL, [0.01, -0.02, 0.0],
                                        np.array([0.01, -0.02, 0.0]) * arm.rate, T, D)
    np.testing.assert_allclose(arm.feedforward_effort, want, rtol=1e-12, atol=1e-12)


def test_the_constructor_compiles_the_ik_of_servo_cp(monkeypatch):
    """The first ``servo_cp`` of an arm made on a cold numba cache compiled the tool-tip IK
    inside the command (4.6 s on this machine, the servo loop held meanwhile): the
    constructor runs it once, so that the first command's cycle compiles nothing."""
    from athenakin import _dispatch
    from athenakin._backend import numba_available

    if not numba_available():
        pytest.skip("the compiled kernels do not run here (numba missing or ATHENAKIN_BACKEND)")
    monkeypatch.setattr(_dispatch, "_WARM", set())   # as in a new process
    SimulatedArm(T, D, q0=Q0, backend=_Driver(Q0))
    assert "line" in _dispatch._WARM                  # q_from_tool_tip's first compiled call
