"""The teleoperation limiter: the longest safe step toward the target, with bounded work (private).

A mixin of :class:`athenakin.teleop.Teleop` (its state lives there). One cycle:

1. The direction. ``J = (d q / d tip_e) u``, joint metres per tip metre along the unit
   direction ``u`` from the commanded tip toward the target, from the closed-form
   tool-tip inverse Jacobian (:meth:`athenakin.fast.ControlLoop.tool_tip_inverse_jacobian`,
   or :func:`athenakin.analysis.tool_tip_inverse_jacobian` on the numpy backend).
2. The step length ``s`` in closed form, linear in ``J``: the velocity and acceleration
   limits (:meth:`_Limiter._bounds`) and the stroke less its margin.
3. The step is checked at most :data:`TRIES` times, one exact IK (``q_from_tool_tip``)
   and one pure tracker candidate (:meth:`athenakin.motion.Tracker.candidate`) each:
   the stroke and fixtures, the tracked branch, the singular-set margins, the velocity
   and acceleration of the exact ``q``, then the bodies' clearance: first its
   first-order limit from the committed pose's witness points
   (:meth:`~athenakin.teleop._guard.BodyGuard.fraction`, no evaluation), then one exact
   evaluation. A check that fails gives the next, shorter ``s`` by a secant of the
   quantity that failed (halving only where no quantity is linear: an IK that fails).
4. Nothing is committed until a step passes; no try changes state (no probe and
   revert).

The work per cycle is bounded: at most :data:`TRIES` IK + candidate pairs in the step,
one more in the brake, and at most :data:`CLEARANCE_EVALUATIONS` exact clearance
evaluations (:data:`STEP_EVALUATIONS` in the step, one in the brake).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import Reason
from ._mapping import SLIDE_BAND_M
from ._options import (
    _ACCELERATION,
    _CLEARANCE,
    _FIXTURE,
    _LIMIT_BITS,
    _SINGULAR,
    _STROKE,
    _VELOCITY,
)

__all__ = ["LIMIT_SLACK", "BRANCH_TOL", "TRIES", "STEP_EVALUATIONS", "CLEARANCE_EVALUATIONS",
           "CLEARANCE_GAIN", "CLEARANCE_SLACK_M", "SHORTEN", "JACOBIAN_TOL"]

_V3 = tuple[float, float, float]
#: Relative slack below the limits that the limiter aims at (rounding of the IK).
LIMIT_SLACK = 1e-6
#: Largest distance between the tracked forward kinematics and the commanded tip, m.
BRANCH_TOL = 1e-9
#: Tries of a step (one exact IK and one tracker candidate each) before the robot brakes.
TRIES = 4
#: Exact clearance evaluations in the step (the first-order limit first, then the check).
STEP_EVALUATIONS = 2
#: Bound K on the exact clearance evaluations of one cycle: the step's, and the brake's one.
CLEARANCE_EVALUATIONS = STEP_EVALUATIONS + 1
#: Bound on a body point's travel per metre of joint travel, for the clearance's braking room.
CLEARANCE_GAIN = 4.0
#: Distance below the clearance floor's target that a shortened step aims at, m.
CLEARANCE_SLACK_M = 1e-6
#: Factor of a secant's step (it aims just inside the limit that failed).
SHORTEN = 1.0 - 1e-6
#: Smallest ``|J_i| * distance`` (m) taken as a joint that moves.
JACOBIAN_TOL = 1e-15
_STROKE_REASONS = (int(Reason.STROKE_LIMIT), int(Reason.AB_ORDER), int(Reason.INSERTION_RANGE))


def _branch_flags() -> int:
    from ..motion import TrackFlag

    return int(TrackFlag.LOST | TrackFlag.MODE_SWITCH | TrackFlag.BRANCH_SWITCH
               | TrackFlag.JUMP)


_BRANCH_FLAGS = _branch_flags()


class _IK:
    """``q_from_tool_tip`` and ``d q / d tip_e`` on plain floats: compiled or the reference."""

    def __init__(self, T: np.ndarray, design: Any, compiled: bool) -> None:
        self.T, self.design = T, design
        self.ctl = None
        if compiled:
            from ..fast import ControlLoop

            self.ctl = ControlLoop(T, design)
            self.buf = np.empty(3)

    def __call__(self, x: float, y: float, z: float) -> tuple[float, float, float, int]:
        if self.ctl is not None:
            b = self.buf
            b[0], b[1], b[2] = x, y, z
            q, r = self.ctl.q_from_tool_tip(b)
            q0, q1, q2 = q.tolist()          # Python floats in one call
            return q0, q1, q2, int(r)
        from ..robot import q_from_tool_tip

        q, res = q_from_tool_tip(self.T, (x, y, z), self.design, errors="flag")
        return float(q[0]), float(q[1]), float(q[2]), int(res.reason)

    def along(self, q: _V3, mode: int, u: _V3) -> _V3:
        """``(d q / d tip_e) u`` at ``q`` (assembly ``mode``): joint m per tip m along ``u``."""
        if self.ctl is not None:
            J = self.ctl.tool_tip_inverse_jacobian(q, mode).tolist()
        else:
            from ..analysis import tool_tip_inverse_jacobian

            J = tool_tip_inverse_jacobian(np.array(q), self.T, self.design, mode=mode,
                                          frame="rcm", backend="numpy").tolist()
        return (J[0][0] * u[0] + J[0][1] * u[1] + J[0][2] * u[2],
                J[1][0] * u[0] + J[1][1] * u[1] + J[1][2] * u[2],
                J[2][0] * u[0] + J[2][1] * u[1] + J[2][2] * u[2])


class _Limiter:
    """The limiter stage of :class:`~athenakin.teleop.Teleop` (see the module docstring)."""

    if TYPE_CHECKING:                  # the Teleop's state and stages that this one uses
        _tip: _V3
        _q: _V3
        _qd: _V3
        _goal: _V3
        _pose: Any
        _ik: _IK
        _tracker: Any
        _guard: Any
        _lo: tuple[float, ...]
        _hi: tuple[float, ...]
        _hard_lo: tuple[float, ...]
        _hard_hi: tuple[float, ...]
        _v_aim: tuple[float, ...]
        _a_aim: tuple[float, ...]
        _link_max: float
        _has_fixtures: bool
        _clear_floor: float
        _fixtures: Any
        _tip_fix: tuple[float, _V3, int]
        _try_fix: tuple[_V3, tuple[float, _V3, int]]
        margins: Any
        options: Any
        rate: float
        dt: float
        v_max: tuple[float, ...]
        a_max: tuple[float, ...]

        def _brake(self, flags: int, tt: float) -> Any: ...
        def _stay(self, flags: int, tt: float) -> Any: ...
        def _accept(self, pose: Any, tip: _V3, flags: int, tt: float) -> Any: ...
        def _to_base(self, p: _V3) -> _V3: ...
        def _fixture_bound(self, x: _V3) -> float: ...

    def _advance(self, g: _V3, flags: int, tt: float) -> Any:
        """The longest safe step from the current tip toward ``g``, or a brake."""
        c, q = self._tip, self._q
        dx = (g[0] - c[0], g[1] - c[1], g[2] - c[2])
        ell = math.sqrt(dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2])
        if ell == 0.0:
            J = u = (0.0, 0.0, 0.0)
        else:
            u = (dx[0] / ell, dx[1] / ell, dx[2] / ell)
            J = self._ik.along(q, self._pose.mode, u)
            if not (math.isfinite(J[0]) and math.isfinite(J[1]) and math.isfinite(J[2])):
                return self._brake(flags | _SINGULAR, tt)
        gp = self._goal
        vg = max(0.0, (g[0] - gp[0]) * u[0] + (g[1] - gp[1]) * u[1] + (g[2] - gp[2]) * u[2])
        self._goal = g
        lo, hi, bind = self._bounds(J, ell, vg)
        if lo > hi:
            return self._brake(flags | _ACCELERATION, tt)
        hs = self._stroke_bound(J, ell)
        if hs < hi:
            if hs < lo:                         # no step keeps both: brake (flagged)
                return self._brake(flags | _STROKE, tt)
            hi, bind = hs, _STROKE
        if hi < ell:
            flags |= bind
        if hi <= 0.0:                          # no step: stop here (|v_i| <= a_max_i dt)
            return self._stay(flags, tt)
        guard = self._guard
        if guard is not None:
            guard.evaluations = 0
        s = hi
        reject = 0
        for _ in range(TRIES):
            tip = (c[0] + s * u[0], c[1] + s * u[1], c[2] + s * u[2])
            pose, f, s2 = self._try(tip, s, lo, J, ell, vg)
            if pose is not None:
                if s < ell and not (flags | reject) & _LIMIT_BITS:
                    reject |= bind or _VELOCITY       # every shortened step is flagged
                return self._accept(pose, tip, flags | reject, tt)
            reject |= f
            if not (lo <= s2 < s and s2 > 0.0):       # no shorter step along u: brake
                break
            s = s2
        return self._brake(flags | reject, tt)

    def _try(self, tip: _V3, s: float, lo: float, J: _V3, ell: float, vg: float
             ) -> tuple[Any, int, float]:
        """One try of the step ``s`` to ``tip``: ``(pose, 0, s)`` or ``(None, flag, next s)``."""
        half = lo + 0.5 * (s - lo)
        x, y, z, r = self._ik(tip[0], tip[1], tip[2])
        if r != 0:
            return None, _STROKE if r in _STROKE_REASONS else _SINGULAR, half
        qn = (x, y, z)
        f = self._soft_q(qn, tip)
        if f:
            return None, f, half
        pose = self._tracker.candidate(qn)
        te = pose.tip_e
        if (not pose.valid or int(pose.flags) & _BRANCH_FLAGS        # int: IntFlag's & is slow
                or abs(te[0] - tip[0]) + abs(te[1] - tip[1]) + abs(te[2] - tip[2]) > BRANCH_TOL):
            return None, _SINGULAR, half
        k = self._singular(pose)
        if k < 1.0:
            return None, _SINGULAR, lo + (s - lo) * max(0.0, k) * SHORTEN
        if not self._kin_ok(qn):
            # curvature: the joint motion of the exact step is not s J; its secant
            q0 = self._q
            Js = ((x - q0[0]) / s, (y - q0[1]) / s, (z - q0[2]) / s)
            lo2, hi2, bind = self._bounds(Js, ell, vg)
            return None, bind or _VELOCITY, hi2 if lo2 <= hi2 else half
        guard = self._guard
        if guard is None:
            return pose, 0, s
        room = CLEARANCE_GAIN * self._stopping(qn)
        floor = self._clear_floor + room
        # the first-order limit (it places the pose's segments) reads only the pairs within
        # the step's reach of the floor (twice a body point's largest travel: at most
        # CLEARANCE_GAIN times the joints'); with none there it is 1, not computed, and the
        # exact check below decides anyway
        q0 = self._q
        dq = max(abs(x - q0[0]), abs(y - q0[1]), abs(z - q0[2]))
        lam = guard.fraction(pose, floor, CLEARANCE_SLACK_M, far=guard.clearance > floor
                             + CLEARANCE_SLACK_M + 2.0 * CLEARANCE_GAIN * dq)
        if lam < 1.0:
            return None, _CLEARANCE, s * lam * SHORTEN
        if guard.evaluations >= STEP_EVALUATIONS:
            return None, _CLEARANCE, lo - 1.0
        d = guard.evaluate(pose, placed=True)
        c0 = guard.clearance
        margin = self.options.clearance_margin
        if d >= floor or (d >= c0 and d >= margin + room):
            return pose, 0, s
        if c0 > floor and d < c0:              # the secant of the least clearance
            return None, _CLEARANCE, s * (c0 - floor) / (c0 - d) * SHORTEN
        return None, _CLEARANCE, lo - 1.0

    def _bounds(self, J: _V3, ell: float, vg: float) -> tuple[float, float, int]:
        """Step lengths ``s`` (m along the tip's direction) within the limits, linear in ``J``.

        ``J``: joint metres per tip metre along the direction; ``ell``: distance to the
        target; ``vg``: the target's advance along the direction this cycle (m).
        Returns ``(lo, hi, the flag of the binding limit)``; ``lo > hi``: none.
        """
        dt = self.dt
        v = self._qd
        lo, hi = 0.0, ell
        bind = 0
        v_aim, a_aim = self._v_aim, self._a_aim
        for i in range(3):
            Ji = J[i]
            vm, am = v_aim[i], a_aim[i]
            if abs(Ji) * ell > JACOBIAN_TOL:
                aJ = abs(Ji)
                sv = vm * dt / aJ
                if sv < hi:
                    hi, bind = sv, _VELOCITY
                # approach: the joint can still stop at the (moving) target at a_max
                adt = am * dt
                w = adt * (math.sqrt(0.25 + 2.0 * aJ * ell / (adt * dt)) - 0.5)
                sa = vg + w * dt / aJ
                if sa < hi:
                    hi, bind = sa, _ACCELERATION
                s1 = (v[i] - adt) * dt / Ji
                s2 = (v[i] + adt) * dt / Ji
                a, b = (s1, s2) if s1 <= s2 else (s2, s1)
                if b < hi:
                    hi, bind = b, _ACCELERATION
                if a > lo:
                    lo = a
            elif abs(v[i]) > am * dt:
                lo = math.inf
        return lo, hi, bind

    def _stroke_bound(self, J: _V3, ell: float) -> float:
        """Longest step (m) whose linear joint motion ``s J`` stays within the soft strokes.

        A joint already beyond its soft limit may only move back (bound 0 outward).
        """
        q = self._q
        hs = math.inf
        for i in range(3):
            Ji = J[i]
            if abs(Ji) * ell <= JACOBIAN_TOL:
                continue
            room = (self._hi[i] - q[i]) / Ji if Ji > 0.0 else (self._lo[i] - q[i]) / Ji
            hs = min(hs, max(room, 0.0))
        return hs

    def _soft_q(self, q: _V3, tip: _V3) -> int:
        """Stroke and fixture flags that ``q`` / ``tip`` break *and* worsen (0: acceptable).

        A tip inside a forbidden region may move outward (not deeper). The fixtures'
        distance of ``tip`` is exact below ``fixture_margin + SLIDE_BAND_M``, a lower bound
        above (:meth:`~athenakin.teleop._mapping._Mapping._fixture_bound`).
        """
        qc = self._q
        flags = 0
        for i in range(3):
            lo, hi = self._lo[i], self._hi[i]
            if not self._hard_lo[i] <= q[i] <= self._hard_hi[i]:
                flags |= _STROKE
            elif (q[i] < lo and q[i] < qc[i]) or (q[i] > hi and q[i] > qc[i]):
                flags |= _STROKE
        if self._has_fixtures:
            fm = self.options.fixture_margin
            b = self._fixture_bound(tip)
            if b >= fm + SLIDE_BAND_M:                # far: the bound stands in (no flag)
                tf = self._tip_fix
                fix = (b, tf[1], tf[2])
            else:
                fix = self._fixtures.nearest(self._to_base(tip))
            self._try_fix = (tip, fix)               # the command's, if this step passes
            d = fix[0]
            if d < fm and d < self._tip_fix[0]:
                flags |= _FIXTURE
        return flags

    def _singular(self, pose: Any) -> float:
        """1 where ``pose`` keeps the singular-set margins, else the secant's step fraction.

        A margin may be broken if the step does not worsen it; for each measure that a
        step breaks and worsens, the fraction of the step at which its linear
        interpolation meets the margin (0 where the current pose is already within it).
        """
        cur = self._pose
        mg = self.margins
        L = self._link_max
        k = 1.0
        for m1, m0, lim in ((pose.half_chord, cur.half_chord, mg.half_chord),
                            (pose.h, cur.h, mg.h), (L - pose.h, L - cur.h, mg.link),
                            (pose.sin_u2, cur.sin_u2, mg.sin_u2),
                            (pose.sin_u4, cur.sin_u4, mg.sin_u4),
                            (abs(pose.p), abs(cur.p), mg.p)):
            if m1 < lim and m1 < m0:
                k = min(k, (m0 - lim) / (m0 - m1) if m0 > lim else 0.0)
        return k

    def _stopping(self, q: _V3) -> float:
        """Largest joint travel to brake at ``a_max`` from the step to ``q``, m."""
        rate = self.rate
        v = (abs(q[0] - self._q[0]) * rate, abs(q[1] - self._q[1]) * rate,
             abs(q[2] - self._q[2]) * rate)
        a = self.a_max
        t = max(v[0] / a[0], v[1] / a[1], v[2] / a[2])
        return 0.5 * t * max(v[0], v[1], v[2])

    def _kin_ok(self, q: _V3) -> bool:
        """``q`` keeps every ``|qd_i| <= v_max_i`` and ``|qdd_i| <= a_max_i``."""
        rate = self.rate
        for i in range(3):
            v = (q[i] - self._q[i]) * rate
            if abs(v) > self.v_max[i] or abs(v - self._qd[i]) * rate > self.a_max[i]:
                return False
        return True
