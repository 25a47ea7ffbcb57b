"""Workspace, conditioning and assembly-mode maps on grids (vectorised, chunked).

Four grids, each a frozen dataclass of arrays:

* :func:`actuator_map` - the actuator plane ``(h, q3)``: where each assembly
  mode closes, conditioning of ``d O_s / d q``, the loci where the modes meet.
  The module is invariant under ``x_M = (q1 + q2) / 2``, so this plane is the
  whole actuator space up to a translation along the rail.
* :func:`point_workspace` - a voxel grid of ``O_s`` positions: which are
  reachable within the stroke limits, in which assembly mode (each ``O_s`` has
  exactly one ``q`` and one mode), the signed distance to the surface where the
  modes meet, conditioning.
* :func:`instrument_cone` - directions ``(azimuth, polar)`` about the RCM in
  frame E times insertions ``p``: the cone of reachable directions and the
  insertion range along each.
* :func:`tool_tip_workspace` - a voxel grid of tool-tip positions in frame E.

Collisions. :func:`point_workspace`, :func:`instrument_cone` and
:func:`tool_tip_workspace` take ``bodies=``, ``environment=`` and ``clearance_margin=``
(any of them turns the check on; :mod:`athenakin.collision`, imported then): each
reachable grid point then gets the least clearance between the robot's bodies and to
the obstacles (``clearance``) and a collision-free layer (``collision_free``: reachable
and a clearance of at least the margin, default 0); the cone also marks the directions
that a collision blocks (``blocked``: in the cone, but no collision-free insertion).
Without the check these fields are None.

Results are saved with :func:`save_npz` (one ``.npz`` archive: the arrays by
field name plus a JSON ``meta`` entry) and read with :func:`load_npz`.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._output import check_output_path, naming_path
from .._typing import BoolArray, FloatArray, Int8Array, IntArray
from .._validation import check_path
from ..design import Design, resolve_design
from ..errors import InvalidInputError
from ..parallel import parallel_ik_from_position
from ..robot import q_from_tool_tip
from ..robot._jacobians import _parallel_jacobian, _state, _tip_matrices
from ._cone import InstrumentCone, _box, _interval, _modes_arg
from ._singularities import _svd
from ._workspace_grid import (
    _clearance,
    _cond,
    _free,
    _map_chunks,
    _map_setup,
    _quiet,
    _resolution,
    _unlimited,
    _within,
)


# --------------------------------------------------------------------------------------
# actuator plane (h, q3)
# --------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class ActuatorMap:
    """Assembly and conditioning of the parallel module over the plane ``(h, q3)``.

    Attributes
    ----------
    h : ndarray, shape (nh,)
        ``(q1 - q2) / 2``, m.
    q3 : ndarray, shape (nq,)
        m.
    modes : ndarray of int, shape (2,)
        ``(+1, -1)``: the last axis of the per-mode arrays.
    assembled : ndarray of bool, shape (nh, nq)
        ``k1`` and ``k2`` intersect (both modes exist; they coincide on ``w = 0``).
    half_chord : ndarray, shape (nh, nq)
        Half-chord ``a`` of ``k1 ∩ k2`` (m), NaN where they do not intersect.
    sigma_min, condition : ndarray, shape (nh, nq, 2)
        Of ``d O_s / d q`` per mode (dimensionless).
    inverse_sigma_min : ndarray, shape (nh, nq, 2)
        ``1 / sigma_max(d O_s / d q)``: 0 at forward singularities.
    h_stroke, q3_stroke : ndarray, shape (2,)
        Range of ``h`` and of ``q3`` that the stroke limits allow.
    """

    h: FloatArray
    q3: FloatArray
    modes: IntArray
    assembled: BoolArray
    half_chord: FloatArray
    sigma_min: FloatArray
    condition: FloatArray
    inverse_sigma_min: FloatArray
    h_stroke: FloatArray
    q3_stroke: FloatArray


def actuator_map(design: Design | None = None, *, resolution: int | tuple[int, int] = 201,
                 h_range: tuple[float, float] | None = None,
                 q3_range: tuple[float, float] | None = None,
                 progress: bool | None = None) -> ActuatorMap:
    """Grid the actuator plane ``(h, q3)`` (``x_M = 0``; the module is invariant in ``x_M``).

    Parameters
    ----------
    design : Design, optional
    resolution : int or (int, int), keyword-only
        Samples of ``h`` and ``q3``.
    h_range, q3_range : (float, float), keyword-only
        Defaults: ``|h| <= min(l1, l3)``; ``q3`` from 0 to ``1.1 (d + r1)_max``.
    progress : bool, keyword-only
        Show a tqdm bar (default: only for large grids).

    Returns
    -------
    ActuatorMap
    """
    design = resolve_design(design)
    nh, nq = _resolution(resolution, 2)
    hm = min(design.l1, design.l3)
    h_lo, h_hi = _interval(h_range, "h_range") or (-hm, hm)
    h = np.linspace(h_lo, h_hi, nh)
    dmax = np.hypot(design.l3 + design.l2, design.l5) + design.l1
    q_lo, q_hi = _interval(q3_range, "q3_range") or (0.0, 1.1 * dmax)
    q3 = np.linspace(q_lo, q_hi, nq)
    H, Q3 = np.meshgrid(h, q3, indexing="ij")
    pts = np.stack([H.ravel(), -H.ravel(), Q3.ravel()], axis=-1)  # q1 = h, q2 = -h

    def fn(qq: FloatArray) -> dict[str, NDArray[Any]]:
        out: dict[str, list[NDArray[Any]]] = {"s": [], "c": [], "i": []}
        a = None
        for m in (1, -1):
            _, g = _state(qq, design, m)
            a = g["a"]
            J = _parallel_jacobian(g)
            sv = _svd(J)
            smin, cond = _cond(J)
            with np.errstate(divide="ignore"):
                out["i"].append(1.0 / sv[..., 0])
            out["s"].append(smin)
            out["c"].append(cond)
        assert a is not None
        return {"a": a, **{k: np.stack(v, axis=-1) for k, v in out.items()}}

    r = _map_chunks(fn, pts, progress, "actuator map")
    smin, smax = design.stroke_min, design.stroke_max
    return ActuatorMap(
        h=h, q3=q3, modes=np.array([1, -1]), assembled=np.isfinite(r["a"]).reshape(nh, nq),
        half_chord=r["a"].reshape(nh, nq), sigma_min=r["s"].reshape(nh, nq, 2),
        condition=r["c"].reshape(nh, nq, 2), inverse_sigma_min=r["i"].reshape(nh, nq, 2),
        h_stroke=np.array([(smin[0] - smax[1]) / 2, (smax[0] - smin[1]) / 2]),
        q3_stroke=np.array([smin[2], smax[2]]))


# --------------------------------------------------------------------------------------
# O_s workspace
# --------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class PointWorkspace:
    """Reachable positions of ``O_s`` on a voxel grid (base frame).

    Attributes
    ----------
    x, y, z : ndarray, shapes (nx,), (ny,), (nz,)
        Grid axes, m.
    mode : ndarray of int8, shape (nx, ny, nz)
        Assembly mode of the unique ``q`` that puts ``O_s`` there (+1 / -1),
        0 where the module cannot put ``O_s`` there at all (ignoring strokes).
    reachable : ndarray of bool, shape (nx, ny, nz)
        ``mode != 0`` and ``q`` within the stroke limits.
    q : ndarray, shape (nx, ny, nz, 3)
        Actuators (ignoring strokes; NaN where ``mode == 0``).
    mode_margin : ndarray, shape (nx, ny, nz)
        ``mode * a`` (m): the signed half-chord of ``k1 ∩ k2``; its zero level set
        is the surface where the two assembly modes meet.
    sigma_min, condition : ndarray, shape (nx, ny, nz)
        Of ``d O_s / d q`` (dimensionless; NaN where ``mode == 0``).
    clearance : ndarray, shape (nx, ny, nz), or None
        Least clearance of the bodies (m, NaN where not reachable) with the serial
        chain set up at ``T_b_e`` (``p > 0``); None without the collision check.
    collision_free : ndarray of bool, shape (nx, ny, nz), or None
        Reachable with a clearance of at least the margin; None without the check.
    """

    x: FloatArray
    y: FloatArray
    z: FloatArray
    mode: Int8Array
    reachable: BoolArray
    q: FloatArray
    mode_margin: FloatArray
    sigma_min: FloatArray
    condition: FloatArray
    clearance: FloatArray | None = None
    collision_free: BoolArray | None = None


def _default_bounds(design: Design) -> tuple[tuple[float, float], ...]:
    lo, hi = design.stroke_min, design.stroke_max
    xm = [(lo[0] + lo[1]) / 2, (hi[0] + hi[1]) / 2]
    if not np.all(np.isfinite(xm)):
        xm = [-0.5, 0.5]
    R = design.l1 + design.l4
    return ((xm[0], xm[1]), (-R, R), (-R, R))


def point_workspace(T_b_e: ArrayLike | None = None, design: Design | None = None, *,
                    resolution: int | tuple[int, int, int] = 41,
                    bounds: tuple[tuple[float, float], ...] | None = None,
                    progress: bool | None = None, bodies: object = None,
                    environment: object = None, clearance_margin: float | None = None
                    ) -> PointWorkspace:
    """Reachable set of ``O_s`` with its assembly-mode regions and conditioning.

    Uses the closed-form IK of the parallel module (paper Section 4), so
    membership is exact at every grid point (no sampling of actuator space).

    Parameters
    ----------
    T_b_e : array-like, shape (4, 4), optional
        RCM frame that places the serial chain and the instrument for the collision
        check (default :func:`~athenakin.default_rcm_frame`). Checked, but not used
        without the check: the ``O_s`` workspace does not depend on it.
    design : Design, optional
    resolution : int or (int, int, int), keyword-only
        Grid points along x, y, z.
    bounds : ((xmin, xmax), (ymin, ymax), (zmin, zmax)), keyword-only
        Default: ``x_M`` over the stroke box, ``|y|, |z| <= l1 + l4``.
    progress : bool, keyword-only
    bodies : athenakin.collision.Bodies, optional, keyword-only
        Check the clearance of these bodies at every reachable point (layers
        ``clearance``, ``collision_free``); default ``Bodies.default(design)`` when
        ``environment`` or ``clearance_margin`` turns the check on.
    environment : athenakin.collision.Environment, optional, keyword-only
        Obstacles (base frame).
    clearance_margin : float, optional, keyword-only
        Least clearance of a collision-free point, m (default 0: no overlap).

    Returns
    -------
    PointWorkspace
    """
    if isinstance(T_b_e, Design):          # the order of every function: (..., T_b_e, design)
        raise TypeError("T_b_e: expected a (4, 4) RCM frame or None, got a Design (the order "
                        "is point_workspace(T_b_e, design); give design=...)")
    design, check, T = _map_setup(T_b_e, design, bodies, environment, clearance_margin)
    n = _resolution(resolution, 3)
    b = _box(bounds) or _default_bounds(design)
    axes = [np.linspace(lo, hi, k) for (lo, hi), k in zip(b, n, strict=True)]
    P = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    free = _unlimited(design)

    def fn(pp: FloatArray) -> dict[str, NDArray[Any]]:
        ik = parallel_ik_from_position(pp, free)
        m = np.where(ik.valid, ik.mode, 0)
        q = np.where(ik.valid[..., None], ik.q, np.nan)
        _, g = _state(np.nan_to_num(q), design, np.where(m == 0, 1, m))
        smin, cond = _cond(_parallel_jacobian(g))
        nan = np.where(m != 0, 1.0, np.nan)
        reach = _within(q, design) & (m != 0)
        out = {"m": m.astype(np.int8), "q": q, "r": reach,
               "mm": m * g["a"] * nan, "s": smin * nan, "c": cond * nan}
        if check is not None:
            assert T is not None
            out["cl"] = _clearance(check, q, T, design, np.where(reach, m, 0),
                                   np.zeros(len(q), dtype=bool))
        return out

    r = _map_chunks(fn, P, progress, "O_s workspace")
    sh = tuple(n)
    cl = None if check is None else r["cl"].reshape(sh)
    reach = r["r"].reshape(sh)
    return PointWorkspace(x=axes[0], y=axes[1], z=axes[2], mode=r["m"].reshape(sh),
                          reachable=reach, q=r["q"].reshape(sh + (3,)),
                          mode_margin=r["mm"].reshape(sh), sigma_min=r["s"].reshape(sh),
                          condition=r["c"].reshape(sh), clearance=cl,
                          collision_free=None if check is None or cl is None
                          else _free(reach, cl, check.margin))


# --------------------------------------------------------------------------------------
# tool-tip workspace
# --------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class ToolTipWorkspace:
    """Reachable tool-tip positions on a voxel grid in the RCM frame E.

    Attributes
    ----------
    x, y, z : ndarray, shapes (nx,), (ny,), (nz,)
        Grid axes in frame E (origin at the RCM), m.
    T_b_e : ndarray, shape (4, 4)
    mode : ndarray of int8, shape (nx, ny, nz)
        Assembly mode (0: unreachable).
    reachable : ndarray of bool, shape (nx, ny, nz)
    q : ndarray, shape (nx, ny, nz, 3)
        Actuators (NaN where unreachable).
    sigma_min, condition : ndarray, shape (nx, ny, nz)
        Of the tool-tip Jacobian ``d tip / d q`` (dimensionless).
    clearance : ndarray, shape (nx, ny, nz), or None
        Least clearance of the bodies, m (NaN where unreachable); None without the
        collision check.
    collision_free : ndarray of bool, shape (nx, ny, nz), or None
        Reachable with a clearance of at least the margin.
    """

    x: FloatArray
    y: FloatArray
    z: FloatArray
    T_b_e: FloatArray
    mode: Int8Array
    reachable: BoolArray
    q: FloatArray
    sigma_min: FloatArray
    condition: FloatArray
    clearance: FloatArray | None = None
    collision_free: BoolArray | None = None


def tool_tip_workspace(T_b_e: ArrayLike | None = None, design: Design | None = None, *,
                       resolution: int | tuple[int, int, int] = 41,
                       bounds: tuple[tuple[float, float], ...] | None = None,
                       modes: tuple[int, ...] = (1,), progress: bool | None = None,
                       bodies: object = None, environment: object = None,
                       clearance_margin: float | None = None) -> ToolTipWorkspace:
    """Reachable tool-tip positions (instrument through the RCM), frame E.

    Parameters
    ----------
    T_b_e : array-like, shape (4, 4), optional
    design : Design, optional
    resolution : int or (int, int, int), keyword-only
    bounds : ((xmin, xmax), (ymin, ymax), (zmin, zmax)), keyword-only
        In frame E; default ``[-L, L]^3`` (``L`` the tool length).
    modes : tuple of {1, -1}, keyword-only
    progress : bool, keyword-only
    bodies, environment, clearance_margin : keyword-only
        The collision check (see :func:`point_workspace`): layers ``clearance`` and
        ``collision_free``.

    Returns
    -------
    ToolTipWorkspace
    """
    design, check, T = _map_setup(T_b_e, design, bodies, environment, clearance_margin)
    allowed = _modes_arg(modes)
    n = _resolution(resolution, 3)
    L = design.tool_length
    b = _box(bounds) or ((-L, L),) * 3
    axes = [np.linspace(lo, hi, k) for (lo, hi), k in zip(b, n, strict=True)]
    P = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)

    def fn(tip: FloatArray) -> dict[str, NDArray[Any]]:
        q, res = q_from_tool_tip(T, tip, design, errors="flag")
        ok = res.valid & np.isin(res.mode, allowed)
        m = np.where(ok, res.mode, 0)
        _, g = _state(np.nan_to_num(q), design, np.where(m == 0, 1, m))
        N, _, _ = _tip_matrices(g, T, L)
        smin, cond = _cond(N @ _parallel_jacobian(g))
        nan = np.where(ok, 1.0, np.nan)
        out = {"m": m.astype(np.int8), "r": ok, "q": q * nan[:, None], "s": smin * nan,
               "c": cond * nan}
        if check is not None:
            out["cl"] = _clearance(check, q, T, design, m,
                                   np.linalg.norm(tip, axis=-1) > L)
        return out

    r = _map_chunks(fn, P, progress, "tool-tip workspace")
    sh = tuple(n)
    reach = r["r"].reshape(sh)
    cl = None if check is None else r["cl"].reshape(sh)
    return ToolTipWorkspace(x=axes[0], y=axes[1], z=axes[2], T_b_e=T, mode=r["m"].reshape(sh),
                            reachable=reach, q=r["q"].reshape(sh + (3,)),
                            sigma_min=r["s"].reshape(sh), condition=r["c"].reshape(sh),
                            clearance=cl, collision_free=None if check is None or cl is None
                            else _free(reach, cl, check.margin))


# --------------------------------------------------------------------------------------
# storage
# --------------------------------------------------------------------------------------
_RESULTS = {c.__name__: c for c in (ActuatorMap, PointWorkspace, InstrumentCone,
                                    ToolTipWorkspace)}


def save_npz(path: str | Path, result: object, *, design: Design | None = None,
             compressed: bool = True, **meta: Any) -> Path:
    """Save a grid result to a NumPy ``.npz`` archive.

    Each array field is stored under its name; ``meta`` (a JSON string) holds
    the result type, the athenakin version, the design as TOML and any extra
    keyword arguments (JSON-serialisable).

    Parameters
    ----------
    path : str or Path
    result : ActuatorMap, PointWorkspace, InstrumentCone or ToolTipWorkspace
    design : Design, optional
        Recorded in ``meta`` (recommended).
    compressed : bool, keyword-only
        ``np.savez_compressed`` (default) or ``np.savez``.
    **meta
        Extra metadata.

    Returns
    -------
    Path
        The file written.
    """
    from .. import __version__

    path = check_output_path(path)
    if design is not None and not isinstance(design, Design):
        raise TypeError(f"design: expected athenakin.Design or None, got {type(design).__name__}")
    name = type(result).__name__
    if name not in _RESULTS or not dataclasses.is_dataclass(result):
        raise TypeError(f"result: expected one of {sorted(_RESULTS)}, got {name}")
    arrays = {f.name: np.asarray(getattr(result, f.name)) for f in dataclasses.fields(result)
              if getattr(result, f.name) is not None}      # the layers left out are None
    info = {"type": name, "athenakin_version": __version__,
            "design_toml": design.to_toml() if design is not None else None, **meta}
    saver: Any = np.savez_compressed if compressed else np.savez
    with naming_path(path):
        saver(path, meta=np.array(json.dumps(info)), **arrays)
    return path if path.suffix == ".npz" else path.with_name(path.name + ".npz")


def load_npz(path: str | Path) -> tuple[object, dict[str, Any]]:
    """Read a file written by :func:`save_npz`.

    Parameters
    ----------
    path : str or Path
        The ``.npz`` archive.

    Returns
    -------
    result : ActuatorMap, PointWorkspace, InstrumentCone or ToolTipWorkspace
    meta : dict
    """
    import zipfile

    from .._input import open_regular

    path = check_path(path)
    with open_regular(path, error=InvalidInputError, what="grid result file") as fh:
        try:
            with np.load(fh, allow_pickle=False) as f:
                if not hasattr(f, "files") or "meta" not in f.files:
                    raise InvalidInputError("no 'meta' entry")
                meta = json.loads(str(f["meta"]))
                if not isinstance(meta, dict):
                    raise InvalidInputError("'meta' is not a JSON object")
                cls = _RESULTS.get(meta.get("type", ""))
                if cls is None:
                    raise InvalidInputError(f"meta.type = {meta.get('type')!r}")
                # the optional layers (default None, e.g. the collision layers) may be absent
                missing = [fl.name for fl in dataclasses.fields(cls) if fl.name not in f.files
                           and fl.default is not None]
                if missing:
                    raise InvalidInputError(f"arrays {missing} missing")
                kw = {fl.name: f[fl.name] for fl in dataclasses.fields(cls) if fl.name in f.files}
        except (InvalidInputError, ValueError, EOFError, KeyError, zipfile.BadZipFile,
                json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise InvalidInputError(f"path: {path} is not an athenakin grid result written by "
                                    f"save_npz ({exc})") from None
    return cls(**kw), meta


def _voxel_volume(*axes: FloatArray) -> float:
    return float(np.prod([ax[1] - ax[0] for ax in axes]))


def workspace_summary(pw: PointWorkspace | None = None, ic: InstrumentCone | None = None,
                      tw: ToolTipWorkspace | None = None) -> dict[str, object]:
    """Scalar figures of merit of grid results (volumes, solid angle, conditioning).

    Volumes are voxel counts times the voxel volume (m^3), so they converge
    with the grid resolution at the rate of the boundary's voxelisation.

    Parameters
    ----------
    pw : PointWorkspace, optional
        From :func:`point_workspace`: reachable volume of ``O_s`` (m^3), per mode.
    ic : InstrumentCone, optional
        From :func:`instrument_cone`: solid angle (sr), insertion range (m).
    tw : ToolTipWorkspace, optional
        From :func:`tool_tip_workspace`: reachable tool-tip volume (m^3).

    Returns
    -------
    dict of str -> float or int
        Keyed by description with the unit in brackets, e.g.
        ``"O_s reachable volume [m^3]"``; only the figures of the results given.
    """
    for name, arg, cls in (("pw", pw, PointWorkspace), ("ic", ic, InstrumentCone),
                           ("tw", tw, ToolTipWorkspace)):
        if arg is not None and not isinstance(arg, cls):
            raise TypeError(f"{name}: expected {cls.__name__} or None, got {type(arg).__name__}")
    out: dict[str, object] = {}
    with np.errstate(invalid="ignore"), _quiet():
        if pw is not None:
            v = _voxel_volume(pw.x, pw.y, pw.z)
            out["O_s reachable volume [m^3]"] = float(pw.reachable.sum() * v)
            for m in (1, -1):
                sel = pw.reachable & (pw.mode == m)
                out[f"O_s volume, mode {m:+d} [m^3]"] = float(sel.sum() * v)
            sel = pw.reachable & (pw.mode == 1)
            out["O_s median cond(dO_s/dq), mode +1"] = float(np.nanmedian(pw.condition[sel]))
            out["O_s min |signed half-chord|, mode +1 [m]"] = float(
                np.nanmin(np.abs(pw.mode_margin[sel]))) if sel.any() else float("nan")
            if pw.collision_free is not None:
                out["O_s collision-free volume [m^3]"] = float(pw.collision_free.sum() * v)
        if ic is not None:
            da = 2 * np.pi / len(ic.azimuth)
            dp = ic.polar[1] - ic.polar[0]
            w = np.sin(ic.polar) * dp * da
            inside = np.isfinite(ic.p_min)
            sa = float((inside * w[None, :]).sum())
            out["cone solid angle [sr]"] = sa
            out["cone fraction of the sphere"] = sa / (4 * np.pi)
            out["cone max insertion range [m]"] = float(np.nanmax(ic.p_max - ic.p_min))
            out["cone directions with 2+ insertion intervals"] = int((ic.n_intervals > 1).sum())
            out["cone median cond(d tip/dq)"] = float(np.nanmedian(ic.condition))
            if ic.collision_free is not None and ic.blocked is not None:
                free = ic.collision_free.any(axis=-1)
                out["cone collision-free solid angle [sr]"] = float((free * w[None, :]).sum())
                out["cone solid angle blocked by a collision [sr]"] = float(
                    (ic.blocked * w[None, :]).sum())
        if tw is not None:
            v = _voxel_volume(tw.x, tw.y, tw.z)
            out["tool-tip reachable volume [m^3]"] = float(tw.reachable.sum() * v)
            out["tool-tip median cond(d tip/dq)"] = float(np.nanmedian(tw.condition))
            if tw.collision_free is not None:
                out["tool-tip collision-free volume [m^3]"] = float(tw.collision_free.sum() * v)
    return out
