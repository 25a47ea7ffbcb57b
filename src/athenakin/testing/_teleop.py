"""The teleoperation invariants as oracles a lab can run on its own sessions (private).

:func:`teleop_violations` counts the cycles of a session that break each safety claim of
:mod:`athenakin.teleop`, with checks that share no code with the core's limiter: the
strokes and the carriages' order of the design, the velocity and acceleration limits
and the backward differences of the commands, the reference forward kinematics of the
commanded tip, coal's signed distance of the tip to every fixture (halfspace, sphere,
capsule, box), and the capsule distances (:func:`athenakin.collision.capsule_capsule`,
coal for the obstacles) of the bodies rebuilt from the forward kinematics
(:func:`athenakin._mechanism.mechanism_points`), over every pair the bodies do not
exclude. :func:`assert_teleop_commands` raises on the first kind found.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray, IntArray
from .._validation import check_scalar
from ..errors import InvalidInputError

__all__ = ["TeleopViolations", "teleop_violations", "assert_teleop_commands", "STROKE_TOL",
           "LIMIT_RTOL", "DIFF_ATOL", "TIP_TOL", "DISTANCE_TOL", "CHECKS"]

#: How far a command may lie beyond a stroke limit (rounding), m.
STROKE_TOL = 1e-12
#: Relative slack on the velocity and acceleration limits (the core aims 1e-6 below).
LIMIT_RTOL = 1e-9
#: Largest difference between a command's velocity (acceleration) and the backward
#: difference of its positions (velocities), relative to the limit.
DIFF_ATOL = 1e-6
#: Largest distance between the commanded tip and the reference FK of its ``q``, m.
TIP_TOL = 1e-9
#: Slack on the fixture and clearance margins (the closed forms' rounding), m.
DISTANCE_TOL = 1e-9
#: The invariants, in the order :class:`TeleopViolations` reports them.
CHECKS = ("nonfinite", "stroke", "order", "velocity", "acceleration", "differences", "tip",
          "fixture", "clearance")


@dataclasses.dataclass(frozen=True)
class TeleopViolations:
    """The cycles of a session that break each invariant.

    Attributes
    ----------
    cycles : int
        Cycles checked.
    counts : mapping of str -> int
        Cycles breaking each check of :data:`CHECKS`.
    first : mapping of str -> int
        Index of the first cycle breaking each check (-1: none).
    worst : mapping of str -> float
        The worst value of each check: the excess over a limit (m, m/s, m/s^2) or the
        depth below a margin (m); 0 where none.
    least_clearance : float
        The least clearance the oracle found between two bodies or a body and an
        obstacle, m (NaN: not checked).
    least_fixture_distance : float
        The least signed distance of the tip to a fixture, m (NaN: no fixture).
    """

    cycles: int
    counts: Mapping[str, int]
    first: Mapping[str, int]
    worst: Mapping[str, float]
    least_clearance: float
    least_fixture_distance: float

    @property
    def total(self) -> int:
        """Cycles-and-checks broken, summed over the checks."""
        return int(sum(self.counts.values()))

    def summary(self) -> str:
        """One line per broken check: count, first cycle, worst value.

        Returns
        -------
        str
            ``""`` when nothing is broken.
        """
        return "\n".join(f"{k}: {self.counts[k]} cycle(s), first at {self.first[k]}, worst "
                         f"{self.worst[k]:.3g}" for k in CHECKS if self.counts[k])


def _columns(commands: Any) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, IntArray]:
    """``q, qd, qdd, tip`` (N, 3) and ``slot`` (N,) of a SessionLog or of commands."""
    if all(hasattr(commands, k) for k in ("q", "qd", "qdd", "tip", "slot")) and \
            isinstance(commands.q, np.ndarray):
        cols = [np.asarray(getattr(commands, k), dtype=float) for k in ("q", "qd", "qdd",
                                                                         "tip")]
        slot = np.asarray(commands.slot, dtype=np.int64)
    else:
        if isinstance(commands, (str, bytes)) or not isinstance(commands, Sequence):
            commands = list(commands)
        try:
            cols = [np.array([getattr(c, k) for c in commands], dtype=float).reshape(-1, 3)
                    for k in ("q", "qd", "qdd", "tip")]
            slot = np.array([int(c.slot) for c in commands], dtype=np.int64)
        except (AttributeError, TypeError, ValueError):
            raise TypeError("commands: expected a SessionLog or a sequence of TeleopCommand "
                            "(q, qd, qdd, tip, slot)") from None
    n = len(slot)
    for name, c in zip(("q", "qd", "qdd", "tip"), cols, strict=True):
        if c.shape != (n, 3):
            raise InvalidInputError(f"commands: {name} of shape {c.shape}, expected ({n}, 3)")
    return cols[0], cols[1], cols[2], cols[3], slot


def _limit(x: float | ArrayLike, name: str) -> FloatArray:
    a = np.broadcast_to(np.asarray(x, dtype=float), (3,)).copy()
    if not np.all(np.isfinite(a) & (a > 0)):
        raise InvalidInputError(f"{name}: expected positive finite limits, got {a.tolist()}")
    return a


def teleop_violations(commands: Any, robot: Any, *, rate: float,
                      v_max: float | ArrayLike = 0.1, a_max: float | ArrayLike = 2.0,
                      bodies: Any = None, environment: Any = None,
                      clearance_margin: float = 0.0, fixture_margin: float = 0.0
                      ) -> TeleopViolations:
    """Count the cycles of a teleoperation session that break each safety invariant.

    Parameters
    ----------
    commands : SessionLog or sequence of TeleopCommand
        The session's commands, in cycle order (``q``, ``qd``, ``qdd`` in m, m/s,
        m/s^2; ``tip`` in the RCM frame E, m; ``slot``).
    robot : athenakin.Robot
        The design, the RCM frame, and the default bodies and environment.
    rate : float, keyword-only
        The cycle rate, Hz (the backward differences).
    v_max, a_max : float or array-like, shape (3,), keyword-only
        The actuator limits, m/s and m/s^2 (the core's defaults 0.1 and 2.0).
    bodies : athenakin.collision.Bodies or False, optional, keyword-only
        The robot's capsules, kept ``clearance_margin`` apart and from the obstacles;
        default the robot's, else :meth:`Bodies.default`; False: no clearance check.
    environment : athenakin.collision.Environment, optional, keyword-only
        Default the robot's. Its halfspaces, spheres, capsules and boxes are fixtures for
        the tip (unless they allow the ``instrument``); every obstacle but a mesh is kept
        ``clearance_margin`` from each body it does not allow.
    clearance_margin, fixture_margin : float, keyword-only
        Least clearance (m) and least distance of the tip to a fixture (m) to hold.

    Returns
    -------
    TeleopViolations

    Raises
    ------
    TypeError, InvalidInputError
        A bad argument (named).
    ImportError
        coal is not installed and there are fixtures or obstacles (extra ``collision``).
    """
    from .._robot_model import Robot

    if not isinstance(robot, Robot):
        raise TypeError(f"robot: expected an athenakin.Robot, got {type(robot).__name__}")
    q, qd, qdd, tip, slot = _columns(commands)
    rate = check_scalar(rate, "rate", positive=True)
    vmax, amax = _limit(v_max, "v_max"), _limit(a_max, "a_max")
    cm = check_scalar(clearance_margin, "clearance_margin", nonnegative=True)
    fm = check_scalar(fixture_margin, "fixture_margin", nonnegative=True)
    design, T = robot.design, np.asarray(robot.T_b_e, dtype=float)
    env = robot.environment if environment is None else environment
    if bodies is None:
        from ..collision import Bodies

        bodies = robot.bodies if robot.bodies is not None else Bodies.default(design)
    n = len(slot)
    bad: dict[str, FloatArray] = {}          # per check: the excess per cycle (> 0: broken)
    finite = np.all(np.isfinite(np.concatenate([q, qd, qdd, tip], axis=1)), axis=1)
    bad["nonfinite"] = np.where(finite, 0.0, np.inf)
    lo, hi = np.asarray(design.stroke_min, float), np.asarray(design.stroke_max, float)
    with np.errstate(invalid="ignore"):
        bad["stroke"] = np.nan_to_num(np.max(np.maximum(lo - q, q - hi), axis=1) - STROKE_TOL,
                                      nan=0.0)
        bad["order"] = np.nan_to_num(-design.h_sign * (q[:, 0] - q[:, 1]), nan=0.0)
        bad["velocity"] = np.nan_to_num(np.max(np.abs(qd) - vmax * (1 + LIMIT_RTOL), axis=1),
                                        nan=0.0)
        bad["acceleration"] = np.nan_to_num(np.max(np.abs(qdd) - amax * (1 + LIMIT_RTOL),
                                                   axis=1), nan=0.0)
        diff = np.zeros(n)
        if n > 1:
            ev = np.abs(qd[1:] - (q[1:] - q[:-1]) * rate) / vmax
            ea = np.abs(qdd[1:] - (qd[1:] - qd[:-1]) * rate) / amax
            diff[1:] = np.nan_to_num(np.maximum(ev.max(axis=1), ea.max(axis=1)) - DIFF_ATOL,
                                     nan=0.0)
        bad["differences"] = diff
    bad["tip"], tip_b = _tip_check(q, tip, slot, T, design, finite)
    fixture, least_fix = _fixture_check(tip_b, env, fm)
    bad["fixture"] = fixture
    if bodies is False:
        clear, least_cl = np.zeros(n), math.nan
    else:
        clear, least_cl = _clearance_check(q, slot, T, design, bodies, env, cm, finite)
    bad["clearance"] = clear
    counts = {k: int(np.count_nonzero(bad[k] > 0)) for k in CHECKS}
    first = {k: int(np.argmax(bad[k] > 0)) if counts[k] else -1 for k in CHECKS}
    worst = {k: float(np.max(bad[k])) if counts[k] else 0.0 for k in CHECKS}
    return TeleopViolations(n, counts, first, worst, least_cl, least_fix)


def assert_teleop_commands(commands: Any, robot: Any, *, rate: float,
                           v_max: float | ArrayLike = 0.1, a_max: float | ArrayLike = 2.0,
                           bodies: Any = None, environment: Any = None,
                           clearance_margin: float = 0.0, fixture_margin: float = 0.0
                           ) -> TeleopViolations:
    """Assert that a teleoperation session keeps every safety invariant.

    Parameters
    ----------
    commands, robot, rate, v_max, a_max, bodies, environment, clearance_margin, fixture_margin
        As for :func:`teleop_violations`.

    Returns
    -------
    TeleopViolations
        All zero (for the record: the least clearance and fixture distance found).

    Raises
    ------
    AssertionError
        A check is broken: the message lists each broken check, its count, first cycle
        and worst value.
    """
    v = teleop_violations(commands, robot, rate=rate, v_max=v_max, a_max=a_max,
                          bodies=bodies, environment=environment,
                          clearance_margin=clearance_margin, fixture_margin=fixture_margin)
    if v.total:
        raise AssertionError(f"teleoperation invariants broken in {v.cycles} cycles:\n"
                             f"{v.summary()}")
    return v


# --- the oracles ------------------------------------------------------------------------------
def _tip_check(q: FloatArray, tip: FloatArray, slot: IntArray, T: FloatArray, design: Any,
               finite: Any) -> tuple[FloatArray, FloatArray]:
    """Distance of the tip from the reference FK of ``q`` beyond TIP_TOL, and the tip (base)."""
    from .._dispatch import forward_kinematics

    n = len(slot)
    err = np.zeros(n)
    tip_b = tip @ T[:3, :3].T + T[:3, 3]
    idx = np.flatnonzero(finite)
    if idx.size:
        sol = forward_kinematics(q[idx], T, design, errors="flag", backend="numpy")
        ref = np.asarray(sol.tip)[np.arange(idx.size), slot[idx]]     # base frame
        d = np.linalg.norm(ref - tip_b[idx], axis=1)
        err[idx] = np.where(np.isfinite(d), d - TIP_TOL, np.inf)
    return err, tip_b


def _coal_shape(o: Any) -> tuple[Any, Any] | None:
    """The coal geometry and pose of a primitive obstacle (None for a mesh)."""
    import coal

    eye = np.eye(3)
    if o.kind == "halfspace":
        n = np.asarray(o.normal, float)
        return coal.Halfspace(n, float(n @ np.asarray(o.point, float))), \
            coal.Transform3s(eye, np.zeros(3))
    if o.kind == "sphere":
        return coal.Sphere(float(o.radius)), coal.Transform3s(eye, np.asarray(o.center, float))
    if o.kind == "capsule":
        a, b = np.asarray(o.a, float), np.asarray(o.b, float)
        L, pose = _capsule_pose(a, b)
        return (coal.Capsule(float(o.radius), L) if L > 0 else coal.Sphere(float(o.radius))), pose
    if o.kind == "box":
        return coal.Box(*(2.0 * np.asarray(o.half_extents, float))), \
            coal.Transform3s(np.ascontiguousarray(o.T_b_o[:3, :3]),
                             np.ascontiguousarray(o.T_b_o[:3, 3]))
    return None


def _capsule_pose(a: FloatArray, b: FloatArray) -> tuple[float, Any]:
    """Length and coal pose (axis z, centred) of the segment a-b."""
    import coal

    d = b - a
    L = float(np.linalg.norm(d))
    z = d / L if L > 0 else np.array([0.0, 0.0, 1.0])
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    R = np.stack([x, np.cross(z, x), z], axis=1)
    return L, coal.Transform3s(np.ascontiguousarray(R), np.ascontiguousarray(0.5 * (a + b)))


def _coal_distance(s1: Any, t1: Any, s2: Any, t2: Any) -> float:
    import coal

    req = coal.DistanceRequest()
    req.enable_signed_distance = True
    return float(coal.distance(s1, t1, s2, t2, req, coal.DistanceResult()))


def _fixture_check(tip_b: FloatArray, env: Any, margin: float) -> tuple[FloatArray, float]:
    """Depth of the tip below ``margin`` from each fixture (coal), and the least distance."""
    n = len(tip_b)
    out = np.zeros(n)
    shapes = [] if env is None else [
        s for o in env.obstacles if "instrument" not in o.allow and o.kind != "mesh"
        for s in [_coal_shape(o)] if s is not None]
    if not shapes:
        return out, math.nan
    import coal

    point = coal.Sphere(0.0)
    least = math.inf
    eye = np.eye(3)
    for i in range(n):
        p = tip_b[i]
        if not np.all(np.isfinite(p)):
            continue
        tp = coal.Transform3s(eye, np.ascontiguousarray(p))
        d = min(_coal_distance(point, tp, s, t) for s, t in shapes)
        least = min(least, d)
        out[i] = margin - DISTANCE_TOL - d
    return out, least


def _clearance_check(q: FloatArray, slot: IntArray, T: FloatArray, design: Any, bodies: Any,
                     env: Any, margin: float, finite: Any) -> tuple[FloatArray, float]:
    """Depth below ``margin`` of the closest pair of bodies (or body and obstacle)."""
    from .._mechanism import BODIES, body_segments, mechanism_points
    from ..collision import Bodies, capsule_capsule

    if not isinstance(bodies, Bodies):
        raise TypeError(f"bodies: expected athenakin.collision.Bodies or False, got "
                        f"{type(bodies).__name__}")
    n = len(slot)
    out = np.zeros(n)
    seg = np.full((n, len(BODIES), 2, 3), np.nan)
    for k in np.unique(slot[finite]):
        rows = np.flatnonzero(finite & (slot == k))
        pts = mechanism_points(q[rows], T, design, slot=int(k), geometry=bodies.geometry)
        seg[rows] = body_segments(pts)
    radius = np.asarray(bodies.radii, float)
    skip = {frozenset(p) for p in bodies.excluded_pairs}
    least = np.full(n, np.inf)
    for i, j in itertools.combinations(range(len(BODIES)), 2):
        if frozenset((BODIES[i], BODIES[j])) in skip:
            continue
        a, b = seg[:, i], seg[:, j]
        ok = np.all(np.isfinite(a), axis=(1, 2)) & np.all(np.isfinite(b), axis=(1, 2))
        if not ok.any():
            continue
        d, _ = capsule_capsule(a[ok, 0], a[ok, 1], radius[i], b[ok, 0], b[ok, 1], radius[j])
        least[ok] = np.minimum(least[ok], d)
    for o in () if env is None else env.obstacles:
        shape = _coal_shape(o)
        if shape is None:
            continue
        s, t = shape
        import coal

        for bi, name in enumerate(BODIES):
            if name in o.allow:
                continue
            for r in np.flatnonzero(np.all(np.isfinite(seg[:, bi]), axis=(1, 2))):
                L, pose = _capsule_pose(seg[r, bi, 0], seg[r, bi, 1])
                cap = coal.Capsule(radius[bi], L) if L > 0 else coal.Sphere(radius[bi])
                least[r] = min(least[r], _coal_distance(cap, pose, s, t))
    good = np.isfinite(least)
    out[good] = margin - DISTANCE_TOL - least[good]
    return out, float(np.min(least[good])) if good.any() else math.nan
