"""Calibration: checked measurements -> identifiability -> nonlinear least squares -> result."""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Iterable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import BoolArray, FloatArray, IntArray
from .._validation import (
    check_array,
    check_choice,
    check_frame,
    check_instance,
    check_scalar,
    check_transform,
)
from ..design import Design, resolve_design
from ..errors import InvalidInputError
from ._errors import CalibrationError, CalibrationWarning, NotIdentifiableError
from ._identify import (
    IDENTIFIABILITY_TOL,
    IdentifiabilityReport,
    analyse_jacobian,
    raise_if_not_identifiable,
)
from ._measurements import MeasurementCheck, _mode_array, _rows, check_measurements
from ._model import (
    PARAMETERS,
    MeasurementFrame,
    Prediction,
    calibrated_name,
    design_from_parameters,
    parameter_vector,
    predict,
    resolve_parameters,
    rotation_from_vector,
)
from ._options import (
    DEFAULT_AXIS_WEIGHT,
    OUTLIER_THRESHOLD,
    RESIDUAL_FLOOR,
    UNITS_WARNING,
    CalibrationOptions,
    Loss,
)

__all__ = [
    "CalibrationOptions",
    "CalibrationResult",
    "Loss",
    "OUTLIER_THRESHOLD",
    "DEFAULT_AXIS_WEIGHT",
    "calibrate",
    "identifiability",
    "check_measurements",
    "MeasurementCheck",
]


_REG = PARAMETERS.index("reg_rx")


@dataclasses.dataclass(frozen=True)
class CalibrationResult:
    """A calibrated ATHENA and how well it is known.

    Attributes
    ----------
    design : Design
        The calibrated design (``l1..l5``, ``tool_length`` estimated or kept; strokes,
        A/B order and name from the nominal design).
    names : tuple of str
        The estimated parameters, in :data:`~athenakin.calibration.PARAMETERS` order.
    estimates, nominal : ndarray, shape (n,)
        Estimated and starting values of ``names`` (m, rad).
    std : ndarray, shape (n,)
        Standard deviations of the estimates (m, rad).
    covariance : ndarray, shape (n, n)
        ``sigma^2 (J^T J)^-1`` at the solution (``sigma`` below).
    parameters : dict of str -> float
        Every parameter of :data:`~athenakin.calibration.PARAMETERS`, estimated or fixed
        (``reg_r*`` relative to a first rigid fit of the nominal tips: use :attr:`T_t_b`).
    q_offset : ndarray, shape (3,)
        Actuator zero offsets: ``q_true = q_reading + q_offset``, m.
    rcm : ndarray, shape (3,)
        RCM point in the base frame (estimated or given), m.
    T_b_e : ndarray, shape (4, 4)
        The RCM frame with its origin at :attr:`rcm` (rotation as given).
    T_t_b : ndarray, shape (4, 4) or None
        Tracker registration (pose of the base in the tracker frame) for ``frame="tracker"``.
    frame : {"base", "tracker"}
        Frame of the measured tips.
    mode : ndarray of int, shape (N,)
        Assembly mode followed for each row.
    residuals_before, residuals_after : ndarray, shape (N, 3) or (N, 6)
        Measured minus predicted (tips, m; then weighted axis errors) with the nominal and
        with the calibrated parameters (NaN for excluded rows).
    rms_before, rms_after : float
        RMS tip error (norm per row, m) over the rows used.
    sigma : float
        Standard deviation of one residual component, from the residuals after
        (``sqrt(SSR / (m - n))``) or the ``sigma`` given.
    outliers : ndarray of bool, shape (N,)
        Rows whose residual exceeds ``outlier_threshold * sigma``; with a robust loss
        they are left out of the final fit and of the covariance.
    excluded : ndarray of bool, shape (N,)
        Rows refused before fitting (:attr:`check` says why).
    check : MeasurementCheck
    identifiability : IdentifiabilityReport
        At the nominal parameters, before solving.
    success : bool
    message : str
    nfev : int
        Model evaluations of the solver.
    """

    design: Design
    names: tuple[str, ...]
    estimates: FloatArray
    nominal: FloatArray
    std: FloatArray
    covariance: FloatArray
    parameters: dict[str, float]
    q_offset: FloatArray
    rcm: FloatArray
    T_b_e: FloatArray
    T_t_b: FloatArray | None
    frame: str
    mode: IntArray
    residuals_before: FloatArray
    residuals_after: FloatArray
    rms_before: float
    rms_after: float
    sigma: float
    outliers: BoolArray
    excluded: BoolArray
    check: MeasurementCheck
    identifiability: IdentifiabilityReport
    success: bool
    message: str
    nfev: int

    @property
    def correlation(self) -> FloatArray:
        """Correlation matrix of the estimates, shape (n, n)."""
        s = np.where(self.std > 0, self.std, 1.0)
        return self.covariance / np.outer(s, s)

    def table(self) -> list[tuple[str, float, float, float]]:
        """Rows ``(name, nominal, estimate, std)`` of the estimated parameters.

        Returns
        -------
        list of (str, float, float, float)
            One row per parameter of :attr:`names`, in the units of each parameter (m for
            lengths and offsets, rad for angles; docs/calibration.md).
        """
        return [(n, float(a), float(b), float(c))
                for n, a, b, c in zip(self.names, self.nominal, self.estimates, self.std,
                                      strict=True)]


# --------------------------------------------------------------------------------------
# the problem
# --------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class _Problem:
    q: FloatArray
    tips: FloatArray
    axes: FloatArray | None
    mode: FloatArray
    R0: FloatArray | None
    theta0: FloatArray
    free: IntArray
    axis_weight: float

    @property
    def rows_per(self) -> int:
        """Residual components per pose: the tip (3), and the weighted axis error (6)."""
        return 3 if self.axes is None else 6

    def full(self, x: FloatArray) -> FloatArray:
        th = self.theta0.copy()
        th[self.free] = x
        return th

    def evaluate(self, theta: FloatArray, jacobian: bool
                 ) -> tuple[Prediction, FloatArray]:
        pr = predict(theta, self.q, self.mode, R0=self.R0, jacobian=jacobian)
        r = pr.tip - self.tips
        if self.axes is not None:
            r = np.concatenate([r, self.axis_weight * (pr.axis - self.axes)], axis=1)
        return pr, r

    def residual(self, x: FloatArray) -> FloatArray:
        return self.evaluate(self.full(x), False)[1].ravel()

    def jacobian(self, x: FloatArray) -> FloatArray:
        return self.jac_full(self.full(x))[:, self.free]

    def jac_full(self, theta: FloatArray) -> FloatArray:
        pr = predict(theta, self.q, self.mode, R0=self.R0, jacobian=True)
        assert pr.J_tip is not None and pr.J_axis is not None
        J = pr.J_tip
        if self.axes is not None:
            J = np.concatenate([J, self.axis_weight * pr.J_axis], axis=1)
        return J.reshape(-1, J.shape[-1])


def _kabsch(p: FloatArray, m: FloatArray
            ) -> tuple[FloatArray, FloatArray]:
    """Rotation R and translation t minimising ``sum |R p + t - m|^2`` (Kabsch / Horn)."""
    pc, mc = p.mean(axis=0), m.mean(axis=0)
    U, _, Vt = np.linalg.svd((p - pc).T @ (m - mc))
    S = np.diag([1.0, 1.0, float(np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0)])
    R = Vt.T @ S @ U.T
    return R, mc - R @ pc


def _setup(q: ArrayLike, tips: ArrayLike, T_b_e: ArrayLike, design: Design | None, *,
           params: Iterable[str] | str | None, frame: str, axes: ArrayLike | None,
           mode: object, q_offset: ArrayLike | None, registration: ArrayLike | None,
           axis_weight: float, bad_rows: str, max_bad_fraction: float
           ) -> tuple[Design, _Problem, tuple[str, ...], MeasurementCheck,
                      FloatArray, FloatArray]:
    """Validate, drop bad rows, build the problem (shared by calibrate and identifiability)."""
    design = resolve_design(design)
    names = resolve_parameters(params, frame)
    qa = _rows(q, "q")
    n = qa.shape[0]
    ta = _rows(tips, "tips", n)
    aa = None if axes is None else _rows(axes, "axes", n)
    T = check_frame(T_b_e, "T_b_e")
    if bad_rows not in ("exclude", "raise"):
        raise ValueError(f"bad_rows: expected 'exclude' or 'raise', got {bad_rows!r}")
    axis_weight = check_scalar(axis_weight, "axis_weight", positive=True)
    off = np.zeros(3) if q_offset is None else check_array(q_offset, "q_offset", (3,))
    if isinstance(mode, str):
        if mode != "auto":
            raise InvalidInputError(f"mode: expected +1, -1, an array of them or 'auto', "
                                    f"got {mode!r}")
        if frame != "base":
            raise InvalidInputError("mode='auto' needs tips in the base frame (frame='base')")
        m = _nearest_mode(qa, ta, design, T, off)
    else:
        m = _mode_array(mode, n)
    chk = check_measurements(qa, T, design, mode=m, tips=ta, axes=aa, q_offset=off)
    nbad = int(np.sum(~chk.usable))
    if nbad:
        if bad_rows == "raise":
            raise InvalidInputError(f"{nbad} of {n} rows cannot be used: {chk.describe()}")
        if nbad > max_bad_fraction * n:
            raise InvalidInputError(
                f"{nbad} of {n} rows cannot be used (more than {max_bad_fraction:.0%}): "
                f"{chk.describe()}; check the columns, units (m) and the nominal design")
        warnings.warn(f"calibration: {nbad} of {n} rows excluded: {chk.describe()}",
                      CalibrationWarning, stacklevel=3)
    use = chk.usable
    theta0 = parameter_vector(design, T[:3, 3], q_offset=off)
    R0 = None
    if frame == "tracker":
        pr = predict(theta0, qa[use], m[use])
        if registration is None:
            if int(np.sum(use)) < 3:
                raise NotIdentifiableError("too few poses to register the tracker (need 3)")
            R0, t0 = _kabsch(pr.tip_base, ta[use])
        else:
            Treg = check_transform(registration, "registration")
            R0, t0 = Treg[:3, :3], Treg[:3, 3]
        theta0[_REG + 3:_REG + 6] = t0
    free = np.array([PARAMETERS.index(nm) for nm in names], dtype=np.int64)
    prob = _Problem(q=qa[use], tips=ta[use], axes=None if aa is None else aa[use], mode=m[use],
                    R0=R0, theta0=theta0, free=free, axis_weight=float(axis_weight))
    return design, prob, names, chk, m, T


def _nearest_mode(q: FloatArray, tips: FloatArray, design: Design,
                  T: FloatArray, off: FloatArray) -> FloatArray:
    """Per row, the assembly mode whose nominal tip is nearer the measured one (+1 on ties)."""
    theta = parameter_vector(design, T[:3, 3], q_offset=off)
    qs = np.nan_to_num(q)
    with np.errstate(invalid="ignore"):
        dist = [np.linalg.norm(predict(theta, qs, np.full(len(q), s)).tip_base - tips, axis=1)
                for s in (1.0, -1.0)]
    d_plus, d_minus = (np.where(np.isfinite(x), x, np.inf) for x in dist)
    return np.where(d_minus < d_plus, -1.0, 1.0)


def identifiability(q: ArrayLike, T_b_e: ArrayLike, design: Design | None = None, *,
                    params: Iterable[str] | str | None = None,
                    frame: MeasurementFrame = "base", axes: bool = False, mode: object = 1,
                    q_offset: ArrayLike | None = None, axis_weight: float = DEFAULT_AXIS_WEIGHT,
                    tol: float = IDENTIFIABILITY_TOL) -> IdentifiabilityReport:
    """Whether these poses can identify these parameters (before measuring anything).

    The identification Jacobian is evaluated at the nominal parameters (the tracker
    registration at identity: it does not change the analysis).

    Parameters
    ----------
    q : array-like, shape (N, 3)
        Actuator readings of the poses, m.
    T_b_e : array-like, shape (4, 4)
        Nominal RCM frame.
    design : Design, optional
    params : iterable of str, keyword-only
        Parameters to estimate (:data:`~athenakin.calibration.PARAMETERS` or groups);
        default ``l1..l5, tool_length`` (plus the registration for ``frame="tracker"``).
    frame : {"base", "tracker"}, keyword-only
    axes : bool, keyword-only
        Whether instrument axes are measured too.
    mode, q_offset
        As in :func:`calibrate`.
    axis_weight : float, keyword-only
        As in :class:`CalibrationOptions`.
    tol : float, keyword-only

    Returns
    -------
    IdentifiabilityReport

    Raises
    ------
    InvalidInputError
        Bad shapes, or rows the nominal design cannot reach (not excluded here).
    """
    check_choice(frame, "frame", ("base", "tracker"))
    qa = _rows(q, "q")
    design = resolve_design(design)
    T = check_frame(T_b_e, "T_b_e")
    tips = predict(parameter_vector(design, T[:3, 3]), np.nan_to_num(qa),
                   _mode_array(mode, qa.shape[0]))
    _, prob, names, _, _, _ = _setup(
        qa, tips.tip_base, T, design, params=params, frame=frame,
        axes=tips.axis if axes else None, mode=mode, q_offset=q_offset,
        registration=np.eye(4) if frame == "tracker" else None, axis_weight=axis_weight,
        bad_rows="raise", max_bad_fraction=0.0)
    return analyse_jacobian(prob.jac_full(prob.theta0)[:, prob.free], names, tol=tol)


def calibrate(q: ArrayLike, tips: ArrayLike, T_b_e: ArrayLike, design: Design | None = None, *,
              params: Iterable[str] | str | None = None, frame: MeasurementFrame = "base",
              axes: ArrayLike | None = None, mode: object = 1, q_offset: ArrayLike | None = None,
              registration: ArrayLike | None = None,
              options: CalibrationOptions | None = None) -> CalibrationResult:
    """Identify the geometry of a real ATHENA from measured tool tips.

    Minimises ``sum_i rho(|tip_model(q_i; theta) - tip_i|^2)`` over the estimated
    parameters with :func:`scipy.optimize.least_squares` (trust region reflective,
    analytic Jacobian, parameters scaled by their Jacobian column norms). The assembly
    mode of every row is the one given (default +1, the working mode) and is kept while
    the parameters change: the model follows the FK slot of the nominal pose.

    Parameters
    ----------
    q : array-like, shape (N, 3)
        Actuator readings ``(q1, q2, q3)``, m; the true values are ``q + q_offset``.
    tips : array-like, shape (N, 3)
        Measured tool tips, m: in the base frame (``frame="base"``) or in the tracker's
        own frame (``frame="tracker"``, registration estimated).
    T_b_e : array-like, shape (4, 4)
        Nominal RCM frame; its origin is the RCM point (estimated with ``params`` ``rcm``..).
    design : Design, optional
        Nominal design (starting values; strokes and A/B order are kept).
    params : iterable of str or str, keyword-only
        Estimated parameters (names of :data:`~athenakin.calibration.PARAMETERS` or
        the groups ``lengths``, ``offsets``, ``rcm``, ``registration``, ``default``).
        Default ``l1..l5, tool_length``.
    frame : {"base", "tracker"}, keyword-only
    axes : array-like, shape (N, 3), optional, keyword-only
        Measured instrument directions (unit, from ``O_s`` towards the RCM), in the frame
        of ``tips``: measurement model (c), full instrument poses.
    mode : {1, -1}, array-like of them, shape (N,), or "auto", keyword-only
        Assembly mode of each row, kept while the parameters change; ``"auto"`` (base
        frame only): per row, the mode whose nominal tip is nearer the measured tip.
    q_offset : array-like, shape (3,), keyword-only
        Starting (or fixed) actuator zero offsets, m.
    registration : array-like, shape (4, 4), keyword-only
        Starting ``T_t_b`` for ``frame="tracker"`` (default: fitted to the nominal tips).
    options : CalibrationOptions, optional, keyword-only
        Solver settings: see the fields of :class:`CalibrationOptions` (default: all defaults).

    Returns
    -------
    CalibrationResult

    Raises
    ------
    InvalidInputError
        Wrong shapes, mismatched lengths, too many bad rows (any, with ``bad_rows="raise"``).
    NotIdentifiableError
        Too few poses, or poses that cannot separate the parameters (combinations named).
    CalibrationError
        The fit diverged to a non-physical design (wrong assembly mode, frame or units).

    Examples
    --------
    >>> import athenakin as ak
    >>> from athenakin import calibration as cal
    >>> d = ak.Design.default(); T = ak.default_rcm_frame(d)
    >>> data = cal.synthetic_measurements(T, d, n=40, rng=1,
    ...                                   options=cal.SyntheticOptions(noise=0.0))
    >>> res = cal.calibrate(data.q, data.tips, T, d)
    >>> abs(res.design.l1 - data.true_design.l1) < 1e-9
    True
    """
    least_squares = _least_squares()
    opts = CalibrationOptions() if options is None else options
    check_instance(opts, "options", CalibrationOptions)
    design, prob, names, chk, m_all, T = _setup(
        q, tips, T_b_e, design, params=params, frame=frame, axes=axes, mode=mode,
        q_offset=q_offset, registration=registration, axis_weight=opts.axis_weight,
        bad_rows=opts.bad_rows, max_bad_fraction=opts.max_bad_fraction)
    report = _check_problem(prob, names, opts)
    sol, use = _fit(least_squares, prob, report, opts)
    theta = prob.full(sol.x)
    r_after = _physical_residuals(prob, theta, sol)
    cov, s_hat, outl = _covariance(prob, theta, r_after, use, opts)
    return _result(design, names, prob, theta, cov, chk, m_all, T, r_after, use, outl, s_hat,
                   report, sol)


def _least_squares() -> Any:
    """:func:`scipy.optimize.least_squares`, with a message naming the extra to install."""
    try:
        from scipy.optimize import least_squares
    except ModuleNotFoundError as exc:  # pragma: no cover - depends on the install
        raise ModuleNotFoundError("calibrate needs scipy: pip install 'athenakin[calibration]'",
                                  name="scipy") from exc
    return least_squares


def _fit(least_squares: Any, prob: _Problem, report: IdentifiabilityReport,
         opts: CalibrationOptions) -> tuple[Any, BoolArray]:
    """The solver's stages; the solution and the rows kept in the final fit.

    A linear least-squares fit; with a robust loss, a robust fit from it (scale
    ``f_scale`` or twice the MAD sigma of the first residuals), then a linear refit
    without the rows beyond ``outlier_threshold`` robust sigmas.
    """
    n_used, rows_per = prob.q.shape[0], prob.rows_per
    x0 = prob.theta0[prob.free]
    x_scale = 1.0 / np.where(report.column_norms > 0, report.column_norms, 1.0)
    x_scale = x_scale / np.max(x_scale)
    solver = dict(method="trf", x_scale=x_scale, ftol=opts.tol, xtol=opts.tol, gtol=opts.tol,
                  max_nfev=opts.max_nfev)
    sol = least_squares(prob.residual, x0, jac=prob.jacobian, loss="linear", **solver)
    use = np.ones(n_used, bool)
    if opts.loss == "linear":
        return sol, use
    r_rows = sol.fun.reshape(n_used, rows_per)
    scale = opts.f_scale if opts.f_scale is not None else 2.0 * _robust_sigma(r_rows)
    if not np.isfinite(scale) or scale <= 0:
        scale = RESIDUAL_FLOOR
    sol = least_squares(prob.residual, sol.x, jac=prob.jacobian, loss=opts.loss, f_scale=scale,
                        **solver)
    r_rows = sol.fun.reshape(n_used, rows_per)
    s_rob = opts.sigma if opts.sigma is not None else _robust_sigma(r_rows)
    use = np.linalg.norm(r_rows, axis=1) <= opts.outlier_threshold * max(s_rob, RESIDUAL_FLOOR)
    sub = dataclasses.replace(prob, q=prob.q[use], tips=prob.tips[use],
                              axes=None if prob.axes is None else prob.axes[use],
                              mode=prob.mode[use])
    sol = least_squares(sub.residual, sol.x, jac=sub.jacobian, loss="linear", **solver)
    return sol, use


def _physical_residuals(prob: _Problem, theta: FloatArray, sol: Any
                        ) -> FloatArray:
    """Residuals at the solution; refuse a non-positive length or a pose it cannot assemble."""
    _, r_after = prob.evaluate(theta, False)
    if np.any(theta[:6] <= 0) or not np.all(np.isfinite(r_after)):
        raise CalibrationError(
            f"calibration diverged ({sol.message}): the fit leaves a non-physical design "
            f"(l1..l5, tool_length = {np.array2string(theta[:6], precision=6)} m) or poses "
            "the model cannot assemble; check the assembly mode, the frame and the units (m)")
    return r_after


def _covariance(prob: _Problem, theta: FloatArray, r_after: FloatArray,
                use: BoolArray, opts: CalibrationOptions
                ) -> tuple[FloatArray, float, BoolArray]:
    """Covariance ``sigma^2 (J^T J)^+`` over the rows used, ``sigma``, and the outlier rows.

    ``sigma`` is the one given, else ``sqrt(SSR / (m - n))``; outliers are the rows left
    out by a robust fit, else those beyond ``outlier_threshold * sigma`` (a warning).
    """
    J = prob.jac_full(theta)[:, prob.free].reshape(prob.q.shape[0], prob.rows_per, -1)[use].reshape(
        -1, prob.free.shape[0])
    dof = J.shape[0] - J.shape[1]
    ssr = float(np.sum(r_after[use] ** 2))
    sigma, threshold = opts.sigma, opts.outlier_threshold
    s_hat = float(sigma) if sigma is not None else float(np.sqrt(ssr / max(dof, 1)))
    cov = np.asarray(s_hat ** 2 * np.linalg.pinv(J.T @ J, rcond=1e-15, hermitian=True),
                     dtype=np.float64)
    outl = np.linalg.norm(r_after, axis=1) > threshold * max(s_hat, RESIDUAL_FLOOR)
    if opts.loss != "linear":
        outl = ~use
    if np.any(outl):
        warnings.warn(f"calibration: {int(np.sum(outl))} row(s) flagged as outliers "
                      f"(residual above {threshold} sigma = "
                      f"{threshold * s_hat:.3g} m)", CalibrationWarning, stacklevel=3)
    return cov, s_hat, outl


def _check_problem(prob: _Problem, names: tuple[str, ...], opts: CalibrationOptions
                   ) -> IdentifiabilityReport:
    """Enough equations, the identifiability of the parameters, plausible units (warnings)."""
    n_used, rows_per = prob.q.shape[0], prob.rows_per
    if rows_per * n_used <= len(names):
        raise NotIdentifiableError(
            f"too few poses: {n_used} usable poses give {rows_per * n_used} equations for "
            f"{len(names)} parameters {list(names)}; measure more than "
            f"{len(names) // rows_per} poses (and more than that for a useful estimate)")
    J0 = prob.jac_full(prob.theta0)[:, prob.free]
    report = analyse_jacobian(J0, names, tol=opts.identifiability_tol)
    if not report.identifiable:
        if opts.on_unidentifiable == "raise":
            raise_if_not_identifiable(report, n_used)
        warnings.warn(f"calibration: not identifiable: {'; '.join(report.combinations)}",
                      CalibrationWarning, stacklevel=3)
    elif report.weak:
        warnings.warn(f"calibration: weakly identifiable (condition {report.condition:.3g}); "
                      "the standard deviations will be large", CalibrationWarning, stacklevel=3)
    rms0 = float(np.sqrt(np.mean(np.sum(prob.evaluate(prob.theta0, False)[1][:, :3] ** 2,
                                        axis=1))))
    if rms0 > UNITS_WARNING:
        warnings.warn(f"calibration: the measured tips are {rms0:.3g} m (RMS) from the nominal "
                      "model; check the units (m), the frame and T_b_e", CalibrationWarning,
                      stacklevel=3)
    return report


def _robust_sigma(r: FloatArray) -> float:
    """Standard deviation of one component from the median absolute deviation (tips only)."""
    return float(1.4826 * np.median(np.abs(r[:, :3])))


def _result(design: Design, names: tuple[str, ...], prob: _Problem, theta: FloatArray,
            cov: FloatArray, chk: MeasurementCheck, m_all: FloatArray,
            T: FloatArray, r_after: FloatArray, use: BoolArray,
            outl: BoolArray, s_hat: float, report: IdentifiabilityReport, sol: object
            ) -> CalibrationResult:
    """The result: residuals before (nominal) and after, spread back over every row."""
    n_all, rows_per = chk.usable.shape[0], prob.rows_per
    _, r_before = prob.evaluate(prob.theta0, False)

    def spread(a: FloatArray) -> FloatArray:
        out = np.full((n_all, rows_per), np.nan)
        out[chk.usable] = -a     # measured minus predicted
        return out

    def spread_b(a: BoolArray) -> BoolArray:
        out = np.zeros(n_all, bool)
        out[chk.usable] = a
        return out

    T_t_b = None
    if prob.R0 is not None:
        T_t_b = np.eye(4)
        T_t_b[:3, :3] = rotation_from_vector(theta[_REG:_REG + 3]) @ prob.R0
        T_t_b[:3, 3] = theta[_REG + 3:_REG + 6]
    T_new = T.copy()
    T_new[:3, 3] = theta[9:12]
    rms = [float(np.sqrt(np.mean(np.sum(r[use][:, :3] ** 2, axis=1))))
           for r in (r_before, r_after)]
    return CalibrationResult(
        design=dataclasses.replace(design_from_parameters(theta, design),
                                   name=calibrated_name(design.name)),
        names=names, estimates=theta[prob.free],
        nominal=prob.theta0[prob.free], std=np.sqrt(np.clip(np.diag(cov), 0.0, None)),
        covariance=cov, parameters={n: float(v) for n, v in zip(PARAMETERS, theta, strict=True)},
        q_offset=theta[6:9].copy(), rcm=theta[9:12].copy(), T_b_e=T_new, T_t_b=T_t_b,
        frame="base" if prob.R0 is None else "tracker", mode=m_all.astype(np.int64),
        residuals_before=spread(r_before), residuals_after=spread(r_after),
        rms_before=rms[0], rms_after=rms[1], sigma=s_hat, outliers=spread_b(outl),
        excluded=~chk.usable, check=chk, identifiability=report,
        success=bool(getattr(sol, "success", False)), message=str(getattr(sol, "message", "")),
        nfev=int(getattr(sol, "nfev", 0)))
