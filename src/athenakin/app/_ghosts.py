"""The ghosted slots of one ``q``, batched over the slots (numpy only).

With the slot selector on "all valid slots", the app draws one slot solid and up to 15
others paler. Building a :class:`~athenakin.plot.RobotGeometry` and a scene per ghost
costs about one reference FK call each in Python overhead; here the parts the ghosts draw (the
U-joint, the instrument, the spherical joint, the parallel module of the other assembly
mode) are computed at once from the forward-kinematics arrays, one numpy operation per
quantity for all slots. :func:`ghost_scene` turns them into the line sets of the static
views' parts, paler.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import ArrayLike

from .._mechanism import O_i_from_T_b_s
from .._transforms import rot_x, rot_z
from .._typing import FloatArray, IntArray
from .._validation import check_array, check_count, check_frame, check_scalar
from ..chain._ups import rotation_u_pair
from ..design import Design
from ..errors import InvalidInputError
from ..plot._geometry import PARALLEL_TOL, RobotGeometry
from ..plot._mpl import ARC_RADIUS
from ..robot import SLOT_MODE, FKSolution
from ._scene import (
    PART_STYLE,
    UJOINT_AXIS_HALF,
    UJOINT_FORK,
    WRIST_AXIS_HALF,
    LineSet,
    Scene,
    rgb,
)

__all__ = ["SlotGhosts", "slot_ghosts", "ghost_scene", "GHOST_BLEND", "ARC_SAMPLES"]

#: How far a ghost's colours are blended towards white (0: solid colour, 1: white).
GHOST_BLEND = 0.7
#: Points on each drawn spherical-joint arc (as :func:`athenakin.plot.arc_points`).
ARC_SAMPLES = 16

_RX90 = rot_x(np.asarray(np.pi / 2))


@dataclasses.dataclass(frozen=True)
class SlotGhosts:
    """Where the ghosted parts of several FK slots of one ``q`` are (base frame, m).

    Values that depend only on the assembly mode are stored once per mode.

    Attributes
    ----------
    q : ndarray, shape (3,)
        Actuators, m.
    slot : ndarray of int, shape (k,)
        The ghosted slots, in the order drawn.
    mode : ndarray of int, shape (k,)
        Assembly mode of each (+1 / -1).
    p : ndarray, shape (k,)
        Passive prismatic joint, m.
    tip : ndarray, shape (k, 3)
        Tool tip.
    ujoint_axes : ndarray, shape (k, 2, 3)
        Unit axes of ``u1`` and ``u2`` through ``O_s``.
    wrist_axes : ndarray, shape (k, 3, 3)
        Unit axes of ``u3``, ``u4``, ``u5`` through the RCM.
    rcm : ndarray, shape (3,)
        The RCM (origin of the set-up frame E).
    O_i_mode, O_s_mode : ndarray, shape (2, 3)
        ``O_i`` and ``O_s`` of assembly mode +1 (row 0) and -1 (row 1), NaN where the
        parallel module cannot take that mode.
    tool_length : float
        ``L``, m.

    Properties: :attr:`O_s` (k, 3), the centre of each ghost's U-joint.
    """

    q: FloatArray
    slot: IntArray
    mode: IntArray
    p: FloatArray
    tip: FloatArray
    ujoint_axes: FloatArray
    wrist_axes: FloatArray
    rcm: FloatArray
    O_i_mode: FloatArray
    O_s_mode: FloatArray
    tool_length: float

    def __len__(self) -> int:
        """Number of ghosted slots."""
        return int(self.slot.shape[0])

    @property
    def O_s(self) -> FloatArray:
        """Centre of the U-joint of each ghost, shape (k, 3) (from :attr:`O_s_mode`)."""
        return self.O_s_mode[(1 - self.mode) // 2]


def slot_ghosts(fk: FKSolution, q: ArrayLike, T_b_e: ArrayLike, design: Design,
                slots: ArrayLike) -> SlotGhosts:
    """The ghosted parts of some valid slots of one ``q``, computed for all at once.

    Parameters
    ----------
    fk : FKSolution
        ``forward_kinematics(q, T_b_e, design)`` of this ``q`` (slots of shape (16,)).
    q : array-like, shape (3,)
        Actuators, m.
    T_b_e : array-like, shape (4, 4)
        RCM frame (already checked).
    design : Design
    slots : array-like of int, shape (k,)
        Valid slots to ghost.

    Returns
    -------
    SlotGhosts
        The same positions as :func:`athenakin.plot.robot_geometry` of each slot
        (to rounding).

    Raises
    ------
    InvalidInputError
        ``fk`` is not the result of one ``q``, ``design`` not a Design, or a slot is out
        of 0..15 or invalid.
    """
    if not isinstance(fk, FKSolution):
        raise InvalidInputError(f"fk: expected the FKSolution of one q, got "
                                f"{type(fk).__name__}")
    if not isinstance(design, Design):
        raise InvalidInputError(f"design: expected a Design, got {type(design).__name__}")
    if np.shape(fk.valid) != (16,):
        raise InvalidInputError(f"fk: expected the solution of one q (valid of shape (16,)), "
                                f"got valid of shape {np.shape(fk.valid)}")
    ka = check_array(slots, "slots", ())
    if ka.ndim > 1 or not np.all(ka == np.round(ka)):
        raise InvalidInputError(f"slots: expected integers in 0..15, got {ka.tolist()}")
    k = ka.astype(np.int64).reshape(-1)
    if np.any((k < 0) | (k > 15)) or not np.all(fk.valid[np.clip(k, 0, 15)]):
        raise InvalidInputError(f"slots: expected valid slots in 0..15, got {k.tolist()} "
                                f"(valid: {np.flatnonzero(fk.valid).tolist()})")
    mode = SLOT_MODE[k].astype(np.int64)
    T_b_s = fk.T_b_s_mode[(1 - mode) // 2]                        # (k, 4, 4)
    R_b_s, O_s = T_b_s[:, :3, :3], T_b_s[:, :3, 3]
    u = fk.u[k]
    c, s = np.cos(u), np.sin(u)
    R_b_3 = R_b_s @ rotation_u_pair(c[:, 0], s[:, 0], c[:, 1], s[:, 1])
    R_4 = R_b_3 @ rot_z(u[:, 2]) @ _RX90                          # before u4
    R_5 = R_4 @ rot_z(u[:, 3]) @ _RX90                            # before u5
    wrist_axes = np.stack([R_b_3[:, :, 2], R_4[:, :, 2], R_5[:, :, 2]], axis=1)
    R_u2 = R_b_s @ rot_z(u[:, 0]) @ _RX90                         # before u2
    ujoint_axes = np.stack([R_b_s[:, :, 2], R_u2[:, :, 2]], axis=1)
    T = check_frame(T_b_e, "T_b_e")
    qa = check_array(q, "q", (3,))
    if qa.shape != (3,):
        raise InvalidInputError(f"q: expected shape (3,), got shape {qa.shape}")
    O_s_mode = fk.T_b_s_mode[:, :3, 3]
    return SlotGhosts(
        q=qa.copy(), slot=k, mode=mode, p=fk.p[k].copy(),
        tip=O_s + design.tool_length * R_b_3[:, :, 2], ujoint_axes=ujoint_axes,
        wrist_axes=wrist_axes, rcm=T[:3, 3].copy(),
        O_i_mode=O_i_from_T_b_s(fk.T_b_s_mode, design), O_s_mode=O_s_mode.copy(),
        tool_length=float(design.tool_length))


def _extreme_scale(v: FloatArray) -> FloatArray:
    """``max |v_i|`` where the norm of ``v`` would overflow or underflow, else 1 (exact)."""
    m = np.abs(v).max(axis=-1, keepdims=True)
    return np.where((m > 1e150) | (m < 1e-150), m, 1.0)


#: Most points of one arc of :func:`arcs_points`.
MAX_ARC_SAMPLES = 10_000


def arcs_points(centre: FloatArray, a: FloatArray, b: FloatArray,
                radius: float, n: int = ARC_SAMPLES) -> FloatArray:
    """Great-circle arcs about ``centre`` from directions ``a`` to ``b``, batched.

    :func:`athenakin.plot.arc_points` over leading axes: ``a``, ``b`` of shape (..., 3)
    give points of shape (..., n, 3); where ``a`` and ``b`` are parallel, ``n`` copies
    of ``centre + radius a``.

    Raises
    ------
    TypeError, InvalidInputError
        A bad argument (named): ``n`` must be 2 to :data:`MAX_ARC_SAMPLES`, ``a`` and
        ``b`` non-zero.
    """
    n = check_count(n, "n", minimum=2, maximum=MAX_ARC_SAMPLES)
    radius = check_scalar(radius, "radius", nonnegative=True)
    centre = check_array(centre, "centre", (3,))
    a = check_array(a, "a", (3,))
    b = check_array(b, "b", (3,))
    for name, v in (("a", a), ("b", b)):
        if np.any(np.all(v == 0.0, axis=-1)):
            raise InvalidInputError(f"{name}: expected non-zero directions, got a zero vector")
    try:
        np.broadcast_shapes(centre.shape[:-1], a.shape[:-1], b.shape[:-1])
    except ValueError:
        raise InvalidInputError(f"centre, a, b: batch shapes {centre.shape[:-1]}, "
                                f"{a.shape[:-1]}, {b.shape[:-1]} do not broadcast") from None
    if a.size // 3 * n > MAX_ARC_SAMPLES * 64:
        raise InvalidInputError(f"n: {a.size // 3} arcs of {n} points exceed "
                                f"{MAX_ARC_SAMPLES * 64:,} points")
    a = a / _extreme_scale(a)
    b = b / _extreme_scale(b)
    a = a / np.linalg.norm(a, axis=-1, keepdims=True)
    b = b / np.linalg.norm(b, axis=-1, keepdims=True)
    # the operations of athenakin.plot.arc_points, batched (the same points to rounding)
    ab = np.sum(a * b, axis=-1, keepdims=True)
    perp = b - ab * a
    norm = np.sqrt(np.sum(perp * perp, axis=-1, keepdims=True))
    plane = norm > PARALLEL_TOL
    ang = np.where(plane[..., 0], np.arctan2(norm[..., 0], ab[..., 0]), 0.0)
    e = np.divide(perp, norm, out=np.zeros_like(perp), where=plane)
    e = e - np.sum(e * a, axis=-1, keepdims=True) * a
    en = np.sqrt(np.sum(e * e, axis=-1, keepdims=True))
    e = np.divide(e, en, out=np.zeros_like(e), where=plane & (en > 0))
    t = np.linspace(0.0, ang, n, axis=-1)[..., None]             # (..., n, 1)
    return centre + radius * (np.cos(t) * a[..., None, :] + np.sin(t) * e[..., None, :])


def _polylines(pts: FloatArray) -> FloatArray:
    """Polylines (..., n, 3) as segments (..., n - 1, 2, 3)."""
    return np.stack([pts[..., :-1, :], pts[..., 1:, :]], axis=-2)


def _pair(a: FloatArray, b: FloatArray) -> FloatArray:
    """Segments from ``a`` to ``b`` (each (..., 3)) as (..., 2, 3)."""
    return np.stack(np.broadcast_arrays(a, b), axis=-2)


def _blend(c: tuple[int, int, int], f: float) -> tuple[int, int, int]:
    r, g, b = (round(v + f * (255 - v)) for v in c)
    return r, g, b


def _style(part: str) -> tuple[tuple[int, int, int], float]:
    """A ghost's colour and width from the solid part's (paler, thinner)."""
    color, width = PART_STYLE[part]
    return _blend(rgb(color), GHOST_BLEND), max(1.0, 0.6 * width)


def ghost_scene(ghosts: SlotGhosts, solid: RobotGeometry) -> Scene:
    """The parts of the ghosted slots, paler, one line set per part for all slots.

    Parts drawn by the solid view are not repeated: the rail and the circles (the same in
    every slot of one q), the frames, and the parallel module of the solid slot's assembly
    mode; the other mode's parallel module is drawn once. Colours and widths are the
    static views' (:func:`robot_scene`) blended by :data:`GHOST_BLEND` towards white.

    Parameters
    ----------
    ghosts : SlotGhosts
    solid : RobotGeometry
        The slot drawn solid (same ``q``): its mode is left out, and the points that do
        not depend on the mode (A, B, D, C) come from it.

    Returns
    -------
    Scene
        Line sets ``ghost_parallel`` and ``ghost_actuator_q3`` (only when a ghost is in
        the other assembly mode), ``ghost_ujoint``, ``ghost_instrument``,
        ``ghost_instrument_axis`` (only when a ghost's RCM is off the shaft) and
        ``ghost_spherical_joint``; in each, the segments of the slots in the order of
        ``ghosts.slot``. No points, no labels.

    Raises
    ------
    InvalidInputError
        ``ghosts`` is not a SlotGhosts or ``solid`` not a RobotGeometry.
    """
    if not isinstance(ghosts, SlotGhosts) or not isinstance(solid, RobotGeometry):
        raise InvalidInputError(f"ghosts, solid: expected a SlotGhosts and a RobotGeometry, got "
                                f"{type(ghosts).__name__} and {type(solid).__name__}")
    g = ghosts
    if len(g) == 0:
        return Scene((), (), ())
    lines: list[LineSet] = []
    P = solid.points
    for m in dict.fromkeys(g.mode.tolist()):       # the other assembly mode, drawn once
        if m == solid.mode:
            continue
        O_i, O_s_m = g.O_i_mode[(1 - m) // 2], g.O_s_mode[(1 - m) // 2]
        par = np.array([[P["A"], O_i], [P["B"], O_i], [P["A"], P["D"]], [P["B"], P["D"]],
                        [P["D"], P["C_foot"]], [P["C_foot"], P["C"]], [O_i, O_s_m]])
        lines.append(LineSet("ghost_parallel", par, *_style("parallel")))
        lines.append(LineSet("ghost_actuator_q3", np.array([[P["C"], O_i]]),
                             *_style("actuator_q3")))
    O_s, ax = g.O_s, g.ujoint_axes
    uj = np.stack([_pair(O_s - UJOINT_AXIS_HALF * ax[:, 0], O_s + UJOINT_AXIS_HALF * ax[:, 0]),
                   _pair(O_s, O_s + UJOINT_FORK * ax[:, 1])], axis=1)
    lines.append(LineSet("ghost_ujoint", uj.reshape(-1, 2, 3), *_style("ujoint")))
    lines.append(LineSet("ghost_instrument", _pair(O_s, g.tip), *_style("instrument")))
    off = (g.p < 0.0) | (g.p > g.tool_length)
    if np.any(off):
        lines.append(LineSet("ghost_instrument_axis", _pair(O_s[off], g.rcm),
                             *_style("instrument_axis")))
    w, rc = g.wrist_axes, g.rcm
    h = WRIST_AXIS_HALF * ARC_RADIUS * w                          # (k, 3, 3)
    axes = _pair(rc - h, rc + h)                                  # (k, 3, 2, 3)
    arcs = _polylines(arcs_points(rc, w[:, :2], w[:, 1:], ARC_RADIUS))   # (k, 2, n-1, 2, 3)
    sph = np.concatenate([axes, arcs.reshape(len(g), -1, 2, 3)], axis=1)
    lines.append(LineSet("ghost_spherical_joint", sph.reshape(-1, 2, 3),
                         *_style("spherical_joint")))
    return Scene(lines=tuple(lines), points=(), labels=())
