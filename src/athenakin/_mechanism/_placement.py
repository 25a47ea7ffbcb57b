"""Where the mechanism is: its points, link frames and tree joints for actuator values.

:func:`mechanism_state` (and :func:`mechanism_points`, :func:`state_from_fk`) is the one
place that places the mechanism, batched over configurations and FK slots; the views,
the collision bodies, the exports' keyframes, ``/tf`` and the tracker's clearance read it.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from .._backend import Backend
from .._dispatch import forward_kinematics
from .._mechanism_formulas import FORMULA_POINTS, mechanism_points_formula, tree_joint_formula
from .._typing import BoolArray, FloatArray, Int8Array
from .._validation import check_array, check_slot
from ..design import Design, resolve_design
from ..errors import InvalidInputError
from ..robot._fk import SLOT_MODE_INDEX
from ..robot._setup import resolve_rcm_frame
from ._bodies import BODIES, BODY_SEGMENTS, POINT_NAMES, BodyGeometry, rail_extent
from ._tree import _O, JOINTS, LINKS, _tree_frames

__all__ = ["MechanismPoints", "MechanismState", "mechanism_state", "mechanism_points",
           "state_from_fk", "body_segments", "link_segments", "O_i_from_T_b_s"]


@dataclasses.dataclass(frozen=True)
class MechanismPoints:
    """The named points of the mechanism for a batch of configurations (base frame, m).

    Attributes
    ----------
    xyz : ndarray, shape (..., n_points, 3)
        Points in the order of :data:`POINT_NAMES`. With ``slot="all"`` the batch
        shape ``...`` ends with an axis of 16 slots.
    valid : ndarray of bool, shape (...)
        Whether the slot holds a valid FK solution; the points of an invalid item are NaN.
    reason : ndarray of int8, shape (...)
        :class:`~athenakin.errors.Reason` of the slot (0 where valid).
    """

    xyz: FloatArray
    valid: BoolArray
    reason: Int8Array

    def __getitem__(self, name: str) -> FloatArray:
        """The point ``name`` (one of :data:`POINT_NAMES`), shape (..., 3)."""
        try:
            return self.xyz[..., POINT_NAMES.index(name), :]
        except ValueError:
            raise InvalidInputError(f"name: expected one of {POINT_NAMES}, got {name!r}") from None


@dataclasses.dataclass(frozen=True)
class MechanismState:
    """Where every part of the mechanism is, for a batch of configurations (base frame).

    The one place that places the mechanism: the views, the collision bodies, the
    exports' keyframes, ``/tf`` and the tracker's clearance read it.

    Attributes
    ----------
    xyz : ndarray, shape (..., n_points, 3)
        The named points of :data:`POINT_NAMES`, m.
    frames : ndarray, shape (..., n_links, 4, 4)
        Pose ``T_base_link`` of every link of :data:`LINKS` (the URDF's link frames and
        MJCF's body frames: each body's frame is that of :attr:`Body.link`), m.
    joints : ndarray, shape (..., n_joints)
        Every joint of :data:`JOINTS` in the model's convention (MJCF ``qpos``; m for
        slides, rad for hinges), from :func:`tree_joint_formula`.
    valid : ndarray of bool, shape (...)
        Whether the slot holds a valid FK solution; everything else of an invalid item
        is NaN.
    reason : ndarray of int8, shape (...)
        :class:`~athenakin.errors.Reason` of the slot (0 where valid).

    With ``slot="all"`` the batch shape ``...`` ends with an axis of 16 slots.
    """

    xyz: FloatArray
    frames: FloatArray
    joints: FloatArray
    valid: BoolArray
    reason: Int8Array

    def __getitem__(self, name: str) -> FloatArray:
        """The point ``name`` (one of :data:`POINT_NAMES`), shape (..., 3)."""
        return _pick(self.xyz, POINT_NAMES, name, "name")

    def frame(self, link: str) -> FloatArray:
        """The pose of ``link`` (one of :data:`LINKS`), shape (..., 4, 4)."""
        return _pick(self.frames, LINKS, link, "link", tail=2)

    def joint(self, name: str) -> FloatArray:
        """The value of joint ``name`` (one of :data:`JOINTS`), shape (...)."""
        return _pick(self.joints, tuple(JOINTS), name, "name", tail=0)

    @property
    def points(self) -> MechanismPoints:
        """The points as :class:`MechanismPoints`."""
        return MechanismPoints(xyz=self.xyz, valid=self.valid, reason=self.reason)

    def segments(self) -> FloatArray:
        """End points of every body of :data:`BODIES`, shape (..., n_bodies, 2, 3), m."""
        return self.xyz[..., _SEGMENT_INDEX, :]


def _pick(arr: FloatArray, names: tuple[str, ...], name: object, what: str,
          tail: int = 1) -> FloatArray:
    if not isinstance(name, str) or name not in names:
        raise InvalidInputError(f"{what}: expected one of {names}, got {name!r}")
    i = names.index(name)
    return arr[(..., i) + (slice(None),) * tail]


assert tuple(POINT_NAMES) == FORMULA_POINTS     # the order of mechanism_points_formula's

_SEGMENT_INDEX = np.array([[POINT_NAMES.index(a), POINT_NAMES.index(b)]
                           for a, b in BODY_SEGMENTS.values()])


def _check_slot(slot: object) -> int | None:
    """:func:`~athenakin._validation.check_slot` with ``"all"`` as None (every slot)."""
    k = check_slot(slot, allow_all=True)
    return None if k == "all" else int(k)


def _state(q: ArrayLike, T_b_e: ArrayLike, design: Design | None, slot: object,
           geometry: BodyGeometry | None, *, frames: bool,
           backend: Backend = "auto") -> MechanismState:
    design = resolve_design(design)
    k = _check_slot(slot)
    geometry = BodyGeometry() if geometry is None else geometry
    if not isinstance(geometry, BodyGeometry):
        raise TypeError(f"geometry: expected a BodyGeometry, got {type(geometry).__name__}")
    q = check_array(q, "q", (3,), allow_nonfinite=True)
    T = resolve_rcm_frame(T_b_e, design, single=False)
    sol = forward_kinematics(q, T, design, errors="flag",
                             fields=("valid", "reason", "p", "u", "T_b_s"), backend=backend)
    return state_from_fk(sol, q, T, design, k, geometry, frames=frames)


def state_from_fk(sol: Any, q: FloatArray, T: FloatArray, design: Design,
                  k: int | None, geometry: BodyGeometry, *, frames: bool = True
                  ) -> MechanismState:
    """:func:`mechanism_state` from a forward-kinematics solution already at hand.

    For a caller that holds ``forward_kinematics(q, T, design, errors="flag")`` (all 16
    slots, e.g. from the compiled backend) and checked its arguments: ``q`` (..., 3) and
    ``T`` (..., 4, 4) as validated arrays, ``k`` a slot or None for all 16.
    """
    sel = slice(None) if k is None else k
    valid = np.asarray(sol.valid[..., sel])
    reason = np.asarray(sol.reason[..., sel])
    # O_s's pose depends on the assembly mode only: take it from the per-mode store
    T_mode = sol.T_b_s_mode
    T_b_s = (T_mode[..., SLOT_MODE_INDEX[k], :, :] if k is not None
             else np.take(T_mode, SLOT_MODE_INDEX, axis=-3))
    p = sol.p[..., sel]
    u5 = sol.u[..., sel, :5]
    batch = valid.shape
    # slot-independent points, broadcast to the batch (with a slot axis for "all")
    qq = np.broadcast_to(q if k is not None else q[..., None, :], batch + (3,))
    T_e = np.broadcast_to(T if k is not None else T[..., None, :, :], batch + (4, 4))
    xyz = np.zeros(batch + (len(POINT_NAMES), 3))
    _points(xyz, qq, T_b_s, T_e, p, u5[..., :3], design, geometry)
    xyz[~valid] = np.nan
    if not frames:
        empty = np.empty(batch + (0,))
        return MechanismState(xyz=xyz, frames=empty, joints=empty, valid=valid, reason=reason)
    l1, l2, l3, l4, l5 = design.lengths
    O_s = T_b_s[..., :3, 3]
    with np.errstate(invalid="ignore", divide="ignore"):
        jv = tree_joint_formula(qq[..., 0], qq[..., 1], qq[..., 2], p, u5[..., 0], u5[..., 1],
                                u5[..., 2], u5[..., 3], u5[..., 4], O_s[..., 1], O_s[..., 2],
                                l1 * l1, l2, l3 * l3, l4, l5)
    joints = np.empty(batch + (len(jv),))
    for i, v in enumerate(jv):
        joints[..., i] = v
    joints[~valid] = np.nan
    fr = _tree_frames(joints, np.asarray(T_e, dtype=float), design)
    fr[~valid] = np.nan
    return MechanismState(xyz=xyz, frames=fr, joints=joints, valid=valid, reason=reason)


def O_i_from_T_b_s(T_b_s: FloatArray, design: Design) -> FloatArray:
    """``O_i``, the end of the ``l4`` offset, from the pose of ``O_s`` (Eq. 9-10).

    Parameters
    ----------
    T_b_s : ndarray, shape (..., 4, 4)
        Pose of ``O_s`` in the base frame (NaN where it does not assemble).
    design : Design

    Returns
    -------
    ndarray, shape (..., 3)
        ``O_s - l4 z_s``, base frame, m.
    """
    return T_b_s[..., :3, 3] - design.l4 * T_b_s[..., :3, 2]  # type: ignore[no-any-return]


def _points(xyz: FloatArray, qq: FloatArray, T_b_s: FloatArray, T_e: FloatArray,
            p: FloatArray, u: FloatArray, design: Design, geometry: BodyGeometry) -> None:
    """Write every point of :data:`POINT_NAMES` into ``xyz`` (..., n_points, 3).

    :func:`athenakin._mechanism_formulas.mechanism_points_formula` on arrays: ``qq``
    (..., 3) the actuators, ``T_b_s`` the slot's pose of ``O_s``, ``T_e`` the RCM frame,
    ``p`` (...) the insertion and ``u`` (..., 3) ``u1, u2, u3`` of the slot.
    """
    _, l2, l3, l4, l5 = design.lengths
    lo, hi = rail_extent(design, geometry)
    G = (l2, l3, l4, l5, design.tool_length, geometry.rail_margin,
         0.5 * geometry.carriage_length, geometry.sphere_radius, lo, hi)
    c, s = np.cos(u), np.sin(u)
    with np.errstate(invalid="ignore"):
        pts = mechanism_points_formula(
            qq[..., 0], qq[..., 1], p, c[..., 0], s[..., 0], c[..., 1], s[..., 1], c[..., 2],
            s[..., 2], T_b_s[..., 0, 3], T_b_s[..., 1, 3], T_b_s[..., 2, 3], T_b_s[..., 1, 2],
            T_b_s[..., 1, 1], T_e[..., 0, 3], T_e[..., 1, 3], T_e[..., 2, 3], T_e[..., 0, 2],
            T_e[..., 1, 2], T_e[..., 2, 2], G, np.sqrt, np.minimum, np.maximum, np.where)
    for i, point in enumerate(pts):
        for j in range(3):
            xyz[..., i, j] = point[j]


def mechanism_state(q: ArrayLike, T_b_e: ArrayLike, design: Design | None = None, *,
                    slot: int | Literal["all"] = 0,
                    geometry: BodyGeometry | None = None,
                    backend: Backend = "auto") -> MechanismState:
    """The points, the link frames and the tree's joint values of the mechanism (batched).

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Actuators ``(q1, q2, q3)``, m.
    T_b_e : array-like, shape (..., 4, 4)
        RCM frame (set-up); broadcasts with ``q``.
    design : Design, optional
        Defaults to :meth:`Design.default`.
    slot : int or "all", keyword-only
        Forward-kinematics slot 0..15 (docs/conventions.md), or ``"all"`` for an extra
        trailing batch axis of 16 slots.
    geometry : BodyGeometry, keyword-only, optional
        Carriage length, spherical-mechanism radius and rail margin.
    backend : {"auto", "numpy", "numba"}, keyword-only
        The backend of the forward kinematics (:func:`athenakin.forward_kinematics`).

    Returns
    -------
    MechanismState
        Points (:data:`POINT_NAMES`), frames (:data:`LINKS`) and joint values
        (:data:`JOINTS`); NaN where the slot holds no solution (``valid`` False).

    Raises
    ------
    InvalidInputError
        ``q`` or ``T_b_e`` of a wrong shape, ``slot`` not in 0..15 or ``"all"``.
    TypeError
        ``geometry`` is not a :class:`BodyGeometry`.

    Examples
    --------
    >>> import athenakin as ak
    >>> from athenakin._mechanism import mechanism_state
    >>> from athenakin.robot import REFERENCE_Q
    >>> st = mechanism_state(REFERENCE_Q, ak.default_rcm_frame())
    >>> bool(abs(st.frame("platform")[:3, 3] - st["O_i"]).max() < 1e-14)
    True
    """
    return _state(q, T_b_e, design, slot, geometry, frames=True, backend=backend)


def mechanism_points(q: ArrayLike, T_b_e: ArrayLike, design: Design | None = None, *,
                     slot: int | Literal["all"] = 0,
                     geometry: BodyGeometry | None = None,
                     backend: Backend = "auto") -> MechanismPoints:
    """Every named point of the mechanism in one FK slot, or in all 16.

    The points of :func:`mechanism_state`, without its frames and joint values.

    Parameters
    ----------
    q, T_b_e, design, slot, geometry, backend
        As for :func:`mechanism_state`.

    Returns
    -------
    MechanismPoints
    """
    return _state(q, T_b_e, design, slot, geometry, frames=False, backend=backend).points


def body_segments(points: MechanismPoints) -> FloatArray:
    """End points of every body of :data:`BODIES`, shape (..., n_bodies, 2, 3), m.

    Parameters
    ----------
    points : MechanismPoints
        From :func:`mechanism_points`.
    """
    if not isinstance(points, MechanismPoints):
        raise TypeError(f"points: expected MechanismPoints, got {type(points).__name__}")
    return points.xyz[..., _SEGMENT_INDEX, :]


def link_segments(state: MechanismState, design: Design | None = None,
                  geometry: BodyGeometry | None = None) -> FloatArray:
    """Every body's segment in the frame of the link that carries it (its capsule's axis).

    What the exports attach to :attr:`Body.link`: ``frame(link) @ a`` is the segment's start
    and ``frame(link) @ b`` its end (tested to 1e-12). Every body is rigid in its link but
    the ``actuator`` (C -> O_i on ``k2_arm``: its end moves with q3) and ``sphere_link_2``
    (its end ``S_3`` slides with ``p`` while ``|p| < sphere_radius``); the rail lies in the
    base frame and grows with the carriages where they leave the strokes.

    Parameters
    ----------
    state : MechanismState
        From :func:`mechanism_state` (``frames`` included).
    design : Design, optional
        The design of ``state``.
    geometry : BodyGeometry, optional
        The geometry of ``state``.

    Returns
    -------
    ndarray, shape (..., n_bodies, 2, 3)
        Start and end of every body of :data:`BODIES` in its link's frame, m.
    """
    if not isinstance(state, MechanismState) or state.joints.shape[-1] != len(JOINTS):
        raise TypeError("state: expected a MechanismState from mechanism_state")
    d = resolve_design(design)
    g = BodyGeometry() if geometry is None else geometry
    batch = state.valid.shape
    out = np.zeros(batch + (len(BODIES), 2, 3))
    at = {b: i for i, b in enumerate(BODIES)}
    half, rs, L = 0.5 * g.carriage_length, g.sphere_radius, d.tool_length
    p, q3 = state.joint("p"), state.joint("q3")
    side = np.where(p >= 0, 1.0, -1.0)
    t = p - side * rs
    z3 = np.where((t >= 0.0) & (t <= L), -side * rs, np.clip(t, 0.0, L) - p)
    ends = {
        "carriage_a": ((-half, 0, 0), (half, 0, 0)), "carriage_b": ((-half, 0, 0), (half, 0, 0)),
        "link_a": (_O, (0, 0, d.l1)), "link_b": (_O, (0, 0, d.l1)),
        "link_ad": (_O, (d.l3, 0, 0)), "link_bd": (_O, (d.l3, 0, 0)),
        "carrier": (_O, (0, d.l2, d.l5)), "platform": (_O, (0, 0, d.l4)),
        "instrument": (_O, (0, 0, L)), "sphere_link_1": ((0, -rs, 0), (0, 0, rs)),
    }
    for name, (a, b) in ends.items():
        out[..., at[name], 0, :] = a
        out[..., at[name], 1, :] = b
    out[..., at["rail"], 0, :] = state["rail_lo"]
    out[..., at["rail"], 1, :] = state["rail_hi"]
    out[..., at["actuator"], 1, 2] = q3                   # C -> O_i along z of k2_arm
    out[..., at["sphere_link_2"], 0, 1] = -rs             # S_4 -> S_3 in sph_3
    out[..., at["sphere_link_2"], 1, 2] = z3
    out[~state.valid] = np.nan
    return out
