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

#: Optional third-party packages and the extra that installs each.
_EXTRA_OF = {"sympy": "symbolic", "matplotlib": "plot", "plotly": "plot", "imageio": "plot",
             "mujoco": "sim", "yourdfpy": "sim", "numba": "fast", "tqdm": "progress",
             "scipy": "analysis", "ruckig": "motion", "toppra": "motion", "pinocchio": "bench"}

#: Subcommand modules, in the order ``athenakin --help`` lists them.
COMMANDS = ["fk", "ik", "demo", "plan", "track", "workspace", "singularities", "view",
            "animate", "export", "derive", "warmup"]


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
    args = parser.parse_args(_protect_negative_numbers(argv))
    try:
        return int(args.func(args) or 0)
    except ModuleNotFoundError as exc:
        extra = _EXTRA_OF.get((exc.name or "").split(".")[0], "all")
        print(f"athenakin {args.command}: error: this command needs the optional package "
              f"{exc.name!r}: pip install 'athenakin[{extra}]'", file=sys.stderr)
        return 1
    except (KinematicsError, ValueError, TypeError, OSError) as exc:
        print(f"athenakin {args.command}: error: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 1


def _protect_negative_numbers(argv: list[str] | None) -> list[str]:
    """Let negative numbers in scientific notation (``-1.4e-14``) pass as values.

    argparse treats ``-1.4e-14`` as an option because its negative-number pattern
    has no exponent; prefixing a space keeps it a value (``float(" -1e-3")`` works).
    """
    import re

    args = sys.argv[1:] if argv is None else list(argv)
    pat = re.compile(r"^-\d*\.?\d+(e[-+]?\d+)?$", re.IGNORECASE)
    return [f" {a}" if pat.match(a) and "e" in a.lower() else a for a in args]


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
