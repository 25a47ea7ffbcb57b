"""Files of the motion subpackage: path CSV in, trajectory CSV / JSON out, q streams in and out.

Column names carry their unit (``_m`` metres, ``_s`` seconds, ``_deg`` degrees,
``_m_s`` m/s, ``_m_s2`` m/s^2, ``_m_s3`` m/s^3); the full reference is in
docs/motion.md. Lines starting with ``#`` and blank lines are ignored. Readers
raise :class:`PathFileError` naming the file, line and column; writers write to
a temporary file and rename it, so that a failed run leaves nothing behind.
"""

from __future__ import annotations

import dataclasses
import io
import math
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from .._csv import Q_COLUMNS, TIP_COLUMNS, read_table
from .._output import write_text_atomic
from .._serialize import json_text
from .._typing import FloatArray
from .._validation import check_instance, check_path
from ._errors import PathFileError
from ._plan import Trajectory
from ._tracker import TrackFlag, TrackLog

__all__ = [
    "PathSpec",
    "TIP_COLUMNS",
    "DIRECTION_COLUMNS",
    "Q_COLUMNS",
    "read_path_csv",
    "read_q_stream_csv",
    "trajectory_columns",
    "trajectory_csv_text",
    "trajectory_json_text",
    "track_csv_text",
    "write_text_atomic",
    "save_trajectory",
]

#: Columns of a direction + insertion path file; ``t_s`` is optional.
DIRECTION_COLUMNS = ("azimuth_deg", "polar_deg", "depth_m")


@dataclasses.dataclass(frozen=True)
class PathSpec:
    """A path read from a CSV file.

    Attributes
    ----------
    kind : {"tip", "direction"}
    tips_e : ndarray, shape (K, 3) or None
        Tool-tip waypoints (frame E, m) for ``kind == "tip"``.
    azimuth, polar, depth : ndarray, shape (K,) or None
        Radians, radians, metres for ``kind == "direction"``.
    times : ndarray, shape (K,) or None
        Arrival times, s, when the file has a ``t_s`` column.
    """

    kind: str
    tips_e: FloatArray | None = None
    azimuth: FloatArray | None = None
    polar: FloatArray | None = None
    depth: FloatArray | None = None
    times: FloatArray | None = None


def _read_table(path: str | Path, *, header_row: bool = True
                ) -> tuple[list[str], list[tuple[int, list[str]]]]:
    """Header and ``(line number, cells)`` rows through the package's one CSV reader."""
    return read_table(path, header_row=header_row, error=PathFileError)


def _numbers(path: str | Path, header: list[str], rows: list[tuple[int, list[str]]],
             columns: list[str], *, allow_nonfinite: bool = False) -> FloatArray:
    idx = [header.index(c) for c in columns]
    out = np.empty((len(rows), len(columns)))
    for r, (lineno, cells) in enumerate(rows):
        if len(cells) != len(header):
            raise PathFileError(f"{path}, line {lineno}: expected {len(header)} values "
                                f"({', '.join(header)}), got {len(cells)}")
        for j, (i, name) in enumerate(zip(idx, columns, strict=True)):
            try:
                v = float(cells[i])
            except ValueError:
                raise PathFileError(f"{path}, line {lineno}, column {name!r}: expected a "
                                    f"number, got {cells[i]!r}") from None
            if not allow_nonfinite and not math.isfinite(v):
                raise PathFileError(f"{path}, line {lineno}, column {name!r}: expected a "
                                    f"finite number, got {cells[i]!r}")
            out[r, j] = v
    return out


def read_path_csv(path: str | Path) -> PathSpec:
    """Read a path file: tool-tip or direction + insertion waypoints, optional times.

    Parameters
    ----------
    path : str or Path
        CSV with a header row. Either ``x_m, y_m, z_m`` (tool tip in the RCM frame,
        m) or ``azimuth_deg, polar_deg, depth_m`` (instrument direction about ``z_e``,
        degrees, and depth of the tip beyond the RCM, m), plus optionally ``t_s``
        (arrival time of each waypoint, s). Column order is free; no other column
        is allowed.

    Returns
    -------
    PathSpec

    Raises
    ------
    PathFileError
        Missing or unknown columns, a non-number, fewer than 2 waypoints (with the
        file, line and column).
    OSError
        The file cannot be opened.
    """
    header, rows = _read_table(path)
    cols = set(header)
    allowed_tip = set(TIP_COLUMNS) | {"t_s"}
    allowed_dir = set(DIRECTION_COLUMNS) | {"t_s"}
    if cols & set(TIP_COLUMNS):
        kind, need, allowed = "tip", TIP_COLUMNS, allowed_tip
    elif cols & set(DIRECTION_COLUMNS):
        kind, need, allowed = "direction", DIRECTION_COLUMNS, allowed_dir
    else:
        raise PathFileError(
            f"{path}: expected the columns {', '.join(TIP_COLUMNS)} (tool tip in frame E) or "
            f"{', '.join(DIRECTION_COLUMNS)} (direction + insertion), optionally t_s; got "
            f"{', '.join(header)}")
    missing = [c for c in need if c not in cols]
    unknown = [c for c in header if c not in allowed]
    if missing or unknown:
        raise PathFileError(f"{path}: a {kind} path needs the columns {', '.join(need)} "
                            f"(optionally t_s); missing {missing}, unknown {unknown}")
    if len(rows) < 2:
        raise PathFileError(f"{path}: expected at least 2 waypoints, got {len(rows)}")
    data = _numbers(path, header, rows, list(need))
    times = _numbers(path, header, rows, ["t_s"])[:, 0] if "t_s" in cols else None
    if times is not None and np.any(np.diff(times) < 0):
        k = int(np.flatnonzero(np.diff(times) < 0)[0])
        raise PathFileError(f"{path}, line {rows[k + 1][0]}, column 't_s': times must not "
                            f"decrease ({times[k]} then {times[k + 1]})")
    if kind == "tip":
        return PathSpec("tip", tips_e=data, times=times)
    if np.any(data[:, 2] <= 0):
        k = int(np.flatnonzero(data[:, 2] <= 0)[0])
        raise PathFileError(f"{path}, line {rows[k][0]}, column 'depth_m': expected a "
                            f"positive depth beyond the RCM, got {data[k, 2]}")
    return PathSpec("direction", azimuth=np.radians(data[:, 0]), polar=np.radians(data[:, 1]),
                    depth=data[:, 2], times=times)


def read_q_stream_csv(path: str | Path) -> tuple[FloatArray, FloatArray | None]:
    """Read recorded actuator readings.

    Parameters
    ----------
    path : str or Path
        CSV with columns ``q1_m, q2_m, q3_m`` (m) and optionally ``t_s``; other
        columns are ignored, so a trajectory file written by ``athenakin plan``
        replays as it is. Empty cells or ``nan`` mark missing readings (the tracker
        flags them ``LOST``). A file without a header row holds three numbers
        per line, q1 q2 q3 in m, separated by commas or whitespace.

    Returns
    -------
    q : ndarray, shape (N, 3)
    t : ndarray, shape (N,) or None

    Raises
    ------
    PathFileError
        Missing columns, a non-number, no data rows.
    """
    header, rows = _read_table(path)
    if not set(Q_COLUMNS) & set(header) and _all_numbers(header):
        _, rows = _read_table(path, header_row=False)
        width = {len(cells) for _, cells in rows}
        if width != {3}:
            bad = next((n, c) for n, c in rows if len(c) != 3)
            raise PathFileError(f"{path}, line {bad[0]}: expected 3 values per row "
                                f"(q1 q2 q3, m), got {len(bad[1])}")
        header = list(Q_COLUMNS)
    missing = [c for c in Q_COLUMNS if c not in header]
    if missing:
        raise PathFileError(f"{path}: a q stream needs the columns {', '.join(Q_COLUMNS)} "
                            f"(optionally t_s); missing {missing}, got {', '.join(header)}")
    if not rows:
        raise PathFileError(f"{path}: no readings (expected at least one data row)")
    rows = [(n, [c if c != "" else "nan" for c in cells]) for n, cells in rows]
    q = _numbers(path, header, rows, list(Q_COLUMNS), allow_nonfinite=True)
    if not np.all(np.isfinite(q[0])):
        raise PathFileError(f"{path}, line {rows[0][0]}: the first reading must be complete "
                            f"(it sets the initial configuration)")
    t = (_numbers(path, header, rows, ["t_s"], allow_nonfinite=True)[:, 0]
         if "t_s" in header else None)
    return q, t


def _all_numbers(cells: list[str]) -> bool:
    try:
        [float(p) for c in cells for p in c.replace(",", " ").split()]
    except ValueError:
        return False
    return bool(cells)


# --------------------------------------------------------------------------------------
def trajectory_columns(traj: Trajectory) -> list[str]:
    """Column names of the trajectory CSV.

    Jerk columns only with a jerk limit; :data:`CLEARANCE_COLUMNS` only when
    collisions were checked.
    """
    cols = ["t_s", "q1_m", "q2_m", "q3_m", "qd1_m_s", "qd2_m_s", "qd3_m_s",
            "qdd1_m_s2", "qdd2_m_s2", "qdd3_m_s2"]
    if traj.qddd is not None:
        cols += ["qddd1_m_s3", "qddd2_m_s3", "qddd3_m_s3"]
    cols += ["tip_x_m", "tip_y_m", "tip_z_m"]
    if getattr(traj, "forces", None) is not None:
        cols += ["f1_N", "f2_N", "f3_N"]
    cols += ["segment"]
    return cols + (CLEARANCE_COLUMNS if traj.clearance is not None else [])


def trajectory_csv_text(traj: Trajectory) -> str:
    """The trajectory as CSV text (columns: :func:`trajectory_columns`)."""
    parts = [traj.t[:, None], traj.q, traj.qd, traj.qdd]
    if traj.qddd is not None:
        parts.append(traj.qddd)
    parts += [traj.tip_e]
    if getattr(traj, "forces", None) is not None:
        parts.append(traj.forces)  # type: ignore[arg-type]
    data = np.concatenate(parts, axis=1)
    buf = io.StringIO()
    buf.write(",".join(trajectory_columns(traj)) + "\n")
    extra = _clearance_cells(traj.clearance, traj.closest_pair, len(traj.t))
    for row, seg, ex in zip(data.tolist(), traj.segment.tolist(), extra, strict=True):
        buf.write(",".join(repr(v) for v in row) + f",{seg}{ex}\n")
    return buf.getvalue()


#: Extra columns of the trajectory and track CSV files when collisions are checked.
CLEARANCE_COLUMNS = ["clearance_m", "closest_a", "closest_b"]


def _clearance_cells(clearance: FloatArray | None, pair: NDArray[np.str_] | None,
                     n: int) -> list[str]:
    """``",clearance,a,b"`` per row ("" per row when not checked)."""
    if clearance is None or pair is None:
        return [""] * n
    return [f",{float(c)!r},{a},{b}" for c, (a, b) in zip(clearance.tolist(), pair.tolist(),
                                                         strict=True)]


def trajectory_json_text(traj: Trajectory) -> str:
    """The trajectory, its limits, margins, set-up and design as JSON text (SI units)."""
    lim = traj.limits
    obj = {
        "units": {"t_s": "s", "q_m": "m", "qd_m_s": "m/s", "qdd_m_s2": "m/s^2",
                  "qddd_m_s3": "m/s^3", "tip_e_m": "m (RCM frame E)",
                  "forces_N": "N (actuators, positive along increasing q; null without "
                              "masses)"},
        "rate_hz": traj.rate,
        "duration_s": traj.duration,
        "design": {f.name: getattr(traj.design, f.name)
                   for f in dataclasses.fields(traj.design)},
        "T_b_e": traj.T_b_e,
        "limits": {"v_max_m_s": lim.v_max, "a_max_m_s2": lim.a_max,
                   "j_max_m_s3": lim.j_max, "tip_speed_m_s": lim.tip_speed},
        "margins": dataclasses.asdict(traj.margins),
        "waypoints_e_m": traj.waypoints_e,
        "waypoint_times_s": traj.waypoint_times,
        "stretched": traj.stretched,
        "t_s": traj.t, "q_m": traj.q, "qd_m_s": traj.qd, "qdd_m_s2": traj.qdd,
        "qddd_m_s3": traj.qddd, "tip_e_m": traj.tip_e, "segment": traj.segment,
        "forces_N": getattr(traj, "forces", None),
        "measures": dataclasses.asdict(traj.measures),
    }
    if traj.clearance is not None:
        obj["clearance_margin_m"] = traj.clearance_margin
        obj["clearance_m"] = traj.clearance
        obj["closest_pair"] = traj.closest_pair
    return json_text(obj)


TRACK_COLUMNS = ["index", "t_s", "q1_m", "q2_m", "q3_m", "valid", "mode", "slot", "p_m",
                 "u1_deg", "u2_deg", "u3_deg", "u4_deg", "u5_deg", "tip_x_m", "tip_y_m",
                 "tip_z_m", "half_chord_m", "sin_u2", "sin_u4", "step", "flags", "flag_names"]


def track_csv_text(log: TrackLog, t: FloatArray | None = None) -> str:
    """A :class:`TrackLog` as CSV text (columns :data:`TRACK_COLUMNS`; tip in frame E).

    When collisions were checked (some clearance is not NaN) the columns
    :data:`CLEARANCE_COLUMNS` follow.
    """
    n = log.q.shape[0]
    tt = np.full(n, np.nan) if t is None else np.asarray(t, float)
    checked = log.clearance is not None
    extra = _clearance_cells(log.clearance, log.closest_pair, n)
    buf = io.StringIO()
    buf.write(",".join(TRACK_COLUMNS + (CLEARANCE_COLUMNS if checked else [])) + "\n")
    u = np.degrees(log.u)
    for i in range(n):
        names = "|".join(str(f.name) for f in TrackFlag if f and f in TrackFlag(int(log.flags[i])))
        vals = [str(i), repr(float(tt[i])), *(repr(float(v)) for v in log.q[i]),
                str(int(log.valid[i])), str(int(log.mode[i])), str(int(log.slot[i])),
                repr(float(log.p[i])), *(repr(float(v)) for v in u[i]),
                *(repr(float(v)) for v in log.tip_e[i]), repr(float(log.half_chord[i])),
                repr(float(log.sin_u2[i])), repr(float(log.sin_u4[i])),
                repr(float(log.step[i])), str(int(log.flags[i])), names]
        buf.write(",".join(vals) + extra[i] + "\n")
    return buf.getvalue()


def save_trajectory(traj: Trajectory, path: str | Path) -> Path:
    """Write a trajectory as CSV or JSON, chosen by the extension of ``path``.

    Parameters
    ----------
    traj : Trajectory
    path : str or Path
        ``*.csv`` (columns :func:`trajectory_columns`) or ``*.json``.

    Returns
    -------
    Path

    Raises
    ------
    ValueError
        Another extension.
    """
    check_instance(traj, "traj", Trajectory)
    path = check_path(path)
    ext = path.suffix.lower()
    if ext not in (".csv", ".json"):
        raise ValueError(f"path: expected a .csv or .json file name, got {str(path)!r}")
    write_text_atomic(path, trajectory_json_text(traj) if ext == ".json"
                      else trajectory_csv_text(traj))
    return path
