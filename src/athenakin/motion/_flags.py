"""The bits of :class:`TrackFlag`, why a tracked sample deserves attention (private).

In a module of their own so that the tracker (:mod:`._tracker`) and its compiled loop
(:mod:`._kernels`) both import them.
"""

from __future__ import annotations

import enum

__all__ = ["TrackFlag"]


class TrackFlag(enum.IntFlag):
    """Why a tracked sample deserves attention (bits; ``NONE`` when all is well).

    Attributes
    ----------
    LOST
        No forward-kinematics solution (outside the workspace, A/B order broken,
        non-finite reading); the pose is that of the last valid sample, ``valid`` False.
    REACQUIRED
        First valid sample after ``LOST``: continuity with the pose before the loss
        is not guaranteed.
    JUMP
        The returned solution moved more than the jump thresholds since the previous sample.
    MODE_SWITCH
        The assembly mode differs from the previous sample's.
    BRANCH_SWITCH
        A serial label (sign of ``p``, U-joint or spherical-joint branch) differs
        from the previous sample's: expected when crossing ``sin u2 = 0`` or
        ``sin u4 = 0``, where the continuous solution changes label.
    AMBIGUOUS
        Another solution is also within the jump thresholds of the previous pose:
        the readings cannot tell which one the robot is in (e.g. next to the mode
        boundary, where both assembly modes meet).
    OUT_OF_STROKE
        A reading lies outside the design's stroke limits (the pose is still computed).
    NEAR_MODE_BOUNDARY, NEAR_H_ZERO, NEAR_LINK_LIMIT, NEAR_UJOINT, NEAR_WRIST, NEAR_P_ZERO
        A singularity measure is below its margin (:class:`Margins`: ``half_chord``,
        ``h``, ``link``, ``sin_u2``, ``sin_u4``, ``p``).
    COLLISION
        Two bodies, or a body and an obstacle, overlap (clearance < 0, as
        :attr:`athenakin.collision.Clearance.colliding`); only
        when the tracker checks collisions (``bodies=``, ``environment=`` or
        ``clearance_margin=``).
    NEAR_COLLISION
        The clearance is below ``clearance_margin`` (set on collisions too, so that
        ``raise_on="NEAR_COLLISION"`` stops at both).
    """

    NONE = 0
    LOST = 1
    REACQUIRED = 2
    JUMP = 4
    MODE_SWITCH = 8
    BRANCH_SWITCH = 16
    AMBIGUOUS = 32
    OUT_OF_STROKE = 64
    NEAR_MODE_BOUNDARY = 128
    NEAR_H_ZERO = 256
    NEAR_LINK_LIMIT = 512
    NEAR_UJOINT = 1024
    NEAR_WRIST = 2048
    NEAR_P_ZERO = 4096
    COLLISION = 8192
    NEAR_COLLISION = 16384

    @property
    def near_singular(self) -> bool:
        """True when any ``NEAR_*`` bit is set."""
        return bool(self & _NEAR_ANY)


_NEAR_ANY = (TrackFlag.NEAR_MODE_BOUNDARY | TrackFlag.NEAR_H_ZERO | TrackFlag.NEAR_LINK_LIMIT
             | TrackFlag.NEAR_UJOINT | TrackFlag.NEAR_WRIST | TrackFlag.NEAR_P_ZERO)
