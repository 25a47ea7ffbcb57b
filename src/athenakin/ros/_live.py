"""The live robot over the Foxglove WebSocket protocol (foxglove-sdk), private.

:class:`FoxgloveStream` serves, on this machine (127.0.0.1 unless told), the
same topics and the same CDR messages as the MCAP files of :mod:`._write`:
``/tf``, ``/tf_static``, ``/athena/joint_states``, ``/athena/tool_tip``,
``/athena/status`` and ``/robot_description``. Foxglove connects to
``ws://127.0.0.1:PORT`` ("Open connection", Foxglove WebSocket) and decodes
them with their ROS 2 schemas. The foxglove-sdk server listens on a free port of
127.0.0.1; the public port is a relay (:mod:`._relay`) that also accepts the old
subprotocol name ``foxglove.websocket.v1`` of Foxglove Studio 1.x and Lichtblick.
WebSocket messages are not latched, so the URDF and the fixed frames are sent
again whenever a client subscribes to them, and the current pose whenever a
client subscribes to anything.
"""

from __future__ import annotations

import errno
import math
import socket
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._validation import check_array, check_slot, check_text
from ..design import Design, resolve_design
from ..errors import InvalidInputError
from ..robot import forward_kinematics
from ..robot._setup import resolve_rcm_frame
from ._encoder import RosEncoder, TrackedBatch, check_uint
from ._errors import ServeError, ros_extra_missing
from ._relay import SubprotocolRelay, bind_socket
from ._write import _MSG_TYPES, TOPICS, msgdef

__all__ = ["FoxgloveStream", "DEFAULT_PORT", "serve_app"]

#: Port of the Foxglove WebSocket server (Foxglove's default).
DEFAULT_PORT = 8765
#: Most poses per second the polling thread of :meth:`FoxgloveStream.follow` publishes.
MAX_RATE = 1000.0
_STATIC = ("robot_description", "tf_static")


class FoxgloveStream:
    """Serve ATHENA's pose live to Foxglove (or any Foxglove WebSocket client).

    Parameters
    ----------
    T_b_e : array-like, shape (4, 4), optional
        RCM frame (default :func:`athenakin.default_rcm_frame`).
    design : Design, optional
    host : str, keyword-only
        Interface to bind (default ``127.0.0.1``: this machine only); a name that does
        not resolve raises :class:`~athenakin.errors.InvalidInputError`.
    port : int, keyword-only
        Port (default 8765; 0: any free port, see :attr:`port`). Clients offering the
        WebSocket subprotocol ``foxglove.sdk.v1``, ``foxglove.sdk.v1.1`` or the older
        ``foxglove.websocket.v1`` (Foxglove Studio 1.x, Lichtblick) connect; others get
        HTTP 400. A port in use raises :class:`ServeError` (an ``OSError``) naming the address.
    name : str, keyword-only
        Server name shown by Foxglove.
    backend : {"auto", "numpy", "numba"}, keyword-only
        The frames and quaternions on the compiled kernels or the numpy reference
        (:mod:`athenakin._backend`).

    Examples
    --------
    ::

        live = ak.ros.FoxgloveStream(port=8765)
        live.publish([-0.10, 0.10, 0.45])      # the pose of q, FK slot 0
        ...
        live.stop()
    """

    def __init__(self, T_b_e: ArrayLike | None = None, design: Design | None = None, *,
                 host: str = "127.0.0.1", port: int = DEFAULT_PORT,
                 name: str = "athenakin", backend: str = "auto") -> None:
        from .._backend import resolve_backend

        try:
            import foxglove
            import websockets.asyncio.server  # noqa: F401
            from foxglove.websocket import Capability  # noqa: F401
        except ModuleNotFoundError as exc:  # pragma: no cover
            raise ros_extra_missing(exc) from None
        if isinstance(port, bool) or not isinstance(port, (int, np.integer)) \
                or not 0 <= port <= 65535:
            raise InvalidInputError(f"port: expected an integer from 0 to 65535, got {port!r}")
        check_text(host, "host")
        check_text(name, "name")
        try:
            socket.getaddrinfo(host, None, type=socket.SOCK_STREAM)
        except (OSError, UnicodeError) as exc:
            raise InvalidInputError(f"host: expected an address or name of this machine's "
                                    f"interface (default 127.0.0.1), got {host!r} ({exc})"
                                    ) from None
        self.design = resolve_design(design)
        self.T_b_e = resolve_rcm_frame(T_b_e, self.design)
        self.backend = "numba" if resolve_backend(backend) else "numpy"
        self.encoder = RosEncoder(self.T_b_e, self.design, backend=self.backend)
        self._lock = threading.RLock()
        self._context = foxglove.Context()
        self._channels: dict[str, Any] = {}
        for key in ("tool_tip", "tf", "tf_static", "joint_states", "status",
                    "robot_description"):
            typ = _MSG_TYPES[key]
            schema = foxglove.Schema(name=typ, encoding="ros2msg", data=msgdef(typ).encode())
            self._channels[key] = foxglove.Channel(TOPICS[key], schema=schema,
                                                   message_encoding="cdr",
                                                   context=self._context)
        self._by_id = {ch.id(): key for key, ch in self._channels.items()}
        self._resend: set[str] = set()
        self._last: tuple[Any, ...] | None = None
        self._sample = 0
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        listener = _Listener(self)
        try:
            sock = bind_socket(host, int(port))
        except OSError as exc:
            busy = exc.errno == errno.EADDRINUSE
            raise ServeError(exc.errno, f"cannot serve Foxglove on {host}:{port}: "
                             + ("the port is in use (another server, or an earlier stream "
                                "not stopped); choose another with port=... / --port, or 0 "
                                "for a free one" if busy else
                                f"{exc.strerror or exc}")) from None
        try:   # the SDK server, on a free port of the loopback, behind the relay
            self._server = foxglove.start_server(name=name, host="127.0.0.1", port=0,
                                                 context=self._context,
                                                 server_listener=listener)  # type: ignore[arg-type]
        except Exception as exc:   # the SDK raises its own RuntimeError: name the address
            sock.close()
            raise ServeError(None, f"cannot serve Foxglove on 127.0.0.1 ({exc})") from None
        try:
            self._relay = SubprotocolRelay(sock, f"ws://127.0.0.1:{int(self._server.port)}")
        except OSError as exc:
            self._server.stop()
            raise ServeError(exc.errno, f"cannot serve Foxglove on {host}:{port} "
                             f"({exc.strerror or exc})") from None
        self.host = host
        self.port = self._relay.port

    @property
    def url(self) -> str:
        """``ws://host:port``, what Foxglove opens."""
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"ws://{host}:{self.port}"

    # ------------------------------------------------------------------ publishing
    def _subscribed(self, channel_id: int) -> None:
        key = self._by_id.get(channel_id)
        if key is not None:
            with self._lock:
                self._resend.add(key)

    def _flush_resend(self, stamp: int) -> None:
        with self._lock:
            keys, self._resend = self._resend, set()
        if "robot_description" in keys:
            self._channels["robot_description"].log(self.encoder.robot_description(),
                                                    log_time=stamp)
        if "tf_static" in keys:
            self._channels["tf_static"].log(self.encoder.tf_static(stamp), log_time=stamp)
        if keys - set(_STATIC) and self._last is not None:
            self._send(*self._last, stamp=stamp)

    def publish(self, q: ArrayLike, *, slot: int | None = None, flags: int = 0,
                stamp_ns: int | None = None) -> bool:
        """Publish the pose of actuators ``q`` in one FK slot.

        Parameters
        ----------
        q : array-like, shape (3,)
            Actuators, m.
        slot : int, keyword-only, optional
            Forward-kinematics slot (default: the first valid one, mode +1 first).
        flags : int, keyword-only
            :class:`~athenakin.motion.TrackFlag` bits for ``/athena/status`` (a uint32,
            0 to 2**32 - 1).
        stamp_ns : int, keyword-only, optional
            Stamp, ns, 0 to 2**63 - 1 (default: now).

        Returns
        -------
        bool
            False when ``q`` has no valid configuration (only the status, ``valid``
            false, is published).
        """
        qa = check_array(q, "q", (3,), allow_nonfinite=True)
        if qa.shape != (3,):
            raise InvalidInputError(f"q: expected shape (3,), got {qa.shape}")
        check_uint(flags, "flags", 2**32)
        if stamp_ns is not None:
            check_uint(stamp_ns, "stamp_ns", 2**63)
        stamp = time.time_ns() if stamp_ns is None else int(stamp_ns)
        self._flush_resend(stamp)
        sol = forward_kinematics(qa, self.T_b_e, self.design, errors="flag")
        valid = np.flatnonzero(sol.valid)
        if slot is not None:
            slot = check_slot(slot)
        k = int(slot) if slot is not None and sol.valid[slot] else \
            (int(valid[0]) if valid.size else -1)
        state = (qa.copy(), k, int(flags), sol)
        with self._lock:
            self._last = state
        self._send(*state, stamp=stamp)
        return k >= 0

    def _send(self, q: Any, k: int, flags: int, sol: Any, *, stamp: int) -> None:
        ok = k >= 0
        nan = math.nan
        b = TrackedBatch(
            stamps_ns=np.array([stamp]), q=q[None], valid=np.array([ok]),
            p=np.array([sol.p[k] if ok else nan]),
            u=(sol.u[k] if ok else np.full(5, nan))[None],
            O_s=(sol.T_b_s[k, :3, 3] if ok else np.full(3, nan))[None],
            mode=np.array([sol.mode[k] if ok else 0]), slot=np.array([max(k, 0)]),
            flags=np.array([flags | (0 if ok else 1)]), step=np.array([0.0]),
            half_chord=np.array([nan]), sin_u2=np.array([abs(np.sin(sol.u[k, 1])) if ok
                                                         else nan]),
            sin_u4=np.array([abs(np.sin(sol.u[k, 3])) if ok else nan]))
        with self._lock:
            self._sample += 1
            status = self.encoder.status(b, self._sample - 1)
        self._channels["status"].log(status[0].tobytes(), log_time=stamp)
        if ok:
            msgs = self.encoder.poses(b.stamps_ns, b.q, b.p, b.u, b.O_s)
            for key in ("tf", "joint_states", "tool_tip"):
                self._channels[key].log(msgs[key][0].tobytes(), log_time=stamp)

    def set_setup(self, design: Design | None, T_b_e: ArrayLike | None) -> None:
        """Change the design and RCM frame; the URDF and fixed frames are sent again.

        Parameters
        ----------
        design : Design or None
            Default :meth:`Design.default`.
        T_b_e : array-like, shape (4, 4), or None
            RCM frame in the base frame, m (default :func:`athenakin.default_rcm_frame`).
        """
        design = resolve_design(design)
        T = resolve_rcm_frame(T_b_e, design)
        encoder = RosEncoder(T, design, backend=self.backend)
        with self._lock:
            self.design, self.T_b_e, self.encoder = design, T, encoder
            self._last = None
            self._resend |= set(_STATIC)

    # ------------------------------------------------------------------ following
    def follow(self, state: Callable[[], tuple[ArrayLike, int | None]], *,
               rate: float = 30.0) -> None:
        """Publish ``state()`` (``(q, slot)``) in a thread, whenever it changes.

        Parameters
        ----------
        state : callable
            Returns the current actuators (m) and FK slot (None: the first valid).
            It is called from the thread, ``rate`` times a second.
        rate : float, keyword-only
            Polls per second (at most 1000); the current pose is also sent again
            once a second and whenever a client subscribes.
        """
        if not callable(state):
            raise TypeError(f"state: expected a callable returning (q, slot), got "
                            f"{type(state).__name__}")
        if isinstance(rate, bool) or not isinstance(rate, (int, float)) \
                or not 0.1 <= rate <= MAX_RATE:
            raise InvalidInputError(f"rate: expected 0.1 to {MAX_RATE:g} per second, got "
                                    f"{rate!r}")
        if self._thread is not None:
            raise RuntimeError("follow: already following a state")
        period = 1.0 / float(rate)

        def loop() -> None:
            last: tuple[Any, ...] | None = None
            sent = 0.0
            while not self._stop.wait(period):
                try:
                    q, slot = state()
                    key = (tuple(np.asarray(q, float).ravel().tolist()), slot)
                    now = time.monotonic()
                    if key != last or now - sent >= 1.0:
                        self.publish(q, slot=slot if isinstance(slot, int) else None)
                        last, sent = key, now
                    self._flush_resend(time.time_ns())
                except Exception:   # noqa: BLE001 - a bad state must not kill the stream
                    continue

        self._thread = threading.Thread(target=loop, name="athenakin-foxglove", daemon=True)
        self._thread.start()

    def poll(self) -> None:
        """Send what newly subscribed clients need (the thread of :meth:`follow` does it)."""
        self._flush_resend(time.time_ns())

    def stop(self) -> None:
        """Stop the thread, close every client and stop the server (idempotent)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
        self._relay.stop()
        self._server.stop()

    def __enter__(self) -> FoxgloveStream:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


def serve_app(app: Any, *, host: str = "127.0.0.1", port: int = DEFAULT_PORT,
              rate: float = 30.0) -> FoxgloveStream:
    """Serve the live robot of an :class:`athenakin.app.AthenaApp` to Foxglove.

    Polls ``app.q``, ``app.slot`` and ``app.setup`` (design, RCM frame) ``rate``
    times a second and publishes every change; call ``.stop()`` on the result.
    """
    setup = app.setup
    live = FoxgloveStream(setup.T_b_e, setup.design, host=host, port=port)
    seen = [setup]

    def state() -> tuple[ArrayLike, int | None]:
        cur = app.setup
        if cur is not seen[0]:
            seen[0] = cur
            live.set_setup(cur.design, cur.T_b_e)
        slot = app.slot
        return np.array(app.q, dtype=float), slot if isinstance(slot, int) else None

    live.follow(state, rate=rate)
    return live


class _Listener:
    """foxglove ServerListener: remember subscriptions to send them the current state."""

    def __init__(self, stream: FoxgloveStream) -> None:
        self.stream = stream

    def on_subscribe(self, client: Any, channel: Any) -> None:
        self.stream._subscribed(int(channel.id))

    def on_unsubscribe(self, client: Any, channel: Any) -> None:
        pass
