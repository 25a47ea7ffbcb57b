"""A planned move's profile: Ruckig's time-optimal jerk-limited trajectory (private).

:meth:`~athenakin.teleop.SimulatedArm.move_jp` moves the setpoint from its position,
velocity and acceleration to a goal along the profile of :func:`move_profile`, sampled
once per servo cycle (:func:`profile_at`). Ruckig is the extra ``motion``.

Units: m, m/s, m/s^2, m/s^3; s.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._typing import FloatArray
from ..errors import KinematicsError

__all__ = ["move_profile", "profile_at"]


def move_profile(q: FloatArray, qd: FloatArray, qdd: FloatArray, goal: FloatArray,
                 goal_velocity: FloatArray, limits: tuple[float, float, float]) -> Any:
    """The time-optimal jerk-limited profile from a setpoint to a goal (Ruckig).

    Parameters
    ----------
    q, qd, qdd : ndarray, shape (3,)
        The setpoint now: m, m/s, m/s^2.
    goal : ndarray, shape (3,)
        m.
    goal_velocity : ndarray, shape (3,)
        m/s, at arrival (the acceleration there is zero).
    limits : tuple of 3 float
        Velocity, acceleration and jerk bounds per actuator: m/s, m/s^2, m/s^3.

    Returns
    -------
    ruckig.Trajectory
        Three degrees of freedom; ``duration`` in s.

    Raises
    ------
    KinematicsError
        Ruckig finds no profile, or fails (its error named).
    ModuleNotFoundError
        ruckig is not installed (extra ``motion``).
    """
    try:
        from ruckig import InputParameter, Result, Ruckig, Trajectory
    except ModuleNotFoundError as exc:
        raise ModuleNotFoundError("move_jp needs ruckig: pip install 'athenakin[motion]'",
                                  name="ruckig") from exc
    inp = InputParameter(3)
    inp.current_position = q.tolist()
    inp.current_velocity = qd.tolist()
    inp.current_acceleration = qdd.tolist()
    inp.target_position = goal.tolist()
    inp.target_velocity = goal_velocity.tolist()
    inp.target_acceleration = [0.0] * 3
    v, a, j = limits
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [v] * 3, [a] * 3, [j] * 3
    traj = Trajectory(3)
    try:
        res = Ruckig(3).calculate(inp, traj)
    except Exception as exc:         # ruckig's own errors (RuntimeError, pybind11's)
        raise KinematicsError(f"move_jp: Ruckig failed ({type(exc).__name__}: {exc})"
                              ) from exc
    if res not in (Result.Working, Result.Finished):
        raise KinematicsError(f"move_jp: Ruckig found no profile ({res})")
    return traj


def profile_at(traj: Any, t: float) -> tuple[FloatArray, FloatArray, FloatArray, bool]:
    """The profile's setpoint at ``t`` s after its start (held at its end).

    Parameters
    ----------
    traj : ruckig.Trajectory
        Of :func:`move_profile`.
    t : float
        s since the start of the move.

    Returns
    -------
    q, qd, qdd : ndarray, shape (3,)
        m, m/s, m/s^2 at ``min(t, duration)``.
    done : bool
        ``t`` reached the end of the profile.
    """
    tt = min(t, traj.duration)
    p, v, a = traj.at_time(tt)
    return np.array(p), np.array(v), np.array(a), tt >= traj.duration
