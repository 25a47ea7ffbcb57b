"""The bodies of ATHENA: the one table, its joints and points, and the parts' dimensions.

:data:`BODY_TABLE` names every body, the segment between two named points
(:data:`POINT_NAMES`) that is its axis, the exported link that carries it and its parts
of the mass model; :data:`BODY_JOINTS` the joints that connect them (the pairs never
checked for clearance, :func:`adjacent_pairs`); :class:`BodyGeometry` the dimensions
that the kinematic model does not fix. The table is drawn in :mod:`athenakin._mechanism`.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .._validation import check_scalar
from ..design import Design
from ..errors import InvalidInputError

__all__ = ["Body", "BODY_TABLE", "BODY_SEGMENTS", "BODIES", "MASS_PART_LINK", "BODY_JOINTS",
           "POINT_NAMES", "adjacent_pairs", "BodyGeometry", "rail_extent"]


@dataclasses.dataclass(frozen=True)
class Body:
    """One body of the mechanism: where it is, which exported link carries it, its parts.

    Attributes
    ----------
    name : str
        athenakin's name of the body (collision, mass model, views).
    start, end : str
        Its segment's end points (names of :data:`POINT_NAMES`): the axis of its
        collision capsule and of its drawing.
    link : str
        The link of the exported tree (URDF link, MJCF body, ``/tf`` frame; ``base`` is
        the URDF's root and MJCF's world body) that carries the body: its collision
        capsule is the segment in that link's frame at the export's configuration.
    mass_parts : tuple of (str, str)
        The parts of the mass model (:data:`athenakin.dynamics.MASS_BODIES`) that make up
        the body, each with the link whose frame is its body frame.
    drawing : str
        Colour group of the views and exports (``rail``, ``parallel``, ``actuator``,
        ``serial``, ``sphere``).
    """

    name: str
    start: str
    end: str
    link: str
    mass_parts: tuple[tuple[str, str], ...]
    drawing: str


#: The one table of ATHENA's bodies; its order is the order of every per-body axis in
#: athenakin (collision pairs, masses, exports). ``actuator`` (C -> O_i) is carried by
#: ``k2_arm``, the housing at C whose frame (origin C, ``z`` towards ``O_i``) is the
#: actuator's body frame in the mass model and the dynamics; the rod (mass part
#: ``actuator_rod``) rides on ``k2_rod``.
BODY_TABLE: tuple[Body, ...] = (
    Body("rail", "rail_lo", "rail_hi", "base", (("rail", "base"),), "rail"),
    Body("carriage_a", "A_lo", "A_hi", "carriage_a", (("carriage_a", "carriage_a"),), "rail"),
    Body("carriage_b", "B_lo", "B_hi", "carriage_b", (("carriage_b", "carriage_b"),), "rail"),
    Body("link_a", "A", "O_i", "link_a1", (("link_a", "link_a1"),), "parallel"),
    Body("link_b", "B", "O_i", "link_b1", (("link_b", "link_b1"),), "parallel"),
    Body("link_ad", "A", "D", "link_a3", (("link_ad", "link_a3"),), "parallel"),
    Body("link_bd", "B", "D", "link_b3", (("link_bd", "link_b3"),), "parallel"),
    Body("carrier", "D", "C", "carrier", (("carrier", "carrier"), ("slider_d", "carrier")),
         "parallel"),
    Body("actuator", "C", "O_i", "k2_arm", (("actuator", "k2_arm"), ("actuator_rod", "k2_rod")),
         "actuator"),
    Body("platform", "O_i", "O_s", "platform", (("platform", "platform"),), "parallel"),
    Body("instrument", "O_s", "tip", "instrument", (("instrument", "instrument"),), "serial"),
    Body("sphere_link_1", "S_5", "S_4", "sph_4", (("sphere_link_1", "sph_4"),), "sphere"),
    Body("sphere_link_2", "S_4", "S_3", "sph_3", (("sphere_link_2", "sph_3"), ("guide", "guide")),
         "sphere"),
)
#: Body name -> (start point, end point), from :data:`BODY_TABLE`.
BODY_SEGMENTS: dict[str, tuple[str, str]] = {b.name: (b.start, b.end) for b in BODY_TABLE}
#: Body names in table order.
BODIES: tuple[str, ...] = tuple(BODY_SEGMENTS)
#: Part of the mass model -> the exported link whose frame is its body frame.
MASS_PART_LINK: dict[str, str] = {part: link for b in BODY_TABLE for part, link in b.mass_parts}

#: Joint -> the bodies it connects. Two bodies that share a joint touch by construction
#: and are never paired in a clearance check (:func:`adjacent_pairs`). ``S_3`` is on the
#: instrument's segment in every configuration (:func:`mechanism_points`).
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


def rail_extent(design: Design, geometry: BodyGeometry | None = None) -> tuple[float, float]:
    """The rail's ``x`` extent, without the carriages: the finite strokes of q1, q2 +- margin.

    One policy for the rail (the mass model's fixed rail; :func:`mechanism_points` extends
    it to cover the carriages): the finite stroke limits of q1 and q2 widened by
    ``geometry.rail_margin``; an infinite limit is left out, and where both lower (upper)
    limits are infinite the rail starts (ends) at the base origin ``x = 0``.

    Parameters
    ----------
    design : Design
    geometry : BodyGeometry, optional

    Returns
    -------
    lo, hi : float
        m, in the base frame.
    """
    g = BodyGeometry() if geometry is None else geometry
    smin, smax = design.stroke_min[:2], design.stroke_max[:2]
    lo = float(smin[np.isfinite(smin)].min()) if np.isfinite(smin).any() else 0.0
    hi = float(smax[np.isfinite(smax)].max()) if np.isfinite(smax).any() else 0.0
    return lo - g.rail_margin, hi + g.rail_margin
