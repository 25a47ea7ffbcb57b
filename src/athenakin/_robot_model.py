"""``ak.Robot``: one ATHENA as a value (design, RCM frame, bodies, masses), as Pinocchio's Model.

A thin model object over the functional core: it bundles the arguments that every call
of athenakin repeats (``T_b_e, design`` and, where they apply, ``bodies``, ``environment``
and ``masses``) and its methods are one-line calls of the public functions, never a
second implementation. The functional forms stay the reference; a method's signature is
its function's (the same keyword-only options and defaults, tested), less the arguments
the Robot holds; a part given to a method (``bodies=``, ``masses=``, ...) wins over the
Robot's own::

    robot = ak.Robot.default()
    sol = robot.forward_kinematics(q)            # ak.forward_kinematics(q, T_b_e, design)
    cl = robot.clearance(q, slot="all")          # ak.collision.clearance(q, T_b_e, design, ...)
    tau = robot.inverse_dynamics(q, qd, qdd)     # ak.dynamics.inverse_dynamics(..., masses=...)

A ``Robot`` is frozen and holds no cache (Pinocchio's ``Model``): the systems take it
(``athenakin.teleop.Teleop(robot, q0=...)``, ``athenakin.motion.Tracker(robot, q0=...)``,
``athenakin.motion.plan(tips_e, robot)``) and build from it, once, the per-call data they
own (the IK and dynamics loops, the clearance pair tables and buffers). Each of them also
takes the functional form ``(T_b_e, design, bodies=, environment=, ...)``, which
:func:`resolve_robot` turns into the Robot.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from ._dispatch import forward_kinematics, inverse_kinematics, q_from_instrument, q_from_tool_tip
from ._typing import FloatArray
from ._validation import _looks_like_design, check_frame
from .design import Design, resolve_design

__all__ = ["Robot", "resolve_robot"]

_KEEP: Any = object()     # replace(): the field as it is


def _part_class(name: str) -> tuple[type, str]:
    """The class of a Robot's part ``name`` (imported on first use) and its public name."""
    if name == "masses":
        from .dynamics import MassModel

        return MassModel, "athenakin.dynamics.MassModel"
    from .collision import Bodies, Environment

    if name == "bodies":
        return Bodies, "athenakin.collision.Bodies"
    return Environment, "athenakin.collision.Environment"


@dataclasses.dataclass(frozen=True, eq=False)
class Robot:
    """One ATHENA: its design, its RCM frame, and (optionally) its bodies, obstacles, masses.

    Attributes
    ----------
    T_b_e : ndarray, shape (4, 4)
        Pose of the RCM frame ``e`` in the base frame ``b`` (m); a read-only copy.
    design : Design
        The geometry and strokes (:class:`athenakin.Design`). The order of every function:
        ``Robot(T_b_e, design)``; the old order is refused by name.
    bodies : athenakin.collision.Bodies or None
        The links as capsules for :meth:`clearance` and the exports (``None``: the
        defaults of :func:`athenakin.collision.clearance`).
    environment : athenakin.collision.Environment or None
        Obstacles for :meth:`clearance` (``None``: none).
    masses : athenakin.dynamics.MassModel or None
        The mass model of the dynamics methods (``None``: the reference masses).

    Examples
    --------
    >>> import numpy as np, athenakin as ak
    >>> robot = ak.Robot.default()
    >>> sol = robot.forward_kinematics([-0.1, 0.1, 0.45])
    >>> int(sol.n_solutions)
    16
    >>> q, _ = robot.q_from_tool_tip(sol.tip[0] @ robot.T_b_e[:3, :3]
    ...                              - robot.T_b_e[:3, 3] @ robot.T_b_e[:3, :3])
    >>> bool(np.allclose(q, [-0.1, 0.1, 0.45], atol=1e-12))
    True
    """

    T_b_e: FloatArray
    design: Design
    bodies: Any = None
    environment: Any = None
    masses: Any = None

    def __post_init__(self) -> None:
        T = np.array(check_frame(self.T_b_e, "T_b_e"), dtype=float)
        object.__setattr__(self, "design", resolve_design(self.design))
        T.setflags(write=False)
        object.__setattr__(self, "T_b_e", T)
        for name in ("bodies", "environment", "masses"):
            value = getattr(self, name)
            if value is not None:
                cls, public = _part_class(name)
                if not isinstance(value, cls):
                    raise TypeError(f"{name}: expected {public} or None, got "
                                    f"{type(value).__name__}")

    @classmethod
    def default(cls, design: Design | None = None, *, bodies: Any = None,
                environment: Any = None, masses: Any = None) -> Robot:
        """The robot of ``design`` (default: the reference) at its reference set-up.

        Parameters
        ----------
        design : Design, optional
            Default :meth:`athenakin.Design.default`.
        bodies : athenakin.collision.Bodies, optional, keyword-only
        environment : athenakin.collision.Environment, optional, keyword-only
        masses : athenakin.dynamics.MassModel, optional, keyword-only
            As for the class.

        Returns
        -------
        Robot
            With ``T_b_e = athenakin.default_rcm_frame(design)``.
        """
        from .robot import default_rcm_frame

        design = resolve_design(design)
        return cls(default_rcm_frame(design), design, bodies=bodies, environment=environment,
                   masses=masses)

    def replace(self, *, T_b_e: ArrayLike | None = None, design: Design | None = None,
                bodies: Any = _KEEP, environment: Any = _KEEP, masses: Any = _KEEP) -> Robot:
        """A copy with some fields changed, checked again.

        Parameters
        ----------
        T_b_e : array-like, shape (4, 4), optional, keyword-only
        design : Design, optional, keyword-only
            New set-up or design (default: this robot's).
        bodies, environment, masses : optional, keyword-only
            New parts; ``None`` removes one (default: this robot's).

        Returns
        -------
        Robot
        """
        return Robot(self.T_b_e if T_b_e is None else T_b_e,  # type: ignore[arg-type]
                     self.design if design is None else design,
                     bodies=self.bodies if bodies is _KEEP else bodies,
                     environment=self.environment if environment is _KEEP else environment,
                     masses=self.masses if masses is _KEEP else masses)

    # --- kinematics (athenakin) -------------------------------------------------------------
    def forward_kinematics(self, q: ArrayLike, *, method: str = "closed", errors: str = "auto",
                           tangent_tol: float = 1e-07, degenerate_tol: float = 1e-12,
                           p_zero_tol: float = 1e-12, closure_tol: float = 1e-09,
                           fields: tuple[str, ...] | None = None,
                           backend: str = "auto") -> Any:
        """:func:`athenakin.forward_kinematics` of this robot.

        Parameters
        ----------
        q : array-like, shape (..., 3)
            Actuators, m.
        method, errors, tangent_tol, degenerate_tol, p_zero_tol, closure_tol, fields, backend
            As for :func:`athenakin.forward_kinematics` (keyword-only).

        Returns
        -------
        FKSolution
        """
        return forward_kinematics(q, self.T_b_e, self.design, method=method,  # type: ignore[arg-type]
                                  errors=errors, tangent_tol=tangent_tol,  # type: ignore[arg-type]
                                  degenerate_tol=degenerate_tol, p_zero_tol=p_zero_tol,
                                  closure_tol=closure_tol, fields=fields,
                                  backend=backend)  # type: ignore[arg-type]

    def inverse_kinematics(self, u345: ArrayLike, *, errors: str = "auto",
                           singular_tol: float = 1e-12, closure_tol: float = 1e-09,
                           fields: tuple[str, ...] | None = None,
                           backend: str = "auto") -> Any:
        """:func:`athenakin.inverse_kinematics` of this robot.

        Parameters
        ----------
        u345 : array-like, shape (..., 3)
            Spherical-joint angles, rad.
        errors, singular_tol, closure_tol, fields, backend
            As for :func:`athenakin.inverse_kinematics` (keyword-only).

        Returns
        -------
        q : ndarray, shape (..., 3)
        passive : PassiveJoints
        """
        return inverse_kinematics(self.T_b_e, u345, self.design,
                                  errors=errors,  # type: ignore[arg-type]
                                  singular_tol=singular_tol, closure_tol=closure_tol,
                                  fields=fields, backend=backend)  # type: ignore[arg-type]

    def q_from_tool_tip(self, tip_e: ArrayLike, *, errors: str = "auto",
                        backend: str = "auto") -> Any:
        """:func:`athenakin.q_from_tool_tip` of this robot.

        Parameters
        ----------
        tip_e : array-like, shape (..., 3)
            The tool tip in the RCM frame E, m.
        errors, backend
            As for :func:`athenakin.q_from_tool_tip` (keyword-only).

        Returns
        -------
        q : ndarray, shape (..., 3)
        result : InstrumentIK
        """
        return q_from_tool_tip(self.T_b_e, tip_e, self.design,
                               errors=errors, backend=backend)  # type: ignore[arg-type]

    def q_from_instrument(self, direction_e: ArrayLike, p: ArrayLike, *, errors: str = "auto",
                          backend: str = "auto") -> Any:
        """:func:`athenakin.q_from_instrument` of this robot.

        Parameters
        ----------
        direction_e : array-like, shape (..., 3)
            Instrument direction in E.
        p : array-like, shape (...)
            Insertion beyond the RCM, m.
        errors, backend
            As for :func:`athenakin.q_from_instrument` (keyword-only).

        Returns
        -------
        q : ndarray, shape (..., 3)
        result : InstrumentIK
        """
        return q_from_instrument(self.T_b_e, direction_e, p, self.design,
                                 errors=errors, backend=backend)  # type: ignore[arg-type]

    # --- analysis ------------------------------------------------------------------------------
    def tool_tip_jacobian(self, q: ArrayLike, *, mode: ArrayLike = 1, frame: str = "base",
                          backend: str = "auto") -> Any:
        """:func:`athenakin.analysis.tool_tip_jacobian` of this robot.

        Parameters
        ----------
        q : array-like, shape (..., 3)
            Actuators, m.
        mode, frame, backend
            As for :func:`athenakin.analysis.tool_tip_jacobian` (keyword-only).

        Returns
        -------
        ndarray, shape (..., 3, 3)
        """
        from .analysis import tool_tip_jacobian

        return tool_tip_jacobian(q, self.T_b_e, self.design, mode=mode,
                                 frame=frame, backend=backend)  # type: ignore[arg-type]

    def singularities(self, q: ArrayLike, *, mode: ArrayLike = 1,
                      tol: Any = None, jacobians: bool = True) -> Any:
        """:func:`athenakin.analysis.singularities` of this robot.

        Parameters
        ----------
        q : array-like, shape (..., 3)
            Actuators, m.
        mode, tol, jacobians
            As for :func:`athenakin.analysis.singularities` (keyword-only).

        Returns
        -------
        SingularityReport
        """
        from .analysis import singularities

        return singularities(q, self.T_b_e, self.design, mode=mode, tol=tol,
                             jacobians=jacobians)

    # --- bodies (athenakin.collision) ----------------------------------------------------------
    def clearance(self, q: ArrayLike, *, slot: int | Literal["all"] = 0, bodies: Any = None,
                  environment: Any = None, margin: float = 0.0, witness: bool = True,
                  backend: str = "auto") -> Any:
        """:func:`athenakin.collision.clearance` with this robot's bodies and environment.

        Parameters
        ----------
        q : array-like, shape (..., 3)
            Actuators, m.
        slot, margin, witness, backend
            As for :func:`athenakin.collision.clearance` (keyword-only).
        bodies, environment : optional, keyword-only
            Default this robot's.

        Returns
        -------
        Clearance
        """
        from .collision import clearance

        return clearance(q, self.T_b_e, self.design, slot=slot,
                         bodies=self._part("bodies", bodies),
                         environment=self._part("environment", environment), margin=margin,
                         witness=witness, backend=backend)  # type: ignore[arg-type]

    # --- dynamics (athenakin.dynamics) ---------------------------------------------------------
    def statics(self, q: ArrayLike, *, masses: Any = None,
                gravity: ArrayLike = (0.0, 0.0, -9.81), tip_force: ArrayLike | None = None,
                slot: int = 0, errors: str = "auto", rcm_load: bool = True,
                backend: str = "auto") -> Any:
        """:func:`athenakin.dynamics.statics` with this robot's masses.

        Parameters
        ----------
        q : array-like, shape (..., 3)
            Actuators, m.
        masses : MassModel, optional, keyword-only
            Default this robot's.
        gravity, tip_force, slot, errors, rcm_load, backend
            As for :func:`athenakin.dynamics.statics` (keyword-only).

        Returns
        -------
        Statics
        """
        from .dynamics import statics

        return self._with_masses(statics, q, masses=masses, gravity=gravity,
                                 tip_force=tip_force, slot=slot, rcm_load=rcm_load,
                                 backend=backend, errors=errors)

    def inverse_dynamics(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, *,
                         masses: Any = None, gravity: ArrayLike = (0.0, 0.0, -9.81),
                         tip_force: ArrayLike | None = None, slot: int = 0,
                         errors: str = "auto", backend: str = "auto") -> Any:
        """:func:`athenakin.dynamics.inverse_dynamics` with this robot's masses.

        Parameters
        ----------
        q, qd, qdd : array-like, shape (..., 3)
            Actuator positions (m), velocities (m/s), accelerations (m/s^2).
        masses : MassModel, optional, keyword-only
            Default this robot's.
        gravity, tip_force, slot, errors, backend
            As for :func:`athenakin.dynamics.inverse_dynamics` (keyword-only).

        Returns
        -------
        ndarray, shape (..., 3)
            Actuator forces, N.
        """
        from .dynamics import inverse_dynamics

        return self._with_masses(inverse_dynamics, q, qd, qdd, masses=masses, gravity=gravity,
                                 tip_force=tip_force, slot=slot, errors=errors, backend=backend)

    def forward_dynamics(self, q: ArrayLike, qd: ArrayLike, forces: ArrayLike, *,
                         masses: Any = None, gravity: ArrayLike = (0.0, 0.0, -9.81),
                         tip_force: ArrayLike | None = None, slot: int = 0,
                         errors: str = "auto", backend: str = "auto") -> Any:
        """:func:`athenakin.dynamics.forward_dynamics` with this robot's masses.

        Parameters
        ----------
        q, qd : array-like, shape (..., 3)
            Actuator positions (m) and velocities (m/s).
        forces : array-like, shape (..., 3)
            Actuator forces, N.
        masses : MassModel, optional, keyword-only
            Default this robot's.
        gravity, tip_force, slot, errors, backend
            As for :func:`athenakin.dynamics.forward_dynamics` (keyword-only).

        Returns
        -------
        ndarray, shape (..., 3)
            Accelerations, m/s^2.
        """
        from .dynamics import forward_dynamics

        return self._with_masses(forward_dynamics, q, qd, forces, masses=masses,
                                 gravity=gravity, tip_force=tip_force, slot=slot,
                                 errors=errors, backend=backend)

    def mass_matrix(self, q: ArrayLike, *, masses: Any = None, slot: int = 0,
                    errors: str = "auto", backend: str = "auto") -> Any:
        """:func:`athenakin.dynamics.mass_matrix` with this robot's masses.

        Parameters
        ----------
        q : array-like, shape (..., 3)
            Actuators, m.
        masses : MassModel, optional, keyword-only
            Default this robot's.
        slot, errors, backend
            As for :func:`athenakin.dynamics.mass_matrix` (keyword-only).

        Returns
        -------
        ndarray, shape (..., 3, 3)
            kg.
        """
        from .dynamics import mass_matrix

        return self._with_masses(mass_matrix, q, masses=masses, slot=slot, errors=errors,
                                 backend=backend)

    def force_capability(self, q: ArrayLike, *, f_max: ArrayLike,
                         f_min: ArrayLike | None = None, masses: Any = None,
                         gravity: ArrayLike = (0.0, 0.0, -9.81), slot: int = 0,
                         errors: str = "auto", cond_max: float = 100.0,
                         backend: str = "auto") -> Any:
        """:func:`athenakin.dynamics.force_capability` with this robot's masses.

        Parameters
        ----------
        q : array-like, shape (..., 3)
            Actuators, m.
        f_max : array-like, keyword-only
            Actuator force bounds, N (required).
        f_min, gravity, slot, errors, cond_max, backend
            As for :func:`athenakin.dynamics.force_capability` (keyword-only;
            ``cond_max`` defaults to :data:`athenakin.dynamics.COND_MARGIN`).
        masses : MassModel, optional, keyword-only
            Default this robot's.

        Returns
        -------
        ForceCapability
        """
        from .dynamics import force_capability

        return self._with_masses(force_capability, q, masses=masses, f_max=f_max, f_min=f_min,
                                 gravity=gravity, slot=slot, cond_max=cond_max,
                                 backend=backend, errors=errors)

    # --- exports (athenakin.sim) ---------------------------------------------------------------
    def mjcf(self, *, q: ArrayLike | None = None, slot: int = 0, gravity: bool = True,
             model_name: str = "athena", bodies: Any = None, collision: bool | None = None,
             environment: Any = None, masses: Any = None) -> str:
        """:func:`athenakin.sim.mjcf_from_design`: the MJCF text, with bodies and masses.

        Parameters
        ----------
        q, slot, gravity, model_name, collision
            As for :func:`athenakin.sim.mjcf_from_design` (keyword-only).
        bodies, environment, masses : optional, keyword-only
            Default this robot's.

        Returns
        -------
        str
        """
        from .sim import mjcf_from_design

        return mjcf_from_design(self.T_b_e, self.design, q=q, slot=slot, gravity=gravity,
                                model_name=model_name, bodies=self._part("bodies", bodies),
                                collision=collision,
                                environment=self._part("environment", environment),
                                masses=self._part("masses", masses))

    def urdf(self, *, robot_name: str = "athena", q_zero: ArrayLike | None = None,
             zero_slot: int = 0, bodies: Any = None, collision: bool = True) -> str:
        """:func:`athenakin.sim.urdf_from_design`: the URDF text, with the bodies.

        Parameters
        ----------
        robot_name, q_zero, zero_slot, collision
            As for :func:`athenakin.sim.urdf_from_design` (keyword-only).
        bodies : optional, keyword-only
            Default this robot's.

        Returns
        -------
        str
        """
        from .sim import urdf_from_design

        return urdf_from_design(self.T_b_e, self.design, robot_name=robot_name, q_zero=q_zero,
                                zero_slot=zero_slot, bodies=self._part("bodies", bodies),
                                collision=collision)

    def _part(self, name: str, value: Any) -> Any:
        """``value``, or this robot's part ``name`` where the caller gave none."""
        return getattr(self, name) if value is None else value

    def _with_masses(self, function: Callable[..., Any], *state: ArrayLike, masses: Any,
                     **options: Any) -> Any:
        """A dynamics function of this robot: ``function(*state, T_b_e, design, masses=...)``.

        ``masses`` is this robot's where the caller gave none; ``options`` go as given.
        """
        return function(*state, self.T_b_e, self.design, masses=self._part("masses", masses),
                        **options)

def resolve_robot(robot: Any, design: Any = None, *, bodies: Any = None,
                  environment: Any = None, masses: Any = None) -> Robot:
    """The :class:`Robot` of a model argument: a Robot, or ``T_b_e`` and a design.

    The one conversion of the systems that take a Robot (``Teleop``, ``Tracker``,
    ``plan``): a Robot is taken as it is, with the parts given beside it filled in
    where it has none; the functional form ``(T_b_e, design, bodies=, ...)`` builds one.

    Parameters
    ----------
    robot : Robot or array-like, shape (4, 4)
        The model, or the RCM frame E in the base frame ``T_b_e`` (m).
    design : Design or str or os.PathLike, optional
        With ``T_b_e`` only (default :meth:`Design.default`); a Robot holds its own.
    bodies : athenakin.collision.Bodies, optional, keyword-only
    environment : athenakin.collision.Environment, optional, keyword-only
    masses : athenakin.dynamics.MassModel, optional, keyword-only
        Parts of the model; beside a Robot, only those it lacks.

    Returns
    -------
    Robot
        ``robot`` itself when it is a Robot and no part is given beside it.

    Raises
    ------
    TypeError
        A design beside a Robot; a part given beside a Robot that has its own; ``robot``
        neither a Robot nor an array-like (named ``robot``); a part of the wrong type.
    InvalidInputError
        ``T_b_e`` not a rigid transform of shape (4, 4), or a design in its place
        (:data:`athenakin._validation.ARGUMENT_ORDER`).
    """
    parts = {"bodies": bodies, "environment": environment, "masses": masses}
    if isinstance(robot, Robot):
        if design is not None:
            raise TypeError("design: give the design in the Robot, not beside it")
        for name, v in parts.items():
            if v is not None and getattr(robot, name) is not None:
                raise TypeError(f"{name}: the Robot has its own {name}; give one, not both")
        given = {k: v for k, v in parts.items() if v is not None}
        return robot.replace(**given) if given else robot
    if not (isinstance(robot, (np.ndarray, list, tuple)) or hasattr(robot, "__array__")
            or _looks_like_design(robot)):          # a design here: the argument order
        raise TypeError(f"robot: expected an athenakin.Robot or its RCM frame T_b_e "
                        f"(array-like, shape (4, 4)), got {type(robot).__name__}")
    return Robot(robot, design, **parts)
