"""``athenakin track``: replay a recorded actuator stream through the continuity tracker."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from ._collision import add_collision_options, collision_options
from ._common import (
    add_design_option,
    add_setup_options,
    check_count,
    fmt,
    load_design,
    load_rcm,
)
from ._output import Outputs, add_force_option, outputs

#: Smallest jump threshold (mm or deg): below it, the threshold in SI units underflows.
JUMP_MIN = 1e-6
#: Flags that make ``--strict`` fail (``COLLISION`` only appears with the collision check).
STRICT_FLAGS = ("LOST", "JUMP", "MODE_SWITCH", "AMBIGUOUS", "COLLISION")


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``track`` subcommand."""
    p = sub.add_parser(
        "track", help="replay a recorded q stream (CSV) through the pose tracker",
        description="Read actuator readings (columns q1_m,q2_m,q3_m, optional t_s; other "
                    "columns ignored, so a trajectory from 'athenakin plan' replays as is), "
                    "follow the forward-kinematics solution continuous with the first "
                    "sample, and report every flagged sample (mode or branch switch, jump, "
                    "ambiguity, loss, approach to a singularity). Columns: docs/motion.md.")
    p.add_argument("path", type=Path, metavar="STREAM.csv", help="recorded readings")
    p.add_argument("-o", "--output", type=Path, metavar="OUT",
                   help="write the tracked poses (.csv or .json)")
    p.add_argument("--slot", type=int, default=None,
                   help="FK slot (0-15) of the first reading (default: mode +1, p > 0, "
                        "branches +1)")
    p.add_argument("--jump-mm", type=float, default=5.0,
                   help="jump threshold on O_s between samples, mm (5)")
    p.add_argument("--jump-deg", type=float, default=math.degrees(0.1),
                   help="jump threshold on the passive angles between samples, deg (5.73)")
    p.add_argument("--margin", action="append", default=[], metavar="NAME=VALUE",
                   help="singularity watch margin (half_chord, h, link, p in m; sin_u2, sin_u4)")
    p.add_argument("--strict", action="store_true",
                   help=f"exit with status 1 if any sample is flagged {', '.join(STRICT_FLAGS)}")
    p.add_argument("--max-events", type=int, default=20, help="events listed (20)")
    add_collision_options(p, what="closer samples are flagged NEAR_COLLISION, overlapping "
                                   "ones COLLISION")
    add_force_option(p)
    add_design_option(p)
    add_setup_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Execute ``track``."""
    out = args.output
    for opt, v, hi in (("--jump-mm", args.jump_mm, 1e6), ("--jump-deg", args.jump_deg, 360.0)):
        if not JUMP_MIN <= v <= hi:
            raise ValueError(f"{opt}: expected a threshold from {JUMP_MIN:g} to {hi:g}, got {v:g}")
    check_count(args.max_events, "--max-events", 0, 10**9, "events")
    if out is not None and Path(out).suffix.lower() not in (".csv", ".json"):
        raise ValueError(f"-o: expected a .csv or .json file name, got {str(out)!r}")
    with outputs(args) as outs:   # checked before any work: never over an input or, without
        if out is not None:       # --force, an existing file; written only at the end
            outs.add(out)
        return _track(args, outs)


def _track(args: argparse.Namespace, outs: Outputs) -> int:
    from .._serialize import json_text
    from ..motion import TrackFlag, track
    from ..motion._io import read_q_stream_csv, track_csv_text
    from ._plan import parse_margins

    out = args.output
    design = load_design(args)
    T = load_rcm(args, design)
    q, t = read_q_stream_csv(args.path)
    if t is not None:
        t = np.asarray(t, dtype=float)
        inf = np.flatnonzero(np.isinf(t))
        if inf.size:
            raise ValueError(f"{args.path}: t_s must be finite (or empty), got {t[inf[0]]} at "
                             f"sample {int(inf[0])}")
        seen = np.flatnonzero(np.isfinite(t))       # empty cells (NaN) are missing readings
        dec = np.flatnonzero(np.diff(t[seen]) < 0)
        if dec.size:
            i, j = int(seen[dec[0]]), int(seen[dec[0] + 1])
            raise ValueError(f"{args.path}: t_s must not decrease, got t_s = {t[j]:g} s at "
                             f"sample {j} after {t[i]:g} s at sample {i}")
    coll = collision_options(args, design)
    log = track(q, T, design, slot=args.slot, jump_m=args.jump_mm * 1e-3,
                jump_rad=math.radians(args.jump_deg), margins=parse_margins(args.margin),
                **coll)
    events = log.events()
    counts: dict[str, int] = {}
    for _, f in events:
        for bit in TrackFlag:
            if bit and bit in f:
                counts[str(bit.name)] = counts.get(str(bit.name), 0) + 1
    print(f"tracked {len(q)} samples from slot {int(log.slot[0])} (mode {int(log.mode[0]):+d}); "
          f"{len(events)} flagged")
    for name, c in sorted(counts.items()):
        print(f"  {name}: {c} samples")
    for i, f in events[:args.max_events]:
        ts = "" if t is None else "t missing, " if np.isnan(t[i]) else f"t = {t[i]:.6g} s, "
        print(f"  sample {i} ({ts}q = {np.round(q[i], 6).tolist()} m): {f.name or int(f)}"
              f", mode {int(log.mode[i]):+d}, slot {int(log.slot[i])}")
    if len(events) > args.max_events:
        print(f"  ... {len(events) - args.max_events} more (see -o)")
    if coll and np.any(np.isfinite(log.clearance)):
        i = int(np.nanargmin(log.clearance))
        a, b = log.closest_pair[i]
        print(f"least clearance: {fmt(float(log.clearance[i]))} m between {a} and {b} at "
              f"sample {i}")
    last = len(q) - 1
    print(f"last pose: tip_e = {np.round(log.tip_e[last], 6).tolist()} m, "
          f"p = {fmt(float(log.p[last]))} m, valid = {bool(log.valid[last])}")
    if out is not None:
        if Path(out).suffix.lower() == ".json":
            import dataclasses

            obj = {k: getattr(log, k) for k in (f.name for f in dataclasses.fields(log))}
            obj["t_s"] = t
            obj["flag_bits"] = {b.name: int(b) for b in TrackFlag if b}
            outs.write(out, json_text(obj))
        else:
            outs.write(out, track_csv_text(log, t))
        outs.commit()
        print(f"wrote {out}")
    if args.strict and any(counts.get(n) for n in STRICT_FLAGS):
        bad = ", ".join(n for n in STRICT_FLAGS if counts.get(n))
        print(f"athenakin track: --strict: flagged {bad}")
        return 1
    return 0
