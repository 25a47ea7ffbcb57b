"""Writes of GUI values by the app itself, told apart from the browser's (private).

viser calls a GUI input's update callbacks in two ways: *synchronously, in the writing
thread*, when Python assigns ``handle.value``; and *on its thread pool* when the browser
sends a new value. The app ignores the first kind (its own echo) and must never drop the
second. A flag on the app object did both at once: while one pool thread wrote the
sliders back, the callback of the next key press, on another pool thread, saw the flag
and returned, and that key press was lost (on a busy machine). The flag is
therefore per thread.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Iterator

__all__ = ["Echo"]


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
