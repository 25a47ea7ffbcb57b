"""Ctrl-C while the command-line interface is still importing: one line, exit 130 (private).

Imported first by the package ``__init__``. When the process is the CLI (the
``athenakin`` script, ``python -m athenakin``), an interrupt during the package's
imports (numpy, the subpackages: before :func:`athenakin.cli.main` can catch it)
prints one line and exits 130 instead of a traceback. A library import (any other
program) leaves ``sys.excepthook`` alone.
"""

from __future__ import annotations

import os
import sys
from types import TracebackType

__all__: list[str] = []


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
