"""Clearance of the robot's bodies along a motion (private; :mod:`athenakin.collision` lazily).

The tracker and the planner check the bodies of :mod:`athenakin.collision` only when
the caller asks for it (``bodies=``, ``environment=`` or ``clearance_margin=``): the
check costs far more than the tracker's scalar fast path. The collision package is
imported inside the functions, so that the motion subpackage still loads without it.

Each sample is checked in the slot of its labels (assembly mode, sign of ``p``, the
spherical joint's branch): :func:`athenakin.analysis._collision.labelled_clearance`.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._validation import check_scalar
from ..design import Design

__all__ = ["DEFAULT_CLEARANCE_MARGIN", "ClearanceCheck", "clearance_check", "sample_clearance"]

#: Clearance (m) below which a sample is ``NEAR_COLLISION`` (tracker) or refused
#: (planner) when the check is asked for without a margin.
DEFAULT_CLEARANCE_MARGIN = 0.005
#: Largest clearance margin accepted, m (a margin of a metre or more is a unit mistake).
MAX_CLEARANCE_MARGIN = 1.0


@dataclasses.dataclass(frozen=True)
class ClearanceCheck:
    """What to check: the robot's bodies, the obstacles and the margin (m)."""

    bodies: Any
    environment: Any
    margin: float


def clearance_check(design: Design, bodies: object, environment: object,
                    clearance_margin: object) -> ClearanceCheck | None:
    """The check the caller asks for, or None when it asks for none.

    Any of ``bodies``, ``environment`` or ``clearance_margin`` turns the check on;
    missing bodies are :meth:`athenakin.collision.Bodies.default` of ``design``,
    a missing margin is :data:`DEFAULT_CLEARANCE_MARGIN`.

    Raises
    ------
    TypeError
        ``bodies`` is not a :class:`~athenakin.collision.Bodies`, or ``environment`` not
        an :class:`~athenakin.collision.Environment`.
    InvalidInputError
        ``clearance_margin`` is negative, NaN or above :data:`MAX_CLEARANCE_MARGIN`.
    """
    if bodies is None and environment is None and clearance_margin is None:
        return None
    from ..collision import Bodies, Environment

    if bodies is None:
        bodies = Bodies.default(design)
    elif not isinstance(bodies, Bodies):
        raise TypeError(f"bodies: expected athenakin.collision.Bodies or None, got "
                        f"{type(bodies).__name__}")
    if environment is not None and not isinstance(environment, Environment):
        raise TypeError(f"environment: expected athenakin.collision.Environment or None, got "
                        f"{type(environment).__name__}")
    if clearance_margin is None:
        margin = DEFAULT_CLEARANCE_MARGIN
    else:
        margin = check_scalar(clearance_margin, "clearance_margin", nonnegative=True)
        if not margin <= MAX_CLEARANCE_MARGIN:
            from ..errors import InvalidInputError

            raise InvalidInputError(f"clearance_margin: expected a distance in [0, "
                                    f"{MAX_CLEARANCE_MARGIN:g}] m, got {margin!r}")
    return ClearanceCheck(bodies=bodies, environment=environment, margin=float(margin))


def sample_clearance(check: ClearanceCheck, q: NDArray[np.float64], T_b_e: NDArray[np.float64],
                     design: Design, mode: NDArray[np.int64], p_sign: NDArray[np.int64],
                     wrist: NDArray[np.int64] | None = None
                     ) -> tuple[NDArray[np.float64], NDArray[np.str_]]:
    """Least clearance of each sample and the pair that has it.

    Parameters
    ----------
    check : ClearanceCheck
    q : ndarray, shape (n, 3)
        Actuators, m.
    T_b_e : ndarray, shape (4, 4)
    design : Design
    mode, p_sign : ndarray of int, shape (n,)
        Assembly mode and sign of ``p`` of each sample (+1 / -1).
    wrist : ndarray of int, shape (n,), optional
        Spherical-joint branch (+1 / -1, default +1): it places the middle joint of the
        spherical mechanism.

    Returns
    -------
    distance : ndarray, shape (n,)
        Signed least distance between the bodies and to the obstacles, m (negative:
        penetration; ``+inf`` when no pair is checked); NaN where no slot of the
        sample's labels is valid.
    pair : ndarray of str, shape (n, 2)
        The two names (body, body or obstacle) of the least distance ("" where NaN).
    """
    from ..analysis._collision import labelled_clearance

    return labelled_clearance(q, T_b_e, design, np.asarray(mode), np.asarray(p_sign) == -1,
                              bodies=check.bodies, environment=check.environment, wrist=wrist)


def describe_pair(pair: NDArray[np.str_] | tuple[str, str]) -> str:
    """``'link_a' and 'instrument'`` for messages."""
    a, b = (str(x) for x in pair)
    return f"{a!r} and {b!r}"


def is_close(distance: float, margin: float) -> bool:
    """``distance < margin`` (False for NaN)."""
    return not math.isnan(distance) and distance < margin
