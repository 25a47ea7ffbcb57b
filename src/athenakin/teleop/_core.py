"""The teleoperation core: master samples -> safe actuator commands, one cycle at a time.

One cycle (:meth:`Teleop.step`) runs, in this order:

1. **Mapping.** ``p_e = R_e_m p_m`` (registration), the tremor filter on ``p_e``,
   ``target = offset + scale * filtered``; on every (re-)engagement of the clutch
   the offset is recomputed so that the target equals the current command (jump 0).
2. **Safety layer**, each event a :class:`TeleopStatus` bit: the target's insertion
   depth (``DEPTH``) and the forbidden regions (``FIXTURE``) are projections of the
   target; then the step from the current tip toward it is shortened, keeping its
   direction, to the longest one whose exact IK (``q_from_tool_tip``) stays on the
   tracked branch (:class:`athenakin.motion.Tracker`) and within the stroke
   (``STROKE``), the singular-set margins (``SINGULAR``), the clearance
   (``CLEARANCE``), the velocity (``VELOCITY``) and acceleration (``ACCELERATION``)
   limits. The watchdog (``WATCHDOG``) and the e-stop (``ESTOP``) freeze the target.
3. **Hold.** Where no step along the tip's direction keeps the acceleration limit (a
   reversal, a freeze), the robot brakes along its own velocity at ``a_max`` (a
   category-2 stop) and holds at rest; the soft margins are at least the stopping
   distance, so braking never crosses a hard limit.
4. **Feed-forward.** ``forces = inverse_dynamics(q, qd, qdd)`` (gravity and inertia)
   of :mod:`athenakin.dynamics` on the tracked slot.

Velocities and accelerations are backward differences of the commands at the fixed
cycle ``1 / rate``: ``qd_k = (q_k - q_{k-1}) rate``, ``qdd_k = (qd_k - qd_{k-1}) rate``.
The loop allocates no numpy array except in the feed-forward call and the reference
(numpy) IK where numba is absent; nothing inside :meth:`Teleop.step` raises.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .._validation import check_array, check_frame, check_scalar
from ..design import Design, resolve_design
from ..errors import InvalidInputError, Reason
from ._filter import TremorFilter, check_rate
from ._fixtures import TipFixtures
from ._options import TeleopOptions, TeleopStatus, _three

__all__ = ["Teleop", "TeleopCommand"]

_V3 = tuple[float, float, float]
# the status bits as plain ints (the loop combines them; :func:`_status` makes the flag)
_CLUTCHED = int(TeleopStatus.CLUTCHED)
_STROKE = int(TeleopStatus.STROKE)
_DEPTH = int(TeleopStatus.DEPTH)
_SINGULAR = int(TeleopStatus.SINGULAR)
_FIXTURE = int(TeleopStatus.FIXTURE)
_CLEARANCE = int(TeleopStatus.CLEARANCE)
_VELOCITY = int(TeleopStatus.VELOCITY)
_ACCELERATION = int(TeleopStatus.ACCELERATION)
_WATCHDOG = int(TeleopStatus.WATCHDOG)
_ESTOP = int(TeleopStatus.ESTOP)
_INVALID = int(TeleopStatus.INVALID)
_JUMP = int(TeleopStatus.JUMP)
_HOLD = int(TeleopStatus.HOLD)
_FAULT = int(TeleopStatus.FAULT)
#: Relative slack below the limits that the limiter aims at (rounding of the IK).
LIMIT_SLACK = 1e-6
#: Longest step probed for the direction of the joint motion, m.
PROBE_M = 1e-6
#: Largest distance between the tracked forward kinematics and the commanded tip, m.
BRANCH_TOL = 1e-9
#: Bisections of a step that fails a constraint before the robot brakes.
BISECTIONS = 12
#: Secant refinements of a step whose exact IK breaks a limit the linear model kept.
SECANTS = 4
#: Largest master coordinate taken as a sample (beyond: ``INVALID``), m.
MAX_MASTER_M = 100.0
#: Distance beyond ``fixture_margin`` within which steps into a fixture slide along it, m.
SLIDE_BAND_M = 0.002
#: Bound on a body point's travel per metre of joint travel, for the clearance's braking room.
CLEARANCE_GAIN = 4.0
_STROKE_REASONS = (int(Reason.STROKE_LIMIT), int(Reason.AB_ORDER), int(Reason.INSERTION_RANGE))


class TeleopCommand(NamedTuple):
    """The command of one cycle (an immutable named tuple of plain floats).

    A named tuple, as :class:`athenakin.motion.TrackedPose`: building it costs a fraction
    of a microsecond, a frozen dataclass several. Wrap the vectors with ``np.asarray``.

    Attributes
    ----------
    t : float
        Time of the cycle, s.
    q, qd, qdd : tuple of 3 float
        Actuator positions (m), velocities (m/s), accelerations (m/s^2) to servo.
    forces : tuple of 3 float
        Feed-forward actuator forces (N, positive along increasing ``q``): gravity and
        inertia of ``(q, qd, qdd)``; NaN with ``feedforward=False``.
    tip : tuple of 3 float
        The commanded tool tip in the RCM frame E, m (as ``q_from_tool_tip`` takes it);
        it is the forward kinematics of ``q`` on the tracked slot.
    target : tuple of 3 float
        The master's target for the tip (frame E, m) after the mapping and the filter,
        before the safety layer.
    status : TeleopStatus
    slot : int
        The tracked forward-kinematics slot of ``q``.
    clearance : float
        Least clearance of the bodies (m); NaN when not checked.
    """

    t: float
    q: _V3
    qd: _V3
    qdd: _V3
    forces: _V3
    tip: _V3
    target: _V3
    status: TeleopStatus
    slot: int
    clearance: float


class _IK:
    """``q_from_tool_tip`` on plain floats: compiled (``fast.ControlLoop``) or the reference."""

    def __init__(self, T: np.ndarray, design: Design, compiled: bool) -> None:
        self.T, self.design = T, design
        self.ctl = None
        if compiled:
            from ..fast import ControlLoop

            self.ctl = ControlLoop(T, design)
            self.buf = np.empty(3)

    def __call__(self, x: float, y: float, z: float) -> tuple[float, float, float, int]:
        if self.ctl is not None:
            b = self.buf
            b[0], b[1], b[2] = x, y, z
            q, r = self.ctl.q_from_tool_tip(b)
            q0, q1, q2 = q.tolist()          # Python floats in one call
            return q0, q1, q2, int(r)
        from ..robot import q_from_tool_tip

        q, res = q_from_tool_tip(self.T, (x, y, z), self.design, errors="flag")
        return float(q[0]), float(q[1]), float(q[2]), int(res.reason)


class Teleop:
    """Teleoperation of ATHENA's tool tip from a master, with a safety layer that never lets go.

    Parameters
    ----------
    T_b_e : array-like, shape (4, 4)
        RCM frame E in the base frame (the set-up).
    design : Design, optional
        Default :meth:`Design.default`.
    q0 : array-like, shape (3,), keyword-only
        Where the robot stands, m.
    scale : float, keyword-only
        Motion scale, tip metres per master metre (0.2); change it with :meth:`set_scale`.
    environment : athenakin.collision.Environment, optional, keyword-only
        Its primitive obstacles are forbidden regions for the tip (virtual fixtures); all
        its obstacles are kept ``clearance_margin`` from every body.
    bodies : athenakin.collision.Bodies, optional, keyword-only
        The robot's capsules, kept ``clearance_margin`` apart and from the obstacles;
        default :meth:`Bodies.default` when ``environment`` is given, else no check.
    v_max, a_max : float or array-like, shape (3,), keyword-only
        Actuator velocity (m/s, default 0.1) and acceleration (m/s^2, default 2.0) limits.
    rate : float, keyword-only
        Cycles per second, Hz (1000).
    slot : int, keyword-only
        Forward-kinematics slot of ``q0`` that the tip follows (0); its instrument must be
        inserted through the RCM (``p > 0``).
    options : TeleopOptions, optional, keyword-only
        Registration, filter, watchdog, margins, masses, ...

    Raises
    ------
    InvalidInputError, TypeError
        A bad argument (named); ``q0`` outside the stroke or with no valid ``slot``; the
        tip of ``q0`` inside a forbidden region; margins below the stopping distance.

    Examples
    --------
    >>> import athenakin as ak
    >>> from athenakin.teleop import Teleop
    >>> d = ak.Design.default()
    >>> tele = Teleop(ak.default_rcm_frame(d), d, q0=[-0.1, 0.1, 0.45],
    ...               options=ak.teleop.TeleopOptions(feedforward=False))
    >>> cmd = tele.step(0.0, [0.0, 0.0, 0.0])
    >>> cmd.tip == tele.tip, int(cmd.status)
    (True, 0)
    """

    def __init__(self, T_b_e: ArrayLike, design: Design | None = None, *, q0: ArrayLike,
                 scale: float = 0.2, environment: object = None, bodies: object = None,
                 v_max: float | ArrayLike = 0.1, a_max: float | ArrayLike = 2.0,
                 rate: float = 1000.0, slot: int = 0,
                 options: TeleopOptions | None = None) -> None:
        from .._dispatch import resolve_backend
        from ..motion import Margins, Tracker

        design = resolve_design(design)
        T = check_frame(T_b_e, "T_b_e")
        opts = TeleopOptions() if options is None else options
        if not isinstance(opts, TeleopOptions):
            raise TypeError(f"options: expected TeleopOptions, got {type(opts).__name__}")
        self.options = opts
        self._max_jump, self._watchdog = opts.max_master_jump, opts.watchdog   # read per cycle
        self.design, self.T_b_e = design, np.array(T)
        self.T_b_e.setflags(write=False)
        self.rate = check_rate(rate)
        self._filter = TremorFilter(opts.filter, self.rate)    # its own least rate
        self.dt = 1.0 / self.rate
        self.v_max, self.a_max = _three(v_max, "v_max"), _three(a_max, "a_max")
        k = 1.0 - LIMIT_SLACK                 # the limits that the limiter aims at
        self._v_aim = tuple(v * k for v in self.v_max)
        self._a_aim = tuple(a * k for a in self.a_max)
        self._scale = check_scalar(scale, "scale", positive=True)
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
        self._ik = _IK(self.T_b_e, design, compiled)
        self._R = tuple(tuple(float(v) for v in row) for row in opts.registration)
        self._Tr = tuple(tuple(float(v) for v in row) for row in T[:3, :4])
        self._fixtures = TipFixtures(environment)
        self._has_fixtures = len(self._fixtures) > 0
        check = (bodies is not None or environment is not None) if opts.check_clearance is None \
            else opts.check_clearance
        self._clear_floor = opts.clearance_margin + opts.clearance_buffer if check else -math.inf
        q = check_array(q0, "q0", (3,))
        if q.shape != (3,):
            raise InvalidInputError(f"q0: expected shape (3,), got {q.shape}")
        self._tracker = Tracker(self.T_b_e, design, q0=q, slot=slot, margins=self.margins,
                                bodies=bodies if check else None,
                                environment=environment if check else None,
                                clearance_margin=opts.clearance_margin if check else None,
                                backend=self._backend)
        self._check_start(self._tracker.pose, check)
        self._masses, self._gravity = _feedforward_model(opts, design)
        # the feed-forward of each FK slot the robot takes: the dynamics' loop object
        # (checked once, the compiled kernel on preallocated buffers, never raises)
        self._ff_loops: dict[int, Any] = {}
        self.fault: BaseException | None = None
        self._reset_state(self._tracker.pose)

    def _check_start(self, pose: Any, check: bool) -> None:
        """``q0``'s tracked pose may start teleoperation (else a named error).

        The instrument inserted through the RCM, ``q0`` within the stroke, its tip outside
        every forbidden region, and (``check``) the bodies' clearance above the margin.
        """
        if pose.p_sign != 1:
            raise InvalidInputError(f"slot: slot {pose.slot} has the instrument behind the RCM "
                                    f"(p < 0); teleoperation needs p > 0")
        if not all(lo <= v <= hi for lo, v, hi in
                   zip(self._hard_lo, pose.q, self._hard_hi, strict=True)):
            raise InvalidInputError(f"q0: {list(pose.q)} is outside the stroke limits")
        d, _, i = self._fixtures.nearest(self._to_base(pose.tip_e))
        if d < 0.0:
            raise InvalidInputError(f"q0: the tool tip is inside the forbidden region "
                                    f"{self._fixtures.names[i]!r} ({-d:.4g} m deep)")
        margin = self.options.clearance_margin
        if check and not pose.clearance >= margin:
            a, b = pose.closest_pair
            raise InvalidInputError(f"q0: clearance {pose.clearance:.4g} m between {a!r} and "
                                    f"{b!r} is below clearance_margin {margin} m")

    # ------------------------------------------------------------------------------
    def _reset_state(self, pose: Any) -> None:
        z = (0.0, 0.0, 0.0)
        self._q, self._qd, self._qdd = tuple(pose.q), z, z
        self._tip = tuple(pose.tip_e)
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
        self._estop = False
        self._hold = False             # watchdog hold: re-engage on the next sample
        self._y: _V3 = z
        self._ff_key: tuple | None = None
        self._ff: _V3 = _NAN3

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
    def backend(self) -> str:
        """``"numba"`` (compiled IK and dynamics) or ``"numpy"``."""
        return self._backend

    def set_scale(self, scale: float) -> None:
        """Change the motion scale without a jump of the tip (clutched or not).

        The offset is recomputed so that the last filtered master position maps to
        the same target as before.
        """
        s = check_scalar(scale, "scale", positive=True)
        y = self._y
        o = self._offset
        d = self._scale - s
        self._offset = (o[0] + d * y[0], o[1] + d * y[1], o[2] + d * y[2])
        self._scale = s

    def estop(self) -> None:
        """Latch the e-stop: the robot brakes to rest and holds until :meth:`release`."""
        self._estop = True

    def release(self) -> None:
        """Release the e-stop; the master re-engages on its next sample (no tip jump)."""
        self._estop = False
        self._engaged = False

    def reset(self, q0: ArrayLike, *, slot: int = 0) -> None:
        """Restart at rest at a known configuration (as the constructor's ``q0``, ``slot``)."""
        q = check_array(q0, "q0", (3,))
        self._reset_state(self._tracker.reset(q, slot=slot))

    # --- helpers --------------------------------------------------------------------
    def _to_base(self, p: _V3) -> _V3:
        T = self._Tr
        return (T[0][0] * p[0] + T[0][1] * p[1] + T[0][2] * p[2] + T[0][3],
                T[1][0] * p[0] + T[1][1] * p[1] + T[1][2] * p[2] + T[1][3],
                T[2][0] * p[0] + T[2][1] * p[1] + T[2][2] * p[2] + T[2][3])

    def _to_e(self, p: _V3) -> _V3:
        T = self._Tr
        v = (p[0] - T[0][3], p[1] - T[1][3], p[2] - T[2][3])
        return (T[0][0] * v[0] + T[1][0] * v[1] + T[2][0] * v[2],
                T[0][1] * v[0] + T[1][1] * v[1] + T[2][1] * v[2],
                T[0][2] * v[0] + T[1][2] * v[1] + T[2][2] * v[2])

    def _depth(self, g: _V3) -> tuple[_V3, int]:
        r = math.sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
        lo, hi = self.depth
        if lo <= r <= hi:
            return g, 0
        if not r > 0.0:
            return self._tip, _DEPTH
        k = (lo if r < lo else hi) / r
        return (g[0] * k, g[1] * k, g[2] * k), _DEPTH

    def _fixture(self, g: _V3) -> tuple[_V3, int]:
        fx = self._fixtures
        if not self._has_fixtures:
            return g, 0
        m = self.options.fixture_margin
        x = self._to_base(g)
        flags = 0
        for _ in range(4):
            d, n, _i = fx.nearest(x)
            if d >= m:
                break
            flags = _FIXTURE
            k = m - d + 1e-9
            x = (x[0] + k * n[0], x[1] + k * n[1], x[2] + k * n[2])
        else:
            return self._tip, _FIXTURE
        if flags:
            g, f2 = self._depth(self._to_e(x))
            if f2:                      # the depth and the fixture disagree: no step
                return self._tip, flags | f2
        return g, flags

    def _soft_q(self, q: _V3, tip: _V3) -> int:
        """Stroke and fixture flags that ``q`` / ``tip`` break *and* worsen (0: acceptable)."""
        qc = self._q
        flags = 0
        for i in range(3):
            lo, hi = self._lo[i], self._hi[i]
            if not self._hard_lo[i] <= q[i] <= self._hard_hi[i]:
                flags |= _STROKE
            elif (q[i] < lo and q[i] < qc[i]) or (q[i] > hi and q[i] > qc[i]):
                flags |= _STROKE
        if self._has_fixtures:
            d, _, _ = self._fixtures.nearest(self._to_base(tip))
            dc, _, _ = self._fixtures.nearest(self._to_base(self._tip))
            if d < 0.0 or (d < self.options.fixture_margin and d < dc):
                flags |= _FIXTURE
        return flags

    def _soft(self, pose: Any) -> int:
        """Singular-set and clearance flags that ``pose`` breaks *and* worsens (0: acceptable)."""
        cur = self._pose
        flags = 0
        mg = self.margins
        link_max = self._link_max
        if ((pose.half_chord < mg.half_chord and pose.half_chord < cur.half_chord)
                or (pose.h < mg.h and pose.h < cur.h)
                or (link_max - pose.h < mg.link and link_max - pose.h < link_max - cur.h)
                or (pose.sin_u2 < mg.sin_u2 and pose.sin_u2 < cur.sin_u2)
                or (pose.sin_u4 < mg.sin_u4 and pose.sin_u4 < cur.sin_u4)
                or (abs(pose.p) < mg.p and abs(pose.p) < abs(cur.p))):
            flags |= _SINGULAR
        if self._clear_floor > -math.inf:
            # keep room to brake: the distance to stop from this step's speed, times a bound
            # on how much faster than the joints a body point moves (NaN clearance: reject)
            room = CLEARANCE_GAIN * self._stopping(pose.q)
            c = pose.clearance
            if not (c >= self._clear_floor + room
                    or (c >= cur.clearance and c >= self.options.clearance_margin + room)):
                flags |= _CLEARANCE
        return flags

    def _stopping(self, q: _V3) -> float:
        """Largest joint travel to brake at ``a_max`` from the step to ``q``, m."""
        rate = self.rate
        v = (abs(q[0] - self._q[0]) * rate, abs(q[1] - self._q[1]) * rate,
             abs(q[2] - self._q[2]) * rate)
        a = self.a_max
        t = max(v[0] / a[0], v[1] / a[1], v[2] / a[2])
        return 0.5 * t * max(v[0], v[1], v[2])

    def _probe(self, q: _V3) -> Any:
        """The tracked pose of ``q`` (the tracker advances; :meth:`_revert` undoes it)."""
        return self._tracker.update(q)

    def _revert(self) -> None:
        """Put the tracker back on the current command after a rejected probe."""
        tr = self._tracker
        pose = tr.update(self._q)
        if pose.slot != self._slot or not pose.valid:
            tr.reset(self._q, slot=self._slot)

    def _try(self, tip: _V3) -> tuple[Any, int]:
        """Pose and rejection flags of the step to ``tip`` (0: accept; the tracker is there)."""
        x, y, z, r = self._ik(tip[0], tip[1], tip[2])
        if r != 0:
            return None, _STROKE if r in _STROKE_REASONS else _SINGULAR
        f = self._soft_q((x, y, z), tip)
        if f:
            return None, f
        pose = self._probe((x, y, z))
        te = pose.tip_e
        if (not pose.valid or int(pose.flags) & _BRANCH_FLAGS        # int: IntFlag's & is slow
                or abs(te[0] - tip[0]) + abs(te[1] - tip[1]) + abs(te[2] - tip[2]) > BRANCH_TOL):
            self._revert()
            return None, _SINGULAR
        f = self._soft(pose)
        if f:
            self._revert()
            return None, f
        return pose, 0

    def _kin_ok(self, q: _V3) -> bool:
        """``q`` keeps every ``|qd_i| <= v_max_i`` and ``|qdd_i| <= a_max_i``."""
        rate = self.rate
        for i in range(3):
            v = (q[i] - self._q[i]) * rate
            if abs(v) > self.v_max[i] or abs(v - self._qd[i]) * rate > self.a_max[i]:
                return False
        return True

    # --- the cycle ------------------------------------------------------------------
    def step(self, t: float, master_position: ArrayLike | None, clutch: bool = True
             ) -> TeleopCommand:
        """One cycle: a master sample (or none) -> the command of this cycle.

        Parameters
        ----------
        t : float
            Time of the sample, s (for the watchdog; the cycle is ``1 / rate``).
        master_position : array-like, shape (3,), or None
            The master handle's position in the master's frame, m; None: no sample this
            cycle. A malformed or non-finite sample counts as none (flag ``INVALID``).
        clutch : bool
            True: the clutch is closed, the tip follows the master. False: the clutch is
            open (dVRK's "clutched"): the master moves freely, the tip holds, and on the
            next True the offset is recomputed so that the tip does not jump.

        Returns
        -------
        TeleopCommand
            Never raises: an internal error holds the robot with ``FAULT``.
        """
        try:
            return self._step(t, master_position, clutch)
        except Exception as exc:            # never raise inside the loop: flag and hold
            self.fault = exc
            try:
                self._tracker.reset(self._q, slot=self._slot)
            except Exception:  # pragma: no cover - the command was valid a cycle ago
                pass
            return self._brake(_FAULT | _HOLD, self._t)

    def _sample(self, t: float, m: object) -> tuple[float, _V3 | None, int]:
        """The cycle's time and the registered master position (None: no valid sample)."""
        flags = 0
        try:
            tt = float(t)
        except (TypeError, ValueError, OverflowError):
            tt = math.nan
        if not (math.isfinite(tt) and tt >= self._t):
            flags |= _INVALID
            tt = self._t + self.dt if math.isfinite(self._t) else 0.0
            if m is not None:
                return tt, None, flags
        if m is None:
            return tt, None, flags
        try:
            x, y, z = (float(m[0]), float(m[1]), float(m[2]))  # type: ignore[index]
            if len(m) != 3:  # type: ignore[arg-type]
                raise ValueError
        except (TypeError, ValueError, LookupError, OverflowError):
            return tt, None, flags | _INVALID
        if not (abs(x) <= MAX_MASTER_M and abs(y) <= MAX_MASTER_M and abs(z) <= MAX_MASTER_M):
            return tt, None, flags | _INVALID          # NaN, inf, or beyond any master
        R = self._R
        p = (R[0][0] * x + R[0][1] * y + R[0][2] * z, R[1][0] * x + R[1][1] * y + R[1][2] * z,
             R[2][0] * x + R[2][1] * y + R[2][2] * z)
        return tt, p, flags

    def _step(self, t: float, m: object, clutch: object) -> TeleopCommand:
        tt, p, flags = self._sample(t, m)
        self._t = tt
        closed = clutch is True or (clutch is not False and bool(clutch))
        if p is not None:
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
        elif tt - self._t_sample >= self._watchdog:
            flags |= _WATCHDOG
            self._hold = True
            self._engaged = False
        elif self._last_p is not None:
            # no sample this cycle (a master slower than the loop): the filter runs every
            # cycle on the master interpolated between its samples (_master_now)
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
        g, f = self._fixture(g)
        flags |= f
        if self._has_fixtures:
            g, f = self._slide(g)
            flags |= f
        return self._advance(g, flags, tt)

    def _master_now(self, tt: float) -> _V3:
        """The master's position that the filter takes at cycle time ``tt``.

        A master sampled every cycle: its latest sample. A slower one (samples more than
        1.5 cycles apart, 100 Hz on a 1 kHz loop): the straight line between its last two
        samples, one sample interval late, so that the filter sees a continuous, piecewise
        linear motion instead of a staircase whose every step would be a velocity jump of
        the command (the acceleration limit would then hold the robot at each sample).
        The delay is the master's own interval, and only where it exceeds the cycle.
        """
        lp, sp, dt = self._last_p, self._step_p, self._dt_p
        assert lp is not None
        if not dt > 1.5 * self.dt:
            return lp
        k = min(tt - self._t_sample, dt) / dt - 1.0        # in [-1, 0]: one interval late
        return (lp[0] + k * sp[0], lp[1] + k * sp[1], lp[2] + k * sp[2])

    def _slide(self, g: _V3) -> tuple[_V3, int]:
        """Near a forbidden region, drop the step's component into it (the tip slides)."""
        c = self._tip
        d, n, _ = self._fixtures.nearest(self._to_base(c))
        if not d < self.options.fixture_margin + SLIDE_BAND_M:
            return g, 0
        T = self._Tr                          # n in E: R^T n
        ne = (T[0][0] * n[0] + T[1][0] * n[1] + T[2][0] * n[2],
              T[0][1] * n[0] + T[1][1] * n[1] + T[2][1] * n[2],
              T[0][2] * n[0] + T[1][2] * n[1] + T[2][2] * n[2])
        dx = (g[0] - c[0], g[1] - c[1], g[2] - c[2])
        k = dx[0] * ne[0] + dx[1] * ne[1] + dx[2] * ne[2]
        if k >= 0.0:
            return g, 0
        g2 = (g[0] - k * ne[0], g[1] - k * ne[1], g[2] - k * ne[2])
        g2, f = self._depth(g2)
        return g2, _FIXTURE | f

    def _advance(self, g: _V3, flags: int, tt: float) -> TeleopCommand:
        """The longest safe step from the current tip toward ``g``, or a brake."""
        c, q = self._tip, self._q
        dx = (g[0] - c[0], g[1] - c[1], g[2] - c[2])
        ell = math.sqrt(dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2])
        if ell == 0.0:
            J = (0.0, 0.0, 0.0)
            u = (0.0, 0.0, 0.0)
        else:
            u = (dx[0] / ell, dx[1] / ell, dx[2] / ell)
            h = min(ell, PROBE_M)
            x1, x2, x3, r = self._ik(c[0] + h * u[0], c[1] + h * u[1], c[2] + h * u[2])
            if r != 0:
                return self._brake(flags | (_STROKE if r in _STROKE_REASONS
                                            else _SINGULAR), tt)
            J = ((x1 - q[0]) / h, (x2 - q[1]) / h, (x3 - q[2]) / h)
        gp = self._goal
        vg = max(0.0, (g[0] - gp[0]) * u[0] + (g[1] - gp[1]) * u[1] + (g[2] - gp[2]) * u[2])
        self._goal = g
        lo, hi, bind = self._bounds(J, ell, vg)
        if lo > hi:
            return self._brake(flags | _ACCELERATION, tt)
        if hi < ell:
            flags |= bind
        if hi <= 0.0:                          # no step: stop here (|v_i| <= a_max_i dt)
            return self._stay(flags, tt)
        s = hi
        reject = 0
        secants = 0
        for _ in range(BISECTIONS):
            tip = (c[0] + s * u[0], c[1] + s * u[1], c[2] + s * u[2])
            pose, f = self._try(tip)
            if pose is not None:
                if self._kin_ok(pose.q):
                    return self._accept(pose, tip, flags | reject, tt)
                self._revert()                 # curvature: the secant of this step
                pq = pose.q
                Js = ((pq[0] - q[0]) / s, (pq[1] - q[1]) / s, (pq[2] - q[2]) / s)
                lo2, hi2, _b = self._bounds(Js, ell, vg)
                if secants < SECANTS and lo2 <= hi2 and 0.0 < hi2 < s:
                    secants += 1
                    s = hi2
                    continue
                f = bind or _VELOCITY
            reject |= f
            s = lo + 0.5 * (s - lo)
        return self._brake(flags | reject, tt)

    def _bounds(self, J: _V3, ell: float, vg: float) -> tuple[float, float, int]:
        """Step lengths ``s`` (m along the tip's direction) within the limits, linear in ``J``.

        ``J``: joint metres per tip metre along the direction; ``ell``: distance to the
        target; ``vg``: the target's advance along the direction this cycle (m).
        Returns ``(lo, hi, the flag of the binding limit)``; ``lo > hi``: none.
        """
        dt = self.dt
        v = self._qd
        lo, hi = 0.0, ell
        bind = 0
        v_aim, a_aim = self._v_aim, self._a_aim
        for i in range(3):
            Ji = J[i]
            vm, am = v_aim[i], a_aim[i]
            if abs(Ji) * ell > 1e-15:
                aJ = abs(Ji)
                sv = vm * dt / aJ
                if sv < hi:
                    hi, bind = sv, _VELOCITY
                # approach: the joint can still stop at the (moving) target at a_max
                adt = am * dt
                w = adt * (math.sqrt(0.25 + 2.0 * aJ * ell / (adt * dt)) - 0.5)
                sa = vg + w * dt / aJ
                if sa < hi:
                    hi, bind = sa, _ACCELERATION
                s1 = (v[i] - adt) * dt / Ji
                s2 = (v[i] + adt) * dt / Ji
                a, b = (s1, s2) if s1 <= s2 else (s2, s1)
                if b < hi:
                    hi, bind = b, _ACCELERATION
                if a > lo:
                    lo = a
            elif abs(v[i]) > am * dt:
                lo = math.inf
        return lo, hi, bind

    def _accept(self, pose: Any, tip: _V3, flags: int, tt: float) -> TeleopCommand:
        rate = self.rate
        q = pose.q
        qd = ((q[0] - self._q[0]) * rate, (q[1] - self._q[1]) * rate,
              (q[2] - self._q[2]) * rate)
        qdd = ((qd[0] - self._qd[0]) * rate, (qd[1] - self._qd[1]) * rate,
               (qd[2] - self._qd[2]) * rate)
        self._q, self._qd, self._qdd = q, qd, qdd
        self._tip, self._pose, self._slot = tip, pose, pose.slot
        return self._command(tt, flags)

    def _stay(self, flags: int, tt: float) -> TeleopCommand:
        """Come to rest at the current command (every ``|qd_i| <= a_max_i dt``)."""
        rate = self.rate
        self._qdd = (-self._qd[0] * rate, -self._qd[1] * rate, -self._qd[2] * rate)
        self._qd = (0.0, 0.0, 0.0)
        return self._command(tt, flags)

    def _brake(self, flags: int, tt: float) -> TeleopCommand:
        """Decelerate along the current velocity at ``a_max`` (rest: hold)."""
        flags |= _HOLD
        v = self._qd
        f = 1.0
        for i in range(3):
            if v[i] != 0.0:
                f = min(f, self._a_aim[i] * self.dt / abs(v[i]))
        f = max(0.0, 1.0 - f) if v != (0.0, 0.0, 0.0) else 0.0
        q0 = self._q
        if f > 0.0:
            qd = (f * v[0], f * v[1], f * v[2])
            q = (q0[0] + qd[0] * self.dt, q0[1] + qd[1] * self.dt, q0[2] + qd[2] * self.dt)
            pose = self._probe(q)
            ok = pose.valid and all(lo <= x <= hi for lo, x, hi in
                                    zip(self._hard_lo, q, self._hard_hi, strict=True))
            if ok and self._has_fixtures:
                ok = self._fixtures.nearest(self._to_base(pose.tip_e))[0] >= 0.0
            if ok and self._clear_floor > -math.inf:
                ok = pose.clearance >= self.options.clearance_margin
            if ok:
                return self._accept(pose, tuple(pose.tip_e), flags, tt)
            self._revert()                     # a hard limit: stop now (flagged)
            flags |= _ACCELERATION
        return self._stay(flags, tt)

    def _command(self, tt: float, flags: int) -> TeleopCommand:
        forces = _NAN3
        if self._masses is not None:
            forces = self._forces()
        st = _STATUSES.get(flags)
        if st is None:
            st = _status(flags)
        return TeleopCommand(tt, self._q, self._qd, self._qdd, forces, self._tip, self._target,
                             st, self._slot, self._pose.clearance)

    def _forces(self) -> _V3:
        key = (self._q, self._qd, self._qdd, self._slot)
        if key == self._ff_key:                # at rest or held: the same state, same forces
            return self._ff
        self._ff_key = key
        loop = self._ff_loops.get(self._slot)
        if loop is None:
            from ..dynamics import InverseDynamicsLoop

            loop = self._ff_loops[self._slot] = InverseDynamicsLoop(
                self.T_b_e, self.design, masses=self._masses, gravity=self._gravity,
                slot=self._slot, backend=self._backend)
        f = loop(self._q, self._qd, self._qdd)  # NaN on a singular set: no feed-forward
        f0, f1, f2 = f.tolist()
        self._ff = (f0, f1, f2)
        return self._ff


_NAN3 = (math.nan, math.nan, math.nan)
#: The TeleopStatus of each combination of bits met so far (at most 2^14): building an
#: IntFlag from an int costs about a microsecond, a dict look-up a few tens of ns.
_STATUSES: dict[int, TeleopStatus] = {0: TeleopStatus.NONE}


def _status(flags: int) -> TeleopStatus:
    st = _STATUSES[flags] = TeleopStatus(flags)
    return st


def _check_margins(opts: TeleopOptions, design: Design, stopping: float) -> tuple[float, float]:
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


def _feedforward_model(opts: TeleopOptions, design: Design) -> tuple[Any, Any]:
    """Mass model and gravity (base frame, m/s^2) of the feed-forward.

    ``(None, None)`` with ``feedforward=False``.
    """
    if not opts.feedforward:
        return None, None
    from ..dynamics import STANDARD_GRAVITY, MassModel

    masses = opts.masses if opts.masses is not None else MassModel.reference(design)
    if not isinstance(masses, MassModel):
        raise TypeError(f"masses: expected athenakin.dynamics.MassModel, got "
                        f"{type(masses).__name__}")
    gravity = np.array(STANDARD_GRAVITY if opts.gravity is None else opts.gravity, dtype=float)
    return masses, gravity


def _branch_flags() -> int:
    from ..motion import TrackFlag

    return int(TrackFlag.LOST | TrackFlag.MODE_SWITCH | TrackFlag.BRANCH_SWITCH
               | TrackFlag.JUMP)


_BRANCH_FLAGS = _branch_flags()
