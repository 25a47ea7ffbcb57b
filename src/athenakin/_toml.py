"""The package's one TOML file reader (private): design files, task files, bounds.

It also holds :class:`TomlOptions`, the TOML round trip of the frozen options objects
(``CalibrationOptions``, ``StudyOptions``, ``RobotStyle``, ...): one table per object,
written with tomli-w like every other writer of the package, read with :func:`read_toml`.

Every TOML reader of athenakin goes through :func:`read_toml`, so that a file that is
not UTF-8, not TOML, or nested too deeply for the parser's recursion is one named
error that says which file and what is wrong, never a raw ``UnicodeDecodeError`` or
``RecursionError`` (the fuzz target ``scripts/fuzz_readers.py`` tries such files).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar, TypeVar

from ._compat import tomllib
from ._input import MAX_CONFIG_BYTES, read_bytes
from ._output import naming_path
from .errors import InvalidInputError

__all__ = ["read_toml", "TomlOptions"]

_T = TypeVar("_T", bound="TomlOptions")


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


class TomlOptions:
    """Mixin of a frozen options dataclass: ``to_mapping`` / ``from_mapping``, TOML round trip.

    The subclass names its table (``TOML_TABLE``, e.g. ``"calibration"``) and validates
    every field in ``__post_init__`` (so that :meth:`from_mapping`, :meth:`from_toml` and
    the constructor refuse the same values with the same named errors). Fields that are
    None are left out of the TOML text (TOML has no null); a field whose default is not
    None must therefore not take None. Tuples are written as arrays and read back as
    tuples. A subclass with a field that is no TOML value (a nested object) overrides
    :meth:`to_mapping` and :meth:`from_mapping`.
    """

    TOML_TABLE: ClassVar[str]

    def to_mapping(self) -> dict[str, Any]:
        """The fields as a dict of TOML values (None left out, tuples as lists).

        Returns
        -------
        dict of str -> TOML value
            One entry per field that is not None, in field order.
        """
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            v = getattr(self, f.name)
            if v is None:
                continue
            out[f.name] = _plain(v)
        return out

    @classmethod
    def from_mapping(cls: type[_T], data: Mapping[str, Any]) -> _T:
        """Build from a mapping of field names (e.g. a parsed TOML table).

        Parameters
        ----------
        data : mapping of str -> value
            Field names to values (TOML lists become tuples); missing fields take their
            defaults.

        Returns
        -------
        instance of the class

        Raises
        ------
        TypeError
            ``data`` is not a mapping.
        InvalidInputError
            An unknown key (named, with the known ones), or a bad value (named by the
            field's own check; a wrong type read from a file is bad input too).
        """
        if not isinstance(data, Mapping):
            raise TypeError(f"data: expected the [{cls.TOML_TABLE}] table (a mapping), got "
                            f"{type(data).__name__}")
        names = [f.name for f in dataclasses.fields(cls)]  # type: ignore[arg-type]
        unknown = sorted(set(data) - set(names))
        if unknown:
            raise InvalidInputError(f"{cls.TOML_TABLE}: unknown key(s) {unknown}; expected "
                                    f"some of {names}")
        kw = {k: tuple(v) if isinstance(v, list) else v for k, v in data.items()}
        try:
            return cls(**kw)
        except TypeError as exc:     # a value of the wrong type, read from a table
            raise InvalidInputError(f"{cls.TOML_TABLE}.{exc}") from None

    def to_toml(self) -> str:
        """TOML text, one ``[TOML_TABLE]`` table, that :meth:`from_toml` reads back equal.

        Returns
        -------
        str
            UTF-8 TOML text.
        """
        import tomli_w

        return tomli_w.dumps({self.TOML_TABLE: self.to_mapping()})

    @classmethod
    def from_toml(cls: type[_T], path: str | Path) -> _T:
        """Read the ``[TOML_TABLE]`` table of a TOML file (defaults when it has none).

        Other tables of the file (``[design]``, ``[task]``, ...) are left to their readers.

        Parameters
        ----------
        path : str or Path
            A TOML file.

        Returns
        -------
        instance of the class

        Raises
        ------
        OSError
            The file cannot be read.
        InvalidInputError
            Not UTF-8 TOML, or a bad table; the message starts with the file name.
        """
        data = read_toml(path, what=f"{cls.TOML_TABLE} options file")
        table = data.get(cls.TOML_TABLE, {})
        try:
            return cls.from_mapping(table)
        except (InvalidInputError, TypeError, ValueError) as exc:
            raise InvalidInputError(f"{path}: {exc}") from None


def _plain(v: Any) -> Any:
    """A TOML value: tuples (nested too) as lists, mappings as tables."""
    if isinstance(v, tuple | list):
        return [_plain(x) for x in v]
    if isinstance(v, Mapping):
        return {str(k): _plain(x) for k, x in v.items()}
    return v
