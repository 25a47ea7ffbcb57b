"""The remaining joints ``v1..v5`` for a root ``p``, in a form that vectorises (Section 3.2, end).

The paper finishes with a Groebner basis of ``lc = lambda rc`` at each root ``p``
(:func:`~athenakin.symbolic.groebner_remaining` does exactly that for exact
numbers). A Groebner basis per pose cannot be batched, so the generated solver
uses the structure that the basis exhibits, derived here once and symbolically:

* At a root ``p`` the skew matrix ``K(p)`` of :func:`~athenakin.symbolic.elimination_steps`
  has rank 2: the quaternion parts ``x`` of the closure ``X`` form a pencil
  ``x = alpha n1 + beta n2`` (the line ``sl ∩ sr`` in P^7).
* The left chain's quaternion part ``(-2 v1 v2, 2, 2 v1, 2 v2)`` (with ``B = 1``)
  is a Segre quadric: LIA of degree 2 (:func:`ujoint_quadric`) gives its one
  implicit equation ``x0 x1 + x2 x3 = 0``. On the pencil it is a quadratic form in
  ``(alpha : beta)``: two U-joint solutions.
* ``v1, v2`` follow from ``x`` by inverting the Segre map (:func:`segre_inverse`).
* The right chain gives ``r345 = M3 G3' M4 G4 M5 ~ conj(x) f_x =: h`` (quaternion
  parts), so ``r34 = M3 G3' M4 G4 ~ h (1, 0, 0, -v5)``: linear in ``v5`` and on the
  Segre quadric of ``r34`` (:func:`wrist_quadric`), a quadratic in ``v5``
  (:func:`wrist_quadratic`): two wrist solutions. ``v3, v4`` by the Segre inverse.

All half-tangents are carried homogeneously, ``v_i = s_i / t_i``, so that a half
turn (``u_i = pi``, ``v_i`` infinite, ``t_i = 0``) is an ordinary solution.
"""

from __future__ import annotations

import functools

import sympy as sp

from ._algebra import (
    V_SYMBOLS,
    X_SYMBOLS,
    checked_symbolic,
    dq_product,
    quaternion_multiply,
    study_G,
    study_M,
)
from ._chain import left_chain
from ._elimination import IDENTITY, assign
from ._lia import implicitize

__all__ = [
    "H_SYMBOLS",
    "S_SYMBOLS",
    "T_SYMBOLS",
    "ujoint_quadric",
    "wrist_quaternion",
    "wrist_quadric",
    "wrist_quadratic",
    "segre_map",
    "segre_inverse",
    "quadric_matrix",
]

#: The quaternion ``h = conj(x) f_x`` of the wrist step.
H_SYMBOLS: tuple[sp.Symbol, ...] = sp.symbols("h0:4", real=True)
#: Homogeneous half-tangents: ``v_i = s_i / t_i``.
S_SYMBOLS: tuple[sp.Symbol, ...] = sp.symbols("s1:6", real=True)
T_SYMBOLS: tuple[sp.Symbol, ...] = sp.symbols("t1:6", real=True)

_X4 = X_SYMBOLS[:4]


def _single(eqs: list[sp.Expr], what: str) -> sp.Expr:
    if len(eqs) != 1:
        raise ValueError(f"{what}: expected exactly one implicit equation, got {len(eqs)}")
    return eqs[0]


@functools.cache
def ujoint_quadric() -> sp.Expr:
    """LIA of degree 2 on the quaternion part of the left chain with ``B = 1``.

    Returns
    -------
    sympy.Expr
        The single quadric in ``x0..x3`` that the U-joint rotations satisfy.
    """
    lc = assign(left_chain(), b=IDENTITY)
    return _single(implicitize(lc[:4], V_SYMBOLS[:2], 2, coordinates=_X4), "U-joint quadric")


@functools.cache
def wrist_quaternion() -> tuple[sp.Expr, ...]:
    """Quaternion part of ``M3 G3' M4 G4`` (``G3' = R_x(pi/2)``, ``G4 = R_x(pi/2)``)."""
    v3, v4 = V_SYMBOLS[2:4]
    prod = dq_product([study_M(v3), study_G(0, 0, 1), study_M(v4), study_G(0, 0, 1)])
    return tuple(prod[:4])


@functools.cache
def wrist_quadric() -> sp.Expr:
    """LIA of degree 2 on :func:`wrist_quaternion`: the quadric of the two-axis wrist part."""
    return _single(implicitize(wrist_quaternion(), V_SYMBOLS[2:4], 2, coordinates=_X4),
                   "wrist quadric")


@functools.cache
def wrist_quadratic() -> tuple[sp.Expr, sp.Expr, sp.Expr]:
    """Coefficients ``(c_ss, c_st, c_tt)`` of the wrist quadratic in ``(s5 : t5)``.

    ``r34 ~ h * (t5, 0, 0, -s5)`` must satisfy :func:`wrist_quadric`; expanded this is
    ``c_ss s5^2 + c_st s5 t5 + c_tt t5^2 = 0`` with ``c_*`` quadratic in ``h0..h3``.
    """
    s5, t5 = S_SYMBOLS[4], T_SYMBOLS[4]
    r = quaternion_multiply(H_SYMBOLS, (t5, 0, 0, -s5))
    Q = wrist_quadric().xreplace(dict(zip(_X4, r, strict=True)))
    P = sp.Poly(sp.expand(Q), s5, t5)
    return (P.coeff_monomial(s5**2), P.coeff_monomial(s5 * t5), P.coeff_monomial(t5**2))


@checked_symbolic(s_a="expr", t_a="expr", s_b="expr", t_b="expr")
def segre_map(s_a: sp.Expr, t_a: sp.Expr, s_b: sp.Expr, t_b: sp.Expr) -> tuple[sp.Expr, ...]:
    """``(-s_a s_b, t_a t_b, s_a t_b, t_a s_b)``: two-axis quaternion, homogeneous half-tangents.

    Projectively equal to the quaternion parts of ``M(v_a) G(0, 0, 1) M(v_b) G(0, 0, 1)``
    (and of the left chain with ``B = 1``) for ``v_a = s_a / t_a``, ``v_b = s_b / t_b``.

    Parameters
    ----------
    s_a, t_a : sympy expression
        Homogeneous half-tangent of the first joint, ``v_a = s_a / t_a``.
    s_b, t_b : sympy expression
        Same for the second joint.

    Returns
    -------
    tuple of 4 sympy.Expr
        ``(-s_a s_b, t_a t_b, s_a t_b, t_a s_b)``.
    """
    return (-s_a * s_b, t_a * t_b, s_a * t_b, t_a * s_b)


@checked_symbolic(r="exprs")
def segre_inverse(r: tuple[sp.Expr, ...]
                  ) -> tuple[tuple[tuple[sp.Expr, sp.Expr], tuple[sp.Expr, sp.Expr]],
                             tuple[tuple[sp.Expr, sp.Expr], tuple[sp.Expr, sp.Expr]]]:
    """Two representatives each of ``(s_a : t_a)`` and ``(s_b : t_b)`` from a quadric point ``r``.

    For ``r = segre_map(s_a, t_a, s_b, t_b)``: ``(s_a : t_a) = (r2 : r1) = (-r0 : r3)``
    (the first is ``t_b`` times it, the second ``s_b`` times it) and
    ``(s_b : t_b) = (r3 : r1) = (-r0 : r2)``. A solver takes the larger of each pair.

    Parameters
    ----------
    r : tuple of 4 sympy expressions
        A point ``(r0, r1, r2, r3)`` of the quadric ``r0 r1 + r2 r3 = 0``.

    Returns
    -------
    ((s_a, t_a), (s_a, t_a)), ((s_b, t_b), (s_b, t_b))
        The two representatives of each half-tangent pair, as above.
    """
    r0, r1, r2, r3 = r
    return ((r2, r1), (-r0, r3)), ((r3, r1), (-r0, r2))


def quadric_matrix(Q: sp.Expr) -> sp.Matrix:
    """Symmetric matrix ``S`` with ``Q(x) = x^T S x`` for a quadratic form in ``x0..x3``."""
    return sp.Matrix(4, 4, lambda i, j: sp.diff(Q, _X4[i], _X4[j]) / 2)
