"""Certified forward kinematics: rigorous enclosures of all 16 solutions (ball arithmetic).

The argument (docs/certified.md) follows the closed form of the forward kinematics,
evaluated in ball arithmetic (python-flint's ``arb``: midpoint-radius intervals with
outward rounding, arbitrary precision) over the input ball:

1. **Parallel module.** ``k = (r1+q3-d)(r1+q3+d)(d-r1+q3)(d+r1-q3)`` decides the
   number of assembly modes: ``k > 0`` proven gives exactly two (one of each label),
   ``k < 0`` proven none (``k1``, ``k2`` disjoint), a ball holding 0 decides nothing
   (tangency).
2. **Serial chain**, for each mode, with ``c = R_b_s^T (t_e - O_s)``, ``n = |c|``,
   ``rho = |(c_x, c_y)| / n``, ``rho4 = |sin u4|``: if ``n > 0``, ``rho > 0`` and
   ``rho4 > 0`` are proven, the chain has exactly 8 solutions (``p = +-n``; two U-joint
   branches; two wrist branches) and no other, and each is an explicit function of the
   data, enclosed here step by step. The 8 are derived from five base angles by exact
   identities (``u1 -> u1 + pi``, ``u2 -> -u2``, ``u2 -> pi - u2``, ...).
3. **Uniqueness.** The boxes of distinct solutions are checked pairwise disjoint
   (angles modulo 2 pi), so each certified box holds exactly one solution and, with
   the count of step 1-2, no solution is missed.

The rotation of ``T_b_e`` is taken through Gram-Schmidt (``z_e`` normalised, then
``x_e`` made orthogonal to it), an exact map to a rotation that equals the input's
within its rigidity tolerance; the certificate is about that rigid transform.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._typing import BoolArray, FloatArray, Int8Array, IntArray
from .._validation import check_array, check_transform
from ..chain import SERIAL_P_SIGN, SERIAL_UJOINT, SERIAL_WRIST
from ..design import Design, resolve_design
from ..errors import InvalidInputError, Reason
from ._balls import angle, ball, import_flint, sign, wrap

__all__ = ["CertStatus", "CertifiedFK", "certified_forward_kinematics",
           "DEFAULT_INPUT_TOL", "DEFAULT_PREC", "MAX_PREC", "OUTPUT_ULPS", "MAX_CERTIFIED_ITEMS"]

#: Relative radius of the input ball (q, T_b_e entries, design lengths): the unit
#: roundoff of float64, i.e. every input stands for all reals that round to it.
DEFAULT_INPUT_TOL = 2.0 ** -53
#: Working precision (bits) of the first attempt.
DEFAULT_PREC = 128
#: Largest precision (bits) tried before a slot is reported undecided.
MAX_PREC = 1024
#: Each box is widened by this many ulps of its scale (pi for angles, the item's largest
#: length for lengths) beyond the rigorous enclosure: room for the last rounding steps of
#: a floating-point solver (atan2, sqrt), so that its solutions lie inside. The box still
#: holds the exact solution and no other one.
OUTPUT_ULPS = 8

_N_FIELDS = 12   # p, u1..u5, O_s (3), tip (3)
_ANGLE_COLS = slice(1, 6)
_LENGTH_COLS = np.r_[0, 6:12]
_TWO_PI = 2.0 * np.pi


class CertStatus(enum.IntEnum):
    """What the certificate says of one FK slot."""

    #: The box holds exactly one exact solution, and it is this slot's.
    CERTIFIED = 0
    #: Proven: the slot holds no solution (strokes, order, links, circles apart).
    ABSENT = 1
    #: Undecided at the largest precision (a singular set, or the input ball meets one).
    UNDECIDED = 2
    #: The slot's box meets another solution's box: uniqueness not proven.
    NOT_SEPARATED = 3
    #: The item holds NaN or inf (batch only; a single item raises).
    NONFINITE_INPUT = 4


_CERTIFIED = int(CertStatus.CERTIFIED)


@dataclasses.dataclass(frozen=True)
class CertifiedFK:
    """Certified enclosures of the 16 FK slots of a batch (leading shape ``...``).

    Slot ``k = 8 m + 4 r + 2 b + w`` as in :class:`athenakin.FKSolution`. Boxes are
    closed intervals of floats: the ball enclosure rounded outward and widened by
    :data:`OUTPUT_ULPS` ulps of its scale; they are NaN where a slot is not certified.

    Attributes
    ----------
    certified : ndarray of bool, shape (..., 16)
        The box holds exactly one exact solution, for every input in the input ball.
    status : ndarray of int8, shape (..., 16)
        :class:`CertStatus` per slot.
    reason : ndarray of int8, shape (..., 16)
        :class:`~athenakin.errors.Reason`: 0 where certified; why the slot is absent,
        or which singular set it could not exclude.
    p_lo, p_hi : ndarray, shape (..., 16)
        Enclosure of the passive prismatic joint ``p``, m.
    u_lo, u_hi : ndarray, shape (..., 16, 5)
        Enclosures of ``u1..u5``, rad. Each box is an interval of width < 2 pi whose
        midpoint lies in (-pi, pi]; it may extend beyond +-pi (angles modulo 2 pi).
    O_s_lo, O_s_hi : ndarray, shape (..., 16, 3)
        Enclosure of ``O_s`` (base frame), m.
    tip_lo, tip_hi : ndarray, shape (..., 16, 3)
        Enclosure of the tool tip ``O_s + tool_length * z3`` (base frame), m.
    complete : ndarray of bool, shape (...)
        Every slot is certified or proven absent: the number of real solutions is
        proven to be :attr:`n_certified`.
    prec : ndarray of int, shape (...)
        Precision (bits) of the final attempt.
    input_tol : float
        Relative radius of the input ball the certificate covers.
    """

    certified: BoolArray
    status: Int8Array
    reason: Int8Array
    p_lo: FloatArray
    p_hi: FloatArray
    u_lo: FloatArray
    u_hi: FloatArray
    O_s_lo: FloatArray
    O_s_hi: FloatArray
    tip_lo: FloatArray
    tip_hi: FloatArray
    complete: BoolArray
    prec: IntArray
    input_tol: float

    @property
    def n_certified(self) -> IntArray:
        """Number of certified slots per item, shape (...)."""
        return np.sum(self.certified, axis=-1)

    def contains(self, p: ArrayLike, u: ArrayLike) -> BoolArray:
        """Which slots' boxes contain the given solutions (angles modulo 2 pi).

        Parameters
        ----------
        p : array-like, shape (..., 16)
            Prismatic joint per slot, m (e.g. ``FKSolution.p``).
        u : array-like, shape (..., 16, 5)
            ``u1..u5`` per slot, rad.

        Returns
        -------
        ndarray of bool, shape (..., 16)
            False where the slot is not certified or the value lies outside its box.
        """
        p = np.asarray(p, dtype=float)
        u = np.asarray(u, dtype=float)
        inside_p = (self.p_lo <= p) & (p <= self.p_hi)
        # bring u into the box: the representative of u modulo 2 pi nearest the box middle
        mid = 0.5 * (self.u_lo + self.u_hi)
        with np.errstate(invalid="ignore"):
            shifted = u + _TWO_PI * np.round((mid - u) / _TWO_PI)
            inside_u = np.all((self.u_lo <= shifted) & (shifted <= self.u_hi), axis=-1)
        return self.certified & inside_p & inside_u


#: Most items certified in one call (checked before any work): interval arithmetic takes
#: about 0.3 ms per item, so this is a few seconds; a larger batch is refused by name.
MAX_CERTIFIED_ITEMS = 10_000


def certified_forward_kinematics(q: ArrayLike, T_b_e: ArrayLike, design: Design | None = None,
                                 *, input_tol: float = DEFAULT_INPUT_TOL,
                                 prec: int = DEFAULT_PREC, max_prec: int = MAX_PREC
                                 ) -> CertifiedFK:
    """All 16 forward-kinematics slots with rigorous enclosures and a proof of count.

    Needs python-flint (extra ``[certified]``).

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Actuators ``(q1, q2, q3)``, m.
    T_b_e : array-like, shape (..., 4, 4)
        RCM frame (rigid within the usual tolerance); broadcasts with ``q``.
    design : Design, optional
        Defaults to :meth:`Design.default`.
    input_tol : float, keyword-only
        Relative radius of the input ball: every entry ``x`` of ``q``, ``T_b_e`` and the
        design lengths stands for ``x (1 +- input_tol)``. The default covers the
        rounding of a backward-stable floating-point solver, so that its solutions lie
        in the boxes; ``0`` certifies the exact input alone (tightest boxes).
    prec : int, keyword-only
        Working precision (bits) of the first attempt; doubled, up to ``max_prec``,
        while a slot is undecided.
    max_prec : int, keyword-only
        Largest precision tried.

    Returns
    -------
    CertifiedFK

    Raises
    ------
    ImportError
        python-flint is missing.
    TypeError, InvalidInputError
        Wrong type or shape, ``T_b_e`` not rigid, bad tolerances; NaN/inf in a single
        item (a batch flags it as ``CertStatus.NONFINITE_INPUT``); a batch of more than
        :data:`MAX_CERTIFIED_ITEMS` items.

    Examples
    --------
    >>> import athenakin as ak
    >>> d = ak.Design.default()
    >>> cert = ak.certified_forward_kinematics([-0.10, 0.10, 0.45], ak.default_rcm_frame(d), d)
    >>> int(cert.n_certified), bool(cert.complete)
    (16, True)
    """
    flint = import_flint()
    design = resolve_design(design)
    input_tol = _check_tol(input_tol)
    prec, max_prec = _check_prec(prec, max_prec)
    qb, Tb, batch = _items(q, T_b_e)
    n = qb.shape[0]
    status = np.empty((n, 16), np.int8)
    reason = np.empty((n, 16), np.int8)
    lo = np.full((n, 16, _N_FIELDS), np.nan)
    hi = np.full((n, 16, _N_FIELDS), np.nan)
    used = np.empty(n, np.int64)
    old = flint.ctx.prec
    try:
        for i in range(n):
            status[i], reason[i], lo[i], hi[i], used[i] = _certify_item(
                flint, qb[i], Tb[i], design, input_tol, prec, max_prec)
    finally:
        flint.ctx.prec = old
    complete = np.all((status == CertStatus.CERTIFIED) | (status == CertStatus.ABSENT), axis=-1)

    def shape(a: NDArray[Any], tail: tuple[int, ...] = ()) -> NDArray[Any]:
        return a.reshape(batch + (16,) + tail)

    return CertifiedFK(
        certified=shape(status == CertStatus.CERTIFIED), status=shape(status),
        reason=shape(reason), p_lo=shape(lo[..., 0]), p_hi=shape(hi[..., 0]),
        u_lo=shape(lo[..., _ANGLE_COLS], (5,)), u_hi=shape(hi[..., _ANGLE_COLS], (5,)),
        O_s_lo=shape(lo[..., 6:9], (3,)), O_s_hi=shape(hi[..., 6:9], (3,)),
        tip_lo=shape(lo[..., 9:12], (3,)), tip_hi=shape(hi[..., 9:12], (3,)),
        complete=complete.reshape(batch), prec=used.reshape(batch), input_tol=input_tol)


def _items(q: ArrayLike, T_b_e: ArrayLike
           ) -> tuple[FloatArray, FloatArray, tuple[int, ...]]:
    """The items to certify: ``q`` (n, 3), ``T_b_e`` (n, 4, 4) and their batch shape.

    NaN and inf are allowed in a batch (flagged per item), not in a single item; a batch
    of more than :data:`MAX_CERTIFIED_ITEMS` items is refused before any work.
    """
    qa = check_array(q, "q", (3,), allow_nonfinite=True)
    T = check_transform(T_b_e, "T_b_e", allow_nonfinite=True)
    try:
        batch = np.broadcast_shapes(qa.shape[:-1], T.shape[:-2])
    except ValueError:
        raise InvalidInputError(f"q and T_b_e: expected broadcastable batch shapes, got "
                                f"q {qa.shape} and T_b_e {T.shape}") from None
    if batch == ():
        check_array(qa, "q", (3,))
        check_array(T, "T_b_e", (4, 4))
    n_items = int(np.prod(batch, dtype=np.int64))
    if n_items > MAX_CERTIFIED_ITEMS:
        raise InvalidInputError(
            f"q, T_b_e: a batch of {n_items:,} items, more than the {MAX_CERTIFIED_ITEMS:,} "
            f"certified per call (about 0.3 ms each in interval arithmetic); certify the "
            f"items that matter, or split the batch")
    return (np.broadcast_to(qa, batch + (3,)).reshape(-1, 3),
            np.broadcast_to(T, batch + (4, 4)).reshape(-1, 4, 4), batch)


def _check_tol(input_tol: object) -> float:
    if isinstance(input_tol, bool) or not isinstance(input_tol, (int, float, np.floating,
                                                                 np.integer)):
        raise TypeError(f"input_tol: expected a real number, got {type(input_tol).__name__}")
    try:
        tol = float(input_tol)
    except OverflowError:
        tol = math.inf
    if not (0.0 <= tol <= 1e-6):
        raise InvalidInputError(f"input_tol: expected a relative radius in [0, 1e-6], got {tol!r}")
    return tol


def _check_prec(prec: object, max_prec: object) -> tuple[int, int]:
    for name, v in (("prec", prec), ("max_prec", max_prec)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
            raise TypeError(f"{name}: expected an int (bits), got {type(v).__name__}")
    p, m = int(prec), int(max_prec)  # type: ignore[call-overload]
    if not 16 <= p <= m <= 65536:
        raise InvalidInputError(f"prec, max_prec: expected 16 <= prec <= max_prec <= 65536 bits, "
                                f"got prec = {p}, max_prec = {m}")
    return p, m


# --------------------------------------------------------------------------- one item
def _certify_item(flint: Any, q: FloatArray, T: FloatArray, design: Design,
                  rel: float, prec: int, max_prec: int
                  ) -> tuple[Int8Array, Int8Array, FloatArray,
                             FloatArray, int]:
    status = np.full(16, CertStatus.ABSENT, np.int8)
    reason = np.zeros(16, np.int8)
    lo = np.full((16, _N_FIELDS), np.nan)
    hi = np.full((16, _N_FIELDS), np.nan)
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(T))):
        status[:] = CertStatus.NONFINITE_INPUT
        reason[:] = Reason.NONFINITE_INPUT
        return status, reason, lo, hi, prec
    pre = _actuator_reason(q, design)
    if pre:
        reason[:] = pre
        return status, reason, lo, hi, prec
    while True:
        flint.ctx.prec = prec
        status, reason, mid, rad = _solve(flint.arb, q, T, design, rel)
        lo, hi = _float_boxes(mid, rad)
        _separate(status, lo, hi)
        undecided = np.any((status == CertStatus.UNDECIDED) | (status == CertStatus.NOT_SEPARATED))
        if not undecided or prec >= max_prec:
            break
        prec = min(2 * prec, max_prec)
    keep = status == CertStatus.CERTIFIED
    lo[~keep] = np.nan
    hi[~keep] = np.nan
    return status, reason, lo, hi, prec


def _actuator_reason(q: FloatArray, design: Design) -> int:
    """Stroke limits and A/B order: exact comparisons of the given floats."""
    if np.any((q < design.stroke_min) | (q > design.stroke_max)):
        return int(Reason.STROKE_LIMIT)
    if design.h_sign * (q[0] - q[1]) < 0:
        return int(Reason.AB_ORDER)
    return 0


def _solve(arb: Any, qf: FloatArray, Tf: FloatArray, design: Design,
           rel: float) -> tuple[Int8Array, Int8Array, FloatArray,
                                FloatArray]:
    """Ball evaluation of the closed form at the current precision.

    Returns status and reason per slot and the midpoints and radii (16, 12) of the
    enclosures of ``p, u1..u5, O_s, tip`` (NaN where not certified).
    """
    status = np.full(16, CertStatus.UNDECIDED, np.int8)
    reason = np.zeros(16, np.int8)
    mid = np.full((16, _N_FIELDS), np.nan)
    rad = np.full((16, _N_FIELDS), np.nan)

    def B(x: float) -> Any:
        return ball(arb, float(x), rel)

    pi = arb.pi()
    q1, q2, q3 = B(qf[0]), B(qf[1]), B(qf[2])
    l1, l2, l3, l4, l5 = (B(v) for v in design.lengths)
    L = B(design.tool_length)

    # ---- parallel module (Eq. 7-8)
    why, absent, module = _module_balls(arb, q1, q2, q3, l1, l2, l3, l5)
    if why:
        if absent:
            status[:] = CertStatus.ABSENT
        reason[:] = why
        return status, reason, mid, rad
    r1, a, by, bz, ey, ez, x_M = module

    t_e, x_e, z_e = _rcm_axes(B, Tf)

    for m, s in enumerate((1, -1)):
        y = by + s * a * ey
        z = bz + s * a * ez
        cy, cz = y / r1, z / r1                     # z_i = (0, cy, cz), R_b_s = Rx(theta)
        O_s = [x_M, y + l4 * cy, z + l4 * cz]
        slots = slice(8 * m, 8 * m + 8)
        # O_s is known even where the serial chain is undecided: it separates the modes
        mid[slots, 6:9], rad[slots, 6:9] = np.transpose([_mid_rad(c) for c in O_s])
        v = [t_e[i] - O_s[i] for i in range(3)]
        why, n, angles = _serial_balls(pi, v, cy, cz, x_e, z_e)
        if why:
            reason[slots] = why
            continue
        _store_eight(mid, rad, status, m, pi, angles, _mid_rad(n),
                     [(L / n) * v[i] for i in range(3)], O_s)
    return status, reason, mid, rad


def _serial_balls(pi: Any, v: list[Any], cy: Any, cz: Any, x_e: list[Any], z_e: list[Any]
                  ) -> tuple[int, Any, tuple[Any, ...]]:
    """The serial chain of one assembly mode in balls: ``(reason, n, five base angles)``.

    ``v = t_e - O_s`` (base frame), ``(0, cy, cz)`` the axis ``z_i`` (``R_b_s = Rx(theta)``),
    ``x_e``, ``z_e`` the RCM axes. ``reason`` is 0 where ``n = |v| > 0``, ``|sin u2| > 0``
    and ``|sin u4| > 0`` are proven and the base angles ``alpha, beta, delta, zeta, gamma``
    are enclosed; else the singular set that could not be excluded (``n``, angles: None).
    """
    n2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
    if sign(n2) == 0:
        return int(Reason.SERIAL_P_ZERO), None, ()
    n = n2.sqrt()
    # R_b_s^T w = (w0, cz w1 - cy w2, cy w1 + cz w2)
    chat = [v[0] / n, (cz * v[1] - cy * v[2]) / n, (cy * v[1] + cz * v[2]) / n]
    col0 = [x_e[0], cz * x_e[1] - cy * x_e[2], cy * x_e[1] + cz * x_e[2]]
    col2 = [z_e[0], cz * z_e[1] - cy * z_e[2], cy * z_e[1] + cz * z_e[2]]
    rho2 = chat[0] * chat[0] + chat[1] * chat[1]
    if sign(rho2) == 0:
        return int(Reason.UJOINT_SINGULAR), None, ()
    rho = rho2.sqrt()
    a1, b1 = chat[0] / rho, chat[1] / rho
    X0 = (-a1 * chat[2], -b1 * chat[2], rho)
    P0 = X0[0] * col0[0] + X0[1] * col0[1] + X0[2] * col0[2]
    P2 = X0[0] * col2[0] + X0[1] * col2[1] + X0[2] * col2[2]
    Q0 = b1 * col0[0] - a1 * col0[1]
    Q2 = b1 * col2[0] - a1 * col2[1]
    S0 = chat[0] * col0[0] + chat[1] * col0[1] + chat[2] * col0[2]
    S2 = chat[0] * col2[0] + chat[1] * col2[1] + chat[2] * col2[2]
    rho4sq = P2 * P2 + Q2 * Q2
    if sign(rho4sq) == 0:
        return int(Reason.WRIST_SINGULAR), None, ()
    rho4 = rho4sq.sqrt()
    Y = (Q2 * P0 - P2 * Q0) / rho4
    X = rho4 * S0 - S2 * (P2 * P0 + Q2 * Q0) / rho4
    alpha = angle(chat[1], chat[0], pi)
    beta = angle(rho, -chat[2], pi)
    delta = angle(Q2, P2, pi)
    zeta = angle(rho4, -S2, pi)
    gamma = angle(Y, X, pi)
    if alpha is None or beta is None:
        return int(Reason.UJOINT_SINGULAR), None, ()
    if delta is None or zeta is None or gamma is None:
        return int(Reason.WRIST_SINGULAR), None, ()
    return 0, n, (alpha, beta, delta, zeta, gamma)


def _module_balls(arb: Any, q1: Any, q2: Any, q3: Any, l1: Any, l2: Any, l3: Any,
                  l5: Any) -> tuple[int, bool, tuple[Any, ...]]:
    """The parallel module in balls: ``(reason, absent, (r1, a, by, bz, ey, ez, x_M))``.

    ``reason`` is nonzero where no slot can be certified (the values are then ``()``):
    ``absent`` True where the module is certainly not assembled, False where the balls
    cannot decide.
    """
    h = (q1 - q2) / 2
    r1sq = l1 * l1 - h * h
    m3 = l3 * l3 - h * h
    s_r1, s_m3 = sign(r1sq), sign(m3)
    if s_r1 < 0 or s_m3 < 0 or (s_r1 == 0 and r1sq.is_zero()):
        return Reason.LINK_TOO_SHORT, True, ()
    if s_r1 == 0 or (s_m3 == 0 and not m3.is_zero()):
        return Reason.LINK_TOO_SHORT, False, ()
    r1 = r1sq.sqrt()
    m_y = (m3.sqrt() if s_m3 else arb(0)) + l2
    d2 = m_y * m_y + l5 * l5
    d = d2.sqrt()
    k = (r1 + q3 - d) * (r1 + q3 + d) * (d - r1 + q3) * (d + r1 - q3)
    s_k = sign(k)
    if s_k < 0:
        return Reason.CIRCLES_DISJOINT, True, ()
    if s_k == 0:
        return Reason.CIRCLES_TANGENT, False, ()
    a = k.sqrt() / (2 * d)
    H = d2 + r1sq - q3 * q3
    by, bz = H * m_y / (2 * d2), H * l5 / (2 * d2)
    ey, ez = -l5 / d, m_y / d
    x_M = (q1 + q2) / 2
    return 0, False, (r1, a, by, bz, ey, ez, x_M)


def _rcm_axes(B: Callable[[float], Any], Tf: FloatArray
              ) -> tuple[list[Any], list[Any], list[Any]]:
    """RCM frame in balls: translation and Gram-Schmidt rotation (columns ``x_e``, ``z_e``)."""
    t_e = [B(Tf[i, 3]) for i in range(3)]
    zc = [B(Tf[i, 2]) for i in range(3)]
    zn = (zc[0] * zc[0] + zc[1] * zc[1] + zc[2] * zc[2]).sqrt()
    z_e = [v / zn for v in zc]
    xc = [B(Tf[i, 0]) for i in range(3)]
    dot = xc[0] * z_e[0] + xc[1] * z_e[1] + xc[2] * z_e[2]
    xo = [xc[i] - dot * z_e[i] for i in range(3)]
    xn = (xo[0] * xo[0] + xo[1] * xo[1] + xo[2] * xo[2]).sqrt()
    x_e = [v / xn for v in xo]
    return t_e, x_e, z_e


def _store_eight(mid: FloatArray, rad: FloatArray, status: Int8Array,
                 m: int, pi: Any, base: tuple[Any, ...], n_mr: tuple[float, float],
                 step: list[Any], O_s: list[Any]) -> None:
    """The eight serial solutions of mode ``m`` from the base angles, into its rows.

    ``base`` is ``(alpha, beta, delta, zeta, gamma)``, ``n_mr`` the midpoint and radius
    of ``|p|``, ``step`` the tool vector (balls).
    """
    alpha, beta, delta, zeta, gamma = base
    # the eight solutions from the base angles (exact identities, module docstring):
    # each distinct value is enclosed and converted once, the slots index into them
    cand: dict[str, dict[Any, Any]] = {
        "u1": {1: alpha, -1: alpha + pi},                                 # by eps
        "u2": {(1, 1): beta, (-1, 1): -beta, (1, -1): pi - beta,
               (-1, -1): beta - pi},                                      # by (sigma, r)
        "u3": {(1, 1): delta, (-1, -1): delta + pi, (1, -1): -delta,
               (-1, 1): pi - delta},                                      # by tau (sigma, eps)
        "u4": {(1, 1): zeta, (-1, 1): -zeta, (1, -1): pi - zeta,
               (-1, -1): zeta - pi},                                      # by (tau, r)
        "u5": {1: gamma, -1: gamma + pi},                                 # by tau r
    }
    num = {name: {key: _mid_rad(wrap(b, pi)) for key, b in d.items()}
           for name, d in cand.items()}
    p_mr = {1: n_mr, -1: (-n_mr[0], n_mr[1])}
    tip_mr = {r: [_mid_rad(O_s[i] + step[i] if r > 0 else O_s[i] - step[i])
                  for i in range(3)] for r in (1, -1)}
    for k_s in range(8):
        r, sg, tau = int(SERIAL_P_SIGN[k_s]), int(SERIAL_UJOINT[k_s]), int(SERIAL_WRIST[k_s])
        eps = sg * r
        row = 8 * m + k_s
        vals = [p_mr[r], num["u1"][eps], num["u2"][(sg, r)],
                num["u3"][(tau * sg, tau * eps)], num["u4"][(tau, r)], num["u5"][tau * r],
                *tip_mr[r]]
        cols = [0, 1, 2, 3, 4, 5, 9, 10, 11]
        mid[row, cols] = [x[0] for x in vals]
        rad[row, cols] = [x[1] for x in vals]
        status[row] = _CERTIFIED


def _mid_rad(x: Any) -> tuple[float, float]:
    """Midpoint and radius of a ball as floats (each rounded to nearest)."""
    return float(x.mid()), float(x.rad())


def _float_boxes(mid: FloatArray, rad: FloatArray
                 ) -> tuple[FloatArray, FloatArray]:
    """Float intervals that contain the balls ``[mid +- rad]`` (rounded outward).

    ``mid`` and ``rad`` are the balls' midpoints and radii rounded to nearest, so each
    is within half an ulp of the exact value; the margin covers both, the rounding of
    the subtraction/addition itself and :data:`OUTPUT_ULPS`.
    """
    scale = np.full(_N_FIELDS, np.pi)
    lengths = np.abs(mid[:, _LENGTH_COLS])
    scale[_LENGTH_COLS] = np.max(lengths, initial=0.0, where=np.isfinite(lengths))
    with np.errstate(invalid="ignore"):
        margin = (rad * (1.0 + 2.0 ** -50) + 2.0 * np.spacing(np.abs(mid))
                  + OUTPUT_ULPS * np.spacing(np.maximum(np.abs(mid), scale)) + 1e-300)
        lo = np.nextafter(mid - margin, -np.inf)
        hi = np.nextafter(mid + margin, np.inf)
    return lo, hi


def _separate(status: Int8Array, lo: FloatArray, hi: FloatArray
              ) -> None:
    """Mark certified slots whose box meets another known solution's box (in place).

    A slot whose serial chain is undecided but whose ``O_s`` is known stands for a box
    with that ``O_s`` and unbounded ``p, u``.
    """
    cert = status == CertStatus.CERTIFIED
    if not np.any(cert):
        return
    known = cert | np.isfinite(lo[:, 6])          # O_s known (the parallel part decided)
    L = np.where(np.isfinite(lo), lo, -np.inf)
    H = np.where(np.isfinite(hi), hi, np.inf)
    lin = np.r_[0, 6, 7, 8]
    ang = np.arange(1, 6)
    meet = np.all((L[:, None, lin] <= H[None, :, lin]) & (L[None, :, lin] <= H[:, None, lin]),
                  axis=-1)
    angmeet = np.zeros((16, 16, 5), bool)
    for shift in (-_TWO_PI, 0.0, _TWO_PI):
        angmeet |= ((L[:, None, ang] <= H[None, :, ang] + shift)
                    & (L[None, :, ang] + shift <= H[:, None, ang]))
    meet &= np.all(angmeet, axis=-1)
    np.fill_diagonal(meet, False)
    bad = cert & np.any(meet & known[None, :], axis=-1)
    status[bad] = CertStatus.NOT_SEPARATED
