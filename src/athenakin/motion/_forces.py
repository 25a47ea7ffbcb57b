"""Actuator forces along a planned trajectory, and force limits by uniform time scaling.

Slowing a trajectory down uniformly by a factor ``k`` (``t -> k t``) divides every
velocity by ``k`` and every acceleration by ``k^2``; the actuator forces of the
closed chain (:func:`athenakin.dynamics.inverse_dynamics`) are then

    tau(k) = tau_g + (tau - tau_g) / k^2,

the static part ``tau_g`` (gravity) unchanged and the inertial part (``M qdd`` and
the velocity terms, both quadratic in the time scale) divided by ``k^2``. So
``|tau_i(k)| <= f_max_i`` holds for ``k^2 >= |tau_i - tau_g,i| / (f_max_i - |tau_g,i|)``
at every sample where the weight alone is within the limit. The planner is run again
with the kinematic limits scaled (``v / k``, ``a / k^2``, ``j / k^3``, tip speed
``/ k``): its time-optimal profile under scaled limits is the scaled profile, up to
the sampling; the forces are checked again and ``k`` grows by 2 % until they hold.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from .._validation import check_array
from ..errors import InvalidInputError
from ._errors import SafetyViolationError

__all__ = ["ForceLimitError", "trajectory_forces", "force_limited", "planned",
           "MAX_FORCE_REPLANS"]

#: Replans with a growing time scale before :class:`ForceLimitError`.
MAX_FORCE_REPLANS = 20


class ForceLimitError(SafetyViolationError):
    """An actuator force exceeds ``f_max`` and slowing down cannot fix it.

    Raised when the weight alone needs more than ``f_max`` (``limit="force"`` at
    the first such sample), or when the times are fixed (``timing="fixed"``).
    """


def _slot(traj: object) -> int:
    mode = np.asarray(traj.mode)  # type: ignore[attr-defined]
    if not np.all(mode == mode[0]):
        raise InvalidInputError("trajectory: the assembly mode changes along it")
    return 0 if int(mode[0]) == 1 else 8


def trajectory_forces(traj: object, masses: object, *, gravity: ArrayLike = (0.0, 0.0, -9.81),
                      backend: str = "auto") -> tuple[FloatArray, FloatArray]:
    """Actuator forces along a trajectory and their static part (N), each (N, 3).

    The configuration is the FK slot of the trajectory's assembly mode with ``p > 0``
    and the first branches of the U-joint and the spherical joint (slot 0 or 8).
    """
    from ..dynamics import actuator_forces, inverse_dynamics

    t: Any = traj
    m: Any = masses
    slot = _slot(t)
    # errors="raise": a sample off the slot is an error of the plan, never a NaN force
    # that no limit would catch
    tau = inverse_dynamics(t.q, t.qd, t.qdd, t.T_b_e, t.design, masses=m, gravity=gravity,
                           slot=slot, errors="raise", backend=backend)  # type: ignore[arg-type]
    tau_g = actuator_forces(t.q, t.T_b_e, t.design, masses=m, gravity=gravity, slot=slot,
                            errors="raise", backend=backend)  # type: ignore[arg-type]
    return tau, tau_g


def _check_f_max(f_max: ArrayLike) -> FloatArray:
    a = check_array(f_max, "f_max", ())         # a str, a ragged list: named TypeError
    out = np.broadcast_to(a, (3,)) if a.ndim == 0 else a
    if out.shape != (3,) or np.any(out <= 0):
        raise InvalidInputError(f"f_max: expected 3 positive force limits (N), got "
                                f"{np.asarray(f_max).tolist()}")
    return out


def _first_violation(traj: object, tau: FloatArray, f_max: FloatArray,
                     what: str) -> ForceLimitError:
    over = np.abs(tau) > f_max
    i, j = np.argwhere(over)[0]
    t = float(traj.t[i])  # type: ignore[attr-defined]
    return ForceLimitError(
        f"f_max: actuator q{j + 1} needs {tau[i, j]:+.3f} N at t = {t:.4f} s (sample {i}), "
        f"beyond its limit {f_max[j]:g} N; {what}",
        time=t, index=int(i), limit="force", value=float(tau[i, j]), bound=float(f_max[j]),
        actuator=int(j))


def force_limited(traj: object, replan: Callable[[float], object], *, masses: object,
                  f_max: ArrayLike | None, fixed_times: bool, backend: str = "auto") -> object:
    """Attach the actuator forces to a trajectory; slow it down until they are within limits.

    Parameters
    ----------
    traj : Trajectory
        The kinematically planned trajectory.
    replan : callable
        ``replan(k)`` plans again with the kinematic limits scaled by ``k`` (k > 1).
    masses : MassModel
    f_max : float or array-like, shape (3,), or None
        Actuator force limits, N (symmetric); None: only attach the forces.
    fixed_times : bool
        The waypoint times are fixed (no time scaling allowed).
    backend : {"auto", "numpy", "numba"}, keyword-only
        The backend of the dynamics.

    Returns
    -------
    Trajectory
        With ``forces`` (N, 3) in N.

    Raises
    ------
    ForceLimitError
        The weight alone exceeds ``f_max`` somewhere, the times are fixed, or
        :data:`MAX_FORCE_REPLANS` replans did not suffice.
    """
    tau, tau_g = trajectory_forces(traj, masses, backend=backend)
    if f_max is None:
        return dataclasses.replace(traj, forces=tau)  # type: ignore[type-var]
    fm = _check_f_max(f_max)
    if np.all(np.abs(tau) <= fm):
        return dataclasses.replace(traj, forces=tau)  # type: ignore[type-var]
    if np.any(np.abs(tau_g) > fm):
        raise _first_violation(traj, tau_g, fm, "the weight alone exceeds it, whatever the speed")
    if fixed_times:
        raise _first_violation(traj, tau, fm, "the waypoint times are fixed (timing='fixed')")
    with np.errstate(divide="ignore", invalid="ignore"):
        need = np.abs(tau - tau_g) / (fm - np.abs(tau_g))
    k = float(np.sqrt(max(1.0, float(np.max(need))))) * (1 + 1e-9)
    for _ in range(MAX_FORCE_REPLANS):
        t2 = replan(k)
        tau, _tg = trajectory_forces(t2, masses, backend=backend)
        if np.all(np.abs(tau) <= fm):
            return dataclasses.replace(t2, forces=tau)  # type: ignore[type-var]
        k *= 1.02
    raise _first_violation(t2, tau, fm, f"still after slowing down by {k:.3g}")


def planned(run: Callable[..., object], *, v_max: ArrayLike, a_max: ArrayLike,
            j_max: ArrayLike | None, tip_speed: float | None, masses: object,
            f_max: ArrayLike | None, fixed_times: bool, backend: str = "auto") -> object:
    """``run(v_max=, a_max=, j_max=, tip_speed=)``, with forces when ``masses`` is given.

    The glue of :func:`athenakin.motion.plan` (``masses=``, ``f_max=``): plans once with
    the given limits, then :func:`force_limited` with the limits scaled by ``k``.
    """
    if masses is None:
        if f_max is not None:
            raise InvalidInputError("f_max: force limits need a mass model (masses=)")
        return run(v_max=v_max, a_max=a_max, j_max=j_max, tip_speed=tip_speed)
    from ..dynamics import MassModel

    if not isinstance(masses, MassModel):
        raise TypeError(f"masses: expected an athenakin.dynamics.MassModel, got "
                        f"{type(masses).__name__}")
    if f_max is not None:
        _check_f_max(f_max)
    traj = run(v_max=v_max, a_max=a_max, j_max=j_max, tip_speed=tip_speed)

    def scaled(k: float) -> object:
        return run(v_max=np.asarray(v_max, float) / k, a_max=np.asarray(a_max, float) / k ** 2,
                   j_max=None if j_max is None else np.asarray(j_max, float) / k ** 3,
                   tip_speed=None if tip_speed is None else tip_speed / k)

    return force_limited(traj, scaled, masses=masses, f_max=f_max, fixed_times=fixed_times,
                         backend=backend)
