"""The viser binding: a local web page with sliders, a tip handle and read-outs (extra ``app``).

Why viser: a maintained 3-D viewer for robotics written for Python, whose web client
ships inside the wheel (works offline, no JavaScript build), with GUI inputs (sliders,
dropdowns, tabs, HTML), draggable transform controls and a websocket that pushes only
what changed. Plotly (the static HTML page) has no server round trip; Dash/Panel would
need a 3-D widget and their own state plumbing; MeshCat has no GUI controls.

Everything the page shows comes from the pure functions of :mod:`athenakin.app`
(:func:`~athenakin.app.forward_view`, :func:`~athenakin.app.inverse_step`, ...): this
module only turns them into scene nodes and GUI values, under one lock. It holds the
app's state, its GUI inputs and what changes them; the scene nodes are written by the
part it owns, :class:`~athenakin.app._page.PageWriter` (``app.page``). The Playback,
Teleop and Set-up tabs are parts of their own (``app.playback_tab``, ``app.teleop``,
``app.setup_tab``: app/_playback_tab.py, _teleop_tab.py, _setup_tab.py).
"""

from __future__ import annotations

import contextlib
import io
import math
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from .._validation import check_argument_order
from ..design import Design
from ..errors import InvalidInputError, KinematicsError
from ._bodies import collision_note
from ._inverse import angles_from_tip, inverse_step, tip_from_angles
from ._model import (
    AppSetup,
    AppView,
    forward_view,
    rcm_reach,
)
from ._page import _ALL, PageWriter, _Read, banner_html, page_title, slot_options, write_value
from ._playback_tab import PlaybackTab
from ._scene import Solid
from ._setup_tab import (
    PlannedSetup,
    SetupTab,
    _error_text,
    check_planned,
    load_setup,
    planned_environment,
    planned_start,
)
from ._sync import Echo, OrderedWorker
from ._text import message_html, view_html

__all__ = ["AthenaApp", "launch", "rcm_reach", "DEFAULT_PORT"]

#: Port the app asks for when none is given (viser takes the next free one if busy).
DEFAULT_PORT = 8080
#: Size of the tip handle's arrows (viser transform controls), m, and their line width, px.
HANDLE_SCALE = 0.15
HANDLE_LINE_WIDTH = 4.0
#: Radius of the tip grip: a sphere at the tool tip that drags the tip in the view plane, m.
GRIP_RADIUS = 0.018
GRIP_COLOR = (255, 190, 40)


def _import_viser() -> Any:
    try:
        import viser
    except ModuleNotFoundError as exc:
        raise ModuleNotFoundError(
            "athenakin.app needs the optional package 'viser': pip install 'athenakin[app]'",
            name="viser") from exc
    return viser


class AthenaApp:
    """The live app: a viser server drawing ATHENA, driven by sliders and a tip handle.

    Parameters
    ----------
    T_b_e : array-like, shape (4, 4), str or Path, optional
        RCM frame, a JSON file ``{"T_b_e": ...}`` or a set-up TOML file. A frame that is
        not rigid is reported in the page (and in :attr:`errors`); the reference set-up is
        used instead.
    design : Design, str or Path, optional
        The design, or a TOML file to load it from. A file that cannot be read, or a
        design that cannot assemble, leaves the app running on the reference design
        with the message shown the same way.
    host : str, keyword-only
        Interface to bind; ``"127.0.0.1"`` (default) serves this machine only.
    port : int, keyword-only
        Port (viser takes the next free one when it is busy; 0: any free port).
    trajectory : str or Path, keyword-only, optional
        Trajectory CSV (``athenakin plan``) to load into the playback tab.
    backend : {"auto", "numba", "numpy"}, keyword-only
    verbose : bool, keyword-only
        viser's own log lines.
    solids : callable, keyword-only, optional
        ``solids(view) -> tuple of Solid``: shaded bodies drawn with the robot at each
        update (e.g. collision bodies), from the :class:`~athenakin.app.AppView` drawn.
    masses : MassModel, str or Path, keyword-only, optional
        Mass model of the force read-out, or a TOML file with a ``[masses]`` table
        (default :meth:`~athenakin.dynamics.MassModel.reference`; app/_forces.py).
    f_max : float or array-like, shape (3,), keyword-only, optional
        Actuator force limits shown and checked, N.
    bodies : athenakin.collision.Bodies, str or Path, keyword-only, optional
        The capsules drawn and checked (clearance read-out, the IK's collision stop, the
        Teleop tab's guard), or a TOML file with a ``[bodies]`` table. Default: the
        default capsules of the design drawn.
    environment : athenakin.collision.Environment, str or Path, keyword-only, optional
        The obstacles: in the clearance read-out and the IK's collision stop, and the
        Teleop tab's virtual fixtures; or a TOML file of ``[[environment.obstacle]]``
        tables. Both are kept in :attr:`bodies` (``app.bodies.bodies``,
        ``app.bodies.environment``). A file that cannot be read or a bad table raises
        before the server starts (:func:`~athenakin.app._bodies.check_collision_models`).
    planned : athenakin.synthesis.Setup, str or Path, keyword-only, optional
        A planned set-up or its file (``athenakin setup plan``): its ``T_b_e`` is the RCM
        frame (give no ``T_b_e``) and its ``[design]`` the design unless ``design`` is
        given (app/_setup_tab.py).
    patient : athenakin.synthesis.Patient, str or Path, keyword-only, optional
        The patient of ``planned`` (or its ``patient.toml``): its meshes drawn where
        ``T_p_b`` places them, with the port and the nominal axis; its surfaces join the
        obstacles as the planner checks them
        (:func:`~athenakin.synthesis.setup_environment`); the app starts with the tool tip
        at the target's centre where the IK reaches it. Both are read and checked before
        the server starts.

    Attributes
    ----------
    url : str
        ``http://HOST:PORT/``.
    errors : list of str
        Start-up problems shown in the page (bad design, frame or trajectory).
    bodies : BodiesLayer
        The solids and the clearance read-out; its ``bodies`` and ``environment`` are the
        app's one copy of the collision models (set them to change the models live).
    """

    def __init__(self, T_b_e: ArrayLike | str | Path | None = None,
                 design: Design | str | Path | None = None, *, host: str = "127.0.0.1",
                 port: int = DEFAULT_PORT, trajectory: str | Path | None = None,
                 backend: str = "auto", verbose: bool = False,
                 solids: Callable[[AppView], tuple[Solid, ...]] | None = None,
                 masses: Any = None, f_max: Any = None,  # forces: app/_forces.py
                 bodies: Any = None, environment: Any = None, planned: Any = None,
                 patient: Any = None) -> None:
        viser = _import_viser()
        # actuator forces: app/_forces.py; bad options raise before the server starts
        from ._forces import ForcesLayer, check_f_max, check_masses

        masses, f_max = check_masses(masses), check_f_max(f_max)
        # a call in the old order (design, T_b_e) is a mistake to raise, not a page message
        check_argument_order(T_b_e, "T_b_e", given_for="frame")
        check_argument_order(design, "design", given_for="design")
        # a planned set-up and its patient (bad files raise before the start): _setup_tab.py
        plan = check_planned(planned, patient)
        if plan is not None:
            if T_b_e is not None:
                raise InvalidInputError("T_b_e: expected none with planned= (the planned "
                                        "set-up holds the RCM frame)")
            T_b_e, design = plan.setup.T_b_e, plan.design if design is None else design
        self._lock = threading.RLock()
        self._echo = Echo()      # this thread is writing GUI values (app/_sync.py)
        self._backend = backend
        self.errors: list[str] = []
        self.setup = load_setup(T_b_e, design, backend=backend, errors=self.errors)
        # the collision models (bad files raise before the server starts): app/_bodies.py
        from ._bodies import BodiesLayer, check_collision_models

        bodies, environment = check_collision_models(bodies, environment, self.setup.design)
        environment = planned_environment(environment, plan)
        self._verbose = verbose
        if verbose:
            self.server = viser.ViserServer(host=host, port=port, verbose=verbose)
        else:  # viser prints its banner whatever ``verbose`` says: keep stdout for the caller
            with contextlib.redirect_stdout(io.StringIO()):
                self.server = viser.ViserServer(host=host, port=port, verbose=verbose)
        self.host = host
        self.port = int(self.server.get_port())
        self.q = self.setup.q_home.copy()
        self.slot: int | str = 0
        start = planned_start(self.setup, plan)      # the tip at the target's centre
        if start is not None:
            self.q, self.slot = start
        self.view: AppView | None = None
        self._dragging = False
        self._grab: tuple[FloatArray, FloatArray] | None = None     # the grip's gesture
        self._moves = OrderedWorker("athena-moves")   # the drags' moves (app/_sync.py)
        self.page = PageWriter(self.server, solids_of=solids)   # the scene nodes it sent
        self._build_gui(plan)
        self.page.send_script(self.title)
        # bodies as solids, closest pair, clearance: app/_bodies.py
        self.bodies = BodiesLayer(self.server, bodies=bodies, environment=environment,
                                  backend=self.setup.backend)
        self.forces = ForcesLayer(self.server, masses=masses, f_max=f_max,  # actuator forces
                                  tip_handle=self._handle, backend=self.setup.backend)
        if trajectory is not None:
            self.playback_tab.load(str(trajectory))
        self._apply_q(self.q, sync_ik=True)
        self.page.frame_camera(self.view)

    @property
    def tip_handle(self) -> Any:
        """The draggable tool-tip handle (viser's transform controls), e.g. to hide it."""
        return self._handle

    @property
    def url(self) -> str:
        """Address of the page."""
        host = "127.0.0.1" if self.host in ("0.0.0.0", "") else self.host
        return f"http://{host}:{self.port}/"

    # ------------------------------------------------------------------ GUI
    def _build_gui(self, plan: PlannedSetup | None) -> None:
        gui, s = self.server.gui, self.setup
        self.server.scene.set_up_direction("+z")
        gui.configure_theme(control_width="large", show_logo=False)
        self._banner = gui.add_html(banner_html(self.setup, self.errors))
        tabs = gui.add_tab_group()
        with tabs.add_tab("Forward"):
            self._q_sliders = []
            for i in range(3):
                lo, hi = float(s.q_lo[i] * 1e3), float(s.q_hi[i] * 1e3)
                sl = gui.add_slider(f"q{i + 1} [mm]", min=lo, max=hi, step=0.5,
                                    initial_value=float(np.clip(self.q[i] * 1e3, lo, hi)),
                                    hint=f"actuator q{i + 1}, stroke {lo:.0f}..{hi:.0f} mm")
                sl.on_update(self._on_q)
                self._q_sliders.append(sl)
            self._slot_dd = gui.add_dropdown("FK slot", options=slot_options(None),
                                             initial_value=slot_options(None)[1])
            self._slot_dd.on_update(self._on_slot)
        with tabs.add_tab("Inverse"):
            L = s.design.tool_length * 1e3
            self._far = rcm_reach(s)
            self._az = gui.add_slider("azimuth [deg]", min=-180.0, max=180.0, step=0.1,
                                      initial_value=0.0, hint="instrument about z_e")
            self._pol = gui.add_slider("polar [deg]", min=0.0, max=180.0, step=0.1,
                                       initial_value=90.0, hint="angle from z_e")
            self._depth = gui.add_slider("tip from RCM [mm]", min=1.0, max=float(L - 1.0),
                                         step=0.5, initial_value=min(250.0, L / 2),
                                         hint="distance of the tool tip from the RCM: below "
                                              "the tool length L when inserted (0 < p < L)")
            for sl in (self._az, self._pol, self._depth):
                sl.on_update(self._on_angles)
            self._handle_cb = gui.add_checkbox(
                "tip handle", initial_value=True,
                hint="drag the yellow ball at the tool tip (in the view plane) or an arrow "
                     "(along one axis)")
            self._handle_cb.on_update(self._on_handle_visible)
        with tabs.add_tab("Playback"):   # a trajectory CSV: app/_playback_tab.py
            self.playback_tab = PlaybackTab(self)
        with tabs.add_tab("Teleop"):     # a virtual master: app/_teleop_tab.py
            from ._teleop_tab import TeleopTab

            self.teleop = TeleopTab(self)
        with tabs.add_tab("Set-up"):     # another set-up, the planned one's patient
            self.setup_tab = SetupTab(self, plan=plan)
        self._status = gui.add_html(message_html("", "ok"))
        self._readouts = gui.add_html("")
        with gui.add_folder("Slots (16 FK solutions)", expand_by_default=False):
            self._slots_html = gui.add_html("")
        self._handle = self.server.scene.add_transform_controls(
            "/tip_handle", scale=HANDLE_SCALE, line_width=HANDLE_LINE_WIDTH,
            disable_rotations=True, depth_test=False)
        self._handle.on_update(self._on_handle)
        self._grip = self.server.scene.add_icosphere(
            "/tip_grip", radius=GRIP_RADIUS, color=GRIP_COLOR, opacity=0.6, subdivisions=2,
            cast_shadow=False, receive_shadow=False)
        self._grip.on_drag("left")(self._on_grip)
        self.server.scene.add_grid("/ground", width=1.2, height=1.2, cell_size=0.05,
                                   section_size=0.25, position=(0.0, 0.25, 0.0))

    # ------------------------------------------------------------------ callbacks
    # viser runs the browser's updates on a thread pool, several at once after quick key
    # presses. Each callback takes the lock *before* it reads the values: the last one to
    # take it then reads the newest values, whatever order the threads ran in (reading
    # first, a callback could apply an older value after a newer one: a lost key press).
    def _on_q(self, _: object) -> None:
        with self._lock:
            if self._echo:
                return
            read = tuple((sl, float(sl.value)) for sl in self._q_sliders)
            q = np.array([v for _, v in read]) * 1e-3
            self._apply_q(q, sync_ik=True, read=read)

    def _on_slot(self, _: object) -> None:
        with self._lock:
            if self._echo:
                return
            v = self._slot_dd.value
            self.slot = "all" if v == _ALL else int(v.split(":")[0].split()[1])
            self._apply_q(self.q, sync_ik=True)

    def _on_angles(self, _: object) -> None:
        with self._lock:
            if self._echo:
                return
            read = tuple((sl, float(sl.value)) for sl in (self._az, self._pol, self._depth))
            az, pol, depth = (v for _, v in read)
            tip = tip_from_angles(math.radians(az), math.radians(pol), depth * 1e-3)
            self._move_tip(tip, snap_angles=True, read=read)

    async def _on_handle(self, event: Any) -> None:
        """A drag of the tip handle: on viser's event loop, in order (app/_sync.py).

        Only the browser fires the handle's events (setting its position here fires
        none), so there is no echo to ignore. The move is :meth:`_drag_move`; the
        handle's position is read here, at its event (the move may run later, after the
        app has placed the handle elsewhere); the drag is over once the end's move has run.
        """
        phase = getattr(event, "phase", "update")
        if phase == "start":
            self._dragging = True
        tip_b = np.array(self._handle.position, dtype=float)
        self._moves.submit(self._drag_move, tip_b, phase == "end")

    def _drag_move(self, tip_b: FloatArray, last: bool) -> None:
        """Move the tip to ``tip_b`` (base frame, m): a move of the handle's or the grip's drag.

        At the end the drag is over, and the handle and the grip are placed on the tip.
        """
        with self._lock:
            T = self.setup.T_b_e
            self._move_tip(T[:3, :3].T @ (tip_b - T[:3, 3]), snap_angles=False)
            if last:
                self._dragging = False
                self._place_handle()

    async def _on_grip(self, event: Any) -> None:
        """A drag of the tip grip: the tip follows the pointer in the view plane.

        On viser's event loop, in order (app/_sync.py): the gesture's grab is never read
        before its start nor after its end. The move (:meth:`_drag_move`) takes the
        newest target, so a slow IK drops the stale ones and the last one applied is the
        end's.
        """
        v = self.view
        if v is None or v.readouts is None:
            return
        if event.phase == "start" or self._grab is None:
            self._dragging = True
            self._grab = (np.asarray(event.start_position, dtype=float),
                          v.readouts.tip_b.copy())
        grab, tip0 = self._grab
        target_b = tip0 + (np.asarray(event.end_position, dtype=float) - grab)
        last = event.phase == "end"
        if last:
            self._grab = None
        self._moves.submit(self._drag_move, target_b, last, newest="grip")

    def _on_handle_visible(self, _: object) -> None:
        self._handle.visible = self._grip.visible = bool(self._handle_cb.value)

    # ------------------------------------------------------------------ actions
    def set_q(self, q: ArrayLike) -> AppView:
        """Move the actuators (m) as the sliders would; returns the new view.

        Parameters
        ----------
        q : array-like, shape (3,)
            Actuators, m.

        Returns
        -------
        AppView
            The view of the new configuration (the IK fields synchronised).
        """
        return self._apply_q(np.asarray(q, dtype=float), sync_ik=True)

    def _move_tip(self, tip_e: FloatArray, *, snap_angles: bool,
                  read: _Read = ()) -> None:
        with self._lock:
            v = self.view
            if v is None or v.readouts is None:
                self._set_status("the tip cannot be moved: no valid configuration", "error")
                return
            r = v.readouts
            # the motion stops before the bodies collide (a move that ignored them could
            # drive the carriages into each other)
            clear = self.bodies.clearance_along(self.setup.T_b_e, self.setup.design,
                                                _inverse_slot(r.slot, r.mode))
            step = inverse_step(self.setup, r.tip_e, tip_e, r.q, r.mode, p_from=r.p,
                                clearance=clear)
            notes = [step.message] if step.message else []
            if self.slot == "all":          # the IK follows the slot drawn solid
                notes.append(f"the tip moves slot {r.slot} (drawn solid); pick 'all valid "
                             f"slots' again to see the others")
            self.slot = _inverse_slot(r.slot, step.mode)
            level = "warn" if step.message else "ok"
            self._apply_q(step.q, sync_ik=not snap_angles or not step.reached,
                          extra=("; ".join(notes), level) if notes else None, read=read)

    def _apply_q(self, q: FloatArray, *, sync_ik: bool,
                 extra: tuple[str, str] | None = None, read: _Read = ()) -> AppView:
        # One atomic block: the scene, the sliders and the read-outs of this q reach the
        # page together, and the event loop is woken once, not once per message.
        with self._lock, self.server.atomic():
            t0 = time.perf_counter()
            try:
                view = forward_view(self.setup, q, slot=self.slot)  # type: ignore[arg-type]
            except (ValueError, TypeError, KinematicsError) as exc:
                self._set_status(_error_text(exc), "error")
                return self.view  # type: ignore[return-value]
            self.q = view.q
            if view.geometry is not None:
                self.view = view
                self.page.draw(view)
                self.bodies.update(view.geometry)    # bodies as solids: app/_bodies.py
                self.forces.update(view.geometry)    # actuator forces: app/_forces.py
            self._sync_gui(view, sync_ik=sync_ik, read=read)
            msg, level = view.message, str(view.level)
            if extra is not None:
                msg = extra[0] + ("; " + msg if msg else "")
                level = "error" if view.level == "error" else extra[1]
            if view.geometry is not None:       # overlapping bodies: said at the top
                note = collision_note(self.bodies.clearance_of(view.geometry))
                if note:
                    msg, level = note + ("; " + msg if msg else ""), "error"
            _, ro, slots = view_html(view)
            self._status.content = message_html(msg, level)
            if ro:
                self._readouts.content = ro
            self._slots_html.content = slots
            self.last_update_s = time.perf_counter() - t0
            return view

    @property
    def title(self) -> str:
        """The page's title: the robot, the design and the app."""
        return page_title(self.setup)

    def _sync_gui(self, view: AppView, *, sync_ik: bool, read: _Read = ()) -> None:
        """Show ``view`` in the GUI's inputs.

        ``read``: the inputs that this update came from, with the values it read.
        """
        with self._echo():
            for i, sl in enumerate(self._q_sliders):
                write_value(sl, float(np.clip(round(view.q[i] * 1e3, 3), sl.min, sl.max)),
                            read)
            opts = slot_options(view)
            if tuple(opts) != tuple(self._slot_dd.options):
                self._slot_dd.options = opts
            want = opts[0] if self.slot == "all" else opts[1 + int(self.slot)]
            if self._slot_dd.value != want:
                self._slot_dd.value = want
            if view.readouts is not None:
                self._set_depth_range(view.readouts.p)
            if sync_ik and view.readouts is not None:
                az, pol, depth = angles_from_tip(view.readouts.tip_e)
                write_value(self._az, float(np.clip(round(math.degrees(az), 2), -180, 180)),
                            read)
                write_value(self._pol, float(np.clip(round(math.degrees(pol), 2), 0, 180)),
                            read)
                write_value(self._depth, float(np.clip(round(depth * 1e3, 2), self._depth.min,
                                                       self._depth.max)), read)
            if not self._dragging:
                self._place_handle()

    def _set_depth_range(self, p: float) -> None:
        """Make the depth slider span the drawn slot's branch of ``p``.

        The slider is the tip's distance from the RCM, ``|L - p|``: below ``L`` for the
        inserted tool (``0 < p < L``), beyond ``L`` for ``p < 0`` (``O_s`` beyond the
        RCM), from 0 for ``p > L`` (the tip behind the RCM).
        """
        L, far = self.setup.design.tool_length * 1e3, self._far * 1e3
        if 0 < p * 1e3 < L:
            lo, hi = 1.0, L - 1.0
        elif p <= 0:
            lo, hi = L + 1.0, L + far
        else:
            lo, hi = 1.0, max(far - L, 2.0)
        if (self._depth.min, self._depth.max) != (lo, hi):
            if self._depth.min < hi:        # keep min < max at every step
                self._depth.max, self._depth.min = hi, lo
            else:
                self._depth.min, self._depth.max = lo, hi
            self._depth.value = float(np.clip(self._depth.value, lo, hi))

    def _place_handle(self) -> None:
        if self.view is not None and self.view.readouts is not None:
            with self._echo():
                tip = tuple(float(x) for x in self.view.readouts.tip_b)
                self._handle.position = tip
                if self._grab is None:
                    self._grip.position = tip

    def _set_status(self, text: str, level: str) -> None:
        self._status.content = message_html(text, level)

    # ------------------------------------------------------------------ set-up
    def use_setup(self, setup: AppSetup) -> AppView:
        """Run on another set-up (design, RCM frame), from its start configuration.

        Parameters
        ----------
        setup : AppSetup
            From :func:`~athenakin.app.app_setup` (the Set-up tab's
            :func:`~athenakin.app._setup_tab.load_setup`).

        Returns
        -------
        AppView
            The view of its start configuration.
        """
        with self._lock:
            self.setup = setup
            self._far = rcm_reach(setup)
            self.errors = []
            self._banner.content = banner_html(self.setup, self.errors)
            self.page.send_script(self.title)
            with self._echo():
                for i, sl in enumerate(self._q_sliders):
                    sl.min, sl.max = float(setup.q_lo[i] * 1e3), float(setup.q_hi[i] * 1e3)
            return self._apply_q(setup.q_home, sync_ik=True)

    # ------------------------------------------------------------------ life cycle
    def stop(self) -> None:
        """Stop the server (the page disconnects)."""
        self.playback_tab.stop()
        self._moves.stop()
        self.forces.stop()
        if self._verbose:
            self.server.stop()
        else:  # viser's stop (which joins its thread) prints a line: keep stdout clean
            with contextlib.redirect_stdout(io.StringIO()):
                self.server.stop()

    def __enter__(self) -> AthenaApp:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


def _inverse_slot(slot: int, mode: int) -> int:
    """The slot with the IK's mode and the branches (sign of ``p``, U, S) of ``slot``."""
    from ..robot import SLOT_P_SIGN, SLOT_UJOINT, SLOT_WRIST, slot_index

    return slot_index(mode, int(SLOT_P_SIGN[slot]), int(SLOT_UJOINT[slot]),
                      int(SLOT_WRIST[slot]))


def launch(T_b_e: ArrayLike | str | Path | None = None, design: Design | str | Path | None = None,
           *, host: str = "127.0.0.1", port: int = DEFAULT_PORT,
           trajectory: str | Path | None = None, backend: str = "auto",
           masses: Any = None, f_max: Any = None,  # forces: app/_forces.py
           bodies: Any = None, environment: Any = None, planned: Any = None,
           patient: Any = None) -> AthenaApp:
    """Start the app in the background (e.g. from a notebook) and print its address.

    Parameters
    ----------
    T_b_e, design, host, port, trajectory, backend, masses, f_max, bodies, environment
        As in :class:`AthenaApp` (``environment="anatomy.toml"``: the obstacles of a file,
        drawn as the Teleop tab's virtual fixtures).
    planned, patient
        As in :class:`AthenaApp` (``planned="setup.toml", patient="patient.toml"``).

    Returns
    -------
    AthenaApp
        Call :meth:`AthenaApp.stop` to end it.
    """
    app = AthenaApp(T_b_e, design, host=host, port=port, trajectory=trajectory,
                    backend=backend, masses=masses, f_max=f_max, bodies=bodies,
                    environment=environment, planned=planned, patient=patient)
    for e in app.errors:
        print(f"athenakin app: {e}", file=sys.stderr)
    print(f"athenakin app: ATHENA at {app.url}")
    return app
