"""The calibration solver's settings (CalibrationOptions) and their defaults."""

from __future__ import annotations

import dataclasses
from typing import ClassVar, Literal

import numpy as np

from .._toml import TomlOptions
from .._validation import (
    check_choice,
    check_count,
    check_scalar,
    check_tolerance,
)
from ..design import LENGTH_RANGE
from ..errors import InvalidInputError
from ._identify import (
    IDENTIFIABILITY_TOL,
)

Loss = Literal["linear", "soft_l1", "huber", "cauchy", "arctan"]


_LOSSES = ("linear", "soft_l1", "huber", "cauchy", "arctan")


#: A row is flagged as an outlier when its residual norm exceeds this many robust standard
#: deviations of one component (for isotropic Gaussian noise ``|r|^2 / sigma^2`` is
#: chi-square with 3 degrees of freedom: ``P(|r| > 4.5 sigma) = 2.6e-4``).
OUTLIER_THRESHOLD = 4.5


#: Weight (m per unit of direction error) of measured instrument axes against tip
#: positions: 0.1 m makes 0.2 mrad of axis error count like 20 um of tip error.
DEFAULT_AXIS_WEIGHT = 0.1


#: Machine epsilon: the least-squares tolerances must exceed it.
_EPS = float(np.finfo(float).eps)


#: Largest share of rows that may be flagged bad and excluded before the data set is refused.
MAX_BAD_FRACTION = 0.1


#: Default ``ftol``, ``xtol`` and ``gtol`` of the least-squares solver.
SOLVER_TOL = 1e-15


#: Default most residual evaluations of one least-squares solve.
MAX_NFEV = 200


#: Floor (m) of the residual standard deviation used to flag outliers: noise-free data
#: leave residuals of rounding size (1e-16 m), which are no outliers.
RESIDUAL_FLOOR = 1e-12


#: RMS distance (m) of the measured tips from the nominal model above which a warning asks
#: to check units, frame and set-up (a calibration corrects millimetres, not decimetres).
UNITS_WARNING = 0.05


#: Margin (m) of the insertion range: a pose needs ``margin < p < L - margin``.
INSERTION_MARGIN = 1e-3


@dataclasses.dataclass(frozen=True)
class CalibrationOptions(TomlOptions):
    """Solver settings of :func:`calibrate` (the data and the model are its arguments).

    Every field is checked here, at construction (a named error); the defaults give
    the results :func:`calibrate` gave before the options object existed. The
    ``[calibration_options]`` table of a TOML file holds them (:meth:`to_toml`,
    :meth:`from_toml`; ``athenakin calibrate --options FILE``).

    Attributes
    ----------
    axis_weight : float
        Metres of residual per unit of axis error (:data:`DEFAULT_AXIS_WEIGHT`), > 0.
    loss : {"linear", "soft_l1", "huber", "cauchy", "arctan"}
        Robust loss of :func:`scipy.optimize.least_squares`. With a robust loss the rows
        flagged as outliers are dropped and the inliers refitted with the linear loss
        (so the covariance is that of least squares on the inliers).
    f_scale : float or None
        Residual (m) at which the robust loss bends, > 0; None: ``2 * sigma`` from a
        first linear fit (median absolute deviation).
    sigma : float or None
        Known standard deviation (m) of one measured coordinate, in ``(0, 10]``; None:
        estimated from the residuals.
    outlier_threshold : float
        Rows with ``|residual| > outlier_threshold * sigma`` are flagged, > 0
        (:data:`OUTLIER_THRESHOLD`).
    bad_rows : {"exclude", "raise"}
        Rows with NaN/inf or outside the nominal workspace: excluded with a
        :class:`CalibrationWarning` (at most ``max_bad_fraction`` of them), or raise.
    max_bad_fraction : float
        Largest share of rows excluded, in ``[0, 1]`` (:data:`MAX_BAD_FRACTION`).
    on_unidentifiable : {"raise", "warn"}
        What to do when the identifiability analysis finds inseparable combinations.
    identifiability_tol : float
        Relative singular value below which a direction is not identifiable, >= 0
        (:data:`~athenakin.calibration.IDENTIFIABILITY_TOL`).
    tol : float
        ``ftol``, ``xtol`` and ``gtol`` of the solver, in ``(eps, 1]`` (machine epsilon).
    max_nfev : int
        Most residual evaluations of one least-squares solve, >= 1.

    Examples
    --------
    >>> from athenakin.calibration import CalibrationOptions
    >>> o = CalibrationOptions(loss="soft_l1", sigma=2e-5)
    >>> print(o.to_toml().splitlines()[0:3])
    ['[calibration_options]', 'axis_weight = 0.1', 'loss = "soft_l1"']
    """

    TOML_TABLE: ClassVar[str] = "calibration_options"   # [calibration]: a result's

    axis_weight: float = DEFAULT_AXIS_WEIGHT
    loss: Loss = "linear"
    f_scale: float | None = None
    sigma: float | None = None
    outlier_threshold: float = OUTLIER_THRESHOLD
    bad_rows: Literal["exclude", "raise"] = "exclude"
    max_bad_fraction: float = MAX_BAD_FRACTION
    on_unidentifiable: Literal["raise", "warn"] = "raise"
    identifiability_tol: float = IDENTIFIABILITY_TOL
    tol: float = SOLVER_TOL
    max_nfev: int = MAX_NFEV

    def __post_init__(self) -> None:
        put = object.__setattr__
        put(self, "axis_weight", check_scalar(self.axis_weight, "axis_weight", positive=True))
        check_choice(self.loss, "loss", _LOSSES)
        for name in ("f_scale", "sigma"):
            v = getattr(self, name)
            if v is not None:
                put(self, name, check_scalar(v, name, positive=True))
        if self.sigma is not None and self.sigma > LENGTH_RANGE[1]:  # squared: no overflow
            raise InvalidInputError(f"sigma: expected a standard deviation (m) of at most "
                                    f"{LENGTH_RANGE[1]:g}, got {self.sigma!r}")
        put(self, "outlier_threshold",
            check_scalar(self.outlier_threshold, "outlier_threshold", positive=True))
        check_choice(self.bad_rows, "bad_rows", ("exclude", "raise"))
        f = check_scalar(self.max_bad_fraction, "max_bad_fraction", nonnegative=True)
        if f > 1.0:
            raise InvalidInputError(f"max_bad_fraction: expected a fraction in [0, 1], got {f:g}")
        put(self, "max_bad_fraction", f)
        check_choice(self.on_unidentifiable, "on_unidentifiable", ("raise", "warn"))
        put(self, "identifiability_tol",
            check_tolerance(self.identifiability_tol, "identifiability_tol"))
        tol = check_tolerance(self.tol, "tol")
        if not _EPS < tol <= 1.0:                # scipy's least_squares needs more than eps
            raise InvalidInputError(f"tol: expected a tolerance in ({_EPS:.3g}, 1], got {tol:g}")
        put(self, "tol", tol)
        put(self, "max_nfev", check_count(self.max_nfev, "max_nfev", minimum=1))
