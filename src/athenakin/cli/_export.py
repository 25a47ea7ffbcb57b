"""``athenakin export``: MJCF (MuJoCo, loops closed) or URDF (tree) of the robot; MuJoCo check."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ..design import Design
from ._common import add_robot_options, check_count, load_robot
from ._output import add_force_option, outputs
from ._view import add_q_argument, add_slot_option, q_from_args

#: Largest error (m and rad) the ``--check`` accepts between MuJoCo and the FK.
CHECK_TOL = 1e-9
#: Most configurations ``--check`` simulates (about 0.1 s each).
MAX_CHECK = 1000


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``export`` subcommand."""
    p = sub.add_parser(
        "export", help="write an MJCF (MuJoCo) or URDF model; optionally simulate it",
        description="Write the robot as MJCF (the whole closed-loop mechanism: prismatic "
                    "actuators q1..q3, passive joints, loop closures as equality constraints, "
                    "keyframe 'home' at the given q) or as URDF (the kinematic tree; loop "
                    "closures listed in the file). With --check N (MJCF), MuJoCo drives the "
                    "model to N seeded configurations and its instrument pose is compared "
                    "with athenakin's forward kinematics.")
    add_q_argument(p)
    p.add_argument("-o", "--output", type=Path, required=True, metavar="FILE",
                   help="output file (.xml / .mjcf for MJCF, .urdf for URDF)")
    p.add_argument("--format", choices=("mjcf", "urdf"), default=None,
                   help="model format (default: from the suffix of -o)")
    add_slot_option(p)
    p.add_argument("--no-gravity", action="store_true", help="MJCF without gravity")
    p.add_argument("--check", type=int, nargs="?", const=20, default=0, metavar="N",
                   help="simulate the MJCF model in MuJoCo at N configurations (default 20) "
                        "and compare with the forward kinematics")
    p.add_argument("--seed", type=int, default=0, help="seed of the --check samples (0)")
    add_force_option(p)
    add_robot_options(p)
    p.set_defaults(func=run)


def _format(args: argparse.Namespace, out: Path) -> str:
    if args.format:
        return str(args.format)
    suffix = out.suffix.lower()
    if suffix in (".xml", ".mjcf"):
        return "mjcf"
    if suffix == ".urdf":
        return "urdf"
    raise ValueError(f"--format: not given and the suffix of {str(out)!r} is neither .xml, "
                     f".mjcf nor .urdf")


def run(args: argparse.Namespace) -> int:
    """Execute ``export``."""
    from ..sim import mjcf_from_design, urdf_from_design

    out = Path(args.output)
    fmt = _format(args, out)
    if args.check and fmt != "mjcf":
        raise ValueError("--check simulates the MJCF model: use --format mjcf")
    check_count(args.check, "--check", 0, MAX_CHECK, "configurations")
    with outputs(args) as outs:
        outs.add(out)
        design, T = load_robot(args)
        q = q_from_args(args)
        if fmt == "mjcf":
            outs.write(out, mjcf_from_design(T, design, q=q, slot=args.slot,
                                             gravity=not args.no_gravity))
            what = (f"MJCF of the closed-loop mechanism, keyframe 'home' in solution "
                    f"{args.slot}")
        else:
            outs.write(out, urdf_from_design(T, design))
            what = "URDF of the kinematic tree (loop closures listed in its header)"
        ok = True
        if args.check:
            ok = _check(args, design, T, q)
        if not ok:
            print(f"{out} not written: the MuJoCo check failed")
            return 1
        outs.commit()
    print(f"wrote {out}: {what}")
    return 0


def _check(args: argparse.Namespace, design: Design, T: np.ndarray, q: np.ndarray | None
           ) -> bool:
    """Simulate the model in MuJoCo at ``--check`` configurations; print the verdict."""
    from ..robot import REFERENCE_Q
    from ..sim import check_fk_with_mujoco, sample_reachable_q

    home = REFERENCE_Q if q is None else q
    targets = np.vstack([home, sample_reachable_q(args.check - 1, T, design, slot=args.slot,
                                                  home_q=home, rng=args.seed)]
                        if args.check > 1 else [home])
    res = check_fk_with_mujoco(targets, T, design, start_slot=args.slot, home_q=home,
                               perturb=0.02, rng=args.seed, progress=True)
    print("MuJoCo check (no gravity): " + res.summary())
    worst = max(float(np.max(res.pose_error)), float(np.max(res.joint_error)))
    ok = bool(np.all(res.slot == args.slot) and np.all(res.nearest_slot == args.slot)
              and worst <= CHECK_TOL)
    print(f"{'PASSED' if ok else 'FAILED'}: MuJoCo agrees with the forward kinematics to "
          f"{worst:.1e} (tolerance {CHECK_TOL:.0e} m / rad) in solution {args.slot}")
    return ok
