"""Errors of the motion subpackage: unsafe trajectories, infeasible timing, bad path files."""

from __future__ import annotations

from ..errors import InvalidInputError, KinematicsError

__all__ = [
    "MotionError",
    "SafetyViolationError",
    "TimingInfeasibleError",
    "PathInfeasibleError",
    "TrajectoryLimitError",
    "PathFileError",
    "TrackingError",
    "CollisionError",
]


class MotionError(KinematicsError):
    """Base class of the errors raised by :mod:`athenakin.motion`."""


class SafetyViolationError(MotionError):
    """A sample of a planned trajectory violates a limit; no trajectory is returned.

    Attributes
    ----------
    time : float
        Time of the first violating sample, s.
    index : int
        Its index in the sampled trajectory (``traj.t[index] == time``).
    limit : str
        Which limit: ``"workspace"``, ``"stroke"``, ``"velocity"``, ``"acceleration"``,
        ``"jerk"``, ``"tip_speed"`` or the name of a singularity margin
        (``"half_chord"``, ``"h"``, ``"link"``, ``"sin_u2"``, ``"sin_u4"``, ``"p"``,
        ``"depth"``, ``"cond"``; see :class:`~athenakin.motion.Margins`).
    value : float
        The offending value (SI units; dimensionless for sines and condition numbers).
    bound : float
        The limit it crosses.
    actuator : int or None
        0, 1, 2 for ``q1, q2, q3`` when the limit is per actuator, else None.
    """

    def __init__(self, message: str, *, time: float, index: int, limit: str, value: float,
                 bound: float, actuator: int | None = None) -> None:
        super().__init__(message)
        self.time = time
        self.index = index
        self.limit = limit
        self.value = value
        self.bound = bound
        self.actuator = actuator


class CollisionError(SafetyViolationError):
    """A sample of a planned trajectory brings two bodies (or a body and an obstacle) too close.

    Raised by :func:`~athenakin.motion.plan` when collisions are checked
    (``bodies=``, ``environment=`` or ``clearance_margin=``). Besides the attributes
    of :class:`SafetyViolationError` (``limit`` is ``"clearance"``, ``value`` the
    signed clearance in m, negative for a penetration, ``bound`` the margin in m),
    it carries ``pair``: the names of the two bodies, or of the body and the
    obstacle (:mod:`athenakin.collision`).
    """

    def __init__(self, message: str, *, time: float, index: int, value: float, bound: float,
                 pair: tuple[str, str]) -> None:
        super().__init__(message, time=time, index=index, limit="clearance", value=value,
                         bound=bound)
        self.pair = pair


class TimingInfeasibleError(SafetyViolationError):
    """Fixed waypoint times ask for more than the limits allow (``timing="fixed"``).

    Besides the attributes of :class:`SafetyViolationError` (the first sample of
    the trajectory squeezed into the requested times that breaks a limit), it
    carries ``segment`` (index ``k`` of the segment from waypoint ``k`` to
    ``k + 1``), ``required`` (the shortest duration the planner found within the
    limits, s) and ``requested`` (the duration the waypoint times give, s).
    """

    def __init__(self, message: str, *, segment: int, required: float, requested: float,
                 **kw: object) -> None:
        super().__init__(message, **kw)  # type: ignore[arg-type]
        self.segment = segment
        self.required = required
        self.requested = requested


class PathInfeasibleError(SafetyViolationError):
    """The path itself breaks a limit, found before any timing or sampling.

    A waypoint, or a point of a segment, is outside the workspace or the stroke
    limits, or the path changes the assembly mode. Besides the attributes of
    :class:`SafetyViolationError` (``time`` is NaN and ``index`` -1: no sample
    exists yet), it carries ``waypoint`` (index ``k`` of the offending waypoint,
    or None) and ``segment`` (index ``k`` of the segment from waypoint ``k`` to
    ``k + 1``, or None).
    """

    def __init__(self, message: str, *, waypoint: int | None = None,
                 segment: int | None = None, **kw: object) -> None:
        kw.setdefault("time", float("nan"))
        kw.setdefault("index", -1)
        super().__init__(message, **kw)  # type: ignore[arg-type]
        self.waypoint = waypoint
        self.segment = segment


class TrajectoryLimitError(MotionError):
    """The trajectory would break a resource limit, or its time law cannot be computed.

    Raised before the trajectory is sampled, so within about a second and in
    bounded memory.

    Attributes
    ----------
    limit : str
        ``"max_duration"`` (s), ``"max_samples"`` or ``"time_law"`` (the time-optimal
        profile of a segment could not be computed within its limits).
    value : float
        The duration (s) or sample count the trajectory would need (NaN for
        ``"time_law"``).
    bound : float
        The limit it exceeds.
    segment : int or None
        The segment responsible (``k``: from waypoint ``k`` to ``k + 1``), if one is.
    """

    def __init__(self, message: str, *, limit: str, value: float, bound: float,
                 segment: int | None = None) -> None:
        super().__init__(message)
        self.limit = limit
        self.value = value
        self.bound = bound
        self.segment = segment


class PathFileError(MotionError, InvalidInputError):
    """A path or stream file cannot be read: missing columns, non-numbers, too few rows.

    The message names the file, the line and the column.
    """


class TrackingError(MotionError):
    """Raised by a :class:`~athenakin.motion.Tracker` in ``strict`` mode on a flagged sample.

    Attributes
    ----------
    pose : TrackedPose
        The pose of the offending sample, with its flags.
    """

    def __init__(self, message: str, pose: object) -> None:
        super().__init__(message)
        self.pose = pose
