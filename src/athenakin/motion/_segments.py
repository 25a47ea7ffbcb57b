"""A path's waypoints and segments: their checks, their bounds and the timing of one segment."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._typing import FloatArray
from ..design import Design
from ..errors import Reason
from ._errors import (
    PathInfeasibleError,
    TimingInfeasibleError,
    TrajectoryLimitError,
)
from ._limits import Limits, _seg_name, _SegmentPlan
from ._path import (
    Segment,
    q_derivatives,
    q_on_tips,
    tip_speed_factor,
)
from ._timing import (
    TimeLawError,
    dwell,
    lam_profile,
    parameter_limits,
    squeezed,
)

#: Grid points per segment on which the derivative bounds of ``q(lam)`` are taken.
BOUND_GRID = 129


#: Factor applied to the grid bounds (the maxima may fall between grid points).
BOUND_SAFETY = 1.05


def _segment_bounds(seg: Segment, T: FloatArray, design: Design
                    ) -> tuple[tuple[FloatArray, ...], float, dict[str, Any]]:
    lam = np.linspace(0.0, 1.0, BOUND_GRID)
    q0, d1, d2, d3 = q_derivatives(seg, lam, T, design)
    with np.errstate(invalid="ignore"):
        K = tuple(BOUND_SAFETY * np.nan_to_num(np.nanmax(np.abs(d), axis=0), nan=0.0)
                  if np.any(np.isfinite(d)) else np.zeros(3) for d in (d1, d2, d3))
    tf = float(np.max(tip_speed_factor(seg, lam))) * BOUND_SAFETY
    tips = seg.tips(lam)
    _, reason, mode = q_on_tips(tips, T, design)
    grid = {"lam": lam, "q": q0, "tip_e": tips, "reason": reason, "mode": mode}
    return K, tf, grid  # type: ignore[return-value]


def _mm_hint(tip: FloatArray, design: Design) -> str:
    r = float(np.linalg.norm(tip))
    if r > 4.0 * max(design.tool_length, float(np.max(design.lengths))):
        return (f"; |tip_e| = {r:.6g} m is far beyond the robot's reach: lengths are in "
                f"metres (millimetres typed?)")
    return ""


def _check_waypoints(tips: FloatArray, T: FloatArray, design: Design) -> None:
    """Each waypoint inside the workspace and the strokes, one assembly mode (before timing)."""
    q, reason, mode = q_on_tips(tips, T, design)
    for k in range(tips.shape[0]):
        tip = np.array2string(tips[k], precision=6)
        if reason[k] != 0:
            r = Reason(int(reason[k]))
            raise PathInfeasibleError(
                f"waypoint {k} (tip_e = {tip} m) is outside the workspace ({r.name}: "
                f"{r.description}){_mm_hint(tips[k], design)}", waypoint=k, limit="workspace",
                value=float(reason[k]), bound=0.0)
        _check_stroke(q[k], f"waypoint {k} (tip_e = {tip} m)", design, waypoint=k)
        if mode[k] != mode[0]:
            raise PathInfeasibleError(
                f"waypoint {k} (tip_e = {tip} m) is reached in assembly mode {int(mode[k]):+d}, "
                f"waypoint 0 in mode {int(mode[0]):+d}: the path would switch the parallel "
                f"module's assembly mode", waypoint=k, limit="assembly_mode",
                value=float(mode[k]), bound=float(mode[0]))


def _check_stroke(q: FloatArray, what: str, design: Design, *,
                  waypoint: int | None = None, segment: int | None = None) -> None:
    lo, hi = design.stroke_min, design.stroke_max
    for i in range(3):
        if q[i] < lo[i] or q[i] > hi[i]:
            b = float(lo[i] if q[i] < lo[i] else hi[i])
            raise PathInfeasibleError(
                f"{what} exceeds the stroke limit of q{i + 1}: {q[i]:.6g} m (limit {b:.6g} m)",
                waypoint=waypoint, segment=segment, limit="stroke", value=float(q[i]),
                bound=b, actuator=i)


def _check_segment(k: int, grid: dict[str, Any], mode0: int, design: Design) -> None:
    """Every grid point of segment ``k`` inside the workspace and strokes, in mode ``mode0``."""
    out = np.flatnonzero(grid["reason"] != 0)
    where = f"segment {k} (waypoint {k} -> {k + 1})"
    if out.size:
        j = int(out[0])
        r = Reason(int(grid["reason"][j]))
        raise PathInfeasibleError(
            f"{where} leaves the workspace at lam = {grid['lam'][j]:.4g} (tip_e = "
            f"{np.array2string(grid['tip_e'][j], precision=6)} m; {r.name}: {r.description})",
            segment=k, limit="workspace", value=float(r), bound=0.0)
    lo, hi = design.stroke_min, design.stroke_max
    bad = np.flatnonzero(np.any((grid["q"] < lo) | (grid["q"] > hi), axis=-1))
    if bad.size:
        j = int(bad[0])
        _check_stroke(grid["q"][j], f"{where} at lam = {grid['lam'][j]:.4g} (tip_e = "
                      f"{np.array2string(grid['tip_e'][j], precision=6)} m)", design,
                      segment=k)
    sw = np.flatnonzero(grid["mode"] != mode0)
    if sw.size:
        j = int(sw[0])
        raise PathInfeasibleError(
            f"{where} switches the parallel module's assembly mode from {mode0:+d} to "
            f"{int(grid['mode'][j]):+d} at lam = {grid['lam'][j]:.4g} (tip_e = "
            f"{np.array2string(grid['tip_e'][j], precision=6)} m)", segment=k,
            limit="assembly_mode", value=float(grid["mode"][j]), bound=float(mode0))


def _check_budget(duration: float, rate: float, max_duration: float, max_samples: int,
                  segment: int | None) -> None:
    """Duration and sample count within their bounds (before any sample is made)."""
    which = "" if segment is None else f" (the longest segment: {segment})"
    if not duration <= max_duration:
        raise TrajectoryLimitError(
            f"the trajectory would last {duration:.6g} s{which}, longer than max_duration = "
            f"{max_duration:g} s (slow near a singularity or the workspace border? raise "
            f"max_duration to accept it)", limit="max_duration", value=duration,
            bound=max_duration, segment=segment)
    n = duration * rate + 2
    if not n <= max_samples:
        raise TrajectoryLimitError(
            f"the trajectory would need {n:.6g} samples ({duration:.6g} s at {rate:g} Hz), "
            f"more than max_samples = {max_samples}: lower the rate or raise max_samples",
            limit="max_samples", value=n, bound=float(max_samples), segment=segment)


def _time_segment(sp: _SegmentPlan, limits: Limits, dt: float, timing: str, k: int,
                  max_duration: float) -> None:
    if sp.seg.scale == 0.0:
        sp.profile = dwell(sp.requested or 0.0)
        return
    f = sp.tighten
    vmax, amax = limits.v_max * f, limits.a_max * f
    jmax = None if limits.j_max is None else limits.j_max * f
    K1, K2, K3 = sp.K
    where = f"segment {k} (waypoint {k} -> {k + 1}, {_seg_name(sp)})"
    try:
        lim = parameter_limits(K1, K2, K3, v_max=vmax, a_max=amax, j_max=jmax,
                               tip_factor=sp.tip_factor,
                               tip_speed=None if limits.tip_speed is None
                               else limits.tip_speed * f)
    except ValueError as exc:
        raise TrajectoryLimitError(f"{where}: {exc}", limit="time_law", value=math.nan,
                                   bound=math.nan, segment=k) from None
    # a rest-to-rest motion over lam in [0, 1] takes at least max(1 / v, 2 / sqrt(a))
    t_low = max(1.0 / lim.v if lim.v > 0 else math.inf, 2.0 / math.sqrt(lim.a)
                if lim.a > 0 else math.inf)
    if not t_low <= max_duration:
        raise TrajectoryLimitError(
            f"{where} would take at least {t_low:.6g} s within the actuator limits, longer "
            f"than max_duration = {max_duration:g} s (the actuators move fast along the path "
            f"there: near a singularity or the workspace border?)", limit="max_duration",
            value=t_low, bound=max_duration, segment=k)
    try:
        if sp.requested is None:
            sp.profile = lam_profile(lim, dt=dt)
            return
        prof = lam_profile(lim, minimum_duration=sp.requested)
    except TimeLawError as exc:
        raise TrajectoryLimitError(f"{where}: {exc}", limit="time_law", value=math.nan,
                                   bound=math.nan, segment=k) from None
    if prof.duration > sp.requested * (1 + 1e-12) + 1e-12 and timing == "fixed":
        if sp.requested <= 0:
            raise TimingInfeasibleError(
                f"timing='fixed': segment {_seg_name(sp)} has zero duration but moves the tip "
                f"{sp.seg.scale:.6g} m", segment=-1, required=prof.duration, requested=0.0,
                time=math.nan, index=-1, limit="velocity", value=math.inf,
                bound=float(limits.v_max.min()))
        prof = squeezed(prof, sp.requested)
    sp.profile = prof
