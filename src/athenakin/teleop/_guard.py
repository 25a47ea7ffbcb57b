"""The bodies' clearance for the teleoperation limiter (private).

One :class:`~athenakin.collision._workspace.ClearanceWorkspace` per pose kept (the
committed pose and the trial one, swapped on a commit: no copy), the body segments
placed from a tracked pose by the one formula of the mechanism's points
(:func:`athenakin._mechanism_formulas.mechanism_points_formula`: compiled in
:mod:`athenakin.teleop._kernels`, on Python floats in
:meth:`athenakin.motion._clearance.PoseClearance.points`, on arrays in
:func:`athenakin._mechanism.mechanism_points`), and the first-order change of every
pair's distance along a step from the witness points of the committed pose.

Where the work goes, and the saving. Profiled on the free-motion case of
``benchmarks/bench_teleop.py guard`` (``Bodies.default`` and three obstacles: 92 columns,
one clearance evaluation a cycle, no coal call; each piece switched off in turn, CPU time
per cycle beside the plain chain's 40 us in the same run), the guard added about 10 us a
cycle and the tip fixtures about 4: the capsule kernel over all 92 columns 4-5 us, the
body placement 2 us, the first-order limit 1-2 us, the rest Python. Only a few pairs
(0.8 on average, 3 at the 99th percentile) are ever within the exact band of the floor;
the others need no exact distance. So each evaluation carries a lower bound from the
committed pose's (:meth:`ClearanceWorkspace.evaluate` with ``since``: a pair's distance
there, less the largest end-point displacements of its two bodies since; the reasoning
in :mod:`athenakin.collision._workspace`) and evaluates exactly only the columns whose
bound is below ``floor + band`` (the kernel's arguments built once). The first-order
limit is not computed where no pair is within the step's reach of the floor (the
limiter's ``far``); the fixtures' distances carry a bound too (:mod:`._mapping`).

What is exact when: every pair's distance below ``floor + band``, so the least clearance
of a pose (:attr:`BodyGuard.clearance`, a command's ``clearance``) is exact wherever it
is below ``floor + band`` and a lower bound above it (never above the exact one).
``band`` is :data:`EXACT_BAND_M`, or more where the limiter's floor can rise higher (its
braking room at ``v_max``, :class:`~athenakin.teleop.Teleop`): the first-order limit
below then reads only exact columns, and treats a carried bound as a pair that closes at
the sum of its bodies' end-point displacements. The limiter's decisions are those of
exact distances (a carried bound is above every floor it is compared with) unless a pair
closes by more than the band less the braking room within one cycle: the first-order
limit and the secant then start from the bound, still a lower bound.

The gradient. For a pair of solids ``a, b`` at signed distance ``d`` with witness points
``w_a, w_b`` (``w_b - w_a = d n``, ``n`` the unit normal from ``a`` to ``b``, for either
sign of ``d``), a step that moves the material points under the witnesses by ``dw_a``,
``dw_b`` changes ``d`` by ``n . (dw_b - dw_a)`` to first order. A witness point's
displacement is interpolated along its body's segment from the two end points'
displacements (a rigid body's points move affinely along its axis to first order).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._typing import FloatArray

__all__ = ["BodyGuard", "EXACT_BAND_M", "NORMAL_TOL_M"]

#: Band above the guard's floor within which every distance is exact (coal for boxes and
#: meshes), m; farther, a bounding-sphere lower bound may stand in.
EXACT_BAND_M = 0.02
#: Pairs closer than this to contact (|d|, m) have no reliable normal from their
#: witnesses: their step limit is the exact check alone.
NORMAL_TOL_M = 1e-9


class BodyGuard:
    """Clearance of a tracked pose's bodies and the step fraction that keeps it.

    Parameters
    ----------
    design, T_b_e
        The robot.
    bodies : Bodies
    environment : Environment or None
    backend : {"auto", "numpy", "numba"}
        The capsule kernel's backend.
    floor : float
        Least clearance the guard keeps (m), the exact band's base.
    band : float
        Every distance below ``floor + band`` is exact (m, at least :data:`EXACT_BAND_M`).

    Attributes
    ----------
    exact_below : float
        ``floor + band``, m: the least clearance is exact below it, a lower bound above.
    """

    def __init__(self, design: Any, T_b_e: FloatArray, bodies: Any, environment: Any, *,
                 backend: str, floor: float, band: float = EXACT_BAND_M) -> None:
        from ..collision._workspace import ClearanceWorkspace
        from ..motion._clearance import PoseClearance

        self._pc = PoseClearance(design, T_b_e, bodies, backend=backend)
        self.exact_below = floor + max(band, EXACT_BAND_M)
        self._cur = ClearanceWorkspace(bodies, environment, backend=backend,
                                       exact_below=self.exact_below)
        self._try = self._cur.twin()
        self.pairs = self._cur.pairs
        self._body = self._cur.body
        self.evaluations = 0             # clearance evaluations of the current cycle
        self.clearance = math.nan        # the committed pose's least clearance, m
        self.closest = -1
        self._seg = np.empty_like(self._cur.segments)
        self._compiled = self._cur.compiled
        if self._compiled:
            from . import _kernels

            self._kernels = _kernels
        pc = self._pc
        self._G = np.array([pc.l1, *pc.G, *pc.rcm, *pc.ze], dtype=np.float64)
        self._index = np.ascontiguousarray(pc.index, dtype=np.intp)
        self._pts = np.empty((19, 3))

    def segments(self, pose: Any) -> FloatArray:
        """The body segments of a tracked pose into the trial buffer, shape (n_bodies, 2, 3)."""
        seg = self._try.segments
        if self._compiled:
            q, u, o = pose.q, pose.u, pose.O_s
            self._kernels.place_segments(q[0], q[1], pose.p, u[0], u[1], u[2], o[0], o[1],
                                         o[2], self._G, self._index, self._pts, seg)
            return seg
        pts = self._pc.points(pose.q, pose.p, pose.u, pose.O_s)
        np.take(pts, self._index, axis=0, out=seg)
        return seg

    def evaluate(self, pose: Any, *, placed: bool = False) -> float:
        """Least clearance of ``pose`` (m; the trial buffer), one evaluation counted.

        Exact below :attr:`exact_below`, a lower bound above: the bounds carried from the
        committed pose's evaluation (none before the first commit).
        ``placed``: :meth:`fraction` has just placed this pose's segments.
        """
        if not placed:
            self.segments(pose)
        self.evaluations += 1
        d, k = self._try.evaluate(since=self._cur)
        self._try_result = (d, k)
        return d

    def commit(self) -> None:
        """The last evaluated pose becomes the committed one (the buffers swap)."""
        self._cur, self._try = self._try, self._cur
        self.clearance, self.closest = self._try_result

    def start(self, pose: Any) -> float:
        """Evaluate and commit ``pose`` (the start or a reset); its least clearance, m."""
        self.evaluate(pose)
        self.commit()
        return self.clearance

    def trial_pair(self) -> tuple[str, str]:
        """The names of the last evaluated pose's closest pair (``("", "")`` with none)."""
        k = self._try_result[1]
        return self.pairs[k] if k >= 0 else ("", "")

    def closest_pair(self) -> tuple[str, str]:
        """The names of the committed pose's closest pair (``("", "")`` with none)."""
        return self.pairs[self.closest] if self.closest >= 0 else ("", "")

    def fraction(self, pose: Any, floor: float, slack: float, *, far: bool = False) -> float:
        """The fraction of the step to ``pose`` that keeps every pair above ``floor`` (m).

        First order, from the committed pose's witness points and the segments of
        ``pose`` (placed here, not evaluated). A pair already below ``floor`` may not
        come closer; one above may come down to ``floor + slack``. Pairs that no step
        of this length can bring to ``floor`` (farther than twice the largest end-point
        displacement) are not looked at. A pair whose committed distance is a carried
        bound (no witness points) closes at most at the sum of its two bodies' largest
        end-point displacements. Returns a fraction in [0, 1]; 1 without a look with
        ``far`` (the caller knows every pair far from ``floor``).
        """
        seg1 = self.segments(pose)
        if far:
            return 1.0
        cur = self._cur
        seg0 = cur.segments
        if self._compiled:
            return float(self._kernels.step_fraction(seg0, seg1, cur.distances, cur.witness_points,
                                          cur.exact, self._body, floor, slack, NORMAL_TOL_M))
        disp = np.subtract(seg1, seg0, out=self._seg)
        move = np.sqrt(np.einsum("ijk,ijk->ij", disp, disp)).max(axis=1)
        reach = 2.0 * float(move.max())
        d0 = cur.distances
        near = np.flatnonzero(d0 < floor + slack + reach)
        if not len(near):
            return 1.0
        k = near
        d = d0[k]
        w = cur.witness_points[k]
        body = self._body[k]
        wa, wb = w[:, 0], w[:, 1]
        dwa = _witness_motion(seg0, disp, body[:, 0], wa)
        dwb = _witness_motion(seg0, disp, np.maximum(body[:, 1], 0), wb)
        dwb[body[:, 1] < 0] = 0.0                   # an obstacle does not move
        ok = np.abs(d) > NORMAL_TOL_M
        with np.errstate(invalid="ignore", divide="ignore"):
            n = (wb - wa) / np.where(ok, d, 1.0)[:, None]
            rate = np.einsum("ij,ij->i", n, dwb - dwa)
            bound = ~cur.exact[k]                   # a carried bound: its largest closing
            rate[bound] = -(move[body[bound, 0]]
                            + np.where(body[bound, 1] < 0, 0.0, move[body[bound, 1]]))
            room = np.where(d > floor, d - floor - slack, 0.0)
            lam = np.where((rate < 0.0) & ok, np.maximum(room, 0.0) / -rate, 1.0)
        out = float(lam.min())
        return min(1.0, out) if out == out else 0.0


def _witness_motion(seg0: FloatArray, disp: FloatArray, i: Any, w: FloatArray) -> FloatArray:
    """Displacement of the material point under witness ``w`` of body ``i`` (rows), m."""
    a = seg0[i, 0]
    ab = seg0[i, 1] - a
    L2 = np.einsum("ij,ij->i", ab, ab)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(L2 > 0.0, np.einsum("ij,ij->i", w - a, ab) / np.where(L2 > 0, L2, 1.0), 0.0)
    t = np.clip(t, 0.0, 1.0)[:, None]
    return disp[i, 0] * (1.0 - t) + disp[i, 1] * t
