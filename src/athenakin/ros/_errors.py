"""Errors of the ros subpackage (private)."""

from __future__ import annotations

from ..errors import InvalidInputError

__all__ = ["RecordingError", "ros_extra_missing"]


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
