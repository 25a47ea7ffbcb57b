"""How accurate is the calibrated robot? Tool-tip error from parameters and encoders.

First order through the Jacobians: the tip ``t(q, theta)`` of the calibrated model has
covariance ``J_theta Sigma_theta J_theta^T + J_q Sigma_q J_q^T`` with ``Sigma_theta`` the
covariance of the estimated parameters (:attr:`CalibrationResult.covariance`) and
``Sigma_q = res^2 / 12 I`` the variance of a uniform quantisation error of an encoder
of resolution ``res``. :func:`tip_error_monte_carlo` samples the same two sources through
the nonlinear model (tests compare the two).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray, IntArray
from .._validation import check_array, check_count, check_instance, check_rng, check_scalar
from ..errors import InvalidInputError
from ..robot import direction_from_angles, q_from_instrument
from ._model import PARAMETERS, Seed, predict
from ._solve import CalibrationResult

__all__ = ["TipError", "TipErrorMap", "tip_error", "tip_error_monte_carlo", "tip_error_map"]


@dataclasses.dataclass(frozen=True)
class TipError:
    """Expected tool-tip error of the calibrated robot at some readings (first order).

    Attributes
    ----------
    covariance : ndarray, shape (N, 3, 3)
        Covariance of the tip in the base frame, m^2 (both sources).
    from_parameters, from_encoders : ndarray, shape (N, 3, 3)
        The two contributions, m^2.
    rms : ndarray, shape (N,)
        ``sqrt(trace(covariance))``: RMS distance of the tip from its prediction, m.
    """

    covariance: FloatArray
    from_parameters: FloatArray
    from_encoders: FloatArray
    rms: FloatArray


@dataclasses.dataclass(frozen=True)
class TipErrorMap:
    """Expected tip error over the instrument cone about the RCM, at one tip depth.

    Attributes
    ----------
    azimuth : ndarray, shape (na,)
        Rad, about ``z_e`` (:func:`~athenakin.direction_from_angles`).
    polar : ndarray, shape (np,)
        Rad, from ``z_e``.
    depth : float
        Distance of the tip beyond the RCM, m (insertion ``p = L - depth``).
    rms : ndarray, shape (na, np)
        RMS tip error (m); NaN where the calibrated robot cannot reach the direction.
    q : ndarray, shape (na, np, 3)
        Readings of each direction (NaN where unreachable), m.
    encoder_resolution : float
        m.
    """

    azimuth: FloatArray
    polar: FloatArray
    depth: float
    rms: FloatArray
    q: FloatArray
    encoder_resolution: float


def _theta(result: CalibrationResult) -> tuple[FloatArray, IntArray]:
    theta = np.array([result.parameters[n] for n in PARAMETERS])
    free = np.array([PARAMETERS.index(n) for n in result.names], dtype=np.int64)
    return theta, free


def _readings(q: ArrayLike) -> FloatArray:
    qa = check_array(q, "q", (3,))
    if qa.ndim != 2:
        raise InvalidInputError(f"q: expected shape (N, 3), got shape {qa.shape}")
    return qa


def tip_error(result: CalibrationResult, q: ArrayLike, *, encoder_resolution: float = 0.0,
              mode: int = 1) -> TipError:
    """First-order tool-tip error of the calibrated robot at readings ``q``.

    Parameters
    ----------
    result : CalibrationResult
    q : array-like, shape (N, 3)
        Actuator readings, m.
    encoder_resolution : float, keyword-only
        Encoder quantum, m (uniform error, variance ``res^2 / 12``).
    mode : {1, -1}, keyword-only
        Assembly mode.

    Returns
    -------
    TipError
    """
    check_instance(result, "result", CalibrationResult)
    qa = _readings(q)
    if encoder_resolution < 0 or not np.isfinite(encoder_resolution):
        raise InvalidInputError(f"encoder_resolution: expected a number >= 0 (m), got "
                                f"{encoder_resolution}")
    theta, free = _theta(result)
    pr = predict(theta, qa, np.full(len(qa), float(mode)), jacobian=True)
    assert pr.J_tip is not None and pr.J_q is not None
    Jt = pr.J_tip[:, :, free]
    Cp = Jt @ result.covariance @ np.swapaxes(Jt, 1, 2)
    Ce = encoder_resolution ** 2 / 12.0 * pr.J_q @ np.swapaxes(pr.J_q, 1, 2)
    C = Cp + Ce
    return TipError(covariance=C, from_parameters=Cp, from_encoders=Ce,
                    rms=np.sqrt(np.trace(C, axis1=1, axis2=2)))


def tip_error_monte_carlo(result: CalibrationResult, q: ArrayLike, *,
                          encoder_resolution: float = 0.0, n_samples: int = 2000,
                          mode: int = 1, rng: Seed = None) -> FloatArray:
    """Covariance (N, 3, 3) of the tip by sampling parameters and encoder errors.

    Parameters are drawn from ``N(estimates, covariance)``, encoder errors uniformly in
    ``[-res/2, res/2]``, and the tip is computed with the nonlinear model.

    Parameters
    ----------
    result : CalibrationResult
    q : array-like, shape (N, 3)
        Readings ``(q1, q2, q3)``, m.
    encoder_resolution : float, keyword-only
        Encoder quantum, m (0: no encoder error).
    n_samples : int, keyword-only
        Parameter draws.
    mode : {1, -1}, keyword-only
        Assembly mode.
    rng : seed or Generator, keyword-only

    Returns
    -------
    ndarray, shape (N, 3, 3)
        Sample covariance of the tip in the base frame, m^2 (cf. the linearised
        :func:`tip_error`).
    """
    check_instance(result, "result", CalibrationResult)
    qa = _readings(q)
    gen = check_rng(rng)
    theta, free = _theta(result)
    draws = gen.multivariate_normal(theta[free], result.covariance, size=n_samples,
                                    method="eigh")
    m = np.full(len(qa), float(mode))
    tips = np.empty((n_samples, len(qa), 3))
    for s in range(n_samples):
        th = theta.copy()
        th[free] = draws[s]
        dq = encoder_resolution * (gen.random(qa.shape) - 0.5)
        tips[s] = predict(th, qa + dq, m).tip_base
    dev = tips - tips.mean(axis=0)
    return np.einsum("sni,snj->nij", dev, dev) / (n_samples - 1)


#: Most directions of one :func:`tip_error_map` (checked before anything is allocated).
MAX_MAP_POINTS = 4_000_000


def tip_error_map(result: CalibrationResult, *, depth: float | None = None,
                  resolution: tuple[int, int] = (72, 37), encoder_resolution: float = 0.0,
                  mode: int = 1) -> TipErrorMap:
    """Expected tip error over the cone of instrument directions about the calibrated RCM.

    Parameters
    ----------
    result : CalibrationResult
    depth : float, keyword-only
        Tip beyond the RCM, m; default half the calibrated tool length.
    resolution : (int, int), keyword-only
        Samples of azimuth over (-pi, pi] and polar angle over [0, pi].
    encoder_resolution : float, keyword-only
        m.
    mode : {1, -1}, keyword-only

    Returns
    -------
    TipErrorMap
    """
    check_instance(result, "result", CalibrationResult)
    d = result.design
    L = d.tool_length
    dep = 0.5 * L if depth is None else check_scalar(depth, "depth")
    if not 0 < dep < L:
        raise InvalidInputError(f"depth: expected 0 < depth < tool_length = {L:.6g} m, got {dep}")
    try:
        na, npol = (check_count(r, "resolution", minimum=2, maximum=100_000) for r in resolution)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"resolution: expected (n_azimuth, n_polar), two integers in "
                                f"2..100000, got {resolution!r} ({exc})") from None
    if na * npol > MAX_MAP_POINTS:
        raise InvalidInputError(f"resolution: {na} x {npol} directions, more than "
                                f"{MAX_MAP_POINTS:,}; expected a coarser map")
    if isinstance(mode, bool) or not isinstance(mode, (int, np.integer)) or mode not in (1, -1):
        raise InvalidInputError(f"mode: expected +1 or -1 (assembly mode), got {mode!r}")
    az = np.linspace(-np.pi, np.pi, na, endpoint=False) + 2 * np.pi / na
    pol = np.linspace(0.0, np.pi, npol)
    A, B = np.meshgrid(az, pol, indexing="ij")
    d_e = direction_from_angles(A.ravel(), B.ravel())
    q_true, ik = q_from_instrument(result.T_b_e, d_e, np.full(len(d_e), L - dep), d,
                                   errors="flag")
    ok = ik.valid & (ik.mode == mode)
    q_read = np.where(ok[:, None], q_true - result.q_offset, np.nan)
    rms = np.full(len(d_e), np.nan)
    if np.any(ok):
        rms[ok] = tip_error(result, q_read[ok], encoder_resolution=encoder_resolution,
                            mode=mode).rms
    return TipErrorMap(azimuth=az, polar=pol, depth=dep, rms=rms.reshape(na, npol),
                       q=q_read.reshape(na, npol, 3), encoder_resolution=encoder_resolution)

