"""Instrument paths about the RCM to sampled actuator trajectories: :func:`plan`.

Pipeline (docs/motion.md):

1. The path is a polyline of tool-tip waypoints in the RCM frame E (straight
   segments), or of direction + insertion waypoints (great-circle direction,
   linear depth). Each segment is traversed rest to rest: the tip stops at every
   waypoint, where the path has a corner.
2. Geometry: every point of the path maps to unique actuator values through the
   controller-form inverse kinematics (:func:`athenakin.q_from_tool_tip`); the
   bounds of ``dq/dlam``, ``d2q/dlam2``, ``d3q/dlam3`` on a grid of the segment turn
   the actuator limits into limits of the path parameter ``lam``.
3. Timing: Ruckig computes the time-optimal jerk-limited profile ``lam(t)`` of each
   segment within those limits, stretched to the requested waypoint times when
   they are longer.
4. Sampling at ``rate``: ``q`` from the exact inverse kinematics of the tip at
   ``lam(t)``, ``qd, qdd, qddd`` by the chain rule.
5. Safety: every sample is checked against the workspace, the stroke limits, the
   singularity margins, and the velocity, acceleration, jerk and tip-speed
   limits; the first violation raises :class:`SafetyViolationError`. Nothing is
   returned unless every sample passes.
6. Collisions, when asked (``bodies=``, ``environment=`` or ``clearance_margin=``):
   every sample's least clearance between the robot's bodies and to the obstacles
   (:mod:`athenakin.collision`) must be at least the margin; the first sample closer
   raises :class:`CollisionError`, naming its time, index and the pair.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_array, check_instance, check_scalar, check_transform
from ..design import Design, resolve_design
from ..errors import InvalidInputError, Reason
from ..robot import direction_from_angles
from ._clearance import ClearanceCheck, clearance_check, sample_clearance
from ._errors import (
    CollisionError,
    PathInfeasibleError,
    SafetyViolationError,
    TimingInfeasibleError,
    TrajectoryLimitError,
)
from ._forces import planned
from ._path import (
    Segment,
    arc_segment,
    line_segment,
    q_derivatives,
    q_on_tips,
    reparametrised,
    tip_speed_factor,
)
from ._safety import MEASURE_NAMES, Margins, SingularityMeasures, singularity_measures
from ._timing import (
    LamProfile,
    TimeLawError,
    dwell,
    lam_profile,
    parameter_limits,
    squeezed,
)

__all__ = ["Limits", "Trajectory", "plan", "plan_directions", "check_samples",
           "LIMIT_RTOL", "BOUND_GRID", "BOUND_SAFETY", "MAX_DURATION", "MAX_SAMPLES",
           "MIN_RATE", "MAX_WAYPOINTS"]

#: Relative tolerance of the velocity / acceleration / jerk / tip-speed checks.
LIMIT_RTOL = 1e-6
#: Grid points per segment on which the derivative bounds of ``q(lam)`` are taken.
BOUND_GRID = 129
#: Factor applied to the grid bounds (the maxima may fall between grid points).
BOUND_SAFETY = 1.05
#: Replanning rounds when a sample still exceeds a kinematic limit.
MAX_REPLANS = 4
#: Default longest trajectory :func:`plan` accepts, s (``max_duration``).
MAX_DURATION = 3600.0
#: Default largest number of samples :func:`plan` accepts (``max_samples``); each
#: sample holds about 60 floats while it is checked, about 1 GB at this bound.
MAX_SAMPLES = 2_000_000
#: Lowest sampling rate :func:`plan` accepts, Hz: a sample period longer than a second
#: is no controller's, and a rate of 1e-300 Hz would make the period infinite.
MIN_RATE = 1.0
#: Most waypoints :func:`plan` accepts (each segment is bounded, timed and checked on
#: its own, about 10 ms): a path of 100,000 waypoints ran for a quarter of an hour.
MAX_WAYPOINTS = 1000
#: Samples checked at a time: a violation stops the sampling there.
CHECK_CHUNK = 20_000

Timing = Literal["stretch", "fixed"]


@dataclasses.dataclass(frozen=True, kw_only=True)
class Limits:
    """Kinematic limits of a trajectory (stroke limits come from the design).

    Attributes
    ----------
    v_max, a_max : ndarray, shape (3,)
        Actuator speed (m/s) and acceleration (m/s^2) limits.
    j_max : ndarray, shape (3,) or None
        Actuator jerk limits (m/s^3); None: not limited (acceleration-limited
        profile, whose acceleration steps).
    tip_speed : float or None
        Tool-tip speed limit (m/s).
    """

    v_max: NDArray[np.float64]
    a_max: NDArray[np.float64]
    j_max: NDArray[np.float64] | None = None
    tip_speed: float | None = None

    @classmethod
    def build(cls, v_max: ArrayLike, a_max: ArrayLike, j_max: ArrayLike | None,
              tip_speed: float | None) -> Limits:
        """Validate scalars or (3,) arrays of positive limits."""
        def vec(x: ArrayLike, name: str) -> NDArray[np.float64]:
            a = check_array(x, name, ())
            if a.ndim not in (0, 1) or (a.ndim == 1 and a.shape != (3,)):
                raise ValueError(f"{name}: expected a number or 3 numbers (q1, q2, q3), "
                                 f"got shape {a.shape}")
            if np.any(a <= 0):
                raise ValueError(f"{name}: expected positive limits, got {a.tolist()}")
            return np.broadcast_to(a, (3,)).astype(float)

        return cls(v_max=vec(v_max, "v_max"), a_max=vec(a_max, "a_max"),
                   j_max=None if j_max is None else vec(j_max, "j_max"),
                   tip_speed=None if tip_speed is None
                   else check_scalar(tip_speed, "tip_speed", positive=True))


@dataclasses.dataclass(frozen=True)
class Trajectory:
    """A planned, checked actuator trajectory sampled at a uniform rate.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Sample times, s, ``t[i] = t[0] + i / rate``.
    q, qd, qdd : ndarray, shape (N, 3)
        Actuator positions (m), velocities (m/s) and accelerations (m/s^2).
    qddd : ndarray, shape (N, 3) or None
        Jerks (m/s^3) when a jerk limit was given, else None.
    tip_e : ndarray, shape (N, 3)
        Tool tip in the RCM frame E, m (on the requested path by construction).
    segment : ndarray of int, shape (N,)
        Segment of each sample (``k``: from waypoint ``k`` to ``k + 1``).
    mode : ndarray of int, shape (N,)
        Assembly mode of the parallel module (+1 / -1).
    measures : SingularityMeasures
        Distance of every sample to every singularity.
    waypoints_e : ndarray, shape (K, 3)
        The tip waypoints (frame E, m).
    waypoint_times : ndarray, shape (K,)
        When the tip is at each waypoint (at rest), s.
    stretched : ndarray of bool, shape (K - 1,)
        Segments made longer than the requested times to respect the limits.
    rate : float
        Samples per second.
    limits : Limits
    margins : Margins
    T_b_e : ndarray, shape (4, 4)
    design : Design
    clearance : ndarray, shape (N,) or None
        Least clearance of each sample between the robot's bodies and to the
        obstacles, m (None when collisions were not checked).
    closest_pair : ndarray of str, shape (N, 2) or None
        The two names (body, body or obstacle) of that clearance.
    clearance_margin : float or None
        The margin every sample keeps, m (None when not checked).
    forces : ndarray, shape (N, 3) or None
        Actuator forces along the motion, N (positive along increasing ``q``), when
        planned with ``masses=`` (:mod:`athenakin.motion._forces`), else None.
    """

    t: NDArray[np.float64]
    q: NDArray[np.float64]
    qd: NDArray[np.float64]
    qdd: NDArray[np.float64]
    qddd: NDArray[np.float64] | None
    tip_e: NDArray[np.float64]
    segment: NDArray[np.int64]
    mode: NDArray[np.int64]
    measures: SingularityMeasures
    waypoints_e: NDArray[np.float64]
    waypoint_times: NDArray[np.float64]
    stretched: NDArray[np.bool_]
    rate: float
    limits: Limits
    margins: Margins
    T_b_e: NDArray[np.float64]
    design: Design
    clearance: NDArray[np.float64] | None = None
    closest_pair: NDArray[np.str_] | None = None
    clearance_margin: float | None = None
    forces: NDArray[np.float64] | None = None

    @property
    def duration(self) -> float:
        """Time from the first to the last sample, s."""
        return float(self.t[-1] - self.t[0])

    @property
    def depth(self) -> NDArray[np.float64]:
        """Depth of the tip beyond the RCM, ``|tip_e|``, m, shape (N,)."""
        return np.linalg.norm(self.tip_e, axis=-1)

    @property
    def direction_e(self) -> NDArray[np.float64]:
        """Unit instrument direction in frame E (O_s through the RCM to the tip), (N, 3)."""
        return self.tip_e / self.depth[:, None]

    @property
    def p(self) -> NDArray[np.float64]:
        """Distance from ``O_s`` to the RCM (the passive prismatic joint), m, shape (N,)."""
        return self.design.tool_length - self.depth


# --------------------------------------------------------------------------------------
def plan(tips_e: ArrayLike, T_b_e: ArrayLike, design: Design | None = None, *,
         rate: float = 1000.0, v_max: ArrayLike = 0.05, a_max: ArrayLike = 0.5,
         j_max: ArrayLike | None = None, tip_speed: float | None = None,
         times: ArrayLike | None = None, timing: Timing = "stretch",
         margins: Margins | None = None, max_duration: float | None = None,
         max_samples: int | None = None, bodies: object = None, environment: object = None,
         clearance_margin: float | None = None, masses: object = None,
         f_max: ArrayLike | None = None) -> Trajectory:
    """Plan an actuator trajectory that moves the tool tip along straight segments.

    Parameters
    ----------
    tips_e : array-like, shape (K, 3)
        Tool-tip waypoints in the RCM frame E (m), K >= 2, visited in order along
        straight segments; the tip stops at each waypoint. Repeating a waypoint
        makes a dwell (with ``times``).
    T_b_e : array-like, shape (4, 4)
        RCM frame (the surgeon's set-up).
    design : Design, optional
        Defaults to :meth:`Design.default`; ``design.tool_length`` is ``L`` in
        ``tip = O_s + L d``.
    rate : float, keyword-only
        Samples per second (default 1 kHz), at least :data:`MIN_RATE` (1 Hz).
    v_max, a_max : float or array-like of shape (3,), keyword-only
        Actuator velocity (m/s) and acceleration (m/s^2) limits.
    j_max : float or array-like of shape (3,), optional, keyword-only
        Actuator jerk limit (m/s^3). Without it the profile is acceleration-limited
        (its acceleration steps) and :attr:`Trajectory.qddd` is None.
    tip_speed : float, optional, keyword-only
        Tool-tip speed limit (m/s).
    times : array-like, shape (K,), optional, keyword-only
        Requested arrival time at each waypoint (s, non-decreasing). Without it
        every segment takes the shortest time the limits allow.
    timing : {"stretch", "fixed"}, keyword-only
        What to do when ``times`` ask for more than the limits allow:
        ``"stretch"`` (default) lengthens those segments (see
        :attr:`Trajectory.stretched`); ``"fixed"`` keeps the times and raises
        :class:`TimingInfeasibleError` at the first sample that breaks a limit.
    margins : Margins, optional, keyword-only
        Least distances to the singularities (default :class:`Margins`).
    max_duration : float, optional, keyword-only
        Longest trajectory accepted, s (default :data:`MAX_DURATION`).
    max_samples : int, optional, keyword-only
        Largest number of samples accepted (default :data:`MAX_SAMPLES`); bounds
        the memory and time of the planning.
    bodies : athenakin.collision.Bodies, optional, keyword-only
        Check that every sample keeps these bodies ``clearance_margin`` apart (and
        from the obstacles). Default: no collision check, unless ``environment`` or
        ``clearance_margin`` is given, then :meth:`Bodies.default(design)
        <athenakin.collision.Bodies.default>`.
    environment : athenakin.collision.Environment, optional, keyword-only
        Obstacles every sample's bodies must keep clear of (turns the check on).
    clearance_margin : float, optional, keyword-only
        Least clearance of every sample, m (turns the check on); default 5 mm when
        the check is on, 0 to refuse only contact and penetration.
    masses : athenakin.dynamics.MassModel, optional, keyword-only
        Attach the actuator forces (:attr:`Trajectory.forces`, N) computed by
        :func:`athenakin.dynamics.inverse_dynamics`.
    f_max : float or array-like of shape (3,), optional, keyword-only
        Actuator force limits, N (needs ``masses``): the trajectory is slowed down
        uniformly until ``|forces| <= f_max`` (:mod:`athenakin.motion._forces`).

    Returns
    -------
    Trajectory
        Every sample is inside the workspace and the stroke limits, keeps the
        margins and respects the kinematic limits (relative tolerance
        :data:`LIMIT_RTOL`) and the force limits.

    Raises
    ------
    PathInfeasibleError
        Checked first, before any timing: a waypoint, or a point of a segment
        (on a grid of :data:`BOUND_GRID` points), is outside the workspace or the
        stroke limits, or the path changes the assembly mode. The message names
        the waypoint or segment (and hints at millimetres typed for metres).
    TrajectoryLimitError
        Checked before sampling: the trajectory would last longer than
        ``max_duration`` or need more than ``max_samples`` samples, or a segment's
        time law cannot be computed within its limits (named in the message).
    SafetyViolationError
        The first sample (time, index) that leaves the workspace or the stroke
        limits, crosses a singularity margin, or (after replanning) a kinematic limit.
        Samples are checked in chunks as they are made, so that the first
        violation stops the planning.
    TimingInfeasibleError
        ``timing="fixed"`` and the requested times break a limit.
    CollisionError
        (A :class:`SafetyViolationError`.) The first sample whose clearance is below
        ``clearance_margin``: its time, index and the pair of bodies (or body and
        obstacle) in the message and the attributes.
    TypeError, ValueError
        Malformed arguments (named in the message).

    Examples
    --------
    >>> import numpy as np, athenakin as ak
    >>> d = ak.Design.default()
    >>> T = ak.default_rcm_frame(d)
    >>> tips = [[0.25, 0.0, 0.0], [0.27, -0.02, 0.0], [0.27, -0.02, 0.02]]
    >>> traj = ak.motion.plan(tips, T, d, rate=1000.0, v_max=0.05, a_max=0.5)
    >>> bool(np.all(np.abs(traj.qd) <= 0.05 * (1 + 1e-6)))
    True
    """
    design = resolve_design(design)
    tips = check_array(tips_e, "tips_e", (3,))
    if tips.ndim != 2 or tips.shape[0] < 2:
        raise ValueError(f"tips_e: expected shape (K, 3) with K >= 2 waypoints, "
                         f"got shape {tips.shape}")
    segs = [line_segment(tips[k], tips[k + 1]) for k in range(tips.shape[0] - 1)]

    def run(**limits: object) -> Trajectory:
        return _plan(segs, tips, T_b_e, design, rate=rate, times=times, timing=timing,
                     margins=margins, max_duration=max_duration, max_samples=max_samples,
                     bodies=bodies, environment=environment,
                     clearance_margin=clearance_margin, **limits)  # type: ignore[arg-type]

    return planned(run, v_max=v_max, a_max=a_max, j_max=j_max, tip_speed=tip_speed,  # type: ignore[return-value]
                   masses=masses, f_max=f_max, fixed_times=timing == "fixed")


def plan_directions(azimuth: ArrayLike, polar: ArrayLike, depth: ArrayLike, T_b_e: ArrayLike,
                    design: Design | None = None, **options: object) -> Trajectory:
    """Plan a trajectory through instrument-direction + insertion waypoints.

    Between waypoints the instrument direction turns on the great circle (about
    the RCM) while the insertion changes linearly; the tip stops at each waypoint.

    Parameters
    ----------
    azimuth, polar : array-like, shape (K,)
        Instrument direction in the RCM frame E, radians, as in
        :func:`athenakin.direction_from_angles` (``polar`` from ``z_e``; ``polar`` near
        0 or pi is the spherical joint's singularity ``sin u4 = 0``).
    depth : array-like, shape (K,)
        Insertion: depth of the tool tip beyond the RCM, m (``p = L - depth``).
    T_b_e : array-like, shape (4, 4)
    design : Design, optional
    **options
        The keyword-only options of :func:`plan` (``rate``, ``v_max``, ``a_max``,
        ``j_max``, ``tip_speed``, ``times``, ``timing``, ``margins``,
        ``max_duration``, ``max_samples``, ``bodies``, ``environment``,
        ``clearance_margin``).

    Returns
    -------
    Trajectory

    Raises
    ------
    PathInfeasibleError, TrajectoryLimitError, SafetyViolationError, TimingInfeasibleError
    CollisionError
        As :func:`plan`.
    TypeError, ValueError
        As :func:`plan`; also ``ValueError`` for a segment between opposite directions.
    """
    design = resolve_design(design)
    az = check_array(azimuth, "azimuth", ())
    po = check_array(polar, "polar", ())
    dp = check_array(depth, "depth", ())
    if az.ndim != 1 or az.shape[0] < 2 or po.shape != az.shape or dp.shape != az.shape:
        raise ValueError(f"azimuth, polar, depth: expected three arrays of the same shape (K,) "
                         f"with K >= 2, got shapes {az.shape}, {po.shape}, {dp.shape}")
    if np.any(dp <= 0):
        raise ValueError(f"depth: expected positive depths beyond the RCM (m), got "
                         f"{dp.tolist()}")
    dirs = direction_from_angles(az, po)
    if np.any(np.sum(dirs[1:] * dirs[:-1], axis=-1) <= -1 + 1e-9):
        raise ValueError("azimuth, polar: two consecutive directions are opposite; the great "
                         "circle between them is undefined")
    tips = dirs * dp[:, None]
    segs = [arc_segment(tips[k], tips[k + 1]) for k in range(tips.shape[0] - 1)]
    opts = dict(options)
    masses, f_max = opts.pop("masses", None), opts.pop("f_max", None)
    lim = {k: opts.pop(k) for k in ("v_max", "a_max", "j_max", "tip_speed") if k in opts}

    def run(**limits: object) -> Trajectory:
        return _plan(segs, tips, T_b_e, design, **opts, **limits)  # type: ignore[arg-type]

    return planned(run, v_max=lim.get("v_max", 0.05), a_max=lim.get("a_max", 0.5),  # type: ignore[return-value, arg-type]
                   j_max=lim.get("j_max"), tip_speed=lim.get("tip_speed"),  # type: ignore[arg-type]
                   masses=masses, f_max=f_max,  # type: ignore[arg-type]
                   fixed_times=opts.get("timing") == "fixed")


# --------------------------------------------------------------------------------------
@dataclasses.dataclass
class _SegmentPlan:
    seg: Segment
    K: tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]
    tip_factor: float
    tighten: float = 1.0        # extra factor (< 1) on all limits after a failed check
    profile: LamProfile | None = None
    requested: float | None = None


def _segment_bounds(seg: Segment, T: NDArray[np.float64], design: Design
                    ) -> tuple[tuple[NDArray[np.float64], ...], float, dict[str, Any]]:
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


def _mm_hint(tip: NDArray[np.float64], design: Design) -> str:
    r = float(np.linalg.norm(tip))
    if r > 4.0 * max(design.tool_length, float(np.max(design.lengths))):
        return (f"; |tip_e| = {r:.6g} m is far beyond the robot's reach: lengths are in "
                f"metres (millimetres typed?)")
    return ""


def _check_waypoints(tips: NDArray[np.float64], T: NDArray[np.float64], design: Design) -> None:
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


def _check_stroke(q: NDArray[np.float64], what: str, design: Design, *,
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


def _plan(segs: list[Segment], tips: NDArray[np.float64], T_b_e: ArrayLike, design: Design, *,
          rate: float = 1000.0, v_max: ArrayLike = 0.05, a_max: ArrayLike = 0.5,
          j_max: ArrayLike | None = None, tip_speed: float | None = None,
          times: ArrayLike | None = None, timing: Timing = "stretch",
          margins: Margins | None = None, max_duration: float | None = None,
          max_samples: int | None = None, bodies: object = None, environment: object = None,
          clearance_margin: float | None = None) -> Trajectory:
    T = check_transform(T_b_e, "T_b_e")
    if T.shape != (4, 4):
        raise ValueError(f"T_b_e: expected one transform of shape (4, 4), got shape {T.shape}")
    rate = check_scalar(rate, "rate", positive=True)
    if not rate >= MIN_RATE:
        raise ValueError(f"rate: expected at least {MIN_RATE:g} sample per second (Hz), "
                         f"got {rate:g}")
    max_duration = MAX_DURATION if max_duration is None else check_scalar(
        max_duration, "max_duration", positive=True)
    if max_samples is None:
        max_samples = MAX_SAMPLES
    elif (isinstance(max_samples, bool) or not isinstance(max_samples, (int, np.integer))
          or max_samples < 2):
        raise ValueError(f"max_samples: expected an integer >= 2, got {max_samples!r}")
    max_samples = int(max_samples)
    limits = Limits.build(v_max, a_max, j_max, tip_speed)
    margins = Margins() if margins is None else margins
    if not isinstance(margins, Margins):
        raise TypeError(f"margins: expected athenakin.motion.Margins, got "
                        f"{type(margins).__name__}")
    if timing not in ("stretch", "fixed"):
        raise ValueError(f"timing: expected 'stretch' or 'fixed', got {timing!r}")
    check = clearance_check(design, bodies, environment, clearance_margin)
    K = tips.shape[0]
    if K > MAX_WAYPOINTS:
        raise ValueError(f"waypoints: expected at most {MAX_WAYPOINTS}, got {K} (plan the path "
                         f"in parts)")
    req: NDArray[np.float64] | None = None
    t0 = 0.0
    if times is not None:
        tt = check_array(times, "times", ())
        if tt.shape != (K,):
            raise ValueError(f"times: expected shape ({K},) (one per waypoint), got {tt.shape}")
        req = np.diff(tt)
        if np.any(req < 0):
            raise ValueError(f"times: expected non-decreasing arrival times, got {tt.tolist()}")
        t0 = float(tt[0])
        _check_budget(float(tt[-1] - tt[0]), rate, max_duration, max_samples, None)
    elif timing == "fixed":
        raise ValueError("timing='fixed' needs times (the arrival time of each waypoint)")

    # the path first: waypoints, then each segment on a grid (no timing can fix these)
    _check_waypoints(tips, T, design)
    mode0 = int(q_on_tips(tips[:1], T, design)[2][0])
    plans = []
    for k, seg in enumerate(segs):
        seg = reparametrised(seg, T, design)
        Kd, tf, grid = _segment_bounds(seg, T, design)
        _check_segment(k, grid, mode0, design)
        plans.append(_SegmentPlan(seg=seg, K=Kd, tip_factor=tf,  # type: ignore[arg-type]
                                  requested=None if req is None else float(req[k])))
    dt = 1.0 / rate
    for _round in range(MAX_REPLANS + 1):
        for k, sp in enumerate(plans):
            _time_segment(sp, limits, dt, timing, k, max_duration)
        durations = [sp.profile.duration for sp in plans]  # type: ignore[union-attr]
        longest = int(np.argmax(durations))
        _check_budget(float(np.sum(durations)), rate, max_duration, max_samples, longest)
        samples, bad = _sample_checked(plans, T, design, rate, t0, limits, margins, check)
        if bad is not None and bad["limit"] == "clearance":
            raise _collision(bad, samples, check)  # type: ignore[arg-type]
        if bad is None:
            break
        k = int(samples["segment"][bad["index"]])
        sp = plans[k]
        squeezed_seg = sp.profile is not None and sp.profile.scale > 1.0
        kinematic = bad["limit"] in ("velocity", "acceleration", "jerk", "tip_speed")
        if kinematic and squeezed_seg:
            raise _timing_error(bad, samples, k, sp)
        if not kinematic or _round == MAX_REPLANS:
            raise _violation(bad, samples)
        # the grid bounds missed a maximum: tighten this segment and replan
        ratio = bad["bound"] / bad["value"] if bad["value"] > 0 else 0.5
        sp.tighten *= min(0.98, ratio ** (1 / 3) * 0.98)
    return _trajectory(samples, plans, tips, limits, margins, T, design, rate, t0, check)


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


def _seg_name(sp: _SegmentPlan) -> str:
    return f"{sp.seg.start.tolist()} -> {sp.seg.end.tolist()}"


def _sample_checked(plans: list[_SegmentPlan], T: NDArray[np.float64], design: Design,
                    rate: float, t0: float, limits: Limits, margins: Margins,
                    check: ClearanceCheck | None = None
                    ) -> tuple[dict[str, Any], dict | None]:  # type: ignore[type-arg]
    """Sample and check in chunks of :data:`CHECK_CHUNK`; stop at the first violation.

    Returns the samples made (all of them, or up to the end of the chunk holding
    the violation) with their measures, and the violation (``check_samples``'s
    dict, index into the returned samples) or None. With a clearance ``check``
    the samples also hold ``clearance`` and ``closest_pair``, and a sample closer
    than the margin is a geometric violation (``limit == "clearance"``, ``pair``).
    """
    durations = np.array([sp.profile.duration for sp in plans])  # type: ignore[union-attr]
    total = float(np.sum(durations))
    n = int(math.floor(total * rate + 1e-9)) + 1
    if (n - 1) / rate < total - 1e-12:
        n += 1
    chunks: list[dict[str, Any]] = []
    mode0: int | None = None
    bad = None
    for i0 in range(0, n, CHECK_CHUNK):
        c = _sample(plans, T, design, rate, t0, limits, np.arange(i0, min(n, i0 + CHECK_CHUNK)))
        if mode0 is None:
            ok = np.flatnonzero(c["reason"] == 0)
            mode0 = int(c["mode"][ok[0]]) if ok.size else 1
        bad = check_samples(c, T, design, limits, margins, mode0=mode0)
        if check is not None:
            bad = _check_clearance(c, bad, check, T, design)
        chunks.append(c)
        if bad is not None:
            bad["index"] += i0
            break
    return _concat(chunks), bad


_KINEMATIC = ("velocity", "acceleration", "jerk", "tip_speed")


def _check_clearance(c: dict[str, Any], bad: dict | None,  # type: ignore[type-arg]
                     check: ClearanceCheck, T: NDArray[np.float64], design: Design
                     ) -> dict | None:  # type: ignore[type-arg]
    """Add the clearance of the samples ``c``; the first violation, geometric ones first.

    A sample closer than the margin is a geometric violation, like leaving the
    workspace: it comes before every kinematic one, and before a later geometric one.
    """
    n = c["q"].shape[0]
    ok = c["reason"] == 0
    dist = np.full(n, np.nan)
    pair = np.full((n, 2), "", dtype="<U64")
    if np.any(ok):
        idx = np.flatnonzero(ok)
        p_sign = np.where(design.tool_length - np.linalg.norm(c["tip_e"][idx], axis=-1) < 0,
                          -1, 1)
        dist[idx], pair[idx] = sample_clearance(check, c["q"][idx], T, design, c["mode"][idx],
                                                p_sign)
    c["clearance"] = dist
    c["closest_pair"] = pair
    with np.errstate(invalid="ignore"):
        close = np.flatnonzero(dist < check.margin)
    if close.size == 0:
        return bad
    i = int(close[0])
    if bad is None or bad["limit"] in _KINEMATIC or i < bad["index"]:
        return {"index": i, "limit": "clearance", "value": float(dist[i]),
                "bound": check.margin, "actuator": None, "pair": tuple(str(x) for x in pair[i])}
    return bad


def _collision(bad: dict, samples: dict, check: ClearanceCheck  # type: ignore[type-arg]
               ) -> CollisionError:
    i = bad["index"]
    a, b = bad["pair"]
    what = ("makes {a!r} and {b!r} overlap" if bad["value"] < 0 else
            "brings {a!r} and {b!r} closer than the clearance margin").format(a=a, b=b)
    msg = (f"trajectory sample {i} at t = {float(samples['t'][i]):.4f} s (segment "
           f"{int(samples['segment'][i])}, tip_e = "
           f"{np.array2string(samples['tip_e'][i], precision=5)} m) {what}: clearance "
           f"{bad['value']:.6g} m < {check.margin:.6g} m")
    return CollisionError(msg, time=float(samples["t"][i]), index=i, value=bad["value"],
                          bound=check.margin, pair=(a, b))


def _concat(chunks: list[dict[str, Any]]) -> dict[str, Any]:
    if len(chunks) == 1:
        return chunks[0]
    out: dict[str, Any] = {}
    for key, v in chunks[0].items():
        if v is None:
            out[key] = None
        elif isinstance(v, np.ndarray):
            out[key] = np.concatenate([c[key] for c in chunks])
        else:  # SingularityMeasures
            out[key] = dataclasses.replace(v, **{
                f.name: np.concatenate([getattr(c[key], f.name) for c in chunks])
                for f in dataclasses.fields(v)})
    return out


def _sample(plans: list[_SegmentPlan], T: NDArray[np.float64], design: Design, rate: float,
            t0: float, limits: Limits, index: NDArray[np.int64]) -> dict[str, Any]:
    """The samples of global indices ``index`` (n,) of the trajectory."""
    durations = np.array([sp.profile.duration for sp in plans])  # type: ignore[union-attr]
    ends = np.cumsum(durations)
    n = index.shape[0]
    tl = index / rate
    k = np.minimum(np.searchsorted(ends, tl, side="right"), len(plans) - 1)
    # a sample exactly at a segment's end belongs to the next one (at rest there)
    starts = ends - durations
    tau = np.minimum(tl - starts[k], durations[k])
    lam = np.zeros((4, n))
    q = np.full((n, 3), np.nan)
    dq = np.zeros((3, n, 3))
    tipf = np.zeros(n)
    tips = np.empty((n, 3))
    for s, sp in enumerate(plans):
        idx = np.flatnonzero(k == s)
        if idx.size == 0:
            continue
        lam[:, idx] = np.stack(sp.profile.evaluate(tau[idx]))  # type: ignore[union-attr]
        q0, d1, d2, d3 = q_derivatives(sp.seg, lam[0, idx], T, design)
        q[idx], dq[0, idx], dq[1, idx], dq[2, idx] = q0, d1, d2, d3
        tipf[idx] = tip_speed_factor(sp.seg, lam[0, idx])
        tips[idx] = sp.seg.tips(lam[0, idx])
    _, reason, mode = q_on_tips(tips, T, design)
    ld, ldd, lddd = lam[1][:, None], lam[2][:, None], lam[3][:, None]
    with np.errstate(invalid="ignore"):
        qd = dq[0] * ld
        qdd = dq[1] * ld ** 2 + dq[0] * ldd
        qddd = dq[2] * ld ** 3 + 3 * dq[1] * ld * ldd + dq[0] * lddd
    return {"t": t0 + tl, "q": q, "qd": qd, "qdd": qdd,
            "qddd": None if limits.j_max is None else qddd, "tip_e": tips,
            "segment": k, "reason": reason, "mode": mode, "tip_speed": tipf * lam[1]}


_SAMPLE_KEYS = {"t": (), "q": (3,), "qd": (3,), "qdd": (3,), "tip_e": (3,), "reason": (),
                "mode": (), "tip_speed": ()}


def _check_sample_arguments(samples: object, T_b_e: object, design: object, limits: object,
                            margins: object, mode0: object) -> None:
    """The boundary checks of :func:`check_samples` (named errors, nothing computed)."""
    if not isinstance(samples, dict):
        raise TypeError(f"samples: expected a dict of sample arrays, got {type(samples).__name__}")
    missing = sorted(set(_SAMPLE_KEYS) - set(samples))
    if missing:
        raise InvalidInputError(f"samples: missing {missing}; expected the keys "
                                f"{sorted(_SAMPLE_KEYS)} (and qddd)")
    n = None
    for k, tail in _SAMPLE_KEYS.items():
        a = samples[k]
        if not isinstance(a, np.ndarray) or a.ndim != 1 + len(tail) or a.shape[1:] != tail \
                or (n is not None and a.shape[0] != n):
            raise InvalidInputError(f"samples[{k!r}]: expected an array of shape "
                                    f"({'N' if n is None else n}{''.join(f', {t}' for t in tail)})"
                                    f", got {getattr(a, 'shape', type(a).__name__)}")
        n = a.shape[0]
    check_transform(T_b_e, "T_b_e")  # type: ignore[arg-type]
    check_instance(design, "design", Design)
    check_instance(limits, "limits", Limits)
    check_instance(margins, "margins", Margins)
    if mode0 is not None and (isinstance(mode0, bool) or not isinstance(mode0, (int, np.integer))
                              or mode0 not in (1, -1)):
        raise InvalidInputError(f"mode0: expected +1, -1 or None, got {mode0!r}")


def check_samples(samples: dict[str, Any], T_b_e: NDArray[np.float64],
                  design: Design, limits: Limits, margins: Margins, *,
                  mode0: int | None = None) -> dict | None:  # type: ignore[type-arg]
    """First sample that breaks a limit, or None.

    Parameters
    ----------
    samples : dict
        ``t (N,)``, ``q, qd, qdd (N, 3)``, ``qddd (N, 3) or None``, ``tip_e (N, 3)``,
        ``reason (N,)`` (inverse-kinematics reason without stroke limits), ``mode (N,)``,
        ``tip_speed (N,)``.
    T_b_e : ndarray, shape (4, 4)
    design : Design
    limits : Limits
    margins : Margins
    mode0 : int, optional, keyword-only
        Assembly mode the samples must keep (default: that of the first sample).

    Returns
    -------
    dict or None
        ``index, limit, value, bound, actuator`` of the first violation of a
        geometric limit (workspace, stroke, assembly mode, margins of
        :data:`MEASURE_NAMES`, in this order at one sample), or if there is none, of
        the first violation of a kinematic limit (velocity, acceleration, jerk, tip
        speed). Geometric limits come first because no timing can fix them.
        The samples' :class:`SingularityMeasures` are stored under
        ``samples["measures"]``.
    """
    _check_sample_arguments(samples, T_b_e, design, limits, margins, mode0)
    q = samples["q"]
    n = q.shape[0]
    # (name, bad (n,) or (n, 3) per actuator, value, bound)
    checks: list[tuple[str, NDArray[np.bool_], NDArray[np.float64], object]] = []
    reason = samples["reason"]
    ok = reason == 0
    checks.append(("workspace", ~ok, reason.astype(float), 0.0))
    lo, hi = design.stroke_min, design.stroke_max
    with np.errstate(invalid="ignore"):
        under, over = q < lo, q > hi
    checks.append(("stroke", (under | over) & ok[:, None], q,
                   np.where(under, lo, hi)))
    mode = samples["mode"]
    m0 = int(mode[0]) if mode0 is None else int(mode0)
    checks.append(("assembly_mode", (mode != m0) & ok, mode.astype(float), float(m0)))
    # samples outside the workspace (mode 0, q NaN) are reported by the workspace check;
    # measure them as mode +1 at q = 0 only to keep the arrays whole
    meas = singularity_measures(np.where(np.isfinite(q), q, 0.0), samples["tip_e"], T_b_e,
                                design, mode=np.where(ok, mode, 1))
    samples["measures"] = meas
    for name in MEASURE_NAMES:
        m = getattr(margins, name)
        v = getattr(meas, name)
        with np.errstate(invalid="ignore"):
            bad = (v > m) if margins.is_upper(name) else (v < m)
        checks.append((name, bad & ok, v, m))
    tol = 1 + LIMIT_RTOL
    for name, arr, lim in (("velocity", samples["qd"], limits.v_max),
                           ("acceleration", samples["qdd"], limits.a_max),
                           ("jerk", samples["qddd"], limits.j_max)):
        if arr is None or lim is None:
            continue
        with np.errstate(invalid="ignore"):
            bad = np.abs(arr) > lim * tol
        checks.append((name, bad & ok[:, None], arr, np.broadcast_to(lim, arr.shape)))
    if limits.tip_speed is not None:
        v = samples["tip_speed"]
        with np.errstate(invalid="ignore"):
            bad = np.abs(v) > limits.tip_speed * tol
        checks.append(("tip_speed", bad & ok, v, limits.tip_speed))
    # geometric limits first: no timing can fix them (and next to the workspace boundary a
    # path may break a kinematic limit before it leaves)
    n_geo = 3 + len(MEASURE_NAMES)
    first = n
    for group in (checks[:n_geo], checks[n_geo:]):
        for _, bad, *_ in group:
            idx = np.flatnonzero(bad if bad.ndim == 1 else np.any(bad, axis=-1))
            if idx.size:
                first = min(first, int(idx[0]))
        if first < n:
            checks = group
            break
    if first == n:
        return None
    for name, bad, val, bnd in checks:
        row = bad[first]
        if not np.any(row):
            continue
        if bad.ndim == 2:
            b = np.asarray(bnd)[first]
            excess = np.where(row, np.abs(val[first] - np.sign(val[first]) * np.abs(b))
                              if name != "stroke" else np.abs(val[first] - b), -np.inf)
            act = int(np.argmax(excess))
            return {"index": first, "limit": name, "value": float(val[first, act]),
                    "bound": float(b[act]), "actuator": act}
        return {"index": first, "limit": name, "value": float(val[first]),
                "bound": float(bnd), "actuator": None}  # type: ignore[arg-type]
    raise AssertionError("unreachable")  # pragma: no cover


def _describe(bad: dict, samples: dict) -> str:  # type: ignore[type-arg]
    i = bad["index"]
    t = float(samples["t"][i])
    tip = np.array2string(samples["tip_e"][i], precision=5)
    lim = bad["limit"]
    who = f" of q{bad['actuator'] + 1}" if bad["actuator"] is not None else ""
    if lim == "workspace":
        r = Reason(int(bad["value"]))
        what = f"leaves the workspace ({r.name}: {r.description})"
    elif lim == "assembly_mode":
        what = (f"switches the parallel module's assembly mode from {bad['bound']:+.0f} to "
                f"{bad['value']:+.0f}")
    elif lim in ("cond",):
        what = (f"exceeds the singularity margin 'cond': condition number of d tip / d q = "
                f"{bad['value']:.6g} > {bad['bound']:.6g}")
    elif lim in MEASURE_NAMES:
        what = (f"crosses the singularity margin '{lim}': {bad['value']:.6g} < "
                f"{bad['bound']:.6g}")
    elif lim == "stroke":
        what = f"exceeds the stroke limit{who}: {bad['value']:.6g} m (limit {bad['bound']:.6g} m)"
    else:
        unit = {"velocity": "m/s", "acceleration": "m/s^2", "jerk": "m/s^3",
                "tip_speed": "m/s"}[lim]
        what = (f"exceeds the {lim.replace('_', ' ')} limit{who}: |{bad['value']:.6g}| > "
                f"{bad['bound']:.6g} {unit}")
    return (f"trajectory sample {i} at t = {t:.4f} s (segment {int(samples['segment'][i])}, "
            f"tip_e = {tip} m) {what}")


def _violation(bad: dict, samples: dict) -> SafetyViolationError:  # type: ignore[type-arg]
    i = bad["index"]
    return SafetyViolationError(_describe(bad, samples), time=float(samples["t"][i]), index=i,
                                limit=bad["limit"], value=bad["value"], bound=bad["bound"],
                                actuator=bad["actuator"])


def _timing_error(bad: dict, samples: dict, k: int,  # type: ignore[type-arg]
                  sp: _SegmentPlan) -> TimingInfeasibleError:
    i = bad["index"]
    prof = sp.profile
    assert prof is not None and sp.requested is not None
    msg = (f"timing='fixed': segment {k} ({_seg_name(sp)}) is given {sp.requested:.6g} s but "
           f"needs {prof.min_duration:.6g} s within the limits; " + _describe(bad, samples))
    return TimingInfeasibleError(msg, segment=k, required=prof.min_duration,
                                 requested=sp.requested, time=float(samples["t"][i]), index=i,
                                 limit=bad["limit"], value=bad["value"], bound=bad["bound"],
                                 actuator=bad["actuator"])


def _trajectory(samples: dict, plans: list[_SegmentPlan], tips: NDArray[np.float64],  # type: ignore[type-arg]
                limits: Limits, margins: Margins, T: NDArray[np.float64], design: Design,
                rate: float, t0: float, check: ClearanceCheck | None = None) -> Trajectory:
    durations = np.array([sp.profile.duration for sp in plans])  # type: ignore[union-attr]
    wt = t0 + np.concatenate([[0.0], np.cumsum(durations)])
    stretched = np.array([sp.requested is not None and sp.profile.duration  # type: ignore[union-attr]
                          > sp.requested * (1 + 1e-9) + 1e-12 for sp in plans], dtype=np.bool_)
    ro = {k: np.asarray(v) for k, v in samples.items() if isinstance(v, np.ndarray)}
    for v in ro.values():
        v.setflags(write=False)
    return Trajectory(
        t=ro["t"], q=ro["q"], qd=ro["qd"], qdd=ro["qdd"], qddd=ro.get("qddd"),
        tip_e=ro["tip_e"], segment=ro["segment"], mode=ro["mode"],
        measures=samples["measures"], waypoints_e=tips.copy(), waypoint_times=wt,
        stretched=stretched, rate=rate, limits=limits, margins=margins, T_b_e=T.copy(),
        design=design, clearance=ro.get("clearance"), closest_pair=ro.get("closest_pair"),
        clearance_margin=None if check is None else check.margin)
