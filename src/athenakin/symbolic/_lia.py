"""The linear implicitization algorithm (LIA) of Walter and Husty.

Given a parametric variety ``X = X(t_1, ..., t_k)`` in projective coordinates
``X_0..X_{n-1}`` (here Study parameters), LIA finds all homogeneous implicit
equations of a chosen degree ``d`` by linear algebra alone:

1. Ansatz: the general form of degree ``d``, ``F = sum_j c_j m_j(X)``, one unknown
   coefficient ``c_j`` per monomial ``m_j`` of degree ``d`` in the ``n`` coordinates.
2. Substitute the parametrization ``X = X(t)`` into every monomial and collect
   the coefficients of each monomial in the parameters ``t``. ``F(X(t)) = 0`` for
   all ``t`` iff all of these vanish: a homogeneous *linear* system ``A c = 0`` in
   the unknowns ``c``. (Because ``F`` is homogeneous, any scale factor of the
   parametrization drops out: projective parametrizations are fine.)
3. A basis of the null space of ``A`` is a basis of the degree-``d`` part of the
   ideal of the variety (of its Zariski closure); each null vector is one
   implicit equation.

The entries of ``A`` may contain further symbols (design or pose parameters that
are not eliminated, e.g. ``b0..b7`` and ``p`` for the left chain); the null space
is then computed over their field of rational functions and each equation is
made polynomial by clearing denominators and removing the content. This is
exact (no numerical rank decisions) and valid for generic values of those
symbols; at special values the rank of ``A`` may drop, i.e. the specialised
variety may satisfy more equations.

References
----------
.. [1] D. Walter and M. L. Husty, "On implicitization of kinematic constraint
   equations", Machine Design & Research, vol. 26, pp. 218-226, 2010
   (reference [1] of the paper).
.. [2] M. L. Husty, M. Pfurner and H.-P. Schroecker, "A new and efficient
   algorithm for the inverse kinematics of a general serial 6R manipulator",
   Mechanism and Machine Theory 42(1), pp. 66-81, 2007 (the left/right split
   of the chain that LIA is applied to).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import sympy as sp
from sympy.polys.matrices import DomainMatrix

from ._algebra import X_SYMBOLS, checked_symbolic

__all__ = ["implicitize", "implicitization_matrix"]


def _coordinates(n: int, coordinates: Sequence[sp.Symbol] | None) -> tuple[sp.Symbol, ...]:
    if coordinates is None:
        if n == 8:
            return X_SYMBOLS
        return tuple(sp.symbols(f"X0:{n}", real=True))
    coordinates = tuple(coordinates)
    if len(coordinates) != n:
        raise ValueError(f"coordinates: expected {n} symbols (one per component of the "
                         f"parametrization), got {len(coordinates)}")
    return coordinates


@checked_symbolic(parametrization="exprs", parameters="symbols", degree="degree")
def implicitization_matrix(parametrization: Sequence[sp.Expr], parameters: Sequence[sp.Symbol],
                           degree: int
                           ) -> tuple[sp.Matrix, list[tuple[int, ...]]]:
    """Step 1-2 of LIA: the linear system ``A c = 0`` of the degree-``degree`` ansatz.

    Parameters
    ----------
    parametrization : sequence of n sympy expressions
        Components of the parametrized point, polynomial in ``parameters``.
    parameters : sequence of sympy symbols
        The parameters to eliminate.
    degree : int
        Degree of the implicit equations, >= 1.

    Returns
    -------
    A : sympy.Matrix, shape (number of parameter monomials, number of ansatz monomials)
    monomials : list of tuples of int
        Column ``j`` of ``A`` is the ansatz monomial ``prod(X[i] for i in monomials[j])``.
    """
    if not isinstance(degree, int) or degree < 1:
        raise ValueError(f"degree: expected an integer >= 1, got {degree!r}")
    comps = [sp.expand(c) for c in parametrization]
    params = tuple(parameters)
    if not params:
        raise ValueError("parameters: expected at least one symbol to eliminate, got none")
    monos = list(itertools.combinations_with_replacement(range(len(comps)), degree))
    columns: list[dict[tuple[int, ...], sp.Expr]] = []
    # products are built incrementally, sharing prefixes
    cache: dict[tuple[int, ...], sp.Poly] = {}

    def prod(m: tuple[int, ...]) -> sp.Poly:
        if m in cache:
            return cache[m]
        if len(m) == 1:
            out = sp.Poly(comps[m[0]], *params)
        else:
            out = prod(m[:-1]) * sp.Poly(comps[m[-1]], *params)
        cache[m] = out
        return out

    for m in monos:
        columns.append(dict(prod(m).terms()))
    rows = sorted({k for col in columns for k in col}, reverse=True)
    A = sp.Matrix(len(rows), len(monos),
                  lambda i, j: columns[j].get(rows[i], sp.Integer(0)))
    return A, monos


def _primitive(vec: list[sp.Expr]) -> list[sp.Expr]:
    """Clear denominators and remove the polynomial content of a null vector."""
    vec = [sp.cancel(sp.together(c)) for c in vec]
    dens = [sp.denom(c) for c in vec if c != 0]
    L = sp.lcm_list(dens) if dens else sp.Integer(1)
    nums = [sp.expand(sp.cancel(c * L)) for c in vec]
    nz = [c for c in nums if c != 0]
    g = sp.gcd_list(nz) if nz else sp.Integer(1)
    out = [sp.expand(sp.cancel(c / g)) for c in nums]
    # sign: make the first non-zero coefficient's leading term positive
    first = next((c for c in out if c != 0), sp.Integer(1))
    lc = sp.Poly(first, *sorted(first.free_symbols, key=str)).LC() if first.free_symbols \
        else first
    return [-c for c in out] if lc < 0 else out


@checked_symbolic(parametrization="exprs", parameters="symbols", degree="degree",
                  coordinates="symbols_or_none")
def implicitize(parametrization: Sequence[sp.Expr], parameters: Sequence[sp.Symbol],
                degree: int = 1, *, coordinates: Sequence[sp.Symbol] | None = None
                ) -> list[sp.Expr]:
    """Implicit equations of a parametrized variety by the linear implicitization algorithm.

    Parameters
    ----------
    parametrization : sequence of n sympy expressions
        Projective coordinates of a point of the variety (e.g. a Study vector,
        :func:`~athenakin.symbolic.left_chain`), polynomial in ``parameters``.
        Any other symbols are treated as generic constants.
    parameters : sequence of sympy symbols
        Parameters to eliminate (e.g. ``v1, v2``).
    degree : int, optional
        Degree ``d`` of the sought homogeneous equations (default 1: the linear
        equations, i.e. the linear span of the variety).
    coordinates : sequence of n sympy symbols, keyword-only, optional
        Names of the implicit coordinates; default ``x0..x3, y0..y3`` when
        ``n = 8`` (Study parameters), else ``X0..X{n-1}``.

    Returns
    -------
    list of sympy.Expr
        A basis of the degree-``d`` homogeneous forms in ``coordinates`` (with
        coefficients polynomial in the remaining symbols, denominators cleared,
        content removed) that vanish on the variety. Empty if there are none.

    Notes
    -----
    Algorithm and references in the module docstring. For the left chain
    ``lc`` (Eq. 13) and the right chain ``rc`` (Eq. 14) at degree 1 this gives the
    sets ``sl`` and ``sr`` of the paper: 4 linear equations each. At degree 2 the
    space also contains products of the linear equations with the coordinates
    and, for a variety on the Study quadric, the quadric itself.

    Examples
    --------
    >>> import sympy as sp
    >>> s, t = sp.symbols("s t")
    >>> implicitize([1 - t**2, 2 * t, 1 + t**2], [t], 2,
    ...             coordinates=sp.symbols("a b c"))  # the unit circle
    [a**2 + b**2 - c**2]
    """
    comps = list(parametrization)
    coords = _coordinates(len(comps), coordinates)
    A, monos = implicitization_matrix(comps, parameters, degree)
    others = sorted(set().union(*(sp.sympify(c).free_symbols for c in comps))
                    - set(parameters), key=str)
    dm = DomainMatrix.from_list_sympy(*A.shape, A.tolist())
    dm = dm.convert_to(sp.QQ.frac_field(*others) if others else sp.QQ)
    null = dm.nullspace().to_Matrix()
    out = []
    for i in range(null.rows):
        c = _primitive(list(null.row(i)))
        F = sum((ci * sp.Mul(*[coords[k] for k in m]) for ci, m in zip(c, monos, strict=True)),
                sp.Integer(0))
        out.append(sp.expand(F))
    return out
