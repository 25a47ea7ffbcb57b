"""``athenakin ik``: actuator values from the spherical-joint angles, a direction or a tool tip."""

from __future__ import annotations

import argparse

import numpy as np

from .._dispatch import inverse_kinematics, q_from_instrument, q_from_tool_tip
from ..design import Design
from ..errors import KinematicsError
from ..robot import direction_from_angles
from ._common import (
    add_json_option,
    add_robot_options,
    dump_json,
    fmt,
    load_robot,
    mm_hint,
    with_hint,
)
from ._warmup import one_shot_backend


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``ik`` subcommand."""
    p = sub.add_parser(
        "ik", help="inverse kinematics: q from u3 u4 u5, a direction + p, or a tool tip",
        description="Unique actuator values q for the RCM frame and one of: the spherical-joint "
                    "angles (paper form), an instrument direction (azimuth, polar about z_e, "
                    "deg) with insertion p (m), or a tool-tip point in frame E (m).")
    g = p.add_mutually_exclusive_group(required=True)
    g.add_argument("--u345", nargs=3, type=float, metavar=("U3", "U4", "U5"),
                   help="spherical-joint angles, deg")
    g.add_argument("--direction", nargs=2, type=float, metavar=("AZIMUTH", "POLAR"),
                   help="instrument direction in E, deg (needs --p)")
    g.add_argument("--tip", nargs=3, type=float, metavar=("X", "Y", "Z"),
                   help="tool-tip point in frame E, m")
    p.add_argument("--p", type=float, help="distance O_s -> RCM, m (with --direction)")
    add_robot_options(p)
    add_json_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Execute ``ik``."""
    if args.p is not None and args.direction is None:
        given = "--tip" if args.tip is not None else "--u345"
        raise ValueError(f"--p goes with --direction only; {given} sets the insertion itself "
                         f"(drop --p)")
    design, T = load_robot(args)
    try:
        out = _solve(args, design, T)
    except KinematicsError as exc:
        hint = (mm_hint(np.linalg.norm(args.tip), design, "|tip|") if args.tip is not None
                else mm_hint(args.p, design, "p") if args.p is not None else "")
        raise with_hint(exc, hint) from None
    return _print(args, out)


def _solve(args: argparse.Namespace, design: Design, T: np.ndarray) -> dict:  # type: ignore[type-arg]
    if args.u345 is not None:
        q, pas = inverse_kinematics(T, np.radians(args.u345), design,
                                    backend=one_shot_backend())
        out = {"form": "paper (u3, u4, u5)", "q_m": q, "mode": int(pas.mode), "p_m": pas.p,
               "u_deg": np.degrees(pas.u), "residual": pas.residual}
    else:
        if args.direction is not None:
            if args.p is None:
                raise ValueError("--direction needs --p (distance O_s -> RCM, m)")
            d_e = direction_from_angles(*np.radians(args.direction))
            q, res = q_from_instrument(T, d_e, args.p, design, backend=one_shot_backend())
            form = "instrument direction + p"
        else:
            q, res = q_from_tool_tip(T, np.array(args.tip), design, backend=one_shot_backend())
            form = "tool tip"
        out = {"form": form, "q_m": q, "mode": int(res.mode), "p_m": res.p,
               "direction_b": res.direction_b, "O_s_m": res.O_s}
    return out


def _print(args: argparse.Namespace, out: dict) -> int:  # type: ignore[type-arg]
    if args.json:
        print(dump_json(out))
        return 0
    print(f"inverse kinematics ({out['form']})")
    print(f"  q = ({', '.join(fmt(v) for v in out['q_m'])}) m, assembly mode {out['mode']:+d}")
    print(f"  p = {fmt(float(out['p_m']))} m")
    if "u_deg" in out:
        print(f"  u1..u5 = ({', '.join(fmt(v, 3) for v in out['u_deg'])}) deg, "
              f"closure residual {float(out['residual']):.1e}")
    else:
        print(f"  O_s = ({', '.join(fmt(v) for v in out['O_s_m'])}) m (base)")
    return 0
