"""Virtual fixtures: obstacles of an Environment as forbidden regions for the tool tip (private).

A point's signed distance to each primitive shape in closed form (halfspace, sphere,
capsule, box; base frame, m, negative inside) with the outward unit normal, on plain
floats (no allocation, no numpy in the loop). An obstacle that allows the
``instrument`` body (``allow=``) is no fixture for its tip. A mesh obstacle is not a tip fixture:
it enters through the bodies' clearance (:mod:`athenakin.collision`), which covers
the instrument's capsule and so its tip.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["TipFixtures"]

_Vec = tuple[float, float, float]


def _sub(a: _Vec, b: _Vec) -> _Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _dot(a: _Vec, b: _Vec) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _radial(v: _Vec, r: float, fallback: _Vec) -> tuple[float, _Vec]:
    """Signed distance ``|v| - r`` and the unit of ``v`` (``fallback`` at ``v = 0``)."""
    n = math.sqrt(_dot(v, v))
    if n > 0.0:
        return n - r, (v[0] / n, v[1] / n, v[2] / n)
    return -r, fallback


class TipFixtures:
    """The primitive obstacles of an environment, ready for per-cycle distances.

    Parameters
    ----------
    environment : athenakin.collision.Environment or None
    compiled : bool, keyword-only
        :meth:`nearest` through the compiled kernel
        (:func:`athenakin.teleop._kernels.fixture_nearest`, the same formulas) instead of
        the scalar Python below, its reference (default False).
    """

    def __init__(self, environment: object, *, compiled: bool = False) -> None:
        if environment is not None:
            from ..collision import Environment

            if not isinstance(environment, Environment):
                raise TypeError(f"environment: expected athenakin.collision.Environment or "
                                f"None, got {type(environment).__name__}")
        shapes: list[tuple] = []
        names: list[str] = []
        for o in () if environment is None else environment.obstacles:  # type: ignore[attr-defined]
            if "instrument" in o.allow:      # the instrument (and its tip) may cross it
                continue
            if o.kind == "halfspace":
                shapes.append((0, tuple(o.point), tuple(o.normal)))
            elif o.kind == "sphere":
                shapes.append((1, tuple(o.center), float(o.radius)))
            elif o.kind == "capsule":
                a = (float(o.a[0]), float(o.a[1]), float(o.a[2]))
                b = (float(o.b[0]), float(o.b[1]), float(o.b[2]))
                ab = _sub(b, a)
                shapes.append((2, a, ab, _dot(ab, ab), float(o.radius)))
            elif o.kind == "box":
                T = o.T_b_o
                R = tuple(tuple(float(T[i, j]) for j in range(3)) for i in range(3))
                c = (float(T[0, 3]), float(T[1, 3]), float(T[2, 3]))
                shapes.append((3, c, R, tuple(float(h) for h in o.half_extents)))
            else:
                continue
            names.append(o.name)
        self.shapes = tuple(shapes)
        self.names = tuple(names)
        self._kernel = None
        if compiled and shapes:
            from ._kernels import fixture_nearest

            self._kernel = fixture_nearest
            self._table = _table(self.shapes)

    def __len__(self) -> int:
        return len(self.shapes)

    def nearest(self, x: _Vec) -> tuple[float, _Vec, int]:
        """Least signed distance of point ``x`` (base frame, m), its outward normal, index.

        ``(inf, (0, 0, 1), -1)`` without fixtures.
        """
        if self._kernel is not None:
            d, n0, n1, n2, i = self._kernel(x[0], x[1], x[2], self._table)
            return d, (n0, n1, n2), i
        best, nb, ib = math.inf, (0.0, 0.0, 1.0), -1
        for i, s in enumerate(self.shapes):
            d, n = self._one(s, x)
            if d < best:
                best, nb, ib = d, n, i
        return best, nb, ib

    @staticmethod
    def _one(s: tuple, x: _Vec) -> tuple[float, _Vec]:
        kind = s[0]
        if kind == 0:                                  # halfspace: n . (x - p)
            n = s[2]
            return _dot(n, _sub(x, s[1])), n
        if kind == 1:                                  # sphere
            return _radial(_sub(x, s[1]), s[2], (0.0, 0.0, 1.0))
        if kind == 2:                                  # capsule: point-segment distance - r
            a, ab, abab, r = s[1], s[2], s[3], s[4]
            ax = _sub(x, a)
            t = 0.0 if abab <= 0.0 else min(1.0, max(0.0, _dot(ax, ab) / abab))
            c = (a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2])
            return _radial(_sub(x, c), r, (0.0, 0.0, 1.0))
        # box: local p = R^T (x - c)
        c, R, h = s[1], s[2], s[3]
        v = _sub(x, c)
        p = (R[0][0] * v[0] + R[1][0] * v[1] + R[2][0] * v[2],
             R[0][1] * v[0] + R[1][1] * v[1] + R[2][1] * v[2],
             R[0][2] * v[0] + R[1][2] * v[1] + R[2][2] * v[2])
        q0, q1, q2 = abs(p[0]) - h[0], abs(p[1]) - h[1], abs(p[2]) - h[2]
        nl: tuple[float, float, float]
        if q0 > 0.0 or q1 > 0.0 or q2 > 0.0:           # outside: distance to the surface
            e0 = math.copysign(q0, p[0]) if q0 > 0.0 else 0.0
            e1 = math.copysign(q1, p[1]) if q1 > 0.0 else 0.0
            e2 = math.copysign(q2, p[2]) if q2 > 0.0 else 0.0
            d = math.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
            nl = (e0 / d, e1 / d, e2 / d)
        elif q0 >= q1 and q0 >= q2:                    # inside: the nearest face
            d, nl = q0, (math.copysign(1.0, p[0]), 0.0, 0.0)
        elif q1 >= q2:
            d, nl = q1, (0.0, math.copysign(1.0, p[1]), 0.0)
        else:
            d, nl = q2, (0.0, 0.0, math.copysign(1.0, p[2]))
        n = (R[0][0] * nl[0] + R[0][1] * nl[1] + R[0][2] * nl[2],
             R[1][0] * nl[0] + R[1][1] * nl[1] + R[1][2] * nl[2],
             R[2][0] * nl[0] + R[2][1] * nl[1] + R[2][2] * nl[2])
        return d, n


def _table(shapes: tuple) -> np.ndarray:
    """The shapes as rows of floats for the kernel: kind, then its parameters (16 columns)."""
    rows = np.zeros((len(shapes), 17))
    for k, s in enumerate(shapes):
        kind = s[0]
        flat: list[float] = [float(kind)]
        if kind == 0:
            flat += [*s[1], *s[2]]
        elif kind == 1:
            flat += [*s[1], s[2]]
        elif kind == 2:
            flat += [*s[1], *s[2], s[3], s[4]]
        else:
            flat += [*s[1], *(v for row in s[2] for v in row), *s[3]]
        rows[k, :len(flat)] = flat
    return rows
