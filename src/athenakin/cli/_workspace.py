"""``athenakin workspace``: O_s workspace, instrument cone, tool-tip workspace, figures + npz."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from ._collision import add_collision_options, collision_options
from ._common import (
    add_json_option,
    add_robot_options,
    check_count,
    check_dpi,
    dump_json,
    load_robot,
    table,
)
from ._output import Outputs, add_force_option, outputs

#: Most grid points per axis of ``--resolution`` (the O_s and tool-tip grids hold
#: resolution^3 points: 201^3 = 8.1 million, a few hundred MB).
MAX_RESOLUTION = 201
#: Most samples of the instrument cone (N_AZ x N_POLAR x N_P).
MAX_CONE_SAMPLES = 2_000_000


def add_output_options(p: argparse.ArgumentParser, default_dir: str) -> None:
    """``--out``, ``--format``, ``--dpi``, ``--no-figures``, ``--no-files``."""
    p.add_argument("--out", default=default_dir, metavar="DIR",
                   help=f"output folder for figures and .npz data (default ./{default_dir})")
    p.add_argument("--format", nargs="+", choices=("png", "svg", "pdf"), default=["png"],
                   help="figure formats (default png)")
    p.add_argument("--dpi", type=int, default=100, help="PNG resolution (default 100)")
    p.add_argument("--no-figures", action="store_true", help="write the .npz data only")
    p.add_argument("--no-files", action="store_true", help="print only; write nothing")
    add_force_option(p)


def save_figure(fig: Any, stem: Path, formats: list[str], dpi: int,
                outs: Outputs | None = None) -> list[str]:
    """Save ``fig`` as ``stem.<fmt>`` for each format, close it; return the paths.

    With ``outs``, each file is rendered into its temporary file (declared before).
    """
    import matplotlib.pyplot as plt

    paths = []
    try:
        for f in dict.fromkeys(formats):
            path = stem.with_suffix(f".{f}")
            fig.savefig(path if outs is None else outs.temp(path), dpi=dpi)
            paths.append(str(path))
    finally:
        plt.close(fig)
    return paths


def declare_outputs(args: argparse.Namespace, outs: Outputs, npz: list[str],
                    figures: list[str]) -> None:
    """Declare ``--out``/name.npz and the figures in each ``--format`` (unless turned off)."""
    if args.no_files:
        return
    for name in npz:
        outs.add_in_folder(args.out, f"{name}.npz", option="--out")
    if not args.no_figures:
        for name in figures:
            for f in dict.fromkeys(args.format):
                outs.add_in_folder(args.out, f"{name}.{f}", option="--out")


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``workspace`` subcommand."""
    p = sub.add_parser(
        "workspace", help="workspace, instrument cone, conditioning and assembly-mode maps",
        description="Reachable O_s (with assembly-mode regions), the cone of instrument "
                    "directions about the RCM with the insertion range along each, the tool-tip "
                    "workspace and conditioning maps; writes figures and .npz data.")
    p.add_argument("--resolution", type=int, default=61,
                   help="grid points per axis of the O_s and tool-tip grids (default 61)")
    p.add_argument("--cone-resolution", type=int, nargs=3, default=(73, 37, 46),
                   metavar=("N_AZ", "N_POLAR", "N_P"),
                   help="azimuth, polar and insertion samples of the cone (default 73 37 46)")
    p.add_argument("--modes", type=int, nargs="+", choices=(1, -1), default=[1],
                   help="assembly modes allowed for the cone and the tool tip (default 1)")
    p.add_argument("--progress", action="store_true", help="show progress bars")
    add_collision_options(p, what="the maps gain a collision-free layer, the cone the "
                                  "directions a collision blocks", default_margin="0")
    add_output_options(p, "athenakin-workspace")
    add_robot_options(p)
    add_json_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Execute ``workspace``."""
    from ..analysis import (
        actuator_map,
        instrument_cone,
        point_workspace,
        save_npz,
        tool_tip_workspace,
        workspace_summary,
    )

    check_count(args.resolution, "--resolution", 2, MAX_RESOLUTION, "grid points per axis")
    for n in args.cone_resolution:
        check_count(n, "--cone-resolution", 2, MAX_RESOLUTION, "samples per axis")
    if int(np.prod(args.cone_resolution)) > MAX_CONE_SAMPLES:
        raise ValueError(f"--cone-resolution: expected at most {MAX_CONE_SAMPLES} samples in "
                         f"all, got {' x '.join(map(str, args.cone_resolution))}")
    check_dpi(args.dpi)
    files: list[str] = []
    with outputs(args, option="--out") as outs:
        declare_outputs(args, outs, ["o_s_workspace", "instrument_cone", "tool_tip",
                                     "actuator_map"],
                        ["workspace", "conditioning", "instrument_cone", "tool_tip"])
        design, T = load_robot(args)
        prog = True if args.progress else None
        modes = tuple(args.modes)
        coll = collision_options(args, design)
        pw = point_workspace(design=design, resolution=args.resolution, progress=prog,
                             **({**coll, "T_b_e": T} if coll else {}))
        ic = instrument_cone(T, design, resolution=tuple(args.cone_resolution), modes=modes,
                             progress=prog, **coll)
        tw = tool_tip_workspace(T, design, resolution=args.resolution, modes=modes,
                                progress=prog, **coll)
        summary = workspace_summary(pw, ic, tw)
        if not args.no_files:
            outdir = Path(args.out)
            am = actuator_map(design, resolution=161, progress=prog)
            for name, res in (("o_s_workspace", pw), ("instrument_cone", ic),
                              ("tool_tip", tw), ("actuator_map", am)):
                save_npz(outs.temp(outdir / f"{name}.npz"), res, design=design,
                         T_b_e=np.asarray(T).tolist(), modes=list(modes))
            if not args.no_figures:
                from ..analysis import figures as F
                from ..robot import REFERENCE_Q

                ref = REFERENCE_Q if args.rcm is None and args.rcm_file is None else None
                figs = (("workspace", lambda: F.figure_workspace(pw)),
                        ("conditioning", lambda: F.figure_conditioning(am, pw, tw)),
                        ("instrument_cone",
                         lambda: F.figure_instrument_cone(ic, reference_q=ref)),
                        ("tool_tip", lambda: F.figure_tool_tip(tw)))
                for name, make in figs:
                    save_figure(make(), outdir / name, args.format, args.dpi, outs)
            files = [str(f) for f in outs.commit()]
    if args.json:
        print(dump_json({"summary": summary, "files": files}))
        return 0
    print(table(["quantity", "value"], [[k, _fmt(v)] for k, v in summary.items()]))
    if any(isinstance(v, float) and v != v for v in summary.values()):
        print("-: no sample to compute it from (a finer --resolution or --cone-resolution "
              "may find some)")
    for f in files:
        print(f"wrote {f}")
    return 0


def _fmt(v: object) -> str:
    if isinstance(v, float):   # NaN: no sample to take it from (a coarse grid, an empty cone)
        return "-" if v != v else f"{v:.6g}"
    if isinstance(v, (tuple, list)):
        return "(" + ", ".join(_fmt(x) for x in v) + ")"
    return str(v)
