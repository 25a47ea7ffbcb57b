"""What the arm refuses: command vectors, positions, tips, and encoder readings (private).

The checks of :class:`~athenakin.teleop.SimulatedArm`, as functions of the values and the
model. A command check returns the reason a value is refused (a string naming it), or
None; the arm decides whether that reason is held and flagged (a servo command) or
raised (a planned move). A reading check returns the reason the arm faults. An argument
of the wrong shape is a programming error and raises :class:`InvalidInputError`.

Units: m, m/s; tips in the base frame or the RCM frame E.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from .._validation import check_array, check_choice
from ..design import Design
from ..errors import InvalidInputError, Reason

__all__ = ["vector3", "position_refusal", "command_refusal", "q_from_tip", "TipFrames",
           "read_encoders",
           "READING_MARGIN", "READING_SPEED_MAX", "VELOCITY_SLACK"]

#: Relative slack of a command's velocity over ``v_max`` (a limiter's rounding), 1.
VELOCITY_SLACK = 1e-9

#: How far beyond the strokes an encoder reading may lie before the arm faults, m.
READING_MARGIN = 0.005
#: Fastest actuator speed a reading may report before the arm faults, m/s.
READING_SPEED_MAX = 10.0


def vector3(x: ArrayLike, name: str, *, allow_nonfinite: bool = False) -> FloatArray:
    """``x`` as a float array of shape (3,) exactly (no batch); a named error otherwise.

    Parameters
    ----------
    x : array-like, shape (3,)
    name : str
        Its name in the error.
    allow_nonfinite : bool, keyword-only
        Keep NaN / inf (a value a command check refuses) instead of raising.

    Returns
    -------
    ndarray, shape (3,)
        A copy, float64.

    Raises
    ------
    InvalidInputError, TypeError
        Not a real array of shape (3,); NaN or inf unless allowed.
    """
    a = check_array(x, name, (3,), allow_nonfinite=allow_nonfinite)
    if a.shape != (3,):
        raise InvalidInputError(f"{name}: expected shape (3,), got {a.shape}")
    return np.array(a, dtype=float)


def position_refusal(q: FloatArray, design: Design, name: str) -> str | None:
    """Why ``q`` is no position to command (not finite, strokes, order), or None.

    Parameters
    ----------
    q : ndarray, shape (3,)
        Actuator positions, m.
    design : Design
    name : str
        Its name in the reason.

    Returns
    -------
    str or None
    """
    from .._mechanism_formulas import actuator_reason_formula, module_params

    # the parallel module's actuator checks of one triple, on Python floats
    code = int(actuator_reason_formula(float(q[0]), float(q[1]), float(q[2]),
                                       module_params(design)))
    if code == Reason.NONFINITE_INPUT:
        return f"{name}: expected finite values, got {q.tolist()}"
    if code == Reason.STROKE_LIMIT:
        return f"{name}: {q.tolist()} m is outside the stroke limits"
    if code == Reason.AB_ORDER:
        return (f"{name}: {q.tolist()} m has the carriages in the wrong order (the "
                f"design's ab_order is {design.ab_order})")
    return None


def command_refusal(q: FloatArray, velocity: FloatArray, design: Design, *,
                    velocity_name: str, v_max: float, effort: FloatArray | None = None,
                    max_force: float = math.inf) -> str | None:
    """Why a command's position, velocity and effort are refused, or None.

    Parameters
    ----------
    q : ndarray, shape (3,)
        Positions, m (named ``q``): :func:`position_refusal`.
    velocity : ndarray, shape (3,)
        m/s: finite, each ``|v_i| <= v_max`` (to a relative :data:`VELOCITY_SLACK`, the
        rounding of a velocity limited to exactly ``v_max``).
    design : Design
    velocity_name : str, keyword-only
        The velocity's name in the reason.
    v_max : float, keyword-only
        The arm's velocity limit, m/s.
    effort : ndarray, shape (3,), optional, keyword-only
        Feed-forward forces, N: each ``|f_i| <= max_force`` (NaN refused).
    max_force : float, keyword-only
        The arm's force limit, N.

    Returns
    -------
    str or None
    """
    why = position_refusal(q, design, "q")
    if why is None and not np.all(np.isfinite(velocity)):
        why = f"{velocity_name}: expected finite values, got {velocity.tolist()}"
    if why is None and not np.all(np.abs(velocity) <= v_max * (1.0 + VELOCITY_SLACK)):
        why = (f"{velocity_name}: {velocity.tolist()} m/s exceeds the arm's v_max "
               f"{v_max:g} m/s")
    if why is None and effort is not None and not np.all(np.abs(effort) <= max_force):
        why = f"effort: {effort.tolist()} N exceeds max_force {max_force:g} N"
    return why


def q_from_tip(tip: ArrayLike, frame: str, T_b_e: FloatArray,
               design: Design) -> tuple[FloatArray, str | None]:
    """The actuator positions of a tool-tip position (exact IK), or why it is out of reach.

    Parameters
    ----------
    tip : array-like, shape (3,) or (4, 4)
        Tip position (m), or a pose whose translation is taken, in ``frame``.
    frame : {"base", "rcm"}
    T_b_e : ndarray, shape (4, 4)
    design : Design

    Returns
    -------
    q : ndarray, shape (3,)
        m (zeros when out of reach).
    reason : str or None
        Why the tip is out of reach (the IK's reason), or None.

    Raises
    ------
    InvalidInputError, ValueError
        A tip of the wrong shape; a ``frame`` not in the list.
    """
    from .. import q_from_tool_tip

    check_choice(frame, "frame", ("base", "rcm"))
    x = np.asarray(tip, dtype=float)
    if x.shape == (4, 4):
        x = x[:3, 3]
    x = check_array(x, "tip", (3,), allow_nonfinite=True)
    if x.shape != (3,):
        raise InvalidInputError(f"tip: expected shape (3,) or (4, 4), got {x.shape}")
    if frame == "base":
        R, c = T_b_e[:3, :3], T_b_e[:3, 3]
        x = R.T @ (x - c)
    q, res = q_from_tool_tip(T_b_e, x, design, errors="flag")
    if not bool(np.all(res.valid)):
        return np.zeros(3), (f"tip: {x.tolist()} m (frame E) is out of reach "
                             f"({Reason(int(res.reason)).name})")
    return np.asarray(q, dtype=float), None


class TipFrames:
    """The tool-tip frame ``T_b_tip`` of actuator positions on one FK slot.

    The compiled kernels (:meth:`athenakin.fast.ControlLoop.fk_slot`) where the backend
    policy allows (equal bit for bit to :attr:`athenakin.FKSolution.T_b_tip` of the same
    kernels, ``tests/test_fast_edges.py``), else the numpy reference
    :func:`athenakin.forward_kinematics`.

    Parameters
    ----------
    T_b_e : ndarray, shape (4, 4)
    design : Design
    slot : int
        Checked by the caller.
    """

    def __init__(self, T_b_e: FloatArray, design: Design, slot: int) -> None:
        from .._backend import resolve_backend

        self.T_b_e, self.design, self.slot = T_b_e, design, slot
        self._loop: Any = None
        if resolve_backend("auto"):
            from ..fast import ControlLoop

            self._loop = ControlLoop(T_b_e, design)

    def __call__(self, q: FloatArray) -> FloatArray:
        """``T_b_tip`` of ``q`` (m), shape (4, 4), a new array; NaN where ``q`` does not assemble.

        Parameters
        ----------
        q : ndarray, shape (3,)
            Actuator positions, m.

        Returns
        -------
        ndarray, shape (4, 4)
        """
        if self._loop is not None:
            return self._loop.fk_slot(q, self.slot)[4].copy()
        from .. import forward_kinematics

        sol = forward_kinematics(q, self.T_b_e, self.design, errors="flag", backend="numpy")
        return np.array(sol.T_b_tip[self.slot], dtype=float)


def read_encoders(backend: Any, lo: FloatArray, hi: FloatArray
                  ) -> tuple[tuple[FloatArray, FloatArray] | None, str | None]:
    """Read a backend's encoders and check the reading.

    Parameters
    ----------
    backend : ArmBackend
        Its ``read_encoders()`` is called once.
    lo, hi : ndarray, shape (3,)
        The strokes, m.

    Returns
    -------
    reading : tuple of two ndarray, shape (3,), or None
        Positions (m) and velocities (m/s), copies; None when the reading is not sound.
    reason : str or None
        Why it is not: unreadable, of the wrong shape, not finite, beyond the strokes by
        more than :data:`READING_MARGIN`, faster than :data:`READING_SPEED_MAX`.
    """
    try:
        reading = backend.read_encoders()
        q, qd = reading
        q = np.asarray(q, dtype=float)
        qd = np.asarray(qd, dtype=float)
    except (TypeError, ValueError) as exc:
        return None, (f"encoders: expected (positions, velocities), got an unreadable value "
                      f"({exc})")
    if q.shape != (3,) or qd.shape != (3,):
        return None, (f"encoders: expected positions and velocities of shape (3,), got "
                      f"{q.shape} and {qd.shape}")
    # A sound reading passes these three comparisons (NaN fails each); a reading that
    # does not is told apart below.
    if ((q >= lo - READING_MARGIN).all() and (q <= hi + READING_MARGIN).all()
            and (np.abs(qd) <= READING_SPEED_MAX).all()):
        return (q.copy(), qd.copy()), None
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):
        return None, f"encoders: non-finite reading {q.tolist()} m, {qd.tolist()} m/s"
    if np.any(q < lo - READING_MARGIN) or np.any(q > hi + READING_MARGIN):
        return None, (f"encoders: {q.tolist()} m beyond the strokes by more than "
                      f"{READING_MARGIN:g} m")
    # finite and within the strokes, yet not sound: the speed is what failed
    return None, f"encoders: speed {qd.tolist()} m/s above {READING_SPEED_MAX:g} m/s"
