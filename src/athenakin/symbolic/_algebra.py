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

from collections.abc import Callable, Mapping, Sequence

import sympy as sp


def _expr(x: object, name: str) -> sp.Expr:
    """``x`` as a sympy expression (numbers allowed), or a TypeError naming ``name``."""
    if isinstance(x, (str, bytes, bool)) or x is None:
        raise TypeError(f"{name}: expected a sympy expression or a number, got "
                        f"{type(x).__name__}")
    try:
        e = sp.sympify(x, strict=True)
    except (sp.SympifyError, TypeError, ValueError, AttributeError):
        raise TypeError(f"{name}: expected a sympy expression or a number, got "
                        f"{type(x).__name__}") from None
    if not isinstance(e, sp.Expr) or isinstance(e, sp.logic.boolalg.BooleanAtom) \
            or e.has(sp.nan, sp.zoo, sp.oo, -sp.oo):
        raise TypeError(f"{name}: expected a finite sympy expression or number, got {x!r}")
    return e


def _show(v: object) -> str:
    """A short text of a value for a message (no 400-digit integers)."""
    if isinstance(v, int) and abs(v) >= 10**6:
        return f"an integer of {len(str(abs(v)))} digits"
    return repr(v) if isinstance(v, (int, float)) else type(v).__name__


#: Largest degree of an implicitisation (the monomial basis grows as the degree to the
#: number of coordinates).
MAX_DEGREE = 12


def _check_expr(name: str, v: object) -> None:
    _expr(v, name)


def _check_exprs(name: str, v: object, count: int | None = None) -> None:
    if isinstance(v, (str, bytes, Mapping)) or not isinstance(v, (Sequence, sp.MatrixBase)):
        raise TypeError(f"{name}: expected a sequence of sympy expressions, got "
                        f"{type(v).__name__}")
    items = list(v)
    if count is not None and len(items) != count:
        raise ValueError(f"{name}: expected {count} entries (a Study vector), got {len(items)}")
    for i, x in enumerate(items):
        _expr(x, f"{name}[{i}]")


def _check_vectors8(name: str, v: object) -> None:
    if isinstance(v, (str, bytes)) or not isinstance(v, Sequence) or not v:
        raise TypeError(f"{name}: expected a non-empty sequence of Study vectors, got "
                        f"{type(v).__name__}")
    for i, x in enumerate(v):
        _check_exprs(f"{name}[{i}]", x, 8)


def _check_symbols(name: str, v: object) -> None:
    if isinstance(v, Sequence) and not isinstance(v, (str, bytes)) and len(v) == 0:
        raise ValueError(f"{name}: expected at least one sympy Symbol, got none")
    if isinstance(v, (str, bytes)) or not isinstance(v, Sequence) \
            or not all(isinstance(x, sp.Symbol) for x in v):
        raise TypeError(f"{name}: expected a non-empty sequence of sympy Symbols, got {v!r}")


def _check_matrix(name: str, v: object) -> None:
    if not isinstance(v, sp.MatrixBase):
        raise TypeError(f"{name}: expected a sympy Matrix, got {type(v).__name__}")


def _check_mapping(name: str, v: object) -> None:
    if not isinstance(v, Mapping) or not all(isinstance(k, sp.Symbol) for k in v):
        raise TypeError(f"{name}: expected a mapping sympy Symbol -> expression, got "
                        f"{type(v).__name__}")
    for k, x in v.items():
        _expr(x, f"{name}[{k}]")


def _check_small_int(name: str, v: object, stop: int, what: str) -> None:
    """``v`` an int (not a bool) in ``0..stop - 1``, or a ValueError naming ``what``."""
    if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v < stop:
        raise ValueError(f"{name}: expected {what} in 0..{stop - 1}, got {_show(v)}")


def _check_indices3(name: str, v: object) -> None:
    if isinstance(v, (str, bytes)) or not isinstance(v, Sequence) or len(v) != 3 \
            or not all(isinstance(i, int) and not isinstance(i, bool) and 0 <= i < 4
                       for i in v):
        raise ValueError(f"{name}: expected 3 indices in 0..3, got {v!r}")


def _check_count(name: str, v: object) -> None:
    if isinstance(v, bool) or not isinstance(v, int) or v < 0:
        raise TypeError(f"{name}: expected a non-negative int, got {v!r}")


#: The argument kinds of :func:`checked_symbolic`: kind -> ``check(name, value)``.
_CHECKS: dict[str, Callable[[str, object], None]] = {
    "expr": _check_expr,
    "exprs": _check_exprs,
    "exprs8": lambda name, v: _check_exprs(name, v, 8),
    "vectors8": _check_vectors8,
    "symbols": _check_symbols,
    "symbols_or_none": lambda name, v: None if v is None else _check_symbols(name, v),
    "matrix": _check_matrix,
    "mapping": _check_mapping,
    "degree": lambda name, v: _check_small_int(name, v, MAX_DEGREE + 1, "a degree"),
    "index4": lambda name, v: _check_small_int(name, v, 4, "an index"),
    "indices3": _check_indices3,
    "int": _check_count,
}


def checked_symbolic(**kinds: str):  # type: ignore[no-untyped-def]
    """Check arguments of a computer-algebra function by kind, naming each.

    Kinds: ``"expr"`` (one expression), ``"exprs"`` (a sequence of them), ``"exprs8"``
    (exactly 8), ``"symbols"`` (a non-empty sequence of sympy Symbols), ``"matrix"``
    (a sympy Matrix), ``"mapping"`` (Symbol -> expression), ``"int"`` (a non-negative int);
    the others of :data:`_CHECKS`.
    """
    import functools
    import inspect

    def check(kind: str, name: str, v: object) -> None:
        if kind in _CHECKS:
            _CHECKS[kind](name, v)

    def wrap(f):  # type: ignore[no-untyped-def]
        sig = inspect.signature(f)

        @functools.wraps(f)
        def inner(*args, **kwargs):  # type: ignore[no-untyped-def]
            try:
                bound = sig.bind(*args, **kwargs)
            except TypeError as exc:
                raise TypeError(f"{f.__name__}: {exc}") from None
            for name, kind in kinds.items():
                if name in bound.arguments:
                    v = bound.arguments[name]
                    if sig.parameters[name].kind is inspect.Parameter.VAR_POSITIONAL:
                        for j, x in enumerate(v):
                            check(kind, f"{name}[{j}]", x)
                    else:
                        check(kind, name, v)
            return f(*args, **kwargs)

        return inner

    return wrap

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


@checked_symbolic(factors="vectors8")
def dq_product(factors: Sequence[Sequence[sp.Expr]]) -> sp.ImmutableMatrix:
    """Product ``F1 * F2 * ... * Fn`` of dual quaternions, left to right, expanded.

    Parameters
    ----------
    factors : sequence of 8-vectors of sympy expressions
        At least one, each ``(x0..x3, y0..y3)`` (e.g. the chain of Eq. 5 / 11).

    Returns
    -------
    sympy.ImmutableMatrix, shape (8, 1)
    """
    factors = list(factors)
    if not factors:
        raise ValueError("factors: expected at least one dual quaternion, got none")
    out = study_vector(list(factors[0]))
    for f in factors[1:]:
        out = dq_multiply(out, f)
    return out


def dq_conj_quaternion(X: Sequence[sp.Expr]) -> sp.ImmutableMatrix:
    """``conj(x) + eps conj(y)``: for a Study vector, the inverse displacement (up to scale).

    Parameters
    ----------
    X : sequence of 8 sympy expressions
        ``(x0, x1, x2, x3, y0, y1, y2, y3)``.

    Returns
    -------
    sympy.ImmutableMatrix, shape (8, 1)
        ``(x0, -x1, -x2, -x3, y0, -y1, -y2, -y3)``.
    """
    X = list(study_vector(X, "X"))
    return study_vector([X[0], -X[1], -X[2], -X[3], X[4], -X[5], -X[6], -X[7]])


def study_M(v: sp.Expr) -> sp.ImmutableMatrix:
    """``M_i`` of Eq. 6 in the half-tangent ``v = tan(u/2)``: ``(1, 0, 0, v, 0, 0, 0, 0)``.

    Parameters
    ----------
    v : sympy expression
        ``tan(u_i / 2)``.

    Returns
    -------
    sympy.ImmutableMatrix, shape (8, 1)
    """
    return study_vector([1, 0, 0, v, 0, 0, 0, 0], "v")


@checked_symbolic(a="expr", d="expr", al="expr")
def study_G(a: sp.Expr, d: sp.Expr, al: sp.Expr) -> sp.ImmutableMatrix:
    """``G_i`` of Eq. 6 in the half-tangent ``al = tan(alpha/2)``.

    ``(1, al, 0, 0, a*al/2, -a/2, -d*al/2, -d/2)``: translation by ``(a, 0, d)``
    followed by the rotation about x by ``alpha``.

    Parameters
    ----------
    a, d : sympy expression
        DH lengths ``a_i``, ``d_i`` (Eq. 12).
    al : sympy expression
        ``tan(alpha_i / 2)`` (``al_i`` of Eq. 12).

    Returns
    -------
    sympy.ImmutableMatrix, shape (8, 1)
    """
    a, d, al = sp.sympify(a), sp.sympify(d), sp.sympify(al)
    return study_vector([1, al, 0, 0, a * al / 2, -a / 2, -d * al / 2, -d / 2], "a, d, al")


def study_quadric(X: Sequence[sp.Expr]) -> sp.Expr:
    """The Study quadric ``x0*y0 + x1*y1 + x2*y2 + x3*y3`` of an 8-vector, expanded.

    Parameters
    ----------
    X : sequence of 8 sympy expressions
        ``(x0, x1, x2, x3, y0, y1, y2, y3)``.

    Returns
    -------
    sympy.Expr
    """
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

    Parameters
    ----------
    X : sequence of 8 sympy expressions
        ``(x0, x1, x2, x3, y0, y1, y2, y3)``.

    Returns
    -------
    sympy.Matrix, shape (4, 4)
        ``Delta * T`` (no division): ``[[Delta, 0], [(p, q, r), Delta * R]]``, a
        polynomial matrix in the Study parameters.
    """
    R, t, D = _eq3_parts(X)
    M = sp.zeros(4, 4)
    M[0, 0] = D
    M[1:, 0] = t
    M[1:, 1:] = R
    return M


def transform_matrix(X: Sequence[sp.Expr]) -> sp.Matrix:
    """The displacement of Eq. 3-4 as ``[[R, t], [0, 1]]`` (ecosystem layout, divided by Delta).

    Parameters
    ----------
    X : sequence of 8 sympy expressions
        ``(x0, x1, x2, x3, y0, y1, y2, y3)``.

    Returns
    -------
    sympy.Matrix, shape (4, 4)
        Rational in the Study parameters.
    """
    R, t, D = _eq3_parts(X)
    M = sp.eye(4)
    M[:3, :3] = R / D
    M[:3, 3] = t / D
    return M
