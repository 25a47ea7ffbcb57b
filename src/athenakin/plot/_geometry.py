"""Where every part of the robot is, for one FK solution (pure numpy; used by views and exports).

The points follow docs/conventions.md: ``A = (q1, 0, 0)``, ``B = (q2, 0, 0)``, midpoint ``M``,
``D = (x_M, sqrt(l3^2 - h^2), 0)``, ``C = D + (0, l2, l5)``, ``O_i`` on ``k1 ∩ k2``,
``O_s = O_i + l4 z_i`` (Eq. 8-10), and the serial chain of Eq. 11-12 from ``O_s`` to
the RCM frame E. The spherical joint at the RCM (the kinematic equivalent of the
passive spherical five-bar, Fig. 3) is described by the axes of ``u3``, ``u4``,
``u5``, which all pass through the RCM. Points, frames and the rail are those of
:func:`athenakin._mechanism.mechanism_state` (the one place that places the mechanism).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable

import numpy as np
from numpy.typing import ArrayLike

from .._mechanism import BodyGeometry, MechanismState, O_i_from_T_b_s, state_from_fk
from .._typing import FloatArray
from .._validation import check_array, check_count, check_instance, check_scalar, check_slot
from ..design import Design, resolve_design
from ..errors import InvalidInputError, Reason, error_for_reason
from ..robot import FKSolution, forward_kinematics
from ..robot._setup import resolve_rcm_frame

__all__ = ["RobotGeometry", "robot_geometry", "circle_points", "N_CIRCLE", "MAX_CURVE_POINTS",
           "ARC_MARGIN", "check_view", "check_length",
           "COLORS", "FRAME_LENGTH", "ARC_RADIUS", "VIEW", "MM", "arc_points", "slot_label",
           "cube_limits", "cube_around", "union_bounds"]

#: Number of points on each drawn circle (k1, k2).
N_CIRCLE = 121
#: ``|b - (a.b) a|`` of unit directions at or below which :func:`arc_points` takes them as
#: parallel (no plane; the arc is then at most 1e-12 of its radius long, or undefined).
PARALLEL_TOL = 1e-12
#: Most points of one curve (:func:`circle_points`, :func:`arc_points`), checked before
#: anything is allocated.
MAX_CURVE_POINTS = 100_000
#: Colours of the parts (paper Fig. 2: parallel module blue, serial part red), shared by
#: the matplotlib and the HTML views.
COLORS = {
    "rail": "#555555", "parallel": "#1f4fbf", "actuator": "#f28e0f", "joint": "#7f7f7f",
    "serial": "#cc2222", "sphere": "#8e44ad", "circle_k1": "#1f4fbf", "circle_k2": "#f28e0f",
    "x": "#d62728", "y": "#2ca02c", "z": "#1f77b4",
}
#: Default length of drawn frame axes, m.
FRAME_LENGTH = 0.08
#: Radius of the drawn spherical-joint arcs about the RCM, m.
ARC_RADIUS = 0.07
#: Default view direction (elevation, azimuth), degrees.
VIEW = (20.0, -35.0)
#: Millimetres per metre: every view shows lengths in mm (the plot boundary).
MM = 1e3
#: Below this sine of the angle between its end directions, an arc has no plane (parallel
#: or antiparallel directions, up to rounding) and is drawn as one repeated point.
ARC_PARALLEL_TOL = 1e-12
#: Angle by which the drawn arc of ``k2`` extends beyond the intersections with ``k1``, rad.
ARC_MARGIN = np.radians(25.0)


@dataclasses.dataclass(frozen=True)
class RobotGeometry:
    """Positions (m, base frame) and frames of the robot in one forward-kinematics slot.

    Attributes
    ----------
    q : ndarray, shape (3,)
        Actuators ``(q1, q2, q3)``, m.
    slot : int
        Forward-kinematics slot ``k = 8 m + 4 r + 2 b + w`` (see ``robot/_fk.py``).
    mode, p_sign, ujoint, wrist : int
        Labels of the slot (+1 / -1).
    p : float
        Passive prismatic joint, signed distance ``O_s`` -> RCM, m.
    u : ndarray, shape (5,)
        ``u1..u5``, radians.
    points : dict of str -> ndarray, shape (3,)
        ``A``, ``B``, ``M``, ``D``, ``C``, ``O_i``, ``O_s``, ``RCM``, ``tip`` (tool tip,
        ``O_s + L z_3``) and ``C_foot`` (the corner ``D + (0, l2, 0)`` of the carrier).
    frames : dict of str -> ndarray, shape (4, 4)
        ``b`` (base), ``i`` (intermediate, Eq. 9), ``s`` (serial base, Eq. 10),
        ``instrument`` (``T_b_s R(u1, u2)``: origin ``O_s``, z along the instrument)
        and ``e`` (the RCM frame, the given set-up).
    wrist_axes : ndarray, shape (3, 3)
        Unit axes (rows) of ``u3``, ``u4``, ``u5`` through the RCM, base frame. Their
        signs tell the two branches of the spherical joint apart.
    ujoint_axes : ndarray, shape (2, 3)
        Unit axes of ``u1`` (``z_s``) and ``u2`` through ``O_s``; the sign of the
        second tells the two U-joint branches apart.
    k1, k2 : ndarray, shape (N_CIRCLE, 3)
        Points of the circles ``k1`` (centre M, radius ``r1``) and ``k2`` (centre C,
        radius ``q3``) in the plane ``x = x_M``.
    k2_arc : ndarray, shape (N_CIRCLE, 3)
        The arc of ``k2`` through both intersections with ``k1`` (on the side of M),
        extended by :data:`ARC_MARGIN` at each end: what views draw of ``k2``.
    intersections : ndarray, shape (2, 3)
        ``k1 ∩ k2``: ``O_i`` of assembly mode +1 and -1 (NaN where absent).
    rail : ndarray, shape (2, 3)
        End points of the base rail (x axis), the ``rail`` body of
        :func:`athenakin._mechanism.mechanism_state` (the strokes of A and B and the
        carriages, widened by the default ``BodyGeometry.rail_margin``).
    design : Design
    T_b_e : ndarray, shape (4, 4)
    state : MechanismState
        The configuration as :func:`athenakin._mechanism.mechanism_state` gives it
        (batch shape ``()``), from which the points and frames here are taken.
    """

    q: FloatArray
    slot: int
    mode: int
    p_sign: int
    ujoint: int
    wrist: int
    p: float
    u: FloatArray
    points: dict[str, FloatArray]
    frames: dict[str, FloatArray]
    wrist_axes: FloatArray
    ujoint_axes: FloatArray
    k1: FloatArray
    k2: FloatArray
    k2_arc: FloatArray
    intersections: FloatArray
    rail: FloatArray
    design: Design
    T_b_e: FloatArray
    state: MechanismState | None = None

    def segments(self) -> dict[str, tuple[FloatArray, FloatArray]]:
        """The bars of the mechanism as named segments ``(start, end)``.

        ``link_a1``, ``link_b1`` (length ``l1``, A/B to ``O_i``), ``link_a3``,
        ``link_b3`` (length ``l3``, A/B to D), ``carrier_y``, ``carrier_z`` (D to C
        by ``(0, l2, 0)`` then ``(0, 0, l5)``), ``actuator_q3`` (C to ``O_i``,
        length ``q3``), ``offset_l4`` (``O_i`` to ``O_s``) and ``instrument``
        (``O_s`` to the tool tip).

        Returns
        -------
        dict of str -> (ndarray, ndarray)
            Start and end, each shape (3,), base frame, m.
        """
        P = self.points
        return {
            "link_a1": (P["A"], P["O_i"]), "link_b1": (P["B"], P["O_i"]),
            "link_a3": (P["A"], P["D"]), "link_b3": (P["B"], P["D"]),
            "carrier_y": (P["D"], P["C_foot"]), "carrier_z": (P["C_foot"], P["C"]),
            "actuator_q3": (P["C"], P["O_i"]), "offset_l4": (P["O_i"], P["O_s"]),
            "instrument": (P["O_s"], P["tip"]),
        }

    def bounds(self) -> tuple[FloatArray, FloatArray]:
        """Axis-aligned box ``(lo, hi)`` (each shape (3,)) around every drawn part.

        The full circle ``k2`` is left out (views draw :attr:`k2_arc`).

        Returns
        -------
        lo, hi : ndarray, shape (3,)
            Base frame, m.
        """
        pts = np.concatenate([np.stack(list(self.points.values())), self.k1, self.k2_arc,
                              self.rail])
        return pts.min(axis=0), pts.max(axis=0)


def check_view(view: object, name: str = "view") -> tuple[float, float]:
    """``(elevation, azimuth)`` in degrees: two finite numbers.

    Raises
    ------
    TypeError, InvalidInputError
        Naming ``name``.
    """
    v = check_array(view, name, (2,))  # type: ignore[arg-type]
    if v.shape != (2,):
        raise InvalidInputError(f"{name}: expected (elevation, azimuth) in degrees, got shape "
                                f"{v.shape}")
    return float(v[0]), float(v[1])


def check_length(x: object, name: str, *, maximum: float = 10.0) -> float:
    """A drawing length or scale: a number in ``(0, maximum]``.

    Raises
    ------
    TypeError, InvalidInputError
        Naming ``name``.
    """
    v = check_scalar(x, name, positive=True)
    if not v <= maximum:
        raise InvalidInputError(f"{name}: expected a number in (0, {maximum:g}], got {v:g}")
    return v


def circle_points(centre: FloatArray, radius: float, n: int = N_CIRCLE
                  ) -> FloatArray:
    """Points of a circle in the plane ``x = centre[0]``, shape (n, 3).

    Parameters
    ----------
    centre : array-like, shape (3,)
        Centre, m.
    radius : float
        Non-negative, m.
    n : int
        Number of points, 2 to :data:`MAX_CURVE_POINTS` (the last repeats the first).

    Returns
    -------
    ndarray, shape (n, 3)
        m, evenly in angle from ``centre + (0, radius, 0)``, counter-clockwise about +x.

    Raises
    ------
    TypeError, InvalidInputError
        A bad argument (named).
    """
    n = check_count(n, "n", minimum=2, maximum=MAX_CURVE_POINTS)
    centre = check_array(centre, "centre", (3,))
    if centre.shape != (3,):
        raise InvalidInputError(f"centre: expected shape (3,), got shape {centre.shape}")
    radius = check_scalar(radius, "radius", nonnegative=True)
    t = np.linspace(0.0, 2 * np.pi, n)
    return np.stack([np.full(n, centre[0]), centre[1] + radius * np.cos(t),
                     centre[2] + radius * np.sin(t)], axis=-1)


def _k2_arc(C: FloatArray, radius: float, M: FloatArray,
            ends: FloatArray, n: int = N_CIRCLE) -> FloatArray:
    """Arc of the circle (centre C, plane x = C[0]) between two points, on M's side."""
    ang = np.arctan2(ends[:, 2] - C[2], ends[:, 1] - C[1])
    ang = ang[np.isfinite(ang)]
    am = np.arctan2(M[2] - C[2], M[1] - C[1])
    rel = np.mod(ang - am + np.pi, 2 * np.pi) - np.pi       # relative to the direction of M
    lo, hi = rel.min() - ARC_MARGIN, rel.max() + ARC_MARGIN
    t = am + np.linspace(lo, hi, n)
    return np.stack([np.full(n, C[0]), C[1] + radius * np.cos(t), C[2] + radius * np.sin(t)],
                    axis=-1)


def robot_geometry(q: ArrayLike | None = None, T_b_e: ArrayLike | None = None,
                   design: Design | None = None, *, slot: int = 0,
                   fk: FKSolution | None = None) -> RobotGeometry:
    """Positions of all parts of the robot for actuator values ``q`` in one FK slot.

    Parameters
    ----------
    q : array-like, shape (3,), optional
        ``(q1, q2, q3)``, m. Defaults to :data:`athenakin.robot.REFERENCE_Q`.
    T_b_e : array-like, shape (4, 4), optional
        RCM frame (set-up). Defaults to :func:`athenakin.default_rcm_frame`.
    design : Design, optional
        Defaults to :meth:`Design.default`.
    slot : int, keyword-only
        Forward-kinematics slot 0..15 (0: mode +1, ``p > 0``, ``sin u2 > 0``,
        ``sin u4 > 0``).
    fk : FKSolution, keyword-only, optional
        The result of ``forward_kinematics(q, T_b_e, design)`` for this ``q`` (slots of
        shape (16,)), e.g. from the numba backend, to draw several slots of one ``q``
        without solving it again; by default it is solved here.

    Returns
    -------
    RobotGeometry

    Raises
    ------
    InvalidInputError
        ``q`` is not of shape (3,) or ``slot`` is not in 0..15.
    KinematicsError
        The slot holds no valid solution (the subclass that matches its reason,
        e.g. :class:`~athenakin.errors.OutOfWorkspaceError`).

    Examples
    --------
    >>> import athenakin as ak
    >>> from athenakin.plot import robot_geometry
    >>> g = robot_geometry()
    >>> bool(abs(g.points["O_s"] - g.frames["s"][:3, 3]).max() < 1e-15)
    True
    """
    from ..robot import REFERENCE_Q

    design = resolve_design(design)
    if fk is not None:
        check_instance(fk, "fk", FKSolution)
    q = check_array(REFERENCE_Q if q is None else q, "q", (3,)).copy()
    if q.shape != (3,):
        raise InvalidInputError(f"q: expected shape (3,), got shape {q.shape}")
    slot = check_slot(slot)
    T = resolve_rcm_frame(T_b_e, design)
    sol = _solved_slot(q, T, design, slot, fk)
    st = state_from_fk(sol, q, T, design, slot, BodyGeometry())
    F = {link: st.frame(link) for link in ("platform", "instrument", "guide", "sph_4", "sph_5")}
    T_b_s = sol.T_b_s[slot]
    p = float(sol.p[slot])
    u = sol.u[slot].copy()
    l1 = design.l1
    h = 0.5 * (q[0] - q[1])
    names = ("A", "B", "M", "D", "C_foot", "C", "O_i", "O_s", "RCM", "tip")
    points = {name: st[name].copy() for name in names}
    M, C = points["M"], points["C"]
    # the axes of the spherical joint (u3, u4, u5) through the RCM and of the U-joint at O_s
    wrist_axes = np.stack([F["guide"][:3, 2], F["sph_4"][:3, 2], F["sph_5"][:3, 2]])
    ujoint_axes = np.stack([F["platform"][:3, 2], F["instrument"][:3, 1]])
    # k1 ∩ k2: O_i of both assembly modes, from the poses of O_s the FK holds per mode
    intersections = O_i_from_T_b_s(sol.T_b_s_mode, design)
    r1 = np.sqrt(l1 * l1 - h * h)
    frames = {"b": np.eye(4), "i": F["platform"].copy(), "s": T_b_s.copy(),
              "instrument": F["instrument"].copy(), "e": T.copy()}
    return RobotGeometry(
        q=q, slot=slot, mode=int(sol.mode[slot]), p_sign=int(sol.p_sign[slot]),
        ujoint=int(sol.ujoint[slot]), wrist=int(sol.wrist[slot]), p=p, u=u, points=points,
        frames=frames, wrist_axes=wrist_axes, ujoint_axes=ujoint_axes, k1=circle_points(M, r1),
        k2=circle_points(C, q[2]), k2_arc=_k2_arc(C, q[2], M, intersections),
        intersections=intersections, rail=np.stack([st["rail_lo"], st["rail_hi"]]),
        design=design, T_b_e=T.copy(), state=st)


def _solved_slot(q: FloatArray, T: FloatArray, design: Design, slot: int,
                 fk: FKSolution | None) -> FKSolution:
    """The forward kinematics of one ``q`` (``fk``, or solved here) with ``slot`` valid.

    Raises the :class:`KinematicsError` of the slot's reason where it holds no solution.
    """
    if fk is None:
        sol = forward_kinematics(q, T, design, errors="flag")
    elif np.shape(fk.valid) != (16,):
        raise InvalidInputError(f"fk: expected the solution of one q (valid of shape (16,)), "
                                f"got valid of shape {np.shape(fk.valid)}")
    else:
        sol = fk
    if not sol.valid[slot]:
        why = Reason(int(sol.reason[slot])).name
        raise error_for_reason(int(sol.reason[slot]), f"slot {slot} of q = {q.tolist()} m ({why})")
    return sol


def slot_label(g: RobotGeometry) -> str:
    """Short text of a slot: ``slot 3: mode +1, p>0, U-, S-``.

    Parameters
    ----------
    g : RobotGeometry
        From :func:`robot_geometry`.

    Returns
    -------
    str

    Raises
    ------
    TypeError
        ``g`` is not a :class:`RobotGeometry`.
    """
    check_instance(g, "g", RobotGeometry)
    return (f"slot {g.slot}: mode {g.mode:+d}, p{'>' if g.p_sign > 0 else '<'}0, "
            f"U{'+' if g.ujoint > 0 else '-'}, S{'+' if g.wrist > 0 else '-'}")


def arc_points(centre: FloatArray, a: FloatArray, b: FloatArray,
               radius: float, n: int = 16) -> FloatArray:
    """Great-circle arc of ``radius`` about ``centre`` from direction a to direction b, (n, 3).

    Parameters
    ----------
    centre : array-like, shape (3,)
        m.
    a, b : array-like, shape (3,)
        Non-zero directions (any length).
    radius : float
        Non-negative, m.
    n : int
        Number of points, 2 to :data:`MAX_CURVE_POINTS`.

    Returns
    -------
    ndarray, shape (n, 3)
        From ``centre + radius a/|a|`` to ``centre + radius b/|b|``, m, evenly in
        angle; all at the first where ``a`` and ``b`` are (anti)parallel.

    Raises
    ------
    TypeError, InvalidInputError
        A bad argument (named).
    """
    n = check_count(n, "n", minimum=2, maximum=MAX_CURVE_POINTS)
    radius = check_scalar(radius, "radius", nonnegative=True)
    vecs = []
    for name, v in (("centre", centre), ("a", a), ("b", b)):
        arr = check_array(v, name, (3,))
        if arr.shape != (3,):
            raise InvalidInputError(f"{name}: expected shape (3,), got shape {arr.shape}")
        vecs.append(arr)
    centre, a, b = vecs
    for name, v in (("a", a), ("b", b)):
        big = float(np.abs(v).max())
        if big == 0.0:
            raise InvalidInputError(f"{name}: expected a non-zero direction, got (0, 0, 0)")
    ma, mb = float(np.abs(a).max()), float(np.abs(b).max())
    if not 1e-150 <= ma <= 1e150:       # the norm would overflow or underflow: scale first
        a = a / ma
    if not 1e-150 <= mb <= 1e150:
        b = b / mb
    a = a / np.linalg.norm(a)
    b = b / np.linalg.norm(b)
    ab = float(np.sum(a * b))
    perp = b - ab * a
    norm = float(np.sqrt(np.sum(perp * perp)))
    if norm <= PARALLEL_TOL:        # (anti)parallel: no plane (or an arc shorter than 1e-12 r)
        return np.repeat((centre + radius * a)[None], n, axis=0)
    ang = float(np.arctan2(norm, ab))     # well conditioned, unlike arccos near 0 and pi
    e = perp / norm
    e = e - float(np.sum(e * a)) * a      # exactly in the plane, orthogonal to a
    e = e / np.sqrt(np.sum(e * e))
    t = np.linspace(0.0, ang, n)[:, None]
    return centre + radius * (np.cos(t) * a + np.sin(t) * e)


def union_bounds(geoms: Iterable[RobotGeometry]
                 ) -> tuple[FloatArray, FloatArray]:
    """Axis-aligned box ``(lo, hi)`` (m) around every geometry's :meth:`~RobotGeometry.bounds`.

    ``geoms`` holds at least one geometry.
    """
    los, his = zip(*(g.bounds() for g in geoms), strict=True)
    return np.min(los, axis=0), np.max(his, axis=0)


def cube_around(geoms: Iterable[RobotGeometry], pad: float = 0.05
                ) -> tuple[FloatArray, FloatArray]:
    """The axis box ``(lo, hi)`` (m) of a view of several solutions or frames.

    A cube around all of them (:func:`union_bounds`) with a margin ``pad`` (m).
    """
    return cube_limits(*union_bounds(geoms), pad)


def cube_limits(lo: FloatArray, hi: FloatArray, pad: float = 0.05
                ) -> tuple[FloatArray, FloatArray]:
    """A cube ``(lo, hi)`` around the box ``lo``, ``hi`` (m) with a margin ``pad`` (m)."""
    c = 0.5 * (lo + hi)
    half = 0.5 * float(np.max(hi - lo)) + pad
    return c - half, c + half
