"""``athenakin calibrate``: measurement CSV -> calibrated design TOML + report; or a pose plan."""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
import warnings
from pathlib import Path

from ._common import add_robot_options, check_count, check_finite, load_robot, table
from ._output import Outputs, add_force_option, outputs


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``calibrate`` subcommand."""
    p = sub.add_parser(
        "calibrate", help="identify the robot's geometry from measured tool tips",
        description="Calibrate: read measurements (CSV columns q1_m,q2_m,q3_m: actuator "
                    "readings; x_m,y_m,z_m: measured tool tip; optional dx,dy,dz: instrument "
                    "axis; all in m), estimate the parameters with their uncertainty, write "
                    "the calibrated design TOML (-o) and a Markdown report with figures. "
                    "With --plan N: write the N poses to measure (D-optimal) to -o instead. "
                    "Columns, units and the model: docs/calibration.md.")
    p.add_argument("measurements", nargs="?", type=Path, metavar="MEASUREMENTS.csv",
                   help="measurement file (not with --plan)")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="OUT",
                   help="calibrated design .toml (or, with --plan, the poses .csv)")
    p.add_argument("--plan", type=int, metavar="N", help="plan N poses to measure")
    p.add_argument("--params", nargs="+", metavar="NAME", default=None,
                   help="parameters to estimate: l1..l5 tool_length q1_offset q2_offset "
                        "q3_offset rcm_x rcm_y rcm_z, or groups lengths offsets rcm default "
                        "(default: l1..l5 tool_length); give MEASUREMENTS.csv before it")
    p.add_argument("--frame", choices=("base", "tracker"), default="base",
                   help="frame of the measured tips: base (registered tracker, default) or "
                        "tracker (registration estimated too)")
    p.add_argument("--mode", choices=("1", "-1", "auto"), default="1",
                   help="assembly mode of the robot: 1 (default), -1, or auto (per row, the "
                        "mode whose nominal tip is nearer the measured one; base frame); a "
                        "'mode' column in the file overrides it per row")
    p.add_argument("--loss", choices=("linear", "soft_l1", "huber", "cauchy", "arctan"),
                   default=None, help="robust loss against outliers (default linear, or the "
                                      "loss of --options)")
    p.add_argument("--options", type=Path, default=None, metavar="FILE.toml",
                   help="solver settings: the [calibration_options] table of a TOML file "
                        "(athenakin.calibration.CalibrationOptions: loss, sigma, "
                        "outlier_threshold, bad_rows, max_bad_fraction, tol, ...); --loss "
                        "overrides its loss")
    p.add_argument("--encoder-resolution", type=float, default=0.0, metavar="M",
                   help="encoder quantum (m) for the tip-error map of the report")
    p.add_argument("--report", type=Path, metavar="REPORT",
                   help="report file, .md or .html (default: OUT with _report.md)")
    p.add_argument("--no-report", action="store_true", help="write no report")
    p.add_argument("--candidates", type=int, default=2000,
                   help="--plan: random candidate poses (default 2000)")
    p.add_argument("--seed", type=int, default=0, help="--plan: random seed (default 0)")
    add_force_option(p)
    add_robot_options(p)
    p.set_defaults(func=run)


#: Most poses ``--plan`` chooses and random candidates it chooses them from.
MAX_PLAN = 10_000
MAX_CANDIDATES = 1_000_000


def run(args: argparse.Namespace) -> int:
    """Execute ``calibrate``."""
    if args.plan is not None:
        check_count(args.plan, "--plan", 1, MAX_PLAN, "poses")
    check_count(args.candidates, "--candidates", 1, MAX_CANDIDATES, "candidate poses")
    check_count(args.seed, "--seed", 0, 2**63 - 1, "(a seed)")
    check_finite(args.encoder_resolution, "--encoder-resolution")
    if not 0 <= args.encoder_resolution <= 1e-2:
        raise ValueError(f"--encoder-resolution: expected 0 to 0.01 m, got "
                         f"{args.encoder_resolution:g}")
    out = Path(args.output)
    with outputs(args) as outs:
        outs.add(out)
        return _run(args, out, outs)


#: Figures the report writes next to it, ``<report stem>_<name>.png``.
REPORT_FIGURES = ("residuals", "parameters", "tip_error")


def _report_path(args: argparse.Namespace, out: Path, outs: Outputs) -> Path | None:
    """Declare the report and its figures as outputs (checked before any work)."""
    if args.no_report or args.plan is not None:
        return None
    rep = Path(args.report or out.with_name(out.stem + "_report.md"))
    outs.add(rep, option="--report")
    for name in REPORT_FIGURES:
        outs.add(Path(f"{rep.with_suffix('')}_{name}.png"), option="--report")
    return rep


def _run(args: argparse.Namespace, out: Path, outs: Outputs) -> int:
    from .. import calibration as cal

    rep = _report_path(args, out, outs)
    design, T = load_robot(args)
    if args.plan is not None:
        if args.measurements is not None:
            raise ValueError("--plan: give no measurement file (it writes the poses to -o)")
        plan = cal.plan_poses(args.plan, T, design, params=args.params, frame=args.frame,
                              n_candidates=args.candidates,
                              mode=-1 if args.mode == "-1" else 1, rng=args.seed)
        outs.write(out, cal.plan_csv_text(plan.q, comment=(
            f"D-optimal for {' '.join(plan.names)}; frame {args.frame}; "
            f"log det = {plan.logdet:.4f}; condition {plan.identifiability.condition:.4g}")))
        outs.commit()
        print(plan.identifiability.summary())
        print(f"wrote {len(plan.q)} poses to {out}")
        return 0
    if args.measurements is None:
        raise ValueError("expected a measurement file (or --plan N)")
    opts = (cal.CalibrationOptions() if args.options is None
            else cal.CalibrationOptions.from_toml(args.options))
    if args.loss is not None:
        opts = dataclasses.replace(opts, loss=args.loss)
    data = cal.read_measurements_csv(args.measurements)
    assert data.tips is not None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", cal.CalibrationWarning)
        res = cal.calibrate(data.q, data.tips, T, design, params=args.params, frame=args.frame,
                            axes=data.axes,
                            mode=_mode(args.mode) if data.mode is None else data.mode,
                            options=opts)
    for w in caught:
        print(f"warning: {w.message}")
    rows = [[n, f"{a:.9g}", f"{b:.9g}", f"{(b - a) * 1e6:+.2f}", f"{s * 1e6:.2f}"]
            for n, a, b, s in res.table()]
    print(table(["parameter", "nominal", "estimate", "change (um|urad)", "std (um|urad)"], rows))
    print(f"RMS tip residual: {res.rms_before * 1e6:.2f} um before, "
          f"{res.rms_after * 1e6:.2f} um after (sigma {res.sigma * 1e6:.2f} um)")
    outs.write(out, cal.calibration_toml(res))
    if rep is not None:   # rendered aside, then committed with the TOML: all or nothing
        with tempfile.TemporaryDirectory() as tmp:
            for f in cal.write_report(res, Path(tmp) / rep.name,
                                      encoder_resolution=args.encoder_resolution):
                outs.write(rep.parent / f.name, f.read_bytes())
    files = outs.commit()
    print("wrote " + ", ".join(str(f) for f in files))
    return 0


def _mode(text: str) -> int | str:
    return text if text == "auto" else int(text)
