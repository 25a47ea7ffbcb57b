"""The teleoperation core: master samples -> safe actuator commands, one cycle at a time.

One cycle (:meth:`Teleop.step`) runs, in this order:

1. **Mapping** (:mod:`._mapping`). ``p_e = R_e_m p_m`` (registration), the tremor filter
   on ``p_e``, ``target = offset + scale * filtered``; on every (re-)engagement of the
   clutch the offset is recomputed so that the target equals the current command (jump 0).
2. **Safety layer**, each event a :class:`TeleopStatus` bit: the target's insertion
   depth (``DEPTH``) and the forbidden regions (``FIXTURE``) are projections of the
   target; then the limiter (:mod:`._limiter`) shortens the step from the current tip
   toward it, keeping its direction, to one whose exact IK (``q_from_tool_tip``) stays
   on the tracked branch (:class:`athenakin.motion.Tracker`) and within the stroke
   (``STROKE``), the singular-set margins (``SINGULAR``), the clearance (``CLEARANCE``),
   the velocity (``VELOCITY``) and acceleration (``ACCELERATION``) limits: the step's
   length from the closed-form tool-tip Jacobian and the clearance's witness points,
   checked by one exact IK (a few at most: :data:`~athenakin.teleop._limiter.TRIES`), at
   most :data:`~athenakin.teleop._limiter.CLEARANCE_EVALUATIONS` clearance evaluations
   per cycle. Every shortened step carries the flag of what shortened it. The watchdog
   (``WATCHDOG``) and the e-stop (``ESTOP``) freeze the target.
3. **Hold** (:mod:`._brake`). Where no step along the tip's direction keeps the limits
   (a reversal, a freeze), the robot brakes along its own velocity at ``a_max`` (a
   category-2 stop) and holds at rest; the soft margins are at least the stopping
   distance, so braking never crosses a hard limit.
4. **Feed-forward.** ``forces = inverse_dynamics(q, qd, qdd)`` (gravity and inertia)
   of :mod:`athenakin.dynamics` on the tracked slot.

Velocities and accelerations are backward differences of the commands at the fixed
cycle ``1 / rate``: ``qd_k = (q_k - q_{k-1}) rate``, ``qdd_k = (qd_k - qd_{k-1}) rate``.
The watchdog counts cycles: ``watchdog * rate`` consecutive cycles without a new master
sample (none, a malformed one, or one whose stamp ``t`` is not after the previous
sample's) hold the robot, whatever the caller's clock says. Nothing inside
:meth:`Teleop.step` raises.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._robot_model import resolve_robot
from .._validation import check_array, check_scalar
from ..errors import InvalidInputError
from ._brake import TeleopCommand, _Brake
from ._filter import TremorFilter, check_rate
from ._fixtures import TipFixtures
from ._limiter import _IK, CLEARANCE_GAIN, CLEARANCE_SLACK_M, LIMIT_SLACK, _Limiter
from ._mapping import _Mapping, clutch_state
from ._options import (
    _CLUTCHED,
    _ESTOP,
    _FAULT,
    _HOLD,
    _INVALID,
    _JUMP,
    _WATCHDOG,
    TeleopOptions,
    _three,
)

__all__ = ["Teleop", "TeleopCommand", "MAX_SCALE", "LINK_LIMIT_TOL", "CYCLE_ROUNDING"]

_V3 = tuple[float, float, float]
#: Largest motion scale, tip metres per master metre (a surgical master scales down).
MAX_SCALE = 10.0
#: Slack on ``watchdog * rate`` before it is rounded up to whole cycles (0.03 s at 1 kHz
#: is 30 cycles, not 31).
CYCLE_ROUNDING = 1e-9
#: Least distance of ``q0``'s ``|h|`` from the link limit ``min(l1, l3)`` (the singular
#: set where the feed-forward and the Jacobian are not defined), m.
LINK_LIMIT_TOL = 1e-9


def _check_scale(scale: object) -> float:
    s = check_scalar(scale, "scale", positive=True)
    if s > MAX_SCALE:
        raise InvalidInputError(f"scale: expected a motion scale in (0, {MAX_SCALE:g}] tip m "
                                f"per master m, got {s:g}")
    return s


class Teleop(_Mapping, _Limiter, _Brake):
    """Teleoperation of ATHENA's tool tip from a master, with a safety layer that never lets go.

    Parameters
    ----------
    robot : athenakin.Robot or array-like, shape (4, 4)
        The robot (its design, RCM frame, bodies, environment and masses), or its RCM
        frame E in the base frame ``T_b_e`` (then ``design``, ``bodies`` and
        ``environment`` build the Robot).
    design : Design, optional
        With ``T_b_e`` only; default :meth:`Design.default`.
    q0 : array-like, shape (3,), keyword-only
        Where the robot stands, m.
    scale : float, keyword-only
        Motion scale, tip metres per master metre (0.2), in ``(0, MAX_SCALE]``; change it
        with :meth:`set_scale`.
    environment : athenakin.collision.Environment, optional, keyword-only
        Its primitive obstacles are forbidden regions for the tip (virtual fixtures); all
        its obstacles are kept ``clearance_margin`` from every body. Default the Robot's.
    bodies : athenakin.collision.Bodies, optional, keyword-only
        The robot's capsules, kept ``clearance_margin`` apart and from the obstacles;
        default the Robot's, else :meth:`Bodies.default` when ``environment`` is given,
        else no check.
    v_max, a_max : float or array-like, shape (3,), keyword-only
        Actuator velocity (m/s, default 0.1) and acceleration (m/s^2, default 2.0) limits.
    rate : float, keyword-only
        Cycles per second, Hz (1000); at least the tremor filter's band rate
        (:data:`~athenakin.teleop._filter.BAND_RATES`).
    slot : int, keyword-only
        Forward-kinematics slot of ``q0`` that the tip follows (0); its instrument must be
        inserted through the RCM (``p > 0``).
    options : TeleopOptions, optional, keyword-only
        Registration, filter, watchdog, margins, masses, backend, ...

    Raises
    ------
    InvalidInputError, TypeError
        A bad argument (named); ``q0`` outside the stroke, with no valid ``slot``, or on
        the singular set ``|h| = min(l1, l3)``; the tip of ``q0`` inside a forbidden
        region; the clearance of ``q0`` below its margin; margins below the stopping
        distance; a scale above :data:`MAX_SCALE`; a rate below the filter's band rate.

    Examples
    --------
    >>> import athenakin as ak
    >>> from athenakin.teleop import Teleop
    >>> robot = ak.Robot.default()
    >>> tele = Teleop(robot, q0=[-0.1, 0.1, 0.45],
    ...               options=ak.teleop.TeleopOptions(feedforward=False))
    >>> cmd = tele.step(0.0, [0.0, 0.0, 0.0])
    >>> cmd.tip == tele.tip, int(cmd.status)
    (True, 0)
    """

    def __init__(self, robot: Any, design: Any = None, *, q0: ArrayLike,
                 scale: float = 0.2, environment: object = None, bodies: object = None,
                 v_max: float | ArrayLike = 0.1, a_max: float | ArrayLike = 2.0,
                 rate: float = 1000.0, slot: int = 0,
                 options: TeleopOptions | None = None) -> None:
        from .._dispatch import resolve_backend
        from ..motion import Margins, Tracker

        opts = TeleopOptions() if options is None else options
        if not isinstance(opts, TeleopOptions):
            raise TypeError(f"options: expected TeleopOptions, got {type(opts).__name__}")
        self.robot = resolve_robot(robot, design, bodies=bodies, environment=environment)
        design, T = self.robot.design, self.robot.T_b_e
        bodies, environment = self.robot.bodies, self.robot.environment
        self.options = opts
        self._max_jump, self._watchdog = opts.max_master_jump, opts.watchdog   # read per cycle
        self.design, self.T_b_e = design, T
        self.rate = check_rate(rate)
        self._filter = TremorFilter(opts.filter, self.rate)    # its band's least rate
        self.dt = 1.0 / self.rate
        #: Consecutive cycles without a new master sample that trip the watchdog.
        self.watchdog_cycles = max(1, math.ceil(opts.watchdog * self.rate - CYCLE_ROUNDING))
        self.v_max, self.a_max = _three(v_max, "v_max"), _three(a_max, "a_max")
        k = 1.0 - LIMIT_SLACK                 # the limits that the limiter aims at
        self._v_aim = tuple(v * k for v in self.v_max)
        self._a_aim = tuple(a * k for a in self.a_max)
        self._scale = _check_scale(scale)
        self.stopping_distance = opts.stopping_distance(self.v_max, self.a_max)
        self.depth = _check_margins(opts, design, self.stopping_distance)
        self.margins = opts.margins if opts.margins is not None else Margins()
        self._lo = tuple(float(v) + opts.stroke_margin for v in design.stroke_min)
        self._hi = tuple(float(v) - opts.stroke_margin for v in design.stroke_max)
        self._hard_lo = tuple(float(v) for v in design.stroke_min)
        self._hard_hi = tuple(float(v) for v in design.stroke_max)
        self._link_max = min(design.l1, design.l3)      # the h margin's far side, m
        compiled = resolve_backend(opts.backend)
        self._backend = "numba" if compiled else "numpy"
        self._ik = _IK(T, design, compiled)
        self._R = tuple(tuple(float(v) for v in row) for row in opts.registration)
        self._Tr = tuple(tuple(float(v) for v in row) for row in T[:3, :4])
        self._fixtures = TipFixtures(environment, compiled=compiled)
        self._has_fixtures = len(self._fixtures) > 0
        check = (bodies is not None or environment is not None) if opts.check_clearance is None \
            else opts.check_clearance
        self._clear_floor = opts.clearance_margin + opts.clearance_buffer if check else -math.inf
        self._guard = None
        if check:
            from ..collision import Bodies
            from ._guard import BodyGuard

            # exact up to the highest floor the limiter sets (its braking room at v_max)
            band = CLEARANCE_GAIN * self.stopping_distance + CLEARANCE_SLACK_M
            self._guard = BodyGuard(design, T, bodies if bodies is not None
                                    else Bodies.default(design), environment,
                                    backend=self._backend, floor=self._clear_floor, band=band)
        q = self._check_q0(q0)
        self._tracker = Tracker(T, design, q0=q, slot=slot, margins=self.margins,
                                backend=self._backend)
        self._masses, self._gravity = _feedforward_model(opts, design, self.robot.masses)
        # the feed-forward of each FK slot the robot takes: the dynamics' loop object
        # (checked once, the compiled kernel on preallocated buffers, never raises)
        self._ff_loops: dict[int, Any] = {}
        self._check_start(self._tracker.pose)
        self.fault: BaseException | None = None
        self._estop = False
        self._reset_state(self._tracker.pose)

    @staticmethod
    def _check_q0(q0: ArrayLike) -> np.ndarray:
        q = check_array(q0, "q0", (3,))
        if q.shape != (3,):
            raise InvalidInputError(f"q0: expected shape (3,), got {q.shape}")
        return q

    def _check_start(self, pose: Any) -> None:
        """``q0``'s tracked pose may start teleoperation (else a named error).

        The instrument inserted through the RCM, ``q0`` within the stroke and off the
        singular set ``|h| = min(l1, l3)``, its tip outside every forbidden region, and
        (with the check) the bodies' clearance at least the margin. Evaluates and
        commits the pose's clearance.
        """
        if pose.p_sign != 1:
            raise InvalidInputError(f"slot: slot {pose.slot} has the instrument behind the RCM "
                                    f"(p < 0); teleoperation needs p > 0")
        if not all(lo <= v <= hi for lo, v, hi in
                   zip(self._hard_lo, pose.q, self._hard_hi, strict=True)):
            raise InvalidInputError(f"q0: {list(pose.q)} is outside the stroke limits")
        J = self._ik.along(pose.q, pose.mode, (1.0, 0.0, 0.0)) + self._ik.along(
            pose.q, pose.mode, (0.0, 1.0, 0.0))
        if not self._link_max - pose.h > LINK_LIMIT_TOL or not all(map(math.isfinite, J)):
            raise InvalidInputError(f"q0: {list(pose.q)} is on the singular set |h| = "
                                    f"min(l1, l3) = {self._link_max} m (|h| = {pose.h:.12g} m):"
                                    f" no tool-tip Jacobian or feed-forward there")
        d, _, i = self._fixtures.nearest(self._to_base(pose.tip_e))
        if d < 0.0:
            raise InvalidInputError(f"q0: the tool tip is inside the forbidden region "
                                    f"{self._fixtures.names[i]!r} ({-d:.4g} m deep)")
        if self._guard is not None:
            c = self._guard.evaluate(pose)
            margin = self.options.clearance_margin
            if not c >= margin:
                a, b = self._guard.trial_pair()
                raise InvalidInputError(f"q0: clearance {c:.4g} m between {a!r} and "
                                        f"{b!r} is below clearance_margin {margin} m")
            self._guard.commit()

    # ------------------------------------------------------------------------------
    def _reset_state(self, pose: Any) -> None:
        z = (0.0, 0.0, 0.0)
        self._q, self._qd, self._qdd = tuple(pose.q), z, z
        self._tip = tuple(pose.tip_e)
        self._tip_fix = self._fixtures.nearest(self._to_base(self._tip))
        self._try_fix = (self._tip, self._tip_fix)   # the last tried tip's distance
        self._pose = pose
        self._slot = pose.slot
        self._target = self._tip
        self._goal = self._tip
        self._offset = self._tip
        self._engaged = False          # the next valid sample (re-)engages
        self._last_p: _V3 | None = None
        self._step_p: _V3 = z          # the master's last step between two samples, m
        self._dt_p = 0.0               # and its interval, s
        self._t_sample = -math.inf
        self._t = -math.inf
        self._silent = 0               # cycles since the last new sample
        self._hold = False             # watchdog hold: re-engage on the next sample
        self._y: _V3 = z
        self._ff_key: tuple | None = None
        self._ff: _V3 = (math.nan, math.nan, math.nan)

    # --- public state ---------------------------------------------------------------
    @property
    def q(self) -> _V3:
        """The last commanded actuator positions, m."""
        return self._q

    @property
    def tip(self) -> _V3:
        """The last commanded tool tip, RCM frame E, m."""
        return self._tip

    @property
    def scale(self) -> float:
        """The motion scale (tip m per master m)."""
        return self._scale

    @property
    def engaged(self) -> bool:
        """Whether the tip follows the master (clutch closed, no watchdog or e-stop hold)."""
        return self._engaged

    @property
    def estopped(self) -> bool:
        """Whether the e-stop is latched (until :meth:`release`)."""
        return self._estop

    @property
    def backend(self) -> str:
        """``"numba"`` (compiled IK and dynamics) or ``"numpy"``."""
        return self._backend

    @property
    def checks_clearance(self) -> bool:
        """Whether every step keeps the robot's bodies apart, and from the environment.

        True when ``bodies`` or ``environment`` was given or
        ``TeleopOptions(check_clearance=True)``; False only where the caller opted out
        (``check_clearance=False``, or neither given).
        """
        return self._guard is not None

    @property
    def clearance_evaluations(self) -> int:
        """Exact clearance evaluations of the last cycle (at most ``CLEARANCE_EVALUATIONS``)."""
        return 0 if self._guard is None else self._guard.evaluations

    def set_scale(self, scale: float) -> None:
        """Change the motion scale without a jump of the tip (clutched or not).

        The offset is recomputed so that the last filtered master position maps to
        the same target as before.

        Parameters
        ----------
        scale : float
            Tip metres per master metre, in ``(0, MAX_SCALE]``.

        Raises
        ------
        InvalidInputError, TypeError
            Not a number in ``(0, MAX_SCALE]``.
        """
        s = _check_scale(scale)
        y = self._y
        o = self._offset
        d = self._scale - s
        self._offset = (o[0] + d * y[0], o[1] + d * y[1], o[2] + d * y[2])
        self._scale = s

    def estop(self) -> None:
        """Latch the e-stop: the robot brakes to rest and holds until :meth:`release`.

        Neither :meth:`reset` nor anything but :meth:`release` clears it.
        """
        self._estop = True

    def release(self) -> None:
        """Release the e-stop; the master re-engages on its next sample (no tip jump)."""
        self._estop = False
        self._engaged = False

    def reset(self, q0: ArrayLike, *, slot: int = 0) -> None:
        """Restart at rest at a known configuration, with the constructor's checks.

        A latched e-stop stays latched (:meth:`release` clears it).

        Parameters
        ----------
        q0 : array-like, shape (3,)
            Where the robot stands, m.
        slot : int, keyword-only
            Its forward-kinematics slot (``p > 0``).

        Raises
        ------
        InvalidInputError, TypeError
            As the constructor's for ``q0`` and ``slot``: outside the stroke, no valid
            slot, the instrument behind the RCM, on the singular set, the tip inside a
            forbidden region, the clearance below its margin. The state is then left
            as it was.
        """
        from ..motion import Tracker

        q = self._check_q0(q0)
        tracker = Tracker(self.T_b_e, self.design, q0=q, slot=slot, margins=self.margins)
        self._check_start(tracker.pose)
        self._tracker = tracker
        self._reset_state(tracker.pose)

    # --- the cycle ------------------------------------------------------------------
    def step(self, t: float, master_position: ArrayLike | None, clutch: bool = True
             ) -> TeleopCommand:
        """One cycle: a master sample (or none) -> the command of this cycle.

        Parameters
        ----------
        t : float
            Time of the cycle and stamp of the sample, s; the cycle itself is ``1 / rate``.
            A sample stamped no later than the previous sample is no new sample (a
            latched topic re-delivering its message); a ``t`` before the previous one,
            or not finite, is ignored (``INVALID``).
        master_position : array-like, shape (3,), or None
            The master handle's position in the master's frame, m: three real numbers
            (a list, tuple or numeric array; not a string or bytes); None: no sample this
            cycle. A malformed or non-finite sample counts as none (flag ``INVALID``).
        clutch : bool
            True: the clutch is closed, the tip follows the master. False: the clutch is
            open (dVRK's "clutched"): the master moves freely, the tip holds, and on the
            next True the offset is recomputed so that the tip does not jump. numpy
            booleans and the integers 0 / 1 are taken too; anything else (an array, a
            string, None) is a malformed clutch: open, flag ``INVALID``.

        Returns
        -------
        TeleopCommand
            Never raises: an internal error holds the robot with ``FAULT``.
        """
        try:
            return self._step(t, master_position, clutch)
        except Exception as exc:            # never raise inside the loop: flag and hold
            self.fault = exc
            return self._brake(_FAULT | _HOLD, self._t)

    def _step(self, t: object, m: object, clutch: object) -> TeleopCommand:
        if self._guard is not None:
            self._guard.evaluations = 0
        tt, p, flags = self._sample(t, m)
        self._t = tt
        if p is not None and not tt > self._t_sample:
            p = None                   # a repeated or frozen stamp is no new sample
        closed = clutch_state(clutch)
        if closed is None:             # a malformed clutch: open (the tip holds), flagged
            flags |= _INVALID
            closed = False
        if p is not None:
            self._silent = 0
            last = self._last_p
            if last is not None and math.dist(p, last) > self._max_jump:
                flags |= _JUMP
                self._engaged = False
            if last is None or flags & _JUMP:
                self._filter.reset(*p)
                self._step_p = (0.0, 0.0, 0.0)
                self._dt_p = 0.0
            else:              # the master's last step and its interval
                self._step_p = (p[0] - last[0], p[1] - last[1], p[2] - last[2])
                self._dt_p = tt - self._t_sample
            self._last_p = p
            self._t_sample = tt
            self._hold = False
            self._y = self._filter(*self._master_now(tt))
        else:
            self._silent += 1
            if self._silent >= self.watchdog_cycles or tt - self._t_sample >= self._watchdog:
                flags |= _WATCHDOG
                self._hold = True
                self._engaged = False
            elif self._last_p is not None:
                # no sample this cycle (a master slower than the loop): the filter runs
                # every cycle on the master interpolated between its samples (_master_now)
                self._y = self._filter(*self._master_now(tt))
        if self._estop:
            flags |= _ESTOP
            self._engaged = False
        if self._hold and not flags & _WATCHDOG:
            flags |= _WATCHDOG
        if flags & (_ESTOP | _WATCHDOG):
            return self._brake(flags | _HOLD, tt)
        if not closed:
            flags |= _CLUTCHED
            self._engaged = False
        elif p is not None and not self._engaged:
            y, s, c = self._y, self._scale, self._tip
            self._offset = (c[0] - s * y[0], c[1] - s * y[1], c[2] - s * y[2])
            self._engaged = True
        if self._engaged:
            y, s, o = self._y, self._scale, self._offset
            g = (o[0] + s * y[0], o[1] + s * y[1], o[2] + s * y[2])
        else:
            g = self._tip
        self._target = g
        g, f = self._depth(g)
        flags |= f
        if self._has_fixtures:
            g, f = self._fixture(g)
            flags |= f
            g, f = self._slide(g)
            flags |= f
        return self._advance(g, flags, tt)


def _check_margins(opts: TeleopOptions, design: Any, stopping: float) -> tuple[float, float]:
    """The insertion depth range ``(min, max)`` (m), checked against the tool length.

    Also checks the stroke margin against the stopping distance ``stopping`` (m).
    """
    if opts.stroke_margin < stopping:
        raise InvalidInputError(f"stroke_margin: {opts.stroke_margin} m is below the "
                                f"stopping distance {stopping:.4g} m of v_max, "
                                f"a_max; raise it or a_max")
    L = design.tool_length
    depth = opts.depth if opts.depth is not None else (0.01, L - 0.03)
    if not depth[1] < L:
        raise InvalidInputError(f"depth: the largest depth must be below the tool length "
                                f"{L} m, got {depth[1]}")
    return depth


def _feedforward_model(opts: TeleopOptions, design: Any, robot_masses: Any) -> tuple[Any, Any]:
    """Mass model and gravity (base frame, m/s^2) of the feed-forward.

    ``options.masses``, else the Robot's, else ``MassModel.reference(design)``;
    ``(None, None)`` with ``feedforward=False``.
    """
    if not opts.feedforward:
        return None, None
    from ..dynamics import STANDARD_GRAVITY, MassModel

    masses = opts.masses if opts.masses is not None else robot_masses
    masses = masses if masses is not None else MassModel.reference(design)
    if not isinstance(masses, MassModel):
        raise TypeError(f"masses: expected athenakin.dynamics.MassModel, got "
                        f"{type(masses).__name__}")
    gravity = np.array(STANDARD_GRAVITY if opts.gravity is None else opts.gravity, dtype=float)
    return masses, gravity
