"""Writing an output file: one atomic writer, errors that name the path (private).

Every writer of a user's file goes through :func:`write_text_atomic` (a temporary
file in the same folder and a rename, so an interrupted write leaves the old file
or none, never half of one) or, for a library that writes by itself (numpy's
``savez``), wraps its call in :func:`naming_path`. An ``OSError`` then always
names the path (``/dev/full``: "No space left on device" alone does not), and a
path that exists but is not a regular file (a FIFO, which would block until a
reader comes; a device; a folder) is refused before anything is written.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path

from ._validation import check_path
from .errors import InvalidInputError

__all__ = ["write_text_atomic", "naming_path", "check_output_path"]


def check_output_path(path: object, name: str = "path") -> Path:
    """Coerce an output path and refuse one that exists and is not a regular file.

    Raises
    ------
    TypeError
        ``path`` is not a str or os.PathLike.
    InvalidInputError
        ``path`` is empty, or names a FIFO, a device, a socket or a folder.
    """
    p = check_path(path, name)
    try:
        mode = os.stat(p).st_mode
    except OSError:
        return p                      # a new file (or an unreadable folder: open says)
    if not stat.S_ISREG(mode):
        kind = ("a FIFO (named pipe)" if stat.S_ISFIFO(mode) else "a folder"
                if stat.S_ISDIR(mode) else "a device" if stat.S_ISCHR(mode)
                or stat.S_ISBLK(mode) else "not a regular file")
        raise InvalidInputError(f"{name}: {os.fspath(p)} is {kind}; expected the path of a "
                                f"regular file to write")
    return p


@contextlib.contextmanager
def naming_path(path: str | os.PathLike[str]) -> Iterator[None]:
    """Re-raise an ``OSError`` of the block as the same class, naming ``path``."""
    try:
        yield
    except OSError as exc:
        if exc.filename is not None:
            raise
        raise type(exc)(exc.errno, exc.strerror or str(exc), os.fspath(path)) from None


def write_text_atomic(path: str | Path, text: str | bytes) -> None:
    """Write a file through a temporary file in the same folder and a rename.

    The file gets the permissions a new file would get (``0o666 & ~umask``) or,
    when it replaces a file, that file's permissions; a symbolic link is
    followed (its target is replaced, the link stays a link).

    Raises
    ------
    TypeError, InvalidInputError
        ``path`` is not a path, or names something other than a regular file.
    OSError
        The file cannot be written (the error names ``path``).
    """
    path = Path(os.path.realpath(check_output_path(path)))
    with naming_path(path):
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
        try:
            with os.fdopen(fd, "wb") as fh:
                fh.write(text.encode("utf-8") if isinstance(text, str) else text)
            try:
                mode = stat.S_IMODE(os.stat(path).st_mode)
            except FileNotFoundError:
                mask = os.umask(0o022)
                os.umask(mask)
                mode = 0o666 & ~mask
            os.chmod(tmp, mode)
            os.replace(tmp, path)
        except BaseException:
            if os.path.exists(tmp):
                os.unlink(tmp)
            raise
