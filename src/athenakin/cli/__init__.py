"""Command-line interface ``athenakin``: parses, calls the library, prints text or JSON.

Each subcommand lives in its own module ``athenakin.cli._<name>`` exposing
``register(subparsers)``; :data:`COMMANDS` lists them in help order. The CLI
holds no kinematics: angles are degrees here and radians everywhere else.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from ..errors import KinematicsError

__all__ = ["main", "COMMANDS"]

#: Subcommand modules, in the order ``athenakin --help`` lists them.
COMMANDS = ["fk", "ik", "demo"]


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every registered subcommand."""
    from .. import __version__

    parser = argparse.ArgumentParser(
        prog="athenakin",
        description="Kinematics of the ATHENA surgical robot (lengths in m, angles in deg).")
    parser.add_argument("--version", action="version", version=f"athenakin {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMANDS:
        importlib.import_module(f"athenakin.cli._{name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the process exit code (0 ok, 1 kinematics error, 2 usage)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (KinematicsError, ValueError, TypeError, OSError) as exc:
        print(f"athenakin {args.command}: error: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
