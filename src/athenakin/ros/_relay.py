"""A WebSocket relay that lets old and new Foxglove clients reach foxglove-sdk, private.

foxglove-sdk 0.30 accepts only the subprotocol names ``foxglove.sdk.v1`` and
``foxglove.sdk.v1.1``; Foxglove Studio 1.x and Lichtblick before its 2025-12
release offer only the older name of the same protocol, ``foxglove.websocket.v1``
(the Foxglove WebSocket protocol v1, foxglove/ws-protocol ``docs/spec.md``).
Foxglove's own stance is that ``foxglove.sdk.v1`` is that protocol under a new
name (foxglove discussion 1131; Lichtblick pull request 819 adds the new name
for that reason), so the relay only renames: it accepts a client offering any of
:data:`SUBPROTOCOLS` (answering with the first of them the client offered),
opens a connection to the SDK server with the SDK's name for it
(``foxglove.websocket.v1`` -> ``foxglove.sdk.v1``) and pipes text and binary
frames both ways unchanged. When either side closes, both are closed.
"""

from __future__ import annotations

import asyncio
import logging
import socket
import threading
from collections.abc import Sequence
from typing import Any

__all__ = ["SUBPROTOCOLS", "LEGACY_SUBPROTOCOL", "SubprotocolRelay", "bind_socket"]

#: The name Foxglove Studio 1.x and older Lichtblick offer.
LEGACY_SUBPROTOCOL = "foxglove.websocket.v1"
#: Names the relay accepts, in the order it prefers them (the SDK's order, then the old name).
SUBPROTOCOLS = ("foxglove.sdk.v1.1", "foxglove.sdk.v1", LEGACY_SUBPROTOCOL)
#: The name the relay offers the SDK server for each accepted name.
_UPSTREAM = {LEGACY_SUBPROTOCOL: "foxglove.sdk.v1"}
#: Largest message (bytes) a client may send; clients of this stream send only small JSON.
MAX_CLIENT_MESSAGE = 1 << 20
#: Logger of the relay; refused handshakes are logged there (silent unless logging is set up).
LOGGER = logging.getLogger("athenakin.ros.foxglove_relay")
LOGGER.addHandler(logging.NullHandler())
#: Seconds to wait for the relay thread to start, for the SDK server to answer, for the stop.
_TIMEOUT_S = 10.0


def bind_socket(host: str, port: int) -> socket.socket:
    """A TCP socket bound to the first address of ``host`` (one socket, so one port)."""
    family, kind, proto, _, addr = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0]
    sock = socket.socket(family, kind, proto)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(addr)
    except OSError:
        sock.close()
        raise
    return sock


def _select(connection: Any, offered: Sequence[str]) -> str:
    """Pick the first of :data:`SUBPROTOCOLS` the client offered, else refuse (HTTP 400)."""
    from websockets.exceptions import NegotiationError

    for name in SUBPROTOCOLS:
        if name in offered:
            return name
    raise NegotiationError(f"expected one of the subprotocols {', '.join(SUBPROTOCOLS)}; "
                           f"the client offered {', '.join(offered) or 'none'}")


async def _pipe(src: Any, dst: Any) -> None:
    """Send every frame of ``src`` to ``dst`` unchanged (text stays text, binary binary)."""
    from websockets.exceptions import ConnectionClosed

    try:
        async for message in src:
            await dst.send(message)
    except ConnectionClosed:
        pass


class SubprotocolRelay:
    """Serve ``sock`` in a daemon thread and relay each client to ``upstream_url``.

    Parameters
    ----------
    sock : socket.socket
        Bound, not yet listening (see :func:`bind_socket`); the relay owns it.
    upstream_url : str
        ``ws://127.0.0.1:PORT`` of the foxglove-sdk server.
    """

    def __init__(self, sock: socket.socket, upstream_url: str) -> None:
        self.port = int(sock.getsockname()[1])
        self._sock = sock
        self._upstream_url = upstream_url
        self._ready = threading.Event()
        self._error: BaseException | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop_event: asyncio.Event | None = None
        self._thread = threading.Thread(target=self._run, name="athenakin-foxglove-relay",
                                        daemon=True)
        self._thread.start()
        if not self._ready.wait(_TIMEOUT_S) or self._error is not None:
            self.stop()
            raise OSError(f"the Foxglove relay did not start ({self._error})")

    def _run(self) -> None:
        try:
            asyncio.run(self._main())
        except BaseException as exc:   # noqa: BLE001 - reported to __init__ through _error
            self._error = exc
            self._ready.set()

    async def _main(self) -> None:
        from websockets.asyncio.server import serve

        self._loop = asyncio.get_running_loop()
        self._stop_event = asyncio.Event()
        server = await serve(self._handle, sock=self._sock,
                             subprotocols=list(SUBPROTOCOLS),  # type: ignore[arg-type]
                             select_subprotocol=_select,  # type: ignore[arg-type]
                             compression=None, max_size=MAX_CLIENT_MESSAGE, logger=LOGGER)
        self._ready.set()
        await self._stop_event.wait()
        server.close()                 # closes every client with 1001 (going away)
        await server.wait_closed()     # and waits for their handlers

    async def _handle(self, client: Any) -> None:
        from websockets.asyncio.client import connect

        name = client.subprotocol
        offered = ", ".join(client.request.headers.get_all("Sec-WebSocket-Protocol"))
        LOGGER.info("client %s offered %s: accepted %s, relayed as %s",
                    client.remote_address, offered, name, _UPSTREAM.get(name, name))
        try:
            upstream = await connect(self._upstream_url,
                                     subprotocols=[_UPSTREAM.get(name, name)],
                                     compression=None, max_size=None, ping_interval=None,
                                     open_timeout=_TIMEOUT_S, close_timeout=2.0,
                                     logger=LOGGER)
        except Exception:   # noqa: BLE001 - the server is stopping or gone: tell the client
            await client.close(1011, "the Foxglove server is not available")
            return
        try:
            tasks = {asyncio.create_task(_pipe(client, upstream)),
                     asyncio.create_task(_pipe(upstream, client))}
            _, pending = await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
            for task in pending:
                task.cancel()
            await asyncio.gather(*pending, return_exceptions=True)
        finally:   # the client first: it must not wait on the SDK's side of the close
            await client.close()
            await upstream.close()

    def stop(self) -> None:
        """Close every client and the listening socket; join the thread (idempotent)."""
        loop, event = self._loop, self._stop_event
        if loop is not None and event is not None and self._thread.is_alive():
            try:
                loop.call_soon_threadsafe(event.set)
            except RuntimeError:   # the loop has already closed
                pass
        self._thread.join(timeout=_TIMEOUT_S)
        self._sock.close()
