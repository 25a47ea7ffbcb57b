"""Options of the teleoperation core, and its status flags (private)."""

from __future__ import annotations

import dataclasses
import enum
import math
from typing import Any

import numpy as np

from .._validation import check_array, check_choice, check_scalar
from ..errors import InvalidInputError
from ._filter import TREMOR_FILTERS

__all__ = ["TeleopOptions", "TeleopStatus", "ROTATION_TOL"]

#: Largest ``|R^T R - I|`` of a registration rotation.
ROTATION_TOL = 1e-9


class TeleopStatus(enum.IntFlag):
    """What the safety layer did in one cycle (bits; ``NONE``: the tip follows the master).

    The first ten are the issue's events, in the order the layer applies them.

    Attributes
    ----------
    CLUTCHED
        The clutch is open (``clutch=False``): the master moves freely, the tip holds.
    STROKE
        The step toward the target would leave the stroke limits less their margin
        (``stroke_margin``), or the IK has no solution there: limited or held.
    DEPTH
        The target's insertion depth ``|tip_e|`` was outside ``depth``: moved onto the
        nearest allowed depth along its direction.
    SINGULAR
        The step would come closer to the singular set than ``margins``, or leave the
        tracked forward-kinematics branch: limited or held.
    FIXTURE
        The target was within ``fixture_margin`` of a forbidden region (an obstacle of
        ``environment``): pushed out along the region's normal, or held.
    CLEARANCE
        The step would bring two bodies, or a body and an obstacle, closer than
        ``clearance_margin + clearance_buffer``: limited or held.
    VELOCITY
        The step was shortened (along the tip's direction) to keep every ``|qd_i| <= v_max_i``.
    ACCELERATION
        The step was shortened to keep ``|qdd_i| <= a_max_i``, or no step along the tip's
        direction could: the robot brakes along its velocity at ``a_max``.
    WATCHDOG
        No new valid master sample for ``watchdog`` s, counted in cycles
        (:attr:`Teleop.watchdog_cycles` = ``ceil(watchdog * rate)`` consecutive cycles,
        whatever ``t`` says; a sample stamped no later than the previous sample is no new
        sample): the robot holds (brakes to rest) until the master returns; it re-engages
        like a clutch (no tip jump).
    ESTOP
        The e-stop is latched (:meth:`Teleop.estop`): the robot brakes to rest and holds
        until :meth:`Teleop.release`.
    INVALID
        The master sample was not three finite real numbers (strings and bytes are not),
        the clutch not a boolean, or ``t`` not finite or before the previous cycle's: the
        sample is ignored (no sample this cycle; a malformed clutch is open).
    JUMP
        The master moved more than ``max_master_jump`` since its previous sample: the
        sample re-engages the clutch (the tip does not follow the jump).
    HOLD
        The command is braking or held (no step toward the target this cycle).
    FAULT
        An unexpected internal error: the robot holds; :attr:`Teleop.fault` keeps it.
    """

    NONE = 0
    CLUTCHED = 1
    STROKE = 2
    DEPTH = 4
    SINGULAR = 8
    FIXTURE = 16
    CLEARANCE = 32
    VELOCITY = 64
    ACCELERATION = 128
    WATCHDOG = 256
    ESTOP = 512
    INVALID = 1024
    JUMP = 2048
    HOLD = 4096
    FAULT = 8192


def _three(x: Any, name: str, *, positive: bool = True) -> tuple[float, float, float]:
    """A scalar or three values, each finite (and positive)."""
    a = check_array(x, name, ())        # named errors for strings, ragged, complex, huge
    if a.shape not in ((), (3,)):
        raise InvalidInputError(f"{name}: expected a number or 3 numbers, got shape {a.shape}")
    a = np.broadcast_to(a, (3,))
    return tuple(check_scalar(float(v), name, positive=positive) for v in a)  # type: ignore[return-value]


@dataclasses.dataclass(frozen=True, kw_only=True)
class TeleopOptions:
    """Settings of :class:`~athenakin.teleop.Teleop` beyond its keyword arguments.

    Parameters
    ----------
    registration : array-like, shape (3, 3)
        Rotation ``R_e_m`` that maps the master's frame to the RCM frame E
        (``tip_e = offset + scale * R_e_m @ p_m``). Default the identity.
    filter : str
        Tremor filter, a key of :data:`~athenakin.teleop.TREMOR_FILTERS`:
        ``"notch8-12"`` (default), ``"notch8-12-lp15"`` (the same band, and a roll-off
        above 15 Hz) or ``"none"``.
    watchdog : float
        Seconds without a new valid master sample after which the robot holds (0.03),
        counted in cycles of ``1 / rate`` (``WATCHDOG``).
    max_master_jump : float
        Master displacement between consecutive samples (master frame, m) above which
        the sample re-engages the clutch instead of moving the tip (0.02).
    stroke_margin : float
        Distance kept from the stroke limits, m (0.005; at least the stopping distance
        ``max v_max^2 / (2 a_max)``).
    depth : tuple of 2 float, optional
        Insertion depth range ``(min, max)`` of the tip beyond the RCM, ``|tip_e|``, m.
        Default ``(0.01, tool_length - 0.03)``.
    margins : athenakin.motion.Margins, optional
        Distances kept from the singular set (``half_chord``, ``h``, ``link``,
        ``sin_u2``, ``sin_u4``, ``p``); default :class:`~athenakin.motion.Margins`.
    fixture_margin : float
        Distance kept between the tip and every forbidden region, m (0.003).
    clearance_margin : float
        Least clearance between bodies, and from the obstacles, m (0.005); checked when
        ``bodies`` or ``environment`` is given.
    check_clearance : bool, optional
        Check the bodies' clearance every cycle (``bodies`` and the obstacles: tens of
        microseconds for the bodies alone, 0.5-1 ms with obstacles). Default: when
        ``bodies`` or ``environment`` is given. False keeps the tip fixtures only.
    clearance_buffer : float
        Extra distance the guard keeps above ``clearance_margin`` (0.003 m), plus four
        times the current stopping distance, so that a braking robot never crosses
        ``clearance_margin``.
    masses : athenakin.dynamics.MassModel, optional
        Masses for the feed-forward forces; default ``MassModel.reference(design)``.
    gravity : array-like, shape (3,), optional
        Gravity in the base frame, m/s^2; default :data:`athenakin.dynamics.STANDARD_GRAVITY`.
    feedforward : bool
        Compute the actuator forces every cycle (default True; False leaves
        ``forces`` NaN and saves the inverse dynamics' cost).
    backend : {"auto", "numpy", "numba"}
        IK and dynamics: compiled where numba imports (``"auto"``) or the numpy reference.
    """

    registration: Any = None
    filter: str = "notch8-12"
    watchdog: float = 0.03
    max_master_jump: float = 0.02
    stroke_margin: float = 0.005
    depth: tuple[float, float] | None = None
    margins: Any = None
    fixture_margin: float = 0.003
    clearance_margin: float = 0.005
    clearance_buffer: float = 0.003
    check_clearance: bool | None = None
    masses: Any = None
    gravity: Any = None
    feedforward: bool = True
    backend: str = "auto"

    def __post_init__(self) -> None:
        R = np.eye(3) if self.registration is None else check_array(self.registration,
                                                                      "registration", (3, 3))
        if R.shape != (3, 3) or not np.all(np.isfinite(R)):
            raise InvalidInputError(f"registration: expected a finite rotation of shape (3, 3), "
                                    f"got shape {R.shape}")
        if (np.abs(R.T @ R - np.eye(3)).max() > ROTATION_TOL
                or not np.linalg.det(R) > 0):
            raise InvalidInputError("registration: expected a rotation matrix (R^T R = I, "
                                    "det R = +1)")
        R = R.copy()
        R.setflags(write=False)
        object.__setattr__(self, "registration", R)
        check_choice(self.filter, "filter", tuple(TREMOR_FILTERS))
        for name in ("watchdog", "max_master_jump"):
            check_scalar(getattr(self, name), name, positive=True)
        for name in ("stroke_margin", "fixture_margin", "clearance_margin", "clearance_buffer"):
            check_scalar(getattr(self, name), name, nonnegative=True)
        if self.depth is not None:
            d = check_array(self.depth, "depth", (2,))
            if d.shape != (2,):
                raise InvalidInputError(f"depth: expected (min, max) in m, got shape {d.shape}")
            lo, hi = (check_scalar(float(v), "depth", positive=True) for v in d)
            if not lo < hi:
                raise InvalidInputError(f"depth: expected (min, max) with min < max, got "
                                        f"{self.depth!r}")
            object.__setattr__(self, "depth", (lo, hi))
        if self.margins is not None:
            from ..motion import Margins

            if not isinstance(self.margins, Margins):
                raise TypeError(f"margins: expected athenakin.motion.Margins, got "
                                f"{type(self.margins).__name__}")
        if self.gravity is not None:
            object.__setattr__(self, "gravity", _three(self.gravity, "gravity", positive=False))
        if self.check_clearance is not None and not isinstance(self.check_clearance, bool):
            raise TypeError(f"check_clearance: expected a bool or None, got "
                            f"{type(self.check_clearance).__name__}")
        if not isinstance(self.feedforward, bool):
            raise TypeError(f"feedforward: expected a bool, got {type(self.feedforward).__name__}")
        check_choice(self.backend, "backend", ("auto", "numpy", "numba"))

    def stopping_distance(self, v_max: tuple[float, ...], a_max: tuple[float, ...]) -> float:
        """Largest joint travel while braking from ``v_max`` at ``a_max``, m.

        Parameters
        ----------
        v_max : tuple of float
            Joint speed bounds, m/s, one per actuator.
        a_max : tuple of float
            Joint acceleration bounds, m/s^2, one per actuator (same length).

        Returns
        -------
        float
            The travel, m (``inf`` where an acceleration bound is 0).
        """
        t = max(v / a for v, a in zip(v_max, a_max, strict=True))   # joints stop together
        return max(0.5 * v * t for v in v_max) if math.isfinite(t) else math.inf


# the status bits as plain ints (the loop combines them; IntFlag arithmetic is slow)
_CLUTCHED = int(TeleopStatus.CLUTCHED)
_STROKE = int(TeleopStatus.STROKE)
_DEPTH = int(TeleopStatus.DEPTH)
_SINGULAR = int(TeleopStatus.SINGULAR)
_FIXTURE = int(TeleopStatus.FIXTURE)
_CLEARANCE = int(TeleopStatus.CLEARANCE)
_VELOCITY = int(TeleopStatus.VELOCITY)
_ACCELERATION = int(TeleopStatus.ACCELERATION)
_WATCHDOG = int(TeleopStatus.WATCHDOG)
_ESTOP = int(TeleopStatus.ESTOP)
_INVALID = int(TeleopStatus.INVALID)
_JUMP = int(TeleopStatus.JUMP)
_HOLD = int(TeleopStatus.HOLD)
_FAULT = int(TeleopStatus.FAULT)
#: The bits that say why a step toward the target was shortened or refused.
_LIMIT_BITS = _STROKE | _SINGULAR | _FIXTURE | _CLEARANCE | _VELOCITY | _ACCELERATION
