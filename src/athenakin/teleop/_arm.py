"""The arm: CRTK's commands over a servo loop and a backend (MuJoCo by default) (private).

:class:`SimulatedArm` is the robot as a lab drives it: CRTK's names (``measured_js``,
``setpoint_js``, ``measured_cp``, ``servo_jp``, ``servo_cp``, ``move_jp``, ``move_cp``,
``hold``, ``enable``, ``disable``, ``pause``, ``resume``, ``home``, operating states), a
PD + feed-forward servo on the three actuators at ``rate`` Hz
(:mod:`~athenakin.teleop._servo`), and a backend that reads the encoders and applies the
forces (:mod:`~athenakin.teleop._arm_backend`: :class:`MujocoBackend` by default, a real
robot through :class:`ArmBackend`'s two methods).

The arm refuses what the teleoperation core refuses (:mod:`~athenakin.teleop._arm_checks`).
A servo command (``servo_jp``, ``servo_cp``) outside the strokes, with the carriages' order
reversed, off the FK slot's workspace, not finite, with a velocity above ``v_max``, an
effort or an inverse dynamics above ``max_force`` is *held and flagged*: the setpoint stays
where the last accepted command put it (at rest) and :attr:`SimulatedArm.refusal` names the
reason; it never raises for a value, as a real-time loop must not. A planned move
(``move_jp``, ``move_cp``, a Ruckig profile: :mod:`~athenakin.teleop._move_profile`)
outside the strokes raises a named error, as a planning call may. The servo approaches a
far setpoint at ``v_max`` and its force is saturated at ``max_force`` per actuator.
A reading of the encoders of the wrong shape, not finite, beyond the strokes by more than
:data:`~athenakin.teleop._arm_checks.READING_MARGIN` or faster than
:data:`~athenakin.teleop._arm_checks.READING_SPEED_MAX`, and a fault of the backend
(MuJoCo's instability, a loop-closure error above
:data:`~athenakin.teleop._arm_backend.CLOSURE_TOL`) put the arm in ``FAULT`` in the cycle
they occur, with :attr:`SimulatedArm.fault` naming the reason; ``FAULT`` and ``DISABLED``
write no force.

Frames and units: joints in m, m/s, N; Cartesian poses are the tool-tip frame in the
base frame (``T_b_tip``, SI); :meth:`SimulatedArm.servo_cp` and
:meth:`SimulatedArm.move_cp` take the tip position in the base frame (``frame="base"``)
or in the RCM frame E (``frame="rcm"``); the instrument's direction follows from the
RCM, so a pose's rotation is not used.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from .._robot_model import resolve_robot
from .._typing import FloatArray
from .._validation import check_count, check_scalar
from ..design import Design
from ..errors import InvalidInputError
from ._arm_backend import ArmBackend, MujocoBackend
from ._arm_checks import (
    TipFrames,
    command_refusal,
    position_refusal,
    q_from_tip,
    read_encoders,
    vector3,
)
from ._crtk import OPERATING_STATES, JointState
from ._filter import check_rate
from ._move_profile import move_profile, profile_at
from ._servo import MAX_FORCE, ServoGains, approach_gain, pd_force, servo_gains

__all__ = ["JointState", "SimulatedArm", "OPERATING_STATES", "MAX_STEPS"]

#: Most servo cycles one :meth:`SimulatedArm.step` call runs.
MAX_STEPS = 1_000_000


class SimulatedArm:
    """ATHENA under a PD + feed-forward servo, with CRTK's commands; MuJoCo by default.

    Parameters
    ----------
    robot : athenakin.Robot or array-like, shape (4, 4)
        The model (its design, RCM frame and masses), or the RCM frame E in the base
        frame ``T_b_e`` with ``design``.
    design : Design, optional
        With a ``T_b_e`` only (default :meth:`Design.default`).
    masses : athenakin.dynamics.MassModel, optional, keyword-only
        Default the robot's, else ``MassModel.reference(design)``: the simulated robot,
        the derived gains and the feed-forward use the same model. Beside a Robot only
        when it has no masses of its own (:func:`athenakin._robot_model.resolve_robot`).
    rate : float, keyword-only
        Servo cycles per second, Hz (1000; 10 Hz or faster with the MuJoCo backend).
    q0 : array-like, shape (3,), optional, keyword-only
        Where the robot stands at start, m (default :data:`athenakin.robot.REFERENCE_Q`):
        within the strokes, in the carriages' order, assembled in ``slot``.
    slot : int, keyword-only
        Its forward-kinematics slot (0).
    gains : ServoGains, optional, keyword-only
        Explicit PD gains (checked for stability at ``rate``); default derived from the
        mass matrix at ``q0`` and the rate (:func:`athenakin.teleop._servo.servo_gains`):
        ``omega = min(BANDWIDTH, BANDWIDTH_PER_RATE rate)``, ``Kp = omega^2 M``,
        ``Kd = 2 omega M`` (critically damped).
    feedforward : bool, keyword-only
        Add the inverse dynamics of the setpoint (:class:`athenakin.dynamics.InverseDynamicsLoop`)
        to the PD forces (True); False: PD only.
    backend : ArmBackend, optional, keyword-only
        A robot driver; default a :class:`MujocoBackend` of the exported MJCF.
    v_max, a_max, j_max : float, keyword-only
        Limits of ``move_jp`` / ``move_cp`` (Ruckig): m/s, m/s^2, m/s^3; ``v_max`` also
        bounds a servo command's velocity and a move's goal velocity (beyond: refused).
    max_force : float, keyword-only
        Saturation of the servo's force per actuator, and the largest effort a servo
        command may carry, N (:data:`~athenakin.teleop._servo.MAX_FORCE`).

    Raises
    ------
    InvalidInputError, TypeError
        A bad argument (named); a design beside a Robot, or masses beside a Robot that
        has its own (TypeError); ``q0`` outside the strokes, in the wrong carriage order
        or not assembled in ``slot``; a mass matrix at ``q0`` with an eigenvalue below
        :data:`~athenakin.teleop._servo.MIN_MODAL_MASS` (``MassModel.zeros()``: no servo
        can be designed for it); explicit gains whose sampled loop is unstable at ``rate``.

    Notes
    -----
    CRTK's operating states: the arm starts ``DISABLED`` (motor power off: it writes no
    force, the brakes hold); :meth:`enable` powers it (from ``DISABLED`` or ``FAULT``),
    :meth:`pause` / :meth:`resume` hold and release it, :meth:`disable` cuts the power.
    Commands are accepted in ``ENABLED`` once :attr:`is_homed`; otherwise they are held
    and flagged (:attr:`refusal`).

    Examples
    --------
    >>> import athenakin as ak
    >>> from athenakin.teleop import SimulatedArm
    >>> arm = SimulatedArm(ak.Robot.default(), q0=[-0.1, 0.1, 0.45])
    >>> arm.operating_state
    'DISABLED'
    >>> arm.enable()
    >>> arm.operating_state, arm.is_homed
    ('ENABLED', True)
    >>> arm.step(5)
    >>> bool(abs(arm.measured_js().position - [-0.1, 0.1, 0.45]).max() < 1e-4)
    True
    >>> arm.servo_jp([-0.1, 0.1, 0.9])        # q3 beyond its stroke: held and flagged
    >>> arm.refusal
    'q: [-0.1, 0.1, 0.9] m is outside the stroke limits'
    """

    def __init__(self, robot: Any, design: Design | None = None, *, masses: Any = None,
                 rate: float = 1000.0, q0: ArrayLike | None = None, slot: int = 0,
                 gains: ServoGains | None = None, feedforward: bool = True,
                 backend: ArmBackend | None = None, v_max: float = 0.1, a_max: float = 1.0,
                 j_max: float = 20.0, max_force: float = MAX_FORCE) -> None:
        from .._validation import check_slot
        from ..dynamics import InverseDynamicsLoop, MassModel
        from ..robot import REFERENCE_Q

        model = resolve_robot(robot, design, masses=masses)
        design = model.design
        self.design, self.T_b_e = design, model.T_b_e
        self.rate = check_rate(rate)
        self.dt = 1.0 / self.rate
        self.masses = MassModel.reference(design) if model.masses is None else model.masses
        if gains is not None and not isinstance(gains, ServoGains):
            raise TypeError(f"gains: expected ServoGains, got {type(gains).__name__}")
        if not isinstance(feedforward, bool):
            raise TypeError(f"feedforward: expected a bool, got {type(feedforward).__name__}")
        self.feedforward = feedforward
        self.limits: tuple[float, float, float] = (
            check_scalar(v_max, "v_max", positive=True),
            check_scalar(a_max, "a_max", positive=True),
            check_scalar(j_max, "j_max", positive=True))
        self.max_force = check_scalar(max_force, "max_force", positive=True)
        self.slot = check_slot(slot)
        self._lo = np.asarray(design.stroke_min, dtype=float)
        self._hi = np.asarray(design.stroke_max, dtype=float)
        q = vector3(REFERENCE_Q if q0 is None else q0, "q0")
        why = position_refusal(q, design, "q0")
        if why is not None:
            raise InvalidInputError(why)
        self._ff_loop = InverseDynamicsLoop(self.T_b_e, design, masses=self.masses,
                                            slot=self.slot)
        self._tip_frame = TipFrames(self.T_b_e, design, self.slot)
        if np.isnan(self._ff_loop(q, np.zeros(3), np.zeros(3))).any():
            raise InvalidInputError(f"q0: {q.tolist()} m does not assemble in FK slot "
                                    f"{self.slot}")
        # servo_cp's IK compiled (or loaded from numba's cache) now, not in a command's cycle
        q_from_tip(self._tip_frame(q), "base", self.T_b_e, design)
        self.gains = gains
        self.kp, self.kd = servo_gains(q, self.T_b_e, design, self.masses, self.slot,
                                       self.rate, gains)
        self._approach = approach_gain(self.kp, self.kd)
        if backend is None:
            backend = MujocoBackend(self.T_b_e, design, q, self.slot, self.masses, self.rate)
        elif not isinstance(backend, ArmBackend):
            raise TypeError("backend: expected an ArmBackend (read_encoders() and write())")
        self.backend = backend
        self._backend_fault = getattr(backend, "fault", None)
        self._backend_home = getattr(backend, "home", None)
        self.t = 0.0
        self._t_set = 0.0                # the arm's time when the setpoint was last set, s
        self._acc_end: float | None = None   # when a servo command's acceleration ends, s
        self._ff_given = False           # the feed-forward is a command's effort
        self._zero = np.zeros(3)
        self._nan = np.full(3, np.nan)
        self._sp_q = q.copy()
        self._sp_qd = np.zeros(3)
        self._sp_qdd = np.zeros(3)
        self._ff = np.zeros(3)           # the feed-forward of the setpoint, N
        self._force = np.zeros(3)        # the force applied in the last cycle, N
        self._q_meas, self._qd_meas = q.copy(), np.zeros(3)
        self._move: Any = None
        self._move_t0 = 0.0
        self._state = "DISABLED"
        self._homed = self._backend_home is None      # absolute encoders: homed
        self.fault: str | None = None
        self.refusal: str | None = None
        self.saturated = False
        why = self._read()
        if why is not None:
            raise InvalidInputError(f"backend: {why} at start")
        self._set_hold()

    # --- CRTK state -----------------------------------------------------------------
    @property
    def operating_state(self) -> str:
        """CRTK operating state: ``"DISABLED"``, ``"ENABLED"``, ``"PAUSED"`` or ``"FAULT"``."""
        return self._state

    @property
    def is_busy(self) -> bool:
        """A ``move_jp`` / ``move_cp`` is under way (CRTK's ``is_busy``)."""
        return self._move is not None

    @property
    def is_homed(self) -> bool:
        """The encoders are referenced (CRTK's ``is_homed``).

        True from the start for a backend without ``home()`` (absolute encoders: MuJoCo);
        else after :meth:`home`.
        """
        return self._homed

    @property
    def feedforward_effort(self) -> FloatArray:
        """The feed-forward of the current setpoint (N, shape (3,)), before the PD terms."""
        return self._ff.copy()

    def enable(self) -> None:
        """Power the servo: ``DISABLED`` or ``FAULT`` -> ``ENABLED``, holding where it is.

        From ``FAULT`` the fault is cleared once the encoders read sound again (else the
        arm stays in ``FAULT`` with the new reason). ``PAUSED`` is left by :meth:`resume`
        only (CRTK); ``enable()`` there changes nothing.
        """
        if self._state not in ("DISABLED", "FAULT"):
            return
        why = self._check_backend()
        if why is not None:
            self._to_fault(why)
            return
        self._move = None
        self._set_hold()
        self._state, self.fault = "ENABLED", None

    def disable(self) -> None:
        """Cut the motor power (any state -> ``DISABLED``): no force is written, brakes on."""
        self._move = None
        self._state = "DISABLED"

    def pause(self) -> None:
        """``ENABLED`` -> ``PAUSED``: hold the measured position and refuse commands."""
        if self._state == "ENABLED":
            self._move = None
            self._set_hold()
            self._state = "PAUSED"

    def resume(self) -> None:
        """``PAUSED`` -> ``ENABLED``: accept commands again, from the held position."""
        if self._state == "PAUSED":
            self._state = "ENABLED"

    def home(self) -> None:
        """Reference the encoders (CRTK's ``home``): the backend's ``home()`` where it has one.

        Only in ``ENABLED``; elsewhere the command is refused (:attr:`refusal`).
        """
        if self._state != "ENABLED":
            self.refusal = f"home: the arm is {self._state}; enable() first"
            return
        if self._backend_home is not None:
            self._backend_home()
            why = self._read()
            if why is not None:
                self._to_fault(why)
                return
            self._set_hold()
        self._homed = True
        self.refusal = None

    def unhome(self) -> None:
        """Forget the homing (CRTK's ``unhome``): commands are refused until :meth:`home`."""
        self._homed = False

    def hold(self) -> None:
        """Stop any motion: the setpoint becomes the measured position at rest."""
        self._move = None
        self._set_hold()

    def _set_hold(self) -> None:
        self._set(self._q_meas, self._zero, self._zero, None, hold=True)

    def _to_fault(self, why: str) -> None:
        self._state, self.fault = "FAULT", why
        self._move = None

    def _accepting(self, what: str) -> bool:
        if self._state != "ENABLED":
            self.refusal = f"{what}: the arm is {self._state}"
            return False
        if not self._homed:
            self.refusal = f"{what}: the arm is not homed; home() first"
            return False
        return True

    # --- CRTK queries ---------------------------------------------------------------
    def measured_js(self) -> JointState:
        """The encoders' last sound reading and the force applied in the last cycle.

        Returns
        -------
        JointState
            Positions (m), velocities (m/s), applied forces (N; zero in ``DISABLED`` and
            ``FAULT``).
        """
        return JointState(self.t, self._q_meas.copy(), self._qd_meas.copy(),
                          self._force.copy())

    def setpoint_js(self) -> JointState:
        """The servo's setpoint and the effort it applied (CRTK).

        Returns
        -------
        JointState
            Setpoint positions (m) and velocities (m/s); ``effort``: the force applied in
            the last cycle (PD + feed-forward, saturated; N). The feed-forward alone is
            :attr:`feedforward_effort`.
        """
        return JointState(self.t, self._sp_q.copy(), self._sp_qd.copy(), self._force.copy())

    def measured_cp(self) -> FloatArray:
        """The tool-tip frame in the base frame from the encoders, ``T_b_tip`` (4, 4), SI.

        Forward kinematics of the last sound reading on :attr:`slot` (rotation: the
        instrument's frame at the tip, :attr:`athenakin.FKSolution.T_b_tip`). No side
        effect.

        Returns
        -------
        ndarray, shape (4, 4)
            NaN where the reading does not assemble in the slot.
        """
        return self._tip_frame(self._q_meas)

    def setpoint_cp(self) -> FloatArray:
        """The setpoint's tool-tip frame in the base frame.

        Returns
        -------
        ndarray, shape (4, 4)
        """
        return self._tip_frame(self._sp_q)

    # --- CRTK commands --------------------------------------------------------------
    def servo_jp(self, q: ArrayLike, velocity: ArrayLike | None = None,
                 effort: ArrayLike | None = None) -> None:
        """Servo to joint positions now, with velocity and effort feed-forward.

        Without ``effort`` the feed-forward is the inverse dynamics of ``q``, ``velocity``
        and the acceleration differenced from the previous setpoint's velocity (when
        ``feedforward``); ``effort`` replaces it. A command the arm refuses is held and
        flagged: the setpoint stays at the last accepted position, at rest, and
        :attr:`refusal` names why (None after an accepted command).

        Parameters
        ----------
        q : array-like, shape (3,)
            Actuator positions, m: within the strokes, in the carriages' order, assembled
            in :attr:`slot`.
        velocity : array-like, shape (3,), optional
            m/s, each within ``v_max`` (default rest).
        effort : array-like, shape (3,), optional
            Feed-forward forces, N, each within ``max_force``.

        Raises
        ------
        InvalidInputError
            An argument of the wrong shape (a programming error, not a value).
        """
        qa = self._vector(q, "q")
        v = self._zero if velocity is None else self._vector(velocity, "velocity")
        e = None if effort is None else self._vector(effort, "effort")
        if not self._accepting("servo_jp"):
            return
        why = command_refusal(qa, v, self.design, velocity_name="velocity",
                              v_max=self.limits[0], effort=e, max_force=self.max_force)
        # the acceleration: differenced over the time since the setpoint was set (one cycle
        # at least) and applied for as long (then the feed-forward of qdd = 0)
        span = max(self.t - self._t_set, self.dt)
        if why is None:
            acc = (v - self._sp_qd) / span if velocity is not None else self._zero
            why = self._set(qa, v, acc, e)
        if why is not None:
            self._refuse(why)
            return
        self._acc_end = self.t + span - 0.5 * self.dt if velocity is not None else None
        self._move = None
        self.refusal = None

    def servo_cp(self, tip: ArrayLike, *, frame: Literal["base", "rcm"] = "base") -> None:
        """Servo the tool tip to a position now (exact IK, ``q_from_tool_tip``).

        A tip the IK cannot reach is held and flagged (:attr:`refusal`), as
        :meth:`servo_jp` holds its refusals.

        Parameters
        ----------
        tip : array-like, shape (3,) or (4, 4)
            Tip position (m), or a pose whose translation is taken, in ``frame``.
        frame : {"base", "rcm"}, keyword-only

        Raises
        ------
        InvalidInputError, ValueError
            A tip of the wrong shape; a ``frame`` not in the list.
        """
        q, why = q_from_tip(tip, frame, self.T_b_e, self.design)
        if why is not None:
            if self._accepting("servo_cp"):
                self._refuse(why)
            return
        self.servo_jp(q)

    def move_jp(self, q: ArrayLike, goal_velocity: ArrayLike | None = None) -> None:
        """Move to joint positions (m) along a time-optimal jerk-limited profile (Ruckig).

        The profile runs over the next :meth:`step` calls; :attr:`is_busy` until it ends.
        Outside ``ENABLED`` (or not homed) the command is refused (:attr:`refusal`).

        Parameters
        ----------
        q : array-like, shape (3,)
            Goal, m: within the strokes, in the carriages' order, assembled in :attr:`slot`.
        goal_velocity : array-like, shape (3,), optional
            Velocity at arrival, m/s, each within ``v_max`` (default rest).

        Raises
        ------
        InvalidInputError
            A goal of the wrong shape, not finite, outside the strokes or the carriages'
            order, or off the slot's workspace; a goal velocity not finite or beyond
            ``v_max``.
        KinematicsError
            Ruckig finds no profile, or fails (its error named).
        ModuleNotFoundError
            ruckig is not installed (extra ``motion``).
        """
        qa = self._vector(q, "q")
        gv = self._zero if goal_velocity is None else self._vector(goal_velocity,
                                                                    "goal_velocity")
        why = command_refusal(qa, gv, self.design, velocity_name="goal_velocity",
                              v_max=self.limits[0])
        if why is None and np.isnan(self._ff_loop(qa, gv, self._zero)).any():
            why = f"q: {qa.tolist()} m does not assemble in FK slot {self.slot}"
        if why is not None:
            raise InvalidInputError(why)
        if not self._accepting("move_jp"):
            return
        traj = move_profile(self._sp_q, self._sp_qd, self._sp_qdd, qa, gv, self.limits)
        self._move, self._move_t0 = traj, self.t
        self.refusal = None

    def move_cp(self, tip: ArrayLike, *, frame: Literal["base", "rcm"] = "base") -> None:
        """Move the tool tip to a position (exact IK, then :meth:`move_jp`).

        Parameters
        ----------
        tip : array-like, shape (3,) or (4, 4)
            Tip position (m), or a pose whose translation is taken, in ``frame``.
        frame : {"base", "rcm"}, keyword-only

        Raises
        ------
        InvalidInputError, KinematicsError
            The tip out of reach, or as :meth:`move_jp`.
        """
        q, why = q_from_tip(tip, frame, self.T_b_e, self.design)
        if why is not None:
            raise InvalidInputError(why)
        self.move_jp(q)

    # --- refusals ------------------------------------------------------------------
    @staticmethod
    def _vector(x: ArrayLike, name: str) -> FloatArray:
        """``x`` as a float array of shape (3,) (NaN kept: a value); a named error otherwise."""
        return vector3(x, name, allow_nonfinite=True)

    def _refuse(self, why: str) -> None:
        """Hold the last accepted position at rest and flag ``why``."""
        self.refusal = why
        self._move = None
        if np.any(self._sp_qd != 0.0) or np.any(self._sp_qdd != 0.0):
            self._set(self._sp_q, self._zero, self._zero, None, hold=True)

    # --- the servo loop -------------------------------------------------------------
    def _set(self, q: FloatArray, qd: FloatArray, qdd: FloatArray,
             effort: FloatArray | None, *, hold: bool = False) -> str | None:
        """Take the setpoint and its feed-forward; the reason it is refused, or None.

        A command's setpoint whose inverse dynamics exceeds ``max_force`` is refused (the
        actuators cannot follow it: near a singular set of the dynamics, or an acceleration
        beyond them); a hold (``hold``: at rest, the safe action) is always taken.
        """
        ff = self._ff_loop(q, qd, qdd)
        if np.isnan(ff).any():
            return f"q: {np.asarray(q).tolist()} m does not assemble in FK slot {self.slot}"
        if not hold and not np.all(np.abs(ff) <= self.max_force):
            return (f"q: following this setpoint takes {np.round(ff, 1).tolist()} N "
                    f"(inverse dynamics), beyond max_force {self.max_force:g} N")
        self._sp_q, self._sp_qd, self._sp_qdd = (np.array(x, dtype=float) for x in (q, qd, qdd))
        self._t_set, self._acc_end, self._ff_given = self.t, None, effort is not None
        chosen = effort if effort is not None else ff if self.feedforward else self._zero
        self._ff = np.array(chosen, dtype=float)
        return None

    def _end_acceleration(self) -> None:
        """The servo command's acceleration has been applied for its span: qdd = 0 now."""
        self._acc_end = None
        self._sp_qdd = self._zero.copy()
        if self.feedforward and not self._ff_given:
            self._ff = np.array(self._ff_loop(self._sp_q, self._sp_qd, self._zero), dtype=float)

    def _read(self) -> str | None:
        """Read the encoders; keep a sound reading, else the reason it is not."""
        reading, why = read_encoders(self.backend, self._lo, self._hi)
        if reading is not None:
            self._q_meas, self._qd_meas = reading
        return why

    def _check_backend(self) -> str | None:
        """The backend's fault (asked first), else the reason its reading is not sound."""
        why = None if self._backend_fault is None else self._backend_fault()
        bad = self._read()
        return why or bad

    def step(self, n: int = 1) -> None:
        """Advance ``n`` servo cycles of ``1 / rate`` s (servo, write, read, check).

        In ``ENABLED`` and ``PAUSED`` the servo writes ``ff + Kp (q_sp - q) + Kd (qd_sp -
        qd)``, its approach velocity bounded by ``v_max`` and the PD force scaled until each
        component is within ``max_force`` (:func:`~athenakin.teleop._servo.pd_force`;
        :attr:`saturated`); in
        ``DISABLED`` and ``FAULT`` it writes zero forces and NaN positions. After the
        write the encoders are read and checked, and the backend asked for a fault: a
        bad reading or a fault puts the arm in ``FAULT`` in that cycle.

        Parameters
        ----------
        n : int
            Cycles, 0 to :data:`MAX_STEPS`.

        Raises
        ------
        InvalidInputError
            ``n`` not an integer in that range.
        """
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
            raise InvalidInputError(f"n: expected an integer number of cycles, got {n!r:.80}")
        n = check_count(n, "n", minimum=0, maximum=MAX_STEPS)
        lim = self.max_force
        for _ in range(n):
            if self._move is not None:
                self._advance_move()
            if self._state in ("ENABLED", "PAUSED"):
                f, self.saturated = pd_force(self._ff, self.kp, self.kd, self._sp_q,
                                             self._sp_qd, self._q_meas, self._qd_meas, lim,
                                             L=self._approach, v_max=self.limits[0])
                positions = self._sp_q
            else:
                f, positions, self.saturated = self._zero.copy(), self._nan, False
            self._force = f
            self.backend.write(f, positions)
            self.t += self.dt
            if self._acc_end is not None and self.t >= self._acc_end:
                self._end_acceleration()
            why = self._check_backend()
            if why is not None and self._state != "FAULT":
                self._to_fault(why)

    def _advance_move(self) -> None:
        p, v, a, done = profile_at(self._move, self.t + self.dt - self._move_t0)
        why = self._set(p, v, a, None)
        if why is not None:
            self.refusal = f"move_jp: stopped, the profile cannot be followed ({why})"
            self._move = None
            self._set_hold()
        elif done:
            self._move = None
