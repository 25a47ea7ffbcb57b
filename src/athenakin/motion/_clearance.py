"""Clearance of the robot's bodies along a motion (private; :mod:`athenakin.collision` lazily).

The tracker and the planner check the bodies of :mod:`athenakin.collision` only when
the caller asks for it (``bodies=``, ``environment=`` or ``clearance_margin=``): the
check costs far more than the tracker's scalar fast path. The collision package is
imported inside the functions, so that the motion subpackage still loads without it.

Each sample is checked in the slot of its labels (assembly mode, sign of ``p``, the
spherical joint's branch): :func:`athenakin.analysis._collision.labelled_clearance`.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from .._typing import FloatArray, IntArray
from ..design import Design

__all__ = ["DEFAULT_CLEARANCE_MARGIN", "ClearanceCheck", "clearance_check", "sample_clearance",
           "PoseClearance"]

#: Clearance (m) below which a sample is ``NEAR_COLLISION`` (tracker) or refused
#: (planner) when the check is asked for without a margin.
DEFAULT_CLEARANCE_MARGIN = 0.005


@dataclasses.dataclass(frozen=True)
class ClearanceCheck:
    """What to check: the robot's bodies, the obstacles, the margin (m) and the backend."""

    bodies: Any
    environment: Any
    margin: float
    backend: str = "auto"


def clearance_check(design: Design, bodies: object, environment: object,
                    clearance_margin: object, *, backend: str = "auto"
                    ) -> ClearanceCheck | None:
    """The check the caller asks for, or None when it asks for none.

    Any of ``bodies``, ``environment`` or ``clearance_margin`` turns the check on;
    missing bodies are :meth:`athenakin.collision.Bodies.default` of ``design``,
    a missing margin is :data:`DEFAULT_CLEARANCE_MARGIN`.

    Parameters
    ----------
    design : Design
    bodies : athenakin.collision.Bodies or None
    environment : athenakin.collision.Environment or None
    clearance_margin : float or None
        m.
    backend : {"auto", "numpy", "numba"}, keyword-only
        The backend of every clearance the check computes.

    Returns
    -------
    ClearanceCheck or None

    Raises
    ------
    TypeError
        ``bodies`` is not a :class:`~athenakin.collision.Bodies`, or ``environment`` not
        an :class:`~athenakin.collision.Environment`.
    InvalidInputError
        ``clearance_margin`` is negative, NaN or above 1 m.
    """
    from ..analysis._collision import collision_options

    opts = collision_options(design, bodies, environment, clearance_margin,
                             default_margin=DEFAULT_CLEARANCE_MARGIN)
    if opts is None:
        return None
    bodies, environment, margin = opts
    return ClearanceCheck(bodies=bodies, environment=environment, margin=float(margin),
                          backend=backend)


def sample_clearance(check: ClearanceCheck, q: FloatArray, T_b_e: FloatArray,
                     design: Design, mode: IntArray, p_sign: IntArray,
                     wrist: IntArray | None = None
                     ) -> tuple[FloatArray, NDArray[np.str_]]:
    """Least clearance of each sample and the pair that has it.

    Parameters
    ----------
    check : ClearanceCheck
    q : ndarray, shape (n, 3)
        Actuators, m.
    T_b_e : ndarray, shape (4, 4)
    design : Design
    mode, p_sign : ndarray of int, shape (n,)
        Assembly mode and sign of ``p`` of each sample (+1 / -1).
    wrist : ndarray of int, shape (n,), optional
        Spherical-joint branch (+1 / -1, default +1): it places the middle joint of the
        spherical mechanism.

    Returns
    -------
    distance : ndarray, shape (n,)
        Signed least distance between the bodies and to the obstacles, m (negative:
        penetration; ``+inf`` when no pair is checked); NaN where no slot of the
        sample's labels is valid.
    pair : ndarray of str, shape (n, 2)
        The two names (body, body or obstacle) of the least distance ("" where NaN).
    """
    from ..analysis._collision import labelled_clearance

    return labelled_clearance(q, T_b_e, design, np.asarray(mode), np.asarray(p_sign) == -1,
                              bodies=check.bodies, environment=check.environment, wrist=wrist,
                              backend=check.backend)


class PoseClearance:
    """The least clearance of one tracked pose, in scalar arithmetic and one kernel call.

    :func:`athenakin.collision.clearance` places the bodies through the numpy forward
    kinematics of all 16 slots, about a millisecond per call; the tracker already holds
    its pose (``O_s``, the instrument axis, ``u1..u5``), so this places the 19 points of
    :data:`athenakin._mechanism.POINT_NAMES` from it with the formulas of
    :func:`athenakin._mechanism.mechanism_points` (the tests check the two agree to
    1e-12 m) and calls the compiled capsule kernel once; with obstacles, the segment
    stage of :func:`~athenakin.collision.clearance` (``segment_clearance``), on the
    backend ``backend`` (``"auto" | "numpy" | "numba"``).
    """

    def __init__(self, design: Design, T_b_e: FloatArray, bodies: Any,
                 environment: Any = None, *, backend: str = "auto") -> None:
        from .._backend import resolve_backend
        from .._mechanism import BODY_SEGMENTS, POINT_NAMES, rail_extent

        self.compiled = resolve_backend(backend)
        self.backend: Literal["numba", "numpy"] = "numba" if self.compiled else "numpy"

        self.l1, self.l3, self.l2, self.l4, self.l5 = (design.l1, design.l3, design.l2,
                                                       design.l4, design.l5)
        self.L = design.tool_length
        geo = bodies.geometry
        self.lo, self.hi = rail_extent(design, geo)      # the rail's ends, margin included
        self.rm, self.half, self.rs = (geo.rail_margin, 0.5 * geo.carriage_length,
                                       geo.sphere_radius)
        self.rcm = tuple(float(v) for v in T_b_e[:3, 3])
        self.ze = tuple(float(v) for v in T_b_e[:3, 2])
        self.index = np.array([[POINT_NAMES.index(a), POINT_NAMES.index(b)]
                               for a, b in BODY_SEGMENTS.values()])
        self.radii = np.ascontiguousarray(bodies.radius_array)
        self.ij = np.ascontiguousarray(bodies.pair_index)
        self.pairs = tuple(bodies.pairs)
        self.bodies = bodies
        self.environment = environment

    def points(self, q: tuple[float, float, float], p: float,
               u: tuple[float, float, float, float, float], O_s: tuple[float, float, float],
               d: tuple[float, float, float]) -> FloatArray:
        """The 19 named points, shape (19, 3), base frame (m), of one tracked pose."""
        q1, q2, _ = q
        h = 0.5 * (q1 - q2)
        xm = 0.5 * (q1 + q2)
        yd = math.sqrt(self.l3 * self.l3 - h * h)
        r1 = math.sqrt(self.l1 * self.l1 - h * h)
        ox, oy, oz = O_s
        cy, cz = oy / (r1 + self.l4), oz / (r1 + self.l4)     # z_i = (0, cy, cz)
        oi = (ox, oy - self.l4 * cy, oz - self.l4 * cz)
        L = self.L
        tip = (ox + L * d[0], oy + L * d[1], oz + L * d[2])
        c1, s1, c2, s2 = math.cos(u[0]), math.sin(u[0]), math.cos(u[1]), math.sin(u[1])
        c3, s3 = math.cos(u[2]), math.sin(u[2])
        # a4 = R_b_s R(u1, u2) (s3, -c3, 0): columns 0 and 1 of R(u1, u2) in frame s
        v0 = s3 * c1 * c2 - c3 * s1
        v1 = s3 * s1 * c2 + c3 * c1
        v2 = s3 * s2
        a4 = (v0, cz * v1 + cy * v2, -cy * v1 + cz * v2)
        side = -1.0 if p < 0 else 1.0
        rc, ze, rs = self.rcm, self.ze, self.rs
        t = p - side * rs
        if 0.0 <= t <= L:
            s_3 = (rc[0] - side * rs * d[0], rc[1] - side * rs * d[1], rc[2] - side * rs * d[2])
        else:                               # the guide holds the instrument's nearest point
            t = min(max(t, 0.0), L)
            s_3 = (ox + t * d[0], oy + t * d[1], oz + t * d[2])
        half = self.half
        return np.array([
            (q1, 0.0, 0.0), (q2, 0.0, 0.0), (xm, 0.0, 0.0), (xm, yd, 0.0),
            (xm, yd + self.l2, 0.0), (xm, yd + self.l2, self.l5), oi, O_s, rc, tip,
            (min(min(q1, q2) - self.rm, self.lo), 0.0, 0.0),
            (max(max(q1, q2) + self.rm, self.hi), 0.0, 0.0),
            (q1 - half, 0.0, 0.0), (q1 + half, 0.0, 0.0),
            (q2 - half, 0.0, 0.0), (q2 + half, 0.0, 0.0),
            s_3,
            (rc[0] + rs * a4[0], rc[1] + rs * a4[1], rc[2] + rs * a4[2]),
            (rc[0] + rs * ze[0], rc[1] + rs * ze[1], rc[2] + rs * ze[2])])

    def __call__(self, q: tuple[float, float, float], p: float,
                 u: tuple[float, float, float, float, float], O_s: tuple[float, float, float],
                 d: tuple[float, float, float]) -> tuple[float, tuple[str, str]]:
        """Least clearance (m; ``inf`` with no pair) and its pair for one tracked pose."""
        seg = self.points(q, p, u, O_s, d)[self.index]
        if self.environment is not None:
            from ..collision._clearance import segment_clearance

            pairs, dd, _ = segment_clearance(seg[None], np.ones(1, dtype=bool), self.bodies,
                                             self.environment, compiled=self.compiled,
                                             witness=False)
            dist = dd[0]
        else:
            from ..collision._clearance import capsule_distances

            pairs = self.pairs
            dist = capsule_distances(seg[None], self.radii, self.ij, backend=self.backend)[0]
        if not len(pairs):
            return math.inf, ("", "")
        k = int(np.argmin(dist))
        return float(dist[k]), (str(pairs[k][0]), str(pairs[k][1]))
