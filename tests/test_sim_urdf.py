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
    path = write_urdf(tmp_path / "athena.urdf", design, T)
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
    assert (lim.lower, lim.upper) == (d.q_min[2], d.q_max[2])


def test_header_documents_every_loop_closure():
    text = urdf_from_design()
    head = text[:text.index("<robot")]
    for c in LOOP_CLOSURES:
        assert c.name in head and c.a in head and c.b in head


@pytest.mark.parametrize("slot", range(16))
def test_closures_hold_in_every_slot(tmp_path, slot):
    robot = load(tmp_path)
    values, g = mechanism_joint_values(slot=slot)
    assert closure_errors(robot, values, g.T_b_e).max() < 1e-13
    np.testing.assert_allclose(robot.get_transform("instrument", "base"),
                               g.frames["instrument"], rtol=0, atol=1e-13)
    np.testing.assert_allclose(robot.get_transform("platform", "base"), g.frames["i"],
                               rtol=0, atol=1e-13)


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
        values, _ = mechanism_joint_values(q[i], T, d, slot=slot)
        assert closure_errors(robot, values, T).max() < 1e-12
        n += 1
    assert n == 150


def test_a_wrong_joint_value_opens_a_loop(tmp_path):
    robot = load(tmp_path)
    values, g = mechanism_joint_values()
    values["b_ujoint_x"] += 1e-6
    assert closure_errors(robot, values, g.T_b_e).max() > 1e-7


def test_other_design_and_setup(tmp_path):
    d = ak.Design(l1=0.34, l2=0.08, l3=0.27, l4=0.12, l5=0.45, tool_length=0.40)
    q = np.array([-0.12, 0.08, 0.50])
    par = ak.parallel.parallel_forward_kinematics(q, d)
    T = np.eye(4)
    T[:3, 3] = par.O_s[0] + np.array([0.05, -0.1, -0.15])
    robot = load(tmp_path, d, T)
    assert robot.joint_map["q1"].limit.lower == -2.0       # unlimited stroke: a wide limit
    sol = ak.forward_kinematics(q, T, d)
    for slot in np.flatnonzero(sol.valid):
        values, _ = mechanism_joint_values(q, T, d, slot=int(slot))
        assert closure_errors(robot, values, T).max() < 1e-13
