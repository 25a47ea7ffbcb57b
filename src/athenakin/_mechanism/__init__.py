"""The one model of ATHENA's mechanism: its bodies, the exports' tree, and where it all is.

Collision (``athenakin.collision``), dynamics (``athenakin.dynamics``), the exports
(``athenakin.sim``), the app, the views and the ROS frames all name the parts of the
robot with the names of :data:`BODIES` and the links of :data:`LINKS`; this package is
the only place that defines them, and :func:`mechanism_state` the one place that places
them (points, link frames, the tree's joint values; batched). Its modules: ``_bodies``
(the table of bodies, their joints and points, :class:`BodyGeometry`), ``_tree`` (the
exports' spanning tree, :data:`TREE`) and ``_placement`` (:func:`mechanism_state` and
what it returns).

Every body (:data:`BODY_TABLE`) is a segment between two named points of the mechanism
(docs/conventions.md, "The mechanism"), carried by one link of the exported tree (URDF
link, MJCF body, ``/tf`` frame), made of one or more parts of the mass model:

==================  ==================  ============  ======================================
body                from -> to          link          what it is
==================  ==================  ============  ======================================
``rail``            rail_lo -> rail_hi  ``base``      the base rail (x axis) over the strokes
``carriage_a``      A_lo -> A_hi        carriage_a    the carriage of q1, centred on A
``carriage_b``      B_lo -> B_hi        carriage_b    the carriage of q2, centred on B
``link_a``          A -> O_i            link_a1       bar of length ``l1``
``link_b``          B -> O_i            link_b1       bar of length ``l1``
``link_ad``         A -> D              link_a3       bar of length ``l3``
``link_bd``         B -> D              link_b3       bar of length ``l3``
``carrier``         D -> C              carrier       carrier of q3 (``C = D + (0, l2, l5)``)
``actuator``        C -> O_i            k2_arm        the q3 actuator (variable length ``q3``)
``platform``        O_i -> O_s          platform      the offset ``l4`` along ``z_i``
``instrument``      O_s -> tip          instrument    the instrument, length ``tool_length``
``sphere_link_1``   S_5 -> S_4          sph_4         spherical mechanism: fixed ``u5`` axis
``sphere_link_2``   S_4 -> S_3          sph_3         ... ``u4`` axis to the instrument guide
==================  ==================  ============  ======================================

The spherical joint at the RCM (the passive spherical five-bar of the paper's Fig. 3,
whose dimensions the paper does not give) is modelled by its kinematic equivalent,
two links whose ends lie on the joint axes at ``sphere_radius`` from the RCM: ``S_3``
on the instrument axis (the guide) on the side of ``O_s`` (outside the patient), ``S_4``
on the axis of ``u4`` in the direction the chain gives it (``R_3 Rz(u3) Rx(pi/2) e_z``)
and ``S_5`` on the fixed axis ``u5`` at ``+z_e``. The ``u4`` axis is perpendicular to the
instrument, and so is ``u5`` at the home pose: a "side of ``O_s``" would flip ``S_4``
and ``S_5`` with the rounding of a zero, so their sides are fixed by the chain instead.
Where that ``S_3`` would lie off the instrument's segment (``O_s`` nearer the RCM than
``sphere_radius``), it is the segment's nearest point: the guide holds the instrument,
so ``instrument`` and ``sphere_link_2`` touch in every configuration.
"""

# the tree's joint-value formula lives in _mechanism_formulas (numpy only, which fast
# compiles; its 16 scalar arguments are a kernel's); re-exported here by name
from .._mechanism_formulas import tree_joint_formula as tree_joint_formula
from ._bodies import (
    BODIES,
    BODY_JOINTS,
    BODY_SEGMENTS,
    BODY_TABLE,
    MASS_PART_LINK,
    POINT_NAMES,
    Body,
    BodyGeometry,
    adjacent_pairs,
    rail_extent,
)
from ._placement import (
    MechanismPoints,
    MechanismState,
    O_i_from_T_b_s,
    body_segments,
    link_segments,
    mechanism_points,
    mechanism_state,
    state_from_fk,
)
from ._tree import JOINTS, LINKS, TREE, TreeJoint, tree_origins

__all__ = ["BODIES", "BODY_SEGMENTS", "BODY_JOINTS", "BODY_TABLE", "Body", "BodyGeometry",
           "MechanismPoints", "MechanismState", "mechanism_points", "mechanism_state",
           "body_segments", "adjacent_pairs", "POINT_NAMES", "JOINTS", "TREE", "TreeJoint",
           "LINKS", "MASS_PART_LINK", "rail_extent", "tree_origins",
           "link_segments", "O_i_from_T_b_s", "state_from_fk"]
