"""The planner's settings (:class:`PlanOptions`) and the bounds of a plan."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any, ClassVar, Literal

import numpy as np
from numpy.typing import ArrayLike

from .._toml import TomlOptions
from .._validation import check_choice, check_instance, check_scalar
from ..analysis._collision import check_clearance_margin
from ..errors import InvalidInputError
from ._forces import _check_f_max
from ._limits import Limits
from ._safety import Margins

__all__ = ["PlanOptions", "MAX_DURATION", "MAX_SAMPLES", "MIN_RATE"]

#: Default longest trajectory :func:`plan` accepts, s (``max_duration``).
MAX_DURATION = 3600.0
#: Default largest number of samples :func:`plan` accepts (``max_samples``); each
#: sample holds about 60 floats while it is checked, about 1 GB at this bound.
MAX_SAMPLES = 2_000_000
#: Lowest sampling rate :func:`plan` accepts, Hz: a sample period longer than a second
#: is no controller's, and a rate of 1e-300 Hz would make the period infinite.
MIN_RATE = 1.0

Timing = Literal["stretch", "fixed"]

#: A limit as given: one number for the three actuators, or one per actuator.
LimitValue = float | tuple[float, float, float]


@dataclasses.dataclass(frozen=True)
class PlanOptions(TomlOptions):
    """Settings of :func:`~athenakin.motion.plan` and :func:`~athenakin.motion.plan_directions`.

    The path, its requested times and the models (bodies, obstacles, masses) are
    arguments of the functions; these are the settings a user keeps from one path to the
    next. Every field is checked here, at construction (a named error); the defaults give
    the trajectories the planner gave before the options object existed. A ``[plan]``
    table of a TOML file holds them, the margins as ``[plan.margins]`` (:meth:`to_toml`,
    :meth:`from_toml`).

    Attributes
    ----------
    rate : float
        Samples per second (default 1 kHz), at least :data:`MIN_RATE` (1 Hz).
    v_max, a_max : float or tuple of 3 float
        Actuator velocity (m/s) and acceleration (m/s^2) limits, > 0.
    j_max : float or tuple of 3 float or None
        Actuator jerk limit (m/s^3). None: the profile is acceleration-limited (its
        acceleration steps) and :attr:`Trajectory.qddd` is None.
    tip_speed : float or None
        Tool-tip speed limit (m/s).
    timing : {"stretch", "fixed"}
        What to do when the requested ``times`` ask for more than the limits allow:
        ``"stretch"`` lengthens those segments (:attr:`Trajectory.stretched`);
        ``"fixed"`` keeps the times and raises :class:`TimingInfeasibleError` at the
        first sample that breaks a limit (it needs ``times``).
    margins : Margins
        Least distances to the singularities (default :class:`Margins`).
    max_duration : float
        Longest trajectory accepted, s, > 0 (:data:`MAX_DURATION`).
    max_samples : int
        Largest number of samples accepted, >= 2 (:data:`MAX_SAMPLES`); bounds the
        memory and time of the planning.
    clearance_margin : float or None
        Least clearance of every sample, m, in ``[0, 1]`` (turns the collision check
        on); None: 5 mm when ``bodies`` or ``environment`` turn it on.
    f_max : float or tuple of 3 float or None
        Actuator force limits, N (needs ``masses``): the trajectory is slowed down
        uniformly until ``|forces| <= f_max`` (:mod:`athenakin.motion._forces`).
    backend : {"auto", "numpy", "numba"}
        The Jacobians, the clearance check and the forces on the compiled kernels or the
        numpy reference (:mod:`athenakin._backend`; default ``"auto"``).

    Examples
    --------
    >>> from athenakin.motion import Margins, PlanOptions
    >>> o = PlanOptions(rate=500.0, j_max=5.0, margins=Margins(h=0.01))
    >>> PlanOptions.from_mapping(o.to_mapping()) == o
    True
    """

    TOML_TABLE: ClassVar[str] = "plan"

    rate: float = 1000.0
    v_max: LimitValue = 0.05
    a_max: LimitValue = 0.5
    j_max: LimitValue | None = None
    tip_speed: float | None = None
    timing: Timing = "stretch"
    margins: Margins = dataclasses.field(default_factory=Margins)
    max_duration: float = MAX_DURATION
    max_samples: int = MAX_SAMPLES
    clearance_margin: float | None = None
    f_max: LimitValue | None = None
    backend: str = "auto"

    def __post_init__(self) -> None:
        put = object.__setattr__
        rate, max_duration, max_samples = check_budget(self.rate, self.max_duration,
                                                       self.max_samples)
        put(self, "rate", rate)
        lim = Limits.build(self.v_max, self.a_max, self.j_max, self.tip_speed)
        for name in ("v_max", "a_max", "j_max"):
            put(self, name, _as_given(getattr(self, name), getattr(lim, name)))
        put(self, "tip_speed", lim.tip_speed)
        check_choice(self.timing, "timing", ("stretch", "fixed"))
        check_choice(self.backend, "backend", ("auto", "numpy", "numba"))
        if not isinstance(self.margins, Margins):
            raise TypeError(f"margins: expected athenakin.motion.Margins, got "
                            f"{type(self.margins).__name__}")
        put(self, "max_duration", max_duration)
        put(self, "max_samples", max_samples)
        if self.clearance_margin is not None:
            put(self, "clearance_margin", check_clearance_margin(self.clearance_margin))
        if self.f_max is not None:
            put(self, "f_max", _as_given(self.f_max, _check_f_max(self.f_max)))

    def to_mapping(self) -> dict[str, Any]:
        """A TOML table; the margins as a ``margins`` sub-table.

        Returns
        -------
        dict of str -> TOML value
            The fields that are not None; ``margins`` as a table of :class:`Margins`' fields.
        """
        out = super().to_mapping()
        out["margins"] = dataclasses.asdict(self.margins)
        return out

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any]) -> PlanOptions:
        """Read a ``plan`` table (:meth:`to_mapping`); unknown keys are refused by name.

        Parameters
        ----------
        data : mapping
            Field names to values; ``margins`` a table of :class:`Margins`' fields.

        Returns
        -------
        PlanOptions

        Raises
        ------
        InvalidInputError
            An unknown key (of the table or of ``margins``) or a bad value (named).
        """
        if isinstance(data, Mapping) and isinstance(data.get("margins"), Mapping):
            table = data["margins"]
            names = [f.name for f in dataclasses.fields(Margins)]
            unknown = sorted(set(table) - set(names))
            if unknown:
                raise InvalidInputError(f"{cls.TOML_TABLE}.margins: unknown key(s) {unknown}; "
                                        f"expected some of {names}")
            data = dict(data, margins=Margins(**table))
        return super().from_mapping(data)


def plan_options(options: object) -> PlanOptions:
    """``options`` of :func:`plan` checked (None: the defaults)."""
    if options is None:
        return PlanOptions()
    check_instance(options, "options", PlanOptions)
    return options  # type: ignore[return-value]


def check_budget(rate: object, max_duration: object, max_samples: object
                 ) -> tuple[float, float, int]:
    """The checked sample rate (Hz), longest duration (s) and most samples of a plan."""
    rate = check_scalar(rate, "rate", positive=True)
    if not rate >= MIN_RATE:
        raise ValueError(f"rate: expected at least {MIN_RATE:g} sample per second (Hz), "
                         f"got {rate:g}")
    max_duration = MAX_DURATION if max_duration is None else check_scalar(
        max_duration, "max_duration", positive=True)
    if max_samples is None:
        max_samples = MAX_SAMPLES
    elif (isinstance(max_samples, bool) or not isinstance(max_samples, (int, np.integer))
          or max_samples < 2):
        raise ValueError(f"max_samples: expected an integer >= 2, got {max_samples!r}")
    return rate, max_duration, int(max_samples)


def _as_given(value: ArrayLike | None, checked: ArrayLike | None) -> LimitValue | None:
    """A checked limit as a TOML value: one float when one was given, else 3."""
    if value is None or checked is None:
        return None
    a = np.asarray(checked, dtype=float)
    if np.ndim(value) == 0:
        return float(a.flat[0])
    return (float(a[0]), float(a[1]), float(a[2]))
