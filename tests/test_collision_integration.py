"""Collisions wherever a pose is made (issue 20, item 4): tracker, planner, workspace, synthesis.

Every clearance here is checked against :func:`athenakin.collision.clearance` called
independently (batch == loop), and the carriages give an exact reference: both lie on
the rail's axis, so the clearance of ``carriage_a`` and ``carriage_b`` is
``(q2 - q1) - carriage_length - r_a - r_b`` in closed form.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin.collision import Bodies, Environment, clearance
from athenakin.errors import InvalidInputError
from athenakin.motion import (
    CollisionError,
    Margins,
    PlanOptions,
    SafetyViolationError,
    Tracker,
    TrackFlag,
    TrackingError,
    plan,
    track,
)

D = ak.Design.default()
T = ak.default_rcm_frame(D)
Q0 = np.array([-0.10, 0.10, 0.45])
BODIES = Bodies.default(D)
#: Gap q2 - q1 at which the carriages touch (m): their length plus both radii.
TOUCH = (BODIES.geometry.carriage_length + BODIES.radius["carriage_a"]
         + BODIES.radius["carriage_b"])
SQUARE = np.array([[0.25, 0.0, 0.0], [0.27, -0.02, 0.0], [0.27, -0.02, 0.02],
                   [0.25, 0.0, 0.02], [0.25, 0.0, 0.0]])


def _closing_stream(n: int = 41, gap_end: float = 0.06) -> np.ndarray:
    """q1 and q2 move towards each other (gap 0.2 m -> ``gap_end``), q3 fixed."""
    gap = np.linspace(Q0[1] - Q0[0], gap_end, n)
    return np.stack([-gap / 2, gap / 2, np.full(n, Q0[2])], axis=-1)


def _reference(q: np.ndarray, slots: np.ndarray, **kw: object) -> tuple[np.ndarray, list]:
    """Least clearance and closest pair of each row, one clearance() call per row."""
    d, pairs = [], []
    for qi, k in zip(q, slots, strict=True):
        c = clearance(qi, T, D, slot=int(k), **kw)  # type: ignore[arg-type]
        d.append(float(c.min_distance))
        pairs.append(c.pairs[int(c.closest_pair)] if c.closest_pair >= 0 else ("", ""))
    return np.array(d), pairs


# --------------------------------------------------------------------------------------
# tracker
# --------------------------------------------------------------------------------------
def test_tracker_default_checks_nothing() -> None:
    log = track(_closing_stream(), T, D)
    assert log.clearance is None and log.closest_pair is None
    bits = TrackFlag.COLLISION | TrackFlag.NEAR_COLLISION
    assert not np.any(log.flags & int(bits))
    tr = Tracker(T, D, q0=Q0)
    assert tr.clearance_margin is None and math.isnan(tr.pose.clearance)


def test_tracker_flags_the_carriages_closing() -> None:
    qs = _closing_stream()
    margin = 0.01
    log = track(qs, T, D, bodies=BODIES, clearance_margin=margin)
    gap = qs[:, 1] - qs[:, 0]
    # batch == loop: each sample against its own clearance() call in the tracked slot
    ref, pairs = _reference(qs, log.slot, bodies=BODIES)
    assert_allclose(log.clearance, ref, rtol=0, atol=1e-12)
    assert [tuple(p) for p in log.closest_pair] == [tuple(p) for p in pairs]
    # the carriages give an upper bound in closed form, reached once they are the closest
    assert np.all(log.clearance <= gap - TOUCH + 1e-12)
    deep = gap < TOUCH - 0.01
    assert deep.any()
    assert_allclose(log.clearance[deep], gap[deep] - TOUCH, rtol=0, atol=1e-12)
    assert np.all(log.closest_pair[deep] == ["carriage_a", "carriage_b"])
    coll = (log.flags & int(TrackFlag.COLLISION)) != 0
    near = (log.flags & int(TrackFlag.NEAR_COLLISION)) != 0
    np.testing.assert_array_equal(coll, log.clearance < 0)
    np.testing.assert_array_equal(near, log.clearance < margin)
    assert coll.any() and (near & ~coll).any() and (~near).any()
    # the Tracker, one update at a time, gives the same poses as track()'s batch
    tr = Tracker(T, D, q0=qs[0], bodies=BODIES, clearance_margin=margin)
    poses = [tr.pose] + [tr.update(q) for q in qs[1:]]
    assert_allclose([p.clearance for p in poses], log.clearance, rtol=0, atol=1e-12)
    assert [int(p.flags) for p in poses] == log.flags.tolist()
    assert [p.closest_pair for p in poses] == [tuple(p) for p in log.closest_pair]


@pytest.mark.parametrize("slot", [1, 3, 9])
def test_tracker_checks_the_tracked_branch(slot: int) -> None:
    """The wrist branch places the spherical mechanism's middle joint: the tracked slot counts."""
    qs = _closing_stream(9)
    log = track(qs, T, D, slot=slot, bodies=BODIES)
    assert (log.slot % 2 == 1).all()
    ref, pairs = _reference(qs, log.slot, bodies=BODIES)
    assert_allclose(log.clearance, ref, rtol=0, atol=1e-12)
    other, _ = _reference(qs, log.slot - 1, bodies=BODIES)
    s1 = np.array([clearance(q, T, D, slot=int(k), bodies=BODIES).distances
                   for q, k in zip(qs, log.slot, strict=True)])
    s0 = np.array([clearance(q, T, D, slot=int(k) - 1, bodies=BODIES).distances
                   for q, k in zip(qs, log.slot, strict=True)])
    assert np.max(np.abs(s1 - s0)) > 1e-3   # the branches place the bodies differently
    assert other.shape == ref.shape


def test_tracker_places_the_bodies_as_the_mechanism_does() -> None:
    """The tracker's scalar placement of the 19 points == athenakin._mechanism's, any slot."""
    from athenakin._mechanism import mechanism_points
    from athenakin.motion._clearance import PoseClearance

    rng = np.random.default_rng(11)
    geo = BODIES.with_geometry(ak.collision.BodyGeometry(carriage_length=0.08,
                                                         sphere_radius=0.12, rail_margin=0.03))
    fast = PoseClearance(D, T, geo)
    checked = 0
    for _ in range(60):
        q = D.stroke_min + (D.stroke_max - D.stroke_min) * rng.random(3)
        fk = ak.forward_kinematics(q, T, D, errors="flag")
        for k in np.flatnonzero(fk.valid)[:: 3]:
            try:
                tr = Tracker(T, D, q0=q, slot=int(k))
            except ak.errors.KinematicsError:
                continue
            pose = tr.pose
            ref = mechanism_points(q, T, D, slot=int(k), geometry=geo.geometry).xyz
            got = fast.points(pose.q, pose.p, pose.u, pose.O_s)
            assert_allclose(got, ref, rtol=0, atol=1e-14)       # the one formula
            d, pair = fast(pose.q, pose.p, pose.u, pose.O_s)
            c = clearance(q, T, D, slot=int(k), bodies=geo)
            assert d == pytest.approx(float(c.min_distance), abs=1e-12)
            # the pair: that of the least distance (ties, e.g. link_a and link_b by symmetry,
            # are broken by rounding)
            assert float(c.distance(*pair)) == pytest.approx(d, abs=1e-12)
            checked += 1
    assert checked > 100


def test_tracker_margin_alone_uses_the_default_bodies() -> None:
    qs = _closing_stream(11)
    a = track(qs, T, D, clearance_margin=0.0)
    b = track(qs, T, D, bodies=Bodies.default(D), clearance_margin=0.0)
    assert_allclose(a.clearance, b.clearance, rtol=0, atol=0)
    # margin 0: NEAR_COLLISION exactly where the bodies overlap
    near = (a.flags & int(TrackFlag.NEAR_COLLISION)) != 0
    np.testing.assert_array_equal(near, a.clearance < 0)
    assert Tracker(T, D, q0=Q0, environment=Environment()).clearance_margin == 0.005


def test_tracker_raise_on_collision_names_the_pair() -> None:
    qs = _closing_stream()
    with pytest.raises(TrackingError, match="'carriage_a' and 'carriage_b'") as ei:
        track(qs, T, D, bodies=BODIES, raise_on="COLLISION")
    log = track(qs, T, D, bodies=BODIES)
    first = int(np.flatnonzero(log.clearance < 0)[0])
    assert ei.value.pose.sample == first and ei.value.pose.clearance < 0
    tr = Tracker(T, D, q0=qs[0], bodies=BODIES, raise_on="COLLISION")
    with pytest.raises(TrackingError, match="COLLISION") as ei2:
        for q in qs[1:]:
            tr.update(q)
    assert ei2.value.pose.sample == first


def test_tracker_environment_obstacle() -> None:
    """A halfspace below the rail: the rail and the carriages lie on it, all else above."""
    env = Environment().halfspace([0.0, 0.0, -0.01], [0.0, 0.0, 1.0], name="table")
    tr = Tracker(T, D, q0=Q0, environment=env, clearance_margin=0.0)
    c = clearance(Q0, T, D, slot=tr.pose.slot, environment=env)
    assert_allclose(tr.pose.clearance, c.min_distance, rtol=0, atol=1e-12)
    # the carriage (radius 25 mm) reaches 15 mm below the table's surface
    assert tr.pose.closest_pair[1] == "table" and tr.pose.clearance == pytest.approx(-0.015,
                                                                                      abs=1e-12)
    assert TrackFlag.COLLISION in tr.pose.flags
    # one update at a time (points from the pose) == track()'s batch (clearance())
    qs = _closing_stream(9)
    env2 = env.sphere([0.0, 0.3, 0.25], 0.05, name="lamp")
    tr = Tracker(T, D, q0=qs[0], environment=env2, clearance_margin=0.0)
    poses = [tr.pose] + [tr.update(q) for q in qs[1:]]
    log = track(qs, T, D, environment=env2, clearance_margin=0.0)
    assert_allclose([p.clearance for p in poses], log.clearance, rtol=0, atol=1e-12)
    assert [int(p.flags) for p in poses] == log.flags.tolist()


@pytest.mark.parametrize(("kw", "err", "match"), [
    ({"clearance_margin": -0.001}, InvalidInputError, "clearance_margin"),
    ({"clearance_margin": math.nan}, InvalidInputError, "clearance_margin"),
    ({"clearance_margin": 5.0}, InvalidInputError, "clearance_margin"),
    ({"bodies": "default"}, TypeError, "bodies"),
    ({"environment": [1, 2]}, TypeError, "environment"),
])
def test_tracker_bad_collision_options_are_named(kw: dict, err: type, match: str) -> None:
    with pytest.raises(err, match=match):
        Tracker(T, D, q0=Q0, **kw)
    with pytest.raises(err, match=match):
        track(_closing_stream(3), T, D, **kw)


def test_lost_samples_are_not_checked() -> None:
    qs = np.array([Q0, [math.nan, 0.1, 0.45], Q0])
    log = track(qs, T, D, bodies=BODIES)
    assert not log.valid[1] and math.isnan(log.clearance[1])
    assert np.isfinite(log.clearance[[0, 2]]).all()


# --------------------------------------------------------------------------------------
# planner
# --------------------------------------------------------------------------------------
def _slots(traj: object) -> np.ndarray:
    """Slot 8 m + 4 r of each sample (the bodies depend on the mode and sign of p only)."""
    return 8 * (traj.mode == -1) + 4 * (traj.p < 0)  # type: ignore[attr-defined]


def test_plan_without_check_is_unchanged() -> None:
    traj = plan(SQUARE, T, D)
    assert traj.clearance is None and traj.closest_pair is None
    assert traj.clearance_margin is None


def test_plan_records_the_clearance_of_every_sample() -> None:
    traj = plan(SQUARE[:3], T, D, bodies=BODIES,
                options=PlanOptions(rate=100.0, clearance_margin=0.0))
    assert traj.clearance_margin == 0.0 and traj.clearance is not None
    ref, pairs = _reference(traj.q, _slots(traj), bodies=BODIES)
    assert_allclose(traj.clearance, ref, rtol=0, atol=1e-12)
    assert [tuple(p) for p in traj.closest_pair] == [tuple(p) for p in pairs]
    assert np.all(traj.clearance >= 0)


def test_plan_refuses_the_first_sample_too_close() -> None:
    """A sphere on the tip's path: the error names the first sample within the margin."""
    mid = 0.5 * (SQUARE[0] + SQUARE[1])
    centre = (T @ np.append(mid, 1.0))[:3]            # on the path, in the base frame
    env = Environment().sphere(centre, 0.004, name="tumour")
    margin = 0.003
    free = plan(SQUARE[:2], T, D, options=PlanOptions(rate=200.0))
    ref, pairs = _reference(free.q, _slots(free), bodies=BODIES, environment=env)
    first = int(np.flatnonzero(ref < margin)[0])
    with pytest.raises(CollisionError) as ei:
        plan(SQUARE[:2], T, D, bodies=BODIES, environment=env,
             options=PlanOptions(rate=200.0, clearance_margin=margin))
    e = ei.value
    assert isinstance(e, SafetyViolationError) and e.limit == "clearance"
    assert e.index == first and e.time == pytest.approx(free.t[first], abs=1e-12)
    assert e.pair == pairs[first] and "tumour" in e.pair
    assert e.value == pytest.approx(ref[first], abs=1e-12) and e.bound == margin
    assert f"sample {first} at t = {free.t[first]:.4f} s" in str(e)
    assert "'tumour'" in str(e)


def test_plan_collision_comes_before_a_kinematic_limit_but_after_an_earlier_geometric_one(
) -> None:
    """The carriages: a margin larger than their clearance everywhere refuses sample 0."""
    traj = plan(SQUARE[:2], T, D, bodies=BODIES,
                options=PlanOptions(rate=100.0, clearance_margin=0.0))
    big = float(np.max(traj.clearance)) + 0.001
    with pytest.raises(CollisionError) as ei:
        plan(SQUARE[:2], T, D, bodies=BODIES, options=PlanOptions(rate=100.0, clearance_margin=big))
    assert ei.value.index == 0
    # a singularity margin broken at sample 0 too: the existing check reports it first
    with pytest.raises(SafetyViolationError) as ei2:
        plan(SQUARE[:2], T, D, bodies=BODIES,
             options=PlanOptions(rate=100.0, clearance_margin=big, margins=Margins(p=10.0)))
    assert ei2.value.limit == "p" and not isinstance(ei2.value, CollisionError)


def test_plan_directions_checks_collisions_too() -> None:
    from athenakin.motion import PlanOptions, plan_directions

    az, po, depth = [0.0, 0.1], [1.5, 1.45], [0.25, 0.25]
    free = plan_directions(az, po, depth, T, D, bodies=BODIES,
                           options=PlanOptions(rate=100.0, clearance_margin=0.0))
    ref, _ = _reference(free.q, _slots(free), bodies=BODIES)
    assert_allclose(free.clearance, ref, rtol=0, atol=1e-12)
    with pytest.raises(CollisionError) as ei:
        plan_directions(az, po, depth, T, D, bodies=BODIES, options=PlanOptions(
            rate=100.0, clearance_margin=float(np.min(ref)) + 1e-4))
    assert ei.value.index == int(np.flatnonzero(ref < np.min(ref) + 1e-4)[0])


def test_plan_bad_collision_options_are_named() -> None:
    with pytest.raises(InvalidInputError, match="clearance_margin"):
        plan(SQUARE[:2], T, D, options=PlanOptions(clearance_margin=-1.0))
    with pytest.raises(TypeError, match="bodies"):
        plan(SQUARE[:2], T, D, bodies={"link_a": 0.01})


# --------------------------------------------------------------------------------------
# command line
# --------------------------------------------------------------------------------------
def test_cli_track_with_bodies_reports_and_writes_the_clearance(tmp_path, capsys) -> None:
    from athenakin.cli import main

    qs = _closing_stream(21)
    src = tmp_path / "stream.csv"
    src.write_text("q1_m,q2_m,q3_m\n" + "".join(f"{a!r},{b!r},{c!r}\n" for a, b, c in qs.tolist()))
    bodies = tmp_path / "design.toml"
    bodies.write_text(BODIES.with_radius(carriage_a=0.03).to_toml())
    out = tmp_path / "log.csv"
    assert main(["track", str(src), "--bodies", str(bodies), "--clearance-margin", "0.002",
                 "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "COLLISION:" in text and "least clearance: " in text
    assert "between carriage_a and carriage_b" in text
    # --strict fails on a collision (the flag exists only with the check)
    assert main(["track", str(src), "--clearance-margin", "0", "--strict"]) == 1
    assert "COLLISION" in capsys.readouterr().out
    lines = out.read_text().splitlines()
    header = lines[0].split(",")
    assert header[-3:] == ["clearance_m", "closest_a", "closest_b"]
    ref = track(qs, T, D, bodies=BODIES.with_radius(carriage_a=0.03), clearance_margin=0.002)
    got = np.array([float(ln.split(",")[-3]) for ln in lines[1:]])
    assert_allclose(got, ref.clearance, rtol=0, atol=0)
    # no collision option: the file keeps its columns
    assert main(["track", str(src), "-o", str(out), "--force"]) == 0
    assert out.read_text().splitlines()[0].split(",")[-1] == "flag_names"


def test_cli_plan_environment_refused_with_the_pair(tmp_path, capsys) -> None:
    from athenakin.cli import main

    src = tmp_path / "path.csv"
    src.write_text("x_m,y_m,z_m\n0.25,0,0\n0.27,-0.02,0\n")
    mid = (T @ np.append(0.5 * (SQUARE[0] + SQUARE[1]), 1.0))[:3]
    env = tmp_path / "env.toml"
    env.write_text(Environment().sphere(mid, 0.004, name="tumour").to_toml())
    out = tmp_path / "traj.json"
    code = main(["plan", str(src), "-o", str(out), "--no-plots", "--rate", "200",
                 "--environment", str(env), "--clearance-margin", "0.003"])
    err = capsys.readouterr().err
    assert code == 1 and "CollisionError" in err and "'tumour'" in err and "sample " in err
    assert not out.exists()
    assert main(["plan", str(src), "-o", str(out), "--no-plots", "--rate", "200",
                 "--clearance-margin", "0"]) == 0
    assert "least clearance: " in capsys.readouterr().out
    import json

    obj = json.loads(out.read_text())
    assert obj["clearance_margin_m"] == 0.0 and len(obj["clearance_m"]) == len(obj["t_s"])
    assert main(["plan", str(src), "-o", str(out), "--no-plots", "--force",
                 "--clearance-margin", "-1"]) == 1
    assert "--clearance-margin" in capsys.readouterr().err


# --------------------------------------------------------------------------------------
# synthesis
# --------------------------------------------------------------------------------------
def _task() -> object:
    from athenakin.synthesis import Task

    return Task(rcm=T[:3, 3], axis=T[:3, 0], half_angle=0.45, depth=(0.2, 0.3))


def _independent_collision_metrics(design: ak.Design, task: object, bodies: Bodies, n: int,
                                   k: int, margin: float = 0.0) -> tuple[float, float]:
    """Reach the task samples, place the bodies in all 16 slots, pick each sample's slot."""
    from athenakin.synthesis import reachability

    s, q, mode, _ = reachability(design, task, samples=n, seed=0)  # type: ignore[arg-type]
    q, mode, depth = q[:k], mode[:k], s.depth[:k]
    ok = mode != 0
    c = clearance(np.where(ok[:, None], q, 0.0), task.T_b_e, design,  # type: ignore[attr-defined]
                  slot="all", bodies=bodies)
    p_neg = design.tool_length - depth < 0
    slot = 8 * (mode == -1) + 4 * p_neg
    d = c.min_distance[np.arange(k), slot]
    # the FK slot with p > 0 sits at index 8 m (or the first valid sibling)
    d = np.where(ok, d, np.nan)
    free = ok & (d >= margin)
    return float(np.count_nonzero(free)) / k, float(np.nanmin(d))


def test_evaluate_design_collision_columns() -> None:
    from athenakin.synthesis import COLLISION_COLUMNS, METRIC_COLUMNS, evaluate_design
    from athenakin.synthesis._metrics import collision_spec

    task = _task()
    m0 = evaluate_design(D, task, samples=3000)  # type: ignore[arg-type]
    assert set(COLLISION_COLUMNS) <= set(m0) == set(METRIC_COLUMNS)
    assert all(math.isnan(m0[c]) for c in COLLISION_COLUMNS)
    big = BODIES.with_radius(instrument=0.004)
    for margin in (0.0, 0.01):
        m = evaluate_design(D, task, samples=3000,  # type: ignore[arg-type]
                            collision=collision_spec(bodies=big, collision_samples=1500,
                                                     clearance_margin=margin))
        free, least = _independent_collision_metrics(D, task, big, 3000, 1500, margin)
        assert m["collision_free_coverage"] == pytest.approx(free, abs=0)
        assert m["min_clearance"] == pytest.approx(least, abs=1e-12)
        assert 0 <= m["collision_free_coverage"] <= m0["coverage"] + 0.05
        # everything else is as without the check
        assert all(m[c] == m0[c] or (math.isnan(m[c]) and math.isnan(m0[c]))
                   for c in METRIC_COLUMNS if c not in COLLISION_COLUMNS)


def test_evaluate_design_scaled_bodies_follow_l1() -> None:
    from athenakin.synthesis import evaluate_design
    from athenakin.synthesis._metrics import collision_spec

    task = _task()
    big = ak.Design(l1=0.4, l2=0.1, l3=0.3, l4=0.15, l5=0.45, q_min=D.q_min, q_max=D.q_max)
    for design in (D, big):
        scaled = evaluate_design(design, task, samples=2000,  # type: ignore[arg-type]
                                 collision=collision_spec(bodies="scaled"))
        given = evaluate_design(design, task, samples=2000,  # type: ignore[arg-type]
                                collision=collision_spec(
                                    bodies=Bodies.default(design, scale_with_design=True)))
        assert scaled["collision_free_coverage"] == given["collision_free_coverage"]
        assert scaled["min_clearance"] == given["min_clearance"]
        rigid = Bodies.default(design, scale_with_design=True)
        m = evaluate_design(design, task, samples=2000,  # type: ignore[arg-type]
                            collision=collision_spec(bodies=rigid))
        free, least = _independent_collision_metrics(design, task, rigid, 2000, 2000)
        assert m["collision_free_coverage"] == free
        assert m["min_clearance"] == pytest.approx(least, abs=1e-12)
    # the reference design's l1 is the reference length: scaled == default radii
    a = evaluate_design(D, task, samples=2000, collision=collision_spec(bodies="scaled"))  # type: ignore[arg-type]
    b = evaluate_design(D, task, samples=2000, collision=collision_spec(bodies="default"))  # type: ignore[arg-type]
    assert a["min_clearance"] == b["min_clearance"]
    # a larger robot with the radii scaled: thicker links, a different clearance
    c = evaluate_design(big, task, samples=2000, collision=collision_spec(bodies="scaled"))  # type: ignore[arg-type]
    e = evaluate_design(big, task, samples=2000, collision=collision_spec(bodies="default"))  # type: ignore[arg-type]
    assert c["min_clearance"] != e["min_clearance"]


@pytest.mark.parametrize(("kw", "err", "match"), [
    ({"bodies": "huge"}, InvalidInputError, "bodies"),
    ({"bodies": 3}, TypeError, "bodies"),
    ({"environment": "table"}, TypeError, "environment"),
    ({"clearance_margin": -0.1}, InvalidInputError, "clearance_margin"),
    ({"collision_samples": 0}, InvalidInputError, "collision_samples"),
])
def test_synthesis_bad_collision_options_are_named(kw: dict, err: type, match: str) -> None:
    pytest.importorskip("dask")
    pytest.importorskip("pandas")
    from athenakin.synthesis import StudyOptions, collision_spec, evaluate

    with pytest.raises(err, match=match):
        evaluate([D], _task(), samples=100, scheduler="synchronous",  # type: ignore[arg-type]
                 options=StudyOptions(collision=collision_spec(**kw)))


def test_evaluate_study_with_collisions(tmp_path) -> None:
    pytest.importorskip("dask")
    pytest.importorskip("pandas")
    from athenakin.synthesis import (
        CollisionSpec,
        StudyMismatchError,
        StudyOptions,
        evaluate,
        evaluate_design,
    )
    from athenakin.synthesis._metrics import collision_spec

    task = _task()
    designs = [D, ak.Design(l1=0.35, l2=0.1, l3=0.25, l4=0.15, l5=0.4, q_min=D.q_min,
                            q_max=D.q_max)]
    out = tmp_path / "study"
    df = evaluate(designs, task, samples=800, scheduler="synchronous", out=out,
                  options=StudyOptions(collision=CollisionSpec(bodies="scaled", samples=500)))
    for i, d in enumerate(designs):
        m = evaluate_design(d, task, samples=800,  # type: ignore[arg-type]
                            collision=collision_spec(bodies="scaled", collision_samples=500))
        assert df["collision_free_coverage"].iloc[i] == m["collision_free_coverage"]
        assert df["min_clearance"].iloc[i] == m["min_clearance"]
    # resuming the same study reads it back; the same folder without the check is another study
    again = evaluate(designs, task, samples=800, scheduler="synchronous", out=out,
                     options=StudyOptions(collision=CollisionSpec(bodies="scaled", samples=500)))
    assert again["min_clearance"].tolist() == df["min_clearance"].tolist()
    with pytest.raises(StudyMismatchError):
        evaluate(designs, task, samples=800, scheduler="synchronous", out=out)  # type: ignore[arg-type]
    plain = evaluate(designs, task, samples=800, scheduler="synchronous")  # type: ignore[arg-type]
    assert plain["min_clearance"].isna().all()


def test_check_constraints_named() -> None:
    from athenakin.synthesis import check_constraints

    assert check_constraints({"min_clearance": (">=", 0)}) == {"min_clearance": (">=", 0.0)}
    assert check_constraints(None) == {}
    with pytest.raises(InvalidInputError, match="unknown metric 'nope'"):
        check_constraints({"nope": (">=", 0)})
    with pytest.raises(InvalidInputError, match=r"constraints\['min_clearance'\]"):
        check_constraints({"min_clearance": ("==", 0)})
    with pytest.raises(InvalidInputError, match="bound"):
        check_constraints({"min_clearance": (">=", math.nan)})
    with pytest.raises(TypeError, match="constraints"):
        check_constraints([("min_clearance", ">=", 0)])


def test_optimize_with_a_clearance_constraint_and_objective() -> None:
    pytest.importorskip("pymoo")
    pytest.importorskip("dask")
    from athenakin.synthesis import optimize

    r = optimize(_task(), population=6, generations=2, samples=400, seed=5,  # type: ignore[arg-type]
                 scheduler="synchronous",
                 objectives={"collision_free_coverage": "max", "size": "min"},
                 constraints={"min_clearance": (">=", -0.02)})
    assert r.constraints == {"min_clearance": (">=", -0.02)}
    assert r.table["min_clearance"].notna().any()       # the check ran (default bodies)
    assert len(r.front) and (r.front["min_clearance"] >= -0.02).all()
    feasible = r.table["valid"] & (r.table["coverage"] > 0) & (r.table["min_clearance"] >= -0.02)
    assert set(r.front["design"]) <= set(r.table["design"][feasible])


# --------------------------------------------------------------------------------------
# workspace maps
# --------------------------------------------------------------------------------------
def _labelled_reference(q: np.ndarray, reach: np.ndarray, p_neg: np.ndarray,
                        mode: np.ndarray, T_b_e: np.ndarray, **kw: object) -> np.ndarray:
    """Least clearance from all 16 slots, keeping a valid slot whose FK labels match."""
    fk = ak.forward_kinematics(np.where(reach[:, None], q, 0.0), T_b_e, D, errors="flag")
    c = clearance(np.where(reach[:, None], q, 0.0), T_b_e, D, slot="all", **kw)  # type: ignore[arg-type]
    want = (fk.mode == mode[:, None]) & (fk.p_sign == np.where(p_neg, -1, 1)[:, None]) & fk.valid
    d = np.where(want, c.min_distance, np.nan)
    with np.errstate(all="ignore"):
        first = np.argmax(want, axis=-1)
    out = d[np.arange(len(q)), first]
    return np.where(reach & want.any(axis=-1), out, np.nan)


def test_instrument_cone_collision_layers() -> None:
    from athenakin.analysis import instrument_cone, workspace_summary

    plain = instrument_cone(T, D, resolution=(12, 9, 8))
    assert plain.clearance is None and plain.collision_free is None and plain.blocked is None
    ic = instrument_cone(T, D, resolution=(12, 9, 8), bodies=BODIES, clearance_margin=0.002)
    np.testing.assert_array_equal(ic.reachable, plain.reachable)
    A, P, Pp = np.meshgrid(ic.azimuth, ic.polar, ic.p, indexing="ij")
    d_e = ak.direction_from_angles(A.ravel(), P.ravel())
    q, res = ak.q_from_instrument(T, d_e, Pp.ravel(), D, errors="flag")
    reach = ic.reachable.ravel()
    ref = _labelled_reference(q, reach, Pp.ravel() < 0, res.mode, T, bodies=BODIES)
    assert_allclose(ic.clearance.ravel(), ref, rtol=0, atol=1e-12)
    assert np.isnan(ic.clearance[~ic.reachable]).all()
    np.testing.assert_array_equal(ic.collision_free, ic.reachable & (ic.clearance >= 0.002))
    np.testing.assert_array_equal(ic.blocked, ic.reachable.any(-1) & ~ic.collision_free.any(-1))
    assert ic.collision_free.any() and (ic.reachable & ~ic.collision_free).any()
    s = workspace_summary(ic=ic)
    assert s["cone collision-free solid angle [sr]"] <= s["cone solid angle [sr]"] + 1e-12
    # a larger margin frees no more
    ic2 = instrument_cone(T, D, resolution=(12, 9, 8), bodies=BODIES, clearance_margin=0.02)
    assert not (ic2.collision_free & ~ic.collision_free).any()
    assert (ic2.blocked | ~ic.blocked).all()


def test_tool_tip_and_point_workspace_collision_layers(tmp_path) -> None:
    from athenakin.analysis import load_npz, point_workspace, save_npz, tool_tip_workspace

    env = Environment().halfspace([0.0, 0.0, -0.05], [0.0, 0.0, 1.0], name="floor")
    tw = tool_tip_workspace(T, D, resolution=7, bodies=BODIES, environment=env)
    X, Y, Z = np.meshgrid(tw.x, tw.y, tw.z, indexing="ij")
    tips = np.stack([X.ravel(), Y.ravel(), Z.ravel()], -1)
    q, res = ak.q_from_tool_tip(T, tips, D, errors="flag")
    reach = tw.reachable.ravel()
    ref = _labelled_reference(q, reach, np.linalg.norm(tips, axis=-1) > D.tool_length,
                              res.mode, T, bodies=BODIES, environment=env)
    assert_allclose(tw.clearance.ravel(), ref, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(tw.collision_free, tw.reachable & (tw.clearance >= 0))
    pw = point_workspace(design=D, resolution=7, bodies=BODIES, clearance_margin=0.0)
    P = np.stack(np.meshgrid(pw.x, pw.y, pw.z, indexing="ij"), -1).reshape(-1, 3)
    r = pw.reachable.ravel()
    ref = _labelled_reference(pw.q.reshape(-1, 3), r, np.zeros(len(P), bool),
                              pw.mode.ravel().astype(int), T, bodies=BODIES)
    assert_allclose(pw.clearance.ravel(), ref, rtol=0, atol=1e-12)
    # the layers survive a save / load round trip; maps without them load as before
    path = save_npz(tmp_path / "tw.npz", tw, design=D)
    back, _ = load_npz(path)
    np.testing.assert_array_equal(back.collision_free, tw.collision_free)  # type: ignore[attr-defined]
    path = save_npz(tmp_path / "plain.npz", tool_tip_workspace(T, D, resolution=5), design=D)
    back, _ = load_npz(path)
    assert back.clearance is None  # type: ignore[attr-defined]


def test_workspace_bad_collision_options_are_named() -> None:
    from athenakin.analysis import instrument_cone, point_workspace

    with pytest.raises(InvalidInputError, match="clearance_margin"):
        instrument_cone(T, D, resolution=4, clearance_margin=-1.0)
    with pytest.raises(TypeError, match="bodies"):
        instrument_cone(T, D, resolution=4, bodies={"link_a": 0.1})
    with pytest.raises(TypeError, match="environment"):
        point_workspace(design=D, resolution=4, environment="floor")
    with pytest.raises(InvalidInputError, match="T_b_e"):
        point_workspace(design=D, resolution=4, clearance_margin=0.0, T_b_e=np.eye(4)[:3])
    with pytest.raises(InvalidInputError, match="T_b_e"):      # checked even without the check
        point_workspace(np.eye(4)[:3], D, resolution=4)


def test_workspace_figures_show_the_collision_layers() -> None:
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from athenakin.analysis import instrument_cone, tool_tip_workspace
    from athenakin.analysis.figures import (
        figure_instrument_cone,
        plot_cone_chart,
        plot_tool_tip_slice,
    )

    ic = instrument_cone(T, D, resolution=(16, 9, 6), clearance_margin=0.0)
    plain = instrument_cone(T, D, resolution=(16, 9, 6))
    assert ic.blocked is not None and ic.blocked.any()

    def labels(ax: object) -> list[str]:
        leg = ax.get_legend()  # type: ignore[attr-defined]
        return [] if leg is None else [t.get_text() for t in leg.get_texts()]

    fig, axes = plt.subplots(1, 3)
    assert "blocked by a collision" in labels(plot_cone_chart(ic, ax=axes[0]))
    assert "blocked by a collision" not in labels(plot_cone_chart(plain, ax=axes[1]))
    ax = plot_cone_chart(ic, quantity="clearance", ax=axes[2])
    assert "clearance" in ax.collections[0].colorbar.ax.get_ylabel()
    with pytest.raises(InvalidInputError, match="collision check"):
        plot_cone_chart(plain, quantity="clearance", ax=axes[2])
    plt.close(fig)
    fig = figure_instrument_cone(ic)
    assert any(a.get_title().startswith("Best clearance") for a in fig.axes)
    plt.close(fig)
    tw = tool_tip_workspace(T, D, resolution=9, clearance_margin=0.0)
    fig, ax = plt.subplots()
    assert labels(plot_tool_tip_slice(tw, ax=ax)) == ["bodies collide"]
    plt.close(fig)


# --------------------------------------------------------------------------------------
# static views: solids
# --------------------------------------------------------------------------------------
def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    t = np.clip(((p - a) @ ab) / max(ab @ ab, 1e-300), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[..., None] * ab), axis=-1)


def test_capsule_surface_is_at_the_radius() -> None:
    from athenakin.plot._solids import capsule_surface

    rng = np.random.default_rng(7)
    for _ in range(20):
        a, b = rng.normal(size=(2, 3))
        if rng.random() < 0.2:
            b = a.copy()                                  # a sphere
        r = float(rng.uniform(0.001, 0.5))
        X, Y, Z = capsule_surface(a, b, r, n_around=12, n_cap=4)
        P = np.stack([X, Y, Z], axis=-1).reshape(-1, 3)
        assert_allclose(_segment_distance(P, a, b), r, rtol=0, atol=1e-12)
        # both poles are reached: the surface spans the whole capsule
        w = (b - a) / max(np.linalg.norm(b - a), 1e-300)
        if np.linalg.norm(b - a) > 0:
            s = (P - a) @ w
            assert s.min() == pytest.approx(-r, abs=1e-12)
            assert s.max() == pytest.approx(np.linalg.norm(b - a) + r, abs=1e-12)
    with pytest.raises(InvalidInputError, match="radius"):
        capsule_surface([0, 0, 0], [1, 0, 0], -1.0)
    with pytest.raises(InvalidInputError, match="n_around"):
        capsule_surface([0, 0, 0], [1, 0, 0], 1.0, n_around=2)


def test_plot_robot_draws_the_bodies_and_the_closest_pair() -> None:
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from athenakin.plot import PlotOptions, plot_robot
    from athenakin.plot._solids import BODY_COLORS, CLOSEST_COLOR, COLLIDING_COLOR, draw_bodies

    sticks = plot_robot(Q0, T, D)
    n0 = sum(isinstance(c, Poly3DCollection) for c in sticks.collections)
    plt.close(sticks.figure)
    ax = plot_robot(Q0, T, D, bodies=True, options=PlotOptions(show_labels=False))
    solids = [c for c in ax.collections if isinstance(c, Poly3DCollection)]
    assert len(solids) - n0 == len(BODIES.names)
    texts = [t.get_text() for t in ax.texts]
    ref = clearance(Q0, T, D, bodies=BODIES)
    a, b = ref.pairs[int(ref.closest_pair)]
    assert any(f"clearance {float(ref.min_distance) * 1e3:.1f} mm" in t and f"{a} - {b}" in t
               for t in texts)
    plt.close(ax.figure)
    # overlapping carriages: the pair is drawn in the colliding colour
    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    q = np.array([-0.03, 0.03, 0.45])
    c = draw_bodies(ax, q, T, D, bodies=BODIES)
    assert bool(c.colliding) and c.pairs[int(c.closest_pair)] == ("carriage_a", "carriage_b")
    faces = [np.asarray(s.get_facecolor())[:, :3].mean(axis=0) for s in ax.collections
             if isinstance(s, Poly3DCollection)]
    assert len(faces) == len(BODIES.names)

    def cos(x: np.ndarray, name: str) -> float:
        y = np.array(matplotlib.colors.to_rgb(name))
        return float(x @ y / np.linalg.norm(x) / np.linalg.norm(y))

    # shading scales the colours; their direction in RGB tells which colour was drawn
    for f, name in zip(faces, BODIES.names, strict=True):
        hot = cos(f, COLLIDING_COLOR) > cos(f, BODY_COLORS[name])
        assert hot == (name in ("carriage_a", "carriage_b")), name
    assert CLOSEST_COLOR != COLLIDING_COLOR
    with pytest.raises(TypeError, match="bodies"):
        draw_bodies(ax, q, T, D, bodies="thick")
    with pytest.raises(InvalidInputError, match="alpha"):
        draw_bodies(ax, q, T, D, alpha=0.0)
    plt.close(fig)


# --------------------------------------------------------------------------------------
# live app: solids, closest pair, clearance
# --------------------------------------------------------------------------------------
def test_app_bodies_view_meshes_and_clearance() -> None:
    from athenakin.app._bodies import bodies_view, capsule_mesh, clearance_html
    from athenakin.plot import robot_geometry

    v, f = capsule_mesh([0.0, 0.0, 0.0], [0.1, 0.02, 0.0], 0.01, n_around=8, n_cap=2)
    assert f.max() < len(v) and f.shape == (2 * 5 * 8, 3)
    assert_allclose(_segment_distance(v.astype(float), np.zeros(3), np.array([0.1, 0.02, 0.0])),
                    0.01, rtol=0, atol=1e-7)                     # float32 vertices
    # outward normals: each triangle's normal points away from the segment
    tri = v[f].astype(float)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    ok = np.linalg.norm(n, axis=-1) > 1e-12
    centre = tri.mean(axis=1)
    t = np.clip(centre @ np.array([0.1, 0.02, 0.0]) / (0.1 ** 2 + 0.02 ** 2), 0, 1)
    out = centre - t[:, None] * np.array([0.1, 0.02, 0.0])
    assert np.all(np.sum(n[ok] * out[ok], axis=-1) > 0)
    for q, colliding in ((Q0, False), (np.array([-0.03, 0.03, 0.45]), True)):
        g = robot_geometry(q, T, D, slot=0)
        bv = bodies_view(g, bodies=BODIES)
        ref = clearance(q, T, D, bodies=BODIES)
        assert bv.clearance == float(ref.min_distance) and bv.colliding == colliding
        assert bv.pair == ref.pairs[int(ref.closest_pair)]
        assert_allclose(bv.witness, ref.witness_points[int(ref.closest_pair)], rtol=0, atol=0)
        assert [m.name for m in bv.meshes] == list(BODIES.names)
        assert {m.name for m in bv.meshes if m.closest} == set(bv.pair)
        text = clearance_html(bv)
        assert f"{bv.clearance * 1e3:.1f} mm" in text and bv.pair[0] in text
        assert ("collision" in text) == colliding


def test_app_draws_the_bodies_in_process() -> None:
    pytest.importorskip("viser")
    from athenakin.app import AthenaApp

    app = AthenaApp(port=0, backend="numpy")
    try:
        layer = app.bodies
        assert layer.view is not None and set(layer._meshes) == set(BODIES.names)
        ref = clearance(app.q, app.setup.T_b_e, app.setup.design, slot=app.view.geometry.slot)
        assert layer.view.clearance == pytest.approx(float(ref.min_distance), abs=1e-12)
        assert "clearance" in layer.readout.content
        app.set_q([-0.03, 0.03, 0.45])                    # the carriages overlap
        assert layer.view.colliding and layer.view.pair == ("carriage_a", "carriage_b")
        assert "collision" in layer.readout.content
        layer.checkbox.value = False
        layer.update(app.view.geometry)
        assert not layer._meshes and layer.readout.content == ""
    finally:
        app.stop()


def test_cli_workspace_and_synthesize_collision_options(tmp_path, capsys) -> None:
    import json

    from athenakin.cli import main

    assert main(["workspace", "--resolution", "7", "--cone-resolution", "8", "6", "5",
                 "--clearance-margin", "0", "--no-files", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)["summary"]
    assert summary["cone collision-free solid angle [sr]"] <= summary["cone solid angle [sr]"]
    assert "tool-tip collision-free volume [m^3]" in summary
    assert main(["workspace", "--resolution", "7", "--cone-resolution", "8", "6", "5",
                 "--no-files", "--json"]) == 0
    assert "tool-tip collision-free volume [m^3]" not in json.loads(
        capsys.readouterr().out)["summary"]
    pytest.importorskip("dask")
    pytest.importorskip("pandas")
    task = tmp_path / "task.toml"
    task.write_text(_task().to_toml())  # type: ignore[attr-defined]
    args = ["synthesize", str(task), "--samples", "300", "--no-figures", "--json",
            "--scheduler", "synchronous", "--collision-samples", "200"]
    assert main([*args, "-o", str(tmp_path / "a"), "--bodies", "scaled"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["collisions"] and "min_clearance" in rep["reference"]
    assert main([*args, "-o", str(tmp_path / "b"), "--min-clearance", "0"]) == 1
    assert "--min-clearance" in capsys.readouterr().err


def test_cli_view_bodies(tmp_path, capsys) -> None:
    pytest.importorskip("matplotlib")
    from athenakin.cli import main

    out = tmp_path / "v.png"
    assert main(["view", "-o", str(out), "--bodies", "--no-labels"]) == 0
    assert out.stat().st_size > 1000
    thick = tmp_path / "bodies.toml"
    thick.write_text(BODIES.with_radius(link_a=0.03).to_toml())
    assert main(["view", "-o", str(out), "--bodies", str(thick), "--force"]) == 0
    assert main(["view", "-o", str(tmp_path / "v.html"), "--bodies"]) == 1
    assert "--bodies" in capsys.readouterr().err
