"""One tracked pose, the branch candidates of a reading, a stream's poses as columns."""

from __future__ import annotations

import dataclasses
import math
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from .._mechanism_formulas import (
    actuator_reason_formula,
    module_closed_form_formula,
    module_params,
)
from .._typing import BoolArray, FloatArray, IntArray
from ..chain import DEGENERATE_TOL, P_ZERO_TOL
from ..design import Design
from ..parallel import TANGENT_TOL
from ._flags import TrackFlag

_TWO_PI = 2.0 * math.pi


def angle_pair(x: float, y: float, z: float, sign: float, degen: float, has_hint: bool,
               hint: float) -> tuple[bool, float, float, float, float, float]:
    """Cosines and sines of an angle pair of ``R(a, b)`` from its axis ``(x, y, z)``.

    ``sign`` is the branch label (``b`` or ``w``). Where ``|(x, y)| <= degen`` (the two
    joint axes aligned) ``a`` is the previous value ``hint``, the continuous choice, or,
    without a hint, there is no candidate. Plain Python over :mod:`math`: the Python
    tracker calls it, and :mod:`athenakin.motion._kernels` compiles this same function.

    Returns
    -------
    ok, rho, cos_a, sin_a, cos_b, sin_b : bool and floats
        ``ok`` False: no candidate; ``rho = |(x, y)|``.
    """
    rho = math.hypot(x, y)
    if rho > degen:
        return True, rho, sign * x / rho, sign * y / rho, -z, sign * rho
    if not has_hint:
        return False, rho, 0.0, 0.0, 0.0, 0.0
    return True, rho, math.cos(hint), math.sin(hint), -z, 0.0


def wrist_matrix(c1: float, s1: float, c2: float, s2: float, cy: float, cz: float,
                 ex: tuple[float, ...], ez: tuple[float, ...]
                 ) -> tuple[float, float, float, float, float, float]:
    """Entries of ``W = R(u1, u2)^T R_s_e`` that the wrist's angles need.

    From the U-joint's cosines and sines ``c1, s1, c2, s2``, the module's tilt ``cy, cz``
    (``R_b_s``) and the RCM frame's x and z axes ``ex``, ``ez`` (base frame). Plain
    Python over floats, compiled by :mod:`athenakin.motion._kernels` as it stands.

    Returns
    -------
    W00, W10, W20, W02, W12, W22 : float
    """
    # R_s_e columns x and z: R_b_s^T e
    Ex0, Ex1, Ex2 = ex[0], cz * ex[1] - cy * ex[2], cy * ex[1] + cz * ex[2]
    Ez0, Ez1, Ez2 = ez[0], cz * ez[1] - cy * ez[2], cy * ez[1] + cz * ez[2]
    # rows x1 and z1 of R(u1, u2)^T
    x10, x11, x12 = c1 * c2, s1 * c2, s2
    z10, z11, z12 = c1 * s2, s1 * s2, c2 * -1.0
    return (x10 * Ex0 + x11 * Ex1 + x12 * Ex2, s1 * Ex0 - c1 * Ex1,
            z10 * Ex0 + z11 * Ex1 + z12 * Ex2, x10 * Ez0 + x11 * Ez1 + x12 * Ez2,
            s1 * Ez0 - c1 * Ez1, z10 * Ez0 + z11 * Ez1 + z12 * Ez2)


def serial_angles(c1: float, s1: float, c2: float, s2: float, c3: float, s3: float, c4: float,
                  s4: float, W00: float, W10: float, W20: float
                  ) -> tuple[float, float, float, float, float]:
    """``u1..u5`` (rad) from the two angle pairs and the entries of :func:`wrist_matrix`.

    Plain Python over :mod:`math`, compiled by :mod:`athenakin.motion._kernels`.

    Returns
    -------
    u1, u2, u3, u4, u5 : float
    """
    return (math.atan2(s1, c1), math.atan2(s2, c2), math.atan2(s3, c3), math.atan2(s4, c4),
            math.atan2(s3 * W00 - c3 * W10, c3 * c4 * W00 + s3 * c4 * W10 + s4 * W20))


class TrackedPose(NamedTuple):
    """The tracked configuration of one sample (an immutable named tuple of plain floats).

    A named tuple rather than a frozen dataclass: building a frozen dataclass of 20
    fields costs about 4 us in CPython, a fifth of the per-sample budget.
    Wrap the vector fields with ``np.asarray`` for array maths.

    Attributes
    ----------
    sample : int
        Sample number (0 for the initial configuration).
    q : tuple of 3 float
        The reading, m.
    valid : bool
        False when the sample is ``LOST`` (then the fields below are those of the last
        valid sample).
    slot : int
        Forward-kinematics slot ``8 m + 4 r + 2 b + w`` (as in
        :class:`~athenakin.FKSolution`).
    mode, p_sign, ujoint, wrist : int
        Its labels (+1 / -1).
    p : float
        Signed distance from ``O_s`` to the RCM, m.
    u : tuple of 5 float
        Passive angles ``u1..u5``, radians in (-pi, pi].
    O_s : tuple of 3 float
        Origin of the serial chain, base frame, m.
    direction_b : tuple of 3 float
        Unit instrument axis ``z3`` (from ``O_s`` towards the RCM when ``p > 0``), base frame.
    tip_b, tip_e : tuple of 3 float
        Tool tip ``O_s + L z3`` in the base frame and in the RCM frame, m.
    half_chord, h, sin_u2, sin_u4 : float
        Singularity measures (see :class:`~athenakin.motion.SingularityMeasures`).
    step : float
        Distance to the previous pose in units of the jump thresholds (0 for the first).
    flags : TrackFlag
    clearance : float
        Least signed distance between the bodies and to the obstacles, m (negative:
        penetration); NaN when collisions are not checked or the sample is ``LOST``.
    closest_pair : tuple of 2 str
        The two names (body, body or obstacle) of ``clearance``; ``("", "")`` when NaN.
    """

    sample: int
    q: tuple[float, float, float]
    valid: bool
    slot: int
    mode: int
    p_sign: int
    ujoint: int
    wrist: int
    p: float
    u: tuple[float, float, float, float, float]
    O_s: tuple[float, float, float]
    direction_b: tuple[float, float, float]
    tip_b: tuple[float, float, float]
    tip_e: tuple[float, float, float]
    half_chord: float
    h: float
    sin_u2: float
    sin_u4: float
    step: float
    flags: TrackFlag
    clearance: float = math.nan
    closest_pair: tuple[str, str] = ("", "")


def _adiff(a: float, b: float) -> float:
    """``|wrap(a - b)|`` for angles in (-pi, pi]."""
    d = abs(a - b)
    return d if d <= math.pi else _TWO_PI - d


_FLAG_NONE = TrackFlag.NONE


# plain-int bits for the per-sample loop (IntFlag arithmetic costs about 1 us per operation)
_B = {f.name: int(f) for f in TrackFlag if f}


class _Geometry:
    """Design constants and the RCM frame as Python floats (for the scalar fast path)."""

    def __init__(self, T: FloatArray, design: Design) -> None:
        self.l1, self.l2, self.l3 = design.l1, design.l2, design.l3
        self.l4, self.l5 = design.l4, design.l5
        self.L = design.tool_length
        self.lo = tuple(float(v) for v in design.stroke_min)
        self.hi = tuple(float(v) for v in design.stroke_max)
        self.h_sign = design.h_sign
        self.c = tuple(float(v) for v in T[:3, 3])
        self.ex = tuple(float(v) for v in T[:3, 0])
        self.ez = tuple(float(v) for v in T[:3, 2])
        self.R = tuple(tuple(float(v) for v in row) for row in T[:3, :3])
        #: The closed form's parameter vector (Python floats) of the design without its
        #: strokes (``q3 >= 0`` only, a length): the tracker follows the mechanism beyond
        #: them and flags such a reading ``OUT_OF_STROKE`` instead of losing it.
        self.P = module_params(dataclasses.replace(design, q_min=None, q_max=None))


def _parallel(g: _Geometry, q1: float, q2: float, q3: float) -> tuple | None:
    """The module's closed form of a reading; None when the module cannot assemble.

    :func:`athenakin._mechanism_formulas.module_closed_form_formula` (the one source that
    :mod:`athenakin.fast._module_form` compiles) over :attr:`_Geometry.P`: the reference's
    validity rule (``parallel_forward_kinematics``) on the design without its strokes.
    ``math.sqrt`` raises (where the compiled one gives NaN) only for ``l1^2 - h^2 < 0`` or
    ``l3^2 - h^2 < 0``, that is ``|h| > l1`` or ``|h| > l3`` (rounding is monotonic): where
    the formula's reason is ``LINK_TOO_SHORT``.
    """
    try:
        par = module_closed_form_formula(q1, q2, q3, actuator_reason_formula(q1, q2, q3, g.P),
                                         g.P, TANGENT_TOL, math.sqrt)
    except ValueError:
        return None
    return None if par[0] != 0.0 else par


def _candidate(g: _Geometry, par: tuple, mode: int, r: int, b: int, w: int,
               hint: tuple | None) -> tuple | None:
    """The forward-kinematics solution with the given labels, from :func:`_parallel`'s ``par``.

    ``O_i`` is the reference's intersection of the mode (``a = 0`` where the circles are
    tangent: the modes merged into mode +1, the FK's ``_fk_stages._parallel_stage``), ``O_s``
    ``l4`` beyond it along ``z_i`` (the FK's ``_serial_stage``). At a serial singularity
    (``sin u2 = 0`` or ``sin u4 = 0``: a continuum of solutions) the free angle is taken
    from ``hint`` (the previous ``u1..u5``), the continuous choice; without a hint, or at
    ``p = 0`` or a merged assembly mode, None.
    """
    _, tangent, x_M, h, _, r1, _, _, _, half, iy, iz, ey, ez = par
    if mode == -1 and tangent:
        return None                      # merged into mode +1 at tangency
    a = mode * (0.0 if tangent else half)
    y = iy + a * ey
    z = iz + a * ez
    cy, cz = y / r1, z / r1
    Ox, Oy, Oz = x_M, y + g.l4 * cy, z + g.l4 * cz
    # RCM seen from O_s in frame s: R_b_s^T (c - O_s), R_b_s = [[1,0,0],[0,cz,cy],[0,-cy,cz]]
    bx, by, bz = g.c[0] - Ox, g.c[1] - Oy, g.c[2] - Oz
    cx, cys, czs = bx, cz * by - cy * bz, cy * by + cz * bz
    n = math.sqrt(cx * cx + cys * cys + czs * czs)
    if n <= P_ZERO_TOL:
        return None
    p = r * n
    zx, zy, zz = cx / p, cys / p, czs / p
    has_hint = hint is not None
    ok, rho, c1, s1, c2, s2 = angle_pair(zx, zy, zz, b, DEGENERATE_TOL, has_hint,
                                         0.0 if hint is None else hint[0])  # u1, u2
    if not ok:
        return None
    W00, W10, W20, W02, W12, W22 = wrist_matrix(c1, s1, c2, s2, cy, cz, g.ex, g.ez)
    ok, rho4, c3, s3, c4, s4 = angle_pair(W02, W12, W22, w, DEGENERATE_TOL, has_hint,
                                          0.0 if hint is None else hint[2])  # u3, u4
    if not ok:
        return None
    u1, u2, u3, u4, u5 = serial_angles(c1, s1, c2, s2, c3, s3, c4, s4, W00, W10, W20)
    if not math.isfinite(Ox + Oy + Oz + p + u1 + u2 + u3 + u4 + u5 + bx + by + bz):
        return None                      # overflow (readings near 1e308): no valid pose
    # instrument axis in the base frame: (c - O_s) / p
    return (mode, r, b, w, p, (u1, u2, u3, u4, u5), (Ox, Oy, Oz), (bx / p, by / p, bz / p),
            half, abs(h), rho, rho4)


def _clearance_text(pose: TrackedPose) -> str:
    if math.isnan(pose.clearance) or not pose.flags & _NEAR_COLLISION:
        return ""
    a, b = pose.closest_pair
    return f"; clearance {pose.clearance:.6g} m between {a!r} and {b!r}"


_NEAR_COLLISION = int(TrackFlag.NEAR_COLLISION)


@dataclasses.dataclass(frozen=True)
class TrackLog:
    """The poses of a whole stream as arrays (see :class:`TrackedPose` for the fields).

    Attributes
    ----------
    q : ndarray, shape (N, 3)
    valid : ndarray of bool, shape (N,)
    slot, mode, p_sign, ujoint, wrist : ndarray of int, shape (N,)
    p, half_chord, h, sin_u2, sin_u4, step : ndarray, shape (N,)
    u : ndarray, shape (N, 5)
    O_s, direction_b, tip_b, tip_e : ndarray, shape (N, 3)
    flags : ndarray of int, shape (N,)
        :class:`TrackFlag` bits.
    clearance : ndarray, shape (N,), or None
        Least clearance of the bodies, m; None when collisions are not checked (NaN only
        at invalid samples).
    closest_pair : ndarray of str, shape (N, 2), or None
        Its two names ("" when NaN).
    """

    q: FloatArray
    valid: BoolArray
    slot: IntArray
    mode: IntArray
    p_sign: IntArray
    ujoint: IntArray
    wrist: IntArray
    p: FloatArray
    u: FloatArray
    O_s: FloatArray
    direction_b: FloatArray
    tip_b: FloatArray
    tip_e: FloatArray
    half_chord: FloatArray
    h: FloatArray
    sin_u2: FloatArray
    sin_u4: FloatArray
    step: FloatArray
    flags: IntArray
    clearance: FloatArray | None
    closest_pair: NDArray[np.str_] | None

    def events(self) -> list[tuple[int, TrackFlag]]:
        """``(sample, flags)`` of every flagged sample.

        Returns
        -------
        list of (int, TrackFlag)
            Row of the sample in the log (0: the initial configuration) and its flags, in order.
        """
        return [(int(i), TrackFlag(int(self.flags[i]))) for i in np.flatnonzero(self.flags)]


# ---------------------------------------------------------------------- the batched tracker
_LOG_FIELDS = tuple(f.name for f in dataclasses.fields(TrackLog))


_FLOAT_FIELDS = ("p", "half_chord", "h", "sin_u2", "sin_u4", "step", "clearance")


_VEC_FIELDS = {"q": 3, "u": 5, "O_s": 3, "direction_b": 3, "tip_b": 3, "tip_e": 3}


_INT_FIELDS = ("slot", "mode", "p_sign", "ujoint", "wrist", "flags")


def _pairs(n: int, idx: NDArray[np.intp], pair: NDArray[np.str_]) -> NDArray[np.str_]:
    """The ``closest_pair`` column: ``pair`` at rows ``idx``, ``("", "")`` elsewhere."""
    out = [("", "")] * n
    for j, i in enumerate(idx.tolist()):
        out[i] = (str(pair[j, 0]), str(pair[j, 1]))
    return np.array(out).reshape(n, 2)


def _pose_columns(poses: list[TrackedPose]) -> dict[str, Any]:
    """Columns of :class:`TrackLog` (and ``sample``) from tracked poses."""
    cols: dict[str, Any] = {k: np.array([getattr(ps, k) for ps in poses])
                            for k in (*_LOG_FIELDS, "sample")}
    for k, m in _VEC_FIELDS.items():
        cols[k] = cols[k].reshape(len(poses), m).astype(float)
    cols["closest_pair"] = cols["closest_pair"].reshape(len(poses), 2)
    for k in _INT_FIELDS:
        cols[k] = cols[k].astype(np.int64)
    return cols


def _join(a: dict[str, Any], b: dict[str, Any]) -> dict[str, Any]:
    """Rows of ``b`` after those of ``a``."""
    return {k: np.concatenate([a[k], b[k]]) for k in a}


def pose_at(cols: dict[str, Any], i: int) -> TrackedPose:
    """Row ``i`` of columns (:func:`track_batch`) as a :class:`TrackedPose`."""
    f = int(cols["flags"][i])
    kw: dict[str, Any] = {k: float(cols[k][i]) for k in _FLOAT_FIELDS}
    kw.update({k: tuple(cols[k][i].tolist()) for k in _VEC_FIELDS})
    kw.update({k: int(cols[k][i]) for k in _INT_FIELDS})
    a, b = cols["closest_pair"][i].tolist()
    return TrackedPose(**kw | {"sample": int(cols["sample"][i]), "valid": bool(cols["valid"][i]),
                               "flags": TrackFlag(f) if f else _FLAG_NONE,
                               "closest_pair": (str(a), str(b))})


def _cand_row(c: tuple) -> list[float]:
    return [*c[:5], *c[5], *c[6], *c[7], *c[8:]]


def _cand_tuple(row: list[float]) -> tuple:
    return (int(row[0]), int(row[1]), int(row[2]), int(row[3]), row[4], tuple(row[5:10]),
            tuple(row[10:13]), tuple(row[13:16]), row[16], row[17], row[18], row[19])


def _empty_columns() -> dict[str, Any]:
    cols: dict[str, Any] = {k: np.empty((0, _VEC_FIELDS[k])) for k in _VEC_FIELDS}
    cols.update({k: np.empty(0) for k in _FLOAT_FIELDS})
    cols.update({k: np.empty(0, np.int64) for k in (*_INT_FIELDS, "sample")})
    cols["valid"] = np.empty(0, bool)
    cols["closest_pair"] = np.empty((0, 2), "<U1")
    return cols
