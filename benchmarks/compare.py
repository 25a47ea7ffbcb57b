"""Compare two checkouts of athenakin case by case: is any benchmark slower after a change?

Usage::

    git worktree add --detach /tmp/old 6c198b4
    python benchmarks/compare.py --old /tmp/old                 # this checkout is the new one
    python benchmarks/compare.py --old /tmp/old --only cases_core cases_ros --quick

Each ``cases_<area>.py`` module is run by each checkout's own ``benchmarks/run.py`` (its own
cases, its own ``src`` on ``PYTHONPATH``), old and new alternately and ``--rounds`` times
(the order flips every round), so that a change of the machine's load hits both sides
alike; a case's time is the best of its rounds. The table gives, per case present in
both, the old and new time per call and ``new/old`` (above 1: slower), with the 1-minute
load average of the two runs beside it: a ratio taken under load is noisier than one
taken on a quiet machine, never more favourable. Cases that exist on one side only are
listed apart. ``--json`` writes every figure.
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def run_module(tree: str, module: str, quick: bool, extra: list[str]) -> dict[str, dict]:
    """Run ``module``'s cases with ``tree``'s run.py and src; ``{case name: row}``."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "r.json")
        env = dict(os.environ, PYTHONPATH=os.path.join(tree, "src"))
        cmd = [sys.executable, os.path.join(tree, "benchmarks", "run.py"), "--only", module,
               "--json", out, *(["--quick"] if quick else []), *extra]
        proc = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=tree)
        if not os.path.exists(out):
            sys.stderr.write(f"{tree} {module}: no results\n{proc.stdout}\n{proc.stderr}\n")
            return {}
        with open(out) as fh:
            rows = json.load(fh)["rows"]
    return {r["name"]: r for r in rows if r.get("error") is None and r.get("seconds")}


def main(argv: list[str] | None = None) -> int:
    """Run the comparison and print the table; exit 1 if a case is slower than allowed."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--old", required=True, help="checkout of the old version")
    ap.add_argument("--new", default=ROOT, help="checkout of the new version (default: this)")
    ap.add_argument("--only", nargs="*", help="cases_<area> modules (default: every one)")
    ap.add_argument("--quick", action="store_true", help="run.py's quick mode")
    ap.add_argument("--rounds", type=int, default=2, help="old/new runs per module")
    ap.add_argument("--limit", type=float, default=1.10, help="largest new/old allowed")
    ap.add_argument("--json", help="write the comparison to this file")
    args, extra = ap.parse_known_args(argv)
    modules = args.only or sorted(os.path.splitext(os.path.basename(p))[0]
                                  for p in glob.glob(os.path.join(args.new, "benchmarks",
                                                                  "cases_*.py")))
    print(f"# benchmarks, old {args.old} vs new {args.new}; load average at start "
          f"{', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print("| module | case | old per call | new per call | new/old | load old | load new |")
    print("|---|---|---:|---:|---:|---:|---:|", flush=True)
    table, slower, only_one = [], [], []
    for module in modules:
        best: dict[str, dict[str, dict]] = {"old": {}, "new": {}}
        for k in range(args.rounds):
            order = ("old", "new") if k % 2 == 0 else ("new", "old")
            for side in order:
                rows = run_module(getattr(args, side), module, args.quick, extra)
                for name, r in rows.items():
                    if name not in best[side] or r["seconds"] < best[side][name]["seconds"]:
                        best[side][name] = r
        old, new = best["old"], best["new"]
        only_one += [f"{module}/{n} (old only)" for n in old if n not in new]
        only_one += [f"{module}/{n} (new only)" for n in new if n not in old]
        for name in [n for n in new if n in old]:
            o, n = old[name], new[name]
            ratio = n["seconds"] / o["seconds"]
            row = {"module": module, "case": name, "old": o["seconds"], "new": n["seconds"],
                   "ratio": ratio, "load_old": o.get("load"), "load_new": n.get("load")}
            table.append(row)
            if ratio > args.limit:
                slower.append(row)
            print(f"| {module} | {name} | {o['seconds']:.4g} s | {n['seconds']:.4g} s | "
                  f"{ratio:.3f} | {o.get('load') or 0:.1f} | {n.get('load') or 0:.1f} |",
                  flush=True)
    if only_one:
        print("\ncases on one side only: " + ", ".join(only_one))
    print(f"\n{len(table)} cases compared, {len(slower)} slower than {args.limit:g}x "
          f"(load average at end {', '.join(f'{x:.2f}' for x in os.getloadavg())})")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"old": args.old, "new": args.new, "rows": table,
                       "one_side": only_one}, fh, indent=1)
    return 1 if slower else 0


if __name__ == "__main__":
    raise SystemExit(main())
