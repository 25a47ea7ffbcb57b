"""Whole-robot inverse kinematics (paper Section 4) and the controller forms.

Paper form: given the RCM frame ``T_b_e`` and the spherical-joint angles
``u3, u4, u5``, the frame ``W`` at the RCM with the instrument as z-axis is
``T_b_w = T_b_e (R(u3, u4) Rz(u5))^-1``. Its y-axis ``y_w = R_b_s (s1, -c1, 0)``
is perpendicular to ``z_s``, which fixes ``theta`` of ``R_b_s = Rx(theta)`` up to
a half turn (the two solutions of the bilinear Eq. 16). ``O_s = c - p z_w`` must
lie on the plane through the base x-axis spanned by ``z_s``: one linear
equation in ``p``. The half turn is then fixed by ``z_s`` pointing away from the
rail axis, and the parallel module's IK gives ``q``.

The construction fails (a continuum of ``q``) when ``y_w`` is parallel to the
base x-axis (``cos u1 = 0``) or the instrument is perpendicular to ``y_s``
(``sin u1 sin u2 = 0``): there the paper's uniqueness claim does not hold
(docs/errata.md).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._transforms import transform_from_rotation_translation, wrap_angle
from .._typing import BoolArray, FloatArray, Int8Array, IntArray
from .._validation import broadcast_batch, check_array, check_names, check_options, check_transform
from ..chain._ups import (
    CLOSURE_TOL,
    P_ZERO_TOL,
    _ups_transform,
    closure_residual,
    rotation_u_pair,
)
from ..design import Design
from ..errors import Reason
from ..parallel._module import IK_ROUNDING_ULPS, link_detail, parallel_ik_from_position, position_ik
from ._common import (
    ErrorPolicy,
    PartialFields,
    ReferenceBackend,
    check_reference_backend,
    partial_result,
    raise_first_failure,
    resolve_design,
    resolve_policy,
)

__all__ = [
    "IK_FIELDS",
    "IK_SINGULAR_TOL",
    "check_ik_fields",
    "passive_joints",
    "PassiveJoints",
    "InstrumentIK",
    "inverse_kinematics",
    "q_from_instrument",
    "q_from_tool_tip",
    "direction_from_angles",
    "angles_from_direction",
]

#: Dimensionless size (``|cos u1|``, ``|sin u1 sin u2|``) at or below which the
#: paper-form IK is declared singular (``Reason.IK_SINGULAR``).
IK_SINGULAR_TOL = 1e-12

#: Largest error bound ``q_error`` (m) of a valid paper-form IK result: beyond it, close
#: to the singular sets ``cos u1 = 0`` and ``sin u1 sin u2 = 0`` (where the error grows like
#: ``eps / distance``), rounding alone could move ``q`` by more than 10 micrometres and the
#: item is flagged ``IK_SINGULAR`` instead. At ``q1 = q2`` the bound is about 1e-6 m
#: (``dq ~ sqrt(dO_s)``): those poses are solved, not flagged.
IK_Q_ERROR_MAX = 1e-5


#: The arrays a :class:`PassiveJoints` can hold, for ``inverse_kinematics(..., fields=...)``.
IK_FIELDS = ("p", "u", "mode", "T_b_s", "residual", "valid", "reason")
#: Each field is the attribute of its name (:func:`missing_field`).
_IK_ATTRS = {f: f for f in IK_FIELDS}


@dataclasses.dataclass(frozen=True)
class PassiveJoints(PartialFields):
    """Passive joints and frames from :func:`inverse_kinematics` (leading shape ``...``).

    Attributes
    ----------
    p : ndarray, shape (...)
        Passive prismatic joint, m.
    u : ndarray, shape (..., 5)
        ``u1..u5`` in (-pi, pi] (``u3..u5`` are the given ones, wrapped).
    mode : ndarray of int, shape (...)
        Assembly mode of the parallel module (+1 / -1; 0 where invalid).
    T_b_s : ndarray, shape (..., 4, 4)
        Pose of ``O_s``.
    residual : ndarray, shape (...)
        Closure residual of ``T_b_s @ T_s_e(p, u)`` against ``T_b_e``.
    valid : ndarray of bool, shape (...)
    reason : ndarray of int8, shape (...)
        :class:`~athenakin.errors.Reason` (0 where valid).
    q_error : ndarray, shape (...)
        Conditioning of the solution: a bound (m) on the error of ``q`` from rounding,
        amplified near the singular sets (``1 / (|cos u1| |sin u1 sin u2|)`` for ``p``,
        ``sqrt`` at ``q1 = q2``). NaN where invalid; never above :data:`IK_Q_ERROR_MAX`
        in a valid item (beyond it the item is ``IK_SINGULAR``).

    A result computed with ``fields=(...)`` holds only those arrays; reading
    another one raises an ``AttributeError`` that says so.
    """

    p: FloatArray
    u: FloatArray
    mode: IntArray
    T_b_s: FloatArray
    residual: FloatArray
    valid: BoolArray
    reason: Int8Array
    q_error: FloatArray
    _FIELDS_OF = (IK_FIELDS, _IK_ATTRS, "inverse_kinematics")

    @property
    def u1(self) -> FloatArray:
        """U-joint angle ``u1``, shape (...)."""
        return self.u[..., 0]

    @property
    def u2(self) -> FloatArray:
        """U-joint angle ``u2``, shape (...)."""
        return self.u[..., 1]


def check_ik_fields(fields: str | tuple[str, ...] | list[str] | None
                    ) -> tuple[str, ...] | None:
    """Validate ``fields`` of :func:`inverse_kinematics`: None (all) or names in :data:`IK_FIELDS`.

    The errors of :func:`athenakin.robot._fk.check_fields`, for the names of :data:`IK_FIELDS`.
    """
    return check_names(fields, "fields", IK_FIELDS)


def passive_joints(fields: tuple[str, ...] | None, **arrays: Any) -> PassiveJoints:
    """A :class:`PassiveJoints` of ``arrays``, or of only ``fields`` of them."""
    if fields is not None:
        return partial_result(PassiveJoints, arrays, fields)
    return PassiveJoints(**arrays)


@dataclasses.dataclass(frozen=True)
class InstrumentIK:
    """Result of the controller-form IK (:func:`q_from_instrument`, :func:`q_from_tool_tip`).

    Attributes
    ----------
    p : ndarray, shape (...)
        Insertion: signed distance ``O_s`` -> RCM along the instrument, m.
    direction_b : ndarray, shape (..., 3)
        Unit instrument direction (``O_s`` towards the RCM for ``p > 0``), base frame.
    O_s : ndarray, shape (..., 3)
        Position of ``O_s``, base frame, m.
    mode : ndarray of int, shape (...)
        Assembly mode (+1 / -1; 0 where invalid).
    valid : ndarray of bool, shape (...)
    reason : ndarray of int8, shape (...)
    q_error : ndarray, shape (...)
        Conditioning of the solution: a bound (m) on the error of ``q`` from rounding
        (largest, about 1e-7 m, at ``q1 = q2``); NaN where invalid.
    """

    p: FloatArray
    direction_b: FloatArray
    O_s: FloatArray
    mode: IntArray
    valid: BoolArray
    reason: Int8Array
    q_error: FloatArray



def inverse_kinematics(T_b_e: ArrayLike, u345: ArrayLike, design: Design | None = None, *,
                       errors: ErrorPolicy = "auto", singular_tol: float = IK_SINGULAR_TOL,
                       closure_tol: float = CLOSURE_TOL, fields: tuple[str, ...] | None = None,
                       backend: ReferenceBackend = "numpy"
                       ) -> tuple[FloatArray, PassiveJoints]:
    """The numpy reference of :func:`athenakin.inverse_kinematics` (the compiled kernels' oracle).

    Parameters
    ----------
    T_b_e, u345, design, errors, singular_tol, closure_tol, fields
        As in :func:`athenakin.inverse_kinematics`.
    backend : {"numpy"}, keyword-only
        Only the reference; :func:`athenakin.inverse_kinematics` chooses the backend.

    Returns
    -------
    q, passive : ndarray (..., 3), PassiveJoints
        As :func:`athenakin.inverse_kinematics` (``q`` in m).
    """
    check_reference_backend(backend, "inverse_kinematics")
    names = check_ik_fields(fields)
    design, T, u345, batch, raise_now, singular_tol, closure_tol = check_ik_arguments(
        T_b_e, u345, design, errors, singular_tol, closure_tol)
    T = np.broadcast_to(T, batch + (4, 4))
    u345 = np.broadcast_to(u345, batch + (3,))
    if raise_now:
        check_array(T, "T_b_e", (4, 4))
        check_array(u345, "u345", (3,))
    finite = np.all(np.isfinite(T), axis=(-2, -1)) & np.all(np.isfinite(u345), axis=-1)
    Tf = np.where(finite[..., None, None], T, np.eye(4))
    uf = np.where(finite[..., None], u345, 0.0)

    c3, s3 = np.cos(uf[..., 0]), np.sin(uf[..., 0])
    c4, s4 = np.cos(uf[..., 1]), np.sin(uf[..., 1])
    c5, s5 = np.cos(uf[..., 2]), np.sin(uf[..., 2])
    W = rotation_u_pair(c3, s3, c4, s4)
    W = W @ np.stack([c5, -s5, 0 * c5, s5, c5, 0 * c5, 0 * c5, 0 * c5, 1 + 0 * c5],
                     axis=-1).reshape(c5.shape + (3, 3))
    R_b_w = Tf[..., :3, :3] @ np.swapaxes(W, -1, -2)
    c = Tf[..., :3, 3]
    z3, yw = R_b_w[..., :, 2], R_b_w[..., :, 1]
    ny = np.hypot(yw[..., 1], yw[..., 2])
    n = yw[..., 1:] / np.where(ny > 0, ny, 1.0)[..., None]
    den = np.sum(z3[..., 1:] * n, axis=-1)
    singular = (ny <= singular_tol) | (np.abs(den) <= singular_tol)
    reason = np.where(finite, 0, Reason.NONFINITE_INPUT).astype(np.int8)
    reason = np.where((reason == 0) & singular, np.int8(Reason.IK_SINGULAR), reason)
    p = np.sum(c[..., 1:] * n, axis=-1) / np.where(singular, 1.0, den)
    O_s = c - p[..., None] * z3
    dO = paper_o_error(c, p, ny, den)
    pik = position_ik(np.where((reason == 0)[..., None], O_s, np.nan), design, dO)
    reason = np.where(reason == 0, pik.reason, reason).astype(np.int8)
    reason = np.where((reason == 0) & ~(pik.q_error <= IK_Q_ERROR_MAX),
                      np.int8(Reason.IK_SINGULAR), reason).astype(np.int8)

    ct, st = np.cos(pik.theta), np.sin(pik.theta)
    zero, one = np.zeros_like(ct), np.ones_like(ct)
    R_b_s = np.stack([one, zero, zero, zero, ct, -st, zero, st, ct],
                     axis=-1).reshape(ct.shape + (3, 3))
    R12 = np.swapaxes(R_b_s, -1, -2) @ R_b_w
    u1 = np.arctan2(R12[..., 0, 1], -R12[..., 1, 1])
    u2 = np.arctan2(R12[..., 2, 0], -R12[..., 2, 2])
    u = wrap_angle(np.concatenate([np.stack([u1, u2], axis=-1), uf], axis=-1))
    T_b_s = transform_from_rotation_translation(R_b_s, O_s)
    with np.errstate(invalid="ignore"):
        res = closure_residual(T_b_s @ _ups_transform(p, u), Tf)
        reason = np.where((reason == 0) & ~(res <= closure_tol), np.int8(Reason.CLOSURE_FAILED),
                          reason).astype(np.int8)
    valid = reason == 0
    if raise_now:
        raise_first_failure(reason, "inverse kinematics", {"u345": u345, "p_rcm_b": c},
                            design=design, q_of=lambda idx: _unlimited_q(O_s[idx], design),
                            detail_of=lambda idx: _detail(int(reason[idx]), O_s[idx], design))
    nan = np.where(valid, 1.0, np.nan)
    q = pik.q * nan[..., None]
    passive = passive_joints(names, p=p * nan, u=u * nan[..., None],
                             mode=np.where(valid, pik.mode, 0),
                             T_b_s=T_b_s * nan[..., None, None], residual=res * nan,
                             valid=valid, reason=reason, q_error=pik.q_error * nan)
    return q, passive


def check_ik_arguments(T_b_e: ArrayLike, u345: ArrayLike, design: Design | None, errors: str,
                       singular_tol: object, closure_tol: object
                       ) -> tuple[Design, FloatArray, FloatArray,
                                  tuple[int, ...], bool, float, float]:
    """The one validation path of the paper-form IK, for every backend (private).

    Order: options (``errors``, tolerances), design, ``T_b_e``, ``u345``, batch broadcast.
    """
    stol, ctol = check_options(errors, singular_tol=singular_tol, closure_tol=closure_tol)
    design = resolve_design(design)
    T = check_transform(T_b_e, "T_b_e", allow_nonfinite=True)
    u345 = check_array(u345, "u345", (3,), allow_nonfinite=True)
    batch = broadcast_batch(T_b_e=T.shape[:-2], u345=u345.shape[:-1])
    raise_now = resolve_policy(errors, batch)
    return design, T, u345, batch, raise_now, stol, ctol


def paper_o_error(c: FloatArray, p: FloatArray, ny: FloatArray,
                  den: FloatArray) -> FloatArray:
    """Bound (m) on the error of ``O_s = c - p z_w`` in the paper-form IK (private).

    ``n = y_w / |y_w|`` carries a relative error ``eps / ny`` and ``p = (c . n) / den``
    divides it by ``den``: ``dp ~ eps (|c| + |p|) (1 + 1 / ny) / |den|`` (the numba kernel
    computes the same, :func:`athenakin.fast._ik_kernels.paper_o_error`).
    """
    s = np.sum(np.abs(c), axis=-1) + np.abs(p)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        a = np.where(ny > 0, 1.0 + 1.0 / np.where(ny > 0, ny, 1.0), np.inf)
        ad = np.abs(den)
        return np.where(ad > 0, IK_ROUNDING_ULPS * _EPS * s * (a / np.where(ad > 0, ad, 1.0)),
                        np.inf)


_EPS = float(np.finfo(float).eps)


def _detail(code: int, O_s: FloatArray, design: Design) -> str:
    """Extra words for a failure at ``O_s``: which way the link test failed."""
    if code == Reason.LINK_TOO_SHORT and np.all(np.isfinite(O_s)):
        return link_detail(O_s, design)
    return ""


def _unlimited_q(O_s: FloatArray, design: Design) -> FloatArray:
    """Actuator values for ``O_s`` ignoring the stroke limits (to name a violated limit)."""
    free = dataclasses.replace(design, q_min=None, q_max=None)
    return parallel_ik_from_position(O_s, free).q


def direction_from_angles(azimuth: ArrayLike, polar: ArrayLike) -> FloatArray:
    """Unit instrument direction in the RCM frame E from two angles about the RCM.

    Spherical coordinates about ``z_e`` (the axis of the last spherical joint,
    whose alignment with the instrument is the spherical joint's singularity):
    ``d_e = (sin(polar) cos(azimuth), sin(polar) sin(azimuth), cos(polar))``.

    Parameters
    ----------
    azimuth, polar : array-like, shape (...)
        Radians; ``polar`` is the angle from ``z_e``.

    Returns
    -------
    ndarray, shape (..., 3)
    """
    a = check_array(azimuth, "azimuth", ())
    b = check_array(polar, "polar", ())
    a, b = np.broadcast_arrays(a, b)
    return np.stack([np.sin(b) * np.cos(a), np.sin(b) * np.sin(a), np.cos(b)], axis=-1)


def angles_from_direction(direction_e: ArrayLike) -> tuple[FloatArray,
                                                           FloatArray]:
    """Inverse of :func:`direction_from_angles`: ``(azimuth, polar)`` of a direction.

    Parameters
    ----------
    direction_e : array-like, shape (..., 3)
        Non-zero direction (normalised here).

    Returns
    -------
    azimuth : ndarray, shape (...)
        In (-pi, pi]; 0 on the poles, where it is undefined.
    polar : ndarray, shape (...)
        In [0, pi].
    """
    d = _unit(check_array(direction_e, "direction_e", (3,)), "direction_e")
    az = np.arctan2(d[..., 1], d[..., 0])
    az = np.where(az <= -np.pi, az + 2 * np.pi, az)
    return az, np.arctan2(np.hypot(d[..., 0], d[..., 1]), d[..., 2])


def _unit(d: FloatArray, name: str) -> FloatArray:
    """``d / |d|`` scaled by the largest component first (no underflow or overflow).

    Non-finite items give NaN; a zero vector raises.
    """
    m = np.max(np.abs(d), axis=-1, keepdims=True)
    if np.any(m == 0):
        from ..errors import InvalidInputError

        raise InvalidInputError(f"{name}: expected a non-zero direction vector, got zero")
    with np.errstate(invalid="ignore"):
        ds = d / m
        return ds / np.linalg.norm(ds, axis=-1, keepdims=True)


def q_from_instrument(T_b_e: ArrayLike, direction_e: ArrayLike, p: ArrayLike,
                      design: Design | None = None, *, errors: ErrorPolicy = "auto",
                      backend: ReferenceBackend = "numpy"
                      ) -> tuple[FloatArray, InstrumentIK]:
    """The numpy reference of :func:`athenakin.q_from_instrument` (the compiled kernels' oracle).

    Parameters
    ----------
    T_b_e, direction_e, p, design, errors : as in :func:`athenakin.q_from_instrument`
    backend : {"numpy"}, keyword-only
        Only the reference; :func:`athenakin.q_from_instrument` chooses the backend.

    Returns
    -------
    q : ndarray, shape (..., 3)
        ``(q1, q2, q3)``, m; NaN where ``result.valid`` is False.
    result : InstrumentIK
        As :func:`athenakin.q_from_instrument`.
    """
    check_reference_backend(backend, "q_from_instrument")
    check_options(errors)
    design = resolve_design(design)
    T = check_transform(T_b_e, "T_b_e", allow_nonfinite=True)
    d_e = _unit(check_array(direction_e, "direction_e", (3,), allow_nonfinite=True),
                "direction_e")
    p = check_array(p, "p", (), allow_nonfinite=True)
    batch = broadcast_batch(T_b_e=T.shape[:-2], direction_e=d_e.shape[:-1], p=p.shape)
    if resolve_policy(errors, batch):   # a failure raises: name the non-finite argument
        check_array(T, "T_b_e", (4, 4))
        check_array(direction_e, "direction_e", (3,))
        check_array(p, "p", ())
    pre = np.where(np.abs(p) <= P_ZERO_TOL, np.int8(Reason.SERIAL_P_ZERO), np.int8(0))
    return _q_from_line(T, d_e, p, design, errors, pre.astype(np.int8))


def q_from_tool_tip(T_b_e: ArrayLike, tip_e: ArrayLike, design: Design | None = None, *,
                    errors: ErrorPolicy = "auto", backend: ReferenceBackend = "numpy"
                    ) -> tuple[FloatArray, InstrumentIK]:
    """The numpy reference of :func:`athenakin.q_from_tool_tip` (the compiled kernels' oracle).

    Parameters
    ----------
    T_b_e, tip_e, design, errors : as in :func:`athenakin.q_from_tool_tip`
    backend : {"numpy"}, keyword-only
        Only the reference; :func:`athenakin.q_from_tool_tip` chooses the backend.

    Returns
    -------
    q, result : ndarray (..., 3), InstrumentIK
        As :func:`athenakin.q_from_tool_tip`: actuators (m) and the line's details.
    """
    check_reference_backend(backend, "q_from_tool_tip")
    check_options(errors)
    design = resolve_design(design)
    T = check_transform(T_b_e, "T_b_e", allow_nonfinite=True)
    tip = check_array(tip_e, "tip_e", (3,), allow_nonfinite=True)
    batch = broadcast_batch(T_b_e=T.shape[:-2], tip_e=tip.shape[:-1])
    if resolve_policy(errors, batch):   # a failure raises: name the non-finite argument
        check_array(T, "T_b_e", (4, 4))
        check_array(tip, "tip_e", (3,))
    m = np.max(np.abs(tip), axis=-1)
    with np.errstate(invalid="ignore"):
        s = m * np.linalg.norm(tip / np.where(m > 0, m, 1.0)[..., None], axis=-1)
    L = design.tool_length
    pre = np.zeros(s.shape, dtype=np.int8)
    pre = np.where(s >= L, np.int8(Reason.INSERTION_RANGE), pre)
    pre = np.where(s == 0, np.int8(Reason.IK_SINGULAR), pre).astype(np.int8)
    with np.errstate(invalid="ignore"):   # scaled first: a unit vector even for subnormals
        ts = tip / np.where(m > 0, m, 1.0)[..., None]
        d_e = ts / np.linalg.norm(ts, axis=-1, keepdims=True)
    d_e = np.where((s > 0)[..., None], d_e, np.array([0.0, 0.0, 1.0]))
    return _q_from_line(T, d_e, L - s, design, errors, pre)


def _q_from_line(T: FloatArray, d_e: FloatArray, p: FloatArray,
                 design: Design, errors: str, pre: Int8Array
                 ) -> tuple[FloatArray, InstrumentIK]:
    batch = broadcast_batch(T_b_e=T.shape[:-2], direction=d_e.shape[:-1], p=p.shape,
                            check=pre.shape)
    raise_now = resolve_policy(errors, batch)
    finite = (np.all(np.isfinite(T), axis=(-2, -1)) & np.all(np.isfinite(d_e), axis=-1)
              & np.isfinite(p))
    pre = np.where(finite, pre, np.int8(Reason.NONFINITE_INPUT)).astype(np.int8)
    with np.errstate(invalid="ignore", over="ignore"):
        d_b = (T[..., :3, :3] @ d_e[..., None])[..., 0]
        O_s = T[..., :3, 3] - p[..., None] * d_b
    O_s, d_b = np.broadcast_to(O_s, batch + (3,)), np.broadcast_to(d_b, batch + (3,))
    pre = np.broadcast_to(pre, batch)
    pik = position_ik(np.where((pre == 0)[..., None], O_s, np.nan), design)
    reason = np.where(pre != 0, pre, pik.reason).astype(np.int8)
    if raise_now:
        raise_first_failure(reason, "instrument inverse kinematics",
                            {"O_s": O_s, "p": np.broadcast_to(p, batch)}, design=design,
                            q_of=lambda idx: _unlimited_q(O_s[idx], design),
                            detail_of=lambda idx: _detail(int(reason[idx]), O_s[idx], design))
    valid = reason == 0
    nan = np.where(valid, 1.0, np.nan)
    res = InstrumentIK(p=np.broadcast_to(p, batch) * nan, direction_b=d_b * nan[..., None],
                       O_s=O_s * nan[..., None], mode=np.where(valid, pik.mode, 0), valid=valid,
                       reason=reason, q_error=pik.q_error * nan)
    return pik.q * nan[..., None], res
