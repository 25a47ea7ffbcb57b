"""Benchmark cases of athenakin.motion: the streaming tracker and the planner.

Groups:

* ``motion-tracker``: cost per encoder sample of :meth:`athenakin.motion.Tracker.update`
  from Python (target: under 20 us, i.e. a 1 kHz loop with a wide margin). Each call
  feeds a recorded stream of ``batch`` readings one at a time, so the per-sample
  figure is ``time / batch``. Baseline: the core 16-solution forward kinematics of one
  reading (what a tracker without a fast path would call every sample).
* ``motion-plan``: planning a 20 mm square about the RCM at 1 kHz (batch = samples).
"""

import numpy as np

import athenakin as ak
from athenakin.motion import PlanOptions, Tracker, plan

SQUARE = np.array([[0.25, 0.0, 0.0], [0.27, -0.02, 0.0], [0.27, -0.02, 0.02],
                   [0.25, 0.0, 0.02], [0.25, 0.0, 0.0]])


def _replay(tracker, q0, stream):
    def call():
        tracker.reset(q0)
        for q in stream:
            tracker.update(q)
    return call


def cases(quick: bool) -> list[dict]:
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    traj = plan(SQUARE, T, d, options=PlanOptions(j_max=5.0))
    n = 1000 if quick else len(traj.q)
    smooth = [tuple(r) for r in traj.q[:n].tolist()]
    g = ak.parallel.circle_geometry(np.array([-0.1, 0.1, 0.3]), d)
    q3 = float(g["d"] - g["r1"]) + np.geomspace(0.004, 1e-9, n)
    boundary = [(-0.1, 0.1, float(v)) for v in q3]
    q_one = traj.q[n // 2]
    return [
        {"name": "Tracker.update, smooth stream (fast path)", "group": "motion-tracker",
         "batch": n, "call": _replay(Tracker(T, d, q0=smooth[0]), smooth[0], smooth),
         "note": "per sample: time / batch; target < 20 us"},
        {"name": "Tracker.update, next to the mode boundary (all 16 candidates)",
         "group": "motion-tracker", "batch": n,
         "call": _replay(Tracker(T, d, q0=boundary[0]), boundary[0], boundary),
         "note": "half-chord below the watch margin: slow path every sample"},
        {"name": "core forward_kinematics of one reading (16 solutions)",
         "group": "motion-tracker", "batch": 1, "baseline": True,
         "call": lambda: ak.forward_kinematics(q_one, T, d)},
        {"name": "plan 20 mm square, 1 kHz, jerk-limited", "group": "motion-plan",
         "batch": len(traj.t), "baseline": True,
         "call": lambda: plan(SQUARE, T, d, options=PlanOptions(j_max=5.0))},
        {"name": "plan 20 mm square, 1 kHz, acceleration-limited", "group": "motion-plan",
         "batch": len(traj.t), "call": lambda: plan(SQUARE, T, d)},
    ]
