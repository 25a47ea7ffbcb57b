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

from .._mechanism_formulas import mechanism_points_formula
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


def _select(c: bool, a: float, b: float) -> float:
    """The formula's select on Python floats (``np.where`` of one item)."""
    return a if c else b


class PoseClearance:
    """The least clearance of one tracked pose, in scalar arithmetic and one kernel call.

    :func:`athenakin.collision.clearance` places the bodies through the numpy forward
    kinematics of all 16 slots, about a millisecond per call; the tracker already holds
    its pose (``O_s``, ``p``, ``u1..u5``), so this places the 19 points of
    :data:`athenakin._mechanism.POINT_NAMES` from it with the formula of
    :func:`athenakin._mechanism.mechanism_points`
    (:func:`athenakin._mechanism_formulas.mechanism_points_formula`, on Python floats; the
    tests check the two agree to 1e-14 m) and calls the compiled capsule kernel once;
    with obstacles, the segment stage of :func:`~athenakin.collision.clearance`
    (``segment_clearance``), on the backend ``backend`` (``"auto" | "numpy" | "numba"``).
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
        #: The constants of :func:`~athenakin._mechanism_formulas.mechanism_points_formula`.
        self.G = (self.l2, self.l3, self.l4, self.l5, self.L, self.rm, self.half, self.rs,
                  float(self.lo), float(self.hi))
        self.index = np.array([[POINT_NAMES.index(a), POINT_NAMES.index(b)]
                               for a, b in BODY_SEGMENTS.values()])
        self.radii = np.ascontiguousarray(bodies.radius_array)
        self.ij = np.ascontiguousarray(bodies.pair_index)
        self.pairs = tuple(bodies.pairs)
        self.bodies = bodies
        self.environment = environment

    def points(self, q: tuple[float, float, float], p: float,
               u: tuple[float, float, float, float, float],
               O_s: tuple[float, float, float]) -> FloatArray:
        """The 19 named points, shape (19, 3), base frame (m), of one tracked pose.

        :func:`athenakin._mechanism_formulas.mechanism_points_formula` on Python floats,
        with ``R_b_s`` from ``O_s``: ``z_s = (O_s - M) / (r1 + l4)``.
        """
        q1, q2, _ = q
        h = 0.5 * (q1 - q2)
        r1l4 = math.sqrt(self.l1 * self.l1 - h * h) + self.l4
        ox, oy, oz = O_s
        rc, ze = self.rcm, self.ze
        cos, sin = math.cos, math.sin
        return np.array(mechanism_points_formula(
            q1, q2, p, cos(u[0]), sin(u[0]), cos(u[1]), sin(u[1]), cos(u[2]), sin(u[2]), ox,
            oy, oz, oy / r1l4, oz / r1l4, rc[0], rc[1], rc[2], ze[0], ze[1], ze[2], self.G,
            math.sqrt, min, max, _select))

    def __call__(self, q: tuple[float, float, float], p: float,
                 u: tuple[float, float, float, float, float], O_s: tuple[float, float, float]
                 ) -> tuple[float, tuple[str, str]]:
        """Least clearance (m; ``inf`` with no pair) and its pair for one tracked pose."""
        seg = self.points(q, p, u, O_s)[self.index]
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
