"""Statics, inverse / forward dynamics and force capability of the closed chain.

Independent checks: the body frames against the mechanism's points
(athenakin._mechanism), the jets' velocities against finite differences of positions,
the actuator forces against finite differences of the Lagrangian ``L = K - V`` (no
Jacobian of the library enters them), and the power balance ``tau . qd = dE/dt``.
Finite-difference tolerances: central differences with step ``h`` err by about
``h^2 |f'''|`` plus ``eps |f| / h``; the bounds below are a few times those.
"""

import numpy as np
import pytest
from _dynamics_models import with_full_inertias
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin._mechanism import mechanism_points
from athenakin.dynamics import (
    MassModel,
    SimulationStoppedError,
    actuator_forces,
    force_capability,
    forward_dynamics,
    inverse_dynamics,
    mass_matrix,
    max_tip_force,
    mechanical_energy,
    simulate,
    statics,
)
from athenakin.dynamics._core import evaluate
from athenakin.dynamics._kinematics import J2, body_jets
from athenakin.errors import InvalidInputError, OutOfWorkspaceError
from athenakin.robot import REFERENCE_Q

D = ak.Design.default()
T = ak.default_rcm_frame(D)
M = MassModel.reference(D)
SLOTS = (0, 3, 5, 9, 14)


MF = with_full_inertias(M, seed=11)   # general inertias, offset centres


@pytest.fixture(scope="module")
def states():
    rng = np.random.default_rng(21)
    q = REFERENCE_Q + rng.uniform(-0.03, 0.03, (6, 3))
    qd = rng.normal(scale=0.2, size=(6, 3))
    qdd = rng.normal(scale=1.0, size=(6, 3))
    return q, qd, qdd


def _jets(q, qd, qdd, slot):
    n = q.shape[0]
    shape = (n, 1)
    qj = [J2(q[:, i, None].copy(), qd[:, i, None].copy(), 0.5 * qdd[:, i, None])
          for i in range(3)]
    z = np.zeros(shape)
    rcm = [J2(np.full(shape, T[i, 3]), z, z) for i in range(3)]
    R_e = [[J2(np.full(shape, T[i, j]), z, z) for j in range(3)] for i in range(3)]
    return body_jets(qj, rcm, R_e, D, slot)


def _c0(v):
    return np.stack([np.broadcast_to(e.c0[:, 0] if isinstance(e, J2) else e, (6,))
                     for e in v], -1)


@pytest.mark.parametrize("slot", SLOTS)
def test_body_frames_sit_on_the_mechanism_points(states, slot):
    q = states[0]
    mp = mechanism_points(q, T, D, slot=slot)
    bj = _jets(q, states[1], states[2], slot)
    assert_allclose(_c0(bj.tip), mp["tip"], rtol=0, atol=1e-12)
    for body, point in [("carriage_a", "A"), ("carriage_b", "B"), ("carrier", "D"),
                        ("actuator", "C"), ("platform", "O_i"), ("instrument", "O_s"),
                        ("guide", "RCM")]:
        assert_allclose(_c0(bj.origin[body]), mp[point], rtol=0, atol=1e-12)

    def z_axis(body, col=2):
        R = bj.rotation[body]
        return _c0([R[i][col] for i in range(3)])

    def unit(v):
        return v / np.linalg.norm(v, axis=-1, keepdims=True)

    for body, (a, b), col in [("link_a", ("A", "O_i"), 2), ("link_b", ("B", "O_i"), 2),
                              ("link_ad", ("A", "D"), 0), ("link_bd", ("B", "D"), 0),
                              ("actuator", ("C", "O_i"), 2), ("platform", ("O_i", "O_s"), 2),
                              ("instrument", ("O_s", "tip"), 2)]:
        assert_allclose(z_axis(body, col), unit(mp[b] - mp[a]), rtol=0, atol=1e-12)
    # every rotation is orthonormal
    for body, R in bj.rotation.items():
        Rm = np.stack([_c0(row) for row in R], -2)
        assert_allclose(Rm @ np.swapaxes(Rm, -1, -2), np.broadcast_to(np.eye(3), Rm.shape),
                        rtol=0, atol=1e-13, err_msg=body)


@pytest.mark.parametrize("slot", (0, 9))
def test_jet_velocities_and_accelerations_match_finite_differences(states, slot):
    q, qd, qdd = states
    ev = evaluate(q, qd, qdd, np.broadcast_to(T, (6, 4, 4)), D, MF, slot)
    h = 1e-4

    def com(t):
        qt = q + qd * t + 0.5 * qdd * t * t
        return evaluate(qt, qd * 0, qd * 0, np.broadcast_to(T, (6, 4, 4)), D, MF, slot).p

    p_m, p_0, p_p = com(-h), com(0.0), com(h)
    assert_allclose(ev.v[:, 0], (p_p - p_m) / (2 * h), rtol=0, atol=2e-8)
    assert_allclose(ev.a, (p_p - 2 * p_0 + p_m) / h ** 2, rtol=0, atol=2e-5)


def _lagrangian_forces(q, qd, qdd, masses, slot, f_tip=None, h=1e-5):
    """tau = d/dt dL/dqd - dL/dq by central differences of the energies alone."""
    def L(qq, vv):
        e = mechanical_energy(qq, vv, T, D, masses=masses, slot=slot)
        k, v = e.kinetic, e.potential
        return k - v

    E = np.eye(3)

    def dL_dqd(qq, vv):
        return np.array([(L(qq, vv + h * e) - L(qq, vv - h * e)) / (2 * h) for e in E])

    def dL_dq(qq, vv):
        return np.array([(L(qq + h * e, vv) - L(qq - h * e, vv)) / (2 * h) for e in E])

    dt = 1e-5
    ddt = (dL_dqd(q + dt * qd + 0.5 * dt * dt * qdd, qd + dt * qdd)
           - dL_dqd(q - dt * qd + 0.5 * dt * dt * qdd, qd - dt * qdd)) / (2 * dt)
    return ddt - dL_dq(q, qd)


@pytest.mark.parametrize("slot", (0, 5, 9))
def test_inverse_dynamics_is_lagrange(states, slot):
    q, qd, qdd = states
    for i in range(2):
        tau = inverse_dynamics(q[i], qd[i], qdd[i], T, D, masses=MF, slot=slot)
        ref = _lagrangian_forces(q[i], qd[i], qdd[i], MF, slot)
        assert_allclose(tau, ref, rtol=0, atol=2e-5 * max(1.0, np.abs(ref).max()))


@pytest.mark.parametrize("slot", SLOTS)
def test_statics_is_the_gradient_of_the_potential(states, slot):
    q = states[0][:3]
    f = actuator_forces(q, T, D, masses=MF, slot=slot)
    h = 1e-6
    grad = np.stack([(mechanical_energy(q + h * e, 0 * q, T, D, masses=MF, slot=slot).potential
                      - mechanical_energy(q - h * e, 0 * q, T, D, masses=MF, slot=slot).potential)
                     / (2 * h) for e in np.eye(3)], -1)
    assert_allclose(f, grad, rtol=0, atol=1e-7)


def test_tip_force_and_tip_jacobian(states):
    q = states[0][0]
    st = statics(q, T, D, masses=MassModel.zeros(), tip_force=[1.0, -2.0, 3.0])
    tip = lambda qq: mechanism_points(qq, T, D)["tip"]  # noqa: E731
    h = 1e-6
    J = np.stack([(tip(q + h * e) - tip(q - h * e)) / (2 * h) for e in np.eye(3)], -1)
    assert_allclose(st.tip_jacobian, J, rtol=0, atol=1e-8)
    assert_allclose(st.forces, -J.T @ [1.0, -2.0, 3.0], rtol=0, atol=1e-7)
    # a tip force alone: the RCM mount carries no moment
    assert_allclose(st.rcm_moment, 0.0, rtol=0, atol=1e-12)


def test_rcm_load_is_the_gradient_of_the_potential_in_the_rcm(states):
    q = states[0][1]
    st = statics(q, T, D, masses=MF)

    def V(Tx):
        return mechanical_energy(q, 0 * q, Tx, D, masses=MF).potential

    h = 1e-6
    grad_c, grad_w = [], []
    for k in range(3):
        Tp, Tm = T.copy(), T.copy()
        Tp[k, 3] += h
        Tm[k, 3] -= h
        grad_c.append((V(Tp) - V(Tm)) / (2 * h))
        w = np.zeros(3)
        w[k] = h
        Rp = _rot(w) @ T[:3, :3]
        Rm = _rot(-w) @ T[:3, :3]
        Tp, Tm = T.copy(), T.copy()
        Tp[:3, :3], Tm[:3, :3] = Rp, Rm
        grad_w.append((V(Tp) - V(Tm)) / (2 * h))
    # the load the robot puts on its mount is -dV/d(mount displacement)
    assert_allclose(st.rcm_force, -np.array(grad_c), rtol=0, atol=1e-7)
    assert_allclose(st.rcm_moment, -np.array(grad_w), rtol=0, atol=1e-7)
    # with massless spherical links the mount carries no moment about the RCM
    data = MF.to_mapping()
    for name in ("sphere_link_1", "sphere_link_2"):
        data.pop(name)
    st0 = statics(q, T, D, masses=MassModel.from_mapping(data))
    assert_allclose(st0.rcm_moment, 0.0, rtol=0, atol=1e-12)


def _rot(w):
    th = np.linalg.norm(w)
    k = w / th
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K


def test_mass_matrix_spd_and_kinetic_energy(states):
    q, qd, _ = states
    Mq = mass_matrix(q, T, D, masses=MF)
    assert_allclose(Mq, np.swapaxes(Mq, -1, -2), rtol=0, atol=1e-14)
    assert np.all(np.linalg.eigvalsh(Mq) > 0.1)
    kin = mechanical_energy(q, qd, T, D, masses=MF).kinetic
    assert_allclose(kin, 0.5 * np.einsum("ni,nij,nj->n", qd, Mq, qd), rtol=1e-13, atol=0)


def test_forward_inverts_inverse_and_batch_equals_loop(states):
    q, qd, qdd = states
    Tb = np.broadcast_to(T, (6, 4, 4))
    tau = inverse_dynamics(q, qd, qdd, Tb, D, masses=MF, tip_force=[0.5, 0, -1])
    for i in range(6):
        assert_allclose(tau[i], inverse_dynamics(q[i], qd[i], qdd[i], T, D, masses=MF,
                                                 tip_force=[0.5, 0, -1]), rtol=0, atol=1e-13)
    back = forward_dynamics(q, qd, tau, T, D, masses=MF, tip_force=[0.5, 0, -1])
    assert_allclose(back, qdd, rtol=0, atol=1e-11)
    assert tau.shape == (6, 3)
    assert inverse_dynamics(q[0], qd[0], qdd[0], T, D).shape == (3,)


def test_power_balance_along_a_trajectory():
    """tau . qd = dE/dt (E = K + V) along q(t) = q0 + A (1 - cos w t)."""
    A = np.array([0.02, -0.015, 0.03])
    w = 2 * np.pi
    t = np.linspace(0.0, 1.0, 401)[:, None]
    q = REFERENCE_Q + A * (1 - np.cos(w * t))
    qd = A * w * np.sin(w * t)
    qdd = A * w * w * np.cos(w * t)
    tau = inverse_dynamics(q, qd, qdd, T, D, masses=MF)
    power = np.einsum("ni,ni->n", tau, qd)
    h = 1e-6
    tt = t[:, 0]

    def E(s):
        qs = REFERENCE_Q + A * (1 - np.cos(w * s[:, None]))
        return mechanical_energy(qs, A * w * np.sin(w * s[:, None]), T, D, masses=MF).total

    dE = (E(tt + h) - E(tt - h)) / (2 * h)
    assert_allclose(power, dE, rtol=0, atol=1e-6 * np.abs(power).max())


def test_simulate_conserves_energy_and_follows_inverse_dynamics():
    q0 = REFERENCE_Q.copy()
    f0 = actuator_forces(q0, T, D, masses=M)
    sim = simulate(q0, [0.05, -0.02, 0.03], f0, T, D, masses=M, duration=0.2, dt=1e-3)
    # constant forces that hold the weight: E_mech - f0 . (q - q0) is conserved
    e = mechanical_energy(sim.q, sim.qd, T, D, masses=M)
    kin, pot = e.kinetic, e.potential
    work = (sim.q - q0) @ f0
    e = kin + pot - work
    assert_allclose(e, e[0], rtol=0, atol=1e-9)
    tau = inverse_dynamics(sim.q, sim.qd, sim.qdd, T, D, masses=M)
    assert_allclose(tau, np.broadcast_to(f0, tau.shape), rtol=0, atol=1e-9)


def test_simulate_stops_at_a_stroke_limit():
    q0 = np.array([-0.295, -0.05, 0.45])               # 5 mm above the stroke of q1 (-0.30)
    f = actuator_forces(q0, T, D, masses=M) + [-20.0, 0.0, 0.0]
    with pytest.raises(SimulationStoppedError, match="q1 = .* left its stroke") as exc:
        simulate(q0, np.zeros(3), f, T, D, masses=M, duration=1.0, dt=2e-3)
    assert 0 < exc.value.t < 1.0
    assert exc.value.partial.q.shape[1] == 3
    assert np.all(exc.value.partial.q[:, 0] >= -0.30)


def test_capability_polytope():
    q = REFERENCE_Q
    cap = force_capability(q, T, D, masses=M, f_max=[60.0, 60.0, 80.0])
    for k in range(8):
        f = statics(q, T, D, masses=M, tip_force=cap.vertices[k]).forces
        corner = [(60.0 if k & 1 else -60.0), (60.0 if k & 2 else -60.0),
                  (80.0 if k & 4 else -80.0)]
        assert_allclose(f, corner, rtol=0, atol=1e-9)
    assert cap.min_force > 0
    s = max_tip_force(q, cap.weakest_direction, T, D, masses=M, f_max=[60.0, 60.0, 80.0])
    assert_allclose(s, cap.min_force, rtol=1e-12)
    rng = np.random.default_rng(2)
    u = rng.normal(size=(50, 3))
    u /= np.linalg.norm(u, axis=-1, keepdims=True)
    s = max_tip_force(q, u, T, D, masses=M, f_max=[60.0, 60.0, 80.0])
    assert np.all(s >= cap.min_force - 1e-9)
    # at s the forces touch a limit and within it they do not exceed one
    f_at = statics(q, T, D, masses=M, tip_force=s[:, None] * u).forces
    lim = np.array([60.0, 60.0, 80.0])
    assert_allclose(np.max(np.abs(f_at) / lim, axis=-1), 1.0, rtol=0, atol=1e-9)


def test_named_errors():
    with pytest.raises(InvalidInputError, match="q: expected finite values"):
        actuator_forces([np.nan, 0.1, 0.45], T, D)
    with pytest.raises(InvalidInputError, match="slot: expected an integer in 0..15"):
        actuator_forces(REFERENCE_Q, T, D, slot=16)
    with pytest.raises(TypeError, match="masses: expected a MassModel"):
        actuator_forces(REFERENCE_Q, T, D, masses={"link_a": 1.0})
    with pytest.raises(InvalidInputError, match="tip_force: expected shape"):
        actuator_forces(REFERENCE_Q, T, D, tip_force=[1.0, 2.0])
    with pytest.raises(OutOfWorkspaceError, match="slot 0 holds no valid configuration"):
        actuator_forces([-0.10, 0.10, 5.0], T, D)
    f = actuator_forces([[-0.10, 0.10, 5.0], list(REFERENCE_Q)], T, D, errors="flag")
    assert np.all(np.isnan(f[0])) and np.all(np.isfinite(f[1]))
    with pytest.raises(InvalidInputError, match="f_min <= f_max"):
        force_capability(REFERENCE_Q, T, D, f_max=1.0, f_min=2.0)
    with pytest.raises(InvalidInputError, match="duration: expected a positive"):
        simulate(REFERENCE_Q, np.zeros(3), np.zeros(3), T, D, duration=0.0)


def test_d_on_the_rail_is_a_named_singularity():
    q = np.array([-0.28, 0.22, 0.45])                  # |q1 - q2| = 2 l3: D on the rail
    from athenakin.errors import SingularConfigurationError
    with pytest.raises(SingularConfigurationError, match="singular set of the dynamics"):
        actuator_forces(q, T, D)
    st = statics(np.stack([q, REFERENCE_Q]), T, D, errors="flag")
    assert st.valid.tolist() == [False, True]
    assert np.all(np.isnan(st.forces[0])) and np.all(np.isfinite(st.forces[1]))


@pytest.mark.parametrize("slot", (0, 9, 14))
def test_numba_kernel_equals_the_numpy_jets(states, slot):
    if not ak._backend.numba_available():
        pytest.skip("numba not available here (or ATHENAKIN_BACKEND=numpy)")
    q, qd, qdd = states
    kw = dict(masses=MF, slot=slot, tip_force=[0.3, -1.0, 2.0], gravity=[0.1, 0.2, -9.8])
    ref = inverse_dynamics(q, qd, qdd, T, D, backend="numpy", **kw)
    fast = inverse_dynamics(q, qd, qdd, T, D, backend="numba", **kw)
    assert_allclose(fast, ref, rtol=0, atol=1e-12)
    Tb = np.broadcast_to(T, (6, 4, 4))
    assert_allclose(inverse_dynamics(q, qd, qdd, Tb, D, backend="numba", **kw), ref, rtol=0,
                    atol=1e-12)


def test_force_metrics_bound_every_tip_motion_within_speed_and_acceleration(states):
    from athenakin.dynamics import force_metrics
    from athenakin.dynamics._core import evaluate as ev_

    q = states[0][:3]
    v, a = 0.1, 1.0
    fm = force_metrics(q, T, D, slot=[0, 0, 0], masses=M, tip_speed=v,
                       tip_acceleration=a, f_max=50.0)
    peak, cap = fm.peak_actuator_force, fm.min_tip_force_capability
    assert (fm.n_configurations, fm.n_valid, fm.n_peak) == (3, 3, 3)
    assert_allclose(cap, force_capability(q, T, D, masses=M, f_max=50.0).min_force.min(),
                    rtol=1e-12)
    rng = np.random.default_rng(4)
    J = statics(q, T, D, masses=M).tip_jacobian
    worst = 0.0
    for _ in range(20):
        u = rng.normal(size=(3, 3))
        u = v * u / np.linalg.norm(u, axis=-1, keepdims=True) * rng.uniform(0, 1, (3, 1))
        w = rng.normal(size=(3, 3))
        w = a * w / np.linalg.norm(w, axis=-1, keepdims=True) * rng.uniform(0, 1, (3, 1))
        qd = np.linalg.solve(J, u[..., None])[..., 0]
        a0 = ev_(q, qd, 0 * qd, np.broadcast_to(T, (3, 4, 4)), D, M, 0).a_tip
        qdd = np.linalg.solve(J, (w - a0)[..., None])[..., 0]
        # the tip really moves at u with acceleration w
        ev = ev_(q, qd, qdd, np.broadcast_to(T, (3, 4, 4)), D, M, 0)
        assert_allclose(ev.a_tip, w, rtol=0, atol=1e-10)
        tau = inverse_dynamics(q, qd, qdd, T, D, masses=M)
        worst = max(worst, float(np.abs(tau).max()))
    assert worst <= peak


def test_simulate_fast_stage_equals_forward_dynamics(states):
    if not ak._backend.numba_available():
        pytest.skip("numba not available here (or ATHENAKIN_BACKEND=numpy)")
    from athenakin.dynamics._simulate import _fast_forward

    q, qd, _ = states
    fast = _fast_forward(D, T, MF, 9, np.array([0.0, 0.1, -9.8]), np.array([1.0, 0.0, -2.0]))
    tau = np.array([3.0, -2.0, 1.0])
    for i in range(3):
        ref = forward_dynamics(q[i], qd[i], tau, T, D, masses=MF, slot=9,
                               gravity=[0.0, 0.1, -9.8], tip_force=[1.0, 0.0, -2.0])
        assert_allclose(fast(q[i], qd[i], tau), ref, rtol=0, atol=1e-11)


def test_empty_batches_and_broadcast_errors():
    assert actuator_forces(np.zeros((0, 3)), T, D).shape == (0, 3)
    assert mass_matrix(np.zeros((0, 3)), T, D).shape == (0, 3, 3)
    with pytest.raises(InvalidInputError, match="do not broadcast"):
        inverse_dynamics(np.tile(REFERENCE_Q, (2, 1)), np.zeros((3, 3)), np.zeros(3), T, D)
