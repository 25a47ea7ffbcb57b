"""Benchmark cases of athenakin.synthesis: the cost of one design, and scale-out on Dask.

Groups:

* ``synthesis-design``: every metric of one design over 1e5 task samples
  (:func:`athenakin.synthesis.evaluate_design`; target: well under 0.1 s per design on
  one core). Batch = task samples, so "per call" is the per-design cost. Baseline: the
  compiled controller-form IK alone on the same samples (the least any study must pay).
* ``synthesis-scale``: designs per second through :func:`athenakin.synthesis.evaluate`
  on a ``distributed.LocalCluster`` of 1 and of 2 single-threaded worker processes
  (loopback). Batch = designs per call; "x base" of the 2-worker case is the speed-up
  over 1 worker (target >= 1.7 on an idle 2-core machine). The clusters start on the
  first (untimed) call and stop at exit; every call uses a new seed, so no result is
  served from the cluster's memory.
* ``synthesis-threads``: the same study on Dask's local schedulers, no cluster: the
  default threaded scheduler (all cores) against ``"synchronous"`` (one thread). The
  compiled kernels release the GIL (``nogil=True``), so threads compute in parallel;
  "x base" is the speed-up of the default over one thread (about 1.5-1.8 expected on an
  idle 2-core machine; the Python and numpy parts still take turns).
"""

import atexit
import itertools

import numpy as np

import athenakin as ak
from athenakin.synthesis import StudyOptions, Task, evaluate, evaluate_design, sample_task

_CLUSTERS: dict[int, object] = {}
_SEEDS = itertools.count(1)


def _task() -> Task:
    T = ak.default_rcm_frame()
    return Task(rcm=T[:3, 3], axis=T[:3, 0], half_angle=np.radians(25.0), depth=(0.2, 0.3))


def _warm() -> None:
    evaluate_design(ak.Design.default(), _task(), samples=100, seed=0)


def _client(n_workers: int):
    if n_workers not in _CLUSTERS:
        from distributed import Client, LocalCluster

        cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                               host="127.0.0.1", dashboard_address="127.0.0.1:0", silence_logs=50)
        client = Client(cluster, set_as_default=False)
        client.wait_for_workers(n_workers)
        client.run(_warm)                     # every worker imports and loads the kernels
        _CLUSTERS[n_workers] = (cluster, client)
        atexit.register(lambda: (client.close(), cluster.close()))
    return _CLUSTERS[n_workers][1]


def _designs(n: int) -> list:
    ref = ak.Design.default()
    rng = np.random.default_rng(0)
    out = []
    for s in rng.uniform(0.9, 1.1, (n, 5)):
        out.append(ak.Design(l1=0.30 * s[0], l2=0.10 * s[1], l3=0.25 * s[2], l4=0.15 * s[3],
                             l5=0.40 * s[4], q_min=ref.q_min, q_max=ref.q_max))
    return out


def _study(n_workers: int, designs: list, task: Task, samples: int):
    def call():
        evaluate(designs, task, samples=samples, seed=next(_SEEDS), scheduler=_client(n_workers),
                 options=StudyOptions(progress=False,   # 8 chunks: 4 per worker of 2
                                      chunk_size=max(1, len(designs) // 8)))
    return call


def _local(scheduler, designs: list, task: Task, samples: int):
    def call():
        evaluate(designs, task, samples=samples, seed=next(_SEEDS), scheduler=scheduler,
                 options=StudyOptions(progress=False, chunk_size=max(1, len(designs) // 8)))
    return call


def cases(quick: bool) -> list[dict]:
    d = ak.Design.default()
    task = _task()
    n = 10_000 if quick else 100_000
    s = sample_task(task, n, seed=0)
    T = task.T_b_e
    p = d.tool_length - s.depth
    n_designs = 8 if quick else 48
    scale_samples = 10_000 if quick else 100_000
    designs = _designs(n_designs)
    return [
        {"name": "compiled IK alone (q_from_instrument, numba)", "group": "synthesis-design",
         "batch": n, "baseline": True,
         "call": lambda: ak.q_from_instrument(T, s.direction_e, p, d, errors="flag",
                                              backend="numba")},
        {"name": "evaluate_design: every metric", "group": "synthesis-design", "batch": n,
         "call": lambda: evaluate_design(d, task, samples=n, seed=0),
         "note": "per call = per design; target well under 0.1 s"},
        {"name": "evaluate on LocalCluster, 1 worker", "group": "synthesis-scale",
         "batch": n_designs, "baseline": True,
         "call": _study(1, designs, task, scale_samples),
         "note": f"{scale_samples} samples per design; poses/s = designs/s"},
        {"name": "evaluate on LocalCluster, 2 workers", "group": "synthesis-scale",
         "batch": n_designs, "call": _study(2, designs, task, scale_samples),
         "note": "x base = speed-up over 1 worker (target >= 1.7)"},
        {"name": "evaluate, Dask local scheduler 'synchronous' (one thread)",
         "group": "synthesis-threads", "batch": n_designs, "baseline": True,
         "call": _local("synchronous", designs, task, scale_samples),
         "note": f"{scale_samples} samples per design; poses/s = designs/s"},
        {"name": "evaluate, Dask's default threaded scheduler (all cores)",
         "group": "synthesis-threads", "batch": n_designs,
         "call": _local(None, designs, task, scale_samples),
         "note": "x base = speed-up of the threads (the kernels release the GIL)"},
    ]
