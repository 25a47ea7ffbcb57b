"""Exceptions raised by athenakin, and the reason codes of batch results.

All domain failures derive from :class:`KinematicsError`. Input errors (wrong
type, shape or non-finite values) raise the built-in :class:`TypeError` or
:class:`ValueError` (through :class:`InvalidInputError`, which is both a
``ValueError`` and a ``KinematicsError``), so that ``except ValueError`` keeps
working for users who treat bad input generically.

Batch policy
------------
A single (unbatched) call raises on the first failure. A batch never aborts
because of one bad item: each item (and each of the 16 forward-kinematics
slots) carries a :class:`Reason` code, and ``errors="raise"`` turns the first
failure into the matching exception instead.
"""

from __future__ import annotations

import enum

__all__ = [
    "KinematicsError",
    "InvalidInputError",
    "NotOnStudyQuadricError",
    "OutOfWorkspaceError",
    "StrokeLimitError",
    "SingularConfigurationError",
    "DegenerateChainError",
    "Reason",
    "error_for_reason",
]


class KinematicsError(Exception):
    """Base class of every error raised by athenakin's kinematics."""


class InvalidInputError(KinematicsError, ValueError):
    """An argument has the wrong shape or holds NaN / inf values."""


class NotOnStudyQuadricError(KinematicsError, ValueError):
    """A Study vector is not on the Study quadric, or its quaternion part is zero."""


class OutOfWorkspaceError(KinematicsError):
    """A configuration or pose is outside what the mechanism can reach.

    The message names the constraint that failed (stroke limit, circle
    intersection, A/B order, link length, ...); :attr:`reason` holds the code.
    """

    def __init__(self, message: str, reason: Reason | None = None) -> None:
        super().__init__(message)
        self.reason = reason


class StrokeLimitError(OutOfWorkspaceError):
    """An actuator value lies outside the stroke limits of the design."""


class SingularConfigurationError(KinematicsError):
    """The requested quantity is not unique (or not defined) at a singular configuration."""

    def __init__(self, message: str, reason: Reason | None = None) -> None:
        super().__init__(message)
        self.reason = reason


class DegenerateChainError(SingularConfigurationError):
    """The serial UPS chain has a continuum of solutions (aligned axes, ``p = 0``)."""


class Reason(enum.IntEnum):
    """Why an item (or a solution slot) of a batch result is not a valid, isolated solution.

    ``OK`` (0) marks a valid item. Codes are stable integers; store them, don't
    compare their names.
    """

    OK = 0
    NONFINITE_INPUT = 1
    STROKE_LIMIT = 2
    AB_ORDER = 3
    LINK_TOO_SHORT = 4
    CIRCLES_DISJOINT = 5
    CIRCLES_TANGENT = 6
    SERIAL_P_ZERO = 7
    UJOINT_SINGULAR = 8
    WRIST_SINGULAR = 9
    CLOSURE_FAILED = 10
    NOT_IN_MODULE_IMAGE = 11
    IK_SINGULAR = 12
    INSERTION_RANGE = 13

    @property
    def description(self) -> str:
        """One line that says what the code means."""
        return _DESCRIPTIONS[self]


_DESCRIPTIONS = {
    Reason.OK: "valid, isolated solution",
    Reason.NONFINITE_INPUT: "input holds NaN or inf",
    Reason.STROKE_LIMIT: "an actuator value is outside the design's stroke limits",
    Reason.AB_ORDER: "the order of A and B on the rail contradicts the design (ab_order)",
    Reason.LINK_TOO_SHORT: ("links l1/l3 cannot span A-B: |q1 - q2| / 2 would reach l1 or "
                            "exceed l3 (for a pose: O_s too far from the rail axis, beyond "
                            "l1 + l4, or too close to it)"),
    Reason.CIRCLES_DISJOINT: "circles k1 and k2 do not intersect (w < 0)",
    Reason.CIRCLES_TANGENT: "circles k1 and k2 touch (w = 0): both assembly modes coincide",
    Reason.SERIAL_P_ZERO: "O_s coincides with the RCM (p = 0): the instrument axis is undefined",
    Reason.UJOINT_SINGULAR: "U-joint axes aligned (sin u2 = 0): u1 is free (continuum)",
    Reason.WRIST_SINGULAR: "spherical joint axes aligned (sin u4 = 0): u3 +/- u5 free (continuum)",
    Reason.CLOSURE_FAILED: "the solution does not close the loop to the required tolerance",
    Reason.NOT_IN_MODULE_IMAGE: "pose not reachable by the parallel module (orientation/axis)",
    Reason.IK_SINGULAR: "inverse kinematics not unique here (a continuum of actuator values)",
    Reason.INSERTION_RANGE: "tool tip not beyond the RCM within the tool length (0 < p < L)",
}


_EXC_FOR_REASON: dict[Reason, type[KinematicsError]] = {
    Reason.NONFINITE_INPUT: InvalidInputError,
    Reason.STROKE_LIMIT: StrokeLimitError,
    Reason.AB_ORDER: OutOfWorkspaceError,
    Reason.LINK_TOO_SHORT: OutOfWorkspaceError,
    Reason.CIRCLES_DISJOINT: OutOfWorkspaceError,
    Reason.CIRCLES_TANGENT: SingularConfigurationError,
    Reason.SERIAL_P_ZERO: DegenerateChainError,
    Reason.UJOINT_SINGULAR: DegenerateChainError,
    Reason.WRIST_SINGULAR: DegenerateChainError,
    Reason.CLOSURE_FAILED: SingularConfigurationError,
    Reason.NOT_IN_MODULE_IMAGE: OutOfWorkspaceError,
    Reason.IK_SINGULAR: SingularConfigurationError,
    Reason.INSERTION_RANGE: OutOfWorkspaceError,
}


def error_for_reason(reason: int, detail: str = "") -> KinematicsError:
    """Build the exception that matches a :class:`Reason` code.

    Parameters
    ----------
    reason : int
        A non-zero :class:`Reason` code.
    detail : str, optional
        Extra text (which item, which values) appended to the description.

    Returns
    -------
    KinematicsError
        An instance of the matching subclass, not raised.
    """
    r = Reason(int(reason))
    cls = _EXC_FOR_REASON.get(r, KinematicsError)
    msg = r.description + (f": {detail}" if detail else "")
    if issubclass(cls, (OutOfWorkspaceError, SingularConfigurationError)):
        return cls(msg, reason=r)
    return cls(msg)
