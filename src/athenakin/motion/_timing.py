"""Time law of the path parameter with Ruckig (private).

Each segment is traversed rest to rest; its parameter ``lam`` goes from 0 to 1
along a jerk-limited (or, without a jerk limit, acceleration-limited) profile
computed by Ruckig's time-optimal 1-DoF solver, optionally stretched to a
minimum duration. Limits on ``lam`` come from the actuator limits through the
bounds of ``dq/dlam``, ``d2q/dlam2`` and ``d3q/dlam3`` along the segment
(:func:`parameter_limits`).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .._typing import FloatArray

__all__ = ["ParameterLimits", "parameter_limits", "LamProfile", "lam_profile", "TimeLawError"]


class TimeLawError(ValueError):
    """Ruckig cannot compute the profile of ``lam`` within the given limits (one line)."""

#: Time step (s) of the acceleration difference that gives the (piecewise-constant) jerk.
_JERK_STEP = 1e-7


@dataclasses.dataclass(frozen=True)
class ParameterLimits:
    """Limits of the path parameter of one segment: ``|lam'| <= v``, ``|lam''| <= a``, ...

    ``j`` is ``inf`` without a jerk limit.
    """

    v: float
    a: float
    j: float


def parameter_limits(K1: FloatArray, K2: FloatArray, K3: FloatArray,
                     *, v_max: FloatArray, a_max: FloatArray,
                     j_max: FloatArray | None, tip_factor: float,
                     tip_speed: float | None) -> ParameterLimits:
    """Limits of ``lam`` that keep every actuator within ``v_max``, ``a_max``, ``j_max``.

    With ``qd = q' l'``, ``qdd = q'' l'^2 + q' l''`` and
    ``qddd = q''' l'^3 + 3 q'' l' l'' + q' l'''`` (primes: derivatives in ``lam``,
    ``l = lam``), and ``K1, K2, K3`` the largest ``|q'|, |q''|, |q'''|`` of each
    actuator on the segment, these limits are sufficient (minima over actuators):

    * ``v = min(v_max / K1, sqrt(a_max / (2 K2)))`` (and ``tip_speed / tip_factor``);
    * ``a = min((a_max - K2 v^2) / K1)``;
    * with a jerk limit, ``v`` and ``a`` are scaled by ``f = min(1, sqrt(j_max / (2 X)))``,
      ``X = K3 v^3 + 3 K2 v a``, then ``j = min((j_max - K3 v^3 - 3 K2 v a) / K1)``.

    Parameters
    ----------
    K1, K2, K3 : ndarray, shape (3,)
        Bounds of the derivatives of ``q(lam)`` (m).
    v_max, a_max : ndarray, shape (3,)
        Actuator limits (m/s, m/s^2).
    j_max : ndarray, shape (3,), or None
        Actuator jerk limits (m/s^3); None for none.
    tip_factor : float
        Largest ``|d tip / d lam|`` on the segment (m).
    tip_speed : float or None
        Tool-tip speed limit (m/s).

    Returns
    -------
    ParameterLimits
    """
    inf = np.inf
    with np.errstate(divide="ignore", invalid="ignore"):
        v = float(np.min(np.where(K1 > 0, v_max / K1, inf)))
        v = min(v, float(np.min(np.where(K2 > 0, np.sqrt(a_max / (2 * K2)), inf))))
        if tip_speed is not None and tip_factor > 0:
            v = min(v, tip_speed / tip_factor)
        a = float(np.min(np.where(K1 > 0, (a_max - K2 * v * v) / K1, inf)))
        if not math.isfinite(v) or not math.isfinite(a):
            raise ValueError("no actuator moves along the segment (or its motion is not "
                             "defined there): no limit of the path parameter")
        if not (v > 0 and a > 0):
            raise ValueError(f"the actuator limits leave no speed or acceleration along the "
                             f"segment (path parameter limits v = {v:.3g} 1/s, a = {a:.3g} "
                             f"1/s^2)")
        j = math.inf
        if j_max is not None:
            X = K3 * v ** 3 + 3 * K2 * v * a
            f = float(np.min(np.where(X > 0, np.sqrt(j_max / (2 * X)), inf)))
            f = min(1.0, f)
            v, a = v * f, a * f
            j = float(np.min(np.where(K1 > 0, (j_max - K3 * v ** 3 - 3 * K2 * v * a) / K1,
                                      inf)))
    return ParameterLimits(v=v, a=a, j=j)


@dataclasses.dataclass(frozen=True)
class LamProfile:
    """A rest-to-rest profile ``lam(t)`` from 0 to 1 on ``[0, duration]``.

    Attributes
    ----------
    duration : float
        Seconds.
    min_duration : float
        Duration of the time-optimal profile within the limits (before any stretch
        or squeeze), s.
    scale : float
        Time scaling applied to Ruckig's profile (1: none; < 1: squeezed into a
        shorter time than the limits allow, see ``timing="fixed"``).
    """

    duration: float
    min_duration: float
    scale: float
    _traj: object | None = dataclasses.field(repr=False, default=None)

    def evaluate(self, tau: FloatArray) -> tuple[FloatArray, ...]:
        """``lam`` and its first three time derivatives at local times ``tau`` (n,).

        Returns
        -------
        lam, lam_d, lam_dd, lam_ddd : ndarray, shape (n,)
            The third derivative is the jerk of the active phase (piecewise constant;
            0 in an acceleration-limited profile, whose acceleration jumps).
        """
        tau = np.asarray(tau, float)
        n = tau.shape[0]
        out = np.zeros((4, n))
        if self._traj is None:  # dwell: lam stays 0 (start == end)
            return out[0], out[1], out[2], out[3]
        k = self.scale
        tr = self._traj
        dur = float(tr.duration)  # type: ignore[attr-defined]
        for i, t in enumerate(tau):
            ts = min(max(t * k, 0.0), dur)
            p, v, a = tr.at_time(ts)  # type: ignore[attr-defined]
            out[0, i], out[1, i], out[2, i] = p[0], v[0], a[0]
            # jerk is constant within a phase: difference of the acceleration over a
            # tiny step (a convex combination of the two phases' jerks at a switch)
            if ts + _JERK_STEP <= dur:
                out[3, i] = (tr.at_time(ts + _JERK_STEP)[2][0] - a[0]) / _JERK_STEP  # type: ignore[attr-defined]
            elif ts >= dur:
                out[3, i] = 0.0
            else:
                out[3, i] = (a[0] - tr.at_time(ts - _JERK_STEP)[2][0]) / _JERK_STEP  # type: ignore[attr-defined]
        out[1] *= k
        out[2] *= k * k
        out[3] *= k ** 3
        return np.clip(out[0], 0.0, 1.0), out[1], out[2], out[3]


def lam_profile(lim: ParameterLimits, *, minimum_duration: float | None = None,
                dt: float | None = None) -> LamProfile:
    """Ruckig's profile of ``lam`` from rest at 0 to rest at 1.

    Parameters
    ----------
    lim : ParameterLimits
    minimum_duration : float, optional
        Stretch the profile to at least this duration (Ruckig's ``minimum_duration``).
    dt : float, optional
        Round the duration up to a multiple of ``dt`` (Ruckig's discrete durations),
        so that the segment ends on a sample.

    Returns
    -------
    LamProfile
    """
    from ruckig import DurationDiscretization, InputParameter, Result, Ruckig, Trajectory

    otg = Ruckig(1, dt) if dt is not None else Ruckig(1)
    inp = InputParameter(1)
    inp.current_position = [0.0]
    inp.target_position = [1.0]
    inp.max_velocity = [lim.v]
    inp.max_acceleration = [lim.a]
    inp.max_jerk = [lim.j]
    if dt is not None:
        inp.duration_discretization = DurationDiscretization.Discrete
    tr = Trajectory(1)
    _calculate(otg, inp, tr, lim, Result)
    t_min = float(tr.duration)
    if minimum_duration is not None and minimum_duration > t_min:
        inp.minimum_duration = float(minimum_duration)
        _calculate(otg, inp, tr, lim, Result, minimum_duration)
    return LamProfile(duration=float(tr.duration), min_duration=t_min, scale=1.0, _traj=tr)


#: Ruckig's error codes (ruckig::Result) and what they mean here.
_RUCKIG_ERRORS = {
    -100: "invalid input (limits not finite or not positive)",
    -101: "the duration exceeds Ruckig's numerical range (about 7e3 s)",
    -102: "the minimum duration exceeds Ruckig's numerical range",
    -110: "no profile within the limits",
    -111: "the minimum duration is too long",
}


def _calculate(otg: object, inp: object, tr: object, lim: ParameterLimits, Result: object,
               minimum_duration: float | None = None) -> None:
    """``otg.calculate(inp, tr)``; any failure becomes a one-line :class:`TimeLawError`."""
    what = (f"path-parameter limits v = {lim.v:.6g} 1/s, a = {lim.a:.6g} 1/s^2, "
            f"j = {lim.j:.6g} 1/s^3" + ("" if minimum_duration is None
                                        else f", minimum duration {minimum_duration:.6g} s"))
    try:
        res = otg.calculate(inp, tr)  # type: ignore[attr-defined]
    except Exception as exc:  # ruckig raises RuckigError, or ValueError for an unknown code
        code = next((int(t) for t in str(exc).replace(":", " ").split()
                     if t.lstrip("-").isdigit() and int(t) < 0), None)
        why = _RUCKIG_ERRORS.get(code, " ".join(str(exc).split())[:200]) if code else \
            " ".join(str(exc).split())[:200]
        raise TimeLawError(f"the time law (Ruckig) failed: {why} ({what})") from None
    if res not in (Result.Working, Result.Finished):  # type: ignore[attr-defined]
        why = _RUCKIG_ERRORS.get(int(res.value) if hasattr(res, "value") else -1, str(res))
        raise TimeLawError(f"the time law (Ruckig) failed: {why} ({what})")


def squeezed(prof: LamProfile, duration: float) -> LamProfile:
    """The same profile run faster so that it lasts ``duration`` (< its own) seconds."""
    return dataclasses.replace(prof, duration=duration, scale=prof.duration / duration)


def dwell(duration: float) -> LamProfile:
    """A profile that holds ``lam = 0`` for ``duration`` seconds (a repeated waypoint)."""
    return LamProfile(duration=duration, min_duration=0.0, scale=1.0, _traj=None)
