"""Sessions: any iterator of master samples through the core and the arm (private).

:func:`run_session`: ``(t, position, clutch)`` items (position None: no sample) ->
:class:`Teleop` -> :class:`SimulatedArm` (``servo_jp`` with velocity and effort
feed-forward), cycle by cycle; a :class:`SessionLog` of arrays. The robot's bodies are
checked against each other by default: a ``Teleop`` that checks no clearance is refused
unless ``check_bodies=False`` says so. A recorded master comes from
:func:`~athenakin.teleop.read_master` (:mod:`~athenakin.teleop._master_recording`); a
log goes to an MCAP file through :func:`~athenakin.teleop.write_session_mcap`
(:mod:`~athenakin.teleop._session_mcap`).

Frames and units: the master in its own frame (m); tips in the RCM frame E unless a name
says ``_b`` (base frame); actuators in m, m/s, m/s^2, N; time in s.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Iterable, Iterator
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._typing import BoolArray, FloatArray, Int8Array, IntArray
from .._validation import check_count
from ..errors import InvalidInputError
from ._options import TeleopStatus

__all__ = ["SessionLog", "run_session"]


@dataclasses.dataclass(frozen=True)
class SessionLog:
    """Every cycle of a session, as arrays (N cycles).

    Attributes
    ----------
    t : ndarray, shape (N,)
        s.
    master : ndarray, shape (N, 3)
        The master's sample in its own frame, m (NaN: no sample that cycle).
    clutch : ndarray of bool, shape (N,)
    target, tip : ndarray, shape (N, 3)
        The master's target and the commanded tip, RCM frame E, m.
    tip_b : ndarray, shape (N, 3)
        The commanded tip, base frame, m.
    measured_tip_b : ndarray, shape (N, 3)
        The arm's tip after the cycle, base frame, m (MuJoCo's site ``tool_tip`` for
        the simulated arm, else the forward kinematics of its encoders).
    q, qd, qdd, forces : ndarray, shape (N, 3)
        The commands (m, m/s, m/s^2, N).
    measured_q, measured_qd : ndarray, shape (N, 3)
        The arm's encoders after the cycle.
    status : ndarray of int64, shape (N,)
        :class:`TeleopStatus` bits.
    closure_error : ndarray, shape (N,)
        Largest loop-closure error of the simulation, m (NaN for other backends).
    clearance : ndarray, shape (N,)
        The core's least clearance of the bodies in the cycle, m (NaN: not checked).
    effort : ndarray, shape (N, 3)
        The force the arm applied in the cycle (PD + feed-forward, saturated), N; without
        an arm the feed-forward of the command.
    arm_state : ndarray of int8, shape (N,)
        Index in :data:`OPERATING_STATES` of the arm's state after the cycle (-1: no arm).
    slot : ndarray of int64, shape (N,)
        The commanded FK slot.
    tip_quat_b, measured_quat_b : ndarray, shape (N, 4)
        Orientation of the commanded and the measured tool-tip frame in the base frame
        (:attr:`athenakin.FKSolution.T_b_tip`), ``(x, y, z, w)`` (ROS order); NaN where the
        FK of ``q`` / ``measured_q`` does not assemble in the slot.
    start_ns : int or None
        Stamp of ``t = 0`` in ns since the epoch (a recording's first pose,
        :attr:`MasterRecording.start_ns`); None: ``t`` is taken as the stamp itself.
    """

    t: FloatArray
    master: FloatArray
    clutch: BoolArray
    target: FloatArray
    tip: FloatArray
    tip_b: FloatArray
    measured_tip_b: FloatArray
    q: FloatArray
    qd: FloatArray
    qdd: FloatArray
    forces: FloatArray
    measured_q: FloatArray
    measured_qd: FloatArray
    status: IntArray
    closure_error: FloatArray
    clearance: FloatArray
    effort: FloatArray
    arm_state: Int8Array
    slot: IntArray
    tip_quat_b: FloatArray
    measured_quat_b: FloatArray
    start_ns: int | None = None

    def __len__(self) -> int:
        """The number of cycles."""
        return int(self.t.shape[0])

    @property
    def tip_error(self) -> FloatArray:
        """``|measured_tip_b - tip_b|`` per cycle, m, shape (N,)."""
        return np.linalg.norm(self.measured_tip_b - self.tip_b, axis=-1)

    def counts(self) -> dict[str, int]:
        """Cycles that carry each :class:`TeleopStatus` flag.

        Returns
        -------
        dict
            Flag name -> cycles, for the flags that occur.
        """
        return {f.name: int(np.count_nonzero(self.status & int(f)))  # type: ignore[misc]
                for f in TeleopStatus if f and np.any(self.status & int(f))}


def run_session(tele: Any, arm: Any, master: Iterable[tuple[float, Any, bool]], *,
                max_cycles: int | None = None, check_bodies: bool = True) -> SessionLog:
    """Drive ``arm`` from ``master`` through ``tele``, one cycle per master item.

    The loop raises nowhere :meth:`Teleop.step` does not: a malformed item's position or
    clutch is the core's ``INVALID`` (logged NaN / not engaged), the arm holds and flags
    what it refuses (:attr:`SimulatedArm.refusal`) and faults on what it cannot trust.

    Parameters
    ----------
    tele : Teleop
        Checking the bodies' clearance (``bodies=``, or an ``environment``) unless
        ``check_bodies=False``.
    arm : SimulatedArm, or None
        ``ENABLED`` (call :meth:`SimulatedArm.enable` first). None: the commands only
        (``measured_*`` are the commands, ``closure_error`` NaN).
    master : iterable of (t, position, clutch)
        ``t`` in s; ``position`` (3,) in m in the master's frame, or None (no sample);
        ``clutch``: True while the tip follows the master. A :class:`MasterRecording`
        also gives the session its time base (:attr:`SessionLog.start_ns`).
    max_cycles : int, optional, keyword-only
        Stop after this many cycles (an endless master).
    check_bodies : bool, keyword-only
        True (default): refuse a ``tele`` that checks no clearance of the robot's bodies
        against each other. False: run without, explicitly.

    Returns
    -------
    SessionLog

    Raises
    ------
    TypeError
        ``tele``, ``arm`` or ``master`` of the wrong kind; a master item that is not a
        ``(t, position, clutch)`` triple.
    InvalidInputError
        ``tele`` checks no body clearance and ``check_bodies`` is True; ``arm`` is not
        ``ENABLED``; a bad ``max_cycles``; a recorded master's named errors (a gap longer
        than :data:`MAX_GAP_S`, a clutch button its Joy lacks) when they are met.
    """
    from ._arm import OPERATING_STATES, SimulatedArm
    from ._core import Teleop

    if not isinstance(tele, Teleop):
        raise TypeError(f"tele: expected an athenakin.teleop.Teleop, got {type(tele).__name__}")
    if arm is not None and not isinstance(arm, SimulatedArm):
        raise TypeError(f"arm: expected an athenakin.teleop.SimulatedArm or None, got "
                        f"{type(arm).__name__}")
    if not isinstance(check_bodies, bool):
        raise TypeError(f"check_bodies: expected a bool, got {type(check_bodies).__name__}")
    if max_cycles is not None:
        max_cycles = check_count(max_cycles, "max_cycles", minimum=0)
    items = _master_items(master, max_cycles)
    if check_bodies and not tele.checks_clearance:
        raise InvalidInputError("tele: checks no clearance of the robot's bodies; build it "
                                "with bodies=athenakin.collision.Bodies.default(design) (or "
                                "an environment), or pass check_bodies=False to run without")
    if arm is not None and arm.operating_state != "ENABLED":
        raise InvalidInputError(f"arm: the arm is {arm.operating_state}; call arm.enable() "
                                f"before the session")
    T = tele.T_b_e
    R, c = T[:3, :3], T[:3, 3]
    rows: list[tuple] = []
    sim = arm is not None and hasattr(arm.backend, "tip_b")
    state_index = {s: i for i, s in enumerate(OPERATING_STATES)}
    for t, pos, clutch in items:
        cmd = tele.step(t, pos, clutch)
        if arm is not None:
            mq, mqd, mtip, ce, eff = _servo(arm, cmd, sim)
            st = state_index[arm.operating_state]
        else:
            mq, mqd, ce, eff, st = cmd.q, cmd.qd, math.nan, cmd.forces, -1
            mtip = R @ np.asarray(cmd.tip) + c
        rows.append((cmd.t, _master_row(pos), _clutch_row(clutch), cmd.target, cmd.tip, cmd.q,
                     cmd.qd, cmd.qdd, cmd.forces, tuple(mq), tuple(mqd), tuple(mtip),
                     int(cmd.status), ce, float(cmd.clearance), tuple(eff), st,
                     int(cmd.slot)))
    start = getattr(master, "start_ns", None)
    return _session_log(rows, tele, None if start is None else int(start))


def _master_items(master: object, max_cycles: int | None
                  ) -> Iterator[tuple[float, Any, bool]]:
    """The ``(t, position, clutch)`` items of ``master`` (at most ``max_cycles``), checked."""
    try:
        items = iter(master)  # type: ignore[call-overload]
    except TypeError:
        raise TypeError(f"master: expected an iterable of (t, position, clutch), got "
                        f"{type(master).__name__}") from None
    return _unpacked(items if max_cycles is None else itertools.islice(items, max_cycles))


def _unpacked(items: Iterator[Any]) -> Iterator[tuple[float, Any, bool]]:
    for item in items:
        try:
            t, pos, clutch = item
        except (TypeError, ValueError):
            raise TypeError(f"master: expected items (t, position, clutch), got {item!r:.80}"
                            ) from None
        yield t, pos, clutch


def _servo(arm: Any, cmd: Any, sim: bool) -> tuple[Any, Any, Any, float, Any]:
    """Send ``cmd`` to ``arm`` and step it one cycle.

    Returns the measured ``q``, ``qd``, tip (base frame), closure error (NaN unless the
    MuJoCo backend reads it out) and the applied effort. The arm holds and flags what it
    refuses; nothing here raises for a command's values.
    """
    effort = cmd.forces if all(math.isfinite(f) for f in cmd.forces) else None
    arm.servo_jp(cmd.q, velocity=cmd.qd, effort=effort)
    arm.step(1)
    js = arm.measured_js()
    if sim:     # the MuJoCo backend's own read-outs (not in the ArmBackend protocol)
        backend: Any = arm.backend
        return js.position, js.velocity, backend.tip_b(), backend.closure_error(), js.effort
    return js.position, js.velocity, arm.measured_cp()[:3, 3], math.nan, js.effort


def _master_row(pos: object) -> tuple[float, ...]:
    """The master's sample as logged: three floats, NaN where it was none or malformed."""
    nan3 = (math.nan,) * 3
    if pos is None or isinstance(pos, (str, bytes, bytearray)):
        return nan3
    try:
        m = tuple(float(v) for v in pos)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        return nan3
    return m if len(m) == 3 else nan3


def _clutch_row(clutch: object) -> bool:
    """The clutch as logged: True only for a real boolean True (anything else: not engaged)."""
    return isinstance(clutch, (bool, np.bool_)) and bool(clutch)


def _session_log(rows: list[tuple], tele: Any, start_ns: int | None) -> SessionLog:
    """The rows of :func:`run_session` as arrays, with the orientations of their tips."""
    T = tele.T_b_e
    R, c = T[:3, :3], T[:3, 3]
    n = len(rows)

    def col(i: int, w: int | None = 3) -> NDArray[Any]:
        if w is None:
            return np.array([r[i] for r in rows])
        return np.array([r[i] for r in rows], dtype=float).reshape(n, w)

    tip = col(4)
    q, mq = col(5), col(9)
    slot = np.array([r[17] for r in rows], dtype=np.int64).reshape(n)
    return SessionLog(t=col(0, None).astype(float).reshape(n), master=col(1),
                      clutch=np.array([r[2] for r in rows], dtype=bool).reshape(n),
                      target=col(3), tip=tip, tip_b=tip @ R.T + c, measured_tip_b=col(11),
                      q=q, qd=col(6), qdd=col(7), forces=col(8), measured_q=mq,
                      measured_qd=col(10),
                      status=np.array([r[12] for r in rows], dtype=np.int64).reshape(n),
                      closure_error=np.array([r[13] for r in rows], dtype=float).reshape(n),
                      clearance=np.array([r[14] for r in rows], dtype=float).reshape(n),
                      effort=col(15),
                      arm_state=np.array([r[16] for r in rows], dtype=np.int8).reshape(n),
                      slot=slot, tip_quat_b=_tip_quaternions(q, slot, tele),
                      measured_quat_b=_tip_quaternions(mq, slot, tele), start_ns=start_ns)


def _tip_quaternions(q: FloatArray, slot: IntArray, tele: Any) -> FloatArray:
    """``(x, y, z, w)`` of the tool-tip frames of ``q`` (N, 3) in their slots; NaN if none."""
    from .._dispatch import forward_kinematics
    from ..study._study import _quaternion_from_rotation

    out = np.full((len(q), 4), np.nan)
    if not len(q):
        return out
    ok = np.all(np.isfinite(q), axis=-1)
    if not ok.any():
        return out
    sol = forward_kinematics(q[ok], tele.T_b_e, tele.design, errors="flag")
    Rt = np.asarray(sol.T_b_tip)[np.arange(int(ok.sum())), slot[ok], :3, :3]
    good = np.all(np.isfinite(Rt), axis=(-2, -1))
    x = np.full((len(Rt), 4), np.nan)
    if good.any():
        x0 = _quaternion_from_rotation(Rt[good])              # (x0, x1, x2, x3), x0 scalar
        x0 = np.where(x0[:, :1] < 0, -x0, x0)
        x[good] = x0[:, [1, 2, 3, 0]]
    out[ok] = x
    return out

