"""athenakin.testing's teleoperation oracles: they catch what they claim, and the core passes.

Hostile master streams with ``Bodies.default`` and a fixture of every shape (halfspace,
sphere, capsule, box) go through :class:`~athenakin.teleop.Teleop`; the commands are
checked by :func:`~athenakin.testing.assert_teleop_commands`, whose distances are coal's
(tip to fixtures, bodies to obstacles) and capsule distances of bodies rebuilt from the
reference FK: no code shared with the core's limiter. A hypothesis property test runs
short random streams (CI-fast).
"""

import math

import numpy as np
import pytest

import athenakin as ak
from athenakin.testing import TeleopViolations, assert_teleop_commands, teleop_violations

pytest.importorskip("coal")

from athenakin.collision import Bodies, Environment  # noqa: E402
from athenakin.teleop import Teleop, TeleopOptions, TeleopStatus, run_session  # noqa: E402

D = ak.Design.default()
T = ak.default_rcm_frame(D)
Q0 = np.array([-0.1, 0.1, 0.45])
RATE = 1000.0
TIP_B = ak.forward_kinematics(Q0, T, D).tip[0]
#: The instrument's direction at Q0 and two directions across it (base frame).
AXIS = (TIP_B - T[:3, 3]) / np.linalg.norm(TIP_B - T[:3, 3])
SIDE = np.cross(AXIS, [0.0, 0.0, 1.0])
SIDE /= np.linalg.norm(SIDE)
UP = np.cross(SIDE, AXIS)


def _fixtures():
    """A fixture of every shape around the tip at Q0, 7-12 mm clear of the instrument."""
    box = np.eye(4)
    box[:3, 3] = TIP_B - 0.025 * UP
    return (Environment()
            .halfspace(TIP_B + 0.012 * AXIS, -AXIS, name="floor")       # deeper: forbidden
            .sphere(TIP_B + 0.015 * SIDE, 0.004, name="vessel")
            .capsule(TIP_B - 0.012 * SIDE - 0.02 * AXIS, TIP_B - 0.012 * SIDE + 0.02 * AXIS,
                     0.002, name="nerve")
            .box(box, (0.006, 0.006, 0.006), name="bone"))


#: Cycles of the hostile stream here (the release campaign runs 10^6).
N_HOSTILE = 300
ROBOT = ak.Robot(T, D, bodies=Bodies.default(D), environment=_fixtures())


def _hostile(n, rng):
    """Jumps, NaN, no sample, targets far outside, clutch chatter, pushes into fixtures."""
    out = []
    for k in range(n):
        t = k / RATE
        s = 2 * math.pi * t
        p = [0.15 * math.sin(1.3 * s), 0.12 * math.sin(0.9 * s + 1), 0.1 * math.sin(0.7 * s)]
        clutch = (k // 97) % 5 != 4                      # pressed one period in five
        r = rng.random()
        if r < 0.02:
            p = [v + rng.normal(0, 0.5) for v in p]      # a jump
        elif r < 0.03:
            p = [math.nan, 0.0, 0.0]
        elif r < 0.05:
            p = None                                     # a lost sample
        elif r < 0.06:
            p = [5.0, -5.0, 5.0]                         # far outside the workspace
        if 300 <= k < 340:
            clutch = k % 2 == 0                          # chatter
        out.append((t, p, clutch))
    return out


def _tele(**kw):
    return Teleop(T, D, q0=Q0, rate=RATE, bodies=ROBOT.bodies, environment=ROBOT.environment,
                  options=TeleopOptions(feedforward=False, **kw))


def test_hostile_streams_with_bodies_and_every_fixture_shape():
    """The bodies kept apart and from every obstacle; the oracle's clearance is the core's."""
    assert {o.kind for o in ROBOT.environment.obstacles} == {"halfspace", "sphere", "capsule",
                                                             "box"}
    tele = _tele()
    log = run_session(tele, None, _hostile(N_HOSTILE, np.random.default_rng(37)))
    margin = tele.options.clearance_margin
    v = assert_teleop_commands(log, ROBOT, rate=RATE, v_max=tele.v_max, a_max=tele.a_max,
                               clearance_margin=margin)
    assert v.cycles == N_HOSTILE and v.total == 0
    assert margin <= v.least_clearance < margin + 0.005      # the guard was at work
    assert np.isfinite(log.clearance).all()
    assert v.least_clearance == pytest.approx(float(log.clearance.min()), abs=1e-6)


def test_hostile_streams_against_tip_fixtures_of_every_shape():
    """Without the bodies' check the fixtures bind the tip itself (coal's distances)."""
    tele = Teleop(T, D, q0=Q0, rate=RATE, environment=ROBOT.environment,
                  options=TeleopOptions(feedforward=False, check_clearance=False))
    log = run_session(tele, None, _hostile(4 * N_HOSTILE, np.random.default_rng(38)),
                      check_bodies=False)
    m = tele.options.fixture_margin
    v = assert_teleop_commands(log, ROBOT, rate=RATE, v_max=tele.v_max, a_max=tele.a_max,
                               bodies=False, fixture_margin=0.0)
    assert 0.0 <= v.least_fixture_distance < m + 0.002        # pressed against a fixture
    assert np.any(log.status & int(TeleopStatus.FIXTURE))


def _commands(q, *, slot=0):
    """Commands with backward-difference velocities and the FK tips of ``q`` (N, 3)."""
    q = np.asarray(q, float)
    qd = np.vstack([np.zeros(3), np.diff(q, axis=0) * RATE])
    qdd = np.vstack([np.zeros(3), np.diff(qd, axis=0) * RATE])
    sol = ak.forward_kinematics(q, T, D, errors="flag")
    tip_b = np.asarray(sol.tip)[:, slot]
    tip = (tip_b - T[:3, 3]) @ T[:3, :3]

    class _Log:
        pass

    log = _Log()
    log.q, log.qd, log.qdd, log.tip = q, qd, qdd, tip
    log.slot = np.full(len(q), slot)
    return log


def _path(n=20, c=(5e-7, -5e-7, 2e-7)):
    """Constant acceleration from rest: ``q_k = Q0 + c k^2`` (qdd = 2 c rate^2 <= 1 m/s^2)."""
    return Q0 + (np.arange(n) ** 2)[:, None] * np.asarray(c)


@pytest.mark.parametrize("edit, check", [
    (lambda c: c.q.__setitem__((5, 2), 0.9), "stroke"),
    (lambda c: c.qd.__setitem__((5, 0), 0.2), "velocity"),
    (lambda c: c.qdd.__setitem__((5, 0), 3.0), "acceleration"),
    (lambda c: c.tip.__setitem__((5, 0), c.tip[5, 0] + 1e-6), "tip"),
    (lambda c: c.qd.__setitem__((5, 0), c.qd[5, 0] + 0.01), "differences"),
    (lambda c: c.q.__setitem__((5, 0), math.nan), "nonfinite"),
])
def test_the_oracle_catches_each_violation(edit, check):
    robot = ak.Robot(T, D)
    c = _commands(_path())
    assert teleop_violations(c, robot, rate=RATE).total == 0
    edit(c)
    v = teleop_violations(c, robot, rate=RATE)
    assert v.counts[check] >= 1 and v.first[check] == 5, v.summary()
    with pytest.raises(AssertionError, match=check):
        assert_teleop_commands(c, robot, rate=RATE)


def test_the_oracle_catches_the_carriages_and_a_tip_in_a_fixture():
    robot = ak.Robot(T, D)
    # the carriages driven towards each other until their capsules overlap
    q = np.array([[-0.1 + 0.01 * k, 0.1 - 0.01 * k, 0.45] for k in range(10)])
    v = teleop_violations(_commands(q), robot, rate=RATE, v_max=100.0, a_max=1e6)
    assert v.counts["clearance"] >= 1 and v.least_clearance < 0
    # a sphere around the tip's path
    env = Environment().sphere(TIP_B, 0.003, name="inside")
    v = teleop_violations(_commands(_path()), robot, rate=RATE, environment=env,
                          bodies=False)
    assert v.counts["fixture"] >= 1 and v.least_fixture_distance < 0
    assert math.isnan(v.least_clearance)


def test_bad_arguments_are_named():
    c = _commands(_path())
    with pytest.raises(TypeError, match="robot"):
        teleop_violations(c, (T, D), rate=RATE)
    with pytest.raises(TypeError, match="commands"):
        teleop_violations([1, 2, 3], ak.Robot(T, D), rate=RATE)
    with pytest.raises(ak.InvalidInputError, match="v_max"):
        teleop_violations(c, ak.Robot(T, D), rate=RATE, v_max=-1.0)
    assert isinstance(teleop_violations(c, ak.Robot(T, D), rate=RATE), TeleopViolations)


hypothesis = pytest.importorskip("hypothesis")
st = hypothesis.strategies


@hypothesis.settings(max_examples=12, deadline=None, derandomize=True)
@hypothesis.given(st.lists(st.tuples(
    st.floats(-0.3, 0.3, allow_nan=False), st.floats(-0.3, 0.3, allow_nan=False),
    st.floats(-0.3, 0.3, allow_nan=False), st.booleans(), st.sampled_from(["ok", "nan", "none",
                                                                           "jump"])),
    min_size=5, max_size=40))
def test_property_every_stream_keeps_the_invariants(samples):
    """Any short stream of positions, gaps, NaN and clutch changes keeps every invariant."""
    tele = _tele()
    items = []
    for k, (x, y, z, clutch, kind) in enumerate(samples):
        p = {"ok": (x, y, z), "nan": (math.nan, y, z), "none": None,
             "jump": (10 * x, 10 * y, 10 * z)}[kind]
        items.append((k / RATE, p, clutch))
    log = run_session(tele, None, items)
    assert_teleop_commands(log, ROBOT, rate=RATE, v_max=tele.v_max, a_max=tele.a_max,
                           clearance_margin=tele.options.clearance_margin)
