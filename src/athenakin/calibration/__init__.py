"""Calibration of a real ATHENA: identify its geometry from measurements, state its accuracy.

* :mod:`._model` - measurement model (tool tip, instrument axis; base or tracker frame)
  with its analytic identification Jacobian;
* :mod:`._identify` - identifiability (singular values, inseparable combinations) and
  D-optimal experiment design;
* :mod:`._solve` - :func:`calibrate` (scipy's trust-region least squares), its solver
  settings (:class:`CalibrationOptions`) and its result;
* :mod:`._accuracy` - tool-tip error from parameter covariance and encoder resolution;
* :mod:`._synthetic` - synthetic data with a documented noise model
  (:class:`SyntheticOptions`);
* :mod:`._io` - measurement / plan CSV files, calibrated TOML, report.

Needs scipy (extra ``[calibration]``). See docs/calibration.md.
"""

from ._accuracy import (
    TipError,
    TipErrorMap,
    tip_error,
    tip_error_map,
    tip_error_monte_carlo,
)
from ._errors import (
    CalibrationError,
    CalibrationWarning,
    MeasurementFileError,
    NotIdentifiableError,
)
from ._identify import (
    IDENTIFIABILITY_TOL,
    WEAK_IDENTIFIABILITY_TOL,
    IdentifiabilityReport,
    analyse_jacobian,
)
from ._io import (
    AXIS_COLUMNS,
    Q_COLUMNS,
    TIP_COLUMNS,
    Measurements,
    calibration_toml,
    measurements_csv_text,
    plan_csv_text,
    read_measurements_csv,
)
from ._measurements import MeasurementCheck, check_measurements
from ._model import (
    DEFAULT_PARAMETERS,
    PARAMETER_GROUPS,
    PARAMETER_UNITS,
    PARAMETERS,
    resolve_parameters,
)
from ._options import DEFAULT_AXIS_WEIGHT, OUTLIER_THRESHOLD, CalibrationOptions
from ._plan import PosePlan, plan_poses
from ._report import (
    plot_parameter_confidence,
    plot_residuals,
    plot_tip_error_map,
    write_report,
)
from ._solve import CalibrationResult, calibrate, identifiability
from ._synthetic import SyntheticData, SyntheticOptions, random_poses, synthetic_measurements

__all__ = [
    "TipError",
    "TipErrorMap",
    "tip_error",
    "tip_error_map",
    "tip_error_monte_carlo",
    "AXIS_COLUMNS",
    "Q_COLUMNS",
    "TIP_COLUMNS",
    "Measurements",
    "calibration_toml",
    "measurements_csv_text",
    "plan_csv_text",
    "read_measurements_csv",
    "plot_parameter_confidence",
    "plot_residuals",
    "plot_tip_error_map",
    "write_report",
    "PosePlan",
    "plan_poses",
    "CalibrationError",
    "CalibrationWarning",
    "MeasurementFileError",
    "NotIdentifiableError",
    "IDENTIFIABILITY_TOL",
    "WEAK_IDENTIFIABILITY_TOL",
    "IdentifiabilityReport",
    "analyse_jacobian",
    "DEFAULT_PARAMETERS",
    "PARAMETER_GROUPS",
    "PARAMETER_UNITS",
    "PARAMETERS",
    "resolve_parameters",
    "DEFAULT_AXIS_WEIGHT",
    "OUTLIER_THRESHOLD",
    "CalibrationOptions",
    "CalibrationResult",
    "MeasurementCheck",
    "calibrate",
    "check_measurements",
    "identifiability",
    "SyntheticData",
    "SyntheticOptions",
    "random_poses",
    "synthetic_measurements",
]
