"""Scalar maths for the compiled kernels (private): branch-free, so that loops vectorise.

numba has no vector maths library here (no SVML), so a call to libm ``atan2``,
``sin`` or ``hypot`` inside a loop stops LLVM from vectorising it and costs
15-30 ns per call. The functions below are straight-line arithmetic (selects,
no calls, no exceptions), and LLVM turns a loop over them into AVX-512 code.

Accuracy: :func:`atan_q1` and :func:`sincos` are the Cephes rational /
polynomial approximations (relative error about 2e-16 on their reduced
ranges); they agree with numpy's ``arctan2`` / ``sin`` / ``cos`` to within a
few units in the last place, which is also how far numpy's own SIMD
``arctan2`` is from the C library's. :func:`sincos` is accurate for
``|x| <= SINCOS_MAX``; the kernels report larger arguments so that the caller
can recompute those items with the C library.

Every function is compiled with ``error_model="numpy"``: a division by zero
gives inf/NaN instead of raising, which is what lets the loops vectorise.
"""

from __future__ import annotations

import math

from .._backend import njit

__all__ = ["PI", "TWO_PI", "SINCOS_MAX", "atan_q1", "atan2_from_q1", "atan2", "sincos",
           "wrap_pi", "wrap_mod", "hypot", "nanmax2", "finite_sum"]

PI = math.pi
TWO_PI = 2.0 * math.pi
HALF_PI = 0.5 * math.pi
QUARTER_PI = 0.25 * math.pi
#: Largest ``|x|`` for which :func:`sincos`'s three-part Cody-Waite reduction is exact enough.
SINCOS_MAX = 2.0 ** 26

# Cephes atan.c
_T3P8 = 2.41421356237309504880
_MOREBITS = 6.123233995736765886130e-17
_P0, _P1, _P2, _P3, _P4 = (-8.750608600031904122785e-1, -1.615753718733365076637e1,
                           -7.500855792314704667340e1, -1.228866684490136173410e2,
                           -6.485021904942025371773e1)
_Q0, _Q1, _Q2, _Q3, _Q4 = (2.485846490142306297962e1, 1.650270098316988542046e2,
                           4.328810604912902668951e2, 4.853903996359136964868e2,
                           1.945506571482613964425e2)
# Cephes sin.c
_DP1 = 7.85398125648498535156e-1
_DP2 = 3.77489470793079817668e-8
_DP3 = 2.69515142907905952645e-15
_S0, _S1, _S2, _S3, _S4, _S5 = (1.58962301576546568060e-10, -2.50507477628578072866e-8,
                                2.75573136213857245213e-6, -1.98412698295895385996e-4,
                                8.33333333332211858878e-3, -1.66666666666666307295e-1)
_C0, _C1, _C2, _C3, _C4, _C5 = (-1.13585365213876817300e-11, 2.08757008419747316778e-9,
                                -2.75573141792967388112e-7, 2.48015872888517045348e-5,
                                -1.38888888888730564116e-3, 4.16666666666665929218e-2)
_FOUR_OVER_PI = 4.0 / math.pi
_PI_HI = math.pi
_PI_LO = 1.2246467991473532e-16    # pi - _PI_HI

_OPTS = dict(error_model="numpy", cache=True, nogil=True)


@njit(**_OPTS)
def atan_q1(n: float, d: float) -> float:
    """``atan2(n, d)`` for ``n, d >= 0``: an angle in ``[0, pi/2]`` (NaN in, NaN out).

    Cephes ``atan`` with the argument ``n / d`` reduced without forming it:
    ``-d / n`` above ``tan(3 pi / 8)``, ``(n - d) / (n + d)`` above 0.66.
    """
    f1 = n > _T3P8 * d
    f2 = (n > 0.66 * d) & (not f1)
    num = -d if f1 else (n - d if f2 else n)
    den = n if f1 else (n + d if f2 else d)
    x = num / den
    x = 0.0 if den == 0.0 else x
    y0 = HALF_PI if f1 else (QUARTER_PI if f2 else 0.0)
    mb = _MOREBITS if f1 else (0.5 * _MOREBITS if f2 else 0.0)
    z = x * x
    p = (((_P0 * z + _P1) * z + _P2) * z + _P3) * z + _P4
    q = ((((z + _Q0) * z + _Q1) * z + _Q2) * z + _Q3) * z + _Q4
    z = z * p / q
    z = x * z + x
    return y0 + (z + mb)


@njit(**_OPTS)
def atan2_from_q1(a: float, s: float, c: float) -> float:
    """``atan2(s, c)`` from ``a = atan_q1(|s|, |c|)``, in ``(-pi, pi]``.

    Signed zeros are honoured as by C's ``atan2`` (``atan2(-0., -1.) = -pi``),
    and the result is then wrapped like the reference (``-pi`` becomes ``pi``).
    """
    r = _PI_HI + (_PI_LO - a) if math.copysign(1.0, c) < 0.0 else a
    r = math.copysign(r, s)
    return r + TWO_PI if r <= -PI else r


@njit(**_OPTS)
def atan2(s: float, c: float) -> float:
    """``atan2(s, c)`` in ``(-pi, pi]`` (branch-free; see :func:`atan2_from_q1`)."""
    return atan2_from_q1(atan_q1(abs(s), abs(c)), s, c)


@njit(**_OPTS)
def sincos(x: float) -> tuple[float, float]:
    """``(sin x, cos x)`` (Cephes ``sin``/``cos``, one shared reduction), ``|x| <= SINCOS_MAX``."""
    ax = abs(x)
    y = math.floor(ax * _FOUR_OVER_PI)
    odd = y - 2.0 * math.floor(0.5 * y)
    y = y + odd
    j = y - 8.0 * math.floor(0.125 * y)   # 0, 2, 4 or 6
    z = ((ax - y * _DP1) - y * _DP2) - y * _DP3
    zz = z * z
    sp = z + z * zz * (((((_S0 * zz + _S1) * zz + _S2) * zz + _S3) * zz + _S4) * zz + _S5)
    cp = 1.0 - 0.5 * zz + zz * zz * (((((_C0 * zz + _C1) * zz + _C2) * zz + _C3) * zz + _C4)
                                     * zz + _C5)
    # octant pair k = j / 2: sin = (sp, cp, -sp, -cp)[k], cos = (cp, -sp, -cp, sp)[k]
    swap = (j == 2.0) | (j == 6.0)
    s = cp if swap else sp
    c = sp if swap else cp
    s = -s if j >= 4.0 else s
    c = -c if (j == 2.0) | (j == 4.0) else c
    s = -s if x < 0.0 else s
    return s, c


@njit(**_OPTS)
def wrap_pi(a: float) -> float:
    """Map an angle in ``[-pi, pi]`` to ``(-pi, pi]`` (the reference's ``_wrap`` of FK)."""
    return a + TWO_PI if a <= -PI else a


@njit(**_OPTS)
def wrap_mod(a: float) -> float:
    """``mod(a + pi, 2 pi) - pi``, then ``-pi`` to ``pi`` (the reference IK's ``_wrap``).

    ``mod`` is formed with ``floor`` (vectorisable) instead of ``fmod``; the two
    agree exactly on ``[0, 2 pi)`` and to an ulp of ``a`` outside it.
    """
    t = a + PI
    m = t - TWO_PI * math.floor(t / TWO_PI)
    m = m + TWO_PI if m < 0.0 else m
    m = m - TWO_PI if m >= TWO_PI else m
    r = m - PI
    return r + TWO_PI if r <= -PI else r


@njit(**_OPTS)
def hypot(x: float, y: float) -> float:
    """``sqrt(x^2 + y^2)`` without the C library call (within an ulp of ``np.hypot``).

    Callers only pass bounded values (unit-vector components, positions in
    metres); overflow to inf, underflow to 0 fall on the same side of every
    threshold the reference tests.
    """
    return math.sqrt(x * x + y * y)


@njit(**_OPTS)
def nanmax2(r: float, d: float) -> float:
    """``max(r, d)`` that propagates NaN from either argument (like ``np.maximum``)."""
    return r if (r != r) | (r >= d) else d


@njit(**_OPTS)
def finite_sum(x: float) -> float:
    """0.0 for a finite ``x``, NaN for inf / NaN (sum these to test many values at once)."""
    return x - x


#: 4 machine epsilons: the rounding allowance of each factor of ``k`` (Eq. 8) per unit of
#: the lengths it is made of (:func:`athenakin.parallel._module.parallel_residual`).
K_ROUND = 4.0 * 2.220446049250313e-16


@njit(**_OPTS)
def parallel_residual(r1: float, q3: float, d: float, k: float, l1: float, l4: float,
                      tangent: bool) -> float:
    """Bound on the position error of ``O_s`` from the rounding of ``k`` (m).

    The same operations, in the same order, as the reference
    :func:`athenakin.parallel._module.parallel_residual`: both backends decide the
    validity of a near-tangent slot from the same bits.
    """
    a1 = (r1 + q3) - d
    a2 = (r1 + q3) + d
    a3 = (d - r1) + q3
    a4 = (d + r1) - q3
    s = ((r1 + abs(q3)) + d) + (l1 * l1) / r1
    dk = (K_ROUND * s) * (((abs((a2 * a3) * a4) + abs((a1 * a3) * a4))
                           + abs((a1 * a2) * a4)) + abs((a1 * a2) * a3))
    two_d = 2.0 * d
    hi = math.sqrt(abs(k) + dk) / two_d
    kl = k - dk
    lo = math.sqrt(kl if kl > 0.0 else 0.0) / two_d
    err = hi if tangent else hi - lo
    return err * ((r1 + l4) / r1)
