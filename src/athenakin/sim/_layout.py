"""The physical model shared by the MJCF and URDF exports: bodies, joints, loop closures.

ATHENA's parallel module is a closed-loop mechanism. Both exports use the same
spanning tree (MuJoCo and URDF joint names alike) and the same loop closures:

Tree (parent -> child: joint)::

    base -> carriage_a : q1 (slide x, actuated)
      carriage_a -> a_cross : a_ujoint_x (hinge x_b)       U-joint at A
        a_cross -> link_a1 : a_ujoint_y (hinge y)          bar A-O_i, length l1
          link_a1 -> platform : platform_y (hinge y)       frame i at O_i (Eq. 9)
            platform -> ujoint_cross : u1 (hinge z_s)      U-joint at O_s (Eq. 10)
              ujoint_cross -> instrument : u2              z along the instrument
                instrument -> guide : p (slide z)          guide at the RCM
                  guide -> sph_3 : u3; sph_3 -> sph_4 : u4; sph_4 -> sph_5 : u5
      carriage_a -> link_a3 : a_base_z (hinge z_b)         bar A-D, length l3
        link_a3 -> carrier : carrier_z (hinge z_b)         carries C = D + (0, l2, l5)
          carrier -> k2_arm : k2_x (hinge x_b at C)
            k2_arm -> k2_rod : q3 (slide, actuated)        the radius of k2
    base -> carriage_b : q2 (slide x, actuated)
      carriage_b -> b_cross : b_ujoint_x; b_cross -> link_b1 : b_ujoint_y   bar B-O_i
      carriage_b -> link_b3 : b_base_z                                      bar B-D
    base -> rcm_setup (fixed at T_b_e: the base of the spherical five-bar, set by S1, S2)

Loop closures (:data:`LOOP_CLOSURES`): the tip of ``link_b1`` is at ``O_i``, the
tip of ``link_b3`` is at D, the tip of ``k2_rod`` is at ``O_i`` (points), the
frame of ``sph_5`` is the set-up frame E (a full pose), and two couplings keep
the platform's x axis and the carrier parallel to the base (``platform_y =
-a_ujoint_y``, ``carrier_z = -a_base_z``: a parallelogram or belt in hardware).

The spherical joint ``u3, u4, u5`` at the RCM is the kinematic equivalent of the
passive spherical five-bar (paper Fig. 3), whose geometry the paper does not give.
The instrument roll (a fourth actuator) does not change the kinematics and is left out.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
from numpy.typing import ArrayLike

from .._mechanism import (
    BODY_TABLE,
    JOINTS,
    BodyGeometry,
    MechanismState,
    link_segments,
    state_from_fk,
)
from .._typing import FloatArray
from .._validation import check_array, check_slot
from ..design import Design, resolve_design
from ..errors import InvalidInputError, Reason, error_for_reason
from ..robot import forward_kinematics as reference_forward_kinematics
from ..robot._setup import resolve_rcm_frame

__all__ = ["JOINTS", "ACTUATED", "LOOP_CLOSURES", "LoopClosure", "MechanismJointValues",
           "mechanism_joint_values", "urdf_joint_zero", "COLLISION_BODY", "collision_segments",
           "single_state", "actuator_drawn_lengths", "ACTUATOR_ROD_FALLBACK", "ACTUATOR_OVERLAP",
           "xml_float", "xml_floats"]

#: Joints of the spanning tree in MJCF order: name -> (kind, parent body, child body); the
#: tree itself (origins, axes) is :data:`athenakin._mechanism.TREE`.

#: The three actuated joints, in the order of ``q``.
ACTUATED = ("q1", "q2", "q3")


@dataclasses.dataclass(frozen=True)
class LoopClosure:
    """One loop-closure constraint of the mechanism.

    Attributes
    ----------
    name : str
    kind : {"point", "pose", "coupling"}
        ``point``: two points coincide (3 equations; MuJoCo ``connect``);
        ``pose``: two frames coincide (6 equations; MuJoCo ``weld``);
        ``coupling``: ``joint1 = -joint2`` (1 equation; MuJoCo ``joint``).
    a, b : str
        Sites (point, pose) or joints (coupling).
    text : str
        What it means, for the docs and the URDF comments.
    """

    name: str
    kind: str
    a: str
    b: str
    text: str


#: Loop closures that turn the tree of :data:`JOINTS` into ATHENA's mechanism.
LOOP_CLOSURES = (
    LoopClosure("close_b1", "point", "link_b1_tip", "platform_oi",
                "bar B-O_i (length l1) ends at O_i on the platform"),
    LoopClosure("close_b3", "point", "link_b3_tip", "carrier_d",
                "bar B-D (length l3) ends at D on the carrier"),
    LoopClosure("close_q3", "point", "k2_rod_tip", "platform_oi",
                "the q3 actuator (radius of k2, from C) ends at O_i"),
    LoopClosure("close_rcm", "pose", "sph_5_frame", "rcm_setup_frame",
                "the spherical joint's last frame is the RCM frame E fixed by S1, S2"),
    LoopClosure("parallel_platform", "coupling", "platform_y", "a_ujoint_y",
                "platform_y = -a_ujoint_y: the platform keeps x_i = x_b (Eq. 9)"),
    LoopClosure("parallel_carrier", "coupling", "carrier_z", "a_base_z",
                "carrier_z = -a_base_z: the carrier keeps its orientation (C = D + (0, l2, l5))"),
)


@dataclasses.dataclass(frozen=True)
class MechanismJointValues:
    """Every joint of the spanning tree in one configuration.

    Attributes
    ----------
    values : dict of str -> float
        Joint name (:data:`JOINTS`) -> value in the model's convention (m for
        slides, rad for hinges): what the MJCF export's ``qpos`` holds. ``q1``,
        ``q2``, ``q3`` are the actuators and ``p``, ``u1..u5`` the passive joints of
        the forward kinematics.
    urdf : dict of str -> float
        The same joints relative to the URDF's joint zero (``values[name] -
        zero[name]``; hinges wrapped to ``(-pi, pi]``): what a ROS
        ``sensor_msgs/JointState`` for the file of
        :func:`~athenakin.sim.urdf_from_design` holds. Mimic joints
        (:data:`~athenakin.sim.MIMIC`) are included; ``robot_state_publisher``
        also derives them itself.
    zero : dict of str -> float
        The URDF's joint zero in the model's convention: the joint values of the
        assembled zero configuration (``q_zero``, ``zero_slot``).
    state : MechanismState
        The configuration the values realise, as :func:`athenakin._mechanism.mechanism_state`
        gives it: every point (``state["tip"]``) and link frame (``state.frame("instrument")``)
        in the base frame; ``values`` are its joint values.
    q : ndarray, shape (3,)
        The actuators, m.
    T_b_e : ndarray, shape (4, 4)
        The RCM frame.
    design : Design
    slot : int
        The forward-kinematics slot (0..15).
    """

    values: dict[str, float]
    urdf: dict[str, float]
    zero: dict[str, float]
    state: MechanismState
    q: FloatArray
    T_b_e: FloatArray
    design: Design
    slot: int


def single_state(q: ArrayLike | None, T_b_e: ArrayLike | None, design: Design | None, *,
                 slot: int, geometry: BodyGeometry | None = None) -> MechanismState:
    """:func:`~athenakin._mechanism.mechanism_state` of one configuration that must assemble.

    Solved with the numpy reference forward kinematics (as the views
    draw it), so that the exports are the same text
    whichever backend runs.

    Parameters
    ----------
    q, T_b_e, design, slot
        As for :func:`mechanism_joint_values` (``q`` of shape (3,), ``slot`` an int).
    geometry : BodyGeometry, keyword-only, optional
        Carriage length, spherical-mechanism radius, rail margin (default
        :class:`~athenakin._mechanism.BodyGeometry`).

    Returns
    -------
    MechanismState
        Batch shape ``()``.

    Raises
    ------
    InvalidInputError
        ``q`` not of shape (3,), ``slot`` not in 0..15.
    KinematicsError
        The slot holds no valid solution (the subclass of its reason).
    """
    from ..robot import REFERENCE_Q

    design = resolve_design(design)
    q = check_array(REFERENCE_Q if q is None else q, "q", (3,))
    if q.shape != (3,):
        raise InvalidInputError(f"q: expected shape (3,), got shape {q.shape}")
    slot = check_slot(slot)
    T = resolve_rcm_frame(T_b_e, design)
    st = _solved_state(np.ascontiguousarray(q, dtype=np.float64).tobytes(),
                       np.ascontiguousarray(T, dtype=np.float64).tobytes(), design, int(slot),
                       BodyGeometry() if geometry is None else geometry)
    if not st.valid:
        why = Reason(int(st.reason)).name
        raise error_for_reason(int(st.reason), f"slot {slot} of q = {q.tolist()} m ({why})")
    return st


@functools.lru_cache(maxsize=16)
def _solved_state(q: bytes, T: bytes, design: Design, slot: int,
                  geometry: BodyGeometry) -> MechanismState:
    """The mechanism state of one export configuration, solved once per set of values.

    The numpy reference FK (as the views): an export's numbers never depend on the backend.
    A file writes its URDF and the URDF's joint zero from the same configuration: one solve
    (about 25 ms) instead of one per use. The arrays are read-only (the state is shared).
    """
    qa = np.frombuffer(q, dtype=np.float64).copy()
    Ta = np.frombuffer(T, dtype=np.float64).reshape(4, 4).copy()
    sol = reference_forward_kinematics(qa, Ta, design, errors="flag")
    st = state_from_fk(sol, qa, Ta, design, slot, geometry)
    for f in dataclasses.fields(st):
        v = getattr(st, f.name)
        if isinstance(v, np.ndarray):
            v.setflags(write=False)
    return st


def _joint_dict(st: MechanismState) -> dict[str, float]:
    return dict(zip(JOINTS, (float(v) for v in st.joints), strict=True))


def urdf_joint_zero(T_b_e: ArrayLike | None = None, design: Design | None = None, *,
                    q_zero: ArrayLike | None = None, zero_slot: int = 0) -> dict[str, float]:
    """The joint values (model convention) that the URDF export takes as joint zero.

    Parameters
    ----------
    T_b_e : array-like, shape (4, 4), optional
        RCM frame (default :func:`athenakin.default_rcm_frame`).
    design : Design, optional
    q_zero : array-like, shape (3,), optional
        Actuators of the zero configuration, m (default
        :data:`athenakin.robot.REFERENCE_Q`, the reference configuration).
    zero_slot : int, keyword-only
        Its forward-kinematics slot (default 0).

    Returns
    -------
    dict of str -> float
        Joint name -> value (m, rad) in the assembled zero configuration.

    Raises
    ------
    KinematicsError
        The zero configuration does not assemble (pick another ``q_zero``).
    """
    if q_zero is not None:
        q_zero = check_array(q_zero, "q_zero", (3,))
    return _joint_dict(single_state(q_zero, T_b_e, design, slot=zero_slot))


def mechanism_joint_values(q: ArrayLike | None = None, T_b_e: ArrayLike | None = None,
                           design: Design | None = None, *, slot: int = 0,
                           q_zero: ArrayLike | None = None, zero_slot: int = 0
                           ) -> MechanismJointValues:
    """Values of every joint of the spanning tree in one forward-kinematics slot.

    Parameters
    ----------
    q : array-like, shape (3,), optional
        Actuators, m (default :data:`athenakin.robot.REFERENCE_Q`).
    T_b_e : array-like, shape (4, 4), optional
        RCM frame (default :func:`athenakin.default_rcm_frame`).
    design : Design, optional
    slot : int, keyword-only
        Forward-kinematics slot 0..15.
    q_zero, zero_slot : keyword-only
        The URDF's zero configuration (see :func:`urdf_joint_zero`); pass the
        values given to :func:`~athenakin.sim.urdf_from_design`.

    Returns
    -------
    MechanismJointValues
        ``.values`` (model / MJCF convention), ``.urdf`` (relative to the URDF
        zero, for ROS), ``.zero``, ``.state`` and the configuration's ``q``, ``T_b_e``,
        ``design``, ``slot``.

    Raises
    ------
    KinematicsError
        The slot holds no valid solution.

    Examples
    --------
    >>> from athenakin.sim import mechanism_joint_values
    >>> jv = mechanism_joint_values()           # the reference configuration, slot 0
    >>> round(jv.values["q3"], 3), abs(jv.urdf["q3"]) < 1e-15   # URDF zero = reference
    (0.45, True)
    """
    from ..robot import REFERENCE_Q

    design = resolve_design(design)
    T = resolve_rcm_frame(T_b_e, design)
    q = check_array(REFERENCE_Q if q is None else q, "q", (3,))
    st = single_state(q, T, design, slot=slot)
    values = _joint_dict(st)
    zero = urdf_joint_zero(T, design, q_zero=q_zero, zero_slot=zero_slot)
    rel = {}
    for name, v in values.items():
        x = v - zero[name]
        if JOINTS[name][0] == "hinge":
            x = float(-np.remainder(-x + np.pi, 2 * np.pi) + np.pi)
        rel[name] = x
    return MechanismJointValues(values=values, urdf=rel, zero=zero, state=st, q=q, T_b_e=T,
                                design=design, slot=int(slot))


#: Length of the drawn rod of the q3 actuator where the stroke of q3 has no positive
#: lower limit, m.
ACTUATOR_ROD_FALLBACK = 0.1
#: Overlap of the drawn housing and rod at full extension, as a share of the rod's length.
ACTUATOR_OVERLAP = 0.1


def actuator_drawn_lengths(design: Design | None = None) -> tuple[float, float]:
    """Lengths of the two drawn parts of the q3 actuator in the exports, m.

    The URDF and MJCF draw the q3 actuator as a real telescoping actuator: a housing
    (on the link ``k2_arm``, at C) from C along the actuator axis ``C -> O_i``, and a
    thinner rod (on the link ``k2_rod``) ending at ``O_i``. Neither can stretch, so
    their lengths are chosen from the stroke ``[q3_min, q3_max]`` of q3 such that,
    over the whole stroke, the two overlap along the axis (no gap) and the rod's far
    end never passes behind C::

        rod     b = q3_min                                 (b <= q3_min)
        housing a = q3_max - b + ACTUATOR_OVERLAP * b      (a + b >= q3_max)

    Parameters
    ----------
    design : Design, optional
        Defaults to :meth:`Design.default`.

    Returns
    -------
    housing, rod : float
        ``a`` and ``b``, m. Where ``q3_min`` is 0 (unlimited) the rod is
        :data:`ACTUATOR_ROD_FALLBACK` long; where ``q3_max`` is unlimited the housing
        covers ``q3`` up to ``3 b``. Outside those the drawing cannot hold both
        conditions (a rigid rod longer than ``q3`` pokes behind C). When
        ``q3_max > 2 q3_min`` the housing reaches past ``O_i`` at the short end of the
        stroke (``q3 < a``), as an inline actuator of that stroke would have to.

    Notes
    -----
    These are drawing lengths only: the mass model's two rigid parts
    (:func:`athenakin.dynamics.actuator_part_length`) and the collision capsule of the
    ``actuator`` body are defined on their own (docs/dynamics.md, docs/collision.md).
    """
    d = resolve_design(design)
    lo, hi = float(d.stroke_min[2]), float(d.stroke_max[2])
    rod = lo if math.isfinite(lo) and lo > 0 else ACTUATOR_ROD_FALLBACK
    reach = hi if math.isfinite(hi) else 3.0 * rod
    housing = max(reach - rod, 0.0) + ACTUATOR_OVERLAP * rod
    return housing, rod


def xml_float(x: float) -> str:
    """A number as both exports write it: ``repr(float(x))``, which reads back to the same float."""
    return repr(float(x))


def xml_floats(v: ArrayLike) -> str:
    """Numbers (any shape, flattened) as both exports write them, separated by spaces."""
    return " ".join(xml_float(x) for x in np.asarray(v, dtype=float).ravel())


#: athenakin body -> the MJCF body / URDF link that carries it (``base``: MJCF's world
#: body), as :data:`athenakin._mechanism.BODY_TABLE` says.
COLLISION_BODY: dict[str, str] = {b.name: b.link for b in BODY_TABLE}


def collision_segments(state: MechanismState, design: Design, geometry: BodyGeometry
                       ) -> dict[str, tuple[FloatArray, FloatArray]]:
    """End points of every body's capsule in the frame of the link that carries it.

    Parameters
    ----------
    state : MechanismState
        The configuration the export is assembled in (:func:`single_state`).
    design : Design
    geometry : BodyGeometry

    Returns
    -------
    dict
        Body name -> (a, b), each shape (3,), in the frame of ``COLLISION_BODY[body]``
        (:func:`athenakin._mechanism.link_segments`).
    """
    segs = link_segments(state, design, geometry)
    return {b.name: (segs[j, 0], segs[j, 1]) for j, b in enumerate(BODY_TABLE)}
