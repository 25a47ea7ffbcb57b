"""ak.Robot: a thin model object whose methods equal the functional core, call for call."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import athenakin as ak
from athenakin import analysis, collision, dynamics, sim
from athenakin.errors import InvalidInputError

D = ak.Design.default()
T = ak.default_rcm_frame(D)
RNG = np.random.default_rng(28)
Q = sim.sample_reachable_q(6, T, D, rng=RNG)


def _same(a, b):
    if dataclasses.is_dataclass(a):
        for f in dataclasses.fields(a):
            _same(getattr(a, f.name), getattr(b, f.name))
    elif isinstance(a, tuple):
        for x, y in zip(a, b, strict=True):
            _same(x, y)
    elif isinstance(a, np.ndarray):
        np.testing.assert_array_equal(a, b)
    else:
        assert a == b or (a != a and b != b)


def test_default_is_the_reference_setup():
    robot = ak.Robot.default()
    assert robot.design == D
    np.testing.assert_array_equal(robot.T_b_e, T)
    assert not robot.T_b_e.flags.writeable


@pytest.mark.parametrize("method, call", [
    ("forward_kinematics", lambda r: (ak.forward_kinematics(Q, T, D), r.forward_kinematics(Q))),
    ("tool_tip_jacobian", lambda r: (analysis.tool_tip_jacobian(Q, T, D),
                                     r.tool_tip_jacobian(Q))),
    ("clearance", lambda r: (collision.clearance(Q, T, D, slot="all"),
                             r.clearance(Q, slot="all"))),
    ("inverse_dynamics", lambda r: (dynamics.inverse_dynamics(Q, 0.1 * Q, Q, T, D),
                                    r.inverse_dynamics(Q, 0.1 * Q, Q))),
    ("mass_matrix", lambda r: (dynamics.mass_matrix(Q, T, D), r.mass_matrix(Q))),
    ("statics", lambda r: (dynamics.statics(Q, T, D), r.statics(Q))),
    ("mjcf", lambda r: (sim.mjcf_from_design(T, D), r.mjcf())),
    ("urdf", lambda r: (sim.urdf_from_design(T, D), r.urdf())),
])
def test_methods_are_the_functions(method, call):
    want, got = call(ak.Robot.default())
    _same(want, got)


def test_ik_round_trip_through_the_robot():
    robot = ak.Robot(T, D)
    sol = robot.forward_kinematics(Q)
    tip_e = (sol.tip[:, 0] - T[:3, 3]) @ T[:3, :3]
    q, res = robot.q_from_tool_tip(tip_e)
    np.testing.assert_allclose(q, Q, rtol=0, atol=1e-10)
    q2, _ = robot.inverse_kinematics(sol.u[:, 0, 2:])
    np.testing.assert_allclose(q2, Q, rtol=0, atol=1e-10)


def test_parts_are_used_and_can_be_overridden():
    masses = dynamics.MassModel.reference(D)
    heavy = dataclasses.replace(masses, mass=2.0 * masses.mass)
    robot = ak.Robot.default(masses=heavy)
    np.testing.assert_array_equal(robot.mass_matrix(Q), dynamics.mass_matrix(Q, T, D,
                                                                              masses=heavy))
    assert not np.allclose(robot.mass_matrix(Q), dynamics.mass_matrix(Q, T, D))
    # an explicit option wins over the robot's part
    np.testing.assert_array_equal(robot.mass_matrix(Q, masses=masses),
                                  dynamics.mass_matrix(Q, T, D, masses=masses))
    # the environment reaches clearance
    env = collision.Environment().sphere(T[:3, 3], 0.02, name="organ")
    with_env = ak.Robot.default(environment=env).clearance(Q)
    _same(with_env, collision.clearance(Q, T, D, environment=env))
    assert with_env.distances.shape[-1] > collision.clearance(Q, T, D).distances.shape[-1]


@pytest.mark.parametrize("kw, err, match", [
    ({"T_b_e": np.eye(3)}, InvalidInputError, "T_b_e"),
    ({"T_b_e": np.full((4, 4), np.nan)}, InvalidInputError, "T_b_e"),
    ({"design": "reference"}, TypeError, "design"),
    ({"bodies": "default"}, TypeError, "bodies"),
    ({"environment": 1.0}, TypeError, "environment"),
    ({"masses": {"link_a": 1.0}}, TypeError, "masses"),
])
def test_bad_parts_are_named(kw, err, match):
    args = {"design": D, "T_b_e": T, **kw}
    with pytest.raises(err, match=match):
        ak.Robot(**args)


def test_old_argument_order_is_refused_by_name():
    with pytest.raises(InvalidInputError, match="T_b_e comes before design"):
        ak.Robot(D, T)


def test_robot_is_frozen_and_replace_checks_again():
    robot = ak.Robot.default()
    with pytest.raises(dataclasses.FrozenInstanceError):
        robot.design = D  # type: ignore[misc]
    with pytest.raises(InvalidInputError, match="T_b_e"):
        robot.replace(T_b_e=np.zeros((4, 4)))


@pytest.mark.parametrize("method, function", [
    ("forward_kinematics", "athenakin._dispatch.forward_kinematics"),
    ("inverse_kinematics", "athenakin._dispatch.inverse_kinematics"),
    ("q_from_tool_tip", "athenakin._dispatch.q_from_tool_tip"),
    ("q_from_instrument", "athenakin._dispatch.q_from_instrument"),
    ("tool_tip_jacobian", "athenakin.analysis.tool_tip_jacobian"),
    ("singularities", "athenakin.analysis.singularities"),
    ("clearance", "athenakin.collision.clearance"),
    ("statics", "athenakin.dynamics.statics"),
    ("inverse_dynamics", "athenakin.dynamics.inverse_dynamics"),
    ("forward_dynamics", "athenakin.dynamics.forward_dynamics"),
    ("mass_matrix", "athenakin.dynamics.mass_matrix"),
    ("force_capability", "athenakin.dynamics.force_capability"),
    ("mjcf", "athenakin.sim.mjcf_from_design"),
    ("urdf", "athenakin.sim.urdf_from_design"),
])
def test_methods_have_their_functions_signatures(method, function):
    """Explicit keyword-only options, named and defaulted as the function's (no **options)."""
    import importlib
    import inspect

    mod, name = function.rsplit(".", 1)
    fn = getattr(importlib.import_module(mod), name)
    want = {k: p.default for k, p in inspect.signature(fn).parameters.items()
            if p.kind is inspect.Parameter.KEYWORD_ONLY}
    got = inspect.signature(getattr(ak.Robot, method)).parameters
    assert not any(p.kind is inspect.Parameter.VAR_KEYWORD for p in got.values())
    kw = {k: p.default for k, p in got.items() if p.kind is inspect.Parameter.KEYWORD_ONLY}
    assert set(kw) == set(want), (set(kw) ^ set(want))
    for k, v in want.items():
        if k in ("bodies", "environment", "masses"):
            assert kw[k] is None           # None: the robot's own part
        else:
            assert kw[k] == v or (kw[k] is v), k
