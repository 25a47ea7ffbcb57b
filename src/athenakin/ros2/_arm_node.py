"""The arm on a ROS 2 graph: CRTK topics over :class:`athenakin.teleop.SimulatedArm` (private).

:class:`ArmNode` is a thin adapter. Its subscriptions convert a message
(:mod:`._convert`) and call the arm's own CRTK method (``servo_jp``, ``move_cp``,
``enable``, ...) under one lock; whatever the arm refuses (an exception: a bad
shape, a NaN, a goal it cannot profile; or a command the arm holds and flags in its
``refusal``: a stroke, an unreachable tip, an effort out of bounds, a state that takes
no command) is answered on ``status`` and never executed. A dedicated servo thread
steps the arm at its rate (or on each servo command's arrival, ``sync="command"``) and
publishes its state every ``rate / publish_rate`` cycles (each topic that has a reader:
:meth:`ArmNode.publish_once`); the ROS executor runs the
subscriptions on its own thread, so a burst of commands never delays a servo cycle by
more than the lock's hold (one method call).

Topics (relative names are under ``namespace``): docs/ros2.md has the table.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from .._validation import check_scalar
from ..design import Design, resolve_design
from ..errors import InvalidInputError
from ..ros._frames import BASE_FRAME, RCM_FRAME, urdf_model
from ._arm_state import StateMessages
from ._convert import actuator_command, stamp_ns, tip_command
from ._runtime import (
    CyclePacer,
    RosContext,
    control_executor,
    crtk_types,
    require_rclpy,
    run_until,
    spin_executor,
    stop_node,
)

__all__ = ["ArmNode", "ARM_TOPICS", "STATE_COMMANDS", "check_namespace"]

#: Topics of :class:`ArmNode`: key -> name (relative: under the namespace).
ARM_TOPICS = {
    "measured_js": "measured_js", "setpoint_js": "setpoint_js", "measured_cp": "measured_cp",
    "setpoint_cp": "setpoint_cp", "measured_cv": "measured_cv",
    "operating_state": "operating_state", "status": "status",
    "servo_jp": "servo_jp", "servo_cp": "servo_cp", "move_jp": "move_jp", "move_cp": "move_cp",
    "state_command": "state_command", "hold": "hold",
    "joint_states": "joint_states", "joint_commands": "joint_commands",
    "urdf_joint_states": "/joint_states", "robot_description": "/robot_description",
}
#: The ``state_command`` strings (CRTK's names) and the arm's method each calls.
STATE_COMMANDS = {"enable": "enable", "disable": "disable", "pause": "pause",
                  "resume": "resume", "home": "home", "unhome": "unhome"}


#: The joint-state publishers (keys of the node's publishers), which
#: :meth:`ArmNode.publish_once` sends first, and the message of
#: :class:`._arm_state.StateMessages` each sends.
_JOINT_TOPICS = {"measured_js": "measured_js", "joint_states": "measured_js",
                 "setpoint_js": "setpoint_js"}
#: The kinematic publishers (each sends the message of its own name), and whether it is
#: sent only where the measured position assembles in the slot.
_POSE_TOPICS = {"measured_cp": False, "setpoint_cp": False, "measured_cv": True,
                "urdf_joint_states": True}


def check_namespace(namespace: str) -> str:
    """A ROS namespace by rclpy's rules, with its leading ``/`` and without a trailing one.

    Raises
    ------
    TypeError
        Not a str.
    InvalidInputError
        Not a namespace (rclpy's reason, on one line).
    """
    from rclpy.exceptions import InvalidNamespaceException
    from rclpy.validate_namespace import validate_namespace

    if not isinstance(namespace, str):
        raise TypeError(f"namespace: expected a str, got {type(namespace).__name__}")
    ns = namespace if namespace.startswith("/") else "/" + namespace
    ns = ns.rstrip("/") or "/"
    try:
        validate_namespace(ns)
    except InvalidNamespaceException as exc:
        raise InvalidInputError(f"namespace: expected names of letters, digits and '_' "
                                f"separated by '/' (e.g. /athena), got {namespace!r}: "
                                f"{_rclpy_reason(exc, 'Invalid namespace: ')}") from None
    return ns


def resolve_topic(name: object, what: str, *, namespace: str = "/",
                  node: str = "node") -> str:
    """The full name of a ROS topic (absolute, relative or private), by rclpy's rules.

    rclpy's validator, its expansion (a relative name under ``namespace``, ``~`` under
    ``namespace/node``) and its check of the full name: what ``create_subscription``
    would refuse is refused here, before any node exists, with the parameter's name.

    Parameters
    ----------
    name : str
        Checked: a str.
    what : str
        The parameter's name in the error.
    namespace : str, keyword-only
        The node's namespace (checked, :func:`check_namespace`).
    node : str, keyword-only
        The node's name (for ``~``).

    Returns
    -------
    str
        The full topic name, e.g. ``/athena/measured_js``.

    Raises
    ------
    TypeError
        ``name`` not a str.
    InvalidInputError
        Not a topic name (rclpy's reason, on one line).
    """
    from rclpy.exceptions import InvalidTopicNameException
    from rclpy.expand_topic_name import expand_topic_name
    from rclpy.validate_full_topic_name import validate_full_topic_name
    from rclpy.validate_topic_name import validate_topic_name

    if not isinstance(name, str):
        raise TypeError(f"{what}: expected a str, got {type(name).__name__}")
    ns = check_namespace(namespace)
    try:
        validate_topic_name(name)
        full = expand_topic_name(name, node, ns)
        validate_full_topic_name(full)
    except (InvalidTopicNameException, ValueError) as exc:
        raise InvalidInputError(f"{what}: expected a ROS topic name (e.g. /master/pose), "
                                f"got {name!r}: {_rclpy_reason(exc, 'Invalid topic name: ')}"
                                ) from None
    return str(full)


def _rclpy_reason(exc: Exception, prefix: str) -> str:
    """The first line of an rclpy validator's message, without its ``prefix``."""
    return str(exc).splitlines()[0].removeprefix(prefix).rstrip(":")


def _qos(depth: int, *, latched: bool = False) -> Any:
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    return QoSProfile(depth=depth, history=HistoryPolicy.KEEP_LAST,
                      reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if latched
                      else DurabilityPolicy.VOLATILE)


class ArmNode:
    """ATHENA's arm on a ROS 2 graph under CRTK's names (rclpy, any RMW; Fast DDS by default).

    Parameters
    ----------
    arm : athenakin.teleop.SimulatedArm, optional
        The arm to serve (any backend); default a MuJoCo :class:`SimulatedArm` of
        ``T_b_e``, ``design``, ``q0`` and ``rate``.
    T_b_e : array-like, shape (4, 4), optional, keyword-only
        RCM frame in the base frame (default :func:`athenakin.default_rcm_frame`); taken
        from ``arm`` when given.
    design : Design, optional, keyword-only
    q0 : array-like, shape (3,), optional, keyword-only
        Start of the default arm, m.
    rate : float, keyword-only
        Servo cycles per second of the default arm, Hz (1000).
    namespace : str, keyword-only
        Namespace of the CRTK topics (``/athena``).
    publish_rate : float, keyword-only
        State messages per second, Hz (100; at most the servo rate, of which it is
        rounded to a whole divisor).
    sync : {"clock", "command"}, keyword-only
        When a servo cycle starts (:class:`~athenakin.ros2._runtime.CyclePacer`):
        ``"clock"`` (default) on the node's own grid of ``1 / rate`` s, so that a
        command waits up to one period for the next cycle; ``"command"`` also on a
        servo command's arrival (``servo_jp``, ``servo_cp``, ``joint_commands``), no
        sooner than 0.75 period after the previous cycle, the grid restarting from it:
        the servo then follows its client's rate (at most 1.02 times its own) and a
        command waits for no grid. The simulated arm advances ``1 / rate`` s of its own
        time per cycle either way.
    enable : bool, keyword-only
        Send ``enable`` to the arm at start (a lab's client usually does, on
        ``state_command``).
    use_sim_time : bool, keyword-only
        Stamp from ``/clock`` (ROS's ``use_sim_time``) instead of the system clock.
    context : RosContext, optional, keyword-only
        The rclpy context to join (default: its own, closed with the node).
    node_name : str, keyword-only

    Raises
    ------
    ModuleNotFoundError
        rclpy is not installed (the message names the extra ``ros2``).
    ValueError, TypeError
        A bad argument, named.

    Examples
    --------
    ::

        node = ArmNode(enable=True)      # /athena/measured_js, ... on the graph
        node.start()
        node.spin()                      # until Ctrl-C
    """

    def __init__(self, arm: Any = None, *, T_b_e: ArrayLike | None = None,
                 design: Design | None = None, q0: ArrayLike | None = None,
                 rate: float = 1000.0, namespace: str = "/athena", publish_rate: float = 100.0,
                 sync: str = "clock", enable: bool = False, use_sim_time: bool = False,
                 context: RosContext | None = None, node_name: str = "athena_arm") -> None:
        require_rclpy()
        from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
        from rclpy.parameter import Parameter

        from ..robot._setup import resolve_rcm_frame
        from ..teleop import SimulatedArm

        self.namespace = check_namespace(namespace)
        if arm is None:
            design = resolve_design(design)
            arm = SimulatedArm(resolve_rcm_frame(T_b_e, design), design, q0=q0, rate=rate)
        elif not isinstance(arm, SimulatedArm):
            raise TypeError(f"arm: expected an athenakin.teleop.SimulatedArm, got "
                            f"{type(arm).__name__}")
        self.arm = arm
        self.design, self.T_b_e = arm.design, np.array(arm.T_b_e, dtype=float)
        publish_rate = check_scalar(publish_rate, "publish_rate", positive=True)
        self.decimation = max(1, round(arm.rate / publish_rate))
        self.publish_rate = arm.rate / self.decimation
        self.crtk = crtk_types()
        self._urdf = urdf_model(self.design, self.T_b_e)
        self._own_context = context is None
        self.context = RosContext() if context is None else context
        self.node = _create_node(node_name, self.namespace, self.context, use_sim_time,
                                 Parameter)
        self._lock = threading.RLock()
        self._stop = threading.Event()
        self._last_stamp: dict[str, int] = {}
        self._last_state: tuple[str, bool] | None = None
        #: Refusals so far: (command, reason) pairs, oldest first (the last 1000).
        self.refusals: list[tuple[str, str]] = []
        #: Servo cycles run.
        self.cycles = 0
        self._pacer = CyclePacer(arm.rate, sync=sync, stop=self._stop)
        #: When a servo cycle starts: ``"clock"`` or ``"command"`` (the ``sync`` argument).
        self.sync = self._pacer.sync
        #: Command messages received (accepted or refused), and refused.
        self.commands = self.refused = 0
        #: The last error of the servo thread (None: none).
        self.error: str | None = None
        from .._backend import resolve_backend

        self._state = StateMessages(self.T_b_e, self.design, int(arm.slot), self._urdf,
                                    dt=1.0 / self.publish_rate, compiled=resolve_backend("auto"))
        self._publishing = threading.Lock()     # the state messages are refilled in place
        self._pubs = self._publishers()
        group = MutuallyExclusiveCallbackGroup()
        self._subscriptions(group)
        self._executor = control_executor(self.context)
        self._executor.add_node(self.node)
        self._threads: list[threading.Thread] = []
        from std_msgs.msg import String

        self._pubs["robot_description"].publish(String(data=self._urdf.text))
        if enable:
            with self._lock:
                self.arm.enable()
        # one state computed before any is published: the kernels of the state messages
        # are compiled (or loaded from numba's cache) now, not after the first measured_js
        with self._lock:
            js, sp = self.arm.measured_js(), self.arm.setpoint_js()
        self._state.warm_up(js, sp, self._now())
        self._publish_state(force=True)

    # --- set-up ---------------------------------------------------------------------
    def _publishers(self) -> dict[str, Any]:
        from geometry_msgs.msg import PoseStamped, TwistStamped
        from sensor_msgs.msg import JointState
        from std_msgs.msg import String

        n, t = self.node, ARM_TOPICS
        kinds = {"measured_js": JointState, "setpoint_js": JointState,
                 "measured_cp": PoseStamped, "setpoint_cp": PoseStamped,
                 "measured_cv": TwistStamped, "joint_states": JointState,
                 "urdf_joint_states": JointState}
        pubs = {k: n.create_publisher(typ, t[k], _qos(10)) for k, typ in kinds.items()}
        pubs["operating_state"] = n.create_publisher(self.crtk.operating_state,
                                                     t["operating_state"], _qos(1, latched=True))
        pubs["status"] = n.create_publisher(self.crtk.string_stamped, t["status"], _qos(100))
        pubs["robot_description"] = n.create_publisher(String, t["robot_description"],
                                                       _qos(1, latched=True))
        return pubs

    def _subscriptions(self, group: Any) -> None:
        from geometry_msgs.msg import PoseStamped
        from sensor_msgs.msg import JointState
        from std_msgs.msg import Empty

        n, t = self.node, ARM_TOPICS
        table: list[tuple[str, Any, Callable[[Any], None]]] = [
            ("servo_jp", JointState, self._on_servo_jp),
            ("joint_commands", JointState, self._on_servo_jp_pair),
            ("move_jp", JointState, self._on_move_jp),
            ("servo_cp", PoseStamped, self._on_servo_cp),
            ("move_cp", PoseStamped, self._on_move_cp),
            ("state_command", self.crtk.string_stamped, self._on_state_command),
            ("hold", Empty, self._on_hold),
        ]
        self._subs = [n.create_subscription(typ, t[key], cb, _qos(100), callback_group=group)
                      for key, typ, cb in table]

    # --- commands -------------------------------------------------------------------
    def refuse(self, command: str, reason: str) -> None:
        """Answer a refused ``command`` on ``status`` (``"refused <command>: <reason>"``).

        Parameters
        ----------
        command : str
            The command's topic name (``servo_jp``, ...).
        reason : str
            Why it was refused (the error's class and message).
        """
        self.refused += 1
        self.refusals.append((command, reason))
        del self.refusals[:-1000]
        self._pubs["status"].publish(self.crtk.string(f"refused {command}: {reason}",
                                                      self._now()))

    def _command(self, name: str, msg: Any, call: Callable[[], None], *,
                 stamped: bool = True, held_refusal: bool = True) -> None:
        """Run ``call`` on the arm, or answer why not: the one path of every command.

        An exception of ``call`` is a refusal; so is, with ``held_refusal``, a command the
        arm held and flagged (its ``refusal`` set after the call, as
        :class:`~athenakin.teleop.SimulatedArm`'s commands do): answered ``held: <why>``.
        The arm's own checks decide (its state included: a motion command outside
        ``ENABLED`` is held and flagged by the arm).
        """
        self.commands += 1
        try:
            if stamped:
                ns = stamp_ns(msg.header)
                last = self._last_stamp.get(name, 0)
                if ns and ns < last:
                    raise ValueError(f"stamp: {ns} ns is older than the previous {name}'s "
                                     f"({last} ns)")
            with self._lock:
                call()
                held = getattr(self.arm, "refusal", None) if held_refusal else None
            if held is not None:
                self.refuse(name, f"held: {held}")
            elif stamped and ns:
                self._last_stamp[name] = ns
        except Exception as exc:    # the arm's refusal, whatever its kind: never executed
            self.refuse(name, f"{type(exc).__name__}: {exc}")
        self._publish_state()

    def _on_servo_jp(self, msg: Any, name: str = "servo_jp") -> None:
        def call() -> None:
            q, v, e = actuator_command(msg)
            self.arm.servo_jp(q, velocity=v, effort=e)
        self._command(name, msg, call)
        self._pacer.arrived()

    def _on_servo_jp_pair(self, msg: Any) -> None:
        self._on_servo_jp(msg, "joint_commands")

    def _on_move_jp(self, msg: Any) -> None:
        def call() -> None:
            q, v, _ = actuator_command(msg)
            self.arm.move_jp(q, goal_velocity=v)
        self._command("move_jp", msg, call)

    def _tip(self, msg: Any) -> tuple[FloatArray, str]:
        return tip_command(msg, {"": "base", BASE_FRAME: "base", RCM_FRAME: "rcm"})

    def _on_servo_cp(self, msg: Any) -> None:
        def call() -> None:
            tip, frame = self._tip(msg)
            self.arm.servo_cp(tip, frame=frame)
        self._command("servo_cp", msg, call)
        self._pacer.arrived()

    def _on_move_cp(self, msg: Any) -> None:
        def call() -> None:
            tip, frame = self._tip(msg)
            self.arm.move_cp(tip, frame=frame)
        self._command("move_cp", msg, call)

    def _on_hold(self, msg: Any) -> None:
        self._command("hold", msg, self.arm.hold, stamped=False, held_refusal=False)

    def _on_state_command(self, msg: Any) -> None:
        text = self.crtk.text(msg).strip()

        def call() -> None:
            method = STATE_COMMANDS.get(text.lower())
            if method is None:
                raise ValueError(f"state_command: expected one of {sorted(STATE_COMMANDS)}, "
                                 f"got {text!r:.40}")
            fn = getattr(self.arm, method, None)
            if fn is None and method == "resume":
                fn = self.arm.enable         # an arm whose enable also resumes
            if fn is None:
                raise ValueError(f"state_command: this arm has no {method!r}")
            fn()
        self._command("state_command", msg, call, stamped=self.crtk.native,
                      held_refusal=text.lower() == "home")

    # --- state ----------------------------------------------------------------------
    @property
    def late_cycles(self) -> int:
        """Servo cycles that started more than one period after their time.

        Returns
        -------
        int
        """
        return self._pacer.late_cycles

    @property
    def synced_cycles(self) -> int:
        """Servo cycles started by a command's arrival (``sync="command"``; else 0).

        Returns
        -------
        int
        """
        return self._pacer.synced_cycles

    def _now(self) -> Any:
        return self.node.get_clock().now().to_msg()

    def _publish_state(self, *, force: bool = False) -> None:
        with self._lock:
            state = (self.arm.operating_state, bool(self.arm.is_busy))
            fault = getattr(self.arm, "fault", None)
        if not force and state == self._last_state:
            return
        self._last_state = state
        homed = bool(getattr(self.arm, "is_homed", True))
        self._pubs["operating_state"].publish(self.crtk.state(
            state[0], is_homed=homed, is_busy=state[1], stamp=self._now()))
        if state[0] == "FAULT" and fault:
            self._pubs["status"].publish(self.crtk.string(f"fault: {fault}", self._now()))

    def publish_once(self) -> None:
        """Publish the arm's state now (each state topic that has a reader); the servo's step.

        The joint states go first, before any kinematics; then one forward kinematics of
        the measured position and one of the setpoint (kept while it does not move) fill
        the poses (:mod:`._arm_state`). The messages are filled in place and all carry
        one stamp. A topic with no subscription matched (``get_subscription_count()``) is
        neither filled nor published: with no reader of the poses, their twist and the
        URDF joints, the kinematics is skipped, and the next ``measured_cv`` has no
        rotation before it (angular rate zero, as the first one after start).
        """
        with self._lock:
            js, sp = self.arm.measured_js(), self.arm.setpoint_js()
        stamp = self._now()
        p, m = self._pubs, self._state
        wanted = {name for name in (*_JOINT_TOPICS, *_POSE_TOPICS)
                  if p[name].get_subscription_count() > 0}
        with self._publishing:
            m.fill_joints(js, sp, stamp)
            for name, message in _JOINT_TOPICS.items():
                if name in wanted:
                    p[name].publish(getattr(m, message))
            if wanted.isdisjoint(_POSE_TOPICS):
                m.forget_rotation()
            else:
                assembled = m.fill_poses(js, sp)
                for name, needs_assembly in _POSE_TOPICS.items():
                    if name in wanted and (assembled or not needs_assembly):
                        p[name].publish(getattr(m, name))
        self._publish_state()

    # --- running --------------------------------------------------------------------
    def _servo_loop(self) -> None:
        k = 0
        self._pacer.begin()
        while not self._stop.is_set():
            try:
                with self._lock:
                    self.arm.step(1)
            except Exception as exc:     # the arm itself failed: stop serving, say why
                self.error = f"servo step: {type(exc).__name__}: {exc}"
                self._pubs["status"].publish(self.crtk.string(f"fault: {self.error}",
                                                              self._now()))
                return
            self.cycles += 1
            k += 1
            if k % self.decimation == 0:
                try:
                    self.publish_once()
                except Exception as exc:   # a state the messages cannot carry: say so, go on
                    self.error = f"publish: {type(exc).__name__}: {exc}"
                    self._pubs["status"].publish(self.crtk.string(f"error: {self.error}",
                                                                  self._now()))
            self._pacer.wait()

    def _spin_loop(self) -> None:
        spin_executor(self._stop, self._executor, self.context)

    def start(self) -> ArmNode:
        """Start the servo thread and the executor's thread (idempotent).

        Returns
        -------
        ArmNode
            ``self``, started.
        """
        if not self._threads:
            self._threads = [threading.Thread(target=self._servo_loop, name="athena-servo",
                                              daemon=True),
                             threading.Thread(target=self._spin_loop, name="athena-executor",
                                              daemon=True)]
            for th in self._threads:
                th.start()
        return self

    def spin(self, timeout: float | None = None) -> None:
        """Run until Ctrl-C, the context's shutdown, or ``timeout`` s.

        Parameters
        ----------
        timeout : float, optional
            Seconds to run at most (default: until shutdown).
        """
        self.start()
        run_until(self._stop, self.context, timeout)

    def close(self) -> None:
        """Stop the threads, destroy the node, shut down its own context (idempotent)."""
        stop_node(self._stop, self._threads, self._executor, self.node,
                  self.context if self._own_context else None)
        self._threads = []

    def __enter__(self) -> ArmNode:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()


def _create_node(name: str, namespace: str, context: RosContext, use_sim_time: bool,
                 Parameter: Any) -> Any:
    from rclpy.node import Node

    if not isinstance(use_sim_time, bool):
        raise TypeError(f"use_sim_time: expected a bool, got {type(use_sim_time).__name__}")
    return Node(name, namespace=namespace, context=context.context,
                parameter_overrides=[Parameter("use_sim_time", value=use_sim_time)])

