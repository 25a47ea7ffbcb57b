"""Command-line interface ``athenakin``: parses, calls the library, prints text or JSON.

Each subcommand lives in its own module ``athenakin.cli._<name>`` exposing
``register(subparsers)``; :data:`COMMANDS` lists them in help order. The CLI
holds no kinematics: angles are degrees here and radians everywhere else.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import signal
import sys
import warnings
from collections.abc import Callable
from typing import NoReturn

from ..errors import KinematicsError

__all__ = ["main", "entry_point", "COMMANDS", "EXTRAS", "COMMAND_EXTRAS", "extra_of", "PIP_NAMES",
           "MissingExtraError", "check_extras"]

#: The extras of pyproject.toml and the modules each installs (with those of the extras it
#: references, ``athenakin[progress]``), in pyproject's order (tests/test_ros_round5.py
#: checks this table against pyproject.toml).
EXTRAS = {
    "symbolic": ("sympy",),
    "plot": ("matplotlib", "plotly", "imageio", "imageio_ffmpeg", "tqdm"),
    "progress": ("tqdm",),
    "analysis": ("scipy", "tqdm"),
    "sim": ("mujoco", "yourdfpy", "tqdm"),
    "motion": ("ruckig", "scipy"),
    "calibration": ("scipy", "matplotlib"),
    "synthesis": ("dask", "distributed", "pandas", "pyarrow", "pymoo", "tqdm"),
    "certified": ("flint",),
    "app": ("viser",),
    "collision": ("coal", "trimesh"),
    "dynamics": ("scipy",),
    "ros": ("rosbags", "mcap", "mcap_ros2", "foxglove", "isal", "websockets", "zstandard",
            "lz4", "tqdm"),
    "teleop": ("mujoco", "yourdfpy", "tqdm", "rosbags", "mcap", "mcap_ros2", "foxglove", "isal",
               "websockets", "zstandard", "lz4", "ruckig", "scipy"),
    "ros2": ("rclpy", "rmw_fastrtps_cpp", "std_msgs", "sensor_msgs", "geometry_msgs",
             "builtin_interfaces", "rosgraph_msgs", "diagnostic_msgs", "mujoco", "ruckig"),
    "ros2-msgs": ("ament_cmake", "ament_cmake_ros", "ament_cmake_ros_core",
                  "ament_cmake_include_directories", "ament_package",
                  "rosidl_default_generators", "rosidl_core_generators", "catkin_pkg"),
}
#: The extra of each command's own optional packages: a package of several extras is
#: named by the command's (``plan`` needs scipy of [motion], not of [analysis]).
COMMAND_EXTRAS = {"plan": "motion", "track": "ros", "synthesize": "synthesis",
                  "setup": "synthesis",
                  "calibrate": "calibration", "view": "plot", "animate": "plot",
                  "export": "sim", "derive": "symbolic", "app": "app",
                  "workspace": "analysis", "singularities": "analysis", "ros2": "ros2",
                  "teleop": "teleop"}


def extra_of(module: str | None, command: str | None = None) -> str:
    """The extra that installs ``module`` (a top-level name), the command's first.

    ``"all"`` for a module of no extra (then every extra installs it, or none does).

    Parameters
    ----------
    module : str or None
        A module name (its top-level package counts), e.g. the ``name`` of a
        ``ModuleNotFoundError``.
    command : str, optional
        CLI subcommand; its extra (:data:`COMMAND_EXTRAS`) wins where it installs ``module``.

    Returns
    -------
    str
        A key of :data:`EXTRAS` (``pip install athenakin[<extra>]``), or ``"all"``.
    """
    top = (module or "").split(".")[0]
    own = COMMAND_EXTRAS.get(command or "")
    if own is not None and top in EXTRAS[own]:
        return own
    return next((e for e, mods in EXTRAS.items() if top in mods), "all")

#: The pip names of the optional modules whose import name differs (``import flint``
#: comes with ``pip install python-flint``).
PIP_NAMES = {"flint": "python-flint", "mcap_ros2": "mcap-ros2-support",
             "foxglove": "foxglove-sdk", "imageio_ffmpeg": "imageio-ffmpeg",
             "pinocchio": "pin"}


def _figures_wanted(args: argparse.Namespace) -> bool:
    return not (getattr(args, "no_files", False) or getattr(args, "no_figures", False))


def _recording_modules(path: object) -> tuple[str, ...]:
    """The modules that read a recording: a rosbag2 folder, else an MCAP file."""
    from pathlib import Path

    if path is not None and Path(str(path)).is_dir():
        return ("rosbags",)
    return ("mcap", "mcap_ros2")


#: The optional modules (with the extra that installs them) each command needs for its
#: arguments, checked before any work starts: ``(module, extra)`` pairs.
_NEEDS: dict[str, Callable[[argparse.Namespace], list[tuple[str, str]]]] = {
    "fk": lambda a: [("flint", "certified")] if getattr(a, "certify", False) else [],
    "workspace": lambda a: [("matplotlib", "plot")] if _figures_wanted(a) else [],
    "singularities": lambda a: [("matplotlib", "plot")] if _figures_wanted(a) else [],
    "teleop": lambda a: _teleop_needs(a),
    "ros2": lambda a: _record_needs(a) if getattr(a, "ros2_command", None) == "record" else [],
}


def _record_needs(args: argparse.Namespace) -> list[tuple[str, str]]:
    """``ros2 record``: rosbags (the schemas) and the chunks' compressor, of ``[ros]``."""
    compressor = {"zstd": ["zstandard"], "lz4": ["lz4"]}.get(getattr(args, "compression", ""),
                                                            [])
    return [(m, "ros") for m in ("rosbags", *compressor)]


def _teleop_needs(args: argparse.Namespace) -> list[tuple[str, str]]:
    """The recording's reader, the MCAP writer, the simulated arm (not with ``--no-arm``).

    Without the arm the ``[ros]`` extra is enough; with it, ``[teleop]`` installs all.
    """
    no_arm = bool(getattr(args, "no_arm", False))
    extra = "ros" if no_arm else "teleop"
    mods = list(_recording_modules(getattr(args, "path", None)))
    if getattr(args, "output", None) is not None:
        mods += ["mcap", "mcap_ros2"]
    if not no_arm:
        mods.append("mujoco")
    return [(m, extra) for m in dict.fromkeys(mods)]


class MissingExtraError(ModuleNotFoundError):
    """An optional module a command needs is missing; ``extra`` installs it."""

    def __init__(self, module: str, extra: str) -> None:
        super().__init__(f"No module named {module!r}", name=module)
        self.extra = extra


def check_extras(args: argparse.Namespace) -> None:
    """Raise :class:`MissingExtraError` for the first optional module the command lacks.

    Called before the command runs, so that a missing extra is named before any work
    (a long computation, an output file) starts.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments (``args.command`` names the command).

    Raises
    ------
    MissingExtraError
        A module of :data:`_NEEDS` for these arguments cannot be imported.
    """
    import importlib.util

    needs = _NEEDS.get(args.command)
    for module, extra in needs(args) if needs is not None else ():
        try:
            found = importlib.util.find_spec(module) is not None
        except (ImportError, ValueError):   # a module set to None in sys.modules
            found = False
        if not found:
            raise MissingExtraError(module, extra)


#: Subcommand modules, in the order ``athenakin --help`` lists them.
COMMANDS = ["fk", "ik", "demo", "plan", "track", "workspace", "singularities", "view",
            "animate", "export", "derive", "design", "calibrate", "synthesize", "setup", "teleop",
            "app", "warmup", "ros2"]


class _Parser(argparse.ArgumentParser):
    """argparse with messages that say what a missing positional expects."""

    def error(self, message: str) -> NoReturn:  # noqa: D102
        if "the following arguments are required: Q" in message:
            message = ("expected three actuator values q1 q2 q3 (m), e.g. "
                       f"'{self.prog} -0.1 0.1 0.45'")
        super().error(message)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every registered subcommand."""
    from .. import __version__

    parser = _Parser(
        prog="athenakin",
        description="Kinematics of the ATHENA surgical robot (lengths in m, angles in deg).",
        epilog=f"Set {DEBUG_ENV}=1 (or pass --debug) to see the traceback of an error.")
    parser.add_argument("--version", action="version", version=f"athenakin {__version__}")
    parser.add_argument("--debug", action="store_true",
                        help="on an error, show the Python traceback and warnings")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMANDS:
        importlib.import_module(f"athenakin.cli._{name}").register(sub)
    for p in sub.choices.values():   # also after the subcommand, where the hint puts it
        with contextlib.suppress(argparse.ArgumentError):   # a command with its own
            p.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                           help="on an error, show the Python traceback and warnings")
    return parser


#: Environment variable that, set to a non-empty value other than 0, acts as ``--debug``.
DEBUG_ENV = "ATHENAKIN_DEBUG"

#: Errors that a bad input (argument, file, design) can cause: one line, exit code 1.
_INPUT_ERRORS = (KinematicsError, ValueError, TypeError, OSError, RecursionError,
                 MemoryError, OverflowError, ZeroDivisionError)


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the process exit code.

    0: success; 1: an error (a bad input, a kinematics error, a failed check:
    one line on standard error that names it, nothing written); 0 too when the
    reader of standard output stops early (``athenakin fk ... | head -1``: whether the
    output fitted the pipe before the reader left is a race, so a closed pipe is not
    an error); 2: a usage error
    (argparse); 70: an internal error (a bug: please report it with the
    traceback that ``--debug`` shows); 130: interrupted (Ctrl-C; no output file is
    left half-written). With ``--debug`` or ``ATHENAKIN_DEBUG=1``,
    errors propagate with their traceback and warnings are shown.

    Parameters
    ----------
    argv : list of str, optional
        Arguments after the program name (default ``sys.argv[1:]``).

    Returns
    -------
    int
        The exit code above (a usage error exits through ``SystemExit(2)``).
    """
    parser = build_parser()
    args = parser.parse_args(_protect_negative_numbers(argv))
    debug = bool(args.debug) or os.environ.get(DEBUG_ENV, "") not in ("", "0")
    name = f"athenakin {args.command}"
    with warnings.catch_warnings():
        if not debug:
            # numeric warnings of intermediate NaN (outside the workspace, at a
            # singularity) are flagged in the results; they are not messages for the user
            warnings.simplefilter("ignore", RuntimeWarning)
        try:
            check_extras(args)
            return int(args.func(args) or 0)
        except BrokenPipeError:     # the reader stopped (| head): its choice, not a failure
            _silence_stdout()
            return 0
        except (KeyboardInterrupt, Exception) as exc:
            if debug:
                raise
            message, code = _failure(exc, args)
            print(f"{name}: {message}", file=sys.stderr)
            return code


def _failure(exc: BaseException, args: argparse.Namespace) -> tuple[str, int]:
    """The message and exit code of a command that failed (:func:`main`'s policy)."""
    if isinstance(exc, KeyboardInterrupt):   # Ctrl-C: outputs are discarded (Outputs)
        return f"interrupted{_resume_hint(args)}", 130
    if isinstance(exc, ModuleNotFoundError):
        return f"error: {missing_extra_message(exc, args.command)}", 1
    if isinstance(exc, _INPUT_ERRORS):
        return f"error: {_one_line(exc)}", 1
    return (f"internal error: {_one_line(exc)} (a bug: rerun with --debug for the traceback "
            f"and report it)", 70)


def missing_extra_message(exc: ModuleNotFoundError, command: str | None = None) -> str:
    """The message of a missing optional package: its name and the extra to install."""
    module = exc.name
    if not module:   # raised without a name: the quoted one of the message, if any
        import re

        m = re.search(r"No module named '([^']+)'|package '([^']+)'", str(exc))
        module = next((g for g in m.groups() if g), None) if m else None
    if not module:
        return f"this command needs an optional package ({_one_line(exc)})"
    top = module.split(".")[0]
    extra = getattr(exc, "extra", None) or extra_of(top, command)
    return (f"this command needs the optional package {PIP_NAMES.get(top, top)!r}: "
            f"pip install 'athenakin[{extra}]'")


def _resume_hint(args: argparse.Namespace) -> str:
    """Where a resumable command left its state (``synthesize``: the Parquet folder)."""
    out = getattr(args, "out", None)
    if args.command == "synthesize" and out:
        return (f"; the finished chunks are kept in {out}: run the same command again to "
                f"resume")
    return " (no output written)"


def _one_line(exc: BaseException) -> str:
    """``Type: message`` on one line (long messages cut)."""
    if isinstance(exc, RecursionError):
        text = "input nested too deeply"
    elif isinstance(exc, OverflowError):
        text = (f"numeric overflow ({' '.join(str(exc).split())}): a length or value is too "
                f"large (lengths are in m)")
    elif isinstance(exc, MemoryError):
        text = "out of memory (reduce the resolution or the number of samples)"
    else:
        text = " ".join(str(exc).split()) or "(no message)"
    if len(text) > 600:
        text = text[:597] + "..."
    return f"{type(exc).__name__}: {text}"


def _silence_stdout() -> None:
    """After a closed pipe (``athenakin demo | head -1``): drop further output quietly."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # stdout replaced (tests): nothing to do
        pass


def entry_point() -> None:
    """Console-script entry point: :func:`main`, exiting quietly on a closed pipe.

    A Ctrl-C once :func:`main` has returned (its outputs written or discarded) changes
    nothing: SIGINT is ignored from there to the exit, so a late one never prints a
    traceback.
    """
    code = 130                      # kept if a Ctrl-C lands before main's code is known
    try:
        try:
            code = main()
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            sys.stdout.flush()
        except BrokenPipeError:
            _silence_stdout()
            code = 0
        except KeyboardInterrupt:   # Ctrl-C before the command ran (importing, parsing)
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            print("athenakin: interrupted (no output written)", file=sys.stderr)
            code = 130
    except KeyboardInterrupt:       # in the few steps before SIGINT is ignored: main's code
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    sys.exit(code)


def _protect_negative_numbers(argv: list[str] | None) -> list[str]:
    """Let negative numbers in scientific notation (``-1.4e-14``) pass as values.

    argparse treats ``-1.4e-14`` as an option because its negative-number pattern
    has no exponent; prefixing a space keeps it a value (``float(" -1e-3")`` works).
    """
    import re

    args = sys.argv[1:] if argv is None else list(argv)
    pat = re.compile(r"^-\d*\.?\d+(e[-+]?\d+)?$", re.IGNORECASE)
    # "-inf" and "-nan" too, so that the value is reported as not finite, not as a missing
    # positional or an unknown option
    nonfinite = re.compile(r"^-(inf|infinity|nan)$", re.IGNORECASE)
    return [f" {a}" if (pat.match(a) and "e" in a.lower()) or nonfinite.match(a) else a
            for a in args]


if __name__ == "__main__":  # pragma: no cover
    entry_point()
