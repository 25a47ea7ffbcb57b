"""Run every benchmark case of ``benchmarks/cases_*.py`` and print one table.

Usage::

    python benchmarks/run.py            # full run (a few minutes)
    python benchmarks/run.py --quick    # small batches, short timings (CI: the suite cannot rot)
    python benchmarks/run.py --only fk-batch fk-single --json results.json

Each ``cases_<area>.py`` defines ``cases(quick: bool) -> list[dict]``; a case has
``name``, ``group`` (ratios are computed within a group), ``batch`` (poses per call),
``call`` (zero-argument callable doing one call) and optionally ``baseline`` (the group's
reference) and ``note``. Every case is called once untimed (numba compiles, caches warm),
then timed with ``time.perf_counter`` over enough calls to last ``--min-time`` seconds,
``--repeat`` times; the best repeat is reported (the least disturbed by other processes).

Columns: time per call, per pose, poses per second, ``x base`` = the baseline's time
per pose divided by the case's (how many times faster than the group's baseline), and the
machine's 1-minute load average when the row was measured (a ratio taken under load is a
share of the CPU, not only of the work). Each row is printed as soon as it is measured
(the baseline of a group is measured before the rest of its group).

Single-core figures: the script limits BLAS to one thread and sets numba's thread count to
1 for every case whose name does not say ``parallel``; those get all cores (OpenMP workers
sleep between calls: ``OMP_WAIT_POLICY=PASSIVE``). The header
states the machine, its core count and load average (shared machines skew timings).

Why not asv or pytest-benchmark: the table has to put athenakin and its peers side by
side, with ratios, from one process and in one run (asv times one project across commits;
pytest-benchmark compares within a test session but has no notion of poses per call or of
a baseline per group). This runner is 200 lines, has no dependency and is what CI runs.
"""

from __future__ import annotations

import argparse
import glob
import importlib.util
import json
import os
import platform
import sys
import time
import traceback

for _var in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
# numba's OpenMP workers must sleep between parallel regions: spinning workers steal the
# second core from the single-core cases, and on a loaded machine a region can then wait
# for a scheduler tick (12 ms per call measured here with the default policy).
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

HERE = os.path.dirname(os.path.abspath(__file__))


def load_cases(quick: bool, only: list[str] | None, skip: list[str] | None = None
               ) -> tuple[list[dict], list[str]]:
    """Import every cases_*.py next to this file and collect their cases (``only`` those
    groups or modules; not the ``skip`` ones)."""
    cases: list[dict] = []
    errors: list[str] = []
    if HERE not in sys.path:
        sys.path.insert(0, HERE)
    for path in sorted(glob.glob(os.path.join(HERE, "cases_*.py"))):
        mod_name = os.path.splitext(os.path.basename(path))[0]
        try:
            spec = importlib.util.spec_from_file_location(f"_bench_{mod_name}", path)
            mod = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(mod)
            for c in mod.cases(quick):
                missing = {"name", "group", "batch", "call"} - set(c)
                if missing:
                    raise ValueError(f"case {c.get('name')!r} lacks {sorted(missing)}")
                c = dict(c, module=mod_name)
                if skip and (c["group"] in skip or mod_name in skip):
                    continue
                if only is None or c["group"] in only or mod_name in only:
                    cases.append(c)
        except Exception:
            errors.append(f"{mod_name}: {traceback.format_exc(limit=3)}")
    return cases, errors


#: The clock of :func:`measure`: wall time, or with ``--cpu-time`` this process's CPU time
#: (on a shared, overloaded machine the wall time counts the other processes' time slices;
#: CPU time sums over threads, so it understates nothing for one core but overstates the
#: ``parallel`` cases).
_clock = time.perf_counter


def measure(call, min_time: float, repeat: int) -> float:
    """Best time per call (s) over ``repeat`` runs of enough calls to last ``min_time``."""
    t0 = _clock()
    call()
    once = _clock() - t0
    number = max(1, int(min_time / max(once, 1e-9)))
    while True:
        t0 = _clock()
        for _ in range(number):
            call()
        dt = _clock() - t0
        if dt >= 0.2 * min_time or number >= 1 << 24:
            break
        number *= 4
    best = dt / number
    for _ in range(repeat - 1):
        t0 = _clock()
        for _ in range(number):
            call()
        best = min(best, (_clock() - t0) / number)
    return best


def _fmt_time(s: float) -> str:
    for unit, f in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6), ("ns", 1e-9)):
        if s >= f or unit == "ns":
            return f"{s / f:.3g} {unit}"
    return f"{s:.3g} s"


def _fmt_rate(r: float) -> str:
    for unit, f in (("G", 1e9), ("M", 1e6), ("k", 1e3), ("", 1.0)):
        if r >= f or unit == "":
            return f"{r / f:.3g} {unit}/s".replace(" /s", "/s")
    return f"{r:.3g}/s"


def machine_line() -> str:
    try:
        load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:
        load = "n/a"
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    import numpy

    try:
        import numba
        nb = numba.__version__
    except ImportError:
        nb = "n/a"
    return (f"{cpu}, {os.cpu_count()} cores, load average {load}; Python "
            f"{platform.python_version()}, numpy {numpy.__version__}, numba {nb}")


def _load1() -> float | None:
    try:
        return os.getloadavg()[0]
    except OSError:
        return None


def baseline_first(cases: list[dict]) -> list[dict]:
    """The cases in their order, each group's baseline moved before the group's first case
    (so that every row can be printed with its ratio as soon as it is measured)."""
    first_base = {}
    for c in cases:
        if c.get("baseline"):
            first_base.setdefault(c["group"], c)
    out, seen = [], set()
    for c in cases:
        b = first_base.get(c["group"])
        for x in (b, c):
            if x is not None and id(x) not in seen:
                seen.add(id(x))
                out.append(x)
    return out


def format_row(r: dict, base_per_pose: float | None) -> str:
    """One table row; sets ``r["ratio"]`` (None for the baseline or without one)."""
    load = "" if r.get("load") is None else f"{r['load']:.1f}"
    if r["error"] is not None:
        r["ratio"] = None
        return (f"| {r['group']} | {r['name']} | {r['batch']} | ERROR | | | | {load} | "
                f"{r['error'][:80]} |")
    per_pose = r["seconds"] / r["batch"]
    b = base_per_pose
    ratio = "base" if r.get("baseline") else (f"{b / per_pose:,.3g}" if b else "")
    r["ratio"] = None if ratio in ("", "base") else b / per_pose
    return (f"| {r['group']} | {r['name']} | {r['batch']} | {_fmt_time(r['seconds'])} | "
            f"{_fmt_time(per_pose)} | {_fmt_rate(1.0 / per_pose)} | {ratio} | {load} | "
            f"{r.get('note', '')} |")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="small batches and short timings")
    ap.add_argument("--only", nargs="*", help="groups or cases_<area> module names to run")
    ap.add_argument("--skip", nargs="*", help="groups or cases_<area> module names not to run "
                                              "(named in the header line)")
    ap.add_argument("--min-time", type=float, default=None, help="seconds per timing")
    ap.add_argument("--repeat", type=int, default=None, help="timings per case (best kept)")
    ap.add_argument("--json", help="also write the results to this JSON file")
    ap.add_argument("--cpu-time", action="store_true",
                    help="time with this process's CPU time (shared, overloaded machines)")
    args = ap.parse_args(argv)
    global _clock
    _clock = time.process_time if args.cpu_time else time.perf_counter
    min_time = args.min_time if args.min_time is not None else (0.01 if args.quick else 0.3)
    repeat = args.repeat if args.repeat is not None else (2 if args.quick else 5)

    try:
        import numba
        n_threads = numba.config.NUMBA_NUM_THREADS
    except ImportError:
        numba, n_threads = None, 1
    print(f"# athenakin benchmarks{' (quick)' if args.quick else ''}"
          f"{' (CPU time)' if args.cpu_time else ''}: {machine_line()}"
          f"{'; skipped: ' + ', '.join(args.skip) if args.skip else ''}")
    cases, errors = load_cases(args.quick, args.only, args.skip)
    print("| group | case | batch | per call | per pose | poses/s | x base | load | note |\n"
          "|---|---|---:|---:|---:|---:|---:|---:|---|", flush=True)
    rows = []
    base: dict[str, float] = {}
    for c in baseline_first(cases):
        par = "parallel" in c["name"].lower()
        if numba is not None:
            numba.set_num_threads(n_threads if par else 1)
        try:
            t = measure(c["call"], min_time, repeat)
            r = dict(c, seconds=t, error=None, load=_load1())
        except Exception as exc:
            r = dict(c, seconds=float("nan"), error=f"{type(exc).__name__}: {exc}", load=_load1())
            errors.append(f"{c['module']}/{c['name']}: {traceback.format_exc(limit=3)}")
        if r.get("baseline") and r["error"] is None:
            base[r["group"]] = r["seconds"] / r["batch"]
        rows.append(r)
        print(format_row(r, base.get(r["group"])), flush=True)
    if numba is not None:
        numba.set_num_threads(n_threads)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"machine": machine_line(), "quick": args.quick,
                       "rows": [{k: v for k, v in r.items() if k != "call"} for r in rows],
                       "errors": errors}, fh, indent=1, default=str)
    for e in errors:
        print(f"\nERROR in {e}", file=sys.stderr)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
