"""Dask scale-out of a design study, measured with its CPU times (not only a wall-clock ratio).

Usage::

    python benchmarks/dask_scaleout.py            # 48 designs x 1e5 samples, 1 and 2 workers
    python benchmarks/dask_scaleout.py --quick    # 8 designs x 1e4 samples (CI: cannot rot)

A wall-clock speed-up of N workers over 1 on a shared machine is partly a share of the CPU
(a second process gets its own time slices from the other jobs), so this script reports,
for a ``distributed.LocalCluster`` of 1 and of 2 single-threaded worker processes and for
plain processes (``concurrent.futures.ProcessPoolExecutor``, the ceiling without Dask):

* the wall time of the study and the machine's load average beside every speed-up;
* each worker's CPU time during the study (``time.process_time`` in the worker, its event
  loop and heartbeats included) and the efficiency ``sum(worker CPU) / (workers x wall)``;
* the per-task overhead: the wall time of a round trip of no-op tasks through the
  scheduler (``client.map`` + ``gather``), per task;
* the client's CPU time per chunk (building the graph, receiving and assembling results);
* an Amdahl extrapolation to 100 and 1,000 workers: per chunk, the serial part ``s`` (the
  client's CPU per chunk plus the per-task overhead) and the parallel part ``w`` (a
  worker's CPU per chunk); for a study of ``M`` chunks on ``N`` workers,
  ``T(N) = M s + ceil(M / N) w``, printed for ``M = 10 N`` (enough chunks to fill the
  workers) as the speed-up ``T(1) / T(N)``, and the ceiling ``(s + w) / s``; and the chunk
  size (designs) at which 100 or 1,000 workers would run at 50% efficiency.

Every cluster is warmed first (imports, numba's cache) and every study uses a new seed, so
nothing comes from a cache. Prints one line per measurement as it finishes.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

import athenakin as ak
from athenakin.synthesis import StudyOptions, Task, evaluate, evaluate_design


def _task() -> Task:
    T = ak.default_rcm_frame()
    return Task(rcm=T[:3, 3], axis=T[:3, 0], half_angle=np.radians(25.0), depth=(0.2, 0.3))


def _designs(n: int) -> list:
    ref = ak.Design.default()
    rng = np.random.default_rng(0)
    return [ak.Design(l1=0.30 * s[0], l2=0.10 * s[1], l3=0.25 * s[2], l4=0.15 * s[3],
                      l5=0.40 * s[4], q_min=ref.q_min, q_max=ref.q_max)
            for s in rng.uniform(0.9, 1.1, (n, 5))]


def _cpu() -> float:
    return time.process_time()


def _noop(x: int) -> int:
    return x


def _warm() -> None:
    evaluate_design(ak.Design.default(), _task(), samples=100, seed=0)


def _chunk(args: tuple) -> float:
    """One chunk in a plain process: its designs evaluated; returns the process's CPU time."""
    designs, samples, seed = args
    for k, d in enumerate(designs):
        evaluate_design(d, _task(), samples=samples, seed=seed + k)
    return time.process_time()


def _load() -> str:
    return f"load {os.getloadavg()[0]:.1f}"


def run_cluster(n_workers: int, designs: list, samples: int, n_chunks: int,
                seed: int) -> dict:
    from distributed import Client, LocalCluster

    cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                           host="127.0.0.1", dashboard_address="127.0.0.1:0", silence_logs=50)
    client = Client(cluster, set_as_default=False)
    try:
        client.wait_for_workers(n_workers)
        client.run(_warm)
        evaluate(designs[:2], _task(), samples=100, seed=0, scheduler=client,
                 options=StudyOptions(progress=False, chunk_size=1))   # the client's path, warm
        n_noop = 200
        client.gather(client.map(_noop, range(20), pure=False))          # warm the path
        t0 = time.perf_counter()
        client.gather(client.map(_noop, range(n_noop), pure=False))
        per_task = (time.perf_counter() - t0) / n_noop
        cpu0 = client.run(_cpu)
        c0, t0 = _cpu(), time.perf_counter()
        evaluate(designs, _task(), samples=samples, seed=seed, scheduler=client,
                 options=StudyOptions(progress=False, chunk_size=max(1, len(designs) // n_chunks)))
        wall, client_cpu = time.perf_counter() - t0, _cpu() - c0
        cpu1 = client.run(_cpu)
        worker_cpu = [cpu1[k] - cpu0[k] for k in cpu0]
    finally:
        client.close()
        cluster.close()
    return {"wall": wall, "worker_cpu": worker_cpu, "client_cpu": client_cpu,
            "per_task": per_task, "load": os.getloadavg()[0]}


def run_processes(n_proc: int, designs: list, samples: int, n_chunks: int, seed: int) -> dict:
    size = max(1, len(designs) // n_chunks)
    chunks = [(designs[i:i + size], samples, seed + i) for i in range(0, len(designs), size)]
    with ProcessPoolExecutor(n_proc) as ex:
        start = list(ex.map(_chunk, [([ak.Design.default()], 100, 0)] * n_proc))  # warm
        t0 = time.perf_counter()
        ends = list(ex.map(_chunk, chunks))
        wall = time.perf_counter() - t0
    return {"wall": wall, "cpu_end": ends, "cpu_start": start, "load": os.getloadavg()[0]}


def amdahl(s: float, w: float, n: int) -> float:
    """Speed-up ``T(1) / T(n)`` of ``M = 10 n`` chunks, serial ``s`` and parallel ``w`` each."""
    m = 10 * n
    return (m * s + m * w) / (m * s + math.ceil(m / n) * w)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="8 designs x 1e4 samples")
    args = ap.parse_args(argv)
    n_designs, samples, n_chunks = (8, 10_000, 8) if args.quick else (48, 100_000, 8)
    designs = _designs(n_designs)
    print(f"# Dask scale-out: {n_designs} designs x {samples} samples in {n_chunks} chunks; "
          f"{os.cpu_count()} cores, {_load()}", flush=True)
    res = {}
    for n in (1, 2):
        r = run_cluster(n, designs, samples, n_chunks, seed=100 + n)
        res[n] = r
        cpu = ", ".join(f"{c:.2f}" for c in r["worker_cpu"])
        eff = sum(r["worker_cpu"]) / (n * r["wall"])
        print(f"LocalCluster {n} worker(s): wall {r['wall']:.2f} s; worker CPU [{cpu}] s "
              f"(efficiency {eff:.0%}); client CPU {r['client_cpu']:.3f} s "
              f"({1e3 * r['client_cpu'] / n_chunks:.1f} ms per chunk); per-task overhead "
              f"{1e3 * r['per_task']:.2f} ms; load {r['load']:.1f}", flush=True)
    speed = res[1]["wall"] / res[2]["wall"]
    print(f"speed-up 2 workers / 1 (wall): {speed:.2f}x, load {res[2]['load']:.1f}; by CPU "
          f"time (the busiest worker's CPU against one worker's): "
          f"{sum(res[1]['worker_cpu']) / max(res[2]['worker_cpu']):.2f}x", flush=True)
    for n in (1, 2):
        p = run_processes(n, designs, samples, n_chunks, seed=200 + n)
        res[f"p{n}"] = p
        print(f"plain processes x{n}: wall {p['wall']:.2f} s; load {p['load']:.1f}", flush=True)
    print(f"speed-up 2 processes / 1 (wall): {res['p1']['wall'] / res['p2']['wall']:.2f}x, "
          f"load {res['p2']['load']:.1f}", flush=True)
    r = res[1]
    w = sum(r["worker_cpu"]) / n_chunks                    # a worker's CPU per chunk
    s = r["client_cpu"] / n_chunks + r["per_task"]         # serial part per chunk
    print(f"Amdahl per chunk: serial {1e3 * s:.1f} ms (client CPU + per-task overhead), "
          f"parallel {1e3 * w:.1f} ms (worker CPU); serial fraction {s / (s + w):.2%}; "
          f"speed-up at 100 workers {amdahl(s, w, 100):.0f}x, at 1,000 workers "
          f"{amdahl(s, w, 1000):.0f}x (ceiling {(s + w) / s:.0f}x); chunks of "
          f"{n_designs // n_chunks} designs x {samples} samples", flush=True)
    w1 = w / max(1, n_designs // n_chunks)                 # a worker's CPU per design
    for n in (100, 1000):       # chunk size for half the workers' worth: f = 1 / (n - 1)
        k = math.ceil(s * (n - 2) / w1)
        print(f"for {n} workers at 50% efficiency (speed-up {n // 2}x), chunks of about {k} "
              f"designs ({k * w1:.0f} s of a worker's CPU each), at least {n} chunks "
              f"(Amdahl: serial fraction 1 / (n - 1))", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
