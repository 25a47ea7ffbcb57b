"""The app's set-up (private): the design and RCM frame it runs, a planned set-up, the patient.

* :func:`load_setup`: a design (object or TOML file) and an RCM frame (array, JSON file or
  set-up TOML of ``athenakin setup plan``) as an :class:`~athenakin.app.AppSetup`; a
  problem goes to the page's list and the reference is used instead;
* :class:`PlannedSetup`, :func:`check_planned`: a planned set-up (a
  :class:`~athenakin.synthesis.Setup` or its file) and its patient (a
  :class:`~athenakin.synthesis.Patient` or ``patient.toml``), checked before the server
  starts; :func:`planned_environment` adds the patient's surfaces to the obstacles
  (:func:`~athenakin.synthesis.setup_environment`, the coverage check's rules);
* :func:`patient_solids`, :func:`planned_start`: the patient's meshes in the base frame,
  and the configuration that puts the tool tip at the target's centre;
* :class:`SetupTab`: the Set-up tab (another design or RCM frame) and the patient, its
  port and the instrument's nominal axis drawn once.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from .._validation import check_instance
from ..design import Design
from ..errors import InvalidInputError, KinematicsError
from ._model import AppSetup, app_setup
from ._scene import Solid, rgb

__all__ = ["load_setup", "PlannedSetup", "check_planned", "planned_environment",
           "patient_solids", "planned_start", "SetupTab", "PORT_RADIUS", "AXIS_WIDTH_PX"]

#: Radius of the port's sphere, m, and the width of the nominal axis, px.
PORT_RADIUS = 0.006
AXIS_WIDTH_PX = 2.0


def _error_text(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}"


def load_setup(T_b_e: ArrayLike | str | Path | None, design: Design | str | Path | None, *,
               backend: str, errors: list[str]) -> AppSetup:
    """The app's set-up from a design and an RCM frame; problems to ``errors``, the reference used.

    Parameters
    ----------
    T_b_e : array-like, shape (4, 4), str, Path or None
        The RCM frame, a JSON file ``{"T_b_e": ...}`` or a set-up TOML file
        (:func:`athenakin.robot._setup.read_rcm_file`); None: the reference set-up.
    design : Design, str, Path or None
        The design or its TOML file; None: the reference design.
    backend : {"auto", "numba", "numpy"}, keyword-only
    errors : list of str, keyword-only
        Each problem is appended (it names the file), for the page's banner.

    Returns
    -------
    AppSetup
        Of the inputs, or of the reference design and set-up where they cannot be used.
    """
    from ..robot._setup import read_rcm_file

    d: Design | None = None
    if isinstance(design, (str, Path)):
        try:
            d = Design.from_toml(design)
        except (OSError, ValueError, TypeError, KinematicsError) as exc:
            errors.append(f"design file {design}: {_error_text(exc)}; showing the reference "
                          f"design instead")
    elif design is not None:
        d = design
    T: ArrayLike | None = None
    if isinstance(T_b_e, (str, Path)):
        try:
            T = read_rcm_file(T_b_e, option="RCM file")
        except OSError as exc:
            errors.append(f"RCM file {T_b_e}: cannot read it ({exc}); using the reference "
                          f"set-up")
        except ValueError as exc:               # names the file
            errors.append(f"{exc}; using the reference set-up")
    else:
        T = T_b_e
    try:
        base = app_setup(None, d, backend=backend)  # type: ignore[arg-type]
    except (ValueError, TypeError, KinematicsError) as exc:
        errors.append(f"design: {_error_text(exc)}; showing the reference design instead")
        d = None
        base = app_setup(None, None, backend=backend)  # type: ignore[arg-type]
    if T is None:
        return base
    try:
        return app_setup(T, d, backend=backend)  # type: ignore[arg-type]
    except (ValueError, TypeError, KinematicsError) as exc:
        where = f"RCM file {T_b_e}" if isinstance(T_b_e, (str, Path)) else "RCM frame"
        errors.append(f"{where}: {_error_text(exc)}; using the reference set-up instead")
        return base


@dataclasses.dataclass(frozen=True, eq=False)
class PlannedSetup:
    """A planned set-up the app starts with, and the patient it was planned for.

    Attributes
    ----------
    setup : athenakin.synthesis.Setup
        ``T_b_e`` (the app's RCM frame), ``T_p_b`` (places the patient), the port, the
        nominal axis.
    design : Design or None
        The set-up file's design (None for a :class:`~athenakin.synthesis.Setup` given
        as an object).
    patient : athenakin.synthesis.Patient or None
    """

    setup: Any
    design: Design | None
    patient: Any


def check_planned(planned: Any, patient: Any) -> PlannedSetup | None:
    """The planned set-up and the patient of :class:`~athenakin.app.AthenaApp`, read and checked.

    Parameters
    ----------
    planned : Setup, str, Path or None
        A set-up, or its TOML file (``athenakin setup plan``, with its ``[design]``).
    patient : Patient, str, Path or None
        The patient, or its ``patient.toml``; needs ``planned`` (its ``T_p_b`` places it).

    Returns
    -------
    PlannedSetup or None
        None when neither is given.

    Raises
    ------
    InvalidInputError
        A patient without a set-up; a file that is not a set-up or patient file (named).
    TypeError
        Neither an object of the expected type nor a path.
    OSError
        A file that cannot be read.
    """
    from ..synthesis import Patient, Setup, read_setup

    if planned is None:
        if patient is not None:
            raise InvalidInputError("patient: drawn where a planned set-up places it (its "
                                    "T_p_b); pass the set-up too (planned=, --setup FILE)")
        return None
    design = None
    if isinstance(planned, (str, Path)):
        planned, design, _ = read_setup(planned)
    check_instance(planned, "planned", Setup)
    if isinstance(patient, (str, Path)):
        patient = Patient.from_toml(patient)
    if patient is not None:
        check_instance(patient, "patient", Patient)
    return PlannedSetup(setup=planned, design=design, patient=patient)


def planned_environment(environment: Any, plan: PlannedSetup | None) -> Any:
    """``environment`` with the patient's surfaces added (the coverage check's rules).

    Parameters
    ----------
    environment : athenakin.collision.Environment or None
        The obstacles given to the app.
    plan : PlannedSetup or None

    Returns
    -------
    athenakin.collision.Environment or None
        ``environment`` where there is no patient.
    """
    if plan is None or plan.patient is None:
        return environment
    from ..collision import Environment
    from ..synthesis import setup_environment

    env = setup_environment(plan.patient, plan.setup)
    return env if environment is None else Environment(environment.obstacles + env.obstacles)


def patient_solids(plan: PlannedSetup) -> tuple[Solid, ...]:
    """The patient's meshes in the robot's base frame, coloured by role.

    Parameters
    ----------
    plan : PlannedSetup
        With a patient.

    Returns
    -------
    tuple of Solid
        ``patient_<mesh name>``, vertices ``T_b_p p`` (m); the colours and opacities of the
        HTML view (:data:`athenakin.plot._setup_view.SETUP_VIEW_COLORS`).
    """
    from .._transforms import invert_transform
    from ..plot._setup_view import SETUP_VIEW_COLORS

    check_instance(plan, "plan", PlannedSetup)
    if plan.patient is None:
        return ()
    T = invert_transform(plan.setup.T_p_b)
    out = []
    for m in plan.patient.meshes:
        color, opacity = SETUP_VIEW_COLORS[m.role]
        out.append(Solid(f"patient_{m.name}", m.vertices @ T[:3, :3].T + T[:3, 3], m.faces,
                         rgb(color), opacity))
    return tuple(out)


def planned_start(setup: AppSetup, plan: PlannedSetup | None) -> tuple[FloatArray, int] | None:
    """The actuators and slot that put the tool tip at the target's centre, through the port.

    Parameters
    ----------
    setup : AppSetup
        The app's set-up (its RCM frame, design and backend).
    plan : PlannedSetup or None

    Returns
    -------
    (q, slot) or None
        ``q`` (3,), m, of the exact IK (:func:`athenakin.q_from_tool_tip`) and the slot of
        its assembly mode with the tool inserted; None without a patient or where the
        IK does not reach the centre.
    """
    from .._dispatch import q_from_tool_tip
    from ..robot import slot_index

    if plan is None or plan.patient is None:
        return None
    T_p_e = plan.setup.T_p_b @ setup.T_b_e
    tip_e = T_p_e[:3, :3].T @ (plan.patient.target_centroid - T_p_e[:3, 3])
    q, res = q_from_tool_tip(setup.T_b_e, tip_e, setup.design, errors="flag",
                             backend=setup.backend)  # type: ignore[arg-type]
    if not bool(res.valid):
        return None
    return np.asarray(q, dtype=float), slot_index(int(res.mode), 1, 1, 1)


class SetupTab:
    """The Set-up tab of the app, and the planned set-up's patient in the scene.

    Parameters
    ----------
    app : AthenaApp
        The app whose set-up this tab changes (``app.use_setup``).
    plan : PlannedSetup or None, keyword-only
        Drawn once, in the base frame: the patient's meshes, the port, the nominal axis;
        the checkbox *patient* shows or hides them.

    Attributes
    ----------
    design_path, rcm_path : viser GUI text inputs
    nodes : dict of str -> viser scene node
        The patient's nodes by name (``patient_<mesh>``, ``port``, ``nominal_axis``).
    """

    def __init__(self, app: Any, *, plan: PlannedSetup | None = None) -> None:
        gui = app.server.gui
        self.app = app
        self.plan = plan
        self.design_path = gui.add_text("design TOML", initial_value="")
        self.rcm_path = gui.add_text("RCM frame", initial_value="",
                                     hint='JSON {"T_b_e": 4x4 nested list} or a set-up TOML '
                                          '(athenakin setup plan)')
        gui.add_button("apply set-up").on_click(lambda _: self.apply())
        self.nodes: dict[str, Any] = {}
        if plan is not None and plan.patient is not None:
            self.patient_cb = gui.add_checkbox("patient", initial_value=True,
                                               hint="the planned set-up's patient, port and "
                                                    "nominal axis")
            self.patient_cb.on_update(lambda _: self._show(bool(self.patient_cb.value)))
            self._draw(plan)

    def apply(self) -> None:
        """Load the design and RCM frame typed in; the status line says why not."""
        design = self.design_path.value.strip() or None
        rcm = self.rcm_path.value.strip() or None
        problems: list[str] = []
        setup = load_setup(rcm, design, backend=self.app._backend, errors=problems)
        if problems:
            self.app._set_status("set-up not changed: " + " | ".join(problems), "error")
            return
        self.app.use_setup(setup)

    def _draw(self, plan: PlannedSetup) -> None:
        from .._transforms import invert_transform
        from ..plot._setup_view import AXIS_OUTSIDE, SETUP_VIEW_COLORS

        scene = self.app.server.scene
        for so in patient_solids(plan):
            self.nodes[so.name] = scene.add_mesh_simple(
                f"/patient/{so.name}", np.asarray(so.vertices, dtype=np.float32),
                np.asarray(so.faces, dtype=np.uint32), color=so.color, opacity=so.opacity,
                flat_shading=True, cast_shadow=False, receive_shadow=False)
        T = invert_transform(plan.setup.T_p_b)
        s = plan.setup           # port, from outside the skin to the target's centre: base frame
        pts = np.stack([s.port, s.port - AXIS_OUTSIDE * s.axis, plan.patient.target_centroid])
        port, outside, centre = pts @ T[:3, :3].T + T[:3, 3]
        self.nodes["port"] = scene.add_icosphere(
            "/patient/port", radius=PORT_RADIUS, color=rgb(SETUP_VIEW_COLORS["port"][0]),
            position=tuple(float(x) for x in port), cast_shadow=False, receive_shadow=False)
        self.nodes["nominal_axis"] = scene.add_line_segments(
            "/patient/nominal_axis", points=np.stack([outside, centre])[None].astype(np.float32),
            colors=rgb(SETUP_VIEW_COLORS["axis"][0]), thickness=AXIS_WIDTH_PX,
            thickness_units="screen")

    def _show(self, on: bool) -> None:
        for h in self.nodes.values():
            h.visible = on
