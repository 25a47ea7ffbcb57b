"""motion.plan checks the path before timing and bounds time and memory (issue 13, item 6).

Each case used to sample the whole trajectory before any check (hours of
trajectory, gigabytes, tens of seconds) or to surface a raw Ruckig error; each
is now a named error that names the waypoint, segment or limit, raised before
any sample is made.
"""

from __future__ import annotations

import numpy as np
import pytest

import athenakin as ak
from athenakin.motion import Margins, PlanOptions, plan, plan_directions
from athenakin.motion import _plan as plan_module
from athenakin.motion._errors import (
    MotionError,
    PathInfeasibleError,
    SafetyViolationError,
    TrajectoryLimitError,
)
from athenakin.motion._path import q_on_tips

D = ak.Design.default()
T = ak.default_rcm_frame(D)
TIP0 = np.array([0.25, 0.0, 0.0])
TOWARD_H0 = np.array([0.22, 0.0, 0.02])   # the line TIP0 -> here leaves the workspace
OFF = Margins(half_chord=0, h=0, link=0, sin_u2=0, sin_u4=0, p=0, depth=0, cond=np.inf)


def _border() -> float:
    """Fraction of TIP0 -> TOWARD_H0 where the workspace ends (bisection)."""
    lo, hi = 0.9, 1.1
    for _ in range(60):
        m = (lo + hi) / 2
        ok = q_on_tips((TIP0 + m * (TOWARD_H0 - TIP0))[None], T, D)[1][0] == 0
        lo, hi = (m, hi) if ok else (lo, m)
    return lo


BORDER = _border()


def test_waypoint_typed_in_mm_names_the_waypoint_and_the_unit():
    with pytest.raises(PathInfeasibleError, match=r"waypoint 0 .*millimetres") as ei:
        plan([[250.0, 0.0, 0.0], [270.0, -20.0, 0.0]], T, D)
    e = ei.value
    assert e.waypoint == 0 and e.segment is None and e.limit == "workspace"
    assert isinstance(e, SafetyViolationError) and np.isnan(e.time) and e.index == -1


def test_waypoint_outside_the_workspace_says_so_not_parameter_limits():
    tips = [TIP0, TIP0 + 1.01 * (TOWARD_H0 - TIP0), TIP0]
    with pytest.raises(PathInfeasibleError, match="waypoint 1 .*outside the workspace") as ei:
        plan(tips, T, D, options=PlanOptions(margins=OFF))
    assert "parameter_limits" not in str(ei.value) and ei.value.waypoint == 1


def test_waypoint_beyond_a_stroke_names_waypoint_and_actuator():
    tight = ak.Design(**{**{f: getattr(D, f) for f in ("l1", "l2", "l3", "l4", "l5")},
                         "tool_length": D.tool_length, "q_min": (-0.12, -0.10, 0.20),
                         "q_max": D.q_max})
    tips = [TIP0, [0.27, -0.02, 0.0]]
    with pytest.raises(PathInfeasibleError, match="waypoint 1 .*stroke limit of q1") as ei:
        plan(tips, T, tight)
    assert ei.value.actuator == 0 and ei.value.bound == -0.12


def test_segment_leaving_the_workspace_between_inside_waypoints_names_the_segment():
    # both ends inside the workspace, the straight line between them is not
    a, b = np.array([0.219, -0.022, -0.048]), np.array([0.228, 0.013, 0.047])
    outside = q_on_tips(np.linspace(a, b, 201), T, D)[1] != 0
    assert not outside[0] and not outside[-1] and outside.any()
    with pytest.raises(PathInfeasibleError, match=r"segment 1 \(waypoint 1 -> 2\) leaves the "
                                                  r"workspace") as ei:
        plan([a + [0.0, 0.0, 0.005], a, b], T, D, options=PlanOptions(margins=OFF))
    assert ei.value.segment == 1 and ei.value.waypoint is None


@pytest.mark.parametrize("eps", [1e-6, 1e-12])
def test_segment_ending_at_the_border_is_refused_by_duration(eps):
    end = TIP0 + BORDER * (1 - eps) * (TOWARD_H0 - TIP0)
    with pytest.raises(TrajectoryLimitError, match=r"segment 0 .*max_duration") as ei:
        plan([TIP0, end], T, D, options=PlanOptions(margins=OFF))
    e = ei.value
    assert e.limit == "max_duration" and e.segment == 0 and e.value > e.bound == 3600.0


def test_ruckig_failure_is_a_named_one_line_error():
    # past max_duration the time law itself fails (Ruckig's -101, formerly
    # "ValueError: -101 is not a valid Result")
    end = TIP0 + BORDER * (1 - 1e-9) * (TOWARD_H0 - TIP0)
    with pytest.raises(TrajectoryLimitError, match=r"segment 0 .*Ruckig") as ei:
        plan([TIP0, end], T, D, options=PlanOptions(margins=OFF, max_duration=1e9))
    assert ei.value.limit == "time_law" and "\n" not in str(ei.value)


def test_rate_1e9_is_a_named_error_naming_the_sample_bound():
    with pytest.raises(TrajectoryLimitError, match="max_samples") as ei:
        plan([TIP0, [0.27, -0.02, 0.0]], T, D, options=PlanOptions(rate=1e9))
    assert ei.value.limit == "max_samples" and ei.value.value > 1e8


def test_max_duration_and_max_samples_are_keywords_with_checked_values():
    tips = [TIP0, [0.27, -0.02, 0.0]]
    with pytest.raises(TrajectoryLimitError, match="max_duration = 0.1 s"):
        plan(tips, T, D, options=PlanOptions(max_duration=0.1))
    with pytest.raises(TrajectoryLimitError, match="max_samples = 10"):
        plan(tips, T, D, options=PlanOptions(max_samples=10))
    with pytest.raises(ValueError, match="max_samples"):
        plan(tips, T, D, options=PlanOptions(max_samples=1.5))
    with pytest.raises(ValueError, match="max_duration"):
        plan(tips, T, D, options=PlanOptions(max_duration=-1.0))
    # fixed times are checked against the bounds before anything else
    with pytest.raises(TrajectoryLimitError, match="max_duration"):
        plan(tips, T, D, times=[0.0, 1e6])
    with pytest.raises(TrajectoryLimitError, match="max_duration"):
        plan_directions([0.0, 0.1], [1.4, 1.4], [0.25, 0.25], T, D,
                        options=PlanOptions(max_duration=1e-3))


def test_chunked_checks_stop_at_the_first_violating_chunk(monkeypatch):
    """The safety check streams: sampling stops in the chunk of the first violation,
    which is found at the same sample as with one chunk."""
    tips = [TIP0, [0.27, -0.02, 0.0], [0.27, -0.02, 0.02]]
    tight = Margins(link=0.12)   # crossed about halfway
    with pytest.raises(SafetyViolationError) as whole:
        plan(tips, T, D, options=PlanOptions(margins=tight))
    calls = []
    orig = plan_module._sample

    def counting(*a, **k):
        calls.append(len(a[-1]))
        return orig(*a, **k)

    monkeypatch.setattr(plan_module, "CHECK_CHUNK", 50)
    monkeypatch.setattr(plan_module, "_sample", counting)
    with pytest.raises(SafetyViolationError) as chunked:
        plan(tips, T, D, options=PlanOptions(margins=tight))
    assert chunked.value.index == whole.value.index > 0
    assert chunked.value.limit == whole.value.limit
    assert chunked.value.time == whole.value.time
    assert len(calls) == whole.value.index // 50 + 1   # no chunk after the violation


def test_chunked_sampling_gives_the_same_trajectory(monkeypatch):
    tips = [TIP0, [0.27, -0.02, 0.0]]
    one = plan(tips, T, D)
    monkeypatch.setattr(plan_module, "CHECK_CHUNK", 97)
    many = plan(tips, T, D)
    np.testing.assert_array_equal(one.q, many.q)
    np.testing.assert_array_equal(one.qdd, many.qdd)
    np.testing.assert_array_equal(one.measures.cond, many.measures.cond)


def test_new_errors_are_motion_errors():
    assert issubclass(PathInfeasibleError, SafetyViolationError)
    assert issubclass(TrajectoryLimitError, MotionError)


def test_margins_and_measures_arguments_named():
    """Audit of issue 13: Margins(half_chord=10**400) and singularity_measures(q="abc",
    T_b_e=None, design=None) were Overflow/Value/KeyErrors from inside."""
    with pytest.raises(ValueError, match="half_chord"):
        Margins(half_chord=10**400)
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    q = np.array([-0.1, 0.1, 0.45])
    tip = np.zeros(3)
    from athenakin.motion import singularity_measures
    with pytest.raises(TypeError, match="q"):
        singularity_measures("abc", tip, T, d)
    with pytest.raises(TypeError, match="T_b_e"):
        singularity_measures(q, tip, None, d)
    with pytest.raises(ValueError, match="mode"):
        singularity_measures(q, tip, T, d, mode=[])
    m = singularity_measures(q, tip, T, None)        # design None: the default, as elsewhere
    assert np.isfinite(m.h)
