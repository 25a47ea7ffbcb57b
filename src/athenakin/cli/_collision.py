"""Collision options of ``track``, ``plan``, ``workspace``: bodies, environment, clearance margin.

``app`` takes ``--bodies`` and ``--environment`` (:func:`add_bodies_options`), ``synthesize``
``--environment`` (:func:`add_environment_option`, :func:`load_environment`); the teleop
sessions (``teleop``, ``ros2 teleop``) keep the bodies apart by default
(:func:`add_session_collision_options`, :func:`session_collision`).

:mod:`athenakin.collision` is imported only when one of them is given.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from ..design import Design


def add_collision_options(p: argparse.ArgumentParser, *, what: str,
                          default_margin: str = "0.005") -> None:
    """Add the three options; any of them turns the clearance check on."""
    g = p.add_argument_group("collisions (any of these turns the clearance check on)")
    add_bodies_options(g, bodies_default="the --design file's [bodies] table, else the "
                                         "default capsules")
    g.add_argument("--clearance-margin", type=float, default=None, metavar="M",
                   help=f"least clearance between the bodies and to the obstacles, m; {what} "
                        f"(default {default_margin} when the check is on)")


def add_bodies_options(g: Any, *, bodies_default: str) -> None:
    """``--bodies FILE`` and ``--environment FILE`` in the argument group ``g``.

    Read by :func:`collision_options`, or passed as paths to
    :class:`athenakin.app.AthenaApp`: the same TOML readers, the same errors.
    """
    g.add_argument("--bodies", type=Path, metavar="FILE",
                   help=f"TOML file with a [bodies] table (radii in m, excluded pairs); "
                        f"default: {bodies_default}")
    add_environment_option(g)


def add_environment_option(g: Any) -> None:
    """``--environment FILE``: the obstacles, read by :func:`load_environment`."""
    g.add_argument("--environment", type=Path, default=None, metavar="FILE",
                   help="obstacles: a TOML file of [[environment.obstacle]] tables")


def load_environment(path: Path | None) -> Any:
    """The :class:`~athenakin.collision.Environment` of ``--environment FILE`` (None: none).

    A file that cannot be read or holds a bad obstacle raises the named error of
    :meth:`Environment.from_toml <athenakin.collision.Environment.from_toml>` (it names
    the file); the CLI prints it on one line and exits 1.
    """
    if path is None:
        return None
    from ..collision import Environment

    return Environment.from_toml(path)


def collision_options(args: argparse.Namespace, design: Design) -> dict[str, Any]:
    """``bodies``, ``environment``, ``clearance_margin`` keyword options (empty: no check)."""
    bodies_path = getattr(args, "bodies", None)
    env_path = getattr(args, "environment", None)
    margin = getattr(args, "clearance_margin", None)
    if bodies_path is None and env_path is None and margin is None:
        return {}
    if margin is not None and not (math.isfinite(margin) and 0.0 <= margin <= 1.0):
        raise ValueError(f"--clearance-margin: expected a distance from 0 to 1 m, got {margin:g}")
    from ..collision import Bodies

    source = bodies_path if bodies_path is not None else getattr(args, "design", None)
    bodies = (Bodies.from_toml(source, design=design) if source is not None
              else Bodies.default(design))
    env = load_environment(env_path)
    return {"bodies": bodies, "environment": env, "clearance_margin": margin}


def add_session_collision_options(p: argparse.ArgumentParser) -> None:
    """The collision options of a teleop session, with ``--no-bodies`` (the opt-out)."""
    add_collision_options(p, what="kept by the safety layer")
    p.add_argument("--no-bodies", action="store_true",
                   help="check no clearance of the bodies (explicit opt-out; with "
                        "--environment its obstacles stay fixtures for the tip)")


def session_collision(args: argparse.Namespace, design: Design) -> dict[str, Any]:
    """``bodies``, ``environment`` and the options of a teleop session's clearance check.

    The bodies default to the ``--design`` file's ``[bodies]`` table, else the default
    capsules: every session keeps them apart unless ``--no-bodies``.

    Returns
    -------
    dict
        ``bodies`` and ``environment`` (for :class:`~athenakin.teleop.Teleop`), and
        ``options``: the :class:`~athenakin.teleop.TeleopOptions` fields they set
        (``clearance_margin``; ``check_clearance=False`` with ``--no-bodies``).

    Raises
    ------
    ValueError
        ``--no-bodies`` with ``--bodies FILE``; a bad ``--clearance-margin``.
    """
    if args.no_bodies and args.bodies is not None:
        raise ValueError("--no-bodies: contradicts --bodies FILE; give one of the two")
    opts = collision_options(args, design)
    if not opts:
        from ..collision import Bodies

        source = getattr(args, "design", None)
        bodies = (Bodies.from_toml(source, design=design) if source is not None
                  else Bodies.default(design))
        opts = {"bodies": bodies, "environment": None, "clearance_margin": None}
    options: dict[str, Any] = {}
    if opts["clearance_margin"] is not None:
        options["clearance_margin"] = opts["clearance_margin"]
    if args.no_bodies:
        opts["bodies"] = None
        options["check_clearance"] = False
    return {"bodies": opts["bodies"], "environment": opts["environment"], "options": options}
