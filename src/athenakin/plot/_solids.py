"""The robot's bodies as solids in matplotlib: capsules as shaded tubes.

:func:`draw_bodies` draws every capsule of :class:`athenakin.collision.Bodies` in one
forward-kinematics slot on a 3-D axes (a tube with hemispherical caps, shaded by
matplotlib's light source), colours the pair with the least clearance, joins its
witness points and writes the clearance. :func:`plot_robot` calls it with
``bodies=``. :func:`capsule_surface` gives the surface grid of one capsule.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from .._validation import check_array, check_axes, check_frame, check_scalar
from ..design import Design, resolve_design
from ..errors import InvalidInputError

__all__ = ["capsule_surface", "draw_bodies", "BODY_COLORS", "CLOSEST_COLOR",
           "COLLIDING_COLOR"]

#: Colour of each body group (the stick view's colours: parallel module blue, q3
#: actuator orange, instrument red, spherical mechanism purple, base grey).
BODY_COLORS: dict[str, str] = {
    "rail": "#7f7f7f", "carriage_a": "#595959", "carriage_b": "#595959",
    "link_a": "#1f77b4", "link_b": "#1f77b4", "link_ad": "#1f77b4", "link_bd": "#1f77b4",
    "carrier": "#2a6f97", "actuator": "#ff7f0e", "platform": "#2ca02c",
    "instrument": "#d62728", "sphere_link_1": "#9467bd", "sphere_link_2": "#9467bd",
}
#: Colour of the two bodies (or body and obstacle) with the least clearance.
CLOSEST_COLOR = "#e7298a"
#: Colour of that pair when it overlaps (clearance < 0).
COLLIDING_COLOR = "#ff0000"
#: Most points around and along a capsule (each surface has ``n_around x n_along`` points).
MAX_RESOLUTION = 256


#: Largest coordinate or radius (m) that :func:`capsule_surface` draws.
MAX_DRAWN_LENGTH = 1e3


def capsule_surface(a: ArrayLike, b: ArrayLike, radius: float, *, n_around: int = 16,
                    n_cap: int = 5) -> tuple[FloatArray, FloatArray,
                                             FloatArray]:
    """Surface grid of the capsule of segment ``a -> b`` and ``radius`` (for ``plot_surface``).

    Parameters
    ----------
    a, b : array-like, shape (3,)
        End points of the segment, m.
    radius : float
        m, >= 0.
    n_around : int, keyword-only
        Points around the axis (>= 3).
    n_cap : int, keyword-only
        Rings on each hemispherical cap (>= 1).

    Returns
    -------
    X, Y, Z : ndarray, shape (2 n_cap + 2, n_around + 1)
        Every point lies at distance ``radius`` from the segment (the tube between the
        end rings, the caps beyond them).
    """
    a = check_array(a, "a", (3,))
    b = check_array(b, "b", (3,))
    for name, pt in (("a", a), ("b", b)):
        if pt.shape != (3,):
            raise InvalidInputError(f"{name}: expected one point of shape (3,), got {pt.shape}")
    r = check_scalar(radius, "radius")
    if not 0 <= r <= MAX_DRAWN_LENGTH or np.max(np.abs(np.r_[a, b])) > MAX_DRAWN_LENGTH:
        raise InvalidInputError(f"radius, a, b: expected a radius in [0, {MAX_DRAWN_LENGTH:g}] m "
                                f"and coordinates within +/-{MAX_DRAWN_LENGTH:g} m, got "
                                f"radius {r!r}, a={a.tolist()}, b={b.tolist()}")
    for name, v, lo in (("n_around", n_around, 3), ("n_cap", n_cap, 1)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) \
                or not lo <= v <= MAX_RESOLUTION:
            raise InvalidInputError(f"{name}: expected an integer in [{lo}, {MAX_RESOLUTION}], "
                                    f"got {v!r}")
    axis = b - a
    length = float(np.linalg.norm(axis))
    w = axis / length if length > 0 else np.array([0.0, 0.0, 1.0])
    helper = np.array([1.0, 0.0, 0.0]) if abs(w[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(w, helper)
    u /= np.linalg.norm(u)
    v_axis = np.cross(w, u)
    # profile: (position along the axis from a, distance from the axis)
    phi = np.linspace(0.0, 0.5 * np.pi, n_cap + 1)
    cap_a = np.stack([-r * np.cos(phi), r * np.sin(phi)], axis=-1)         # pole -> equator
    cap_b = np.stack([length + r * np.sin(phi), r * np.cos(phi)], axis=-1)  # equator -> pole
    prof = np.concatenate([cap_a, cap_b], axis=0)
    t = np.linspace(0.0, 2.0 * np.pi, n_around + 1)
    ring = np.cos(t)[None, :, None] * u + np.sin(t)[None, :, None] * v_axis
    P = a + prof[:, 0, None, None] * w + prof[:, 1, None, None] * ring
    return P[..., 0], P[..., 1], P[..., 2]


def draw_bodies(ax: Any, q: ArrayLike, T_b_e: ArrayLike, design: Design | None = None, *,
                slot: int = 0, bodies: Any = None, environment: Any = None,
                alpha: float = 0.35, n_around: int = 16, show_closest: bool = True,
                show_clearance: bool = True) -> Any:
    """Draw the robot's bodies as shaded capsules and mark the pair with the least clearance.

    Parameters
    ----------
    ax : mpl_toolkits.mplot3d.Axes3D
    q : array-like, shape (3,)
        Actuators, m.
    T_b_e : array-like, shape (4, 4)
        RCM frame.
    design : Design, optional
    slot : int, keyword-only
        Forward-kinematics slot 0..15 that places the bodies.
    bodies : athenakin.collision.Bodies, optional, keyword-only
        Default :meth:`Bodies.default(design) <athenakin.collision.Bodies.default>`.
    environment : athenakin.collision.Environment, optional, keyword-only
        Obstacles checked for the clearance (not drawn).
    alpha : float, keyword-only
        Opacity of the capsules, in (0, 1].
    n_around : int, keyword-only
        Points around each capsule.
    show_closest : bool, keyword-only
        Colour the two bodies of the least clearance (:data:`CLOSEST_COLOR`, or
        :data:`COLLIDING_COLOR` when they overlap) and join their witness points.
    show_clearance : bool, keyword-only
        Write the least clearance and its pair in the corner of the axes.

    Returns
    -------
    athenakin.collision.Clearance
        The clearance of the drawn configuration (batch shape ``()``).

    Raises
    ------
    KinematicsError
        The slot holds no solution (nothing to draw).
    """
    from ..collision import clearance
    from ..collision._bodies import resolve_bodies
    from ..errors import KinematicsError

    _check_solids_args(ax, alpha=alpha, show_closest=show_closest,
                       show_clearance=show_clearance)
    design = resolve_design(design)
    bodies = resolve_bodies(bodies, design)
    T_b_e = check_frame(T_b_e, "T_b_e")
    q = check_array(q, "q", (3,))
    if q.shape != (3,):
        raise InvalidInputError(f"q: expected shape (3,) (one configuration), got {q.shape}")
    from .._mechanism import body_segments, mechanism_points

    pts = mechanism_points(q, T_b_e, design, slot=slot, geometry=bodies.geometry)
    if not bool(pts.valid):
        raise KinematicsError(f"slot {slot}: no forward-kinematics solution for q = "
                              f"{q.tolist()} (nothing to draw)")
    seg = body_segments(pts)
    c = clearance(q, T_b_e, design, slot=slot, bodies=bodies, environment=environment)
    k = int(c.closest_pair)
    pair = c.pairs[k] if k >= 0 else ("", "")
    hot = COLLIDING_COLOR if bool(c.colliding) else CLOSEST_COLOR
    for i, name in enumerate(bodies.names):
        r = bodies.radius[name]
        if r <= 0:
            continue
        X, Y, Z = capsule_surface(seg[i, 0], seg[i, 1], r, n_around=n_around)
        color = hot if show_closest and name in pair else BODY_COLORS.get(name, "0.5")
        ax.plot_surface(X, Y, Z, color=color, alpha=alpha, linewidth=0, antialiased=True,
                        shade=True, rstride=1, cstride=1)
    if show_closest and k >= 0:
        w = c.witness_points[k]
        ax.plot(*w.T, color=hot, lw=2.0, marker="o", ms=3)
    if show_clearance and k >= 0:
        d = float(c.min_distance)
        ax.text2D(0.98, 0.02, f"clearance {d * 1e3:.1f} mm\n{pair[0]} - {pair[1]}",
                  transform=ax.transAxes, ha="right", va="bottom", fontsize=7, color=hot)
    return c


def _check_solids_args(ax: Any, *, alpha: object, show_closest: object,
                       show_clearance: object) -> None:
    """The drawing arguments of :func:`draw_bodies`, else a named error."""
    check_axes(ax, "ax")
    if getattr(ax, "name", "") != "3d":
        raise TypeError(f"ax: expected a 3-D matplotlib Axes (projection='3d'), got "
                        f"{type(ax).__name__}")
    for name, flag in (("show_closest", show_closest), ("show_clearance", show_clearance)):
        if not isinstance(flag, (bool, np.bool_)):
            raise TypeError(f"{name}: expected a bool, got {type(flag).__name__}")
    if isinstance(alpha, bool) or not isinstance(alpha, (int, float)) or not 0 < alpha <= 1:
        raise InvalidInputError(f"alpha: expected an opacity in (0, 1], got {alpha!r}")
