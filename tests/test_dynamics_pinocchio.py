"""Pinocchio, a second engine, checks athenakin.dynamics.inverse_dynamics.

Pinocchio's own MJCF parser keeps only the first tree under ``worldbody`` (it drops
carriage B), so the spanning tree is rebuilt here joint by joint from the MJCF that
MuJoCo compiled (``mjcf_from_design(..., masses=)``: body placements, joint axes,
inertias). Pinocchio then gives the tree's inverse dynamics (RNEA) and the
kinematics of the loop closures: their Jacobian ``J_c`` (points that coincide, the
weld at E, the two joint couplings) and their drift ``J_c' v`` (classical
accelerations with ``a = 0``). With ``N`` the joint velocities that close the loops
for unit actuator speeds, the closed chain's actuator forces are
``N^T RNEA(q, N qd, a)`` with ``a`` the joint accelerations that keep the loops
closed (``J_c a = -J_c' v``) and give ``qdd`` at the actuators: nothing of
athenakin's dynamics enters.
"""

import mujoco
import numpy as np
import pytest
from _dynamics_models import with_full_inertias
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin.dynamics import MassModel, inverse_dynamics
from athenakin.robot import REFERENCE_Q
from athenakin.sim import ACTUATED, JOINTS, LOOP_CLOSURES, mechanism_joint_values, mjcf_from_design

pin = pytest.importorskip("pinocchio")

D = ak.Design.default()
T = ak.default_rcm_frame(D)


M = with_full_inertias(MassModel.reference(D), seed=17)   # general inertias, offset centres


def _quat_R(qw):
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, np.asarray(qw, float))
    return R.reshape(3, 3)


@pytest.fixture(scope="module")
def engine():
    mj = mujoco.MjModel.from_xml_string(mjcf_from_design(T, D, masses=M))
    model = pin.Model()
    pin_joint_of_body = {0: 0}
    for b in range(1, mj.nbody):
        parent = int(mj.body_parentid[b])
        placement = pin.SE3(_quat_R(mj.body_quat[b]), mj.body_pos[b].copy())
        nj = int(mj.body_jntnum[b])
        if nj == 0:          # rcm_setup, fixed to the world: only a frame target
            pin_joint_of_body[b] = None
            continue
        assert nj == 1
        j = int(mj.body_jntadr[b])
        axis = mj.jnt_axis[j].copy()
        if mj.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE:
            jm = pin.JointModelRevoluteUnaligned(axis)
        else:
            jm = pin.JointModelPrismaticUnaligned(axis)
        jid = model.addJoint(pin_joint_of_body[parent], jm, placement, mj.joint(j).name)
        Ri = _quat_R(mj.body_iquat[b])
        inertia = pin.Inertia(float(mj.body_mass[b]), mj.body_ipos[b].copy(),
                              Ri @ np.diag(mj.body_inertia[b]) @ Ri.T)
        model.appendBodyToJoint(jid, inertia, pin.SE3.Identity())
        pin_joint_of_body[b] = jid
    sites = {}
    for s in range(mj.nsite):
        jid = pin_joint_of_body[int(mj.site_bodyid[s])]
        if jid is None:
            continue
        name = mj.site(s).name
        sites[name] = model.addFrame(pin.Frame(
            name, jid, pin.SE3(_quat_R(mj.site_quat[s]), mj.site_pos[s].copy()),
            pin.FrameType.OP_FRAME))
    model.gravity.linear = np.array([0.0, 0.0, -9.81])
    assert [model.names[i] for i in range(1, model.njoints)] == list(JOINTS)
    return model, sites


def _closures(model, data, sites, q, v):
    """Constraint Jacobian (rows) and drift J' v of every loop closure."""
    pin.forwardKinematics(model, data, q, v, np.zeros(model.nv))
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    W = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    rows, drift = [], []
    for c in LOOP_CLOSURES:
        if c.kind == "point":
            Ja = pin.getFrameJacobian(model, data, sites[c.a], W)[:3]
            Jb = pin.getFrameJacobian(model, data, sites[c.b], W)[:3]
            aa = pin.getFrameClassicalAcceleration(model, data, sites[c.a], W).linear
            ab = pin.getFrameClassicalAcceleration(model, data, sites[c.b], W).linear
            rows.append(Ja - Jb)
            drift.append(aa - ab)
        elif c.kind == "pose":       # sph_5's frame held at the fixed set-up frame
            rows.append(pin.getFrameJacobian(model, data, sites[c.a], W))
            acc = pin.getFrameClassicalAcceleration(model, data, sites[c.a], W)
            drift.append(np.concatenate([acc.linear, acc.angular]))
        else:                        # joint1 = -joint2
            r = np.zeros((1, model.nv))
            r[0, model.getJointId(c.a) - 1] = 1.0
            r[0, model.getJointId(c.b) - 1] = 1.0
            rows.append(r)
            drift.append(np.zeros(1))
    return np.concatenate(rows), np.concatenate(drift)


def _pinocchio_forces(engine, q, qd, qdd, slot):
    model, sites = engine
    data = model.createData()
    values = mechanism_joint_values(q, T, D, slot=slot).values
    qf = np.array([values[n] for n in JOINTS])
    act = [list(JOINTS).index(n) for n in ACTUATED]
    pas = [i for i in range(model.nv) if i not in act]
    Jc, _ = _closures(model, data, sites, qf, np.zeros(model.nv))
    N = np.zeros((model.nv, 3))
    for j in range(3):
        e = np.zeros(3)
        e[j] = 1.0
        N[act, j] = e
        N[pas, j] = np.linalg.lstsq(Jc[:, pas], -Jc[:, act] @ e, rcond=None)[0]
    assert np.abs(Jc @ N).max() < 1e-12
    v = N @ qd
    Jc, gamma = _closures(model, data, sites, qf, v)
    a = N @ qdd
    a[pas] += np.linalg.lstsq(Jc[:, pas], -gamma - Jc @ (N @ qdd), rcond=None)[0]
    assert np.abs(Jc @ a + gamma).max() < 1e-10
    tau_full = pin.rnea(model, data, qf, v, a)
    return N.T @ tau_full


@pytest.mark.parametrize("slot", [0, 9])
def test_inverse_dynamics_equals_pinocchio(engine, slot):
    rng = np.random.default_rng(slot)
    for _ in range(3):
        q = REFERENCE_Q + rng.uniform(-0.02, 0.02, 3)
        qd = rng.normal(scale=0.2, size=3)
        qdd = rng.normal(scale=1.0, size=3)
        ref = _pinocchio_forces(engine, q, qd, qdd, slot)
        ours = inverse_dynamics(q, qd, qdd, T, D, masses=M, slot=slot)
        # measured 1e-10 N: the export nudges massless and boundary inertias by 1e-12
        # kg m^2 and 1e-9 relative (sim._mjcf_masses.TINY_INERTIA)
        assert_allclose(ours, ref, rtol=0, atol=1e-8 * max(1.0, np.abs(ref).max()))
