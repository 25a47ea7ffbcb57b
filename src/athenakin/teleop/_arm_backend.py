"""The arm's backends: the driver interface and the MuJoCo simulation (private).

:class:`ArmBackend` is what a robot driver gives :class:`~athenakin.teleop.SimulatedArm`:
``read_encoders()`` and ``write(forces, positions)``. :class:`MujocoBackend`, the
embedded default, is the exported MJCF (:func:`athenakin.sim.mjcf_from_design` with
``masses=``: the mass model's inertias, force motors, the loops closed by equality
constraints) stepped by MuJoCo; it reports MuJoCo's instability (its warning counters)
and a loop-closure error above :data:`CLOSURE_TOL` as a fault, and engages simulated
brakes (:data:`BRAKE_FORCE`) while no command is written. Its stroke ends are as stiff as its
loop closures (:data:`CONSTRAINT_STEPS`): ``MAX_FORCE`` into one sinks a carriage about
0.1 mm past it, well within the arm's reading margin.

Units: m, m/s, N; s.
"""

from __future__ import annotations

import math
from typing import Any, Protocol, runtime_checkable

import numpy as np

from .._typing import FloatArray
from .._validation import check_count
from ..design import Design
from ..errors import InvalidInputError
from ._arm_checks import vector3
from ._filter import check_rate
from ._servo import MIN_MODAL_MASS

__all__ = ["ArmBackend", "MujocoBackend", "CLOSURE_TOL", "SUBSTEP_S", "MAX_SUBSTEPS",
           "BRAKE_FORCE"]

#: Largest loop-closure error of the simulation before the arm faults, m.
CLOSURE_TOL = 1e-6
#: Longest MuJoCo step of :class:`MujocoBackend` (it takes ``ceil(1 / (rate SUBSTEP_S))``
#: steps per cycle), s.
SUBSTEP_S = 5e-4
#: Time constant of the loop-closure constraints and the brakes, in MuJoCo steps (2: the
#: stiffest MuJoCo keeps stable, its ``solref`` floor).
CONSTRAINT_STEPS = 2.0
#: Most MuJoCo steps per cycle (so the MuJoCo backend runs at 10 Hz or faster).
MAX_SUBSTEPS = 200
#: Friction force of the simulated brakes (``DISABLED``, ``FAULT``), N.
BRAKE_FORCE = 1000.0


@runtime_checkable
class ArmBackend(Protocol):
    """What a robot driver provides to :class:`~athenakin.teleop.SimulatedArm`: two methods.

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
        0.5 ms, RK4, Newton's constraint solver to 1e-12, the loop closures and the
        brakes with a time constant of :data:`CONSTRAINT_STEPS` steps; the loop-closure
        error stays below 1e-7 m, a tenth of :data:`CLOSURE_TOL`, for the reference and
        slender-rod mass models at 100 Hz to 4 kHz in ``tests/test_teleop_arm_strict.py``).
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

        q0 = vector3(q0, "q0")
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
        m.eq_solref[:] = [CONSTRAINT_STEPS * dt, 1.0]
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
        m.dof_solref[self._vadr] = [CONSTRAINT_STEPS * dt, 1.0]   # the brakes: a stiff dry friction
        m.dof_solimp[self._vadr] = [0.9999, 0.9999, 0.001, 0.5, 2.0]
        jids = [m.joint(n).id for n in ACTUATED]       # the stroke ends: as stiff as the loops
        m.jnt_solref[jids] = [CONSTRAINT_STEPS * dt, 1.0]
        m.jnt_solimp[jids] = [0.9999, 0.9999, 0.001, 0.5, 2.0]
        self._tip = m.site("tool_tip").id
        pairs = [(m.site(c.a).id, m.site(c.b).id) for c in LOOP_CLOSURES
                 if c.kind in ("point", "pose")]
        self._site_a = np.array([a for a, _ in pairs])
        self._site_b = np.array([b for _, b in pairs])
        self._unstable = np.array([int(w) for w in (mujoco.mjtWarning.mjWARN_BADQACC,
                                                    mujoco.mjtWarning.mjWARN_BADQVEL,
                                                    mujoco.mjtWarning.mjWARN_BADQPOS)])
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

    def _warnings(self) -> int:
        """How often MuJoCo has warned of a bad acceleration, velocity or position."""
        return int(self.data.warning.number[self._unstable].sum())

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
        gap = self.data.site_xpos[self._site_a] - self.data.site_xpos[self._site_b]
        return float(np.sqrt(np.einsum("ij,ij->i", gap, gap).max()))

