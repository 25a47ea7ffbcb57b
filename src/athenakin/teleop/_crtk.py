"""CRTK's data of the arm: its operating states and the joint state it reports (private).

Units: s, m, m/s, N.
"""

from __future__ import annotations

import dataclasses

from .._typing import FloatArray

__all__ = ["OPERATING_STATES", "JointState"]

#: CRTK operating states.
OPERATING_STATES = ("DISABLED", "ENABLED", "PAUSED", "FAULT")


@dataclasses.dataclass(frozen=True)
class JointState:
    """CRTK's joint state (``sensor_msgs/JointState``) of the three actuators.

    Attributes
    ----------
    t : float
        Time, s (the arm's clock).
    position : ndarray, shape (3,)
        m.
    velocity : ndarray, shape (3,)
        m/s.
    effort : ndarray, shape (3,)
        N, positive along increasing ``q``: the force the servo applied in the last
        cycle (zero in ``DISABLED`` and ``FAULT``).
    """

    t: float
    position: FloatArray
    velocity: FloatArray
    effort: FloatArray
