"""A live ATHENA in the browser: move the actuators, the tool tip or a recorded trajectory.

``athenakin app`` (or :func:`launch` from Python or a notebook) starts a local web
server (viser, extra ``app``) that draws the robot with the geometry of the static
views and answers every slider in a few milliseconds.

The app's logic is pure and testable without a browser (numpy only):

* :func:`app_setup`: check a design and an RCM frame, find the start configuration;
* :func:`forward_view`: actuator values -> the 16 slots with their reasons, the robot
  and its read-outs (:class:`AppView`);
* :func:`inverse_step`: move the tool tip towards a target, the actuators follow
  through the controller-form IK and stop at the workspace boundary;
* :func:`load_playback`, :func:`playback_q`: a trajectory CSV from ``athenakin plan``;
* :func:`robot_scene`, :func:`ghost_scene`: the lines and points to draw, the ghosted
  slots batched (:func:`slot_ghosts`); shaded bodies (:class:`Solid`) join a scene
  through :func:`with_solids`;
* :func:`view_html`, :func:`readouts_html`, :func:`slots_html`: the read-outs as HTML.

Only :class:`AthenaApp` and :func:`launch` import viser (``pip install 'athenakin[app]'``).
"""

from ._ghosts import GHOST_BLEND, SlotGhosts, ghost_scene, slot_ghosts
from ._inverse import InverseStep, angles_from_tip, inverse_step, tip_from_angles
from ._model import (
    INVERSE_STEPS,
    WARN_CONDITION,
    WARN_DISTANCE_M,
    WARN_SINE,
    AppSetup,
    AppView,
    Distance,
    Readouts,
    SlotStatus,
    app_setup,
    forward_view,
    readouts,
    slot_statuses,
)
from ._playback import Playback, load_playback, playback_q
from ._scene import PART_STYLE, Label, LineSet, PointSet, Scene, Solid, robot_scene, with_solids
from ._text import SINGULAR_NAMES, message_html, readouts_html, slots_html, view_html

__all__ = [
    "GHOST_BLEND",
    "INVERSE_STEPS",
    "PART_STYLE",
    "SINGULAR_NAMES",
    "WARN_CONDITION",
    "WARN_DISTANCE_M",
    "WARN_SINE",
    "AppSetup",
    "AppView",
    "AthenaApp",
    "Distance",
    "InverseStep",
    "Label",
    "LineSet",
    "Playback",
    "PointSet",
    "Readouts",
    "Scene",
    "Solid",
    "SlotGhosts",
    "SlotStatus",
    "angles_from_tip",
    "app_setup",
    "forward_view",
    "ghost_scene",
    "inverse_step",
    "launch",
    "load_playback",
    "playback_q",
    "readouts",
    "message_html",
    "readouts_html",
    "robot_scene",
    "slot_ghosts",
    "slot_statuses",
    "slots_html",
    "tip_from_angles",
    "view_html",
    "with_solids",
]


def __getattr__(name: str) -> object:
    """Import the viser binding on first use (extra ``app``)."""
    if name in ("AthenaApp", "launch"):
        from . import _server

        return getattr(_server, name)
    raise AttributeError(f"module 'athenakin.app' has no attribute {name!r}")
