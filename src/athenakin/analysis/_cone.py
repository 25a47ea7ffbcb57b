"""The instrument cone: the directions an instrument through the RCM reaches at each depth."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._typing import BoolArray, FloatArray, Int8Array, IntArray
from .._validation import check_array
from ..design import Design
from ..errors import InvalidInputError
from ..robot import direction_from_angles, q_from_instrument
from ..robot._jacobians import _parallel_jacobian, _state, _tip_matrices
from . import _workspace_grid as _grid


# --------------------------------------------------------------------------------------
# instrument cone
# --------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class InstrumentCone:
    """Instrument directions about the RCM and the insertion range along each.

    Attributes
    ----------
    azimuth : ndarray, shape (na,)
        rad, about ``z_e`` (:func:`~athenakin.direction_from_angles`).
    polar : ndarray, shape (npol,)
        rad, from ``z_e``.
    p : ndarray, shape (np,)
        Insertions (distance ``O_s`` -> RCM), m.
    T_b_e : ndarray, shape (4, 4)
    mode : ndarray of int8, shape (na, npol, np)
        Assembly mode of the configuration (0: not reachable within strokes).
    reachable : ndarray of bool, shape (na, npol, np)
        Reachable within the strokes in an allowed mode (see ``modes`` argument).
    p_min, p_max : ndarray, shape (na, npol)
        Smallest / largest reachable insertion along the direction (NaN: none).
    n_intervals : ndarray of int, shape (na, npol)
        Number of separate reachable insertion intervals (0: direction not in the cone).
    condition : ndarray, shape (na, npol, np)
        Condition number of the tool-tip Jacobian (NaN where unreachable).
    clearance : ndarray, shape (na, npol, np), or None
        Least clearance of the bodies, m (NaN where unreachable); None without the
        collision check.
    collision_free : ndarray of bool, shape (na, npol, np), or None
        Reachable with a clearance of at least the margin.
    blocked : ndarray of bool, shape (na, npol), or None
        Directions in the cone (some insertion reachable) that a collision blocks:
        no reachable insertion along them is collision-free.
    """

    azimuth: FloatArray
    polar: FloatArray
    p: FloatArray
    T_b_e: FloatArray
    mode: Int8Array
    reachable: BoolArray
    p_min: FloatArray
    p_max: FloatArray
    n_intervals: IntArray
    condition: FloatArray
    clearance: FloatArray | None = None
    collision_free: BoolArray | None = None
    blocked: BoolArray | None = None


def _interval(x: object, name: str) -> tuple[float, float] | None:
    """None, or ``(lo, hi)``: two finite numbers with ``lo <= hi`` (a named error otherwise)."""
    if x is None:
        return None
    a = check_array(x, name, (2,))  # type: ignore[arg-type]
    if a.shape != (2,) or not a[0] <= a[1]:
        raise InvalidInputError(f"{name}: expected (lo, hi) with lo <= hi, got {x!r}")
    return float(a[0]), float(a[1])


def _box(bounds: object) -> tuple[tuple[float, float], ...] | None:
    """None, or three intervals ``((x_lo, x_hi), (y_lo, y_hi), (z_lo, z_hi))``."""
    if bounds is None:
        return None
    a = check_array(bounds, "bounds", (2,))  # type: ignore[arg-type]
    if a.shape != (3, 2) or not np.all(a[:, 0] <= a[:, 1]):
        raise InvalidInputError(f"bounds: expected ((x_lo, x_hi), (y_lo, y_hi), (z_lo, z_hi)) "
                                f"with lo <= hi, got {bounds!r}")
    return tuple((float(lo), float(hi)) for lo, hi in a)


def _modes_arg(modes: tuple[int, ...]) -> tuple[int, ...]:
    try:
        m = tuple(int(v) for v in modes)
    except (TypeError, ValueError, OverflowError):
        raise InvalidInputError(f"modes: expected a non-empty tuple of +1 / -1, got "
                                f"{modes!r}") from None
    if not m or any(v not in (1, -1) for v in m):
        raise InvalidInputError(f"modes: expected a non-empty tuple of +1 / -1, got {modes!r}")
    return m


def instrument_cone(T_b_e: ArrayLike | None = None, design: Design | None = None, *,
                    resolution: int | tuple[int, int, int] = (73, 37, 46),
                    p_range: tuple[float, float] | None = None, modes: tuple[int, ...] = (1,),
                    progress: bool | None = None, bodies: object = None,
                    environment: object = None, clearance_margin: float | None = None
                    ) -> InstrumentCone:
    """The cone of instrument directions about the RCM with its insertion ranges.

    For each direction ``d`` (spherical angles in E) and insertion ``p`` the
    parallel module's IK puts ``O_s = c - p d`` (:func:`~athenakin.q_from_instrument`).

    Parameters
    ----------
    T_b_e : array-like, shape (4, 4), optional
        RCM frame; default :func:`~athenakin.default_rcm_frame`.
    design : Design, optional
    resolution : int or (int, int, int), keyword-only
        Samples of azimuth over (-pi, pi], polar over [0, pi] and ``p``.
    p_range : (float, float), keyword-only
        Insertions; default ``(0.01 L, L)`` with ``L`` the tool length (the
        instrument must pass the RCM).
    modes : tuple of {1, -1}, keyword-only
        Assembly modes counted as reachable (default: the working mode +1).
    progress : bool, keyword-only
    bodies, environment, clearance_margin : keyword-only
        The collision check (see :func:`point_workspace`): layers ``clearance``,
        ``collision_free`` and the directions a collision ``blocked``.

    Returns
    -------
    InstrumentCone
    """
    design, check, T = _grid._map_setup(T_b_e, design, bodies, environment, clearance_margin)
    na, npol, npp = _grid._resolution(resolution, 3)
    allowed = _modes_arg(modes)
    L = design.tool_length
    pr = _interval(p_range, "p_range") or (0.01 * L, L)
    az = np.linspace(-np.pi, np.pi, na, endpoint=False) + 2 * np.pi / na
    pol = np.linspace(0.0, np.pi, npol)
    p = np.linspace(pr[0], pr[1], npp)
    A, B, Pp = np.meshgrid(az, pol, p, indexing="ij")
    pts = np.stack([A.ravel(), B.ravel(), Pp.ravel()], axis=-1)

    def fn(x: FloatArray) -> dict[str, NDArray[Any]]:
        d_e = direction_from_angles(x[:, 0], x[:, 1])
        q, res = q_from_instrument(T, d_e, x[:, 2], design, errors="flag")
        ok = res.valid & np.isin(res.mode, allowed)
        m = np.where(ok, res.mode, 0)
        _, g = _state(np.nan_to_num(q), design, np.where(m == 0, 1, m))
        N, _, _ = _tip_matrices(g, T, L)
        _, cond = _grid._cond(N @ _parallel_jacobian(g))
        out = {"m": m.astype(np.int8), "r": ok, "c": np.where(ok, cond, np.nan)}
        if check is not None:
            out["cl"] = _grid._clearance(check, q, T, design, m, x[:, 2] < 0)
        return out

    r = _grid._map_chunks(fn, pts, progress, "instrument cone")
    sh = (na, npol, npp)
    reach = r["r"].reshape(sh)
    pm = np.where(reach, p, np.nan)
    with np.errstate(invalid="ignore"), _grid._quiet():
        p_min, p_max = np.nanmin(pm, axis=-1), np.nanmax(pm, axis=-1)
    starts = reach & ~np.concatenate([np.zeros(sh[:-1] + (1,), bool), reach[..., :-1]], axis=-1)
    cl = free = blocked = None
    if check is not None:
        cl = r["cl"].reshape(sh)
        free = _grid._free(reach, cl, check.margin)
        blocked = np.asarray(reach.any(axis=-1) & ~free.any(axis=-1), dtype=bool)
    return InstrumentCone(azimuth=az, polar=pol, p=p, T_b_e=T, mode=r["m"].reshape(sh),
                          reachable=reach, p_min=p_min, p_max=p_max,
                          n_intervals=starts.sum(axis=-1), condition=r["c"].reshape(sh),
                          clearance=cl, collision_free=free, blocked=blocked)
