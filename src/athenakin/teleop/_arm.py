"""The arm: CRTK's commands over a servo loop and a backend (MuJoCo by default) (private).

:class:`SimulatedArm` is the robot as a lab drives it: CRTK's names (``measured_js``,
``setpoint_js``, ``measured_cp``, ``servo_jp``, ``servo_cp``, ``move_jp``, ``move_cp``,
``hold``, ``enable``, ``disable``, ``pause``, ``resume``, ``home``, operating states), a
PD + feed-forward servo on the three actuators at ``rate`` Hz, and a backend that reads
the encoders and applies the forces. The embedded default is :class:`MujocoBackend`: the
exported MJCF (:func:`athenakin.sim.mjcf_from_design` with ``masses=``: the mass model's
inertias, force motors, the loops closed by equality constraints) stepped by MuJoCo. A
real robot plugs in through :class:`ArmBackend`'s two methods.

The arm refuses what the teleoperation core refuses. A servo command (``servo_jp``,
``servo_cp``) outside the strokes, with the carriages' order reversed, off the FK slot's
workspace, not finite, or with an effort above ``max_force`` is *held and flagged*: the
setpoint stays where the last accepted command put it (at rest) and :attr:`SimulatedArm.refusal`
names the reason; it never raises for a value, as a real-time loop must not. A planned
move (``move_jp``, ``move_cp``) outside the strokes raises a named error, as a planning
call may. The servo's force is saturated at ``max_force`` per actuator. A reading of the
encoders of the wrong shape, not finite, beyond the strokes by more than
:data:`READING_MARGIN` or faster than :data:`READING_SPEED_MAX`, a MuJoCo instability
(its warning counters) and a loop-closure error above :data:`CLOSURE_TOL` put the arm in
``FAULT`` in the cycle they occur, with :attr:`SimulatedArm.fault` naming the reason;
``FAULT`` and ``DISABLED`` write no force.

Frames and units: joints in m, m/s, N; Cartesian poses are the tool-tip frame in the
base frame (``T_b_tip``, SI); :meth:`SimulatedArm.servo_cp` and
:meth:`SimulatedArm.move_cp` take the tip position in the base frame (``frame="base"``)
or in the RCM frame E (``frame="rcm"``); the instrument's direction follows from the
RCM, so a pose's rotation is not used.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Literal, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from .._validation import check_array, check_choice, check_count, check_frame, check_scalar
from ..design import Design, resolve_design
from ..errors import InvalidInputError, KinematicsError, Reason
from ._filter import check_rate

__all__ = ["ArmBackend", "JointState", "MujocoBackend", "ServoGains", "SimulatedArm",
           "OPERATING_STATES", "CLOSURE_TOL", "READING_MARGIN", "READING_SPEED_MAX",
           "MAX_FORCE", "MAX_STEPS", "SUBSTEP_S", "BANDWIDTH", "BANDWIDTH_PER_RATE",
           "STABILITY_RADIUS"]

#: CRTK operating states.
OPERATING_STATES = ("DISABLED", "ENABLED", "PAUSED", "FAULT")
#: Largest loop-closure error of the simulation before the arm faults, m.
CLOSURE_TOL = 1e-6
#: How far beyond the strokes an encoder reading may lie before the arm faults, m.
READING_MARGIN = 0.005
#: Fastest actuator speed a reading may report before the arm faults, m/s.
READING_SPEED_MAX = 10.0
#: Default bound of the servo's force per actuator (saturation, and the largest effort
#: a servo command may carry), N.
MAX_FORCE = 100.0
#: Most servo cycles one :meth:`SimulatedArm.step` call runs.
MAX_STEPS = 1_000_000
#: Longest MuJoCo step of :class:`MujocoBackend` (it takes ``ceil(1 / (rate SUBSTEP_S))``
#: steps per cycle), s.
SUBSTEP_S = 1e-4
#: Most MuJoCo steps per cycle (so the MuJoCo backend runs at 10 Hz or faster).
MAX_SUBSTEPS = 1000
#: Bandwidth of the derived servo gains, rad/s, at most ...
BANDWIDTH = 150.0
#: ... and at most this fraction of the cycle rate (rad/s per Hz): ``omega dt <= 0.15``.
BANDWIDTH_PER_RATE = 0.15
#: Damping ratio of the derived gains.
DAMPING_RATIO = 1.0
#: Largest spectral radius of the sampled servo loop (mass matrix at ``q0``, force held
#: over the cycle) that the constructor accepts for given gains.
STABILITY_RADIUS = 0.98
#: Smallest eigenvalue of the mass matrix at ``q0`` that the servo needs, kg.
MIN_MODAL_MASS = 1e-3
#: Friction force of the simulated brakes (``DISABLED``, ``FAULT``), N.
BRAKE_FORCE = 1000.0


@runtime_checkable
class ArmBackend(Protocol):
    """What a robot driver provides to :class:`SimulatedArm`: two methods.

    ``read_encoders()`` returns the actuators' positions (m) and velocities (m/s), each
    a float array of shape (3,). ``write(forces, positions)`` sends this cycle's
    commands: the actuator forces of the servo (N, PD + feed-forward, within
    ``max_force``) and the position setpoint (m), for a driver that closes its own
    position loop; a driver uses one of the two. In ``DISABLED`` and ``FAULT`` the arm
    writes zero forces and NaN positions: no command, motor power off (a driver engages
    its brakes). ``write`` returns when the next cycle may start (a simulator advances
    by ``1 / rate``; a real driver waits for its clock).

    Optional: ``home()`` (a driver whose encoders need homing; without it the encoders
    are taken as absolute and the arm starts homed) and ``fault()`` (returns a reason
    string, or None while the backend is sound; the arm calls it after every write).
    """

    def read_encoders(self) -> tuple[FloatArray, FloatArray]:
        """Actuator positions (m) and velocities (m/s), shape (3,) each.

        Returns
        -------
        tuple of two ndarray, shape (3,)
        """
        ...

    def write(self, forces: FloatArray, positions: FloatArray) -> None:
        """Send one cycle's forces (N) and position setpoint (m), shape (3,) each.

        Parameters
        ----------
        forces, positions : ndarray, shape (3,)
            NaN positions and zero forces: no command (``DISABLED``, ``FAULT``).
        """
        ...


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
        N, positive along increasing ``q``: the force the servo applied in the last
        cycle (zero in ``DISABLED`` and ``FAULT``).
    """

    t: float
    position: FloatArray
    velocity: FloatArray
    effort: FloatArray


@dataclasses.dataclass(frozen=True, kw_only=True)
class ServoGains:
    """Explicit PD gains of the servo, the same on every actuator.

    Without ``gains`` :class:`SimulatedArm` derives them from the mass model and the
    rate (``Kp = omega^2 M(q0)``, ``Kd = 2 zeta omega M(q0)``, :data:`BANDWIDTH`); explicit
    gains are checked for the stability of the sampled loop at the arm's rate
    (:data:`STABILITY_RADIUS`).

    Parameters
    ----------
    kp : float
        N/m (default 4e4).
    kd : float
        N s/m (default 800: about critical for a few kg at ``kp``).

    Raises
    ------
    InvalidInputError, TypeError
        A gain that is not a finite non-negative number.
    """

    kp: float = 4.0e4
    kd: float = 800.0

    def __post_init__(self) -> None:
        check_scalar(self.kp, "kp", nonnegative=True)
        check_scalar(self.kd, "kd", nonnegative=True)


def _substeps(rate: float, substeps: int | None) -> int:
    """MuJoCo steps per cycle: given, else ``ceil(1 / (rate SUBSTEP_S))``; a named refusal."""
    if substeps is not None:
        return check_count(substeps, "substeps", minimum=1, maximum=MAX_SUBSTEPS)
    n = max(1, math.ceil(1.0 / (rate * SUBSTEP_S) - 1e-9))
    if n > MAX_SUBSTEPS:
        raise InvalidInputError(f"rate: the MuJoCo backend needs at least "
                                f"{1.0 / (MAX_SUBSTEPS * SUBSTEP_S):g} Hz (at most "
                                f"{MAX_SUBSTEPS} steps of {SUBSTEP_S:g} s per cycle), got "
                                f"{rate:g} Hz")
    return n


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
        Cycles per second (10 Hz or faster); each :meth:`write` advances ``1 / rate``.
    substeps : int, optional, keyword-only
        MuJoCo steps per cycle (default ``ceil(1 / (rate SUBSTEP_S))``: steps of at most
        0.1 ms, RK4, a stiff constraint solver, as ``tests/test_dynamics_mujoco.py``
        tightens it).
    gravity : bool, keyword-only

    Raises
    ------
    ModuleNotFoundError
        mujoco is not installed (extra ``sim``).
    InvalidInputError
        A bad ``q0``, ``rate`` or ``substeps`` (named); a mass model MuJoCo refuses.
    """

    def __init__(self, T_b_e: FloatArray, design: Design, q0: FloatArray,
                 slot: int, masses: Any, rate: float, *, substeps: int | None = None,
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
        self.substeps = _substeps(rate, substeps)
        self._mj = mujoco
        xml = mjcf_from_design(T_b_e, design, q=q0, masses=masses, slot=slot, gravity=gravity)
        try:
            m = mujoco.MjModel.from_xml_string(xml)
        except ValueError as exc:          # MuJoCo's compiler (massless bodies and the like)
            raise InvalidInputError(f"masses: MuJoCo cannot simulate this mass model ({exc})"
                                    ) from None
        dt = 1.0 / (rate * self.substeps)
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
        self._qadr = np.array([m.jnt_qposadr[m.joint(n).id] for n in ACTUATED])
        self._vadr = np.array([m.jnt_dofadr[m.joint(n).id] for n in ACTUATED])
        for name, adr in zip(ACTUATED, self._vadr, strict=True):
            body = m.body(int(m.jnt_bodyid[m.joint(name).id])).name
            if not m.dof_M0[adr] >= MIN_MODAL_MASS:   # a massless slide: MuJoCo diverges
                raise InvalidInputError(
                    f"masses: the actuated joint {name!r} moves {m.dof_M0[adr]:.3g} kg of its "
                    f"own (MuJoCo body {body!r}), below {MIN_MODAL_MASS:g} kg: MuJoCo cannot "
                    f"simulate the closed loop stably; give that body a mass")
        m.dof_solref[self._vadr] = [5 * dt, 1.0]          # the brakes: a stiff dry friction
        m.dof_solimp[self._vadr] = [0.9999, 0.9999, 0.001, 0.5, 2.0]
        self._tip = m.site("tool_tip").id
        self._pairs = [(m.site(c.a).id, m.site(c.b).id) for c in LOOP_CLOSURES
                       if c.kind in ("point", "pose")]
        self._unstable = tuple(int(w) for w in (mujoco.mjtWarning.mjWARN_BADQACC,
                                                mujoco.mjtWarning.mjWARN_BADQVEL,
                                                mujoco.mjtWarning.mjWARN_BADQPOS))
        self._warned = self._warnings()
        self._braked = False

    def read_encoders(self) -> tuple[FloatArray, FloatArray]:
        """Actuator positions (m) and velocities (m/s) of the simulation.

        Returns
        -------
        tuple of two ndarray, shape (3,)
        """
        d = self.data
        return d.qpos[self._qadr].copy(), d.qvel[self._vadr].copy()

    def write(self, forces: FloatArray, positions: FloatArray) -> None:
        """Apply ``forces`` (N) to the motors for one cycle.

        Parameters
        ----------
        forces : ndarray, shape (3,)
            N.
        positions : ndarray, shape (3,)
            Unused as a setpoint; NaN (no command) engages the simulated brakes (a dry
            friction of :data:`BRAKE_FORCE` on the actuated joints) for the cycle.
        """
        brake = not bool(np.all(np.isfinite(positions)))
        if brake != self._braked:
            self.model.dof_frictionloss[self._vadr] = BRAKE_FORCE if brake else 0.0
            self._braked = brake
        self.data.ctrl[:] = 0.0 if brake else forces
        for _ in range(self.substeps):
            self._mj.mj_step(self.model, self.data)

    def fault(self) -> str | None:
        """Why the simulation can no longer be trusted, or None.

        Returns
        -------
        str or None
            MuJoCo's instability (its warning counters of a NaN / huge ``qacc``, ``qvel``
            or ``qpos``: it reset the state) or a loop-closure error above
            :data:`CLOSURE_TOL`.
        """
        w = self._warnings()
        if w != self._warned:
            self._warned = w
            return ("MuJoCo: the simulation is unstable (a NaN or huge acceleration, "
                    "velocity or position; MuJoCo reset its state)")
        err = self.closure_error()
        if not err <= CLOSURE_TOL:
            return f"MuJoCo: loop-closure error {err:.3g} m above {CLOSURE_TOL:g} m"
        return None

    def _warnings(self) -> tuple[int, ...]:
        return tuple(int(self.data.warning[i].number) for i in self._unstable)

    # --- the simulation's truth (not part of ArmBackend) -----------------------------
    @property
    def time(self) -> float:
        """Simulated time, s."""
        return float(self.data.time)

    def tip_b(self) -> FloatArray:
        """MuJoCo's tool tip (site ``tool_tip``), base frame, m.

        Returns
        -------
        ndarray, shape (3,)
        """
        return self.data.site_xpos[self._tip].copy()

    def closure_error(self) -> float:
        """Largest distance between the two sites of a point or pose loop closure, m.

        Returns
        -------
        float
        """
        x = self.data.site_xpos
        return max(float(np.linalg.norm(x[a] - x[b])) for a, b in self._pairs)


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
        the derived gains and the feed-forward use the same model.
    rate : float, keyword-only
        Servo cycles per second, Hz (1000; 10 Hz or faster with the MuJoCo backend).
    q0 : array-like, shape (3,), optional, keyword-only
        Where the robot stands at start, m (default :data:`athenakin.robot.REFERENCE_Q`):
        within the strokes, in the carriages' order, assembled in ``slot``.
    slot : int, keyword-only
        Its forward-kinematics slot (0).
    gains : ServoGains, optional, keyword-only
        Explicit PD gains (checked for stability at ``rate``); default derived from the
        mass matrix at ``q0`` and the rate: ``omega = min(BANDWIDTH, BANDWIDTH_PER_RATE
        rate)``, ``Kp = omega^2 M``, ``Kd = 2 omega M`` (critically damped).
    feedforward : bool, keyword-only
        Add the inverse dynamics of the setpoint (:class:`athenakin.dynamics.InverseDynamicsLoop`)
        to the PD forces (True); False: PD only.
    backend : ArmBackend, optional, keyword-only
        A robot driver; default a :class:`MujocoBackend` of the exported MJCF.
    v_max, a_max, j_max : float, keyword-only
        Limits of ``move_jp`` / ``move_cp`` (Ruckig): m/s, m/s^2, m/s^3.
    max_force : float, keyword-only
        Saturation of the servo's force per actuator, and the largest effort a servo
        command may carry, N (:data:`MAX_FORCE`).

    Raises
    ------
    InvalidInputError, TypeError
        A bad argument (named); ``q0`` outside the strokes, in the wrong carriage order or
        not assembled in ``slot``; a mass matrix at ``q0`` with an eigenvalue below
        :data:`MIN_MODAL_MASS` (``MassModel.zeros()``: no servo can be designed for it);
        explicit gains whose sampled loop is unstable at ``rate``.

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
        from .._robot_model import Robot
        from .._validation import check_slot
        from ..dynamics import InverseDynamicsLoop, MassModel
        from ..robot import REFERENCE_Q

        if isinstance(robot, Robot):
            if design is not None:
                raise TypeError("design: give either an athenakin.Robot or (T_b_e, design), "
                                "not both")
            design, T = robot.design, robot.T_b_e
            masses = robot.masses if masses is None else masses
        else:
            design = resolve_design(design)
            T = check_frame(robot, "T_b_e")
        self.design, self.T_b_e = design, np.array(T, dtype=float)
        self.T_b_e.setflags(write=False)
        self.rate = check_rate(rate)
        self.dt = 1.0 / self.rate
        self.masses = MassModel.reference(design) if masses is None else masses
        if not isinstance(self.masses, MassModel):
            raise TypeError(f"masses: expected athenakin.dynamics.MassModel, got "
                            f"{type(self.masses).__name__}")
        if gains is not None and not isinstance(gains, ServoGains):
            raise TypeError(f"gains: expected ServoGains, got {type(gains).__name__}")
        if not isinstance(feedforward, bool):
            raise TypeError(f"feedforward: expected a bool, got {type(feedforward).__name__}")
        self.feedforward = feedforward
        self.limits = tuple(check_scalar(x, n, positive=True)
                            for x, n in ((v_max, "v_max"), (a_max, "a_max"), (j_max, "j_max")))
        self.max_force = check_scalar(max_force, "max_force", positive=True)
        self.slot = check_slot(slot)
        self._lo = np.asarray(design.stroke_min, dtype=float)
        self._hi = np.asarray(design.stroke_max, dtype=float)
        q = np.array(check_array(REFERENCE_Q if q0 is None else q0, "q0", (3,)), dtype=float)
        if q.shape != (3,):
            raise InvalidInputError(f"q0: expected shape (3,), got {q.shape}")
        why = self._position_refusal(q, "q0")
        if why is not None:
            raise InvalidInputError(why)
        self._ff_loop = InverseDynamicsLoop(self.T_b_e, design, masses=self.masses,
                                            slot=self.slot)
        if np.isnan(self._ff_loop(q, np.zeros(3), np.zeros(3))).any():
            raise InvalidInputError(f"q0: {q.tolist()} m does not assemble in FK slot "
                                    f"{self.slot}")
        self.gains = gains
        self.kp, self.kd = _servo_gains(q, self.T_b_e, design, self.masses, self.slot,
                                        self.rate, gains)
        if backend is None:
            backend = MujocoBackend(self.T_b_e, design, q, self.slot, self.masses, self.rate)
        elif not isinstance(backend, ArmBackend):
            raise TypeError("backend: expected an ArmBackend (read_encoders() and write())")
        self.backend = backend
        self._backend_fault = getattr(backend, "fault", None)
        self._backend_home = getattr(backend, "home", None)
        self.t = 0.0
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
        why = None if self._backend_fault is None else self._backend_fault()
        bad = self._read()
        why = why or bad
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
        self._set(self._q_meas, self._zero, self._zero, None)

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

    def _tip_frame(self, q: FloatArray) -> FloatArray:
        from .. import forward_kinematics

        sol = forward_kinematics(q, self.T_b_e, self.design, errors="flag")
        return np.array(sol.T_b_tip[self.slot], dtype=float)

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
            m/s (default rest).
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
        why = self._position_refusal(qa, "q")
        if why is None and not np.all(np.isfinite(v)):
            why = f"velocity: expected finite values, got {v.tolist()}"
        if why is None and e is not None and not np.all(np.abs(e) <= self.max_force):
            why = f"effort: {e.tolist()} N exceeds max_force {self.max_force:g} N"
        if why is None:
            acc = (v - self._sp_qd) * self.rate if velocity is not None else self._zero
            why = self._set(qa, v, acc, e)
        if why is not None:
            self._refuse(why)
            return
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
        q, why = self._ik(tip, frame)
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
            Velocity at arrival, m/s (default rest).

        Raises
        ------
        InvalidInputError
            A goal of the wrong shape, not finite, outside the strokes or the carriages'
            order, or off the slot's workspace.
        KinematicsError
            Ruckig finds no profile, or fails (its error named).
        ModuleNotFoundError
            ruckig is not installed (extra ``motion``).
        """
        qa = self._vector(q, "q")
        gv = self._zero if goal_velocity is None else self._vector(goal_velocity,
                                                                    "goal_velocity")
        why = self._position_refusal(qa, "q")
        if why is None and not np.all(np.isfinite(gv)):
            why = f"goal_velocity: expected finite values, got {gv.tolist()}"
        if why is None and np.isnan(self._ff_loop(qa, gv, self._zero)).any():
            why = f"q: {qa.tolist()} m does not assemble in FK slot {self.slot}"
        if why is not None:
            raise InvalidInputError(why)
        if not self._accepting("move_jp"):
            return
        try:
            from ruckig import InputParameter, Result, Ruckig, Trajectory
        except ModuleNotFoundError as exc:
            raise ModuleNotFoundError("move_jp needs ruckig: pip install 'athenakin[motion]'",
                                      name="ruckig") from exc
        inp = InputParameter(3)
        inp.current_position = self._sp_q.tolist()
        inp.current_velocity = self._sp_qd.tolist()
        inp.current_acceleration = self._sp_qdd.tolist()
        inp.target_position = qa.tolist()
        inp.target_velocity = gv.tolist()
        inp.target_acceleration = [0.0] * 3
        v, a, j = self.limits
        inp.max_velocity, inp.max_acceleration, inp.max_jerk = [v] * 3, [a] * 3, [j] * 3
        traj = Trajectory(3)
        try:
            res = Ruckig(3).calculate(inp, traj)
        except Exception as exc:         # ruckig's own errors (RuntimeError, pybind11's)
            raise KinematicsError(f"move_jp: Ruckig failed ({type(exc).__name__}: {exc})"
                                  ) from exc
        if res not in (Result.Working, Result.Finished):
            raise KinematicsError(f"move_jp: Ruckig found no profile ({res})")
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
        q, why = self._ik(tip, frame)
        if why is not None:
            raise InvalidInputError(why)
        self.move_jp(q)

    # --- checks ---------------------------------------------------------------------
    @staticmethod
    def _vector(x: ArrayLike, name: str) -> FloatArray:
        """``x`` as a float array of shape (3,) (NaN kept: a value); a named error otherwise."""
        a = check_array(x, name, (3,), allow_nonfinite=True)
        if a.shape != (3,):
            raise InvalidInputError(f"{name}: expected shape (3,), got {a.shape}")
        return np.array(a, dtype=float)

    def _position_refusal(self, q: FloatArray, name: str) -> str | None:
        """Why ``q`` is no position to command (not finite, strokes, order), or None."""
        from ..parallel._module import _actuator_checks

        code = int(_actuator_checks(q, self.design))
        if code == Reason.NONFINITE_INPUT:
            return f"{name}: expected finite values, got {q.tolist()}"
        if code == Reason.STROKE_LIMIT:
            return f"{name}: {q.tolist()} m is outside the stroke limits"
        if code == Reason.AB_ORDER:
            return (f"{name}: {q.tolist()} m has the carriages in the wrong order (the "
                    f"design's ab_order is {self.design.ab_order})")
        return None

    def _refuse(self, why: str) -> None:
        """Hold the last accepted position at rest and flag ``why``."""
        self.refusal = why
        self._move = None
        if np.any(self._sp_qd != 0.0) or np.any(self._sp_qdd != 0.0):
            self._set(self._sp_q, self._zero, self._zero, None)

    def _ik(self, tip: ArrayLike, frame: str) -> tuple[FloatArray, str | None]:
        from .. import q_from_tool_tip

        check_choice(frame, "frame", ("base", "rcm"))
        x = np.asarray(tip, dtype=float)
        if x.shape == (4, 4):
            x = x[:3, 3]
        x = check_array(x, "tip", (3,), allow_nonfinite=True)
        if x.shape != (3,):
            raise InvalidInputError(f"tip: expected shape (3,) or (4, 4), got {x.shape}")
        if frame == "base":
            R, c = self.T_b_e[:3, :3], self.T_b_e[:3, 3]
            x = R.T @ (x - c)
        q, res = q_from_tool_tip(self.T_b_e, x, self.design, errors="flag")
        if not bool(np.all(res.valid)):
            return self._zero, (f"tip: {x.tolist()} m (frame E) is out of reach "
                                f"({Reason(int(res.reason)).name})")
        return np.asarray(q, dtype=float), None

    # --- the servo loop -------------------------------------------------------------
    def _set(self, q: FloatArray, qd: FloatArray, qdd: FloatArray,
             effort: FloatArray | None) -> str | None:
        """Take the setpoint and its feed-forward; the reason it is refused, or None."""
        ff = self._ff_loop(q, qd, qdd)
        if np.isnan(ff).any():
            return f"q: {np.asarray(q).tolist()} m does not assemble in FK slot {self.slot}"
        self._sp_q, self._sp_qd, self._sp_qdd = (np.array(q, dtype=float),
                                                 np.array(qd, dtype=float),
                                                 np.array(qdd, dtype=float))
        if effort is not None:
            self._ff = np.array(effort, dtype=float)
        elif self.feedforward:
            self._ff = np.array(ff, dtype=float)
        else:
            self._ff = np.zeros(3)
        return None

    def _read(self) -> str | None:
        """Read the encoders; keep a sound reading, else the reason it is not."""
        try:
            reading = self.backend.read_encoders()
            q, qd = reading
            q = np.asarray(q, dtype=float)
            qd = np.asarray(qd, dtype=float)
        except (TypeError, ValueError) as exc:
            return f"encoders: expected (positions, velocities), got an unreadable value ({exc})"
        if q.shape != (3,) or qd.shape != (3,):
            return (f"encoders: expected positions and velocities of shape (3,), got "
                    f"{q.shape} and {qd.shape}")
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):
            return f"encoders: non-finite reading {q.tolist()} m, {qd.tolist()} m/s"
        if np.any(q < self._lo - READING_MARGIN) or np.any(q > self._hi + READING_MARGIN):
            return (f"encoders: {q.tolist()} m beyond the strokes by more than "
                    f"{READING_MARGIN:g} m")
        if np.any(np.abs(qd) > READING_SPEED_MAX):
            return f"encoders: speed {qd.tolist()} m/s above {READING_SPEED_MAX:g} m/s"
        self._q_meas, self._qd_meas = q.copy(), qd.copy()
        return None

    def step(self, n: int = 1) -> None:
        """Advance ``n`` servo cycles of ``1 / rate`` s (servo, write, read, check).

        In ``ENABLED`` and ``PAUSED`` the servo writes ``ff + Kp (q_sp - q) + Kd (qd_sp -
        qd)``, each component saturated at ``max_force`` (:attr:`saturated` says so); in
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
                f = (self._ff + self.kp @ (self._sp_q - self._q_meas)
                     + self.kd @ (self._sp_qd - self._qd_meas))
                self.saturated = bool(np.any(np.abs(f) > lim))
                f = np.clip(f, -lim, lim)
                positions = self._sp_q
            else:
                f, positions, self.saturated = self._zero.copy(), self._nan, False
            self._force = f
            self.backend.write(f, positions)
            self.t += self.dt
            why = None if self._backend_fault is None else self._backend_fault()
            bad = self._read()
            why = why or bad
            if why is not None and self._state != "FAULT":
                self._to_fault(why)

    def _advance_move(self) -> None:
        traj = self._move
        tt = min(self.t + self.dt - self._move_t0, traj.duration)
        p, v, a = traj.at_time(tt)
        why = self._set(np.array(p), np.array(v), np.array(a), None)
        if why is not None:
            self.refusal = f"move_jp: the profile leaves the workspace ({why})"
            self._move = None
            self._set_hold()
        elif tt >= traj.duration:
            self._move = None


def _servo_gains(q0: FloatArray, T_b_e: FloatArray, design: Design, masses: Any, slot: int,
                 rate: float, gains: ServoGains | None) -> tuple[FloatArray, FloatArray]:
    """The PD gain matrices ``(Kp, Kd)``, (3, 3) each: derived, or explicit and checked."""
    from ..dynamics import mass_matrix

    M = np.asarray(mass_matrix(q0, T_b_e, design, masses=masses, slot=slot, errors="raise"),
                   dtype=float)
    M = 0.5 * (M + M.T)
    lam = float(np.min(np.linalg.eigvalsh(M))) if np.all(np.isfinite(M)) else math.nan
    if not lam >= MIN_MODAL_MASS:
        raise InvalidInputError(f"masses: the mass matrix at q0 has an eigenvalue of "
                                f"{lam:.3g} kg, below {MIN_MODAL_MASS:g} kg: no servo can be "
                                f"designed for it (give the moving parts mass along every "
                                f"actuator, e.g. MassModel.reference(design))")
    dt = 1.0 / rate
    if gains is None:
        w = min(BANDWIDTH, BANDWIDTH_PER_RATE * rate)
        Kp, Kd = w * w * M, 2.0 * DAMPING_RATIO * w * M
    else:
        Kp, Kd = gains.kp * np.eye(3), gains.kd * np.eye(3)
    rho = _spectral_radius(Kp, Kd, M, dt)
    if not rho < STABILITY_RADIUS:
        raise InvalidInputError(f"gains: the sampled servo loop is unstable at {rate:g} Hz "
                                f"with this mass model (spectral radius {rho:.3g} >= "
                                f"{STABILITY_RADIUS}); lower kp / kd, or leave gains=None for "
                                f"gains derived from the masses and the rate")
    Kp.setflags(write=False)
    Kd.setflags(write=False)
    return Kp, Kd


def _spectral_radius(Kp: FloatArray, Kd: FloatArray, M: FloatArray, dt: float) -> float:
    """Spectral radius of the PD loop on ``M qdd = f``, ``f`` held over each cycle ``dt``.

    The error ``e`` and its rate ``v`` advance exactly over one cycle of constant
    acceleration ``a = -M^-1 (Kp e + Kd v)``: ``e' = e + dt v + dt^2 a / 2``,
    ``v' = v + dt a``.
    """
    G = np.linalg.solve(M, np.eye(3))
    A = -G @ Kp
    B = -G @ Kd
    eye = np.eye(3)
    phi = np.block([[eye + 0.5 * dt * dt * A, dt * eye + 0.5 * dt * dt * B],
                    [dt * A, eye + dt * B]])
    return float(np.max(np.abs(np.linalg.eigvals(phi))))
