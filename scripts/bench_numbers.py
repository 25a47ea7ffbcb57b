"""Write the benchmark figures quoted in README.md and docs/*.md from one benchmark run.

Usage (from the repository root)::

    python scripts/bench_numbers.py --run     # run benchmarks/run.py --json, then rewrite
    python scripts/bench_numbers.py           # rewrite from the committed JSON
    python scripts/bench_numbers.py --check   # exit 1 if a page differs from the JSON

The JSON is ``benchmarks/results.json``: what ``benchmarks/run.py --json`` writes, plus
``date`` (UTC) and ``command``, which this script adds. Groups in :data:`OWN_RUNS` are
measured in a run of their own, written to their own JSON (``python
scripts/bench_numbers.py --run-own ros`` reruns only that one) and quoted from it. Every
quoted figure lives in a marked region of a page::

    <!-- bench:KEY -->
    ... generated text, never edited by hand ...
    <!-- /bench:KEY -->

and :data:`RENDER` maps each KEY to the function that writes its text from the JSON. Each
region states the date of the run, the machine and its load average (a shared machine
skews timings; ratios within one run are the figures to compare).
``tests/test_bench_numbers.py`` checks that every region equals what the JSON gives.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import json
import re
import subprocess
import sys
import textwrap
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
JSON = ROOT / "benchmarks" / "results.json"
#: The benchmark modules whose rows the pages quote, and the options of the run.
MODULES = ("cases_core", "cases_symbolic", "cases_calibration", "cases_fast_jacobians",
           "cases_motion", "cases_certified")
RUN_OPTIONS = ("--cpu-time", "--min-time", "0.2", "--repeat", "3")
#: Runs of their own: key -> (JSON, benchmark modules, options). The ROS pipeline's cases
#: take a tenth of a second each, write files and move with the machine's load: more
#: repeats (the best is kept), and its page quotes only them.
OWN_RUNS = {
    "ros": (ROOT / "benchmarks" / "results_ros.json", ("cases_ros",),
            ("--cpu-time", "--min-time", "0.3", "--repeat", "7")),
}
#: Line width of the generated sentences (that of the pages).
WIDTH = 96
#: The pages that may hold regions.
PAGES = ("README.md", "docs/performance.md", "docs/calibration.md", "docs/motion.md",
         "docs/certified.md", "docs/ros.md")
_REGION = re.compile(r"(<!-- bench:(?P<key>[\w-]+) -->\n)(?P<body>.*?)(<!-- /bench:(?P=key) -->)",
                     re.S)


class Results:
    """The rows of one run, looked up by group and case name."""

    def __init__(self, data: dict, own: dict[str, Results] | None = None) -> None:
        self.data = data
        self.rows = [r for r in data["rows"] if r.get("error") is None]
        #: The runs of :data:`OWN_RUNS` found, by key.
        self.own = own or {}

    def of(self, key: str) -> Results:
        """The results of the run of its own ``key``."""
        if key not in self.own:
            raise KeyError(f"no {OWN_RUNS[key][0].name}: run python scripts/bench_numbers.py "
                           f"--run-own {key}")
        return self.own[key]

    def row(self, group: str, name: str) -> dict:
        """The row of case ``name`` in ``group``."""
        for r in self.rows:
            if r["group"] == group and r["name"] == name:
                return r
        raise KeyError(f"no benchmark row {group!r} / {name!r} in {JSON.name}: rerun "
                       f"python scripts/bench_numbers.py --run")

    def per_pose(self, group: str, name: str) -> float:
        """Seconds per pose of a case."""
        r = self.row(group, name)
        return float(r["seconds"]) / int(r["batch"])

    def group(self, group: str) -> list[dict]:
        """The rows of a group, in run order."""
        return [r for r in self.rows if r["group"] == group]

    def baseline(self, group: str) -> float:
        """Seconds per pose of the group's baseline."""
        for r in self.group(group):
            if r.get("baseline"):
                return float(r["seconds"]) / int(r["batch"])
        raise KeyError(f"group {group!r} has no baseline row")

    @property
    def load(self) -> str:
        """The load average of the machine (1 and 5 min)."""
        m = re.search(r"load average ([\d.]+), ([\d.]+), ([\d.]+)", self.data["machine"])
        return f"{m.group(1)} (1 min), {m.group(2)} (5 min)" if m else "n/a"

    @property
    def cpu(self) -> str:
        """The machine: CPU model and core count."""
        return self.data["machine"].split(", load average")[0]

    @property
    def stamp(self) -> str:
        """Date, machine, load and command of the run."""
        return f"{self.data['date']} on {self.cpu}, load average {self.load}"

    @property
    def command(self) -> str:
        """The command of the run, as a Markdown code span."""
        return f"`{self.data['command']}`"


def fmt_time(s: float) -> str:
    """``s`` seconds with a unit and 3 significant digits (us for microseconds)."""
    for unit, f in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6), ("ns", 1e-9)):
        if s >= f or unit == "ns":
            return f"{s / f:.3g} {unit}"
    return f"{s:.3g} s"


def fmt_rate(r: float) -> str:
    """``r`` per second with an SI prefix and 3 significant digits."""
    for unit, f in (("G", 1e9), ("M", 1e6), ("k", 1e3), ("", 1.0)):
        if r >= f or unit == "":
            return f"{r / f:.3g} {unit}/s".replace(" /s", "/s")
    return f"{r:.3g}/s"


def fmt_ratio(x: float) -> str:
    """A ratio with 3 significant digits and thousands separators."""
    return f"{x:,.3g}" if x < 1000 else f"{x:,.0f}"


def _table(res: Results, groups: tuple[str, ...], names: set[str] | None = None) -> str:
    lines = ["| group | case | batch | per pose | poses/s | x base |",
             "|---|---|---:|---:|---:|---:|"]
    for g in groups:
        base = res.baseline(g)
        for r in res.group(g):
            if names is not None and r["name"] not in names and not r.get("baseline"):
                continue
            per = float(r["seconds"]) / int(r["batch"])
            ratio = "base" if r.get("baseline") else fmt_ratio(base / per)
            lines.append(f"| {g} | {r['name']} | {r['batch']} | {fmt_time(per)} | "
                         f"{fmt_rate(1 / per)} | {ratio} |")
    return "\n".join(lines)


CORE_GROUPS = ("fk-batch", "fk-single", "ik-batch", "ik-single")
#: The rows of the README's table (the baselines are always shown).
README_ROWS = {
    "athenakin numpy reference",
    "ak.forward_kinematics, default args",
    "ak.forward_kinematics, default args, 2e5 poses",
    "ak.forward_kinematics, fields=(p, u, valid), 2e5 poses",
    "athenakin.fast.sweep_fk (counts only)",
    "scipy least_squares on closure eqs",
    "Pinocchio serial forward map, loop",
    "ak.forward_kinematics(q, T, d), default args",
    "athenakin.fast.ControlLoop.fk (raw arrays)",
    "ak.inverse_kinematics, default args, 2e5 poses",
    "ak.q_from_tool_tip, default args",
    "ak.inverse_kinematics(T, u345, d), default args",
    "ak.q_from_tool_tip(T, tip, d), default args",
    "athenakin.fast.ControlLoop.ik (raw)",
}


def render_readme_table(res: Results) -> str:
    """The README's table: the public calls, the raw entry, the peers."""
    return (f"Measured {res.stamp} with {res.command} (CPU time of one core; `x base` = "
            f"how many times faster per pose than the group's pure-Python baseline, within "
            f"the same run):\n\n"
            + _table(res, CORE_GROUPS, README_ROWS))


def render_core_table(res: Results) -> str:
    """Every row of the four core groups."""
    return (f"Measured {res.stamp} with {res.command}. CPU time of this process "
            f"(`--cpu-time`: on a shared machine the wall time counts other processes' time "
            f"slices; the `parallel` rows "
            f"sum the CPU time of their threads, so they show no gain here). Per pose = time "
            f"per call / batch; `x base` = the group baseline's time per pose over the "
            f"case's:\n\n" + _table(res, CORE_GROUPS))


def render_speed_summary(res: Results) -> str:
    """The README's sentence on the raw single-pose entry, the sweep and the Jacobians."""
    cl = res.per_pose("fk-single", "athenakin.fast.ControlLoop.fk (raw arrays)")
    fk1 = res.per_pose("fk-single", "ak.forward_kinematics(q, T, d), default args")
    sweep = res.per_pose("fk-batch", "athenakin.fast.sweep_fk (counts only)")
    pers, ratios = [], []
    for g in ("jacobian", "jacobian-tool-tip", "jacobian-parallel"):
        for r in res.group(g):
            if r["name"].startswith("athenakin.fast, ") and "shared frame" not in r["name"]:
                per = float(r["seconds"]) / int(r["batch"])
                ref = r["name"].replace("athenakin.fast, ", "numpy reference, ")
                pers.append(per)
                ratios.append(res.per_pose(g, ref) / per)
    return (f"`fast.ControlLoop(T_b_e, d).fk(q)` answers one pose in {fmt_time(cl)} with raw "
            f"arrays ({fmt_ratio(fk1 / cl)}x faster than `ak.forward_kinematics` on one pose, "
            f"{fmt_time(fk1)}); `fast.sweep_fk(gen, T_b_e, d, n=10**8)` reduces "
            f"{fmt_rate(1 / sweep).replace('/s', '')} poses per second in bounded memory "
            f"(10^8 poses in about {1e8 * sweep:.0f} s); the compiled Jacobians take "
            f"{fmt_time(min(pers))} to {fmt_time(max(pers))} per item in batches of "
            f"{res.group('jacobian')[0]['batch']}, {min(ratios):.0f} to {max(ratios):.0f}x the "
            f"numpy reference. Measured {res.stamp}.")


def render_algebraic(res: Results) -> str:
    """The algebraic FK against the default closed form, at the benchmark's batch."""
    r = res.row("fk-algebraic", "forward_kinematics_algebraic (paper's route)")
    ratio = res.per_pose("fk-algebraic", "forward_kinematics_algebraic (paper's route)") \
        / res.baseline("fk-algebraic")
    one = res.per_pose("fk-algebraic-single", "forward_kinematics_algebraic, one pose") \
        / res.baseline("fk-algebraic-single")
    return (f"The algebraic solver is {ratio:.0f}x slower than the default (compiled) closed "
            f"form at a batch of {r['batch']:,} poses and {one:.0f}x slower on one pose "
            f"(`python benchmarks/run.py --only fk-algebraic fk-algebraic-single`; measured "
            f"{res.stamp}). It is an independent check of the closed form, not a faster path.")


def render_calibration(res: Results) -> str:
    """The time of a calibration of 200 poses, over the parameter sets benchmarked."""
    rows = [r for r in res.group("calibration-solve") if r["name"].startswith("calibrate")]
    t = [float(r["seconds"]) for r in rows]
    n = {int(r["batch"]) for r in rows}
    plain = res.row("calibration-solve",
                    "calibrate (checks, identifiability, solve, covariance; l1..l5, L)")
    return (f"A calibration of {min(n)} poses takes {fmt_time(min(t))} to {fmt_time(max(t))} on "
            f"one core ({fmt_time(float(plain['seconds']))} for `l1..l5` and the tool length, "
            f"the most for 12-13 parameters or the robust loss; checks, identifiability, "
            f"solve and covariance included; `python benchmarks/run.py --only "
            f"calibration-solve`, measured {res.stamp}).")


#: The targets of docs/performance.md: (what, group, case, target per pose in s or None
#: for a rate target given as poses/s).
TARGETS = (
    ("FK, 16 solutions, batch of 4000, >= 5 M poses/s", "fk-batch",
     "athenakin.fast -> FKSolution", 1 / 5e6),
    ("FK through `ak.forward_kinematics`, 2x10^5 poses, >= 5 M poses/s", "fk-batch",
     "ak.forward_kinematics, default args, 2e5 poses", 1 / 5e6),
    ("FK sweep in bounded memory, >= 5 M poses/s", "fk-batch",
     "athenakin.fast.sweep_fk (counts only)", 1 / 5e6),
    ("FK single call, raw entry, <= 5 us", "fk-single",
     "athenakin.fast.ControlLoop.fk (raw arrays)", 5e-6),
    ("FK single call, `ak.forward_kinematics`, <= 5 us", "fk-single",
     "ak.forward_kinematics(q, T, d), default args", 5e-6),
    ("IK batch, paper form, >= 20 M poses/s", "ik-batch", "athenakin.fast, paper form", 1 / 20e6),
    ("IK batch, `q_from_tool_tip`, >= 20 M poses/s", "ik-batch",
     "athenakin.fast, q_from_tool_tip", 1 / 20e6),
    ("IK single call, raw entry, <= 2 us", "ik-single", "athenakin.fast.ControlLoop.ik (raw)",
     2e-6),
    ("IK single call, `ak.inverse_kinematics`, <= 2 us", "ik-single",
     "ak.inverse_kinematics(T, u345, d), default args", 2e-6),
)


def render_targets(res: Results) -> str:
    """The targets table of docs/performance.md, each measured in the one run."""
    lines = [f"Measured {res.stamp}.", "",
             "| target (one core) | measured | met? |", "|---|---|---|"]
    for what, group, name, limit in TARGETS:
        per = res.per_pose(group, name)
        batch = int(res.row(group, name)["batch"])
        shown = fmt_time(per) if batch == 1 else f"{fmt_rate(1 / per)} ({fmt_time(per)} per pose)"
        lines.append(f"| {what} | {shown}: {name} | {'yes' if per <= limit else '**no**'} |")
    ls = res.per_pose("fk-batch", "scipy least_squares on closure eqs")
    fk = res.per_pose("fk-batch", "athenakin.fast -> FKSolution")
    lines.append(f"| >= 10,000 x scipy least_squares per pose, 16 solutions instead of 1 | "
                 f"{fmt_ratio(ls / fk)} x (`athenakin.fast -> FKSolution`) | "
                 f"{'yes' if ls / fk >= 1e4 else '**no**'} |")
    return "\n".join(lines)


def render_motion(res: Results) -> str:
    """The tracker and planner costs of docs/motion.md."""
    lines = [f"Measured {res.stamp} (`python benchmarks/run.py --only motion-tracker "
             f"motion-plan`, CPU time of one core):", "",
             "| case | per call | per sample |", "| --- | ---: | ---: |"]
    for g in ("motion-tracker", "motion-plan"):
        for r in res.group(g):
            t, n = float(r["seconds"]), int(r["batch"])
            lines.append(f"| {r['name']} | {fmt_time(t)} | "
                         f"{fmt_time(t / n) if n > 1 else fmt_time(t)} |")
    return "\n".join(lines)


def render_certified(res: Results) -> str:
    """The cost of the certified FK against the float FK (docs/certified.md)."""
    one = res.per_pose("fk-certified", "certified FK, one pose (16 boxes)")
    batch = res.row("fk-certified", "certified FK, batch of seeded poses")
    per = float(batch["seconds"]) / int(batch["batch"])
    fk = res.per_pose("fk-certified", "ak.forward_kinematics, default args (compiled)")
    return (f"Ball arithmetic runs in Python over python-flint: {fmt_time(one)} for one pose "
            f"of 16 slots, {fmt_time(per)} per pose in a batch of {batch['batch']} seeded "
            f"poses, {fmt_ratio(one / fk)}x the compiled float FK of one pose "
            f"({fmt_time(fk)}); the float FK is the one for a control loop "
            f"(`python benchmarks/run.py --only fk-certified`, measured {res.stamp}).")


#: The ROS pipeline's rows quoted in docs/ros.md, with the words of the table.
ROS_ROWS = (
    ("CSV in, track, CSV out", "CSV in, track, CSV out (`athenakin track S.csv -o O.csv`)"),
    ("MCAP in, track, MCAP out (track_recording)",
     "MCAP in, track, MCAP out (`athenakin track R.mcap -o O.mcap`), zstd level {level}"),
    ("MCAP in, track, MCAP out, zstd level 1", "the same, zstd level 1"),
    ("MCAP in, track, MCAP out, lz4", "the same, lz4"),
    ("decode only (read_joint_states)", "decoding only (`read_joint_states`)"),
    ("track only (motion.track)", "tracking only (`motion.track`, compiled)"),
    ("track only, Tracker.update per reading",
     "tracking with `Tracker.update` once per reading (the live API)"),
    ("encode + write only (write_track_log)",
     "encoding and writing only (every topic, zstd level {level})"),
    ("compress only (zstd level {level} of the output)", "zstd level {level} of the output alone"),
    ("compress only (zstd level 1 of the output)", "zstd level 1 of the output alone"),
)
#: Issue 22's target: readings per second end to end, one core.
ROS_TARGET = 200e3


def render_ros_speed(res: Results) -> str:
    """docs/ros.md: the pipeline end to end and its parts, and issue 22's target."""
    r = res.of("ros")
    group = "ros-track"
    level = int(re.search(r"zstd level (-?\d+) \(the default\)",
                          r.row(group, ROS_ROWS[1][0])["note"]).group(1))
    base = r.baseline(group)
    lines = [f"Measured {r.stamp} with {r.command} (CPU time of one core, "
             f"{r.row(group, ROS_ROWS[0][0])['batch']:,} readings; `bytes` = bytes per reading "
             f"of the MCAP written, or compressed in the `alone` rows; `load` = the 1-minute "
             f"load average when the row was measured):", "",
             "| case | readings/s | per reading | vs CSV | bytes | load |",
             "|---|---:|---:|---:|---:|---:|"]
    for name, words in ROS_ROWS:
        row = r.row(group, name.format(level=level))
        per = float(row["seconds"]) / int(row["batch"])
        ratio = "1" if row.get("baseline") else fmt_ratio(base / per)
        load = "n/a" if row.get("load") is None else f"{float(row['load']):.1f}"
        size = re.search(r"; (\d+) B per reading", row.get("note", ""))
        lines.append(f"| {words.format(level=level)} | {fmt_rate(1 / per).replace('/s', '')} | "
                     f"{fmt_time(per)} | {ratio} | {size.group(1) + ' B' if size else ''} | "
                     f"{load} |")
    end = r.per_pose(group, ROS_ROWS[1][0])
    old = r.per_pose(group, ROS_ROWS[2][0])
    met = 1 / end >= ROS_TARGET
    def rate(per: float) -> str:
        return fmt_rate(1 / per).replace("/s", " readings/s")

    before = "also above" if 1 / old >= ROS_TARGET else "below"
    lines += ["", f"Issue 22's target, at least {rate(1 / ROS_TARGET)} end to end on one core: "
              f"**{'met' if met else 'not met'}** in this run, {rate(end)} with the default "
              f"zstd level {level} ({fmt_ratio(base / end)} times the CSV path); {rate(old)} at "
              f"zstd level 1, the level before ({before} the target). On this shared machine the "
              f"figures move from run to run with the other processes' load; the ratios within "
              f"one run are the ones to compare."]
    return "\n".join(lines)


RENDER: dict[str, Callable[[Results], str]] = {
    "motion": render_motion,
    "certified": render_certified,
    "readme-table": render_readme_table,
    "core-table": render_core_table,
    "speed-summary": render_speed_summary,
    "algebraic": render_algebraic,
    "calibration": render_calibration,
    "targets": render_targets,
    "ros-speed": render_ros_speed,
}
#: Regions quoted from a run of its own (:data:`OWN_RUNS`), by region key.
REGION_RUN = {"ros-speed": "ros"}


def load(path: Path = JSON) -> Results:
    """The committed benchmark JSON, with the runs of their own found beside it."""
    own = {k: Results(json.loads(p.read_text())) for k, (p, _, _) in OWN_RUNS.items()
           if p.exists()}
    return Results(json.loads(path.read_text()), own)


def source(key: str, res: Results) -> Results:
    """The results region ``key`` quotes."""
    return res.of(REGION_RUN[key]) if key in REGION_RUN else res


def rewrite(text: str, res: Results) -> str:
    """``text`` with every marked region replaced by what the JSON gives."""
    def one(m: re.Match) -> str:
        key = m.group("key")
        if key not in RENDER:
            raise KeyError(f"unknown benchmark region {key!r} (known: {sorted(RENDER)})")
        # prose wrapped as the pages are; tables as they are
        paragraphs = RENDER[key](res).split("\n\n")
        text = "\n\n".join(
            p if p.startswith("|") else textwrap.fill(p, width=WIDTH, break_long_words=False,
                                                      break_on_hyphens=False)
            for p in paragraphs)
        return f"{m.group(1)}{text}\n{m.group(4)}"
    return _REGION.sub(one, text)


def regions(text: str) -> dict[str, str]:
    """The regions of a page: key -> body (without the markers)."""
    return {m.group("key"): m.group("body") for m in _REGION.finditer(text)}


def run_benchmarks(path: Path = JSON, modules: tuple[str, ...] = MODULES,
                   options: tuple[str, ...] = RUN_OPTIONS) -> None:
    """Run ``benchmarks/run.py`` on ``modules``; add the date and the command."""
    date = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    args = ["benchmarks/run.py", "--only", *modules, *options, "--json", str(path)]
    subprocess.run([sys.executable, *args], cwd=ROOT, check=True)
    add_stamp(path, date, "python " + " ".join(args[:-2]))


def add_stamp(path: Path, date: str, command: str) -> None:
    """Add ``date`` and ``command`` to a JSON written by ``benchmarks/run.py``."""
    data = json.loads(path.read_text())
    data["date"], data["command"] = date, command
    path.write_text(json.dumps(data, indent=1) + "\n")


def main(argv: list[str] | None = None) -> int:
    """Rewrite (or check) the regions; run the benchmarks first with ``--run``."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--run", action="store_true",
                    help="run the benchmarks first, the main run and the runs of their own "
                         "(minutes)")
    ap.add_argument("--run-own", nargs="+", choices=sorted(OWN_RUNS), default=[],
                    help="run only these runs of their own first")
    ap.add_argument("--check", action="store_true",
                    help="write nothing; exit 1 if a page differs from the JSON")
    ap.add_argument("--json", type=Path, default=JSON, help=f"default {JSON.relative_to(ROOT)}")
    args = ap.parse_args(argv)
    if args.run:
        run_benchmarks(args.json)
    for key in sorted(OWN_RUNS) if args.run else args.run_own:
        run_benchmarks(*OWN_RUNS[key])
    res = load(args.json)
    stale = []
    for page in PAGES:
        path = ROOT / page
        old = path.read_text()
        new = rewrite(old, res)
        if new != old:
            stale.append(page)
            if not args.check:
                path.write_text(new)
    verb = "differ from" if args.check else "rewritten from"
    print(f"{', '.join(stale) or 'no page'} {verb} {args.json.name} ({res.data['date']})")
    return 1 if (args.check and stale) else 0


if __name__ == "__main__":
    sys.exit(main())
