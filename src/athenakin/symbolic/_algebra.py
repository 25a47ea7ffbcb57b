"""Dual-quaternion algebra in sympy (paper Eq. 1-6): the building blocks of the derivation.

A Study vector is an 8-tuple ``(x0, x1, x2, x3, y0, y1, y2, y3)`` read as the dual
quaternion ``x + eps*y`` with Hamilton products, ``x0`` the scalar part (docs/conventions.md).
Here it is a :class:`sympy.ImmutableMatrix` of shape (8, 1). The translation of a
Study vector is ``t = -2 y conj(x) / |x|^2`` (Eq. 3-4), i.e. ``y = -t x / 2``.

The joint transforms of Eq. 6 in half-tangents (``v = tan(u/2)``, ``al = tan(alpha/2)``)
are, projectively,

* ``M(v) = (1, 0, 0, v, 0, 0, 0, 0)`` (rotation about z by ``u``),
* ``G(a, d, al) = (1, al, 0, 0, a*al/2, -a/2, -d*al/2, -d/2)`` (translate by
  ``(a, 0, d)``, then rotate about x by ``alpha``),

the same vectors as :func:`athenakin.study.study_M_from_half_tangent` and
:func:`athenakin.study.study_G_from_half_tangent`.
"""

from __future__ import annotations

from collections.abc import Sequence

import sympy as sp

__all__ = [
    "B_SYMBOLS",
    "E_SYMBOLS",
    "F_SYMBOLS",
    "X_SYMBOLS",
    "V_SYMBOLS",
    "P_SYMBOL",
    "study_vector",
    "quaternion_multiply",
    "dq_multiply",
    "dq_product",
    "dq_conj_quaternion",
    "study_M",
    "study_G",
    "study_quadric",
    "paper_matrix",
    "transform_matrix",
]

#: Study parameters of the intermediate frame ``B`` (Eq. 10): ``b0..b7``.
B_SYMBOLS: tuple[sp.Symbol, ...] = sp.symbols("b0:8", real=True)
#: Study parameters of the end-effector (RCM) frame ``E``: ``e0..e7``.
E_SYMBOLS: tuple[sp.Symbol, ...] = sp.symbols("e0:8", real=True)
#: Study parameters of ``F = B^-1 E`` (the RCM frame seen from ``O_s``): ``f0..f7``.
F_SYMBOLS: tuple[sp.Symbol, ...] = sp.symbols("f0:8", real=True)
#: The unknown Study vector ``X = (x0, x1, x2, x3, y0, y1, y2, y3)`` of the closure.
X_SYMBOLS: tuple[sp.Symbol, ...] = sp.symbols("x0:4 y0:4", real=True)
#: Half-tangents ``v1..v5`` of the joint angles ``u1..u5``.
V_SYMBOLS: tuple[sp.Symbol, ...] = sp.symbols("v1:6", real=True)
#: The passive prismatic joint ``p`` (``d3`` of Eq. 12).
P_SYMBOL: sp.Symbol = sp.Symbol("p", real=True)


def study_vector(entries: Sequence[sp.Expr], name: str = "entries") -> sp.ImmutableMatrix:
    """An 8-vector ``(x0..x3, y0..y3)`` as an immutable (8, 1) sympy matrix.

    Raises
    ------
    TypeError
        ``entries`` is not a sequence of expressions (sympy cannot read an entry).
    ValueError
        It does not have 8 entries. Both messages start with ``name``.
    """
    try:
        if isinstance(entries, (str, bytes)):
            raise TypeError
        entries = list(entries)
    except TypeError:
        raise TypeError(f"{name}: expected 8 sympy expressions (x0..x3, y0..y3), got "
                        f"{type(entries).__name__}") from None
    if len(entries) != 8:
        raise ValueError(f"{name}: expected 8 components (x0..x3, y0..y3), got {len(entries)}")
    try:
        return sp.ImmutableMatrix(8, 1, [sp.sympify(c, strict=True) for c in entries])
    except (sp.SympifyError, TypeError, ValueError) as exc:
        raise TypeError(f"{name}: expected sympy expressions or numbers, got {exc}") from None


def quaternion_multiply(a: Sequence[sp.Expr], b: Sequence[sp.Expr]) -> list[sp.Expr]:
    """Hamilton product of quaternions ``(w, x, y, z)`` (scalar first), not expanded."""
    a0, a1, a2, a3 = a
    b0, b1, b2, b3 = b
    return [a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
            a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
            a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
            a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0]


def dq_multiply(X1: Sequence[sp.Expr], X2: Sequence[sp.Expr]) -> sp.ImmutableMatrix:
    """Dual-quaternion product ``X1 * X2`` (composes displacements), expanded.

    Parameters
    ----------
    X1, X2 : sequence of 8 sympy expressions
        ``(x0..x3, y0..y3)``.

    Returns
    -------
    sympy.ImmutableMatrix, shape (8, 1)
        ``(x1 x2, x1 y2 + y1 x2)``.
    """
    X1, X2 = list(study_vector(X1, "X1")), list(study_vector(X2, "X2"))
    x = quaternion_multiply(X1[:4], X2[:4])
    y = [u + w for u, w in zip(quaternion_multiply(X1[:4], X2[4:]),
                               quaternion_multiply(X1[4:], X2[:4]), strict=True)]
    return study_vector([sp.expand(c) for c in x + y])


def dq_product(factors: Sequence[Sequence[sp.Expr]]) -> sp.ImmutableMatrix:
    """Product ``F1 * F2 * ... * Fn`` of dual quaternions, left to right, expanded."""
    factors = list(factors)
    if not factors:
        raise ValueError("factors: expected at least one dual quaternion, got none")
    out = study_vector(list(factors[0]))
    for f in factors[1:]:
        out = dq_multiply(out, f)
    return out


def dq_conj_quaternion(X: Sequence[sp.Expr]) -> sp.ImmutableMatrix:
    """``conj(x) + eps conj(y)``: for a Study vector, the inverse displacement (up to scale)."""
    X = list(study_vector(X, "X"))
    return study_vector([X[0], -X[1], -X[2], -X[3], X[4], -X[5], -X[6], -X[7]])


def study_M(v: sp.Expr) -> sp.ImmutableMatrix:
    """``M_i`` of Eq. 6 in the half-tangent ``v = tan(u/2)``: ``(1, 0, 0, v, 0, 0, 0, 0)``."""
    return study_vector([1, 0, 0, v, 0, 0, 0, 0], "v")


def study_G(a: sp.Expr, d: sp.Expr, al: sp.Expr) -> sp.ImmutableMatrix:
    """``G_i`` of Eq. 6 in the half-tangent ``al = tan(alpha/2)``.

    ``(1, al, 0, 0, a*al/2, -a/2, -d*al/2, -d/2)``: translation by ``(a, 0, d)``
    followed by the rotation about x by ``alpha``.
    """
    a, d, al = sp.sympify(a), sp.sympify(d), sp.sympify(al)
    return study_vector([1, al, 0, 0, a * al / 2, -a / 2, -d * al / 2, -d / 2], "a, d, al")


def study_quadric(X: Sequence[sp.Expr]) -> sp.Expr:
    """The Study quadric ``x0*y0 + x1*y1 + x2*y2 + x3*y3`` of an 8-vector, expanded."""
    X = list(study_vector(X, "X"))
    return sp.expand(sum(X[i] * X[i + 4] for i in range(4)))


def _eq3_parts(X: Sequence[sp.Expr]) -> tuple[sp.Matrix, sp.Matrix, sp.Expr]:
    x0, x1, x2, x3, y0, y1, y2, y3 = list(study_vector(X, "X"))
    R = sp.Matrix([
        [x0**2 + x1**2 - x2**2 - x3**2, 2 * (x1 * x2 - x0 * x3), 2 * (x1 * x3 + x0 * x2)],
        [2 * (x1 * x2 + x0 * x3), x0**2 - x1**2 + x2**2 - x3**2, 2 * (x2 * x3 - x0 * x1)],
        [2 * (x1 * x3 - x0 * x2), 2 * (x2 * x3 + x0 * x1), x0**2 - x1**2 - x2**2 + x3**2]])
    t = sp.Matrix([2 * (-x0 * y1 + x1 * y0 - x2 * y3 + x3 * y2),
                   2 * (-x0 * y2 + x1 * y3 + x2 * y0 - x3 * y1),
                   2 * (-x0 * y3 - x1 * y2 + x2 * y1 + x3 * y0)])
    return R, t, x0**2 + x1**2 + x2**2 + x3**2


def paper_matrix(X: Sequence[sp.Expr]) -> sp.Matrix:
    """Eq. 3-4 literally: the 4x4 matrix in the paper's layout (homogenising coordinate first).

    Returns ``Delta * T`` (no division): ``[[Delta, 0], [(p, q, r), Delta * R]]``,
    a polynomial matrix in the Study parameters.
    """
    R, t, D = _eq3_parts(X)
    M = sp.zeros(4, 4)
    M[0, 0] = D
    M[1:, 0] = t
    M[1:, 1:] = R
    return M


def transform_matrix(X: Sequence[sp.Expr]) -> sp.Matrix:
    """The displacement of Eq. 3-4 as ``[[R, t], [0, 1]]`` (ecosystem layout, divided by Delta)."""
    R, t, D = _eq3_parts(X)
    M = sp.eye(4)
    M[:3, :3] = R / D
    M[:3, 3] = t / D
    return M
