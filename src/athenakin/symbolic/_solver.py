"""Forward kinematics the paper's way: all 16 solutions through the quadratic in ``p``.

This is the second FK solver of athenakin, generated from the derivation
(:mod:`athenakin.symbolic._derivation`): the expressions it evaluates are the
cached results of LIA and the elimination of Section 3.2, turned into numpy code
(``_cache/_numeric.py``); it does not import sympy. Per assembly mode:

1. Study vectors ``b`` of ``T_b_s`` (Eq. 10) and ``e`` of ``T_b_e``; the paper's
   assignment of values with ``B = 1``: ``f = B^-1 E`` (dual-quaternion product).
2. The quadratic in ``p`` (generated from :func:`~athenakin.symbolic.p_quadratic`):
   two roots, ``r = 0`` the positive one.
3. At each root the skew matrix ``K(p)`` (``sr`` in ``x`` after ``y`` from ``sl``)
   has rank 2; its null space is the pencil of quaternion parts ``x`` of the
   closure, spanned by the columns of the dual matrix ``K~`` (``K K~ = -Pf(K) I``).
4. The U-joint quadric (LIA of degree 2) on the pencil: a homogeneous quadratic,
   two points ``x``; the Segre inverse gives ``(v1, v2)`` homogeneously.
5. The wrist: ``h = conj(x) f_x``, the generated wrist quadratic in ``v5``, then
   ``(v3, v4)`` by the Segre inverse.

Half-tangents are kept homogeneous (``v = s / t``), so half turns (``u = pi``,
``t = 0``), where the affine ``v`` of the paper is infinite, are ordinary
solutions; angles are ``u = 2 atan2(s, t)`` in (-pi, pi].

The result is a :class:`~athenakin.robot.FKSolution` with the slot layout and
reason codes of :func:`athenakin.forward_kinematics` (slot ``k = 8m + 4r + 2b + w``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._typing import BoolArray, FloatArray, Int8Array
from .._validation import check_array, check_tolerance
from ..chain import DEGENERATE_TOL, P_ZERO_TOL, closure_residual, ups_transform
from ..errors import Reason
from ..parallel import ParallelSolution
from ..robot._fk import register_serial_step
from ..study import dq_conj_quaternion, dq_multiply, study_from_transform
from ..study._study import _qmul

__all__ = ["serial_solutions_algebraic", "serial_step_algebraic",
           "PENCIL_TOL"]

#: Largest coefficient (relative, unit pencil vectors) of the U-joint quadratic on the
#: pencil, or of the wrist quadratic, at which it counts as identically zero: the
#: whole pencil lies on the quadric, a continuum (``sin u2 = 0`` or ``sin u4 = 0``).
PENCIL_TOL = 1e-12

_checked_hash = False


def _numeric():  # type: ignore[no-untyped-def]
    """The generated module, checked once against the cache's hash."""
    global _checked_hash
    from ._cache import _numeric as gen

    if not _checked_hash:
        import hashlib
        import json
        from pathlib import Path

        path = Path(__file__).parent / "_cache" / "derivation.json"
        if not path.is_file():
            raise RuntimeError(
                f"{path}: the cached derivation is missing, so the generated solver code "
                f"cannot be checked; install athenakin with its package data "
                f"(symbolic/_cache/*.json) or regenerate with "
                f"python -m athenakin.symbolic._derivation")
        data = json.loads(path.read_text())
        text = json.dumps(data["results"], sort_keys=True, separators=(",", ":"))
        h = hashlib.sha256(text.encode()).hexdigest()
        if not (h == data["sha256"] == gen.DERIVATION_SHA256):
            raise RuntimeError(
                f"{path}: the cached derivation (hash {h[:12]}..., stored "
                f"{str(data['sha256'])[:12]}...) and the generated code (from "
                f"{gen.DERIVATION_SHA256[:12]}...) disagree; regenerate with "
                f"python -m athenakin.symbolic._derivation")
        _checked_hash = True
    return gen


def _dual(K: FloatArray) -> FloatArray:
    """Dual of skew 4x4 matrices: ``K K~ = -Pf(K) I`` (``Pf = k01 k23 - k02 k13 + k03 k12``)."""
    k01, k02, k03 = K[..., 0, 1], K[..., 0, 2], K[..., 0, 3]
    k12, k13, k23 = K[..., 1, 2], K[..., 1, 3], K[..., 2, 3]
    z = np.zeros_like(k01)
    return np.stack([z, k23, -k13, k12, -k23, z, k03, -k02,
                     k13, -k03, z, k01, -k12, k02, -k01, z], axis=-1).reshape(K.shape)


def _pencil(K: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Orthonormal basis ``(n1, n2)`` of the null space of rank-2 skew matrices (..., 4, 4).

    At a root of the Pfaffian (the quadratic in ``p``) ``K K~ = 0``: the columns of the
    dual ``K~`` span the null space. ``n1`` is the longest column, normalised; ``n2`` the
    column with the largest part orthogonal to it (Gram-Schmidt).
    """
    C = np.swapaxes(_dual(K), -1, -2)                      # rows = columns of K~
    norms = np.linalg.norm(C, axis=-1)
    i = np.argmax(norms, axis=-1)
    a = np.take_along_axis(C, i[..., None, None], axis=-2)[..., 0, :]
    n1 = a / np.linalg.norm(a, axis=-1, keepdims=True)
    R = C - np.sum(C * n1[..., None, :], axis=-1, keepdims=True) * n1[..., None, :]
    j = np.argmax(np.linalg.norm(R, axis=-1), axis=-1)
    b = np.take_along_axis(R, j[..., None, None], axis=-2)[..., 0, :]
    return n1, b / np.linalg.norm(b, axis=-1, keepdims=True)


def _hroots(A: FloatArray, B: FloatArray, C: FloatArray
            ) -> FloatArray:
    """Both roots ``(a : b)`` of ``A a^2 + B a b + C b^2 = 0``, shape (..., 2, 2).

    Stable form: ``q = -(B + sign(B) sqrt(B^2 - 4AC)) / 2``, roots ``(q : A)``, ``(C : q)``;
    a root at infinity (``A = 0``) is ``(q : 0)``. A negative discriminant (rounding
    at a double root) is clipped to 0.
    """
    sq = np.sqrt(np.maximum(B * B - 4.0 * A * C, 0.0))
    q = -0.5 * (B + np.where(B >= 0, sq, -sq))
    return np.stack([np.stack([q, A], axis=-1), np.stack([C, q], axis=-1)], axis=-2)


def _segre_inverse(r: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``(s_a, t_a)``, ``(s_b, t_b)`` from ``r ~ (-s_a s_b, t_a t_b, s_a t_b, t_a s_b)``.

    Of the two representatives of each pair (see
    :func:`athenakin.symbolic.segre_inverse`) the one with the larger norm is used.
    """
    r0, r1, r2, r3 = np.moveaxis(r, -1, 0)
    a1, a2 = np.stack([r2, r1], axis=-1), np.stack([-r0, r3], axis=-1)
    b1, b2 = np.stack([r3, r1], axis=-1), np.stack([-r0, r2], axis=-1)
    ua = np.hypot(r2, r1) >= np.hypot(r0, r3)
    ub = np.hypot(r3, r1) >= np.hypot(r0, r2)
    return np.where(ua[..., None], a1, a2), np.where(ub[..., None], b1, b2)


def _angle(st: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Angle ``2 atan2(s, t)`` in (-pi, pi] and its sine, from homogeneous ``(s, t)``."""
    s, t = st[..., 0], st[..., 1]
    u = 2.0 * np.arctan2(s, t)
    u = np.where(u > np.pi, u - 2 * np.pi, u)
    u = np.where(u <= -np.pi, u + 2 * np.pi, u)
    sin = 2.0 * s * t / (s * s + t * t)
    return u, sin


def _order(first_negative: BoolArray, a: FloatArray, axis: int
           ) -> FloatArray:
    """Swap the two entries along ``axis`` where ``first_negative`` (broadcast) holds."""
    flipped = np.flip(a, axis=axis)
    return np.where(first_negative, flipped, a)


def serial_solutions_algebraic(f: ArrayLike, *, degenerate_tol: float = DEGENERATE_TOL,
                               p_zero_tol: float = P_ZERO_TOL
                               ) -> tuple[FloatArray, FloatArray,
                                          Int8Array]:
    """The 8 serial solutions for the Study vector ``f`` of ``T_s_e`` (steps 2-5 of the module).

    Parameters
    ----------
    f : array-like, shape (..., 8)
        Study vector of the RCM frame in ``O_s`` (on the Study quadric, any scale).
    degenerate_tol : float, keyword-only
        ``|sin u2|`` / ``|sin u4|`` at or below which the slot is a continuum.
    p_zero_tol : float, keyword-only
        ``|p|`` (m) at or below which all slots get ``SERIAL_P_ZERO``.

    Returns
    -------
    p : ndarray, shape (..., 8)
    u : ndarray, shape (..., 8, 5)
        Radians in (-pi, pi].
    reason : ndarray of int8, shape (..., 8)
        0, ``SERIAL_P_ZERO``, ``UJOINT_SINGULAR`` or ``WRIST_SINGULAR`` (values are
        still filled where finite; the caller masks them).
    """
    gen = _numeric()
    f = check_array(f, "f", (8,))
    degenerate_tol = check_tolerance(degenerate_tol, "degenerate_tol")
    p_zero_tol = check_tolerance(p_zero_tol, "p_zero_tol")
    with np.errstate(invalid="ignore", divide="ignore"):
        return _serial(gen, f / np.linalg.norm(f[..., :4], axis=-1, keepdims=True),
                       degenerate_tol, p_zero_tol)


def _serial(gen, f: FloatArray, degenerate_tol: float,  # type: ignore[no-untyped-def]
            p_zero_tol: float) -> tuple[FloatArray, FloatArray,
                                        Int8Array]:
    """Body of :func:`serial_solutions_algebraic` (``f`` normalised, warnings silenced)."""
    batch = f.shape[:-1]
    # 2. quadratic in p
    a2, a1, a0 = np.moveaxis(gen.quadratic_coefficients(f), -1, 0)
    roots = _hroots(a2, a1, a0)                                  # (..., 2, 2): (p_num, p_den)
    p = roots[..., 0] / roots[..., 1]
    p = np.where(np.isfinite(p), p, 0.0)
    p = np.sort(p, axis=-1)[..., ::-1]                           # r = 0: larger (p > 0)
    pzero = np.all(np.abs(p) <= p_zero_tol, axis=-1)
    # 3. pencil: null space of K(p)
    K = gen.k_matrix(f[..., None, :], p)                         # (..., 2, 4, 4)
    n1, n2 = _pencil(K)                                          # (..., 2, 4)
    # 4. U-joint quadric on the pencil
    S = gen.UJOINT_QUADRIC
    A = np.einsum("...i,ij,...j->...", n1, S, n1)
    B = 2.0 * np.einsum("...i,ij,...j->...", n1, S, n2)
    C = np.einsum("...i,ij,...j->...", n2, S, n2)
    uj_flat = np.maximum(np.maximum(np.abs(A), np.abs(B)), np.abs(C)) <= PENCIL_TOL
    ab = _hroots(A, B, C)                                        # (..., 2, 2 branch, 2)
    x = ab[..., 0, None] * n1[..., None, :] + ab[..., 1, None] * n2[..., None, :]
    x = x / np.linalg.norm(x, axis=-1, keepdims=True)            # (..., 2, 2, 4)
    st1, st2 = _segre_inverse(x)
    u1, _ = _angle(st1)
    u2, sin2 = _angle(st2)
    neg = (sin2[..., 0] < 0)[..., None]                          # b = 0: sin u2 > 0
    u1, u2, sin2 = (_order(neg, a, -1) for a in (u1, u2, sin2))
    x = _order(neg[..., None], x, -2)
    # 5. wrist
    h = _qmul(x * np.array([1.0, -1.0, -1.0, -1.0]), f[..., None, None, :4])
    css, cst, ctt = np.moveaxis(gen.wrist_quadratic(h), -1, 0)   # (..., 2, 2)
    wr_flat = np.maximum(np.maximum(np.abs(css), np.abs(cst)), np.abs(ctt)) <= PENCIL_TOL
    st5 = _hroots(css, cst, ctt)                                 # (..., 2, 2, 2 w, 2)
    m5c = np.stack([st5[..., 1], 0 * st5[..., 1], 0 * st5[..., 1], -st5[..., 0]], axis=-1)
    r34 = _qmul(h[..., None, :], m5c)              # (..., 2, 2, 2, 4)
    st3, st4 = _segre_inverse(r34)
    u3, _ = _angle(st3)
    u4, sin4 = _angle(st4)
    u5, _ = _angle(st5)
    negw = (sin4[..., 0] < 0)[..., None]                         # w = 0: sin u4 > 0
    u3, u4, u5, sin4 = (_order(negw, a, -1) for a in (u3, u4, u5, sin4))

    full = batch + (2, 2, 2)
    u = np.stack([np.broadcast_to(u1[..., None], full), np.broadcast_to(u2[..., None], full),
                  u3, u4, u5], axis=-1).reshape(batch + (8, 5))
    pp = np.broadcast_to(p[..., None, None], full).reshape(batch + (8,))
    deg_u = ~(np.abs(sin2) > degenerate_tol) | uj_flat[..., None]
    deg_w = ~(np.abs(sin4) > degenerate_tol) | wr_flat[..., None]
    deg_u = np.broadcast_to(deg_u[..., None], full).reshape(batch + (8,))
    deg_w = deg_w.reshape(batch + (8,))
    reason = np.zeros(batch + (8,), dtype=np.int8)
    reason = np.where(np.broadcast_to(pzero[..., None], reason.shape),
                      np.int8(Reason.SERIAL_P_ZERO), reason)
    reason = np.where((reason == 0) & deg_u, np.int8(Reason.UJOINT_SINGULAR), reason)
    reason = np.where((reason == 0) & deg_w, np.int8(Reason.WRIST_SINGULAR), reason)
    return pp, u, reason.astype(np.int8)


def serial_step_algebraic(par: ParallelSolution, T: FloatArray, *,
                          degenerate_tol: float, p_zero_tol: float, closure_tol: float
                          ) -> tuple[FloatArray, FloatArray, Int8Array,
                                     FloatArray]:
    """The serial step of the forward kinematics, the paper's way (shape (..., 2, 8)).

    Plugged into :func:`athenakin.forward_kinematics` by ``method="algebraic"``.

    Parameters
    ----------
    par : ParallelSolution
        Both assembly modes for the batch.
    T : ndarray, shape (..., 4, 4)
        RCM frames (may hold NaN items).
    degenerate_tol, p_zero_tol, closure_tol : float, keyword-only

    Returns
    -------
    p, u, reason, residual : ndarray
        Shapes (..., 2, 8), (..., 2, 8, 5), (..., 2, 8), (..., 2, 8).
    """
    finite = np.all(np.isfinite(T), axis=(-2, -1))
    Ts = np.where(par.valid[..., None, None], par.T_b_s, np.eye(4))       # (..., 2, 4, 4)
    Te = np.where(finite[..., None, None], T, np.eye(4))
    b = study_from_transform(Ts)                                          # (..., 2, 8)
    e = study_from_transform(Te)[..., None, :]
    f = dq_multiply(dq_conj_quaternion(b), e)                             # B^-1 E
    p, u, sreason = serial_solutions_algebraic(f, degenerate_tol=degenerate_tol,
                                               p_zero_tol=p_zero_tol)     # (..., 2, 8)
    T_s_e = np.linalg.solve(Ts, Te[..., None, :, :])                      # (..., 2, 4, 4)
    with np.errstate(invalid="ignore"):
        res = closure_residual(ups_transform(np.where(np.isfinite(p), p, 0.0),
                                             np.where(np.isfinite(u), u, 0.0)),
                               T_s_e[..., None, :, :])
    res = np.where(np.all(np.isfinite(u), axis=-1) & np.isfinite(p), res, np.inf)
    sreason = np.where(~finite[..., None, None], np.int8(Reason.NONFINITE_INPUT), sreason)
    sreason = np.where((sreason == 0) & ~(res <= closure_tol), np.int8(Reason.CLOSURE_FAILED),
                       sreason)
    return p, u, sreason.astype(np.int8), res


# the whole-robot FK's method="algebraic" (robot never imports symbolic: registered from here)
register_serial_step("algebraic", serial_step_algebraic)
