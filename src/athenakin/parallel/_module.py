"""The 3-DoF parallel module (paper Eq. 7-10, Section 4): both assembly modes and its IK.

Geometry (docs/conventions.md): ``A = (q1, 0, 0)``, ``B = (q2, 0, 0)``, midpoint ``M``,
``h = (q1 - q2) / 2``. In the plane ``x = x_M`` (coordinates ``(y, z)`` relative
to ``M``), circle ``k1`` has centre ``(0, 0)`` and radius ``r1 = sqrt(l1^2 - h^2)``;
circle ``k2`` has centre ``C = (m_y, l5)``, ``m_y = sqrt(l3^2 - h^2) + l2``, and
radius ``q3``. ``O_i`` is an intersection; mode ``+1`` has the larger z.

The intersection is computed in the stable factored form
``w = m_y^2 * (r1 + q3 - d)(r1 + q3 + d)(d - r1 + q3)(d + r1 - q3)``, ``d = |C|``,
which is the paper's ``w`` of Eq. 8; the printed Eq. 8 has ``sqrt(w)`` in the
y coordinate where ``-l5/m_y * sqrt(w)`` belongs (see docs/errata.md).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import ArrayLike

from .._transforms import wrap_angle
from .._typing import BoolArray, FloatArray, Int8Array, IntArray
from .._validation import check_array, check_tolerance, check_transform
from ..design import Design, resolve_design
from ..errors import Reason

__all__ = [
    "TANGENT_TOL",
    "MODES",
    "ParallelSolution",
    "ParallelIK",
    "parallel_forward_kinematics",
    "parallel_ik_from_position",
    "parallel_inverse_kinematics",
    "circle_geometry",
    "IK_ROUNDING_ULPS",
    "position_ik_error",
]

#: Half-chord length (m) of ``k1 ∩ k2`` at or below which the circles count as tangent.
#: Near tangency the intersection moves like ``sqrt(w)``: a rounding error of one ulp
#: in ``q3`` (1e-16 m) alone changes the half-chord by about ``sqrt(1e-16 m * 0.3 m) ~
#: 5e-9 m`` on the reference design; below 1e-7 m (a hundred times the rounding noise,
#: a tenth of a micrometre) the two modes are numerically the same configuration.
TANGENT_TOL = 1e-7

#: Assembly-mode labels in slot order.
MODES = np.array([1, -1])


@dataclasses.dataclass(frozen=True)
class ParallelSolution:
    """Both assembly modes of the parallel module for a batch of ``q``.

    Attributes
    ----------
    valid : ndarray of bool, shape (..., 2)
        Slot 0 is mode +1, slot 1 mode -1.
    reason : ndarray of int, shape (..., 2)
        :class:`~athenakin.errors.Reason` codes (0 where valid).
    mode : ndarray of int, shape (2,)
        ``(+1, -1)``.
    O_i, O_s : ndarray, shape (..., 2, 3)
        Origins of the intermediate frame and of the serial base frame, base
        coordinates, m (NaN in invalid slots).
    T_b_i, T_b_s : ndarray, shape (..., 2, 4, 4)
        Poses of the intermediate frame and of ``O_s`` (Eq. 9, 10, with the
        rotation entries divided by ``r1``).
    theta : ndarray, shape (..., 2)
        Angle of ``R_b_i = Rx(theta)``, radians in (-pi, pi].
    r1, m_y, w, half_chord : ndarray, shape (...)
        Radius of ``k1``, y of C, the paper's ``w`` (Eq. 8) and the half-chord
        ``a = sqrt(max(w, 0)) / (2 m_y d)`` of the two intersections (m).
    residual : ndarray, shape (..., 2)
        How far (m) the reported ``O_s`` may be from the true mechanism's, from the
        rounding of ``k`` (:func:`parallel_residual`; about 1e-15 m for an isolated
        intersection, growing like ``1 / a`` towards tangency); where the modes merge
        (half-chord ``<= tangent_tol``) ``O_i`` is put at the chord midpoint, up to the
        half-chord ``a`` off the true intersections, and ``O_s`` up to
        ``a (r1 + l4) / r1``, plus that rounding. NaN in invalid slots.
        :func:`~athenakin.forward_kinematics` adds it to every slot's ``residual``.
    """

    valid: BoolArray
    reason: Int8Array
    mode: IntArray
    O_i: FloatArray
    O_s: FloatArray
    T_b_i: FloatArray
    T_b_s: FloatArray
    theta: FloatArray
    r1: FloatArray
    m_y: FloatArray
    w: FloatArray
    half_chord: FloatArray
    residual: FloatArray


@dataclasses.dataclass(frozen=True)
class ParallelIK:
    """Result of the parallel module's inverse kinematics.

    Attributes
    ----------
    q : ndarray, shape (..., 3)
        Actuator values ``(q1, q2, q3)``, m (NaN where invalid).
    mode : ndarray of int, shape (...)
        Assembly mode of the pose (+1 or -1; +1 on the tangent boundary; 0 where invalid).
    theta : ndarray, shape (...)
        ``R_b_s = Rx(theta)``, radians.
    valid : ndarray of bool, shape (...)
    reason : ndarray of int, shape (...)
    q_error : ndarray, shape (...)
        The conditioning of the solution: a bound (m) on the error of every entry of
        ``q`` caused by rounding of ``O_s`` (see :func:`position_ik_error`); NaN where
        invalid. Near ``q1 = q2`` the IK is ill-conditioned (``dq ~ sqrt(dO_s)``) and
        this grows to about ``1e-7`` m on the reference design.
    """

    q: FloatArray
    mode: IntArray
    theta: FloatArray
    valid: BoolArray
    reason: Int8Array
    q_error: FloatArray


def _actuator_checks(q: FloatArray, design: Design) -> Int8Array:
    """Reason code per item for non-finite values, stroke limits and A/B order."""
    reason = np.zeros(q.shape[:-1], dtype=np.int8)
    finite = np.all(np.isfinite(q), axis=-1)
    lo, hi = design.stroke_min, design.stroke_max
    with np.errstate(invalid="ignore"):
        stroke = np.any((q < lo) | (q > hi), axis=-1)
        order = design.h_sign * (q[..., 0] - q[..., 1]) < 0
    reason = np.where(order, np.int8(Reason.AB_ORDER), reason)
    reason = np.where(stroke, np.int8(Reason.STROKE_LIMIT), reason)
    reason = np.where(~finite, np.int8(Reason.NONFINITE_INPUT), reason)
    return reason.astype(np.int8)


def circle_terms(r1: FloatArray, m_y: FloatArray, l5: float,
                 q3: FloatArray) -> tuple[FloatArray, ...]:
    """The terms of Eq. 8 that meet the circles ``k1`` (radius ``r1`` about ``M``) and ``k2``.

    ``k2`` has radius ``q3`` about ``C = M + (m_y, l5)`` in the plane ``x = x_M``.
    Unchecked and without tolerances (callers decide what a negative ``k`` means).

    Parameters
    ----------
    r1, m_y, q3 : ndarray, shape (...)
        m (NaN propagates).
    l5 : float
        m.

    Returns
    -------
    d2, d, H, k : ndarray, shape (...)
        ``d^2 = |C - M|^2``, ``d``, ``H = d^2 + r1^2 - q3^2`` (the paper's ``h``) and
        ``k = (r1 + q3 - d)(r1 + q3 + d)(d - r1 + q3)(d + r1 - q3) = 4 d^2 a^2``
        (``a`` the half-chord; ``k < 0``: the circles do not meet).
    """
    d2 = m_y * m_y + l5 * l5
    d = np.sqrt(d2)
    H = d2 + r1 * r1 - q3 * q3
    k = (r1 + q3 - d) * (r1 + q3 + d) * (d - r1 + q3) * (d + r1 - q3)
    return d2, d, H, k


def circle_geometry(q: ArrayLike, design: Design) -> dict[str, FloatArray]:
    """The quantities of Eq. 7-8 for a batch of ``q``.

    Parameters
    ----------
    q : array-like, shape (..., 3)
    design : Design

    Returns
    -------
    dict of ndarray, each shape (...)
        ``x_M``, ``h``, ``r1``, ``m_y``, ``d`` (= ``|C - M|``), ``H`` (the paper's
        ``h = m_y^2 + l5^2 + r1^2 - q3^2``), ``k = w / m_y^2 = 4 d^2 a^2``, ``w`` (the
        paper's ``w``) and ``half_chord`` ``a`` (0 where ``k < 0``). ``r1`` and
        ``m_y`` are NaN where the links cannot span A-B.
    """
    design = resolve_design(design)
    q = check_array(q, "q", (3,), allow_nonfinite=True)
    q1, q2, q3 = q[..., 0], q[..., 1], q[..., 2]
    h = 0.5 * (q1 - q2)
    with np.errstate(invalid="ignore"):
        r1 = np.sqrt(design.l1 ** 2 - h * h)
        m_y = np.sqrt(design.l3 ** 2 - h * h) + design.l2
        d2, d, H, k = circle_terms(r1, m_y, design.l5, q3)
        half = np.sqrt(np.maximum(k, 0.0)) / (2 * d)
    return {"x_M": 0.5 * (q1 + q2), "h": h, "r1": r1, "m_y": m_y, "d": d, "H": H,
            "k": k, "w": m_y * m_y * k, "half_chord": half}


def _frames(x_M: FloatArray, y: FloatArray, z: FloatArray,
            r1: FloatArray, l4: float
            ) -> tuple[FloatArray, FloatArray]:
    """T_b_i and T_b_s from O_i = (x_M, y, z) on k1 of radius r1."""
    cy, cz = y / r1, z / r1  # z_i = (0, cy, cz)
    T = np.zeros(np.shape(y) + (4, 4))
    T[..., 0, 0] = 1.0
    T[..., 1, 1] = cz
    T[..., 1, 2] = cy
    T[..., 2, 1] = -cy
    T[..., 2, 2] = cz
    T[..., 3, 3] = 1.0
    T[..., 0, 3] = x_M
    T[..., 1, 3] = y
    T[..., 2, 3] = z
    Ts = T.copy()
    Ts[..., 1, 3] = y + l4 * cy
    Ts[..., 2, 3] = z + l4 * cz
    return T, Ts


#: 4 machine epsilons: the rounding allowance of each factor of ``k`` (Eq. 8) per unit of
#: the lengths it is made of.
K_ROUND = 4.0 * 2.220446049250313e-16


def parallel_residual(r1: FloatArray, q3: FloatArray, d: FloatArray,
                      k: FloatArray, l1: float, l4: float,
                      tangent: BoolArray) -> FloatArray:
    """Bound on the position error of ``O_s`` caused by the rounding of ``k`` (m).

    ``k = 4 d^2 a^2`` (Eq. 8, ``a`` the half-chord) is a product of four factors; near
    tangency one of them is a difference of nearly equal lengths and its rounding,
    about ``eps`` times the lengths, dominates: ``|dk| <= dk = 4 eps S sum_i |prod_{j != i}
    f_j|`` with ``S = r1 + |q3| + d + l1^2 / r1`` (the last term: the rounding of
    ``r1 = sqrt(l1^2 - h^2)``). The true half-chord then lies in
    ``[sqrt(max(k - dk, 0)), sqrt(|k| + dk)] / (2 d)``; a merged (``tangent``) mode,
    drawn at half-chord 0, is off by up to the upper end, a distinct mode by the width
    of the interval. ``O_s`` is ``(r1 + l4) / r1`` times as far from the axis as ``O_i``.

    The operations, and their order, are those of the compiled kernel
    (``athenakin.fast._scalar.parallel_residual``): both backends decide the validity
    of a near-tangent slot (:func:`athenakin.forward_kinematics`: residual at most
    ``closure_tol``, else ``CIRCLES_TANGENT``) from the same bits.
    """
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        a1 = (r1 + q3) - d
        a2 = (r1 + q3) + d
        a3 = (d - r1) + q3
        a4 = (d + r1) - q3
        s = ((r1 + np.abs(q3)) + d) + (l1 * l1) / r1
        dk = (K_ROUND * s) * (((np.abs((a2 * a3) * a4) + np.abs((a1 * a3) * a4))
                               + np.abs((a1 * a2) * a4)) + np.abs((a1 * a2) * a3))
        two_d = 2.0 * d
        hi = np.sqrt(np.abs(k) + dk) / two_d
        kl = k - dk
        lo = np.sqrt(np.where(kl > 0.0, kl, 0.0)) / two_d
        err = np.where(tangent, hi, hi - lo)
        return err * ((r1 + l4) / r1)


def parallel_forward_kinematics(q: ArrayLike, design: Design | None = None, *,
                                tangent_tol: float = TANGENT_TOL) -> ParallelSolution:
    """Forward kinematics of the parallel module: both intersections of ``k1`` and ``k2``.

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Actuator values ``(q1, q2, q3)`` in metres. NaN/inf items are flagged
        (``Reason.NONFINITE_INPUT``), not raised.
    design : Design, optional
        Defaults to :meth:`Design.default`.
    tangent_tol : float, keyword-only
        Half-chord (m) at or below which ``k1`` and ``k2`` count as tangent
        (paper's ``w = 0``): mode -1 is then reported as merged into mode +1
        (``Reason.CIRCLES_TANGENT``). Range ``[0, 1e-3]`` m
        (:data:`athenakin._validation.TOLERANCE_MAXIMA`).

    Returns
    -------
    ParallelSolution
        Slot 0 mode +1, slot 1 mode -1 (Eq. 8-10).

    Raises
    ------
    TypeError, InvalidInputError
        Wrong type or trailing shape of ``q``.
    """
    design = resolve_design(design)
    q = check_array(q, "q", (3,), allow_nonfinite=True)
    tangent_tol = check_tolerance(tangent_tol, "tangent_tol")
    reason = _actuator_checks(q, design)
    qs = np.where(reason[..., None] == Reason.NONFINITE_INPUT, 0.0, q)
    g = circle_geometry(qs, design)
    h = g["h"]
    link = (np.abs(h) >= design.l1) | (np.abs(h) > design.l3)
    reason = np.where((reason == 0) & link, np.int8(Reason.LINK_TOO_SHORT), reason)
    # signed half-chord: negative when the circles are apart (k < 0)
    k = g["k"]
    signed = np.sign(k) * np.sqrt(np.abs(k)) / (2 * g["d"])
    disjoint = ~link & (signed < -tangent_tol)
    reason = np.where((reason == 0) & disjoint, np.int8(Reason.CIRCLES_DISJOINT), reason)
    ok = reason == 0
    tangent = ok & (g["half_chord"] <= tangent_tol)

    safe = np.where(ok, 1.0, np.nan)
    r1, m_y, d, H = g["r1"] * safe, g["m_y"] * safe, g["d"] * safe, g["H"] * safe
    l5 = design.l5
    a = np.where(tangent, 0.0, g["half_chord"]) * safe  # half-chord
    by, bz = H * m_y / (2 * d * d), H * l5 / (2 * d * d)
    ey, ez = -l5 / d, m_y / d  # unit vector along the chord, pointing to larger z
    s = MODES.astype(float)
    y = by[..., None] + s * a[..., None] * ey[..., None]
    z = bz[..., None] + s * a[..., None] * ez[..., None]
    x_M = np.broadcast_to(g["x_M"][..., None], y.shape) * safe[..., None]
    T_b_i, T_b_s = _frames(x_M, y, z, r1[..., None], design.l4)

    slot_reason = np.stack([reason, np.where(tangent, np.int8(Reason.CIRCLES_TANGENT), reason)],
                           axis=-1).astype(np.int8)
    valid = slot_reason == 0
    nanmask = np.where(valid, 1.0, np.nan)
    T_b_i = T_b_i * nanmask[..., None, None]
    T_b_s = T_b_s * nanmask[..., None, None]
    theta = wrap_angle(np.arctan2(-y / r1[..., None], z / r1[..., None])) * nanmask
    pres = parallel_residual(g["r1"], qs[..., 2], g["d"], k, design.l1, design.l4,
                             tangent) * safe
    return ParallelSolution(
        valid=valid, reason=slot_reason, mode=MODES.copy(),
        O_i=T_b_i[..., :3, 3], O_s=T_b_s[..., :3, 3], T_b_i=T_b_i, T_b_s=T_b_s, theta=theta,
        r1=g["r1"], m_y=g["m_y"], w=g["w"], half_chord=g["half_chord"],
        residual=pres[..., None] * nanmask)


def parallel_ik_from_position(O_s: ArrayLike, design: Design | None = None) -> ParallelIK:
    """Actuator values that put ``O_s`` at a given point (paper Section 4, first paragraph).

    The orientation follows from the position: ``z_i`` is the unit vector from
    the base x-axis to ``O_s`` in the plane ``x = x_M``.

    Parameters
    ----------
    O_s : array-like, shape (..., 3)
        Position of the serial base frame, base coordinates, m.
    design : Design, optional

    Returns
    -------
    ParallelIK
        Invalid items carry a reason: ``NOT_IN_MODULE_IMAGE`` (closer than
        ``l4`` to the rail axis), ``LINK_TOO_SHORT`` (``r1 > l1`` or ``|h| > l3``),
        ``STROKE_LIMIT``, ``NONFINITE_INPUT``.
    """
    design = resolve_design(design)
    O_s = check_array(O_s, "O_s", (3,), allow_nonfinite=True)
    return position_ik(O_s, design)


#: Rounding of a position, in units of ``eps * (|O_s| + l1 + l4)``, that the parallel IK
#: absorbs: a point that the forward kinematics put at ``r1 = l1`` (``q1 = q2``) comes back
#: a few ulps beyond ``l1`` and must not read as "out of the workspace".
IK_ROUNDING_ULPS = 64.0


def position_ik(O_s: FloatArray, design: Design,
                dO: FloatArray | float = 0.0) -> ParallelIK:
    """:func:`parallel_ik_from_position` on a checked array (private; shared with the robot IK).

    ``dO`` is a bound (m) on the error of ``O_s`` already present in the input
    (from an upstream computation); rounding of ``O_s`` itself is always added.
    """
    finite = np.all(np.isfinite(O_s), axis=-1)
    P = np.where(finite[..., None], O_s, 0.0)
    scale = np.max(np.abs(P[..., 1:]), axis=-1, initial=0.0)   # what r1 is computed from
    with np.errstate(over="ignore", invalid="ignore"):
        rho = np.hypot(P[..., 1], P[..., 2])
    reason = np.where(finite, 0, Reason.NONFINITE_INPUT).astype(np.int8)
    reason = np.where((reason == 0) & (rho <= design.l4), np.int8(Reason.NOT_IN_MODULE_IMAGE),
                      reason)
    l1, l3 = design.l1, design.l3
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        r1 = rho - design.l4
        dr = IK_ROUNDING_ULPS * _EPS * (scale + l1 + design.l4) + dO
        # within rounding of the span: h = 0 (ill-conditioned, not out of the workspace)
        r1 = np.where((r1 > l1) & (r1 - l1 <= dr), l1, r1)
        h_abs = np.sqrt((l1 - r1) * (l1 + r1))
        # within rounding of |h| = l3 (links l3 stretched along the rail): on it, not out
        # of the workspace (the FK produces such poses)
        h_abs = np.where((h_abs > l3) & (h_abs - l3 <= _h_error(r1, h_abs, dr)), l3, h_abs)
        bad_link = (r1 > l1) | (h_abs > l3)
        reason = np.where((reason == 0) & bad_link, np.int8(Reason.LINK_TOO_SHORT), reason)
        ok = reason == 0
        # |h| indistinguishable from 0 at this rounding: q1 = q2 exactly
        h_abs = np.where(h_abs * h_abs <= 2.0 * r1 * dr, 0.0, h_abs)
        safe = np.where(ok, 1.0, np.nan)
        h = design.h_sign * h_abs * safe
        x_M = P[..., 0] * safe
        f = r1 / rho
        y, z = P[..., 1] * f * safe, P[..., 2] * f * safe
        m_y = np.sqrt(l3 ** 2 - h * h) + design.l2
        q3 = np.hypot(y - m_y, z - design.l5)
        cross = m_y * z - design.l5 * y
        # and the rounding of x_M (q1, q2 = x_M +/- h)
        err = _q_error(r1, h_abs, dr, design) + IK_ROUNDING_ULPS * _EPS * np.abs(P[..., 0])
    mode = np.where(cross >= 0, 1, -1)
    q = np.stack([x_M + h, x_M - h, q3], axis=-1)
    # within the error bound of a stroke limit: on it (a pose the FK produced at the limit)
    lo, hi = design.stroke_min, design.stroke_max
    e = err[..., None]
    with np.errstate(invalid="ignore"):
        q = np.where((q < lo) & (q >= lo - e), lo, q)
        q = np.where((q > hi) & (q <= hi + e), hi, q)
    act = _actuator_checks(np.where(ok[..., None], q, 0.0), design)
    reason = np.where(ok & (act != 0), act, reason).astype(np.int8)
    valid = reason == 0
    q = np.where(valid[..., None], q, np.nan)
    theta = np.where(valid, wrap_angle(np.arctan2(-y, z)), np.nan)
    return ParallelIK(q=q, mode=np.where(valid, mode, 0), theta=theta, valid=valid,
                      reason=reason, q_error=np.where(valid, err, np.nan))


_EPS = float(np.finfo(float).eps)


def _q_error(r1: FloatArray, h_abs: FloatArray, dr: FloatArray,
             design: Design) -> FloatArray:
    """Bound on the error of ``q`` for an error ``dr`` of ``r1`` (and of ``O_s``).

    ``|h(r1 + dr) - h(r1)| <= 2 r1 dr / (sqrt(h^2 + 2 r1 dr) + h)`` (``h = sqrt(l1^2 -
    r1^2)``): ``r1 dr / h`` away from ``h = 0`` and ``sqrt(2 r1 dr)`` at it. ``q3`` moves
    with ``O_i`` (``dr``) and with ``m_y`` (``|h| dh / sqrt(l3^2 - h^2)``).
    """
    dh = _h_error(r1, h_abs, dr)
    s3 = np.sqrt(np.maximum(design.l3 ** 2 - (h_abs + dh) ** 2, 0.0))
    # m_y = sqrt(l3^2 - h^2): slope (h + dh) / s3 away from |h| = l3, and at most
    # sqrt(|h'^2 - h^2|) <= sqrt((2 h + dh) dh) everywhere (the square root's modulus)
    near = np.sqrt((2.0 * h_abs + dh) * dh)
    dmy = np.where(s3 > 0, np.minimum((h_abs + dh) * dh / np.where(s3 > 0, s3, 1.0), near),
                   near)
    return 2.0 * dr + dh + dmy


def _h_error(r1: FloatArray, h_abs: FloatArray, dr: FloatArray
             ) -> FloatArray:
    """Bound on the error of ``|h| = sqrt(l1^2 - r1^2)`` for an error ``dr`` of ``r1``."""
    r1p = np.maximum(r1, 0.0)
    return 2.0 * r1p * dr / (np.sqrt(h_abs * h_abs + 2.0 * r1p * dr) + h_abs) + dr


def position_ik_error(O_s: ArrayLike, design: Design | None = None,
                      dO: ArrayLike = 0.0) -> FloatArray:
    """Bound (m) on the error of :func:`parallel_ik_from_position`'s ``q`` at ``O_s``.

    Parameters
    ----------
    O_s : array-like, shape (..., 3)
        Position of the serial base frame, m (NaN items give NaN).
    design : Design, optional
    dO : array-like, shape (...)
        Error (m) already in ``O_s``; rounding of ``O_s`` (``IK_ROUNDING_ULPS`` ulps of
        ``|O_s| + l1 + l4``) is added.

    Returns
    -------
    ndarray, shape (...)
        The ``q_error`` that :class:`ParallelIK` reports.
    """
    design = resolve_design(design)
    pos = check_array(O_s, "O_s", (3,), allow_nonfinite=True)
    dO = check_array(dO, "dO", ())
    return position_ik(pos, design, dO).q_error


def link_detail(O_s: ArrayLike, design: Design) -> str:
    """Say why ``O_s`` (3,) fails the link test: too far from, or too close to, the rail axis."""
    pos = np.asarray(O_s, dtype=float)
    rho = float(np.hypot(pos[1], pos[2]))
    far = rho - design.l4 > design.l1
    if far:
        return (f"O_s is {rho:.6g} m from the rail axis, farther than l1 + l4 = "
                f"{design.l1 + design.l4:.6g} m (too far)")
    lim = design.l4 + float(np.sqrt(max(design.l1 ** 2 - design.l3 ** 2, 0.0)))
    return (f"O_s is {rho:.6g} m from the rail axis, closer than l4 + sqrt(l1^2 - l3^2) = "
            f"{lim:.6g} m: |h| would exceed l3 (too close)")


#: Tolerance on the orientation test of :func:`parallel_inverse_kinematics`.
MODULE_POSE_TOL = 1e-9


def parallel_inverse_kinematics(T_b_s: ArrayLike, design: Design | None = None, *,
                                tol: float = MODULE_POSE_TOL) -> ParallelIK:
    """Inverse kinematics of the parallel module from a pose of ``O_s``.

    A pose is in the module's image only if ``R_b_s = Rx(theta)`` and ``z_s``
    points from the base x-axis to ``O_s`` (paper Section 4).

    Parameters
    ----------
    T_b_s : array-like, shape (..., 4, 4)
    design : Design, optional
    tol : float, keyword-only
        Tolerance of the orientation test.

    Returns
    -------
    ParallelIK
        Items whose orientation is not that of the module get ``NOT_IN_MODULE_IMAGE``.
    """
    design = resolve_design(design)
    T = check_transform(T_b_s, "T_b_s", allow_nonfinite=True)
    return module_orientation_check(parallel_ik_from_position(T[..., :3, 3], design), T, tol)


def module_orientation_check(res: ParallelIK, T: FloatArray, tol: float) -> ParallelIK:
    """Invalidate the items of a position IK whose pose ``T`` is not ``Rx(theta)`` (private).

    Shared by the reference and the compiled :func:`parallel_inverse_kinematics`.
    """
    tol = check_tolerance(tol, "tol")
    R = T[..., :3, :3]
    with np.errstate(invalid="ignore"):
        c, s = np.cos(res.theta), np.sin(res.theta)
        Rx = np.zeros(R.shape)
        Rx[..., 0, 0] = 1.0
        Rx[..., 1, 1], Rx[..., 1, 2], Rx[..., 2, 1], Rx[..., 2, 2] = c, -s, s, c
        err = np.abs(R - Rx).max(axis=(-2, -1))
    bad = res.valid & ~(err <= tol)
    reason = np.where(bad, np.int8(Reason.NOT_IN_MODULE_IMAGE), res.reason).astype(np.int8)
    valid = reason == 0
    return dataclasses.replace(
        res, q=np.where(valid[..., None], res.q, np.nan),
        theta=np.where(valid, res.theta, np.nan), valid=valid, reason=reason,
        q_error=np.where(valid, res.q_error, np.nan))
