"""Benchmark cases of the certified forward kinematics (athenakin.certified).

Group ``fk-certified``: all 16 slots of one pose with rigorous enclosures (python-flint
ball arithmetic) against the floating-point FK of the same pose (numpy reference, the
baseline) and the pure-Python FK. Target: at most 2 ms per pose for the certified FK
at default precision on one core.
"""

from __future__ import annotations

import os
import sys

import numpy as np

import athenakin as ak
from athenakin.testing import random_configurations

sys.path.insert(0, os.path.dirname(__file__))
import baselines as bl  # noqa: E402


def cases(quick: bool) -> list[dict]:
    from athenakin.certified import certified_forward_kinematics

    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    q1 = np.array(ak.robot.REFERENCE_Q)
    n = 10 if quick else 200
    cfg = random_configurations(n, d, rng=11)
    dt = bl.DesignTuple(d)
    return [
        {"name": "athenakin numpy reference FK (floats)", "group": "fk-certified", "batch": 1,
         "baseline": True, "call": lambda: ak.robot.forward_kinematics(q1, T, d)},
        {"name": "ak.forward_kinematics, default args (compiled)", "group": "fk-certified",
         "batch": 1, "call": lambda: ak.forward_kinematics(q1, T, d)},
        {"name": "pure Python FK (math module)", "group": "fk-certified", "batch": 1,
         "call": lambda: bl.fk_python(q1.tolist(), T.tolist(), dt)},
        {"name": "certified FK, one pose (16 boxes)", "group": "fk-certified", "batch": 1,
         "call": lambda: certified_forward_kinematics(q1, T, d),
         "note": "target <= 2 ms per pose"},
        {"name": "certified FK, batch of seeded poses", "group": "fk-certified", "batch": n,
         "call": lambda: certified_forward_kinematics(cfg.q, cfg.T_b_e, d),
         "note": "one RCM frame per pose"},
        {"name": "certified FK, exact input (input_tol=0)", "group": "fk-certified",
         "batch": 1, "call": lambda: certified_forward_kinematics(q1, T, d, input_tol=0.0)},
    ]
