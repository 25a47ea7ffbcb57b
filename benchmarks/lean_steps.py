"""Where the time of a public single call goes: the lean FK / IK cut after each step.

Usage::

    python benchmarks/lean_steps.py [--rounds 7]

``ak.forward_kinematics(q, T, d)`` and ``ak.inverse_kinematics(T, u345, d)`` take the
lean path of :mod:`athenakin.fast._api` (``lean_fk`` / ``lean_ik``). This script
compiles copies of those two functions that return right after each step (the guard's
parts, the result's arrays, the kernel, the result object), times each copy, and prints
the increments in ns beside :class:`athenakin.fast.ControlLoop`'s time for the same
pose (the ``fk-loop`` / ``ik-loop`` groups of ``cases_core.py``) and the machine load.
Each figure is the best of ``--rounds`` rounds of 3 x 10,000 calls; a step's increment
includes freeing what it made.
"""

from __future__ import annotations

import argparse
import inspect
import os
import timeit

import numpy as np

import athenakin as ak
from athenakin import fast
from athenakin.fast import _api

#: (label, first source line not run) of each cut, in order.
FK_STEPS = [("entry (a call with 10 arguments)", "if fields is not None or not (method"),
            ("option checks", "qa = _lean_inputs("),
            ("q and T_b_e checks", "hit = _LAST     # read once"),
            ("design look-up", "= fk_one_outputs()"),
            ("6 result arrays", "if _fk_one_lean("),
            ("kernel (numba's dispatcher)", "obj = _object_new(FKSolution)")]
IK_STEPS = [("entry (a call with 7 arguments)", "if fields is not None or not (errors"),
            ("option checks", "Ua = _lean_inputs("),
            ("u345 and T_b_e checks", "hit = _LAST     # read once"),
            ("design look-up", "fbuf = _empty(_one.ONE_F)"),
            ("3 result buffers", "if _ik_paper_lean("),
            ("kernel (numba's dispatcher)", "obj = _object_new(PassiveJoints)")]


def cuts(fn, steps):
    """Copies of ``fn`` returning None before each step's first line (after the warm-up)."""
    lines = inspect.getsource(fn).splitlines()
    out = []
    for label, first in steps:
        idx = [i for i, line in enumerate(lines) if first in line]
        if not idx:
            raise SystemExit(f"lean_steps: {fn.__name__} has no line {first!r} any more; "
                             "update FK_STEPS / IK_STEPS")
        ns = dict(fn.__globals__)
        src = "\n".join(lines[:idx[0]] + ["    return None"])
        exec(src.replace(f"def {fn.__name__}(", "def _cut("), ns)  # noqa: S102 (own source)
        out.append((label, ns["_cut"]))
    return out


def best(cases, rounds):
    r = {k: [] for k, _ in cases}
    for _ in range(rounds):
        for k, f in cases:
            r[k].append(min(timeit.repeat(f, number=10_000, repeat=3)) / 10_000 * 1e9)
    return {k: min(v) for k, v in r.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=7)
    rounds = ap.parse_args().rounds
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    q = np.array(ak.robot.REFERENCE_Q)
    u = np.array(ak.forward_kinematics(q, T, d).u[0, 2:])
    ctl = fast.ControlLoop(T, d)
    for _ in range(2):             # compile / load the kernels
        ak.forward_kinematics(q, T, d)
        ak.inverse_kinematics(T, u, d)
    fk = [(lab, lambda f=f: f(q, T, d)) for lab, f in cuts(_api.lean_fk, FK_STEPS)]
    fk += [("result object (= fast._api.lean_fk)", lambda: _api.lean_fk(q, T, d)),
           ("dispatch (= ak.forward_kinematics)", lambda: ak.forward_kinematics(q, T, d))]
    ik = [(lab, lambda f=f: f(T, u, d)) for lab, f in cuts(_api.lean_ik, IK_STEPS)]
    ik += [("result object (= fast._api.lean_ik)", lambda: _api.lean_ik(T, u, d)),
           ("dispatch (= ak.inverse_kinematics)", lambda: ak.inverse_kinematics(T, u, d))]
    for name, cases, base in (("forward_kinematics", fk, ("ControlLoop.fk", lambda: ctl.fk(q))),
                              ("inverse_kinematics", ik, ("ControlLoop.ik", lambda: ctl.ik(u)))):
        load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
        t = best([*cases, base], rounds)
        print(f"\n{name} (load {load})\n| step | + ns | total ns |\n|---|---:|---:|")
        prev = 0.0
        for k, _ in cases:
            print(f"| {k} | {t[k] - prev:+.0f} | {t[k]:.0f} |")
            prev = t[k]
        print(f"| [{base[0]}] | | {t[base[0]]:.0f} |")
        print(f"ratio ControlLoop / public call: {t[base[0]] / prev:.3f} (target >= 0.5)")


if __name__ == "__main__":
    main()
