"""athenakin.motion.Tracker: the scalar FK against the core, continuity, flags, no silent switch."""

import dataclasses
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin.motion import (
    Margins,
    PlanOptions,
    TrackedPose,
    Tracker,
    TrackFlag,
    TrackingError,
    plan,
    track,
)

SEED = 7031
D = ak.Design.default()
T = ak.default_rcm_frame(D)
Q_REF = np.array([-0.10, 0.10, 0.45])


def wrapped(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def random_q(n, rng):
    """Seeded actuator values inside the strokes, with the A/B order of the design."""
    q = rng.uniform(D.stroke_min, D.stroke_max, size=(n, 3))
    return q[q[:, 0] < q[:, 1] - 0.02]


def tangent_q3(q12):
    g = ak.parallel.circle_geometry(np.array([q12[0], q12[1], 0.3]), D)
    return float(g["d"] - g["r1"])


def mode_boundary_stream(depth=1e-10, n=400):
    """q3 slowing down to the tangency of k1 and k2 (d - r1 + depth) and back."""
    qt = tangent_q3(Q_REF[:2])
    dl = np.geomspace(0.065, depth, n)
    q3 = qt + np.concatenate([dl, dl[::-1][1:]])
    return np.stack([np.full_like(q3, Q_REF[0]), np.full_like(q3, Q_REF[1]), q3], axis=-1)


def ujoint_crossing_stream(n=401):
    """O_s crossing the ray from the rail axis through the RCM: sin u2 goes through 0."""
    c = T[:3, 3]
    u = np.array([0.0, c[1], c[2]]) / np.hypot(c[1], c[2])
    s = np.linspace(-0.02, 0.02, n)
    O_s = np.array([c[0], 0.0, 0.0]) + 0.4 * u + s[:, None] * np.array([1.0, 0.0, 0.0])
    pik = ak.parallel.parallel_ik_from_position(O_s, D)
    assert pik.valid.all()
    return pik.q


def assert_no_silent_switch(log):
    """Every change of mode / labels / large step carries its flag."""
    f = log.flags
    for i in range(1, len(f)):
        if not log.valid[i] or not log.valid[i - 1]:
            continue
        if log.mode[i] != log.mode[i - 1]:
            assert f[i] & TrackFlag.MODE_SWITCH, i
        if (log.p_sign[i], log.ujoint[i], log.wrist[i]) != (
                log.p_sign[i - 1], log.ujoint[i - 1], log.wrist[i - 1]):
            assert f[i] & TrackFlag.BRANCH_SWITCH, i
        if log.step[i] > 1.0:
            assert f[i] & TrackFlag.JUMP, i


# --- the closed-form scalar FK equals the core FK, slot by slot ------------------------------
def test_every_slot_matches_core_forward_kinematics():
    rng = np.random.default_rng(SEED)
    qs = random_q(160, rng)
    sol = ak.forward_kinematics(qs, T, D)
    checked = 0
    for i in range(len(qs)):
        for k in np.flatnonzero(sol.valid[i]):
            pose = Tracker(T, D, q0=qs[i], slot=int(k)).pose
            assert pose.slot == k and pose.valid
            assert (pose.mode, pose.p_sign, pose.ujoint, pose.wrist) == (
                sol.mode[i, k], sol.p_sign[i, k], sol.ujoint[i, k], sol.wrist[i, k])
            assert pose.p == pytest.approx(sol.p[i, k], abs=1e-12)
            assert_allclose(wrapped(np.array(pose.u) - sol.u[i, k]), 0.0, atol=1e-9)
            assert_allclose(pose.O_s, sol.T_b_s[i, k, :3, 3], atol=1e-12)
            checked += 1
    assert checked > 1000


def test_pose_fields_are_consistent():
    rng = np.random.default_rng(SEED + 1)
    for q in random_q(60, rng)[:40]:
        try:
            tr = Tracker(T, D, q0=q)
        except ak.KinematicsError:
            continue
        p = tr.pose
        O_s, z = np.array(p.O_s), np.array(p.direction_b)
        assert np.linalg.norm(z) == pytest.approx(1.0, abs=1e-12)
        # the instrument axis passes through the RCM, p along it
        assert_allclose(O_s + p.p * z, T[:3, 3], atol=1e-12)
        assert_allclose(p.tip_b, O_s + D.tool_length * z, atol=1e-15)
        assert_allclose(p.tip_e, T[:3, :3].T @ (np.array(p.tip_b) - T[:3, 3]), atol=1e-15)
        assert p.sin_u2 == pytest.approx(abs(math.sin(p.u[1])), abs=1e-12)
        assert p.sin_u4 == pytest.approx(abs(math.sin(p.u[3])), abs=1e-12)
        assert p.h == pytest.approx(abs(q[0] - q[1]) / 2, abs=1e-15)


def test_default_slot_prefers_mode_plus_and_positive_p():
    tr = Tracker(T, D, q0=Q_REF)
    assert tr.pose.slot == 0 and tr.pose.mode == 1 and tr.pose.p > 0


# --- continuity -------------------------------------------------------------------------------
def test_replays_a_planned_trajectory_without_flags():
    tips = np.array([[0.25, 0.0, 0.0], [0.27, -0.02, 0.0], [0.27, -0.02, 0.02], [0.25, 0, 0]])
    traj = plan(tips, T, D, options=PlanOptions(j_max=5.0))
    log = track(traj.q, T, D)
    assert not log.flags.any()
    assert_allclose(log.tip_e, traj.tip_e, atol=1e-12)
    assert_allclose(D.tool_length - log.p, traj.depth, atol=1e-12)
    assert np.all(log.mode == 1) and np.all(log.slot == 0)


@pytest.mark.parametrize("slot", range(16))
def test_smooth_streams_keep_their_labels(slot):
    """A smooth stream far from singularities keeps every slot's labels, = core FK slot."""
    rng = np.random.default_rng(SEED + slot)
    t = np.linspace(0, 1, 300)
    amp = rng.uniform(0.005, 0.02, 3)
    qs = Q_REF + amp * np.sin(2 * np.pi * np.outer(t, rng.uniform(0.5, 2.0, 3)))
    log = track(qs, T, D, slot=slot)
    sol = ak.forward_kinematics(qs, T, D)
    assert np.all(log.slot == slot)
    trouble = (TrackFlag.JUMP | TrackFlag.MODE_SWITCH | TrackFlag.BRANCH_SWITCH
               | TrackFlag.LOST | TrackFlag.AMBIGUOUS)
    assert not (log.flags & trouble).any()
    assert_allclose(log.p, sol.p[:, slot], atol=1e-12)
    assert_allclose(wrapped(log.u - sol.u[:, slot]), 0.0, atol=1e-9)
    assert_no_silent_switch(log)


def test_random_streams_across_the_workspace_never_switch_silently():
    rng = np.random.default_rng(SEED + 3)
    qs0 = random_q(200, rng)
    sol = ak.forward_kinematics(qs0, T, D)
    starts = qs0[sol.valid[:, 0]][:20]
    for q0 in starts:
        t = np.linspace(0, 1, 200)[:, None]
        stream = q0 + rng.uniform(0.002, 0.02, 3) * np.sin(2 * np.pi * rng.uniform(0.5, 2, 3) * t)
        log = track(stream, T, D)
        assert_no_silent_switch(log)
        # the tracker computes poses beyond the strokes (flagged), the core FK does not
        ref = ak.forward_kinematics(stream, T, dataclasses.replace(D, q_min=None, q_max=None))
        lost = (log.flags & TrackFlag.LOST) != 0
        assert_allclose(lost, ref.n_solutions == 0)
        outside = np.any((stream < D.stroke_min) | (stream > D.stroke_max), axis=1)
        flagged = (log.flags & TrackFlag.OUT_OF_STROKE) != 0
        assert_allclose(flagged[~lost], outside[~lost])
        ok = log.valid & ~lost
        # the tracked solution is one of the core FK's solutions at every valid sample
        rows = np.flatnonzero(ok)
        sl = log.slot[rows]
        good = ref.valid[rows, sl]
        assert np.all(good | (log.flags[rows] != 0))
        assert_allclose(log.p[rows][good], ref.p[rows, sl][good], atol=1e-12)


# --- the parallel module's mode boundary --------------------------------------------------------
@pytest.mark.parametrize("slot", [0, 8])
def test_mode_boundary_is_flagged_and_the_mode_kept(slot):
    qs = mode_boundary_stream()
    sol = ak.forward_kinematics(qs, T, D)
    assert sol.valid[:, 0].all()                 # FK has a solution all along
    log = track(qs, T, D, slot=slot)
    mode = 1 if slot == 0 else -1
    assert np.all(log.mode == mode)              # no silent switch: the mode is kept ...
    assert not (log.flags & TrackFlag.MODE_SWITCH).any()
    near = (log.flags & TrackFlag.NEAR_MODE_BOUNDARY) != 0
    assert_allclose(near, log.half_chord < Margins().half_chord)   # ... and flagged
    amb = (log.flags & TrackFlag.AMBIGUOUS) != 0
    assert amb.sum() > 100                       # both modes within the jump threshold
    assert np.all(log.half_chord[amb] < 0.005)
    assert log.half_chord.min() < 1e-5
    assert_no_silent_switch(log)


def test_stream_through_the_mode_boundary_is_lost_then_reacquired_ambiguous():
    qt = tangent_q3(Q_REF[:2])
    q3 = np.concatenate([np.linspace(qt + 0.01, qt - 0.002, 300),
                         np.linspace(qt - 0.002, qt + 0.01, 300)[1:]])
    qs = np.stack([np.full_like(q3, Q_REF[0]), np.full_like(q3, Q_REF[1]), q3], axis=-1)
    log = track(qs, T, D)
    sol = ak.forward_kinematics(qs, T, D)
    lost = (log.flags & TrackFlag.LOST) != 0
    assert_allclose(lost, sol.n_solutions == 0)          # lost exactly where FK has none
    assert not log.valid[lost].any()
    re = np.flatnonzero(log.flags & TrackFlag.REACQUIRED)
    assert len(re) == 1 and re[0] == np.flatnonzero(lost)[-1] + 1
    assert log.flags[re[0]] & TrackFlag.AMBIGUOUS        # which mode came back is unknown
    assert np.all(log.mode[log.valid] == 1)


def test_mode_switch_is_always_flagged_in_random_walks_near_the_boundary():
    rng = np.random.default_rng(SEED + 99)
    qt = tangent_q3(Q_REF[:2])
    for _ in range(5):
        q3 = qt + np.abs(0.003 + np.cumsum(rng.normal(0, 4e-4, 400)))
        qs = np.stack([np.full_like(q3, Q_REF[0]), np.full_like(q3, Q_REF[1]), q3], -1)
        log = track(qs, T, D, jump_m=0.02)
        assert_no_silent_switch(log)
        assert np.all(log.mode == 1) or (log.flags & TrackFlag.MODE_SWITCH).any()


# --- serial singularities ------------------------------------------------------------------------
@pytest.mark.parametrize("n", [401, 400])   # 401 hits sin u2 = 0 exactly, 400 steps over it
def test_ujoint_crossing_changes_label_with_a_flag(n):
    qs = ujoint_crossing_stream(n)
    log = track(qs, T, D)
    assert log.sin_u2.min() < 1e-3
    assert np.all(log.mode == 1) and log.valid.all()
    sw = np.flatnonzero(log.flags & TrackFlag.BRANCH_SWITCH)
    assert len(sw) == 1
    i = sw[0]
    assert log.ujoint[i] != log.ujoint[i - 1]
    assert log.flags[i] & TrackFlag.NEAR_UJOINT
    # the continuous solution: u1 does not jump across the singularity
    assert abs(wrapped(log.u[i, 0] - log.u[i - 1, 0])) < 0.1
    near = (log.flags & TrackFlag.NEAR_UJOINT) != 0
    assert_allclose(near, log.sin_u2 < Margins().sin_u2)
    assert_no_silent_switch(log)


# --- jumps, losses, strokes, strict mode --------------------------------------------------------
def test_jump_is_flagged_and_can_raise():
    tr = Tracker(T, D, q0=Q_REF)
    p = tr.update(Q_REF + [0.0, 0.0, 0.001])
    assert p.flags == TrackFlag.NONE
    p = tr.update(Q_REF + [-0.03, 0.03, 0.0])
    assert p.flags & TrackFlag.JUMP and p.step > 1.0 and p.mode == 1
    strict = Tracker(T, D, q0=Q_REF, raise_on=TrackFlag.JUMP | TrackFlag.LOST)
    with pytest.raises(TrackingError, match="JUMP") as ei:
        strict.update(Q_REF + [-0.03, 0.03, 0.0])
    assert isinstance(ei.value.pose, TrackedPose) and ei.value.pose.flags & TrackFlag.JUMP


def test_lost_reading_keeps_last_pose():
    tr = Tracker(T, D, q0=Q_REF)
    good = tr.update(Q_REF + 1e-4)
    for bad in ([np.nan, 0.1, 0.45], [0.1, -0.1, 0.45], [-0.1, 0.1, 0.05]):   # NaN, A/B, k2
        p = tr.update(bad)
        assert p.flags & TrackFlag.LOST and not p.valid
        assert p.tip_e == good.tip_e and p.sample == tr.pose.sample
    p = tr.update(Q_REF)
    assert p.valid and p.flags & TrackFlag.REACQUIRED and p.slot == good.slot


def test_out_of_stroke_is_flagged_not_lost():
    tight = dataclasses.replace(D, q_max=(0.1, 0.3, 0.451))
    tr = Tracker(T, tight, q0=Q_REF)
    p = tr.update(Q_REF + [0.0, 0.0, 0.002])
    assert p.valid and p.flags == TrackFlag.OUT_OF_STROKE


def test_track_log_events_and_rows():
    qs = np.array([Q_REF, Q_REF + 1e-4, [np.nan] * 3, Q_REF])
    log = track(qs, T, D)
    assert log.q.shape == (4, 3) and log.u.shape == (4, 5)
    ev = log.events()
    assert [i for i, _ in ev] == [2, 3]
    assert ev[0][1] & TrackFlag.LOST and ev[1][1] & TrackFlag.REACQUIRED


# --- arguments --------------------------------------------------------------------------------
def test_bad_arguments():
    with pytest.raises(ak.InvalidInputError, match="slot"):
        Tracker(T, D, q0=Q_REF, slot=16)
    q_tangent = [Q_REF[0], Q_REF[1], tangent_q3(Q_REF[:2])]
    # tangent: mode -1 merged into +1, whose position is known to about 1e-8 m only, beyond
    # closure_tol: no slot is valid (issue 23), and the tracker says why
    sol = ak.forward_kinematics(q_tangent, T, D, errors="flag")
    assert not sol.valid.any() and np.all(sol.reason == ak.Reason.CIRCLES_TANGENT)
    with pytest.raises(ak.SingularConfigurationError, match="circles k1 and k2 touch"):
        Tracker(T, D, q0=q_tangent, slot=8)
    with pytest.raises(ak.OutOfWorkspaceError):
        Tracker(T, D, q0=[0.1, -0.1, 0.45])
    tr = Tracker(T, D, q0=Q_REF)
    with pytest.raises(ak.InvalidInputError, match="3 numbers"):
        tr.update([0.1, 0.2])
    with pytest.raises(ak.InvalidInputError, match="3 numbers"):
        tr.update("abc")
    with pytest.raises(ValueError, match="jump_m"):
        Tracker(T, D, q0=Q_REF, jump_m=0.0)
    with pytest.raises(TypeError, match="margins"):
        Tracker(T, D, q0=Q_REF, margins=0.01)
    with pytest.raises(ak.InvalidInputError, match="q_stream"):
        track(np.zeros((0, 3)), T, D)


def test_tracker_slot_bool_and_mapping_reading_named():
    """Audit of issue 13: slot=True and a dict reading were numpy / KeyError tracebacks."""
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    q0 = np.array([-0.1, 0.1, 0.45])
    with pytest.raises(ak.InvalidInputError, match="slot"):
        ak.motion.Tracker(T, d, q0=q0, slot=True)
    tr = ak.motion.Tracker(T, d, q0=q0)
    with pytest.raises(ak.InvalidInputError, match="q: expected 3 numbers"):
        tr.update({"q1": -0.1})
