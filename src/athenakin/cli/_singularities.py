"""``athenakin singularities``: the singularity conditions at q, the loci of a design, figures."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from ._common import (
    add_json_option,
    add_robot_options,
    check_count,
    check_dpi,
    check_finite,
    dump_json,
    fmt,
    load_design,
    load_rcm,
    table,
)
from ._output import Outputs, outputs
from ._workspace import add_output_options, declare_outputs, save_figure

#: Most samples per axis of the (h, q3) map (it holds resolution^2 points).
MAX_MAP_RESOLUTION = 2001


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``singularities`` subcommand."""
    p = sub.add_parser(
        "singularities", help="singularity conditions at q, singular loci of the design",
        description="Without Q: which singular sets the design's stroke limits reach, and the "
                    "loci in actuator space (figure + npz). With Q1 Q2 Q3 (m): the value of "
                    "every singularity condition at that configuration and which are near.")
    p.add_argument("q", nargs="*", type=float, metavar="Q",
                   help="actuators q1 q2 q3, m (optional)")
    p.add_argument("--mode", type=int, choices=(1, -1), default=1, help="assembly mode (+1/-1)")
    p.add_argument("--tol", type=float, default=None,
                   help="tolerance of 'near' for every condition (default 1e-6)")
    p.add_argument("--parallel-only", action="store_true",
                   help="evaluate only the parallel module's conditions (no RCM frame)")
    p.add_argument("--resolution", type=int, default=241,
                   help="samples per axis of the (h, q3) map (default 241)")
    add_output_options(p, "athenakin-singularities")
    add_robot_options(p)
    add_json_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Execute ``singularities``."""
    if len(args.q) not in (0, 3):
        raise ValueError(f"q: expected 3 values q1 q2 q3 (m) or none, got {len(args.q)}")
    if args.q:
        check_finite(args.q, "q")
    if args.tol is not None:
        check_finite(args.tol, "--tol", positive=True)
    check_count(args.resolution, "--resolution", 2, MAX_MAP_RESOLUTION, "samples per axis")
    check_dpi(args.dpi)
    with outputs(args, option="--out") as outs:
        declare_outputs(args, outs, ["actuator_map"], ["singularities"])
        return _run(args, outs)


def _run(args: argparse.Namespace, outs: Outputs) -> int:
    from ..analysis import actuator_map, save_npz, singular_sets_within_strokes, singularities

    design = load_design(args)
    out: dict[str, object] = {}
    if args.q:
        T = None if args.parallel_only else load_rcm(args, design)
        rep = singularities(np.array(args.q), T, design, mode=args.mode, tol=args.tol)
        out["configuration"] = {
            "q_m": args.q, "mode": args.mode, "assembled": bool(rep.assembled),
            "conditions": {k: {"kind": c.kind, "value": float(c.value), "unit": c.unit,
                               "near": bool(c.near), "tol": c.tol, "test": c.test}
                           for k, c in rep.conditions.items()},
            "measures": {k: float(v) for k, v in rep.measures.items()}}
    sets = singular_sets_within_strokes(design)
    out["design"] = {k: v for k, v in sets.items()}
    files: list[str] = []
    if not args.no_files:
        outdir = Path(args.out)
        am = actuator_map(design, resolution=args.resolution)
        save_npz(outs.temp(outdir / "actuator_map.npz"), am, design=design)
        if not args.no_figures:
            from ..analysis.figures import figure_singularities

            save_figure(figure_singularities(design, am=am), outdir / "singularities",
                        args.format, args.dpi, outs)
        files = [str(f) for f in outs.commit()]
    out["files"] = files
    if args.json:
        print(dump_json(out))
        return 0
    if args.q:
        cfg = out["configuration"]
        assert isinstance(cfg, dict)
        print(f"singularity conditions at q = {args.q} m, mode {args.mode:+d}"
              f"{'' if cfg['assembled'] else ' (NOT assembled)'}:")
        rows = [[k, c.kind, fmt(float(c.value), 9), c.unit, "NEAR" if bool(c.near) else "-"]
                for k, c in rep.conditions.items()]
        print(table(["condition", "kind", "value", "unit", "near"], rows))
        print(table(["measure", "value"],
                    [[k, "-" if np.isnan(float(v)) else f"{float(v):.6g}"]
                     for k, v in rep.measures.items()]))
        print()
    print("singular sets within the stroke limits of the design:")
    rows = [[k, "yes" if v["reachable"] else "no", str(v["detail"])]
            for k, v in sets.items() if "reachable" in v]
    print(table(["set", "reachable", "detail"], rows))
    safe: Any = sets["mode_safe_q3"]["value"]
    lo, hi = float(safe[0]), float(safe[1])
    print(f"q3 strictly inside ({lo:.4f}, {hi:.4f}) m keeps both circles intersecting for every "
          f"allowed h: no assembly-mode change possible")
    for f in files:
        print(f"wrote {f}")
    return 0
