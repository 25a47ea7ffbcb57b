"""Certified forward kinematics: rigorous enclosures of every solution, in ball arithmetic.

:func:`certified_forward_kinematics` returns, for each of the 16 slots, a box that
provably holds exactly one exact solution, or says that the slot is proven empty, or
that it could not decide; the argument is in ``docs/certified.md``. Needs python-flint
(extra ``[certified]``), imported on first use.
"""

from ._fk import (
    DEFAULT_INPUT_TOL,
    DEFAULT_PREC,
    MAX_CERTIFIED_ITEMS,
    MAX_PREC,
    OUTPUT_ULPS,
    CertifiedFK,
    CertStatus,
    certified_forward_kinematics,
)

__all__ = ["CertStatus", "CertifiedFK", "certified_forward_kinematics", "DEFAULT_INPUT_TOL",
           "DEFAULT_PREC", "MAX_PREC", "OUTPUT_ULPS", "MAX_CERTIFIED_ITEMS"]
