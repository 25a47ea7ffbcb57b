"""The app's state as pure functions: set-up, forward view, inverse step, playback (numpy only).

Nothing here knows about a browser: :func:`forward_view` turns actuator values into
everything the page shows (the 16 slots with their reasons, the robot's geometry, the
read-outs), :func:`inverse_step` moves the actuators towards a tool-tip target without a
jump, and :func:`load_playback` / :func:`playback_q` read and sample a trajectory CSV. The
viser binding (:mod:`athenakin.app._server`) only draws what these return.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from .._backend import resolve_backend
from .._dispatch import forward_kinematics
from .._typing import BoolArray, FloatArray
from .._validation import check_array, check_instance, check_slot
from ..design import Design, resolve_design
from ..errors import InvalidInputError, OutOfWorkspaceError, Reason
from ..parallel import parallel_forward_kinematics
from ..plot._geometry import RobotGeometry, robot_geometry
from ..robot import (
    REFERENCE_Q,
    SLOT_MODE,
    SLOT_P_SIGN,
    SLOT_UJOINT,
    SLOT_WRIST,
)
from ..robot._setup import reference_rcm_frame, resolve_rcm_frame
from ._ghosts import SlotGhosts, slot_ghosts

__all__ = [
    "WARN_DISTANCE_M",
    "WARN_SINE",
    "WARN_CONDITION",
    "INVERSE_STEPS",
    "AppSetup",
    "SlotStatus",
    "Distance",
    "Readouts",
    "AppView",
    "app_setup",
    "rcm_reach",
    "slot_statuses",
    "forward_view",
    "readouts",
]

#: Distance (m) to a singular set at or below which a read-out turns to the warning colour.
WARN_DISTANCE_M = 0.005
#: Dimensionless distance (a sine) at or below which a read-out warns: ``sin 5 deg``.
WARN_SINE = math.sin(math.radians(5.0))
#: Condition number at or above which a Jacobian read-out warns.
WARN_CONDITION = 100.0
#: Points on the straight tool-tip segment from the last reached tip to a target that
#: :func:`inverse_step` checks (the actuators stop at the last valid one).
INVERSE_STEPS = 48
#: Half-width of the slider range of an actuator without stroke limits, m.
UNLIMITED_HALF_RANGE = 0.3
#: Points per actuator of the app's grid of the actuator ranges (:func:`actuator_grid`), on
#: which :func:`app_setup` looks for an assembled pose.
SEARCH_GRID = 9

Slot = int | Literal["all"]


@dataclasses.dataclass(frozen=True)
class AppSetup:
    """What the app works on: a design, an RCM frame, the actuator ranges.

    Attributes
    ----------
    design : Design
    T_b_e : ndarray, shape (4, 4)
        RCM frame (checked rigid).
    q_lo, q_hi : ndarray, shape (3,)
        Slider ranges of ``q1, q2, q3``, m: the stroke limits, or
        ``q_home -/+ UNLIMITED_HALF_RANGE`` where a stroke is unlimited.
    q_home : ndarray, shape (3,)
        Start configuration: :data:`~athenakin.robot.REFERENCE_Q` where it assembles,
        else the assembled grid point nearest to it.
    backend : {"numba", "numpy"}
        Kernels used for the forward and inverse kinematics.
    """

    design: Design
    T_b_e: FloatArray
    q_lo: FloatArray
    q_hi: FloatArray
    q_home: FloatArray
    backend: Literal["numba", "numpy"]


def actuator_grid(q_lo: FloatArray, q_hi: FloatArray) -> FloatArray:
    """:data:`SEARCH_GRID` points per actuator over the box ``q_lo..q_hi`` (m), shape (n, 3).

    The app's one grid of the actuator ranges (:func:`app_setup`'s start search, the depth
    slider's reach), ``q1`` slowest.
    """
    axes = [np.linspace(a, b, SEARCH_GRID) for a, b in zip(q_lo, q_hi, strict=True)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def app_setup(T_b_e: ArrayLike | None = None, design: Design | None = None, *,
              backend: Literal["auto", "numba", "numpy"] = "auto") -> AppSetup:
    """Check a design and an RCM frame for the app and find where it starts.

    Parameters
    ----------
    T_b_e : array-like, shape (4, 4), optional
        RCM frame; default: the reference set-up (:func:`~athenakin.default_rcm_frame`),
        built at the start configuration when the reference ``q`` does not assemble.
    design : Design, optional
        Defaults to :meth:`Design.default`.
    backend : {"auto", "numba", "numpy"}, keyword-only
        ``"auto"``: the compiled kernels where numba imports, else the numpy reference
        (:func:`athenakin.forward_kinematics`).

    Returns
    -------
    AppSetup

    Raises
    ------
    InvalidInputError
        ``T_b_e`` is not a rigid transform of shape (4, 4), or ``backend`` is unknown.
    ImportError
        ``backend="numba"`` where numba is off (:mod:`athenakin._backend`).
    OutOfWorkspaceError
        The parallel module assembles nowhere on a grid over the stroke ranges (the
        design cannot assemble).
    """
    design = resolve_design(design)
    if not isinstance(backend, str) or backend not in ("auto", "numba", "numpy"):
        raise InvalidInputError(f"backend: expected 'auto', 'numba' or 'numpy', got {backend!r}")
    chosen: Literal["numba", "numpy"] = "numba" if resolve_backend(backend) else "numpy"
    lo, hi = design.stroke_min.copy(), design.stroke_max.copy()
    ref = np.clip(REFERENCE_Q, lo, hi)
    lo = np.where(np.isfinite(lo), lo, ref - UNLIMITED_HALF_RANGE)
    hi = np.where(np.isfinite(hi), hi, ref + UNLIMITED_HALF_RANGE)
    if parallel_forward_kinematics(ref, design).valid[0]:
        home = ref
    else:
        grid = actuator_grid(lo, hi)
        ok = parallel_forward_kinematics(grid, design).valid[:, 0]
        if not np.any(ok):
            raise OutOfWorkspaceError(
                f"design {design.name or '(unnamed)'}: the parallel module assembles nowhere "
                f"within the actuator ranges q_min = {np.round(lo, 4).tolist()} m, q_max = "
                f"{np.round(hi, 4).tolist()} m (checked on a {SEARCH_GRID}^3 grid): check "
                f"the link lengths l1..l5 and the strokes", Reason.CIRCLES_DISJOINT)
        cand = grid[ok]
        home = cand[np.argmin(np.linalg.norm(cand - ref, axis=-1))]
    T = (reference_rcm_frame(parallel_forward_kinematics(home, design).O_s[0]) if T_b_e is None
         else resolve_rcm_frame(T_b_e, design))
    return AppSetup(design=design, T_b_e=T, q_lo=lo, q_hi=hi, q_home=home.copy(),
                    backend=chosen)


def rcm_reach(setup: AppSetup) -> float:
    """Largest ``|p|`` (m): the farthest ``O_s`` from the RCM, for the depth slider's range.

    Over the grid of the actuator ranges (:func:`~athenakin.app._model.actuator_grid`,
    both modes), rounded up to 10 mm.

    Parameters
    ----------
    setup : AppSetup
        Its design, actuator ranges and RCM frame.

    Returns
    -------
    float
        m; 1.0 where the parallel module assembles nowhere on the grid.
    """
    grid = actuator_grid(setup.q_lo, setup.q_hi)
    O_s = np.asarray(parallel_forward_kinematics(grid, setup.design).O_s)
    dist = np.linalg.norm(O_s - setup.T_b_e[:3, 3], axis=-1)
    far = float(np.nanmax(dist)) if np.any(np.isfinite(dist)) else 1.0
    return math.ceil(far * 100.0) / 100.0


@dataclasses.dataclass(frozen=True)
class SlotStatus:
    """One of the 16 forward-kinematics slots at the current ``q``.

    Attributes
    ----------
    slot : int
    valid : bool
    reason : int
        :class:`~athenakin.errors.Reason` code (0 where valid).
    label : str
        ``"slot 3: mode +1, p>0, U-, S-"``.
    why : str
        ``""`` where valid, else the reason's name and description.
    """

    slot: int
    valid: bool
    reason: int
    label: str
    why: str


def _label(k: int) -> str:
    return (f"slot {k}: mode {int(SLOT_MODE[k]):+d}, p{'>' if SLOT_P_SIGN[k] > 0 else '<'}0, "
            f"U{'+' if SLOT_UJOINT[k] > 0 else '-'}, S{'+' if SLOT_WRIST[k] > 0 else '-'}")


def slot_statuses(valid: ArrayLike, reason: ArrayLike) -> tuple[SlotStatus, ...]:
    """The 16 slots from an FK result's ``valid`` and ``reason`` (each shape (16,)).

    Parameters
    ----------
    valid : array-like of bool, shape (16,)
        :attr:`FKSolution.valid <athenakin.robot.FKSolution>` of one item.
    reason : array-like of int, shape (16,)
        :class:`~athenakin.errors.Reason` codes of the same item.

    Returns
    -------
    tuple of 16 SlotStatus
        In slot order, each with its label and, where invalid, why.

    Raises
    ------
    TypeError, InvalidInputError
        ``valid`` is not 16 booleans or ``reason`` not 16 :class:`Reason` codes.
    """
    va = check_array(valid, "valid", (16,))
    if va.shape != (16,) or not np.all((va == 0) | (va == 1)):
        raise InvalidInputError(f"valid: expected 16 booleans (an FK result's valid), got "
                                f"shape {va.shape}")
    ra = check_array(reason, "reason", (16,))
    codes = {int(r) for r in Reason}
    if ra.shape != (16,) or not all(float(r).is_integer() and int(r) in codes for r in ra):
        raise InvalidInputError(f"reason: expected 16 Reason codes (an FK result's reason), "
                                f"got {ra.tolist() if ra.size <= 16 else ra.shape}")
    out = []
    for k, (v, r) in enumerate(zip(va.astype(bool).tolist(), ra.astype(int).tolist(),
                                   strict=True)):
        why = "" if v else f"{Reason(r).name}: {Reason(r).description}"
        out.append(SlotStatus(slot=k, valid=bool(v), reason=int(r), label=_label(k), why=why))
    return tuple(out)


@dataclasses.dataclass(frozen=True)
class Distance:
    """Distance of the configuration to one singular set (a read-out line).

    Attributes
    ----------
    name : str
        Key of :data:`athenakin.analysis.CONDITIONS`.
    value : float
        The condition's closed-form measure (m or dimensionless; NaN if undefined).
    unit : str
        ``"m"`` or ``"1"``.
    warn_at : float
        Threshold of the warning colour (:data:`WARN_DISTANCE_M` or :data:`WARN_SINE`).
    near : bool
        ``value <= warn_at``.
    meaning : str
    """

    name: str
    value: float
    unit: str
    warn_at: float
    near: bool
    meaning: str


@dataclasses.dataclass(frozen=True)
class Readouts:
    """The live read-outs of one configuration (one slot).

    Attributes
    ----------
    q : ndarray, shape (3,)
        Actuators, m.
    slot, mode : int
    p : float
        Passive prismatic joint, m.
    u : ndarray, shape (5,)
        ``u1..u5``, rad.
    tip_b, tip_e : ndarray, shape (3,)
        Tool tip in the base frame and in the RCM frame E, m.
    distances : tuple of Distance
        One per singularity condition of :func:`athenakin.analysis.singularities`.
    conditioning : dict of str -> float
        2-norm condition numbers of the Jacobians ``d O_s / d q``
        (``parallel_condition``) and ``d tip / d q`` (``tool_tip_condition``),
        dimensionless (inf where singular, NaN where undefined).
    conditioning_warn : dict of str -> bool
        Not below :data:`WARN_CONDITION` (or not finite).
    """

    q: FloatArray
    slot: int
    mode: int
    p: float
    u: FloatArray
    tip_b: FloatArray
    tip_e: FloatArray
    distances: tuple[Distance, ...]
    conditioning: dict[str, float]
    conditioning_warn: dict[str, bool]

    @property
    def near(self) -> list[str]:
        """Names of the singular sets within the warning distance."""
        return [d.name for d in self.distances if d.near]


def readouts(setup: AppSetup, g: RobotGeometry) -> Readouts:
    """Read-outs of the slot drawn in ``g`` (its q, joints, tip, singularity distances).

    Parameters
    ----------
    setup : AppSetup
    g : RobotGeometry
        From :func:`athenakin.plot.robot_geometry` with the set-up's design and frame.

    Returns
    -------
    Readouts
    """
    from ..analysis import (
        CONDITIONS,
        condition_number,
        parallel_jacobian,
        singularities,
        tool_tip_jacobian,
    )

    check_instance(setup, "setup", AppSetup)
    check_instance(g, "g", RobotGeometry)
    rep = singularities(g.q, setup.T_b_e, setup.design, mode=g.mode, jacobians=False)
    dist = []
    for name, c in rep.conditions.items():
        v = float(c.value)
        warn_at = WARN_DISTANCE_M if c.unit == "m" else WARN_SINE
        dist.append(Distance(name=name, value=v, unit=c.unit, warn_at=warn_at,
                             near=bool(np.isfinite(v) and v <= warn_at),
                             meaning=CONDITIONS[name].meaning))
    be = setup.backend
    with np.errstate(invalid="ignore", divide="ignore"):
        jacs = {"parallel_condition": parallel_jacobian(g.q, setup.design, g.mode, backend=be),
                "tool_tip_condition": tool_tip_jacobian(g.q, setup.T_b_e, setup.design,
                                                        mode=g.mode, backend=be)}
        cond = {k: float(condition_number(J)) for k, J in jacs.items()}
    warn = {k: bool(not v < WARN_CONDITION) for k, v in cond.items()}
    tip_b = g.points["tip"]
    T = setup.T_b_e
    tip_e = T[:3, :3].T @ (tip_b - T[:3, 3])
    return Readouts(q=g.q.copy(), slot=g.slot, mode=g.mode, p=g.p, u=g.u.copy(), tip_b=tip_b.copy(),
                    tip_e=tip_e, distances=tuple(dist), conditioning=cond, conditioning_warn=warn)


@dataclasses.dataclass(frozen=True)
class AppView:
    """Everything the page shows for one actuator configuration.

    Attributes
    ----------
    q : ndarray, shape (3,)
        Actuators, m.
    slots : tuple of SlotStatus
        All 16 slots, valid or not (with the reason).
    requested : int or "all"
        The slot asked for.
    geometry : RobotGeometry or None
        The slot drawn solid (None: no slot is valid at ``q``).
    ghosts : SlotGhosts or None
        The other valid slots (drawn ghosted), batched over the slots, when
        ``requested == "all"`` (None otherwise or when no other slot is valid).
    readouts : Readouts or None
        Of :attr:`geometry`.
    message : str
        Status line (why nothing is drawn, which slot stands in for an invalid one).
    level : {"ok", "warn", "error"}
    """

    q: FloatArray
    slots: tuple[SlotStatus, ...]
    requested: Slot
    geometry: RobotGeometry | None
    ghosts: SlotGhosts | None
    readouts: Readouts | None
    message: str
    level: Literal["ok", "warn", "error"]


def _check_slot(slot: object) -> Slot:
    return check_slot(slot, allow_all=True)  # type: ignore[no-any-return]


def _nearest_valid(k: int, valid: BoolArray) -> int:
    """The valid slot that shares the most labels with slot ``k`` (the lowest on a tie)."""
    labels = np.stack([SLOT_MODE, SLOT_P_SIGN, SLOT_UJOINT, SLOT_WRIST], axis=-1)
    same = np.sum(labels == labels[k], axis=-1) + 0.5 * (np.arange(16) == k)
    same = np.where(valid, same, -1.0)
    return int(np.argmax(same))


def forward_view(setup: AppSetup, q: ArrayLike, *, slot: Slot = 0) -> AppView:
    """The view of the robot at actuator values ``q`` (forward mode).

    Parameters
    ----------
    setup : AppSetup
    q : array-like, shape (3,)
        Actuators, m.
    slot : int or "all", keyword-only
        Slot 0..15 to draw, or ``"all"``: the first valid slot solid, the other
        valid ones ghosted. An invalid slot is replaced by the valid slot sharing
        the most labels with it, and the message says so.

    Returns
    -------
    AppView
        Never raises for a configuration without a solution: ``geometry`` is then
        None and ``message`` holds the reasons.

    Raises
    ------
    InvalidInputError
        ``q`` is not 3 finite numbers, or ``slot`` is not in 0..15 or ``"all"``.
    """
    check_instance(setup, "setup", AppSetup)
    q = check_array(q, "q", (3,)).copy()
    if q.shape != (3,):
        raise InvalidInputError(f"q: expected shape (3,), got shape {q.shape}")
    requested = _check_slot(slot)
    sol = forward_kinematics(q, setup.T_b_e, setup.design, errors="flag", backend=setup.backend)
    valid = np.asarray(sol.valid)
    slots = slot_statuses(valid, sol.reason)
    if not valid.any():
        reasons = sorted({s.why for s in slots})
        return AppView(q=q, slots=slots, requested=requested, geometry=None, ghosts=None,
                       readouts=None, level="error",
                       message="no solution at this q: " + "; ".join(reasons))
    message = ""
    level: Literal["ok", "warn", "error"] = "ok"
    if requested == "all":
        first = int(np.flatnonzero(valid)[0])
        others = [int(k) for k in np.flatnonzero(valid) if k != first]
        message = f"{int(valid.sum())} valid slots: {slots[first].label} solid, the others ghosted"
    else:
        first = requested if valid[requested] else _nearest_valid(requested, valid)
        others = []
        if first != requested:
            message = (f"slot {requested} has no solution here ({slots[requested].why}); "
                       f"showing {slots[first].label}")
            level = "warn"
    geom = robot_geometry(q, setup.T_b_e, setup.design, slot=first, fk=sol)
    ghosts = slot_ghosts(sol, q, setup.T_b_e, setup.design, others) if others else None
    ro = readouts(setup, geom)
    if ro.near and level == "ok":
        level = "warn"
        message = (message + "; " if message else "") + "near: " + ", ".join(ro.near)
    return AppView(q=q, slots=slots, requested=requested, geometry=geom, ghosts=ghosts,
                   readouts=ro, message=message, level=level)


