"""Writes of GUI values by the app itself, told apart from the browser's (private).

viser calls a GUI input's update callbacks in two ways: *synchronously, in the writing
thread*, when Python assigns ``handle.value``; and *on its thread pool* when the browser
sends a new value. The app ignores the first kind (its own echo) and must never drop the
second. A flag on the app object did both at once: while one pool thread wrote the
sliders back, the callback of the next key press, on another pool thread, saw the flag
and returned, and that key press was lost (on a busy machine). The flag is
therefore per thread.

The drags (the tip handle, the tip grip, the force handle) have a gesture's state: a
start, updates and an end. On the thread pool those may be handled in any order (an end
before its start left a drag on for ever). Their callbacks are ``async``: viser awaits
them on its event loop in the order the page sent the events (its own advice for
stateful drags), where they keep the gesture's state; each hands its move (the IK, the
scene) to an :class:`OrderedWorker`, one thread, so that the event loop never waits for
a move and the moves run in the events' order.
"""

from __future__ import annotations

import contextlib
import functools
import sys
import threading
import traceback
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any

__all__ = ["Echo", "OrderedWorker"]


class Echo:
    """True in the thread that is writing GUI values (``with echo(): handle.value = v``)."""

    def __init__(self) -> None:
        self._local = threading.local()

    def __bool__(self) -> bool:
        return bool(getattr(self._local, "on", False))

    @contextlib.contextmanager
    def __call__(self) -> Iterator[None]:
        prev = bool(self)
        self._local.on = True
        try:
            yield
        finally:
            self._local.on = prev


class OrderedWorker:
    """One thread that runs the moves of the drags, in the order they are submitted.

    Parameters
    ----------
    name : str
        The thread's name prefix.
    """

    def __init__(self, name: str) -> None:
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix=name)
        self._lock = threading.Lock()
        self._newest: dict[str, tuple[Callable[..., Any], tuple[Any, ...]]] = {}

    def submit(self, fn: Callable[..., Any], *args: Any, newest: str | None = None) -> None:
        """Run ``fn(*args)`` after the moves submitted before it; none once stopped.

        With ``newest`` (a key), a move of that key still waiting is replaced by this
        one: a slow move leaves no backlog of stale ones, and the last submitted runs.
        An exception of ``fn`` is printed with its traceback on stderr (a future would
        keep it silent).
        """
        job: Callable[[], Any]
        if newest is None:
            job = functools.partial(fn, *args)
        else:
            with self._lock:
                waiting = newest in self._newest
                self._newest[newest] = (fn, args)
            if waiting:
                return
            job = functools.partial(self._run_newest, newest)
        try:
            done = self._pool.submit(job)
        except RuntimeError:          # stopped: the app takes no more moves
            return
        done.add_done_callback(_print_error)

    def _run_newest(self, key: str) -> None:
        with self._lock:
            fn, args = self._newest.pop(key)
        fn(*args)

    def drain(self) -> None:
        """Block until every move submitted so far has run (nothing to wait for once stopped)."""
        try:
            self._pool.submit(lambda: None).result()
        except RuntimeError:
            return

    def stop(self) -> None:
        """Let the moves submitted run, then end the thread; later ones are dropped."""
        self._pool.shutdown(wait=True)


def _print_error(done: Future[Any]) -> None:
    exc = done.exception()
    if exc is not None:
        traceback.print_exception(type(exc), exc, exc.__traceback__, file=sys.stderr)
