"""Property-based tests of the outer subpackages (issue 23), with hypothesis.

Study conversions, synthesis (RCM frames, task samples), the app's model functions, the
plot helpers, the exports (URDF / MJCF names) and the calibration files: each property
over generated inputs, including magnitudes near the float range. ``derandomize=True``
makes every run draw the same examples (reproducible in CI); ``max_examples`` keeps the
file to a few seconds.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import athenakin as ak
from athenakin import InvalidInputError

D = ak.Design.default()
T0 = ak.default_rcm_frame(D)
SETTINGS = settings(max_examples=150, derandomize=True, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])

finite = st.floats(min_value=-1e3, max_value=1e3, allow_nan=False, allow_infinity=False)
unit_interval = st.floats(min_value=-1.0, max_value=1.0, allow_nan=False)
scale = st.sampled_from([1e-300, 1e-150, 1e-20, 1.0, 3.7, 1e20, 1e150, 1e300])


@st.composite
def quaternions(draw):
    q = np.array([draw(unit_interval) for _ in range(4)])
    if np.linalg.norm(q) < 1e-3:
        q = np.array([1.0, 0.0, 0.0, 0.0])
    return q / np.linalg.norm(q)


@st.composite
def transforms(draw):
    T = np.eye(4)
    T[:3, :3] = ak.study.rotation_from_quaternion(draw(quaternions()))
    T[:3, 3] = [draw(finite) for _ in range(3)]
    return T


# --- study conversions -------------------------------------------------------------------------
@SETTINGS
@given(T=transforms(), s=scale)
def test_study_round_trip_at_any_scale(T, s):
    X = ak.study.study_from_transform(T)
    got = ak.study.transform_from_study(X * s)
    tol = 1e-12 * (1.0 + np.abs(T[:3, 3]).max())
    np.testing.assert_allclose(got, T, rtol=0, atol=tol)
    P = ak.study.paper_matrix_from_study(X * s)
    np.testing.assert_allclose(P[1:, 1:], T[:3, :3], rtol=0, atol=1e-12)


@SETTINGS
@given(q=quaternions(), s=scale)
def test_rotation_from_any_nonzero_quaternion_is_a_rotation(q, s):
    R = ak.study.rotation_from_quaternion(q * s)
    np.testing.assert_allclose(R.T @ R, np.eye(3), rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, rtol=0, atol=1e-12)


# --- synthesis --------------------------------------------------------------------------------
@SETTINGS
@given(axis=st.tuples(finite, finite, finite), s=scale, rcm=st.tuples(finite, finite, finite))
def test_rcm_frame_from_any_axis_is_rigid_and_along_it(axis, s, rcm):
    a = np.array(axis) * s
    if not np.all(np.isfinite(a)) or not np.any(a):
        with pytest.raises((InvalidInputError, TypeError)):
            ak.synthesis.rcm_frame_from_axis(rcm, a)
        return
    F = ak.synthesis.rcm_frame_from_axis(rcm, a)
    R = F[:3, :3]
    np.testing.assert_allclose(R.T @ R, np.eye(3), rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, rtol=0, atol=1e-12)
    d = np.array(axis) / np.max(np.abs(axis))            # scaled first: no under/overflow
    d = d / np.linalg.norm(d)
    np.testing.assert_allclose(R[:, 0], d, rtol=0, atol=1e-12)
    np.testing.assert_allclose(F[:3, 3], rcm, rtol=0, atol=0)


@SETTINGS
@given(half=st.floats(0.01, np.pi / 2), lo=st.floats(0.0, 0.1), span=st.floats(0.001, 0.1),
       n=st.integers(1, 200), seed=st.integers(0, 2**32 - 1))
def test_task_samples_lie_in_the_task(half, lo, span, n, seed):
    task = ak.synthesis.Task(rcm=T0[:3, 3], axis=T0[:3, 0], half_angle=half,
                             depth=(lo, lo + span))
    s = ak.synthesis.sample_task(task, n, seed=seed)
    assert s.direction_e.shape == (n, 3) and s.depth.shape == (n,)
    np.testing.assert_allclose(np.linalg.norm(s.direction_e, axis=-1), 1.0, rtol=0, atol=1e-12)
    assert np.all(s.theta <= half + 1e-12) and np.all(s.theta >= 0)
    assert np.all((s.depth >= lo) & (s.depth <= lo + span))
    s2 = ak.synthesis.sample_task(task, n, seed=seed)
    np.testing.assert_array_equal(s.direction_e, s2.direction_e)       # seeded


@SETTINGS
@given(n=st.one_of(st.integers(-5, 0), st.integers(10**6 + 1, 10**12)))
def test_sample_task_refuses_counts_out_of_range(n):
    task = ak.synthesis.Task(rcm=T0[:3, 3], axis=T0[:3, 0], half_angle=0.3, depth=(0.05, 0.1))
    with pytest.raises(InvalidInputError, match=r"^n: "):
        ak.synthesis.sample_task(task, n)


# --- the app's model functions ---------------------------------------------------------------
@SETTINGS
@given(az=st.floats(-np.pi + 1e-3, np.pi - 1e-3), pol=st.floats(1e-3, np.pi - 1e-3),
       depth=st.floats(1e-4, 0.3))
def test_tip_angles_round_trip(az, pol, depth):
    tip = ak.app.tip_from_angles(az, pol, depth)
    a2, p2, d2 = ak.app.angles_from_tip(tip)
    np.testing.assert_allclose(ak.app.tip_from_angles(a2, p2, d2), tip, rtol=0, atol=1e-12)
    assert abs(d2 - depth) <= 1e-12


@SETTINGS
@given(valid=st.lists(st.booleans(), min_size=16, max_size=16))
def test_slot_statuses_follow_valid(valid):
    v = np.array(valid)
    reason = np.where(v, 0, int(ak.Reason.STROKE_LIMIT))
    out = ak.app.slot_statuses(v, reason)
    assert [s.valid for s in out] == valid and [s.slot for s in out] == list(range(16))
    assert all((s.why == "") == s.valid for s in out)


@SETTINGS
@given(text=st.text(max_size=40), level=st.sampled_from(["ok", "warn", "error"]))
def test_message_html_escapes_any_text(text, level):
    html = ak.app.message_html(text, level)
    assert html.startswith("<div") and html.endswith("</div>")
    inner = html[html.index(">") + 1:-len("</div>")]
    assert "<" not in inner and ">" not in inner


# --- plot helpers -----------------------------------------------------------------------------
@SETTINGS
@given(c=st.tuples(finite, finite, finite), r=st.floats(0.0, 10.0), n=st.integers(2, 500))
def test_circle_points_lie_on_the_circle(c, r, n):
    pts = ak.plot.circle_points(np.array(c), r, n)
    assert pts.shape == (n, 3)
    np.testing.assert_array_equal(pts[:, 0], c[0])
    dist = np.hypot(pts[:, 1] - c[1], pts[:, 2] - c[2])
    np.testing.assert_allclose(dist, r, rtol=0, atol=1e-12 * (1 + max(map(abs, c))))


@SETTINGS
@given(a=st.tuples(finite, finite, finite), b=st.tuples(finite, finite, finite),
       r=st.floats(0.01, 1.0), n=st.integers(2, 100), s=scale)
def test_arc_points_lie_on_the_sphere_from_a(a, b, r, n, s):
    av, bv = np.array(a) * s, np.array(b) * s
    if not (np.all(np.isfinite(av)) and np.all(np.isfinite(bv)) and np.any(av) and np.any(bv)):
        with pytest.raises((InvalidInputError, TypeError)):
            ak.plot.arc_points(np.zeros(3), av, bv, r, n)
        return
    pts = ak.plot.arc_points(np.zeros(3), av, bv, r, n)
    assert pts.shape == (n, 3) and np.all(np.isfinite(pts))
    np.testing.assert_allclose(np.linalg.norm(pts, axis=-1), r, rtol=0, atol=1e-12)
    u = av / np.abs(av).max()                  # scaled first: |a| of a subnormal a is 0
    np.testing.assert_allclose(pts[0], r * u / np.linalg.norm(u), rtol=0, atol=1e-12)


@SETTINGS
@given(n=st.integers(10**5 + 1, 10**15))
def test_curve_sizes_are_bounded(n):
    with pytest.raises(InvalidInputError, match=r"^n: "):
        ak.plot.circle_points(np.zeros(3), 0.1, n)


# --- exports ----------------------------------------------------------------------------------
printable = st.text(st.characters(blacklist_categories=("Cc", "Cs"),
                                  blacklist_characters="\ufffe\uffff"), min_size=1, max_size=30)


@settings(max_examples=15, derandomize=True, deadline=None)
@given(name=printable)
def test_any_printable_name_round_trips_through_urdf_and_mjcf(name):
    urdf = ak.sim.urdf_from_design(T0, D, robot_name=name)
    assert ET.fromstring(urdf.split("-->", 1)[-1]).get("name") == name
    mjcf = ak.sim.mjcf_from_design(T0, D, model_name=name)
    assert ET.fromstring(mjcf.split("-->", 1)[-1]).get("model") == name


@SETTINGS
@given(prefix=st.text(max_size=5), ctrl=st.sampled_from(["\x00", "\x01", "\x1b", "\x7f",
                                                         "\x85", "\n", "\t", "\ud800"]))
def test_a_control_character_in_a_name_is_refused(prefix, ctrl):
    name = prefix + ctrl
    with pytest.raises(InvalidInputError, match=r"^robot_name: "):
        ak.sim.urdf_from_design(T0, D, robot_name=name)


# --- calibration files ------------------------------------------------------------------------
@settings(max_examples=15, derandomize=True, deadline=None)
@given(n=st.integers(1, 20), seed=st.integers(0, 1000),
       comment=st.text(st.characters(blacklist_categories=("Cc", "Cs"),
                                     blacklist_characters="\ufffe\uffff"), max_size=30))
def test_measurements_csv_round_trip(tmp_path_factory, n, seed, comment):
    rng = np.random.default_rng(seed)
    q = rng.uniform(-0.3, 0.7, (n, 3))
    tips = rng.normal(scale=0.3, size=(n, 3))
    text = ak.calibration.measurements_csv_text(q, tips, comment=comment)
    f = tmp_path_factory.mktemp("m") / "m.csv"
    f.write_text(text, encoding="utf-8")
    m = ak.calibration.read_measurements_csv(f)
    np.testing.assert_array_equal(m.q, q)          # repr round trip: exact
    np.testing.assert_array_equal(m.tips, tips)


@SETTINGS
@given(ctrl=st.sampled_from(["\x00", "\x1b", "\x7f"]))
def test_a_control_character_in_a_csv_comment_is_refused(ctrl):
    with pytest.raises(InvalidInputError, match=r"^comment: "):
        ak.calibration.measurements_csv_text(np.zeros((1, 3)), np.zeros((1, 3)),
                                             comment="a" + ctrl)


@settings(max_examples=10, derandomize=True, deadline=None)
@given(n=st.integers(4, 30), seed=st.integers(0, 1000))
def test_random_poses_are_reachable_and_within_strokes(n, seed):
    q = ak.calibration.random_poses(n, T0, D, rng=seed)
    assert q.shape == (n, 3)
    assert np.all(q >= D.stroke_min) and np.all(q <= D.stroke_max)
    par = ak.parallel.parallel_forward_kinematics(q, D)
    assert np.all(par.valid[:, 0])
