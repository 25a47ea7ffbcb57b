"""Options and printing shared by the subcommands (private)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from .._serialize import json_text, to_jsonable  # noqa: F401  (re-exported)
from .._transforms import rot_x, rot_y, rot_z, transform_from_rotation_translation
from .._typing import FloatArray
from ..design import Design
from ..errors import InvalidInputError
from ..robot import default_rcm_frame
from ..robot._setup import check_rcm_position, read_rcm_file, read_rcm_json  # noqa: F401


def add_design_option(p: argparse.ArgumentParser) -> None:
    """``--design FILE`` (TOML)."""
    p.add_argument("--design", metavar="FILE", type=Path,
                   help="design TOML file (default: the reference design, Design.default())")


def add_setup_options(p: argparse.ArgumentParser) -> None:
    """``--rcm X Y Z ROLL PITCH YAW`` or ``--rcm-file FILE`` for the RCM frame."""
    g = p.add_mutually_exclusive_group()
    g.add_argument("--rcm", nargs=6, type=float, metavar=("X", "Y", "Z", "ROLL", "PITCH", "YAW"),
                   help="RCM frame E in the base frame: position (m) and fixed-axis x-y-z "
                        "angles (deg), R = Rz(yaw) Ry(pitch) Rx(roll) "
                        "(default: the reference set-up, default_rcm_frame)")
    g.add_argument("--rcm-file", "--rcm-frame", metavar="FILE", type=Path, dest="rcm_file",
                   help='JSON file {"T_b_e": 4x4 nested list} (ecosystem layout [[R, t], [0, 1]]), '
                        'or a set-up file setup.toml of `athenakin setup plan`')


def add_robot_options(p: argparse.ArgumentParser) -> None:
    """The robot a command works on: ``--design FILE`` and the RCM frame's options.

    See :func:`add_design_option`, :func:`add_setup_options`; :func:`load_robot` reads them.
    """
    add_design_option(p)
    add_setup_options(p)


def add_json_option(p: argparse.ArgumentParser) -> None:
    """``--json``."""
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")


def load_design(args: argparse.Namespace) -> Design:
    """The design named by ``--design`` or the default."""
    if not getattr(args, "design", None):
        return Design.default()
    return Design.from_toml(args.design)   # deep nesting: a named error of the one TOML reader


def load_rcm(args: argparse.Namespace, design: Design) -> FloatArray:
    """The RCM frame from ``--rcm`` / ``--rcm-file`` or the reference set-up."""
    if getattr(args, "rcm", None):
        check_finite(args.rcm, "--rcm")
        x, y, z, r, p, w = args.rcm
        R = rot_z(np.radians(w)) @ rot_y(np.radians(p)) @ rot_x(np.radians(r))
        return check_rcm_position(transform_from_rotation_translation(R, np.array([x, y, z])),
                                  "--rcm")
    if getattr(args, "rcm_file", None):
        return read_rcm_file(args.rcm_file)
    return default_rcm_frame(design)


def load_robot(args: argparse.Namespace) -> tuple[Design, FloatArray]:
    """The design and the RCM frame ``T_b_e`` (4, 4) of :func:`add_robot_options`."""
    design = load_design(args)
    return design, load_rcm(args, design)


#: Resolution bounds of raster figures (dots per inch): a 10 x 8 inch figure at the
#: upper bound is 6000 x 4800 pixels, about 115 MB in memory.
DPI_RANGE = (10, 600)


def check_dpi(dpi: int, option: str = "--dpi") -> int:
    """``dpi`` within :data:`DPI_RANGE`, else ``ValueError``."""
    lo, hi = DPI_RANGE
    if not lo <= dpi <= hi:
        raise ValueError(f"{option}: expected a resolution from {lo} to {hi} dots per inch, "
                         f"got {dpi}")
    return dpi


def check_count(value: int, option: str, lo: int, hi: int, what: str = "") -> int:
    """An integer option within ``[lo, hi]`` (a resource limit checked up front)."""
    if not lo <= value <= hi:
        raise ValueError(f"{option}: expected {lo} to {hi}{' ' + what if what else ''}, "
                         f"got {value}")
    return value


def force_limits(args: argparse.Namespace) -> float | tuple[float, ...] | None:
    """``--f-max``: one force limit (N) for the three actuators or one each, None when absent.

    The count is checked here (1 or 3, a named error); the values by the library.
    """
    f_max = getattr(args, "f_max", None)
    if f_max is None:
        return None
    if len(f_max) not in (1, 3):
        raise InvalidInputError(f"--f-max: expected 1 or 3 force limits (N), got {len(f_max)}")
    return f_max[0] if len(f_max) == 1 else tuple(f_max)


def check_finite(values: Any, option: str, *, positive: bool = False) -> None:
    """Every number of an option finite (and positive), else ``ValueError``."""
    a = np.atleast_1d(np.asarray(values, dtype=float))
    if not np.all(np.isfinite(a)) or (positive and not np.all(a > 0)):
        kind = "finite positive" if positive else "finite"
        shown = a.tolist() if a.size > 1 else float(a[0])
        raise ValueError(f"{option}: expected {kind} numbers, got {shown}")


def table(headers: list[str], rows: list[list[Any]]) -> str:
    """Plain-text table with right-aligned columns."""
    cells = [[str(h) for h in headers]] + [[str(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(headers))]
    lines = ["  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def fmt(x: float, nd: int = 6) -> str:
    """Fixed-point number (scientific beyond 1e9 in magnitude), or '-' for NaN or inf."""
    if not np.isfinite(x):
        return "-"
    if abs(x) >= 1e9:
        return f"{x:.{nd}e}"
    text = f"{x:.{nd}f}"
    return text[1:] if text.startswith("-") and float(text) == 0 else text


def dump_json(obj: Any) -> str:
    """JSON text of ``obj``, indented (see :func:`athenakin._serialize.to_jsonable`)."""
    return json_text(obj, indent=2)


def mm_hint(values: Any, design: Design, what: str) -> str:
    """The millimetre hint of ``plan`` and :class:`~athenakin.Design`, or "".

    ``"; {what} = ... m is far beyond the robot's reach: lengths are in metres
    (millimetres typed?)"`` when the largest finite magnitude of ``values`` (m) exceeds
    four times the robot's longest length (its links or tool), the bound of
    ``athenakin plan``.
    """
    a = np.abs(np.asarray(values, dtype=float))
    a = a[np.isfinite(a)]
    if a.size == 0:
        return ""
    r = float(a.max())
    if r > 4.0 * max(design.tool_length, float(np.max(design.lengths))):
        return (f"; {what} = {r:.6g} m is far beyond the robot's reach: lengths are in "
                f"metres (millimetres typed?)")
    return ""


def with_hint(exc: BaseException, hint: str) -> BaseException:
    """``exc`` with ``hint`` appended to its message (its class and fields kept)."""
    if hint and exc.args and isinstance(exc.args[0], str):
        exc.args = (exc.args[0] + hint, *exc.args[1:])
    return exc
