"""The elimination of Section 3.2: ``sl``, ``sr``, ``y``, ``x`` and the quadratic in ``p``.

The steps, each a function returning its result:

1. :func:`implicit_sets`: LIA (degree 1) on the left chain (eliminating ``v1, v2``)
   and on the right chain (eliminating ``v3, v4, v5``) gives the sets ``sl`` (in
   ``b0..b7``, ``p``) and ``sr`` (in ``e0..e7``): four equations each, all linear in
   the Study parameters ``x0..y3`` of the closure ``X``.
2. :func:`assign`: the paper assigns values to the Study parameters of the
   intermediate system ``B`` and of ``E`` ("the equations get quite involved"
   otherwise). The default assignment is ``B = 1`` (the chain expressed in its own
   base frame ``O_s``) and ``E = F = (f0, ..., f7)``, the symbolic Study vector of
   ``T_s_e = B^-1 E``: general, and small enough to carry symbolically.
3. :func:`solve_y_from_sl`: ``sl`` is solved linearly for ``y0..y3``.
4. :func:`sr_in_x`: substituted into ``sr``, four equations remain, linear in
   ``x0..x3``: ``M(p) x = 0``.
5. :func:`reduce_study`: on the Study quadrics of ``B`` and ``E`` the symmetric
   part of ``M`` vanishes; ``M`` is then skew-symmetric, so ``det M = Pf(M)^2``.
6. :func:`solve_x_from_sr`: three equations are solved for three of the ``x_i``
   (Cramer's rule) in terms of the fourth. Because ``M`` is skew, the choice matters:
   the three equations ``i, j, k`` solved for ``x_i, x_j, x_k`` form a principal
   minor of a 3x3 skew matrix, whose determinant is identically 0. The default
   solves equations 1, 2, 3 for ``x0, x1, x2`` (the paper's "e.g. x0, x1, x2").
7. :func:`back_substitute` / :func:`p_quadratic`: back substitution into the
   remaining equation leaves ``Pf(K(p))`` times factors free of ``p``: the
   quadratic in ``p`` (for special data the minor can share a root with the
   Pfaffian, which then cancels: :func:`p_quadratic` returns ``-Pf(K)`` itself).
8. :func:`groebner_remaining`: for numeric (exact) values, the paper's last step:
   ``lc = lambda rc`` at a root ``p`` and a lex Groebner basis for ``v1..v5``.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Mapping, Sequence

import numpy as np
import sympy as sp

from ._algebra import (
    B_SYMBOLS,
    E_SYMBOLS,
    F_SYMBOLS,
    P_SYMBOL,
    V_SYMBOLS,
    X_SYMBOLS,
    checked_symbolic,
)
from ._chain import left_chain, right_chain
from ._lia import implicitize

__all__ = [
    "IDENTITY",
    "LAMBDA",
    "EliminationSteps",
    "GroebnerStep",
    "implicit_sets",
    "assign",
    "solve_y_from_sl",
    "sr_in_x",
    "reduce_study",
    "solve_x_from_sr",
    "back_substitute",
    "elimination_steps",
    "p_quadratic",
    "groebner_remaining",
]

#: The identity displacement as a Study vector.
IDENTITY: tuple[int, ...] = (1, 0, 0, 0, 0, 0, 0, 0)
#: The unknown scale of ``lc = lambda * rc`` in :func:`groebner_remaining`.
LAMBDA = sp.Symbol("lambda")

_X = X_SYMBOLS[:4]
_Y = X_SYMBOLS[4:]


@functools.cache
def implicit_sets() -> tuple[tuple[sp.Expr, ...], tuple[sp.Expr, ...]]:
    """``(sl, sr)``: LIA of degree 1 on :func:`left_chain` and :func:`right_chain`.

    Returns
    -------
    sl : tuple of 4 sympy expressions
        Linear in ``x0..y3``, coefficients polynomial in ``b0..b7`` and ``p``.
    sr : tuple of 4 sympy expressions
        Linear in ``x0..y3``, coefficients polynomial in ``e0..e7``.
    """
    sl = implicitize(left_chain(), V_SYMBOLS[:2], 1)
    sr = implicitize(right_chain(), V_SYMBOLS[2:], 1)
    return tuple(sl), tuple(sr)


def _values(vec: Sequence[sp.Expr] | None, default: Sequence[sp.Expr], name: str
            ) -> tuple[sp.Expr, ...]:
    if isinstance(vec, (str, bytes)):
        raise TypeError(f"{name}: expected a Study vector of 8 numbers or sympy expressions, "
                        f"got {type(vec).__name__}")
    try:
        vec = tuple(default if vec is None else vec)  # type: ignore[arg-type]
    except TypeError:
        raise TypeError(f"{name}: expected a Study vector of 8 numbers or sympy expressions, "
                        f"got {type(vec).__name__}") from None
    if len(vec) != 8:
        raise ValueError(f"{name}: expected a Study vector of 8 entries, got {len(vec)}")
    out = []
    for v in vec:
        if isinstance(v, float) and not np.isfinite(v):
            raise ValueError(f"{name}: expected finite entries, got {v}")
        try:
            x = sp.nsimplify(v) if isinstance(v, float) else sp.sympify(v, strict=True)
        except (sp.SympifyError, TypeError, ValueError):
            raise TypeError(f"{name}: expected numbers or sympy expressions, got "
                            f"{type(v).__name__}") from None
        if not isinstance(x, sp.Expr):
            raise TypeError(f"{name}: expected numbers or sympy expressions, got {v!r}")
        out.append(x)
    return tuple(out)


@checked_symbolic(exprs="exprs")
def assign(exprs: Sequence[sp.Expr], *, b: Sequence[sp.Expr] | None = IDENTITY,
           e: Sequence[sp.Expr] | None = F_SYMBOLS) -> tuple[sp.Expr, ...]:
    """Assign values (numbers or symbols) to the Study parameters of ``B`` and ``E``.

    Parameters
    ----------
    exprs : sequence of sympy expressions
        In ``b0..b7``, ``e0..e7`` (and anything else, left alone).
    b, e : sequence of 8 values, keyword-only
        Default ``B = 1`` and ``E = (f0..f7)`` (the RCM frame seen from ``O_s``).
        ``None`` keeps the symbols. Floats are converted to exact rationals.

    Returns
    -------
    tuple of sympy expressions
        ``exprs`` with the values substituted, expanded.
    """
    bv = _values(b, B_SYMBOLS, "b")
    ev = _values(e, E_SYMBOLS, "e")
    sub = {**dict(zip(B_SYMBOLS, bv, strict=True)), **dict(zip(E_SYMBOLS, ev, strict=True))}
    return tuple(sp.expand(sp.sympify(x).xreplace(sub)) for x in exprs)


@checked_symbolic(sl="exprs")
def solve_y_from_sl(sl: Sequence[sp.Expr]) -> dict[sp.Symbol, sp.Expr]:
    """Step 3: solve the four equations of ``sl`` linearly for ``y0..y3``.

    Parameters
    ----------
    sl : sequence of 4 sympy expressions
        The left chain's implicit equations (:func:`implicit_sets`, after :func:`assign`),
        linear in ``y0..y3``.

    Returns
    -------
    dict
        ``{y_i: expression in x0..x3, p and the coefficients of B}``.

    Raises
    ------
    ValueError
        If ``sl`` does not determine ``y`` (its ``y``-coefficient matrix is singular).
    """
    A, r = sp.linear_eq_to_matrix(list(sl), list(_Y))
    if A.det() == 0:
        raise ValueError("sl: expected 4 equations that determine y0..y3, the y-coefficient "
                         "matrix is singular")
    sol = A.LUsolve(r)
    return {y: sp.cancel(s) for y, s in zip(_Y, sol, strict=True)}


@checked_symbolic(sr="exprs", y_solution="mapping")
def sr_in_x(sr: Sequence[sp.Expr], y_solution: Mapping[sp.Symbol, sp.Expr]) -> sp.Matrix:
    """Step 4: substitute ``y`` into ``sr``; the coefficient matrix ``M`` of ``M x = 0``.

    Each equation is made polynomial (numerator of the substituted equation).

    Parameters
    ----------
    sr : sequence of 4 sympy expressions
        The right chain's implicit equations (:func:`implicit_sets`, after :func:`assign`).
    y_solution : mapping of sympy.Symbol to sympy.Expr
        ``{y_i: ...}`` from :func:`solve_y_from_sl`.

    Returns
    -------
    sympy.Matrix, shape (4, 4)
        Row ``i`` is equation ``i`` of ``sr``, column ``j`` the coefficient of ``x_j``.
    """
    eqs = [sp.expand(sp.numer(sp.together(s.xreplace(dict(y_solution))))) for s in sr]
    M, rhs = sp.linear_eq_to_matrix(eqs, list(_X))
    if any(r != 0 for r in rhs):
        raise ValueError("sr: expected equations homogeneous in x0..x3 after substituting y")
    return M


@checked_symbolic(expr="expr", vectors="exprs8")
def reduce_study(expr: sp.Expr, *vectors: Sequence[sp.Expr]) -> sp.Expr:
    """Normal form of ``expr`` modulo the Study quadrics of the given symbolic vectors.

    Each quadric ``x0*y0 + ... + x3*y3`` is used as a rewrite rule for its
    leading monomial ``x0*y0`` (grevlex), i.e. ``x0*y0 -> -(x1*y1 + x2*y2 + x3*y3)``.
    Vectors without symbols (assigned numbers) are skipped: they either are on
    the quadric, or the caller's values are wrong.

    Parameters
    ----------
    expr : sympy.Expr
        A polynomial.
    *vectors : sequence of 8 sympy expressions
        Study vectors ``(x0..x3, y0..y3)`` whose quadrics are zero (e.g. ``B_SYMBOLS``).

    Returns
    -------
    sympy.Expr
        The remainder, expanded (``expr`` itself when no vector has symbols).
    """
    rules = []
    gens: list[sp.Symbol] = []
    for vec in vectors:
        vec = [sp.sympify(v) for v in vec]
        if all(v.is_Symbol for v in vec):
            rules.append(sum(vec[i] * vec[i + 4] for i in range(4)))
            gens += vec
    expr = sp.expand(expr)
    if not rules or expr == 0:
        return expr
    others = sorted(expr.free_symbols - set(gens), key=str)
    _, r = sp.reduced(expr, rules, *gens, *others, order="grevlex")
    return sp.expand(r)


@checked_symbolic(M="matrix", unknowns="indices3", equations="indices3")
def solve_x_from_sr(M: sp.Matrix, *, unknowns: Sequence[int] = (0, 1, 2),
                    equations: Sequence[int] = (1, 2, 3)
                    ) -> tuple[dict[sp.Symbol, sp.Expr], sp.Expr]:
    """Step 6: solve three equations of ``M x = 0`` for three ``x_i`` by Cramer's rule.

    Parameters
    ----------
    M : sympy.Matrix, shape (4, 4)
    unknowns : 3 ints, keyword-only
        Indices of the ``x_i`` solved for (default ``x0, x1, x2``).
    equations : 3 ints, keyword-only
        Rows used (default 1, 2, 3). With rows equal to the unknowns (a principal
        minor) a skew-symmetric ``M`` gives a zero determinant.

    Returns
    -------
    solution : dict
        ``{x_i: N_i * x_k / D}`` with ``x_k`` the remaining unknown.
    D : sympy.Expr
        The 3x3 minor (the common denominator).

    Raises
    ------
    ValueError
        If the chosen minor is identically zero.
    """
    unknowns, equations = list(unknowns), list(equations)
    if not all(isinstance(i, (int, np.integer)) and not isinstance(i, bool) and 0 <= i < 4
               for i in unknowns + equations) or len(set(unknowns)) != 3 \
            or len(set(equations)) != 3:
        raise ValueError(f"unknowns, equations: expected 3 distinct indices in 0..3 each, got "
                         f"{unknowns} and {equations}")
    free = next(k for k in range(4) if k not in unknowns)
    A = M.extract(equations, unknowns)
    c = -M.extract(equations, [free])
    D = sp.expand(A.det(method="bareiss"))
    if D == 0:
        raise ValueError(f"equations {equations}: the 3x3 minor for x{unknowns} is identically "
                         f"zero (for a skew-symmetric M a principal minor always is)")
    sol = {}
    for j, k in enumerate(unknowns):
        Aj = A.copy()
        Aj[:, j] = c
        sol[_X[k]] = sp.expand(Aj.det(method="bareiss")) * _X[free] / D
    return sol, D


@checked_symbolic(M="matrix", x_solution="mapping", equation="index4")
def back_substitute(M: sp.Matrix, x_solution: Mapping[sp.Symbol, sp.Expr], equation: int
                    ) -> sp.Expr:
    """Step 7: substitute the ``x_i`` into the remaining equation; its numerator.

    The remaining unknown ``x_k`` factors out. The substituted equation is
    ``(sum_j M[equation, j] N_j + M[equation, k] D) x_k / D``; returned is the
    numerator of this fraction after cancelling common factors with ``D``.

    Parameters
    ----------
    M : sympy.Matrix, shape (4, 4)
        Coefficient matrix of ``M x = 0`` (:func:`sr_in_x`).
    x_solution : mapping of sympy.Symbol to sympy.Expr
        Three ``x_i`` in terms of the fourth (:func:`solve_x_from_sr`).
    equation : int
        Row of ``M`` not used by ``x_solution`` (0..3).

    Returns
    -------
    sympy.Expr
        Polynomial in ``p`` and the assigned parameters; with the defaults, ``Pf(K(p))``
        (the quadratic in ``p`` of Section 3.2) times factors free of ``p``.
    """
    eq = sum(M[equation, j] * _X[j] for j in range(4))
    free = [s for s in _X if s not in x_solution]
    frac = sp.cancel(sp.together(eq.xreplace(dict(x_solution))) / free[0])
    return sp.expand(sp.numer(frac))


@dataclasses.dataclass(frozen=True)
class EliminationSteps:
    """Every intermediate result of Section 3.2 (see the module docstring).

    Attributes
    ----------
    sl, sr : tuple of sympy.Expr
        The implicit sets after assigning ``B`` and ``E``.
    y_solution : dict
        ``y0..y3`` from ``sl``.
    M : sympy.Matrix, shape (4, 4)
        ``sr`` in ``x`` after substituting ``y`` (as derived).
    K : sympy.Matrix, shape (4, 4)
        ``M`` reduced modulo the Study quadrics (skew-symmetric).
    symmetric_part : sympy.Matrix, shape (4, 4)
        ``(M + M^T) / 2`` before reduction: a multiple of the Study quadric(s).
    x_solution : dict
        Three ``x_i`` in terms of the fourth (from ``K``).
    minor : sympy.Expr
        The 3x3 minor of the Cramer solution.
    pfaffian : sympy.Expr
        ``Pf(K) = K01 K23 - K02 K13 + K03 K12``; ``det K = Pf(K)^2``.
    equations : tuple of int
        The three equations used for the Cramer step.
    back_substituted : sympy.Expr
        Numerator of the remaining equation after back substitution, common
        factors with the minor cancelled (the paper's step).
    factors : tuple of (sympy.Expr, int)
        Its factorisation (factor, multiplicity), constants dropped.
    quadratic : sympy.Poly
        ``-Pf(K)``, primitive, leading coefficient positive: the quadratic in ``p``.
        Generically ``back_substituted`` is this quadratic times factors free of
        ``p``; for special data the minor can share a root with ``Pf(K)``, and the
        back-substituted equation then misses that root (``roots_lost``).
    roots_lost : bool
        Whether ``back_substituted`` has fewer roots in ``p`` than the quadratic.
    """

    sl: tuple[sp.Expr, ...]
    sr: tuple[sp.Expr, ...]
    y_solution: dict[sp.Symbol, sp.Expr]
    M: sp.Matrix
    K: sp.Matrix
    symmetric_part: sp.Matrix
    x_solution: dict[sp.Symbol, sp.Expr]
    minor: sp.Expr
    pfaffian: sp.Expr
    equations: tuple[int, ...]
    back_substituted: sp.Expr
    factors: tuple[tuple[sp.Expr, int], ...]
    quadratic: sp.Poly
    roots_lost: bool


@functools.lru_cache(maxsize=16)
def _elimination_steps(b: tuple[sp.Expr, ...], e: tuple[sp.Expr, ...],
                       unknowns: tuple[int, ...], equations: tuple[int, ...] | None
                       ) -> EliminationSteps:
    return _run_steps(b, e, unknowns, equations)


def elimination_steps(*, b: Sequence[sp.Expr] | None = IDENTITY,
                      e: Sequence[sp.Expr] | None = F_SYMBOLS,
                      unknowns: Sequence[int] = (0, 1, 2),
                      equations: Sequence[int] | None = None) -> EliminationSteps:
    """Run steps 1-7 of Section 3.2 for an assignment of ``B`` and ``E``.

    Parameters
    ----------
    b, e : sequence of 8 values, keyword-only
        See :func:`assign`. Numbers must lie on the Study quadric. Fully
        symbolic ``b`` *and* ``e`` is correct but impractically large (the 3x3
        minor alone has about 29,000 terms), as the paper warns.
    unknowns, equations : 3 ints each, keyword-only
        See :func:`solve_x_from_sr`; the remaining equation is back-substituted.
        Default equations: the first of (1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2)
        whose minor is not identically zero.

    Returns
    -------
    EliminationSteps
        Memoised per argument set (``elimination_steps.cache_clear()`` forgets).

    Raises
    ------
    ValueError
        If the assigned numbers are not on the Study quadric (``K`` not skew).
    """
    try:
        unknowns = tuple(unknowns)
        equations = None if equations is None else tuple(equations)
    except TypeError:
        raise TypeError(f"unknowns, equations: expected 3 indices each, got "
                        f"{type(unknowns).__name__} and {type(equations).__name__}") from None
    for name, idx in (("unknowns", unknowns), ("equations", equations)):
        if idx is not None and not (len(idx) == 3 and all(
                isinstance(i, (int, np.integer)) and not isinstance(i, bool) and 0 <= i < 4
                for i in idx)):
            raise ValueError(f"{name}: expected 3 indices in 0..3, got {idx!r}")
    return _elimination_steps(_values(b, B_SYMBOLS, "b"), _values(e, E_SYMBOLS, "e"),
                              unknowns, equations)


def _run_steps(bv: tuple[sp.Expr, ...], ev: tuple[sp.Expr, ...], unknowns: tuple[int, ...],
               equations: tuple[int, ...] | None) -> EliminationSteps:
    sl0, sr0 = implicit_sets()
    sl = assign(sl0, b=bv, e=ev)
    sr = assign(sr0, b=bv, e=ev)
    ysol = solve_y_from_sl(sl)
    M = sr_in_x(sr, ysol)
    sym = (M + M.T) / 2
    K = M.applyfunc(lambda m: reduce_study(m, bv, ev))
    if sp.expand(K + K.T) != sp.zeros(4):
        raise ValueError("b, e: expected Study vectors on the Study quadric (the symmetric "
                         "part of M does not vanish)")
    pf = sp.expand(K[0, 1] * K[2, 3] - K[0, 2] * K[1, 3] + K[0, 3] * K[1, 2])
    choices = [equations] if equations is not None else [
        c for c in ((1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2)) if set(c) != set(unknowns)]
    for eqs in choices:
        try:
            xsol, D = solve_x_from_sr(K, unknowns=unknowns, equations=eqs)
        except ValueError:
            if equations is not None:
                raise
            continue
        break
    else:
        raise ValueError(f"no three equations determine x{list(unknowns)} (all minors vanish)")
    rest = next(i for i in range(4) if i not in eqs)
    num = reduce_study(back_substitute(K, xsol, rest), bv, ev)
    _, flist = sp.factor_list(num)
    factors = tuple((f, m) for f, m in flist if f.free_symbols)
    q = sp.Poly(-pf, P_SYMBOL)
    if q.degree() != 2:
        raise ValueError(f"expected Pf(K) of degree 2 in p, got degree {q.degree()}")
    q = q.primitive()[1]
    if q.LC().could_extract_minus_sign():
        q = -q
    deg_num = sum(m * sp.degree(f, P_SYMBOL) for f, m in factors if P_SYMBOL in f.free_symbols)
    return EliminationSteps(sl=sl, sr=sr, y_solution=ysol, M=M, K=K, symmetric_part=sym,
                            x_solution=xsol, minor=D, pfaffian=pf, equations=tuple(eqs),
                            back_substituted=num, factors=factors, quadratic=q,
                            roots_lost=deg_num < 2)


def p_quadratic(*, b: Sequence[sp.Expr] | None = IDENTITY,
                e: Sequence[sp.Expr] | None = F_SYMBOLS) -> sp.Poly:
    """The quadratic in ``p`` of Section 3.2 (steps 1-7).

    Parameters
    ----------
    b, e : sequence of 8 values, keyword-only
        Assignment of the Study parameters of ``B`` and ``E`` (:func:`assign`);
        default ``B = 1``, ``E = (f0..f7)``.

    Returns
    -------
    sympy.Poly
        In ``p``; its two roots are the values of the prismatic joint.

    Examples
    --------
    >>> from athenakin.symbolic import p_quadratic
    >>> p_quadratic(e=(1, 0, 0, 0, 0, 0, 0, -1))  # E: translation (0, 0, 2) from O_s
    Poly(p**2 - 4, p, domain='ZZ')
    """
    return elimination_steps(b=b, e=e).quadratic


@dataclasses.dataclass(frozen=True)
class GroebnerStep:
    """The paper's last step for numeric data: ``lc = lambda rc`` at one root ``p``.

    Attributes
    ----------
    p : sympy.Expr
        The value of the prismatic joint.
    equations : tuple of sympy.Expr
        ``lc_i - lambda * rc_i``, ``i = 0..7``.
    basis : tuple of sympy.Expr
        Reduced lex Groebner basis (variable order ``lambda, v1, v3, v5, v2, v4``).
    solutions : tuple of dict
        The solutions ``{lambda, v1, ..., v5}`` (exact where sympy finds them).
    """

    p: sp.Expr
    equations: tuple[sp.Expr, ...]
    basis: tuple[sp.Expr, ...]
    solutions: tuple[dict[sp.Symbol, sp.Expr], ...]


@checked_symbolic(p="expr", e="exprs8")
def groebner_remaining(p: sp.Expr, *, b: Sequence[sp.Expr] | None = IDENTITY,
                       e: Sequence[sp.Expr]) -> GroebnerStep:
    """Section 3.2, last step: the joints ``v1..v5`` for a root ``p`` by a Groebner basis.

    Parameters
    ----------
    p : number or sympy expression
        A root of :func:`p_quadratic` for the same ``b, e`` (exact).
    b, e : sequence of 8 numbers, keyword-only
        Exact Study vectors of ``B`` and ``E`` (rationals), on the Study quadric.

    Returns
    -------
    GroebnerStep
        Four solutions for a generic pose.
    """
    bv = _values(b, B_SYMBOLS, "b")
    ev = _values(e, E_SYMBOLS, "e")
    pv = sp.nsimplify(p) if isinstance(p, float) else sp.sympify(p)
    lc = assign(left_chain(), b=bv, e=ev)
    rc = assign(right_chain(), b=bv, e=ev)
    eqs = tuple(sp.expand(l_.xreplace({P_SYMBOL: pv}) - LAMBDA * r_)
                for l_, r_ in zip(lc, rc, strict=True))
    v1, v2, v3, v4, v5 = V_SYMBOLS
    gens = (LAMBDA, v1, v3, v5, v2, v4)
    G = sp.groebner(eqs, *gens, order="lex")
    sols = sp.solve(list(G.exprs), list(gens), dict=True)
    return GroebnerStep(p=pv, equations=eqs, basis=tuple(G.exprs), solutions=tuple(sols))


elimination_steps.cache_clear = _elimination_steps.cache_clear  # type: ignore[attr-defined]
