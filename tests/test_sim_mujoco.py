"""The MJCF model in MuJoCo reproduces athenakin's forward kinematics.

MuJoCo integrates the exported tree under its equality constraints; nothing of
Eq. 7-16 is in it. Driving the actuators to q and letting it settle must land on
the FK solution whose labels MuJoCo's state carries, in all 16 slots, to 1e-9
(m and rad). Measured: about 1e-12. Why that tolerance: without gravity there
is no load, so MuJoCo's soft constraints (Baumgarte-like, time constant 4 ms)
relax to zero violation and the servos to zero error; the hold ends when every
speed is below 1e-11, which leaves about 1e-12 of motion, above double rounding
through 18 joints (about 1e-15) and MuJoCo's solver tolerance (1e-12).
"""

import mujoco
import numpy as np
import pytest

import athenakin as ak
from athenakin.robot import REFERENCE_Q
from athenakin.sim import (
    ACTUATED,
    JOINTS,
    LOOP_CLOSURES,
    check_fk_with_mujoco,
    load_model,
    mechanism_joint_values,
    mjcf_from_design,
    sample_reachable_q,
    settle,
)

SEED = 6
#: Agreement required between MuJoCo's settled state and the FK (m, rad).
TOL = 1e-9


def equality_residual(data):
    rows = data.efc_type[:data.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY
    return np.abs(data.efc_pos[:data.nefc][rows]).max()


def assert_agrees(res, slot):
    assert np.all(res.slot == slot), res.slot
    assert np.all(res.nearest_slot == slot), res.nearest_slot
    for name in ("pose_error", "tip_error", "axis_error", "joint_error", "constraint_residual"):
        worst = float(np.max(getattr(res, name)))
        assert worst <= TOL, f"{name} = {worst:.2e} > {TOL:.0e}: {res.summary()}"
    np.testing.assert_allclose(res.q_reached, res.q, rtol=0, atol=TOL)


def test_model_structure():
    m = load_model()
    assert [m.joint(i).name for i in range(m.njnt)] == list(JOINTS)
    assert m.nq == m.nv == 18
    assert [m.actuator(i).name for i in range(m.nu)] == list(ACTUATED)
    for i, name in enumerate(ACTUATED):
        assert m.actuator_trnid[i, 0] == m.joint(name).id
        np.testing.assert_allclose(m.actuator_ctrlrange[i], [ak.Design.default().stroke_min[i],
                                                              ak.Design.default().stroke_max[i]])
    kinds = sorted(int(t) for t in m.eq_type)
    assert kinds == sorted([int(mujoco.mjtEq.mjEQ_CONNECT)] * 3 + [int(mujoco.mjtEq.mjEQ_WELD)]
                           + [int(mujoco.mjtEq.mjEQ_JOINT)] * 2)
    assert [m.equality(i).name for i in range(m.neq)] == [c.name for c in LOOP_CLOSURES]


def test_mobility_is_three():
    """At the keyframe the loop closures leave exactly the 3 actuated freedoms."""
    m = load_model()
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_forward(m, d)
    J = np.zeros((d.nefc, m.nv))
    if mujoco.mj_isSparse(m):
        mujoco.mju_sparse2dense(J, d.efc_J, d.efc_J_rownnz, d.efc_J_rowadr, d.efc_J_colind)
    else:
        J = d.efc_J[:d.nefc * m.nv].reshape(d.nefc, m.nv)
    assert np.linalg.matrix_rank(J, tol=1e-9) == m.nv - 3
    act = np.zeros((3, m.nv))
    for i, name in enumerate(ACTUATED):
        act[i, m.joint(name).dofadr[0]] = 1.0
    assert np.linalg.matrix_rank(np.vstack([J, act]), tol=1e-9) == m.nv


@pytest.mark.parametrize("slot", range(16))
def test_keyframe_of_every_slot_is_assembled(slot):
    """MuJoCo's own kinematics at our joint values closes every loop and puts E at T_b_e."""
    m = load_model(slot=slot)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_forward(m, d)
    assert equality_residual(d) < 1e-13
    jv = mechanism_joint_values(slot=slot)
    st = jv.state
    T = np.eye(4)
    T[:3, :3] = d.body("instrument").xmat.reshape(3, 3)
    T[:3, 3] = d.body("instrument").xpos
    np.testing.assert_allclose(T, st.frame("instrument"), rtol=0, atol=1e-13)
    np.testing.assert_allclose(d.body("sph_5").xmat.reshape(3, 3), jv.T_b_e[:3, :3], atol=1e-13)
    np.testing.assert_allclose(d.site("tool_tip").xpos, st["tip"], atol=1e-13)
    np.testing.assert_allclose(d.site("platform_oi").xpos, st["O_i"], atol=1e-13)
    np.testing.assert_allclose(d.body("k2_arm").xpos, st["C"], atol=1e-13)


def test_mujoco_settles_on_fk_many_configurations():
    """The heart: 150 seeded targets, every joint disturbed by up to 0.02 at the start."""
    q = sample_reachable_q(150, rng=SEED)
    res = check_fk_with_mujoco(q, perturb=0.02, rng=SEED)
    assert_agrees(res, 0)


@pytest.mark.parametrize("slot", range(16))
def test_mujoco_settles_on_fk_in_every_slot(slot):
    q = sample_reachable_q(3, slot=slot, rng=SEED + slot)
    res = check_fk_with_mujoco(q, start_slot=slot, perturb=0.02, rng=SEED + slot)
    assert_agrees(res, slot)


def test_other_design_and_setup():
    """A different design and RCM frame (built from one of its configurations)."""
    d = ak.Design(l1=0.34, l2=0.08, l3=0.27, l4=0.12, l5=0.45, q_min=(-0.35, -0.1, 0.2),
                  q_max=(0.1, 0.35, 0.8), tool_length=0.40)
    home = np.array([-0.12, 0.08, 0.50])
    par = ak.parallel.parallel_forward_kinematics(home, d)
    x_e = np.array([-0.2, -0.4, -1.0]) / np.linalg.norm([-0.2, -0.4, -1.0])
    z_e = np.cross(x_e, [0.0, 1.0, 0.0])
    z_e /= np.linalg.norm(z_e)
    T = np.eye(4)
    T[:3, :3] = np.stack([x_e, np.cross(z_e, x_e), z_e], axis=-1)
    T[:3, 3] = par.O_s[0] + 0.18 * x_e
    q = sample_reachable_q(12, T, d, home_q=home, radius=0.06, rng=SEED)
    res = check_fk_with_mujoco(q, T, d, home_q=home, perturb=0.02, rng=SEED)
    assert_agrees(res, 0)


def test_near_ujoint_singularity_converges_slower():
    """Near sin u2 = 0 the mechanism is soft in one direction: MuJoCo still gets there, slowly."""
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    q_far = sample_reachable_q(1, rng=SEED)
    q_near = np.array([-0.0479, 0.1311, 0.5632])     # sin u2 = 0.10 in slot 0
    sol = ak.forward_kinematics(q_near, T, d)
    assert abs(np.sin(sol.u[0, 1])) < 0.11
    res = check_fk_with_mujoco(np.vstack([q_far, q_near]), settle_time=20.0)
    assert_agrees(res, 0)
    assert res.hold_time[1] > 2 * res.hold_time[0]


def test_mujoco_sees_the_parallel_singularity_at_h_zero():
    """With q held, MuJoCo's constraint Jacobian loses a rank at h = (q1 - q2)/2 = 0, like |h|.

    The core found this singularity of the parallel module (dO_s/dq is singular at
    h = 0); MuJoCo's model of the mechanism, built from bars and joints, agrees.
    """
    m = load_model()
    d = mujoco.MjData(m)
    act = np.zeros((3, m.nv))
    for i, name in enumerate(ACTUATED):
        act[i, m.joint(name).dofadr[0]] = 1.0

    def smallest_singular_value(q):
        v = mechanism_joint_values(q).values
        d.qpos[:] = [v[n] for n in JOINTS]
        mujoco.mj_forward(m, d)
        J = np.zeros((d.nefc, m.nv))
        if mujoco.mj_isSparse(m):
            mujoco.mju_sparse2dense(J, d.efc_J, d.efc_J_rownnz, d.efc_J_rowadr, d.efc_J_colind)
        else:
            J = d.efc_J[:d.nefc * m.nv].reshape(d.nefc, m.nv)
        return np.linalg.svd(np.vstack([J, act]), compute_uv=False)[-1]

    hs = np.array([0.04, 0.01, 1e-3, 1e-4])
    s = np.array([smallest_singular_value([-0.01 - h, -0.01 + h, 0.5]) for h in hs])
    np.testing.assert_allclose(s / hs, s[0] / hs[0], rtol=0.15)    # proportional to |h|
    assert smallest_singular_value([-0.01, -0.01, 0.5]) < 1e-12


def test_gravity_opens_the_loops_by_the_constraint_compliance_only():
    """Under gravity the servos sag and the soft loops open a little; FK at the reached q holds."""
    q = sample_reachable_q(3, rng=SEED)
    res = check_fk_with_mujoco(q, gravity=True, settle_time=3.0, speed_tol=0.0)
    sag = np.abs(res.q_reached - q).max()
    assert 1e-6 < sag < 1e-3
    assert 1e-7 < res.constraint_residual.max() < 1e-4
    assert res.tip_error.max() < 1e-4
    assert np.all(res.slot == 0)


def test_export_needs_a_valid_slot():
    with pytest.raises(ak.StrokeLimitError):
        mjcf_from_design(q=[0.2, 0.1, 0.45])
    with pytest.raises(ak.InvalidInputError, match="slot"):
        mjcf_from_design(slot=16)


def test_gravity_switch():
    assert 'gravity="0 0 -9.81"' in mjcf_from_design()
    assert 'gravity="0 0 0"' in mjcf_from_design(gravity=False)
    m = load_model(gravity=True)
    np.testing.assert_allclose(m.opt.gravity, [0, 0, -9.81])


def test_keyframe_q_is_the_requested_q():
    q = np.array([-0.12, 0.07, 0.42])
    m = load_model(q=q, slot=5)
    np.testing.assert_allclose(m.key_ctrl[0], q)
    v = mechanism_joint_values(q, slot=5).values
    np.testing.assert_allclose(m.key_qpos[0], [v[n] for n in JOINTS], atol=1e-15)
    assert np.all(REFERENCE_Q != q)


def test_check_detects_a_micrometre_error():
    """The comparison is sharp: FK of a design whose l4 is 1 um longer misses by about 1 um."""
    d = ak.Design.default()
    q = sample_reachable_q(1, rng=SEED)[0]
    m = load_model(design=d)
    data = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, data, 0)
    settle(m, data, q)
    mujoco.mj_forward(m, data)
    tip = data.site("tool_tip").xpos
    good = mechanism_joint_values(q, design=d).state["tip"]
    wrong_design = ak.Design(l1=d.l1, l2=d.l2, l3=d.l3, l4=d.l4 + 1e-6, l5=d.l5,
                             q_min=d.q_min, q_max=d.q_max, tool_length=d.tool_length)
    wrong = mechanism_joint_values(q, ak.default_rcm_frame(d), wrong_design).state["tip"]
    assert np.linalg.norm(tip - good) < TOL
    assert np.linalg.norm(tip - wrong) > 100 * TOL


def test_audit_arguments_named():
    """Audit of issue 13: settle(None, ...), perturb=None, slot=nan, radius=nan and an
    unreachable sample were AttributeError / TypeError / IndexError / RuntimeError."""
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    model = ak.sim.load_model(T, d)
    data = mujoco.MjData(model)
    with pytest.raises(TypeError, match="model"):
        ak.sim.settle(None, data, REFERENCE_Q)
    with pytest.raises(TypeError, match="data"):
        ak.sim.settle(model, None, REFERENCE_Q)
    with pytest.raises(ak.InvalidInputError, match="ramp_time"):
        ak.sim.settle(model, data, REFERENCE_Q, ramp_time=1e200)
    with pytest.raises(TypeError, match="perturb"):
        ak.sim.check_fk_with_mujoco(REFERENCE_Q, T, d, perturb=None)
    with pytest.raises(ak.InvalidInputError, match="slot"):
        ak.sim.sample_reachable_q(2, T, d, slot=float("nan"))
    with pytest.raises(ak.InvalidInputError, match="radius"):
        ak.sim.sample_reachable_q(2, T, d, radius=float("nan"))
    with pytest.raises(ak.OutOfWorkspaceError, match="reachable"):
        ak.sim.sample_reachable_q(2, np.eye(4), d, rng=1, max_tries=2)
    with pytest.raises(TypeError, match="model_name"):
        ak.sim.mjcf_from_design(T, d, model_name=None)
    with pytest.raises(TypeError, match="rng"):
        ak.sim.sample_reachable_q(2, T, d, rng=[[1.0, 2.0, 3.0], [4.0]])
