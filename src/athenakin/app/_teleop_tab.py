"""The Teleop tab in viser: a draggable master handle drives :class:`athenakin.teleop.Teleop`.

The logic is :mod:`athenakin.app._teleop` (pure); this module only turns its results into
GUI values and scene nodes. A thread runs the cycles on the app's clock at
:data:`~athenakin.app._teleop.TELEOP_RATE` while teleoperation is on, draws the robot
through the app's own :meth:`~athenakin.app.AthenaApp.set_q` when the command moved,
and shows the flags every cycle they change. Controls:

* **start / stop teleop**; the master handle (transform controls, translation only)
  appears at the tool tip, and its numeric field ``handle [mm]`` (base frame) moves it too;
* **clutch**: a button that toggles, and a held clutch: the button *hold to clutch*, or
  the key **C** held while the Teleop tab is shown. The first hold message opens it and
  the button's release (its click) closes it, so a loaded server that handles the
  repeated hold messages late never re-engages while the button is still held; the
  messages are handled in their order of arrival (coroutine callbacks on viser's event
  loop, not its thread pool). viser (1.1.1) reports no key events to Python (its
  hotkeys fire once, on the press), so a page script turns the held key into a held
  press of that button and its release into the button's release. A press that ends
  without a click (a cancelled touch) leaves the clutch open, the safe side: the tip
  holds until the button is pressed and released again;
* **scale** (0.05..1.0), changed at any time without a tip jump (``Teleop.set_scale``);
* **pause master**: no samples, the watchdog holds the robot after 30 ms;
* **E-STOP** and **release**.

The environment's obstacles (``app.bodies.environment``) are drawn as the virtual
fixtures and passed to the core with the app's bodies (clearance guard). Teleoperation
stops by itself when the robot is moved from another tab, the set-up changes or the
page closes.
"""

from __future__ import annotations

import dataclasses
import json
import threading
import time
from typing import Any

import numpy as np

from .._validation import check_array
from ..errors import InvalidInputError, KinematicsError
from ._script import run_page_script
from ._teleop import (
    SCALE_RANGE,
    TELEOP_RATE,
    Master,
    TeleopFrame,
    fixture_solids,
    hold_clutch,
    start_teleop,
    teleop_cycles,
    teleop_frame,
    teleop_html,
    teleop_scene,
)

__all__ = ["TeleopTab", "CLUTCH_KEY", "HOLD_LABEL"]

#: The key (``event.code``) that holds the clutch open while pressed.
CLUTCH_KEY = "KeyC"
#: Label of the hold button (the page script finds it by this text).
HOLD_LABEL = "hold to clutch (or hold C)"
#: Most redraws of the robot per second (the cycles run at TELEOP_RATE).
DRAW_HZ = 20.0
#: Largest difference between the app's q and the last drawn command before the tab
#: takes the robot as moved from elsewhere, m.
MOVED_TOL_M = 1e-9
_HANDLE_SCALE = 0.12


def _clutch_key_script() -> str:
    """Page script: the held key C presses the visible hold button; its key-up releases it.

    The release also clicks the button: the click is the release the server acts on.
    """
    return (
        "if (!window.__athenakinClutch) { window.__athenakinClutch = true; let held = null;"
        f" const label = {json.dumps(HOLD_LABEL)}, code = {json.dumps(CLUTCH_KEY)};"
        " const opts = {bubbles: true, button: 0, pointerId: 1, isPrimary: true};"
        " const up = () => { if (held) { held.dispatchEvent(new PointerEvent('pointerup', opts));"
        " held.click(); held = null; } };"
        " document.addEventListener('keydown', (e) => { const t = e.target;"
        " if (e.code !== code || e.repeat || held || t instanceof HTMLInputElement"
        " || t instanceof HTMLTextAreaElement) return;"
        " const b = [...document.querySelectorAll('button')].find((x) =>"
        " x.textContent.trim() === label && x.offsetParent !== null);"
        " if (b) { held = b; b.dispatchEvent(new PointerEvent('pointerdown', opts)); } });"
        " document.addEventListener('keyup', (e) => { if (e.code === code) up(); });"
        " window.addEventListener('blur', up); }")


class TeleopTab:
    """The Teleop tab's controls, built inside the open tab of ``app``'s tab group.

    Parameters
    ----------
    app : AthenaApp
        Read: ``setup``, ``q``, ``slot``, ``view``, ``bodies``, ``server``; written
        through :meth:`AthenaApp.set_q` only.

    Attributes
    ----------
    frame : TeleopFrame or None
        The last cycle shown (None while off).
    tele : athenakin.teleop.Teleop or None
    master : Master or None
    error : Exception or None
        An unexpected error that stopped the loop (also said in the tab).
    """

    def __init__(self, app: Any) -> None:
        self.app, self.server = app, app.server
        self.tele: Any = None
        self.master: Master | None = None
        self.frame: TeleopFrame | None = None
        self._lock = threading.RLock()
        self._run: object | None = None           # the running loop's token
        self._t0 = time.perf_counter()
        self._nodes: dict[str, Any] = {}
        self._tip_visible = True
        self.error: BaseException | None = None   # what stopped the loop, if not a user
        self._build()
        run_page_script(self.server, _clutch_key_script())

    def _build(self) -> None:
        gui = self.server.gui
        self.start_btn = gui.add_button("start teleop", hint="the handle at the tool tip "
                                        "becomes the master; the tip follows it, scaled")
        self.start_btn.on_click(lambda _: self.stop() if self.running else self.start())
        self.clutch_btn = gui.add_button("clutch: closed (click to open)", disabled=True)
        self.clutch_btn.on_click(lambda _: self._toggle_clutch())
        self.hold_btn = gui.add_button(HOLD_LABEL, disabled=True,
                                       hint="the master moves freely while held; the tip holds")
        self.hold_btn.on_hold(self._on_hold, callback_hz=20.0)
        self.hold_btn.on_click(self._on_hold_released)
        self.scale = gui.add_slider("scale", min=SCALE_RANGE[0], max=SCALE_RANGE[1], step=0.01,
                                    initial_value=0.2, hint="tip motion per master motion")
        self.scale.on_update(lambda _: self._set_scale())
        self.pause = gui.add_checkbox("pause master", initial_value=False,
                                      hint="no master samples: the watchdog holds the robot")
        self.pause.on_update(lambda _: self._update_master(paused=bool(self.pause.value)))
        self.handle_mm = gui.add_vector3("handle [mm]", initial_value=(0.0, 0.0, 0.0), step=1.0,
                                         disabled=True, hint="master handle, base frame")
        self.handle_mm.on_update(lambda _: self._on_handle_mm())
        self.estop_btn = gui.add_button("E-STOP", color="red", disabled=True)
        self.estop_btn.on_click(lambda _: self._estop(True))
        self.release_btn = gui.add_button("release e-stop", disabled=True)
        self.release_btn.on_click(lambda _: self._estop(False))
        self.readout = gui.add_html(teleop_html(None))
        self._handle = self.server.scene.add_transform_controls(
            "/teleop/handle", scale=_HANDLE_SCALE, line_width=3.0, disable_rotations=True,
            depth_test=False, visible=False)
        self._handle.on_update(lambda _: self._on_handle())

    # ------------------------------------------------------------------ state
    @property
    def running(self) -> bool:
        """Whether teleoperation is on."""
        return self._run is not None

    def _now(self) -> float:
        return time.perf_counter() - self._t0

    async def _on_hold(self, _: Any) -> None:
        """A hold message of the hold button (coroutine: handled in arrival order)."""
        with self._lock:
            if self.master is not None and not self.master.held:
                self.master = hold_clutch(self.master)

    async def _on_hold_released(self, _: Any) -> None:
        """The hold button's click: its release (coroutine: after its hold messages)."""
        with self._lock:
            if self.master is not None and self.master.held:
                self.master = hold_clutch(self.master, held=False)

    def _update_master(self, **changes: Any) -> None:
        with self._lock:
            if self.master is None:
                return
            self.master = dataclasses.replace(self.master, **changes)
        if "clutched" in changes:
            self.clutch_btn.label = ("clutch: OPEN, tip holds (click to close)"
                                     if changes["clutched"] else "clutch: closed (click to open)")

    def _toggle_clutch(self) -> None:
        m = self.master
        if m is not None:
            self._update_master(clutched=not m.clutched)

    def set_handle(self, handle_b: Any, *, drawn: bool = False) -> None:
        """Move the master handle to ``handle_b`` (base frame, m), as a drag would.

        ``drawn``: the browser has put the handle there already (a drag): only the master
        and the numeric field follow (writing the position back could undo a newer one).
        """
        p = check_array(handle_b, "handle_b", (3,), allow_nonfinite=True)
        if p.shape != (3,):
            raise InvalidInputError(f"handle_b: expected shape (3,), got shape {p.shape}")
        h = (float(p[0]), float(p[1]), float(p[2]))
        self._update_master(handle_b=h)
        if np.all(np.isfinite(h)):
            if not drawn:
                self._handle.position = h
            mm = tuple(round(x * 1e3, 3) for x in h)
            if tuple(self.handle_mm.value) != mm:
                self.handle_mm.value = mm

    def _on_handle(self) -> None:
        self.set_handle(self._handle.position, drawn=True)

    def _on_handle_mm(self) -> None:
        h = np.asarray(self.handle_mm.value, dtype=float) * 1e-3
        if self.master is not None and not np.allclose(h, self.master.handle_b, rtol=0,
                                                       atol=5e-7):
            self.set_handle(h)

    def _set_scale(self) -> None:
        with self._lock:
            if self.tele is not None:
                self.tele.set_scale(float(self.scale.value))

    def _estop(self, on: bool) -> None:
        with self._lock:
            if self.tele is not None:
                self.tele.estop() if on else self.tele.release()

    # ------------------------------------------------------------------ life cycle
    def start(self) -> None:
        """Start teleoperation at the configuration drawn (a message says why it cannot)."""
        app = self.app
        view = app.view
        if self.running or view is None or view.geometry is None:
            return
        from ..collision import Bodies

        env, bodies = app.bodies.environment, app.bodies.bodies   # as the Inverse tab's
        try:                                                        # collision stop
            tele, master = start_teleop(
                app.setup, view.q, slot=view.geometry.slot, scale=float(self.scale.value),
                environment=env,
                bodies=bodies if bodies is not None else Bodies.default(app.setup.design))
        except (ValueError, TypeError, KinematicsError) as exc:
            self.readout.content = teleop_html(None, note=f"cannot start: {exc}")
            return
        master = dataclasses.replace(master, paused=bool(self.pause.value))
        with self._lock:
            self.tele, self.master, self.frame = tele, master, None
            self._run = token = object()
        self._draw_fixtures(fixture_solids(env))
        self.set_handle(master.handle_b)
        self._handle.visible = True
        self._tip_visible = bool(app.tip_handle.visible)   # the IK handle, back on stop
        app.tip_handle.visible = False
        for b in (self.clutch_btn, self.hold_btn, self.handle_mm, self.estop_btn,
                  self.release_btn):
            b.disabled = False
        self.start_btn.label = "stop teleop"
        threading.Thread(target=self._loop, args=(token, app.setup), daemon=True,
                         name="athenakin-teleop").start()

    def stop(self, note: str = "") -> None:
        """Stop teleoperation (the robot stays where it is)."""
        with self._lock:                         # not while the loop sends a frame
            self._run = None
            self.tele = self.master = self.frame = None
            self._handle.visible = False
            self.app.tip_handle.visible = self._tip_visible
            for b in (self.clutch_btn, self.hold_btn, self.handle_mm, self.estop_btn,
                      self.release_btn):
                b.disabled = True
            self.clutch_btn.label = "clutch: closed (click to open)"
            self.start_btn.label = "start teleop"
            self._draw_fixtures(())
            for name in [n for n in self._nodes if not n.startswith("fixture_")]:
                self._nodes.pop(name).remove()
            self.readout.content = teleop_html(None, note=note)

    def _loop(self, token: object, setup: Any) -> None:
        """The cycles on the app's clock; an unexpected error stops them, said in the tab."""
        try:
            self._cycles(token, setup)
        except Exception as exc:                 # a GUI thread: report, never die silently
            self.error = exc
            self._stop_run(token, f"stopped: {type(exc).__name__}: {exc}")

    def _stop_run(self, token: object, note: str) -> None:
        """Stop the run of ``token`` (not one started since)."""
        with self._lock:
            if self._run is token:
                self.stop(note)

    def _cycles(self, token: object, setup: Any) -> None:
        """Run the cycles due, redraw the robot at most DRAW_HZ times a second."""
        dt, t_last, t_draw, shown = 1.0 / TELEOP_RATE, self._now(), -1.0, ""
        drawn = np.asarray(self.app.q, dtype=float)
        while self._run is token:
            if self.app.setup is not setup or not self.server.get_clients():
                self._stop_run(token, "stopped: the set-up changed"
                               if self.app.setup is not setup else "stopped: the page closed")
                return
            with self._lock:
                master = self.master
                if self._run is not token or master is None:
                    return
                cmd, t_last = teleop_cycles(self.tele, master, t_last, self._now())
                frame = None if cmd is None else teleop_frame(self.tele, master, cmd)
                self.frame = frame or self.frame
            if frame is not None:
                if np.max(np.abs(np.asarray(self.app.q) - drawn)) > MOVED_TOL_M:
                    self._stop_run(token, "stopped: the robot was moved from another tab")
                    return
                if (np.max(np.abs(frame.q - drawn)) > 0 and self._now() - t_draw
                        >= 1.0 / DRAW_HZ):
                    self.app.slot = frame.slot
                    drawn, t_draw = np.asarray(self.app.set_q(frame.q).q), self._now()
                with self._lock:
                    if self._run is not token:
                        return
                    shown = self._show(frame, shown)
            time.sleep(max(0.0, t_last + dt - self._now()))

    def _show(self, frame: TeleopFrame, shown: str) -> str:
        """Send the tips and the read-out of ``frame`` (the read-out only when it changed)."""
        scene, nodes = teleop_scene(frame), self._nodes
        with self.server.atomic():
            ps = scene.points[0]
            h = nodes.get(ps.name)
            if h is not None and len(h.points) == len(ps.points):
                h.points = ps.points.astype(np.float32)
            else:
                if h is not None:
                    h.remove()
                nodes[ps.name] = self.server.scene.add_point_cloud(
                    f"/teleop/{ps.name}", points=ps.points.astype(np.float32),
                    colors=ps.colors, point_size=ps.size, point_shape="circle")
            line = nodes.pop("teleop_correction", None)
            if scene.lines and line is not None:
                line.points = scene.lines[0].segments.astype(np.float32)
            elif scene.lines:
                ls = scene.lines[0]
                line = self.server.scene.add_line_segments(
                    f"/teleop/{ls.name}", points=ls.segments.astype(np.float32),
                    colors=ls.color, thickness=ls.width, thickness_units="screen")
            elif line is not None:
                line.remove()
                line = None
            if line is not None:
                nodes["teleop_correction"] = line
            text = teleop_html(frame)
            if text != shown:
                self.readout.content = text
        return text

    def _draw_fixtures(self, solids: tuple[Any, ...]) -> None:
        for name in [n for n in self._nodes if n.startswith("fixture_")]:
            self._nodes.pop(name).remove()
        for so in solids:
            self._nodes[so.name] = self.server.scene.add_mesh_simple(
                f"/teleop/fixtures/{so.name}", np.asarray(so.vertices, dtype=np.float32),
                np.asarray(so.faces, dtype=np.uint32), color=so.color, opacity=so.opacity,
                flat_shading=True, cast_shadow=False, receive_shadow=False)
