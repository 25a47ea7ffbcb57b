"""athenakin.motion.plan / plan_directions: round trips, RCM, limits, timing, margins, errors."""

import dataclasses

import numpy as np
import pytest
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin.motion import (
    Margins,
    PlanOptions,
    SafetyViolationError,
    TimingInfeasibleError,
    plan,
    plan_directions,
)
from athenakin.motion._jet import q_jet
from athenakin.motion._path import arc_segment, line_segment, q_derivatives, q_on_tips

SEED = 20240611
D = ak.Design.default()
T = ak.default_rcm_frame(D)
TIP0 = np.array([0.25, 0.0, 0.0])          # reference configuration's tip
SQUARE = np.array([[0.25, 0.0, 0.0], [0.27, -0.02, 0.0], [0.27, -0.02, 0.02],
                   [0.25, 0.0, 0.02], [0.25, 0.0, 0.0]])
OFF = Margins(half_chord=0, h=0, link=0, sin_u2=0, sin_u4=0, p=0, depth=0, cond=np.inf)
TOWARD_H0 = np.array([0.22, 0.0, 0.02])    # the line TIP0 -> here ends at |h| ~ 4 mm


def random_paths(n, rng):
    """Seeded short paths in the region around the reference tip that stays valid."""
    out = []
    while len(out) < n:
        k = rng.integers(2, 5)
        pts = TIP0 + rng.uniform([0.0, -0.025, -0.01], [0.03, 0.005, 0.025], size=(k, 3))
        q, r, _ = q_on_tips(pts, T, D)
        if np.all(r == 0):
            out.append(pts)
    return out


def fk_tip_and_axis(q, mode):
    """Tool tip (frame E) and the RCM's distance to the instrument axis, from the core FK."""
    sol = ak.forward_kinematics(q, T, D)
    slot = np.where(mode == 1, 0, 8)
    rows = np.arange(len(q))
    assert np.all(sol.valid[rows, slot])
    O_s = sol.T_b_s[rows, slot, :3, 3]
    u = sol.u[rows, slot]
    R_b_s = sol.T_b_s[rows, slot, :3, :3]
    z_s = np.stack([np.cos(u[:, 0]) * np.sin(u[:, 1]), np.sin(u[:, 0]) * np.sin(u[:, 1]),
                    -np.cos(u[:, 1])], axis=-1)
    z_b = np.einsum("nij,nj->ni", R_b_s, z_s)
    tip_b = O_s + D.tool_length * z_b
    tip_e = (tip_b - T[:3, 3]) @ T[:3, :3]
    dist = np.linalg.norm(np.cross(T[:3, 3] - O_s, z_b), axis=-1)
    return tip_e, dist, O_s


def dist_to_segments(tips, traj):
    """Distance of each sample's tip to its straight segment."""
    a = traj.waypoints_e[traj.segment]
    b = traj.waypoints_e[traj.segment + 1]
    ab = b - a
    ln = np.maximum(np.sum(ab * ab, axis=-1), 1e-300)
    lam = np.clip(np.sum((tips - a) * ab, axis=-1) / ln, 0, 1)
    return np.linalg.norm(a + lam[:, None] * ab - tips, axis=-1)


# --- round trips, RCM, path --------------------------------------------------------------
@pytest.mark.parametrize("j_max", [None, 5.0])
def test_round_trip_square(j_max):
    traj = plan(SQUARE, T, D, options=PlanOptions(rate=1000.0, v_max=0.05, a_max=0.5, j_max=j_max))
    tip_e, dist, _ = fk_tip_and_axis(traj.q, traj.mode)
    assert_allclose(tip_e, traj.tip_e, rtol=0, atol=1e-12)          # FK of q = planned tip
    assert dist.max() <= 1e-12                                       # axis through the RCM
    assert dist_to_segments(traj.tip_e, traj).max() <= 1e-12         # on the straight segments
    assert_allclose(np.diff(traj.t), 1e-3, rtol=0, atol=1e-12)
    assert traj.t[0] == 0.0 and traj.t[-1] >= traj.waypoint_times[-1] - 1e-12
    # waypoints are reached at rest, in order
    for k, tw in enumerate(traj.waypoint_times):
        i = int(round((tw - traj.t[0]) * traj.rate))
        assert abs(traj.t[i] - tw) < 1e-9          # durations are multiples of 1 / rate
        assert_allclose(traj.tip_e[i], SQUARE[k], rtol=0, atol=1e-12)
        assert_allclose(traj.qd[i], 0.0, atol=1e-12)
    assert np.all(np.diff(traj.segment) >= 0)


def test_round_trip_seeded_paths():
    rng = np.random.default_rng(SEED)
    for tips in random_paths(25, rng):
        rate = float(rng.choice([250.0, 500.0, 1000.0]))
        v, a, j = rng.uniform(0.02, 0.1), rng.uniform(0.2, 1.0), rng.uniform(2.0, 20.0)
        traj = plan(tips, T, D, options=PlanOptions(rate=rate, v_max=v, a_max=a, j_max=j))
        tip_e, dist, _ = fk_tip_and_axis(traj.q, traj.mode)
        assert_allclose(tip_e, traj.tip_e, rtol=0, atol=1e-12)
        assert dist.max() <= 1e-12
        assert dist_to_segments(traj.tip_e, traj).max() <= 1e-12
        assert np.all(np.abs(traj.qd) <= v * (1 + 1e-6))
        assert np.all(np.abs(traj.qdd) <= a * (1 + 1e-6))
        assert np.all(np.abs(traj.qddd) <= j * (1 + 1e-6))
        # the binding limit is nearly reached: the bounds are not uselessly cautious
        use = max(np.abs(traj.qd).max() / v, np.abs(traj.qdd).max() / a,
                  np.abs(traj.qddd).max() / j)
        assert use > 0.5
        assert_allclose(traj.q[[0, -1]], q_on_tips(tips[[0, -1]], T, D)[0], atol=1e-12)


def test_round_trip_seeded_direction_paths():
    rng = np.random.default_rng(SEED + 5)
    done = 0
    while done < 10:
        k = int(rng.integers(2, 5))
        az = np.radians(rng.uniform(-6.0, 2.0, k))
        po = np.radians(rng.uniform(84.0, 94.0, k))
        depth = rng.uniform(0.24, 0.28, k)
        tips = ak.direction_from_angles(az, po) * depth[:, None]
        if np.any(q_on_tips(tips, T, D)[1] != 0):
            continue
        try:
            traj = plan_directions(az, po, depth, T, D, options=PlanOptions(j_max=5.0))
        except SafetyViolationError:
            continue          # a great circle may leave the workspace between valid ends
        done += 1
        tip_e, dist, _ = fk_tip_and_axis(traj.q, traj.mode)
        assert_allclose(tip_e, traj.tip_e, atol=1e-12)
        assert dist.max() <= 1e-12
        az_w, po_w = ak.angles_from_direction(traj.direction_e[[0, -1]])
        assert_allclose(po_w, po[[0, -1]], atol=1e-12)
        assert_allclose(traj.depth[[0, -1]], depth[[0, -1]], atol=1e-12)


def test_derivatives_match_finite_differences_of_samples():
    traj = plan(SQUARE, T, D, options=PlanOptions(j_max=5.0))
    dt = 1.0 / traj.rate
    qd_fd = (traj.q[2:] - traj.q[:-2]) / (2 * dt)
    qdd_fd = (traj.qd[2:] - traj.qd[:-2]) / (2 * dt)
    assert np.abs(qd_fd - traj.qd[1:-1]).max() < 5e-6          # O(dt^2 jerk)
    # acceleration: jerk steps at phase changes give errors ~ j_max dt / 2
    assert np.abs(qdd_fd - traj.qdd[1:-1]).max() < 5.0 * dt
    # jerk: exact within the phases of the profile, off only at its ~7 switches per segment
    err = np.abs((traj.qdd[2:] - traj.qdd[:-2]) / (2 * dt) - traj.qddd[1:-1]).max(axis=1)
    assert np.median(err) < 1e-4
    assert np.mean(err > 1e-3) < 0.03


def test_path_derivatives_are_exact_taylor_coefficients():
    """The Taylor-arithmetic derivatives agree with finite differences of the exact IK."""
    rng = np.random.default_rng(SEED + 1)
    for tips in random_paths(4, rng):
        for seg in (line_segment(tips[0], tips[1]), arc_segment(tips[0], tips[1])):
            lam = np.linspace(0.05, 0.95, 7)
            jets = q_jet(seg.tips_jet(lam), T, D)
            assert_allclose(np.stack([j.c[0] for j in jets], -1),
                            q_on_tips(seg.tips_lam(lam), T, D)[0], rtol=0, atol=1e-13)
            h = 1e-4

            def f(x, seg=seg):
                return q_on_tips(seg.tips_lam(x), T, D)[0]

            d1 = np.stack([j.derivatives()[1] for j in jets], -1)
            d2 = np.stack([j.derivatives()[2] for j in jets], -1)
            assert_allclose(d1, (f(lam + h) - f(lam - h)) / (2 * h), rtol=0,
                            atol=1e-7 * max(1.0, np.abs(d1).max()))
            assert_allclose(d2, (f(lam + h) - 2 * f(lam) + f(lam - h)) / h ** 2, rtol=0,
                            atol=1e-5 * max(1.0, np.abs(d2).max()))


def test_reparametrisation_keeps_the_geometry():
    """The pace parameter s only moves along the path: same points, lam(s) monotone."""
    from athenakin.motion._path import reparametrised

    seg = line_segment(TIP0, TIP0 + 0.97 * (TOWARD_H0 - TIP0))
    rep = reparametrised(seg, T, D)
    assert rep.lam_of_s is not None
    s = np.linspace(0, 1, 501)
    lam = rep.lam(s)
    assert np.all(np.diff(lam) > 0) and abs(lam[0]) < 1e-12 and abs(lam[-1] - 1) < 1e-12
    assert_allclose(rep.tips(s), seg.tips_lam(lam), atol=1e-15)
    # actuator speed along s is nearly uniform (that is the point of the reparametrisation)
    _, d1, _, _ = q_derivatives(rep, s, T, D)
    speed = np.linalg.norm(d1, axis=-1)
    assert speed.max() / speed.min() < 1.01


def test_plan_directions_great_circle_and_linear_depth():
    az = np.radians([0.0, -3.0, -3.0, 0.0])
    po = np.radians([90.0, 90.0, 86.0, 86.0])
    depth = np.array([0.25, 0.26, 0.26, 0.25])
    traj = plan_directions(az, po, depth, T, D, options=PlanOptions(j_max=5.0))
    dirs = ak.direction_from_angles(az, po)
    k = traj.segment
    n = np.cross(dirs[k], dirs[k + 1])
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    assert np.abs(np.sum(n * traj.direction_e, axis=-1)).max() < 1e-12  # on the great circle
    # depth linear in the turned angle
    ang = np.arctan2(np.linalg.norm(np.cross(dirs[k], traj.direction_e), axis=-1),
                     np.sum(dirs[k] * traj.direction_e, axis=-1))
    tot = np.arctan2(np.linalg.norm(np.cross(dirs[k], dirs[k + 1]), axis=-1),
                     np.sum(dirs[k] * dirs[k + 1], axis=-1))
    assert_allclose(traj.depth, depth[k] + ang / tot * (depth[k + 1] - depth[k]), atol=1e-12)
    tip_e, dist, _ = fk_tip_and_axis(traj.q, traj.mode)
    assert_allclose(tip_e, traj.tip_e, atol=1e-12)
    assert dist.max() <= 1e-12
    assert_allclose(traj.p, D.tool_length - traj.depth)


# --- limits and timing -----------------------------------------------------------------------
def test_limits_respected_per_actuator_and_tip_speed():
    v = np.array([0.03, 0.05, 0.02])
    a = np.array([0.3, 0.5, 0.2])
    traj = plan(SQUARE, T, D,
                options=PlanOptions(v_max=v, a_max=a, j_max=[3.0, 5.0, 2.0], tip_speed=0.01))
    assert np.all(np.abs(traj.qd) <= v * (1 + 1e-6))
    assert np.all(np.abs(traj.qdd) <= a * (1 + 1e-6))
    assert np.all(np.abs(traj.qddd) <= np.array([3.0, 5.0, 2.0]) * (1 + 1e-6))
    tip_speed = np.linalg.norm(np.diff(traj.tip_e, axis=0), axis=-1) * traj.rate
    assert tip_speed.max() <= 0.01 * (1 + 1e-3)
    assert tip_speed.max() >= 0.005           # the limit binds: not uselessly slow


def test_tighter_limits_take_longer():
    durations = [plan(SQUARE, T, D, options=PlanOptions(v_max=v, a_max=0.5)).duration
                 for v in (0.08, 0.04, 0.02)]
    assert durations[0] < durations[1] < durations[2]


def test_close_to_time_optimal_without_jerk_limit():
    """Within 10 % of the time-optimal duration (TOPP-RA) on the reference square."""
    import toppra as ta
    import toppra.algorithm as algo
    import toppra.constraint as constraint

    traj = plan(SQUARE, T, D, options=PlanOptions(v_max=0.05, a_max=0.5))
    optimal = 0.0
    for k in range(len(SQUARE) - 1):
        seg = line_segment(SQUARE[k], SQUARE[k + 1])
        s = np.linspace(0, 1, 401)
        path = ta.SplineInterpolator(s, q_on_tips(seg.tips_lam(s), T, D)[0], bc_type="clamped")
        inst = algo.TOPPRA([constraint.JointVelocityConstraint(np.full(3, 0.05)),
                            constraint.JointAccelerationConstraint(np.full(3, 0.5))],
                           path, gridpoints=np.linspace(0, 1, 1001),
                           parametrizer="ParametrizeConstAccel")
        optimal += inst.compute_trajectory(0, 0).duration
    # TOPP-RA's own discretisation is good to about 1 %
    assert 0.98 * optimal <= traj.duration <= 1.10 * optimal


def test_requested_times_are_kept_when_feasible():
    times = np.array([1.0, 4.0, 5.5, 8.0, 10.0])
    for timing in ("stretch", "fixed"):
        traj = plan(SQUARE, T, D, times=times, options=PlanOptions(timing=timing, j_max=5.0))
        assert_allclose(traj.waypoint_times, times, atol=1e-9)
        assert traj.t[0] == 1.0 and traj.t[-1] >= 10.0 - 1e-12
        assert not traj.stretched.any()
        assert np.all(np.abs(traj.qd) <= 0.05 * (1 + 1e-6))


def test_too_fast_times_are_stretched():
    times = np.array([0.0, 2.5, 2.8, 5.0, 6.5])       # segment 1 asked for 0.3 s
    traj = plan(SQUARE, T, D, times=times)
    assert traj.stretched.tolist() == [False, True, False, False]
    assert_allclose(np.diff(traj.waypoint_times)[[0, 2, 3]], np.diff(times)[[0, 2, 3]],
                    atol=1e-9)
    assert np.diff(traj.waypoint_times)[1] > 0.3
    assert np.all(np.abs(traj.qd) <= 0.05 * (1 + 1e-6))
    assert np.all(np.abs(traj.qdd) <= 0.5 * (1 + 1e-6))


def test_too_fast_fixed_times_raise_with_where_and_which_limit():
    times = np.array([0.0, 2.5, 2.8, 5.0, 6.5])
    with pytest.raises(TimingInfeasibleError, match="segment 1") as ei:
        plan(SQUARE, T, D, times=times, options=PlanOptions(timing="fixed"))
    e = ei.value
    assert isinstance(e, SafetyViolationError) and isinstance(e, ak.KinematicsError)
    assert e.segment == 1 and e.requested == pytest.approx(0.3)
    assert e.required > 0.3
    assert e.limit in ("velocity", "acceleration")
    assert 2.5 <= e.time <= 2.8 and e.index == int(round(e.time * 1000))
    assert abs(e.value) > e.bound and e.actuator in (0, 1, 2)
    assert f"t = {e.time:.4f} s" in str(e) and f"sample {e.index}" in str(e)


def test_dwell_on_a_repeated_waypoint():
    tips = np.array([TIP0, TIP0 + [0.01, -0.01, 0.0], TIP0 + [0.01, -0.01, 0.0], TIP0])
    traj = plan(tips, T, D, times=[0.0, 2.0, 3.0, 5.0], options=PlanOptions(timing="fixed"))
    hold = (traj.t > 2.0 + 1e-9) & (traj.t < 3.0 - 1e-9)
    assert hold.sum() > 900
    assert_allclose(traj.q[hold], np.broadcast_to(traj.q[hold][0], traj.q[hold].shape),
                    atol=1e-15)
    assert_allclose(traj.qd[hold], 0.0, atol=1e-15)


# --- safety: workspace, stroke, margins ----------------------------------------------------
def test_near_singular_path_honours_the_margin():
    """A path ending 10 mm from the h = 0 singularity: refused with h >= 12 mm, kept with 5 mm."""
    end = TIP0 + 0.99 * (TOWARD_H0 - TIP0)
    with pytest.raises(SafetyViolationError, match="singularity margin 'h'") as ei:
        plan([TIP0, end], T, D, options=PlanOptions(margins=dataclasses.replace(OFF, h=0.012)))
    e = ei.value
    assert e.limit == "h" and e.value < 0.012 and e.bound == 0.012 and e.actuator is None
    assert e.time == pytest.approx(e.index / 1000.0)
    traj = plan([TIP0, end], T, D,
                options=PlanOptions(margins=dataclasses.replace(OFF, h=0.005), j_max=5.0))
    assert traj.measures.h.min() >= 0.005
    assert traj.measures.h.min() < 0.012                      # it did go near
    # the measure is the truth: |h| = |q1 - q2| / 2 on every sample
    assert_allclose(traj.measures.h, np.abs(traj.q[:, 0] - traj.q[:, 1]) / 2, atol=1e-15)
    # near the singularity the actuators move faster per metre of tip, yet limits hold
    assert np.all(np.abs(traj.qd) <= 0.05 * (1 + 1e-6))
    assert np.all(np.abs(traj.qddd) <= 5.0 * (1 + 1e-6))


def test_default_margins_refuse_the_near_singular_path():
    with pytest.raises(SafetyViolationError) as ei:
        plan([TIP0, TOWARD_H0], T, D)
    assert ei.value.limit in ("h", "cond")


@pytest.mark.parametrize("name,value", [("sin_u4", 0.99), ("depth", 0.255), ("p", 0.199),
                                        ("sin_u2", 0.70), ("cond", 5.0)])
def test_each_margin_is_checked(name, value):
    """Each measure's margin stops a path that crosses it (and only when crossed)."""
    az, po = np.radians([0.0, 0.0]), np.radians([90.0, 75.0])
    depth = [0.25, 0.26]
    traj = plan_directions(az, po, depth, T, D, options=PlanOptions(margins=OFF))
    meas = getattr(traj.measures, name)
    crossed = meas.max() > value if name == "cond" else meas.min() < value
    assert crossed, f"test path does not cross {name} = {value}"
    with pytest.raises(SafetyViolationError) as ei:
        plan_directions(az, po, depth, T, D,
                        options=PlanOptions(margins=dataclasses.replace(OFF, **{name: value})))
    e = ei.value
    assert e.limit == name
    i = e.index
    assert (meas[i] > value) if name == "cond" else (meas[i] < value)
    ok = meas[:i] <= value if name == "cond" else meas[:i] >= value
    assert np.all(ok)                                          # the first sample that crosses


def test_sin_u4_is_the_sine_of_the_polar_angle():
    az, po = np.radians([0.0, 10.0]), np.radians([90.0, 75.0])
    traj = plan_directions(az, po, [0.25, 0.25], T, D, options=PlanOptions(margins=OFF))
    _, polar = ak.angles_from_direction(traj.direction_e)
    assert_allclose(traj.measures.sin_u4, np.sin(polar), atol=1e-12)
    # and equals |sin u4| of the core FK
    sol = ak.forward_kinematics(traj.q[::50], T, D)
    assert_allclose(traj.measures.sin_u4[::50], np.abs(np.sin(sol.u[:, 0, 3])), atol=1e-9)
    assert_allclose(traj.measures.sin_u2[::50], np.abs(np.sin(sol.u[:, 0, 1])), atol=1e-9)


def test_leaving_the_workspace_raises_workspace():
    # the end waypoint is outside: found before any timing, naming the waypoint (issue 13.6)
    end = TIP0 + 1.02 * (TOWARD_H0 - TIP0)
    with pytest.raises(SafetyViolationError, match="waypoint 1 .* outside the workspace") as ei:
        plan([TIP0, end], T, D, options=PlanOptions(margins=OFF))
    assert ei.value.limit == "workspace"
    assert ei.value.waypoint == 1 and ei.value.index == -1


def test_stroke_limit_names_the_actuator():
    tight = dataclasses.replace(D, q_min=(-0.12, -0.10, 0.20))
    with pytest.raises(SafetyViolationError, match="stroke limit of q1") as ei:
        plan(SQUARE, T, tight)
    e = ei.value
    assert e.limit == "stroke" and e.actuator == 0 and e.bound == -0.12 and e.value < -0.12


def test_ambient_checks_do_not_fire_on_a_safe_path():
    traj = plan(SQUARE, T, D)
    for name, r in traj.measures.ratio(traj.margins).items():
        assert np.all(r >= 1.0), name
    assert np.all(traj.q >= D.stroke_min) and np.all(traj.q <= D.stroke_max)
    assert np.all(traj.mode == 1)


# --- arguments -------------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs,exc,match", [
    ({"tips_e": [[0.25, 0, 0]]}, ValueError, "K >= 2"),
    ({"tips_e": [[0.25, 0]]}, ValueError, "tips_e"),
    ({"tips_e": "abc"}, TypeError, "tips_e"),
    ({"v_max": -1.0}, ValueError, "v_max"),
    ({"a_max": [0.5, 0.5]}, ValueError, "a_max"),
    ({"rate": 0.0}, ValueError, "rate"),
    ({"times": [0.0, 1.0]}, ValueError, "times"),
    ({"times": [0.0, 2.0, 1.0, 3.0, 4.0]}, ValueError, "non-decreasing"),
    ({"timing": "exact"}, ValueError, "timing"),
    ({"timing": "fixed"}, ValueError, "needs times"),
    ({"margins": {"h": 0.01}}, TypeError, "margins"),
    ({"T_b_e": np.eye(3)}, ValueError, "T_b_e"),
    ({"design": "default"}, TypeError, "design"),
])
def test_bad_arguments(kwargs, exc, match):
    args = {"tips_e": SQUARE, "T_b_e": T, "design": D}
    args.update(kwargs)
    names = {f.name for f in dataclasses.fields(PlanOptions)}
    with pytest.raises(exc, match=match):
        opts = PlanOptions(**{k: args.pop(k) for k in list(args) if k in names})
        plan(args.pop("tips_e"), args.pop("T_b_e"), args.pop("design"), **args, options=opts)


def test_bad_direction_arguments():
    with pytest.raises(ValueError, match="depth"):
        plan_directions([0, 0.1], [1.5, 1.5], [0.25, -0.1], T, D)
    with pytest.raises(ValueError, match="opposite"):
        plan_directions([0, np.pi], [np.pi / 2, np.pi / 2], [0.25, 0.25], T, D)
    with pytest.raises(ValueError, match="same shape"):
        plan_directions([0, 0.1], [1.5], [0.25, 0.25], T, D)


@pytest.mark.parametrize("kw", [{"h": -1.0}, {"cond": 0.5}, {"sin_u2": np.nan},
                                {"p": np.inf}])
def test_bad_margins(kw):
    with pytest.raises(ValueError, match="Margins"):
        Margins(**kw)


def test_trajectory_is_read_only():
    traj = plan(SQUARE[:2], T, D)
    with pytest.raises(ValueError):
        traj.q[0, 0] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        traj.rate = 10.0  # type: ignore[misc]


def test_cond_is_the_condition_number_of_the_tip_jacobian():
    """Cross-check of the analysis-based measure with central differences of the core FK."""
    traj = plan(SQUARE[:3], T, D)
    idx = np.linspace(0, len(traj.t) - 1, 7).astype(int)
    h = 1e-7
    for i in idx:
        J = np.empty((3, 3))
        for j in range(3):
            e = np.zeros(3)
            e[j] = h
            tp = fk_tip_and_axis(np.array([traj.q[i] + e]), traj.mode[[i]])[0][0]
            tm = fk_tip_and_axis(np.array([traj.q[i] - e]), traj.mode[[i]])[0][0]
            J[:, j] = (tp - tm) / (2 * h)
        assert traj.measures.cond[i] == pytest.approx(np.linalg.cond(J), rel=1e-5)
