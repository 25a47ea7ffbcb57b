"""Bodies and collisions: ATHENA's links as capsules, obstacles, and clearance.

- :class:`Bodies`: one capsule (segment + radius) per body of the one table of body
  names (:data:`BODIES`, docs/conventions.md "Bodies"), the pairs never checked
  (adjacent bodies share a joint) and a TOML ``[bodies]`` table;
- :class:`Environment`: halfspaces, spheres, capsules, boxes and meshes around the robot,
  built by chaining, with ``allow=`` for the bodies that may cross them;
- :func:`clearance`: the signed distance of every checked pair for a batch of
  configurations, in one FK slot or all 16 (:class:`Clearance`).

Capsule pairs (and spheres, capsules and halfspaces of the environment) use exact closed
forms, compiled (numba) by default; boxes and meshes go through coal, imported only
then (extra ``[collision]``: ``pip install 'athenakin[collision]'``). See
docs/collision.md.
"""

from .._mechanism import BODIES, BODY_SEGMENTS, BodyGeometry, adjacent_pairs
from ._bodies import DEFAULT_RADII, MAX_RADIUS, Bodies
from ._clearance import MAX_MARGIN, Clearance, clearance
from ._distance import capsule_capsule, capsule_halfspace, point_segment, segment_segment
from ._environment import (
    MAX_OBSTACLES,
    OBSTACLE_KINDS,
    Environment,
    Obstacle,
    OpenMeshWarning,
)
from ._mesh import MAX_MESH_FACES

__all__ = [
    "BODIES",
    "BODY_SEGMENTS",
    "BodyGeometry",
    "adjacent_pairs",
    "Bodies",
    "DEFAULT_RADII",
    "MAX_RADIUS",
    "Environment",
    "Obstacle",
    "OpenMeshWarning",
    "OBSTACLE_KINDS",
    "MAX_OBSTACLES",
    "MAX_MESH_FACES",
    "clearance",
    "Clearance",
    "MAX_MARGIN",
    "segment_segment",
    "point_segment",
    "capsule_capsule",
    "capsule_halfspace",
]
