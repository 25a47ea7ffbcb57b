"""The teleoperation mapping: master sample -> target of the tool tip (private).

A mixin of :class:`athenakin.teleop.Teleop` (its state lives there): the sample's
checks, the registration ``p_e = R_e_m p_m``, the master interpolated between samples
for the filter, and the target's projections onto the insertion depth range and out of
the forbidden regions (tip fixtures), with the sliding along a fixture near it.

The fixtures' distance of a point far from them is not computed: a signed distance is
1-Lipschitz (each fixture's is, so their least is too), so the committed tip's distance
less a point's distance from the tip is a lower bound of the point's
(:meth:`_Mapping._fixture_bound`). Where that bound is at least ``fixture_margin``
(``+ SLIDE_BAND_M`` for a tip the limiter tries) every decision it feeds is the one the
exact distance gives: no projection, no flag, no slide. The committed tip's distance
(``_tip_fix``) is therefore exact below ``fixture_margin + SLIDE_BAND_M`` and a lower bound
above it, its normal then that of an earlier exact evaluation (read only below).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from ._options import _DEPTH, _FIXTURE, _INVALID

__all__ = ["MAX_MASTER_M", "SLIDE_BAND_M", "FIXTURE_PUSH_M", "FIXTURE_PUSHES"]

_V3 = tuple[float, float, float]
#: Largest master coordinate taken as a sample (beyond: ``INVALID``), m.
MAX_MASTER_M = 100.0
#: Distance beyond ``fixture_margin`` within which steps into a fixture slide along it, m.
SLIDE_BAND_M = 0.002
#: Extra distance a target is pushed out beyond ``fixture_margin`` (rounding), m.
FIXTURE_PUSH_M = 1e-9
#: Pushes of a target out of the fixtures before it is refused (fixtures that overlap).
FIXTURE_PUSHES = 4
_REAL = (int, float, np.integer, np.floating)
_SEQUENCES = (list, tuple)


def _real3(m: object) -> _V3 | None:
    """Three finite-or-not real numbers from a sample, None when it is not one.

    Strings, bytes, booleans and containers of them are no master position (``"123"``
    and ``b"abc"`` index into three characters or ints); nor is anything of another
    length, or an array of another shape or a non-numeric dtype.
    """
    if type(m) is np.ndarray:
        if m.shape != (3,) or m.dtype.kind not in "iuf":
            return None
        x, y, z = m.tolist()
        return float(x), float(y), float(z)
    if not isinstance(m, _SEQUENCES) or len(m) != 3:
        return None
    out = []
    for v in m:
        if type(v) is float:
            out.append(v)
        elif isinstance(v, _REAL) and not isinstance(v, (bool, np.bool_)):
            out.append(float(v))
        else:
            return None
    return out[0], out[1], out[2]


def clutch_state(clutch: object) -> bool | None:
    """The clutch as a bool: True / False, numpy booleans, 0 / 1; None when malformed."""
    if clutch is True or clutch is False:
        return clutch
    if isinstance(clutch, np.bool_):
        return bool(clutch)
    if isinstance(clutch, np.ndarray) and clutch.shape == () and clutch.dtype.kind in "biu":
        v = clutch.item()
        return bool(v) if v in (0, 1) else None
    if isinstance(clutch, (int, np.integer)) and clutch in (0, 1):
        return bool(clutch)
    return None


class _Mapping:
    """The mapping stage of :class:`~athenakin.teleop.Teleop` (see the module docstring)."""

    if TYPE_CHECKING:                  # the Teleop's state that this stage reads
        _R: tuple[tuple[float, ...], ...]
        _Tr: tuple[tuple[float, ...], ...]
        _t: float
        _t_sample: float
        _last_p: _V3 | None
        _step_p: _V3
        _dt_p: float
        _tip: _V3
        dt: float
        depth: tuple[float, float]
        options: Any
        _fixtures: Any
        _tip_fix: tuple[float, _V3, int]

    def _sample(self, t: object, m: object) -> tuple[float, _V3 | None, int]:
        """The cycle's time and the registered master position (None: no valid sample)."""
        flags = 0
        try:
            tt = float(t)  # type: ignore[arg-type]
        except (TypeError, ValueError, OverflowError):
            tt = math.nan
        if not (math.isfinite(tt) and tt >= self._t):
            flags |= _INVALID
            tt = self._t + self.dt if math.isfinite(self._t) else 0.0
            if m is not None:
                return tt, None, flags
        if m is None:
            return tt, None, flags
        try:
            v = _real3(m)
        except Exception:                # a sample whose own methods raise: no sample
            v = None
        if v is None:
            return tt, None, flags | _INVALID
        x, y, z = v
        if not (abs(x) <= MAX_MASTER_M and abs(y) <= MAX_MASTER_M and abs(z) <= MAX_MASTER_M):
            return tt, None, flags | _INVALID          # NaN, inf, or beyond any master
        R = self._R
        p = (R[0][0] * x + R[0][1] * y + R[0][2] * z, R[1][0] * x + R[1][1] * y + R[1][2] * z,
             R[2][0] * x + R[2][1] * y + R[2][2] * z)
        return tt, p, flags

    def _master_now(self, tt: float) -> _V3:
        """The master's position that the filter takes at cycle time ``tt``.

        A master sampled every cycle: its latest sample. A slower one (samples more than
        1.5 cycles apart, 100 Hz on a 1 kHz loop): the straight line between its last two
        samples, one sample interval late, so that the filter sees a continuous, piecewise
        linear motion instead of a staircase whose every step would be a velocity jump of
        the command (the acceleration limit would then hold the robot at each sample).
        The delay is the master's own interval, and only where it exceeds the cycle.
        """
        lp, sp, dt = self._last_p, self._step_p, self._dt_p
        assert lp is not None
        if not dt > 1.5 * self.dt:
            return lp
        k = min(tt - self._t_sample, dt) / dt - 1.0        # in [-1, 0]: one interval late
        return (lp[0] + k * sp[0], lp[1] + k * sp[1], lp[2] + k * sp[2])

    # --- frames ---------------------------------------------------------------------
    def _to_base(self, p: _V3) -> _V3:
        T = self._Tr
        return (T[0][0] * p[0] + T[0][1] * p[1] + T[0][2] * p[2] + T[0][3],
                T[1][0] * p[0] + T[1][1] * p[1] + T[1][2] * p[2] + T[1][3],
                T[2][0] * p[0] + T[2][1] * p[1] + T[2][2] * p[2] + T[2][3])

    def _to_e(self, p: _V3) -> _V3:
        T = self._Tr
        v = (p[0] - T[0][3], p[1] - T[1][3], p[2] - T[2][3])
        return (T[0][0] * v[0] + T[1][0] * v[1] + T[2][0] * v[2],
                T[0][1] * v[0] + T[1][1] * v[1] + T[2][1] * v[2],
                T[0][2] * v[0] + T[1][2] * v[1] + T[2][2] * v[2])

    # --- the target's projections ---------------------------------------------------------
    def _depth(self, g: _V3) -> tuple[_V3, int]:
        r = math.sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
        lo, hi = self.depth
        if lo <= r <= hi:
            return g, 0
        if not r > 0.0:
            return self._tip, _DEPTH
        k = (lo if r < lo else hi) / r
        return (g[0] * k, g[1] * k, g[2] * k), _DEPTH

    def _fixture_bound(self, x: _V3) -> float:
        """A lower bound of the fixtures' distance of ``x`` (frame E), m (module docstring)."""
        c = self._tip
        dx, dy, dz = x[0] - c[0], x[1] - c[1], x[2] - c[2]
        return self._tip_fix[0] - math.sqrt(dx * dx + dy * dy + dz * dz)

    def _fixture(self, g: _V3) -> tuple[_V3, int]:
        fx = self._fixtures
        m = self.options.fixture_margin
        if self._fixture_bound(g) >= m:           # far from every fixture: no projection
            return g, 0
        x = self._to_base(g)
        flags = 0
        for _ in range(FIXTURE_PUSHES):
            d, n, _i = fx.nearest(x)
            if d >= m:
                break
            flags = _FIXTURE
            k = m - d + FIXTURE_PUSH_M
            x = (x[0] + k * n[0], x[1] + k * n[1], x[2] + k * n[2])
        else:
            return self._tip, _FIXTURE
        if flags:
            g, f2 = self._depth(self._to_e(x))
            if f2:                      # the depth and the fixture disagree: no step
                return self._tip, flags | f2
        return g, flags

    def _slide(self, g: _V3) -> tuple[_V3, int]:
        """Near a forbidden region, drop the step's component into it (the tip slides)."""
        c = self._tip
        d, n, _ = self._tip_fix
        if not d < self.options.fixture_margin + SLIDE_BAND_M:
            return g, 0
        T = self._Tr                          # n in E: R^T n
        ne = (T[0][0] * n[0] + T[1][0] * n[1] + T[2][0] * n[2],
              T[0][1] * n[0] + T[1][1] * n[1] + T[2][1] * n[2],
              T[0][2] * n[0] + T[1][2] * n[1] + T[2][2] * n[2])
        dx = (g[0] - c[0], g[1] - c[1], g[2] - c[2])
        k = dx[0] * ne[0] + dx[1] * ne[1] + dx[2] * ne[2]
        if k >= 0.0:
            return g, 0
        g2 = (g[0] - k * ne[0], g[1] - k * ne[1], g[2] - k * ne[2])
        g2, f = self._depth(g2)
        return g2, _FIXTURE | f
