"""The teleoperation brake and the cycle's command (private).

A mixin of :class:`athenakin.teleop.Teleop` (its state lives there): a step that
passed the limiter becomes the command (:meth:`_Brake._accept`: the tracker and the
clearance guard commit to it); where no step along the tip's direction keeps the
limits, the robot brakes along its own velocity at ``a_max`` (a category-2 stop,
:meth:`_Brake._brake`) and holds at rest (:meth:`_Brake._stay`); the feed-forward of
the command (:meth:`_Brake._forces`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, NamedTuple

from ._options import _ACCELERATION, _HOLD, TeleopStatus

__all__ = ["TeleopCommand"]

_V3 = tuple[float, float, float]
_NAN3 = (math.nan, math.nan, math.nan)


class TeleopCommand(NamedTuple):
    """The command of one cycle (an immutable named tuple of plain floats).

    A named tuple, as :class:`athenakin.motion.TrackedPose`: building it costs a fraction
    of a microsecond, a frozen dataclass several. Wrap the vectors with ``np.asarray``.

    Attributes
    ----------
    t : float
        Time of the cycle, s.
    q, qd, qdd : tuple of 3 float
        Actuator positions (m), velocities (m/s), accelerations (m/s^2) to servo.
    forces : tuple of 3 float
        Feed-forward actuator forces (N, positive along increasing ``q``): gravity and
        inertia of ``(q, qd, qdd)``; NaN with ``feedforward=False``.
    tip : tuple of 3 float
        The commanded tool tip in the RCM frame E, m (as ``q_from_tool_tip`` takes it);
        it is the forward kinematics of ``q`` on the tracked slot.
    target : tuple of 3 float
        The master's target for the tip (frame E, m) after the mapping and the filter,
        before the safety layer.
    status : TeleopStatus
    slot : int
        The tracked forward-kinematics slot of ``q``.
    clearance : float
        Least clearance of the bodies (m), exact wherever it is within
        ``clearance_margin + clearance_buffer + EXACT_BAND_M`` (2 cm) of contact (the band
        wider, ``CLEARANCE_GAIN * stopping_distance + CLEARANCE_SLACK_M``, where that is
        more); farther, a lower bound: a box or mesh obstacle's bounding sphere, or a
        pair's distance at an earlier exact evaluation less its two bodies' largest
        end-point displacements since. Never above the exact clearance. NaN when not
        checked.
    """

    t: float
    q: _V3
    qd: _V3
    qdd: _V3
    forces: _V3
    tip: _V3
    target: _V3
    status: TeleopStatus
    slot: int
    clearance: float


#: The TeleopStatus of each combination of bits met so far (at most 2^14): building an
#: IntFlag from an int costs about a microsecond, a dict look-up a few tens of ns.
_STATUSES: dict[int, TeleopStatus] = {0: TeleopStatus.NONE}


def _status(flags: int) -> TeleopStatus:
    st = _STATUSES[flags] = TeleopStatus(flags)
    return st


class _Brake:
    """The brake and command stage of :class:`~athenakin.teleop.Teleop`."""

    if TYPE_CHECKING:
        _q: _V3
        _qd: _V3
        _qdd: _V3
        _tip: _V3
        _target: _V3
        _pose: Any
        _slot: int
        _tracker: Any
        _guard: Any
        _masses: Any
        _gravity: Any
        _ff_key: tuple | None
        _ff: _V3
        _ff_loops: dict[int, Any]
        _a_aim: tuple[float, ...]
        _hard_lo: tuple[float, ...]
        _hard_hi: tuple[float, ...]
        _has_fixtures: bool
        _clear_floor: float
        _fixtures: Any
        _tip_fix: tuple[float, _V3, int]
        _try_fix: tuple[_V3, tuple[float, _V3, int]]
        _backend: str
        options: Any
        design: Any
        T_b_e: Any
        rate: float
        dt: float

        def _to_base(self, p: _V3) -> _V3: ...

    def _accept(self, pose: Any, tip: _V3, flags: int, tt: float) -> TeleopCommand:
        """Command ``pose`` (a tracker candidate that passed): commit it, and its clearance."""
        rate = self.rate
        q = pose.q
        qd = ((q[0] - self._q[0]) * rate, (q[1] - self._q[1]) * rate,
              (q[2] - self._q[2]) * rate)
        qdd = ((qd[0] - self._qd[0]) * rate, (qd[1] - self._qd[1]) * rate,
               (qd[2] - self._qd[2]) * rate)
        self._tracker.commit(pose)
        if self._guard is not None:
            self._guard.commit()
        self._q, self._qd, self._qdd = q, qd, qdd
        self._tip, self._pose, self._slot = tip, pose, pose.slot
        if self._has_fixtures:
            tried = self._try_fix
            self._tip_fix = (tried[1] if tried[0] is tip
                             else self._fixtures.nearest(self._to_base(tip)))
        return self._command(tt, flags)

    def _stay(self, flags: int, tt: float) -> TeleopCommand:
        """Come to rest at the current command (every ``|qd_i| <= a_max_i dt``)."""
        rate = self.rate
        self._qdd = (-self._qd[0] * rate, -self._qd[1] * rate, -self._qd[2] * rate)
        self._qd = (0.0, 0.0, 0.0)
        return self._command(tt, flags)

    def _brake(self, flags: int, tt: float) -> TeleopCommand:
        """Decelerate along the current velocity at ``a_max`` (rest: hold)."""
        flags |= _HOLD
        v = self._qd
        f = 1.0
        for i in range(3):
            if v[i] != 0.0:
                f = min(f, self._a_aim[i] * self.dt / abs(v[i]))
        f = max(0.0, 1.0 - f) if v != (0.0, 0.0, 0.0) else 0.0
        q0 = self._q
        if f > 0.0:
            qd = (f * v[0], f * v[1], f * v[2])
            q = (q0[0] + qd[0] * self.dt, q0[1] + qd[1] * self.dt, q0[2] + qd[2] * self.dt)
            pose = self._tracker.candidate(q)
            ok = pose.valid and all(lo <= x <= hi for lo, x, hi in
                                    zip(self._hard_lo, q, self._hard_hi, strict=True))
            if ok and self._has_fixtures:
                d = self._fixtures.nearest(self._to_base(pose.tip_e))[0]
                ok = d >= 0.0 or d >= self._tip_fix[0]
            if ok and self._guard is not None:
                c = self._guard.evaluate(pose)
                ok = c >= self.options.clearance_margin or c >= self._guard.clearance
            if ok:
                return self._accept(pose, tuple(pose.tip_e), flags, tt)
            flags |= _ACCELERATION             # a hard limit: stop now (flagged)
        return self._stay(flags, tt)

    def _command(self, tt: float, flags: int) -> TeleopCommand:
        forces = _NAN3
        if self._masses is not None:
            forces = self._forces()
        st = _STATUSES.get(flags)
        if st is None:
            st = _status(flags)
        g = self._guard
        return TeleopCommand(tt, self._q, self._qd, self._qdd, forces, self._tip, self._target,
                             st, self._slot, math.nan if g is None else g.clearance)

    def _forces(self) -> _V3:
        key = (self._q, self._qd, self._qdd, self._slot)
        if key == self._ff_key:                # at rest or held: the same state, same forces
            return self._ff
        self._ff_key = key
        loop = self._ff_loops.get(self._slot)
        if loop is None:
            from ..dynamics import InverseDynamicsLoop

            loop = self._ff_loops[self._slot] = InverseDynamicsLoop(
                self.T_b_e, self.design, masses=self._masses, gravity=self._gravity,
                slot=self._slot, backend=self._backend)
        f = loop(self._q, self._qd, self._qdd)  # NaN on a singular set: no feed-forward
        f0, f1, f2 = f.tolist()
        self._ff = (f0, f1, f2)
        return self._ff
