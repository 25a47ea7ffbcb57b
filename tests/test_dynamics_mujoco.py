"""MuJoCo, an engine nobody here wrote, checks athenakin.dynamics.

The MJCF export with ``masses=`` (:func:`athenakin.sim.mjcf_from_design`) carries the
mass model's inertias in the same body frames, motor actuators on ``q1, q2, q3`` and
no damping or armature. MuJoCo closes the loops with its own (soft) equality
constraints and integrates the 18-joint tree; athenakin never enters its dynamics.

How the constraint solver is tightened for these checks (``_tight``): Newton solver,
tolerance 1e-12, 100 iterations (the export's own settings); impedance ``solimp``
raised to its maximum 0.9999 at zero violation (MuJoCo's regularisation ``R`` is then
``1e-4`` of the constraint-space inertia, so accelerations agree to about 1e-4
relative); time constant ``solref`` 0.5 ms with RK4 steps of 0.1 ms (the constraint
error left by ``R`` is pulled back within a few steps).
"""

import mujoco
import numpy as np
import pytest
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin.dynamics import (
    MassModel,
    actuator_forces,
    forward_dynamics,
    inverse_dynamics,
    mass_matrix,
    mechanical_energy,
)
from athenakin.robot import REFERENCE_Q
from athenakin.sim import ACTUATED, mjcf_from_design

D = ak.Design.default()
T = ak.default_rcm_frame(D)
M = MassModel.reference(D)
#: The planned motion q(t) = q0 + A (1 - cos 2 pi t) over 1 s.
AMPLITUDE = np.array([0.02, -0.015, 0.03])
#: Largest allowed distance of MuJoCo's actuators from the plan over 1 s, m.
DRIFT_TOL = 1e-6


def _tight(model, dt=1e-4):
    model.opt.timestep = dt
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    model.opt.solver = mujoco.mjtSolver.mjSOL_NEWTON
    model.opt.tolerance = 1e-12
    model.opt.iterations = 100
    model.eq_solref[:] = [5 * dt, 1.0]
    model.eq_solimp[:] = [0.9999, 0.9999, 0.001, 0.5, 2.0]
    return model


def _model(q=REFERENCE_Q, masses=M, slot=0):
    xml = mjcf_from_design(T, D, q=q, masses=masses, slot=slot)
    model = _tight(mujoco.MjModel.from_xml_string(xml))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    mujoco.mj_forward(model, data)
    return model, data


def _actuated(model):
    dof = [int(model.jnt_dofadr[model.joint(n).id]) for n in ACTUATED]
    qpos = [int(model.jnt_qposadr[model.joint(n).id]) for n in ACTUATED]
    return dof, qpos


def _velocity_map(model, data):
    """N (nv x 3): the joint velocities that close the loops for unit actuator speeds.

    Solved from MuJoCo's own constraint Jacobian (exact, no differences).
    """
    dof, _ = _actuated(model)
    J = data.efc_J.reshape(data.nefc, model.nv)
    passive = [i for i in range(model.nv) if i not in dof]
    N = np.zeros((model.nv, 3))
    for j in range(3):
        e = np.zeros(3)
        e[j] = 1.0
        v, *_ = np.linalg.lstsq(J[:, passive], -J[:, dof] @ e, rcond=None)
        N[dof, j] = e
        N[passive, j] = v
    assert np.abs(J @ N).max() < 1e-12
    return N


def test_export_is_backward_compatible_and_carries_the_masses():
    plain = mujoco.MjModel.from_xml_string(mjcf_from_design(T, D))
    assert [plain.actuator(i).name for i in range(plain.nu)] == list(ACTUATED)
    assert plain.actuator_gaintype[0] == mujoco.mjtGain.mjGAIN_FIXED
    assert plain.actuator_biastype[0] == mujoco.mjtBias.mjBIAS_AFFINE   # position servos
    model, data = _model()
    assert model.actuator_biastype[0] == mujoco.mjtBias.mjBIAS_NONE     # motors
    assert np.all(model.dof_damping == 0) and np.all(model.dof_armature == 0)
    moving = sum(model.body_mass[model.body(n).id] for n in
                 ("carriage_a", "carriage_b", "link_a1", "link_b1", "link_a3", "link_b3",
                  "carrier", "k2_arm", "k2_rod", "platform", "instrument", "guide", "sph_3",
                  "sph_4"))
    assert_allclose(moving, M.total_mass, rtol=1e-9)
    # the keyframe holds the static forces
    assert_allclose(data.ctrl, actuator_forces(REFERENCE_Q, T, D, masses=M), rtol=0, atol=1e-12)


@pytest.mark.parametrize("slot", [0, 9])
def test_mass_matrix_and_energy_equal_mujocos(slot):
    model, data = _model(slot=slot)
    N = _velocity_map(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    M_mj = N.T @ full @ N
    assert_allclose(M_mj, mass_matrix(REFERENCE_Q, T, D, masses=M, slot=slot), rtol=0,
                    atol=1e-9)
    # potential energy: MuJoCo adds the fixed bodies (rcm_setup, sph_5) at their places
    model.opt.enableflags |= mujoco.mjtEnableBit.mjENBL_ENERGY
    qd = np.array([0.05, -0.1, 0.07])
    data.qvel[:] = N @ qd
    mujoco.mj_forward(model, data)
    kin = mechanical_energy(REFERENCE_Q, qd, T, D, masses=M, slot=slot).kinetic
    assert_allclose(data.energy[1], kin, rtol=1e-9)


@pytest.mark.parametrize("slot", [0, 9])
def test_forward_dynamics_agrees_with_mujoco(slot):
    """At rest (MuJoCo's constraint acceleration leaves out the term J' qd, which its
    Baumgarte stabilisation corrects afterwards; the velocity terms are checked by the
    trajectory test below and by Lagrange's equations in test_dynamics.py)."""
    model, data = _model(slot=slot)
    dof, _ = _actuated(model)
    N = _velocity_map(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    rng = np.random.default_rng(5)
    assert np.abs(data.qvel).max() == 0
    for _ in range(3):
        tau = rng.normal(scale=5.0, size=3)
        data.ctrl[:] = tau
        mujoco.mj_forward(model, data)
        ours = forward_dynamics(REFERENCE_Q, np.zeros(3), tau, T, D, masses=M, slot=slot)
        # MuJoCo's solver (soft constraints, impedance 0.9999): to about 1e-3 relative
        assert_allclose(data.qacc[dof], ours, rtol=0, atol=2e-3 * max(1.0, np.abs(ours).max()))
        # MuJoCo's M, gravity and constraint Jacobian with the loops closed exactly
        # (at rest J' qd = 0): N^T M N qdd = N^T (qfrc_actuator - qfrc_bias)
        hard = np.linalg.solve(N.T @ full @ N, N.T @ (data.qfrc_actuator - data.qfrc_bias))
        assert_allclose(hard, ours, rtol=0, atol=1e-9 * max(1.0, np.abs(ours).max()))


def test_mujoco_driven_by_inverse_dynamics_follows_the_plan():
    model, data = _model()
    _, qpos = _actuated(model)
    dt = model.opt.timestep
    n = int(round(1.0 / dt))
    w = 2 * np.pi
    # forces at mid-step (MuJoCo holds ctrl through the RK4 stages)
    tm = ((np.arange(n) + 0.5) * dt)[:, None]
    q = REFERENCE_Q + AMPLITUDE * (1 - np.cos(w * tm))
    tau = inverse_dynamics(q, AMPLITUDE * w * np.sin(w * tm), AMPLITUDE * w * w * np.cos(w * tm),
                           T, D, masses=M)
    drift = 0.0
    for k in range(n):
        data.ctrl[:] = tau[k]
        mujoco.mj_step(model, data)
        plan = REFERENCE_Q + AMPLITUDE * (1 - np.cos(w * (k + 1) * dt))
        drift = max(drift, float(np.abs(data.qpos[qpos] - plan).max()))
    assert drift < DRIFT_TOL, f"MuJoCo left the plan by {drift:.2e} m"
    # the forces matter: without the inertial part MuJoCo leaves the plan by far more
    data2 = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data2, 0)
    g = actuator_forces(q, T, D, masses=M)
    far = 0.0
    for k in range(n // 4):
        data2.ctrl[:] = g[k]
        mujoco.mj_step(model, data2)
        plan = REFERENCE_Q + AMPLITUDE * (1 - np.cos(w * (k + 1) * dt))
        far = max(far, float(np.abs(data2.qpos[qpos] - plan).max()))
    assert far > 100 * DRIFT_TOL
