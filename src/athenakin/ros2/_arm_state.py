"""The arm node's state messages: one forward kinematics per state, filled in place (private).

:class:`StateMessages` keeps one message object per state topic and refills it every
publishing cycle: the numbers go into the messages' own ``array('d')`` fields through
numpy views, every header takes the cycle's one stamp, and nothing is built again but
the floats of the poses. ``measured_js`` and the ``joint_states`` of
topic_based_ros2_control are one message (the same contents on two topics). The joint
states need no kinematics (:meth:`StateMessages.fill_joints`): the node publishes them
before it fills the poses (:meth:`StateMessages.fill_poses`).

The kinematics of a cycle is one forward kinematics of the measured position on the
arm's slot (its tip frame on ``measured_cp``, its joints on ``/joint_states``, its tip
Jacobian for ``measured_cv``) and one of the setpoint (its tip frame on ``setpoint_cp``,
kept while the setpoint stays where it is): compiled
(:meth:`athenakin.fast.ControlLoop.fk_slot`, ``tool_tip_jacobian`` and the joint values
of ``/tf``, :func:`athenakin.fast._frame_kernels.joint_values_into`) or, where the backend
policy says numpy, the reference functions; the same numbers to rounding (tested).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._typing import FloatArray
from ..design import Design
from ..robot._fk import SLOT_MODE
from ..ros._frames import BASE_FRAME, UrdfModel, joint_values, quaternion_xyzw
from ..sim import JOINTS
from ._convert import ACTUATORS, joint_state, pose_stamped, twist_stamped

__all__ = ["StateMessages", "rotation_rate"]


def rotation_rate(R0: FloatArray, R1: FloatArray, dt: float) -> FloatArray:
    """Angular velocity (base frame, rad/s) that turns ``R0`` into ``R1`` in ``dt`` s.

    Parameters
    ----------
    R0, R1 : ndarray, shape (3, 3)
        Two rotations, base frame.
    dt : float
        Time between them, s.

    Returns
    -------
    ndarray, shape (3,)
    """
    (a, b, c), (d, e, f), (g, h, i) = (R0.T @ R1).tolist()
    angle = math.acos(min(1.0, max(-1.0, (a + e + i - 1.0) / 2.0)))
    s = math.sin(angle)
    k = 0.5 if s < 1e-9 else angle / (2.0 * s)
    w = np.array([(h - f) * k, (c - g) * k, (d - b) * k])
    return np.asarray(R0 @ w / dt, dtype=float)


class _SlotKinematics:
    """Forward kinematics of one reading on one slot, its tip Jacobian and URDF joints.

    Compiled (two :class:`~athenakin.fast.ControlLoop`: the measured reading and the
    setpoint keep their own buffers) or the numpy reference.
    """

    def __init__(self, T_b_e: FloatArray, design: Design, slot: int, urdf: UrdfModel,
                 compiled: bool) -> None:
        self.T_b_e, self.design, self.slot, self.urdf = T_b_e, design, slot, urdf
        self.mode = int(SLOT_MODE[slot])
        self.compiled = compiled
        if compiled:
            from ..fast import ControlLoop
            from ..ros._frames import kernel_plan

            self._measured, self._setpoint = ControlLoop(T_b_e, design), ControlLoop(T_b_e,
                                                                                    design)
            self._plan = kernel_plan(urdf, ())[0]
            self._q1, self._p1 = np.empty((1, 3)), np.empty(1)
            self._u1, self._O1 = np.empty((1, 5)), np.empty((1, 3))
            self._valid1 = np.ones(1, dtype=bool)

    def setpoint_tip(self, q: FloatArray) -> FloatArray:
        """``T_b_tip`` (4, 4) of ``q`` on the slot (NaN where it does not assemble there)."""
        if self.compiled:
            return self._setpoint.fk_slot(q, self.slot)[4]
        from ..robot import forward_kinematics

        sol = forward_kinematics(q, self.T_b_e, self.design, errors="flag")
        return np.asarray(sol.T_b_tip[self.slot])

    def measured(self, q: FloatArray, joints: FloatArray
                 ) -> tuple[bool, FloatArray, FloatArray | None]:
        """The tip frame of ``q``, its Jacobian (base frame) and the URDF joints into ``joints``.

        Returns ``(valid, T_b_tip, J)``: ``valid`` False (``J`` None, ``joints`` untouched)
        where ``q`` does not assemble in the slot.
        """
        if self.compiled:
            from ..fast._frame_kernels import joint_values_into

            reason, p, u, T_b_s, tip = self._measured.fk_slot(q, self.slot)
            if reason != 0:
                return False, tip, None
            self._q1[0], self._p1[0], self._u1[0], self._O1[0] = q, p, u, T_b_s[:3, 3]
            joint_values_into(self._q1, self._p1, self._u1, self._O1, self._valid1,
                              *self._plan, joints[None])
            return True, tip, self._measured.tool_tip_jacobian(q, self.mode)
        from ..analysis import tool_tip_jacobian
        from ..robot import forward_kinematics

        sol = forward_kinematics(q, self.T_b_e, self.design, errors="flag")
        k = self.slot
        tip = np.asarray(sol.T_b_tip[k])
        if not sol.valid[k]:
            return False, tip, None
        jv = joint_values(self.urdf, q[None], sol.p[k][None], sol.u[k][None],
                          sol.T_b_s[k, :3, 3][None])
        joints[:] = [v[0] for v in jv.values()]
        return True, tip, tool_tip_jacobian(q, self.T_b_e, self.design, mode=self.mode)


class StateMessages:
    """The arm's state messages of one cycle, refilled in place.

    Parameters
    ----------
    T_b_e : ndarray, shape (4, 4)
        The arm's RCM frame.
    design : Design
    slot : int
        The arm's FK slot (:attr:`athenakin.teleop.SimulatedArm.slot`).
    urdf : UrdfModel
        The URDF of ``/robot_description`` (its joints make ``/joint_states``).
    dt : float
        Time between two published states, s (the angular velocity of ``measured_cv``).
    compiled : bool
        The compiled kinematics (else the numpy reference).

    Attributes
    ----------
    measured_js, setpoint_js, urdf_joint_states : sensor_msgs.msg.JointState
    measured_cp, setpoint_cp : geometry_msgs.msg.PoseStamped
    measured_cv : geometry_msgs.msg.TwistStamped
        The messages :meth:`fill` writes; publish them before the next call.
    """

    def __init__(self, T_b_e: FloatArray, design: Design, slot: int, urdf: UrdfModel, *,
                 dt: float, compiled: bool) -> None:
        self._kin = _SlotKinematics(T_b_e, design, slot, urdf, compiled)
        self.dt = dt
        zero = np.zeros(3)
        self.measured_js = joint_state(ACTUATORS, zero, zero, zero)
        self.setpoint_js = joint_state(ACTUATORS, zero, zero, zero)
        self.urdf_joint_states = joint_state(list(JOINTS), np.zeros(len(JOINTS)))
        self.measured_cp = pose_stamped(np.eye(4), BASE_FRAME)
        self.setpoint_cp = pose_stamped(np.eye(4), BASE_FRAME)
        self.measured_cv = twist_stamped(zero, zero, BASE_FRAME)
        # numpy views of the messages' array('d') fields (written in place, never resized)
        self._js = tuple(np.frombuffer(getattr(m, f), dtype=float)
                         for m in (self.measured_js, self.setpoint_js)
                         for f in ("position", "velocity", "effort"))
        self._joints = np.frombuffer(self.urdf_joint_states.position, dtype=float)
        self._R = np.empty((2, 3, 3))          # the rotations of measured_cp, setpoint_cp
        self._sp_q: FloatArray | None = None   # the setpoint whose tip frame is held
        self._sp_tip = np.full((4, 4), np.nan)
        self._prev_R: FloatArray | None = None

    def warm_up(self, js: Any, sp: Any, stamp: Any) -> None:
        """:meth:`fill` once and forget it: the kernels compiled or loaded before any state.

        Parameters
        ----------
        js, sp, stamp
            As in :meth:`fill`.
        """
        self.fill(js, sp, stamp)
        self.forget_rotation()       # the first published state has no rotation before it

    def forget_rotation(self) -> None:
        """No rotation before the next :meth:`fill_poses` (a cycle without its kinematics).

        The next ``measured_cv`` then has an angular rate of zero, as the first one after
        start: a rate from two rotations more than a cycle apart would be a wrong one.
        """
        self._prev_R = None

    def fill(self, js: Any, sp: Any, stamp: Any) -> bool:
        """Write one cycle's state into the messages: :meth:`fill_joints`, :meth:`fill_poses`.

        Parameters
        ----------
        js, sp : athenakin.teleop.JointState
            The arm's ``measured_js()`` and ``setpoint_js()`` (positions m, velocities
            m/s, efforts N; shape (3,) each).
        stamp : builtin_interfaces.msg.Time
            The stamp of every message.

        Returns
        -------
        bool
            As :meth:`fill_poses`.
        """
        self.fill_joints(js, sp, stamp)
        return self.fill_poses(js, sp)

    def fill_joints(self, js: Any, sp: Any, stamp: Any) -> None:
        """Write the actuators' messages (``measured_js``, ``setpoint_js``) and every stamp.

        No kinematics: the joint states can be published before :meth:`fill_poses` runs.

        Parameters
        ----------
        js, sp, stamp
            As in :meth:`fill`.
        """
        for view, values in zip(self._js, (js.position, js.velocity, js.effort, sp.position,
                                           sp.velocity, sp.effort), strict=True):
            view[:] = values
        for m in (self.measured_js, self.setpoint_js, self.urdf_joint_states,
                  self.measured_cp, self.setpoint_cp, self.measured_cv):
            m.header.stamp = stamp

    def fill_poses(self, js: Any, sp: Any) -> bool:
        """Write the kinematic messages: the tip poses, its twist and the URDF joints.

        Parameters
        ----------
        js, sp
            As in :meth:`fill` (the stamps are :meth:`fill_joints`'s).

        Returns
        -------
        bool
            True where the measured position assembles in the slot: ``measured_cv`` and
            ``urdf_joint_states`` hold this cycle (else they are not to be published).
        """
        q = np.asarray(js.position, dtype=float)
        valid, tip, J = self._kin.measured(q, self._joints)
        sq = np.asarray(sp.position, dtype=float)
        if self._sp_q is None or not np.array_equal(sq, self._sp_q):
            self._sp_tip[:] = self._kin.setpoint_tip(sq)
            self._sp_q = sq.copy()
        self._R[0], self._R[1] = tip[:3, :3], self._sp_tip[:3, :3]
        quat = quaternion_xyzw(self._R).tolist()
        _set_pose(self.measured_cp, tip, quat[0])
        _set_pose(self.setpoint_cp, self._sp_tip, quat[1])
        if not valid:
            return False
        assert J is not None
        R = self._R[0].copy()
        ang = (0.0, 0.0, 0.0) if self._prev_R is None else \
            rotation_rate(self._prev_R, R, self.dt).tolist()
        self._prev_R = R
        lin, w = self.measured_cv.twist.linear, self.measured_cv.twist.angular
        lin.x, lin.y, lin.z = (J @ np.asarray(js.velocity, dtype=float)).tolist()
        w.x, w.y, w.z = ang
        return True


def _set_pose(msg: Any, T: FloatArray, xyzw: list[float]) -> None:
    """The position (m) of ``T`` and the quaternion ``xyzw`` into a ``PoseStamped``."""
    p, o = msg.pose.position, msg.pose.orientation
    p.x, p.y, p.z = T[:3, 3].tolist()
    o.x, o.y, o.z, o.w = xyzw
