"""The arm's servo: PD gains from the masses, the sampled loop's stability, the force law (private).

:class:`~athenakin.teleop.SimulatedArm` servoes its three actuators with
``f = ff + Kp (q_sp - q) + Kd (qd_sp - qd)``, its approach velocity bounded by ``v_max``
and the PD force scaled, its direction kept, until each component is within ``max_force``
(:func:`pd_force`). Without explicit
:class:`ServoGains` the gains follow from the mass matrix at ``q0`` and the rate
(:func:`servo_gains`: ``Kp = omega^2 M``, ``Kd = 2 zeta omega M``,
``omega = min(BANDWIDTH, BANDWIDTH_PER_RATE rate)``); either way
the sampled loop (force held over each cycle) must have a spectral radius below
:data:`STABILITY_RADIUS`.

Units: m, m/s, N, kg; gains in N/m and N s/m; rates in Hz.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from .._typing import FloatArray
from .._validation import check_scalar
from ..design import Design
from ..errors import InvalidInputError

__all__ = ["ServoGains", "servo_gains", "approach_gain", "pd_force", "MAX_FORCE", "BANDWIDTH",
           "BANDWIDTH_PER_RATE", "DAMPING_RATIO", "STABILITY_RADIUS", "MIN_MODAL_MASS"]

#: Default bound of the servo's force per actuator (saturation, and the largest effort
#: a servo command may carry), N.
MAX_FORCE = 100.0
#: Bandwidth of the derived servo gains, rad/s, at most ...
BANDWIDTH = 150.0
#: ... and at most this fraction of the cycle rate (rad/s per Hz): ``omega dt <= 0.15``.
BANDWIDTH_PER_RATE = 0.15
#: Damping ratio of the derived gains.
DAMPING_RATIO = 1.0
#: Largest spectral radius of the sampled servo loop (mass matrix at ``q0``, force held
#: over the cycle) that the constructor accepts for given gains.
STABILITY_RADIUS = 0.98
#: Smallest eigenvalue of the mass matrix at ``q0`` that the servo needs, kg.
MIN_MODAL_MASS = 1e-3


@dataclasses.dataclass(frozen=True, kw_only=True)
class ServoGains:
    """Explicit PD gains of the servo, the same on every actuator.

    Without ``gains`` :class:`~athenakin.teleop.SimulatedArm` derives them from the mass
    model and the rate (``Kp = omega^2 M(q0)``, ``Kd = 2 zeta omega M(q0)``,
    :data:`BANDWIDTH`); explicit gains are checked for the stability of the sampled loop
    at the arm's rate (:data:`STABILITY_RADIUS`).

    Parameters
    ----------
    kp : float
        N/m (default 4e4).
    kd : float
        N s/m (default 800: about critical for a few kg at ``kp``).

    Raises
    ------
    InvalidInputError, TypeError
        A gain that is not a finite non-negative number.
    """

    kp: float = 4.0e4
    kd: float = 800.0

    def __post_init__(self) -> None:
        check_scalar(self.kp, "kp", nonnegative=True)
        check_scalar(self.kd, "kd", nonnegative=True)


def servo_gains(q0: FloatArray, T_b_e: FloatArray, design: Design, masses: Any, slot: int,
                rate: float, gains: ServoGains | None) -> tuple[FloatArray, FloatArray]:
    """The PD gain matrices ``(Kp, Kd)``: derived from the masses, or explicit and checked.

    Parameters
    ----------
    q0 : ndarray, shape (3,)
        Where the mass matrix is taken, m.
    T_b_e : ndarray, shape (4, 4)
    design : Design
    masses : athenakin.dynamics.MassModel
    slot : int
        The forward-kinematics slot.
    rate : float
        Servo cycles per second, Hz.
    gains : ServoGains or None
        Explicit gains; None: derived (:data:`BANDWIDTH`, :data:`DAMPING_RATIO`).

    Returns
    -------
    Kp, Kd : ndarray, shape (3, 3)
        N/m and N s/m, read-only.

    Raises
    ------
    InvalidInputError
        A mass matrix with an eigenvalue below :data:`MIN_MODAL_MASS`; a sampled loop
        whose spectral radius is not below :data:`STABILITY_RADIUS`.
    """
    from ..dynamics import mass_matrix

    M = np.asarray(mass_matrix(q0, T_b_e, design, masses=masses, slot=slot, errors="raise"),
                   dtype=float)
    M = 0.5 * (M + M.T)
    lam = float(np.min(np.linalg.eigvalsh(M))) if np.all(np.isfinite(M)) else math.nan
    if not lam >= MIN_MODAL_MASS:
        raise InvalidInputError(f"masses: the mass matrix at q0 has an eigenvalue of "
                                f"{lam:.3g} kg, below {MIN_MODAL_MASS:g} kg: no servo can be "
                                f"designed for it (give the moving parts mass along every "
                                f"actuator, e.g. MassModel.reference(design))")
    dt = 1.0 / rate
    if gains is None:
        w = min(BANDWIDTH, BANDWIDTH_PER_RATE * rate)
        Kp, Kd = w * w * M, 2.0 * DAMPING_RATIO * w * M
    else:
        Kp, Kd = gains.kp * np.eye(3), gains.kd * np.eye(3)
    rho = _spectral_radius(Kp, Kd, M, dt)
    if not rho < STABILITY_RADIUS:
        raise InvalidInputError(f"gains: the sampled servo loop is unstable at {rate:g} Hz "
                                f"with this mass model (spectral radius {rho:.3g} >= "
                                f"{STABILITY_RADIUS}); lower kp / kd, or leave gains=None for "
                                f"gains derived from the masses and the rate")
    Kp.setflags(write=False)
    Kd.setflags(write=False)
    return Kp, Kd


def _spectral_radius(Kp: FloatArray, Kd: FloatArray, M: FloatArray, dt: float) -> float:
    """Spectral radius of the PD loop on ``M qdd = f``, ``f`` held over each cycle ``dt``.

    The error ``e`` and its rate ``v`` advance exactly over one cycle of constant
    acceleration ``a = -M^-1 (Kp e + Kd v)``: ``e' = e + dt v + dt^2 a / 2``,
    ``v' = v + dt a``.
    """
    G = np.linalg.solve(M, np.eye(3))
    A = -G @ Kp
    B = -G @ Kd
    eye = np.eye(3)
    phi = np.block([[eye + 0.5 * dt * dt * A, dt * eye + 0.5 * dt * dt * B],
                    [dt * A, eye + dt * B]])
    return float(np.max(np.abs(np.linalg.eigvals(phi))))


def approach_gain(Kp: FloatArray, Kd: FloatArray) -> FloatArray | None:
    """``L = Kd^-1 Kp``, 1/s: the velocity with which the PD law approaches its setpoint.

    The PD force is ``Kd (qd_sp + L (q_sp - q) - qd)`` (:func:`pd_force`); where ``Kd`` is
    singular (explicit ``kd = 0``) there is no approach velocity to bound: None, which
    leaves :func:`pd_force` the plain PD law.

    Parameters
    ----------
    Kp, Kd : ndarray, shape (3, 3)
        N/m, N s/m.

    Returns
    -------
    ndarray, shape (3, 3), or None
        1/s, read-only.
    """
    if np.linalg.matrix_rank(Kd) < 3:
        return None
    L = np.linalg.solve(Kd, Kp)
    L.setflags(write=False)
    return np.asarray(L, dtype=float)


def pd_force(ff: FloatArray, Kp: FloatArray, Kd: FloatArray, q_sp: FloatArray,
             qd_sp: FloatArray, q: FloatArray, qd: FloatArray,
             max_force: float, *, L: FloatArray | None = None,
             v_max: float = math.inf) -> tuple[FloatArray, bool]:
    """One cycle's servo force ``ff + Kp (q_sp - q) + Kd (qd_sp - qd)``, bounded, saturated.

    The PD terms are ``Kd (qd_sp + v_corr - qd)`` with the approach velocity
    ``v_corr = L (q_sp - q)`` (``L = Kd^-1 Kp``, :func:`approach_gain`); where a component of
    ``v_corr`` exceeds ``v_max``, ``v_corr`` is scaled down to it, direction kept (the
    velocity saturation of Khatib's operational-space control): a far setpoint is
    approached at ``v_max`` on top of the setpoint's own velocity, and a near one gets the
    plain PD law (a tracking lag is caught up as the PD law does). Where a
    component of ``ff + pd`` exceeds ``max_force`` the PD force ``pd`` is scaled down, its
    direction kept, until every component is within it (then clipped, for a feed-forward
    beyond it): clipping each component alone turns the force of a coupled mass matrix
    into one that can accelerate the carriages away from the setpoint.

    Parameters
    ----------
    ff : ndarray, shape (3,)
        Feed-forward, N.
    Kp, Kd : ndarray, shape (3, 3)
        N/m, N s/m.
    q_sp, qd_sp : ndarray, shape (3,)
        Setpoint, m and m/s.
    q, qd : ndarray, shape (3,)
        Measured, m and m/s.
    max_force : float
        Saturation per actuator, N.
    L : ndarray, shape (3, 3), optional, keyword-only
        ``Kd^-1 Kp``, 1/s (default none: the plain PD law, no velocity bound).
    v_max : float, keyword-only
        Bound of each component of the approach velocity ``v_corr``, m/s (default none).

    Returns
    -------
    force : ndarray, shape (3,)
        N, each component within ``max_force``.
    saturated : bool
        The force was scaled (the force, not the approach velocity).
    """
    e = q_sp - q
    pd = Kp @ e + Kd @ (qd_sp - qd)
    if L is not None:
        v_corr = L @ e
        peak = np.abs(v_corr).max()
        if peak > v_max:
            pd = Kd @ (qd_sp + v_corr * (v_max / peak) - qd)
    f = ff + pd
    saturated = not np.abs(f).max() <= max_force
    if saturated:
        # the largest s in [0, 1] with |ff + s pd| <= max_force in every component: the PD
        # force keeps its direction, so M^-1 f still points where the servo accelerates
        with np.errstate(divide="ignore", invalid="ignore"):
            room = np.where(pd > 0, (max_force - ff) / pd, (-max_force - ff) / pd)
        s = float(np.clip(np.min(np.where(pd != 0, room, np.inf)), 0.0, 1.0))
        f = np.clip(ff + s * pd, -max_force, max_force)
    return f, saturated
