"""Write every figure of docs/figures from athenakin's own plotting functions.

Run from anywhere::

    python docs/figures/regenerate.py                 # all figures, docs resolution
    python docs/figures/regenerate.py instrument_cone synthesis_pareto
    python docs/figures/regenerate.py --quick --out /tmp/figs   # coarse grids (CI: a minute)
    python docs/figures/regenerate.py --list

``app`` (the screenshots of ``athenakin app``) needs playwright and a Chromium and is not
part of the default set; it runs ``examples/_app_screenshots.py``,
``examples/_app_forces_screenshot.py`` and ``examples/_app_teleop_screenshot.py``.
``foxglove`` (the Foxglove Studio screenshots of docs/ros.md, a file and the live stream,
and of docs/teleop.md, a replayed session) runs ``tools/foxglove-shot/shot.py`` and needs,
besides playwright and Chromium, ``npm ci`` in tools/foxglove-shot (and the ``sim`` extra
for the session). ``teleop`` (the 20 s session of docs/teleop.md, two runs in MuJoCo:
minutes) runs ``benchmarks/bench_teleop.py session`` and needs the ``sim`` extra. ``ros2``
(the session of docs/ros2.md recorded from live nodes) runs
``scripts/ros2_session_figure.py`` and needs the ``ros2``, ``ros`` and ``sim`` extras. Every
other figure needs only the ``plot``, ``analysis``, ``calibration``, ``motion`` and
``synthesis`` extras.
With ``--quick`` the grids and sample counts are coarser (the figures look the same, a little
blockier); the committed PNGs are written without it.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

import athenakin as ak  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
D = ak.Design.default()
T = ak.default_rcm_frame(D)


class Settings:
    """Where to write and how fine the grids are."""

    def __init__(self, out: Path, quick: bool) -> None:
        self.out = out
        self.quick = quick

    def res(self, full: int, quick: int) -> int:
        """A grid resolution or sample count: ``full``, or ``quick`` with ``--quick``."""
        return quick if self.quick else full


def _save(fig: object, path: Path, dpi: int) -> None:
    fig.savefig(path, dpi=dpi)  # type: ignore[attr-defined]
    plt.close(fig)  # type: ignore[arg-type]


def robot_reference(s: Settings) -> list[Path]:
    """README: ``athenakin view`` (reference configuration, slot 0)."""
    from athenakin.plot import save_view

    path = s.out / "robot_reference.png"
    save_view(path, dpi=120)
    return [path]


def fk_solutions(s: Settings) -> list[Path]:
    """docs/visualization.md: ``athenakin view --all`` (the 16 solutions side by side)."""
    from athenakin.plot import plot_fk_solutions

    path = s.out / "fk_solutions.png"
    _save(plot_fk_solutions(), path, dpi=72)
    return [path]


def singularity_loci(s: Settings) -> list[Path]:
    """docs/singularities.md, Figure 1."""
    from athenakin.analysis import actuator_map
    from athenakin.analysis import figures as F

    path = s.out / "singularity_loci.png"
    am = actuator_map(D, resolution=s.res(241, 61))
    _save(F.figure_singularities(D, am=am), path, dpi=80)
    return [path]


def workspace_os(s: Settings) -> list[Path]:
    """docs/singularities.md, Figure 2."""
    from athenakin.analysis import figures as F
    from athenakin.analysis import point_workspace

    path = s.out / "workspace_os.png"
    _save(F.figure_workspace(point_workspace(design=D, resolution=s.res(81, 31))), path, dpi=80)
    return [path]


def conditioning(s: Settings) -> list[Path]:
    """docs/singularities.md, Figure 3."""
    from athenakin.analysis import actuator_map, point_workspace, tool_tip_workspace
    from athenakin.analysis import figures as F

    path = s.out / "conditioning.png"
    fig = F.figure_conditioning(actuator_map(D, resolution=s.res(161, 51)),
                                point_workspace(design=D, resolution=s.res(81, 31)),
                                tool_tip_workspace(T, D, resolution=s.res(81, 31)))
    _save(fig, path, dpi=80)
    return [path]


def instrument_cone(s: Settings) -> list[Path]:
    """docs/singularities.md, Figure 4."""
    from athenakin.analysis import figures as F
    from athenakin.analysis import instrument_cone as cone

    path = s.out / "instrument_cone.png"
    ic = cone(T, D, resolution=(37, 19, 24)) if s.quick else cone(T, D)
    _save(F.figure_instrument_cone(ic, reference_q=ak.robot.REFERENCE_Q), path, dpi=80)
    return [path]


def tool_tip(s: Settings) -> list[Path]:
    """docs/singularities.md, Figure 5."""
    from athenakin.analysis import figures as F
    from athenakin.analysis import tool_tip_workspace

    path = s.out / "tool_tip.png"
    _save(F.figure_tool_tip(tool_tip_workspace(T, D, resolution=s.res(81, 31))), path, dpi=80)
    return [path]


def measure_scaling(s: Settings) -> list[Path]:
    """docs/singularities.md, Figure 0."""
    from athenakin.analysis import figures as F

    path = s.out / "measure_scaling.png"
    _save(F.figure_measure_scaling(D, n=s.res(45, 15)), path, dpi=80)
    return [path]


def calibration(s: Settings) -> list[Path]:
    """docs/calibration.md: the report figures of the worked example."""
    from athenakin.cli import main

    with tempfile.TemporaryDirectory() as tmp:
        rc = main(["calibrate", str(ROOT / "examples/calibration/measurements.csv"), "-o",
                   str(Path(tmp) / "calibrated.toml"), "--params", "default", "offsets",
                   "--loss", "soft_l1", "--encoder-resolution", "10e-6"])
        if rc != 0:
            raise RuntimeError(f"athenakin calibrate failed (exit {rc})")
        out = []
        for name in ("residuals", "parameters", "tip_error"):
            dst = s.out / f"calibration_{name}.png"
            shutil.copyfile(Path(tmp) / f"calibrated_report_{name}.png", dst)
            out.append(dst)
    return out


def motion_path3d(s: Settings) -> list[Path]:
    """docs/motion.md: ``athenakin plan examples/motion/tip_square.csv`` (3-D path)."""
    from athenakin.cli import main

    with tempfile.TemporaryDirectory() as tmp:
        rc = main(["plan", str(ROOT / "examples/motion/tip_square.csv"), "-o",
                   str(Path(tmp) / "square.csv"), "--j-max", "5"])
        if rc != 0:
            raise RuntimeError(f"athenakin plan failed (exit {rc})")
        dst = s.out / "motion_path3d.png"
        shutil.copyfile(Path(tmp) / "square_path3d.png", dst)
    return [dst]


def synthesis_pareto(s: Settings) -> list[Path]:
    """docs/synthesis.md: the NSGA-II search of the example task, in two of its objectives."""
    from athenakin.synthesis import (
        StudyOptions,
        Task,
        bounds_from_toml,
        example_task_path,
        optimize,
    )
    from athenakin.synthesis.figures import plot_pareto

    task = Task.from_toml(example_task_path())
    res = optimize(task, bounds=bounds_from_toml(example_task_path()),
                   samples=s.res(20_000, 2_000), population=s.res(24, 12), generations=s.res(8, 3),
                   seed=0, options=StudyOptions(progress=False))
    fig, ax = plt.subplots(figsize=(7.2, 5.0), layout="constrained")
    plot_pareto(res.table, front=res.front, reference=res.table.iloc[0], ax=ax)
    path = s.out / "synthesis_pareto.png"
    _save(fig, path, dpi=100)
    return [path]


def app(s: Settings) -> list[Path]:
    """docs/visualization.md: screenshots of ``athenakin app`` (playwright, Chromium)."""
    subprocess.run([sys.executable, str(ROOT / "examples/_app_screenshots.py")], check=True)
    subprocess.run([sys.executable, str(ROOT / "examples/_app_forces_screenshot.py")],
                   check=True)                                      # issue 21: app forces
    subprocess.run([sys.executable, str(ROOT / "examples/_app_teleop_screenshot.py")],
                   check=True)                                      # issue 29: Teleop tab
    names = ("app_forward.png", "app_all_slots.png", "app_inverse.png", "app_forces.png",
             "app_teleop.png")
    if s.out != HERE:
        for n in names:
            shutil.copyfile(HERE / n, s.out / n)
    return [s.out / n for n in names]


def foxglove(s: Settings) -> list[Path]:
    """docs/ros.md, teleop.md: Foxglove Studio 1.48: a tracked MCAP, live, a teleop session."""
    path = s.out / "foxglove_track.png"
    subprocess.run([sys.executable, str(ROOT / "tools/foxglove-shot/shot.py"), "--out",
                    str(path)], check=True)
    live = s.out / "foxglove_live.png"
    subprocess.run([sys.executable, str(ROOT / "tools/foxglove-shot/shot.py"), "--source",
                    "live", "--settle", "12", "--out", str(live)], check=True)
    teleop = s.out / "foxglove_teleop.png"                      # docs/teleop.md
    subprocess.run([sys.executable, str(ROOT / "tools/foxglove-shot/shot.py"), "--recording",
                    "teleop", "--at", "0.95", "--out", str(teleop)], check=True)
    return [path, live, teleop]


def teleop(s: Settings) -> list[Path]:
    """docs/teleop.md: a 20 s teleop session in MuJoCo (benchmarks/bench_teleop.py session)."""
    path = s.out / "teleop_session.png"
    subprocess.run([sys.executable, str(ROOT / "benchmarks/bench_teleop.py"), "session",
                    "--seconds", "20", "--figure", str(path)], check=True)
    return [path]


def ros2(s: Settings) -> list[Path]:
    """docs/ros2.md: a session recorded from live ROS 2 nodes (scripts/ros2_session_figure.py)."""
    path = s.out / "ros2_session.png"
    subprocess.run([sys.executable, str(ROOT / "scripts/ros2_session_figure.py"), "--out",
                    str(path)], check=True)
    return [path]


def robot_solids(s: Settings) -> list[Path]:
    """docs/visualization.md: the bodies as capsules, the closest pair coloured (issue 20)."""
    from athenakin.plot import plot_robot

    path = s.out / "robot_solids.png"
    ax = plot_robot(bodies=True)
    _save(ax.figure, path, dpi=100)
    return [path]


def instrument_cone_collisions(s: Settings) -> list[Path]:
    """docs/motion.md, section 7: the cone with the directions a collision blocks."""
    from athenakin.analysis import figures as F
    from athenakin.analysis import instrument_cone as cone

    path = s.out / "instrument_cone_collisions.png"
    kw = {"resolution": (37, 19, 24)} if s.quick else {}
    ic = cone(T, D, clearance_margin=0.0, **kw)
    _save(F.figure_instrument_cone(ic, reference_q=ak.robot.REFERENCE_Q), path, dpi=80)
    return [path]


def collision_numbers(s: Settings) -> list[Path]:
    """docs/motion.md, section 7: the numbers quoted there (printed, no figure)."""
    import collections

    import numpy as np

    from athenakin.analysis import instrument_cone as cone
    from athenakin.analysis import workspace_summary
    from athenakin.analysis._collision import labelled_clearance
    from athenakin.collision import Bodies

    ic = cone(T, D, clearance_margin=0.0)
    for k, v in workspace_summary(ic=ic).items():
        if "solid angle" in k:
            print(f"{k}: {v:.3f}")
    A, P, Pp = np.meshgrid(ic.azimuth, ic.polar, ic.p, indexing="ij")
    bad = ic.reachable & ~ic.collision_free
    d_e = ak.direction_from_angles(A[bad], P[bad])
    q, res = ak.q_from_instrument(T, d_e, Pp[bad], D, errors="flag")
    _, pair = labelled_clearance(q, T, D, res.mode, Pp[bad] < 0, bodies=Bodies.default(D),
                                 environment=None)
    share = collections.Counter(f"{a}/{b}" for a, b in pair)
    print(f"colliding (direction, insertion) samples: {bad.sum()} of {ic.reachable.sum()}")
    for name, n in share.most_common(6):
        print(f"  closest pair {name}: {n}")
    return []


def _script(name: str, s: Settings, written: tuple[str, ...]) -> list[Path]:
    """Run docs/figures/NAME.py (its own figures and numbers) into ``s.out``."""
    import os

    env = dict(os.environ, ATHENAKIN_FIGURES_OUT=str(s.out),
               ATHENAKIN_FIGURES_QUICK="1" if s.quick else "0")
    subprocess.run([sys.executable, str(HERE / f"{name}.py")], check=True, env=env)
    return [s.out / w for w in written]


def collision(s: Settings) -> list[Path]:
    """docs/collision.md: the bodies, and the collision-free strokes and cone (the finding)."""
    return _script("collision", s, ("collision_bodies.png", "collision_workspace.png",
                                    "collision_cone.png"))


def dynamics(s: Settings) -> list[Path]:
    """docs/dynamics.md: gravity forces, force capability and the example motion's forces."""
    return _script("dynamics", s, ("dynamics_gravity_cone.png", "dynamics_gravity_plane.png",
                                   "dynamics_capability.png", "dynamics_motion.png"))


FIGURES: dict[str, Callable[[Settings], list[Path]]] = {
    "robot_reference": robot_reference,
    "fk_solutions": fk_solutions,
    "measure_scaling": measure_scaling,
    "singularity_loci": singularity_loci,
    "workspace_os": workspace_os,
    "conditioning": conditioning,
    "instrument_cone": instrument_cone,
    "tool_tip": tool_tip,
    "calibration": calibration,
    "motion_path3d": motion_path3d,
    "synthesis_pareto": synthesis_pareto,
    "robot_solids": robot_solids,
    "instrument_cone_collisions": instrument_cone_collisions,
    "collision": collision,
    "dynamics": dynamics,
}
#: Figures written only when named (they need more than the extras).
OPTIONAL = {"app": app, "foxglove": foxglove, "teleop": teleop, "ros2": ros2,
            "collision_numbers": collision_numbers}


def main(argv: list[str] | None = None) -> int:
    """Write the named figures (default: all but the optional ones)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("names", nargs="*", metavar="NAME",
                    help=f"figures to write (default: all of {', '.join(FIGURES)}; also "
                         f"{', '.join(OPTIONAL)})")
    ap.add_argument("--quick", action="store_true", help="coarse grids (CI)")
    ap.add_argument("--out", type=Path, default=HERE, help="folder (default docs/figures)")
    ap.add_argument("--list", action="store_true", help="list the figure names and stop")
    args = ap.parse_args(argv)
    known = {**FIGURES, **OPTIONAL}
    if args.list:
        for name, fn in known.items():
            print(f"{name:18s} {(fn.__doc__ or '').splitlines()[0]}")
        return 0
    unknown = [n for n in args.names if n not in known]
    if unknown:
        ap.error(f"unknown figure(s) {unknown}; known: {sorted(known)}")
    args.out.mkdir(parents=True, exist_ok=True)
    settings = Settings(args.out, args.quick)
    for name in args.names or list(FIGURES):
        t0 = time.perf_counter()
        paths = known[name](settings)
        print(f"{name}: wrote {', '.join(p.name for p in paths)} "
              f"({time.perf_counter() - t0:.1f} s)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
