"""``ak.Robot``: one ATHENA as a value (design, RCM frame, bodies, masses), as Pinocchio's Model.

A thin model object over the functional core: it bundles the arguments that every call
of athenakin repeats (``T_b_e, design`` and, where they apply, ``bodies``, ``environment``
and ``masses``) and its methods are one-line calls of the public functions, never a
second implementation. The functional forms stay the reference; a method's options are
those of its function, passed through unchanged (keyword-only)::

    robot = ak.Robot.default()
    sol = robot.forward_kinematics(q)            # ak.forward_kinematics(q, T_b_e, design)
    cl = robot.clearance(q, slot="all")          # ak.collision.clearance(q, T_b_e, design, ...)
    tau = robot.inverse_dynamics(q, qd, qdd)     # ak.dynamics.inverse_dynamics(..., masses=...)

A ``Robot`` is frozen and holds no cache: Pinocchio's ``Data`` has no counterpart here,
each call returns its own frozen result.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ._dispatch import forward_kinematics, inverse_kinematics, q_from_instrument, q_from_tool_tip
from ._typing import FloatArray
from ._validation import check_frame
from .design import Design, resolve_design

__all__ = ["Robot"]


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
        if self.bodies is not None:
            from .collision import Bodies

            if not isinstance(self.bodies, Bodies):
                raise TypeError(f"bodies: expected athenakin.collision.Bodies or None, got "
                                f"{type(self.bodies).__name__}")
        if self.environment is not None:
            from .collision import Environment

            if not isinstance(self.environment, Environment):
                raise TypeError(f"environment: expected athenakin.collision.Environment or "
                                f"None, got {type(self.environment).__name__}")
        if self.masses is not None:
            from .dynamics import MassModel

            if not isinstance(self.masses, MassModel):
                raise TypeError(f"masses: expected athenakin.dynamics.MassModel or None, got "
                                f"{type(self.masses).__name__}")

    @classmethod
    def default(cls, design: Design | None = None, **parts: Any) -> Robot:
        """The robot of ``design`` (default: the reference) at its reference set-up.

        Parameters
        ----------
        design : Design, optional
            Default :meth:`athenakin.Design.default`.
        **parts
            ``bodies``, ``environment``, ``masses`` as for the class.

        Returns
        -------
        Robot
            With ``T_b_e = athenakin.default_rcm_frame(design)``.
        """
        from .robot import default_rcm_frame

        design = resolve_design(design)
        return cls(default_rcm_frame(design), design, **parts)

    def replace(self, **changes: Any) -> Robot:
        """A copy with some fields changed (``dataclasses.replace``), checked again.

        Parameters
        ----------
        **changes
            New values of ``design``, ``T_b_e``, ``bodies``, ``environment``, ``masses``.

        Returns
        -------
        Robot
        """
        return dataclasses.replace(self, **changes)

    # --- kinematics (athenakin) -------------------------------------------------------------
    def forward_kinematics(self, q: ArrayLike, **options: Any) -> Any:
        """:func:`athenakin.forward_kinematics` of this robot: ``q`` (..., 3) in m."""
        return forward_kinematics(q, self.T_b_e, self.design, **options)

    def inverse_kinematics(self, u345: ArrayLike, **options: Any) -> Any:
        """:func:`athenakin.inverse_kinematics`: spherical-joint angles (..., 3), rad."""
        return inverse_kinematics(self.T_b_e, u345, self.design, **options)

    def q_from_tool_tip(self, tip_e: ArrayLike, **options: Any) -> Any:
        """:func:`athenakin.q_from_tool_tip`: the tool tip (..., 3) in the RCM frame, m."""
        return q_from_tool_tip(self.T_b_e, tip_e, self.design, **options)

    def q_from_instrument(self, direction_e: ArrayLike, p: ArrayLike, **options: Any) -> Any:
        """:func:`athenakin.q_from_instrument`: direction (..., 3) in ``e`` and ``p`` (...), m."""
        return q_from_instrument(self.T_b_e, direction_e, p, self.design, **options)

    # --- analysis ------------------------------------------------------------------------------
    def tool_tip_jacobian(self, q: ArrayLike, **options: Any) -> Any:
        """:func:`athenakin.analysis.tool_tip_jacobian`, shape (..., 3, 3)."""
        from .analysis import tool_tip_jacobian

        return tool_tip_jacobian(q, self.T_b_e, self.design, **options)

    def singularities(self, q: ArrayLike, **options: Any) -> Any:
        """:func:`athenakin.analysis.singularities`."""
        from .analysis import singularities

        return singularities(q, self.T_b_e, self.design, **options)

    # --- bodies (athenakin.collision) ----------------------------------------------------------
    def clearance(self, q: ArrayLike, **options: Any) -> Any:
        """:func:`athenakin.collision.clearance` with this robot's bodies and environment."""
        from .collision import clearance

        return clearance(q, self.T_b_e, self.design, **self._parts(options, "bodies",
                                                                    "environment"))

    # --- dynamics (athenakin.dynamics) ---------------------------------------------------------
    def statics(self, q: ArrayLike, **options: Any) -> Any:
        """:func:`athenakin.dynamics.statics` with this robot's masses."""
        from .dynamics import statics

        return statics(q, self.T_b_e, self.design, **self._parts(options, "masses"))

    def inverse_dynamics(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike,
                         **options: Any) -> Any:
        """:func:`athenakin.dynamics.inverse_dynamics`: actuator forces (..., 3), N."""
        from .dynamics import inverse_dynamics

        return inverse_dynamics(q, qd, qdd, self.T_b_e, self.design,
                                **self._parts(options, "masses"))

    def forward_dynamics(self, q: ArrayLike, qd: ArrayLike, forces: ArrayLike,
                         **options: Any) -> Any:
        """:func:`athenakin.dynamics.forward_dynamics`: accelerations (..., 3), m/s^2."""
        from .dynamics import forward_dynamics

        return forward_dynamics(q, qd, forces, self.T_b_e, self.design,
                                **self._parts(options, "masses"))

    def mass_matrix(self, q: ArrayLike, **options: Any) -> Any:
        """:func:`athenakin.dynamics.mass_matrix`, shape (..., 3, 3), kg."""
        from .dynamics import mass_matrix

        return mass_matrix(q, self.T_b_e, self.design, **self._parts(options, "masses"))

    def force_capability(self, q: ArrayLike, **options: Any) -> Any:
        """:func:`athenakin.dynamics.force_capability` (``f_max=`` required)."""
        from .dynamics import force_capability

        return force_capability(q, self.T_b_e, self.design, **self._parts(options, "masses"))

    # --- exports (athenakin.sim) ---------------------------------------------------------------
    def mjcf(self, **options: Any) -> str:
        """:func:`athenakin.sim.mjcf_from_design`: the MJCF text, with bodies and masses."""
        from .sim import mjcf_from_design

        return mjcf_from_design(self.T_b_e, self.design,
                                **self._parts(options, "bodies", "environment", "masses"))

    def urdf(self, **options: Any) -> str:
        """:func:`athenakin.sim.urdf_from_design`: the URDF text, with the bodies."""
        from .sim import urdf_from_design

        return urdf_from_design(self.T_b_e, self.design, **self._parts(options, "bodies"))

    def _parts(self, options: dict[str, Any], *names: str) -> dict[str, Any]:
        """``options`` with this robot's parts filled in where the caller gave none."""
        for name in names:
            value = getattr(self, name)
            if value is not None and name not in options:
                options[name] = value
        return options
