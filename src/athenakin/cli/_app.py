"""``athenakin app``: a live ATHENA in the browser (local web server, extra ``app``)."""

from __future__ import annotations

import argparse
import signal
import sys
import threading
from pathlib import Path
from typing import Any

from ._collision import add_bodies_options
from ._common import add_robot_options, force_limits

#: Interface the app binds unless told otherwise (this machine only).
DEFAULT_HOST = "127.0.0.1"


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``app`` subcommand."""
    p = sub.add_parser(
        "app", help="live robot in the browser: sliders q1..q3, a draggable tool tip, read-outs",
        description="Start a local web server (viser) showing the robot live: sliders for "
                    "q1, q2, q3 within the strokes, the 16 FK solutions (or all valid ones "
                    "ghosted), a draggable tool tip and azimuth / polar / depth sliders "
                    "driving the controller-form IK, read-outs of q, p, u1..u5, the tip, the "
                    "assembly mode, the distances to the singular sets and the Jacobians' "
                    "conditioning, playback of a trajectory CSV from 'athenakin plan', and the "
                    "actuator forces f1, f2, f3 that hold the robot against gravity and a "
                    "tip force dragged at the tool tip (--masses, --f-max). The bodies and "
                    "the obstacles (--bodies, --environment) are checked in the clearance "
                    "read-out and the IK, and the obstacles are the Teleop tab's virtual "
                    "fixtures; a bad --bodies or --environment file stops the start. "
                    "--setup and --patient start on a planned set-up with its patient "
                    "(athenakin setup plan); a bad file stops the start. "
                    "Prints the URL; Ctrl-C stops it. A design, RCM frame or trajectory that "
                    "cannot be used is reported at start-up and in the page, and the app runs "
                    "on the reference set-up instead.")
    add_robot_options(p)
    p.add_argument("--trajectory", metavar="CSV", type=Path,
                   help="trajectory CSV to play back (columns q1_m, q2_m, q3_m, optional t_s)")
    p.add_argument("--host", default=DEFAULT_HOST,
                   help=f"interface to bind ({DEFAULT_HOST}: this machine only; 0.0.0.0: "
                        f"every interface, only when asked)")
    p.add_argument("--port", type=int, default=8080,
                   help="port (8080; the next free one is taken when it is busy; 0: any)")
    p.add_argument("--backend", choices=("auto", "numba", "numpy"), default="auto",
                   help="kinematics kernels (auto: numba when installed)")
    p.add_argument("--foxglove", nargs="?", type=int, const=8765, default=None, metavar="PORT",
                   help="also serve the live robot to Foxglove over its WebSocket protocol on "
                        "--host (port 8765; extra 'ros'; topics: docs/ros.md)")
    # actuator forces: app/_forces.py
    p.add_argument("--masses", type=Path, default=None, metavar="FILE",
                   help="TOML file with a [masses] table (e.g. the design file) for the "
                        "actuator-force read-out (default: the reference mass model)")
    p.add_argument("--f-max", type=float, nargs="+", default=None, metavar="N",
                   help="actuator force limits in N, one for all or one per actuator: shown "
                        "with the forces, which turn red beyond them")
    # the collision models (the Teleop tab's virtual fixtures): app/_bodies.py
    add_bodies_options(p.add_argument_group("collisions (clearance read-out, the IK's "
                                            "collision stop, the Teleop tab's fixtures)"),
                       bodies_default="the default capsules of the design shown")
    g = p.add_argument_group("a planned set-up (athenakin setup plan)")
    g.add_argument("--setup", type=Path, default=None, metavar="SETUP.toml",
                   help="start on a planned set-up: its T_b_e (no --rcm/--rcm-file) and its "
                        "design (unless --design)")
    g.add_argument("--patient", type=Path, default=None, metavar="PATIENT.toml",
                   help="the patient of --setup: its meshes drawn where T_p_b places them, "
                        "the port and the nominal axis; its surfaces join the obstacles; the "
                        "tool tip starts at the target's centre")
    p.set_defaults(func=run)


def check_host(host: str) -> str:
    """``host`` if this machine can listen on it, else ``ValueError`` naming it.

    Checked before the server starts: the web server binds in a thread of its own,
    and an address it cannot bind (``999.1.1.1``, another machine's) would leave
    it waiting for ever, deaf to Ctrl-C.
    """
    import socket

    try:
        infos = socket.getaddrinfo(host, 0, type=socket.SOCK_STREAM)
    except (OSError, UnicodeError) as exc:
        raise ValueError(f"--host {host!r}: not an address of this machine "
                         f"({getattr(exc, 'strerror', None) or exc})") from None
    family, kind, proto, _, addr = infos[0]
    with socket.socket(family, kind, proto) as s:
        try:
            s.bind(addr)
        except OSError as exc:
            raise ValueError(f"--host {host!r}: cannot listen on it "
                             f"({exc.strerror or exc})") from None
    return host


def run(args: argparse.Namespace) -> int:
    """Execute ``app``: serve until SIGINT (Ctrl-C) or SIGTERM."""
    from ..app import _server
    from ._common import load_rcm

    try:
        _server._import_viser()
    except ModuleNotFoundError as exc:
        print(f"athenakin app: error: {exc}", file=sys.stderr)
        return 1
    if not 0 <= args.port <= 65535:
        raise ValueError(f"--port: expected 0..65535, got {args.port}")
    if args.foxglove is not None and not 0 <= args.foxglove <= 65535:
        raise ValueError(f"--foxglove: expected a port 0..65535, got {args.foxglove}")
    check_host(args.host)
    if args.setup is not None and (args.rcm or args.rcm_file):
        raise ValueError("--setup: the planned set-up holds the RCM frame; drop --rcm / "
                         "--rcm-file")
    masses, f_max = _force_options(args)    # actuator forces: app/_forces.py
    rcm: Any = args.rcm_file
    if args.rcm:
        from ..design import Design

        rcm = load_rcm(args, Design.default())
    stop = threading.Event()

    def on_signal(signum: int, frame: object) -> None:
        stop.set()

    # handlers first: a Ctrl-C during the start (or right after the URL) also stops cleanly
    old = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    app = None
    live: Any = None
    try:
        if args.backend != "numpy":
            print("athenakin app: starting (a first start compiles the numba kernels: up to "
                  "a minute)", flush=True)
        app = _server.AthenaApp(rcm, args.design, host=args.host, port=args.port,
                                trajectory=args.trajectory, backend=args.backend,
                                masses=masses, f_max=f_max, bodies=args.bodies,
                                environment=args.environment, planned=args.setup,
                                patient=args.patient)
        for e in app.errors:
            print(f"athenakin app: warning: {e}", file=sys.stderr)
        if args.foxglove is not None:
            from ..ros._live import serve_app

            live = serve_app(app, host=args.host, port=args.foxglove)
            print(f"athenakin app: Foxglove WebSocket at {live.url}", flush=True)
        print(f"athenakin app: serving ATHENA at {app.url} (Ctrl-C stops)", flush=True)
        while not stop.wait(0.2):
            pass
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        if live is not None:
            live.stop()
        if app is not None:
            app.stop()
    print("athenakin app: stopped", flush=True)
    return 0


def _force_options(args: argparse.Namespace) -> tuple[Any, Any]:
    """``masses``, ``f_max`` of ``--masses FILE`` and ``--f-max``, checked before the start."""
    from ..app._forces import check_f_max, check_masses
    from ..errors import InvalidInputError

    try:
        masses = check_masses(args.masses)
    except InvalidInputError as exc:
        raise InvalidInputError(f"--masses: {exc}") from None
    limits = force_limits(args)
    try:
        f_max = check_f_max(limits)
    except InvalidInputError as exc:
        raise InvalidInputError(f"--f-max: {exc}") from None
    return masses, f_max
