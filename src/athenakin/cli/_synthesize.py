"""``athenakin synthesize``: a design study against a surgical task, locally or on a cluster."""

from __future__ import annotations

import argparse
import dataclasses
import os
from pathlib import Path
from typing import Any

from ._collision import add_environment_option, load_environment
from ._common import add_json_option, check_count, check_finite, dump_json, fmt, table
from ._output import Outputs

_SHOWN = ("coverage", "coverage_mode", "size", "tip_error_max", "margin_min", "cond_tip_max")


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``synthesize`` subcommand."""
    p = sub.add_parser(
        "synthesize", help="design study against a surgical task (Dask; local or a cluster)",
        description="Evaluate designs against the task of TASK.toml (RCM, cone of instrument "
                    "directions, tip depths): the reference design alone, N random designs "
                    "within the [bounds] of the file (--designs), or an NSGA-II search "
                    "(--optimize). Writes the table as Parquet (resumable) and figures.")
    p.add_argument("task", metavar="TASK.toml", nargs="?", default=None,
                   help="task file ([task], optional [bounds]); default: the example task "
                        "shipped with athenakin (athenakin.synthesis.example_task_path())")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--designs", type=int, default=0, metavar="N",
                   help="N random designs within the bounds, after the reference design")
    g.add_argument("--optimize", action="store_true", help="NSGA-II over l1..l5 and strokes")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="Dask scheduler: tcp://host:port of a distributed cluster, or "
                        "threads|processes|synchronous (default: local threads)")
    p.add_argument("-o", "--out", default="synthesis.parquet", metavar="PATH",
                   help="Parquet folder of the results (default synthesis.parquet); an "
                        "interrupted study resumes from it")
    p.add_argument("--samples", type=int, default=20_000,
                   help="task samples per design (default 20000)")
    p.add_argument("--seed", type=int, default=0, help="seed of samples and search")
    p.add_argument("--population", type=int, default=24, help="NSGA-II population (24)")
    p.add_argument("--generations", type=int, default=8, help="NSGA-II generations (8)")
    p.add_argument("--encoder-resolution", type=float, default=None, metavar="M",
                   help="actuator encoder resolution for the tip error, m (default 1e-6, or "
                        "that of --options)")
    p.add_argument("--figures", default=None, metavar="DIR",
                   help="folder for figures (default: next to the output, <out>-figures)")
    p.add_argument("--no-figures", action="store_true", help="write no figures")
    p.add_argument("--top", type=int, default=5, help="designs listed (default 5)")
    p.add_argument("--connect-timeout", type=float, default=None, metavar="S",
                   help="seconds to wait for the scheduler (default 5, or that of --options)")
    p.add_argument("--options", type=Path, default=None, metavar="FILE.toml",
                   help="study settings: the [study] table of a TOML file "
                        "(athenakin.synthesis.StudyOptions: encoder_resolution, chunk_size, "
                        "connect_timeout, retries and a [study.collision] check); the options "
                        "given here override it")
    p.add_argument("--force", action="store_true",
                   help="replace existing figures (the results folder -o is resumed, "
                        "never replaced)")
    g = p.add_argument_group("collisions (any of these turns the clearance check on: columns "
                             "collision_free_coverage, min_clearance)")
    g.add_argument("--bodies", default=None, metavar="default|scaled|FILE",
                   help="the default capsules for every design, those scaled with l1, or the "
                        "[bodies] table of a TOML file (radii in m)")
    add_environment_option(g)
    g.add_argument("--clearance-margin", type=float, default=None, metavar="M",
                   help="a sample is collision-free with at least this clearance, m (0)")
    g.add_argument("--collision-samples", type=int, default=None, metavar="N",
                   help="task samples checked per design (default 10000)")
    g.add_argument("--min-clearance", type=float, default=None, metavar="M",
                   help="with --optimize: designs whose min_clearance is below M are "
                        "infeasible (a constraint)")
    add_json_option(p)
    p.set_defaults(func=run)


#: Figures written to --figures, and the bounds of the counts (checked before any work).
FIGURES = ("pareto", "parameters", "coverage")
MAX_DESIGNS = 100_000
MAX_POPULATION = 10_000
MAX_GENERATIONS = 10_000


def _check_options(args: argparse.Namespace) -> None:
    """Every option within its bounds, before any work (nothing is written on a failure)."""
    from ..synthesis._study import MAX_SAMPLES

    check_count(args.samples, "--samples", 1, MAX_SAMPLES, "task samples per design")
    check_count(args.designs, "--designs", 0, MAX_DESIGNS, "random designs")
    check_count(args.population, "--population", 2, MAX_POPULATION, "designs per generation")
    check_count(args.generations, "--generations", 1, MAX_GENERATIONS, "generations")
    check_count(args.top, "--top", 0, MAX_DESIGNS, "designs listed")
    check_count(args.seed, "--seed", 0, 2**63 - 1, "(a seed)")
    if args.connect_timeout is not None:
        check_finite(args.connect_timeout, "--connect-timeout", positive=True)
    if args.encoder_resolution is not None:
        check_finite(args.encoder_resolution, "--encoder-resolution", positive=True)
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"-o: {str(out)!r} is a file; expected a results folder (new, or "
                         f"one to resume)")
    parent = next((f for f in (out.parent, *out.parent.parents) if f.exists()), Path("."))
    if not out.exists() and not os.access(parent, os.W_OK | os.X_OK):
        raise PermissionError(f"-o: folder {str(parent)!r} is not writable")


def run(args: argparse.Namespace) -> int:
    """Execute ``synthesize``."""
    from .. import Design
    from ..synthesis import Task, bounds_from_toml, default_bounds, example_task_path

    _check_options(args)
    if args.task is None:
        args.task = str(example_task_path())
    task = Task.from_toml(args.task)
    ref = Design.default()
    bounds = bounds_from_toml(args.task) or default_bounds(ref)
    out = Path(args.out)
    inputs = [Path(args.task)] + ([] if args.options is None else [Path(args.options)])
    with Outputs(force=args.force, inputs=inputs, option="--figures") as outs:
        figs: dict[str, Path] = {}
        if not args.no_figures:   # checked before any work: never replaced without --force
            folder = Path(args.figures or f"{out}-figures")
            figs = {n: outs.add_in_folder(folder, f"{n}.png", option="--figures")
                    for n in FIGURES}
        return _run(args, task, ref, bounds, out, outs, figs)


def _collision_options(args: argparse.Namespace) -> dict[str, Any]:
    """``bodies``, ``environment``, ``clearance_margin``, ``collision_samples`` as given."""
    out: dict[str, Any] = {}
    if args.bodies is not None:
        if args.bodies in ("default", "scaled"):
            out["bodies"] = args.bodies
        else:
            from ..collision import Bodies

            out["bodies"] = Bodies.from_toml(args.bodies)
    if args.environment is not None:
        out["environment"] = load_environment(args.environment)
    if args.clearance_margin is not None:
        out["clearance_margin"] = args.clearance_margin
    if args.collision_samples is not None:
        out["collision_samples"] = args.collision_samples
    return out


def _run(args: argparse.Namespace, task: Any, ref: Any, bounds: Any, out: Path,
         outs: Outputs, figs: dict[str, Path]) -> int:
    from ..synthesis import (
        StudyOptions,
        collision_spec,
        evaluate,
        optimize,
        random_designs,
        row_from_design,
    )

    opts = StudyOptions() if args.options is None else StudyOptions.from_toml(args.options)
    given = {k: v for k, v in (("encoder_resolution", args.encoder_resolution),
                               ("connect_timeout", args.connect_timeout)) if v is not None}
    coll = _collision_options(args)
    if coll and opts.collision is not None:    # the flags given replace those of the file
        names = {"clearance_margin": "margin", "collision_samples": "samples"}
        given["collision"] = dataclasses.replace(
            opts.collision, **{names.get(k, k): v for k, v in coll.items()})
    elif coll:
        given["collision"] = collision_spec(**coll)
    opts = dataclasses.replace(opts, progress=not args.json, **given)
    common: dict[str, Any] = dict(samples=args.samples, seed=args.seed,
                                  scheduler=args.scheduler, options=opts)
    result: Any = None
    if args.min_clearance is not None and not args.optimize:
        raise ValueError("--min-clearance: a constraint of the search; use it with --optimize")
    if args.optimize:
        if args.min_clearance is not None:
            check_finite(args.min_clearance, "--min-clearance")
            common["constraints"] = {"min_clearance": (">=", args.min_clearance)}
        if out.exists() and (not out.is_dir() or any(out.iterdir())):
            raise FileExistsError(f"{out}: exists and is not an empty folder; a search writes "
                                  f"a new one (-o)")
        result = optimize(task, bounds=bounds, reference=ref, population=args.population,
                          generations=args.generations, **common)
        df = result.table
        out.mkdir(parents=True, exist_ok=True)
        df.to_parquet(out / "part-000000.parquet", index=False)
    else:
        rows = [row_from_design(ref) | {"name": ref.name}]
        if args.designs:
            rows += random_designs(args.designs, bounds, seed=args.seed, base=ref)
        df = evaluate(rows, task, out=out, **common)
    files = [str(out)]
    if figs:
        _figures(df, result, task, ref, figs, args, outs)
        files += [str(f) for f in outs.commit()]
    report = _report(df, result, args.top)
    if args.json:
        print(dump_json({"task": task.to_mapping(), "results": str(out), "files": files,
                         **report}))
        return 0
    _print(task, report, files, result is not None)
    return 0


def _figures(df: Any, result: Any, task: Any, ref: Any, figs: dict[str, Path],
             args: argparse.Namespace, outs: Outputs) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..synthesis import design_from_row
    from ..synthesis.figures import (
        plot_coverage_map,
        plot_parameter_coordinates,
        plot_pareto,
    )
    from ._workspace import save_figure

    front = result.front if result is not None else None
    reference = df.iloc[0]
    fig, ax = plt.subplots(figsize=(6.4, 4.8), layout="constrained")
    plot_pareto(df, front=front, reference=reference, ax=ax)
    save_figure(fig, figs["pareto"].with_suffix(""), ["png"], 110, outs)
    if int(df["valid"].sum()) > 1:
        fig, ax = plt.subplots(figsize=(9, 4.8), layout="constrained")
        plot_parameter_coordinates(df, highlight=front, ax=ax)
        save_figure(fig, figs["parameters"].with_suffix(""), ["png"], 110, outs)
    else:   # one valid design: no parameter plot
        outs.drop(figs["parameters"])
    best = df[df["valid"]].sort_values("coverage_mode", ascending=False)
    chosen = [design_from_row(reference)]
    if len(best) and best.index[0] != 0:
        chosen.append(design_from_row(best.iloc[0]))
    fig, axes = plt.subplots(1, len(chosen), figsize=(5 * len(chosen), 4.6),
                             layout="constrained", squeeze=False)
    names = ["reference design", f"best coverage (design {best['design'].iloc[0]})"
             if len(best) else ""]
    for ax, d, name in zip(axes[0], chosen, names, strict=False):
        plot_coverage_map(d, task, samples=min(args.samples, 20_000), seed=args.seed, ax=ax)
        ax.set_title(name)
    save_figure(fig, figs["coverage"].with_suffix(""), ["png"], 110, outs)


def _report(df: Any, result: Any, top: int) -> dict[str, Any]:
    checked = "min_clearance" in df and bool(df["valid"].any()) and bool(
        df["collision_free_coverage"].notna().any())
    cols = ["design", "name", *_SHOWN, *(("collision_free_coverage", "min_clearance")
                                         if checked else ())]
    valid = df[df["valid"]]
    best = valid.sort_values("coverage_mode", ascending=False).head(top)
    rep: dict[str, Any] = {
        "designs": int(len(df)), "valid": int(df["valid"].sum()), "collisions": checked,
        "reference": {k: df.iloc[0][k] for k in cols},
        "best": [{k: r[k] for k in cols} for _, r in best.iterrows()],
        "invalid": [{"design": int(r["design"]), "reason": r["reason"]}
                    for _, r in df[~df["valid"]].head(top).iterrows()]}
    if result is not None:
        rep["front"] = [{k: r[k] for k in cols} for _, r in result.front.iterrows()]
        rep["reference_on_front"] = result.reference_on_front
        rep["dominating"] = result.dominating
        rep["gains"] = result.gains
        rep["trade_offs"] = result.trade_offs
    return rep


def _print(task: Any, rep: dict[str, Any], files: list[str], search: bool) -> None:
    import math

    print(f"task {task.name!r}: cone {math.degrees(task.half_angle):.1f} deg about "
          f"{[round(x, 4) for x in task.axis.tolist()]}, depth {task.depth[0]:.3f}.."
          f"{task.depth[1]:.3f} m beyond the RCM")
    n = rep["designs"]
    print(f"{n} design{'' if n == 1 else 's'}, {rep['valid']} valid")
    headers = ["design", "coverage", "cov. 1 mode", "size m", "tip err. um", "margin m",
               "cond tip"] + (["cov. free", "clearance mm"] if rep["collisions"] else [])

    def line(r: dict[str, Any]) -> list[Any]:
        extra = ([fmt(r["collision_free_coverage"], 4), fmt(r["min_clearance"] * 1e3, 2)]
                 if rep["collisions"] else [])
        return [r["design"], fmt(r["coverage"], 4), fmt(r["coverage_mode"], 4),
                fmt(r["size"], 3), fmt(r["tip_error_max"] * 1e6, 2), fmt(r["margin_min"], 4),
                fmt(r["cond_tip_max"], 1)] + extra

    rows = [r for r in rep["best"] if r["design"] != 0]
    print(table(headers, [line(rep["reference"])] + [line(r) for r in rows]))
    print("design 0: the reference design" + (
        f"; below it the {len(rows)} valid design{'' if len(rows) == 1 else 's'} of highest "
        f"coverage in one assembly mode ('cov. 1 mode')" if rows else ""))
    for r in rep["invalid"]:
        print(f"design {r['design']} invalid: {r['reason']}")
    if search:
        print(f"Pareto front: {len(rep['front'])} designs; the reference design is "
              f"{'on the front' if rep['reference_on_front'] else 'dominated'}"
              + (f" by {rep['dominating']} of them" if rep["dominating"] else ""))
        for k, v in rep["gains"].items():
            print(f"  best gain over the reference in {k}: {v:.4g}")
        for k, t in rep["trade_offs"].items():
            others = ", ".join(f"{m} {t[m]:+.4g}" for m in t if m not in ("design", k))
            print(f"  best {k} on the front: design {int(t['design'])}, {t[k]:+.4g} against "
                  f"the reference, at {others}")
    print("files: " + ", ".join(files))
