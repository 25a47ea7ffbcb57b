"""URDF of the kinematic tree: loads in yourdfpy, and the documented loop closures hold."""

import numpy as np
import pytest
import yourdfpy

import athenakin as ak
from athenakin.sim import (
    CLOSURE_PAIRS,
    JOINTS,
    LOOP_CLOSURES,
    MIMIC,
    mechanism_joint_values,
    urdf_from_design,
    write_urdf,
)

SEED = 77


def load(tmp_path, design=None, T=None):
    path = write_urdf(tmp_path / "athena.urdf", T, design)
    return yourdfpy.URDF.load(str(path), build_scene_graph=True, load_meshes=False)


def closure_errors(robot, values, T_b_e):
    robot.update_cfg({n: values[n] for n in robot.actuated_joint_names})
    err = []
    for a, b in CLOSURE_PAIRS:
        Ta, Tb = robot.get_transform(a, "base"), robot.get_transform(b, "base")
        err.append(np.abs(Ta[:3, 3] - Tb[:3, 3]).max())
    T5 = robot.get_transform("sph_5_frame", "base")
    err.append(np.abs(T5 - T_b_e).max())                   # full pose of the last closure
    return np.array(err)


def test_loads_and_has_the_tree(tmp_path):
    robot = load(tmp_path)
    assert robot.validate()
    assert set(JOINTS) <= set(robot.joint_map)
    assert sorted(robot.actuated_joint_names) == sorted(set(JOINTS) - set(MIMIC))
    for name, (kind, parent, child) in JOINTS.items():
        j = robot.joint_map[name]
        assert (j.parent, j.child) == (parent, child)
        assert j.type == ("prismatic" if kind == "slide" else "continuous")
    for name, (master, mult) in MIMIC.items():
        assert robot.joint_map[name].mimic.joint == master
        assert robot.joint_map[name].mimic.multiplier == mult
    d = ak.Design.default()
    lim = robot.joint_map["q3"].limit
    q3_zero = ak.robot.REFERENCE_Q[2]                      # joint zero: the reference q3
    np.testing.assert_allclose([lim.lower, lim.upper],
                               [d.q_min[2] - q3_zero, d.q_max[2] - q3_zero], rtol=0, atol=1e-15)


def test_header_documents_every_loop_closure():
    text = urdf_from_design()
    head = text[:text.index("<robot")]
    for c in LOOP_CLOSURES:
        assert c.name in head and c.a in head and c.b in head


@pytest.mark.parametrize("slot", range(16))
def test_closures_hold_in_every_slot(tmp_path, slot):
    robot = load(tmp_path)
    jv = mechanism_joint_values(slot=slot)
    values = jv.urdf
    assert closure_errors(robot, values, jv.T_b_e).max() < 1e-13
    np.testing.assert_allclose(robot.get_transform("instrument", "base"),
                               jv.state.frame("instrument"), rtol=0, atol=1e-13)
    np.testing.assert_allclose(robot.get_transform("platform", "base"),
                               jv.state.frame("platform"), rtol=0, atol=1e-13)


def test_closures_hold_over_seeded_configurations(tmp_path):
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    robot = load(tmp_path)
    rng = np.random.default_rng(SEED)
    q = rng.uniform(d.stroke_min, d.stroke_max, (400, 3))
    sol = ak.forward_kinematics(q, T, d, errors="flag")
    n = 0
    for i in np.flatnonzero(sol.valid.any(axis=1))[:150]:
        slot = int(rng.choice(np.flatnonzero(sol.valid[i])))
        values = mechanism_joint_values(q[i], T, d, slot=slot).urdf
        assert closure_errors(robot, values, T).max() < 1e-12
        n += 1
    assert n == 150


def test_a_wrong_joint_value_opens_a_loop(tmp_path):
    robot = load(tmp_path)
    jv = mechanism_joint_values()
    values = jv.urdf
    values["b_ujoint_x"] += 1e-6
    assert closure_errors(robot, values, jv.T_b_e).max() > 1e-7


def test_other_design_and_setup(tmp_path):
    d = ak.Design(l1=0.34, l2=0.08, l3=0.27, l4=0.12, l5=0.45, tool_length=0.40)
    q = np.array([-0.12, 0.08, 0.50])
    par = ak.parallel.parallel_forward_kinematics(q, d)
    T = np.eye(4)
    T[:3, 3] = par.O_s[0] + np.array([0.05, -0.1, -0.15])
    robot = load(tmp_path, d, T)
    lim = robot.joint_map["q1"].limit                      # unlimited stroke: a wide limit
    np.testing.assert_allclose(lim.lower, -2.0 - mechanism_joint_values(q, T, d).zero["q1"])
    sol = ak.forward_kinematics(q, T, d)
    for slot in np.flatnonzero(sol.valid):
        values = mechanism_joint_values(q, T, d, slot=int(slot)).urdf
        assert closure_errors(robot, values, T).max() < 1e-13


# --- ROS: joint zero = the assembled reference configuration, tool_tip link ---------------
def fk_tip(q, T, d, slot):
    """Tool tip from the FK solution: O_s + L z_3 with z_3 = T_b_s Rz(u1) Rx(90) Rz(u2) Rx(90) z."""
    sol = ak.forward_kinematics(q, T, d, errors="flag")
    u1, u2 = sol.u[slot, 0], sol.u[slot, 1]
    rz = lambda a: np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])  # noqa: E731
    rx90 = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])
    z3 = sol.T_b_s[slot, :3, :3] @ rz(u1) @ rx90 @ rz(u2) @ rx90 @ [0.0, 0.0, 1.0]
    return sol.T_b_s[slot, :3, 3] + d.tool_length * z3


def test_zero_pose_is_the_assembled_reference_configuration(tmp_path):
    """All joints at 0 close every loop (was: gaps of 0.29 m and 0.96 m) at the reference q."""
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    robot = load(tmp_path)
    zeros = dict.fromkeys(robot.actuated_joint_names, 0.0)
    assert closure_errors(robot, zeros, T).max() < 1e-12
    q1, q2, _ = ak.robot.REFERENCE_Q
    np.testing.assert_allclose([robot.get_transform("carriage_a", "base")[0, 3],
                                robot.get_transform("carriage_b", "base")[0, 3]], [q1, q2],
                               rtol=0, atol=1e-15)
    np.testing.assert_allclose(robot.get_transform("tool_tip", "base")[:3, 3],
                               fk_tip(ak.robot.REFERENCE_Q, T, d, 0), rtol=0, atol=1e-12)


def test_every_joint_zero_lies_within_its_limits(tmp_path):
    robot = load(tmp_path)
    for j in robot.joint_map.values():
        if j.type == "prismatic":
            assert j.limit.lower < 0.0 < j.limit.upper, j.name
        else:
            assert j.type in ("continuous", "fixed"), j.name


def test_moving_one_actuator_alone_opens_the_loops_only_by_its_motion(tmp_path):
    """Zero is assembled; jv.urdf of a nearby q (all joints) keeps the loops closed."""
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    robot = load(tmp_path)
    q = np.asarray(ak.robot.REFERENCE_Q) + [0.01, 0.0, 0.0]
    jv = mechanism_joint_values(q, T, d)
    np.testing.assert_allclose(jv.urdf["q1"], 0.01, rtol=0, atol=1e-15)
    assert closure_errors(robot, jv.urdf, T).max() < 1e-12


def test_tool_tip_link_is_at_the_fk_tip_over_seeded_configurations(tmp_path):
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    robot = load(tmp_path)
    rng = np.random.default_rng(SEED + 1)
    q = rng.uniform(d.stroke_min, d.stroke_max, (200, 3))
    sol = ak.forward_kinematics(q, T, d, errors="flag")
    rows = np.flatnonzero(sol.valid.any(axis=1))[:40]
    assert len(rows) == 40
    for i in rows:
        slot = int(rng.choice(np.flatnonzero(sol.valid[i])))
        jv = mechanism_joint_values(q[i], T, d, slot=slot)
        robot.update_cfg({n: jv.urdf[n] for n in robot.actuated_joint_names})
        np.testing.assert_allclose(robot.get_transform("tool_tip", "base")[:3, 3],
                                   fk_tip(q[i], T, d, slot), rtol=0, atol=1e-12)


def test_mechanism_joint_values_is_a_mapping_per_convention():
    """It returns a documented dataclass of joint name -> value mappings, not a bare tuple."""
    jv = mechanism_joint_values()
    assert isinstance(jv, ak.sim.MechanismJointValues)
    assert set(jv.values) == set(jv.urdf) == set(jv.zero) == set(JOINTS)
    for name in JOINTS:
        np.testing.assert_allclose(jv.urdf[name], 0.0, rtol=0, atol=1e-15)
    np.testing.assert_allclose([jv.values[n] for n in ("q1", "q2", "q3")],
                               ak.robot.REFERENCE_Q, rtol=0, atol=0)


def test_zero_configuration_can_be_chosen(tmp_path):
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    qz = np.array([-0.12, 0.08, 0.47])
    path = tmp_path / "z.urdf"
    path.write_text(urdf_from_design(T, d, q_zero=qz, zero_slot=9))
    robot = yourdfpy.URDF.load(str(path), build_scene_graph=True, load_meshes=False)
    robot.update_cfg(dict.fromkeys(robot.actuated_joint_names, 0.0))
    st = mechanism_joint_values(qz, T, d, slot=9).state
    np.testing.assert_allclose(robot.get_transform("tool_tip", "base")[:3, 3], st["tip"],
                               rtol=0, atol=1e-12)
    jv = mechanism_joint_values(ak.robot.REFERENCE_Q, T, d, q_zero=qz, zero_slot=9)
    assert closure_errors(robot, jv.urdf, T).max() < 1e-12


def test_rpy_conversion_agrees_with_scipy_and_survives_gimbal_lock():
    from scipy.spatial.transform import Rotation

    from athenakin.sim._urdf import _matrix_from_rpy, _rpy_from_matrix

    rng = np.random.default_rng(SEED + 2)
    for R in Rotation.random(200, random_state=rng).as_matrix():
        rpy = _rpy_from_matrix(R)
        np.testing.assert_allclose(rpy, Rotation.from_matrix(R).as_euler("xyz"), rtol=0,
                                   atol=1e-9)
        np.testing.assert_allclose(_matrix_from_rpy(tuple(rpy)), R, rtol=0, atol=1e-12)
    for pitch in (np.pi / 2, -np.pi / 2):                   # gimbal lock: the matrix holds
        R = Rotation.from_euler("xyz", [0.3, pitch, -0.7]).as_matrix()
        np.testing.assert_allclose(_matrix_from_rpy(tuple(_rpy_from_matrix(R))), R, rtol=0,
                                   atol=1e-12)


def test_audit_arguments_named():
    """Audit of issue 13: robot_name=None and q_zero=10**400 named their argument."""
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    with pytest.raises(TypeError, match="robot_name"):
        ak.sim.urdf_from_design(T, d, robot_name=None)
    with pytest.raises(TypeError, match="q_zero"):
        ak.sim.urdf_joint_zero(T, d, q_zero=[10**400, 0, 0])
    with pytest.raises(TypeError, match="path"):
        ak.sim.write_urdf(1, T, d)
