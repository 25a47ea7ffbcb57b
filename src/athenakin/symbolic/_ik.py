"""Eq. 15-16: the two bilinear equations in ``v1, v2`` of the inverse kinematics (Section 4).

``B = E G5^-1 M5^-1 G4^-1 M4^-1 G3^-1 M3^-1 G2^-1 M2^-1 G1^-1 M1^-1`` (corrected
Eq. 15; :func:`~athenakin.symbolic.ik_product`). ``B`` is a rotation about the
base x-axis followed by a translation, so the quaternion part of its Study
vector is ``(c, s, 0, 0)``: entries ``x2`` and ``x3`` (the paper's "third and
fourth entry") vanish. These two entries of the right-hand side, with
``v3, v4, v5`` given, are the two equations; each is bilinear in ``v1, v2``.
"""

from __future__ import annotations

import functools

import sympy as sp

from ._algebra import V_SYMBOLS, checked_symbolic
from ._chain import ChainComparison, compare_vectors, ik_product

__all__ = ["ik_bilinear_equations", "compare_eq16", "bilinear_coefficients"]


def _primitive(expr: sp.Expr) -> sp.Expr:
    _, prim = sp.Poly(expr, *sorted(expr.free_symbols, key=str)).primitive()
    return prim.as_expr()


@functools.cache
def ik_bilinear_equations() -> tuple[sp.Expr, sp.Expr]:
    """The two equations of Section 4: entries ``x2`` and ``x3`` of the corrected Eq. 15.

    Returns
    -------
    tuple of 2 sympy expressions
        Polynomials in ``e0..e3`` and ``v1..v5`` (content removed), each ``= 0``
        at an inverse-kinematics solution; bilinear in ``v1, v2``.
    """
    R = ik_product()
    return _primitive(sp.expand(R[2])), _primitive(sp.expand(R[3]))


@checked_symbolic(eq="expr")
def bilinear_coefficients(eq: sp.Expr) -> tuple[sp.Expr, sp.Expr, sp.Expr, sp.Expr]:
    """Coefficients ``(c11, c1, c2, c0)`` of ``c11 v1 v2 + c1 v1 + c2 v2 + c0``.

    Parameters
    ----------
    eq : sympy.Expr
        Polynomial of degree at most 1 in each of ``v1, v2`` (e.g. Eq. 16).

    Returns
    -------
    tuple of 4 sympy.Expr
        ``(c11, c1, c2, c0)``, free of ``v1, v2``.

    Raises
    ------
    ValueError
        If ``eq`` is not bilinear in ``v1, v2``.
    """
    v1, v2 = V_SYMBOLS[:2]
    P = sp.Poly(eq, v1, v2)
    if P.degree(v1) > 1 or P.degree(v2) > 1:
        raise ValueError(f"eq: expected a bilinear polynomial in v1, v2, got degrees "
                         f"{P.degree(v1)}, {P.degree(v2)}")
    return (P.coeff_monomial(v1 * v2), P.coeff_monomial(v1), P.coeff_monomial(v2),
            P.coeff_monomial(1))


def compare_eq16() -> dict[int, ChainComparison]:
    """Compare the printed Eq. 16 with each quaternion entry ``x0..x3`` of the corrected Eq. 15.

    Returns
    -------
    dict of int -> ChainComparison
        Entry index -> comparison (``.equal`` tells which entry the printed
        equation is, up to a constant scale).
    """
    from ._printed import printed_eq16

    R = ik_product()
    out = {}
    for i in range(4):
        out[i] = compare_vectors([R[i]], [printed_eq16()])
    return out
