"""The package's one TOML file reader (private): design files, task files, bounds.

Every TOML reader of athenakin goes through :func:`read_toml`, so that a file that is
not UTF-8, not TOML, or nested too deeply for the parser's recursion is one named
error that says which file and what is wrong, never a raw ``UnicodeDecodeError`` or
``RecursionError`` (issue 13, found by the fuzz target ``scripts/fuzz_readers.py``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ._compat import tomllib
from ._input import MAX_CONFIG_BYTES, read_bytes
from ._output import naming_path
from .errors import InvalidInputError

__all__ = ["read_toml"]


def read_toml(path: str | Path, *, error: type[Exception] = InvalidInputError,
              what: str = "TOML file") -> dict[str, Any]:
    r"""Parse a TOML file into a dict.

    Parameters
    ----------
    path : str or Path
        UTF-8 text; a leading byte-order mark (as Windows editors write) is ignored.
    error : exception class, keyword-only
        Raised (with a one-line message naming ``path``) when the content is not UTF-8
        TOML or is nested too deeply. Default :class:`~athenakin.errors.InvalidInputError`.
    what : str, keyword-only
        What the file is, for the messages (e.g. ``"task file"``).

    Returns
    -------
    dict
        The parsed top-level table.

    Raises
    ------
    OSError
        The file cannot be opened or read (left to the caller, which knows the option);
        its ``filename`` is always ``path`` (a failed read, EIO, names it too).
    error
        Not UTF-8, not valid TOML, tables / arrays nested too deeply, or an integer
        of more digits than Python converts.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "a.toml"
    >>> _ = f.write_bytes(b"\xef\xbb\xbfl1 = 0.3\n")   # with a byte-order mark
    >>> read_toml(f)
    {'l1': 0.3}
    """
    # a read that fails on an open file (EIO on a failing disk or a network share)
    # carries no file name: naming_path gives it the file's, same class and errno
    with naming_path(path):
        raw = read_bytes(path, limit=MAX_CONFIG_BYTES, error=error, what=what)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise error(f"{path}: {what} is not UTF-8 text (byte {exc.start})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: not valid TOML ({exc})") from None
    except RecursionError:  # tomllib recurses once per nested array or table
        raise error(f"{path}: {what}: TOML nested too deeply") from None
    except ValueError as exc:  # an integer beyond sys.get_int_max_str_digits()
        raise error(f"{path}: {what}: a number that cannot be read "
                    f"({' '.join(str(exc).split())[:120]})") from None
