"""The ROS 2 client (rclpy) and the CRTK message types, imported on demand (private).

rclpy and the interface packages come from the wheels of the ``ros2`` extra; nothing
here needs a ROS installation. :func:`crtk_types` gives CRTK's own
``crtk_msgs/msg/OperatingState`` and ``StringStamped`` where the package is built
(:func:`athenakin.ros2.build_crtk_msgs`), else their ``std_msgs`` stand-ins.
"""

from __future__ import annotations

import dataclasses
import math
import threading
import time
from typing import Any

__all__ = ["require_rclpy", "ros2_extra_missing", "CrtkTypes", "crtk_types", "RosContext",
           "control_executor", "CyclePacer", "SYNC_MODES", "SYNC_WINDOW", "MAX_CATCH_UP",
           "RATE_SLACK", "SYNC_CREDIT", "sync_window"]

#: When a node's control loop starts a cycle: on its own clock, or on a command's arrival.
SYNC_MODES = ("clock", "command")
#: Fraction of a period by which a cycle synchronised to commands starts early or late.
SYNC_WINDOW = 0.25
#: Most cycles a loop catches up at once after a stall (then it skips ahead).
MAX_CATCH_UP = 10
#: Synchronised to commands, a loop runs at most this fraction faster than its rate...
RATE_SLACK = 0.02
#: ...after a burst of at most this many periods ahead of its starts' schedule.
SYNC_CREDIT = 2.0


def ros2_extra_missing(exc: ModuleNotFoundError) -> ModuleNotFoundError:
    """The error to raise when a package of the ``ros2`` extra is not installed."""
    name = (exc.name or "").split(".")[0] or None
    return ModuleNotFoundError(f"athenakin.ros2 needs the package {name!r} (the ROS 2 client "
                               f"wheels): install the extra with  pip install 'athenakin[ros2]'",
                               name=name)


def require_rclpy() -> Any:
    """``rclpy``, or a ``ModuleNotFoundError`` that names the ``ros2`` extra."""
    try:
        import rclpy
        import rclpy.executors  # noqa: F401
    except ModuleNotFoundError as exc:
        raise ros2_extra_missing(exc) from None
    return rclpy


@dataclasses.dataclass(frozen=True)
class CrtkTypes:
    """The message types of CRTK's ``operating_state`` and ``state_command`` topics.

    Attributes
    ----------
    operating_state : type
        ``crtk_msgs/msg/OperatingState`` (header, ``state``, ``is_homed``, ``is_busy``),
        or ``std_msgs/msg/String`` holding the state name.
    string_stamped : type
        ``crtk_msgs/msg/StringStamped`` (header, ``string``), or ``std_msgs/msg/String``.
    native : bool
        True: CRTK's own types (``crtk_msgs`` is built and importable).
    """

    operating_state: type
    string_stamped: type
    native: bool

    def string(self, text: str, stamp: Any = None, frame_id: str = "") -> Any:
        """A ``string_stamped`` message holding ``text`` (stamped where the type has a header).

        Parameters
        ----------
        text : str
            The message's text.
        stamp : builtin_interfaces.msg.Time, optional
            The header's stamp (native CRTK type only).
        frame_id : str
            The header's frame (native CRTK type only).

        Returns
        -------
        crtk_msgs.msg.StringStamped or std_msgs.msg.String
            The message.
        """
        if self.native:
            msg = self.string_stamped(string=text)
            if stamp is not None:
                msg.header.stamp = stamp
            msg.header.frame_id = frame_id
            return msg
        return self.string_stamped(data=text)

    def text(self, msg: Any) -> str:
        """The text of a ``string_stamped`` message.

        Parameters
        ----------
        msg : crtk_msgs.msg.StringStamped or std_msgs.msg.String
            A message of this set's ``string_stamped`` type.

        Returns
        -------
        str
            Its text.
        """
        return str(msg.string if self.native else msg.data)

    def state(self, state: str, *, is_homed: bool, is_busy: bool, stamp: Any = None) -> Any:
        """An ``operating_state`` message.

        Parameters
        ----------
        state : str
            CRTK's state name (``DISABLED``, ``ENABLED``, ``PAUSED``, ``FAULT``).
        is_homed, is_busy : bool, keyword-only
            CRTK's flags (carried by the native type only).
        stamp : builtin_interfaces.msg.Time, optional, keyword-only
            The header's stamp (native type only).

        Returns
        -------
        crtk_msgs.msg.OperatingState or std_msgs.msg.String
            The message (the stand-in carries the state name).
        """
        if self.native:
            msg = self.operating_state(state=state, is_homed=is_homed, is_busy=is_busy)
            if stamp is not None:
                msg.header.stamp = stamp
            return msg
        return self.operating_state(data=state)


def crtk_types(*, native: bool | None = None) -> CrtkTypes:
    """CRTK's message types: ``crtk_msgs`` where importable, else the ``std_msgs`` stand-ins.

    Parameters
    ----------
    native : bool, optional, keyword-only
        True: require ``crtk_msgs`` (``ModuleNotFoundError`` naming the set-up step when it
        is not built); False: the stand-ins; None (default): ``crtk_msgs`` where importable.

    Returns
    -------
    CrtkTypes
    """
    require_rclpy()
    from std_msgs.msg import String

    if native is not False:
        try:
            from crtk_msgs.msg import OperatingState, StringStamped
        except ModuleNotFoundError:
            if native:
                raise ModuleNotFoundError(
                    "crtk_msgs is not built: run  athenakin ros2 build-msgs  (the rosidl "
                    "generator wheels of the extra 'ros2-msgs', cmake and a C compiler)",
                    name="crtk_msgs") from None
        else:
            return CrtkTypes(OperatingState, StringStamped, True)
    return CrtkTypes(String, String, False)


class RosContext:
    """One rclpy context, initialised on construction and shut down by :meth:`close`.

    A node of this package runs in its own context, so that a test, a benchmark or an
    application may hold several (an arm and a teleop node in one process) and close
    each without touching rclpy's global one.

    Parameters
    ----------
    args : list of str, optional
        ROS arguments (``["--ros-args", ...]``).
    domain_id : int, optional
        ``ROS_DOMAIN_ID`` of this context (default: the environment's).
    """

    def __init__(self, args: list[str] | None = None, *, domain_id: int | None = None) -> None:
        rclpy = require_rclpy()
        from rclpy.context import Context

        self.context = Context()
        kw: dict[str, Any] = {}
        if domain_id is not None:
            if isinstance(domain_id, bool) or not isinstance(domain_id, int) \
                    or not 0 <= domain_id <= 232:
                raise ValueError(f"domain_id: expected an integer from 0 to 232, got "
                                 f"{domain_id!r}")
            kw["domain_id"] = domain_id
        rclpy.init(args=args, context=self.context, **kw)
        self._lock = threading.Lock()
        self._closed = False

    @property
    def ok(self) -> bool:
        """The context is initialised and not shut down."""
        return bool(self.context.ok())

    def close(self) -> None:
        """Shut the context down (idempotent)."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
        if self.context.ok():
            self.context.try_shutdown()



def sync_window(previous: float, grid: float, synced: bool, period: float,
                floor: float = -math.inf) -> tuple[float, float]:
    """When the cycle after ``previous`` may start, synchronised to commands.

    Parameters
    ----------
    previous : float
        Start of the previous cycle, s (any monotonic clock).
    grid : float
        The next cycle's time on the loop's own grid, s.
    synced : bool
        Whether the previous cycle started on a command.
    period : float
        The loop's period, s.
    floor : float
        No cycle before it: the loop's rate limit (:class:`CyclePacer` advances it by
        ``(1 - RATE_SLACK) period`` a cycle, never more than ``SYNC_CREDIT`` periods
        behind the latest start, so that commands faster than the loop do not run it
        faster than its rate).

    Returns
    -------
    earliest, latest : float
        A command's arrival starts the cycle, but not before ``earliest``, the later of
        ``previous + (1 - SYNC_WINDOW) period`` (a cycle never follows the previous one
        sooner) and ``floor``; with no arrival the cycle starts at ``latest``: ``previous
        + (1 + SYNC_WINDOW) period`` after a cycle started on a command (a command a
        little late is waited for), else ``grid``.
    """
    earliest = max(previous + (1.0 - SYNC_WINDOW) * period, floor)
    latest = previous + (1.0 + SYNC_WINDOW) * period if synced else grid
    return earliest, max(earliest, latest)


class CyclePacer:
    """When a node's control loop runs its next cycle: on a fixed grid, or on a command.

    ``sync="clock"``: cycle k starts at ``t0 + k / rate`` (``time.perf_counter``). A cycle
    that starts more than one period after its time is counted in :attr:`late_cycles`;
    after a stall of more than :data:`MAX_CATCH_UP` periods the grid skips ahead to now
    rather than racing to catch up.

    ``sync="command"``: as ``"clock"``, but a call of :meth:`arrived` (a servo command, a
    master sample: from any thread) starts the next cycle at once, within the window of
    :func:`sync_window`, and the grid restarts from that cycle. A command then waits for
    no grid (at a 1 kHz servo, up to a millisecond otherwise); the cycles run at the
    commands' rate, the loop's own between them, and commands faster than the loop run it
    at most :data:`RATE_SLACK` faster than ``rate``: the k-th cycle after any cycle's start
    ``s`` starts no sooner than ``s + ((k - 1) (1 - RATE_SLACK) - SYNC_CREDIT) / rate``.

    Parameters
    ----------
    rate : float
        Cycles per second, Hz (positive, finite).
    sync : {"clock", "command"}, keyword-only
    stop : threading.Event, keyword-only
        The node's stop event: :meth:`wait` returns at once when it is set.

    Examples
    --------
    ::

        pacer = CyclePacer(1000.0, sync="command", stop=stop)
        pacer.begin()
        while not stop.is_set():
            step()
            pacer.wait()          # a subscription calls pacer.arrived()
    """

    def __init__(self, rate: float, *, sync: str = "clock", stop: threading.Event) -> None:
        from .._validation import check_choice, check_scalar

        rate = check_scalar(rate, "rate", positive=True)
        self.sync = check_choice(sync, "sync", SYNC_MODES)
        self.period, self._stop = 1.0 / rate, stop
        self._arrival = threading.Event()
        self._start = self._grid = time.perf_counter()
        self._floor = -math.inf
        self._synced = False
        #: Cycles that started more than one period after their time.
        self.late_cycles = 0
        #: Cycles started by a command's arrival (``sync="command"``).
        self.synced_cycles = 0

    @property
    def started(self) -> float:
        """When the current cycle started (:meth:`begin`, or :meth:`wait`'s return), s.

        Returns
        -------
        float
            ``time.perf_counter()`` at the start.
        """
        return self._start

    def begin(self) -> None:
        """Start the grid now: the time of the loop's first cycle."""
        self._floor = -math.inf
        self._mark(time.perf_counter())
        self._grid = self._start
        self._synced = False
        self._arrival.clear()

    def arrived(self) -> None:
        """A command arrived: with ``sync="command"`` the next cycle starts now (thread-safe)."""
        if self.sync == "command":
            self._arrival.set()

    def wait(self) -> None:
        """Block until the next cycle is due (or the stop event is set), and mark its start."""
        self._grid += self.period
        now = time.perf_counter()
        if now - self._grid > self.period:
            self.late_cycles += 1
            if now - self._grid > MAX_CATCH_UP * self.period:
                self._grid = now
        if self.sync == "command":
            earliest, latest = sync_window(self._start, self._grid, self._synced, self.period,
                                           self._floor)
            self._synced = self._arrival.wait(max(0.0, latest - now))
            if self._synced:
                self._arrival.clear()
                self.synced_cycles += 1
                now = time.perf_counter()
                if now < earliest:
                    self._stop.wait(earliest - now)
                self._mark(time.perf_counter())
                self._grid = self._start
                return
            self._grid = max(self._grid, latest)
        wait = self._grid - time.perf_counter()
        if wait > 0:
            self._stop.wait(wait)
        self._mark(time.perf_counter())

    def _mark(self, start: float) -> None:
        """A cycle starts at ``start``: the next one's floor (the rate limit) moves on."""
        self._floor = max(self._floor + (1.0 - RATE_SLACK) * self.period,
                          start - SYNC_CREDIT * self.period)
        self._start = start


def run_until(stop: threading.Event, context: RosContext, timeout: float | None) -> None:
    """Block until ``stop`` is set, ``context`` shuts down (Ctrl-C), or ``timeout`` s pass.

    Parameters
    ----------
    stop : threading.Event
        The node's stop event.
    context : RosContext
        The node's ROS context.
    timeout : float, optional
        Seconds to block at most (default: until shutdown).
    """
    end = math.inf if timeout is None else time.monotonic() + float(timeout)
    while context.ok and not stop.is_set() and time.monotonic() < end:
        time.sleep(min(0.1, max(0.0, end - time.monotonic())))


def control_executor(context: RosContext) -> Any:
    """The executor of a node whose control loop runs in its own thread.

    rclpy's events executor (``rclpy.experimental.EventsExecutor``): the middleware's
    events are queued in C++ and each one runs its callback, where rclpy's
    ``SingleThreadedExecutor`` rebuilds and waits on a wait set of every entity in
    Python for each callback it runs: a plain subscriber takes less than half the CPU
    per message with this one (benchmarks/bench_ros2_executors.py). With commands at
    1 kHz that Python work and the servo thread share one GIL, and the single-threaded
    executor fell behind the graph (fewer than half the servo cycles run, reliable
    commands lost from a full queue); the events executor keeps up
    (benchmarks/bench_ros2.py, docs/ros2.md "How fast"). It runs callbacks one at a
    time in the thread that spins it and passes a raw subscription no message info, so
    a node that reads the info (the recorder) keeps the single-threaded executor.

    Parameters
    ----------
    context : RosContext
        The node's ROS context.

    Returns
    -------
    rclpy.executors.Executor
        An events executor on ``context``.
    """
    from rclpy.experimental import EventsExecutor

    return EventsExecutor(context=context.context)


def spin_executor(stop: threading.Event, executor: Any, context: RosContext) -> None:
    """Run ``executor``'s callbacks until ``stop`` is set or ``context`` shuts down.

    A node's executor thread. An error of the executor after the context shut down (or
    after ``stop``) ends the loop; any other is raised.

    Parameters
    ----------
    stop : threading.Event
        The node's stop event.
    executor : rclpy.executors.Executor
        The executor the node was added to.
    context : RosContext
        The node's ROS context.
    """
    while not stop.is_set() and context.ok:
        try:
            executor.spin_once(timeout_sec=0.05)
        except Exception:    # the context shut down under the executor
            if not context.ok or stop.is_set():
                return
            raise


def stop_node(stop: threading.Event, threads: list[threading.Thread], executor: Any,
              node: Any, own_context: RosContext | None) -> None:
    """Stop a node's threads, remove and destroy the node, close a context it owns.

    Idempotent: a node already destroyed is passed over.

    Parameters
    ----------
    stop : threading.Event
        Set, so that the node's loops end.
    threads : list of threading.Thread
        The node's loop and executor threads (joined, 5 s each at most).
    executor : rclpy.executors.Executor
        The executor the node was added to.
    node : rclpy.node.Node
        The node.
    own_context : RosContext or None
        The context to close (only one the node created itself).
    """
    stop.set()
    for th in threads:
        th.join(timeout=5.0)
    try:
        executor.remove_node(node)
        executor.shutdown()
        node.destroy_node()
    except Exception:  # pragma: no cover - already destroyed
        pass
    if own_context is not None:
        own_context.close()
