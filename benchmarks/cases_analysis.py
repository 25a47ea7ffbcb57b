"""Benchmark cases of athenakin.analysis: Jacobians, singularity reports, workspace grids.

Groups: ``analysis-jacobian`` (per-pose cost of the analytic Jacobians; baseline: central
finite differences of the core forward kinematics, 6 FK calls), ``analysis-singularities``
and ``analysis-workspace`` (grid throughput).
"""

import numpy as np

import athenakin as ak
from athenakin.analysis import (
    instrument_cone,
    parallel_jacobian,
    point_workspace,
    singularities,
    tool_tip_jacobian,
)
from athenakin.testing import random_configurations


def _fd_parallel_jacobian(q, mode, design, eps=1e-7):
    def f(x):
        par = ak.parallel.parallel_forward_kinematics(x, design)
        return np.where((mode == 1)[:, None], par.O_s[:, 0], par.O_s[:, 1])

    cols = [(f(q + eps * e) - f(q - eps * e)) / (2 * eps) for e in np.eye(3)]
    return np.stack(cols, axis=-1)


def cases(quick: bool) -> list[dict]:
    d = ak.Design.default()
    n = 2_000 if quick else 100_000
    rc = random_configurations(n, d, rng=1)
    q, m, T = rc.q, rc.mode, rc.T_b_e
    res = 21 if quick else 61
    return [
        {"name": "parallel_jacobian (analytic)", "group": "analysis-jacobian", "batch": n,
         "call": lambda: parallel_jacobian(q, d, m)},
        {"name": "parallel Jacobian by central differences of FK", "group": "analysis-jacobian",
         "batch": n, "baseline": True, "call": lambda: _fd_parallel_jacobian(q, m, d),
         "note": "6 batched parallel FK calls"},
        {"name": "tool_tip_jacobian (analytic)", "group": "analysis-jacobian", "batch": n,
         "call": lambda: tool_tip_jacobian(q, T, d, mode=m)},
        {"name": "singularities, parallel only", "group": "analysis-singularities", "batch": n,
         "baseline": True, "call": lambda: singularities(q, None, d, mode=m)},
        {"name": "singularities, whole robot", "group": "analysis-singularities", "batch": n,
         "call": lambda: singularities(q, T, d, mode=m)},
        {"name": f"point_workspace {res}^3", "group": "analysis-workspace", "batch": res ** 3,
         "baseline": True,
         "call": lambda: point_workspace(design=d, resolution=res, progress=False)},
        {"name": f"instrument_cone {res}x{res // 2}x{res // 2}", "group": "analysis-workspace",
         "batch": res * (res // 2) ** 2,
         "call": lambda: instrument_cone(None, d, resolution=(res, res // 2, res // 2),
                                         progress=False)},
    ]
