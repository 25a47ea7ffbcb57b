"""Streaming forward kinematics with continuity: encoder readings -> instrument pose.

The robot's forward kinematics has up to 16 solutions (2 assembly modes x 2
signs of ``p`` x 2 U-joint branches x 2 spherical-joint branches). A
:class:`Tracker` follows one of them through a stream of actuator readings: at
each sample it returns the solution continuous with the previous pose, and it
says so, with :class:`TrackFlag` bits, whenever continuity is in doubt instead
of switching silently.

Continuity. The distance of a candidate to the previous pose is
``step = max(|dO_s| / jump_m, max_i |wrap(du_i)| / jump_rad)`` (``O_s`` the origin
of the serial chain, ``u1..u5`` the passive angles); ``step <= 1`` is "within the
jump thresholds". The candidate with the previous labels (mode, sign of ``p``,
branches) is kept while it is within the thresholds; otherwise the nearest
candidate is taken and the label change is flagged.

A pure step. :meth:`Tracker.candidate` returns the pose that :meth:`Tracker.update`
would return without changing the tracker; :meth:`Tracker.commit` takes it
(``update = commit(candidate)``, then ``raise_on``): a controller tries candidates and
commits the one it commands, with no probe to revert.

Cost. Away from the singularities only the candidate with the previous labels is
computed, in closed form with scalar arithmetic (no numpy in the loop): a few
microseconds per sample. Near a singularity (any measure below its margin), after
a large step, or when that candidate is not valid, all 16 are computed.
:func:`~athenakin.motion.track` (a recorded stream, :mod:`athenakin.motion._stream`)
runs the same algorithm compiled, reading after reading in one loop
(:mod:`athenakin.motion._kernels`, :func:`~athenakin.motion._stream.track_batch`): the
same poses and steps to 1e-12 and the same flags, about a microsecond per reading.

Collisions. Asked for with ``bodies=``, ``environment=`` or ``clearance_margin=``
(:mod:`athenakin.collision`, imported then), every valid sample also gets the least
clearance between the robot's bodies and to the obstacles, the pair that has it, and
the flags ``COLLISION`` (clearance < 0: overlap) and ``NEAR_COLLISION`` (clearance
below the margin, collisions included). The check is off by default.
:meth:`Tracker.update` places the bodies from the tracked pose in scalar arithmetic
and calls the compiled capsule kernel once (tens of microseconds per sample, several
times the tracker's own work; about a millisecond with obstacles);
:func:`~athenakin.motion.track` checks a recorded stream in one batch of
:func:`athenakin.collision.clearance`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from .._robot_model import Robot, resolve_robot
from .._validation import check_array, check_scalar, check_slot
from ..design import Design
from ..errors import InvalidInputError
from ..robot import forward_kinematics
from ._candidates import (
    _B,
    _FLAG_NONE,
    TrackedPose,
    TrackLog,
    _adiff,
    _candidate,
    _clearance_text,
    _Geometry,
    _parallel,
)
from ._clearance import PoseClearance, clearance_check
from ._errors import TrackingError
from ._flags import TrackFlag
from ._safety import Margins

__all__ = ["TrackFlag", "TrackedPose", "Tracker", "TrackLog", "JUMP_M", "JUMP_RAD"]

#: Default jump threshold on ``O_s`` between consecutive samples, m.
JUMP_M = 0.005
#: Default jump threshold on the passive angles between consecutive samples, rad.
JUMP_RAD = 0.1


_ALL_FLAGS = TrackFlag(sum(int(f) for f in TrackFlag))


def _track_flag(x: object, name: str) -> TrackFlag:
    """A :class:`TrackFlag` from a flag, its int, or names (``"LOST"``, ``"LOST|JUMP"``)."""
    if isinstance(x, TrackFlag):
        return x
    if isinstance(x, str):
        out = TrackFlag.NONE
        for part in x.split("|"):
            key = part.strip().upper()
            if key not in TrackFlag.__members__:
                raise InvalidInputError(f"{name}: expected TrackFlag names such as 'LOST' or "
                                        f"'LOST|JUMP', got {x!r} ({part.strip()!r} is not one "
                                        f"of {list(TrackFlag.__members__)})")
            out |= TrackFlag[key]
        return out
    if isinstance(x, (int, np.integer)) and not isinstance(x, bool):
        if not 0 <= int(x) <= int(_ALL_FLAGS):
            raise InvalidInputError(f"{name}: expected TrackFlag bits within "
                                    f"0..{int(_ALL_FLAGS)}, got {int(x)}")
        return TrackFlag(int(x))
    raise TypeError(f"{name}: expected a TrackFlag (or its name), got {type(x).__name__}")


def _slot(mode: int, r: int, b: int, w: int) -> int:
    return 8 * (mode == -1) + 4 * (r == -1) + 2 * (b == -1) + (w == -1)


class Tracker:
    """Follow the robot's configuration through a stream of actuator readings.

    Parameters
    ----------
    robot : athenakin.Robot or array-like, shape (4, 4)
        The model (its design, RCM frame, and the bodies and obstacles checked), or its
        RCM frame E in the base frame ``T_b_e`` (m); then ``design``, ``bodies`` and
        ``environment`` build the Robot (:func:`athenakin._robot_model.resolve_robot`).
        Everything that depends on the model alone (the geometry of the scalar fast
        path, the clearance pair tables) is built here, once.
    design : Design, optional
        With ``T_b_e`` only; default :meth:`Design.default`.
    q0 : array-like, shape (3,), keyword-only
        The first reading (m), whose configuration must be known.
    slot : int, optional, keyword-only
        Forward-kinematics slot of ``q0`` (``8 m + 4 r + 2 b + w``, see
        :func:`athenakin.robot.slot_index`). Default: the valid slot with labels
        closest to (mode +1, p > 0, sin u2 > 0, sin u4 > 0), in that priority.
    jump_m, jump_rad : float, keyword-only
        Jump thresholds on ``O_s`` (m) and on the passive angles (rad) between
        consecutive samples; see the module docstring.
    margins : Margins, optional, keyword-only
        Below these distances to the singularities samples get ``NEAR_*`` flags
        and all 16 solutions are examined (only ``half_chord``, ``h``, ``link``,
        ``sin_u2``, ``sin_u4`` and ``p`` are used).
    raise_on : TrackFlag, keyword-only
        Flags that make :meth:`update` raise :class:`TrackingError` (default none).
    bodies : athenakin.collision.Bodies, optional, keyword-only
        Check the clearance of these bodies at every valid sample (flags
        ``COLLISION``, ``NEAR_COLLISION``; fields ``clearance``, ``closest_pair``).
        Default the Robot's; with none, no check unless ``environment`` or
        ``clearance_margin`` is given, then :meth:`Bodies.default(design)
        <athenakin.collision.Bodies.default>`. Beside a Robot only if it has none.
    environment : athenakin.collision.Environment, optional, keyword-only
        Obstacles checked against the bodies (turns the check on); default the
        Robot's. Beside a Robot only if it has none.
    clearance_margin : float, optional, keyword-only
        Clearance (m) below which a sample is ``NEAR_COLLISION`` (turns the check on);
        default 5 mm when the check is on.
    backend : {"auto", "numpy", "numba"}, keyword-only
        The compiled stream of :func:`~athenakin.motion._stream.track_batch` and the
        clearance check on the numba kernels or the numpy reference
        (:mod:`athenakin._backend`); the same poses and flags.

    Raises
    ------
    KinematicsError
        ``q0`` has no valid configuration, or ``slot`` is not valid for it.
    TypeError, InvalidInputError
        A malformed option (named); ``robot`` neither a Robot nor a frame, a design or
        a part (``bodies``, ``environment``) beside a Robot that has its own;
        ``bodies`` or ``environment`` of the wrong type, a negative or NaN
        ``clearance_margin``.

    Examples
    --------
    >>> import athenakin as ak
    >>> robot = ak.Robot.default()
    >>> tr = ak.motion.Tracker(robot, q0=[-0.10, 0.10, 0.45])
    >>> pose = tr.update([-0.1001, 0.1001, 0.4499])
    >>> pose.mode, pose.flags == ak.motion.TrackFlag.NONE
    (1, True)

    The functional form builds the same Robot:

    >>> same = ak.motion.Tracker(robot.T_b_e, robot.design, q0=[-0.10, 0.10, 0.45])
    >>> same.update([-0.1001, 0.1001, 0.4499]) == pose
    True
    """

    def __init__(self, robot: Robot | ArrayLike, design: Design | None = None, *,
                 q0: ArrayLike, slot: int | None = None, jump_m: float = JUMP_M,
                 jump_rad: float = JUMP_RAD, margins: Margins | None = None,
                 raise_on: TrackFlag = TrackFlag.NONE, bodies: object = None,
                 environment: object = None, clearance_margin: float | None = None,
                 backend: str = "auto") -> None:
        from .._backend import resolve_backend

        #: The model (:class:`athenakin.Robot`); read here only.
        self.robot = resolve_robot(robot, design, bodies=bodies, environment=environment)
        T, design = self.robot.T_b_e, self.robot.design
        margins = Margins() if margins is None else margins
        if not isinstance(margins, Margins):
            raise TypeError(f"margins: expected athenakin.motion.Margins, got "
                            f"{type(margins).__name__}")
        self.T_b_e = T                   # the Robot's read-only copy
        self.design = design
        self.jump_m = check_scalar(jump_m, "jump_m", positive=True)
        self.jump_rad = check_scalar(jump_rad, "jump_rad", positive=True)
        self.margins = margins
        self.raise_on = _track_flag(raise_on, "raise_on")
        self._raise_bits = int(self.raise_on)
        self._g = _Geometry(T, design)
        self.backend = "numba" if resolve_backend(backend) else "numpy"
        self._check = clearance_check(design, self.robot.bodies, self.robot.environment,
                                      clearance_margin, backend=self.backend)
        self._pose_clearance = (None if self._check is None else PoseClearance(
            design, T, self._check.bodies, self._check.environment, backend=self.backend))
        # fast-path thresholds: a candidate far from every singularity, and far enough
        # from the mode boundary that the other mode cannot be within the jump threshold
        self._watch = (max(margins.half_chord, self.jump_m), margins.h, margins.link,
                       margins.sin_u2, margins.sin_u4, margins.p)
        self.reset(q0, slot=slot)

    # ------------------------------------------------------------------------------
    def reset(self, q0: ArrayLike, *, slot: int | None = None) -> TrackedPose:
        """Restart the stream at a known configuration (see the class parameters).

        Parameters
        ----------
        q0 : array-like, shape (3,)
            Actuators, m, at which the stream restarts.
        slot : int, optional, keyword-only
            FK solution slot 0-15 to track (default: the first assembled slot in the
            order mode +1, p > 0, U-joint +1, wrist +1).

        Returns
        -------
        TrackedPose
            The tracked pose at ``q0``.

        Raises
        ------
        InvalidInputError
            ``q0`` is not a finite (3,) vector, or ``slot`` is not assembled there.
        KinematicsError
            The forward kinematics at ``q0`` fails (``errors="raise"``).
        """
        q = check_array(q0, "q0", (3,))
        if q.shape != (3,):
            raise InvalidInputError(f"q0: expected shape (3,), got {q.shape}")
        sol = forward_kinematics(q, self.T_b_e, self.design, errors="raise")
        if slot is None:
            order = sorted(range(16), key=lambda k: (sol.mode[k] != 1, sol.p_sign[k] != 1,
                                                     sol.ujoint[k] != 1, sol.wrist[k] != 1))
            slot = next(k for k in order if sol.valid[k])
        elif not sol.valid[check_slot(slot)]:
            raise InvalidInputError(f"slot: slot {slot} is not a valid solution for q0 = "
                                    f"{q.tolist()} (valid slots: "
                                    f"{np.flatnonzero(sol.valid).tolist()})")
        labels = (int(sol.mode[slot]), int(sol.p_sign[slot]), int(sol.ujoint[slot]),
                  int(sol.wrist[slot]))
        q1, q2, q3 = (float(v) for v in q)
        par = _parallel(self._g, q1, q2, q3)
        cand = None if par is None else _candidate(self._g, par, *labels, None)
        if cand is None:  # pragma: no cover - the core FK said it is valid
            raise InvalidInputError(f"q0 = {q.tolist()}: slot {slot} is degenerate")
        self._index = 0
        self._prev = cand
        self._lost = False
        self.pose = self._pose((q1, q2, q3), cand, 0.0, self._near(cand))
        if self._check is not None:
            self.pose = self._collide(self.pose)
        return self.pose

    @property
    def clearance_margin(self) -> float | None:
        """The clearance margin (m), None when collisions are not checked."""
        return None if self._check is None else self._check.margin

    def _collide(self, pose: TrackedPose) -> TrackedPose:
        """``pose`` with its clearance, closest pair and collision flags."""
        check = self._check
        assert check is not None
        assert self._pose_clearance is not None       # the points from the pose, one call
        d, names = self._pose_clearance(pose.q, pose.p, pose.u, pose.O_s)
        pair = np.array([names])
        flags = int(pose.flags)
        if d < check.margin:              # False for NaN (no valid slot: nothing to check)
            flags |= _B["NEAR_COLLISION"]
            if d < 0.0:
                flags |= _B["COLLISION"]
        return pose._replace(clearance=d, closest_pair=(str(pair[0, 0]), str(pair[0, 1])),
                             flags=TrackFlag(flags) if flags else _FLAG_NONE)

    def _finish(self, pose: TrackedPose) -> TrackedPose:
        """``pose`` with its collision check (when asked); nothing is stored."""
        return self._collide(pose) if self._check is not None else pose

    # ------------------------------------------------------------------------------
    def _near(self, c: tuple) -> int:
        hc, hw, lk, s2, s4, pp = self._watch
        f = 0
        if c[8] < self.margins.half_chord:
            f |= _B["NEAR_MODE_BOUNDARY"]
        if c[9] < hw:
            f |= _B["NEAR_H_ZERO"]
        if min(self._g.l1, self._g.l3) - c[9] < lk:
            f |= _B["NEAR_LINK_LIMIT"]
        if c[10] < s2:
            f |= _B["NEAR_UJOINT"]
        if c[11] < s4:
            f |= _B["NEAR_WRIST"]
        if abs(c[4]) < pp:
            f |= _B["NEAR_P_ZERO"]
        return f

    def _step(self, c: tuple) -> float:
        prev = self._prev
        o, po = c[6], prev[6]
        dO = math.sqrt((o[0] - po[0]) ** 2 + (o[1] - po[1]) ** 2 + (o[2] - po[2]) ** 2)
        u, pu = c[5], prev[5]
        du = max(_adiff(u[0], pu[0]), _adiff(u[1], pu[1]), _adiff(u[2], pu[2]),
                 _adiff(u[3], pu[3]), _adiff(u[4], pu[4]))
        return max(dO / self.jump_m, du / self.jump_rad)

    def _pose(self, q: tuple[float, float, float], c: tuple, step: float, flags: int,
              valid: bool = True, sample: int | None = None) -> TrackedPose:
        g = self._g
        o, dz = c[6], c[7]
        L = g.L
        tb = (o[0] + L * dz[0], o[1] + L * dz[1], o[2] + L * dz[2])
        v = (tb[0] - g.c[0], tb[1] - g.c[1], tb[2] - g.c[2])
        R = g.R
        te = (R[0][0] * v[0] + R[1][0] * v[1] + R[2][0] * v[2],
              R[0][1] * v[0] + R[1][1] * v[1] + R[2][1] * v[2],
              R[0][2] * v[0] + R[1][2] * v[1] + R[2][2] * v[2])
        mode, r, b, w = c[0], c[1], c[2], c[3]
        n = self._index if sample is None else sample
        return TrackedPose(n, q, valid, _slot(mode, r, b, w), mode, r, b, w, c[4],
                           c[5], o, dz, tb, te, c[8], c[9], c[10], c[11], step,
                           TrackFlag(flags) if flags else _FLAG_NONE)

    # ------------------------------------------------------------------------------
    def update(self, q: ArrayLike | Sequence[float]) -> TrackedPose:
        """Process one reading and return the tracked pose: :meth:`commit` of :meth:`candidate`.

        Parameters
        ----------
        q : array-like, shape (3,)
            Actuator reading ``(q1, q2, q3)``, m.

        Returns
        -------
        TrackedPose
            Also stored as :attr:`pose`.

        Raises
        ------
        InvalidInputError
            ``q`` is not three numbers.
        TrackingError
            When the pose carries a flag of ``raise_on`` (the pose is committed first).
        """
        pose, what = self._evaluate(q)
        self.commit(pose)
        flags = int(pose.flags)
        if flags & self._raise_bits:
            if not pose.valid:
                raise TrackingError(f"sample {pose.sample} (q = {list(pose.q)} m): no forward-"
                                    f"kinematics solution: {TrackFlag(flags)!r}", pose)
            where = f" (q = {list(pose.q)} m)" if what else ""
            raise TrackingError(f"sample {pose.sample}{where}: {TrackFlag(flags)!r}"
                                + _clearance_text(pose), pose)
        return pose

    def candidate(self, q: ArrayLike | Sequence[float]) -> TrackedPose:
        """The pose that :meth:`update` would return for ``q``, without changing the tracker.

        A pure step: the tracker's state (its last pose, labels, sample count) is left
        as it is; :meth:`commit` takes the candidate. A controller tries candidates
        (several ``q`` toward a target) and commits the one it commands; ``raise_on``
        does not apply here (it applies in :meth:`update`).

        Parameters
        ----------
        q : array-like, shape (3,)
            Actuator reading ``(q1, q2, q3)``, m.

        Returns
        -------
        TrackedPose
            With its clearance when the tracker checks collisions.

        Raises
        ------
        InvalidInputError
            ``q`` is not three numbers.
        """
        return self._evaluate(q)[0]

    def commit(self, candidate: TrackedPose) -> TrackedPose:
        """Advance the tracker to ``candidate`` (a :meth:`candidate` of its current state).

        Parameters
        ----------
        candidate : TrackedPose
            Returned by :meth:`candidate` since the last :meth:`commit`, :meth:`update`
            or :meth:`reset`.

        Returns
        -------
        TrackedPose
            ``candidate``, now also :attr:`pose`.

        Raises
        ------
        TypeError
            ``candidate`` is not a :class:`TrackedPose`.
        InvalidInputError
            ``candidate`` was not computed from the tracker's current state (its sample
            number is not the next one).
        """
        if not isinstance(candidate, TrackedPose):
            raise TypeError(f"candidate: expected a TrackedPose from Tracker.candidate, got "
                            f"{type(candidate).__name__}")
        if candidate.sample != self._index + 1:
            raise InvalidInputError(f"candidate: sample {candidate.sample} is not a candidate "
                                    f"of the tracker's current state (next sample "
                                    f"{self._index + 1}); call candidate() again")
        self._index = candidate.sample
        if candidate.valid:
            c = candidate
            self._prev = (c.mode, c.p_sign, c.ujoint, c.wrist, c.p, c.u, c.O_s, c.direction_b,
                          c.half_chord, c.h, c.sin_u2, c.sin_u4)
            self._lost = False
        else:
            self._lost = True
        self.pose = candidate
        return candidate

    def _evaluate(self, q: ArrayLike | Sequence[float]) -> tuple[TrackedPose, bool]:
        """The candidate pose of ``q`` and whether it took the slow path (state unchanged)."""
        try:
            q1, q2, q3 = float(q[0]), float(q[1]), float(q[2])  # type: ignore[index,arg-type]
            if len(q) != 3:  # type: ignore[arg-type]
                raise ValueError
        except (TypeError, ValueError, LookupError, OverflowError):
            raise InvalidInputError(f"q: expected 3 numbers (q1, q2, q3) in m, got {q!r}") \
                from None
        n = self._index + 1
        g = self._g
        qt = (q1, q2, q3)
        flags = 0
        finite = math.isfinite(q1) and math.isfinite(q2) and math.isfinite(q3)
        if finite and not (g.lo[0] <= q1 <= g.hi[0] and g.lo[1] <= q2 <= g.hi[1]
                           and g.lo[2] <= q3 <= g.hi[2]):
            flags |= _B["OUT_OF_STROKE"]
        par = _parallel(g, q1, q2, q3) if finite else None
        prev = self._prev
        if par is None:
            return self._lose(qt, flags, n), True
        if self._lost:
            flags |= _B["REACQUIRED"]
        # fast path: the candidate with the previous labels, far from every singularity
        c = _candidate(g, par, prev[0], prev[1], prev[2], prev[3], prev[5])
        if c is not None and not self._lost:
            hc, hw, lk, s2, s4, pp = self._watch
            step = self._step(c)
            if (step <= 1.0 and c[8] >= hc and c[9] >= hw and c[10] >= s2 and c[11] >= s4
                    and abs(c[4]) >= pp and min(g.l1, g.l3) - c[9] >= lk):
                return self._finish(self._pose(qt, c, step, flags, sample=n)), False
        # slow path: all candidates
        cands = []
        for mode in (1, -1):
            for r in (1, -1):
                for b in (1, -1):
                    for w in (1, -1):
                        cc = _candidate(g, par, mode, r, b, w, prev[5])
                        if cc is not None:
                            cands.append((self._step(cc), cc))
        if not cands:
            return self._lose(qt, flags, n), True
        same = [sc for sc in cands if sc[1][:4] == prev[:4]]
        if same and same[0][0] <= 1.0:
            step, c = same[0]
        else:
            step, c = min(cands, key=lambda sc: sc[0])
        if any(sc[0] <= 1.0 and sc[1][:4] != c[:4] for sc in cands):
            flags |= _B["AMBIGUOUS"]
        if step > 1.0:
            flags |= _B["JUMP"]
        if c[0] != prev[0]:
            flags |= _B["MODE_SWITCH"]
        if c[1:4] != prev[1:4]:
            flags |= _B["BRANCH_SWITCH"]
        flags |= self._near(c)
        return self._finish(self._pose(qt, c, step, flags, sample=n)), True

    def _lose(self, qt: tuple[float, float, float], flags: int, n: int) -> TrackedPose:
        return self._pose(qt, self._prev, math.inf, flags | _B["LOST"], valid=False, sample=n)
