"""Options and printing shared by the subcommands (private)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._serialize import json_text, to_jsonable  # noqa: F401  (re-exported)
from .._transforms import rot_x, rot_y, rot_z, transform_from_rotation_translation
from ..design import Design
from ..robot import default_rcm_frame


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
    g.add_argument("--rcm-file", metavar="FILE", type=Path,
                   help='JSON file {"T_b_e": 4x4 nested list} (ecosystem layout [[R, t], [0, 1]])')


def add_json_option(p: argparse.ArgumentParser) -> None:
    """``--json``."""
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")


def load_design(args: argparse.Namespace) -> Design:
    """The design named by ``--design`` or the default."""
    return Design.from_toml(args.design) if getattr(args, "design", None) else Design.default()


def load_rcm(args: argparse.Namespace, design: Design) -> NDArray[np.float64]:
    """The RCM frame from ``--rcm`` / ``--rcm-file`` or the reference set-up."""
    if getattr(args, "rcm", None):
        x, y, z, r, p, w = args.rcm
        R = rot_z(np.radians(w)) @ rot_y(np.radians(p)) @ rot_x(np.radians(r))
        return transform_from_rotation_translation(R, np.array([x, y, z]))
    if getattr(args, "rcm_file", None):
        data = json.loads(Path(args.rcm_file).read_text())
        if not isinstance(data, dict) or "T_b_e" not in data:
            raise ValueError(f"{args.rcm_file}: expected a JSON object with key 'T_b_e'")
        return np.asarray(data["T_b_e"], dtype=float)
    return default_rcm_frame(design)


def table(headers: list[str], rows: list[list[Any]]) -> str:
    """Plain-text table with right-aligned columns."""
    cells = [[str(h) for h in headers]] + [[str(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(headers))]
    lines = ["  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def fmt(x: float, nd: int = 6) -> str:
    """Fixed-point number, or '-' for NaN."""
    if not np.isfinite(x):
        return "-"
    text = f"{x:.{nd}f}"
    return text[1:] if text.startswith("-") and float(text) == 0 else text


def dump_json(obj: Any) -> str:
    """JSON text of ``obj``, indented (see :func:`athenakin._serialize.to_jsonable`)."""
    return json_text(obj, indent=2)
