"""Errors of the synthesis subpackage: bad task files, unreachable schedulers, study mismatches."""

from __future__ import annotations

from ..errors import InvalidInputError, KinematicsError

__all__ = ["SynthesisError", "TaskFileError", "SchedulerUnreachableError", "StudyMismatchError"]


class SynthesisError(KinematicsError):
    """Base class of the errors raised by :mod:`athenakin.synthesis`."""


class TaskFileError(SynthesisError, InvalidInputError):
    """A task file cannot be read: not TOML, a missing or unknown key, a bad value."""


class SchedulerUnreachableError(SynthesisError, ConnectionError):
    """No Dask scheduler answers at the given address within the connect timeout."""


class StudyMismatchError(SynthesisError, InvalidInputError):
    """An output folder holds chunks of a different study (designs, task, samples or seed)."""
