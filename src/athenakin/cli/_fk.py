"""``athenakin fk``: the 16 forward-kinematics solutions of one actuator triple."""

from __future__ import annotations

import argparse

import numpy as np

from .._dispatch import forward_kinematics
from ..certified import CertifiedFK, CertStatus
from ..design import Design
from ..errors import KinematicsError, Reason
from ..robot import FKSolution
from ._common import (
    add_json_option,
    add_robot_options,
    dump_json,
    fmt,
    load_robot,
    mm_hint,
    table,
    with_hint,
)
from ._warmup import one_shot_backend


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``fk`` subcommand."""
    p = sub.add_parser("fk", help="forward kinematics: all 16 solutions for q1 q2 q3",
                       description="All (up to) 16 configurations for actuator values q (m).")
    p.add_argument("q", nargs=3, type=float, metavar="Q",
                   help="actuators q1 q2 q3, m (negative values are fine: -0.1)")
    add_robot_options(p)
    add_json_option(p)
    p.add_argument("--certify", action="store_true",
                   help="prove the solutions: rigorous enclosures of p and u1..u5 per slot and "
                        "a proof of their count (ball arithmetic, extra [certified])")
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


def certified_rows(cert: CertifiedFK) -> list[list[str]]:
    """Table rows of a certificate, one per slot: status, then midpoint +- half-width.

    ``p`` in m, angles in degrees in ``fk``'s range (-180, 180]: a box that reaches
    -180 deg is shown about +180 deg (the same angles); the half-width is rounded up so
    that the printed interval contains the certified box.
    """
    def box(lo: float, hi: float, scale: float = 1.0, angle: bool = False) -> str:
        if not np.isfinite(lo):
            return "-"
        mid, half = 0.5 * (lo + hi) * scale, 0.5 * (hi - lo) * scale
        if angle and mid - half <= -180.0:    # the box reaches -180 deg: show it about 180
            mid += 360.0
        elif angle and mid - half > 180.0:
            mid -= 360.0
        return f"{mid:.12f} +- {np.nextafter(half * (1 + 1e-15), np.inf):.1e}"

    rows = []
    for k in range(16):
        status = CertStatus(int(cert.status[k])).name
        if cert.status[k] not in (CertStatus.CERTIFIED, CertStatus.NONFINITE_INPUT):
            status += f" ({Reason(int(cert.reason[k])).name})"
        rows.append([str(k), status, box(cert.p_lo[k], cert.p_hi[k])]
                    + [box(cert.u_lo[k, j], cert.u_hi[k, j], 180.0 / np.pi, angle=True)
                       for j in range(5)])
    return rows


CERTIFIED_HEADERS = ["slot", "certificate", "p [m]", "u1 [deg]", "u2 [deg]", "u3 [deg]",
                     "u4 [deg]", "u5 [deg]"]


def certified_json(cert: CertifiedFK) -> dict:  # type: ignore[type-arg]
    """JSON-ready dict of an unbatched certificate (SI units: m, rad)."""
    return {"complete": bool(cert.complete), "n_certified": int(cert.n_certified),
            "prec_bits": int(cert.prec), "input_tol": cert.input_tol, "slots": [
                {"slot": k, "status": CertStatus(int(cert.status[k])).name,
                 "reason": Reason(int(cert.reason[k])).name,
                 "p_m": [cert.p_lo[k], cert.p_hi[k]],
                 "u_rad": np.stack([cert.u_lo[k], cert.u_hi[k]], axis=-1),
                 "O_s_m": np.stack([cert.O_s_lo[k], cert.O_s_hi[k]], axis=-1),
                 "tip_m": np.stack([cert.tip_lo[k], cert.tip_hi[k]], axis=-1)}
                for k in range(16)]}


def run(args: argparse.Namespace) -> int:
    """Execute ``fk``."""
    design, T = load_robot(args)
    if args.certify:
        return _run_certified(args, design, T)
    # the public function: the CLI shows what the library gives; one pose in a fresh process
    # runs the numpy reference, not numba's ~1 s of loading (cli/_warmup.one_shot_backend)
    try:
        sol = forward_kinematics(np.array(args.q), T, design, backend=one_shot_backend())
    except KinematicsError as exc:
        raise with_hint(exc, mm_hint(args.q, design, "max |q|")) from None
    if args.json:
        print(dump_json({"q_m": args.q, "T_b_e": T, **fk_json(sol)}))
    else:
        print(f"forward kinematics, q = {args.q} m: {int(sol.n_solutions)} solutions")
        print(table(FK_HEADERS, fk_rows(sol)))
    return 0


def _run_certified(args: argparse.Namespace, design: Design, T: np.ndarray) -> int:
    from ..certified import certified_forward_kinematics

    cert = certified_forward_kinematics(np.array(args.q), T, design)
    if args.json:
        print(dump_json({"q_m": args.q, "T_b_e": T, "certificate": certified_json(cert)}))
        return 0
    count = (f"exactly {int(cert.n_certified)} real solutions (proven)" if cert.complete else
             f"{int(cert.n_certified)} solutions certified; the count is not proven")
    print(f"certified forward kinematics, q = {args.q} m: {count}")
    print(table(CERTIFIED_HEADERS, certified_rows(cert)))
    print("each certified box holds exactly one exact solution (docs/certified.md)")
    return 0
