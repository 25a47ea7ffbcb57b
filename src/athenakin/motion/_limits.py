"""The planner's limits and its per-segment plan."""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from .._validation import check_array, check_scalar
from ._path import (
    Segment,
)
from ._timing import (
    LamProfile,
)

#: Relative tolerance of the velocity / acceleration / jerk / tip-speed checks.
LIMIT_RTOL = 1e-6


@dataclasses.dataclass(frozen=True, kw_only=True)
class Limits:
    """Kinematic limits of a trajectory (stroke limits come from the design).

    Attributes
    ----------
    v_max, a_max : ndarray, shape (3,)
        Actuator speed (m/s) and acceleration (m/s^2) limits.
    j_max : ndarray, shape (3,) or None
        Actuator jerk limits (m/s^3); None: not limited (acceleration-limited
        profile, whose acceleration steps).
    tip_speed : float or None
        Tool-tip speed limit (m/s).
    """

    v_max: FloatArray
    a_max: FloatArray
    j_max: FloatArray | None = None
    tip_speed: float | None = None

    @classmethod
    def build(cls, v_max: ArrayLike, a_max: ArrayLike, j_max: ArrayLike | None,
              tip_speed: float | None) -> Limits:
        """Validate scalars or (3,) arrays of positive limits.

        Parameters
        ----------
        v_max, a_max : float or array-like, shape (3,)
            Actuator velocity (m/s) and acceleration (m/s^2) limits, one for all or per actuator.
        j_max : float or array-like, shape (3,), or None
            Jerk limits, m/s^3 (None: none).
        tip_speed : float or None
            Tool-tip speed limit, m/s (None: none).

        Returns
        -------
        Limits

        Raises
        ------
        ValueError
            A limit that is not positive, or not one number or three (named).
        """
        def vec(x: ArrayLike, name: str) -> FloatArray:
            a = check_array(x, name, ())
            if a.ndim not in (0, 1) or (a.ndim == 1 and a.shape != (3,)):
                raise ValueError(f"{name}: expected a number or 3 numbers (q1, q2, q3), "
                                 f"got shape {a.shape}")
            if np.any(a <= 0):
                raise ValueError(f"{name}: expected positive limits, got {a.tolist()}")
            return np.broadcast_to(a, (3,)).astype(float)

        return cls(v_max=vec(v_max, "v_max"), a_max=vec(a_max, "a_max"),
                   j_max=None if j_max is None else vec(j_max, "j_max"),
                   tip_speed=None if tip_speed is None
                   else check_scalar(tip_speed, "tip_speed", positive=True))


# --------------------------------------------------------------------------------------
@dataclasses.dataclass
class _SegmentPlan:
    seg: Segment
    K: tuple[FloatArray, FloatArray, FloatArray]
    tip_factor: float
    tighten: float = 1.0        # extra factor (< 1) on all limits after a failed check
    profile: LamProfile | None = None
    requested: float | None = None


def _seg_name(sp: _SegmentPlan) -> str:
    return f"{sp.seg.start.tolist()} -> {sp.seg.end.tolist()}"
