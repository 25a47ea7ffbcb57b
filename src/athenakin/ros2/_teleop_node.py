"""Teleoperation on a ROS 2 graph: a master's topics -> :class:`Teleop` -> ``servo_jp`` (private).

:class:`TeleopNode` is a thin adapter. Its subscriptions keep the master's latest
sample (``PoseStamped`` position, ``Joy`` clutch button) and latch the e-stop; a
dedicated loop thread runs :meth:`athenakin.teleop.Teleop.step` at the teleop rate
with the ROS clock's time and the sample received since the previous cycle (None
when none came: the core's watchdog counts those cycles and holds the robot after
``TeleopOptions.watchdog`` s), and publishes the command as ``servo_jp`` (positions,
velocity and effort feed-forward) and the core's flags on ``status``.
"""

from __future__ import annotations

import math
import threading
import time
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._validation import check_scalar
from ..design import Design, resolve_design
from ._arm_node import _create_node, _qos, check_namespace, resolve_topic
from ._convert import ACTUATORS, joint_state, master_position, stamp_ns
from ._runtime import (
    CyclePacer,
    RosContext,
    control_executor,
    require_rclpy,
    run_until,
    spin_executor,
    stop_node,
)

__all__ = ["TeleopNode", "TELEOP_TOPICS", "MASTER_PRESETS", "DVRK_PRESET", "STATUS_KEYS",
           "MAX_REFUSALS"]

#: Default topics of :class:`TeleopNode` (the arm's under ``arm_namespace``).
TELEOP_TOPICS = {"pose": "/master/pose", "clutch": "/master/joy", "servo_jp": "servo_jp",
                 "measured_js": "measured_js", "status": "teleop/status",
                 "estop": "teleop/estop", "release": "teleop/release"}
#: dVRK's right master tool manipulator and its clutch pedal.
DVRK_PRESET = {"pose": "/MTMR/measured_cp", "clutch": "/footpedals/clutch"}
#: Named master topic sets (``--preset``).
MASTER_PRESETS = {"default": {"pose": TELEOP_TOPICS["pose"], "clutch": TELEOP_TOPICS["clutch"]},
                  "dvrk-mtmr": DVRK_PRESET}
#: Refusals (texts) one status message carries at most; those beyond are counted.
MAX_REFUSALS = 8
#: The keys of the status message's values, in order.
STATUS_KEYS = ("t", "cycle", "flags", "names", "clutched", "limited", "hold", "watchdog",
               "estop", "sample_age_s", "tip_b", "clearance_m", "refused")


class TeleopNode:
    """A master on the graph drives the arm node through :class:`athenakin.teleop.Teleop`.

    Parameters
    ----------
    T_b_e : array-like, shape (4, 4), optional
        RCM frame (default :func:`athenakin.default_rcm_frame`): the arm node's.
    design : Design, optional
    q0 : array-like, shape (3,), optional, keyword-only
        Where the robot stands, m; default the first ``measured_js`` of the arm node
        (waited for up to ``wait_for_arm`` s).
    rate : float, keyword-only
        Teleop cycles per second, Hz (1000).
    scale : float, keyword-only
        Motion scale (0.2).
    options : TeleopOptions, optional, keyword-only
        The core's options (watchdog, filter, registration, ...).
    bodies : athenakin.collision.Bodies, optional, keyword-only
        The robot's bodies the core keeps apart, and from ``environment``; default
        ``Bodies.default(design)`` (every session checks them unless ``check_bodies``
        is False).
    environment : athenakin.collision.Environment, optional, keyword-only
        Obstacles: virtual fixtures for the tip, and kept clear of the bodies.
    check_bodies : bool, keyword-only
        True (default): the core checks the bodies' clearance (``bodies`` or the
        default capsules); a core built without (``TeleopOptions(check_clearance=
        False)``) is refused. False: the explicit opt-out, ``bodies`` as given.
    arm_namespace : str, keyword-only
        The arm node's namespace (``/athena``).
    pose_topic, clutch_topic : str, keyword-only
        The master's ``geometry_msgs/PoseStamped`` (m) and ``sensor_msgs/Joy``;
        ``clutch_topic=None``: always engaged. Defaults: :data:`TELEOP_TOPICS`
        (``MASTER_PRESETS["dvrk-mtmr"]`` for a dVRK MTMR).
    clutch_button : int, keyword-only
        The Joy button that decouples while held (0).
    master_frame : str, optional, keyword-only
        The ``frame_id`` the master's poses must carry (default: any).
    status_every : int, keyword-only
        Publish the status every this many cycles (10), on every change of flags and
        at the first cycle after a refused message (its ``refused`` value: every
        refusal since the previous status, ``"; "``-separated, the first
        :data:`MAX_REFUSALS`, then ``"and N more"``).
    wait_for_arm : float, keyword-only
        Longest wait for the arm's first ``measured_js`` when ``q0`` is None, s (30).
    use_sim_time : bool, keyword-only
    clock : {"ros", "master"}, keyword-only
        ``"ros"`` (default): the loop runs at ``rate`` on the ROS clock, each cycle with
        the sample received since the previous one (None when none came: the watchdog
        counts it). ``"master"``: one cycle per master message at its header stamp, as
        :func:`athenakin.teleop.run_session` runs a recording (a message whose stamp is
        not after the previous one's runs no cycle); the watchdog then sees only the
        stamps' own gaps, so this is for replays, never for a live master.
    context : RosContext, optional, keyword-only
    node_name : str, keyword-only

    Raises
    ------
    TimeoutError
        No ``measured_js`` from the arm within ``wait_for_arm`` s (``q0`` None).
    InvalidInputError
        ``check_bodies`` True and ``options`` turn the clearance check off; the core's
        own refusals (a ``q0`` off the strokes, in a fixture, with the bodies too close).
    ValueError
        A namespace or a topic name that ROS does not accept, named.
    ModuleNotFoundError
        rclpy is not installed (the extra ``ros2``).
    """

    def __init__(self, T_b_e: ArrayLike | None = None, design: Design | None = None, *,
                 q0: ArrayLike | None = None, rate: float = 1000.0, scale: float = 0.2,
                 options: Any = None, bodies: Any = None, environment: Any = None,
                 check_bodies: bool = True, arm_namespace: str = "/athena",
                 pose_topic: str = TELEOP_TOPICS["pose"],
                 clutch_topic: str | None = TELEOP_TOPICS["clutch"], clutch_button: int = 0,
                 master_frame: str | None = None, status_every: int = 10,
                 wait_for_arm: float = 30.0, use_sim_time: bool = False,
                 clock: str = "ros",
                 context: RosContext | None = None, node_name: str = "athena_teleop") -> None:
        require_rclpy()
        from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
        from rclpy.parameter import Parameter

        from .._validation import check_choice, check_count
        from ..robot._setup import resolve_rcm_frame

        self.design = resolve_design(design)
        self.T_b_e = resolve_rcm_frame(T_b_e, self.design)
        bodies = _session_bodies(self.design, bodies, options, check_bodies)
        self.namespace = check_namespace(arm_namespace)
        resolve_topic(pose_topic, "pose_topic", namespace=self.namespace, node=node_name)
        if clutch_topic is not None:
            resolve_topic(clutch_topic, "clutch_topic", namespace=self.namespace,
                          node=node_name)
        self.rate = check_scalar(rate, "rate", positive=True)
        self.clutch_button = check_count(clutch_button, "clutch_button", minimum=0)
        self.status_every = check_count(status_every, "status_every", minimum=1)
        self.master_frame = master_frame
        self.clock = check_choice(clock, "clock", ("ros", "master"))
        self._last_ns = -1
        self._own_context = context is None
        self.context = RosContext() if context is None else context
        self.node = _create_node(node_name, self.namespace, self.context, use_sim_time,
                                 Parameter)
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._sample: tuple[float, float, float] | None = None
        self._seq = self._used = 0
        self._t_sample = -math.inf
        self._clutch = True
        self._refusals: list[str] = []      # since the last status (MAX_REFUSALS kept)
        self._refusal_count = 0
        self._estop = False
        self.cycles = 0
        # the loop on its own clock: the core's limits are per cycle of 1 / rate s
        self._pacer = CyclePacer(self.rate, sync="clock", stop=self._stop)
        self._last_flags = -1
        self._executor = control_executor(self.context)
        self._executor.add_node(self.node)
        self._pubs, self._subs = self._topics(pose_topic, clutch_topic,
                                              MutuallyExclusiveCallbackGroup())
        self._threads: list[threading.Thread] = []
        from ..teleop import Teleop

        try:
            if q0 is None:
                q0 = self._wait_for_arm(check_scalar(wait_for_arm, "wait_for_arm",
                                                     positive=True))
            self.teleop = Teleop(self.T_b_e, self.design, q0=q0, scale=scale, rate=self.rate,
                                 options=options, bodies=bodies, environment=environment)
        except BaseException:           # no arm, or the core refused q0: no node left behind
            self.close()
            raise
        with self._lock:
            if self._estop:             # latched while the node waited for the arm
                self.teleop.estop()

    def _topics(self, pose_topic: str, clutch_topic: str | None, group: Any
                ) -> tuple[dict[str, Any], list[Any]]:
        from diagnostic_msgs.msg import DiagnosticArray
        from geometry_msgs.msg import PoseStamped
        from sensor_msgs.msg import JointState, Joy
        from std_msgs.msg import Bool, Empty

        n, t = self.node, TELEOP_TOPICS
        pubs = {"servo_jp": n.create_publisher(JointState, t["servo_jp"], _qos(10)),
                "status": n.create_publisher(DiagnosticArray, t["status"], _qos(100))}
        subs = [n.create_subscription(PoseStamped, pose_topic, self._on_pose, _qos(10),
                                      callback_group=group),
                n.create_subscription(Bool, t["estop"], self._on_estop, _qos(10),
                                      callback_group=group),
                n.create_subscription(Empty, t["release"], self._on_release, _qos(10),
                                      callback_group=group)]
        if clutch_topic is not None:
            subs.append(n.create_subscription(Joy, clutch_topic, self._on_joy, _qos(10),
                                              callback_group=group))
        return pubs, subs

    def _wait_for_arm(self, timeout: float) -> Any:
        from sensor_msgs.msg import JointState

        got: list[Any] = []
        sub = self.node.create_subscription(JointState, TELEOP_TOPICS["measured_js"],
                                            got.append, _qos(10))
        end = time.monotonic() + timeout
        while not got and time.monotonic() < end and self.context.ok:
            self._executor.spin_once(timeout_sec=0.05)
        self.node.destroy_subscription(sub)
        if not got:
            raise TimeoutError(f"no {self.namespace}/measured_js within {timeout:g} s: start "
                               f"the arm node (athenakin ros2 arm) or give q0")
        from ._convert import actuator_command

        return actuator_command(got[0])[0]

    # --- callbacks: keep the latest sample ------------------------------------------
    def _on_pose(self, msg: Any) -> None:
        if self.master_frame is not None and msg.header.frame_id != self.master_frame:
            self._refuse(f"master pose: frame_id {msg.header.frame_id!r:.40}, expected "
                         f"{self.master_frame!r}")
            return
        p = master_position(msg)
        if self.clock == "master":     # one cycle on this sample, at its own stamp
            ns = stamp_ns(msg.header)
            if ns <= self._last_ns:     # a repeated or older message is no new cycle
                self._refuse(f"master pose: stamp {ns} ns is not after the previous "
                             f"one's ({self._last_ns} ns)")
                return
            self._last_ns = ns
            self._cycle(ns * 1e-9, p, msg.header.stamp)
            return
        with self._lock:
            self._sample = p          # a non-finite one: the core flags INVALID
            self._seq += 1

    def _on_joy(self, msg: Any) -> None:
        if len(msg.buttons) <= self.clutch_button:
            self._refuse(f"clutch: the Joy has {len(msg.buttons)} buttons, no button "
                         f"{self.clutch_button}")
            return
        with self._lock:
            self._clutch = not bool(msg.buttons[self.clutch_button])   # held: decoupled

    def _on_estop(self, msg: Any) -> None:
        if msg.data:
            with self._lock:
                self._estop = True
                tele = getattr(self, "teleop", None)
                if tele is not None:
                    tele.estop()

    def _on_release(self, msg: Any) -> None:
        with self._lock:
            self._estop = False
            tele = getattr(self, "teleop", None)
            if tele is not None:
                tele.release()

    def _refuse(self, text: str) -> None:
        """Keep a refusal for the next status (the first :data:`MAX_REFUSALS`, then a count)."""
        with self._lock:
            if len(self._refusals) < MAX_REFUSALS:
                self._refusals.append(text)
            self._refusal_count += 1

    # --- the loop -------------------------------------------------------------------
    @property
    def late_cycles(self) -> int:
        """Teleop cycles that started more than one period after their time.

        Returns
        -------
        int
        """
        return self._pacer.late_cycles

    def step_once(self) -> Any:
        """One teleop cycle now: the latest sample through the core, ``servo_jp`` out.

        Returns
        -------
        athenakin.teleop.TeleopCommand
        """
        t = self.node.get_clock().now().nanoseconds * 1e-9
        with self._lock:
            fresh = self._seq != self._used
            self._used = self._seq
            sample = self._sample if fresh else None
        return self._cycle(t, sample, None, fresh=fresh)

    def _cycle(self, t: float, sample: Any, stamp: Any, *, fresh: bool = True) -> Any:
        """Run the core on one sample (or None) at ``t`` s; publish ``servo_jp`` and status."""
        with self._lock:
            if fresh:
                self._t_sample = t
            cmd = self.teleop.step(t, sample, self._clutch)
        if stamp is None:
            stamp = self.node.get_clock().now().to_msg()
        effort = cmd.forces if all(math.isfinite(f) for f in cmd.forces) else ()
        self._pubs["servo_jp"].publish(joint_state(ACTUATORS, cmd.q, cmd.qd, effort,
                                                   stamp=stamp))
        flags = int(cmd.status)
        self.cycles += 1
        if flags != self._last_flags or self.cycles % self.status_every == 0 \
                or self._refusal_count:
            self._publish_status(cmd, t, stamp)
            self._last_flags = flags
        return cmd

    def _publish_status(self, cmd: Any, t: float, stamp: Any) -> None:
        from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

        from ..teleop import TeleopStatus

        s = TeleopStatus(int(cmd.status))
        names = "|".join(f.name for f in TeleopStatus if f and f in s)  # type: ignore[misc]
        limited = bool(s & (TeleopStatus.STROKE | TeleopStatus.DEPTH | TeleopStatus.SINGULAR
                            | TeleopStatus.FIXTURE | TeleopStatus.CLEARANCE
                            | TeleopStatus.VELOCITY | TeleopStatus.ACCELERATION))
        R, c = self.T_b_e[:3, :3], self.T_b_e[:3, 3]
        tip_b = R @ np.asarray(cmd.tip) + c
        with self._lock:
            kept, n = self._refusals, self._refusal_count
            self._refusals, self._refusal_count = [], 0
        refused = "; ".join(kept) + (f"; and {n - len(kept)} more" if n > len(kept) else "")
        values = {"t": repr(t), "cycle": str(self.cycles), "flags": str(int(s)),
                  "names": names, "clutched": str(bool(s & TeleopStatus.CLUTCHED)),
                  "limited": str(limited), "hold": str(bool(s & TeleopStatus.HOLD)),
                  "watchdog": str(bool(s & TeleopStatus.WATCHDOG)),
                  "estop": str(bool(s & TeleopStatus.ESTOP)),
                  "sample_age_s": repr(t - self._t_sample),
                  "tip_b": " ".join(repr(float(v)) for v in tip_b),
                  "clearance_m": repr(float(cmd.clearance)), "refused": refused}
        error = s & (TeleopStatus.WATCHDOG | TeleopStatus.ESTOP | TeleopStatus.FAULT)
        st = DiagnosticStatus(level=DiagnosticStatus.ERROR if error else
                              DiagnosticStatus.WARN if (limited or refused) else
                              DiagnosticStatus.OK,
                              name="athena/teleop", message=names or "following",
                              hardware_id="athena",
                              values=[KeyValue(key=k, value=values[k]) for k in STATUS_KEYS])
        arr = DiagnosticArray(status=[st])
        arr.header.stamp = stamp
        self._pubs["status"].publish(arr)

    def _loop(self) -> None:
        self._pacer.begin()
        while not self._stop.is_set() and self.context.ok:
            self.step_once()
            self._pacer.wait()

    def _spin_loop(self) -> None:
        spin_executor(self._stop, self._executor, self.context)

    def start(self) -> TeleopNode:
        """Start the teleop loop and the executor's threads (idempotent).

        Returns
        -------
        TeleopNode
            ``self``, started.
        """
        if not self._threads:
            self._threads = [threading.Thread(target=self._spin_loop, name="teleop-executor",
                                              daemon=True)]
            if self.clock == "ros":
                self._threads.append(threading.Thread(target=self._loop, name="athena-teleop",
                                                      daemon=True))
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

    def __enter__(self) -> TeleopNode:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()


def _session_bodies(design: Design, bodies: Any, options: Any, check_bodies: bool) -> Any:
    """The bodies the node's core checks: ``bodies``, by default the default capsules.

    Raises
    ------
    TypeError
        ``check_bodies`` not a bool.
    InvalidInputError
        ``check_bodies`` with ``options.check_clearance`` False.
    """
    from ..collision import Bodies
    from ..errors import InvalidInputError

    if not isinstance(check_bodies, bool):
        raise TypeError(f"check_bodies: expected a bool, got {type(check_bodies).__name__}")
    if not check_bodies:
        return bodies
    if getattr(options, "check_clearance", None) is False:
        raise InvalidInputError("options: check_clearance=False turns off the bodies' "
                                "clearance check; pass check_bodies=False to run without it")
    return Bodies.default(design) if bodies is None else bodies
