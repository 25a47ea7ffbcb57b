"""The app's inverse kinematics: the tip from its angles and back, one drag step (inverse_step)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from .._dispatch import q_from_instrument, q_from_tool_tip
from .._typing import BoolArray, FloatArray
from .._validation import check_array, check_count, check_instance, check_scalar
from ..errors import InvalidInputError, Reason
from ..robot import InstrumentIK
from ._model import INVERSE_STEPS, AppSetup


def tip_from_angles(azimuth: float, polar: float, depth: float) -> FloatArray:
    """Tool tip in frame E from the instrument's angles about the RCM and the depth.

    Parameters
    ----------
    azimuth, polar : float
        Radians (:func:`~athenakin.direction_from_angles`).
    depth : float
        Distance of the tip beyond the RCM, m (``|tip_e|``).

    Returns
    -------
    ndarray, shape (3,)

    Raises
    ------
    TypeError, InvalidInputError
        An angle is not a finite number, or ``depth`` is negative.
    """
    from ..robot import direction_from_angles

    az = check_scalar(azimuth, "azimuth")
    pol = check_scalar(polar, "polar")
    dep = check_scalar(depth, "depth", nonnegative=True)
    return dep * direction_from_angles(az, pol)


def angles_from_tip(tip_e: ArrayLike) -> tuple[float, float, float]:
    """``(azimuth, polar, depth)`` of a tool tip in frame E (rad, rad, m).

    The inverse of :func:`tip_from_angles` (azimuth 0 on the poles, all 0 at the RCM).

    Parameters
    ----------
    tip_e : array-like, shape (3,)
        Tool tip in the RCM frame E, m; finite.

    Returns
    -------
    azimuth, polar : float
        Radians (:func:`~athenakin.robot.angles_from_direction`).
    depth : float
        ``|tip_e|``, m.
    """
    from ..robot import angles_from_direction

    tip = check_array(tip_e, "tip_e", (3,))
    if tip.shape != (3,):
        raise InvalidInputError(f"tip_e: expected shape (3,), got shape {tip.shape}")
    depth = float(np.linalg.norm(tip))
    if not math.isfinite(depth):
        raise InvalidInputError(f"tip_e: expected a tip within the float range, got "
                                f"{tip.tolist()}")
    if depth == 0:
        return 0.0, 0.0, 0.0
    az, pol = angles_from_direction(tip)
    return float(az), float(pol), depth


@dataclasses.dataclass(frozen=True)
class InverseStep:
    """Result of :func:`inverse_step`.

    Attributes
    ----------
    q : ndarray, shape (3,)
        New actuator values, m (the previous ones where nothing could be reached).
    tip_e : ndarray, shape (3,)
        Tool tip the actuators now hold, frame E, m.
    mode : int
        Assembly mode of ``q`` (+1 / -1).
    reached : bool
        The target itself was reached.
    reason : int
        :class:`~athenakin.errors.Reason` that stopped the motion (0 if reached or
        stopped by a collision).
    message : str
    collision : bool
        The motion stopped before the bodies would collide (``clearance`` of
        :func:`inverse_step`).
    """

    q: FloatArray
    tip_e: FloatArray
    mode: int
    reached: bool
    reason: int
    message: str
    collision: bool = False


#: Most samples of :func:`inverse_step` (checked before anything is allocated).
MAX_INVERSE_STEPS = 10_000


def inverse_step(setup: AppSetup, tip_from: ArrayLike, tip_to: ArrayLike, q_from: ArrayLike,
                 mode_from: int = 1, *, n: int = INVERSE_STEPS,
                 p_from: float | None = None,
                 clearance: Callable[[FloatArray], ArrayLike] | None = None
                 ) -> InverseStep:
    """Move the tool tip from where it is towards a target; the actuators follow, never jump.

    The straight segment ``tip_from -> tip_to`` (frame E) is sampled at ``n`` points
    and solved by the controller-form IK (:func:`~athenakin.q_from_tool_tip`). The
    actuators go to the last point before the first one that fails (out of the
    workspace, a stroke limit, the tip not beyond the RCM) or changes the assembly
    mode, so a target across the workspace boundary leaves the robot at the boundary.
    The motion stays on the branch of ``p`` it starts on (``p_from``): the inserted
    tool ``0 < p < L``, ``O_s`` beyond the RCM ``p < 0`` (the tip ``L - p > L`` from
    the RCM) or the tip behind the RCM ``p > L``; the two others are solved by
    :func:`~athenakin.q_from_instrument`, and the motion stops before ``p`` would reach
    0 or ``L``. With ``clearance``, it also stops before the bodies collide.

    Parameters
    ----------
    setup : AppSetup
    tip_from : array-like, shape (3,)
        Tip held now (frame E, m).
    tip_to : array-like, shape (3,)
        Target tip (frame E, m).
    q_from : array-like, shape (3,)
        Actuators now, m (returned unchanged if even the first step fails).
    mode_from : int
        Assembly mode now (+1 or -1).
    n : int, keyword-only
        Samples on the segment, 1 to :data:`MAX_INVERSE_STEPS`.
    p_from : float, keyword-only, optional
        Passive prismatic joint now, m (the drawn slot's ``p``): picks the branch.
        Default: the inserted tool, ``0 < p < L``.
    clearance : callable, keyword-only, optional
        ``clearance(q)``: least signed distance between the bodies (m, negative when
        they overlap) of configurations ``q`` of shape (k, 3) in the slot moved, shape
        (k,); e.g. the ``min_distance`` of :func:`athenakin.collision.clearance`. The
        motion stops before the first sample whose clearance is below 0 and below that
        of ``q_from``: a motion into a collision stops, one out of it goes on.

    Returns
    -------
    InverseStep
    """
    check_instance(setup, "setup", AppSetup)
    a = check_array(tip_from, "tip_from", (3,))
    b = check_array(tip_to, "tip_to", (3,))
    q0 = check_array(q_from, "q_from", (3,))
    for name, v in (("tip_from", a), ("tip_to", b), ("q_from", q0)):
        if v.shape != (3,):
            raise InvalidInputError(f"{name}: expected shape (3,), got shape {v.shape}")
    if isinstance(mode_from, bool) or not isinstance(mode_from, (int, np.integer)) \
            or mode_from not in (1, -1):
        raise InvalidInputError(f"mode_from: expected +1 or -1, got {mode_from!r}")
    mode_from = int(mode_from)
    n = check_count(n, "n", minimum=1, maximum=MAX_INVERSE_STEPS)
    if clearance is not None and not callable(clearance):
        raise InvalidInputError(f"clearance: expected a function of q or None, got "
                                f"{type(clearance).__name__}")
    L = setup.design.tool_length
    p0 = 0.5 * L if p_from is None else float(check_array(p_from, "p_from", ()))
    branch = 0 if 0.0 < p0 < L else (-1 if p0 <= 0.0 else 1)
    s = np.linspace(0.0, 1.0, int(n) + 1)[1:]
    tips = a + s[:, None] * (b - a)
    q, res, side = _solve_on_branch(setup, tips, branch)
    ok = side & np.asarray(res.valid) & (np.asarray(res.mode) == mode_from)
    hit = _collisions(clearance, q0, q, ok) if clearance is not None else np.zeros_like(ok)
    bad = np.flatnonzero(~ok | hit)
    if bad.size == 0:
        return InverseStep(q=q[-1].copy(), tip_e=b.copy(), mode=int(mode_from), reached=True,
                           reason=0, message="")
    k = int(bad[0])
    if hit[k]:
        return _stop_before(k, (q0, a), (q, tips), mode_from, 0, "the bodies would collide",
                            collision=True)
    r, why = _why_stopped(res, side, k, branch, L, mode_from)
    return _stop_before(k, (q0, a), (q, tips), mode_from, r, why)


def _solve_on_branch(setup: AppSetup, tips: FloatArray, branch: int
                     ) -> tuple[FloatArray, InstrumentIK, BoolArray]:
    """Actuators of the tips (frame E, shape (n, 3)) on one branch of ``p``.

    Returns
    -------
    q : ndarray, shape (n, 3)
    res : InstrumentIK
        The flagged solve (``valid``, ``mode``, ``reason``).
    side : ndarray of bool, shape (n,)
        The tip lies on the branch (``branch`` 0: the inserted tool ``0 < p < L``, always;
        -1: ``p < 0``, the tip farther than ``L`` from the RCM; +1: ``p > L``, the tip
        behind the RCM).
    """
    if branch == 0:
        q, res = q_from_tool_tip(setup.T_b_e, tips, setup.design, errors="flag",
                                 backend=setup.backend)
        return q, res, np.ones(len(tips), dtype=bool)
    L = setup.design.tool_length          # tip_e = (L - p) d
    depth = np.linalg.norm(tips, axis=-1)
    unit = np.where((depth > 0)[:, None], tips / np.where(depth > 0, depth, 1.0)[:, None],
                    np.array([0.0, 0.0, 1.0]))   # a tip at the RCM: off the branch anyway
    side = depth > L if branch < 0 else depth > 0
    p = np.where(side, L - depth, -1.0) if branch < 0 else L + depth
    q, res = q_from_instrument(setup.T_b_e, unit if branch < 0 else -unit, p,
                               setup.design, errors="flag", backend=setup.backend)
    return q, res, side


def _why_stopped(res: InstrumentIK, side: BoolArray, k: int, branch: int, L: float,
                 mode_from: int) -> tuple[int, str]:
    """The :class:`~athenakin.errors.Reason` code and the words for the failed sample ``k``."""
    r = int(res.reason[k]) if side[k] else int(
        Reason.SERIAL_P_ZERO if branch < 0 else Reason.INSERTION_RANGE)
    if not side[k] and branch < 0:
        why = (f"the branch p < 0 ends where the tip is the tool length L = {L * 1e3:.1f} mm "
               f"from the RCM (p = 0); pick a slot with p > 0 to come nearer")
    elif not side[k]:
        why = ("the branch p > L (tip behind the RCM) ends with the tip at the RCM; pick a "
               "slot with p < L to insert the tool")
    elif r:
        why = f"{Reason(r).name}: {Reason(r).description}"
    else:
        why = f"the assembly mode would change from {mode_from:+d}"
    return r, why


def _stop_before(k: int, start: tuple[FloatArray, FloatArray],
                 samples: tuple[FloatArray, FloatArray], mode: int,
                 reason: int, why: str, *, collision: bool = False) -> InverseStep:
    """The step that ends on the sample before ``k``; at ``k = 0`` the actuators are held.

    ``start`` is ``(q_from, tip_from)``, ``samples`` the solved ``(q, tips)`` of the segment.
    """
    if k == 0:
        return InverseStep(q=start[0].copy(), tip_e=start[1].copy(), mode=int(mode),
                           reached=False, reason=reason, collision=collision,
                           message=f"target out of reach ({why}); actuators held")
    message = ("stopped before a collision of the bodies" if collision
               else f"stopped at the workspace boundary ({why})")
    return InverseStep(q=samples[0][k - 1].copy(), tip_e=samples[1][k - 1].copy(),
                       mode=int(mode), reached=False, reason=reason, collision=collision,
                       message=message)


def _collisions(clearance: Callable[[FloatArray], ArrayLike],
                q0: FloatArray, q: FloatArray,
                ok: BoolArray) -> BoolArray:
    """Samples that ``clearance`` puts in a collision deeper than at ``q0``, shape (n,).

    Only samples solved (``ok``) count.
    """
    qs = np.concatenate([q0[None], np.where(ok[:, None], q, q0)])
    d = np.asarray(clearance(qs), dtype=float)
    if d.shape != (len(qs),):
        raise InvalidInputError(f"clearance: expected shape ({len(qs)},) for q of shape "
                                f"{qs.shape}, got shape {d.shape}")
    floor = min(0.0, float(d[0])) if np.isfinite(d[0]) else 0.0
    return ok & ~(d[1:] >= floor)
