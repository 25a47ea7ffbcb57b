"""Set-up planning on the shipped phantom: the time to a set-up that covers the target.

Run from the repository root (the machine's load is printed beside every figure)::

    python benchmarks/bench_setup.py [--population 16] [--generations 8] [--polish 3] [--seed 0]
    python benchmarks/bench_setup.py --compare-polish [0.85 0.9833 1.0167 1.15]

The target (docs/setup.md): a set-up covering >= 95 % of the pancreas with every margin
>= 5 mm (singularity length conditions, clearance of the bodies) and 0 colliding
configurations, found within 120 s on a 2-core machine. Printed: the time of the whole
search, the time at which the first generation holding such a set-up was done, and the
baseline of the same run, one evaluation of the reference guess on the same samples
(the ratio: how many evaluations the search cost). ``--compare-polish``: phantoms of the
given sizes planned with ``polish=0`` and with ``--polish``, each seeded as the cohort of
``scripts/setup_figures.py --cohort 10`` seeds its phantom of that size; the chosen
set-ups' figures side by side.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from athenakin.design import Design
from athenakin.synthesis import (
    SetupOptions,
    evaluate_setup,
    phantom,
    plan_setup,
    reference_decision,
    setup_from_decision,
)


def _load() -> str:
    a, b, c = os.getloadavg()
    return f"load {a:.2f} / {b:.2f} / {c:.2f} on {os.cpu_count()} cores"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--population", type=int, default=16)
    ap.add_argument("--generations", type=int, default=8)
    ap.add_argument("--polish", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--compare-polish", type=float, nargs="*", default=None, metavar="SIZE")
    args = ap.parse_args()
    if args.compare_polish is not None:
        compare_polish(args.compare_polish or [0.85, 0.98333, 1.01667, 1.15], args)
        return
    patient, design, opts = phantom(), Design.default(), SetupOptions()
    guess = setup_from_decision(patient, reference_decision(patient, design,
                                                            yaw=np.radians(270), roll=0.4))
    P = patient.target_samples(opts.samples, seed=args.seed)
    evaluate_setup(patient, guess, design, points=P, options=opts,
                   collision_samples=opts.collision_samples)          # warm (numba, coal)
    t0 = time.perf_counter()
    evaluate_setup(patient, guess, design, points=P, options=opts,
                   collision_samples=opts.collision_samples)
    base = time.perf_counter() - t0
    print(f"baseline: one candidate ({opts.samples} samples, {opts.collision_samples} "
          f"clearance checks) {base:.3f} s ({_load()})", flush=True)
    t0 = time.perf_counter()
    plan = plan_setup(patient, design=design, population=args.population,
                      generations=args.generations, polish=args.polish, seed=args.seed,
                      options=opts)
    total = time.perf_counter() - t0
    f = plan.figures
    ok = (f["coverage"] >= 0.95 and f["margin_min"] >= 0.005 and f["min_clearance"] >= 0.005
          and f["collisions"] == 0)
    t = plan.table
    good = t[(t["coverage"] >= 0.95) & (t["margin_min"] >= 0.005)
             & (t["min_clearance"] >= 0.005) & (t["collisions"] == 0)]
    first = float(good["seconds"].min()) if len(good) else float("nan")
    print(f"search: {args.population} x {args.generations} set-ups and {args.polish} polish "
          f"rounds ({len(t)} set-ups) in {total:.1f} s "
          f"({total / base:.0f} x the baseline; {_load()})")
    print(f"first generation with a set-up >= 95 % covered, margins >= 5 mm, 0 collisions: "
          f"{first:.1f} s ({first / base:.0f} x the baseline)")
    print(f"chosen set-up on {opts.final_samples} fresh samples: coverage "
          f"{100 * f['coverage']:.2f} %, least clearance {1000 * f['min_clearance']:.1f} mm, "
          f"least margin {1000 * f['margin_min']:.1f} mm, collisions {int(f['collisions'])}: "
          f"{'meets' if ok else 'misses'} the target; within 120 s: {total <= 120.0} "
          f"({_load()})")


def compare_polish(sizes: list[float], args: argparse.Namespace) -> None:
    """Each phantom size planned without and with the compass polish."""
    cohort = np.linspace(0.85, 1.15, 10)                 # the docs' cohort and its seeds
    for size in sizes:
        seed = int(np.argmin(np.abs(cohort - size)))
        p = phantom(size=size)
        for polish in (0, args.polish):
            t0 = time.perf_counter()
            plan = plan_setup(p, population=args.population, generations=args.generations,
                              polish=polish, seed=seed, scheduler="synchronous")
            f = plan.figures
            print(f"size {size:.3f} (seed {seed}) polish {polish}: coverage "
                  f"{100 * f['coverage']:.1f} %, least clearance "
                  f"{1000 * f['min_clearance']:.1f} mm, least margin "
                  f"{1000 * f['margin_min']:.1f} mm, {len(plan.table)} set-ups, "
                  f"{time.perf_counter() - t0:.0f} s ({_load()})", flush=True)


if __name__ == "__main__":
    main()
