"""``athenakin fk``: the 16 forward-kinematics solutions of one actuator triple."""

from __future__ import annotations

import argparse

import numpy as np

from .._dispatch import forward_kinematics
from ..errors import Reason
from ..robot import FKSolution
from ._common import (
    add_design_option,
    add_json_option,
    add_setup_options,
    dump_json,
    fmt,
    load_design,
    load_rcm,
    table,
)


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``fk`` subcommand."""
    p = sub.add_parser("fk", help="forward kinematics: all 16 solutions for q1 q2 q3",
                       description="All (up to) 16 configurations for actuator values q (m).")
    p.add_argument("q", nargs=3, type=float, metavar="Q",
                   help="actuators q1 q2 q3, m (negative values are fine: -0.1)")
    add_design_option(p)
    add_setup_options(p)
    add_json_option(p)
    p.set_defaults(func=run)


def fk_rows(sol: FKSolution) -> list[list[str]]:
    """Table rows, one per slot, angles in degrees."""
    rows = []
    for k in range(16):
        deg = np.degrees(sol.u[k])
        status = "ok" if sol.valid[k] else Reason(int(sol.reason[k])).name
        rows.append([str(k), f"{int(sol.mode[k]):+d}", f"{int(sol.p_sign[k]):+d}",
                     f"{int(sol.ujoint[k]):+d}", f"{int(sol.wrist[k]):+d}", status,
                     fmt(sol.p[k])] + [fmt(a, 3) for a in deg]
                    + ["-" if not np.isfinite(sol.residual[k]) else f"{sol.residual[k]:.1e}"]
                    + [fmt(x) for x in sol.tip[k]])
    return rows


FK_HEADERS = ["slot", "mode", "p+-", "U", "S", "status", "p [m]", "u1 [deg]", "u2 [deg]",
              "u3 [deg]", "u4 [deg]", "u5 [deg]", "residual", "tip x [m]", "tip y [m]",
              "tip z [m]"]


def fk_json(sol: FKSolution) -> dict:  # type: ignore[type-arg]
    """JSON-ready dict of an unbatched solution (degrees; tip and ``T_b_tip`` in the base frame)."""
    return {"n_solutions": int(sol.n_solutions), "solutions": [
        {"slot": k, "valid": bool(sol.valid[k]), "reason": Reason(int(sol.reason[k])).name,
         "mode": int(sol.mode[k]), "p_sign": int(sol.p_sign[k]), "ujoint": int(sol.ujoint[k]),
         "wrist": int(sol.wrist[k]), "p_m": sol.p[k], "u_deg": np.degrees(sol.u[k]),
         "residual": sol.residual[k], "O_s_m": sol.T_b_s[k, :3, 3], "tip_m": sol.tip[k],
         "T_b_tip": sol.T_b_tip[k]} for k in range(16)]}


def run(args: argparse.Namespace) -> int:
    """Execute ``fk``."""
    design = load_design(args)
    T = load_rcm(args, design)
    sol = forward_kinematics(np.array(args.q), T, design)
    if args.json:
        print(dump_json({"q_m": args.q, "T_b_e": T, **fk_json(sol)}))
    else:
        print(f"forward kinematics, q = {args.q} m: {int(sol.n_solutions)} solutions")
        print(table(FK_HEADERS, fk_rows(sol)))
    return 0
