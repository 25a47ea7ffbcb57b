"""How long the compiled kernels take to compile on a cold numba cache, kernel by kernel.

Run from the repository root (the load is printed beside the figures)::

    python benchmarks/bench_compile.py [--top 15]

A fresh process per run, with ``NUMBA_CACHE_DIR`` a new temporary folder, runs
``athenakin warmup``'s entry points (FK, IK, Jacobians, the control loop's tool-tip
Jacobians), the bodies' clearance, the dynamics (the batch and ``InverseDynamicsLoop``), a
batched tracker and ``Teleop.step`` with its bodies: what a user's first session compiles.
numba's documented compile events (``numba.core.event``, ``"numba:compile"``) time each
kernel; a kernel's time excludes the kernels compiled inside it (its callees). The
baseline, in the same process, is the compile of one trivial kernel (numba's fixed cost a
kernel): each figure is also given as a multiple of it.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile

from _machine import load_text

#: The child's program: compile everything, print one line per kernel (seconds, count, name).
CHILD = r"""
import collections, time
import numba.core.event as ev
records = []
class Listener(ev.Listener):
    def on_start(self, e):
        records.append((True, time.perf_counter(), e.data["dispatcher"].py_func))
    def on_end(self, e):
        records.append((False, time.perf_counter(), e.data["dispatcher"].py_func))
ev.register("numba:compile", Listener())
import numba
import numpy as np
t0 = time.perf_counter()
numba.njit(lambda x: x + 1.0)(1.0)
baseline = time.perf_counter() - t0
records.clear()
import athenakin as ak
from athenakin._dispatch import warmup
T = ak.default_rcm_frame()
q = np.array([[-0.10, 0.10, 0.45], [-0.11, 0.09, 0.46]])
t0 = time.perf_counter()
warmup()
ctl = ak.fast.ControlLoop(T)
ctl.tool_tip_jacobian(q[0]); ctl.tool_tip_inverse_jacobian(q[0])
ak.collision.clearance(q, T); ak.collision.clearance(q, T, witness=False)
z = np.zeros_like(q)
ak.dynamics.inverse_dynamics(q, z, z, T)
ak.dynamics.InverseDynamicsLoop(T)(q[0], z[0], z[0])
ak.motion.track(q, T)
tele = ak.teleop.Teleop(T, q0=q[0], bodies=ak.collision.Bodies.default())
for k in range(3):
    tele.step(k * 1e-3, [1e-4 * k, 0.0, 0.0])
total = time.perf_counter() - t0
stack, own, count = [], collections.Counter(), collections.Counter()
for start, t, f in records:
    name = f.__module__.removeprefix("athenakin.") + "." + f.__qualname__
    if start:
        if stack:
            own[stack[-1][0]] += t - stack[-1][1]
        stack.append([name, t])
        count[name] += 1
    else:
        name, t_start = stack.pop()
        own[name] += t - t_start
        if stack:
            stack[-1][1] = t
print(f"baseline {baseline:.4f}")
print(f"total {total:.4f} {sum(count.values())}")
for name, s in own.most_common():
    print(f"kernel {s:.4f} {count[name]} {name}")
"""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--top", type=int, default=15, help="kernels listed (the slowest first)")
    args = ap.parse_args()
    print(f"# cold-cache compile of the kernels of a first session ({load_text()})")
    with tempfile.TemporaryDirectory(prefix="athenakin-bench-compile-") as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        env["PYTHONPATH"] = os.pathsep.join(
            [os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "src"),
             env.get("PYTHONPATH", "")])
        out = subprocess.run([sys.executable, "-c", CHILD], env=env, capture_output=True,
                             text=True, check=False)
    if out.returncode != 0:
        print(out.stderr[-3000:], file=sys.stderr)
        return 1
    lines = [ln.split(maxsplit=3) for ln in out.stdout.splitlines()]
    baseline = float(next(ln[1] for ln in lines if ln[0] == "baseline"))
    total, n = next((float(ln[1]), int(ln[2])) for ln in lines if ln[0] == "total")
    kernels = [(float(ln[1]), int(ln[2]), ln[3]) for ln in lines if ln[0] == "kernel"]
    by_area: dict[str, float] = {}
    for s, _, name in kernels:
        area = name.split(".")[0]
        by_area[area] = by_area.get(area, 0.0) + s
    print(f"baseline (one trivial kernel): {baseline * 1e3:.0f} ms")
    print(f"total: {total:.1f} s for {n} compiles ({total / baseline:.0f} x baseline)")
    print("by area: " + ", ".join(f"{a} {s:.1f} s" for a, s in
                                  sorted(by_area.items(), key=lambda kv: -kv[1])))
    print("| kernel | compiles | s (own) | x baseline |")
    print("|---|---|---|---|")
    for s, c, name in kernels[:args.top]:
        print(f"| {name} | {c} | {s:.2f} | {s / baseline:.0f} |")
    print(f"# done ({load_text()})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
