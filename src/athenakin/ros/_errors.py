"""Errors of the ros subpackage (private)."""

from __future__ import annotations

import importlib

from ..errors import InvalidInputError, KinematicsError

__all__ = ["RecordingError", "RecordingWarning", "ServeError", "ros_extra_missing", "require_ros"]


class RecordingError(InvalidInputError):
    """A recording cannot be used (the message, one line, names the file and the fault).

    Not a bag or MCAP file, truncated or corrupt, no such
    topic, absent joint names, a message type other than ``sensor_msgs/JointState``,
    stamps that go backwards. The message (one line) names the file and what was found.
    """


def ros_extra_missing(exc: ModuleNotFoundError) -> ModuleNotFoundError:
    """The error to raise when a package of the ``ros`` extra is not installed."""
    name = (exc.name or "").split(".")[0] or None
    return ModuleNotFoundError(f"athenakin.ros needs the package {name!r}: install the "
                               f"extra with  pip install 'athenakin[ros]'", name=name)


class RecordingWarning(UserWarning):
    """A recording was read only in part (a truncated MCAP file: what was lost is said)."""


class ServeError(KinematicsError, OSError):
    """The live stream cannot be served (a port in use, an address not of this machine).

    An ``OSError`` too (``errno`` kept); the message names the address and what to do.
    """


#: Modules of the ``ros`` extra that reading recordings and writing MCAP need.
READ_MODULES = ("rosbags", "mcap", "zstandard", "lz4")
WRITE_MODULES = ("rosbags", "zstandard")


def require_ros(modules: tuple[str, ...]) -> None:
    """Import ``modules`` now, so that a missing extra is named before any work.

    Raises
    ------
    ModuleNotFoundError
        :func:`ros_extra_missing` of the first one missing.
    """
    for m in modules:
        try:
            importlib.import_module(m)
        except ModuleNotFoundError as exc:
            raise ros_extra_missing(exc) from None
