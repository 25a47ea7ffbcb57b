"""Reading an input file with a bound on its size (private).

Every reader of a user's file (CSV tables, TOML, the RCM JSON) reads through
:func:`read_bytes`, so that a path to ``/dev/zero``, ``/dev/urandom`` or a
multi-gigabyte file by mistake is one named error, quickly, instead of memory
exhausted after seconds (or minutes, on a machine without a memory limit).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path
from typing import BinaryIO

__all__ = ["read_bytes", "open_regular", "MAX_TABLE_BYTES", "MAX_CONFIG_BYTES"]

#: Largest CSV table read, bytes: a q stream of 2 million readings (the most samples a
#: plan makes) is about 200 MB.
MAX_TABLE_BYTES = 512 * 2**20
#: Largest configuration file (design or task TOML, RCM JSON) read, bytes.
MAX_CONFIG_BYTES = 16 * 2**20


def read_bytes(path: str | Path, *, limit: int, error: type[Exception] = ValueError,
               what: str = "file") -> bytes:
    r"""The content of ``path``, at most ``limit`` bytes.

    Parameters
    ----------
    path : str or Path
    limit : int, keyword-only
        Largest size accepted, bytes.
    error : exception class, keyword-only
        Raised when the file holds more than ``limit`` bytes.
    what : str, keyword-only
        What the file is, for the message.

    Returns
    -------
    bytes

    Raises
    ------
    OSError
        The file cannot be opened or read.
    error
        The file is larger than ``limit`` bytes, or is not a regular file (a FIFO,
        which would block until a writer comes, a device such as ``/dev/zero``, a
        folder).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "a.csv"
    >>> _ = f.write_text("x_m\n0.25\n")
    >>> read_bytes(f, limit=100)
    b'x_m\n0.25\n'
    """
    with open_regular(path, error=error, what=what) as fh:
        data = fh.read(limit + 1)
    if len(data) > limit:
        raise error(f"{path}: {what} larger than {limit / 2**20:g} MiB; expected a smaller "
                    f"file (is it the right one?)")
    return data


def open_regular(path: str | Path | int, *, error: type[Exception] = ValueError,
                 what: str = "file") -> BinaryIO:
    """Open ``path`` for binary reading, refusing anything but a regular file.

    The file is opened with ``O_NONBLOCK`` so that a FIFO without a writer does not
    block the open itself; its kind is then checked on the open descriptor (no race
    with a rename), and the descriptor is returned to blocking mode.

    Raises
    ------
    TypeError
        ``path`` is not a str or os.PathLike (an int would be taken for a descriptor).
    OSError
        The file cannot be opened (the error names the path).
    error
        ``path`` is not a regular file.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path: expected a file path (str or os.PathLike), got "
                        f"{type(path).__name__}")
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    fd = os.open(path, flags)
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            kind = ("a FIFO (named pipe)" if stat.S_ISFIFO(mode) else "a folder"
                    if stat.S_ISDIR(mode) else "a device" if stat.S_ISCHR(mode)
                    or stat.S_ISBLK(mode) else "a socket" if stat.S_ISSOCK(mode)
                    else "not a regular file")
            raise error(f"{os.fspath(path)}: the {what} is {kind}; expected a regular file")
        if hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise
