"""Files of calibration: measurement CSV in, plan CSV out, calibrated design TOML out.

Measurement CSV (docs/calibration.md): a header row with the columns ``q1_m, q2_m, q3_m``
(actuator readings, m) and ``x_m, y_m, z_m`` (measured tool tip, m, in the base or the
tracker frame), optionally ``dx, dy, dz`` (measured unit instrument axis, same frame) and
``mode`` (assembly mode of the row, +1 or -1); other columns are ignored. Lines starting
with ``#`` and blank lines are skipped. An empty cell or ``nan`` makes its row a bad row
(excluded and reported by :func:`~athenakin.calibration.calibrate`); text that is not a
number is an error naming file, line and column.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from .._csv import Q_COLUMNS, TIP_COLUMNS, read_table
from .._typing import FloatArray, IntArray
from .._validation import check_array, check_choice, check_instance
from ..errors import InvalidInputError
from ._errors import MeasurementFileError
from ._solve import CalibrationResult

__all__ = [
    "Q_COLUMNS",
    "TIP_COLUMNS",
    "AXIS_COLUMNS",
    "Measurements",
    "read_measurements_csv",
    "measurements_csv_text",
    "plan_csv_text",
    "calibration_toml",
]

#: Measured instrument axis (unit vector, optional).
AXIS_COLUMNS = ("dx", "dy", "dz")


@dataclasses.dataclass(frozen=True)
class Measurements:
    """A measurement file.

    Attributes
    ----------
    q : ndarray, shape (N, 3)
        Readings, m (NaN for empty / ``nan`` cells).
    tips : ndarray, shape (N, 3) or None
        Measured tips, m; None in a plan file (readings only).
    axes : ndarray, shape (N, 3) or None
        Measured axes when the file has ``dx, dy, dz``.
    lines : ndarray of int, shape (N,)
        Line number of each row in the file (1-based), for reports.
    mode : ndarray of int, shape (N,) or None
        Assembly mode of each row (+1 / -1) when the file has a ``mode`` column.
    """

    q: FloatArray
    tips: FloatArray | None
    axes: FloatArray | None
    lines: IntArray
    mode: IntArray | None = None


def _cell(text: str, path: str | Path, line: int, col: str) -> float:
    t = text.strip()
    if t == "" or t.lower() == "nan":
        return math.nan
    try:
        return float(t)
    except ValueError:
        raise MeasurementFileError(f"{path}: line {line}, column {col!r}: expected a number "
                                   f"(m), got {text!r}") from None


def read_measurements_csv(path: str | Path, *, require_tips: bool = True) -> Measurements:
    """Read a measurement (or, with ``require_tips=False``, a plan) CSV file.

    Parameters
    ----------
    path : str or Path
    require_tips : bool, keyword-only
        Whether ``x_m, y_m, z_m`` must be present.

    Returns
    -------
    Measurements

    Raises
    ------
    MeasurementFileError
        Missing header or columns, a row with too few fields, a cell that is not a number,
        no data rows. (``OSError`` if the file cannot be read.)
    """
    header, rows = read_table(path, error=MeasurementFileError)
    need = Q_COLUMNS + (TIP_COLUMNS if require_tips else ())
    missing = [c for c in need if c not in header]
    if missing:
        raise MeasurementFileError(f"{path}: missing column(s) {missing}; the header has "
                                   f"{header}, expected {list(need)} (units in the names: m)")
    has_tips = all(c in header for c in TIP_COLUMNS)
    has_axes = all(c in header for c in AXIS_COLUMNS)
    partial = [c for c in AXIS_COLUMNS if c in header]
    if partial and not has_axes:
        raise MeasurementFileError(f"{path}: axis columns must be all of {list(AXIS_COLUMNS)}, "
                                   f"got only {partial}")
    if not rows:
        raise MeasurementFileError(f"{path}: no data rows after the header")
    cols = list(Q_COLUMNS) + (list(TIP_COLUMNS) if has_tips else []) + (
        list(AXIS_COLUMNS) if has_axes else [])
    idx = [header.index(c) for c in cols]
    data = np.empty((len(rows), len(cols)))
    for r, (ln, rec) in enumerate(rows):
        if len(rec) < len(header):  # (a row may carry trailing extra cells)
            raise MeasurementFileError(f"{path}: line {ln}: expected {len(header)} fields "
                                       f"({', '.join(header)}), got {len(rec)}")
        for k, (c, i) in enumerate(zip(cols, idx, strict=True)):
            data[r, k] = _cell(rec[i], path, ln, c)
    mode = None
    if "mode" in header:
        i = header.index("mode")
        vals = []
        for ln, rec in rows:
            t = rec[i].strip()
            if t not in ("1", "+1", "-1"):
                raise MeasurementFileError(f"{path}: line {ln}, column 'mode': expected +1 or "
                                           f"-1 (assembly mode), got {rec[i]!r}")
            vals.append(int(t))
        mode = np.array(vals, dtype=np.int64)
    return Measurements(q=data[:, 0:3], tips=data[:, 3:6] if has_tips else None,
                        axes=data[:, 6:9] if has_axes else None,
                        lines=np.array([ln for ln, _ in rows], dtype=np.int64), mode=mode)


def _fmt_rows(a: FloatArray) -> list[str]:
    return [",".join(repr(float(x)) for x in row) for row in a]


def _comment(comment: object) -> str:
    """A comment for ``#`` lines: text (newlines allowed; other control characters not)."""
    from .._validation import check_text

    return check_text(comment, "comment", allow_empty=True, allow_newlines=True,
                      max_length=100_000)


def measurements_csv_text(q: FloatArray, tips: FloatArray,
                          axes: FloatArray | None = None, *, frame: str = "base",
                          comment: str = "") -> str:
    """CSV text of a measurement set that :func:`read_measurements_csv` reads back.

    Parameters
    ----------
    q : ndarray, shape (n, 3)
        Actuator readings, m.
    tips : ndarray, shape (n, 3)
        Measured tool tips in ``frame``, m.
    axes : ndarray, shape (n, 3), optional
        Measured instrument axes (unit vectors, ``O_s`` towards the RCM).
    frame : {"base", "tracker"}, keyword-only
        Frame of ``tips`` and ``axes``, written in the header.
    comment : str, keyword-only
        Written as ``#`` lines after the header.

    Returns
    -------
    str
        Columns ``q1_m, q2_m, q3_m, x_m, y_m, z_m`` (and ``dx, dy, dz`` with ``axes``).
    """
    cols = Q_COLUMNS + TIP_COLUMNS + (AXIS_COLUMNS if axes is not None else ())
    check_choice(frame, "frame", ("base", "tracker"))
    parts = [check_array(q, "q", (3,), allow_nonfinite=True)]
    n = parts[0].shape[0] if parts[0].ndim == 2 else -1
    for name, a in (("tips", tips), ("axes", axes)):
        if a is not None:
            parts.append(check_array(a, name, (3,), allow_nonfinite=True))
    if n < 0 or any(p.shape != (n, 3) for p in parts):
        raise InvalidInputError(f"q, tips, axes: expected arrays of shape (n, 3) with one n, "
                                f"got {[p.shape for p in parts]}")
    lines = [f"# athenakin calibration measurements; tips in the {frame} frame",
             "# q1_m,q2_m,q3_m: actuator readings (m); x_m,y_m,z_m: measured tool tip (m)"]
    if axes is not None:
        lines.append("# dx,dy,dz: measured instrument axis (unit vector, O_s towards the RCM)")
    lines += [f"# {c}" for c in _comment(comment).splitlines() if c]
    lines.append(",".join(cols))
    lines += _fmt_rows(np.concatenate(parts, axis=1))
    return "\n".join(lines) + "\n"


def plan_csv_text(q: FloatArray, *, comment: str = "") -> str:
    """CSV text of a measurement plan: ``pose, q1_m, q2_m, q3_m`` (readings to command).

    Parameters
    ----------
    q : ndarray, shape (n, 3)
        Actuator values to command, m.
    comment : str, keyword-only
        Written as ``#`` lines after the header.

    Returns
    -------
    str
    """
    lines = ["# athenakin calibration plan: command these actuator values (m), measure the "
             "tool tip at each", *[f"# {c}" for c in _comment(comment).splitlines() if c],
             "pose," + ",".join(Q_COLUMNS)]
    qa = check_array(q, "q", (3,), allow_nonfinite=True)
    if qa.ndim != 2:
        raise InvalidInputError(f"q: expected shape (n, 3), got {qa.shape}")
    lines += [f"{i}," + r for i, r in enumerate(_fmt_rows(qa))]
    return "\n".join(lines) + "\n"


def calibration_toml(result: CalibrationResult) -> str:
    """TOML text of a calibration: the calibrated design and a ``[calibration]`` table.

    The ``[design]`` table is read back by :meth:`Design.from_toml`; ``[calibration]``
    holds the offsets, RCM, registration, noise, residuals and standard deviations.

    Parameters
    ----------
    result : CalibrationResult

    Returns
    -------
    str
        TOML text (lengths in m, angles in rad).
    """
    check_instance(result, "result", CalibrationResult)
    import tomli_w

    cal: dict[str, object] = {
        "frame": result.frame,
        "estimated": list(result.names),
        "q_offset": [float(v) for v in result.q_offset],
        "rcm": [float(v) for v in result.rcm],
        "sigma": float(result.sigma),
        "rms_before": float(result.rms_before),
        "rms_after": float(result.rms_after),
        "rows": int(result.excluded.size),
        "rows_excluded": int(np.sum(result.excluded)),
        "rows_outliers": int(np.sum(result.outliers)),
        "condition": float(result.identifiability.condition),
    }
    if result.T_t_b is not None:
        cal["T_t_b"] = [[float(v) for v in row] for row in result.T_t_b]
    cal["std"] = {n: float(v) for n, v in zip(result.names, result.std, strict=True)}
    return (result.design.to_toml() + "\n# athenakin calibrate: q_true = q_reading + q_offset "
            "(m); std = 1 sigma\n" + tomli_w.dumps({"calibration": cal}))
