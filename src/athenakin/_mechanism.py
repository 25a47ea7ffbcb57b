"""The one vocabulary of ATHENA's bodies, and where their end points are (batched).

Collision (``athenakin.collision``), dynamics (``athenakin.dynamics``), the exports
(``athenakin.sim``), the app and the ROS frames all name the parts of the robot with
the names of :data:`BODIES`; this table is the only place that defines them.

Every body is a segment between two named points of the mechanism
(docs/conventions.md, "The mechanism"):

==================  =================  ==========================================
body                from -> to         what it is
==================  =================  ==========================================
``rail``            rail_lo -> rail_hi  the base rail (x axis) over the strokes of A, B
``carriage_a``      A_lo -> A_hi       the carriage of q1, centred on A, along x
``carriage_b``      B_lo -> B_hi       the carriage of q2, centred on B, along x
``link_a``          A -> O_i           bar of length ``l1``
``link_b``          B -> O_i           bar of length ``l1``
``link_ad``         A -> D             bar of length ``l3``
``link_bd``         B -> D             bar of length ``l3``
``carrier``         D -> C             the carrier of the q3 actuator (``C = D + (0, l2, l5)``)
``actuator``        C -> O_i           the q3 actuator (variable length ``q3``)
``platform``        O_i -> O_s         the offset ``l4`` along ``z_i``
``instrument``      O_s -> tip         the instrument, length ``tool_length``
``sphere_link_1``   S_5 -> S_4         spherical mechanism: from the fixed ``u5`` axis
``sphere_link_2``   S_4 -> S_3         ... to the ``u4`` axis, to the instrument guide
==================  =================  ==========================================

The spherical joint at the RCM (the passive spherical five-bar of the paper's Fig. 3,
whose dimensions the paper does not give) is modelled by its kinematic equivalent,
two links whose ends lie on the joint axes at ``sphere_radius`` from the RCM: ``S_3``
on the instrument axis (the guide) on the side of ``O_s`` (outside the patient), ``S_4``
on the axis of ``u4`` in the direction the chain gives it (``R_3 Rz(u3) Rx(pi/2) e_z``)
and ``S_5`` on the fixed axis ``u5`` at ``+z_e``. The ``u4`` axis is perpendicular to the
instrument, and so is ``u5`` at the home pose: a "side of ``O_s``" would flip ``S_4``
and ``S_5`` with the rounding of a zero, so their sides are fixed by the chain instead.
"""

from __future__ import annotations

import dataclasses
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._dispatch import forward_kinematics
from ._validation import check_array, check_scalar
from .design import Design, resolve_design
from .errors import InvalidInputError
from .robot._fk import SLOT_MODE_INDEX
from .robot._setup import resolve_rcm_frame

__all__ = ["BODIES", "BODY_SEGMENTS", "BODY_JOINTS", "BodyGeometry", "MechanismPoints",
           "mechanism_points", "body_segments", "adjacent_pairs", "POINT_NAMES"]

#: Body name -> (start point, end point); the order of this table is the order of every
#: per-body axis in athenakin (collision pairs, masses, exports).
BODY_SEGMENTS: dict[str, tuple[str, str]] = {
    "rail": ("rail_lo", "rail_hi"),
    "carriage_a": ("A_lo", "A_hi"),
    "carriage_b": ("B_lo", "B_hi"),
    "link_a": ("A", "O_i"),
    "link_b": ("B", "O_i"),
    "link_ad": ("A", "D"),
    "link_bd": ("B", "D"),
    "carrier": ("D", "C"),
    "actuator": ("C", "O_i"),
    "platform": ("O_i", "O_s"),
    "instrument": ("O_s", "tip"),
    "sphere_link_1": ("S_5", "S_4"),
    "sphere_link_2": ("S_4", "S_3"),
}
#: Body names in table order.
BODIES: tuple[str, ...] = tuple(BODY_SEGMENTS)

#: Joint -> the bodies it connects. Two bodies that share a joint touch by construction
#: and are never paired in a clearance check (:func:`adjacent_pairs`).
BODY_JOINTS: dict[str, tuple[str, ...]] = {
    "A": ("rail", "carriage_a", "link_a", "link_ad"),
    "B": ("rail", "carriage_b", "link_b", "link_bd"),
    "D": ("link_ad", "link_bd", "carrier"),
    "C": ("carrier", "actuator"),
    "O_i": ("link_a", "link_b", "actuator", "platform"),
    "O_s": ("platform", "instrument"),
    "S_3": ("instrument", "sphere_link_2"),
    "S_4": ("sphere_link_1", "sphere_link_2"),
}

#: Names of the points of :class:`MechanismPoints`, in the order of its ``xyz`` axis.
POINT_NAMES: tuple[str, ...] = (
    "A", "B", "M", "D", "C_foot", "C", "O_i", "O_s", "RCM", "tip",
    "rail_lo", "rail_hi", "A_lo", "A_hi", "B_lo", "B_hi", "S_3", "S_4", "S_5")


def adjacent_pairs() -> tuple[tuple[str, str], ...]:
    """Pairs of bodies that share a joint (:data:`BODY_JOINTS`), in table order.

    Returns
    -------
    tuple of (str, str)
        Each pair ``(a, b)`` with ``a`` before ``b`` in :data:`BODIES`.
    """
    order = {b: i for i, b in enumerate(BODIES)}
    pairs = set()
    for members in BODY_JOINTS.values():
        for a in members:
            for b in members:
                if order[a] < order[b]:
                    pairs.add((a, b))
    return tuple(sorted(pairs, key=lambda ab: (order[ab[0]], order[ab[1]])))


@dataclasses.dataclass(frozen=True)
class BodyGeometry:
    """Dimensions of the parts that the kinematic model does not fix (m).

    Attributes
    ----------
    carriage_length : float
        Length of each carriage along the rail, centred on A (B). Default 0.06 m.
    sphere_radius : float
        Distance from the RCM of the spherical mechanism's link ends ``S_3, S_4, S_5``.
        Default 0.10 m.
    rail_margin : float
        How far the rail extends beyond the strokes of A and B. Default 0.05 m.
    """

    carriage_length: float = 0.06
    sphere_radius: float = 0.10
    rail_margin: float = 0.05

    def __post_init__(self) -> None:
        for name in ("carriage_length", "sphere_radius", "rail_margin"):
            v = check_scalar(getattr(self, name), name)
            if not (0.0 <= v <= 1e3):
                raise InvalidInputError(f"{name}: expected a length in [0, 1000] m, got {v!r}")
            object.__setattr__(self, name, float(v))


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

    xyz: NDArray[np.float64]
    valid: NDArray[np.bool_]
    reason: NDArray[np.int8]

    def __getitem__(self, name: str) -> NDArray[np.float64]:
        """The point ``name`` (one of :data:`POINT_NAMES`), shape (..., 3)."""
        try:
            return self.xyz[..., POINT_NAMES.index(name), :]
        except ValueError:
            raise InvalidInputError(f"name: expected one of {POINT_NAMES}, got {name!r}") from None


def _check_slot(slot: object) -> int | None:
    if isinstance(slot, str) and slot == "all":
        return None
    if isinstance(slot, bool) or not isinstance(slot, (int, np.integer)) or not 0 <= slot < 16:
        raise InvalidInputError(f"slot: expected an integer in 0..15 or 'all', got {slot!r}")
    return int(slot)


def mechanism_points(q: ArrayLike, T_b_e: ArrayLike, design: Design | None = None, *,
                     slot: int | Literal["all"] = 0,
                     geometry: BodyGeometry | None = None) -> MechanismPoints:
    """Every named point of the mechanism in one FK slot, or in all 16.

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

    Returns
    -------
    MechanismPoints
    """
    design = resolve_design(design)
    k = _check_slot(slot)
    geometry = BodyGeometry() if geometry is None else geometry
    if not isinstance(geometry, BodyGeometry):
        raise TypeError(f"geometry: expected a BodyGeometry, got {type(geometry).__name__}")
    q = check_array(q, "q", (3,), allow_nonfinite=True)
    T = resolve_rcm_frame(T_b_e, design, single=False)
    sol = forward_kinematics(q, T, design, errors="flag",
                             fields=("valid", "reason", "p", "u", "T_b_s"))
    sel = slice(None) if k is None else k
    valid = np.asarray(sol.valid[..., sel])
    reason = np.asarray(sol.reason[..., sel])
    # O_s's pose depends on the assembly mode only: take it from the per-mode store
    T_mode = sol.T_b_s_mode
    T_b_s = (T_mode[..., SLOT_MODE_INDEX[k], :, :] if k is not None
             else np.take(T_mode, SLOT_MODE_INDEX, axis=-3))
    p = sol.p[..., sel]
    u = sol.u[..., sel, :3]
    batch = valid.shape
    # slot-independent points, broadcast to the batch (with a slot axis for "all")
    qq = np.broadcast_to(q if k is not None else q[..., None, :], batch + (3,))
    T_e = np.broadcast_to(T if k is not None else T[..., None, :, :], batch + (4, 4))
    l1, l2, l3, l4, l5 = design.lengths
    q1, q2 = qq[..., 0], qq[..., 1]
    h = 0.5 * (q1 - q2)
    x_M = 0.5 * (q1 + q2)
    with np.errstate(invalid="ignore"):
        y_D = np.sqrt(l3 * l3 - h * h)
    xyz = np.zeros(batch + (len(POINT_NAMES), 3))
    at = {name: i for i, name in enumerate(POINT_NAMES)}

    def put(name: str, x: ArrayLike, y: ArrayLike = 0.0, z: ArrayLike = 0.0) -> None:
        i = at[name]
        xyz[..., i, 0] = x
        xyz[..., i, 1] = y
        xyz[..., i, 2] = z

    def put3(name: str, v: NDArray[np.float64]) -> None:
        xyz[..., at[name], :] = v

    half = 0.5 * geometry.carriage_length
    put("A", q1)
    put("B", q2)
    put("M", x_M)
    put("D", x_M, y_D)
    put("C_foot", x_M, y_D + l2)
    put("C", x_M, y_D + l2, l5)
    put("A_lo", q1 - half)
    put("A_hi", q1 + half)
    put("B_lo", q2 - half)
    put("B_hi", q2 + half)
    R_s = T_b_s[..., :3, :3]
    O_s = T_b_s[..., :3, 3]
    put3("O_s", O_s)
    put3("O_i", O_s - l4 * R_s[..., :, 2])
    c, s = np.cos(u), np.sin(u)
    ca, sa, cb, sb, c3, s3 = c[..., 0], s[..., 0], c[..., 1], s[..., 1], c[..., 2], s[..., 2]

    def rot(x: NDArray[np.float64], y: NDArray[np.float64],
            z: NDArray[np.float64]) -> NDArray[np.float64]:
        """R_s (x, y, z) for vectors given by components."""
        return (R_s[..., :, 0] * x[..., None] + R_s[..., :, 1] * y[..., None]
                + R_s[..., :, 2] * z[..., None])

    # R_3 = R_s R(u1, u2) (chain._ups.rotation_u_pair, rows (ca cb, sa, ca sb),
    # (sa cb, -ca, sa sb), (sb, 0, -cb)): its third column is the instrument axis
    # (O_s -> RCM if p > 0), and R_3 (sin u3, -cos u3, 0) the axis of u4
    d = rot(ca * sb, sa * sb, -cb)
    a4 = rot(ca * cb * s3 - sa * c3, sa * cb * s3 + ca * c3, sb * s3)
    put3("tip", O_s + design.tool_length * d)
    RCM = T_e[..., :3, 3]
    put3("RCM", RCM)
    side = np.sign(p)[..., None]                         # O_s is on the side -p d of the RCM
    side = np.where(side == 0, 1.0, side)
    rs = geometry.sphere_radius
    put3("S_3", RCM + rs * (-side * d))                  # towards O_s
    # S_4 on the u4 axis as the chain orients it, S_5 on +z_e: u4 is perpendicular to the
    # instrument, and at the home pose so is u5, so a side of O_s would flip them with
    # the rounding of a zero dot product.
    put3("S_4", RCM + rs * a4)
    put3("S_5", RCM + rs * T_e[..., :3, 2])
    lo = np.min(np.where(np.isfinite(design.stroke_min[:2]), design.stroke_min[:2], np.inf))
    hi = np.max(np.where(np.isfinite(design.stroke_max[:2]), design.stroke_max[:2], -np.inf))
    lo_b = np.minimum(np.minimum(q1, q2), lo) if np.isfinite(lo) else np.minimum(q1, q2)
    hi_b = np.maximum(np.maximum(q1, q2), hi) if np.isfinite(hi) else np.maximum(q1, q2)
    rm = geometry.rail_margin
    put("rail_lo", lo_b - rm)
    put("rail_hi", hi_b + rm)
    xyz[~valid] = np.nan
    return MechanismPoints(xyz=xyz, valid=valid, reason=reason)


def body_segments(points: MechanismPoints) -> NDArray[np.float64]:
    """End points of every body of :data:`BODIES`, shape (..., n_bodies, 2, 3), m.

    Parameters
    ----------
    points : MechanismPoints
        From :func:`mechanism_points`.
    """
    if not isinstance(points, MechanismPoints):
        raise TypeError(f"points: expected MechanismPoints, got {type(points).__name__}")
    idx = np.array([[POINT_NAMES.index(a), POINT_NAMES.index(b)]
                    for a, b in BODY_SEGMENTS.values()])
    return points.xyz[..., idx, :]
