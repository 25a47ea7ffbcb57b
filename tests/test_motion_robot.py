"""The tracker and the planner take an ``ak.Robot`` as their model; ``(T_b_e, design, ...)`` stays.

Both forms go through the one conversion (``athenakin._robot_model.resolve_robot``, that of
``Teleop``), so they give the same results bit for bit: compared here by ``repr`` (exact for
floats, NaN included) on seeded streams and paths. A bad model is refused by name.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import athenakin as ak
from athenakin._robot_model import resolve_robot
from athenakin._validation import ARGUMENT_ORDER
from athenakin.collision import Bodies, Environment
from athenakin.dynamics import MassModel
from athenakin.errors import InvalidInputError
from athenakin.motion import PlanOptions, Tracker, plan, plan_directions, track

SEED = 37_2026
D = ak.Design.default()
ROBOT = ak.Robot.default(D)
T = ROBOT.T_b_e
Q0 = np.array([-0.10, 0.10, 0.45])
BODIES = Bodies.default(D)
ENV = Environment().sphere(T[:3, 3] + [0.0, 0.0, -0.3], 0.02, name="ball")
TIPS = np.array([[0.25, 0.0, 0.0], [0.26, -0.01, 0.01]])
FAST = PlanOptions(rate=200.0)


def _stream(seed: int, n: int = 300) -> np.ndarray:
    """A seeded walk from ``Q0`` with jumps and NaN readings (fast and slow paths, LOST)."""
    rng = np.random.default_rng(seed)
    q = Q0 + np.cumsum(rng.normal(0.0, 4e-4, (n, 3)), axis=0)
    q[rng.choice(n, 6, replace=False)] += rng.normal(0.0, 0.03, (6, 3))
    q[rng.choice(n, 4, replace=False), rng.integers(0, 3, 4)] = np.nan
    q[0] = Q0
    return q


def _same(a: object, b: object) -> bool:
    """Bit for bit: the reprs of two poses (floats round-trip exactly, NaN included)."""
    return repr(a) == repr(b)


def _same_log(a: ak.motion.TrackLog, b: ak.motion.TrackLog) -> None:
    for f in dataclasses.fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if x is None or y is None:
            assert x is None and y is None, f.name
        elif np.asarray(x).dtype.kind in "fc":
            assert np.array_equal(x, y, equal_nan=True), f.name
        else:
            assert np.array_equal(x, y), f.name


# --------------------------------------------------------------------------------------
# Tracker
# --------------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", [SEED, SEED + 1])
def test_tracker_of_a_robot_equals_the_functional_form_bit_for_bit(seed: int) -> None:
    qs = _stream(seed)
    a, b = Tracker(ROBOT, q0=qs[0]), Tracker(T, D, q0=qs[0])
    assert _same(a.pose, b.pose)
    for q in qs[1:].tolist():
        assert _same(a.candidate(q), b.candidate(q))
        assert _same(a.update(q), b.update(q))
    assert a.robot is ROBOT and b.robot.design == D
    assert np.array_equal(a.T_b_e, b.T_b_e) and not a.T_b_e.flags.writeable


def test_tracker_takes_the_robots_bodies_and_environment() -> None:
    qs = _stream(SEED, 60)
    robot = ROBOT.replace(bodies=BODIES, environment=ENV)
    a = Tracker(robot, q0=qs[0], clearance_margin=0.01)
    b = Tracker(T, D, q0=qs[0], bodies=BODIES, environment=ENV, clearance_margin=0.01)
    c = Tracker(ROBOT, q0=qs[0], bodies=BODIES, environment=ENV, clearance_margin=0.01)
    assert a.clearance_margin == 0.01 and np.isfinite(a.pose.clearance)
    for q in qs[1:].tolist():
        pa, pb, pc = a.update(q), b.update(q), c.update(q)
        assert _same(pa, pb) and _same(pa, pc)


@pytest.mark.parametrize("robot", [ROBOT, ROBOT.replace(bodies=BODIES)], ids=["plain", "bodies"])
def test_track_of_a_robot_equals_the_functional_form_bit_for_bit(robot: ak.Robot) -> None:
    qs = _stream(SEED + 2)
    _same_log(track(qs, robot), track(qs, T, D, bodies=robot.bodies))
    if robot.bodies is not None:               # the Robot's bodies are checked, in one batch
        assert track(qs, robot).clearance is not None


def test_a_bad_model_is_refused_by_name() -> None:
    with pytest.raises(TypeError, match="robot: expected an athenakin.Robot"):
        Tracker("robot.toml.bak", q0=Q0)
    with pytest.raises(TypeError, match="robot: expected an athenakin.Robot"):
        Tracker(object(), q0=Q0)
    with pytest.raises(InvalidInputError, match="T_b_e: expected shape"):
        Tracker(np.eye(3), D, q0=Q0)
    with pytest.raises(InvalidInputError, match=ARGUMENT_ORDER.replace("(", r"\(")
                       .replace(")", r"\)")):
        Tracker(D, T, q0=Q0)                                     # the old order
    with pytest.raises(TypeError, match="design: give the design in the Robot"):
        Tracker(ROBOT, D, q0=Q0)
    with pytest.raises(TypeError, match="bodies: the Robot has its own bodies"):
        Tracker(ROBOT.replace(bodies=BODIES), q0=Q0, bodies=BODIES)
    with pytest.raises(TypeError, match="environment: the Robot has its own"):
        track(np.array([Q0, Q0]), ROBOT.replace(environment=ENV), environment=ENV)
    with pytest.raises(TypeError, match="bodies: expected athenakin.collision.Bodies"):
        Tracker(T, D, q0=Q0, bodies="default")


def test_resolve_robot_takes_a_robot_as_it_is() -> None:
    assert resolve_robot(ROBOT) is ROBOT
    filled = resolve_robot(ROBOT, bodies=BODIES)
    assert filled.bodies is BODIES and filled.design == ROBOT.design
    built = resolve_robot(T.tolist(), D, environment=ENV)
    assert isinstance(built, ak.Robot) and built.environment is ENV
    assert np.array_equal(built.T_b_e, T)


# --------------------------------------------------------------------------------------
# plan, plan_directions
# --------------------------------------------------------------------------------------
def _same_trajectory(a: ak.motion.Trajectory, b: ak.motion.Trajectory) -> None:
    for name in ("t", "q", "qd", "qdd", "tip_e", "segment", "mode", "T_b_e", "forces",
                 "clearance"):
        x, y = getattr(a, name), getattr(b, name)
        assert (x is None and y is None) or np.array_equal(x, y, equal_nan=True), name
    assert a.design == b.design


def test_plan_of_a_robot_equals_the_functional_form_bit_for_bit() -> None:
    _same_trajectory(plan(TIPS, ROBOT, options=FAST), plan(TIPS, T, D, options=FAST))
    az, po, dp = [0.0, -0.04], [np.pi / 2, np.pi / 2 - 0.04], [0.25, 0.26]
    _same_trajectory(plan_directions(az, po, dp, ROBOT, options=FAST),
                     plan_directions(az, po, dp, T, D, options=FAST))


def test_plan_takes_the_robots_parts() -> None:
    masses = MassModel.reference(D)
    robot = ROBOT.replace(bodies=BODIES, masses=masses)
    a = plan(TIPS, robot, options=FAST)
    b = plan(TIPS, T, D, bodies=BODIES, masses=masses, options=FAST)
    assert a.forces is not None and a.clearance is not None
    _same_trajectory(a, b)
    with pytest.raises(TypeError, match="masses: the Robot has its own masses"):
        plan(TIPS, robot, masses=masses, options=FAST)
    with pytest.raises(TypeError, match="design: give the design in the Robot"):
        plan(TIPS, ROBOT, D, options=FAST)
    with pytest.raises(TypeError, match="robot: expected an athenakin.Robot"):
        plan(TIPS, {"T_b_e": T}, options=FAST)
