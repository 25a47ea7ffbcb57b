"""The package's one CSV reader (private): header and numbered rows of a text table.

Used by every file format built on CSV (motion paths and q streams, calibration
measurements); each format adds its own columns, units and messages on top.
"""

from __future__ import annotations

import csv
from pathlib import Path

from ._input import MAX_TABLE_BYTES, read_bytes
from ._validation import check_path

__all__ = ["read_table", "Q_COLUMNS", "TIP_COLUMNS"]

#: Columns of actuator readings, m: q streams, trajectories and calibration measurements.
Q_COLUMNS = ("q1_m", "q2_m", "q3_m")
#: Columns of a tool-tip position, m: tip paths (frame E) and measured tips (tracker frame).
TIP_COLUMNS = ("x_m", "y_m", "z_m")


def read_table(path: str | Path, *, header_row: bool = True, error: type[Exception] = ValueError
               ) -> tuple[list[str], list[tuple[int, list[str]]]]:
    """Header cells and ``(line number, cells)`` rows of a CSV file.

    Blank lines and lines starting with ``#`` are skipped; a UTF-8 byte-order mark is
    not part of the first column; cells are stripped of spaces.

    Parameters
    ----------
    path : str or Path
    header_row : bool, keyword-only
        With False every line is a row (cells split at commas or whitespace) and the
        header is empty.
    error : exception class, keyword-only
        Raised (with the file, the line and what was expected) for a file that is not
        UTF-8 text or not CSV, an empty file, duplicate column names, or a file larger
        than :data:`~athenakin._input.MAX_TABLE_BYTES`.

    Returns
    -------
    header : list of str
    rows : list of (int, list of str)
        1-based line numbers and the cells of each data row.
    """
    path = check_path(path)
    raw = read_bytes(path, limit=MAX_TABLE_BYTES, error=error, what="CSV file")
    try:
        text = raw.decode("utf-8-sig")  # a byte-order mark is not a column
    except UnicodeDecodeError as exc:
        raise error(f"{path}: not a UTF-8 text file ({exc.reason})") from None
    nul = text.find("\x00")
    if nul >= 0:   # a binary file: never echo its bytes (a header of 4096 NULs) in a message
        raise error(f"{path}, line {text.count(chr(10), 0, nul) + 1}: not a text file (a NUL "
                    f"byte); expected a CSV table")
    rows = []
    header: list[str] | None = None
    for lineno, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        if not header_row:
            rows.append((lineno, line.replace(",", " ").split()))
            continue
        try:
            cells = [c.strip() for c in next(csv.reader([line]))]
        except csv.Error as exc:  # a NUL byte, a cell longer than the csv module's limit
            raise error(f"{path}, line {lineno}: not CSV ({exc})") from None
        if header is None:
            header = cells
            continue
        rows.append((lineno, cells))
    if not header_row:
        if not rows:
            raise error(f"{path}: empty file (expected data rows)")
        return [], rows
    if header is None:
        raise error(f"{path}: empty file, no header row (expected a header row and data rows)")
    dup = sorted({c for c in header if header.count(c) > 1})
    if dup:
        raise error(f"{path}: duplicate column(s) {dup}")
    return header, rows
