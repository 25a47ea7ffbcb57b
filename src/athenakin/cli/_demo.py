"""``athenakin demo``: the 16 FK solutions of the reference configuration and the IK back."""

from __future__ import annotations

import argparse

import numpy as np

from .._dispatch import forward_kinematics, inverse_kinematics
from ..robot import REFERENCE_Q
from ._common import add_design_option, add_json_option, dump_json, fmt, load_robot, table
from ._fk import FK_HEADERS, fk_json, fk_rows


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``demo`` subcommand."""
    p = sub.add_parser("demo", help="FK of the reference configuration (16 solutions) and IK back",
                       description="Forward kinematics of the reference configuration, then the "
                                   "paper-form inverse kinematics of every solution.")
    add_design_option(p)
    add_json_option(p)
    p.set_defaults(func=run, rcm=None, rcm_file=None)


def run(args: argparse.Namespace) -> int:
    """Execute ``demo``."""
    design, T = load_robot(args)
    q = REFERENCE_Q
    sol = forward_kinematics(q, T, design)
    ok = np.flatnonzero(sol.valid)
    q_back, pas = inverse_kinematics(T, sol.u[ok, 2:], design, errors="flag")
    if args.json:
        print(dump_json({"q_m": q, "T_b_e": T, **fk_json(sol),
                         "ik": [{"slot": int(k), "q_m": q_back[i], "mode": int(pas.mode[i]),
                                 "valid": bool(pas.valid[i])} for i, k in enumerate(ok)]}))
        return 0
    np.set_printoptions(precision=6, suppress=True)
    if args.design is None:
        print("athenakin demo: ATHENA reference design and set-up")
    else:                 # the RCM frame is the reference set-up's recipe for this design
        print(f"athenakin demo: design {design.name or '(unnamed)'} from {args.design}, "
              f"RCM frame by the reference set-up's recipe (default_rcm_frame)")
    print(f"design: l1..l5 = {design.lengths.tolist()} m, tool length {design.tool_length} m")
    print(f"RCM frame T_b_e =\n{T}")
    print(f"\nforward kinematics of q = {q.tolist()} m: {int(sol.n_solutions)} solutions")
    print(table(FK_HEADERS, fk_rows(sol)))
    print("\ninverse kinematics (paper form: T_b_e and u3, u4, u5 of each solution -> q)")
    rows = []
    for i, k in enumerate(ok):
        err = np.abs(q_back[i] - q).max()
        rows.append([str(k), f"{int(pas.mode[i]):+d}"] + [fmt(v) for v in q_back[i]]
                    + [f"{err:.1e}"])
    print(table(["slot", "mode", "q1 [m]", "q2 [m]", "q3 [m]", "|q - q_ref|"], rows))
    worst = np.nanmax(np.abs(q_back - q))
    print(f"\nevery solution's IK recovers q to {worst:.1e} m")
    return 0
