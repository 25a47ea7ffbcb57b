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
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._robot_model import Robot, resolve_robot
from .._typing import BoolArray, FloatArray, IntArray
from .._validation import check_array, check_frame
from ..design import Design
from ..robot import direction_from_angles
from ._check import _check_clearance, _collision, _timing_error, _violation, check_samples
from ._clearance import ClearanceCheck, clearance_check
from ._forces import planned
from ._limits import LIMIT_RTOL, Limits, _SegmentPlan
from ._options import MAX_DURATION, MAX_SAMPLES, MIN_RATE, PlanOptions, Timing, plan_options
from ._path import (
    Segment,
    arc_segment,
    line_segment,
    q_derivatives,
    q_on_tips,
    reparametrised,
    tip_speed_factor,
)
from ._safety import Margins, SingularityMeasures
from ._segments import (
    BOUND_GRID,
    BOUND_SAFETY,
    _check_budget,
    _check_segment,
    _check_waypoints,
    _segment_bounds,
    _time_segment,
)

__all__ = ["Limits", "PlanOptions", "Trajectory", "plan", "plan_directions", "check_samples",
           "LIMIT_RTOL", "BOUND_GRID", "BOUND_SAFETY", "MAX_DURATION", "MAX_SAMPLES",
           "MIN_RATE", "MAX_WAYPOINTS"]

#: Replanning rounds when a sample still exceeds a kinematic limit.
MAX_REPLANS = 4
#: Most waypoints :func:`plan` accepts (each segment is bounded, timed and checked on
#: its own, about 10 ms): a path of 100,000 waypoints ran for a quarter of an hour.
MAX_WAYPOINTS = 1000
#: Samples checked at a time: a violation stops the sampling there.
CHECK_CHUNK = 20_000


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

    t: FloatArray
    q: FloatArray
    qd: FloatArray
    qdd: FloatArray
    qddd: FloatArray | None
    tip_e: FloatArray
    segment: IntArray
    mode: IntArray
    measures: SingularityMeasures
    waypoints_e: FloatArray
    waypoint_times: FloatArray
    stretched: BoolArray
    rate: float
    limits: Limits
    margins: Margins
    T_b_e: FloatArray
    design: Design
    clearance: FloatArray | None = None
    closest_pair: NDArray[np.str_] | None = None
    clearance_margin: float | None = None
    forces: FloatArray | None = None

    @property
    def duration(self) -> float:
        """Time from the first to the last sample, s."""
        return float(self.t[-1] - self.t[0])

    @property
    def depth(self) -> FloatArray:
        """Depth of the tip beyond the RCM, ``|tip_e|``, m, shape (N,)."""
        return np.linalg.norm(self.tip_e, axis=-1)

    @property
    def direction_e(self) -> FloatArray:
        """Unit instrument direction in frame E (O_s through the RCM to the tip), (N, 3)."""
        return self.tip_e / self.depth[:, None]

    @property
    def p(self) -> FloatArray:
        """Distance from ``O_s`` to the RCM (the passive prismatic joint), m, shape (N,)."""
        return self.design.tool_length - self.depth


# --------------------------------------------------------------------------------------
def plan(tips_e: ArrayLike, robot: Robot | ArrayLike, design: Design | None = None, *,
         times: ArrayLike | None = None, bodies: object = None, environment: object = None,
         masses: object = None, options: PlanOptions | None = None) -> Trajectory:
    """Plan an actuator trajectory that moves the tool tip along straight segments.

    Parameters
    ----------
    tips_e : array-like, shape (K, 3)
        Tool-tip waypoints in the RCM frame E (m), K >= 2, visited in order along
        straight segments; the tip stops at each waypoint. Repeating a waypoint
        makes a dwell (with ``times``).
    robot : athenakin.Robot or array-like, shape (4, 4)
        The robot (its design, RCM frame, and the bodies, obstacles and masses of the
        checks), or its RCM frame E in the base frame ``T_b_e`` (m, the surgeon's
        set-up); then ``design``, ``bodies``, ``environment`` and ``masses`` build the
        Robot (:func:`athenakin._robot_model.resolve_robot`).
    design : Design, optional
        With ``T_b_e`` only; default :meth:`Design.default`. ``design.tool_length`` is
        ``L`` in ``tip = O_s + L d``.
    times : array-like, shape (K,), optional, keyword-only
        Requested arrival time at each waypoint (s, non-decreasing). Without it
        every segment takes the shortest time the limits allow.
    bodies : athenakin.collision.Bodies, optional, keyword-only
        Check that every sample keeps these bodies ``clearance_margin`` apart (and
        from the obstacles). Default the Robot's; with none, no collision check
        unless ``environment`` or ``options.clearance_margin`` is given, then
        :meth:`Bodies.default(design) <athenakin.collision.Bodies.default>`.
    environment : athenakin.collision.Environment, optional, keyword-only
        Obstacles every sample's bodies must keep clear of (turns the check on);
        default the Robot's.
    masses : athenakin.dynamics.MassModel, optional, keyword-only
        Attach the actuator forces (:attr:`Trajectory.forces`, N) computed by
        :func:`athenakin.dynamics.inverse_dynamics` (and hold ``options.f_max``);
        default the Robot's. Beside a Robot, each of ``bodies``, ``environment`` and
        ``masses`` only where the Robot has none.
    options : PlanOptions, optional, keyword-only
        Sample rate, kinematic and force limits, timing policy, singularity and
        clearance margins, duration and sample bounds (default ``PlanOptions()``).

    Returns
    -------
    Trajectory
        Every sample is inside the workspace and the stroke limits, keeps the
        margins and respects the kinematic limits (relative tolerance
        :data:`LIMIT_RTOL`) and the force limits.

    Raises
    ------
    PathInfeasibleError
        Checked first, before any timing: a waypoint, or a point of a segment (on a
        grid of :data:`BOUND_GRID` points), is outside the workspace or the stroke
        limits, or the path changes the assembly mode (the message names it).
    TrajectoryLimitError
        Checked before sampling: longer than ``max_duration``, more than
        ``max_samples`` samples, or a segment's time law cannot be computed.
    SafetyViolationError
        The first sample (time, index) that leaves the workspace or the stroke limits,
        crosses a singularity margin, or (after replanning) a kinematic limit.
    TimingInfeasibleError
        ``timing="fixed"`` and the requested times break a limit.
    CollisionError
        (A :class:`SafetyViolationError`.) The first sample whose clearance is below
        the margin: its time, index and the pair of bodies in the message.
    TypeError, ValueError
        Malformed arguments (named in the message); ``robot`` neither a Robot nor a
        frame, a design or a part given beside a Robot that has its own.

    Examples
    --------
    >>> import numpy as np, athenakin as ak
    >>> robot = ak.Robot.default()
    >>> tips = [[0.25, 0.0, 0.0], [0.27, -0.02, 0.0], [0.27, -0.02, 0.02]]
    >>> opts = ak.motion.PlanOptions(rate=1000.0, v_max=0.05, a_max=0.5)
    >>> traj = ak.motion.plan(tips, robot, options=opts)
    >>> bool(np.all(np.abs(traj.qd) <= 0.05 * (1 + 1e-6)))
    True

    The functional form ``(T_b_e, design)`` builds the same Robot:

    >>> same = ak.motion.plan(tips, robot.T_b_e, robot.design, options=opts)
    >>> bool(np.array_equal(same.q, traj.q))
    True
    """
    model = resolve_robot(robot, design, bodies=bodies, environment=environment,
                          masses=masses)
    tips = check_array(tips_e, "tips_e", (3,))
    if tips.ndim != 2 or tips.shape[0] < 2:
        raise ValueError(f"tips_e: expected shape (K, 3) with K >= 2 waypoints, "
                         f"got shape {tips.shape}")
    segs = [line_segment(tips[k], tips[k + 1]) for k in range(tips.shape[0] - 1)]
    return _planned(segs, tips, model, times, options)


def plan_directions(azimuth: ArrayLike, polar: ArrayLike, depth: ArrayLike,
                    robot: Robot | ArrayLike, design: Design | None = None, *,
                    times: ArrayLike | None = None,
                    bodies: object = None, environment: object = None, masses: object = None,
                    options: PlanOptions | None = None) -> Trajectory:
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
    robot : athenakin.Robot or array-like, shape (4, 4)
        The robot, or its RCM frame ``T_b_e`` (m), as for :func:`plan`.
    design : Design, optional
        With ``T_b_e`` only, as for :func:`plan`.
    times, bodies, environment, masses, options : keyword-only
        As :func:`plan`.

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
    model = resolve_robot(robot, design, bodies=bodies, environment=environment,
                          masses=masses)
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
    return _planned(segs, tips, model, times, options)


def _planned(segs: list[Segment], tips: FloatArray, robot: Robot, times: ArrayLike | None,
             options: PlanOptions | None) -> Trajectory:
    """:func:`_plan` with the options' limits, and with the forces when the Robot has masses."""
    o = plan_options(options)

    def run(**limits: object) -> Trajectory:
        return _plan(segs, tips, robot.T_b_e, robot.design, rate=o.rate, times=times,
                     timing=o.timing, margins=o.margins, max_duration=o.max_duration,
                     max_samples=o.max_samples, bodies=robot.bodies,
                     environment=robot.environment, clearance_margin=o.clearance_margin,
                     backend=o.backend, **limits)  # type: ignore[arg-type]

    return planned(run, v_max=o.v_max, a_max=o.a_max, j_max=o.j_max,  # type: ignore[return-value]
                   tip_speed=o.tip_speed, masses=robot.masses, f_max=o.f_max,
                   fixed_times=o.timing == "fixed", backend=o.backend)


def _plan(segs: list[Segment], tips: FloatArray, T_b_e: ArrayLike, design: Design, *,
          rate: float, v_max: ArrayLike, a_max: ArrayLike, j_max: ArrayLike | None,
          tip_speed: float | None, times: ArrayLike | None, timing: Timing, margins: Margins,
          max_duration: float, max_samples: int, bodies: object, environment: object,
          clearance_margin: float | None, backend: str = "auto") -> Trajectory:
    """Plan the segments with checked settings (those of a :class:`PlanOptions`)."""
    T = check_frame(T_b_e, "T_b_e")
    limits = Limits.build(v_max, a_max, j_max, tip_speed)
    check = clearance_check(design, bodies, environment, clearance_margin, backend=backend)
    K = tips.shape[0]
    if K > MAX_WAYPOINTS:
        raise ValueError(f"waypoints: expected at most {MAX_WAYPOINTS}, got {K} (plan the path "
                         f"in parts)")
    req, t0 = _requested(times, K, timing, rate, max_duration, max_samples)

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
        samples, bad = _sample_checked(plans, T, design, rate, t0, limits, margins, check,
                                       backend=backend)
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


def _requested(times: ArrayLike | None, K: int, timing: str, rate: float, max_duration: float,
               max_samples: int) -> tuple[FloatArray | None, float]:
    """The requested duration of each segment (None: as fast as the limits allow), the start."""
    req: FloatArray | None = None
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
    return req, t0


def _sample_checked(plans: list[_SegmentPlan], T: FloatArray, design: Design,
                    rate: float, t0: float, limits: Limits, margins: Margins,
                    check: ClearanceCheck | None = None, *, backend: str = "auto"
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
        bad = check_samples(c, T, design, limits, margins, mode0=mode0, backend=backend)
        if check is not None:
            bad = _check_clearance(c, bad, check, T, design)
        chunks.append(c)
        if bad is not None:
            bad["index"] += i0
            break
    return _concat(chunks), bad


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


def _sample(plans: list[_SegmentPlan], T: FloatArray, design: Design, rate: float,
            t0: float, limits: Limits, index: IntArray) -> dict[str, Any]:
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


def _trajectory(samples: dict, plans: list[_SegmentPlan], tips: FloatArray,  # type: ignore[type-arg]
                limits: Limits, margins: Margins, T: FloatArray, design: Design,
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
