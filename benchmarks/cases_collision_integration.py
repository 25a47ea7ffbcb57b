"""Benchmark cases of the collision check wherever a pose is made (issue 20, item 4).

Groups (each a ratio against its peer without the check, in the same run; the run's
header prints the machine load, os.getloadavg):

* ``collision-tracker``: cost per encoder sample of :meth:`athenakin.motion.Tracker.update`
  with the default bodies (the tracker places the bodies from its pose and calls the
  capsule kernel once), against the same stream without the check (baseline); and of
  :func:`athenakin.motion.track` with the check (one batch of ``collision.clearance``).
* ``collision-plan``: ``plan`` of the 20 mm square at 1 kHz with the clearance of every
  sample, against the same plan without it (baseline); batch = samples.
* ``collision-cone``: ``instrument_cone`` with the collision-free layer against the cone
  alone (baseline); batch = grid points.
"""

import numpy as np
from cases_motion import SQUARE, _replay  # the same path and replay as the motion group

import athenakin as ak
from athenakin.analysis import instrument_cone
from athenakin.motion import PlanOptions, Tracker, plan, track


def cases(quick: bool) -> list[dict]:
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    n = 200 if quick else 2000
    gap = np.linspace(0.2, 0.12, n)
    stream = np.stack([-gap / 2, gap / 2, np.full(n, 0.45)], -1)
    rows = [tuple(r) for r in stream.tolist()]
    n_plan = len(plan(SQUARE, T, d).t)
    res = (12, 9, 8) if quick else (36, 19, 16)
    n_cone = int(np.prod(res))
    return [
        {"name": "Tracker.update, no collision check", "group": "collision-tracker",
         "batch": n, "baseline": True, "call": _replay(Tracker(T, d, q0=rows[0]), rows[0], rows)},
        {"name": "Tracker.update, default bodies", "group": "collision-tracker", "batch": n,
         "call": _replay(Tracker(T, d, q0=rows[0], clearance_margin=0.0), rows[0], rows),
         "note": "points from the pose, one kernel call per sample"},
        {"name": "track(stream), default bodies (one batch)", "group": "collision-tracker",
         "batch": n, "call": lambda: track(stream, T, d, clearance_margin=0.0)},
        {"name": "plan 20 mm square, 1 kHz", "group": "collision-plan", "batch": n_plan,
         "baseline": True, "call": lambda: plan(SQUARE, T, d)},
        {"name": "plan 20 mm square, 1 kHz, clearance of every sample",
         "group": "collision-plan", "batch": n_plan,
         "call": lambda: plan(SQUARE, T, d, options=PlanOptions(clearance_margin=0.0))},
        {"name": "instrument_cone", "group": "collision-cone", "batch": n_cone,
         "baseline": True, "call": lambda: instrument_cone(T, d, resolution=res)},
        {"name": "instrument_cone with the collision-free layer", "group": "collision-cone",
         "batch": n_cone, "call": lambda: instrument_cone(T, d, resolution=res,
                                                          clearance_margin=0.0)},
    ]
