"""The arm: CRTK's commands over a servo loop and a backend (MuJoCo by default) (private).

:class:`SimulatedArm` is the robot as a lab drives it: CRTK's names (``measured_js``,
``setpoint_js``, ``measured_cp``, ``servo_jp``, ``servo_cp``, ``move_jp``, ``move_cp``,
``hold``, ``enable``, ``disable``, operating states), a PD + feed-forward servo on the
three actuators at ``rate`` Hz, and a backend that reads the encoders and applies the
forces. The embedded default is :class:`MujocoBackend`: the exported MJCF
(:func:`athenakin.sim.mjcf_from_design` with ``masses=``: the mass model's inertias,
force motors, the loops closed by equality constraints) stepped by MuJoCo. A real
robot plugs in through :class:`ArmBackend`'s two methods.

Frames and units: joints in m, m/s, N; Cartesian poses are the tool-tip frame in the
base frame (``T_b_tip``, SI); :meth:`SimulatedArm.servo_cp` and
:meth:`SimulatedArm.move_cp` take the tip position in the base frame (``frame="base"``)
or in the RCM frame E (``frame="rcm"``); the instrument's direction follows from the
RCM, so a pose's rotation is not used.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Literal, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from .._validation import check_array, check_choice, check_count, check_frame, check_scalar
from ..design import Design, resolve_design
from ..errors import InvalidInputError, KinematicsError
from ._filter import check_rate

__all__ = ["ArmBackend", "JointState", "MujocoBackend", "ServoGains", "SimulatedArm",
           "OPERATING_STATES"]

#: CRTK operating states.
OPERATING_STATES = ("DISABLED", "ENABLED", "PAUSED", "FAULT")


@runtime_checkable
class ArmBackend(Protocol):
    """What a robot driver provides to :class:`SimulatedArm`: two methods.

    ``read_encoders()`` returns the actuators' positions (m) and velocities (m/s), each
    a float array of shape (3,). ``write(forces, positions)`` sends this cycle's
    commands: the actuator forces of the servo (N, PD + feed-forward) and the position
    setpoint (m), for a driver that closes its own position loop; a driver uses one
    of the two. It returns when the next cycle may start (a simulator advances by
    ``1 / rate``; a real driver waits for its clock).
    """

    def read_encoders(self) -> tuple[FloatArray, FloatArray]: ...

    def write(self, forces: FloatArray, positions: FloatArray) -> None: ...


@dataclasses.dataclass(frozen=True)
class JointState:
    """CRTK's joint state (``sensor_msgs/JointState``) of the three actuators.

    Attributes
    ----------
    t : float
        Time, s (the arm's clock).
    position : ndarray, shape (3,)
        m.
    velocity : ndarray, shape (3,)
        m/s.
    effort : ndarray, shape (3,)
        N, positive along increasing ``q``.
    """

    t: float
    position: FloatArray
    velocity: FloatArray
    effort: FloatArray


@dataclasses.dataclass(frozen=True, kw_only=True)
class ServoGains:
    """PD gains of the servo, per actuator.

    Parameters
    ----------
    kp : float
        N/m (default 4e4).
    kd : float
        N s/m (default 800: about critical for a few kg at ``kp``).
    """

    kp: float = 4.0e4
    kd: float = 800.0

    def __post_init__(self) -> None:
        check_scalar(self.kp, "kp", nonnegative=True)
        check_scalar(self.kd, "kd", nonnegative=True)


class MujocoBackend:
    """The exported MJCF in MuJoCo: encoders from ``qpos``/``qvel``, forces to the motors.

    Parameters
    ----------
    T_b_e : array-like, shape (4, 4)
    design : Design
    q0 : array-like, shape (3,)
        Where the model is assembled (keyframe ``home``), m.
    slot : int
        Its forward-kinematics slot.
    masses : athenakin.dynamics.MassModel
    rate : float
        Cycles per second; each :meth:`write` advances ``1 / rate`` in ``substeps`` steps.
    substeps : int
        MuJoCo steps per cycle (10: 0.1 ms at 1 kHz, RK4, a stiff constraint solver, as
        ``tests/test_dynamics_mujoco.py`` tightens it).
    gravity : bool
    """

    def __init__(self, T_b_e: FloatArray, design: Design, q0: FloatArray,
                 slot: int, masses: Any, rate: float, *, substeps: int = 10,
                 gravity: bool = True) -> None:
        try:
            import mujoco
        except ModuleNotFoundError as exc:  # the sim extra
            raise ModuleNotFoundError("SimulatedArm's MuJoCo backend needs mujoco: pip "
                                      "install 'athenakin[sim]'", name="mujoco") from exc
        from ..sim import ACTUATED, LOOP_CLOSURES, mjcf_from_design

        q0 = check_array(q0, "q0", (3,))
        if q0.shape != (3,):
            raise InvalidInputError(f"q0: expected shape (3,), got {q0.shape}")
        rate = check_rate(rate)
        substeps = check_count(substeps, "substeps", minimum=1, maximum=1000)
        self._mj = mujoco
        xml = mjcf_from_design(T_b_e, design, q=q0, masses=masses, slot=slot, gravity=gravity)
        m = mujoco.MjModel.from_xml_string(xml)
        dt = 1.0 / (rate * substeps)
        m.opt.timestep = dt
        m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
        m.opt.solver = mujoco.mjtSolver.mjSOL_NEWTON
        m.opt.tolerance = 1e-12
        m.opt.iterations = 100
        m.eq_solref[:] = [5 * dt, 1.0]
        m.eq_solimp[:] = [0.9999, 0.9999, 0.001, 0.5, 2.0]
        self.model, self.data = m, mujoco.MjData(m)
        mujoco.mj_resetDataKeyframe(m, self.data, 0)
        mujoco.mj_forward(m, self.data)
        self.substeps = substeps
        self._qadr = np.array([m.jnt_qposadr[m.joint(n).id] for n in ACTUATED])
        self._vadr = np.array([m.jnt_dofadr[m.joint(n).id] for n in ACTUATED])
        self._tip = m.site("tool_tip").id
        self._pairs = [(m.site(c.a).id, m.site(c.b).id) for c in LOOP_CLOSURES
                       if c.kind in ("point", "pose")]

    def read_encoders(self) -> tuple[FloatArray, FloatArray]:
        """Actuator positions (m) and velocities (m/s) of the simulation, shape (3,) each."""
        d = self.data
        return d.qpos[self._qadr].copy(), d.qvel[self._vadr].copy()

    def write(self, forces: FloatArray, positions: FloatArray) -> None:
        """Apply ``forces`` (N) to the motors for one cycle (``positions`` unused)."""
        self.data.ctrl[:] = forces
        for _ in range(self.substeps):
            self._mj.mj_step(self.model, self.data)

    # --- the simulation's truth (not part of ArmBackend) -----------------------------
    @property
    def time(self) -> float:
        """Simulated time, s."""
        return float(self.data.time)

    def tip_b(self) -> FloatArray:
        """MuJoCo's tool tip (site ``tool_tip``), base frame, m, shape (3,)."""
        return self.data.site_xpos[self._tip].copy()

    def closure_error(self) -> float:
        """Largest distance between the two sites of a point or pose loop closure, m."""
        x = self.data.site_xpos
        return max(float(np.linalg.norm(x[a] - x[b])) for a, b in self._pairs)


class SimulatedArm:
    """ATHENA under a PD + feed-forward servo, with CRTK's commands; MuJoCo by default.

    Parameters
    ----------
    T_b_e : array-like, shape (4, 4)
        RCM frame E in the base frame.
    design : Design, optional
    masses : athenakin.dynamics.MassModel, optional, keyword-only
        Default ``MassModel.reference(design)``: the simulated robot and the
        feed-forward use the same model.
    rate : float, keyword-only
        Servo cycles per second, Hz (1000).
    q0 : array-like, shape (3,), optional, keyword-only
        Where the robot stands at start, m (default :data:`athenakin.robot.REFERENCE_Q`).
    slot : int, keyword-only
        Its forward-kinematics slot (0).
    gains : ServoGains, optional, keyword-only
    feedforward : bool, keyword-only
        Add the inverse dynamics of the setpoint to the PD forces (True); False: PD only.
    backend : ArmBackend, optional, keyword-only
        A robot driver; default a :class:`MujocoBackend` of the exported MJCF.
    v_max, a_max, j_max : float, keyword-only
        Limits of ``move_jp`` / ``move_cp`` (Ruckig): m/s, m/s^2, m/s^3.

    Examples
    --------
    >>> import athenakin as ak
    >>> from athenakin.teleop import SimulatedArm
    >>> d = ak.Design.default()
    >>> arm = SimulatedArm(ak.default_rcm_frame(d), d, q0=[-0.1, 0.1, 0.45])
    >>> arm.operating_state
    'ENABLED'
    >>> arm.step(5)
    >>> bool(abs(arm.measured_js().position - [-0.1, 0.1, 0.45]).max() < 1e-4)
    True
    """

    def __init__(self, T_b_e: ArrayLike, design: Design | None = None, *, masses: Any = None,
                 rate: float = 1000.0, q0: ArrayLike | None = None, slot: int = 0,
                 gains: ServoGains | None = None, feedforward: bool = True,
                 backend: ArmBackend | None = None, v_max: float = 0.1, a_max: float = 1.0,
                 j_max: float = 20.0) -> None:
        from ..dynamics import MassModel
        from ..motion import Tracker
        from ..robot import REFERENCE_Q

        design = resolve_design(design)
        T = check_frame(T_b_e, "T_b_e")
        self.design, self.T_b_e = design, np.array(T)
        self.rate = check_rate(rate)
        self.dt = 1.0 / self.rate
        q = np.array(check_array(REFERENCE_Q if q0 is None else q0, "q0", (3,)), dtype=float)
        if q.shape != (3,):
            raise InvalidInputError(f"q0: expected shape (3,), got {q.shape}")
        self.masses = MassModel.reference(design) if masses is None else masses
        if not isinstance(self.masses, MassModel):
            raise TypeError(f"masses: expected athenakin.dynamics.MassModel, got "
                            f"{type(self.masses).__name__}")
        self.gains = ServoGains() if gains is None else gains
        if not isinstance(self.gains, ServoGains):
            raise TypeError(f"gains: expected ServoGains, got {type(self.gains).__name__}")
        if not isinstance(feedforward, bool):
            raise TypeError(f"feedforward: expected a bool, got {type(feedforward).__name__}")
        self.feedforward = feedforward
        self.limits = tuple(check_scalar(x, n, positive=True)
                            for x, n in ((v_max, "v_max"), (a_max, "a_max"), (j_max, "j_max")))
        self._tracker = Tracker(self.T_b_e, design, q0=q, slot=slot)
        self.slot = self._tracker.pose.slot
        if backend is None:
            backend = MujocoBackend(self.T_b_e, design, q, self.slot, self.masses, self.rate)
        elif not isinstance(backend, ArmBackend):
            raise TypeError("backend: expected an ArmBackend (read_encoders() and write())")
        self.backend = backend
        self.t = 0.0
        self._sp_q = q.copy()
        self._sp_qd = np.zeros(3)
        self._sp_qdd = np.zeros(3)
        self._sp_effort = np.zeros(3)   # the feed-forward of the setpoint, N
        self._user_effort: FloatArray | None = None
        self._force = np.zeros(3)
        self._move: Any = None
        self._move_t0 = 0.0
        self._state = "ENABLED"
        self.fault: str | None = None
        self._update_ff()

    # --- CRTK state -----------------------------------------------------------------
    @property
    def operating_state(self) -> str:
        """CRTK operating state: ``"DISABLED"``, ``"ENABLED"``, ``"PAUSED"`` or ``"FAULT"``."""
        return self._state

    @property
    def is_busy(self) -> bool:
        """A ``move_jp`` / ``move_cp`` is under way (CRTK's ``is_busy``)."""
        return self._move is not None

    def enable(self) -> None:
        """Power the servo (``DISABLED`` or ``PAUSED`` -> ``ENABLED``), holding where it is."""
        if self._state == "FAULT":
            return
        if self._state == "DISABLED":
            self.hold()
        self._state = "ENABLED"

    def disable(self) -> None:
        """Stop accepting commands; the brakes hold the robot where it is (``DISABLED``).

        The simulated brakes are the servo holding the measured position at rest.
        """
        self.hold()
        self._state = "DISABLED"

    def pause(self) -> None:
        """``PAUSED``: hold the current setpoint and ignore commands until :meth:`enable`."""
        if self._state == "ENABLED":
            self.hold()
            self._state = "PAUSED"

    def hold(self) -> None:
        """Stop any motion: the setpoint becomes the measured position at rest."""
        q, _ = self.backend.read_encoders()
        self._move = None
        self._set(q, np.zeros(3), np.zeros(3), None)

    def _accepting(self) -> bool:
        return self._state == "ENABLED"

    # --- CRTK queries ---------------------------------------------------------------
    def measured_js(self) -> JointState:
        """Measured actuator positions (m), velocities (m/s) and servo forces (N)."""
        q, qd = self.backend.read_encoders()
        return JointState(self.t, q, qd, self._force.copy())

    def setpoint_js(self) -> JointState:
        """The servo's setpoint: positions (m), velocities (m/s), feed-forward forces (N)."""
        return JointState(self.t, self._sp_q.copy(), self._sp_qd.copy(), self._sp_effort.copy())

    def measured_cp(self) -> FloatArray:
        """The tool-tip frame in the base frame, ``T_b_tip`` (4, 4), SI, from the encoders.

        Forward kinematics of the measured actuators on the tracked slot
        (:class:`athenakin.motion.Tracker`); rotation: the instrument's frame at the tip
        (:attr:`athenakin.FKSolution.T_b_tip`).
        """
        from .. import forward_kinematics

        q, _ = self.backend.read_encoders()
        pose = self._tracker.update(q)
        sol = forward_kinematics(np.array(pose.q), self.T_b_e, self.design, errors="flag")
        return sol.T_b_tip[pose.slot].copy()

    def setpoint_cp(self) -> FloatArray:
        """The setpoint's tool-tip frame in the base frame, (4, 4)."""
        from .. import forward_kinematics

        sol = forward_kinematics(self._sp_q, self.T_b_e, self.design, errors="flag")
        return sol.T_b_tip[self.slot].copy()

    # --- CRTK commands --------------------------------------------------------------
    def servo_jp(self, q: ArrayLike, velocity: ArrayLike | None = None,
                 effort: ArrayLike | None = None) -> None:
        """Servo to joint positions now (m), with velocity (m/s) and effort (N) feed-forward.

        Without ``effort`` the feed-forward is the inverse dynamics of ``q``, ``velocity``
        and the acceleration differenced from the previous setpoint's velocity (when
        ``feedforward``); ``effort`` replaces it. Ignored unless ``ENABLED``.
        """
        if not self._accepting():
            return
        qa = check_array(q, "q", (3,))
        v = np.zeros(3) if velocity is None else check_array(velocity, "velocity", (3,))
        e = None if effort is None else check_array(effort, "effort", (3,))
        self._move = None
        acc = (v - self._sp_qd) * self.rate if velocity is not None else np.zeros(3)
        self._set(qa, v, acc, e)

    def servo_cp(self, tip: ArrayLike, *, frame: Literal["base", "rcm"] = "base") -> None:
        """Servo the tool tip to a position now (exact IK, ``q_from_tool_tip``).

        Parameters
        ----------
        tip : array-like, shape (3,) or (4, 4)
            Tip position (m), or a pose whose translation is taken, in ``frame``.
        frame : {"base", "rcm"}, keyword-only
        """
        self.servo_jp(self._ik(tip, frame))

    def move_jp(self, q: ArrayLike, goal_velocity: ArrayLike | None = None) -> None:
        """Move to joint positions (m) along a time-optimal jerk-limited profile (Ruckig).

        ``goal_velocity`` (m/s, default rest) is the velocity at arrival. The profile runs
        over the next :meth:`step` calls; :attr:`is_busy` until it ends.
        """
        if not self._accepting():
            return
        from ruckig import InputParameter, Result, Ruckig, Trajectory

        qa = check_array(q, "q", (3,))
        lo, hi = np.asarray(self.design.stroke_min), np.asarray(self.design.stroke_max)
        if np.any(qa < lo) or np.any(qa > hi):
            raise InvalidInputError(f"q: {qa.tolist()} is outside the stroke limits")
        inp = InputParameter(3)
        inp.current_position = self._sp_q.tolist()
        inp.current_velocity = self._sp_qd.tolist()
        inp.current_acceleration = self._sp_qdd.tolist()
        inp.target_position = qa.tolist()
        inp.target_velocity = ([0.0] * 3 if goal_velocity is None else
                               check_array(goal_velocity, "goal_velocity", (3,)).tolist())
        inp.target_acceleration = [0.0] * 3
        v, a, j = self.limits
        inp.max_velocity, inp.max_acceleration, inp.max_jerk = [v] * 3, [a] * 3, [j] * 3
        traj = Trajectory(3)
        res = Ruckig(3).calculate(inp, traj)
        if res not in (Result.Working, Result.Finished):
            raise KinematicsError(f"move_jp: Ruckig found no profile ({res})")
        self._move, self._move_t0 = traj, self.t

    def move_cp(self, tip: ArrayLike, *, frame: Literal["base", "rcm"] = "base") -> None:
        """Move the tool tip to a position (exact IK, then :meth:`move_jp`)."""
        self.move_jp(self._ik(tip, frame))

    def _ik(self, tip: ArrayLike, frame: str) -> FloatArray:
        from .. import q_from_tool_tip

        check_choice(frame, "frame", ("base", "rcm"))
        x = np.asarray(tip, dtype=float)
        if x.shape == (4, 4):
            x = x[:3, 3]
        x = check_array(x, "tip", (3,))
        if frame == "base":
            R, c = self.T_b_e[:3, :3], self.T_b_e[:3, 3]
            x = R.T @ (x - c)
        q, _ = q_from_tool_tip(self.T_b_e, x, self.design, errors="raise")
        return np.asarray(q, dtype=float)

    # --- the servo loop -------------------------------------------------------------
    def _set(self, q: FloatArray, qd: FloatArray, qdd: FloatArray,
             effort: FloatArray | None) -> None:
        self._sp_q, self._sp_qd, self._sp_qdd = (np.array(q, dtype=float),
                                                 np.array(qd, dtype=float),
                                                 np.array(qdd, dtype=float))
        self._user_effort = effort
        self._update_ff()

    def _update_ff(self) -> None:
        if self._user_effort is not None:
            self._sp_effort = np.array(self._user_effort, dtype=float)
            return
        if not self.feedforward:
            self._sp_effort = np.zeros(3)
            return
        from ..dynamics import inverse_dynamics

        try:
            self._sp_effort = np.asarray(inverse_dynamics(
                self._sp_q, self._sp_qd, self._sp_qdd, self.T_b_e, self.design,
                masses=self.masses, slot=self.slot, errors="flag"), dtype=float)
        except KinematicsError:      # pragma: no cover - a setpoint off the workspace
            self._sp_effort = np.zeros(3)
        if not np.all(np.isfinite(self._sp_effort)):
            self._sp_effort = np.zeros(3)

    def step(self, n: int = 1) -> None:
        """Advance ``n`` servo cycles of ``1 / rate`` s (read, servo, write)."""
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 0:
            raise InvalidInputError(f"n: expected a non-negative integer, got {n!r}")
        g = self.gains
        for _ in range(int(n)):
            if self._move is not None:
                tt = min(self.t + self.dt - self._move_t0, self._move.duration)
                p, v, a = self._move.at_time(tt)
                self._sp_q, self._sp_qd, self._sp_qdd = np.array(p), np.array(v), np.array(a)
                self._user_effort = None
                self._update_ff()
                if tt >= self._move.duration:
                    self._move = None
            q, qd = self.backend.read_encoders()
            if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):
                self._state, self.fault = "FAULT", "non-finite encoder reading"
            if self._state == "FAULT":
                f = np.zeros(3)
            else:
                f = self._sp_effort + g.kp * (self._sp_q - q) + g.kd * (self._sp_qd - qd)
            self._force = f
            self.backend.write(f, self._sp_q)
            self.t += self.dt
