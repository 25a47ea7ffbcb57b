"""The passive serial UPS chain (paper Eq. 5, 6, 11, 12) and its 8 solutions.

``T_s_e = Rz(u1) Rx(pi/2) Rz(u2) Rx(pi/2) Tz(p) Rz(u3) Rx(pi/2) Rz(u4) Rx(pi/2) Rz(u5)``.

Closed form used here (derived in docs/conventions.md): with
``R(a, b) = Rz(a) Rx(pi/2) Rz(b) Rx(pi/2)``, whose columns are
``x = (ca cb, sa cb, sb)``, ``y = (sa, -ca, 0)``, ``z = (ca sb, sa sb, -cb)``,

* ``T_s_e = [[R(u1, u2) R(u3, u4) Rz(u5), p * z(u1, u2)], [0, 1]]``;
* the RCM (origin of E) seen from ``O_s`` is ``c = p * z(u1, u2)``, so
  ``p = +|c|`` or ``-|c|`` (the paper's quadratic in ``p`` is ``p^2 = |c|^2``);
* for each ``p``, ``z(u1, u2) = c / p`` gives two U-joint branches
  ``(u1, u2)`` and ``(u1 + pi, -u2)`` (``sigma = sign(sin u2)``);
* for each, ``W = R(u1, u2)^T R_s_e = R(u3, u4) Rz(u5)`` gives two wrist
  branches ``(u3, u4, u5)`` and ``(u3 + pi, -u4, u5 + pi)`` (``tau = sign(sin u4)``).

Slot ``k = 4 * r + 2 * b + w`` holds root ``r`` (0: ``p > 0``), U-joint branch
``b`` (0: ``sin u2 > 0``) and wrist branch ``w`` (0: ``sin u4 > 0``).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._typing import BoolArray, FloatArray, Int8Array
from .._validation import broadcast_batch, check_array, check_tolerance, check_transform
from ..errors import InvalidInputError, Reason
from ..study import dq_multiply, study_G, study_M

__all__ = [
    "DEGENERATE_TOL",
    "DEGENERATE_ULPS",
    "CLOSURE_ULPS",
    "P_ZERO_TOL",
    "CLOSURE_TOL",
    "SERIAL_P_SIGN",
    "SERIAL_UJOINT",
    "SERIAL_WRIST",
    "UPSSolution",
    "ups_transform",
    "ups_study",
    "ups_solutions",
    "rotation_u_pair",
    "u_pair_entries",
    "closure_residual",
]

#: ``|sin u2|`` / ``|sin u4|`` at or below which the U-joint / spherical joint is
#: declared degenerate (a continuum of solutions).
DEGENERATE_TOL = 1e-12
#: ``|p|`` (m) at or below which ``O_s`` is at the RCM (instrument axis undefined).
P_ZERO_TOL = 1e-12
#: Largest closure residual (see :func:`closure_residual`) of a solution reported valid.
CLOSURE_TOL = 1e-9

#: Rounding (in ulps of the coordinates' size) below which ``|sin u2|`` and ``|sin u4|``
#: count as zero: the instrument direction ``t / p`` is only known to ``eps * size / p``,
#: so for a short ``p`` the fixed ``DEGENERATE_TOL`` alone would accept an arbitrary ``u1``.
DEGENERATE_ULPS = 64.0
_EPS = float(np.finfo(float).eps)
#: Rounding of a closure check, in ulps of the chain's scale: the translation of a pose
#: ``scale`` metres from the origin is known only to about ``eps * scale``, so a closure
#: residual of that size is rounding, not a failure (a far RCM, 1e8 m). The
#: closure test is ``residual <= closure_tol + CLOSURE_ULPS * eps * scale``.
CLOSURE_ULPS = 16.0

#: Labels of the 8 serial slots: sign of p, of sin u2, of sin u4.
SERIAL_P_SIGN = np.array([1, 1, 1, 1, -1, -1, -1, -1])
SERIAL_UJOINT = np.array([1, 1, -1, -1, 1, 1, -1, -1])
SERIAL_WRIST = np.array([1, -1, 1, -1, 1, -1, 1, -1])


@dataclasses.dataclass(frozen=True)
class UPSSolution:
    """All 8 solutions of the serial chain for given ``T_s_e``.

    Attributes
    ----------
    valid : ndarray of bool, shape (..., 8)
    reason : ndarray of int, shape (..., 8)
        :class:`~athenakin.errors.Reason` (0 valid; ``SERIAL_P_ZERO``,
        ``UJOINT_SINGULAR``, ``WRIST_SINGULAR`` for continua, ``CLOSURE_FAILED``).
    p : ndarray, shape (..., 8)
        Passive prismatic joint, m (NaN where invalid).
    u : ndarray, shape (..., 8, 5)
        ``u1..u5``, radians in (-pi, pi] (NaN where invalid).
    residual : ndarray, shape (..., 8)
        Closure residual of each solution (NaN where invalid).
    """

    valid: BoolArray
    reason: Int8Array
    p: FloatArray
    u: FloatArray
    residual: FloatArray


def rotation_u_pair(ca: ArrayLike, sa: ArrayLike, cb: ArrayLike, sb: ArrayLike
                    ) -> FloatArray:
    """``R(a, b) = Rz(a) Rx(pi/2) Rz(b) Rx(pi/2)`` from cosines and sines.

    Parameters
    ----------
    ca, sa, cb, sb : array-like, shape (...)

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    args = [check_array(v, n, (), allow_nonfinite=True)
            for v, n in ((ca, "ca"), (sa, "sa"), (cb, "cb"), (sb, "sb"))]
    try:
        ca, sa, cb, sb = np.broadcast_arrays(*args)
    except ValueError:
        raise InvalidInputError(f"ca, sa, cb, sb: expected broadcastable shapes, got "
                                f"{[a.shape for a in args]}") from None
    z = np.zeros_like(ca)
    return np.stack(u_pair_entries(ca, sa, cb, sb, z), axis=-1).reshape(ca.shape + (3, 3))


def u_pair_entries(ca: Any, sa: Any, cb: Any, sb: Any, zero: Any) -> tuple[Any, ...]:
    """The nine entries of :func:`rotation_u_pair`, row by row, of unchecked operands.

    The one expression of ``R(a, b)``: :func:`rotation_u_pair` stacks it over arrays,
    a single-pose caller (:meth:`athenakin.fast.ControlLoop.fk_slot`) fills a (3, 3)
    buffer from it without the checks and the stacking.

    Parameters
    ----------
    ca, sa, cb, sb : float or ndarray
        Cosines and sines of ``a`` and ``b``.
    zero : float or ndarray
        The zero entry, of the operands' kind.

    Returns
    -------
    tuple of 9
        ``R[0, 0], R[0, 1], ..., R[2, 2]``.
    """
    return (ca * cb, sa, ca * sb,
            sa * cb, -ca, sa * sb,
            sb, zero, -cb)


def _rz(c: FloatArray, s: FloatArray) -> FloatArray:
    z, o = np.zeros_like(c), np.ones_like(c)
    return np.stack([c, -s, z, s, c, z, z, z, o], axis=-1).reshape(c.shape + (3, 3))


def ups_transform(p: ArrayLike, u: ArrayLike) -> FloatArray:
    """Forward map of the serial chain, ``T_s_e(p, u1..u5)`` (Eq. 11 without ``B``).

    Parameters
    ----------
    p : array-like, shape (...)
        Passive prismatic joint (signed distance ``O_s`` -> RCM along z3), m.
    u : array-like, shape (..., 5)
        ``u1..u5`` in radians.

    Returns
    -------
    ndarray, shape (..., 4, 4)
    """
    p = check_array(p, "p", ())
    u = check_array(u, "u", (5,))
    batch = broadcast_batch(p=p.shape, u=u.shape[:-1])
    return _ups_transform(np.broadcast_to(p, batch), np.broadcast_to(u, batch + (5,)))


def _ups_transform(p: FloatArray, u: FloatArray) -> FloatArray:
    c, s = np.cos(u), np.sin(u)
    return _chain_from_cs(p, *(c[..., i] for i in range(5)), *(s[..., i] for i in range(5)))


def _chain_from_cs(p: FloatArray, c1: FloatArray, c2: FloatArray,
                   c3: FloatArray, c4: FloatArray, c5: FloatArray,
                   s1: FloatArray, s2: FloatArray, s3: FloatArray,
                   s4: FloatArray, s5: FloatArray) -> FloatArray:
    """``T_s_e`` from ``p`` and the cosines/sines of ``u1..u5``.

    Element-wise products: numpy's matmul on stacks of 3x3 matrices is slow.
    """
    # R1 = R(u1, u2) columns; W = R(u3, u4) Rz(u5) columns (module docstring)
    zero = np.zeros_like(c1)
    a = ((c1 * c2, s1 * c2, s2), (s1, -c1, zero), (c1 * s2, s1 * s2, -c2))
    bx, by, bz = (c3 * c4, s3 * c4, s4), (s3, -c3, np.zeros_like(c3)), (c3 * s4, s3 * s4, -c4)
    wcols = (tuple(c5 * x + s5 * y for x, y in zip(bx, by, strict=True)),
             tuple(c5 * y - s5 * x for x, y in zip(bx, by, strict=True)), bz)
    shape = np.broadcast_shapes(np.shape(p), np.shape(c1), np.shape(c3), np.shape(c5))
    T = np.zeros(shape + (4, 4))
    for j in range(3):
        for i in range(3):
            T[..., i, j] = a[0][i] * wcols[j][0] + a[1][i] * wcols[j][1] + a[2][i] * wcols[j][2]
        T[..., j, 3] = p * a[2][j]
    T[..., 3, 3] = 1.0
    return T


def ups_study(p: ArrayLike, u: ArrayLike) -> FloatArray:
    """Study vector of the serial chain as the product ``M1 G1 M2 G2 ... M5 G5`` (Eq. 11, 12).

    This is the paper's formulation; it is independent of :func:`ups_transform`
    and the two agree by the homomorphism of Study's mapping.

    Parameters
    ----------
    p : array-like, shape (...)
    u : array-like, shape (..., 5)

    Returns
    -------
    ndarray, shape (..., 8)
        Unnormalised Study vector.
    """
    p = check_array(p, "p", ())
    u = check_array(u, "u", (5,))
    half = np.pi / 2
    zero = np.zeros_like(p)
    G = [study_G(zero, zero, half), study_G(zero, zero, half), study_G(zero, p, half),
         study_G(zero, zero, half), study_G(zero, zero, zero)]
    X = None
    for i in range(5):
        Xi = dq_multiply(study_M(u[..., i]), G[i])
        X = Xi if X is None else dq_multiply(X, Xi)
    assert X is not None
    return X


def closure_residual(T: FloatArray, T_target: FloatArray
                     ) -> FloatArray:
    """Closure residual ``max(max|R - R*|, max|t - t*| / 1 m)`` of two transforms (..., 4, 4).

    Parameters
    ----------
    T, T_target : array-like, shape (..., 4, 4)
        Transforms, broadcast against each other (NaN items give NaN).

    Returns
    -------
    ndarray, shape (...)
    """
    T = check_array(T, "T", (4, 4), allow_nonfinite=True)
    T_target = check_array(T_target, "T_target", (4, 4), allow_nonfinite=True)
    broadcast_batch(T=T.shape[:-2], T_target=T_target.shape[:-2])
    dR = np.abs(T[..., :3, :3] - T_target[..., :3, :3]).max(axis=(-2, -1))
    dt = np.abs(T[..., :3, 3] - T_target[..., :3, 3]).max(axis=-1)
    return np.maximum(dR, dt)


#: The two signs of a slot choice (p, sigma, tau), read only.
_PLUS_MINUS = np.array([1.0, -1.0])
_PLUS_MINUS.flags.writeable = False


def _check_scale(scale: ArrayLike, batch: tuple[int, ...]) -> FloatArray:
    """``scale`` of :func:`ups_solutions`: an array that broadcasts to the batch."""
    sc = check_array(scale, "scale", (), allow_nonfinite=True)
    if broadcast_batch(T_s_e=batch, scale=sc.shape) != batch:
        raise InvalidInputError(f"scale: expected a shape that broadcasts to the batch of "
                                f"T_s_e {batch}, got {sc.shape}")
    return sc


def _sines_as_kernel(T: FloatArray, zx: FloatArray, zy: FloatArray,
                     zz: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``|sin u2|`` and ``|sin u4|`` of the slot p > 0, in the compiled kernel's operations.

    ``(zx, zy, zz)`` is the unit instrument direction (the kernel's names); the
    kernel is ``fast/_fk_stages.py``, ``_serial_stage`` (so both backends classify
    an input on a threshold alike, to the last bit).
    """
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        rho_k = np.sqrt(zx * zx + zy * zy)              # |sin u2| (kernel: hypot)
        rr = np.where(rho_k > 0.0, rho_k, 1.0)
        A1, B1 = zx / rr, zy / rr
        rho2 = A1 * zx + B1 * zy
        n2 = np.sqrt(rho2 * rho2 + zz * zz)
        cc2, ss2 = -zz / n2, rho2 / n2
        e02, e12, e22 = T[..., 0, 2], T[..., 1, 2], T[..., 2, 2]
        W02k = ((A1 * cc2) * e02 + (B1 * cc2) * e12) + ss2 * e22
        W12k = B1 * e02 - A1 * e12
        rho4_k = np.sqrt(W02k * W02k + W12k * W12k)     # |sin u4| (kernel: rho4)
    return rho_k, rho4_k


def _slot_reasons(base_reason: NDArray[np.int_], deg_u: BoolArray,
                  deg_w: BoolArray, res: FloatArray, pp: FloatArray,
                  ctol: FloatArray) -> Int8Array:
    """Reason code of each of the 8 slots (..., 8): the first failed check wins.

    ``deg_u``, ``deg_w`` (..., 2, 2, 2): the U-joint and wrist degeneracies; ``ctol``
    (..., 1): the closure tolerance with the rounding of a far pose (a NaN scale, of an
    unassembled mode, allows nothing); ``pp`` (..., 8): ``p``, infinite where ``|t|^2``
    overflowed (no solution, as the kernels flag it).
    """
    batch = res.shape[:-1]
    reason = np.broadcast_to(base_reason[..., None], batch + (8,)).astype(np.int8)
    reason = np.where((reason == 0) & deg_u.reshape(batch + (8,)),
                      np.int8(Reason.UJOINT_SINGULAR), reason)
    reason = np.where((reason == 0) & deg_w.reshape(batch + (8,)),
                      np.int8(Reason.WRIST_SINGULAR), reason)
    reason = np.where((reason == 0) & ~(res <= ctol), np.int8(Reason.CLOSURE_FAILED),
                      reason).astype(np.int8)
    return np.where((reason == 0) & ~np.isfinite(pp), np.int8(Reason.CLOSURE_FAILED),
                    reason).astype(np.int8)


def _pose_checks(c: FloatArray, finite: BoolArray, scale: ArrayLike | None,
                 degenerate_tol: float, p_zero_tol: float
                 ) -> tuple[NDArray[np.int_], FloatArray, FloatArray,
                            FloatArray]:
    """What decides validity before any angle, from the translation ``c`` (..., 3) of T_s_e.

    Returns the reason of the pose (..., ``NONFINITE_INPUT``, ``SERIAL_P_ZERO`` or 0),
    ``|p|`` (1 where it is zero), the scale of its rounding and the degeneracy tolerance
    of ``|sin u2|``, ``|sin u4|`` (...). ``|p|`` is computed with the very operations,
    in the same order, as the compiled kernel (fast/_fk_stages.py, _serial_stage), so
    both backends classify every input alike, even one that sits on a threshold to the
    last bit.
    """
    c0, c1, c2 = c[..., 0], c[..., 1], c[..., 2]
    with np.errstate(over="ignore"):
        n = np.sqrt((c0 * c0 + c1 * c1) + c2 * c2)     # inf beyond 1e154 m: no solution
    base_reason = np.where(finite, 0, Reason.NONFINITE_INPUT)
    base_reason = np.where((base_reason == 0) & (n <= p_zero_tol), Reason.SERIAL_P_ZERO,
                           base_reason)
    nn = np.where(n > p_zero_tol, n, 1.0)
    sc = n if scale is None else _check_scale(scale, n.shape)
    with np.errstate(invalid="ignore", over="ignore"):
        dtol = np.maximum(degenerate_tol, DEGENERATE_ULPS * _EPS * sc / nn)   # (...)
    return base_reason, nn, sc, dtol


def _ujoint_angles(z3: FloatArray) -> tuple[FloatArray, ...]:
    """``u1, u2`` and their cosines and sines (..., 2, 2) from the instrument axis ``z3``.

    ``z3`` (..., 2, 3): the unit direction for each sign of ``p``; the last axis of the
    result is the U-joint branch ``sigma = +-1``. ``u1`` from the direction, ``u2`` from
    its projection onto the plane ``u1`` fixes.
    """
    sig = _PLUS_MINUS
    u1 = np.arctan2(sig * z3[..., 1, None], sig * z3[..., 0, None])
    c1, s1 = np.cos(u1), np.sin(u1)
    u2 = np.arctan2(c1 * z3[..., 0, None] + s1 * z3[..., 1, None],
                    np.broadcast_to(-z3[..., 2, None], u1.shape))
    return u1, u2, c1, s1, np.cos(u2), np.sin(u2)


def _wrist_angles(W: FloatArray) -> tuple[FloatArray, ...]:
    """``u3, u4, u5`` and the cosines and sines ``c3, s3, c4, s4, c5, s5`` (..., 2, 2, 2).

    ``W = R(u1, u2)^T R_s_e`` (..., 2, 2, 3, 3), the rotation left to the wrist; the last
    axis of the result is the wrist branch ``tau = +-1``. ``u3`` from its third column,
    ``u4`` from the projection onto the plane ``u3`` fixes, ``u5`` from the remaining
    matrix; ``c5, s5`` are the cosine and sine of the reported ``u5`` to 1 ulp.
    """
    tau = _PLUS_MINUS
    u3 = np.arctan2(tau * W[..., 1, 2, None], tau * W[..., 0, 2, None])
    c3, s3 = np.cos(u3), np.sin(u3)
    u4 = np.arctan2(c3 * W[..., 0, 2, None] + s3 * W[..., 1, 2, None],
                    np.broadcast_to(-W[..., 2, 2, None], u3.shape))
    c4, s4 = np.cos(u4), np.sin(u4)
    W00, W10, W20 = W[..., 0, 0, None], W[..., 1, 0, None], W[..., 2, 0, None]
    y5 = s3 * W00 - c3 * W10
    x5 = c3 * c4 * W00 + s3 * c4 * W10 + s4 * W20
    n5 = np.hypot(x5, y5)
    return u3, u4, np.arctan2(y5, x5), c3, s3, c4, s4, x5 / n5, y5 / n5


def ups_solutions(T_s_e: ArrayLike, *, degenerate_tol: float = DEGENERATE_TOL,
                  p_zero_tol: float = P_ZERO_TOL, closure_tol: float = CLOSURE_TOL,
                  scale: ArrayLike | None = None, _checked: bool = False) -> UPSSolution:
    """All 8 solutions ``(p, u1..u5)`` of the serial chain for a pose ``T_s_e``.

    Parameters
    ----------
    T_s_e : array-like, shape (..., 4, 4)
        Pose of the RCM frame E in the serial base frame ``O_s``. NaN items are
        flagged (``NONFINITE_INPUT``).
    degenerate_tol : float, keyword-only
        ``|sin u2|`` and ``|sin u4|`` at or below which the U-joint or the
        spherical joint is degenerate: the slots get ``UJOINT_SINGULAR`` /
        ``WRIST_SINGULAR`` and NaN values (a continuum, not an isolated solution).
    p_zero_tol : float, keyword-only
        ``|p|`` (m) at or below which all 8 slots get ``SERIAL_P_ZERO``.
    closure_tol : float, keyword-only
        Largest residual of a valid solution, in ``[0, 1e-3]``.
    scale : array-like, shape (...), optional, keyword-only
        Size (m) of the coordinates ``T_s_e``'s translation was computed from (e.g.
        ``|t_b_e| + |O_s|``): its rounding, about ``eps * scale``, tilts the instrument
        direction by ``eps * scale / p``, so ``|sin u2|`` and ``|sin u4|`` below
        ``DEGENERATE_ULPS * eps * scale / p`` are degenerate whatever ``degenerate_tol``
        says. Default: ``|t_s_e|`` itself.

    Returns
    -------
    UPSSolution
        Slots ordered ``k = 4 r + 2 b + w`` (module docstring).
    """
    T = T_s_e if _checked else check_transform(T_s_e, "T_s_e", allow_nonfinite=True)
    degenerate_tol = check_tolerance(degenerate_tol, "degenerate_tol")
    p_zero_tol = check_tolerance(p_zero_tol, "p_zero_tol")
    # internal callers (``_checked``) may ask for every slot whatever its closure (inf)
    closure_tol = check_tolerance(closure_tol, "closure_tol",
                                  maximum=math.inf if _checked else None)
    finite = np.all(np.isfinite(T), axis=(-2, -1))
    T = np.where(finite[..., None, None], T, np.eye(4))
    c = T[..., :3, 3]
    base_reason, nn, sc, dtol = _pose_checks(c, finite, scale, degenerate_tol, p_zero_tol)
    p = nn[..., None] * _PLUS_MINUS                     # (..., 2)
    z3 = c[..., None, :] / p[..., None]                 # (..., 2, 3)
    rho_k, rho4_k = _sines_as_kernel(T, c[..., 0] / nn, c[..., 1] / nn, c[..., 2] / nn)
    rho = np.broadcast_to(rho_k[..., None], p.shape)    # (..., 2): the same for both signs
    # Each angle pair is solved sequentially so that closure holds to rounding even
    # where the first angle is ill-conditioned (near sin u2 = 0 or sin u4 = 0): the
    # first angle from the direction, the second from the projection onto the
    # plane it fixes, the last rotation from the remaining matrix.
    u1, u2, c1, s1, c2, s2 = _ujoint_angles(z3)         # (..., 2, 2)
    uj_deg = np.broadcast_to((rho <= dtol[..., None])[..., None], u1.shape)
    W = np.swapaxes(rotation_u_pair(c1, s1, c2, s2), -1, -2) @ T[..., None, None, :3, :3]
    u3, u4, u5, c3, s3, c4, s4, c5, s5 = _wrist_angles(W)   # (..., 2, 2, 2)
    # |sin u4| is decided once per pose (rho4_k): per slot it would round differently
    wr_deg = np.broadcast_to((rho4_k <= dtol)[..., None, None, None], u3.shape)

    full = u3.shape  # (..., 2, 2, 2)
    batch = full[:-3]
    u = np.empty(batch + (2, 2, 2, 5))
    u[..., 0] = u1[..., None]
    u[..., 1] = u2[..., None]
    u[..., 2], u[..., 3], u[..., 4] = u3, u4, u5
    u[u == -np.pi] = np.pi          # report angles in (-pi, pi]
    pp = np.broadcast_to(p[..., None, None], full)
    # closure check of the reported solution, from the cosines and sines of its angles
    Tsol = _chain_from_cs(pp, c1[..., None], c2[..., None], c3, c4, c5,
                          s1[..., None], s2[..., None], s3, s4, s5)
    res = closure_residual(Tsol, T[..., None, None, None, :, :]).reshape(batch + (8,))
    u = u.reshape(batch + (8, 5))
    pp = pp.reshape(batch + (8,))

    reason = _slot_reasons(base_reason, np.broadcast_to(uj_deg[..., None], full), wr_deg, res,
                           pp, closure_tol + CLOSURE_ULPS * _EPS * np.fmax(sc, 0.0)[..., None])
    valid = reason == 0
    nan = np.where(valid, 1.0, np.nan)
    return UPSSolution(valid=valid, reason=reason, p=pp * nan, u=u * nan[..., None],
                       residual=res * nan)
