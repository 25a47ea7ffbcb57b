"""Ctrl-C that is not lost (private).

Imported first by the package ``__init__``. When the process is the CLI (the
``athenakin`` script, ``python -m athenakin``), an interrupt during the package's
imports (numpy, the subpackages: before :func:`athenakin.cli.main` can catch it)
prints one line and exits 130 instead of a traceback. A library import (any other
program) leaves ``sys.excepthook`` alone.

:func:`remembered_interrupt` and :func:`check_interrupt` keep a Ctrl-C that Python
raised where it cannot propagate. Python runs the SIGINT handler in whatever Python code
the main thread is executing; inside a ``__del__``, a weakref callback or a finalizer
(matplotlib's callback registry creates and drops such objects with every artist) the
``KeyboardInterrupt`` is printed as "Exception ignored" and lost, and ``athenakin
animate`` would run to the end and exit 0 (about 1 run in 11). Within
:func:`remembered_interrupt` the handler also records the signal, and a long loop calls
:func:`check_interrupt` at each step to raise it again.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator
from types import FrameType, TracebackType

__all__: list[str] = []

#: Set by the SIGINT handler of :func:`remembered_interrupt`; cleared when it ends.
_PENDING = threading.Event()


@contextlib.contextmanager
def remembered_interrupt() -> Iterator[None]:
    """SIGINT raises ``KeyboardInterrupt`` as usual, and is remembered for :func:`check_interrupt`.

    Only in the main thread while the default handler is installed (a program with its
    own SIGINT handler keeps it); elsewhere this does nothing. A Ctrl-C remembered and
    not raised again when the block ends is raised at its end.
    """
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler):
        yield
        return

    def handler(signum: int, frame: FrameType | None) -> None:
        _PENDING.set()
        raise KeyboardInterrupt

    _PENDING.clear()
    signal.signal(signal.SIGINT, handler)
    try:
        yield
        check_interrupt()
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)
        _PENDING.clear()


def check_interrupt() -> None:
    """Raise ``KeyboardInterrupt`` if a Ctrl-C was remembered (:func:`remembered_interrupt`).

    Cheap (one flag); a no-op outside :func:`remembered_interrupt`.
    """
    if _PENDING.is_set():
        raise KeyboardInterrupt


def _cli_interrupt_hook(exc_type: type[BaseException], exc: BaseException,
                        tb: TracebackType | None) -> None:
    if issubclass(exc_type, KeyboardInterrupt):
        sys.stderr.write("athenakin: interrupted (no output written)\n")
        sys.stderr.flush()
        os._exit(130)
    sys.__excepthook__(exc_type, exc, tb)


def _is_cli() -> bool:
    """The process was started as the CLI (``-m`` while locating, or the script)."""
    return bool(sys.argv) and (sys.argv[0] == "-m"
                               or os.path.basename(sys.argv[0]) == "athenakin")


if _is_cli() and sys.excepthook is sys.__excepthook__:
    sys.excepthook = _cli_interrupt_hook
