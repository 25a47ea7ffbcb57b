"""Errors and warnings of the calibration subpackage."""

from __future__ import annotations

from ..errors import InvalidInputError, KinematicsError

__all__ = [
    "CalibrationError",
    "NotIdentifiableError",
    "MeasurementFileError",
    "CalibrationWarning",
]


class CalibrationError(KinematicsError):
    """Base class of the errors raised by :mod:`athenakin.calibration`."""


class NotIdentifiableError(CalibrationError):
    """The chosen parameters cannot be separated by the given poses.

    Attributes
    ----------
    combinations : tuple of str
        The inseparable parameter combinations, written in parameter names
        (e.g. ``"+1 q1_offset +1 q2_offset -1 reg_tx"``).
    singular_values : tuple of float
        Singular values of the column-normalised identification Jacobian.
    """

    def __init__(self, message: str, combinations: tuple[str, ...] = (),
                 singular_values: tuple[float, ...] = ()) -> None:
        super().__init__(message)
        self.combinations = combinations
        self.singular_values = singular_values


class MeasurementFileError(CalibrationError, InvalidInputError):
    """A measurement or plan CSV file is malformed (the message names file, line and column)."""


class CalibrationWarning(UserWarning):
    """Something the user should know: excluded rows, flagged outliers, a weak data set."""
