"""Reading an input file with a bound on its size (private).

Every reader of a user's file (CSV tables, TOML, the RCM JSON) reads through
:func:`read_bytes`, so that a path to ``/dev/zero``, ``/dev/urandom`` or a
multi-gigabyte file by mistake is one named error, quickly, instead of memory
exhausted after seconds (or minutes, on a machine without a memory limit).
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["read_bytes", "MAX_TABLE_BYTES", "MAX_CONFIG_BYTES"]

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
        The file is larger than ``limit`` bytes (or endless, as ``/dev/zero``).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "a.csv"
    >>> _ = f.write_text("x_m\n0.25\n")
    >>> read_bytes(f, limit=100)
    b'x_m\n0.25\n'
    """
    with open(path, "rb") as fh:
        data = fh.read(limit + 1)
    if len(data) > limit:
        raise error(f"{path}: {what} larger than {limit / 2**20:g} MiB; expected a smaller "
                    f"file (is it the right one?)")
    return data
