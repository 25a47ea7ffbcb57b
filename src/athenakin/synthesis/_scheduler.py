"""Opening a design study's scheduler: a local one, an Executor, or a Dask client by address."""

from __future__ import annotations

import concurrent.futures
import re
import socket
import struct
import time
from typing import Any

from ..errors import InvalidInputError
from ._errors import SchedulerUnreachableError

#: Names of Dask's local schedulers accepted by ``scheduler=``.
LOCAL_SCHEDULERS = ("threads", "processes", "synchronous", "sync", "single-threaded")


#: Seconds to wait for a scheduler given by address before :class:`SchedulerUnreachableError`.
CONNECT_TIMEOUT = 5.0


#: The form of a scheduler address: ``[protocol://]host:port``.
_ADDRESS = re.compile(r"^([a-z][a-z0-9+.-]*://)?[^\s/]+:\d{1,5}$")


#: Largest first message (bytes) a ``distributed`` scheduler sends on a new connection; its
#: handshake is a few hundred bytes. A larger announced size means the peer is not a scheduler.
MAX_HANDSHAKE_BYTES = 1 << 20


def _extra() -> str:
    return "pip install 'athenakin[synthesis]'"


def _require(name: str) -> Any:
    import importlib

    try:
        return importlib.import_module(name)
    except ModuleNotFoundError as exc:
        raise ModuleNotFoundError(f"athenakin.synthesis needs {name!r}: {_extra()}",
                                  name=name) from exc


def open_scheduler(scheduler: Any, *, connect_timeout: float = CONNECT_TIMEOUT
                   ) -> tuple[str, Any, bool]:
    """Resolve ``scheduler=`` into ``(kind, handle, owned)``.

    ``None`` -> Dask's local threaded scheduler; a name of :data:`LOCAL_SCHEDULERS`
    -> that local scheduler; a ``distributed.Client`` -> that client; any other
    string -> the address of a ``distributed`` scheduler (``"tcp://host:8786"``),
    connected here (``owned``: the caller closes it).

    Raises
    ------
    SchedulerUnreachableError
        If no scheduler answers at the address within ``connect_timeout`` s.
    TypeError
        For any other kind of object.
    """
    if scheduler is None:
        return "local", "threads", False
    if isinstance(scheduler, str) and scheduler in LOCAL_SCHEDULERS:
        return "local", scheduler, False
    if isinstance(scheduler, str):
        if not _ADDRESS.match(scheduler):   # distributed.Client would fail and then print a
            raise InvalidInputError(        # traceback from its __del__, 10 s later
                f"scheduler: expected one of {LOCAL_SCHEDULERS} or an address "
                f"'tcp://host:port', got {scheduler!r}")
        distributed = _require("distributed")
        _probe_scheduler(scheduler, connect_timeout)
        import logging

        logger = logging.getLogger("distributed")
        level = logger.level
        logger.setLevel(logging.CRITICAL)
        try:
            client = distributed.Client(scheduler, timeout=connect_timeout,
                                        set_as_default=False)
        except (OSError, TimeoutError, ValueError, MemoryError, OverflowError) as exc:
            why = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise _unreachable(scheduler, connect_timeout, why) from None
        finally:
            logger.setLevel(level)
        return "distributed", client, True
    if _is_client(scheduler):
        return "distributed", scheduler, False
    if isinstance(scheduler, concurrent.futures.Executor):
        return "executor", scheduler, False
    raise TypeError(f"scheduler: expected None, one of {LOCAL_SCHEDULERS}, an address string, "
                    f"a distributed.Client or a concurrent.futures.Executor, got "
                    f"{type(scheduler).__name__}")


def _unreachable(address: str, timeout: float, why: str) -> SchedulerUnreachableError:
    return SchedulerUnreachableError(
        f"cannot reach a Dask scheduler at {address!r} within {timeout:g} s ({why})")


def _probe_scheduler(address: str, timeout: float) -> None:
    """Check that a ``tcp://`` address (or a bare ``host:port``) speaks Dask's protocol.

    A ``distributed`` scheduler writes its handshake first on every new connection: an
    8-byte little-endian size, then that many bytes of msgpack. Read the size (within
    ``timeout`` s) and require it to be a handshake's, before ``distributed.Client`` would
    trust it and allocate whatever a foreign server's first bytes announce (3 EiB for an
    HTTP reply). Other protocols (``tls://``, ``ucx://``, ...) are left to ``distributed``.

    Raises
    ------
    SchedulerUnreachableError
        If nothing accepts the connection, nothing is said within ``timeout`` s, or what is
        said is not a Dask handshake.
    """
    protocol, sep, rest = address.rpartition("://")
    if sep and protocol != "tcp":
        return
    host, _, port = rest.rpartition(":")
    host = host.strip("[]")
    deadline = time.monotonic() + timeout
    try:
        sock = socket.create_connection((host, int(port)), timeout=timeout)
    except TimeoutError:
        raise _unreachable(address, timeout, "nothing accepted the connection") from None
    except (OSError, ValueError) as exc:
        why = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise _unreachable(address, timeout, why) from None
    head = b""
    with sock:
        try:
            while len(head) < 8:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise TimeoutError
                sock.settimeout(left)
                chunk = sock.recv(8 - len(head))
                if not chunk:
                    raise _unreachable(address, timeout,
                                       "the peer closed the connection without a handshake")
                head += chunk
        except SchedulerUnreachableError:   # a ConnectionError, hence an OSError: as it is
            raise
        except TimeoutError:
            raise _unreachable(address, timeout, "connected, but no handshake came") from None
        except OSError as exc:
            raise _unreachable(address, timeout, str(exc) or type(exc).__name__) from None
    (size,) = struct.unpack("<Q", head)
    if not 0 < size <= MAX_HANDSHAKE_BYTES:
        raise _unreachable(address, timeout,
                           f"something answers, but not a Dask scheduler: its first message "
                           f"announces {size} bytes, a handshake is under "
                           f"{MAX_HANDSHAKE_BYTES} bytes")


def _is_client(obj: object) -> bool:
    try:
        from distributed import Client
    except ModuleNotFoundError:
        return False
    return isinstance(obj, Client)
