"""Benchmark cases of the core kinematics: athenakin's paths against the peers a user would pick.

Groups (ratios are per pose, against the group's baseline):

* ``fk-batch``: all 16 FK solutions of a batch of poses (one RCM frame). Baseline: the
  straightforward per-pose pure-Python implementation (``baselines.fk_python``). Also:
  the public function with default arguments (``ak.forward_kinematics(q, T, d)``: the
  compiled kernels; batches of 2e5 poses, with only ``p, u, valid`` and with the full
  result), athenakin's numpy reference (``backend="numpy"``), the compiled paths
  (FKSolution; reused output arrays; a counting sweep without per-pose output),
  ``scipy.optimize.least_squares`` (one solution per pose) and Pinocchio's serial forward
  map (the easier direction, one pose at a time from Python).
* ``fk-single``: one pose per call from Python (latency).
* ``ik-batch`` / ``ik-single``: the paper-form IK (``u3, u4, u5`` -> ``q``) and the
  controller form ``q_from_tool_tip``; baseline: the pure-Python paper form. In
  ``ik-batch-frames`` every pose has its own RCM frame (a batch of ``T_b_e``), against
  the same pure-Python loop over its frames (target >= 380x).
* ``fk-loop`` / ``ik-loop``: the public single call (``ak.forward_kinematics(q, T, d)``,
  ``ak.inverse_kinematics(T, u345, d)``) against ``fast.ControlLoop``'s (preallocated,
  raw arrays); ``x base`` >= 0.5 is "within 2x of the control loop".
"""

from __future__ import annotations

import os
import sys

import numpy as np

import athenakin as ak
import athenakin.testing  # noqa: F401  (ak.testing)
from athenakin import fast

sys.path.insert(0, os.path.dirname(__file__))
import baselines as bl  # noqa: E402


def cases(quick: bool) -> list[dict]:
    d = ak.Design.default()
    dt = bl.DesignTuple(d)
    T = ak.default_rcm_frame(d)
    Tl = T.tolist()
    n = 2_000 if quick else 4_000           # compiled / numpy batches (results stay in cache)
    n_big = 4_000 if quick else 50_000      # a batch whose results do not fit in cache
    n_py = 50 if quick else 1_000           # pure-Python loops
    n_ls = 3 if quick else 50               # scipy least_squares
    n_sweep = 200_000 if quick else 10_000_000
    n_2e5 = 20_000 if quick else 200_000    # the issue-11 batch size
    rng = np.random.default_rng(2024)
    q = rng.uniform(d.stroke_min, d.stroke_max, (n, 3))
    q_big = rng.uniform(d.stroke_min, d.stroke_max, (n_big, 3))
    q_2e5 = rng.uniform(d.stroke_min, d.stroke_max, (n_2e5, 3))
    q_py = q[:n_py].tolist()
    q1 = np.array(ak.robot.REFERENCE_Q)
    q1_list = q1.tolist()
    ref1 = ak.forward_kinematics(q1, T, d)
    rc = ak.testing.random_configurations(max(n, n_ls), d, rng=5)
    u345 = ak.forward_kinematics(q, T, d).u[:, 0, 2:]
    u345 = np.where(np.isnan(u345), ref1.u[0, 2:], u345)
    u345_py = u345[:n_py].tolist()
    u1 = np.array(ref1.u[0, 2:])
    u345_2e5 = np.resize(u345, (n_2e5, 3))
    puv = ("p", "u", "valid")
    tips = rng.uniform(-0.15, 0.15, (n, 3)) + [0.2, 0.0, 0.0]
    tips_py = tips[:n_py].tolist()
    tip1 = np.array([0.25, 0.0, 0.0])
    x0 = np.c_[rc.p, rc.u][:n_ls] + rng.uniform(-0.1, 0.1, (n_ls, 6))
    model, data, joint = bl.pinocchio_ups_model()
    xs = np.c_[rc.u[:n, :2], rc.p[:n], rc.u[:n, 2:]]
    ctl = fast.ControlLoop(T, d)
    out = fast.forward_kinematics(q, T, d)
    # one RCM frame per pose: the frames and u345 of random valid configurations
    T_each = np.ascontiguousarray(rc.T_b_e[:n])
    u_each = np.ascontiguousarray(rc.u[:n, 2:])
    each_py = [(T_each[i].tolist(), u_each[i].tolist()) for i in range(n_py)]

    def draw(a, b):
        return np.random.default_rng(a).uniform(d.stroke_min, d.stroke_max, (b - a, 3))

    def loop(f, items):
        def call():
            for it in items:
                f(it)
        return call

    return [
        # --- FK, batch -------------------------------------------------------------------
        {"name": "pure Python per pose (math module)", "group": "fk-batch", "batch": n_py,
         "baseline": True, "call": loop(lambda x: bl.fk_python(x, Tl, dt), q_py)},
        {"name": "athenakin numpy reference", "group": "fk-batch", "batch": n,
         "call": lambda: ak.forward_kinematics(q, T, d, backend="numpy")},
        {"name": "ak.forward_kinematics, default args", "group": "fk-batch", "batch": n,
         "call": lambda: ak.forward_kinematics(q, T, d)},
        {"name": "ak.forward_kinematics, default args, 2e5 poses", "group": "fk-batch",
         "batch": n_2e5, "call": lambda: ak.forward_kinematics(q_2e5, T, d),
         "note": "target >= 5 M/s; 1.2 KiB/pose to fresh pages"},
        {"name": "ak.forward_kinematics, fields=(p, u, valid), 2e5 poses",
         "group": "fk-batch", "batch": n_2e5,
         "call": lambda: ak.forward_kinematics(q_2e5, T, d, fields=puv),
         "note": "target >= 8 M/s; 784 B/pose"},
        {"name": "athenakin.fast -> FKSolution", "group": "fk-batch", "batch": n,
         "call": lambda: fast.forward_kinematics(q, T, d),
         "note": "allocates 1.2 KiB/pose of results"},
        {"name": "athenakin.fast -> FKSolution, large batch", "group": "fk-batch",
         "batch": n_big, "call": lambda: fast.forward_kinematics(q_big, T, d),
         "note": "memory-bound: 1.2 KiB/pose written to fresh pages"},
        {"name": "athenakin.fast, out= (arrays reused)", "group": "fk-batch", "batch": n,
         "call": lambda: fast.forward_kinematics(q, T, d, out=out)},
        {"name": "athenakin.fast, out=, parallel=True", "group": "fk-batch", "batch": n,
         "call": lambda: fast.forward_kinematics(q, T, d, out=out, parallel=True),
         "note": "all cores"},
        {"name": "athenakin.fast.sweep_fk (counts only)", "group": "fk-batch",
         "batch": n_sweep,
         "call": lambda: fast.sweep_fk(draw, T, d, n=n_sweep, progress=False),
         "note": "incl. drawing q; bounded memory"},
        {"name": "athenakin.fast.sweep_fk, parallel=True", "group": "fk-batch",
         "batch": n_sweep,
         "call": lambda: fast.sweep_fk(draw, T, d, n=n_sweep, progress=False, parallel=True),
         "note": "all cores"},
        {"name": "scipy least_squares on closure eqs", "group": "fk-batch", "batch": n_ls,
         "call": loop(lambda i: bl.fk_least_squares(rc.q[i], rc.T_b_e[i], d, x0[i]),
                      range(n_ls)),
         "note": "1 solution per pose (guess-dependent)"},
        {"name": "Pinocchio serial forward map, loop", "group": "fk-batch", "batch": n_py,
         "call": loop(lambda x: bl.pinocchio_fk(model, data, joint, x), xs[:n_py]),
         "note": "easier problem: (p,u)->T_s_e, 1 solution"},
        # --- FK, one pose per call ---------------------------------------------------------
        {"name": "pure Python (math module)", "group": "fk-single", "batch": 1,
         "baseline": True, "call": lambda: bl.fk_python(q_py[0], Tl, dt)},
        {"name": "athenakin numpy reference", "group": "fk-single", "batch": 1,
         "call": lambda: ak.forward_kinematics(q1, T, d, backend="numpy"),
         "note": "the no-numba fallback; target <= 60 us"},
        {"name": "ak.forward_kinematics(q, T, d), default args", "group": "fk-single",
         "batch": 1, "call": lambda: ak.forward_kinematics(q1, T, d),
         "note": "target <= 4 us"},
        {"name": "athenakin.fast -> FKSolution", "group": "fk-single", "batch": 1,
         "call": lambda: fast.forward_kinematics(q1, T, d)},
        {"name": "athenakin.fast.ControlLoop.fk (raw arrays)", "group": "fk-single",
         "batch": 1, "call": lambda: ctl.fk(q1), "note": "target <= 5 us"},
        {"name": "scipy least_squares on closure eqs", "group": "fk-single", "batch": 1,
         "call": lambda: bl.fk_least_squares(rc.q[0], rc.T_b_e[0], d, x0[0]),
         "note": "1 solution"},
        {"name": "Pinocchio serial forward map", "group": "fk-single", "batch": 1,
         "call": lambda: bl.pinocchio_fk(model, data, joint, xs[0]),
         "note": "easier problem, 1 solution"},
        # --- IK, batch -------------------------------------------------------------------
        {"name": "pure Python per pose, paper form", "group": "ik-batch", "batch": n_py,
         "baseline": True,
         "call": loop(lambda x: bl.ik_python(Tl, x, dt), u345_py)},
        {"name": "athenakin numpy reference, paper form", "group": "ik-batch", "batch": n,
         "call": lambda: ak.inverse_kinematics(T, u345, d, backend="numpy")},
        {"name": "ak.inverse_kinematics, default args, 2e5 poses", "group": "ik-batch",
         "batch": n_2e5, "call": lambda: ak.inverse_kinematics(T, u345_2e5, d),
         "note": "target >= 25 M/s"},
        {"name": "athenakin.fast, paper form", "group": "ik-batch", "batch": n,
         "call": lambda: fast.inverse_kinematics(T, u345, d)},
        {"name": "athenakin.fast, paper form, parallel=True", "group": "ik-batch", "batch": n,
         "call": lambda: fast.inverse_kinematics(T, u345, d, parallel=True),
         "note": "all cores"},
        {"name": "pure Python per pose, q_from_tool_tip", "group": "ik-batch", "batch": n_py,
         "call": loop(lambda x: bl.q_from_tool_tip_python(Tl, x, dt), tips_py)},
        {"name": "athenakin numpy reference, q_from_tool_tip", "group": "ik-batch",
         "batch": n,
         "call": lambda: ak.q_from_tool_tip(T, tips, d, errors="flag", backend="numpy")},
        {"name": "ak.q_from_tool_tip, default args", "group": "ik-batch", "batch": n,
         "call": lambda: ak.q_from_tool_tip(T, tips, d, errors="flag")},
        {"name": "athenakin.fast, q_from_tool_tip", "group": "ik-batch", "batch": n,
         "call": lambda: fast.q_from_tool_tip(T, tips, d, errors="flag")},
        {"name": "athenakin.fast, q_from_tool_tip, parallel=True", "group": "ik-batch",
         "batch": n, "call": lambda: fast.q_from_tool_tip(T, tips, d, errors="flag",
                                                          parallel=True),
         "note": "all cores"},
        {"name": "pure Python per pose, paper form, its own frame", "group": "ik-batch-frames",
         "batch": n_py, "baseline": True,
         "call": loop(lambda x: bl.ik_python(x[0], x[1], dt), each_py)},
        {"name": "ak.inverse_kinematics, one RCM frame per pose", "group": "ik-batch-frames",
         "batch": n, "call": lambda: ak.inverse_kinematics(T_each, u_each, d),
         "note": "target >= 380x"},
        {"name": "athenakin numpy reference, one RCM frame per pose",
         "group": "ik-batch-frames", "batch": n,
         "call": lambda: ak.inverse_kinematics(T_each, u_each, d, backend="numpy")},
        # --- single calls against the control loop ------------------------------------------
        {"name": "athenakin.fast.ControlLoop.fk (raw arrays)", "group": "fk-loop", "batch": 1,
         "baseline": True, "call": lambda: ctl.fk(q1)},
        {"name": "ak.forward_kinematics(q, T, d)", "group": "fk-loop", "batch": 1,
         "call": lambda: ak.forward_kinematics(q1, T, d),
         "note": "target x base >= 0.5 (within 2x)"},
        {"name": "ak.forward_kinematics(list q, T, d)", "group": "fk-loop", "batch": 1,
         "call": lambda: ak.forward_kinematics(q1_list, T, d)},
        {"name": "athenakin.fast.ControlLoop.ik (raw)", "group": "ik-loop", "batch": 1,
         "baseline": True, "call": lambda: ctl.ik(u1)},
        {"name": "ak.inverse_kinematics(T, u345, d)", "group": "ik-loop", "batch": 1,
         "call": lambda: ak.inverse_kinematics(T, u1, d),
         "note": "target x base >= 0.5 (within 2x)"},
        # --- IK, one item per call -------------------------------------------------------------
        {"name": "pure Python, paper form", "group": "ik-single", "batch": 1, "baseline": True,
         "call": lambda: bl.ik_python(Tl, u345_py[0], dt)},
        {"name": "athenakin numpy reference, paper form", "group": "ik-single", "batch": 1,
         "call": lambda: ak.inverse_kinematics(T, u1, d, backend="numpy")},
        {"name": "ak.inverse_kinematics(T, u345, d), default args", "group": "ik-single",
         "batch": 1, "call": lambda: ak.inverse_kinematics(T, u1, d),
         "note": "target <= 1.5 us"},
        {"name": "ak.q_from_tool_tip(T, tip, d), default args", "group": "ik-single",
         "batch": 1, "call": lambda: ak.q_from_tool_tip(T, tip1, d),
         "note": "target <= 1.5 us"},
        {"name": "athenakin.fast, paper form", "group": "ik-single", "batch": 1,
         "call": lambda: fast.inverse_kinematics(T, u1, d)},
        {"name": "athenakin.fast.ControlLoop.ik (raw)", "group": "ik-single", "batch": 1,
         "call": lambda: ctl.ik(u1), "note": "target <= 2 us"},
        {"name": "athenakin.fast.ControlLoop.q_from_tool_tip", "group": "ik-single",
         "batch": 1, "call": lambda: ctl.q_from_tool_tip(tip1), "note": "target <= 2 us"},
        {"name": "athenakin.fast.q_from_tool_tip", "group": "ik-single", "batch": 1,
         "call": lambda: fast.q_from_tool_tip(T, tip1, d)},
    ]
