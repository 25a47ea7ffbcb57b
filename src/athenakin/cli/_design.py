"""``athenakin design``: print the design as TOML or write it to a file."""

from __future__ import annotations

import argparse
from pathlib import Path

from ._common import add_design_option, load_design
from ._output import outputs


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``design`` subcommand."""
    p = sub.add_parser(
        "design", help="print the design as TOML, or write it to a file",
        description="Print the design (the reference design, or the one of --design) as the "
                    "TOML that --design reads; with --write FILE, write it to FILE, a starting "
                    "point to edit (lengths in m). An existing FILE is kept unless --force.")
    p.add_argument("--write", metavar="FILE", type=Path, help="write the TOML to FILE")
    p.add_argument("--force", action="store_true", help="replace FILE if it exists")
    add_design_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Execute ``design``."""
    design = load_design(args)
    if args.write is None:
        if args.force:
            raise ValueError("--force goes with --write FILE")
        print(design.to_toml(), end="")
        return 0
    with outputs(args, option="--write") as outs:
        outs.write(outs.add(args.write), design.to_toml())
        outs.commit()
    print(f"wrote {args.write}")
    return 0
