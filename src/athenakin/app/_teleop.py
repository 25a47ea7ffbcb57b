"""The Teleop tab's logic: the live app as a virtual master of :mod:`athenakin.teleop` (numpy only).

The app's draggable handle is the master, in the scene's frame (the robot's base frame):
:func:`start_teleop` builds the one core object, :class:`athenakin.teleop.Teleop`, at the
configuration drawn, with the registration ``R_e_b`` (the handle's motion maps to a
tip motion in the same direction on the screen, times the scale), and a
:class:`Master` at the tip. The app's own clock drives the cycles
(:func:`teleop_cycles`, :data:`TELEOP_RATE`): while the tab runs, every cycle gets the
handle's last position (a virtual master never goes silent), except when the master
is paused (:attr:`Master.paused`): ``step(t, None)``, and the watchdog holds the robot
after 30 ms. Nothing here re-implements the mapping, the filter, the IK or the safety
layer: :meth:`Teleop.step <athenakin.teleop.Teleop.step>` does it all.

:func:`teleop_frame` says what one cycle draws and shows (:class:`TeleopFrame`);
:func:`teleop_scene` the commanded tip and the target, :func:`fixture_solids` the
environment's obstacles (the virtual fixtures), :func:`teleop_html` the flags, the
watchdog and the scale. The viser binding is :mod:`athenakin.app._teleop_tab`.
"""

from __future__ import annotations

import dataclasses
import html
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray, IntArray
from .._validation import check_instance, check_scalar
from ._model import AppSetup
from ._scene import LineSet, PointSet, Scene, Solid, rgb
from ._text import ERROR_COLOR, WARN_COLOR

__all__ = ["TELEOP_RATE", "SCALE_RANGE", "MAX_CYCLES", "SHOWN_FLAGS", "GUARD_FLAGS",
           "Master", "TeleopFrame", "start_teleop", "hold_clutch", "clutch_closed",
           "teleop_state",
           "teleop_cycles", "teleop_frame", "teleop_scene", "fixture_solids", "teleop_html"]

#: Cycles per second of the app's teleoperation loop, Hz (the tremor filter needs >= 100).
TELEOP_RATE = 100.0
#: Range of the scale slider (tip metres per master metre); the default is Teleop's, 0.2.
SCALE_RANGE = (0.05, 1.0)
#: Most cycles one tick of the loop runs: a loop late by more drops the backlog (the
#: robot moves slower in wall time, never faster than ``v_max`` per cycle).
MAX_CYCLES = 10
#: The flags shown, in the safety layer's order (the issue's ten, then the four extra).
SHOWN_FLAGS = ("CLUTCHED", "STROKE", "DEPTH", "SINGULAR", "FIXTURE", "CLEARANCE", "VELOCITY",
               "ACCELERATION", "WATCHDOG", "ESTOP", "INVALID", "JUMP", "HOLD", "FAULT")
#: The flags of a guard that shortened or refused the step toward the master's target.
GUARD_FLAGS = ("STROKE", "DEPTH", "SINGULAR", "FIXTURE", "CLEARANCE", "VELOCITY",
               "ACCELERATION", "JUMP", "INVALID")
#: Colour of the state word while the tip follows the master.
FOLLOWING_COLOR = "#1b7e3c"
#: Colours of the commanded tip, the target and the fixtures; the fixtures' opacity.
TIP_COLOR = "#1b9e77"
TARGET_COLOR = "#7570b3"
FIXTURE_COLOR = "#c0392b"
FIXTURE_OPACITY = 0.35
#: Half-size of the square drawn for a halfspace fixture, m; size of the tip points, m.
HALFSPACE_HALF_M = 0.12
POINT_SIZE_M = 0.01


@dataclasses.dataclass(frozen=True)
class Master:
    """The virtual master's inputs (each GUI event makes a new one).

    Attributes
    ----------
    handle_b : tuple of 3 float
        The handle's position, base frame (the app's scene), m; passed to the core as
        it is (NaN or a far jump are the core's to flag).
    clutched : bool
        The clutch button is on: the master moves freely, the tip holds (dVRK's
        "clutched"; ``clutch=False`` of :meth:`Teleop.step`).
    held : bool
        A held clutch (the hold button or its key) is down: open from the first hold
        message until the button's release, however late the messages arrive.
    paused : bool
        No master samples (``step(t, None)``): the watchdog holds the robot.
    """

    handle_b: tuple[float, float, float]
    clutched: bool = False
    held: bool = False
    paused: bool = False


@dataclasses.dataclass(frozen=True)
class TeleopFrame:
    """What one cycle draws and shows.

    Attributes
    ----------
    t : float
        App time of the cycle, s.
    q : ndarray, shape (3,)
        Commanded actuators, m (the robot is drawn there).
    slot : int
        Tracked forward-kinematics slot of ``q``.
    tip_b, target_b, handle_b : ndarray, shape (3,)
        Commanded tool tip, the master's target for it (before the safety layer) and
        the master handle, base frame, m.
    status : athenakin.teleop.TeleopStatus
    flags : tuple of str
        Names of the set flags, in :data:`SHOWN_FLAGS` order.
    scale : float
        Motion scale, tip m per master m.
    following : bool
        The clutch is closed and the master samples (the tip follows the handle).
    watchdog, estop : bool
        The watchdog or the e-stop holds the robot.
    """

    t: float
    q: FloatArray
    slot: int
    tip_b: FloatArray
    target_b: FloatArray
    handle_b: FloatArray
    status: Any
    flags: tuple[str, ...]
    scale: float
    following: bool
    watchdog: bool
    estop: bool


def start_teleop(setup: AppSetup, q: ArrayLike, *, slot: int = 0, scale: float = 0.2,
                 bodies: Any = None, environment: Any = None,
                 options: Any = None) -> tuple[Any, Master]:
    """The core at the configuration drawn, and a master handle at its tool tip.

    Parameters
    ----------
    setup : AppSetup
    q : array-like, shape (3,)
        Where the robot stands, m.
    slot : int, keyword-only
        Forward-kinematics slot drawn (the tip follows its branch; ``p > 0``).
    scale : float, keyword-only
        Motion scale.
    bodies, environment : keyword-only, optional
        As in :class:`~athenakin.teleop.Teleop` (clearance guard, virtual fixtures).
    options : TeleopOptions, keyword-only, optional
        Default ``TeleopOptions(filter="none", feedforward=False, backend=setup.backend)``:
        a mouse has no tremor, and the handle moves in steps (one per browser event) on
        which the 8-12 Hz notch rings (a 40 % overshoot, seconds to settle at 100 Hz); the
        app servoes no arm, so no forces. Its registration is replaced by ``R_e_b``: the
        master is the scene's handle.

    Returns
    -------
    tele : athenakin.teleop.Teleop
        Running at :data:`TELEOP_RATE`.
    master : Master
        The handle at the commanded tip, clutch closed.

    Raises
    ------
    InvalidInputError, TypeError
        As :class:`~athenakin.teleop.Teleop` (e.g. a slot with ``p < 0``, ``q`` in a
        fixture or with the bodies too close).
    """
    from ..teleop import Teleop, TeleopOptions

    check_instance(setup, "setup", AppSetup)
    if options is None:
        options = TeleopOptions(filter="none", feedforward=False, backend=setup.backend)
    check_instance(options, "options", TeleopOptions)
    options = dataclasses.replace(options, registration=setup.T_b_e[:3, :3].T)
    tele = Teleop(setup.T_b_e, setup.design, q0=q, scale=scale, environment=environment,
                  bodies=bodies, rate=TELEOP_RATE, slot=slot, options=options)
    return tele, Master(handle_b=_to_base(setup, tele.tip))


def _to_base(setup: AppSetup, p_e: Any) -> tuple[float, float, float]:
    T = setup.T_b_e
    x = T[:3, :3] @ np.asarray(p_e, dtype=float) + T[:3, 3]
    return float(x[0]), float(x[1]), float(x[2])


def hold_clutch(master: Master, *, held: bool = True) -> Master:
    """``master`` with the held clutch down (a hold message) or up (``held=False``).

    Parameters
    ----------
    master : Master
    held : bool, keyword-only
        True: a hold message of the button or its key (the clutch stays open until the
        release); False: the hold button's release, or the key's key-up.

    Returns
    -------
    Master
        ``master`` with :attr:`Master.held` set (the toggle :attr:`Master.clutched` is
        kept).
    """
    check_instance(master, "master", Master)
    if not isinstance(held, bool):
        raise TypeError(f"held: expected a bool, got {type(held).__name__}")
    return dataclasses.replace(master, held=held)


def clutch_closed(master: Master) -> bool:
    """Whether the tip follows the master: the clutch neither toggled nor held open.

    Parameters
    ----------
    master : Master

    Returns
    -------
    bool
        ``not (master.clutched or master.held)``.
    """
    check_instance(master, "master", Master)
    return not (master.clutched or master.held)


def teleop_cycles(tele: Any, master: Master, t_last: float, t_now: float
                  ) -> tuple[Any, float]:
    """Run the cycles due between the last one (``t_last``) and ``t_now`` (app time, s).

    One cycle every ``1 / tele.rate`` s; at most :data:`MAX_CYCLES` (a late loop drops the
    backlog, the last cycle then falls at ``t_now``). Each cycle's sample is the handle's
    position, or None while the master is paused.

    Returns
    -------
    cmd : athenakin.teleop.TeleopCommand or None
        The last cycle's command (None: no cycle was due).
    t_last : float
        Time of the last cycle run, s.
    """
    from ..teleop import Teleop

    check_instance(tele, "tele", Teleop)
    check_instance(master, "master", Master)
    dt = 1.0 / tele.rate
    t_last, t_now = check_scalar(t_last, "t_last"), check_scalar(t_now, "t_now")
    n = math.floor((t_now - t_last) / dt + 1e-9)
    if n > MAX_CYCLES:
        t_last, n = t_now - MAX_CYCLES * dt, MAX_CYCLES
    sample = None if master.paused else master.handle_b
    closed, cmd = clutch_closed(master), None
    for k in range(1, n + 1):
        t = t_last + k * dt
        cmd = tele.step(t, sample, clutch=closed)
    return cmd, t_last + max(n, 0) * dt


def teleop_frame(tele: Any, master: Master, cmd: Any) -> TeleopFrame:
    """What the command ``cmd`` of ``tele`` draws and shows (see :class:`TeleopFrame`)."""
    from ..teleop import Teleop, TeleopStatus

    check_instance(tele, "tele", Teleop)
    check_instance(master, "master", Master)
    st = TeleopStatus(cmd.status)
    flags = tuple(n for n in SHOWN_FLAGS if st & TeleopStatus[n])
    T = tele.T_b_e
    tip_b = T[:3, :3] @ np.asarray(cmd.tip) + T[:3, 3]
    target_b = T[:3, :3] @ np.asarray(cmd.target) + T[:3, 3]
    held = bool(st & (TeleopStatus.WATCHDOG | TeleopStatus.ESTOP))
    return TeleopFrame(t=float(cmd.t), q=np.array(cmd.q, dtype=float), slot=int(cmd.slot),
                       tip_b=tip_b, target_b=target_b,
                       handle_b=np.array(master.handle_b, dtype=float), status=st, flags=flags,
                       scale=float(tele.scale),
                       following=not held and not st & TeleopStatus.CLUTCHED
                       and not master.paused,
                       watchdog=bool(st & TeleopStatus.WATCHDOG),
                       estop=bool(st & TeleopStatus.ESTOP))


def teleop_scene(frame: TeleopFrame) -> Scene:
    """The commanded tip (green), the target (purple) and the correction between them.

    The segment from the commanded tip to the target shows what the safety layer (or the
    clutch) kept the tip from; it is drawn only where they differ by more than 0.1 mm.
    """
    check_instance(frame, "frame", TeleopFrame)
    pts = np.stack([frame.tip_b, frame.target_b])
    ok = np.all(np.isfinite(pts), axis=-1)
    cols = np.array([rgb(TIP_COLOR), rgb(TARGET_COLOR)], dtype=np.uint8)
    points = (PointSet("teleop_tips", pts[ok], cols[ok], POINT_SIZE_M),)
    lines: tuple[LineSet, ...] = ()
    if ok.all() and np.linalg.norm(pts[1] - pts[0]) > 1e-4:
        lines = (LineSet("teleop_correction", pts[None], rgb(TARGET_COLOR), 2.0),)
    return Scene(lines=lines, points=points, labels=())


def fixture_solids(environment: Any) -> tuple[Solid, ...]:
    """The obstacles of an environment as shaded solids (the virtual fixtures), base frame.

    A sphere or a capsule as a capsule mesh, a box as its 12 triangles, a mesh as its
    triangles, a halfspace as a square of side ``2 HALFSPACE_HALF_M`` on its plane around
    its point. Obstacles that allow the instrument are drawn paler: they are no fixture
    for the tip, only for the bodies' clearance.

    Parameters
    ----------
    environment : athenakin.collision.Environment or None

    Returns
    -------
    tuple of Solid
        Named ``fixture_<obstacle name>``; empty for None.
    """
    if environment is None:
        return ()
    from ..collision import Environment

    check_instance(environment, "environment", Environment)
    out = []
    for o in environment.obstacles:
        v, f = _obstacle_mesh(o)
        opacity = FIXTURE_OPACITY * (0.4 if "instrument" in o.allow else 1.0)
        out.append(Solid(f"fixture_{o.name}", v, f, rgb(FIXTURE_COLOR), opacity))
    return tuple(out)


def _obstacle_mesh(o: Any) -> tuple[FloatArray, IntArray]:
    """Vertices (n, 3) in the base frame and faces (m, 3) of one obstacle."""
    from ._bodies import capsule_mesh

    if o.kind in ("sphere", "capsule"):
        a, b = (o.center, o.center) if o.kind == "sphere" else (o.a, o.b)
        vc, fc = capsule_mesh(a, b, o.radius)
        return vc.astype(np.float64), fc.astype(np.int64)
    if o.kind == "halfspace":
        n = np.asarray(o.normal, dtype=float)
        e1 = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(n, e1)
        h = HALFSPACE_HALF_M
        v = np.asarray(o.point) + h * np.array([-e1 - e2, e1 - e2, e1 + e2, -e1 + e2])
        return v, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64)
    if o.kind == "box":
        corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)],
                           dtype=float) * np.asarray(o.half_extents)
        faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                          [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]],
                         dtype=np.int64)
        verts = corners
    else:                                          # mesh: its triangles in the shape frame
        verts, faces = np.asarray(o.vertices, dtype=float), np.asarray(o.faces, dtype=np.int64)
    T = np.asarray(o.T_b_o, dtype=float)
    return verts @ T[:3, :3].T + T[:3, 3], faces


def teleop_state(frame: TeleopFrame) -> tuple[str, str]:
    """The state word of ``frame`` and its colour: what the robot does this cycle.

    In order: ``E-STOP``, ``WATCHDOG``, ``FAULT`` (red; the robot brakes and holds);
    ``clutched`` (the master moves freely, the tip holds); ``paused`` (no master
    samples); ``held by NAME ...`` (a guard of :data:`GUARD_FLAGS` refused the step: the
    tip holds, ``HOLD`` is set); ``limited by NAME ...`` (a guard shortened the step: the
    tip follows more slowly or stops short); ``following`` (green: the tip follows the
    master, scaled).

    Parameters
    ----------
    frame : TeleopFrame

    Returns
    -------
    state : str
    color : str
        CSS colour.
    """
    check_instance(frame, "frame", TeleopFrame)
    flags = frame.flags
    guards = " ".join(n for n in GUARD_FLAGS if n in flags)
    if frame.estop:
        return "E-STOP", ERROR_COLOR
    if frame.watchdog:
        return "WATCHDOG", ERROR_COLOR
    if "FAULT" in flags:
        return "FAULT", ERROR_COLOR
    if "CLUTCHED" in flags:
        return "clutched", WARN_COLOR
    if not frame.following:
        return "paused", WARN_COLOR
    if "HOLD" in flags:
        return (f"held by {guards}" if guards else "held"), WARN_COLOR
    if guards:
        return f"limited by {guards}", WARN_COLOR
    return "following", FOLLOWING_COLOR


def teleop_html(frame: TeleopFrame | None, *, note: str = "") -> str:
    """The Teleop tab's read-out: the state, the flags by name, the scale, the tip.

    Every flag of :data:`SHOWN_FLAGS` is a cell ``data-flag="NAME"`` with ``data-on="1"``
    when set; ``data-ro="teleop_state"`` is :func:`teleop_state`'s word, or ``off``;
    ``data-ro="teleop_flags"`` lists the set flags.

    Parameters
    ----------
    frame : TeleopFrame or None
        None: teleoperation is off.
    note : str, keyword-only
        A line shown above (why teleoperation stopped, ...).
    """
    top = f'<div data-ro="teleop_note">{html.escape(note)}</div>' if note else ""
    if frame is None:
        return top + '<div><b>teleop</b> <span data-ro="teleop_state">off</span></div>'
    check_instance(frame, "frame", TeleopFrame)
    state, color = teleop_state(frame)
    cells = []
    for name in SHOWN_FLAGS:
        on = name in frame.flags
        hot = ERROR_COLOR if name in ("WATCHDOG", "ESTOP", "FAULT") else WARN_COLOR
        style = f"background:{hot};color:white;font-weight:bold" if on else "color:#aaaaaa"
        cells.append(f'<span data-flag="{name}" data-on="{int(on)}" style="{style};'
                     f'padding:0 0.25em;margin:0.1em;display:inline-block">{name}</span>')
    tip = "".join(f'<td data-ro="teleop_tip_b_{a}" data-v="{float(v)!r}" '
                  f'style="text-align:right">{v * 1e3:.2f}</td>'
                  for a, v in zip("xyz", frame.tip_b, strict=True))
    return (f'{top}<div><b>teleop</b> <span data-ro="teleop_state" style="color:{color};'
            f'font-weight:bold">{state}</span> &middot; scale <span data-ro="teleop_scale">'
            f'{frame.scale:.2f}</span> &middot; t <span data-ro="teleop_t">{frame.t:.2f}</span>'
            f' s</div><div data-ro="teleop_flags" data-v="{" ".join(frame.flags)}" '
            f'style="font-size:0.75em">{"".join(cells)}</div>'
            f'<table style="font-size:0.8em;width:100%"><tr><td>commanded tip in base [mm]</td>'
            f"{tip}</tr></table>")

