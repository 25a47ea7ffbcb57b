"""The one TOML reader of the package (private): design, task and bounds files.

Every reader of a TOML file goes through :func:`read_toml`, so that a file is
read the same way everywhere: UTF-8 with or without a byte-order mark (as
Windows editors write it), and every way it can be malformed (not UTF-8, not
TOML, nested too deeply for the parser, an integer too long to convert) is one
error of the caller's type whose message starts with the file name.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ._compat import tomllib
from .errors import InvalidInputError

__all__ = ["read_toml"]


def read_toml(path: str | Path, *, error: type[Exception] = InvalidInputError
              ) -> dict[str, Any]:
    r"""The parsed content of a TOML file.

    Parameters
    ----------
    path : str or Path
        The file (UTF-8; a leading byte-order mark is ignored).
    error : type of Exception
        The error raised for a file that is not valid TOML (default
        :class:`~athenakin.errors.InvalidInputError`).

    Returns
    -------
    dict
        The top-level table.

    Raises
    ------
    OSError
        The file cannot be read (missing, a folder, no permission).
    error
        Not UTF-8, not TOML, nested too deeply or holding an integer of more
        digits than Python converts; the message names the file and the problem.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "a.toml"
    >>> _ = f.write_bytes(b"\xef\xbb\xbfl1 = 0.3\n")
    >>> read_toml(f)
    {'l1': 0.3}
    """
    raw = Path(path).read_bytes()
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise error(f"{path}: not a UTF-8 text file (byte {exc.start}: {exc.reason})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: not valid TOML ({exc})") from None
    except RecursionError:  # tomllib recurses once per nested array or table
        raise error(f"{path}: TOML nested too deeply") from None
    except ValueError as exc:  # an integer beyond sys.get_int_max_str_digits()
        raise error(f"{path}: a number that cannot be read ({' '.join(str(exc).split())[:120]})"
                    ) from None
