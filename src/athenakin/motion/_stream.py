"""A recorded stream through the tracker: :func:`track` and its compiled batch.

:func:`track` runs a :class:`~athenakin.motion.Tracker` over a whole stream of
readings; :func:`track_batch` advances a tracker by a block of readings at once,
in the compiled loop of :mod:`athenakin.motion._kernels` where the tracker's backend
is numba (the poses and steps of :meth:`Tracker.update` to 1e-12, the same flags),
else by :meth:`Tracker.update` itself. With a collision check, :func:`track` checks
the whole stream in one batch of :func:`athenakin.collision.clearance` calls.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._robot_model import Robot, resolve_robot
from .._typing import BoolArray, FloatArray, IntArray
from .._validation import check_array, kernel_array
from ..chain import DEGENERATE_TOL, P_ZERO_TOL
from ..design import Design
from ..errors import InvalidInputError
from ..parallel import TANGENT_TOL
from ._candidates import (
    _B,
    _LOG_FIELDS,
    TrackLog,
    _cand_row,
    _cand_tuple,
    _clearance_text,
    _empty_columns,
    _join,
    _pairs,
    _pose_columns,
    pose_at,
)
from ._clearance import clearance_check, sample_clearance
from ._errors import TrackingError
from ._flags import TrackFlag
from ._tracker import Tracker, _track_flag

__all__ = ["track", "track_batch"]


def track(q_stream: ArrayLike, robot: Robot | ArrayLike, design: Design | None = None,
          **options: object) -> TrackLog:
    """Run a :class:`Tracker` over a recorded stream; the first reading is ``q0``.

    The readings after the first go through :func:`track_batch`: the compiled tracker
    where numba runs (:meth:`Tracker.update`'s poses to 1e-12, its flags, tested), else
    :meth:`Tracker.update` itself.

    Parameters
    ----------
    q_stream : array-like, shape (N, 3)
        Readings, m, N >= 1.
    robot : athenakin.Robot or array-like, shape (4, 4)
        The robot (its design, RCM frame, and the bodies and obstacles checked), or its
        RCM frame E in the base frame ``T_b_e`` (m), as for :class:`Tracker`.
    design : Design, optional
        With ``T_b_e`` only; default :meth:`Design.default`.
    **options
        Keyword options of :class:`Tracker` (``slot``, ``jump_m``, ``jump_rad``,
        ``margins``, ``raise_on``, ``bodies``, ``environment``, ``clearance_margin``,
        ``backend``).

    Returns
    -------
    TrackLog
        Row 0 is the initial configuration (flags: its ``NEAR_*`` bits).
    """
    qs = check_array(q_stream, "q_stream", (3,), allow_nonfinite=True)
    if qs.ndim != 2 or qs.shape[0] < 1:
        raise InvalidInputError(f"q_stream: expected shape (N, 3) with N >= 1, got {qs.shape}")
    model = resolve_robot(robot, design, bodies=options.pop("bodies", None),
                          environment=options.pop("environment", None))
    margin = options.pop("clearance_margin", None)
    if model.bodies is not None or model.environment is not None or margin is not None:
        cols = _track_checked(qs, model, margin, options)
    else:
        tr = Tracker(model, q0=qs[0], **options)  # type: ignore[arg-type]
        cols = _join(_pose_columns([tr.pose]), track_batch(tr, qs[1:]))
        cols["clearance"] = cols["closest_pair"] = None   # not checked: no value, not NaN
    return TrackLog(**{k: cols[k] for k in _LOG_FIELDS})


def _track_checked(qs: FloatArray, model: Robot, margin: object,
                   options: dict[str, object]) -> dict[str, Any]:
    """:func:`track` with the collision check: the stream first, then all clearances at once.

    The same poses and flags as a :class:`Tracker` checking every sample (the check
    does not steer the tracking), in one batch of :func:`athenakin.collision.clearance`
    calls instead of one call per sample; ``raise_on`` raises at the first sample
    whose flags, collisions included, carry one of its bits.
    """
    raise_bits = int(_track_flag(options.pop("raise_on", TrackFlag.NONE), "raise_on"))
    tr = Tracker(model.replace(bodies=None, environment=None), q0=qs[0],
                 **options)  # type: ignore[arg-type]
    check = clearance_check(tr.design, model.bodies, model.environment, margin,
                            backend=tr.backend)
    assert check is not None
    cols = _join(_pose_columns([tr.pose]), track_batch(tr, qs[1:]))
    idx = np.flatnonzero(cols["valid"])
    dist, pair = sample_clearance(check, cols["q"][idx].reshape(-1, 3), tr.T_b_e, tr.design,
                                  cols["mode"][idx], cols["p_sign"][idx], cols["wrist"][idx])
    dist = np.asarray(dist, dtype=float)
    cols["clearance"][idx] = dist
    cols["closest_pair"] = _pairs(len(qs), idx, pair)
    near = np.zeros(len(qs), bool)
    near[idx] = dist < check.margin
    coll_bits = np.zeros(len(qs), np.int64)
    coll_bits[idx] = np.where(dist < 0.0, _B["COLLISION"], 0)
    cols["flags"] = cols["flags"] | np.where(near, _B["NEAR_COLLISION"] | coll_bits, 0)
    hit = np.flatnonzero(cols["flags"][1:] & raise_bits)
    if hit.size:
        ps = pose_at(cols, int(hit[0]) + 1)
        what = "" if ps.valid else " no forward-kinematics solution:"
        raise TrackingError(f"sample {ps.sample} (q = {list(ps.q)} m):{what} "
                            f"{ps.flags!r}" + _clearance_text(ps), ps)
    return cols


def _kernel_geometry(tr: Tracker) -> FloatArray:
    """The geometry vector of :func:`athenakin.motion._kernels.track_stream`."""
    g = tr._g
    return np.array([g.l1, g.l2, g.l3, g.l4, g.l5, g.h_sign, *g.c, *g.ex, *g.ez, *g.lo, *g.hi,
                     tr.jump_m, tr.jump_rad, *tr._watch, tr.margins.half_chord, TANGENT_TOL,
                     P_ZERO_TOL, DEGENERATE_TOL, *g.P], dtype=float)


def track_batch(tr: Tracker, q: FloatArray) -> dict[str, Any]:
    """:meth:`Tracker.update` of every reading of ``q`` (n, 3), as columns; advances ``tr``.

    The compiled loop of :mod:`athenakin.motion._kernels` (the poses and steps of
    :meth:`Tracker.update` to 1e-12, the same flags, tested) where the tracker's
    backend (:attr:`Tracker.backend`) is numba, else :meth:`Tracker.update` itself.
    The collision check of a tracker that has one is
    :meth:`Tracker.update`'s too (the same scalar placement and kernel per valid
    reading). ``raise_on`` raises :class:`TrackingError` at the first reading that
    carries one of its bits, with the message and the pose of :meth:`Tracker.update`
    (the tracker is then past the stream, not at that reading).

    Returns
    -------
    dict of str -> ndarray
        The fields of :class:`TrackLog` and ``sample``, one row per reading.
    """
    q = kernel_array(q).reshape(-1, 3)     # a read-only stream copied: one specialization
    n = len(q)
    if tr.backend != "numba":
        poses = [tr.update(row) for row in q.tolist()]
        return _pose_columns(poses) if poses else _empty_columns()
    from ._kernels import NCAND, track_stream

    prev = np.array(_cand_row(tr._prev), dtype=float)
    lost = np.array([1 if tr._lost else 0], dtype=np.int64)
    c = np.empty((n, NCAND))
    step = np.empty(n)
    flags = np.empty(n, np.int64)
    valid = np.empty(n, bool)
    fast = np.empty(n, bool)
    if n:
        from .._dispatch import _WARM, _first

        geo = _kernel_geometry(tr)

        def run() -> None:
            track_stream(q, geo, prev, lost, c, step, flags, valid, fast)

        if "track_stream" in _WARM:
            run()
        else:                          # the first call may compile: a notice on stderr
            _first("track_stream", run)
    cols = _kernel_columns(tr, q, c, step, flags, valid)
    if tr._check is not None and n:
        _collide_rows(tr, cols)
    tr._index += n
    tr._prev = _cand_tuple(prev.tolist())
    tr._lost = bool(lost[0])
    if n:
        tr.pose = pose_at(cols, n - 1)
    _raise_on(tr, cols, fast)
    return cols


def _kernel_columns(tr: Tracker, q: FloatArray, c: FloatArray,
                    step: FloatArray, flags: IntArray,
                    valid: BoolArray) -> dict[str, Any]:
    """The columns of :func:`track_batch` from the kernel's candidate rows ``c`` (n, NCAND)."""
    n = len(q)
    g = tr._g
    mode = c[:, 0].astype(np.int64)
    r, b, w = (c[:, k].astype(np.int64) for k in (1, 2, 3))
    o, dz = c[:, 10:13], c[:, 13:16]
    L = g.L
    tb = np.empty((n, 3))
    for k in range(3):
        tb[:, k] = o[:, k] + L * dz[:, k]
    v = [tb[:, k] - g.c[k] for k in range(3)]
    R = g.R
    te = np.empty((n, 3))
    for k in range(3):
        te[:, k] = R[0][k] * v[0] + R[1][k] * v[1] + R[2][k] * v[2]
    return {
        "sample": tr._index + 1 + np.arange(n), "q": q.copy(), "valid": valid,
        "slot": 8 * (mode == -1) + 4 * (r == -1) + 2 * (b == -1) + (w == -1),
        "mode": mode, "p_sign": r, "ujoint": b, "wrist": w, "p": c[:, 4].copy(),
        "u": c[:, 5:10].copy(), "O_s": o.copy(), "direction_b": dz.copy(), "tip_b": tb,
        "tip_e": te, "half_chord": c[:, 16].copy(), "h": c[:, 17].copy(),
        "sin_u2": c[:, 18].copy(), "sin_u4": c[:, 19].copy(), "step": step, "flags": flags,
        "clearance": np.full(n, math.nan), "closest_pair": np.full((n, 2), "")}


def _raise_on(tr: Tracker, cols: dict[str, Any], fast: BoolArray) -> None:
    """:class:`TrackingError` at the first row whose flags carry a bit of ``raise_on``."""
    hit = np.flatnonzero(cols["flags"] & tr._raise_bits)
    if hit.size:
        i = int(hit[0])
        ps = pose_at(cols, i)
        qt = list(ps.q)
        if not ps.valid:
            raise TrackingError(f"sample {ps.sample} (q = {qt} m): no forward-"
                                f"kinematics solution: {ps.flags!r}", ps)
        what = "" if fast[i] else f" (q = {qt} m)"
        raise TrackingError(f"sample {ps.sample}{what}: {ps.flags!r}" + _clearance_text(ps), ps)


def _collide_rows(tr: Tracker, cols: dict[str, Any]) -> None:
    """:meth:`Tracker._collide` of every valid row (the same call per row)."""
    check, pc = tr._check, tr._pose_clearance
    assert check is not None and pc is not None
    pairs: list[tuple[str, str]] = [("", "")] * len(cols["q"])
    q, p, u, o = (cols[k].tolist() for k in ("q", "p", "u", "O_s"))
    flags = cols["flags"]
    for i in np.flatnonzero(cols["valid"]).tolist():
        d, names = pc(tuple(q[i]), p[i], tuple(u[i]), tuple(o[i]))
        pair = np.array([names])
        cols["clearance"][i] = d
        pairs[i] = (str(pair[0, 0]), str(pair[0, 1]))
        if d < check.margin:
            flags[i] |= _B["NEAR_COLLISION"] | (_B["COLLISION"] if d < 0.0 else 0)
    cols["closest_pair"] = np.array(pairs).reshape(-1, 2)
