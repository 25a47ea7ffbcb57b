"""``athenakin setup``: the phantom as files, a set-up plan for a patient file, its HTML view."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from ._common import check_count, dump_json, fmt, load_design, table
from ._output import Outputs, add_force_option

_SHOWN = ("coverage", "min_clearance", "margin_min", "cond_tip_max", "depth_min", "depth_max")


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``setup`` subcommand and its ``phantom`` and ``plan`` commands."""
    p = sub.add_parser("setup", help="patient-specific set-up: where the port goes and where "
                                     "the robot stands",
                       description="Plan the port on the skin and the robot's base for a "
                                   "patient (closed surfaces by role, patient.toml).")
    cmds = p.add_subparsers(dest="setup_command", metavar="SETUP_COMMAND")
    cmds.required = True
    ph = cmds.add_parser("phantom", help="write the parametric phantom as STL files and "
                                         "patient.toml",
                         description="Write the shipped phantom (abdominal wall, pancreas, "
                                     "aorta, portal vein, table) as STL files in metres, in "
                                     "the patient's frame, and DIR/patient.toml naming them "
                                     "(with --second-port, its assistant's port too).")
    ph.add_argument("--write", required=True, metavar="DIR", type=Path,
                    help="folder of the files (created if missing)")
    ph.add_argument("--size", type=float, default=1.0, help="scale of the patient (1.0)")
    ph.add_argument("--target-size", type=float, default=1.0,
                    help="scale of the pancreas about its centre (1.0)")
    ph.add_argument("--second-port", action="store_true",
                    help="add an assistant's port and its instrument ([[patient.second_port]])")
    ph.add_argument("--force", action="store_true", help="replace files that exist")
    ph.set_defaults(func=run_phantom)
    pl = cmds.add_parser("plan", help="plan the set-up of a patient (NSGA-II on Dask)",
                         description="Search the port and the robot's base (NSGA-II, Dask) "
                                     "and write the chosen set-up as TOML: T_p_b, T_b_e, the "
                                     "port, the design and the figures. Any command reads it "
                                     "with --rcm-frame setup.toml (and --design setup.toml).")
    pl.add_argument("patient", metavar="PATIENT.toml", type=Path, help="patient file")
    pl.add_argument("-o", "--out", type=Path, default=Path("setup.toml"), metavar="FILE",
                    help="set-up file written (default setup.toml)")
    pl.add_argument("--design", metavar="FILE", type=Path,
                    help="design TOML file (default: the reference design)")
    pl.add_argument("--population", type=int, default=16, help="NSGA-II population (16)")
    pl.add_argument("--generations", type=int, default=8, help="NSGA-II generations (8)")
    pl.add_argument("--polish", type=int, default=3,
                    help="rounds of compass search after NSGA-II, 14 set-ups each (3)")
    pl.add_argument("--seed", type=int, default=0, help="seed of samples and search")
    pl.add_argument("--scheduler", default=None, metavar="ADDRESS",
                    help="Dask scheduler: tcp://host:port, or threads|processes|synchronous "
                         "(default: local threads)")
    pl.add_argument("--options", type=Path, default=None, metavar="FILE.toml",
                    help="the [setup_options] table of a TOML file (SetupOptions)")
    pl.add_argument("--top", type=int, default=5, help="set-ups of the front listed (5)")
    pl.add_argument("--force", action="store_true", help="replace the set-up file")
    pl.add_argument("--json", action="store_true", help="print the figures as JSON")
    pl.set_defaults(func=run_plan)
    vw = cmds.add_parser("view", help="draw a planned set-up as an interactive HTML page",
                         description="Write a self-contained HTML page (plotly) of a set-up "
                                     "in the patient's frame: the skin, the forbidden "
                                     "structures and the table, the target coloured face by "
                                     "face by coverage (every test of the planner, every "
                                     "clearance), the port and the instrument's nominal "
                                     "axis, and the robot at a few covered targets with a "
                                     "menu between them.")
    vw.add_argument("patient", metavar="PATIENT.toml", type=Path, help="patient file")
    vw.add_argument("setup", metavar="SETUP.toml", type=Path,
                    help="set-up file of 'setup plan' (its design is the robot drawn)")
    vw.add_argument("-o", "--output", type=Path, required=True, metavar="FILE.html",
                    help="the page written (.html)")
    vw.add_argument("--targets", type=int, default=3,
                    help="covered targets at which the robot is drawn (3)")
    vw.add_argument("--cdn", action="store_true",
                    help="link plotly.js from its CDN (a small page that needs the network) "
                         "instead of embedding it")
    vw.add_argument("--options", type=Path, default=None, metavar="FILE.toml",
                    help="the [setup_options] table of a TOML file (the tests of coverage)")
    add_force_option(vw)
    vw.set_defaults(func=run_view)


def run_phantom(args: argparse.Namespace) -> int:
    """Write the phantom."""
    from ..synthesis import phantom, write_patient

    path = write_patient(phantom(size=args.size, target_size=args.target_size,
                                 second_port=args.second_port), args.write,
                         overwrite=args.force)
    print(f"wrote {path} and its meshes")
    return 0


def run_plan(args: argparse.Namespace) -> int:
    """Plan a set-up and write it."""
    from ..synthesis import Patient, SetupOptions, plan_setup

    check_count(args.top, "--top", 1, 1000)
    if args.out.exists() and not args.force:
        raise FileExistsError(f"-o: {args.out} exists; pass --force to replace it")
    patient = Patient.from_toml(args.patient)
    design = load_design(args)
    opts = SetupOptions.from_toml(args.options) if args.options else SetupOptions()
    t0 = os.times().elapsed
    plan = plan_setup(patient, design=design, population=args.population,
                      generations=args.generations, polish=args.polish, seed=args.seed,
                      scheduler=args.scheduler,
                      options=opts, progress=not args.json)
    path = plan.write(args.out, patient=str(args.patient))
    if args.json:
        print(dump_json({"setup": str(path), "figures": plan.figures,
                         "T_b_e": plan.chosen.T_b_e, "T_p_b": plan.chosen.T_p_b,
                         "port": plan.chosen.port,
                         "second_ports": [sp.to_table() for sp in patient.second_ports]}))
        return 0
    rows = [[int(r["setup"])] + [fmt(float(r[c]), 4) for c in _SHOWN]
            for _, r in plan.front.head(args.top).iterrows()]
    print(table(["setup", *_SHOWN], rows))
    f = plan.figures
    print(f"chosen set-up on {opts.final_samples} fresh target samples: coverage "
          f"{100 * f['coverage']:.1f} %, least clearance {1000 * f['min_clearance']:.1f} mm, "
          f"least margin {1000 * f['margin_min']:.1f} mm, collisions {int(f['collisions'])}")
    print(f"port (patient frame, m): {fmt(plan.chosen.port[0], 4)} "
          f"{fmt(plan.chosen.port[1], 4)} {fmt(plan.chosen.port[2], 4)}")
    for sp in patient.second_ports:
        print(f"second port {sp.name!r} (patient frame, m): {fmt(sp.port[0], 4)} "
              f"{fmt(sp.port[1], 4)} {fmt(sp.port[2], 4)}; its instrument is in the "
              f"least clearance")
    print(f"wrote {path} in {os.times().elapsed - t0:.0f} s; use it with --rcm-frame {path}")
    return 0


def run_view(args: argparse.Namespace) -> int:
    """Write the HTML view of a set-up."""
    from ..plot import write_setup_html
    from ..synthesis import Patient, SetupOptions, read_setup

    if args.output.suffix.lower() != ".html":
        raise ValueError(f"-o: expected a file ending in .html, got {str(args.output)!r}")
    check_count(args.targets, "--targets", 1, 12)
    inputs = [args.patient, args.setup] + ([args.options] if args.options else [])
    with Outputs(force=args.force, inputs=inputs) as outs:
        out = outs.add(args.output)
        patient = Patient.from_toml(args.patient)
        setup, design, _ = read_setup(args.setup)
        opts = SetupOptions.from_toml(args.options) if args.options else SetupOptions()
        write_setup_html(outs.temp(out), patient, setup, design, targets=args.targets,
                         options=opts, include_plotlyjs="cdn" if args.cdn else True)
        outs.commit()
    print(f"wrote {out}")
    return 0
