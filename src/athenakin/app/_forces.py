"""The actuator forces in the live app: gravity plus a tip force the user drags.

The pure part (numpy only, testable without a browser): :func:`forces_view` computes,
for the drawn solution (:class:`~athenakin.plot.RobotGeometry`), the actuator forces
``(f1, f2, f3)`` that hold it still against gravity and a tip force, and the load on the
RCM mount (:func:`athenakin.dynamics.statics` of the drawn slot);
:func:`tip_force_from_handle` / :func:`handle_from_tip_force` map the draggable
handle's position to the tip force and back (:data:`FORCE_SCALE_M_PER_N`);
:func:`check_f_max`, :func:`check_masses`, :func:`check_tip_force` are the boundary
checks of the options; :func:`forces_html` is the read-out (one bar per actuator,
coloured by the share of its limit). :class:`ForcesLayer` sends them to a viser scene;
the app calls :meth:`ForcesLayer.update` after its page writer drew the robot.

Conventions (docs/conventions.md, "Forces"): actuator forces are positive along
increasing ``q1, q2, q3`` (N); the tip force is the force the environment applies to
the tool tip, base frame, N.
"""

from __future__ import annotations

import dataclasses
import html
import math
import threading
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import BoolArray, FloatArray
from .._validation import check_array
from ..errors import InvalidInputError, KinematicsError
from ..plot._geometry import RobotGeometry
from ._scene import rgb
from ._sync import Echo, OrderedWorker
from ._text import ERROR_COLOR, WARN_COLOR

__all__ = ["ForcesView", "forces_view", "forces_html", "tip_force_from_handle",
           "handle_from_tip_force", "check_f_max", "check_masses", "check_tip_force",
           "ForcesLayer", "FORCE_SCALE_M_PER_N", "MAX_TIP_FORCE_N", "WARN_SHARE",
           "TIP_FORCE_COLOR"]

#: Length of the drawn tip-force arrow per newton, m/N (10 N: 50 mm). Dragging the
#: handle by ``d`` metres changes the tip force by ``d / FORCE_SCALE_M_PER_N`` newtons.
FORCE_SCALE_M_PER_N = 0.005
#: Largest tip force the app takes (from the handle or the numeric input), N. A handle
#: dragged further gives a force of this size in the direction dragged.
MAX_TIP_FORCE_N = 500.0
#: A force is drawn in the warning colour from this share of its limit on.
WARN_SHARE = 0.8
#: Colour of the tip-force arrow and of the bars within their limits.
TIP_FORCE_COLOR = "#16a085"
#: Scale of the tip-force handle's gizmo (the tip handle's is 0.08).
HANDLE_SCALE = 0.06


@dataclasses.dataclass(frozen=True)
class ForcesView:
    """The static forces of one drawn solution.

    Attributes
    ----------
    q : ndarray, shape (3,)
        Actuators, m.
    slot : int
        Forward-kinematics slot of the drawn solution.
    forces : ndarray, shape (3,)
        ``(f1, f2, f3)``, N, positive along increasing ``q``: what the actuators push to
        hold the robot still against gravity and ``tip_force``
        (:func:`athenakin.dynamics.actuator_forces`).
    gravity_forces : ndarray, shape (3,)
        The part of ``forces`` that holds the weight alone (``forces + J^T tip_force``
        with ``J = d tip / d q``), N.
    tip_force : ndarray, shape (3,)
        Force the environment applies to the tool tip, base frame, N.
    rcm_force : ndarray, shape (3,)
        Force the robot exerts on the fixed mount of the spherical mechanism at the
        RCM, base frame, N.
    rcm_moment : ndarray, shape (3,)
        Moment about the RCM on that mount, base frame, N m.
    f_max : ndarray, shape (3,), or None
        Actuator force limits, N (``|f_i| <= f_max_i``); None: no limits given.
    over : ndarray of bool, shape (3,)
        ``|f_i| > f_max_i`` (all False without limits).
    """

    q: FloatArray
    slot: int
    forces: FloatArray
    gravity_forces: FloatArray
    tip_force: FloatArray
    rcm_force: FloatArray
    rcm_moment: FloatArray
    f_max: FloatArray | None
    over: BoolArray

    @property
    def exceeded(self) -> bool:
        """Some actuator force exceeds its limit."""
        return bool(np.any(self.over))


# ---------------------------------------------------------------------- boundary checks
def check_f_max(f_max: ArrayLike | None) -> FloatArray | None:
    """Actuator force limits as shape (3,), N, or None.

    Parameters
    ----------
    f_max : float, array-like of shape (3,), or None
        One limit for all three actuators or one each; each positive and finite.

    Raises
    ------
    InvalidInputError
        A limit that is not positive or not finite, or not 1 or 3 values.
    """
    if f_max is None:
        return None
    try:
        a = np.asarray(f_max, dtype=float)
    except (TypeError, ValueError):
        a = np.zeros((0,))
    if isinstance(f_max, (str, bytes, bool)) or a.ndim > 1 or a.size not in (1, 3):
        raise InvalidInputError(f"f_max: expected one force limit or three (N, positive), got "
                                f"{f_max!r}")
    out = np.broadcast_to(a.reshape(-1), (3,)).copy()
    if not np.all(np.isfinite(out)) or not np.all(out > 0):
        raise InvalidInputError(f"f_max: expected positive, finite force limits (N), got "
                                f"{out.tolist()}")
    return out


def check_masses(masses: object) -> Any:
    """The mass model: None (the reference model of the drawn design), or a MassModel.

    Parameters
    ----------
    masses : MassModel, str, Path or None
        A model, or a TOML file with a ``[masses]`` table
        (:meth:`athenakin.dynamics.MassModel.from_toml`).

    Returns
    -------
    MassModel or None

    Raises
    ------
    InvalidInputError
        A file that cannot be read, has no ``[masses]`` table or a bad entry (the
        message names ``masses`` and the file).
    TypeError
        Neither a MassModel, a path nor None.
    """
    from ..dynamics import MassModel

    if masses is None or isinstance(masses, MassModel):
        return masses
    if not isinstance(masses, (str, Path)):
        raise TypeError(f"masses: expected a MassModel, a TOML file or None, got "
                        f"{type(masses).__name__}")
    if str(masses) == "":
        raise InvalidInputError("masses: expected a TOML file, got an empty path")
    try:
        return MassModel.from_toml(masses)
    except OSError as exc:
        raise InvalidInputError(f"masses: cannot read {masses} "
                                f"({exc.strerror or type(exc).__name__})") from None
    except (InvalidInputError, TypeError) as exc:
        raise InvalidInputError(f"masses: {exc}") from None


def check_tip_force(tip_force: ArrayLike | None) -> FloatArray:
    """A tip force as shape (3,), N (None: zero); at most :data:`MAX_TIP_FORCE_N` long.

    Raises
    ------
    InvalidInputError
        Not three finite numbers, or longer than :data:`MAX_TIP_FORCE_N`.
    """
    if tip_force is None:
        return np.zeros(3)
    f = check_array(tip_force, "tip_force", (3,))
    if f.ndim != 1:
        raise InvalidInputError(f"tip_force: expected one force of shape (3,), got shape "
                                f"{f.shape}")
    n = float(np.linalg.norm(f))
    if n > MAX_TIP_FORCE_N:
        raise InvalidInputError(f"tip_force: expected at most {MAX_TIP_FORCE_N:g} N, got "
                                f"{n:.6g} N")
    return f.copy()


# ---------------------------------------------------------------------- the handle
def tip_force_from_handle(handle_b: ArrayLike, tip_b: ArrayLike, *,
                          scale: float = FORCE_SCALE_M_PER_N) -> FloatArray:
    """The tip force that a handle at ``handle_b`` sets: ``(handle_b - tip_b) / scale``.

    Parameters
    ----------
    handle_b, tip_b : array-like, shape (3,)
        The handle's position and the tool tip, base frame, m.
    scale : float, keyword-only
        Arrow length per newton, m/N.

    Returns
    -------
    ndarray, shape (3,)
        Base frame, N; a longer force is cut to :data:`MAX_TIP_FORCE_N` along the
        same direction.
    """
    h = check_array(handle_b, "handle_b", (3,))
    t = check_array(tip_b, "tip_b", (3,))
    if not (math.isfinite(scale) and scale > 0):
        raise InvalidInputError(f"scale: expected a positive length per newton, got {scale}")
    f = (h - t) / scale
    n = float(np.linalg.norm(f))
    return f * (MAX_TIP_FORCE_N / n) if n > MAX_TIP_FORCE_N else f


def handle_from_tip_force(tip_force: ArrayLike, tip_b: ArrayLike, *,
                          scale: float = FORCE_SCALE_M_PER_N) -> FloatArray:
    """Where the handle of ``tip_force`` sits: the head of its arrow, ``tip_b + scale f``.

    Inverse of :func:`tip_force_from_handle` (within :data:`MAX_TIP_FORCE_N`).
    """
    return (check_array(tip_b, "tip_b", (3,))
            + scale * check_array(tip_force, "tip_force", (3,)))


# ---------------------------------------------------------------------- the numbers
def forces_view(g: RobotGeometry, *, masses: Any = None, tip_force: ArrayLike | None = None,
                f_max: ArrayLike | None = None, backend: str = "auto") -> ForcesView:
    """The actuator forces holding the drawn solution ``g`` still, and the RCM load.

    Parameters
    ----------
    g : RobotGeometry
        The solution drawn (its ``q``, ``T_b_e``, ``design`` and ``slot``).
    masses : MassModel, keyword-only, optional
        Default :meth:`MassModel.reference(g.design) <athenakin.dynamics.MassModel.reference>`.
    tip_force : array-like, shape (3,), keyword-only, optional
        Force on the tool tip, base frame, N (default zero).
    f_max : float or array-like, shape (3,), keyword-only, optional
        Actuator force limits, N.
    backend : {"auto", "numpy", "numba"}, keyword-only
        The backend of :func:`athenakin.dynamics.statics`.

    Returns
    -------
    ForcesView

    Raises
    ------
    SingularConfigurationError
        ``g`` lies on a singular set of the statics.
    """
    from ..dynamics import statics

    if not isinstance(g, RobotGeometry):
        raise TypeError(f"g: expected a RobotGeometry, got {type(g).__name__}")
    m = check_masses(masses)
    f_tip = check_tip_force(tip_force)
    lim = check_f_max(f_max)
    st = statics(g.q, g.T_b_e, g.design, masses=m, tip_force=f_tip, slot=int(g.slot),
                 backend=backend)  # type: ignore[arg-type]
    forces = np.asarray(st.forces, dtype=float)
    gravity_forces = forces + np.asarray(st.tip_jacobian).T @ f_tip
    over = (np.abs(forces) > lim) if lim is not None else np.zeros(3, dtype=bool)
    return ForcesView(q=np.asarray(g.q, dtype=float).copy(), slot=int(g.slot), forces=forces,
                      gravity_forces=gravity_forces, tip_force=f_tip,
                      rcm_force=np.asarray(st.rcm_force, dtype=float),
                      rcm_moment=np.asarray(st.rcm_moment, dtype=float), f_max=lim, over=over)


def _fmt(x: float, nd: int = 2) -> str:
    text = f"{x:+.{nd}f}"
    return text.replace("-", "+", 1) if float(text) == 0 else text


def _bar(f: float, ref: float, color: str) -> str:
    """A two-sided bar: right of the centre for a positive force, left for a negative one."""
    w = 50.0 * min(abs(f) / ref, 1.0) if ref > 0 else 0.0
    left = 50.0 if f >= 0 else 50.0 - w
    return ('<div style="position:relative;height:0.8em;background:#eee;min-width:5em">'
            f'<div style="position:absolute;left:{left:.2f}%;width:{w:.2f}%;top:0;bottom:0;'
            f'background:{color}"></div>'
            '<div style="position:absolute;left:50%;top:0;bottom:0;width:1px;'
            'background:#888"></div></div>')


def forces_html(fv: ForcesView) -> str:
    """The read-out: f1..f3 with a bar each, the limits, the tip force and the RCM load.

    With limits, each bar is full at ``f_max_i`` and turns orange from
    :data:`WARN_SHARE` of it and red beyond it (the line under the table names the
    actuators over their limits); without, the bars share the largest ``|f_i|``.
    Cells carry ``data-force="f1"`` ... with ``data-force-n`` (the value, N) and
    ``data-over="1"`` beyond a limit; the summary ``data-force="status"``.
    """
    lim = fv.f_max
    ref = float(np.max(np.abs(fv.forces))) if lim is None else 0.0
    rows = []
    for i in range(3):
        f = float(fv.forces[i])
        if lim is None:
            color, share, bound = TIP_FORCE_COLOR, "", ""
        else:
            s = abs(f) / float(lim[i])
            color = (ERROR_COLOR if fv.over[i] else WARN_COLOR if s >= WARN_SHARE
                     else TIP_FORCE_COLOR)
            share, bound = f"{100 * s:.0f}%", f"/ {float(lim[i]):g}"
        over = ' data-over="1"' if fv.over[i] else ""
        style = f"text-align:right;{f'color:{ERROR_COLOR};font-weight:bold' if fv.over[i] else ''}"
        rows.append(
            f'<tr title="gravity alone: {_fmt(float(fv.gravity_forces[i]))} N">'
            f"<td>f{i + 1} [N]</td>"
            f'<td data-force="f{i + 1}" data-force-n="{f!r}"{over} style="{style}">'
            f"{_fmt(f)}</td><td style='text-align:right'>{bound}</td>"
            f"<td style='width:45%'>{_bar(f, float(lim[i]) if lim is not None else ref, color)}"
            f"</td><td style='text-align:right'>{share}</td></tr>")
    p = '<p data-force="status" data-level="{}" style="margin:0;font-size:0.85em;{}">{}</p>'
    if lim is None:
        status = p.format("ok", "", "no force limits given (--f-max)")
    elif fv.exceeded:
        names = ", ".join(f"f{i + 1} ({_fmt(float(fv.forces[i]))} N, limit {float(lim[i]):g} N)"
                          for i in np.flatnonzero(fv.over))
        status = p.format("error", f"color:{ERROR_COLOR}",
                          f"<b>over the limit</b>: {html.escape(names)}")
    else:
        status = p.format("ok", "", "within the limits")
    t, r = fv.tip_force, fv.rcm_force
    tip = ", ".join(_fmt(float(x), 1) for x in t)
    rcm = ", ".join(_fmt(float(x), 1) for x in r)
    return ('<div data-force="panel">'
            f'<table style="font-size:0.8em;border-collapse:collapse;width:100%">'
            f"{''.join(rows)}</table>{status}"
            f'<p style="margin:0;font-size:0.8em">tip force (base) '
            f'<span data-force="tip">[{tip}]</span> N, |F| {float(np.linalg.norm(t)):.1f} N; '
            f'RCM load <span data-force="rcm">[{rcm}]</span> N, '
            f"|M| {float(np.linalg.norm(fv.rcm_moment)):.3f} N m (slot {fv.slot})</p></div>")


# ---------------------------------------------------------------------- the viser layer
class ForcesLayer:
    """The actuator forces in a viser scene: read-out, tip-force arrow and handle.

    GUI (a folder *Actuator forces*): a checkbox that shows or hides the forces; the tip
    force as a numeric vector (N, base frame); *drag tip force*, which shows a handle at
    the head of the tip-force arrow (and hides the tip-move handle while it is on); a
    reset button; the read-out (:func:`forces_html`).

    Parameters
    ----------
    server : viser.ViserServer
    masses : MassModel, str or Path, keyword-only, optional
        As :func:`check_masses` (default: the reference model of the drawn design).
    f_max : float or array-like, shape (3,), keyword-only, optional
        Actuator force limits, N.
    tip_handle : viser transform-controls handle, keyword-only, optional
        The app's tip-move handle, hidden while the tip-force handle is shown.
    visible : bool, keyword-only
        Initial state of the "actuator forces" checkbox.
    backend : {"auto", "numpy", "numba"}, keyword-only
        The backend of the statics.
    """

    def __init__(self, server: Any, *, masses: Any = None, f_max: ArrayLike | None = None,
                 tip_handle: Any = None, visible: bool = True, backend: str = "auto") -> None:
        self.backend = backend
        self.masses = check_masses(masses)
        self.f_max = check_f_max(f_max)
        self.server = server
        self.tip_force = np.zeros(3)
        self.view: ForcesView | None = None
        self.message = ""
        self._tip_handle = tip_handle
        self._tip_handle_was_visible = True
        self._geometry: RobotGeometry | None = None
        self._lock = threading.RLock()
        self._echo = Echo()   # this thread writes the GUI's values (app/_sync.py)
        self._dragging = False
        self._moves = OrderedWorker("athena-forces")   # the handle's moves (app/_sync.py)
        self._arrow: Any = None
        self._last_key: tuple[object, ...] | None = None
        self._reference: tuple[Any, Any] | None = None
        gui = server.gui
        with gui.add_folder("Actuator forces"):
            self.checkbox = gui.add_checkbox(
                "actuator forces", initial_value=visible,
                hint="forces f1, f2, f3 holding the robot against gravity and the tip force")
            self.force_input = gui.add_vector3(
                "tip force [N]", initial_value=(0.0, 0.0, 0.0), step=0.1,
                hint="force on the tool tip, base frame x, y, z")
            self.drag_checkbox = gui.add_checkbox(
                "drag tip force", initial_value=False,
                hint=f"a handle at the head of the tip-force arrow "
                     f"({FORCE_SCALE_M_PER_N * 1e3:g} mm per N)")
            self.reset_button = gui.add_button("reset tip force")
            self.readout = gui.add_html("")
        self.handle = server.scene.add_transform_controls(
            "/forces/handle", scale=HANDLE_SCALE, disable_rotations=True, depth_test=False,
            visible=False)
        self.checkbox.on_update(lambda _: self.update(self._geometry))
        self.force_input.on_update(self._on_input)
        self.drag_checkbox.on_update(lambda _: self._show_handle())
        self.reset_button.on_click(lambda _: self.set_tip_force(np.zeros(3)))
        self.handle.on_update(self._on_handle)

    # ------------------------------------------------------------------ actions
    def set_tip_force(self, tip_force: ArrayLike, *, place_handle: bool = True) -> None:
        """Set the tip force (N, base frame) and redraw; a bad value is shown, not kept."""
        try:
            f = check_tip_force(tip_force)
        except (ValueError, TypeError) as exc:
            with self._lock:
                self.message = f"{type(exc).__name__}: {exc}"
                self.readout.content = _message(self.message)
            return
        with self._lock, self.server.atomic():
            self.tip_force = f
            with self._echo():
                v = tuple(round(float(x), 3) for x in f)
                if tuple(self.force_input.value) != v:
                    self.force_input.value = v
            self._redraw(place_handle=place_handle)

    def update(self, g: RobotGeometry | None) -> ForcesView | None:
        """Compute and draw the forces of ``g`` (None, or unchecked: nothing is drawn)."""
        with self._lock:
            self._geometry = g
            return self._redraw(place_handle=not self._dragging)

    # ------------------------------------------------------------------ callbacks
    def _on_input(self, _: object) -> None:
        with self._lock:        # then read: the last of quick updates reads the newest value
            if self._echo:
                return
            self.set_tip_force(np.asarray(self.force_input.value, dtype=float))

    async def _on_handle(self, event: Any) -> None:
        """A drag of the force handle: on viser's event loop, in order (app/_sync.py).

        The handle's position is read here, at its event; the drag is over once the
        end's move has run.
        """
        phase = getattr(event, "phase", "update")
        if phase == "start":
            self._dragging = True
        at = np.array(self.handle.position, dtype=float)
        self._moves.submit(self._apply_handle, at, phase == "end")

    def _apply_handle(self, at: FloatArray, last: bool) -> None:
        """Set the tip force of a handle at ``at`` (base frame, m).

        At the end the handle snaps to the force set (cut at MAX_TIP_FORCE_N).
        """
        with self._lock:
            g = self._geometry
            if g is not None:
                self.set_tip_force(tip_force_from_handle(at, g.points["tip"]),
                                   place_handle=last)
            if last:
                self._dragging = False

    def stop(self) -> None:
        """Let the force handle's pending moves run; none after (the app is stopping)."""
        self._moves.stop()

    def _show_handle(self) -> None:
        with self._lock:
            on = bool(self.drag_checkbox.value) and bool(self.checkbox.value)
            if self._tip_handle is not None:
                if on and not self.handle.visible:
                    self._tip_handle_was_visible = bool(self._tip_handle.visible)
                    self._tip_handle.visible = False
                elif not on and self.handle.visible:
                    self._tip_handle.visible = self._tip_handle_was_visible
            self.handle.visible = on
            self._place_handle()

    # ------------------------------------------------------------------ drawing
    def _place_handle(self) -> None:
        g = self._geometry
        if g is not None:
            self.handle.position = tuple(
                float(x) for x in handle_from_tip_force(self.tip_force, g.points["tip"]))

    def _redraw(self, *, place_handle: bool) -> ForcesView | None:
        g = self._geometry
        if g is None or not self.checkbox.value:
            self._remove_arrow()
            self.readout.content = ""
            self.view = None
            if self.handle.visible:
                self._show_handle()
            return None
        # the same drawn solution and tip force as last time (a redraw of the read-outs,
        # an IK move held at the boundary): the statics are not computed again
        key = (np.asarray(g.q, float).tobytes(), int(g.slot), id(g.design),
               np.asarray(g.T_b_e, float).tobytes(), self.tip_force.tobytes())
        if key == self._last_key and self.view is not None:
            fv = self.view
        else:
            try:
                fv = forces_view(g, masses=self._masses_of(g.design), tip_force=self.tip_force,
                                 f_max=self.f_max, backend=self.backend)
            except (ValueError, TypeError, KinematicsError) as exc:
                self.message = f"{type(exc).__name__}: {exc}"
                self.readout.content = _message(self.message)
                self.view = None
                self._last_key = None
                return None
            self._last_key = key
        self.message = ""
        self._draw_arrow(g.points["tip"], fv.tip_force)
        if place_handle:
            self._place_handle()
        if bool(self.drag_checkbox.value) != bool(self.handle.visible):
            self._show_handle()
        text = forces_html(fv)
        if self.readout.content != text:
            self.readout.content = text
        self.view = fv
        return fv

    def _masses_of(self, design: Any) -> Any:
        """The given model, or the reference model of ``design`` (built once per design)."""
        if self.masses is not None:
            return self.masses
        if self._reference is None or self._reference[0] is not design:
            from ..dynamics import MassModel

            self._reference = (design, MassModel.reference(design))
        return self._reference[1]

    def _remove_arrow(self) -> None:
        if self._arrow is not None:
            self._arrow.remove()
            self._arrow = None

    def _draw_arrow(self, tip_b: FloatArray, f: FloatArray) -> None:
        if not np.any(f):
            self._remove_arrow()
            return
        pts = np.stack([tip_b, handle_from_tip_force(f, tip_b)])[None].astype(np.float32)
        if self._arrow is None:
            self._arrow = self.server.scene.add_arrows(
                "/forces/tip_force", points=pts, colors=rgb(TIP_FORCE_COLOR),
                shaft_radius=0.003, head_radius=0.009, head_length=0.02)
        else:
            self._arrow.points = pts


def _message(text: str) -> str:
    return (f'<p data-force="status" data-level="error" style="margin:0;font-size:0.85em;'
            f'color:{ERROR_COLOR}">actuator forces: {html.escape(text)}</p>')
